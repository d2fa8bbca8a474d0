//! The level-of-detail tree of a heightmap drawn as a grid on the GPU: square nodes of
//! [`PATCH_CELLS`] x [`PATCH_CELLS`] cells at strides 1, 2, 4... (a node at level k spans
//! `PATCH_CELLS * 2^k` cells), each with the range of its heights and a bound on how far its
//! patch strays vertically from the full-resolution surface.
//!
//! Every frame [`TerrainTree::select`] walks the tree from its root and keeps the coarsest nodes
//! whose error stays within a few pixels on screen: about two thousand patches cover a map of
//! 8193 x 8193 samples. The GPU draws them all with one instanced draw of a single patch mesh,
//! reading heights from a texture, so the map's geometry costs no memory beyond its heights.
//! Skirts hide the cracks between neighbours at different levels: they hang only under the edges
//! where the neighbour drawn has another stride, as deep as the errors on both sides.
//!
//! The tree holds 12 bytes per node: about 1 byte per height sample.

use std::collections::HashMap;

use glam::Vec3;
use rayon::prelude::*;

use super::Heightmap;
use super::heightfield::cell_surface;
use crate::camera::Frustum;
use crate::config::SceneConfig;

/// Cells along a side of a patch: a patch has `(PATCH_CELLS + 1)^2` vertices.
///
/// A patch is drawn at the level its nearest, roughest part needs, so smaller patches follow the
/// view more closely and draw fewer triangles for the same error on screen. At the course
/// island's start view, 4 cells draw 23,856 triangles of land where 8 drew 34,080 and 16 drew
/// 52,832: lavapipe's frames are bound by their triangles (see docs/terrain-speed-log.md), and patches
/// of 4 cells drew the modern look's frames fastest on every map measured, the 8193 map's
/// included. The price is the tree's size (a node per 16 cells: 1 byte a height sample, where
/// patches of 16 cells took 0.06) and about 1 ms to choose the patches of an 8193 x 8193 map for
/// a pass.
pub const PATCH_CELLS: u32 = 4;

/// The smallest size, in pixels, a cell may have on screen before refining stops even if the
/// error asks for more: finer detail is left to the per-pixel normals, and the GPU is spared
/// triangles smaller than the pixels they cover.
pub const MIN_CELL_PIXELS: f32 = 4.0;

/// The most sample visits spent on exact node errors (see [`TerrainTree::new`]).
const EXACT_ERROR_BUDGET: usize = 48_000_000;

/// One patch to draw: the GPU instance data (16 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Patch {
    /// Column of the patch's first sample.
    pub column: u32,
    /// Row of the patch's first sample.
    pub row: u32,
    /// Samples between neighbouring vertices: `2^level`.
    pub stride: u32,
    /// How far, in world units, the skirts hang below the patch's edges.
    pub skirt_depth: f32,
}

/// What the selection needs to know about the view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeView {
    /// The camera's position (for the distances that set the level of detail).
    pub eye: Vec3,
    /// What must be drawn (of the mirrored world, when `mirrored`).
    pub frustum: Frustum,
    /// Pixels covered by one world unit seen face-on at a distance of one unit (for a
    /// perspective view), or at any distance when `orthographic`.
    pub pixels_per_unit: f32,
    /// Largest error allowed on screen, in pixels.
    pub max_error_pixels: f32,
    /// Whether this is a mirrored pass (boxes are tested mirrored in y = 0).
    pub mirrored: bool,
    /// An orthographic view (the sun's): the error allowed does not grow with distance.
    pub orthographic: bool,
}

/// The statistics of one level's nodes, row by row.
#[derive(Debug, Clone, Default)]
struct Level {
    nodes_x: u32,
    nodes_z: u32,
    /// Lowest and highest world height of each node's samples.
    low: Vec<f32>,
    high: Vec<f32>,
    /// Bound on the vertical distance between the node's patch and the full-resolution surface.
    error: Vec<f32>,
}

/// The tree of a heightmap placed in the world.
#[derive(Debug, Clone)]
pub struct TerrainTree {
    columns: u32,
    rows: u32,
    cell: f32,
    /// World x, z of sample (0, 0).
    origin: [f32; 2],
    /// Level 0 (stride 1) first, the root last.
    levels: Vec<Level>,
}

