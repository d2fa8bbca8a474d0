//! The terrain's static mesh, built once: the part of the heightfield at or above the water, in
//! square chunks, each at several levels of detail.
//!
//! Every chunk covers [`CHUNK_CELLS`] x [`CHUNK_CELLS`] cells and is stored at strides 1, 2, 4, ...
//! up to its size (level 0 is every sample, level 1 every other one, ...). Each level knows how far
//! it strays vertically from the full surface, so a renderer can pick per chunk the coarsest level
//! whose error is too small to see ([`TerrainMesh::select`]). Chunk edges hang short vertical
//! "skirts" below the surface, which hide the cracks where neighbouring chunks at different levels
//! meet.
//!
//! Triangles are cut along the water (y = 0): heights vary linearly across a triangle, so this
//! keeps exactly the surface the course's renderer kept by discarding fragments below the water,
//! but the GPU never sees the underwater part and needs no `discard` (which would cost it its
//! early depth test).

use std::collections::HashMap;

use glam::Vec3;

use super::Heightfield;
use super::chunk::{BlockGrid, block_floors};
pub use super::chunk::{CHUNK_CELLS, Chunk, ChunkLevel, DrawRange, EDGE_COUNT};
use super::heightfield::cell_surface;
use super::occlusion::WaterOcclusion;
use crate::camera::Frustum;

/// What the level-of-detail choice needs to know about the view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodView {
    /// The camera's position.
    pub eye: Vec3,
    /// What the camera sees (of the mirrored world, when `mirrored`).
    pub frustum: Frustum,
    /// The world-to-clip matrix the frustum is made of.
    pub view_projection: glam::Mat4,
    /// Pixels covered by one world unit seen face-on at a distance of one unit:
    /// `viewport height / (2 tan(vertical field of view / 2))`.
    pub pixels_per_unit: f32,
    /// Largest error allowed on screen, in pixels.
    pub max_error_pixels: f32,
    /// Whether this is the mirrored pass (chunks are tested mirrored in y = 0).
    pub mirrored: bool,
    /// The largest distance from the eye, in world units, of a point in front of the camera that
    /// the near plane clips away.
    pub near_reach: f32,
}

/// The terrain above the water as indexed triangle lists, in chunks and levels of detail.
///
/// Every part of a chunk level (its surface, each strip of its skirts) has its own compact block
/// of vertices (its samples, the points where its edges cross the water, the bottoms of its
/// skirts) and 16-bit indices relative to the block: a GPU then only processes the vertices a
/// draw uses. Surface triangles are wound counter-clockwise seen from above (their normals point
/// up, +y); each skirt has a strip facing either way.
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainMesh {
    /// World positions (x, y, z) of all blocks, one after the other.
    pub positions: Vec<[f32; 3]>,
    /// Triangle-list indices, relative to their level's `base_vertex`, chunk by chunk and level
    /// by level.
    pub indices: Vec<u16>,
    /// The chunks, row by row from the far row. Chunks entirely under water have no indices.
    pub chunks: Vec<Chunk>,
    /// Where the chunks' blocks lie, to tell which mirrored chunks the land hides.
    pub grid: BlockGrid,
}

