//! The page's options, read from its address (`index.html?seed=3&look=course`): the same
//! choices as `rayterra terrain`'s command line, spelled the same way.

use terrain::camera::{CameraPose, MAX_FIELD_OF_VIEW_DEGREES, MIN_FIELD_OF_VIEW_DEGREES};
use terrain::world::dem::{PlaceOptions, WaterLevel};
use terrain::{Look, SceneConfig};

/// The largest heightmap the page builds a world from (`grid=`, or a file), in samples a side:
/// one thread and a browser tab's memory set the bound, not the engine (whose limit is 8193).
pub const MAX_PAGE_SIDE: u32 = 4097;

/// The largest canvas `size=` may ask for, in pixels a side.
pub const MAX_CANVAS_SIDE: u32 = 4096;

/// Which graphics API the page asks the browser for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BrowserApi {
    /// WebGPU where the browser has it, WebGL2 otherwise.
    Auto,
    /// WebGL2 only, even where WebGPU exists.
    WebGl,
}

/// What the page was asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct PageOptions {
    /// Seed of the procedural world (`seed=N`).
    pub seed: u32,
    /// Samples a side of the procedural heightmap (`grid=N`).
    pub grid: u32,
    /// Where the camera starts (`camera=x,y,z,yaw,pitch`).
    pub pose: CameraPose,
    /// Vertical field of view in degrees (`fov=D`).
    pub field_of_view_degrees: f32,
    /// Scene time at start, in seconds (`time=S`).
    pub start_time_seconds: f64,
    /// Whether the scene's clock stands still (`paused`): the water does not drift.
    pub paused: bool,
    /// The look (`look=modern|course`).
    pub look: Look,
    /// The graphics API (`api=auto|webgl`).
    pub api: BrowserApi,
    /// A fixed canvas size in CSS pixels (`size=WxH`); `None` fills the page.
    pub canvas_size: Option<(u32, u32)>,
    /// How elevation data picked or dropped on the page is placed.
    pub elevation: ElevationOptions,
}

/// How elevation data is placed, as `rayterra terrain`'s options of the same names.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ElevationOptions {
    /// Metres between samples where the file states none (`cell-size=M`; 1 m without it).
    pub cell_size: Option<f64>,
    /// The water level in metres or none (`water-level=M|none`) and the factor on the heights
    /// (`vertical-exaggeration=X`).
    pub place: PlaceOptions,
}

impl Default for PageOptions {
    fn default() -> Self {
        let config = SceneConfig::default();
        Self {
            seed: 1,
            grid: 512,
            pose: config.camera_start,
            field_of_view_degrees: config.field_of_view_degrees,
            start_time_seconds: 0.0,
            paused: false,
            look: Look::Modern,
            api: BrowserApi::Auto,
            canvas_size: None,
            elevation: ElevationOptions::default(),
        }
    }
}

/// An option of the address that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the address's `{name}={value}` {problem}")]
pub struct AddressError {
    /// The option's name.
    pub name: String,
    /// Its value, as given (decoded).
    pub value: String,
    /// What is wrong with it.
    pub problem: String,
}

impl PageOptions {
    /// Reads the options from an address's query (`?a=1&b=2`, with or without the `?`).
    /// Options not given keep their defaults; unknown ones are errors, so a typo is not
    /// silently ignored.
    pub fn from_query(query: &str) -> Result<Self, AddressError> {
        let mut options = Self::default();
        for pair in query.trim_start_matches('?').split('&').filter(|pair| !pair.is_empty()) {
            let (name, value) = pair.split_once('=').unwrap_or((pair, ""));
            let (name, value) = (decode(name), decode(value));
            let error = |problem: String| AddressError { name: name.clone(), value: value.clone(), problem };
            match name.as_str() {
                "seed" => options.seed = value.parse().map_err(|_| error("is not a whole number".into()))?,
                "grid" => {
                    options.grid =
                        value.parse().ok().filter(|grid| (2..=MAX_PAGE_SIDE).contains(grid)).ok_or_else(
                            || error(format!("must be a whole number from 2 to {MAX_PAGE_SIDE}")),
                        )?;
                }
                "camera" => options.pose = value.parse().map_err(|problem| error(format!("{problem}")))?,
                "fov" => {
                    options.field_of_view_degrees = value
                        .parse()
                        .ok()
                        .filter(|degrees| (MIN_FIELD_OF_VIEW_DEGREES..=MAX_FIELD_OF_VIEW_DEGREES).contains(degrees))
                        .ok_or_else(|| {
                            error(format!(
                                "must be a field of view from {MIN_FIELD_OF_VIEW_DEGREES} to {MAX_FIELD_OF_VIEW_DEGREES} degrees"
                            ))
                        })?;
                }
                "time" => {
                    options.start_time_seconds = value
                        .parse()
                        .ok()
                        .filter(|seconds: &f64| seconds.is_finite())
                        .ok_or_else(|| error("is not a number of seconds".into()))?;
                }
                "paused" => {
                    options.paused = match value.as_str() {
                        "" | "1" | "true" | "yes" => true,
                        "0" | "false" | "no" => false,
                        _ => return Err(error("must be 1 or 0".into())),
                    }
                }
                "look" => options.look = value.parse().map_err(error)?,
                "api" => {
                    options.api = match value.to_ascii_lowercase().as_str() {
                        "auto" => BrowserApi::Auto,
                        "webgl" | "webgl2" => BrowserApi::WebGl,
                        _ => return Err(error("must be `auto` or `webgl`".into())),
                    }
                }
                "size" => {
                    let size = value
                        .split_once(['x', 'X'])
                        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
                    options.canvas_size = Some(
                        size.filter(|&(w, h): &(u32, u32)| {
                            (1..=MAX_CANVAS_SIDE).contains(&w) && (1..=MAX_CANVAS_SIDE).contains(&h)
                        })
                        .ok_or_else(|| {
                            error(format!("must be WIDTHxHEIGHT, each 1 to {MAX_CANVAS_SIDE} pixels"))
                        })?,
                    );
                }
                "water-level" => {
                    options.elevation.place.water_level = value.parse::<WaterLevel>().map_err(error)?;
                }
                "vertical-exaggeration" => {
                    options.elevation.place.vertical_exaggeration =
                        positive(&value).ok_or_else(|| error("must be a positive number".into()))?;
                }
                "cell-size" => {
                    options.elevation.cell_size = Some(
                        positive(&value)
                            .ok_or_else(|| error("must be a positive number of metres".into()))?,
                    );
                }
                _ => {
                    return Err(error(
                        "is not an option (expected seed, grid, camera, fov, time, paused, look, api, size, water-level, vertical-exaggeration or cell-size)".into(),
                    ));
                }
            }
        }
        Ok(options)
    }
}