impl TerrainTree {
    /// Builds the tree of `heightmap` placed with `config` (in parallel; about a second for
    /// 8193 x 8193 samples on two cores). Node errors are exact for maps of up to about 2049
    /// samples a side, and bounded (each level's deviation from the next finer one, summed) for
    /// larger ones.
    pub fn new(heightmap: &Heightmap, config: &SceneConfig) -> Self {
        let (columns, rows) = (heightmap.columns(), heightmap.rows());
        let cell = super::Heightfield::cell_size_of(heightmap, config);
        let extent = [columns as f32 * cell, rows as f32 * cell];
        let origin = [0.5 * cell - extent[0] / 2.0, 0.5 * cell - extent[1] / 2.0];
        let height = |row: u32, column: u32| config.height_of_level(heightmap.level(row, column));
        let cells = (columns - 1).max(rows - 1);
        let level_count = (cells.div_ceil(PATCH_CELLS).next_power_of_two().trailing_zeros() + 1) as usize;
        // Exact errors visit every sample once per level; beyond this budget (maps larger than
        // about 2049 samples a side) a bound built level by level is used instead.
        let exact = columns as usize * rows as usize * level_count <= EXACT_ERROR_BUDGET;
        let mut levels: Vec<Level> = Vec::with_capacity(level_count);
        for k in 0..level_count {
            let span = PATCH_CELLS << k;
            let (nodes_x, nodes_z) = ((columns - 1).div_ceil(span), (rows - 1).div_ceil(span));
            let finer = levels.last();
            let stats: Vec<(f32, f32, f32)> = (0..nodes_x * nodes_z)
                .into_par_iter()
                .map(|index| {
                    let (i, j) = (index % nodes_x, index / nodes_x);
                    match finer {
                        None => leaf_range(&height, columns, rows, i * span, j * span),
                        Some(finer) => {
                            let children = [(0, 0), (1, 0), (0, 1), (1, 1)]
                                .map(|(di, dj)| (2 * i + di, 2 * j + dj))
                                .into_iter()
                                .filter(|&(ci, cj)| ci < finer.nodes_x && cj < finer.nodes_z)
                                .map(|(ci, cj)| (cj * finer.nodes_x + ci) as usize);
                            let (mut low, mut high, mut error) = (f32::MAX, f32::MIN, 0.0f32);
                            for child in children {
                                low = low.min(finer.low[child]);
                                high = high.max(finer.high[child]);
                                error = error.max(finer.error[child]);
                            }
                            let step = span / PATCH_CELLS;
                            let error = if exact {
                                exact_error(&height, columns, rows, i * span, j * span, step)
                            } else {
                                error + patch_deviation(&height, columns, rows, i * span, j * span, step)
                            };
                            (low, high, error)
                        }
                    }
                })
                .collect();
            levels.push(Level {
                nodes_x,
                nodes_z,
                low: stats.iter().map(|s| s.0).collect(),
                high: stats.iter().map(|s| s.1).collect(),
                error: stats.iter().map(|s| s.2).collect(),
            });
        }
        Self { columns, rows, cell, origin, levels }
    }

