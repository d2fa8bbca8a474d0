//! The course's photon mapper (spec section 10) end to end: estimates that converge to known
//! irradiances, caustics where glass focuses light, the course's photon-mapping scenes rendered
//! without over-exposure, and images that do not depend on the thread count.

mod support;

use glam::DVec3;
use raytracer::geometry::Ray;
use raytracer::integrator::classic::TraceContext;
use raytracer::integrator::photon::{PhotonEstimate, build_photon_map};
use raytracer::integrator::{Classic, Model};
use raytracer::render::{Progress, RenderSettings, Sampling};
use raytracer::sampler::{PixelRng, Siblings};
use raytracer::scene::{self, PhotonSettings, SourceFile};
use raytracer::{PreparedScene, TextureSearch};
use support::{course_assets, from_text, load, workspace};

/// A diffuse plane z = 0 of colour `0.8 0.6 0.4` and `diff= 0.9` under `light`, with the given
/// photon settings and an ambient background of 0.1.
fn plane_under(light: &str, emit: u64, k: u64, dist: f64) -> PreparedScene {
    from_text(&format!(
        "background\n color= 0.1 0.1 0.1\nend\n\
         camera\n emit_photons= {emit}\n max_photons= {emit}\n sample_photons= {k}\n sample_dist= {dist}\nend\n\
         {light}\n\
         primitive plane\n N= 0 0 1\n R= 0\n color= 0.8 0.6 0.4\n diff= 0.9\nend\n"
    ))
}

/// The relative errors of the estimate against `exact` over 64 points of the circle of radius
/// `rho` around the origin of the plane: `(error of the mean, root mean square of each point's)`.
fn ring_error(scene: &PreparedScene, rho: f64, exact: &dyn Fn(DVec3) -> f64) -> (f64, f64) {
    let settings = scene.scene.camera.photons.clone();
    let (map, stats) = build_photon_map(scene, &settings, 0, &|_, _| {});
    assert_eq!(stats.emitted, settings.emit_photons);
    let estimate = PhotonEstimate::new(&map, &settings);
    let (mut got, mut want, mut squares) = (0.0, 0.0, 0.0);
    for i in 0..64 {
        let a = i as f64 / 64.0 * std::f64::consts::TAU;
        let p = DVec3::new(rho * a.cos(), rho * a.sin(), 0.0);
        let e = estimate.irradiance(p, DVec3::Z);
        // A grey light: every channel carries the same estimate.
        assert!((e.x - e.y).abs() <= 1e-6 * e.x && (e.x - e.z).abs() <= 1e-6 * e.x, "{e}");
        let x = exact(p);
        got += e.x;
        want += x;
        squares += ((e.x - x) / x).powi(2);
    }
    ((got - want).abs() / want, (squares / 64.0).sqrt())
}

/// Whether the ring's mean error is within three standard errors of its 64 estimates (their noise
/// is nearly independent) plus the k-nearest estimator's own bias (`k / (k - 1)`, under 1%).
fn unbiased(mean: f64, rms: f64) -> bool {
    mean < 3.0 * rms / 64f64.sqrt() + 0.01
}

#[test]
fn a_point_light_estimate_converges_to_its_irradiance() {
    // Irradiance I cos / d^2 from a light of colour 2 at height 1: 2 / (1 + rho^2)^(3/2).
    let light = "light point\n O= 0 0 1\n color= 2 2 2\nend";
    let exact = |p: DVec3| 2.0 / (1.0 + p.length_squared()).powf(1.5);
    // More photons, and more of them in each estimate (as sqrt of the count), make the estimate
    // both less noisy and less blurred: the error falls.
    let runs = [(20_000, 40), (200_000, 150), (2_000_000, 500)];
    let errors: Vec<(f64, f64)> =
        runs.iter().map(|&(n, k)| ring_error(&plane_under(light, n, k, 0.5), 0.5, &exact)).collect();
    eprintln!("point light: relative errors (of the mean, rms) {errors:?} with (photons, k) = {runs:?}");
    let rms: Vec<f64> = errors.iter().map(|e| e.1).collect();
    assert!(rms[0] > rms[1] && rms[1] > rms[2], "the error must fall as photons grow: {rms:?}");
    assert!(rms[2] < 0.06, "{rms:?}");
    assert!(errors.iter().all(|&(mean, rms)| unbiased(mean, rms)), "biased on average: {errors:?}");
}