/// A finite number above 0.
fn positive(text: &str) -> Option<f64> {
    text.parse::<f64>().ok().filter(|value| value.is_finite() && *value > 0.0)
}

/// Decodes `%XX` escapes and `+` (a space) of a query's name or value; a malformed escape is
/// kept as it is.
fn decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < bytes.len() => {
                match std::str::from_utf8(&bytes[i + 1..i + 3])
                    .ok()
                    .and_then(|hex| u8::from_str_radix(hex, 16).ok())
                {
                    Some(byte) => {
                        out.push(byte);
                        i += 2;
                    }
                    None => out.push(b'%'),
                }
            }
            byte => out.push(byte),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn defaults_are_the_command_lines() {
        let options = PageOptions::from_query("").expect("empty");
        assert_eq!(options, PageOptions::default());
        assert_eq!(options.seed, 1);
        assert_eq!(options.grid, 512);
        assert_eq!(options.pose, SceneConfig::default().camera_start);
        assert_eq!(options.look, Look::Modern);
    }

    #[test]
    fn every_option_is_read() {
        let options = PageOptions::from_query(
            "?seed=7&grid=257&camera=1,2.5,-3,90,-10&fov=60&time=2.5&paused&look=course&api=webgl&size=640x360",
        )
        .expect("valid");
        assert_eq!(options.seed, 7);
        assert_eq!(options.grid, 257);
        assert_eq!(options.pose, CameraPose::new(Vec3::new(1.0, 2.5, -3.0), 90.0, -10.0));
        assert_eq!(options.field_of_view_degrees, 60.0);
        assert_eq!(options.start_time_seconds, 2.5);
        assert!(options.paused);
        assert_eq!(options.look, Look::Course);
        assert_eq!(options.api, BrowserApi::WebGl);
        assert_eq!(options.canvas_size, Some((640, 360)));
        let options =
            PageOptions::from_query("water-level=-12.5&vertical-exaggeration=3&cell-size=30").expect("valid");
        assert_eq!(options.elevation.place.water_level, WaterLevel::Metres(-12.5));
        assert_eq!(options.elevation.place.vertical_exaggeration, 3.0);
        assert_eq!(options.elevation.cell_size, Some(30.0));
        let options = PageOptions::from_query("water-level=none").expect("valid");
        assert_eq!(options.elevation.place.water_level, WaterLevel::None);
        assert_eq!(PageOptions::default().elevation.place, PlaceOptions::default());
    }

    #[test]
    fn escapes_are_decoded() {
        let options = PageOptions::from_query("camera=0%2C3%2C8%2C0%2C-5").expect("escaped commas");
        assert_eq!(options.pose, CameraPose::new(Vec3::new(0.0, 3.0, 8.0), 0.0, -5.0));
        assert_eq!(decode("a+b%41%zz%4"), "a bA%zz%4");
    }

    #[test]
    fn bad_options_name_themselves() {
        for (query, named) in [
            ("seed=-1", "seed=-1"),
            ("grid=1", "grid=1"),
            ("grid=5000", "grid=5000"),
            ("camera=1,2", "camera=1,2"),
            ("fov=0", "fov=0"),
            ("time=nan", "time=nan"),
            ("look=shiny", "look=shiny"),
            ("api=vulkan", "api=vulkan"),
            ("size=0x10", "size=0x10"),
            ("size=big", "size=big"),
            ("paused=maybe", "paused=maybe"),
            ("sede=3", "sede=3"),
            ("water-level=deep", "water-level=deep"),
            ("vertical-exaggeration=0", "vertical-exaggeration=0"),
            ("cell-size=-2", "cell-size=-2"),
            ("cell-size=inf", "cell-size=inf"),
        ] {
            let error = PageOptions::from_query(query).expect_err(query);
            assert!(error.to_string().contains(&format!("`{named}`")), "{query}: {error}");
        }
    }
}