    /// Number of levels (the root's level is one less).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Bytes the tree takes in memory.
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|level| 3 * size_of::<f32>() * level.low.len()).sum()
    }

    /// The error bound of node (`i`, `j`) of `level`, in world units.
    pub fn error(&self, level: usize, i: u32, j: u32) -> f32 {
        let l = &self.levels[level];
        l.error[(j * l.nodes_x + i) as usize]
    }

    /// The box around node (`i`, `j`) of `level` (its surface, without skirts).
    fn node_box(&self, level: usize, i: u32, j: u32) -> (Vec3, Vec3) {
        let l = &self.levels[level];
        let index = (j * l.nodes_x + i) as usize;
        let span = PATCH_CELLS << level;
        let first = [i * span, j * span];
        let last = [(first[0] + span).min(self.columns - 1), (first[1] + span).min(self.rows - 1)];
        let x = |column: u32| self.origin[0] + column as f32 * self.cell;
        let z = |row: u32| self.origin[1] + row as f32 * self.cell;
        (Vec3::new(x(first[0]), l.low[index], z(first[1])), Vec3::new(x(last[0]), l.high[index], z(last[1])))
    }

    /// The patches to draw for `view`: the coarsest nodes whose error stays within
    /// `view.max_error_pixels` on screen (or whose cells would fall below [`MIN_CELL_PIXELS`]),
    /// leaving out those out of view or entirely under water. They go into `out` (cleared first)
    /// grouped by which of their edges need skirts ([`SKIRT_MASKS`] groups, by mask: bit 0 the
    /// first row, 1 the last row, 2 the first column, 3 the last column), nearest first in each
    /// group; returns how many each group has.
    pub fn select(&self, view: &TreeView, out: &mut Vec<Patch>) -> [u32; SKIRT_MASKS] {
        out.clear();
        let mut chosen: Vec<Chosen> = Vec::new();
        let root = self.levels.len() - 1;
        let root_level = &self.levels[root];
        for j in 0..root_level.nodes_z {
            for i in 0..root_level.nodes_x {
                self.visit(view, root, i, j, &mut chosen);
            }
        }
        self.set_skirts(&mut chosen);
        chosen.sort_by(|a, b| a.skirts.cmp(&b.skirts).then(a.order.total_cmp(&b.order)));
        let mut counts = [0u32; SKIRT_MASKS];
        for c in &chosen {
            counts[c.skirts as usize] += 1;
        }
        out.extend(chosen.iter().map(|c| c.patch));
        counts
    }

    fn visit(&self, view: &TreeView, level: usize, i: u32, j: u32, chosen: &mut Vec<Chosen>) {
        let (min, max) = self.node_box(level, i, j);
        // Land entirely under the water is never drawn: the water's surface covers it.
        if max.y < 0.0 {
            return;
        }
        let (min, max) = if view.mirrored {
            (Vec3::new(min.x, -max.y, min.z), Vec3::new(max.x, -min.y, max.z))
        } else {
            (min, max)
        };
        // The skirts hang below the box: test it with room for them.
        let reach = self.cell * (1u32 << level) as f32;
        if !view.frustum.intersects_box(min - Vec3::Y * reach, max + Vec3::Y * reach) {
            return;
        }
        let distance =
            if view.orthographic { 1.0 } else { (view.eye.clamp(min, max) - view.eye).length().max(1e-3) };
        let pixels = view.pixels_per_unit / distance;
        let error = self.error(level, i, j);
        let stride = 1u32 << level;
        let fine_enough = error * pixels <= view.max_error_pixels;
        let cells_too_small = 0.5 * stride as f32 * self.cell * pixels < MIN_CELL_PIXELS;
        if level == 0 || fine_enough || cells_too_small {
            let span = PATCH_CELLS << level;
            chosen.push(Chosen {
                patch: Patch { column: i * span, row: j * span, stride, skirt_depth: 0.0 },
                level,
                error,
                skirts: 0,
                order: ((min + max) * 0.5 - view.eye).length_squared(),
            });
            return;
        }
        let finer = &self.levels[level - 1];
        for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (ci, cj) = (2 * i + di, 2 * j + dj);
            if ci < finer.nodes_x && cj < finer.nodes_z {
                self.visit(view, level - 1, ci, cj, chosen);
            }
        }
    }

    /// Decides which edges of each chosen patch need a skirt (those along a drawn neighbour of
    /// another stride: where they meet, the two surfaces differ) and how deep: the crack is at
    /// most the patch's error plus its neighbour's, so the skirt hangs that deep (the deepest
    /// neighbour along the whole edge), plus half a cell. The neighbours are found in the tree
    /// (the node across the edge, or the drawn node above it, or the drawn nodes below it along
    /// the edge), so the work grows with the patches chosen, not with the map.
    fn set_skirts(&self, chosen: &mut [Chosen]) {
        let drawn: HashMap<(usize, u32, u32), f32> = chosen.iter().map(|c| (c.node(), c.error)).collect();
        for c in chosen.iter_mut() {
            let (level, i, j) = c.node();
            let mut deepest = 0.0f32;
            for (edge, across) in EDGE_NEIGHBOURS.iter().enumerate() {
                let (Some(ni), Some(nj)) = (i.checked_add_signed(across.0), j.checked_add_signed(across.1))
                else {
                    continue;
                };
                if let Some(error) = self.other_stride_along(&drawn, (level, ni, nj), edge) {
                    c.skirts |= 1 << edge;
                    deepest = deepest.max(error);
                }
            }
            c.patch.skirt_depth = c.error + deepest + 0.5 * self.cell * c.patch.stride as f32;
        }
    }

    /// The largest error of the drawn nodes of another level than `node` along its side that
    /// faces a patch across `edge` (the patch's edge, [`EDGE_NEIGHBOURS`] order), `node` being
    /// that patch's neighbour at its own level; `None` when that side is drawn at the patch's
    /// level or not at all.
    fn other_stride_along(
        &self,
        drawn: &HashMap<(usize, u32, u32), f32>,
        node: (usize, u32, u32),
        edge: usize,
    ) -> Option<f32> {
        let (level, i, j) = node;
        let nodes = &self.levels[level];
        if i >= nodes.nodes_x || j >= nodes.nodes_z || drawn.contains_key(&node) {
            return None;
        }
        // A coarser node drawn over the neighbour covers the whole edge.
        if let Some(error) = (level + 1..self.levels.len())
            .find_map(|up| drawn.get(&(up, i >> (up - level), j >> (up - level))))
        {
            return Some(*error);
        }
        self.finer_along(drawn, node, edge)
    }

    /// The largest error of the drawn nodes below `node` on its side facing `edge`'s patch.
    fn finer_along(
        &self,
        drawn: &HashMap<(usize, u32, u32), f32>,
        (level, i, j): (usize, u32, u32),
        edge: usize,
    ) -> Option<f32> {
        if level == 0 {
            return None;
        }
        let finer = &self.levels[level - 1];
        // The two children on the side facing the patch: the neighbour lies before the patch's
        // first row or column (edges 0 and 2) or after its last one (edges 1 and 3).
        let facing = u32::from(edge.is_multiple_of(2));
        let children = if edge < 2 { [(0, facing), (1, facing)] } else { [(facing, 0), (facing, 1)] };
        children
            .into_iter()
            .map(|(di, dj)| (level - 1, 2 * i + di, 2 * j + dj))
            .filter(|&(_, ci, cj)| ci < finer.nodes_x && cj < finer.nodes_z)
            .filter_map(|child| drawn.get(&child).copied().or_else(|| self.finer_along(drawn, child, edge)))
            .reduce(f32::max)
    }
}

