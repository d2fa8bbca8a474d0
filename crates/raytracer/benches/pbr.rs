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
//!    `../shared/mitsuba-data` (skipped, loudly, without it); and `cbox.xml` with its small box
//!    replaced by a ball of 1,046,528 triangles (a bumpy sphere the bench writes as a binary PLY
//!    under `target/bench-data/`, with the scene file beside it), for a scene of a million
//!    triangles read by both.
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
    let mut cases = vec![
        XmlCase { path: data.join("scenes/cbox/cbox.xml"), defines: d(&[("res", "256")]), spp: 64 },
        XmlCase {
            path: data.join("scenes/matpreview/matpreview.xml"),
            defines: d(&[("width", "256"), ("height", "192")]),
            spp: 64,
        },
    ];
    match million_triangle_scene(root, &data) {
        Ok(path) => cases.push(XmlCase { path, defines: d(&[("res", "256")]), spp: 64 }),
        Err(e) => println!("**** the million-triangle scene could not be written: {e} ****"),
    }
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

/// Rows and columns of the bumpy ball's latitude-longitude grid: 2 x 1024 x 511 = 1,046,528
/// triangles (the rows at the poles are fans of one triangle a column).
const BALL_GRID: (usize, usize) = (512, 1024);

/// Writes (once) `target/bench-data/ball.ply`, a unit sphere whose radius varies by up to 4% in a
/// pattern of bumps, and `cbox-million.xml` beside it: Mitsuba's `cbox.xml` with the ball, 90
/// units across its radius, where the small box stood (paths made absolute).
fn million_triangle_scene(root: &Path, data: &Path) -> std::io::Result<PathBuf> {
    use std::io::Write;
    let dir = root.join("target/bench-data");
    std::fs::create_dir_all(&dir)?;
    let ply = dir.join("ball.ply");
    let (rows, cols) = BALL_GRID;
    if !ply.is_file() {
        let mut vertices: Vec<[f32; 3]> = vec![[0.0, 0.0, 1.0]];
        for r in 1..rows {
            let theta = std::f64::consts::PI * r as f64 / rows as f64;
            for c in 0..cols {
                let phi = std::f64::consts::TAU * c as f64 / cols as f64;
                let bump = 1.0 + 0.04 * (7.0 * theta).sin() * (9.0 * phi).cos();
                let (st, ct) = theta.sin_cos();
                let (sp, cp) = phi.sin_cos();
                vertices.push([(bump * st * cp) as f32, (bump * st * sp) as f32, (bump * ct) as f32]);
            }
        }
        vertices.push([0.0, 0.0, -1.0]);
        let ring = |r: usize, c: usize| (1 + (r - 1) * cols + c % cols) as i32;
        let south = vertices.len() as i32 - 1;
        let mut faces: Vec<[i32; 3]> = Vec::with_capacity(2 * cols * (rows - 1));
        for c in 0..cols {
            faces.push([0, ring(1, c), ring(1, c + 1)]);
            faces.push([south, ring(rows - 1, c + 1), ring(rows - 1, c)]);
        }
        for r in 1..rows - 1 {
            for c in 0..cols {
                faces.push([ring(r, c), ring(r + 1, c), ring(r + 1, c + 1)]);
                faces.push([ring(r, c), ring(r + 1, c + 1), ring(r, c + 1)]);
            }
        }
        let mut out = Vec::with_capacity(vertices.len() * 12 + faces.len() * 13 + 256);
        write!(
            out,
            "ply\nformat binary_little_endian 1.0\ncomment a bumpy ball written by rayterra's pbr bench\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar int vertex_indices\nend_header\n",
            vertices.len(),
            faces.len()
        )?;
        for v in &vertices {
            for x in v {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        for f in &faces {
            out.push(3);
            for i in f {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        let partial = dir.join("ball.ply.partial");
        std::fs::write(&partial, out)?;
        std::fs::rename(&partial, &ply)?;
    }
    let cbox = data.join("scenes/cbox");
    let text = std::fs::read_to_string(cbox.join("cbox.xml"))?;
    let small_box = "<string name=\"filename\" value=\"meshes/cbox_smallbox.obj\"/>";
    if !text.contains(small_box) {
        return Err(std::io::Error::other("cbox.xml has no small box to replace"));
    }
    let ball = format!(
        "<string name=\"filename\" value=\"{}\"/>\n        <transform name=\"to_world\">\
         <scale value=\"90\"/><translate x=\"186\" y=\"92\" z=\"170\"/></transform>",
        ply.display()
    );
    let text = text
        .replace(
            &format!("<shape type=\"obj\">\n        {small_box}"),
            &format!("<shape type=\"ply\">\n        {ball}"),
        )
        .replace("value=\"meshes/", &format!("value=\"{}/meshes/", cbox.display()));
    let xml = dir.join("cbox-million.xml");
    std::fs::write(&xml, text)?;
    Ok(xml)
}
