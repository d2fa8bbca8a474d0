//! How the engine draws: the look (the course's or the modern one) and every switch and number of
//! the modern look, saved to and loaded from a TOML file (`--settings FILE`).
//!
//! Directions follow the camera's convention (world y-up): an azimuth of 0 degrees points toward
//! -z (ahead at the course's start), 90 toward +x; an elevation is in degrees above the horizon.
//! Colours are RGB in 0..=1, in the same (non-sRGB) values as the textures.
//!
//! Every field has a default, so a file only lists what it changes; unknown keys and values out of
//! range are errors naming the key.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::output::{SaveError, write_file};
use crate::world::atmosphere::{TimeOfDay, solar_position};
use crate::world::splat::GroundLines;

/// Largest settings file read, in bytes (a full one is about 1 KB).
pub const MAX_SETTINGS_BYTES: u64 = 1 << 20;

/// Which look the renderer draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Look {
    /// The course's picture, exactly: textures as they are, the mirrored world under a
    /// translucent sheet of drifting water.
    Course,
    /// Sun light with shadows, fog into the sky, and water that reflects and refracts.
    #[default]
    Modern,
}

impl Look {
    /// Both looks, in the order a help text lists them.
    pub const ALL: [Look; 2] = [Look::Modern, Look::Course];

    /// The name in files and on command lines: `modern` or `course`.
    pub fn name(self) -> &'static str {
        match self {
            Look::Course => "course",
            Look::Modern => "modern",
        }
    }
}

impl std::str::FromStr for Look {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Look::ALL
            .into_iter()
            .find(|look| look.name().eq_ignore_ascii_case(text))
            .ok_or_else(|| format!("unknown look `{text}` (expected `modern` or `course`)"))
    }
}

/// The resolution of the water's reflection, relative to the frame's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReflectionQuality {
    /// No reflection of the land: the water reflects the sky only.
    Off,
    /// A quarter of the frame's width and height.
    Quarter,
    /// Half the frame's width and height.
    #[default]
    Half,
    /// The frame's own resolution.
    Full,
}

impl ReflectionQuality {
    /// Every choice, from the cheapest.
    pub const ALL: [ReflectionQuality; 4] = [
        ReflectionQuality::Off,
        ReflectionQuality::Quarter,
        ReflectionQuality::Half,
        ReflectionQuality::Full,
    ];

    /// The reflection's size as a fraction of the frame's width and height (0 when off).
    pub fn scale(self) -> f32 {
        match self {
            ReflectionQuality::Off => 0.0,
            ReflectionQuality::Quarter => 0.25,
            ReflectionQuality::Half => 0.5,
            ReflectionQuality::Full => 1.0,
        }
    }

    /// The name in files: `off`, `quarter`, `half` or `full`.
    pub fn name(self) -> &'static str {
        match self {
            ReflectionQuality::Off => "off",
            ReflectionQuality::Quarter => "quarter",
            ReflectionQuality::Half => "half",
            ReflectionQuality::Full => "full",
        }
    }
}

/// The sun and the light of the sky (modern look).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SunSettings {
    /// Light the land from the sun and the sky (off: the colour map as it is, unlit).
    pub lighting: bool,
    /// The sun's height above the horizon, in degrees (-10 to 90).
    pub elevation_degrees: f32,
    /// The sun's compass direction, in degrees: 0 toward -z, 90 toward +x.
    pub azimuth_degrees: f32,
    /// A tint on the sun's light, RGB 0..=1 (white: the atmosphere's colour as it is).
    pub colour: [f32; 3],
    /// The exposure of the whole sky and its light (0 to 4; 1 lights a surface facing the sun
    /// above the air with its full albedo).
    pub intensity: f32,
    /// The strength of the light from the sky dome (0 to 2; 1: the atmosphere's as it is).
    pub ambient: f32,
    /// Shadows cast by the land on itself.
    pub shadows: bool,
}