/// Across each edge of a patch ([`SKIRT_MASKS`] bit order: first row, last row, first column,
/// last column), the step to its neighbour at the same level.
const EDGE_NEIGHBOURS: [(i32, i32); 4] = [(0, -1), (0, 1), (-1, 0), (1, 0)];

/// Number of skirt masks: one bit for each of a patch's four edges.
pub const SKIRT_MASKS: usize = 16;

/// A node chosen for drawing.
struct Chosen {
    patch: Patch,
    level: usize,
    error: f32,
    /// The edges with skirts (see [`TerrainTree::select`]).
    skirts: u8,
    order: f32,
}

impl Chosen {
    /// The node: its level and position in the level.
    fn node(&self) -> (usize, u32, u32) {
        let span = PATCH_CELLS << self.level;
        (self.level, self.patch.column / span, self.patch.row / span)
    }
}

/// The lowest and highest height of the level-0 node whose first sample is (`column`, `row`), and
/// its error (0: it is the full resolution).
fn leaf_range(
    height: &impl Fn(u32, u32) -> f32,
    columns: u32,
    rows: u32,
    column: u32,
    row: u32,
) -> (f32, f32, f32) {
    let (mut low, mut high) = (f32::MAX, f32::MIN);
    for r in row..=(row + PATCH_CELLS).min(rows - 1) {
        for c in column..=(column + PATCH_CELLS).min(columns - 1) {
            let h = height(r, c);
            low = low.min(h);
            high = high.max(h);
        }
    }
    (low, high, 0.0)
}

