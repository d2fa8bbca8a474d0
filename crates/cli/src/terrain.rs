//! `rayterra terrain`: the terrain engine's command (window and off-screen screenshot).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use terrain::camera::{CameraPose, MAX_FIELD_OF_VIEW_DEGREES, MIN_FIELD_OF_VIEW_DEGREES};
use terrain::controls;
use terrain::headless::HeadlessRenderer;
use terrain::render::{Backend, FrameView, Gpu, GpuMemory};
use terrain::window::{self, Notice, WindowOptions};
use terrain::world::atmosphere::TimeOfDay;
use terrain::world::dem::{self, WaterLevel};
use terrain::world::erosion::{self, ErosionParams};
use terrain::world::procedural::{self, ProceduralOptions, Progress, Stage};
use terrain::world::{self as terrain_world, Heightmap, World};
use terrain::{Look, SceneConfig, Settings};

/// Largest accepted side of `--size`, in pixels (GPUs may allow less; that is checked too).
const MAX_SIDE: u32 = 16_384;

/// The largest `--grid` the island is eroded at without `--erode` (larger ones would hold up
/// the start: about 50 s at 4097 samples on two cores, 3 s at 1025).
const DEFAULT_EROSION_MAX_SIDE: u32 = 1025;

/// Where the window's panel saves its settings without `--settings`.
const DEFAULT_SETTINGS_FILE: &str = "rayterra-terrain.toml";

/// The help text after the options: the window's controls and examples.
fn after_help() -> String {
    format!(
        "Controls:\n{}\nExamples:\n  rayterra terrain\n  rayterra terrain --seed 3\n  \
         rayterra terrain --assets ../shared/course-assets/terrain\n  rayterra terrain --heightmap dem.png\n  \
         rayterra terrain --heightmap N42E001.hgt --water-level 1500\n  \
         rayterra terrain --screenshot island.png --size 1280x720 --camera 0,2.5,10,0,0 --time 3\n  \
         rayterra terrain --look course\n  rayterra terrain --no-erode --seed 2\n  \
         rayterra terrain export --heightmap island.tif --splat island-splat.png\n  \
         rayterra terrain --heightmap dem.tif --erode 2 export --heightmap eroded.tif\n  rayterra terrain --settings sunset.toml --screenshot sunset.png",
        controls::help()
    )
}

/// Arguments of `rayterra terrain`. With no options it opens a window on the built-in procedural
/// island; the controls are listed in the help text.
#[derive(Debug, clap::Args)]
#[command(after_help = after_help())]
pub struct TerrainArgs {
    /// Load the world from a folder laid out like the course's: heightmap.bmp,
    /// terrain-texture3.bmp, detail.bmp and SkyBox0.bmp..SkyBox5.bmp (four sky walls, the sky
    /// top, the water texture).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["heightmap", "seed", "grid"])]
    assets: Option<PathBuf>,

    /// Use this heightmap, with a colour map painted from its heights and the default sky, detail
    /// and water: elevation data in metres (GeoTIFF, SRTM .hgt, Esri ASCII grid, OpenEXR; see
    /// docs/terrain-elevation.md) or a greyscale image (8- or 16-bit PNG, BMP, ...) laid out as the
    /// course's. The format is recognised from the content; 2 to 8193 samples a side.
    #[arg(long, value_name = "FILE", conflicts_with = "grid")]
    heightmap: Option<PathBuf>,

    /// Metres between samples of elevation data whose file does not say (an OpenEXR image, an
    /// ASCII grid or TIFF without geographic tags). Default: 1.
    #[arg(long, value_name = "METRES", value_parser = parse_positive)]
    cell_size: Option<f64>,

