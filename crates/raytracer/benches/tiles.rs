//! How evenly `--tile K/N` shares the work of a render, for several block heights: every tile of
//! a few scenes is rendered on its own (one thread), and the bench prints, for each number of tiles
//! and block height, the largest tile's work over the mean (1.00 is a perfect share) and all
//! tiles' work over the whole render's (the rows traced again at block borders for adaptive
//! anti-aliasing), counted in rays (deterministic) and in seconds (noisy on a shared machine).
//!
//! `cargo bench -p raytracer --bench tiles` (course scenes from `../shared/course-assets` when
//! present). This is how [`raytracer::parts::tile_block_rows`] was chosen: the wall time of a
//! tiled render is about (largest / mean) x (all / whole) x whole / N.

use std::path::Path;
use std::time::Instant;

use raytracer::parts::{Split, tile_rows_in_blocks};
use raytracer::render::{RenderSettings, Rows, render_portion};
use raytracer::scene::{self, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

fn load(path: &Path) -> Option<PreparedScene> {
    let source = SourceFile::read(path).ok()?;
    let parsed = scene::parse(&source).ok()?;
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::new(parsed.scene, &search).ok()
}

/// Rays and seconds of rendering `rows` on one thread.
fn cost(scene: &PreparedScene, settings: &RenderSettings, rows: &Rows) -> (u64, f64) {
    let started = Instant::now();
    let portion = render_portion(scene, settings, rows, 0..1, &|_| {}).expect("renders");
    (portion.stats.rays, started.elapsed().as_secs_f64())
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut scenes = vec![
        ("scenes/showcase.txt", root.join("scenes/showcase.txt"), 640, 380),
        ("scenes/cornell.txt", root.join("scenes/cornell.txt"), 512, 512),
        ("scenes/caustics.txt (photon)", root.join("scenes/caustics.txt"), 640, 380),
    ];
    let course = root.join("../shared/course-assets/scenes/classic.txt");
    if course.is_file() {
        scenes.insert(0, ("classic.txt (course)", course, 640, 380));
    } else {
        eprintln!("note: ../shared/course-assets is absent; the course's classic.txt is left out");
    }
    println!(
        "{:<30} {:>5} {:>6} {:>16} {:>16} {:>16}",
        "scene", "tiles", "block", "largest / mean", "all / whole", "product"
    );
    println!(
        "{:<30} {:>5} {:>6} {:>8} {:>7} {:>8} {:>7} {:>8} {:>7}",
        "", "", "rows", "rays", "time", "rays", "time", "rays", "time"
    );
    for (name, path, w, h) in scenes {
        let Some(scene) = load(&path) else {
            eprintln!("cannot load {}", path.display());
            continue;
        };
        let settings = RenderSettings {
            width: w,
            height: h,
            threads: Some(1),
            photons: Some(500_000),
            ..RenderSettings::for_scene(&scene)
        };
        let (whole_rays, whole_time) = cost(&scene, &settings, &Rows::full(w, h));
        for tiles in [4, 8, 16] {
            // The block height tile_rows chooses, marked with a star, among others.
            let chosen = raytracer::parts::tile_block_rows(h, tiles);
            let mut blocks = vec![4, 8, 16, 32, chosen];
            blocks.sort_unstable();
            blocks.dedup();
            for block in blocks {
                let mut rays = Vec::new();
                let mut times = Vec::new();
                for k in 0..tiles {
                    let blocks =
                        tile_rows_in_blocks(h, Split { index: k, count: tiles }, block).expect("tiles");
                    let (r, t) = cost(&scene, &settings, &Rows::from_blocks(w, blocks));
                    rays.push(r as f64);
                    times.push(t);
                }
                let ratio = |v: &[f64]| {
                    v.iter().cloned().fold(0.0, f64::max) / (v.iter().sum::<f64>() / v.len() as f64)
                };
                let (rays_all, times_all) =
                    (rays.iter().sum::<f64>() / whole_rays as f64, times.iter().sum::<f64>() / whole_time);
                println!(
                    "{name:<30} {tiles:>5} {:>6} {:>8.2} {:>7.2} {:>8.3} {:>7.3} {:>8.2} {:>7.2}",
                    format!("{}{block}", if block == chosen { "*" } else { "" }),
                    ratio(&rays),
                    ratio(&times),
                    rays_all,
                    times_all,
                    ratio(&rays) * rays_all,
                    ratio(&times) * times_all,
                );
            }
        }
    }
}