/// The largest vertical distance between the visible surface (above the water) of the patch of
/// stride `step` whose first sample is (`column`, `row`) and that of the full resolution, over
/// every sample the patch covers.
fn exact_error(
    height: &impl Fn(u32, u32) -> f32,
    columns: u32,
    rows: u32,
    column: u32,
    row: u32,
    step: u32,
) -> f32 {
    let clamp_c = |c: u32| c.min(columns - 1);
    let clamp_r = |r: u32| r.min(rows - 1);
    let mut worst = 0.0f32;
    for a in 0..PATCH_CELLS {
        let (r0, r1) = (clamp_r(row + a * step), clamp_r(row + (a + 1) * step));
        if r0 == r1 {
            break;
        }
        for b in 0..PATCH_CELLS {
            let (c0, c1) = (clamp_c(column + b * step), clamp_c(column + (b + 1) * step));
            if c0 == c1 {
                break;
            }
            let [h00, h10, h01, h11] = [(r0, c0), (r1, c0), (r0, c1), (r1, c1)].map(|(r, c)| height(r, c));
            for r in r0..=r1 {
                let fz = (r - r0) as f32 / (r1 - r0) as f32;
                for c in c0..=c1 {
                    let fx = (c - c0) as f32 / (c1 - c0) as f32;
                    let coarse = cell_surface([h00, h10, h01, h11], fx, fz);
                    worst = worst.max((coarse.max(0.0) - height(r, c).max(0.0)).abs());
                }
            }
        }
    }
    worst
}

