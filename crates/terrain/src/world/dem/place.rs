//! Placing prepared elevation data in the scene.
//!
//! The engine draws every world at the same size: the terrain's longer side spans
//! [`SceneConfig::terrain_length`] world units (20), so the sky box, the fog, the camera's speed
//! and its near and far planes suit any data. Elevation data keeps its true proportions: a world
//! unit is `metres_per_unit` metres horizontally and vertically (times the vertical
//! exaggeration). The water plane y = 0 is the water level: heights are measured from it, and
//! where the data lies wholly above it (or there is no water level) the lowest ground is put at
//! y = 0 and no sea is drawn.

use glam::Vec3;
use rayon::prelude::*;

use super::Prepared;
use crate::camera::CameraPose;
use crate::config::SceneConfig;
use crate::world::heightmap::sixteen_of_level;
use crate::world::{Heightmap, HeightmapError};

/// Where the water is, in metres of the data's heights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WaterLevel {
    /// Water up to this height (metres).
    Metres(f64),
    /// No water at all.
    None,
}

impl Default for WaterLevel {
    /// Sea level: 0 m.
    fn default() -> Self {
        WaterLevel::Metres(0.0)
    }
}

impl std::str::FromStr for WaterLevel {
    type Err = String;

    /// `none`, or a height in metres.
    fn from_str(text: &str) -> Result<Self, String> {
        if text.eq_ignore_ascii_case("none") {
            return Ok(WaterLevel::None);
        }
        text.parse::<f64>()
            .ok()
            .filter(|metres| metres.is_finite())
            .map(WaterLevel::Metres)
            .ok_or_else(|| format!("`{text}` is neither a height in metres nor `none`"))
    }
}

/// How to place elevation data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaceOptions {
    /// The water level.
    pub water_level: WaterLevel,
    /// Factor on the heights (1: true proportions).
    pub vertical_exaggeration: f64,
}

impl Default for PlaceOptions {
    fn default() -> Self {
        Self { water_level: WaterLevel::default(), vertical_exaggeration: 1.0 }
    }
}

/// What the world knows of the elevation data it was made from.
#[derive(Debug, Clone, PartialEq)]
pub struct ElevationInfo {
    /// Metres between neighbouring samples (square cells).
    pub cell_size_metres: f64,
    /// Metres of ground a world unit spans horizontally.
    pub metres_per_unit: f64,
    /// The factor on the heights.
    pub vertical_exaggeration: f64,
    /// The data's height (metres) at world y = 0: the water level, or the lowest ground when no
    /// water is drawn.
    pub base_metres: f64,
    /// Whether a sea is drawn (the water level lies above some of the ground).
    pub sea: bool,
    /// The lowest and highest heights, in metres (voids filled).
    pub range_metres: (f32, f32),
    /// `true` for samples the file had no data for (filled from their neighbours), row by row
    /// from the northern (far, -z) row, as the heightmap; empty when the file had no void (no
    /// byte a sample spent on nothing).
    pub voids: Vec<bool>,
}

impl ElevationInfo {
    /// Number of void samples.
    pub fn void_count(&self) -> usize {
        self.voids.iter().filter(|&&v| v).count()
    }

    /// Whether sample `index` (row by row from the northern row) was a void.
    pub fn is_void(&self, index: usize) -> bool {
        self.voids.get(index).copied().unwrap_or(false)
    }

    /// World height (y) of a height in metres.
    pub fn world_height(&self, metres: f64) -> f32 {
        ((metres - self.base_metres) * self.vertical_exaggeration / self.metres_per_unit) as f32
    }
}

/// Elevation data ready to draw: the heightmap (grey levels), the scene numbers that turn those
/// levels into world heights, and what the world keeps of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct DemScene {
    /// The heights as grey levels 0..=255, kept as 16-bit values (2 bytes a sample).
    pub heightmap: Heightmap,
    /// The course's scene numbers with the height mapping, the sea and the start pose of this
    /// data.
    pub config: SceneConfig,
    /// The data's sizes, water and void mask.
    pub info: ElevationInfo,
}

