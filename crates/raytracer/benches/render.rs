//! Render benchmark: `cargo bench -p raytracer`.
//!
//! Renders the course's `classic.txt` and `seed-report.txt` and the project's showcase at 1280x760,
//! prints the median wall time over a few runs, rays per second per thread, and the speed-up over
//! the course's own C++ renderer, whose times on this 2-core machine are recorded in
//! `../shared/course-assets/reference/README.md` (2 threads, OpenMP, -O2). Nothing is asserted:
//! speed is measured, not tested. `RAYTERRA_BENCH_RUNS` sets the number of runs (default 3).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use raytracer::render::{Progress, RenderSettings, RenderStats};
use raytracer::scene::{self, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

/// The course renderer's wall time for a scene at 1280x760, in seconds (low, high).
struct Baseline {
    low: f64,
    high: f64,
}

struct Case {
    name: &'static str,
    path: PathBuf,
    baseline: Option<Baseline>,
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let assets = root.join("../shared/course-assets/scenes");
    let runs: usize =
        std::env::var("RAYTERRA_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3).max(1);
    let mut cases = vec![];
    if assets.is_dir() {
        cases.push(Case {
            name: "classic.txt",
            path: assets.join("classic.txt"),
            baseline: Some(Baseline { low: 25.0, high: 35.0 }),
        });
        cases.push(Case {
            name: "seed-report.txt",
            path: assets.join("seed-report.txt"),
            baseline: Some(Baseline { low: 49.0, high: 79.0 }),
        });
    } else {
        eprintln!(
            "**** the course scenes are missing ({}): only the project's scenes are measured ****",
            assets.display()
        );
    }
    cases.push(Case { name: "showcase.txt", path: root.join("scenes/showcase.txt"), baseline: None });

    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "rayterra render benchmark: 1280x760, adaptive sampling, median of {runs} runs, {threads} threads"
    );
    println!(
        "{:<16} {:>9} {:>11} {:>13} {:>18}  vs course renderer (2 threads)",
        "scene", "time", "rays", "Mrays/s", "Mrays/s/thread"
    );
    for case in &cases {
        let scene = load(&case.path);
        let settings = RenderSettings { width: 1280, height: 760, ..RenderSettings::for_scene(&scene) };
        let mut times = Vec::with_capacity(runs);
        let mut stats = RenderStats::default();
        for _ in 0..runs {
            let started = Instant::now();
            let rendered = raytracer::render(&scene, &settings, &|_: Progress| {}).expect("render");
            times.push(started.elapsed());
            stats = rendered.stats;
        }
        times.sort();
        let median = times[times.len() / 2];
        let seconds = median.as_secs_f64();
        let rate = stats.rays as f64 / seconds / 1e6;
        let versus = match &case.baseline {
            Some(b) => format!(
                "{:.1}x faster ({:.0}-{:.0} s -> {})",
                (b.low + b.high) / 2.0 / seconds,
                b.low,
                b.high,
                format_duration(median)
            ),
            None => "-".to_owned(),
        };
        println!(
            "{:<16} {:>9} {:>11} {:>13.1} {:>18.1}  {}",
            case.name,
            format_duration(median),
            stats.rays,
            rate,
            rate / stats.threads.max(1) as f64,
            versus
        );
    }
}

fn load(path: &Path) -> PreparedScene {
    let source = SourceFile::read(path).expect("readable scene");
    let parsed = scene::parse(&source).expect("valid scene");
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::new(parsed.scene, &search).expect("textures")
}

fn format_duration(d: Duration) -> String {
    format!("{:.2} s", d.as_secs_f64())
}