    /// Factor on the heights of elevation data (1 keeps the true proportions).
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = parse_positive)]
    vertical_exaggeration: f64,

    /// Water level of elevation data in metres, or `none` for no water. Land wholly above it has
    /// no sea. Default: 0 (sea level).
    #[arg(long, value_name = "METRES|none", allow_hyphen_values = true)]
    water_level: Option<WaterLevel>,

    /// Downsample elevation data larger than N samples a side to N (2 to 8193); without it larger
    /// data is refused before it is decoded.
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u32).range(2..=i64::from(terrain_world::MAX_HEIGHTMAP_SIDE)))]
    max_size: Option<u32>,

    /// Erode the heights before drawing them (any heightmap: the procedural island, an image or
    /// elevation data): water droplets carve valleys and channels and leave sediment (rivers end
    /// at the sea), then steep slopes slide to the talus angle. STRENGTH (0 to 10) is the
    /// droplets a sample; 0 turns erosion off. The --seed seeds the droplets. Default: 4 for the
    /// procedural island in the modern look up to --grid 1025, no erosion for a --heightmap, the
    /// course look or a larger island.
    #[arg(long, value_name = "STRENGTH", value_parser = parse_strength, conflicts_with = "assets",
          allow_hyphen_values = true)]
    erode: Option<f32>,

    /// Do not erode the procedural island (the same as --erode 0).
    #[arg(long, conflicts_with = "erode")]
    no_erode: bool,

    /// Write the heights (eroded) to FILE and exit; the same as `export --heightmap FILE`.
    #[arg(long, value_name = "OUT.tif|OUT.png", conflicts_with = "screenshot")]
    export_heightmap: Option<PathBuf>,

    /// Seed of the procedural world: the same seed always gives the same island, textures and sky.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u32,

    /// Samples per side of the procedural island's heightmap (2 to 8193).
    #[arg(long, value_name = "N", default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(2..=i64::from(terrain_world::MAX_HEIGHTMAP_SIDE)))]
    grid: u32,

    /// Render one frame off-screen into this image (.png, .bmp or .jpg) and exit: no window and no
    /// display needed.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,

    /// Size of the screenshot, or of the window, in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = parse_size)]
    size: (u32, u32),

    /// Camera pose: position x,y,z in world units (y is up, the water is y = 0, the island spans
    /// -10..10 in x and z), then yaw and pitch in degrees (yaw 0 looks toward -z, 90 toward +x;
    /// positive pitch looks up). Default: 0,2.5,10,0,0.
    #[arg(long, value_name = "x,y,z,yaw,pitch", allow_hyphen_values = true,
          value_parser = parse_pose)]
    camera: Option<CameraPose>,

    /// Vertical field of view in degrees (1 to 90). Default: 45 (or the settings file's view).
    #[arg(long, value_name = "DEGREES", value_parser = parse_fov)]
    fov: Option<f32>,

    /// Scene time in seconds: where the drifting water is (the window's clock starts there).
    /// Default: 0 (or the settings file's view).
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = parse_time)]
    time: Option<f64>,

    /// The look: `modern` (sun, shadows, fog, reflecting and refracting water; the default) or
    /// `course` (the course's picture, exactly). Overrides the settings file's.
    #[arg(long, value_name = "LOOK", value_parser = parse_look)]
    look: Option<Look>,

    /// Time of day, local solar time HH:MM (12:00: the sun at its highest), modern look: puts
    /// the sun in the sky for --latitude and --day-of-year, and the sky, the light and the fog
    /// follow it (dawn, noon, dusk, night). Overrides the settings file's `[sky]`.
    #[arg(long, value_name = "HH:MM", value_parser = parse_time_of_day)]
    time_of_day: Option<TimeOfDay>,

    /// Latitude of the place in degrees (-90 south to 90 north; the map's north is -z), with
    /// --time-of-day. Default: 45 (or the settings file's).
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_latitude)]
    latitude: Option<f32>,

    /// Day of the year (1 = 1 January, to 366), with --time-of-day. Default: 172 (21 June).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=366))]
    day_of_year: Option<u32>,

    /// The sun's elevation in degrees above the horizon (-10 to 90), instead of a time of day.
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_sun_elevation)]
    sun_elevation: Option<f32>,

    /// The sun's compass azimuth in degrees (0 toward -z, 90 toward +x), instead of a time of day.
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_sun_azimuth)]
    sun_azimuth: Option<f32>,

    /// Settings file (TOML): the look and every tunable of the modern look, and optionally a
    /// camera and time. Read at start; the window's panel (F1) saves to it. `--screenshot`
    /// renders with it (the command line's --camera, --fov, --time and --look win).
    #[arg(long, value_name = "FILE")]
    settings: Option<PathBuf>,

    /// Graphics backend (the chosen adapter is printed).
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,

    /// Close the window by itself after drawing N frames (for tests and demos).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,

    /// Draw as fast as possible instead of waiting for the display's refresh.
    #[arg(long)]
    no_vsync: bool,

    /// Write the world's images into DIR as a course asset folder (8-bit heightmap, BMP files),
    /// to inspect or edit them and load them again with --assets, then exit.
    #[arg(long, value_name = "DIR", conflicts_with = "screenshot")]
    export_assets: Option<PathBuf>,

    /// What to do instead of opening a window.
    #[command(subcommand)]
    command: Option<TerrainCommand>,
}

/// `rayterra terrain`'s subcommands.
#[derive(Debug, clap::Subcommand)]
enum TerrainCommand {
    /// Write the world's (eroded) heights and its ground materials' weights for other tools, and
    /// exit: no window, no GPU. The world options (--heightmap FILE, --seed, --grid, --erode,
    /// --settings, ...) go before `export`.
    #[command(
        after_help = "Examples:\n  rayterra terrain export --heightmap island.tif --splat island.png\n  \
         rayterra terrain --heightmap dem.tif --erode 2 export --heightmap eroded.png"
    )]
    Export(ExportArgs),
}