impl TerrainMesh {
    /// Builds the mesh of `field`'s part at or above y = 0.
    pub fn new(field: &Heightfield) -> Self {
        let spans = |samples: u32| -> Vec<(u32, u32)> {
            (0..samples - 1)
                .step_by(CHUNK_CELLS as usize)
                .map(|start| (start, (start + CHUNK_CELLS).min(samples - 1)))
                .collect()
        };
        let (row_spans, column_spans) = (spans(field.rows()), spans(field.columns()));
        let errors: Vec<Vec<f32>> = row_spans
            .iter()
            .flat_map(|&r| column_spans.iter().map(move |&c| (r, c)))
            .map(|(r, c)| level_errors(field, r, c))
            .collect();
        let mut mesh = TerrainMesh {
            positions: Vec::new(),
            indices: Vec::new(),
            chunks: Vec::with_capacity(errors.len()),
            grid: BlockGrid::new(field, column_spans.len() as u32),
        };
        for (i, &rows) in row_spans.iter().enumerate() {
            for (j, &columns) in column_spans.iter().enumerate() {
                // Skirts hang deep enough to meet any neighbour's coarsest surface.
                let coarsest_error = |di: isize, dj: isize| {
                    let (ni, nj) = (i as isize + di, j as isize + dj);
                    let inside = (0..row_spans.len() as isize).contains(&ni)
                        && (0..column_spans.len() as isize).contains(&nj);
                    let errors = inside.then(|| &errors[ni as usize * column_spans.len() + nj as usize]);
                    errors.and_then(|e| e.last().copied()).unwrap_or(0.0)
                };
                let skirt_depth = [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)]
                    .iter()
                    .map(|&(di, dj)| coarsest_error(di, dj))
                    .fold(0.0, f32::max)
                    + 0.5 * field.cell_size();
                let chunk_errors = &errors[i * column_spans.len() + j];
                let chunk = mesh.add_chunk(field, rows, columns, chunk_errors, skirt_depth);
                mesh.chunks.push(chunk);
            }
        }
        mesh
    }

    /// Builds every level of the chunk spanning samples `rows.0..=rows.1` x
    /// `columns.0..=columns.1`, appending their blocks.
    fn add_chunk(
        &mut self,
        field: &Heightfield,
        rows: (u32, u32),
        columns: (u32, u32),
        errors: &[f32],
        skirt_depth: f32,
    ) -> Chunk {
        let mut levels = Vec::with_capacity(errors.len());
        for (level, &error) in errors.iter().enumerate() {
            let stride = 1 << level;
            let (row_samples, column_samples) = (samples(rows, stride), samples(columns, stride));
            let mut block = Block::default();
            for &row in &row_samples {
                for &column in &column_samples {
                    block.positions.push(field.point(row, column).to_array());
                }
            }
            let width = column_samples.len();
            let (last_row, last_column) = (row_samples.len() - 1, width - 1);
            let at = |i: usize, j: usize| (i * width + j) as u32;
            for i in 0..last_row {
                for j in 0..last_column {
                    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
                    // (a, b, c) and (c, b, d) turn counter-clockwise seen from above.
                    block.add([a, b, c]);
                    block.add([c, b, d]);
                }
            }
            // The edges' samples, in increasing order along each edge ([`EDGE_COUNT`] order).
            let edges: [Vec<[f32; 3]>; EDGE_COUNT] = [
                (0..width).map(|j| block.positions[at(0, j) as usize]).collect(),
                (0..width).map(|j| block.positions[at(last_row, j) as usize]).collect(),
                (0..=last_row).map(|i| block.positions[at(i, 0) as usize]).collect(),
                (0..=last_row).map(|i| block.positions[at(i, last_column) as usize]).collect(),
            ];
            let block_floors = block_floors(field, (rows, columns), &row_samples, &column_samples);
            let surface = self.push_block(block);
            let mut edge_index = 0;
            let skirts = edges.map(|edge| {
                // Rows are planes of constant z, columns of constant x.
                let axis = if edge_index < 2 { 2 } else { 0 };
                edge_index += 1;
                let strips = [0, 1].map(|side| skirt_strip(&edge, side, skirt_depth));
                // Order the strips by the side they face: toward -axis first.
                let facing_negative = |strip: &Block| {
                    strip.indices.chunks_exact(3).next().is_some_and(|t| {
                        let p = |i: u32| Vec3::from_array(strip.positions[i as usize]);
                        let normal = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
                        normal[axis] < 0.0
                    })
                };
                let [first, second] = strips;
                let ordered = if facing_negative(&second) { [second, first] } else { [first, second] };
                ordered.map(|strip| self.push_block(strip))
            });
            levels.push(ChunkLevel { surface, skirts, error, block_floors });
        }
        let heights =
            (rows.0..=rows.1).flat_map(|r| (columns.0..=columns.1).map(move |c| field.height(r, c)));
        let (low, high) = heights.fold((f32::MAX, f32::MIN), |(lo, hi), h| (lo.min(h), hi.max(h)));
        let (first, last) = (field.point(rows.0, columns.0), field.point(rows.1, columns.1));
        Chunk {
            min: Vec3::new(first.x, (low - skirt_depth).max(0.0), first.z),
            max: Vec3::new(last.x, high.max(0.0), last.z),
            edge_planes: [first.z, last.z, first.x, last.x],
            levels,
        }
    }

    /// Appends a block's vertices and indices and returns its range.
    fn push_block(&mut self, block: Block) -> DrawRange {
        // A block has at most 33 x 33 samples plus a few crossings, far below the 65536 that
        // 16-bit indices can reach.
        debug_assert!(block.positions.len() <= usize::from(u16::MAX) + 1);
        let range = DrawRange {
            first_index: self.indices.len() as u32,
            index_count: block.indices.len() as u32,
            base_vertex: self.positions.len() as u32,
        };
        self.positions.extend(block.positions);
        self.indices.extend(block.indices.iter().map(|&i| i as u16));
        range
    }

    /// The surface triangles of `level` over all chunks (chunks with fewer levels at their
    /// coarsest), as world positions, without skirts.
    pub fn surface_triangles(&self, level: usize) -> Vec<[Vec3; 3]> {
        self.chunks
            .iter()
            .filter_map(|chunk| chunk.levels.get(level).or(chunk.levels.last()))
            .flat_map(|l| self.triangles(&l.surface))
            .collect()
    }

    /// The triangles of `range`, as world positions.
    pub fn triangles(&self, range: &DrawRange) -> Vec<[Vec3; 3]> {
        let start = range.first_index as usize;
        let end = start + range.index_count as usize;
        let vertex = |i: u16| Vec3::from_array(self.positions[range.base_vertex as usize + usize::from(i)]);
        self.indices[start..end].chunks_exact(3).map(|t| [vertex(t[0]), vertex(t[1]), vertex(t[2])]).collect()
    }

    /// Number of surface triangles of `level` over all chunks (chunks with fewer levels count
    /// at their coarsest).
    pub fn triangle_count(&self, level: usize) -> usize {
        self.chunks
            .iter()
            .filter_map(|chunk| chunk.levels.get(level).or(chunk.levels.last()))
            .map(|l| l.surface.index_count as usize / 3)
            .sum()
    }

    /// What to draw for `view`: the chunks in view, nearest first (so the depth test hides what
    /// is behind before it is shaded), each at the coarsest level whose error stays within
    /// `view.max_error_pixels` on screen, as its surface and the skirt strips that face the camera
    /// (up to five ranges a chunk). Chunks out of view or under water are left out.
    pub fn select(&self, view: &LodView) -> Vec<DrawRange> {
        self.ranges(view, &self.choose(view))
    }

    /// What the direct pass (`direct`) and the mirrored pass (`mirrored`) draw, as
    /// [`Self::select`] chooses it for each, except the mirrored chunks that the land drawn by
    /// the direct pass hides from the eye ([`WaterOcclusion`]): they would draw no pixel.
    pub fn select_pair(&self, direct: &LodView, mirrored: &LodView) -> [Vec<DrawRange>; 2] {
        let direct_chosen = self.choose(direct);
        let mut mirrored_chosen = self.choose(mirrored);
        let levels = direct_chosen.iter().map(|&(_, chunk, level)| (chunk, level));
        if let Some(mut occlusion) = WaterOcclusion::new(
            &self.grid,
            &self.chunks,
            levels,
            (direct.eye, direct.view_projection),
            direct.near_reach,
        ) {
            mirrored_chosen.retain(|&(_, chunk, _)| !occlusion.hides(&self.chunks[chunk]));
        }
        [self.ranges(direct, &direct_chosen), self.ranges(mirrored, &mirrored_chosen)]
    }

    /// The chunks in `view` (by index), nearest first, each with the level to draw it at, and
    /// the key they are ordered by.
    fn choose(&self, view: &LodView) -> Vec<(f32, usize, usize)> {
        let mut chosen: Vec<(f32, usize, usize)> = self
            .chunks
            .iter()
            .enumerate()
            .filter(|(_, chunk)| chunk.levels.first().is_some_and(|l| !l.is_empty()))
            .filter_map(|(index, chunk)| {
                let (min, max) = if view.mirrored {
                    (
                        Vec3::new(chunk.min.x, -chunk.max.y, chunk.min.z),
                        Vec3::new(chunk.max.x, -chunk.min.y, chunk.max.z),
                    )
                } else {
                    (chunk.min, chunk.max)
                };
                if !view.frustum.intersects_box(min, max) {
                    return None;
                }
                let distance = (view.eye.clamp(min, max) - view.eye).length().max(1e-3);
                let allowed = view.max_error_pixels * distance / view.pixels_per_unit;
                let level = chunk.levels.iter().rposition(|l| l.error <= allowed).unwrap_or(0);
                // Order by the distance to the box's centre: the eye may be inside several boxes,
                // which are all at distance 0 from their surfaces.
                let order = ((min + max) * 0.5 - view.eye).length_squared();
                Some((order, index, level))
            })
            .collect();
        chosen.sort_by(|a, b| a.0.total_cmp(&b.0));
        chosen
    }

    /// The ranges drawing the `chosen` chunk levels for `view`: each surface and the skirt strips
    /// facing the camera.
    fn ranges(&self, view: &LodView, chosen: &[(f32, usize, usize)]) -> Vec<DrawRange> {
        let mut ranges = Vec::with_capacity(chosen.len() * (1 + EDGE_COUNT));
        for &(_, index, level) in chosen {
            let chunk = &self.chunks[index];
            let level = &chunk.levels[level];
            ranges.push(level.surface);
            for (edge, strips) in level.skirts.iter().enumerate() {
                // Rows are planes of constant z, columns of constant x. The mirror image keeps x
                // and z, so the same strip faces the camera in both passes.
                let eye = if edge < 2 { view.eye.z } else { view.eye.x };
                let offset = eye - chunk.edge_planes[edge];
                // Within a millimetre of the plane both strips are drawn, so that rounding can
                // never drop a strip the GPU would rasterise.
                if offset < SKIRT_SIDE_MARGIN {
                    ranges.push(strips[0]);
                }
                if offset > -SKIRT_SIDE_MARGIN {
                    ranges.push(strips[1]);
                }
            }
        }
        ranges.retain(|range| range.index_count > 0);
        ranges
    }
}

