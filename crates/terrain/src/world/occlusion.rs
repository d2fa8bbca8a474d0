//! Which chunks of the land's mirror image the land itself hides.
//!
//! The mirror image lies below the water (y <= 0) and is seen only through it. Take a point `q`
//! on the ray from the eye to a mirrored point, at height `c >= 0`. Where the land drawn in the
//! same frame stands higher than `c` at `q`, the ray passed under the land's surface between the
//! eye (above it) and `q`: it met the land on its way, whose fragment is nearer, and the mirrored
//! one fails the depth test. A mirrored chunk all of whose rays pass under the land somewhere
//! draws nothing, and [`WaterOcclusion::hides`] says so without changing a pixel.
//!
//! The land is tracked in blocks of [`BLOCK_CELLS`] x [`BLOCK_CELLS`] cells, each with its floor
//! at a chunk's level of detail: the lowest corner of that level's cells overlapping it (its
//! triangles lie above their corners' lowest height).

use glam::{Mat4, Vec2, Vec3};

use super::chunk::Chunk;
pub use super::chunk::{BLOCK_CELLS, BlockFloors, BlockGrid, CHUNK_BLOCKS, block_floors};

/// Heights relative to the eye's at which rays are tested, as fractions of the eye's height.
const TEST_HEIGHTS: usize = 32;

/// Tiles across and down the screen over which the land's depth is bounded.
const TILES: [usize; 2] = [128, 72];

/// How much nearer (relatively) than a mirrored chunk the land's bound must be to hide it, so
/// that the GPU's rounding of depths can never turn the test around.
const DEPTH_MARGIN: f32 = 1e-3;

/// The land as one frame draws it, as a bound on its depth over tiles of the screen, ready to
/// say which mirrored chunks it hides.
#[derive(Debug, Clone)]
pub struct WaterOcclusion {
    view_projection: Mat4,
    eye: Vec3,
    floors: FloorTables,
    /// The rays from the eye through the corners of the tiles, row by row from the top.
    rays: Vec<Vec3>,
    /// For each tile (row by row from the top), once asked for, a clip-space w (the depth along
    /// the view) that the land seen through any pixel of the tile is nearer than; infinity where
    /// unknown.
    land_before: Vec<Option<f32>>,
}

impl WaterOcclusion {
    /// The occlusion of the land drawn at `levels` (pairs of a chunk's index in `chunks` and the
    /// level drawn), seen from `eye` through `view_projection`; `near_reach` is the largest
    /// distance from the eye of a point the near plane clips away. `None` where the argument
    /// above does not hold: the eye at or under the water, inside or near the land (the near
    /// plane could cut a hole in it), or outside a map whose border stands above the water.
    pub fn new(
        grid: &BlockGrid,
        chunks: &[Chunk],
        levels: impl IntoIterator<Item = (usize, usize)>,
        (eye, view_projection): (Vec3, Mat4),
        near_reach: f32,
    ) -> Option<Self> {
        if eye.y <= near_reach {
            return None;
        }
        for chunk in chunks.iter().filter(|chunk| chunk.levels.first().is_some_and(|l| !l.is_empty())) {
            let over =
                eye.x >= chunk.min.x && eye.x <= chunk.max.x && eye.z >= chunk.min.z && eye.z <= chunk.max.z;
            if over && eye.y <= chunk.max.y + near_reach {
                return None;
            }
            if (eye.clamp(chunk.min, chunk.max) - eye).length() <= near_reach {
                return None;
            }
        }
        let end = grid.origin + Vec2::new(grid.cells[0] as f32, grid.cells[1] as f32) * grid.cell_size;
        let inside = eye.x >= grid.origin.x && eye.x <= end.x && eye.z >= grid.origin.y && eye.z <= end.y;
        if grid.open_edges && !inside {
            return None;
        }
        let floors = FloorTables::new(grid, chunks, levels, eye);
        // The rays through the corners of the tiles (NDC x to the right, y up).
        let inverse = view_projection.inverse();
        let rays = (0..=TILES[1])
            .flat_map(|j| (0..=TILES[0]).map(move |i| (i, j)))
            .map(|(i, j)| {
                let ndc = Vec2::new(
                    -1.0 + 2.0 * i as f32 / TILES[0] as f32,
                    1.0 - 2.0 * j as f32 / TILES[1] as f32,
                );
                inverse.project_point3(ndc.extend(1.0)) - eye
            })
            .collect();
        let land_before = vec![None; TILES[0] * TILES[1]];
        Some(Self { view_projection, eye, floors, rays, land_before })
    }