/// Arguments of `rayterra terrain export`.
#[derive(Debug, clap::Args)]
#[command(group = clap::ArgGroup::new("outputs").required(true).multiple(true))]
struct ExportArgs {
    /// Write the heights to this file: .tif as 32-bit float samples (metres for elevation data,
    /// world units otherwise) or .png as 16-bit grey (which --heightmap reads back as the same
    /// heights). Row 0 is the far (-z, north) row.
    #[arg(long, value_name = "OUT.tif|OUT.png", group = "outputs")]
    heightmap: Option<PathBuf>,

    /// Write the ground materials' weights (those the modern look draws) as 8-bit RGBA PNG: OUT.png
    /// holds rock, scree, grass and sand in red, green, blue and alpha, OUT_1.png snow in red;
    /// one pixel a height sample, the eight bytes of a pixel summing to 255.
    #[arg(long, value_name = "OUT.png", group = "outputs")]
    splat: Option<PathBuf>,
}

/// The graphics backends on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum BackendArg {
    /// The platform's primary API (Vulkan on Linux and Windows, Metal on macOS).
    Auto,
    /// Vulkan (without a GPU on Linux: Mesa's lavapipe).
    Vulkan,
    /// OpenGL through EGL (without a GPU on Linux: Mesa's llvmpipe).
    Gl,
    /// Metal (macOS).
    Metal,
    /// Direct3D 12 (Windows).
    Dx12,
}

impl From<BackendArg> for Backend {
    fn from(arg: BackendArg) -> Self {
        match arg {
            BackendArg::Auto => Backend::Auto,
            BackendArg::Vulkan => Backend::Vulkan,
            BackendArg::Gl => Backend::Gl,
            BackendArg::Metal => Backend::Metal,
            BackendArg::Dx12 => Backend::Dx12,
        }
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    crate::size::parse_size(text, MAX_SIDE)
}

fn parse_positive(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|value| value.is_finite() && *value > 0.0)
        .ok_or_else(|| format!("`{text}` is not a positive number"))
}

fn parse_strength(text: &str) -> Result<f32, String> {
    let strength: f32 = text.parse().map_err(|_| format!("`{text}` is not a number"))?;
    if strength == 0.0 {
        return Ok(0.0);
    }
    ErosionParams::with_strength(strength, 0).map(|_| strength).map_err(|_| {
        format!("{text} is out of range: the strength must be 0 (no erosion) to {}", erosion::MAX_STRENGTH)
    })
}

fn parse_look(text: &str) -> Result<Look, String> {
    text.parse()
}

fn parse_time_of_day(text: &str) -> Result<TimeOfDay, String> {
    text.parse()
}

/// A number of degrees within `min..=max`, for `what`.
fn parse_degrees(text: &str, what: &str, min: f32, max: f32) -> Result<f32, String> {
    let degrees: f32 = text.parse().map_err(|_| format!("`{text}` is not a number"))?;
    if (min..=max).contains(&degrees) {
        Ok(degrees)
    } else {
        Err(format!("{degrees} degrees is out of range: the {what} must be between {min} and {max}"))
    }
}

fn parse_latitude(text: &str) -> Result<f32, String> {
    parse_degrees(text, "latitude", -90.0, 90.0)
}

fn parse_sun_elevation(text: &str) -> Result<f32, String> {
    parse_degrees(text, "sun's elevation", -10.0, 90.0)
}

fn parse_sun_azimuth(text: &str) -> Result<f32, String> {
    parse_degrees(text, "sun's azimuth", -360.0, 720.0)
}

fn parse_pose(text: &str) -> Result<CameraPose, String> {
    text.parse().map_err(|error| format!("{error}"))
}

fn parse_fov(text: &str) -> Result<f32, String> {
    let degrees: f32 = text.parse().map_err(|_| format!("`{text}` is not a number"))?;
    if (MIN_FIELD_OF_VIEW_DEGREES..=MAX_FIELD_OF_VIEW_DEGREES).contains(&degrees) {
        Ok(degrees)
    } else {
        Err(format!(
            "{degrees} degrees is out of range: the field of view must be between {MIN_FIELD_OF_VIEW_DEGREES} and {MAX_FIELD_OF_VIEW_DEGREES}"
        ))
    }
}

fn parse_time(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|seconds| seconds.is_finite())
        .ok_or_else(|| format!("`{text}` is not a finite number of seconds"))
}

