// The heightmap on the GPU (group 1, bindings 0 and 1): its layout in the world and its
// 16-bit samples. Shared by the terrain grid and the water (which finds the sea floor in it).

struct Grid {
    // Samples per row and number of rows of the heightmap.
    columns: u32,
    rows: u32,
    // Cells along a patch's side.
    patch_cells: u32,
    padding0: u32,
    // World x, z of sample (0, 0), and the distance between samples.
    origin: vec2<f32>,
    cell: f32,
    // Height mapping: height = (level + level_offset) * unit_height, level = value / 257.
    level_offset: f32,
    unit_height: f32,
    // Repeats of the detail map across the terrain.
    detail_repeat: f32,
    // 1 / (width, depth) of the terrain's footprint: maps x, z to the colour map's u, v.
    inverse_extent: vec2<f32>,
}

@group(1) @binding(0) var<uniform> grid: Grid;
@group(1) @binding(1) var heights: texture_2d<u32>;

// The world height of sample (column, row), clamped to the map.
fn sample_height(column: u32, row: u32) -> f32 {
    let c = min(column, grid.columns - 1u);
    let r = min(row, grid.rows - 1u);
    let value = textureLoad(heights, vec2<i32>(i32(c), i32(r)), 0).r;
    return (f32(value) / 257.0 + grid.level_offset) * grid.unit_height;
}

