//! Where a heightmap stands in the world: grid positions, world heights and height queries.

use glam::{Vec2, Vec3};

use super::Heightmap;
use crate::config::SceneConfig;

/// A heightmap placed in the world (y-up, water at y = 0).
///
/// The terrain is centred on the origin and its longer side spans `terrain_length`; cells are
/// square. As in the course, sample (row i, column j) sits at the centre of its image pixel:
/// `x = (j + 0.5) * cell - width / 2`, `z = (i + 0.5) * cell - depth / 2`, so row 0 is the far (-z)
/// edge, and its height is `(level + level_offset) * unit_height`. The colour map, stretched over
/// the whole footprint, is sampled at the same pixel centres.
#[derive(Debug, Clone, PartialEq)]
pub struct Heightfield {
    columns: u32,
    rows: u32,
    cell_size: f32,
    heights: Vec<f32>,
}

impl Heightfield {
    /// Places `heightmap` in the world with the sizes and height mapping of `config`.
    pub fn new(heightmap: &Heightmap, config: &SceneConfig) -> Self {
        let (columns, rows) = (heightmap.columns(), heightmap.rows());
        Self {
            columns,
            rows,
            cell_size: Self::cell_size_of(heightmap, config),
            heights: heightmap.levels().map(|level| config.height_of_level(level)).collect(),
        }
    }

    /// Distance between neighbouring samples of `heightmap` placed with `config`, in world units.
    pub fn cell_size_of(heightmap: &Heightmap, config: &SceneConfig) -> f32 {
        config.terrain_length / heightmap.columns().max(heightmap.rows()) as f32
    }

    /// Samples per row.
    pub fn columns(&self) -> u32 {
        self.columns
    }

    /// Number of rows.
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// Distance between neighbouring samples, in world units.
    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    /// Size of the terrain's footprint along x and z (the image's full extent, pixel edge to edge).
    pub fn extent(&self) -> Vec2 {
        Vec2::new(self.columns as f32, self.rows as f32) * self.cell_size
    }

    /// World heights of all samples, row by row from the far (-z) row.
    pub fn heights(&self) -> &[f32] {
        &self.heights
    }

    /// World height of sample (`row`, `column`). Panics when out of range.
    pub fn height(&self, row: u32, column: u32) -> f32 {
        assert!(row < self.rows && column < self.columns, "sample out of range");
        self.heights[(row * self.columns + column) as usize]
    }

    /// World position of sample (`row`, `column`).
    pub fn point(&self, row: u32, column: u32) -> Vec3 {
        let half = self.extent() * 0.5;
        Vec3::new(
            (column as f32 + 0.5) * self.cell_size - half.x,
            self.height(row, column),
            (row as f32 + 0.5) * self.cell_size - half.y,
        )
    }

    /// Terrain height under (`x`, `z`), interpolated bilinearly between the four surrounding
    /// samples; `None` outside the grid of samples.
    pub fn height_at(&self, x: f32, z: f32) -> Option<f32> {
        bilinear(self.columns, self.rows, self.cell_size, x, z, |row, column| self.height(row, column))
    }

    /// Texture coordinates of (`x`, `z`) on a map stretched over the footprint: (0, 0) at the
    /// -x, -z corner, (1, 1) at the +x, +z corner (image rows run toward +z).
    pub fn uv(&self, x: f32, z: f32) -> Vec2 {
        Vec2::new(x, z) / self.extent() + 0.5
    }
}

/// Terrain height under (`x`, `z`) of `heightmap` placed with `config`, as
/// [`Heightfield::height_at`] gives it, without a copy of the heights (for a single query).
pub fn height_under(heightmap: &Heightmap, config: &SceneConfig, x: f32, z: f32) -> Option<f32> {
    let cell = Heightfield::cell_size_of(heightmap, config);
    bilinear(heightmap.columns(), heightmap.rows(), cell, x, z, |row, column| {
        config.height_of_level(heightmap.level(row, column))
    })
}