/// Runs `rayterra terrain`.
pub fn run(args: TerrainArgs) -> Result<(), ExitCode> {
    terrain::heap::keep_freed_memory();
    execute(args).map_err(|message| {
        errln!("error: {message}");
        ExitCode::FAILURE
    })
}

fn execute(args: TerrainArgs) -> Result<(), String> {
    let export = export_outputs(&args)?;
    let windowed = args.screenshot.is_none() && args.export_assets.is_none() && export.is_none();
    // Say so before any work when there is nowhere to open the window.
    if windowed && !window::display_available() {
        return Err(no_display_message("neither DISPLAY nor WAYLAND_DISPLAY is set"));
    }
    if let Some(out) = &args.screenshot {
        // Refuse an unwritable format or folder before any work.
        terrain::output::check_output(out).map_err(|error| error.to_string())?;
    }
    let settings = load_settings(&args)?;
    let (world, config) = load_world(&args, erosion_strength(&args, settings.look))?;
    if let Some(export) = export {
        return write_exports(&export, &world, &config, &settings);
    }
    if let Some(dir) = &args.export_assets {
        let written = terrain_world::export::save_course_folder(&world, dir).map_err(|e| e.to_string())?;
        outln!("wrote {} files to {}", written.len(), dir.display());
        return Ok(());
    }
    let heightmap_bytes = world.heightmap.levels().len() * world.heightmap.bytes_per_sample();
    errln!(
        "memory (CPU): world {} (heightmap {}, {} bytes a sample; images {})",
        megabytes(world.memory_bytes() as u64),
        megabytes(heightmap_bytes as u64),
        world.heightmap.bytes_per_sample(),
        megabytes((world.memory_bytes() - heightmap_bytes) as u64),
    );
    // The command line's view, then the settings file's, then the course's start.
    let saved = settings.view.as_ref();
    let pose = args.camera.unwrap_or_else(|| {
        saved.map_or(config.camera_start, |v| {
            CameraPose::new(v.position.into(), v.yaw_degrees, v.pitch_degrees)
        })
    });
    let source = if args.camera.is_some() { "--camera" } else { "the settings file's view" };
    let pose = keep_camera_inside(pose, &world, &config, source);
    let view = FrameView {
        pose,
        field_of_view_degrees: args.fov.or(saved.map(|v| v.field_of_view_degrees)).unwrap_or(45.0),
        time_seconds: args.time.or(saved.map(|v| v.time_seconds)).unwrap_or(0.0),
    };
    match &args.screenshot {
        Some(out) => screenshot(&args, &world, &config, &settings, &view, out),
        None => open_window(&args, &world, &config, settings, &view),
    }
}

/// What `export` (or `--export-heightmap`) writes.
struct Exports {
    /// The heights' file.
    heightmap: Option<PathBuf>,
    /// The splat map's first file (the second is named from it).
    splat: Option<PathBuf>,
}

/// The files to export, if any, each checked (format, folder) before any work.
fn export_outputs(args: &TerrainArgs) -> Result<Option<Exports>, String> {
    let (heightmap, splat) = match &args.command {
        Some(TerrainCommand::Export(export)) => {
            if args.export_heightmap.is_some() && export.heightmap.is_some() {
                return Err("give the heights' file once: --export-heightmap or export --heightmap".into());
            }
            (export.heightmap.clone().or_else(|| args.export_heightmap.clone()), export.splat.clone())
        }
        None => (args.export_heightmap.clone(), None),
    };
    if heightmap.is_none() && splat.is_none() {
        return Ok(None);
    }
    if args.screenshot.is_some() || args.export_assets.is_some() {
        return Err("export writes files instead of a screenshot or an asset folder: leave out --screenshot and --export-assets".into());
    }
    if let Some(out) = &heightmap {
        terrain_world::export::HeightFormat::check(out).map_err(|error| error.to_string())?;
    }
    if let Some(out) = &splat {
        terrain_world::export::splat_paths(out).map_err(|error| error.to_string())?;
    }
    Ok(Some(Exports { heightmap, splat }))
}

/// Writes the files of `export` for `world`.
fn write_exports(
    export: &Exports,
    world: &World,
    config: &SceneConfig,
    settings: &Settings,
) -> Result<(), String> {
    let (columns, rows) = (world.heightmap.columns(), world.heightmap.rows());
    if let Some(out) = &export.heightmap {
        terrain_world::export::save_heightmap(world, config, out).map_err(|e| e.to_string())?;
        outln!("wrote {} ({columns}x{rows} heights)", out.display());
    }
    if let Some(out) = &export.splat {
        let map = terrain_world::splat::splat_map(world, config, &settings.ground.lines(config));
        let [first, second] = terrain_world::export::save_splat(&map, out).map_err(|e| e.to_string())?;
        outln!(
            "wrote {} (rock, scree, grass, sand) and {} (snow), {columns}x{rows} weights",
            first.display(),
            second.display()
        );
    }
    Ok(())
}

