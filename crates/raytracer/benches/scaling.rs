//! How render time, load time and memory grow with the number of objects:
//! `cargo bench -p raytracer --bench scaling`.
//!
//! - **Spheres**: scenes of 10, 10,000 and 1,000,000 spheres (generated from a seed, in the same
//!   box in front of the camera, radii shrinking with the count so the picture stays about as
//!   full), rendered at 640x380 with one sample a pixel: the same number of camera rays whatever
//!   the count. Prints the time to load (parse and prepare) each scene, the bytes its geometry
//!   takes per sphere ([`PreparedScene::geometry_memory`]), and the render time and its ratio to
//!   the 10-sphere render.
//! - **Triangles**: a sphere subdivided into about 1,000 and about 1,000,000 triangles and
//!   displaced by noise (from a seed), written as OBJ files and loaded as `primitive mesh` over a
//!   floor, rendered at 1280x720 with the default adaptive sampling. Prints the time to read and
//!   build the mesh, the bytes a triangle, and the render time and the ratio of the two renders.
//!
//! Times are wall-clock, median of `RAYTERRA_BENCH_RUNS` runs (default 3; loads and renders
//! alike), all threads; the ratios are what docs/raytracer-speed.md quotes. Nothing is asserted: speed is
//! measured, not tested.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::scene::{self, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

