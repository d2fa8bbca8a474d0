//! The physically based models end to end: SPPM agrees with the path tracer on the Cornell box
//! and its error falls as passes grow (the estimator is consistent); white furnaces; the
//! analytic point light under SPPM; images that do not depend on the thread count; and renders
//! split into pixel rectangles and sample ranges that merge into the very same values (issue 12).

mod support;

use glam::DVec3;
use raytracer::integrator::Model;
use raytracer::integrator::sppm::{self, SppmSettings};
use raytracer::parts::Split;
use raytracer::render::{RenderSettings, Rows, Sampling, camera_for, path_sums};
use raytracer::sampler::ExactSum;
use support::pbr::{Halves, compare, path_halves, render_model};
use support::{from_text, load, workspace};

/// Pixels of the test renders of the Cornell box, and the block side of comparisons.
const SIZE: (u32, u32) = (32, 32);
const BLOCK: u32 = 8;

/// The relative RMS difference of the 8x8 block means (all channels) of `a` against `b`.
fn block_error(a: &Halves, b: &Halves) -> f64 {
    let (w, h) = (a.width, a.height);
    let (mut sum, mut count) = (0.0, 0);
    for by in 0..h / BLOCK {
        for bx in 0..w / BLOCK {
            for c in 0..3 {
                let (mut x, mut y) = (0.0, 0.0);
                for py in by * BLOCK..(by + 1) * BLOCK {
                    for px in bx * BLOCK..(bx + 1) * BLOCK {
                        let i = (py * w + px) as usize;
                        x += a.mean[i][c];
                        y += b.mean[i][c];
                    }
                }
                if y > 0.0 {
                    sum += ((x - y) / y).powi(2);
                    count += 1;
                }
            }
        }
    }
    (sum / count as f64).sqrt()
}

#[test]
fn sppm_agrees_with_the_path_tracer_and_converges_as_passes_grow() {
    let scene = load(&workspace().join("scenes/cornell-box.txt"));
    let reference = path_halves(&scene, SIZE, 2048);
    let photons = Some(20_000);
    let sppm =
        |passes: u64, seed: u64| render_model(&scene, Model::Sppm, SIZE, 1, seed, Some(passes), photons);
    // The error against the path tracer falls as passes grow.
    let errors: Vec<(u64, f64)> = [4, 16, 64]
        .into_iter()
        .map(|passes| {
            let one = sppm(passes, 0);
            (passes, block_error(&Halves::new(&one, &one), &reference))
        })
        .collect();
    eprintln!("sppm against path, relative RMS error of 8x8 blocks by passes: {errors:?}");
    assert!(errors.windows(2).all(|w| w[1].1 < w[0].1), "the error must fall: {errors:?}");
    // After enough passes, every block agrees as the path tracer agrees with Mitsuba.
    let converged = Halves::new(&sppm(160, 0), &sppm(160, 1));
    let a = compare(&converged, &reference, BLOCK, 0.02, 1e-4, |_, _| true);
    eprintln!("sppm (2 x 160 passes) against path (2048 spp): {a:?}");
    assert!(a.failures.is_empty(), "{}", a.failures.join("\n"));
    assert!(a.whole.iter().all(|w| w.abs() < 0.01), "{:?}", a.whole);
}

/// A furnace: an object in a uniform environment of radiance 0.5 that only reflects and
/// transmits (albedo 1) looks exactly like the environment.
fn furnace(object: &str) -> raytracer::PreparedScene {
    from_text(&format!(
        "background\n color= 0.5 0.5 0.5\nend\n\
         camera\n O= 0 -4 0\n N= 0 1 0\n lens_W= 0.3\n lens_H= 0.3\nend\n{object}"
    ))
}

#[test]
fn white_furnaces_are_white() {
    // A Lambertian sphere of albedo 1: exactly 0.5 in every sample of the path tracer.
    let diffuse = furnace("primitive sphere\n O= 0 0 0\n R= 1\n color= 1 1 1\n diff= 1\nend\n");
    let image = render_model(&diffuse, Model::Path, (8, 8), 4, 0, None, None);
    assert!(image.pixels().iter().flatten().all(|&v| (v - 0.5).abs() < 1e-6), "{:?}", image.pixels());
    // Glass (no Fresnel loss, radiance scaled in and out by eta^2): 0.5 on average, Russian
    // roulette being the only noise. A deep limit: the light bounces inside.
    let glass = furnace("primitive sphere\n O= 0 0 0\n R= 1\n refr= 1\n rindex= 1.5\nend\n");
    let settings = RenderSettings {
        width: 8,
        height: 8,
        sampling: Sampling::Uniform(256),
        model: Model::Path,
        max_depth: 64,
        ..RenderSettings::for_scene(&glass)
    };
    let image = raytracer::render(&glass, &settings, &|_| {}).expect("render").image;
    let values: Vec<f64> = image.pixels().iter().flatten().map(|&v| v as f64).collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    assert!((mean - 0.5).abs() < 0.005, "glass furnace: {mean}");
    // SPPM: the environment's light reaches the diffuse sphere through photons only.
    let image = render_model(&diffuse, Model::Sppm, (8, 8), 1, 0, Some(32), Some(20_000));
    let mean = image.pixels().iter().flatten().map(|&v| v as f64).sum::<f64>() / 192.0;
    assert!((mean - 0.5).abs() < 0.01, "sppm furnace: {mean}");
}