/// Places `prepared` in the scene with `options`.
pub fn place(prepared: Prepared, options: &PlaceOptions) -> Result<DemScene, HeightmapError> {
    let Prepared { columns, rows, heights, voids, cell_size, .. } = prepared;
    let (min, max) =
        heights.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    let defaults = SceneConfig::default();
    let metres_per_unit = cell_size * f64::from(columns.max(rows)) / f64::from(defaults.terrain_length);
    let (sea, base) = match options.water_level {
        WaterLevel::Metres(level) if f64::from(min) < level => (true, level),
        _ => (false, f64::from(min)),
    };
    let exaggeration = options.vertical_exaggeration;
    let voids = if voids.contains(&true) { voids } else { Vec::new() };
    let info = ElevationInfo {
        cell_size_metres: cell_size,
        metres_per_unit,
        vertical_exaggeration: exaggeration,
        base_metres: base,
        sea,
        range_metres: (min, max),
        voids,
    };
    // Grey levels 0..=255 span the data's range (16-bit precision on the GPU).
    let (low, high) = (info.world_height(f64::from(min)), info.world_height(f64::from(max)));
    let unit_height = ((high - low) / 255.0).max(1e-6);
    // Kept as 16-bit values (2 bytes a sample, what the GPU's height texture holds anyway):
    // 65535 steps over the data's range.
    let values: Vec<u16> = heights
        .par_iter()
        .map(|&h| sixteen_of_level((info.world_height(f64::from(h)) - low) / unit_height))
        .collect();
    drop(heights);
    let heightmap = Heightmap::from_sixteen_bit(columns, rows, values)?;
    let mut config = SceneConfig { unit_height, level_offset: low / unit_height, sea, ..defaults };
    config.camera_start = start_pose(&heightmap, &config);
    Ok(DemScene { heightmap, config, info })
}

/// Where the camera starts over a placed DEM: above the southern (near, +z) edge's middle, high
/// enough to clear the highest ground, looking north down toward the terrain's centre.
fn start_pose(heightmap: &Heightmap, config: &SceneConfig) -> CameraPose {
    let cell = crate::world::Heightfield::cell_size_of(heightmap, config);
    let half_depth = heightmap.rows() as f32 * cell / 2.0;
    let top = config.height_of_level(255.0);
    let centre = config.height_of_level(heightmap.level(heightmap.rows() / 2, heightmap.columns() / 2));
    let y = (top + 1.0).max(2.5);
    let z = half_depth;
    let pitch = -((y - centre) / (z * 1.4)).atan().to_degrees();
    CameraPose::new(Vec3::new(0.0, y, z), 0.0, pitch)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prepared(heights: Vec<f32>, columns: u32, cell: f64) -> Prepared {
        let rows = heights.len() as u32 / columns;
        Prepared {
            columns,
            rows,
            voids: vec![false; heights.len()],
            heights,
            cell_size: cell,
            source_size: (columns, rows),
            cell_size_given: false,
            resampled: None,
            source_voids: 0,
        }
    }

    #[test]
    fn heights_keep_their_proportions_above_the_water() {
        // 4 x 2 samples 100 m apart: 400 m wide, a world unit is 20 m.
        let scene = place(
            prepared(vec![-10.0, 0.0, 50.0, 100.0, 0.0, 0.0, 0.0, 0.0], 4, 100.0),
            &PlaceOptions::default(),
        )
        .expect("valid");
        assert!(scene.info.sea);
        assert_eq!(scene.info.metres_per_unit, 20.0);
        let height = |column| scene.config.height_of_level(scene.heightmap.level(0, column));
        // Within a 16-bit step of the range (5.5 / 65535).
        let step = 5.5 / 65535.0;
        assert!((height(0) + 0.5).abs() <= step && height(1).abs() <= step, "{} {}", height(0), height(1));
        assert!((height(3) - 5.0).abs() <= step);
        // The camera starts above the highest ground.
        assert!(scene.config.camera_start.position.y > 5.0);
    }

    #[test]
    fn land_wholly_above_the_water_has_no_sea() {
        let options = PlaceOptions { vertical_exaggeration: 2.0, ..PlaceOptions::default() };
        let scene = place(prepared(vec![1000.0, 1100.0, 1000.0, 1200.0], 2, 100.0), &options).expect("valid");
        assert!(!scene.info.sea && !scene.config.sea);
        assert_eq!(scene.info.base_metres, 1000.0);
        let top = scene.config.height_of_level(scene.heightmap.level(1, 1));
        // 200 m up, doubled, at 10 m a unit.
        assert!((top - 40.0).abs() < 1e-4, "{top}");
        let none = PlaceOptions { water_level: WaterLevel::None, ..PlaceOptions::default() };
        let scene = place(prepared(vec![-5.0, 10.0, 0.0, 0.0], 2, 1.0), &none).expect("valid");
        assert!(!scene.config.sea && scene.info.base_metres == -5.0);
    }

    #[test]
    fn water_levels_parse() {
        assert_eq!("none".parse(), Ok(WaterLevel::None));
        assert_eq!("-3.5".parse(), Ok(WaterLevel::Metres(-3.5)));
        assert!("deep".parse::<WaterLevel>().is_err());
    }
}
