//! `rayterra terrain --erode`, `--no-erode`, `export` and `--export-heightmap` as a user runs
//! them: the island eroded by default, the eroded island beside the uneroded one, exported heights
//! and ground weights, the same bytes at any thread count, and errors for a bad strength or a bad
//! destination before any work.

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
    for strength in ["-1", "11", "nan", "inf", "-0.5"] {
        let output = rayterra(&["--grid", "16", "--erode", strength, "--export-heightmap", out]);
        assert_fails(&output, 2, "the strength must be 0 (no erosion) to 10");
    }
    assert_fails(&rayterra(&["--erode", "1", "--no-erode", "--export-heightmap", out]), 2, "--no-erode");
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
        args.extend(if erode { ["--erode", "1"] } else { ["--erode", "0"] });
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
        args.extend(if erode { ["--erode", "2"] } else { ["--erode", "0"] });
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

/// `rayterra terrain ARGS` (world options first, then `export` with its own), expected to work;
/// returns its standard error.
fn export_ok(threads: Option<usize>, args: &[&str]) -> String {
    let output = rayterra_with_threads(threads, args);
    assert!(output.status.success(), "{}", stderr(&output));
    stderr(&output)
}

#[test]
fn the_island_is_eroded_by_default_and_can_be_left_alone() {
    let heights = |name: &str, options: &[&str]| -> (Vec<u8>, String) {
        let out = scratch(name);
        let _ = std::fs::remove_file(&out);
        let mut args = vec!["--grid", "96", "--seed", "3"];
        args.extend_from_slice(options);
        args.extend(["export", "--heightmap", out.to_str().expect("utf-8")]);
        let text = export_ok(None, &args);
        (std::fs::read(&out).expect("written"), text)
    };
    let (default, text) = heights("default.tif", &[]);
    assert!(text.contains("erosion: strength 4, 96x96 samples"), "{text}");
    let (explicit, _) = heights("explicit.tif", &["--erode", "4"]);
    assert!(default == explicit, "the default is not --erode 4");
    let (off, text) = heights("off.tif", &["--no-erode"]);
    assert!(!text.contains("erosion:"), "{text}");
    let (zero, _) = heights("zero.tif", &["--erode", "0"]);
    assert!(off == zero, "--no-erode and --erode 0 differ");
    assert!(off != default, "the default changed nothing");
    // The course look keeps the course's picture: no erosion unless asked for.
    let (course, text) = heights("course.tif", &["--look", "course"]);
    assert!(!text.contains("erosion:"), "{text}");
    assert!(course == off, "the course look's island was eroded");
    let (course_eroded, _) = heights("course-eroded.tif", &["--look", "course", "--erode", "4"]);
    assert!(course_eroded == default);
    // A huge island is not held up for minutes by default.
    let out = scratch("large.png");
    let text = export_ok(None, &["--grid", "1026", "export", "--heightmap", out.to_str().expect("utf-8")]);
    assert!(text.contains("not eroded by default above 1025 samples"), "{text}");
    assert!(!text.contains("erosion:"), "{text}");
}

#[test]
fn exports_heights_and_ground_weights_the_same_at_one_and_two_threads() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let run = |threads: usize| -> (Vec<u8>, Vec<u8>, Vec<u8>) {
        let (tif, splat) =
            (dir.path().join(format!("h{threads}.tif")), dir.path().join(format!("g{threads}.png")));
        let text = export_ok(
            Some(threads),
            &[
                "--grid",
                "200",
                "--seed",
                "5",
                "export",
                "--heightmap",
                tif.to_str().expect("utf-8"),
                "--splat",
                splat.to_str().expect("utf-8"),
            ],
        );
        assert!(text.contains("erosion: strength 4"), "{text}");
        let second = dir.path().join(format!("g{threads}_1.png"));
        let read = |path: &Path| std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        (read(&tif), read(&splat), read(&second))
    };
    let one = run(1);
    let two = run(2);
    assert!(one == two, "the exports differ between 1 and 2 threads");
    let first = image::load_from_memory(&one.1).expect("a PNG").into_rgba8();
    let second = image::load_from_memory(&one.2).expect("a PNG").into_rgba8();
    assert_eq!((first.dimensions(), second.dimensions()), ((200, 200), (200, 200)));
    // Every pixel's weights sum to 255; the island has rock, grass, sand and (high up) snow.
    let mut most = [0u8; 5];
    for (a, b) in first.pixels().zip(second.pixels()) {
        let weights = [a[0], a[1], a[2], a[3], b[0]];
        assert_eq!(weights.iter().map(|&w| u32::from(w)).sum::<u32>(), 255, "{weights:?}");
        assert_eq!((b[1], b[2], b[3]), (0, 0, 0));
        for (m, w) in most.iter_mut().zip(weights) {
            *m = (*m).max(w);
        }
    }
    for (name, m) in ["rock", "scree", "grass", "sand", "snow"].iter().zip(most) {
        assert!(m > 128, "{name} is nowhere the main material: {most:?}");
    }
    // The old flag writes the same heights.
    let old = dir.path().join("old.tif");
    export_ok(None, &["--grid", "200", "--seed", "5", "--export-heightmap", old.to_str().expect("utf-8")]);
    assert!(std::fs::read(&old).expect("written") == one.0);
}

#[test]
fn bad_export_destinations_are_refused_before_any_work() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let missing = dir.path().join("no-such-folder");
    let cases = [
        (vec!["--splat".to_string(), dir.path().join("g.jpg").display().to_string()], "g.jpg"),
        (vec!["--splat".to_string(), missing.join("g.png").display().to_string()], "no-such-folder"),
        (vec!["--heightmap".to_string(), dir.path().join("h.exr").display().to_string()], "h.exr"),
        (vec!["--heightmap".to_string(), missing.join("h.tif").display().to_string()], "no-such-folder"),
    ];
    for (export, needle) in cases {
        let mut args = vec!["--grid".to_string(), "64".to_string(), "export".to_string()];
        args.extend(export);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let output = rayterra(&args);
        assert_fails(&output, 1, needle);
        assert!(!stderr(&output).contains("erosion:"), "worked before refusing: {}", stderr(&output));
    }
    assert_fails(&rayterra(&["export"]), 2, "--splat");
    let out = dir.path().join("h.tif");
    let out = out.to_str().expect("utf-8");
    assert_fails(&rayterra(&["--export-heightmap", out, "export", "--heightmap", out]), 1, "once");
    assert!(std::fs::read_dir(dir.path()).expect("folder").next().is_none(), "a file was written");
}