#[test]
fn sppm_gives_the_analytic_radiance_under_a_point_light() {
    // Direct light comes from next-event estimation, and a lone plane has no indirect light:
    // L = albedo / pi * I cos / d^2 at every visible point, whatever the passes.
    let scene = from_text(
        "camera\n O= 0 0 2\n N= 0 0 -1\n lens_W= 0.0002\n lens_H= 0.0002\nend\n\
         light point\n O= 1 0 2\n color= 3 3 3\nend\n\
         primitive plane\n N= 0 0 1\n R= 0\n color= 0.8 0.6 0.4\n diff= 0.9\nend\n",
    );
    let image = render_model(&scene, Model::Sppm, (4, 4), 1, 0, Some(2), Some(1000));
    let d2: f64 = 1.0 + 4.0;
    let expect = DVec3::new(0.8, 0.6, 0.4) * 0.9 / std::f64::consts::PI * 3.0 * (2.0 / d2.sqrt()) / d2;
    for p in image.pixels() {
        // The view is 0.0004 wide: the cosine and distance vary by less than 0.01%.
        let got = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        assert!((got - expect).abs().max_element() < 2e-3 * expect.max_element(), "{got} vs {expect}");
    }
}

#[test]
fn physically_based_renders_do_not_depend_on_threads() {
    let scene = load(&workspace().join("scenes/absorbing-glass.txt"));
    for model in [Model::Path, Model::Sppm] {
        let render = |threads| {
            let settings = RenderSettings {
                width: 24,
                height: 18,
                sampling: Sampling::Uniform(4),
                threads: Some(threads),
                model,
                passes: Some(3),
                photons: Some(3000),
                ..RenderSettings::for_scene(&scene)
            };
            raytracer::render(&scene, &settings, &|_| {}).expect("render").image
        };
        let one = render(1);
        assert!(one.pixels() == render(3).pixels(), "{model:?}: 1 and 3 threads differ");
    }
}

#[test]
fn tiles_and_sample_ranges_merge_into_the_same_values() {
    // Depth of field too: the lens samples come from the same streams.
    let text = std::fs::read_to_string(workspace().join("scenes/glossy.txt")).expect("scene");
    let scene = from_text(&text.replace("    image_H= 480\n", "    image_H= 480\n    aperture= 0.05\n"));
    let settings =
        RenderSettings { width: 16, height: 12, model: Model::Path, ..RenderSettings::for_scene(&scene) };
    let full = Rows::full(16, 12);
    let (whole, _) = path_sums(&scene, &settings, &full, 0..8, &|_| {});
    // Passes: samples 0..3, 3..8.
    let (mut merged, _) = path_sums(&scene, &settings, &full, 0..3, &|_| {});
    let (rest, _) = path_sums(&scene, &settings, &full, 3..8, &|_| {});
    merged.iter_mut().zip(&rest).for_each(|(a, b)| a.merge(b));
    assert_eq!(whole, merged, "sample ranges must merge exactly");
    // Tiles: a tile's rows render exactly as in the whole image.
    let tile = Rows::tile(16, 12, Split { index: 1, count: 3 }).expect("tile");
    let (part, _) = path_sums(&scene, &settings, &tile, 0..8, &|_| {});
    for (i, sum) in part.iter().enumerate() {
        let (x, y) = (i % 16, tile.ys().nth(i / 16).expect("row") as usize);
        assert_eq!(*sum, whole[y * 16 + x], "pixel ({x}, {y})");
    }
    // The image is the mean of the sums.
    let image = raytracer::render(
        &scene,
        &RenderSettings { sampling: Sampling::Uniform(8), ..settings.clone() },
        &|_| {},
    )
    .expect("render")
    .image;
    let means: Vec<[f32; 3]> = whole.iter().map(|s: &ExactSum| s.mean(8).as_vec3().to_array()).collect();
    assert!(image.pixels() == means.as_slice());
    // SPPM: a tile's rows render as in the whole image.
    let sppm_settings = SppmSettings {
        passes: 2,
        photons: 2000,
        ..SppmSettings::new(&scene.scene.camera.photons, false, None, 10, 0)
    };
    let camera = camera_for(&scene, &settings);
    let (all, _) = sppm::render(&scene, &camera, &sppm_settings, &Rows::full(16, 12), &|_| {});
    let rows = Rows::from_blocks(16, vec![2..3, 6..12]);
    let (part, _) = sppm::render(&scene, &camera, &sppm_settings, &rows, &|_| {});
    for (i, c) in part.iter().enumerate() {
        let (x, y) = (i % 16, rows.ys().nth(i / 16).expect("row") as usize);
        assert_eq!(*c, all[y * 16 + x], "sppm pixel ({x}, {y})");
    }
}