/// Bilinear interpolation at (`x`, `z`) of a `columns` x `rows` grid of samples `cell` apart,
/// centred on the origin, `height(row, column)` giving the samples; `None` outside the grid.
fn bilinear(
    columns: u32,
    rows: u32,
    cell: f32,
    x: f32,
    z: f32,
    height: impl Fn(u32, u32) -> f32,
) -> Option<f32> {
    let half = Vec2::new(columns as f32, rows as f32) * cell * 0.5;
    let column = (x + half.x) / cell - 0.5;
    let row = (z + half.y) / cell - 0.5;
    let (last_column, last_row) = ((columns - 1) as f32, (rows - 1) as f32);
    if !(0.0..=last_column).contains(&column) || !(0.0..=last_row).contains(&row) {
        return None;
    }
    let (c0, r0) = ((column.floor() as u32).min(columns - 2), (row.floor() as u32).min(rows - 2));
    let (fx, fz) = (column - c0 as f32, row - r0 as f32);
    let top = lerp(height(r0, c0), height(r0, c0 + 1), fx);
    let bottom = lerp(height(r0 + 1, c0), height(r0 + 1, c0 + 1), fx);
    Some(lerp(top, bottom, fz))
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The height of a cell's surface with corners `[h00, h10, h01, h11]` (`h10` one row on, `h01`
/// one column on) at the fractions `fx` (along columns) and `fz` (along rows): triangles
/// (h00, h10, h01) below the diagonal and (h01, h10, h11) above it, the split of the terrain's
/// mesh at every level of detail.
pub fn cell_surface([h00, h10, h01, h11]: [f32; 4], fx: f32, fz: f32) -> f32 {
    if fx + fz <= 1.0 {
        h00 + (h01 - h00) * fx + (h10 - h00) * fz
    } else {
        h11 + (h10 - h11) * (1.0 - fx) + (h01 - h11) * (1.0 - fz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(columns: u32, rows: u32, levels: Vec<f32>) -> Heightfield {
        let map = Heightmap::new(columns, rows, levels).expect("valid");
        Heightfield::new(&map, &SceneConfig::default())
    }

    #[test]
    fn course_layout_puts_samples_at_pixel_centres() {
        let f = field(256, 256, vec![100.0; 256 * 256]);
        assert_eq!(f.extent(), Vec2::splat(20.0));
        let cell = 20.0 / 256.0;
        let first = f.point(0, 0);
        assert!((first.x - (-10.0 + cell / 2.0)).abs() < 1e-5);
        assert!((first.z - (-10.0 + cell / 2.0)).abs() < 1e-5);
        assert_eq!(first.y, 0.0);
        let last = f.point(255, 255);
        assert!((last.x - (10.0 - cell / 2.0)).abs() < 1e-5);
        // Texture coordinates of a sample hit its pixel's centre.
        let uv = f.uv(first.x, first.z);
        assert!((uv.x - 0.5 / 256.0).abs() < 1e-6 && (uv.y - 0.5 / 256.0).abs() < 1e-6);
    }

    #[test]
    fn non_square_maps_keep_square_cells() {
        let f = field(8, 4, vec![0.0; 32]);
        assert_eq!(f.cell_size(), 2.5);
        assert_eq!(f.extent(), Vec2::new(20.0, 10.0));
        assert_eq!(f.point(3, 7), Vec3::new(8.75, -1.5, 3.75));
    }

    #[test]
    fn height_at_interpolates_and_stops_at_the_grid() {
        // 2x2 samples: levels 100 (y 0) on the left column and 200 (y 1.5) on the right.
        let f = field(2, 2, vec![100.0, 200.0, 100.0, 200.0]);
        let left = f.point(0, 0);
        let right = f.point(0, 1);
        assert_eq!(f.height_at(left.x, left.z), Some(0.0));
        assert_eq!(f.height_at(right.x, right.z), Some(1.5));
        let mid = f.height_at((left.x + right.x) / 2.0, 0.0).expect("inside");
        assert!((mid - 0.75).abs() < 1e-5);
        assert_eq!(f.height_at(right.x + 0.01, 0.0), None);
        assert_eq!(f.height_at(0.0, 100.0), None);
    }

    #[test]
    fn a_single_query_agrees_with_the_field() {
        let config = SceneConfig::default();
        let levels: Vec<f32> = (0..35).map(|i| (i * 37 % 255) as f32).collect();
        let map = Heightmap::new(7, 5, levels).expect("valid");
        let f = Heightfield::new(&map, &config);
        for (x, z) in [(0.0, 0.0), (-7.3, 2.9), (8.4, -3.3), (9.9, 0.0), (0.0, 9.0), (-30.0, 1.0)] {
            assert_eq!(height_under(&map, &config, x, z), f.height_at(x, z), "at {x}, {z}");
        }
    }
}