impl Default for SunSettings {
    fn default() -> Self {
        // Where the procedural sky paints its sun (`world::procedural::SUN_DIRECTION`).
        Self {
            lighting: true,
            elevation_degrees: 25.0,
            azimuth_degrees: 305.0,
            colour: [1.0, 1.0, 1.0],
            intensity: 1.15,
            ambient: 1.0,
            shadows: true,
        }
    }
}

impl SunSettings {
    /// Unit vector toward the sun (y-up).
    pub fn direction(&self) -> Vec3 {
        crate::world::atmosphere::sun::direction(self.elevation_degrees, self.azimuth_degrees)
    }
}

/// The time of day and the place, which put the sun in the sky (modern look). Without a time
/// of day the sun stands where [`SunSettings`] puts it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkySettings {
    /// Local solar time (`"HH:MM"`; 12:00 is the sun's highest), or none: the sun's elevation
    /// and azimuth settings.
    pub time_of_day: Option<TimeOfDay>,
    /// The place's latitude in degrees (-90 south to 90 north). The map's north is -z.
    pub latitude_degrees: f32,
    /// The day of the year, 1 (1 January) to 366.
    pub day_of_year: u32,
    /// Whether the day runs (the time of day advances; the window's `T` key switches it).
    pub day_runs: bool,
    /// How fast the day runs, hours of the day per second (0 to 24).
    pub day_hours_per_second: f32,
}

impl Default for SkySettings {
    fn default() -> Self {
        // Midsummer in the middle latitudes.
        Self {
            time_of_day: None,
            latitude_degrees: 45.0,
            day_of_year: 172,
            day_runs: false,
            day_hours_per_second: 0.25,
        }
    }
}

impl SkySettings {
    /// Advances the time of day by `seconds` of real time when the day runs (starting from
    /// noon when no time is set). Returns whether it moved.
    pub fn run(&mut self, seconds: f32) -> bool {
        if !self.day_runs || self.day_hours_per_second <= 0.0 || seconds <= 0.0 {
            return false;
        }
        let now = self.time_of_day.map_or(12.0, TimeOfDay::hours);
        self.time_of_day = Some(TimeOfDay::from_hours(now + seconds * self.day_hours_per_second));
        true
    }
}

/// Aerial perspective: distance and height fog into the sky's colour (modern look).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FogSettings {
    /// Fog on or off (when off the world still meets the sky box without a seam at its walls).
    pub enabled: bool,
    /// Extinction at the water's level, per world unit (0 to 1): the fog hides half of what is
    /// `ln 2 / density` units away.
    pub density: f32,
    /// How fast the fog thins with height, per world unit (0 to 10): at height h it is
    /// `exp(-h * height_falloff)` as dense as at the water.
    pub height_falloff: f32,
}

impl Default for FogSettings {
    fn default() -> Self {
        Self { enabled: true, density: 0.025, height_falloff: 0.35 }
    }
}

/// The water's surface (modern look).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WaterSettings {
    /// The colour of deep water, RGB 0..=1 (what light scattered inside the water looks like).
    pub colour: [f32; 3],
    /// The depth, in world units, at which the sea floor fades to half its colour (0.01 to 10).
    pub clarity: f32,
    /// The waves' drift as a multiple of the course's speed (0 to 10).
    pub wave_speed: f32,
    /// The waves' size: world units one tile of the wave normal map spans (0.1 to 20).
    pub wave_scale: f32,
    /// How much the waves tilt the surface (0 to 2).
    pub wave_strength: f32,
    /// The resolution of the land's reflection.
    pub reflection: ReflectionQuality,
    /// The sea floor seen through shallow water (off: the water's colour only).
    pub refraction: bool,
    /// The sun's glint on the waves.
    pub glint: bool,
    /// Foam where the water meets the shore.
    pub foam: bool,
}