/// How close to a skirt's plane, in world units, the camera draws both of its strips.
const SKIRT_SIDE_MARGIN: f32 = 1e-3;

/// One strip of the skirt hanging `depth` below `edge` (its samples in increasing order), cut at
/// the water: `side` 0 or 1 picks the strip's winding, one facing each side of the edge's plane.
/// The triangles are those of the course engine's two-sided skirt, in its order, each with its
/// own copy of the edge's vertices.
fn skirt_strip(edge: &[[f32; 3]], side: usize, depth: f32) -> Block {
    let mut block = Block::default();
    block.positions.extend_from_slice(edge);
    for pair in 0..edge.len().saturating_sub(1) {
        let (p, q) = (pair as u32, pair as u32 + 1);
        // Nothing to hide where the edge is under water.
        if block.height(p) < 0.0 && block.height(q) < 0.0 {
            continue;
        }
        let mut below = |v: u32| {
            let [x, y, z] = block.positions[v as usize];
            block.positions.push([x, y - depth, z]);
            block.positions.len() as u32 - 1
        };
        let (p_low, q_low) = (below(p), below(q));
        let triangles =
            if side == 0 { [[p, q, q_low], [p, q_low, p_low]] } else { [[q, p, p_low], [q, p_low, q_low]] };
        for triangle in triangles {
            block.add(triangle);
        }
    }
    block
}