/// The largest vertical distance, at the vertices of the patch of stride `step / 2` (its
/// children's), between the surface of the patch of stride `step` whose first sample is
/// (`column`, `row`) and those vertices' heights. The coarse triangles split along the same
/// diagonal as the fine ones, so the fine surface refines the coarse one and the largest
/// difference between the two is at a fine vertex. Cells entirely under the water count for
/// nothing: what is under it is never seen (the water covers it, or it is discarded).
fn patch_deviation(
    height: &impl Fn(u32, u32) -> f32,
    columns: u32,
    rows: u32,
    column: u32,
    row: u32,
    step: u32,
) -> f32 {
    let half = step / 2;
    let clamp_c = |c: u32| c.min(columns - 1);
    let clamp_r = |r: u32| r.min(rows - 1);
    let mut worst = 0.0f32;
    for a in 0..PATCH_CELLS {
        let (r0, r1) = (clamp_r(row + a * step), clamp_r(row + (a + 1) * step));
        if r0 == r1 {
            break;
        }
        for b in 0..PATCH_CELLS {
            let (c0, c1) = (clamp_c(column + b * step), clamp_c(column + (b + 1) * step));
            if c0 == c1 {
                break;
            }
            let [h00, h10, h01, h11] = [(r0, c0), (r1, c0), (r0, c1), (r1, c1)].map(|(r, c)| height(r, c));
            let fine = |fr: u32, fc: u32| height(clamp_r(r0 + fr).min(r1), clamp_c(c0 + fc).min(c1));
            // Under the water both surfaces are hidden: a cell entirely below it (its corners and
            // its fine vertices, hence both surfaces across it) adds no visible error.
            let all_under = [h00, h10, h01, h11].iter().all(|&h| h <= 0.0)
                && [0, half, step].iter().all(|&fr| [0, half, step].iter().all(|&fc| fine(fr, fc) <= 0.0));
            if all_under {
                continue;
            }
            for fr in [0, half, step] {
                for fc in [0, half, step] {
                    let (r, c) = (clamp_r(r0 + fr).min(r1), clamp_c(c0 + fc).min(c1));
                    let fz = (r - r0) as f32 / (r1 - r0) as f32;
                    let fx = (c - c0) as f32 / (c1 - c0) as f32;
                    let coarse = cell_surface([h00, h10, h01, h11], fx, fz);
                    worst = worst.max((coarse - height(r, c)).abs());
                }
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{CameraPose, Lens};

    fn map(columns: u32, rows: u32, level: impl Fn(u32, u32) -> f32) -> Heightmap {
        let levels = (0..rows).flat_map(|r| (0..columns).map(move |c| (r, c))).map(|(r, c)| level(r, c));
        Heightmap::new(columns, rows, levels.collect()).expect("valid")
    }

    fn view(pose: CameraPose, error: f32) -> TreeView {
        let lens = Lens { field_of_view_degrees: 45.0, near: 0.1, far: 500.0 };
        TreeView {
            eye: pose.position,
            frustum: Frustum::from_view_projection(lens.projection(16.0 / 9.0) * pose.view_matrix()),
            pixels_per_unit: 720.0 / (2.0 * 22.5f32.to_radians().tan()),
            max_error_pixels: error,
            mirrored: false,
            orthographic: false,
        }
    }

    /// The full-resolution height under the patch surface of `patch` at sample (`r`, `c`).
    fn patch_height(m: &Heightmap, config: &SceneConfig, patch: &Patch, r: u32, c: u32) -> f32 {
        let h = |r: u32, c: u32| config.height_of_level(m.level(r.min(m.rows() - 1), c.min(m.columns() - 1)));
        let s = patch.stride;
        let (r0, c0) = (patch.row + (r - patch.row) / s * s, patch.column + (c - patch.column) / s * s);
        let (r1, c1) = ((r0 + s).min(m.rows() - 1), (c0 + s).min(m.columns() - 1));
        let fz = if r1 > r0 { (r - r0) as f32 / (r1 - r0) as f32 } else { 0.0 };
        let fx = if c1 > c0 { (c - c0) as f32 / (c1 - c0) as f32 } else { 0.0 };
        let [h00, h10, h01, h11] = [(r0, c0), (r1, c0), (r0, c1), (r1, c1)].map(|(r, c)| h(r, c));
        if fx + fz <= 1.0 {
            h00 + (h01 - h00) * fx + (h10 - h00) * fz
        } else {
            h11 + (h10 - h11) * (1.0 - fx) + (h01 - h11) * (1.0 - fz)
        }
    }

    #[test]
    fn levels_cover_the_map_up_to_one_root() {
        let config = SceneConfig::default();
        let tree = TerrainTree::new(&map(257, 200, |_, _| 150.0), &config);
        // 256 cells: 64 level-0 nodes across, then 32, 16, 8, 4, 2, 1.
        assert_eq!(tree.level_count(), 7);
        assert_eq!((tree.levels[0].nodes_x, tree.levels[0].nodes_z), (64, 50));
        assert_eq!((tree.levels[6].nodes_x, tree.levels[6].nodes_z), (1, 1));
        // A flat map has no error anywhere.
        assert!(tree.levels.iter().all(|l| l.error.iter().all(|&e| e == 0.0)));
    }

    #[test]
    fn errors_bound_the_true_deviation() {
        let config = SceneConfig::default();
        // Hills and a sea floor: the levels cross the water (level 100).
        let m = map(161, 129, |r, c| {
            100.0 + 60.0 * ((r as f32 * 0.07).sin() * (c as f32 * 0.05).cos()) + (r * c % 7) as f32
        });
        let tree = TerrainTree::new(&m, &config);
        for level in 0..tree.level_count() {
            let l = &tree.levels[level];
            let span = PATCH_CELLS << level;
            for j in 0..l.nodes_z {
                for i in 0..l.nodes_x {
                    let patch =
                        Patch { column: i * span, row: j * span, stride: 1 << level, skirt_depth: 0.0 };
                    let mut worst = 0.0f32;
                    for r in j * span..=((j + 1) * span).min(m.rows() - 1) {
                        for c in i * span..=((i + 1) * span).min(m.columns() - 1) {
                            // What shows is above the water.
                            let truth = config.height_of_level(m.level(r, c)).max(0.0);
                            let drawn = patch_height(&m, &config, &patch, r, c).max(0.0);
                            worst = worst.max((drawn - truth).abs());
                        }
                    }
                    let bound = tree.error(level, i, j);
                    assert!(worst <= bound + 1e-4, "level {level} node {i},{j}: {worst} > {bound}");
                }
            }
        }
    }

    #[test]
    fn exact_errors_are_within_the_bound() {
        let config = SceneConfig::default();
        let m = map(129, 129, |r, c| 100.0 + 60.0 * ((r as f32 * 0.11).sin() * (c as f32 * 0.07).cos()));
        let height = |r: u32, c: u32| config.height_of_level(m.level(r, c));
        let tree = TerrainTree::new(&m, &config);
        let mut bound = 0.0f32;
        for level in 1..tree.level_count() {
            let step = 1 << level;
            // The bound of the root's corner node, built level by level.
            bound += patch_deviation(&height, 129, 129, 0, 0, step);
            let exact = exact_error(&height, 129, 129, 0, 0, step);
            assert_eq!(tree.error(level, 0, 0), exact);
            assert!(exact <= bound + 1e-5, "level {level}: {exact} > {bound}");
        }
    }

    #[test]
    fn selection_tiles_the_visible_land_nearest_first() {
        let config = SceneConfig::default();
        // Hills everywhere above the water.
        let m = map(513, 513, |r, c| {
            let (r, c) = (r as f32, c as f32);
            170.0 + 30.0 * ((r / 40.0).sin() + (c / 55.0).cos()) + 6.0 * (r / 3.0).sin() * (c / 4.0).cos()
        });
        let tree = TerrainTree::new(&m, &config);
        // From high above, looking straight down: every sample is covered exactly once.
        let pose = CameraPose::new(Vec3::new(0.0, 60.0, 0.0), 0.0, -89.0);
        let mut patches = Vec::new();
        let groups = tree.select(&view(pose, 2.0), &mut patches);
        assert_eq!(groups.iter().sum::<u32>() as usize, patches.len());
        let mut covered = vec![0u8; 512 * 512];
        for p in &patches {
            let span = PATCH_CELLS * p.stride;
            for r in p.row..p.row + span {
                for c in p.column..p.column + span {
                    covered[(r * 512 + c) as usize] += 1;
                }
            }
            assert!(p.skirt_depth > 0.0);
        }
        assert!(covered.iter().all(|&n| n == 1), "cells covered twice or not at all");
        // Low over the land looking ahead: fine near, coarse far, nothing behind.
        let pose = CameraPose::new(Vec3::new(0.0, 2.0, 8.0), 0.0, -5.0);
        let v = view(pose, 2.0);
        let groups = tree.select(&v, &mut patches);
        // Nearest first within each group of skirts.
        let centre_distance = |p: &Patch| {
            let span = (PATCH_CELLS * p.stride) as f32 * tree.cell;
            let x = tree.origin[0] + p.column as f32 * tree.cell + span / 2.0;
            let z = tree.origin[1] + p.row as f32 * tree.cell + span / 2.0;
            Vec3::new(x - pose.position.x, 0.0, z - pose.position.z).length()
        };
        let mut start = 0;
        for count in groups {
            let group = &patches[start..start + count as usize];
            assert!(group.windows(2).all(|w| centre_distance(&w[0]) <= centre_distance(&w[1]) + 1.0));
            start += count as usize;
        }
        // Finer near the camera than far from it.
        let nearest = patches.iter().min_by(|a, b| centre_distance(a).total_cmp(&centre_distance(b)));
        let farthest = patches.iter().max_by(|a, b| centre_distance(a).total_cmp(&centre_distance(b)));
        let (Some(nearest), Some(farthest)) = (nearest, farthest) else { panic!("nothing chosen") };
        assert!(nearest.stride < farthest.stride, "{patches:?}");
        let centre = |p: &Patch| {
            let span = (PATCH_CELLS * p.stride) as f32 * tree.cell;
            Vec3::new(
                tree.origin[0] + p.column as f32 * tree.cell + span / 2.0,
                0.0,
                tree.origin[1] + p.row as f32 * tree.cell + span / 2.0,
            )
        };
        assert!(patches.iter().all(|p| centre(p).z < 8.0 + 2.0), "a patch behind the camera");
        // A larger error allows fewer patches.
        let mut coarse = Vec::new();
        tree.select(&view(pose, 8.0), &mut coarse);
        assert!(coarse.len() < patches.len(), "{} vs {}", coarse.len(), patches.len());
    }

    #[test]
    fn skirts_reach_the_neighbours_error() {
        let config = SceneConfig::default();
        let m = map(257, 257, |r, c| 150.0 + ((r * 31 + c * 17) % 23) as f32);
        let tree = TerrainTree::new(&m, &config);
        let pose = CameraPose::new(Vec3::new(-9.0, 1.0, 9.0), 45.0, -10.0);
        let mut patches = Vec::new();
        tree.select(&view(pose, 2.0), &mut patches);
        let error_of = |p: &Patch| {
            tree.error(
                p.stride.trailing_zeros() as usize,
                p.column / (PATCH_CELLS * p.stride),
                p.row / (PATCH_CELLS * p.stride),
            )
        };
        let largest = patches.iter().map(error_of).fold(0.0f32, f32::max);
        assert!(largest > 0.0);
        for p in &patches {
            assert!(p.skirt_depth >= error_of(p));
        }
        // Some patch's skirt is deeper than its own error: a coarser neighbour's error.
        assert!(
            patches.iter().any(|p| p.skirt_depth > error_of(p) + 0.5 * tree.cell * p.stride as f32 + 1e-6)
        );
        // Patches whose neighbours all share their stride have no skirts: the edges meet exactly.
        let flat = TerrainTree::new(&map(257, 257, |_, _| 150.0), &config);
        let groups =
            flat.select(&view(CameraPose::new(Vec3::new(0.0, 90.0, 0.0), 0.0, -89.0), 2.0), &mut patches);
        assert_eq!(groups[0] as usize, patches.len(), "{groups:?}");
    }

    #[test]
    fn skirts_are_those_a_raster_of_the_drawn_patches_finds() {
        let config = SceneConfig::default();
        let m = map(257, 257, |r, c| {
            let (x, z) = (r as f32, c as f32);
            150.0 + 40.0 * (x / 19.0).sin() * (z / 23.0).cos() + ((r * 31 + c * 17) % 23) as f32
        });
        let tree = TerrainTree::new(&m, &config);
        let (width, depth) = (tree.levels[0].nodes_x as usize, tree.levels[0].nodes_z as usize);
        let mut with_skirts = 0;
        for pose in [
            CameraPose::new(Vec3::new(-9.0, 1.0, 9.0), 45.0, -10.0),
            CameraPose::new(Vec3::new(0.0, 3.0, 12.0), 0.0, -15.0),
            CameraPose::new(Vec3::new(2.0, 25.0, 2.0), 30.0, -80.0),
        ] {
            let mut patches = Vec::new();
            let groups = tree.select(&view(pose, 2.0), &mut patches);
            let masks =
                groups.iter().enumerate().flat_map(|(mask, &n)| std::iter::repeat_n(mask, n as usize));
            // The stride (0: nothing) and error of the patch drawn over each level-0 node.
            let square = |p: &Patch| {
                let level = p.stride.trailing_zeros() as usize;
                let span = PATCH_CELLS * p.stride;
                let error = tree.error(level, p.column / span, p.row / span);
                ((p.column / PATCH_CELLS) as isize, (p.row / PATCH_CELLS) as isize, p.stride as isize, error)
            };
            let mut raster = vec![(0u32, 0.0f32); width * depth];
            for p in &patches {
                let (i0, j0, n, error) = square(p);
                for j in j0..(j0 + n).min(depth as isize) {
                    for i in i0..(i0 + n).min(width as isize) {
                        raster[j as usize * width + i as usize] = (p.stride, error);
                    }
                }
            }
            let at = |i: isize, j: isize| {
                let inside = (0..width as isize).contains(&i) && (0..depth as isize).contains(&j);
                if inside { raster[j as usize * width + i as usize] } else { (0, 0.0) }
            };
            for (p, mask) in patches.iter().zip(masks) {
                let (i0, j0, n, error) = square(p);
                let outside: [&dyn Fn(isize) -> (isize, isize); 4] =
                    [&|k| (i0 + k, j0 - 1), &|k| (i0 + k, j0 + n), &|k| (i0 - 1, j0 + k), &|k| {
                        (i0 + n, j0 + k)
                    }];
                let (mut expected, mut deepest) = (0, 0.0f32);
                for (edge, cell) in outside.iter().enumerate() {
                    for (other, other_error) in (0..n).map(|k| at(cell(k).0, cell(k).1)) {
                        if other != 0 && other != p.stride {
                            expected |= 1 << edge;
                            deepest = deepest.max(other_error);
                        }
                    }
                }
                assert_eq!(mask, expected, "{p:?}");
                assert_eq!(p.skirt_depth, error + deepest + 0.5 * tree.cell * p.stride as f32, "{p:?}");
                with_skirts += usize::from(mask != 0);
            }
        }
        assert!(with_skirts > 10, "only {with_skirts} patches with skirts");
    }

    #[test]
    fn land_under_water_is_left_out() {
        let config = SceneConfig::default();
        let tree = TerrainTree::new(&map(129, 129, |_, c| if c < 64 { 20.0 } else { 200.0 }), &config);
        let pose = CameraPose::new(Vec3::new(0.0, 40.0, 0.0), 0.0, -89.0);
        let mut patches = Vec::new();
        tree.select(&view(pose, 2.0), &mut patches);
        assert!(!patches.is_empty());
        // Every patch reaches the land (from column 64 on).
        assert!(patches.iter().all(|p| p.column + PATCH_CELLS * p.stride >= 64), "{patches:?}");
    }
}