impl Default for WaterSettings {
    fn default() -> Self {
        Self {
            colour: [0.06, 0.22, 0.30],
            clarity: 0.35,
            wave_speed: 1.0,
            wave_scale: 2.0,
            wave_strength: 0.6,
            reflection: ReflectionQuality::Half,
            refraction: true,
            glint: true,
            foam: true,
        }
    }
}

/// The land's geometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TerrainSettings {
    /// The largest error, in pixels, the level of detail may put on screen (0.5 to 16; the
    /// course look's default, 2, keeps its picture exactly).
    pub lod_error_pixels: f32,
    /// Draw the triangles' edges instead of their faces (where the GPU can).
    pub wireframe: bool,
}

impl Default for TerrainSettings {
    fn default() -> Self {
        Self { lod_error_pixels: 2.0, wireframe: false }
    }
}

/// The ground's materials (modern look): rock on cliffs, scree below them, grass and soil on
/// gentle slopes (the colour map's colours, darker soil where water gathers), sand on the shores
/// and snow high up, chosen by slope, height, curvature, aspect and the erosion's flow, blended by
/// their own relief and projected from three sides where the ground is steep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GroundSettings {
    /// Materials from the land's shape (off: the colour map with the detail map, as before).
    pub materials: bool,
    /// The slope in degrees where bare rock takes over (10 to 80).
    pub rock_slope_degrees: f32,
    /// The snow line, as a fraction of the land's highest point above the water (0 to 1.5; over
    /// 1, no snow). Lower on slopes facing north (-z), none on the steepest.
    pub snow_line: f32,
    /// How high above the water the shore's sand reaches, as a fraction of the land's highest
    /// point (0 to 0.5).
    pub sand_line: f32,
    /// The strength of the materials' relief on the light (detail normals, 0 to 2).
    pub detail: f32,
    /// The size of the materials' grain: world units one tile of their texture spans, as a
    /// fraction of the terrain's side (0.002 to 0.5).
    pub texture_size: f32,
}

impl GroundSettings {
    /// Where the materials start in a scene laid out by `config`, in world units.
    pub fn lines(&self, config: &crate::config::SceneConfig) -> GroundLines {
        GroundLines::new(self.rock_slope_degrees, self.snow_line, self.sand_line, config)
    }
}

impl Default for GroundSettings {
    fn default() -> Self {
        Self {
            materials: true,
            rock_slope_degrees: 38.0,
            snow_line: 0.72,
            sand_line: 0.035,
            detail: 1.0,
            texture_size: 0.03,
        }
    }
}

/// A camera and a time, saved so that a screenshot can be taken again exactly. Every key is
/// optional: a missing one takes the course's start (see [`Default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ViewSettings {
    /// The camera's position x, y, z in world units.
    pub position: [f32; 3],
    /// Yaw in degrees (0 toward -z, 90 toward +x).
    pub yaw_degrees: f32,
    /// Pitch in degrees (positive looks up).
    pub pitch_degrees: f32,
    /// Vertical field of view in degrees.
    pub field_of_view_degrees: f32,
    /// Scene time in seconds.
    pub time_seconds: f64,
}

impl Default for ViewSettings {
    /// The course's start ([`crate::SceneConfig`]'s `camera_start`), a field of view of 45
    /// degrees and time 0: what `--screenshot` draws without a view.
    fn default() -> Self {
        let start = crate::config::SceneConfig::default().camera_start;
        Self {
            position: start.position.to_array(),
            yaw_degrees: start.yaw_degrees,
            pitch_degrees: start.pitch_degrees,
            field_of_view_degrees: 45.0,
            time_seconds: 0.0,
        }
    }
}

impl ViewSettings {
    /// A fly camera (with the default motion) at the pose and field of view it keeps.
    pub fn camera(&self) -> crate::camera::FlyCamera {
        use crate::camera::{CameraPose, FlyCamera, MotionSettings};
        let pose = CameraPose::new(self.position.into(), self.yaw_degrees, self.pitch_degrees);
        FlyCamera::new(pose, self.field_of_view_degrees, MotionSettings::default())
    }
}