/// The samples of the span `first..=last` at `stride`, always including `last`.
fn samples((first, last): (u32, u32), stride: u32) -> Vec<u32> {
    let mut list: Vec<u32> = (first..last).step_by(stride as usize).collect();
    list.push(last);
    list
}

/// The error of each level of the chunk spanning `rows` x `columns`: the largest vertical distance
/// between the visible surfaces (heights below the water count as the water's 0) of the level and
/// of the full resolution, made non-decreasing from level to level. Levels go up to the stride that
/// spans the whole chunk.
fn level_errors(field: &Heightfield, rows: (u32, u32), columns: (u32, u32)) -> Vec<f32> {
    let span = (rows.1 - rows.0).max(columns.1 - columns.0).max(1);
    let level_count = (span.next_power_of_two().trailing_zeros() + 1) as usize;
    let visible = |r: u32, c: u32| field.height(r, c).max(0.0);
    let mut errors = Vec::with_capacity(level_count);
    let mut worst = 0.0f32;
    for level in 0..level_count {
        let stride = 1u32 << level;
        let (row_samples, column_samples) = (samples(rows, stride), samples(columns, stride));
        for pair in row_samples.windows(2) {
            for step in column_samples.windows(2) {
                let (ra, rb, ca, cb) = (pair[0], pair[1], step[0], step[1]);
                let [ha, hb, hc, hd] =
                    [(ra, ca), (rb, ca), (ra, cb), (rb, cb)].map(|(r, c)| field.height(r, c));
                for r in ra..=rb {
                    for c in ca..=cb {
                        let fz = (r - ra) as f32 / (rb - ra) as f32;
                        let fx = (c - ca) as f32 / (cb - ca) as f32;
                        let coarse = cell_surface([ha, hb, hc, hd], fx, fz);
                        worst = worst.max((coarse.max(0.0) - visible(r, c)).abs());
                    }
                }
            }
        }
        errors.push(worst);
    }
    errors
}

