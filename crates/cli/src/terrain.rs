//! `rayterra terrain`: the terrain engine's command (window and off-screen screenshot).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use terrain::SceneConfig;
use terrain::camera::{CameraPose, MAX_FIELD_OF_VIEW_DEGREES, MIN_FIELD_OF_VIEW_DEGREES};
use terrain::controls;
use terrain::headless::render_image;
use terrain::render::{Backend, FrameView, Gpu};
use terrain::window::{self, Notice, WindowOptions};
use terrain::world::procedural::{self, ProceduralOptions, Stage};
use terrain::world::{self as terrain_world, Heightmap, World};

/// Largest accepted side of `--size`, in pixels (GPUs may allow less; that is checked too).
const MAX_SIDE: u32 = 16_384;

/// The help text after the options: the window's controls and examples.
fn after_help() -> String {
    format!(
        "Controls:\n{}\nExamples:\n  rayterra terrain\n  rayterra terrain --seed 3\n  \
         rayterra terrain --assets ../shared/course-assets/terrain\n  rayterra terrain --heightmap dem.png\n  \
         rayterra terrain --screenshot island.png --size 1280x720 --camera 0,2.5,10,0,0 --time 3",
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

    /// Use this greyscale image (8- or 16-bit PNG, BMP, ...; 2 to 8193 pixels a side, square or
    /// not) as the heightmap, with a colour map painted from its heights and the default sky, detail and water.
    #[arg(long, value_name = "FILE", conflicts_with = "grid")]
    heightmap: Option<PathBuf>,

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

    /// Vertical field of view in degrees (1 to 90).
    #[arg(long, value_name = "DEGREES", default_value_t = 45.0, value_parser = parse_fov)]
    fov: f32,

    /// Scene time in seconds: where the drifting water is (the window's clock starts there).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = parse_time)]
    time: f64,

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
    execute(args).map_err(|message| {
        eprintln!("error: {message}");
        ExitCode::FAILURE
    })
}

fn execute(args: TerrainArgs) -> Result<(), String> {
    let config = SceneConfig::default();
    let windowed = args.screenshot.is_none() && args.export_assets.is_none();
    // Say so before any work when there is nowhere to open the window.
    if windowed && !window::display_available() {
        return Err(no_display_message("neither DISPLAY nor WAYLAND_DISPLAY is set"));
    }
    if let Some(out) = &args.screenshot {
        // Refuse an unwritable format or folder before any work.
        terrain::output::check_output(out).map_err(|error| error.to_string())?;
    }
    let world = load_world(&args, &config)?;
    if let Some(dir) = &args.export_assets {
        let written = terrain_world::export::save_course_folder(&world, dir).map_err(|e| e.to_string())?;
        println!("wrote {} files to {}", written.len(), dir.display());
        return Ok(());
    }
    let pose = args.camera.unwrap_or(config.camera_start);
    match &args.screenshot {
        Some(out) => screenshot(&args, &world, &config, pose, out),
        None => open_window(&args, &world, &config, pose),
    }
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

/// Loads or generates the world the options ask for, showing progress.
fn load_world(args: &TerrainArgs, config: &SceneConfig) -> Result<World, String> {
    let started = Instant::now();
    if let Some(dir) = &args.assets {
        let spinner = spinner(format!("loading the course assets from {}", dir.display()));
        let world = terrain_world::assets::load_course_folder(dir);
        spinner.finish_and_clear();
        let world = world.map_err(|error| error.to_string())?;
        eprintln!(
            "world: course assets from {}, {}x{} heightmap ({})",
            dir.display(),
            world.heightmap.columns(),
            world.heightmap.rows(),
            seconds(started.elapsed())
        );
        return Ok(world);
    }
    let bar = ProgressBar::new(Stage::ALL.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} generating the world: {msg} [{pos}/{len}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(100));
    let mut progress = |stage: Stage| {
        let done = Stage::ALL.iter().position(|&s| s == stage).unwrap_or(0);
        bar.set_position(done as u64);
        bar.set_message(stage.describe());
    };
    let world = match &args.heightmap {
        Some(path) => {
            progress(Stage::Heightmap);
            Heightmap::load(path)
                .map(|heightmap| procedural::dress_heightmap(heightmap, args.seed, config, &mut progress))
                .map_err(|error| error.to_string())
        }
        None => {
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
    eprintln!(
        "world: {source}, seed {}, {}x{} heightmap ({})",
        args.seed,
        world.heightmap.columns(),
        world.heightmap.rows(),
        seconds(started.elapsed())
    );
    Ok(world)
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
    eprintln!("adapter: {}", gpu.describe());
    Ok(gpu)
}

fn screenshot(
    args: &TerrainArgs,
    world: &World,
    config: &SceneConfig,
    pose: CameraPose,
    out: &Path,
) -> Result<(), String> {
    let gpu = open_gpu(args.backend.into())?;
    let view = FrameView { pose, field_of_view_degrees: args.fov, time_seconds: args.time };
    let started = Instant::now();
    let image = render_image(&gpu, world, config, args.size, &view).map_err(|error| error.to_string())?;
    terrain::output::save_frame(&image, out).map_err(|error| error.to_string())?;
    eprintln!("rendered in {}", seconds(started.elapsed()));
    println!("wrote {} ({}x{})", out.display(), args.size.0, args.size.1);
    Ok(())
}

fn open_window(
    args: &TerrainArgs,
    world: &World,
    config: &SceneConfig,
    pose: CameraPose,
) -> Result<(), String> {
    let options = WindowOptions {
        backend: args.backend.into(),
        size: args.size,
        pose,
        field_of_view_degrees: args.fov,
        start_time_seconds: args.time,
        max_frames: args.frames,
        vsync: !args.no_vsync,
        screenshot_dir: PathBuf::from("."),
    };
    eprint!("controls:\n{}", controls::help());
    let mut notice = |notice: Notice| match notice {
        Notice::Adapter(adapter) => eprintln!("adapter: {adapter}"),
        Notice::ScreenshotSaved(path) => println!("saved screenshot {}", path.display()),
        Notice::ScreenshotFailed(reason) => eprintln!("screenshot failed: {reason}"),
        Notice::MouseCaptured(true) => {
            eprintln!("mouse captured for looking around (Tab releases it)")
        }
        Notice::MouseCaptured(false) => {
            eprintln!("mouse released (click in the window or press Tab to look around)")
        }
    };
    let summary = window::run(world, config, options, &mut notice).map_err(|error| match error {
        window::WindowError::NoDisplay(reason) => no_display_message(&display_failure(&reason)),
        other => other.to_string(),
    })?;
    if summary.frames > 0 {
        eprintln!(
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
    fn field_of_view_and_time() {
        assert_eq!(parse_fov("60"), Ok(60.0));
        assert!(parse_fov("0.5").is_err());
        assert!(parse_fov("120").is_err());
        assert_eq!(parse_time("-2.5"), Ok(-2.5));
        assert!(parse_time("nan").is_err());
    }
}
