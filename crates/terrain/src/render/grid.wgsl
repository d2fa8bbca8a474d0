// The terrain as a grid on the GPU: one patch of PATCH_CELLS x PATCH_CELLS cells, drawn once per
// chosen quadtree node (an instance: its first sample, its stride and its skirts' depth), its
// heights read from the 16-bit texture of `heights.wgsl`. Each patch vertex says where in the
// patch it is (a vertex buffer of small integers, so the shader divides nothing).

struct GridVertex {
    @builtin(position) clip: vec4<f32>,
    // The point in the world as it is (not mirrored).
    @location(0) world: vec3<f32>,
    @location(1) uv: vec2<f32>,
}

// The world position of the patch vertex `corner` (its column and row in the patch, then 1 for
// a skirt's bottom, 0 on the surface) of the patch `node` (first column, first row, stride,
// skirt depth as bits).
fn grid_point(corner: vec4<u32>, node: vec4<u32>) -> vec3<f32> {
    let column = min(node.x + corner.x * node.z, grid.columns - 1u);
    let row = min(node.y + corner.y * node.z, grid.rows - 1u);
    let drop = select(0.0, bitcast<f32>(node.w), corner.z != 0u);
    let height = sample_height(column, row) - drop;
    return vec3<f32>(grid.origin.x + f32(column) * grid.cell, height, grid.origin.y + f32(row) * grid.cell);
}

@vertex
fn vs_main(@location(0) corner: vec4<u32>, @location(1) node: vec4<u32>) -> GridVertex {
    let world = grid_point(corner, node);
    var out: GridVertex;
    out.clip = to_clip(world);
    out.world = world;
    out.uv = world.xz * grid.inverse_extent + vec2<f32>(0.5, 0.5);
    return out;
}