/// One chunk level's vertices and indices under construction. Triangles are cut along y = 0,
/// each crossing point shared by the triangles of its edge.
#[derive(Default)]
struct Block {
    positions: Vec<[f32; 3]>,
    /// Crossing vertex of each cut edge, keyed by its endpoints (smaller index first).
    crossings: HashMap<(u32, u32), u32>,
    indices: Vec<u32>,
}

impl Block {
    fn height(&self, vertex: u32) -> f32 {
        self.positions[vertex as usize][1]
    }

    /// Adds the part of `triangle` at or above the water.
    fn add(&mut self, triangle: [u32; 3]) {
        let above = triangle.map(|v| self.height(v) >= 0.0);
        if above.iter().all(|&a| a) {
            self.indices.extend(triangle);
            return;
        }
        if !above.iter().any(|&a| a) {
            return;
        }
        // Sutherland-Hodgman against one plane: keep the vertices above, insert the crossings,
        // in the triangle's own order (so the winding is kept). Gives 3 or 4 vertices.
        let mut polygon = Vec::with_capacity(4);
        for i in 0..3 {
            let (p, q) = (triangle[i], triangle[(i + 1) % 3]);
            if above[i] {
                polygon.push(p);
            }
            if above[i] != above[(i + 1) % 3] {
                polygon.push(self.crossing(p, q));
            }
        }
        for k in 1..polygon.len() - 1 {
            self.indices.extend([polygon[0], polygon[k], polygon[k + 1]]);
        }
    }

    /// The vertex where edge (p, q) crosses y = 0 (one above, one below).
    fn crossing(&mut self, p: u32, q: u32) -> u32 {
        let key = (p.min(q), p.max(q));
        if let Some(&vertex) = self.crossings.get(&key) {
            return vertex;
        }
        // Interpolate from the lower-indexed end so both triangles of the edge agree exactly.
        let (from, to) = (self.positions[key.0 as usize], self.positions[key.1 as usize]);
        let t = from[1] / (from[1] - to[1]);
        let vertex = self.positions.len() as u32;
        self.positions.push([from[0] + (to[0] - from[0]) * t, 0.0, from[2] + (to[2] - from[2]) * t]);
        self.crossings.insert(key, vertex);
        vertex
    }
}

#[cfg(test)]
mod tests {
    use proptest::strategy::Strategy;

    use super::*;
    use crate::camera::{CameraPose, Lens};
    use crate::config::SceneConfig;
    use crate::world::Heightmap;

    fn field(columns: u32, rows: u32, levels: Vec<f32>) -> Heightfield {
        let map = Heightmap::new(columns, rows, levels).expect("valid");
        Heightfield::new(&map, &SceneConfig::default())
    }

    /// Area of triangles projected on the water plane (summed in f64).
    fn plan_area(triangles: &[[Vec3; 3]]) -> f32 {
        triangles
            .iter()
            .map(|&[a, b, c]| {
                let flat = |v: Vec3| glam::DVec3::new(f64::from(v.x), 0.0, f64::from(v.z));
                (flat(b) - flat(a)).cross(flat(c) - flat(a)).length() / 2.0
            })
            .sum::<f64>() as f32
    }

    #[test]
    fn full_resolution_land_is_two_upward_triangles_per_cell() {
        for (columns, rows) in [(2, 2), (3, 7), (16, 5), (70, 40)] {
            // Levels 100..=255: all at or above the water.
            let levels = (0..columns * rows).map(|i| 100.0 + (i * 37 % 156) as f32).collect();
            let f = field(columns, rows, levels);
            let mesh = TerrainMesh::new(&f);
            assert_eq!(mesh.triangle_count(0), 2 * ((columns - 1) * (rows - 1)) as usize);
            let surface = mesh.surface_triangles(0);
            for [a, b, c] in &surface {
                assert!((*b - *a).cross(*c - *a).y > 0.0, "triangle faces down");
            }
            let extent = f.extent() - f.cell_size();
            assert!((plan_area(&surface) - extent.x * extent.y).abs() < 1e-3);
        }
    }