#[test]
fn a_square_light_estimate_converges_to_the_mean_over_its_area() {
    let light = "light square\n O= 0 0 1\n Dx= 0.5 0 0\n Dy= 0 0.5 0\n color= 3 3 3\nend";
    // The mean of I cos / d^2 over the light's points (64 x 64 midpoint rule).
    let exact = |p: DVec3| {
        let n = 64;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let q = DVec3::new((i as f64 + 0.5) / n as f64 - 0.5, (j as f64 + 0.5) / n as f64 - 0.5, 1.0);
                let d = q - p;
                sum += 3.0 * d.z / d.length().powi(3);
            }
        }
        sum / (n * n) as f64
    };
    let (mean, rms) = ring_error(&plane_under(light, 1_000_000, 300, 0.5), 0.4, &exact);
    assert!(unbiased(mean, rms) && rms < 0.08, "relative errors: of the mean {mean}, rms {rms}");
}

#[test]
fn the_pixel_is_colour_diff_times_ambient_plus_irradiance() {
    let scene = plane_under("light point\n O= 0 0 1\n color= 2 2 2\nend", 200_000, 100, 0.5);
    let settings = scene.scene.camera.photons.clone();
    let (map, _) = build_photon_map(&scene, &settings, 0, &|_, _| {});
    let estimate = PhotonEstimate::new(&map, &settings);
    let classic = Classic::with_photons(&scene, estimate);
    let mut rng = PixelRng::new(0, 0, 0, 0);
    let mut cx = TraceContext::new(&mut rng);
    let ray = Ray::new(DVec3::new(0.3, 0.0, 2.0), DVec3::new(0.0, 0.0, -1.0));
    let c = classic.radiance(&mut cx, &ray, Siblings::ALONE, None);
    let e = estimate.irradiance(DVec3::new(0.3, 0.0, 0.0), DVec3::Z);
    let expect = (DVec3::new(0.8, 0.6, 0.4) * 0.9 * (DVec3::splat(0.1) + e)).min(DVec3::ONE);
    assert!((c - expect).abs().max_element() < 1e-9, "{c} vs {expect}");
    assert_eq!((cx.rays, cx.lookups), (1, 1), "one camera ray, one lookup, no shadow ray");
}

/// The brightest ratio of floor irradiance with the glass to floor irradiance without it, over a
/// grid of floor points around each glass sphere of `path`'s scene (floor `z = floor_z`).
fn caustic_gain(path: &std::path::Path, photons: u64) -> Vec<f64> {
    let source = SourceFile::read(path).expect("readable");
    let parsed = scene::parse(&source).expect("parses");
    let search = TextureSearch { scene_dir: source.dir().map(|d| d.to_path_buf()), extra_dirs: Vec::new() };
    let spheres: Vec<(DVec3, f64)> = parsed
        .scene
        .primitives
        .iter()
        .filter(|p| p.material.as_course().is_some_and(|m| m.refr > 0.0))
        .filter_map(|p| match &p.shape {
            raytracer::geometry::Shape::Sphere(s) => Some((s.centre, s.radius)),
            _ => None,
        })
        .collect();
    assert!(!spheres.is_empty(), "{} has no glass ball", path.display());
    let with_glass = PreparedScene::new(parsed.scene.clone(), &search).expect("prepares");
    let mut clear = parsed.scene;
    clear.primitives.retain(|p| p.material.as_course().is_some_and(|m| m.refr == 0.0));
    let without_glass = PreparedScene::new(clear, &search).expect("prepares");
    let estimates = [&with_glass, &without_glass].map(|scene| {
        let mut settings: PhotonSettings = scene.scene.camera.photons.clone();
        settings.emit_photons = photons;
        build_photon_map(scene, &settings, 0, &|_, _| {})
    });
    let settings = PhotonSettings { emit_photons: photons, ..with_glass.scene.camera.photons.clone() };
    let [lit, plain] = [&estimates[0].0, &estimates[1].0].map(|map| PhotonEstimate::new(map, &settings));
    spheres
        .iter()
        .map(|&(centre, r)| {
            let floor = centre.z - r;
            let mut best: f64 = 0.0;
            // Within 1.5 radii of the contact point (the caustic lies within one radius of it).
            for i in -6..=6 {
                for j in -6..=6 {
                    let p = DVec3::new(centre.x + i as f64 * r / 4.0, centre.y + j as f64 * r / 4.0, floor);
                    let (a, b) = (lit.irradiance(p, DVec3::Z), plain.irradiance(p, DVec3::Z));
                    let (a, b) = (a.x + a.y + a.z, b.x + b.y + b.z);
                    if b > 0.0 {
                        best = best.max(a / b);
                    }
                }
            }
            best
        })
        .collect()
}