/// Everything that sets how a frame looks, apart from the world and the camera.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The look.
    pub look: Look,
    /// The sun and the sky's light.
    pub sun: SunSettings,
    /// The time of day and the place (the sun's position when a time is set).
    pub sky: SkySettings,
    /// The fog.
    pub fog: FogSettings,
    /// The water.
    pub water: WaterSettings,
    /// The land's geometry.
    pub terrain: TerrainSettings,
    /// The ground's materials.
    pub ground: GroundSettings,
    /// A saved camera and time (written by the window's panel; `--screenshot` uses it unless
    /// the command line gives its own).
    pub view: Option<ViewSettings>,
}

/// Why settings could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is not valid TOML or has unknown keys or wrong types.
    #[error("{}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// What the parser said, with the line and column.
        message: String,
    },
    /// A value is out of its range.
    #[error(
        "{}{}: `{key}` is {value}, it must be between {min} and {max}",
        path.display(),
        line.map_or_else(String::new, |line| format!(":{line}"))
    )]
    Range {
        /// The file.
        path: PathBuf,
        /// The 1-based line of the value in the file, when it can be found.
        line: Option<usize>,
        /// The key, e.g. `fog.density`.
        key: &'static str,
        /// The value found.
        value: f64,
        /// The smallest value allowed.
        min: f64,
        /// The largest value allowed.
        max: f64,
    },
}

impl Settings {
    /// The course's look (everything else at its default).
    pub fn course() -> Self {
        Self { look: Look::Course, ..Self::default() }
    }

    /// Unit vector toward the sun (y-up): from the time of day, latitude and day of the year
    /// when a time is set, else from the sun's elevation and azimuth.
    pub fn sun_direction(&self) -> Vec3 {
        match self.sky.time_of_day {
            Some(time) => solar_position(time, self.sky.latitude_degrees, self.sky.day_of_year).direction(),
            None => self.sun.direction(),
        }
    }

    /// Every number with its key and allowed range, for checking and for the panel.
    pub fn ranges(&self) -> Vec<(&'static str, f64, f64, f64)> {
        let f = f64::from;
        let mut ranges = vec![
            ("sun.elevation_degrees", f(self.sun.elevation_degrees), -10.0, 90.0),
            ("sun.azimuth_degrees", f(self.sun.azimuth_degrees), -360.0, 720.0),
            ("sun.intensity", f(self.sun.intensity), 0.0, 4.0),
            ("sun.ambient", f(self.sun.ambient), 0.0, 2.0),
            ("sky.latitude_degrees", f(self.sky.latitude_degrees), -90.0, 90.0),
            ("sky.day_of_year", f64::from(self.sky.day_of_year), 1.0, 366.0),
            ("sky.day_hours_per_second", f(self.sky.day_hours_per_second), 0.0, 24.0),
            ("fog.density", f(self.fog.density), 0.0, 1.0),
            ("fog.height_falloff", f(self.fog.height_falloff), 0.0, 10.0),
            ("water.clarity", f(self.water.clarity), 0.01, 10.0),
            ("water.wave_speed", f(self.water.wave_speed), 0.0, 10.0),
            ("water.wave_scale", f(self.water.wave_scale), 0.1, 20.0),
            ("water.wave_strength", f(self.water.wave_strength), 0.0, 2.0),
            ("terrain.lod_error_pixels", f(self.terrain.lod_error_pixels), 0.5, 16.0),
            ("ground.rock_slope_degrees", f(self.ground.rock_slope_degrees), 10.0, 80.0),
            ("ground.snow_line", f(self.ground.snow_line), 0.0, 1.5),
            ("ground.sand_line", f(self.ground.sand_line), 0.0, 0.5),
            ("ground.detail", f(self.ground.detail), 0.0, 2.0),
            ("ground.texture_size", f(self.ground.texture_size), 0.002, 0.5),
        ];
        let colour_keys = [
            ["sun.colour[0]", "sun.colour[1]", "sun.colour[2]"],
            ["water.colour[0]", "water.colour[1]", "water.colour[2]"],
        ];
        for (keys, colour) in colour_keys.iter().zip([self.sun.colour, self.water.colour]) {
            for (key, value) in keys.iter().zip(colour) {
                ranges.push((key, f(value), 0.0, 1.0));
            }
        }
        if let Some(view) = &self.view {
            for (key, value) in
                ["view.position[0]", "view.position[1]", "view.position[2]"].iter().zip(view.position)
            {
                ranges.push((key, f(value), -1e6, 1e6));
            }
            ranges.push(("view.yaw_degrees", f(view.yaw_degrees), -1e6, 1e6));
            ranges.push(("view.pitch_degrees", f(view.pitch_degrees), -89.0, 89.0));
            ranges.push(("view.field_of_view_degrees", f(view.field_of_view_degrees), 1.0, 90.0));
            ranges.push(("view.time_seconds", view.time_seconds, -1e9, 1e9));
        }
        ranges
    }

