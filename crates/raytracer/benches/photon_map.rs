//! Photon-map benchmark: `cargo bench -p raytracer --bench photon_map` (add
//! `--features compare-kiddo` to measure the `kiddo` crate's k-d tree on the same data).
//!
//! For each photon-mapping scene, traces its photons as the photon model does, then times the
//! phases of a render: tracing photons, building the search tree, and the k-nearest queries of
//! the gathering pass (at the diffuse points the camera sees, one query a pixel of a 640x380 grid,
//! with the scene's `sample_photons=` and `sample_dist=`), then the whole render at the issue's
//! size. Queries run single-threaded so the structures compare per core. With the comparison on,
//! kiddo's `ImmutableKdTree` answers the same queries, its answers are checked against ours (same
//! counts, same radius), and the ratio of the two query rates is printed. Nothing is asserted:
//! speed is measured, not tested. `RAYTERRA_BENCH_RUNS` sets the runs of the full render (default
//! 3; the median is printed).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::DVec3;
use raytracer::camera::Camera;
use raytracer::integrator::Model;
use raytracer::integrator::photon::{self, PhotonStats};
use raytracer::integrator::photon_map::{Found, PhotonMap};
use raytracer::render::{Progress, RenderSettings};
use raytracer::scene::{self, PhotonSettings, SourceFile};
use raytracer::{PreparedScene, TextureSearch};

struct Case {
    name: &'static str,
    path: PathBuf,
    /// The size the issue times the whole render at.
    size: (u32, u32),
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let assets = root.join("../shared/course-assets/scenes");
    let runs: usize =
        std::env::var("RAYTERRA_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3).max(1);
    let mut cases =
        vec![Case { name: "caustics.txt", path: root.join("scenes/caustics.txt"), size: (640, 380) }];
    if assets.is_dir() {
        cases.push(Case {
            name: "glass-trio-area-light",
            path: assets.join("glass-trio-area-light.txt"),
            size: (640, 380),
        });
        cases.push(Case {
            name: "mirror-ball-area-light",
            path: assets.join("mirror-ball-area-light.txt"),
            size: (420, 420),
        });
    } else {
        eprintln!(
            "**** the course scenes are missing ({}): only the project's scene is measured ****",
            assets.display()
        );
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("rayterra photon-map benchmark ({threads} threads for tracing and building, 1 for queries)");
    for case in &cases {
        let scene = load(&case.path);
        let settings = scene.scene.camera.photons.clone();
        let (map, stats) = photon::build_photon_map(&scene, &settings, 0, &|_, _| {});
        print_phases(case.name, &settings, &stats);
        let queries = query_points(&scene);
        let ours = time_queries(&map, &settings, &queries);
        println!(
            "  queries: {} at k = {}: ours {:.2} M/s a core ({:.2} us each)",
            queries.len(),
            settings.sample_photons,
            queries.len() as f64 / ours.as_secs_f64() / 1e6,
            ours.as_secs_f64() * 1e6 / queries.len() as f64
        );
        #[cfg(feature = "compare-kiddo")]
        compare_kiddo(&map, &settings, &queries, ours);
        let full = median_render(&scene, case.size, runs);
        println!(
            "  whole render at {}x{} (all phases, {threads} threads): {:.2} s, median of {runs}",
            case.size.0,
            case.size.1,
            full.as_secs_f64()
        );
    }
}

fn load(path: &Path) -> PreparedScene {
    let source = SourceFile::read(path).expect("readable scene");
    let parsed = scene::parse(&source).unwrap_or_else(|e| panic!("{}:\n{e}", path.display()));
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::new(parsed.scene, &search).unwrap_or_else(|d| panic!("{d:?}"))
}

fn print_phases(name: &str, settings: &PhotonSettings, stats: &PhotonStats) {
    let trace = stats.trace_time.as_secs_f64();
    println!("{name}:");
    println!(
        "  tracing: {} photons emitted (of {}), {} stored in {:.3} s: {:.2} M photons/s, {:.1} M rays/s",
        stats.emitted,
        settings.emit_photons,
        stats.stored,
        trace,
        stats.emitted as f64 / trace / 1e6,
        stats.rays as f64 / trace / 1e6
    );
    println!(
        "  building: {:.3} s ({:.1} M photons/s), {:.1} bytes a stored photon",
        stats.build_time.as_secs_f64(),
        stats.stored as f64 / stats.build_time.as_secs_f64() / 1e6,
        stats.map_bytes as f64 / stats.stored.max(1) as f64
    );
}

/// The diffuse points seen through a 640x380 grid of pixel centres, with their normals facing the
/// camera: where the gathering pass queries the map first.
fn query_points(scene: &PreparedScene) -> Vec<(DVec3, DVec3)> {
    let (w, h) = (640, 380);
    let camera = Camera::new(&scene.scene.camera, w, h, 1.0);
    let mut points = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let ray = camera.ray(x as f64 + 0.5, y as f64 + 0.5, (0.0, 0.0));
            if let Some((primitive, hit)) = scene.closest_surface(&ray)
                && scene.course_material(primitive).diff > 0.0
            {
                let at = scene.interaction(&ray, primitive, hit);
                points.push((at.point, at.normal));
            }
        }
    }
    points
}