fn main() {
    let runs: usize =
        std::env::var("RAYTERRA_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3).max(1);
    let only = std::env::args().skip(1).find(|a| a == "spheres" || a == "triangles");
    if only.as_deref() != Some("triangles") {
        spheres(runs);
    }
    if only.as_deref() != Some("spheres") {
        triangles(runs);
    }
}

fn spheres(runs: usize) {
    println!("spheres at 640x380, 1 sample a pixel, median of {runs} runs");
    println!(
        "{:>9} {:>10} {:>14} {:>10} {:>12} {:>10}",
        "spheres", "load", "bytes/sphere", "render", "vs 10", "rays"
    );
    let mut base = None;
    for n in [10usize, 10_000, 1_000_000] {
        let text = sphere_scene(n, 7);
        let (prepared, load) = median_load(&format!("{n}-spheres.txt"), &text, None, runs);
        let per_sphere = prepared.geometry_memory() as f64 / n as f64;
        let settings = RenderSettings {
            width: 640,
            height: 380,
            sampling: Sampling::Uniform(1),
            ..RenderSettings::for_scene(&prepared)
        };
        let (time, rays) = median_render(&prepared, &settings, runs);
        let base = *base.get_or_insert(time);
        println!(
            "{n:>9} {:>9.3}s {:>14.0} {:>9.3}s {:>11.1}x {:>10}",
            load,
            per_sphere,
            time,
            time / base,
            rays
        );
    }
}

fn triangles(runs: usize) {
    println!("a displaced sphere mesh at 1280x720, adaptive sampling, median of {runs} runs");
    println!("{:>10} {:>12} {:>12} {:>10} {:>10}", "triangles", "read+build", "bytes/tri", "render", "vs 1k");
    let dir = tempfile::tempdir().expect("temporary folder");
    let mut base = None;
    // 16 and 500 rings: 960 and 998,000 triangles.
    for rings in [16, 500] {
        let (obj, count) = displaced_sphere(rings, 3);
        let path = dir.path().join(format!("sphere-{count}.obj"));
        std::fs::write(&path, obj).expect("write the mesh");
        let text = format!(
            "background\n color= 0.1 0.1 0.15\nend\n\
             camera\n O= 0 -4 1.2\n N= 0 1 -0.3\n image_W= 1280\n image_H= 720\n lens_W= 0.8\n lens_H= 0.45\nend\n\
             light point\n O= 3 -4 5\n color= 0.9 0.9 0.9\nend\n\
             primitive plane\n N= 0 0 1\n R= -1.1\n color= 0.8 0.8 0.8\n diff= 0.6\n refl= 0.3\nend\n\
             primitive mesh\n file= {}\n color= 0.9 0.5 0.3\n diff= 0.8\n spec= 0.3\nend\n",
            path.display()
        );
        let (prepared, load) = median_load("mesh.txt", &text, Some(dir.path()), runs);
        let stats = prepared.mesh_stats();
        let settings = RenderSettings { width: 1280, height: 720, ..RenderSettings::for_scene(&prepared) };
        let (time, _) = median_render(&prepared, &settings, runs);
        let base = *base.get_or_insert(time);
        println!(
            "{:>10} {:>11.3}s {:>12.0} {:>9.3}s {:>9.2}x",
            stats.triangles,
            load,
            stats.bytes as f64 / stats.triangles as f64,
            time,
            time / base
        );
    }
}

/// Loads the scene `runs` times ([`load_text`]); returns the last load and the median time.
fn median_load(name: &str, text: &str, dir: Option<&Path>, runs: usize) -> (PreparedScene, f64) {
    let mut times = Vec::with_capacity(runs);
    let mut prepared = None;
    for _ in 0..runs {
        let text = text.to_owned();
        drop(prepared.take());
        let started = Instant::now();
        prepared = Some(load_text(name, text, dir));
        times.push(started.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (prepared.expect("at least one run"), times[times.len() / 2])
}

/// Parses and prepares scene text; prints the time of each step with `RAYTERRA_BENCH_VERBOSE`.
fn load_text(name: &str, text: String, dir: Option<&Path>) -> PreparedScene {
    let started = Instant::now();
    let source = SourceFile::from_text(name, dir.map(Path::to_path_buf), text);
    let parsed = scene::parse(&source).expect("a valid scene");
    let parse = started.elapsed().as_secs_f64();
    let prepared = PreparedScene::new(parsed.scene, &TextureSearch::default()).expect("prepared");
    if std::env::var_os("RAYTERRA_BENCH_VERBOSE").is_some() {
        eprintln!("  parse {parse:.3} s, prepare {:.3} s", started.elapsed().as_secs_f64() - parse);
    }
    prepared
}

fn median_render(scene: &PreparedScene, settings: &RenderSettings, runs: usize) -> (f64, u64) {
    let mut times = Vec::with_capacity(runs);
    let mut rays = 0;
    for _ in 0..runs {
        let started = Instant::now();
        let rendered = raytracer::render(scene, settings, &|_: Progress| {}).expect("render");
        times.push(started.elapsed().as_secs_f64());
        rays = rendered.stats.rays;
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], rays)
}

/// A small deterministic generator of uniform numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` spheres at random in the box `[-4, 4] x [4, 12] x [-2.4, 2.4]` seen by the camera, with
/// radii so that they cover about as much of the picture whatever `n`, in eight materials.
fn sphere_scene(n: usize, seed: u64) -> String {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut s = String::with_capacity(n * 120 + 1000);
    s.push_str(
        "background\n color= 0.1 0.1 0.1\nend\n\
         camera\n O= 0 -2 0\n N= 0 1 0\n image_W= 640\n image_H= 380\n lens_W= 1.0\n lens_H= 0.59375\nend\n\
         light point\n O= 2 -1 4\n color= 1 1 1\nend\n",
    );
    // Spheres of radius r in a volume V cover about n pi r^2 / (V^(2/3)) of a view across it.
    let radius = 0.6 * (8.0 * 8.0 * 4.8 / n as f64).powf(1.0 / 3.0);
    for _ in 0..n {
        let (x, y, z) = (rng.uniform() * 8.0 - 4.0, rng.uniform() * 8.0 + 4.0, rng.uniform() * 4.8 - 2.4);
        let m = (rng.uniform() * 8.0) as usize;
        let (r, g, b) = (0.3 + 0.1 * (m % 3) as f64, 0.4 + 0.15 * (m % 2) as f64, 0.8 - 0.1 * m as f64);
        let _ = writeln!(
            s,
            "primitive sphere\n O= {x:.5} {y:.5} {z:.5}\n R= {radius:.5}\n color= {r:.2} {g:.2} {b:.2}\n diff= 0.8\n spec= 0.2\nend"
        );
    }
    s
}

/// A unit sphere as a grid of `k` rings of `2 k` quads (each two triangles; the poles fans),
/// displaced along the normal by a sum of a few sines with seeded phases: about `4 k^2`
/// triangles. Returns the OBJ text and the triangle count.
fn displaced_sphere(k: usize, seed: u64) -> (String, usize) {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let waves: Vec<(f64, f64, f64, f64)> = (0..6)
        .map(|i| {
            (
                rng.uniform() * std::f64::consts::TAU,
                rng.uniform() * std::f64::consts::TAU,
                2.0 + i as f64 * 1.7,
                0.05 / (1.0 + i as f64),
            )
        })
        .collect();
    let height = |x: f64, y: f64, z: f64| {
        1.0 + waves
            .iter()
            .map(|&(p, q, f, a)| a * (f * x + p).sin() * (f * y + q).cos() * (f * z).sin())
            .sum::<f64>()
    };
    let mut obj = String::with_capacity(k * k * 2 * 60);
    let around = 2 * k;
    let mut count = 0;
    // Vertices: the two poles, then k - 1 rings.
    for p in [1.0f64, -1.0] {
        let h = height(0.0, 0.0, p);
        let _ = writeln!(obj, "v 0 0 {:.6}", p * h);
    }
    for i in 1..k {
        let theta = std::f64::consts::PI * i as f64 / k as f64;
        for j in 0..around {
            let phi = std::f64::consts::TAU * j as f64 / around as f64;
            let (x, y, z) = (theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            let h = height(x, y, z);
            let _ = writeln!(obj, "v {:.6} {:.6} {:.6}", x * h, y * h, z * h);
        }
    }
    let ring = |i: usize, j: usize| 3 + (i - 1) * around + j % around;
    for j in 0..around {
        let _ = writeln!(obj, "f 1 {} {}", ring(1, j), ring(1, j + 1));
        let _ = writeln!(obj, "f 2 {} {}", ring(k - 1, j + 1), ring(k - 1, j));
        count += 2;
    }
    for i in 1..k - 1 {
        for j in 0..around {
            let _ = writeln!(
                obj,
                "f {} {} {} {}",
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1)
            );
            count += 2;
        }
    }
    (obj, count)
}