    /// Parses settings from TOML `text`; `path` names the source in errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SettingsError> {
        let settings: Settings = toml::from_str(text).map_err(|error| SettingsError::Syntax {
            path: path.to_path_buf(),
            message: error.to_string(),
        })?;
        for (key, value, min, max) in settings.ranges() {
            if !(min..=max).contains(&value) {
                let line = line_of_key(text, key);
                return Err(SettingsError::Range { path: path.to_path_buf(), line, key, value, min, max });
            }
        }
        Ok(settings)
    }

    /// The settings as TOML text, every key written out.
    pub fn to_toml(&self) -> String {
        // Serialising plain numbers, booleans and strings cannot fail.
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads settings from a TOML file (a regular file of at most [`MAX_SETTINGS_BYTES`]).
    pub fn load(path: &Path) -> Result<Self, SettingsError> {
        let read_error = |source| SettingsError::Read { path: path.to_path_buf(), source };
        // Never waits on a named pipe; a folder or device is refused.
        let file = atomic_file::open_regular(path).map_err(read_error)?;
        let metadata = file.metadata().map_err(read_error)?;
        if metadata.len() > MAX_SETTINGS_BYTES {
            return Err(read_error(std::io::Error::other(format!(
                "{} bytes is too large for a settings file (at most {MAX_SETTINGS_BYTES})",
                metadata.len()
            ))));
        }
        let mut text = String::new();
        std::io::Read::read_to_string(&mut std::io::Read::take(file, MAX_SETTINGS_BYTES + 1), &mut text)
            .map_err(read_error)?;
        Self::from_toml(&text, path)
    }

    /// Writes the settings to a TOML file, whole or not at all.
    pub fn save(&self, path: &Path) -> Result<(), SaveError> {
        let text =
            format!("# rayterra terrain settings (rayterra terrain --settings FILE)\n{}", self.to_toml());
        write_file(path, text.as_bytes())
    }
}

