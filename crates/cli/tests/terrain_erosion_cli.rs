//! `rayterra terrain --erode` and `--export-heightmap` as a user runs them: the eroded island
//! beside the uneroded one, exported heights, the same bytes at any thread count, and usage errors
//! for a bad strength.

use std::path::{Path, PathBuf};
use std::process::Output;

mod terrain_common;
use terrain_common::{assert_fails, no_gpu, rayterra, stderr, terrain_command};

fn rayterra_with_threads(threads: Option<usize>, args: &[&str]) -> Output {
    let mut command = terrain_command();
    command.args(args);
    if let Some(threads) = threads {
        command.env("RAYON_NUM_THREADS", threads.to_string());
    }
    command.output().expect("rayterra runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("terrain-erosion-cli");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

#[test]
fn a_bad_strength_is_a_usage_error() {
    let out = scratch("never.tif");
    let out = out.to_str().expect("utf-8 path");
    for strength in ["0", "-1", "11", "nan", "inf"] {
        let output = rayterra(&["--grid", "16", "--erode", strength, "--export-heightmap", out]);
        assert_fails(&output, 2, "the strength must be greater than 0 and at most 10");
    }
    assert_fails(&rayterra(&["--erode", "strong", "--export-heightmap", out]), 2, "`strong` is not a number");
    assert_fails(&rayterra(&["--erode", "1", "--assets", "x", "--export-heightmap", out]), 2, "--assets");
    assert_fails(&rayterra(&["--grid", "16", "--export-heightmap", "h.jpg"]), 1, "h.jpg");
    assert!(!Path::new(out).exists());
}

#[test]
fn eroded_heights_are_exported_the_same_at_one_and_two_threads() {
    let export = |threads: usize, erode: bool, name: &str| -> Vec<u8> {
        let out = scratch(name);
        let _ = std::fs::remove_file(&out);
        let mut args =
            vec!["--grid", "300", "--seed", "2", "--export-heightmap", out.to_str().expect("utf-8")];
        if erode {
            args.extend(["--erode", "1"]);
        }
        let output = rayterra_with_threads(Some(threads), &args);
        assert!(output.status.success(), "{}", stderr(&output));
        if erode {
            assert!(stderr(&output).contains("erosion: strength 1, 300x300 samples"), "{}", stderr(&output));
        }
        std::fs::read(&out).expect("written")
    };
    let one = export(1, true, "one.tif");
    let two = export(2, true, "two.tif");
    assert!(one == two, "the eroded heights differ between 1 and 2 threads");
    let plain = export(2, false, "plain.tif");
    assert_eq!(plain.len(), one.len());
    assert!(plain != one, "--erode changed nothing");
    let png = export(2, true, "eroded.png");
    assert_eq!(&png[1..4], b"PNG");
    // 16-bit grey: bit depth 16, colour type 0.
    assert_eq!((png[24], png[25]), (16, 0));
}

#[test]
fn the_eroded_island_beside_the_uneroded_one() {
    let shot = |erode: bool, name: &str| -> Option<image::RgbImage> {
        let out = scratch(name);
        let _ = std::fs::remove_file(&out);
        let mut args = vec![
            "--screenshot",
            out.to_str().expect("utf-8"),
            "--size",
            "480x270",
            "--camera",
            "0,5,9,0,-25",
            "--backend",
            "vulkan",
        ];
        if erode {
            args.extend(["--erode", "2"]);
        }
        let output = rayterra(&args);
        if no_gpu(&output) {
            return None;
        }
        assert!(output.status.success(), "{}", stderr(&output));
        Some(image::open(&out).expect("a screenshot").into_rgb8())
    };
    let Some(plain) = shot(false, "island.png") else { return };
    let Some(eroded) = shot(true, "island-eroded.png") else { return };
    assert_eq!(plain.dimensions(), eroded.dimensions());
    // The land changes (carved valleys, new shading), the sky above it does not.
    let difference = |rows: std::ops::Range<u32>| {
        let mut total = 0u64;
        for y in rows.clone() {
            for x in 0..plain.width() {
                let (a, b) = (plain.get_pixel(x, y), eroded.get_pixel(x, y));
                total += (0..3).map(|c| u64::from(a[c].abs_diff(b[c]))).sum::<u64>();
            }
        }
        total as f64 / (f64::from(plain.width()) * rows.len() as f64 * 3.0)
    };
    let (sky, land) = (difference(0..20), difference(150..270));
    assert!(land > 2.0, "the eroded land looks the same: mean difference {land}");
    assert!(sky < 0.5, "the sky changed: mean difference {sky}");
}
