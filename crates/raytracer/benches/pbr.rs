//! Physically based models' benchmark: `cargo bench -p raytracer --bench pbr`.
//!
//! 1. The path tracer against Mitsuba 3's two CPU variants, `llvm_ad_rgb` (vectorised: Dr.Jit
//!    compiles the integrator into one kernel; warm, its kernel cache filled by a first run that is
//!    not counted) and `scalar_rgb`, each with its `path` integrator through
//!    `tools/mitsuba/rayterra_mitsuba.py`, on `scenes/cornell-box.txt`, at the same size, samples a
//!    pixel, depth and Russian roulette, all on every core, in the same run: the runs alternate
//!    (ours, llvm, scalar, ours, ...) so that all see the same load on a shared machine, and the
//!    ratio of each round is printed with its median and range. Times are of the rendering alone
//!    (Mitsuba's own timer around `mi.render` up to the finished image, ours around
//!    `raytracer::render`; loading is not counted on either side). Ours also prints samples and
//!    rays a second a core. Without LLVM (`DRJIT_LIBLLVM_PATH`, default
//!    `/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1`) the bench says so and compares with
//!    `scalar_rgb` alone.
//! 2. The same on Mitsuba's own scene files, the same file read by both renderers (through
//!    `tools/mitsuba/render_xml.py` on Mitsuba's side, the size set through the files' own `-D`
//!    parameters): `scenes/cbox/cbox.xml` (256x256, 64 spp, the file's depth 6) and
//!    `scenes/matpreview/matpreview.xml` (meshes, an environment map, a plastic; 256x192, 64 spp,
//!    unbounded depth with Russian roulette from depth 5), from
//!    `../shared/mitsuba-data` (skipped, loudly, without it).
//! 3. SPPM on the course's `glass-trio-area-light.txt` at 640x380: the time of a render whose
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

/// Mitsuba's render time in seconds with `variant`, as its tool reports it; `llvm` is the LLVM
/// library Dr.Jit loads for the `llvm_ad_rgb` variant.
fn mitsuba(
    python: &Path,
    variant: &str,
    llvm: &Path,
    scene: &Path,
    out: &Path,
    threads: usize,
) -> Option<f64> {
    let result = Command::new(python)
        .env("DRJIT_LIBLLVM_PATH", llvm)
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
            "--variant",
            variant,
        ])
        .output()
        .ok()?;
    let stdout = String::from_utf8_lossy(&result.stdout);
    if !result.status.success() {
        eprintln!("the Mitsuba tool ({variant}) failed: {}", String::from_utf8_lossy(&result.stderr));
        return None;
    }
    stdout.split_whitespace().skip_while(|w| *w != "render").nth(1)?.parse().ok()
}

/// The median, smallest and largest of `v` (not empty), as text.
fn spread(v: &[f64]) -> String {
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    format!("{:.3} ({lo:.3}-{hi:.3})", median(v.to_vec()))
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
    let per_core = |count: f64, seconds: f64| count / seconds / threads as f64 / 1e6;
    println!(
        "path tracer against Mitsuba 3: cornell-box.txt {}x{}, {SPP} spp, depth {DEPTH}, {threads} threads, {runs} rounds",
        SIZE.0, SIZE.1
    );
    let llvm = std::env::var_os("DRJIT_LIBLLVM_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"));
    let mut variants = vec!["scalar_rgb"];
    let out = std::env::temp_dir().join("rayterra-bench-mitsuba.exr");
    if !llvm.is_file() {
        println!(
            "**** no LLVM at {} (apt-get install libllvm19, or set DRJIT_LIBLLVM_PATH): compared with \
             scalar_rgb alone ****",
            llvm.display()
        );
    } else if mitsuba(&python, "llvm_ad_rgb", &llvm, &cornell, &out, threads).is_some() {
        // That first run filled Dr.Jit's kernel cache: the rounds time it warm.
        variants.insert(0, "llvm_ad_rgb");
    }
    let mut ours_all = Vec::new();
    let mut rays_all = Vec::new();
    let mut theirs: Vec<(&str, Vec<f64>, Vec<f64>)> =
        variants.iter().map(|v| (*v, Vec::new(), Vec::new())).collect();
    for run in 0..runs {
        let started = Instant::now();
        let rendered = raytracer::render(&scene, &settings, &|_: Progress| {}).expect("render");
        let ours = started.elapsed().as_secs_f64();
        let rays = rendered.stats.rays as f64;
        let mut line = format!(
            "  round {run}: ours {ours:.2} s ({:.3} M samples/s a core, {:.2} M rays/s a core)",
            per_core(samples, ours),
            per_core(rays, ours)
        );
        for (variant, times, ratios) in theirs.iter_mut() {
            match mitsuba(&python, variant, &llvm, &cornell, &out, threads) {
                Some(t) => {
                    line += &format!(", {variant} {t:.2} s (ours/theirs {:.3})", ours / t);
                    times.push(t);
                    ratios.push(ours / t);
                }
                None => line += &format!(", {variant} unavailable at {}", python.display()),
            }
        }
        println!("{line}");
        ours_all.push(ours);
        rays_all.push(rays / ours);
    }
    let ours = median(ours_all);
    println!(
        "median: ours {ours:.2} s, {:.3} M samples/s a core, {:.2} M rays/s a core",
        per_core(samples, ours),
        median(rays_all) / threads as f64 / 1e6
    );
    for (variant, times, ratios) in &theirs {
        if !times.is_empty() {
            println!(
                "  {variant}: {:.2} s, {:.3} M samples/s a core; time ratio ours/{variant} {} (median, range of rounds)",
                median(times.clone()),
                per_core(samples, median(times.clone())),
                spread(ratios)
            );
        }
    }

    mitsuba_files(&root, &python, &llvm, llvm.is_file(), runs, threads);

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