    /// Whether the land hides every point of `chunk`'s mirror image (its box mirrored in y = 0):
    /// its rays all pass under the land's floors ([`Self::passes_under`]), or the land's depth
    /// bound is nearer than it all over the screen where it lies ([`Self::behind_bound`]).
    pub fn hides(&mut self, chunk: &Chunk) -> bool {
        self.passes_under(chunk) || self.behind_bound(chunk)
    }

    /// Whether every ray to the mirror image of `chunk`, split in pieces (2 x 2 parts of its
    /// footprint, 4 bands of its heights), passes at one of the test heights over blocks whose
    /// floor is higher, piece by piece.
    fn passes_under(&self, chunk: &Chunk) -> bool {
        const PARTS: usize = 2;
        const BANDS: usize = 4;
        let (low, high) = (Vec2::new(chunk.min.x, chunk.min.z), Vec2::new(chunk.max.x, chunk.max.z));
        let step = (high - low) / PARTS as f32;
        let band = (chunk.max.y - chunk.min.y) / BANDS as f32;
        (0..PARTS * PARTS).all(|p| {
            let (column, row) = (p % PARTS, p / PARTS);
            let from = low + step * Vec2::new(column as f32, row as f32);
            let to = Vec2::new(
                if column == PARTS - 1 { high.x } else { from.x + step.x },
                if row == PARTS - 1 { high.y } else { from.y + step.y },
            );
            (0..BANDS).all(|b| {
                let below = chunk.min.y + band * b as f32;
                let above = if b == BANDS - 1 { chunk.max.y } else { below + band };
                (0..TEST_HEIGHTS).any(|k| self.piece_passes_under(k, (from, to), (below, above)))
            })
        })
    }

    /// Whether every ray to the mirror image of the box `footprint` x `heights` passes, at the
    /// `k`-th test height, over blocks whose floor is higher.
    fn piece_passes_under(&self, k: usize, (low, high): (Vec2, Vec2), (below, above): (f32, f32)) -> bool {
        let eye = self.eye;
        let c = self.floors.test_height(k);
        // The ray to the mirror of a point at height y reaches height c at the eye's xz plus
        // `s = (eye.y - c) / (eye.y + y)` times the way to the point: for the whole box, within the
        // box spanned by its footprint scaled by the extreme values of s.
        let scales = [(eye.y - c) / (eye.y + above), (eye.y - c) / (eye.y + below)];
        let eye_xz = Vec2::new(eye.x, eye.z);
        let corners = scales.map(|s| [eye_xz + (low - eye_xz) * s, eye_xz + (high - eye_xz) * s]);
        let from = corners.iter().flatten().fold(Vec2::MAX, |a, &b| a.min(b));
        let to = corners.iter().flatten().fold(Vec2::MIN, |a, &b| a.max(b));
        self.floors.all_above(k, from, to)
    }