fn time_queries(map: &PhotonMap, settings: &PhotonSettings, queries: &[(DVec3, DVec3)]) -> Duration {
    let k = settings.sample_photons as usize;
    let r2 = (settings.sample_dist * settings.sample_dist) as f32;
    let mut found: Vec<Found> = Vec::new();
    let started = Instant::now();
    let mut total = 0usize;
    for (p, _) in queries {
        total += map.k_nearest(*p, k, r2, &mut found).found;
    }
    std::hint::black_box(total);
    started.elapsed()
}

#[cfg(feature = "compare-kiddo")]
fn compare_kiddo(map: &PhotonMap, settings: &PhotonSettings, queries: &[(DVec3, DVec3)], ours: Duration) {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    use std::num::NonZero;

    let points: Vec<[f32; 3]> = (0..map.len() as u32).map(|i| map.photon(i).position.to_array()).collect();
    let started = Instant::now();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&points).expect("kiddo builds");
    let build = started.elapsed();
    let k = NonZero::new(settings.sample_photons as usize).expect("positive");
    let r2 = (settings.sample_dist * settings.sample_dist) as f32;
    let started = Instant::now();
    let mut total = 0usize;
    for (p, _) in queries {
        let q = p.as_vec3().to_array();
        total += tree.query(&q).nearest_n::<SquaredEuclidean<f32>>(k).within(r2).execute().len();
    }
    let theirs = started.elapsed();
    std::hint::black_box(total);
    // Same answers: the count and the farthest distance of every query.
    let mut found = Vec::new();
    for (p, _) in queries.iter().step_by(97) {
        let q = p.as_vec3().to_array();
        let result = tree.query(&q).nearest_n::<SquaredEuclidean<f32>>(k).within(r2).execute();
        let ours = map.k_nearest(*p, k.get(), r2, &mut found);
        assert_eq!(result.len(), ours.found, "kiddo and ours disagree at {p}");
        if ours.found == k.get() {
            let far = result.iter().map(|r| r.distance).fold(0.0f32, f32::max);
            assert_eq!(far, ours.radius2, "kiddo and ours disagree at {p}");
        }
    }
    println!(
        "  kiddo 6 ImmutableKdTree: build {:.3} s (1 thread), queries {:.2} M/s a core; ours / kiddo query rate = {:.2}",
        build.as_secs_f64(),
        queries.len() as f64 / theirs.as_secs_f64() / 1e6,
        theirs.as_secs_f64() / ours.as_secs_f64()
    );
}

fn median_render(scene: &PreparedScene, (width, height): (u32, u32), runs: usize) -> Duration {
    let mut times: Vec<Duration> = (0..runs)
        .map(|_| {
            let settings =
                RenderSettings { width, height, model: Model::Photon, ..RenderSettings::for_scene(scene) };
            let started = Instant::now();
            raytracer::render(scene, &settings, &|_: Progress| {}).expect("renders");
            started.elapsed()
        })
        .collect();
    times.sort();
    times[times.len() / 2]
}