    #[test]
    fn every_level_covers_the_whole_land() {
        let levels = (0..70 * 40).map(|i| 100.0 + (i * 37 % 156) as f32).collect();
        let f = field(70, 40, levels);
        let mesh = TerrainMesh::new(&f);
        let extent = f.extent() - f.cell_size();
        for level in 0..6 {
            let surface = mesh.surface_triangles(level);
            assert!((plan_area(&surface) - extent.x * extent.y).abs() < 1e-3, "level {level}");
            if level > 0 {
                assert!(mesh.triangle_count(level) < mesh.triangle_count(level - 1));
            }
        }
    }

    #[test]
    fn chunks_split_the_grid() {
        let f = field(70, 40, vec![150.0; 70 * 40]);
        let mesh = TerrainMesh::new(&f);
        // 69 x 39 cells: 3 x 2 chunks of up to 32 cells.
        assert_eq!(mesh.chunks.len(), 6);
        assert_eq!(mesh.chunks[0].levels.len(), 6, "strides 1 to 32");
        assert_eq!(mesh.chunks[5].levels.len(), 4, "a 5 x 7-cell chunk: strides 1 to 8");
        // Blocks follow one another without gaps or overlaps, and index only their own vertices.
        let ranges: Vec<&DrawRange> =
            mesh.chunks.iter().flat_map(|c| &c.levels).flat_map(ChunkLevel::ranges).collect();
        let (mut next_vertex, mut next_index) = (0, 0);
        for (i, range) in ranges.iter().enumerate() {
            assert_eq!((range.base_vertex, range.first_index), (next_vertex, next_index));
            let end = ranges.get(i + 1).map_or(mesh.positions.len() as u32, |r| r.base_vertex);
            let indices =
                &mesh.indices[range.first_index as usize..(range.first_index + range.index_count) as usize];
            assert!(indices.iter().all(|&v| range.base_vertex + u32::from(v) < end));
            next_vertex = end;
            next_index += range.index_count;
        }
        assert_eq!(next_index as usize, mesh.indices.len());
    }

    #[test]
    fn planes_have_no_error_and_bumps_do() {
        // A tilted plane is exact at every level.
        let ramp = field(33, 33, (0..33 * 33).map(|i| 110.0 + (i % 33) as f32 * 3.0).collect());
        let mesh = TerrainMesh::new(&ramp);
        assert!(mesh.chunks[0].levels.iter().all(|l| l.error < 1e-4));
        // A single raised sample: exact at level 0, off by its height when skipped.
        let mut levels = vec![150.0; 33 * 33];
        levels[16 * 33 + 15] = 250.0;
        let bump = field(33, 33, levels);
        let mesh = TerrainMesh::new(&bump);
        let errors: Vec<f32> = mesh.chunks[0].levels.iter().map(|l| l.error).collect();
        assert_eq!(errors[0], 0.0);
        assert!((errors[1] - 1.5).abs() < 1e-4, "{errors:?}");
        assert!(errors.windows(2).all(|w| w[0] <= w[1]), "{errors:?}");
    }

    #[test]
    fn nothing_under_water_is_kept() {
        let mesh = TerrainMesh::new(&field(4, 4, vec![20.0; 16]));
        assert!(mesh.indices.is_empty());
    }

    #[test]
    fn the_coast_is_cut_exactly_at_the_waterline() {
        // A ramp along x: levels 40, 80, ..., so heights -0.9, -0.3, 0.3, 0.9, 1.5 (y = 0 halfway
        // between columns 1 and 2).
        let levels = (0..5 * 3).map(|i| 40.0 + 40.0 * (i % 5) as f32).collect();
        let f = field(5, 3, levels);
        let mesh = TerrainMesh::new(&f);
        let surface = mesh.surface_triangles(0);
        for [a, b, c] in &surface {
            assert!(a.y >= 0.0 && b.y >= 0.0 && c.y >= 0.0);
            assert!((*b - *a).cross(*c - *a).y > 0.0, "winding kept");
        }
        // Kept: from the waterline (x halfway between columns 1 and 2) to the last column,
        // i.e. 2.5 cells wide, over 2 cells of depth.
        let cell = f.cell_size();
        let expected = 2.5 * cell * 2.0 * cell;
        assert!((plan_area(&surface) - expected).abs() < 1e-4, "{}", plan_area(&surface));
        // The crossing points sit exactly on the waterline between columns 1 and 2.
        let x = (f.point(0, 1).x + f.point(0, 2).x) / 2.0;
        let waterline: Vec<Vec3> = surface.iter().flatten().copied().filter(|v| v.y == 0.0).collect();
        assert!(!waterline.is_empty());
        for v in waterline {
            let on_row = (0..3).any(|r| (v.z - f.point(r, 0).z).abs() < 1e-5);
            if on_row {
                assert!((v.x - x).abs() < 1e-5, "{v:?}");
            }
        }
    }