/// `pose` moved where the window lets the camera go (inside the sky box, 0.2 units above the
/// water and the ground), with a warning naming `source` when it had to move: from under the
/// water the view is upside down, from outside the sky box it is black.
fn keep_camera_inside(pose: CameraPose, world: &World, config: &SceneConfig, source: &str) -> CameraPose {
    let limits = config.camera_limits();
    let wanted = pose.position;
    let ground = |x, z| terrain_world::heightfield::height_under(&world.heightmap, config, x, z);
    let allowed = limits.clamp(wanted, ground);
    if allowed == wanted {
        return pose;
    }
    let reason = if wanted.x < limits.min.x
        || wanted.z < limits.min.z
        || wanted.x > limits.max.x
        || wanted.z > limits.max.z
        || wanted.y > limits.max.y
    {
        format!(
            "outside the sky box (the camera stays within x {:.0}..{:.0}, z {:.0}..{:.0}, y up to {:.0})",
            limits.min.x, limits.max.x, limits.min.z, limits.max.z, limits.max.y
        )
    } else if ground(wanted.x, wanted.z).is_some_and(|h| h > limits.min.y && wanted.y < h + limits.clearance)
    {
        format!("under the ground or closer to it than {} units", limits.clearance)
    } else {
        format!("under the water or closer to it than {} units", limits.clearance)
    };
    errln!(
        "warning: {source} puts the camera at {},{},{}, {reason}; moved to {},{},{} as the window would",
        wanted.x,
        wanted.y,
        wanted.z,
        allowed.x,
        allowed.y,
        allowed.z
    );
    CameraPose { position: allowed, ..pose }
}

/// The settings of `--settings` (defaults without it), with `--look` applied. In a window a
/// file that does not exist yet is fine: the panel's Save creates it.
fn load_settings(args: &TerrainArgs) -> Result<Settings, String> {
    let mut settings = match &args.settings {
        None => Settings::default(),
        Some(path) if !path.exists() && args.screenshot.is_none() => {
            errln!(
                "settings: {} does not exist yet; starting from the defaults (the panel's Save, F1, writes it)",
                path.display()
            );
            Settings::default()
        }
        Some(path) => Settings::load(path).map_err(|error| error.to_string())?,
    };
    if let Some(look) = args.look {
        settings.look = look;
    }
    if args.time_of_day.is_some() && (args.sun_elevation.is_some() || args.sun_azimuth.is_some()) {
        return Err("--time-of-day places the sun itself: leave out --sun-elevation and --sun-azimuth".into());
    }
    if let Some(time) = args.time_of_day {
        settings.sky.time_of_day = Some(time);
    }
    if let Some(latitude) = args.latitude {
        settings.sky.latitude_degrees = latitude;
    }
    if let Some(day) = args.day_of_year {
        settings.sky.day_of_year = day;
    }
    if args.sun_elevation.is_some() || args.sun_azimuth.is_some() {
        settings.sky.time_of_day = None;
    }
    if let Some(elevation) = args.sun_elevation {
        settings.sun.elevation_degrees = elevation;
    }
    if let Some(azimuth) = args.sun_azimuth {
        settings.sun.azimuth_degrees = azimuth;
    }
    Ok(settings)
}

/// Bytes as megabytes, for memory reports.
fn megabytes(bytes: u64) -> String {
    format!("{:.1} MB", bytes as f64 / 1e6)
}

/// Prints what the renderer holds on the GPU (and the CPU), and what a height sample costs.
fn report_gpu_memory(memory: &GpuMemory, tree_bytes: usize, world: &World) {
    let samples = u64::from(world.heightmap.columns()) * u64::from(world.heightmap.rows());
    let per_sample = memory.bytes_per_sample(samples)
        + world.heightmap.bytes_per_sample() as f64
        + tree_bytes as f64 / samples as f64;
    errln!(
        "memory (GPU): {} (height texture {}, static mesh {}, light map {}, textures {}, depth {}); LOD tree {} on the CPU",
        megabytes(memory.total()),
        megabytes(memory.heights),
        megabytes(memory.mesh),
        megabytes(memory.light_map),
        megabytes(memory.textures),
        megabytes(memory.depth),
        megabytes(tree_bytes as u64),
    );
    errln!("memory: a height sample costs {per_sample:.2} bytes in all (CPU and GPU)");
}

