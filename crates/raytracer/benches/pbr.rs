//! Physically based models' benchmark: `cargo bench -p raytracer --bench pbr`.
//!
//! 1. The path tracer against Mitsuba 3 (`scalar_rgb`, its `path` integrator, through
//!    `tools/mitsuba/rayterra_mitsuba.py`) on `scenes/cornell-box.txt`, at the same size, samples
//!    a pixel and depth, both on every core, in the same run: the runs alternate (ours, Mitsuba,
//!    ours, ...) so that both see the same load on a shared machine, and the ratio of each pair is
//!    printed with its median. Times are of the rendering alone (Mitsuba's own timer around
//!    `mi.render`, ours around `raytracer::render`; loading is not counted on either side).
//! 2. SPPM on the course's `glass-trio-area-light.txt` at 640x380: the time of a render whose
//!    caustics are clearly visible (32 passes of 250,000 photons), with passes and photons a
//!    second.
//!
//! Nothing is asserted: speed is measured, not tested. `RAYTERRA_BENCH_RUNS` sets the number of
//! pairs (default 3), `RAYTERRA_MITSUBA_PYTHON` the Python that has Mitsuba (default
//! `target/mitsuba-venv/bin/python`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use raytracer::integrator::Model;
use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::scene::{self, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

const SIZE: (u32, u32) = (256, 256);
const SPP: u32 = 64;
const DEPTH: u32 = 10;

fn load(path: &Path) -> PreparedScene {
    let source = SourceFile::read(path).expect("readable scene");
    let parsed = scene::parse(&source).expect("valid scene");
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::new(parsed.scene, &search).expect("textures")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Mitsuba's render time in seconds, as its tool reports it.
fn mitsuba(python: &Path, scene: &Path, out: &Path, threads: usize) -> Option<f64> {
    let result = Command::new(python)
        .arg(scene.parent()?.join("../tools/mitsuba/rayterra_mitsuba.py"))
        .arg(scene)
        .args(["-o", &out.to_string_lossy(), "--size", &format!("{}x{}", SIZE.0, SIZE.1)])
        .args([
            "--spp",
            &SPP.to_string(),
            "--max-depth",
            &DEPTH.to_string(),
            "--threads",
            &threads.to_string(),
        ])
        .output()
        .ok()?;
    let stdout = String::from_utf8_lossy(&result.stdout);
    if !result.status.success() {
        eprintln!("the Mitsuba tool failed: {}", String::from_utf8_lossy(&result.stderr));
        return None;
    }
    stdout.split_whitespace().skip_while(|w| *w != "render").nth(1)?.parse().ok()
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let runs: usize =
        std::env::var("RAYTERRA_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3).max(1);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let python = std::env::var_os("RAYTERRA_MITSUBA_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/mitsuba-venv/bin/python"));
    let cornell = root.join("scenes/cornell-box.txt");
    let scene = load(&cornell);
    let settings = RenderSettings {
        width: SIZE.0,
        height: SIZE.1,
        sampling: Sampling::Uniform(SPP),
        model: Model::Path,
        max_depth: DEPTH,
        ..RenderSettings::for_scene(&scene)
    };
    let samples = (SIZE.0 * SIZE.1 * SPP) as f64;
    println!(
        "path tracer against Mitsuba 3 scalar_rgb: cornell-box.txt {}x{}, {SPP} spp, depth {DEPTH}, {threads} threads, {runs} pairs",
        SIZE.0, SIZE.1
    );
    let out = std::env::temp_dir().join("rayterra-bench-mitsuba.exr");
    let (mut ratios, mut ours_all, mut theirs_all) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..runs {
        let started = Instant::now();
        raytracer::render(&scene, &settings, &|_: Progress| {}).expect("render");
        let ours = started.elapsed().as_secs_f64();
        let Some(theirs) = mitsuba(&python, &cornell, &out, threads) else {
            println!("  run {run}: ours {ours:.2} s; Mitsuba unavailable at {}", python.display());
            ours_all.push(ours);
            continue;
        };
        println!(
            "  run {run}: ours {ours:.2} s ({:.3} M samples/s a core), Mitsuba {theirs:.2} s ({:.3} M samples/s a core), ratio {:.3}",
            samples / ours / threads as f64 / 1e6,
            samples / theirs / threads as f64 / 1e6,
            ours / theirs
        );
        ratios.push(ours / theirs);
        ours_all.push(ours);
        theirs_all.push(theirs);
    }
    let ours = median(ours_all);
    print!("median: ours {ours:.2} s, {:.3} M samples/s a core", samples / ours / threads as f64 / 1e6);
    if !ratios.is_empty() {
        let theirs = median(theirs_all);
        println!(
            "; Mitsuba {theirs:.2} s, {:.3} M samples/s a core; time ratio ours/Mitsuba {:.3} (median of pairs)",
            samples / theirs / threads as f64 / 1e6,
            median(ratios)
        );
    } else {
        println!();
    }

    let trio = root.join("../shared/course-assets/scenes/glass-trio-area-light.txt");
    if !trio.is_file() {
        println!("**** the course scenes are missing ({}): SPPM not measured ****", trio.display());
        return;
    }
    let scene = load(&trio);
    let settings = RenderSettings {
        width: 640,
        height: 380,
        model: Model::Sppm,
        passes: Some(32),
        photons: Some(250_000),
        ..RenderSettings::for_scene(&scene)
    };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let started = Instant::now();
        let rendered = raytracer::render(&scene, &settings, &|_: Progress| {}).expect("render");
        times.push(started.elapsed().as_secs_f64());
        last = rendered.stats.sppm;
    }
    let t = median(times);
    if let Some(s) = last {
        println!(
            "sppm: glass-trio-area-light.txt 640x380, {} passes of {} photons: {t:.2} s (median), {:.2} passes/s, \
             {:.2} M photons/s, {:.1} s of it tracing photons",
            s.passes,
            s.photons / s.passes.max(1),
            s.passes as f64 / t,
            s.photons as f64 / t / 1e6,
            s.photon_seconds
        );
    }
}
