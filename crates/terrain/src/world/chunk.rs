//! The chunked mesh's layout: chunks of [`CHUNK_CELLS`] cells a side, each level of detail with
//! its draw ranges, and the blocks of [`BLOCK_CELLS`] cells a side in which the land's floors are
//! tracked for the water's occlusion test. Plain data and the functions that compute it; the
//! mesh is built in [`super::mesh`] and the occlusion test is [`super::occlusion`]. World
//! convention: y-up, the water is y = 0.

use glam::{Vec2, Vec3};

use super::Heightfield;

/// Cells along a side of a chunk (the last chunk of a row or column may be smaller).
pub const CHUNK_CELLS: u32 = 32;

/// The four edges of a chunk, in the order of [`ChunkLevel::skirts`] and [`Chunk::edge_planes`]:
/// its first (far, -z) row, its last (near, +z) row, its first (left, -x) column and its last
/// (right, +x) column.
pub const EDGE_COUNT: usize = 4;

/// One level of detail of one chunk: its surface and its skirts, each a range of indices into
/// its own compact block of vertices.
///
/// Each skirt is stored as two one-sided strips, one facing each side of the edge's vertical
/// plane. Only the strip facing the camera can produce pixels (the other is culled as a back
/// face), so a frame draws one strip per edge ([`TerrainMesh::select`]): the picture is the same
/// as with two-sided skirts, for half of their triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChunkLevel {
    /// The surface's triangles.
    pub surface: DrawRange,
    /// The skirts along the four edges ([`EDGE_COUNT`] order), each as `[strip facing toward
    /// -axis, strip facing toward +axis]` (the axis is z for rows, x for columns).
    pub skirts: [[DrawRange; 2]; EDGE_COUNT],
    /// Largest vertical distance, in world units, between this level's visible surface and the
    /// full-resolution one (never less than the finer levels').
    pub error: f32,
    /// The lowest height of this level's surface over each block of the chunk
    /// ([`block_floors`]).
    pub block_floors: BlockFloors,
}

impl ChunkLevel {
    /// Every range of this level: the surface, then the skirts' strips edge by edge.
    pub fn ranges(&self) -> impl Iterator<Item = &DrawRange> {
        std::iter::once(&self.surface).chain(self.skirts.iter().flatten())
    }

    /// Whether the level has no triangle above the water.
    pub fn is_empty(&self) -> bool {
        self.ranges().all(|range| range.index_count == 0)
    }
}

/// A square of the terrain at all its levels of detail.
#[derive(Debug, Clone, PartialEq)]
pub struct Chunk {
    /// Lowest corner of the box around the chunk's geometry above the water.
    pub min: Vec3,
    /// Highest corner of that box.
    pub max: Vec3,
    /// The coordinates of the vertical planes of the four edges ([`EDGE_COUNT`] order): z of the
    /// first and last rows, x of the first and last columns.
    pub edge_planes: [f32; EDGE_COUNT],
    /// Level 0 (every sample) first, then successively halved resolutions.
    pub levels: Vec<ChunkLevel>,
}

/// What to draw for one part of a chunk at one level: a range of indices into a block of vertices.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DrawRange {
    /// First index in [`TerrainMesh::indices`].
    pub first_index: u32,
    /// Number of indices.
    pub index_count: u32,
    /// Added to every index to find the vertex in [`TerrainMesh::positions`].
    pub base_vertex: u32,
}

/// Cells along a side of a block (a chunk is [`CHUNK_BLOCKS`] blocks a side).
pub const BLOCK_CELLS: u32 = 4;

/// Blocks along a side of a chunk.
pub const CHUNK_BLOCKS: u32 = CHUNK_CELLS / BLOCK_CELLS;

/// The floors of the blocks of one chunk level, row by row (`CHUNK_BLOCKS` a row); blocks outside
/// the chunk are at minus infinity.
pub type BlockFloors = [f32; (CHUNK_BLOCKS * CHUNK_BLOCKS) as usize];

/// The floors of the blocks of the chunk spanning samples `rows.0..=rows.1` x
/// `columns.0..=columns.1` for the level of detail whose samples are `row_samples` x
/// `column_samples` (sample indices in the field): the lowest height of the level's surface over
/// each block (or lower).
pub fn block_floors(
    field: &Heightfield,
    (rows, columns): ((u32, u32), (u32, u32)),
    row_samples: &[u32],
    column_samples: &[u32],
) -> BlockFloors {
    let mut floors = [f32::NEG_INFINITY; (CHUNK_BLOCKS * CHUNK_BLOCKS) as usize];
    let blocks = |(first, last): (u32, u32)| (last - first).div_ceil(BLOCK_CELLS);
    for i in 0..blocks(rows) {
        for j in 0..blocks(columns) {
            floors[(i * CHUNK_BLOCKS + j) as usize] = f32::INFINITY;
        }
    }
    // Each level cell lowers the floors of the blocks it overlaps to its lowest corner.
    let overlapped =
        |(a, b): (u32, u32), first: u32| (a - first) / BLOCK_CELLS..=(b - first - 1) / BLOCK_CELLS;
    for pair in row_samples.windows(2) {
        for step in column_samples.windows(2) {
            let corners = [(pair[0], step[0]), (pair[0], step[1]), (pair[1], step[0]), (pair[1], step[1])];
            let lowest = corners.iter().map(|&(r, c)| field.height(r, c)).fold(f32::INFINITY, f32::min);
            for i in overlapped((pair[0], pair[1]), rows.0) {
                for j in overlapped((step[0], step[1]), columns.0) {
                    let floor = &mut floors[(i * CHUNK_BLOCKS + j) as usize];
                    *floor = floor.min(lowest);
                }
            }
        }
    }
    floors
}

/// Where a mesh's blocks lie in the world, and what surrounds the map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockGrid {
    /// x and z of sample (0, 0), the corner of the grid of samples.
    pub origin: Vec2,
    /// Distance between neighbouring samples, in world units.
    pub cell_size: f32,
    /// Cells along x and along z (one fewer than the samples).
    pub cells: [u32; 2],
    /// Chunks along x (chunks are numbered row by row).
    pub chunk_columns: u32,
    /// Whether a sample on the map's border is above the water: the land then ends in a wall a
    /// ray from outside the map may pass under.
    pub open_edges: bool,
}

impl BlockGrid {
    /// The grid of `field`, whose chunks are `chunk_columns` a row.
    pub fn new(field: &Heightfield, chunk_columns: u32) -> Self {
        let (columns, rows) = (field.columns(), field.rows());
        let border = (0..columns)
            .flat_map(|c| [(0, c), (rows - 1, c)])
            .chain((0..rows).flat_map(|r| [(r, 0), (r, columns - 1)]));
        let first = field.point(0, 0);
        Self {
            origin: Vec2::new(first.x, first.z),
            cell_size: field.cell_size(),
            cells: [columns - 1, rows - 1],
            chunk_columns,
            open_edges: border.into_iter().any(|(r, c)| field.height(r, c) > 0.0),
        }
    }

    pub(super) fn blocks(&self) -> [usize; 2] {
        self.cells.map(|cells| cells.div_ceil(BLOCK_CELLS) as usize)
    }
}