/// Why the display could not be opened, for people: winit's message without the location in
/// winit's own sources that it starts with, and the display that was tried.
fn display_failure(reason: &str) -> String {
    // winit says "os error at /path/to/winit/src/...rs:788: Failed to open connection to X server".
    let reason = match reason.strip_prefix("os error at ") {
        Some(rest) => rest
            .split_once(".rs:")
            .and_then(|(_, after)| after.split_once(": "))
            .map_or(rest, |(_, message)| message),
        None => reason,
    };
    let tried: Vec<String> = ["DISPLAY", "WAYLAND_DISPLAY"]
        .into_iter()
        .filter_map(|name| std::env::var(name).ok().filter(|v| !v.is_empty()).map(|v| format!("{name}={v}")))
        .collect();
    if tried.is_empty() { reason.to_string() } else { format!("{}: {reason}", tried.join(", ")) }
}

/// Keeps Mesa's Vulkan device-select layer from asking a Wayland compositor that cannot exist
/// for the default GPU: without `XDG_RUNTIME_DIR` (headless machines, CI, ssh) libwayland
/// prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment." twice on every
/// run. wgpu chooses the adapter itself, so the layer has nothing to add then. Must run before
/// any other thread starts.
pub fn quiet_vulkan_device_select() {
    let runtime_dir_ok = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|dir| Path::new(&dir).is_dir());
    if !runtime_dir_ok && std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: called first thing in `main`, before any other thread exists, so nothing can
        // read the environment at the same time.
        #[allow(unsafe_code)]
        unsafe {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    }
}

fn no_display_message(reason: &str) -> String {
    format!(
        "no display to open a window on ({reason}).\n       Run it in a desktop session, or render off-screen instead, e.g.:\n       rayterra terrain --screenshot island.png"
    )
}

/// The STRENGTH to erode the heights with, if any: `--erode` (0 for none), else
/// [`erosion::ISLAND_STRENGTH`] for the procedural island in the modern look (the course look
/// keeps the course's picture exactly) up to [`DEFAULT_EROSION_MAX_SIDE`] samples a side, none
/// for other heights or with `--no-erode`.
fn erosion_strength(args: &TerrainArgs, look: Look) -> Option<f32> {
    if args.no_erode {
        return None;
    }
    match args.erode {
        Some(strength) => (strength > 0.0).then_some(strength),
        None if args.heightmap.is_some() || args.assets.is_some() || look != Look::Modern => None,
        None if args.grid > DEFAULT_EROSION_MAX_SIDE => {
            errln!(
                "note: the island is not eroded by default above {DEFAULT_EROSION_MAX_SIDE} samples a side \
                 (it would hold up the start: 50 s or more at 4097 on two cores); --erode {} erodes it anyway",
                erosion::ISLAND_STRENGTH
            );
            None
        }
        None => Some(erosion::ISLAND_STRENGTH),
    }
}

/// Loads or generates the world the options ask for, eroded with `strength` (see
/// [`erosion_strength`]), showing progress, with the scene numbers to draw it with (the course's,
/// or those that fit elevation data).
fn load_world(args: &TerrainArgs, strength: Option<f32>) -> Result<(World, SceneConfig), String> {
    let config = SceneConfig::default();
    if let Some(path) = &args.heightmap {
        let elevation = dem::is_elevation_file(path)
            .map_err(|error| format!("cannot read {}: {error}", path.display()))?;
        if elevation {
            return load_elevation(args, path, strength);
        }
        let given = [
            (args.cell_size.is_some(), "--cell-size"),
            (args.vertical_exaggeration != 1.0, "--vertical-exaggeration"),
            (args.water_level.is_some(), "--water-level"),
            (args.max_size.is_some(), "--max-size"),
        ];
        for (_, option) in given.iter().filter(|(set, _)| *set) {
            eprintln!(
                "warning: {option} applies to elevation data; {} is a greyscale image, laid out as the course's",
                path.display()
            );
        }
    }
    load_world_with(args, &config, strength).map(|world| (world, config))
}

/// Loads elevation data (metres) from `path`, with a colour map painted from its heights.
fn load_elevation(
    args: &TerrainArgs,
    path: &Path,
    strength: Option<f32>,
) -> Result<(World, SceneConfig), String> {
    let started = Instant::now();
    let options = dem::LoadOptions {
        cell_size: args.cell_size,
        max_size: args.max_size,
        place: dem::PlaceOptions {
            water_level: args.water_level.unwrap_or_default(),
            vertical_exaggeration: args.vertical_exaggeration,
        },
    };
    let reading = spinner(format!("reading the elevation data {}", path.display()));
    let loaded = dem::load_file(path, &options);
    reading.finish_and_clear();
    let loaded = loaded.map_err(|error| error.to_string())?;
    let read = started.elapsed();
    eprintln!("elevation: {} ({})", loaded.describe(), seconds(read));
    let dem::DemScene { heightmap, config, info } = loaded.scene;
    let (heightmap, maps) = erode_if_asked(args.seed, strength, heightmap, &config)?;
    let painting = spinner("painting the colour map".to_string());
    let mut world = procedural::dress_heightmap(heightmap, args.seed, &config, &mut |_| {});
    painting.finish_and_clear();
    world.elevation = Some(info);
    world.erosion = maps;
    eprintln!(
        "world: elevation data {}, {}x{} heightmap ({})",
        path.display(),
        world.heightmap.columns(),
        world.heightmap.rows(),
        seconds(started.elapsed())
    );
    Ok((world, config))
}

