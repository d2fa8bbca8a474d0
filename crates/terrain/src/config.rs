//! The scene's numbers: sizes, height mapping, water and camera defaults.
//!
//! [`SceneConfig::default`] holds the course's numbers (spec section 2). All lengths are in world
//! units, the world is **y-up** and the water is the plane y = 0.

use glam::{Vec2, Vec3};

use crate::camera::{CameraPose, Limits};

/// The numbers that lay out the scene. `Default` gives the course's values.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneConfig {
    /// Side of the terrain's square footprint, centred on the origin (course: 20). A heightmap that
    /// is not square spans this length along its longer side and keeps square cells.
    pub terrain_length: f32,
    /// Added to a heightmap's grey level (0..=255) before scaling (course `Y0`: -100).
    pub level_offset: f32,
    /// World units per grey level (course `unitHeight`: 0.015), so 0..=255 maps to -1.5..=2.325.
    pub unit_height: f32,
    /// How many times the detail map repeats across the terrain (course `detailScale`: 10).
    pub detail_repeat: f32,
    /// Size of the sky box: x width, y height (from y = 0 up) and z depth (course: 200, 200, 280).
    pub sky_box_size: Vec3,
    /// Opacity of the water drawn over the mirrored world (course: 0.8).
    pub water_alpha: f32,
    /// How many times the water texture repeats along x and z over the sky box's floor
    /// (course: 20 x 28).
    pub water_repeat: Vec2,
    /// Drift of the water texture in texture repeats per second, along x and z (course: -0.02, -0.02).
    pub wave_velocity: Vec2,
    /// Where the camera starts (course: at (0, 2.5, 10) looking toward -z).
    pub camera_start: CameraPose,
    /// Vertical field of view at start, in degrees (course: 45).
    pub field_of_view_degrees: f32,
    /// Near clipping distance in world units (course: 0.1).
    pub near: f32,
    /// Far clipping distance in world units (course: 500).
    pub far: f32,
    /// Whether the water plane (y = 0) is drawn (course: yes). Elevation data wholly above its
    /// water level, or with none, has no sea.
    pub sea: bool,
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            terrain_length: 20.0,
            level_offset: -100.0,
            unit_height: 0.015,
            detail_repeat: 10.0,
            sky_box_size: Vec3::new(200.0, 200.0, 280.0),
            water_alpha: 0.8,
            water_repeat: Vec2::new(20.0, 28.0),
            wave_velocity: Vec2::new(-0.02, -0.02),
            camera_start: CameraPose::new(Vec3::new(0.0, 2.5, 10.0), 0.0, 0.0),
            field_of_view_degrees: 45.0,
            near: 0.1,
            far: 500.0,
            sea: true,
        }
    }
}

impl SceneConfig {
    /// World height (y) of a heightmap grey level: `(level + level_offset) * unit_height`.
    pub fn height_of_level(&self, level: f32) -> f32 {
        (level + self.level_offset) * self.unit_height
    }

    /// Grey level whose world height is `height`: the inverse of [`Self::height_of_level`].
    pub fn level_of_height(&self, height: f32) -> f32 {
        height / self.unit_height - self.level_offset
    }

    /// Where the fly camera may go: inside the sky box (1 unit from its walls and ceiling) and
    /// at least 0.2 units above the water and the terrain.
    pub fn camera_limits(&self) -> Limits {
        let half = self.sky_box_size * 0.5;
        Limits {
            min: Vec3::new(-half.x + 1.0, 0.0, -half.z + 1.0),
            max: Vec3::new(half.x - 1.0, self.sky_box_size.y - 1.0, half.z - 1.0),
            clearance: 0.2,
        }
    }

    /// Offset of the water texture at `time_seconds`, in texture repeats, wrapped into [0, 1)
    /// so that it keeps full precision however long the program runs.
    pub fn water_offset(&self, time_seconds: f64) -> Vec2 {
        let wrap = |speed: f32| (f64::from(speed) * time_seconds).rem_euclid(1.0) as f32;
        Vec2::new(wrap(self.wave_velocity.x), wrap(self.wave_velocity.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn course_height_mapping() {
        let config = SceneConfig::default();
        assert!((config.height_of_level(0.0) - -1.5).abs() < 1e-6);
        assert!((config.height_of_level(255.0) - 2.325).abs() < 1e-5);
        assert_eq!(config.height_of_level(100.0), 0.0);
        assert!((config.level_of_height(config.height_of_level(37.5)) - 37.5).abs() < 1e-4);
    }

    #[test]
    fn water_offset_drifts_and_wraps() {
        let config = SceneConfig::default();
        assert_eq!(config.water_offset(0.0), Vec2::ZERO);
        let one = config.water_offset(1.0);
        assert!((one.x - 0.98).abs() < 1e-6 && (one.y - 0.98).abs() < 1e-6);
        // A week of running: still in [0, 1) and equal to the short-time value modulo 1.
        let late_time = 7.0 * 86_400.0 + 1.0;
        let late = config.water_offset(late_time);
        assert!((0.0..1.0).contains(&late.x) && (0.0..1.0).contains(&late.y));
        let exact = (f64::from(config.wave_velocity.x) * late_time).rem_euclid(1.0);
        assert!((f64::from(late.x) - exact).abs() < 1e-6, "{late:?} vs {exact}");
    }
}