#[test]
fn glass_balls_focus_light_into_caustics_on_the_floor() {
    // Brighter than the same floor lit with no glass in the way: light is concentrated, not only
    // let through.
    let gains = caustic_gain(&workspace().join("scenes/caustics.txt"), 1_000_000);
    eprintln!("caustics.txt: brightest gain near each glass ball {gains:?}");
    assert!(gains.iter().all(|&g| g > 3.0), "{gains:?}");
}

#[test]
fn the_course_glass_trio_has_a_caustic_under_each_ball() {
    let Some(assets) = course_assets() else { return };
    let gains = caustic_gain(&assets.join("scenes/glass-trio-area-light.txt"), 1_000_000);
    eprintln!("glass-trio-area-light.txt: brightest gain near each glass ball {gains:?}");
    assert_eq!(gains.len(), 3);
    assert!(gains.iter().all(|&g| g > 3.0), "{gains:?}");
}

/// Fraction of pixels with some channel at 255.
fn saturated(image: &image::RgbImage) -> f64 {
    image.pixels().filter(|p| p.0.contains(&255)).count() as f64 / (image.width() * image.height()) as f64
}

fn render(
    scene: &PreparedScene,
    w: u32,
    h: u32,
    model: Model,
    photons: Option<u64>,
    threads: Option<usize>,
) -> image::RgbImage {
    let settings = RenderSettings {
        width: w,
        height: h,
        model,
        photons,
        threads,
        sampling: Sampling::Adaptive,
        ..RenderSettings::for_scene(scene)
    };
    raytracer::render(scene, &settings, &|_: Progress| {}).expect("renders").image.to_rgb8(false)
}

#[test]
fn the_course_photon_scenes_are_not_over_exposed_in_the_photon_model() {
    let Some(assets) = course_assets() else { return };
    for name in [
        "glass-trio-area-light",
        "diffuse-ball-area-light",
        "mirror-ball-area-light",
        "glass-ball-area-light",
    ] {
        let scene = load(&assets.join(format!("scenes/{name}.txt")));
        let photon = render(&scene, 96, 57, Model::Photon, Some(300_000), None);
        let classic = render(&scene, 96, 57, Model::Classic, None, None);
        let (p, c) = (saturated(&photon), saturated(&classic));
        eprintln!("{name}: saturated pixels photon {p:.3}, classic {c:.3}");
        assert!(p < 0.02, "{name}: {p} of the photon model's pixels are saturated");
        assert!(c > 0.2, "{name}: the classic model should over-expose this file ({c})");
    }
}

#[test]
fn photon_renders_do_not_depend_on_threads() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    let one = render(&scene, 64, 38, Model::Photon, Some(100_000), Some(1));
    let three = render(&scene, 64, 38, Model::Photon, Some(100_000), Some(3));
    assert!(one == three, "1 and 3 threads rendered different images");
}

#[test]
fn the_photon_map_does_not_depend_on_threads_and_stops_when_full() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    let settings =
        PhotonSettings { emit_photons: 300_000, max_photons: 50_000, ..scene.scene.camera.photons.clone() };
    let build = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| build_photon_map(&scene, &settings, 7, &|_, _| {}))
    };
    let (a, sa) = build(1);
    let (b, sb) = build(3);
    assert_eq!(sa.stored, 50_000);
    assert!(sa.emitted < 300_000, "tracing stops once the map is full ({} emitted)", sa.emitted);
    assert_eq!((sa.emitted, sa.stored), (sb.emitted, sb.stored));
    for i in 0..a.len() as u32 {
        assert_eq!(a.photon(i), b.photon(i));
    }
}