    /// Whether the land's depth bound is nearer than `chunk`'s mirror image over every tile its
    /// box covers on the screen.
    fn behind_bound(&mut self, chunk: &Chunk) -> bool {
        let (min, max) = (
            Vec3::new(chunk.min.x, -chunk.max.y, chunk.min.z),
            Vec3::new(chunk.max.x, -chunk.min.y, chunk.max.z),
        );
        let mut nearest = f32::INFINITY;
        let (mut low, mut high) = (Vec2::MAX, Vec2::MIN);
        for corner in 0..8 {
            let p =
                Vec3::select(glam::BVec3::new(corner & 1 != 0, corner & 2 != 0, corner & 4 != 0), max, min);
            let clip = self.view_projection * p.extend(1.0);
            if clip.w <= 0.0 {
                return false;
            }
            nearest = nearest.min(clip.w);
            let ndc = Vec2::new(clip.x, clip.y) / clip.w;
            (low, high) = (low.min(ndc), high.max(ndc));
        }
        // The tiles the box covers (NDC y up, tile rows down), one more on each side.
        let tile = |ndc: f32, axis: usize, flip: bool| {
            let t = if flip { (1.0 - ndc) / 2.0 } else { (ndc + 1.0) / 2.0 } * TILES[axis] as f32;
            t.floor().clamp(-1.0, TILES[axis] as f32) as isize
        };
        let columns =
            (tile(low.x, 0, false) - 1).max(0)..=(tile(high.x, 0, false) + 1).min(TILES[0] as isize - 1);
        let rows = (tile(high.y, 1, true) - 1).max(0)..=(tile(low.y, 1, true) + 1).min(TILES[1] as isize - 1);
        let limit = nearest * (1.0 - DEPTH_MARGIN);
        rows.flat_map(|j| columns.clone().map(move |i| (i, j)))
            .all(|(i, j)| self.land_before(i as usize, j as usize) < limit)
    }

    /// The bound on the depth of the land seen through tile (`i`, `j`), worked out once.
    fn land_before(&mut self, i: usize, j: usize) -> f32 {
        if let Some(bound) = self.land_before[j * TILES[0] + i] {
            return bound;
        }
        let ray = |i: usize, j: usize| self.rays[j * (TILES[0] + 1) + i];
        let corners = [ray(i, j), ray(i + 1, j), ray(i, j + 1), ray(i + 1, j + 1)];
        let eye = self.eye;
        let depth = self.view_projection.row(3);
        let mut bound = f32::INFINITY;
        if corners.iter().all(|d| d.y < 0.0) {
            // From the eye's height down: the first test height whose plane the tile's rays meet
            // over land standing higher.
            for k in (0..TEST_HEIGHTS).rev() {
                let c = self.floors.test_height(k);
                // Where the tile's rays reach the height c: within the quadrilateral of its
                // corners' (the tile's pyramid cut by a plane).
                let hits = corners.map(|d| eye + d * ((c - eye.y) / d.y));
                let low = hits.iter().fold(Vec2::MAX, |a, h| a.min(Vec2::new(h.x, h.z)));
                let high = hits.iter().fold(Vec2::MIN, |a, h| a.max(Vec2::new(h.x, h.z)));
                if self.floors.all_above(k, low, high) {
                    // Depth is linear over the plane: the furthest corner bounds the tile.
                    bound = hits.iter().map(|h| depth.dot(h.extend(1.0))).fold(f32::MIN, f32::max);
                    break;
                }
            }
        }
        self.land_before[j * TILES[0] + i] = Some(bound);
        bound
    }
}

/// For each test height `c`, a summed-area table of the blocks whose floor is above `c`.
#[derive(Debug, Clone)]
struct FloorTables {
    grid: BlockGrid,
    eye_height: f32,
    /// Blocks along x, plus one: the row length of the tables.
    stride: usize,
    /// At `(z, x)`: the number of blocks above the test height in rows `0..z`, columns `0..x`.
    above: Vec<Vec<u32>>,
}

