//! Heightmaps read from real files: 8- and 16-bit, PNG and BMP, odd sizes, and broken files.

mod common;

use std::path::{Path, PathBuf};

use image::{ImageBuffer, Luma};
use terrain::world::{Heightmap, HeightmapError, WorldError};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("heightmap-files");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

fn ramp8(columns: u32, rows: u32) -> ImageBuffer<Luma<u8>, Vec<u8>> {
    ImageBuffer::from_fn(columns, rows, |x, y| Luma([((x * 7 + y * 3) % 256) as u8]))
}

#[test]
fn eight_bit_png_and_bmp_of_odd_sizes() {
    for (columns, rows) in [(3, 7), (257, 2), (2, 2), (100, 63)] {
        let image = ramp8(columns, rows);
        for extension in ["png", "bmp"] {
            let path = scratch(&format!("ramp-{columns}x{rows}.{extension}"));
            image.save(&path).expect("write");
            let map = Heightmap::load(&path).expect("loads");
            assert_eq!((map.columns(), map.rows()), (columns, rows), "{}", path.display());
            for (x, y) in [(0, 0), (columns - 1, rows - 1), (columns / 2, rows / 3)] {
                let expected = f32::from(image.get_pixel(x, y).0[0]);
                assert_eq!(map.level(y, x), expected, "{} at {x},{y}", path.display());
            }
        }
    }
}

#[test]
fn sixteen_bit_png_keeps_its_precision() {
    let image: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_fn(5, 3, |x, y| Luma([(x * 13_000 + y * 11) as u16]));
    let path = scratch("sixteen.png");
    image.save(&path).expect("write");
    let map = Heightmap::load(&path).expect("loads");
    assert_eq!(map.level(0, 0), 0.0);
    assert!((map.level(2, 4) - (4.0 * 13_000.0 + 22.0) / 257.0).abs() < 1e-3);
    // Neighbouring 16-bit values stay distinct (an 8-bit reading would merge them).
    assert_ne!(map.level(1, 1), map.level(2, 1));
}

#[test]
fn a_colour_image_reads_as_its_luminance() {
    let image = image::RgbImage::from_fn(4, 4, |x, _| image::Rgb([(x * 50) as u8; 3]));
    let path = scratch("grey-rgb.jpg");
    image.save(&path).expect("write");
    let map = Heightmap::load(&path).expect("loads");
    assert!((map.level(0, 3) - 150.0).abs() <= 3.0, "{}", map.level(0, 3));
}

#[test]
fn broken_files_are_errors_naming_the_file() {
    let truncated = scratch("truncated.png");
    let mut bytes = Vec::new();
    ramp8(64, 64).write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encode");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).expect("write");
    let empty = scratch("empty.bmp");
    std::fs::write(&empty, b"").expect("write");
    let text = scratch("notes.png");
    std::fs::write(&text, b"this is not an image").expect("write");
    for path in [&truncated, &empty, &text] {
        let error = Heightmap::load(path).expect_err("broken");
        assert!(matches!(error, WorldError::Decode { .. }), "{error}");
        assert!(error.to_string().contains(path.to_str().unwrap_or("?")), "{error}");
    }
    let missing = scratch("missing.png");
    let error = Heightmap::load(&missing).expect_err("missing");
    assert!(matches!(error, WorldError::Read { .. }) && error.to_string().contains("missing.png"));
}

#[test]
fn too_small_images_are_refused() {
    let path = scratch("line.png");
    ramp8(1, 5).save(&path).expect("write");
    match Heightmap::load(&path) {
        Err(WorldError::BadHeightmap { path: named, problem }) => {
            assert_eq!(named, path);
            assert_eq!(problem, HeightmapError::TooSmall { columns: 1, rows: 5 });
        }
        other => panic!("expected a bad-heightmap error, got {other:?}"),
    }
}

#[test]
fn the_course_heightmap_is_a_palettised_bmp() {
    let Some(dir) = common::course_assets() else {
        return;
    };
    let map = Heightmap::load(&dir.join("heightmap.bmp")).expect("loads");
    assert_eq!((map.columns(), map.rows()), (256, 256));
    assert!(map.levels().iter().all(|level| level.fract() == 0.0));
    let mean = map.levels().iter().sum::<f32>() / map.levels().len() as f32;
    // Its grey levels (read independently with another decoder) average 131.727, range 0..251.
    assert!((mean - 131.727).abs() < 0.01, "mean {mean}");
    let highest = map.levels().iter().copied().fold(0.0, f32::max);
    assert_eq!(highest, 251.0);
}

/// The heightmap fuzz target's seed corpus and every input a fuzzer ever crashed on
/// (`fuzz/seeds/heightmap`, `fuzz/regressions/heightmap`), run through the same code as the
/// target, so a fixed crash stays fixed without a fuzzer at hand.
#[test]
fn fuzz_inputs_load_or_fail_cleanly() {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut count = 0;
    for kind in ["seeds", "regressions"] {
        let Ok(entries) = std::fs::read_dir(fuzz.join(kind).join("heightmap")) else { continue };
        for entry in entries.filter_map(Result::ok) {
            let bytes = std::fs::read(entry.path()).expect("readable input");
            let loaded = Heightmap::decode(&bytes, &entry.path().display().to_string());
            if kind == "seeds" {
                let map = loaded.unwrap_or_else(|e| panic!("a seed must load: {e}"));
                assert!(map.levels().iter().all(|l| l.is_finite()));
            }
            count += 1;
        }
    }
    assert!(count > 0, "no seed inputs under {}", fuzz.display());
}
