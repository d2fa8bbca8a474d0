//! Frame-time benchmark: the median time to draw one 1280x720 frame off-screen (drawing and
//! waiting for the GPU, without reading the image back, as a window would), for the course's
//! island, the default procedural island and a 2049x2049 procedural heightmap.
//!
//! Run with `cargo bench -p terrain`. It forces the Vulkan backend (on a machine without a GPU,
//! Mesa's lavapipe) unless `RAYTERRA_BENCH_BACKEND` names another (`gl`, `metal`, `dx12`,
//! `auto`). It prints ratios against `benches/frame_time_baseline.txt` when that exists;
//! `RAYTERRA_BENCH_SAVE=1` rewrites it with this run's medians.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use terrain::SceneConfig;
use terrain::headless::HeadlessRenderer;
use terrain::render::{Backend, FrameView, Gpu};
use terrain::world::World;
use terrain::world::assets::load_course_folder;
use terrain::world::procedural::{ProceduralOptions, generate};

const SIZE: (u32, u32) = (1280, 720);
const WARM_UP_FRAMES: usize = 3;
const MEASURED_FRAMES: usize = 25;

fn main() {
    let backend: Backend = std::env::var("RAYTERRA_BENCH_BACKEND")
        .map(|name| name.parse().unwrap_or_else(|error| panic!("RAYTERRA_BENCH_BACKEND: {error}")))
        .unwrap_or(Backend::Vulkan);
    let gpu = match Gpu::headless(backend) {
        Ok(gpu) => gpu,
        Err(error) => {
            eprintln!("frame_time: cannot benchmark without a GPU: {error}");
            return;
        }
    };
    println!("adapter: {}", gpu.describe());
    println!(
        "frame: {}x{} off-screen, start view, median of {MEASURED_FRAMES} frames after {WARM_UP_FRAMES} warm-up frames",
        SIZE.0, SIZE.1
    );
    let config = SceneConfig::default();
    let course_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/course-assets/terrain");
    let mut results = BTreeMap::new();
    let scenes = [
        ("course-island-256", Scene::Course),
        ("procedural-512", Scene::Procedural(512)),
        ("procedural-2049", Scene::Procedural(2049)),
    ];
    println!(
        "{:<20} {:>10} {:>10} {:>10} {:>9} {:>18}",
        "scene", "median ms", "min ms", "max ms", "setup s", "terrain triangles"
    );
    for (name, scene) in scenes {
        let Some(world) = scene.world(&config, &course_dir) else {
            continue;
        };
        let setup = Instant::now();
        let mut headless = match HeadlessRenderer::new(&gpu, &world, &config, &terrain::Settings::course(), SIZE.0, SIZE.1) {
            Ok(headless) => headless,
            Err(error) => {
                println!("{name:<20} cannot render: {error}");
                continue;
            }
        };
        let setup = setup.elapsed();
        let view = FrameView {
            pose: config.camera_start,
            field_of_view_degrees: config.field_of_view_degrees,
            time_seconds: 0.0,
        };
        let mut times: Vec<Duration> = Vec::with_capacity(MEASURED_FRAMES);
        for frame in 0..WARM_UP_FRAMES + MEASURED_FRAMES {
            let started = Instant::now();
            if let Err(error) = headless.draw(&gpu, &view) {
                println!("{name:<20} failed: {error}");
                break;
            }
            if frame >= WARM_UP_FRAMES {
                times.push(started.elapsed());
            }
        }
        if times.is_empty() {
            continue;
        }
        times.sort();
        let ms = |d: Duration| d.as_secs_f64() * 1000.0;
        let median = ms(times[times.len() / 2]);
        let [direct, mirrored] = headless.renderer().terrain_triangles();
        println!(
            "{name:<20} {median:>10.1} {:>10.1} {:>10.1} {:>9.2} {:>18}",
            ms(times[0]),
            ms(times[times.len() - 1]),
            setup.as_secs_f64(),
            format!("{direct} + {mirrored}"),
        );
        results.insert(name.to_string(), median);
    }
    compare_with_baseline(&results);
}

/// A world to measure.
enum Scene {
    /// The course's asset folder.
    Course,
    /// The procedural island (seed 1) with a heightmap of this many samples per side.
    Procedural(u32),
}

impl Scene {
    fn world(&self, config: &SceneConfig, course_dir: &Path) -> Option<World> {
        match self {
            Scene::Course => load_course_folder(course_dir)
                .map_err(|error| eprintln!("course island skipped: {error}"))
                .ok(),
            &Scene::Procedural(size) => {
                let options = ProceduralOptions { seed: 1, heightmap_size: size };
                generate(options, config, &mut |_| {}).ok()
            }
        }
    }
}

fn compare_with_baseline(results: &BTreeMap<String, f64>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/frame_time_baseline.txt");
    if std::env::var("RAYTERRA_BENCH_SAVE").is_ok_and(|v| v == "1") {
        let text: String = results.iter().map(|(name, ms)| format!("{name} {ms:.2}\n")).collect();
        match std::fs::write(&path, text) {
            Ok(()) => println!("baseline saved to {}", path.display()),
            Err(error) => eprintln!("cannot save the baseline {}: {error}", path.display()),
        }
        return;
    }
    let Ok(text) = std::fs::read_to_string(&path) else {
        println!("no baseline at {} (RAYTERRA_BENCH_SAVE=1 writes one)", path.display());
        return;
    };
    println!("against the baseline (below 1 is faster):");
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        let (Some(name), Some(Ok(baseline))) = (parts.next(), parts.next().map(str::parse::<f64>)) else {
            continue;
        };
        if let Some(now) = results.get(name) {
            println!("  {name:<20} {now:>8.1} ms / {baseline:>8.1} ms = {:.2}", now / baseline);
        }
    }
}