/// The 1-based line of the value of `key` (`fog.density`, `sun.colour[2]`) in the TOML `text`,
/// wherever the file puts it (a table, a dotted key, an inline table).
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let (names, index) = match key.split_once('[') {
        Some((names, rest)) => (names, rest.trim_end_matches(']').parse::<usize>().ok()),
        None => (key, None),
    };
    let root = DeTable::parse(text).ok()?;
    let mut table = root.get_ref();
    let mut found = None;
    let mut parts = names.split('.').peekable();
    while let Some(part) = parts.next() {
        let value = table.iter().find(|(k, _)| k.get_ref().as_ref() == part).map(|(_, v)| v)?;
        if parts.peek().is_none() {
            found = Some(value);
        } else if let DeValue::Table(inner) = value.get_ref() {
            table = inner;
        } else {
            return None;
        }
    }
    let mut span = found?.span();
    if let (Some(i), Some(DeValue::Array(items))) = (index, found.map(|v| v.get_ref())) {
        span = items.get(i)?.span();
    }
    Some(text.get(..span.start)?.matches('\n').count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_toml() {
        let mut settings = Settings { look: Look::Course, ..Settings::default() };
        settings.sun.elevation_degrees = 4.5;
        settings.water.reflection = ReflectionQuality::Quarter;
        settings.view = Some(ViewSettings {
            position: [1.0, 2.0, 3.0],
            yaw_degrees: 10.0,
            pitch_degrees: -5.0,
            field_of_view_degrees: 50.0,
            time_seconds: 12.25,
        });
        let text = settings.to_toml();
        assert!(text.contains("look = \"course\""), "{text}");
        assert_eq!(Settings::from_toml(&text, Path::new("a.toml")).expect("valid"), settings);
    }

    /// Issue 31, defect 7: every key is optional, within `[view]` too.
    #[test]
    fn a_view_lists_only_what_it_changes() {
        let settings =
            Settings::from_toml("[view]\ntime_seconds = 3.0\n", Path::new("v.toml")).expect("valid");
        let view = settings.view.expect("a view");
        assert_eq!(view.time_seconds, 3.0);
        assert_eq!(ViewSettings { time_seconds: 0.0, ..view.clone() }, ViewSettings::default());
        assert_eq!(view.position, [0.0, 2.5, 10.0]);
        assert_eq!(view.field_of_view_degrees, 45.0);
        let settings = Settings::from_toml("[view]\n", Path::new("v.toml")).expect("valid");
        assert_eq!(settings.view, Some(ViewSettings::default()));
    }

    #[test]
    fn a_file_lists_only_what_it_changes() {
        let text = "look = \"modern\"\n[fog]\ndensity = 0.1\n";
        let settings = Settings::from_toml(text, Path::new("a.toml")).expect("valid");
        assert_eq!(settings.fog.density, 0.1);
        assert_eq!(settings.sun, SunSettings::default());
        assert_eq!(Settings::from_toml("", Path::new("a.toml")).expect("valid"), Settings::default());
    }

    #[test]
    fn errors_name_the_file_the_key_and_the_place() {
        let error =
            Settings::from_toml("[fog]\ndensty = 0.1\n", Path::new("my.toml")).expect_err("unknown key");
        let text = error.to_string();
        assert!(text.contains("my.toml") && text.contains("densty") && text.contains("line 2"), "{text}");
        let error = Settings::from_toml("[fog]\ndensity = 7\n", Path::new("my.toml")).expect_err("range");
        assert!(error.to_string().contains("`fog.density` is 7"), "{error}");
        // Issue 31, defect 7: out-of-range values name their line, wherever they are written.
        assert!(error.to_string().starts_with("my.toml:2: "), "{error}");
        for (text, line) in [
            ("look = \"modern\"\n\n[sun]\nintensity = 1\nelevation_degrees = 95\n", 5),
            ("sun.elevation_degrees = -40\n", 1),
            ("[water]\ncolour = [\n  0.1,\n  0.2,\n  1.5,\n]\n", 5),
            ("[view]\nfield_of_view_degrees = 120\n", 2),
        ] {
            let error = Settings::from_toml(text, Path::new("r.toml")).expect_err("range").to_string();
            assert!(error.starts_with(&format!("r.toml:{line}: ")), "{text}: {error}");
        }
        let error = Settings::from_toml("look = \"fancy\"\n", Path::new("my.toml")).expect_err("bad look");
        assert!(error.to_string().contains("fancy"), "{error}");
        let error = Settings::from_toml("[water]\ncolour = [0.1, 0.2, 1.5]\n", Path::new("w.toml"))
            .expect_err("colour out of range");
        assert!(error.to_string().contains("water.colour[2]"), "{error}");
    }

    #[test]
    fn folders_devices_and_huge_files_are_refused_before_reading() {
        let error = Settings::load(&std::env::temp_dir()).expect_err("a folder").to_string();
        assert!(error.contains("it is a directory"), "{error}");
        if Path::new("/dev/zero").exists() {
            let error = Settings::load(Path::new("/dev/zero")).expect_err("a device").to_string();
            assert!(error.contains("/dev/zero") && error.contains("not a regular file"), "{error}");
        }
        let path = std::env::temp_dir().join(format!("rayterra-huge-settings-{}.toml", std::process::id()));
        let file = std::fs::File::create(&path).expect("temp file");
        file.set_len(MAX_SETTINGS_BYTES + 1).expect("sparse file");
        let error = Settings::load(&path).expect_err("too large").to_string();
        let _ = std::fs::remove_file(&path);
        assert!(error.contains("too large"), "{error}");
    }

    #[test]
    fn the_default_sun_is_where_the_procedural_sky_paints_it() {
        let painted = Vec3::from_array(crate::world::procedural::SUN_DIRECTION.map(|c| c as f32)).normalize();
        let sun = SunSettings::default().direction();
        assert!(sun.dot(painted) > 0.9999, "{sun} vs {painted}");
        // Azimuth 90 points toward +x, like a yaw of 90.
        let east = SunSettings { azimuth_degrees: 90.0, elevation_degrees: 0.0, ..SunSettings::default() };
        assert!((east.direction() - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn a_time_of_day_places_the_sun() {
        let text = "[sky]\ntime_of_day = \"12:00\"\nlatitude_degrees = 40.0\nday_of_year = 80\n";
        let settings = Settings::from_toml(text, Path::new("s.toml")).expect("valid");
        let elevation = settings.sun_direction().y.asin().to_degrees();
        assert!((elevation - 50.0).abs() < 1.0, "{elevation}");
        // Without a time, the sun's own elevation and azimuth.
        assert_eq!(Settings::default().sun_direction(), SunSettings::default().direction());
        // Round trip, and errors naming the file and the value.
        assert_eq!(Settings::from_toml(&settings.to_toml(), Path::new("s.toml")).expect("valid"), settings);
        let error = Settings::from_toml("[sky]\ntime_of_day = \"25:00\"\n", Path::new("t.toml"))
            .expect_err("bad time")
            .to_string();
        assert!(error.contains("t.toml") && error.contains("25:00"), "{error}");
        let error = Settings::from_toml("[sky]\nlatitude_degrees = 95\n", Path::new("t.toml"))
            .expect_err("bad latitude")
            .to_string();
        assert!(error.starts_with("t.toml:2: ") && error.contains("sky.latitude_degrees"), "{error}");
        // A running day advances the clock, wrapping at midnight.
        let mut sky = SkySettings { day_runs: true, day_hours_per_second: 2.0, ..SkySettings::default() };
        assert!(sky.run(1.0));
        assert_eq!(sky.time_of_day.map(|t| t.to_string()), Some("14:00".to_string()));
        assert!(sky.run(5.0));
        assert_eq!(sky.time_of_day.map(|t| t.to_string()), Some("00:00".to_string()));
        sky.day_runs = false;
        assert!(!sky.run(1.0));
    }

    #[test]
    fn saves_whole_files() {
        let dir = std::env::temp_dir().join(format!("rayterra-settings-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("s.toml");
        let settings = Settings { look: Look::Course, ..Settings::default() };
        settings.save(&path).expect("writable");
        assert_eq!(Settings::load(&path).expect("readable"), settings);
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 1, "a temporary file was left");
        let error = Settings::load(&dir.join("missing.toml")).expect_err("missing");
        assert!(error.to_string().contains("missing.toml"), "{error}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
