//! Loading a huge elevation model: `cargo bench -p terrain --bench dem_load` writes an
//! 8193 x 8193 float32 Deflate GeoTIFF (about 225 MB, in a temporary folder) and times reading it
//! (decoding only) and loading it (decoding, filling voids, placing), on every core. Nothing is
//! asserted: speed is measured, not tested. `RAYTERRA_KEEP_BIG_TIFF=FILE` keeps the file there
//! (to time `rayterra terrain --heightmap FILE` on it).

use std::path::{Path, PathBuf};

use terrain::world::dem;

/// An 8193 x 8193 float32 GeoTIFF with Deflate (strips of 8 rows, projected, 2 m cells) of a
/// rough, non-repeating surface, written with the tiff crate's encoder.
fn write_big_geotiff(path: &Path, side: u32) {
    use tiff::encoder::{Compression, DeflateLevel, TiffEncoder, colortype};
    use tiff::tags::Tag;
    let heights: Vec<f32> = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32, (i / side) as f32);
            let hash = (i.wrapping_mul(2_654_435_761) >> 16) as f32 / 65536.0;
            800.0 + 400.0 * (x / 700.0).sin() * (y / 900.0).cos() + 30.0 * (x / 37.0 + y / 53.0).sin() + hash
        })
        .collect();
    let file = std::io::BufWriter::new(std::fs::File::create(path).expect("writable"));
    let mut encoder =
        TiffEncoder::new(file).expect("encoder").with_compression(Compression::Deflate(DeflateLevel::Fast));
    let mut image = encoder.new_image::<colortype::Gray32Float>(side, side).expect("image");
    image.rows_per_strip(8).expect("strips");
    let dir = image.encoder();
    dir.write_tag(Tag::ModelPixelScaleTag, &[2.0f64, 2.0, 0.0][..]).expect("tag");
    dir.write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 400_000.0, 5_000_000.0, 0.0][..]).expect("tag");
    dir.write_tag(Tag::GeoKeyDirectoryTag, &[1u16, 1, 0, 1, 1024, 0, 1, 1][..]).expect("tag");
    image.write_data(&heights).expect("data");
}

fn main() {
    let side = 8193;
    let dir = tempfile::tempdir().expect("temp dir");
    // RAYTERRA_KEEP_BIG_TIFF=FILE keeps the file there (to time `rayterra terrain` on it).
    let kept = std::env::var_os("RAYTERRA_KEEP_BIG_TIFF").map(PathBuf::from);
    let path = kept.clone().unwrap_or_else(|| dir.path().join("big.tif"));
    let started = std::time::Instant::now();
    write_big_geotiff(&path, side);
    let bytes = std::fs::metadata(&path).expect("written").len();
    println!(
        "wrote {side}x{side} float32 Deflate GeoTIFF, {:.1} MB, in {:.2} s",
        bytes as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    let started = std::time::Instant::now();
    let elevation = dem::read_file(&path, false).expect("readable");
    let read = started.elapsed().as_secs_f64();
    assert_eq!((elevation.columns, elevation.rows), (side, side));
    drop(elevation);
    let started = std::time::Instant::now();
    let loaded = dem::load_file(&path, &dem::LoadOptions::default()).expect("loadable");
    let load = started.elapsed().as_secs_f64();
    println!(
        "read (decode only) {read:.2} s; read, fill, place {load:.2} s on {} threads: {}",
        rayon::current_num_threads(),
        loaded.describe()
    );
    assert_eq!(loaded.scene.heightmap.bytes_per_sample(), 2);
    println!("target: under 10 s: {}", if load < 10.0 { "met" } else { "missed" });
    if kept.is_none() {
        let _ = std::fs::remove_file(&path);
    }
}