/// Mitsuba's render time in seconds for a Mitsuba scene file, through `render_xml.py`.
fn mitsuba_xml(
    python: &Path,
    variant: &str,
    llvm: &Path,
    root: &Path,
    case: &XmlCase,
    out: &Path,
) -> Option<f64> {
    let mut cmd = Command::new(python);
    cmd.env("DRJIT_LIBLLVM_PATH", llvm).arg(root.join("tools/mitsuba/render_xml.py")).arg(&case.path);
    cmd.args(["-o", &out.to_string_lossy()]);
    for (k, v) in &case.defines {
        cmd.args(["-D", &format!("{k}={v}")]);
    }
    cmd.args(["--spp", &case.spp.to_string(), "--variant", variant]);
    let result = cmd.output().ok()?;
    if !result.status.success() {
        eprintln!(
            "Mitsuba ({variant}) failed on {}: {}",
            case.path.display(),
            String::from_utf8_lossy(&result.stderr)
        );
        return None;
    }
    let stdout = String::from_utf8_lossy(&result.stdout);
    stdout.split_whitespace().skip_while(|w| *w != "render").nth(1)?.parse().ok()
}

/// A Mitsuba scene file of the benchmark, its size given through the file's own parameters
/// (`-D`), so that both renderers read the same film.
struct XmlCase {
    path: PathBuf,
    defines: Vec<(String, String)>,
    spp: u32,
}

/// Part 2: Mitsuba's scene files, rendered alternately by both.
fn mitsuba_files(root: &Path, python: &Path, llvm: &Path, has_llvm: bool, runs: usize, threads: usize) {
    let data = root.join("../shared/mitsuba-data");
    if !data.join("SOURCES.md").is_file() {
        println!("**** the Mitsuba scenes are missing ({}): not measured ****", data.display());
        return;
    }
    let d = |pairs: &[(&str, &str)]| pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let cases = [
        XmlCase { path: data.join("scenes/cbox/cbox.xml"), defines: d(&[("res", "256")]), spp: 64 },
        XmlCase {
            path: data.join("scenes/matpreview/matpreview.xml"),
            defines: d(&[("width", "256"), ("height", "192")]),
            spp: 64,
        },
    ];
    let out = std::env::temp_dir().join("rayterra-bench-mitsuba-xml.exr");
    for case in &cases {
        let doc = match raytracer::scene::mitsuba::read_file(&case.path, &case.defines) {
            Ok(doc) => doc,
            Err(e) => {
                println!("**** {} cannot be read: {e} ****", case.path.display());
                continue;
            }
        };
        let built = raytracer::scene::mitsuba::build(&doc).expect("the benchmark's scenes build");
        let scene = PreparedScene::new(built.scene, &TextureSearch::default()).expect("prepares");
        let settings =
            RenderSettings { sampling: Sampling::Uniform(case.spp), ..RenderSettings::for_scene(&scene) };
        let name = case.path.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
        println!(
            "path tracer against Mitsuba 3 on {name}: {}x{}, {} spp, depth {} (the file's), {threads} threads, {runs} rounds",
            settings.width, settings.height, case.spp, settings.max_depth
        );
        let mut variants = vec!["scalar_rgb"];
        if has_llvm && mitsuba_xml(python, "llvm_ad_rgb", llvm, root, case, &out).is_some() {
            // Warm: the first run filled Dr.Jit's kernel cache.
            variants.insert(0, "llvm_ad_rgb");
        }
        let mut ratios: Vec<(&str, Vec<f64>)> = variants.iter().map(|v| (*v, Vec::new())).collect();
        for run in 0..runs {
            let started = Instant::now();
            raytracer::render(&scene, &settings, &|_: Progress| {}).expect("render");
            let ours = started.elapsed().as_secs_f64();
            let mut line = format!("  round {run}: ours {ours:.2} s");
            for (variant, list) in ratios.iter_mut() {
                if let Some(t) = mitsuba_xml(python, variant, llvm, root, case, &out) {
                    line += &format!(", {variant} {t:.2} s (ours/theirs {:.3})", ours / t);
                    list.push(ours / t);
                }
            }
            println!("{line}");
        }
        for (variant, list) in &ratios {
            if !list.is_empty() {
                println!("  time ratio ours/{variant} on {name}: {} (median, range of rounds)", spread(list));
            }
        }
    }
}
