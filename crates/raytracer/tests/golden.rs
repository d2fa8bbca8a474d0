//! Golden images: small renders of the project's own scenes, compared with committed images.
//!
//! A missing golden is a failure. To create or refresh goldens on purpose, run
//! `RAYTERRA_BLESS=1 cargo test -p raytracer --test golden` and look at the images in
//! `crates/raytracer/tests/golden/` before committing them.

mod support;

use std::path::PathBuf;

use support::{difference, load, render, workspace, write_failure_images};

/// Tolerances. Renders are deterministic, so on one machine the image is the golden bit for bit;
/// last-bit differences of floating-point libraries across machines may flip the refinement of
/// a few pixels. Anything more is a change: the drift these tolerances were tightened against
/// (5% of the showcase's pixels off by up to 16 steps, after changes to sampling) fails.
const MAX_MEAN: f64 = 0.1;
/// At most this fraction of pixels may differ by more than 2 steps of 255 (0.2%: 30 pixels of
/// a 160x95 image).
const MAX_FRACTION_OVER_2: f64 = 0.002;
/// At most this fraction of pixels may differ by more than 24 steps.
const MAX_FRACTION_OVER_24: f64 = 0.001;

fn check(scene: &str, width: u32, height: u32) {
    let prepared = load(&workspace().join("scenes").join(format!("{scene}.txt")));
    let actual = render(&prepared, width, height, None, None);
    let golden: PathBuf =
        [env!("CARGO_MANIFEST_DIR"), "tests", "golden", &format!("{scene}.png")].iter().collect();
    if std::env::var_os("RAYTERRA_BLESS").is_some() {
        actual.save(&golden).expect("write golden");
        eprintln!("blessed {}", golden.display());
        return;
    }
    let expected = match image::open(&golden) {
        Ok(img) => img.to_rgb8(),
        Err(e) => {
            let paths = write_failure_images(&format!("golden-{scene}"), &actual, &actual);
            panic!(
                "missing golden image {} ({e}).\nIf the new render is right, create it with \
                 RAYTERRA_BLESS=1 cargo test -p raytracer --test golden\n{paths}",
                golden.display()
            );
        }
    };
    let d = difference(&actual, &expected);
    if d.mean > MAX_MEAN
        || d.fraction_over_2 > MAX_FRACTION_OVER_2
        || d.fraction_over_24 > MAX_FRACTION_OVER_24
    {
        let paths = write_failure_images(&format!("golden-{scene}"), &actual, &expected);
        panic!("{scene} differs from its golden image: {d:?}\n{paths}");
    }
}

#[test]
fn showcase() {
    check("showcase", 160, 95);
}

#[test]
fn cornell() {
    check("cornell", 128, 128);
}

#[test]
fn glass_and_light() {
    check("glass-and-light", 160, 90);
}

/// The course's photon mapper (the file says `algorithm= PM`).
#[test]
fn caustics() {
    check("caustics", 160, 95);
}
