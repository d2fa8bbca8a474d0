//! Frame-time benchmark: the median time to draw one 1280x720 frame off-screen (drawing and
//! waiting for the GPU, without reading the image back, as a window would), for the course's
//! island, the default procedural island and procedural islands of 4097 and 8193 samples a side,
//! in both looks; then, for the course island, what each draw adds to a frame of either look (the
//! frame drawn up to each draw in turn, measured in the same rounds) and, in the modern look, what
//! each of its features costs (the frame with one feature switched off); and, for the maps the
//! course look draws as its static mesh, what culling the hidden mirrored land saves.
//!
//! Run with `cargo bench -p terrain`. It forces the Vulkan backend (on a machine without a GPU,
//! Mesa's lavapipe) unless `RAYTERRA_BENCH_BACKEND` names another (`gl`, `metal`, `dx12`,
//! `auto`). It prints ratios against `benches/frame_time_baseline.txt` when that exists;
//! `RAYTERRA_BENCH_SAVE=1` rewrites it with this run's medians. `RAYTERRA_BENCH_QUICK=1` skips
//! the large maps.
//!
//! Variants of one world are measured in interleaved rounds (a few frames of each in turn), so
//! that a machine shared with other work slows them alike and their ratios stay meaningful. On
//! Linux each line also gives the CPU time the process spent a frame (all threads, lavapipe's
//! included: what a software GPU's frame costs), which other work on the machine disturbs much
//! less than the wall-clock time.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use terrain::headless::HeadlessRenderer;
use terrain::render::{Backend, FrameView, Gpu, MESH_MAX_SIDE, draw_names};
use terrain::settings::ReflectionQuality;
use terrain::world::World;
use terrain::world::assets::load_course_folder;
use terrain::world::procedural::{ProceduralOptions, generate};
use terrain::{Look, SceneConfig, Settings};

const SIZE: (u32, u32) = (1280, 720);
const WARM_UP_FRAMES: usize = 2;
const ROUNDS: usize = 6;
const FRAMES_PER_ROUND: usize = 4;

fn main() {
    // As `rayterra terrain` does, so that the frames measured are the ones users get.
    terrain::heap::keep_freed_memory();
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
        "frame: {}x{} off-screen, start view, median of {} frames ({ROUNDS} interleaved rounds of {FRAMES_PER_ROUND})",
        SIZE.0,
        SIZE.1,
        ROUNDS * FRAMES_PER_ROUND
    );
    let config = SceneConfig::default();
    // Beside the repository, or in the nearest folder above it (a git worktree in a subfolder).
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let course_dir = manifest
        .ancestors()
        .map(|dir| dir.join("shared/course-assets/terrain"))
        .find(|dir| dir.is_dir())
        .unwrap_or_else(|| manifest.join("../../../shared/course-assets/terrain"));
    let quick = std::env::var("RAYTERRA_BENCH_QUICK").is_ok_and(|v| v == "1");
    let mut scenes = vec![("course-island-256", Scene::Course), ("procedural-512", Scene::Procedural(512))];
    if !quick {
        scenes.extend([
            ("procedural-4097", Scene::Procedural(4097)),
            ("procedural-8193", Scene::Procedural(8193)),
        ]);
    }
    println!(
        "{:<44} {:>10} {:>8} {:>8} {:>8} {:>9} {:>20}",
        "scene / look", "median ms", "min ms", "max ms", "CPU ms", "setup s", "terrain triangles"
    );
    let mut results = BTreeMap::new();
    for (name, scene) in scenes {
        let started = Instant::now();
        let Some(world) = scene.world(&config, &course_dir) else {
            continue;
        };
        println!("{name}: world ready in {:.1} s", started.elapsed().as_secs_f64());
        let looks = [("course", Settings::course()), ("modern", Settings::default())];
        for (look, median, _) in measure(&gpu, &world, &config, name, &looks) {
            results.insert(format!("{name}/{look}"), median);
        }
        if matches!(scene, Scene::Course) {
            draw_by_draw(&gpu, &world, &config);
            breakdown(&gpu, &world, &config);
        }
        // Only the static mesh (maps up to MESH_MAX_SIDE) culls its reflection.
        if !matches!(scene, Scene::Procedural(size) if size > MESH_MAX_SIDE) {
            culling(&gpu, &world, &config, name);
        }
    }
    compare_with_baseline(&results);
}