impl FloorTables {
    fn new(
        grid: &BlockGrid,
        chunks: &[Chunk],
        levels: impl IntoIterator<Item = (usize, usize)>,
        eye: Vec3,
    ) -> Self {
        let [blocks_x, blocks_z] = grid.blocks();
        let mut floors = vec![f32::NEG_INFINITY; blocks_x * blocks_z];
        for (index, level) in levels {
            let level_floors = &chunks[index].levels[level].block_floors;
            let (chunk_row, chunk_column) =
                (index as u32 / grid.chunk_columns, index as u32 % grid.chunk_columns);
            for i in 0..CHUNK_BLOCKS {
                for j in 0..CHUNK_BLOCKS {
                    let (z, x) =
                        ((chunk_row * CHUNK_BLOCKS + i) as usize, (chunk_column * CHUNK_BLOCKS + j) as usize);
                    if z < blocks_z && x < blocks_x {
                        floors[z * blocks_x + x] = level_floors[(i * CHUNK_BLOCKS + j) as usize];
                    }
                }
            }
        }
        let stride = blocks_x + 1;
        let mut tables =
            Self { grid: *grid, eye_height: eye.y, stride, above: Vec::with_capacity(TEST_HEIGHTS) };
        for k in 0..TEST_HEIGHTS {
            let c = tables.test_height(k);
            let mut table = vec![0u32; stride * (blocks_z + 1)];
            for z in 0..blocks_z {
                for x in 0..blocks_x {
                    table[(z + 1) * stride + x + 1] = u32::from(floors[z * blocks_x + x] > c)
                        + table[z * stride + x + 1]
                        + table[(z + 1) * stride + x]
                        - table[z * stride + x];
                }
            }
            tables.above.push(table);
        }
        tables
    }

    /// The `k`-th height at which rays are tested: from the water up toward the eye.
    fn test_height(&self, k: usize) -> f32 {
        self.eye_height * k as f32 / TEST_HEIGHTS as f32
    }