    #[test]
    fn skirts_hang_below_the_chunk_edges() {
        let f = field(40, 40, vec![150.0; 1600]);
        let mesh = TerrainMesh::new(&f);
        let chunk = &mesh.chunks[0];
        let level = chunk.levels[0];
        let top = f.height(0, 0);
        for (edge, strips) in level.skirts.iter().enumerate() {
            let [toward_negative, toward_positive] = strips.map(|strip| mesh.triangles(&strip));
            assert!(!toward_negative.is_empty() && toward_negative.len() == toward_positive.len());
            for (triangles, sign) in [(&toward_negative, -1.0), (&toward_positive, 1.0)] {
                assert!(triangles.iter().flatten().all(|v| v.y <= top + 1e-6 && v.y >= 0.0));
                assert!(triangles.iter().flatten().any(|v| v.y < top));
                // Vertical, in the edge's plane, facing the side the strip is filed under.
                assert!(plan_area(triangles) < 1e-6);
                let axis = if edge < 2 { 2 } else { 0 };
                for [a, b, c] in triangles {
                    assert!((a[axis] - chunk.edge_planes[edge]).abs() < 1e-6);
                    assert!((b - a).cross(c - a)[axis] * sign > 0.0, "edge {edge} faces the wrong way");
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn any_heightmap_gives_a_valid_mesh(
            (columns, rows, levels) in (2u32..40, 2u32..40).prop_flat_map(|(c, r)| {
                (proptest::strategy::Just(c), proptest::strategy::Just(r),
                 proptest::collection::vec(0.0f32..=255.0, (c * r) as usize))
            })
        ) {
            let f = field(columns, rows, levels);
            let mesh = TerrainMesh::new(&f);
            for level in mesh.chunks.iter().flat_map(|c| &c.levels) {
                for range in level.ranges() {
                    for [a, b, c] in mesh.triangles(range) {
                        proptest::prop_assert!(a.y >= 0.0 && b.y >= 0.0 && c.y >= 0.0, "below the water");
                    }
                }
                for [a, b, c] in mesh.triangles(&level.surface) {
                    proptest::prop_assert!((b - a).cross(c - a).y >= -1e-6, "a surface triangle faces down");
                }
            }
            // The full-resolution surface never covers more than the grid.
            let extent = f.extent() - f.cell_size();
            proptest::prop_assert!(plan_area(&mesh.surface_triangles(0)) <= extent.x * extent.y * (1.0 + 1e-4));
        }
    }

    fn view(mesh_mirrored: bool, pose: CameraPose) -> LodView {
        let lens = Lens { field_of_view_degrees: 45.0, near: 0.1, far: 500.0 };
        let view_projection = lens.projection(16.0 / 9.0) * pose.view_matrix();
        LodView {
            eye: pose.position,
            frustum: crate::camera::Frustum::from_view_projection(view_projection),
            view_projection,
            pixels_per_unit: 720.0 / (2.0 * (22.5f32).to_radians().tan()),
            max_error_pixels: 1.0,
            mirrored: mesh_mirrored,
            near_reach: 0.2,
        }
    }

    #[test]
    fn distant_chunks_are_coarser_and_hidden_ones_left_out() {
        // Gentle hills: coarse levels are good enough far away.
        let levels = (0..257 * 257)
            .map(|i| {
                let (x, z) = ((i % 257) as f32, (i / 257) as f32);
                150.0 + 40.0 * (x / 20.0).sin() * (z / 15.0).cos()
            })
            .collect();
        let mesh = TerrainMesh::new(&field(257, 257, levels));
        // The chunk and level a range belongs to.
        let owner = |range: &DrawRange| {
            mesh.chunks
                .iter()
                .enumerate()
                .flat_map(|(c, chunk)| chunk.levels.iter().enumerate().map(move |(l, level)| (c, l, level)))
                .find(|(_, _, level)| level.ranges().any(|r| r == range))
                .map(|(c, l, _)| (c, l))
                .expect("a chunk level")
        };
        // From above the middle looking at the horizon toward -z: the near chunks are fine,
        // the far ones coarse, and the ones behind are culled.
        let pose = CameraPose::new(Vec3::new(0.0, 2.5, 0.0), 0.0, -10.0);
        let v = view(false, pose);
        let chosen = mesh.select(&v);
        let surfaces: Vec<&DrawRange> =
            chosen.iter().filter(|r| mesh.chunks[owner(r).0].levels[owner(r).1].surface == **r).collect();
        assert!(surfaces.len() < mesh.chunks.len(), "nothing was culled");
        let levels: Vec<usize> = surfaces.iter().map(|r| owner(r).1).collect();
        assert!(levels.contains(&0) && levels.iter().any(|&l| l > 0), "{levels:?}");
        // Every choice keeps its error within a pixel.
        for range in &chosen {
            let (c, l) = owner(range);
            let chunk = &mesh.chunks[c];
            let distance = (v.eye.clamp(chunk.min, chunk.max) - v.eye).length();
            assert!(chunk.levels[l].error * v.pixels_per_unit / distance <= 1.0 + 1e-4 || l == 0);
        }
        // Nearest first, each chunk's ranges together.
        let centre_distance = |range: &DrawRange| {
            let chunk = &mesh.chunks[owner(range).0];
            ((chunk.min + chunk.max) * 0.5 - v.eye).length()
        };
        assert!(chosen.windows(2).all(|w| centre_distance(&w[0]) <= centre_distance(&w[1])));
        // Far above, everything fits in few triangles.
        let high = CameraPose::new(Vec3::new(0.0, 150.0, 0.0), 0.0, -89.0);
        let coarse: u32 = mesh.select(&view(false, high)).iter().map(|r| r.index_count).sum();
        let fine: u32 = chosen.iter().map(|r| r.index_count).sum();
        assert!(coarse < fine, "{coarse} vs {fine}");
    }

    #[test]
    fn only_the_skirt_strips_facing_the_camera_are_drawn() {
        let mesh = TerrainMesh::new(&field(97, 97, vec![180.0; 97 * 97]));
        for (pose, mirrored) in [
            (CameraPose::new(Vec3::new(-3.0, 4.0, 2.0), 30.0, -30.0), false),
            (CameraPose::new(Vec3::new(1.0, 6.0, -2.0), 200.0, -60.0), true),
        ] {
            let chosen = mesh.select(&view(mirrored, pose));
            for chunk in &mesh.chunks {
                let level = chunk.levels.iter().find(|l| chosen.contains(&l.surface));
                let Some(level) = level else { continue };
                for (edge, strips) in level.skirts.iter().enumerate() {
                    let eye = if edge < 2 { pose.position.z } else { pose.position.x };
                    // The strip facing the camera is drawn, the other (a back face) is not.
                    let facing = usize::from(eye > chunk.edge_planes[edge]);
                    assert!(chosen.contains(&strips[facing]), "edge {edge}");
                    assert!(!chosen.contains(&strips[1 - facing]), "edge {edge}");
                }
            }
        }
    }

    #[test]
    fn the_mirrored_pass_tests_mirrored_chunks() {
        let mesh = TerrainMesh::new(&field(33, 33, vec![250.0; 33 * 33]));
        // High above the land looking straight up: the land is behind, its mirror image further.
        let up = CameraPose::new(Vec3::new(0.0, 5.0, 0.0), 0.0, 89.0);
        assert!(mesh.select(&view(false, up)).is_empty());
        assert!(mesh.select(&view(true, up)).is_empty());
        // Looking down, both the land and its mirror image are ahead.
        let down = CameraPose::new(Vec3::new(0.0, 5.0, 0.0), 0.0, -89.0);
        // One chunk: its surface and one strip of each of its four skirts.
        assert_eq!(mesh.select(&view(false, down)).len(), 5);
        assert_eq!(mesh.select(&view(true, down)).len(), 5);
    }
}