/// Loads or generates the world with the course's scene numbers.
fn load_world_with(args: &TerrainArgs, config: &SceneConfig, strength: Option<f32>) -> Result<World, String> {
    let started = Instant::now();
    if let Some(dir) = &args.assets {
        let spinner = spinner(format!("loading the course assets from {}", dir.display()));
        let world = terrain_world::assets::load_course_folder(dir);
        spinner.finish_and_clear();
        let world = world.map_err(|error| error.to_string())?;
        errln!(
            "world: course assets from {}, {}x{} heightmap ({})",
            dir.display(),
            world.heightmap.columns(),
            world.heightmap.rows(),
            seconds(started.elapsed())
        );
        return Ok(world);
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{spinner} generating the world: {msg} {percent:>3}% [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(100));
    let mut progress = |progress: Progress| {
        bar.set_position((progress.overall() * 1000.0).round() as u64);
        bar.set_message(progress.stage.describe());
    };
    let world = match (&args.heightmap, strength) {
        (Some(path), None) => {
            progress(Progress { stage: Stage::Heightmap, done: 0.0 });
            Heightmap::load(path)
                .map(|heightmap| procedural::dress_heightmap(heightmap, args.seed, config, &mut progress))
                .map_err(|error| error.to_string())
        }
        (Some(path), Some(_)) => {
            progress(Progress { stage: Stage::Heightmap, done: 0.0 });
            let heightmap = Heightmap::load(path).map_err(|error| error.to_string());
            bar.finish_and_clear();
            let (heightmap, maps) = erode_if_asked(args.seed, strength, heightmap?, config)?;
            let mut world = procedural::dress_heightmap(heightmap, args.seed, config, &mut |_| {});
            world.erosion = maps;
            Ok(world)
        }
        (None, Some(_)) => {
            progress(Progress { stage: Stage::Heightmap, done: 0.0 });
            let heightmap = procedural::island_heightmap(args.seed, args.grid, config, &mut |done| {
                progress(Progress { stage: Stage::Heightmap, done })
            });
            bar.finish_and_clear();
            let (heightmap, maps) =
                erode_if_asked(args.seed, strength, heightmap.map_err(|error| error.to_string())?, config)?;
            let mut world = procedural::dress_heightmap(heightmap, args.seed, config, &mut |_| {});
            world.erosion = maps;
            Ok(world)
        }
        (None, None) => {
            let options = ProceduralOptions { seed: args.seed, heightmap_size: args.grid };
            procedural::generate(options, config, &mut progress).map_err(|error| error.to_string())
        }
    };
    bar.finish_and_clear();
    let world = world?;
    let source = match &args.heightmap {
        Some(path) => format!("heightmap {}", path.display()),
        None => "procedural island".to_string(),
    };
    errln!(
        "world: {source}, seed {}, {}x{} heightmap ({})",
        args.seed,
        world.heightmap.columns(),
        world.heightmap.rows(),
        seconds(started.elapsed())
    );
    Ok(world)
}

/// The heightmap eroded with `strength` (with a progress bar) and droplets seeded with `seed`,
/// with the erosion's maps; as it is without a strength. Droplets end at the sea (y = 0) when
/// the scene has one.
fn erode_if_asked(
    seed: u32,
    strength: Option<f32>,
    heightmap: Heightmap,
    config: &SceneConfig,
) -> Result<(Heightmap, Option<erosion::ErosionMaps>), String> {
    let Some(strength) = strength else {
        return Ok((heightmap, None));
    };
    let mut params = ErosionParams::with_strength(strength, u64::from(seed)).map_err(|e| e.to_string())?;
    params.sea_level = config.sea.then_some(0.0);
    let started = Instant::now();
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{spinner} eroding the heights: {bar:30} {percent:>3}% [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(Duration::from_millis(100));
    let eroded = erosion::erode_heightmap(&heightmap, config, &params, &mut |done| {
        bar.set_position((done * 1000.0).round() as u64)
    });
    bar.finish_and_clear();
    let (eroded, maps) = eroded.map_err(|error| error.to_string())?;
    errln!(
        "erosion: strength {strength}, {}x{} samples ({})",
        eroded.columns(),
        eroded.rows(),
        seconds(started.elapsed())
    );
    Ok((eroded, Some(maps)))
}

fn spinner(message: String) -> ProgressBar {
    let spinner = ProgressBar::new_spinner();
    spinner.set_message(message);
    spinner.enable_steady_tick(Duration::from_millis(100));
    spinner
}

fn seconds(duration: Duration) -> String {
    format!("{:.2} s", duration.as_secs_f64())
}

fn open_gpu(backend: Backend) -> Result<Gpu, String> {
    let gpu = Gpu::headless(backend).map_err(|error| error.to_string())?;
    errln!("adapter: {}", gpu.describe());
    Ok(gpu)
}

fn screenshot(
    args: &TerrainArgs,
    world: &World,
    config: &SceneConfig,
    settings: &Settings,
    view: &FrameView,
    out: &Path,
) -> Result<(), String> {
    let gpu = open_gpu(args.backend.into())?;
    let started = Instant::now();
    let (width, height) = args.size;
    let mut headless = HeadlessRenderer::new(&gpu, world, config, settings, width, height)
        .map_err(|error| error.to_string())?;
    report_gpu_memory(&headless.renderer().gpu_memory(), headless.renderer().cpu_bytes(), world);
    let image = headless.render(&gpu, view).map_err(|error| error.to_string())?;
    terrain::output::save_frame(image, out).map_err(|error| error.to_string())?;
    errln!("rendered in {} ({} look)", seconds(started.elapsed()), settings.look.name());
    outln!("wrote {} ({}x{})", out.display(), args.size.0, args.size.1);
    Ok(())
}

fn open_window(
    args: &TerrainArgs,
    world: &World,
    config: &SceneConfig,
    settings: Settings,
    view: &FrameView,
) -> Result<(), String> {
    let options = WindowOptions {
        backend: args.backend.into(),
        size: args.size,
        pose: view.pose,
        field_of_view_degrees: view.field_of_view_degrees,
        start_time_seconds: view.time_seconds,
        max_frames: args.frames,
        vsync: !args.no_vsync,
        screenshot_dir: PathBuf::from("."),
        settings,
        settings_path: args.settings.clone().unwrap_or_else(|| PathBuf::from(DEFAULT_SETTINGS_FILE)),
    };
    err!("controls:\n{}", controls::help());
    let mut notice = |notice: Notice| match notice {
        Notice::Adapter(adapter) => errln!("adapter: {adapter}"),
        Notice::GpuMemory { memory, tree_bytes } => report_gpu_memory(&memory, tree_bytes, world),
        Notice::SettingsSaved(path) => outln!("saved settings {}", path.display()),
        Notice::SettingsFailed(reason) => errln!("settings not saved: {reason}"),
        Notice::ScreenshotSaved(path) => outln!("saved screenshot {}", path.display()),
        Notice::ScreenshotFailed(reason) => errln!("screenshot failed: {reason}"),
        Notice::MouseCaptured(true) => {
            errln!("mouse captured for looking around (Tab releases it)")
        }
        Notice::MouseCaptured(false) => {
            errln!("mouse released (click in the window or press Tab to look around)")
        }
    };
    let summary = window::run(world, config, options, &mut notice).map_err(|error| match error {
        window::WindowError::NoDisplay(reason) => no_display_message(&display_failure(&reason)),
        other => other.to_string(),
    })?;
    if summary.frames > 0 {
        errln!(
            "{} frames in {}: {:.1} ms a frame on average",
            summary.frames,
            seconds(Duration::from_secs_f64(summary.seconds)),
            summary.seconds * 1000.0 / summary.frames as f64
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_failures_lose_winits_source_location() {
        let reason = "os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/winit-0.30.13/src/platform_impl/linux/mod.rs:788: Failed to open connection to X server";
        let shown = display_failure(reason);
        assert!(shown.ends_with("Failed to open connection to X server"), "{shown}");
        assert!(!shown.contains("winit") && !shown.contains(".rs"), "{shown}");
        assert!(display_failure("no compositor").ends_with("no compositor"));
    }

    #[test]
    fn a_strength_of_zero_means_no_erosion() {
        assert_eq!(parse_strength("0"), Ok(0.0));
        assert_eq!(parse_strength("2.5"), Ok(2.5));
        for bad in ["-1", "10.5", "nan", "inf", "x"] {
            assert!(parse_strength(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn field_of_view_and_time() {
        assert_eq!(parse_fov("60"), Ok(60.0));
        assert!(parse_fov("0.5").is_err());
        assert!(parse_fov("120").is_err());
        assert_eq!(parse_time("-2.5"), Ok(-2.5));
        assert!(parse_time("nan").is_err());
    }
}
