//! Every real elevation model in `../shared/terrain-dem/` (see its SOURCES.md) read with its
//! known size, height range, spacing and voids, then prepared and placed without a spike.

use std::path::{Path, PathBuf};

use terrain::world::dem::{self, Spacing};

/// The shared elevation models, or `None` after a loud skip (a failure under CI).
fn shared() -> Option<PathBuf> {
    test_skips::shared_data(Path::new(env!("CARGO_MANIFEST_DIR")), "terrain-dem", "terrain DEM tests")
}

/// What SOURCES.md says of a file.
struct Known {
    file: &'static str,
    size: (u32, u32),
    /// Lowest and highest heights as SOURCES.md gives them (whole metres).
    range: (f32, f32),
    /// Metres between columns and between rows (at the tile's latitude for degrees).
    metres: (f64, f64),
    geographic: bool,
    voids: Option<usize>,
}

const KNOWN: [Known; 7] = [
    Known {
        file: "N42E001.hgt",
        size: (1201, 1201),
        range: (349.0, 3100.0),
        metres: (68.3, 92.6),
        geographic: true,
        voids: Some(7652),
    },
    // Web Mercator's 4.777 m at the equator, times the cosine of the tile's latitude (8.6 N).
    Known {
        file: "mapzen_z14_10348_7801_f32_deflate_pred3_tiled_3857.tif",
        size: (512, 512),
        range: (600.0, 646.0),
        metres: (4.724, 4.724),
        geographic: false,
        voids: Some(0),
    },
    Known {
        file: "vinschgau_f32_lzw_utm32n_nodata.tif",
        size: (252, 194),
        range: (388.0, 3863.0),
        metres: (250.0, 250.0),
        geographic: false,
        voids: Some(445),
    },
    Known {
        file: "zion_srtm_u16_deflate_epsg4326.tif",
        size: (465, 457),
        range: (1024.0, 2892.0),
        metres: (73.9, 92.5),
        geographic: true,
        voids: None,
    },
    Known {
        file: "dallas_i16_tiled16_epsg4326.tif",
        size: (367, 359),
        range: (147.0, 298.0),
        metres: (78.2, 92.4),
        geographic: true,
        voids: None,
    },
    Known {
        file: "longyearbyen1995_f32_deflate_pred2_utm33n.tif",
        size: (1332, 985),
        range: (8.0, 1022.0),
        metres: (20.0, 20.0),
        geographic: false,
        voids: None,
    },
    Known {
        file: "frontrange_srtmgl3_geographic.asc",
        size: (240, 144),
        range: (1943.0, 3286.0),
        metres: (71.0, 92.5),
        geographic: true,
        voids: None,
    },
];

#[test]
fn every_shared_dem_reads_with_its_known_size_range_and_spacing() {
    let Some(dir) = shared() else { return };
    for known in &KNOWN {
        let path = dir.join(known.file);
        let dem = dem::read_file(&path, false).unwrap_or_else(|error| panic!("{error}"));
        let name = known.file;
        assert_eq!((dem.columns, dem.rows), known.size, "{name}");
        let finite: Vec<f32> = dem.heights.iter().copied().filter(|h| h.is_finite()).collect();
        let low = finite.iter().copied().fold(f32::INFINITY, f32::min);
        let high = finite.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        assert!(
            (low - known.range.0).abs() <= 1.0 && (high - known.range.1).abs() <= 1.0,
            "{name}: {low}..{high}"
        );
        if let Some(voids) = known.voids {
            assert_eq!(dem.heights.len() - finite.len(), voids, "{name}: voids");
        }
        assert_eq!(
            matches!(dem.spacing, Spacing::Degrees { .. }),
            known.geographic,
            "{name}: {:?}",
            dem.spacing
        );
        let (x, y) = dem.spacing.metres().expect("the file states its spacing");
        let near = |a: f64, b: f64| (a - b).abs() <= 0.005 * b + 0.01;
        assert!(near(x, known.metres.0) && near(y, known.metres.1), "{name}: {x} x {y} m");

        // Prepared and placed: square cells, no void left, nothing outside the data's range.
        let loaded =
            dem::load_file(&path, &dem::LoadOptions::default()).unwrap_or_else(|error| panic!("{error}"));
        let info = &loaded.scene.info;
        assert_eq!(loaded.source_voids, dem.heights.len() - finite.len(), "{name}");
        assert!(
            info.range_metres.0 >= low - 0.01 && info.range_metres.1 <= high + 0.01,
            "{name}: {:?}",
            info.range_metres
        );
        assert!(
            (info.cell_size_metres - x.min(y)).abs() < 0.01 * x.min(y),
            "{name}: cell {}",
            info.cell_size_metres
        );
        // The mask covers every sample where there were voids, and is empty otherwise.
        let samples = loaded.scene.heightmap.levels().len();
        let had_voids = finite.len() < dem.heights.len();
        assert_eq!(info.voids.len(), if had_voids { samples } else { 0 }, "{name}");
        assert!(loaded.scene.heightmap.levels().all(|level| (0.0..=255.0).contains(&level)), "{name}");
        // Every one of these lies above sea level: land, no sea.
        assert!(!info.sea && !loaded.scene.config.sea, "{name}");
    }
}

#[test]
fn the_pyrenees_tile_starts_with_the_camera_above_its_highest_peak() {
    let Some(dir) = shared() else { return };
    let options = dem::LoadOptions {
        place: dem::PlaceOptions { water_level: dem::WaterLevel::Metres(1500.0), vertical_exaggeration: 1.0 },
        ..Default::default()
    };
    let loaded = dem::load_file(&dir.join("N42E001.hgt"), &options).expect("readable");
    let scene = &loaded.scene;
    // A lake at 1500 m: the valleys below it are under water.
    assert!(scene.config.sea);
    let top = scene.config.height_of_level(255.0);
    assert!((top - scene.info.world_height(f64::from(scene.info.range_metres.1))).abs() < 1e-4);
    assert!(scene.config.camera_start.position.y > top, "{:?}", scene.config.camera_start);
    assert!(scene.config.camera_start.pitch_degrees < 0.0);
}

#[test]
fn downsampling_is_asked_for_and_said() {
    let Some(dir) = shared() else { return };
    let options = dem::LoadOptions { max_size: Some(300), ..Default::default() };
    let loaded = dem::load_file(&dir.join("longyearbyen1995_f32_deflate_pred2_utm33n.tif"), &options)
        .expect("readable");
    assert_eq!((loaded.scene.heightmap.columns(), loaded.scene.heightmap.rows()), (300, 222));
    assert!(loaded.describe().contains("downsampled from 1332x985"), "{}", loaded.describe());
    assert!((loaded.scene.info.cell_size_metres - 20.0 * 1332.0 / 300.0).abs() < 0.01);
}