/// Measures `variants` of `world` in interleaved rounds; prints a line each and returns their
/// names, medians and fastest frames in milliseconds.
fn measure(
    gpu: &Gpu,
    world: &World,
    config: &SceneConfig,
    scene: &str,
    variants: &[(&str, Settings)],
) -> Vec<(String, f64, f64)> {
    let variants: Vec<Variant> =
        variants.iter().map(|(name, settings)| Variant::new(name, settings)).collect();
    measure_variants(gpu, world, config, scene, &variants)
}

/// A variant to measure.
struct Variant {
    name: String,
    settings: Settings,
    /// Whether the course look culls the mirrored chunks the land hides.
    cull: bool,
    /// How many of the look's draws a frame makes (`None`: all).
    draws: Option<usize>,
}

impl Variant {
    /// The full frame of `settings`.
    fn new(name: &str, settings: &Settings) -> Self {
        Variant { name: name.to_string(), settings: settings.clone(), cull: true, draws: None }
    }
}

/// Measures `variants` of `world` in interleaved rounds; prints a line each and returns their
/// names, medians and fastest frames in milliseconds.
fn measure_variants(
    gpu: &Gpu,
    world: &World,
    config: &SceneConfig,
    scene: &str,
    variants: &[Variant],
) -> Vec<(String, f64, f64)> {
    let view = FrameView {
        pose: config.camera_start,
        field_of_view_degrees: config.field_of_view_degrees,
        time_seconds: 0.0,
    };
    let setup = Instant::now();
    let mut headless = match HeadlessRenderer::new(gpu, world, config, &variants[0].settings, SIZE.0, SIZE.1)
    {
        Ok(headless) => headless,
        Err(error) => {
            println!("{scene:<28} cannot render: {error}");
            return Vec::new();
        }
    };
    let mut setups = vec![Duration::ZERO; variants.len()];
    let mut times: Vec<Vec<Duration>> = vec![Vec::new(); variants.len()];
    let mut triangles = vec![[0; 2]; variants.len()];
    let mut cpu = vec![Some(Duration::ZERO); variants.len()];
    for round in 0..ROUNDS {
        for (i, variant) in variants.iter().enumerate() {
            let switch = Instant::now();
            let ready = headless.renderer_mut().apply(gpu, world, &variant.settings).and_then(|()| {
                headless.renderer_mut().set_cull_hidden_reflection(variant.cull);
                headless.renderer_mut().set_draw_limit(variant.draws);
                // The first frames of a look upload its resources and draw its light map.
                let warm_up = if round == 0 { WARM_UP_FRAMES } else { 1 };
                (0..warm_up).try_for_each(|_| headless.draw(gpu, &view))
            });
            if let Err(error) = ready {
                println!("{scene:<28} failed: {error}");
                return Vec::new();
            }
            if round == 0 {
                setups[i] = if i == 0 { setup.elapsed() } else { switch.elapsed() };
            }
            let cpu_before = process_cpu_time();
            for _ in 0..FRAMES_PER_ROUND {
                let started = Instant::now();
                if let Err(error) = headless.draw(gpu, &view) {
                    println!("{scene:<28} failed: {error}");
                    return Vec::new();
                }
                times[i].push(started.elapsed());
            }
            cpu[i] = match (cpu[i], cpu_before, process_cpu_time()) {
                (Some(total), Some(before), Some(after)) => Some(total + after.saturating_sub(before)),
                _ => None,
            };
            triangles[i] = headless.renderer().terrain_triangles();
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    variants
        .iter()
        .zip(times.iter_mut())
        .zip(setups.iter().zip(&triangles).zip(&cpu))
        .map(|((variant, times), ((setup, [direct, mirrored]), cpu))| {
            let name = &variant.name;
            let cpu =
                cpu.map_or_else(|| "-".to_string(), |cpu| format!("{:.1}", ms(cpu) / times.len() as f64));
            times.sort();
            let median = ms(times[times.len() / 2]);
            println!(
                "{:<44} {median:>10.1} {:>8.1} {:>8.1} {cpu:>8} {:>9.2} {:>20}",
                format!("{scene} / {name}"),
                ms(times[0]),
                ms(times[times.len() - 1]),
                setup.as_secs_f64(),
                format!("{direct} + {mirrored}"),
            );
            (name.to_string(), median, ms(times[0]))
        })
        .collect()
}

/// Where a frame's time goes on `world`, draw by draw, in both looks: the frame drawn up to each
/// of its draws in turn, in the same interleaved rounds; the difference is what the draw adds
/// (drawn over what came before it: the land hides much of what follows it).
fn draw_by_draw(gpu: &Gpu, world: &World, config: &SceneConfig) {
    for (look, settings) in [("course", Settings::course()), ("modern", Settings::default())] {
        let names = draw_names(settings.look);
        let variants: Vec<Variant> = (0..=names.len())
            .map(|limit| Variant {
                name: if limit == 0 { "nothing drawn".into() } else { format!("+ {}", names[limit - 1]) },
                draws: Some(limit),
                ..Variant::new("", &settings)
            })
            .collect();
        println!("where the {look} look's time goes (course island; the frame drawn up to each draw):");
        let medians = measure_variants(gpu, world, config, "  course-island-256", &variants);
        for ((_, median_before, fastest_before), (name, median, fastest)) in medians.iter().zip(&medians[1..])
        {
            println!(
                "  {name:<26} {:>+8.1} ms (fastest frames {:+.1} ms)",
                median - median_before,
                fastest - fastest_before
            );
        }
    }
}

/// Where the modern look's time goes on `world`: the frame with each feature switched off, in
/// the same interleaved rounds as the full frame; the difference is the feature's cost.
fn breakdown(gpu: &Gpu, world: &World, config: &SceneConfig) {
    let full = Settings::default();
    let mut variants = vec![("modern, everything on", full.clone())];
    let mut with = |name, change: fn(&mut Settings)| {
        let mut settings = full.clone();
        change(&mut settings);
        variants.push((name, settings));
    };
    with("no reflection", |s| s.water.reflection = ReflectionQuality::Off);
    with("quarter reflection", |s| s.water.reflection = ReflectionQuality::Quarter);
    with("no sea floor", |s| s.water.refraction = false);
    with("no glint, no foam", |s| {
        s.water.glint = false;
        s.water.foam = false;
    });
    with("no fog", |s| s.fog.enabled = false);
    with("ground materials off", |s| s.ground.materials = false);
    with("unlit", |s| s.sun.lighting = false);
    with("LOD error 4 px", |s| s.terrain.lod_error_pixels = 4.0);
    with("course look", |s| s.look = Look::Course);
    println!("where the modern look's time goes (course island; each line switches one thing off):");
    let medians = measure(gpu, world, config, "  course-island-256", &variants);
    if let Some((_, reference, _)) = medians.first() {
        for (name, median, _) in &medians[1..] {
            println!(
                "  {name:<26} {:>+8.1} ms ({:.2} of the full frame)",
                median - reference,
                median / reference
            );
        }
    }
}

/// What leaving the hidden mirrored chunks out saves in the course look on `world`, in the same
/// interleaved rounds as drawing them all.
fn culling(gpu: &Gpu, world: &World, config: &SceneConfig, scene: &str) {
    let variants = [
        Variant::new("course, culled reflection", &Settings::course()),
        Variant { cull: false, ..Variant::new("course, whole reflection", &Settings::course()) },
    ];
    let medians = measure_variants(gpu, world, config, &format!("  {scene}"), &variants);
    if let [(_, culled, _), (_, whole, _)] = medians[..] {
        println!(
            "  culling the hidden reflection: {:+.1} ms ({culled:.1} / {whole:.1} = {:.2})",
            culled - whole,
            culled / whole
        );
    }
}

/// The CPU time this process has used (user and system, all threads), where the system tells
/// (`/proc/self/stat` on Linux, in clock ticks of 1/100 s: `USER_HZ`, fixed by Linux's ABI).
fn process_cpu_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command's name, in parentheses, may hold spaces: the fields after it are plain.
    let fields: Vec<&str> = stat.get(stat.rfind(')')? + 1..)?.split_whitespace().collect();
    // utime and stime are the stat's 14th and 15th fields, the 12th and 13th after the name.
    let ticks = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(Duration::from_millis(ticks * 10))
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
    println!("against the baseline {} (below 1 is faster):", path.display());
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        let (Some(name), Some(Ok(baseline))) = (parts.next(), parts.next().map(str::parse::<f64>)) else {
            continue;
        };
        if let Some(now) = results.get(name) {
            println!("  {name:<28} {now:>8.1} ms / {baseline:>8.1} ms = {:.2}", now / baseline);
        }
    }
}
