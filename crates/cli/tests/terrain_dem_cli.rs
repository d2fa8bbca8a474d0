//! `rayterra terrain --heightmap` on real elevation data: a screenshot of a real place, and clear
//! errors (exit 1, the file named) for broken files.

use std::path::{Path, PathBuf};
mod terrain_common;
use terrain_common::{assert_fails_with, no_gpu, rayterra, stderr};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("terrain-dem-cli");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

/// The shared elevation models, or `None` after a loud skip (a failure under CI).
fn shared() -> Option<PathBuf> {
    test_skips::shared_data(
        Path::new(env!("CARGO_MANIFEST_DIR")),
        "terrain-dem",
        "rayterra terrain DEM tests",
    )
}

#[test]
fn renders_a_real_place_with_a_sensible_start_view() {
    let Some(dir) = shared() else { return };
    let dem = dir.join("zion_srtm_u16_deflate_epsg4326.tif");
    let out = scratch("zion.png");
    let _ = std::fs::remove_file(&out);
    let output = rayterra(&[
        "--heightmap",
        dem.to_str().expect("utf-8 path"),
        "--screenshot",
        out.to_str().expect("utf-8 path"),
        "--size",
        "320x180",
        "--backend",
        "vulkan",
    ]);
    if no_gpu(&output) {
        return;
    }
    let text = stderr(&output);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("elevation: GeoTiff 465x572 samples, cell 73.86"), "{text}");
    assert!(text.contains("no sea"), "{text}");
    let image = image::open(&out).expect("a PNG").into_rgb8();
    assert_eq!(image.dimensions(), (320, 180));
    // The top rows are sky (blue above red), the bottom third is ground: lit, textured land
    // (many different colours, not the sky's and not black).
    let sky = image.get_pixel(160, 5).0;
    assert!(sky[2] > sky[0] + 40, "sky {sky:?}");
    let mut ground: Vec<[u8; 3]> = (120..180)
        .flat_map(|y| (0..320).map(move |x| (x, y)))
        .map(|(x, y)| image.get_pixel(x, y).0)
        .collect();
    let bluish = ground.iter().filter(|p| p[2] > p[1] && p[2] > p[0] + 30).count();
    assert!(bluish < ground.len() / 20, "{bluish} of the ground's pixels look like sky");
    let dark = ground.iter().filter(|p| p.iter().all(|&c| c < 10)).count();
    assert!(dark < ground.len() / 50, "{dark} black pixels in the ground");
    ground.sort_unstable();
    ground.dedup();
    assert!(ground.len() > 2000, "only {} colours in the ground", ground.len());
}

#[test]
fn broken_elevation_files_are_named_with_exit_one() {
    let out = scratch("never.png");
    let out_arg = out.to_str().expect("utf-8 path");
    let run =
        |path: &Path| rayterra(&["--heightmap", path.to_str().expect("utf-8 path"), "--screenshot", out_arg]);

    let hgt = scratch("N10E010.hgt");
    std::fs::write(&hgt, vec![0u8; 1201 * 1201 * 2 - 2]).expect("write");
    assert_fails_with(&run(&hgt), 1, &["N10E010.hgt", "this file is 2884800 bytes"]);

    let grid = scratch("broken.asc");
    std::fs::write(&grid, "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2 3\n4 five 6\n")
        .expect("write");
    assert_fails_with(&run(&grid), 1, &["broken.asc", "line 7 (row 2): `five` is not a number"]);

    let short = scratch("short.asc");
    std::fs::write(&short, "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2 3\n4 5 6\n")
        .expect("write");
    assert_fails_with(&run(&short), 1, &["short.asc", "row 3 is missing"]);

    // A 16-bit PNG whose pixels are 8-bit: the header's bit depth does not match the data.
    let png = scratch("lying16.png");
    let grey = image::GrayImage::from_fn(16, 16, |x, y| image::Luma([(x * 16 + y) as u8]));
    grey.save(&png).expect("write");
    let mut bytes = std::fs::read(&png).expect("read");
    assert_eq!(&bytes[12..16], b"IHDR");
    bytes[24] = 16;
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(&png, &bytes).expect("write");
    assert_fails_with(&run(&png), 1, &["lying16.png"]);

    if let Some(dir) = shared() {
        // A real GeoTIFF cut short: its strips point past the end.
        let whole = std::fs::read(dir.join("vinschgau_f32_lzw_utm32n_nodata.tif")).expect("readable");
        let cut = scratch("cut.tif");
        std::fs::write(&cut, &whole[..whole.len() / 2]).expect("write");
        assert_fails_with(&run(&cut), 1, &["cut.tif", "past the end of the file"]);
    }
    assert!(!out.exists());
}

#[test]
fn elevation_options_are_checked() {
    let args = |extra: &[&str]| {
        let mut all = vec!["--heightmap", "x.tif", "--screenshot", "x.png"];
        all.extend_from_slice(extra);
        rayterra(&all)
    };
    assert_fails_with(&args(&["--water-level", "deep"]), 2, &["neither a height in metres nor `none`"]);
    assert_fails_with(&args(&["--vertical-exaggeration", "0"]), 2, &["not a positive number"]);
    assert_fails_with(&args(&["--max-size", "9000"]), 2, &["9000"]);
}

/// PNG's CRC-32 of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &byte in bytes {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xedb8_8320 } else { crc >> 1 };
        }
    }
    !crc
}