    /// Whether every block meeting the rectangle `low`..`high` (x and z) has its floor above the
    /// `k`-th test height (false where the rectangle leaves the map).
    fn all_above(&self, k: usize, low: Vec2, high: Vec2) -> bool {
        let margin = Vec2::splat(0.01 * self.grid.cell_size);
        let size = Vec2::new(self.grid.cells[0] as f32, self.grid.cells[1] as f32) * self.grid.cell_size;
        let (from, to) = (low - margin - self.grid.origin, high + margin - self.grid.origin);
        if from.x < 0.0 || from.y < 0.0 || to.x > size.x || to.y > size.y {
            return false;
        }
        let block = BLOCK_CELLS as f32 * self.grid.cell_size;
        let [blocks_x, blocks_z] = self.grid.blocks();
        let (first, last) = ((from / block).floor(), (to / block).floor());
        let (x0, z0) = (first.x as usize, first.y as usize);
        let (x1, z1) = ((last.x as usize).min(blocks_x - 1), (last.y as usize).min(blocks_z - 1));
        if x0 > x1 || z0 > z1 {
            return false;
        }
        let table = &self.above[k];
        let at = |z: usize, x: usize| table[z * self.stride + x];
        let count = at(z1 + 1, x1 + 1) + at(z0, x0) - at(z0, x1 + 1) - at(z1 + 1, x0);
        count as usize == (x1 + 1 - x0) * (z1 + 1 - z0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{CameraPose, Frustum, Lens};
    use crate::config::SceneConfig;
    use crate::world::mesh::LodView;
    use crate::world::{Heightfield, Heightmap, TerrainMesh};

    /// A 97 x 97 map: water (level 20) around a plateau at `plateau` (a grey level) over
    /// samples 8..89, with a lake (level 20) over the samples `lake` (rows and columns).
    fn field(plateau: f32, lake: std::ops::Range<u32>) -> Heightfield {
        let levels = (0..97 * 97)
            .map(|i| {
                let (r, c) = (i / 97, i % 97);
                let land = (8..89).contains(&r) && (8..89).contains(&c);
                let in_lake = lake.contains(&r) && lake.contains(&c);
                if land && !in_lake { plateau } else { 20.0 }
            })
            .collect();
        Heightfield::new(&Heightmap::new(97, 97, levels).expect("valid"), &SceneConfig::default())
    }

    fn view(pose: CameraPose, mirrored: bool) -> LodView {
        let lens = Lens { field_of_view_degrees: 45.0, near: 0.1, far: 500.0 };
        let view_projection = lens.projection(16.0 / 9.0) * pose.view_matrix();
        LodView {
            eye: pose.position,
            frustum: Frustum::from_view_projection(view_projection),
            view_projection,
            pixels_per_unit: 720.0 / (2.0 * (22.5f32).to_radians().tan()),
            max_error_pixels: 1.0,
            mirrored,
            near_reach: 0.2,
        }
    }

    #[test]
    fn floors_are_the_lowest_corner_of_the_level_cells() {
        let f = field(200.0, 40..41);
        let plateau = f.height(50, 50);
        let inside = (32, 64);
        // Level 0 of the chunk over rows and columns 32..=64: the lake sample (40, 40) lowers
        // the blocks around it only.
        let samples: Vec<u32> = (inside.0..=inside.1).collect();
        let floors = block_floors(&f, (inside, inside), &samples, &samples);
        let water = f.height(40, 40);
        assert_eq!(floors[(CHUNK_BLOCKS + 1) as usize], water, "the block holding the lake");
        assert_eq!(floors[(CHUNK_BLOCKS + 2) as usize], water, "its cells reach the next block");
        assert_eq!(floors[(5 * CHUNK_BLOCKS + 5) as usize], plateau);
        // At stride 32 one cell spans the chunk: its corners are on the plateau.
        let coarse = block_floors(&f, (inside, inside), &[32, 64], &[32, 64]);
        assert!(coarse.iter().all(|&floor| floor == plateau));
        // A chunk of 5 cells has two blocks a side; the others are below everything.
        let small = block_floors(&f, ((50, 55), (50, 55)), &[50, 55], &[50, 55]);
        assert_eq!(small[0], plateau);
        assert_eq!(small[2], f32::NEG_INFINITY);
    }

    #[test]
    fn the_plateau_hides_the_mirror_image_behind_its_edge() {
        let mesh = TerrainMesh::new(&field(200.0, 0..0));
        // Above the shore looking across the plateau: only its far edge could show a reflection.
        let pose = CameraPose::new(glam::Vec3::new(0.0, 4.0, 9.0), 0.0, -20.0);
        let [direct, mirrored] = mesh.select_pair(&view(pose, false), &view(pose, true));
        assert_eq!(direct, mesh.select(&view(pose, false)));
        let whole = mesh.select(&view(pose, true));
        assert!(mirrored.len() < whole.len() / 2, "{} of {}", mirrored.len(), whole.len());
        assert!(mirrored.iter().all(|range| whole.contains(range)));
    }

    #[test]
    fn a_lake_in_front_keeps_what_it_reflects() {
        // A lake in the plateau's middle reflects the land beyond it.
        let lake = TerrainMesh::new(&field(200.0, 30..67));
        let solid = TerrainMesh::new(&field(200.0, 0..0));
        let pose = CameraPose::new(glam::Vec3::new(0.0, 4.0, 9.0), 0.0, -20.0);
        let kept = |mesh: &TerrainMesh| mesh.select_pair(&view(pose, false), &view(pose, true))[1].len();
        assert!(kept(&lake) > kept(&solid), "{} vs {}", kept(&lake), kept(&solid));
    }

    #[test]
    fn no_culling_near_the_land_or_below_the_water() {
        let mesh = TerrainMesh::new(&field(200.0, 0..0));
        for pose in [
            // On the plateau, a few centimetres above it: the near plane may cut it open.
            CameraPose::new(glam::Vec3::new(0.0, mesh.chunks[4].max.y + 0.05, 0.0), 0.0, -20.0),
            // Under the water.
            CameraPose::new(glam::Vec3::new(0.0, -1.0, 12.0), 0.0, 10.0),
        ] {
            let [_, mirrored] = mesh.select_pair(&view(pose, false), &view(pose, true));
            assert_eq!(mirrored, mesh.select(&view(pose, true)));
        }
    }
}
