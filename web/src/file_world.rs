//! A world built from a file picked or dropped on the page, as `rayterra terrain --heightmap
//! FILE` builds it: the format recognised from the content, elevation data (GeoTIFF, SRTM
//! `.hgt`, Esri ASCII grid, OpenEXR) read in metres with its own scene (height mapping, sea or
//! none, camera start), a greyscale image laid out as the course's heightmaps with the course's
//! scene. Runs in the page's worker; no browser needed, so it is tested natively.

use terrain::SceneConfig;
use terrain::world::dem::{self, DemFormat, WaterLevel};
use terrain::world::procedural::{self, Progress, Stage};
use terrain::world::{Heightmap, MAX_HEIGHTMAP_SIDE, World};

use crate::address::{ElevationOptions, MAX_PAGE_SIDE};

/// What the page shows of elevation data: its size, spacing, heights and water.
#[derive(Debug, Clone, PartialEq)]
pub struct ElevationSummary {
    /// The format it was read as.
    pub format: DemFormat,
    /// The file's own size in samples (columns, rows).
    pub source_size: (u32, u32),
    /// Metres between neighbouring samples of the heightmap drawn (square cells).
    pub cell_size_metres: f64,
    /// Whether the file stated no spacing (the address's `cell-size`, or 1 m, was taken).
    pub cell_size_assumed: bool,
    /// Lowest and highest heights, metres.
    pub range_metres: (f32, f32),
    /// Whether a sea is drawn (some ground lies below the water level).
    pub sea: bool,
    /// The water level.
    pub water_level: WaterLevel,
    /// The factor on the heights.
    pub vertical_exaggeration: f64,
    /// Samples the file had no data for, filled from their neighbours.
    pub voids: usize,
}

/// A world made from a file, with the scene it is drawn in.
#[derive(Debug, Clone, PartialEq)]
pub struct FileWorld {
    /// The world.
    pub world: World,
    /// Its scene: the course's for an image; the data's height mapping, sea and camera start
    /// for elevation data (as `rayterra terrain --heightmap` uses).
    pub config: SceneConfig,
    /// One line for the page saying what was loaded.
    pub description: String,
    /// Elevation data's numbers (none for an image).
    pub elevation: Option<ElevationSummary>,
}

/// Builds the world of the file `name` whose content is `bytes`, with the textures of `seed`.
/// Elevation data is placed with `options` (the native program's defaults: water at 0 m, true
/// proportions, 1 m cells where the file states none) and is refused above
/// [`MAX_HEIGHTMAP_SIDE`] samples a side before it is decoded; what exceeds [`MAX_PAGE_SIDE`] a
/// side is downsampled to it. Images are refused above [`MAX_PAGE_SIDE`]. Errors name the file.
pub fn world_from_file(
    bytes: &[u8],
    name: &str,
    seed: u32,
    options: &ElevationOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<FileWorld, String> {
    progress(Progress { stage: Stage::Heightmap, done: 0.0 });
    match dem::detect(bytes, name) {
        Some(format) => {
            elevation_world(bytes, name, format, seed, options, progress).map_err(|error| error.to_string())
        }
        None => image_world(bytes, name, seed, progress),
    }
}

fn image_world(
    bytes: &[u8],
    name: &str,
    seed: u32,
    progress: &mut dyn FnMut(Progress),
) -> Result<FileWorld, String> {
    let heightmap = Heightmap::decode(bytes, name).map_err(|error| error.to_string())?;
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    if columns.max(rows) > MAX_PAGE_SIDE {
        return Err(format!(
            "{name} is {columns}x{rows} samples; the page takes heightmap images up to {MAX_PAGE_SIDE} a side (the `rayterra terrain` program takes up to {MAX_HEIGHTMAP_SIDE})"
        ));
    }
    let config = SceneConfig::default();
    let world = procedural::dress_heightmap(heightmap, seed, &config, progress);
    Ok(FileWorld {
        world,
        config,
        description: format!("heightmap {name}, {columns}x{rows}"),
        elevation: None,
    })
}

fn elevation_world(
    bytes: &[u8],
    name: &str,
    format: DemFormat,
    seed: u32,
    options: &ElevationOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<FileWorld, dem::DemError> {
    // As `dem::load_bytes` without --max-size (nothing above the engine's limit is decoded),
    // then fitted within the page's limit.
    let elevation = dem::read(bytes, name, false).map_err(for_the_page)?;
    let source_size = (elevation.columns, elevation.rows);
    let prepared = dem::prepare(elevation, name, options.cell_size, MAX_PAGE_SIDE)?;
    let (cell_size_assumed, voids) = (prepared.cell_size_given, prepared.source_voids);
    let scene = dem::place::place(prepared, &options.place)
        .map_err(|error| dem::DemError::new(name, error.to_string()))?;
    let dem::DemScene { heightmap, config, info } = scene;
    let summary = ElevationSummary {
        format,
        source_size,
        cell_size_metres: info.cell_size_metres,
        cell_size_assumed,
        range_metres: info.range_metres,
        sea: info.sea,
        water_level: options.place.water_level,
        vertical_exaggeration: options.place.vertical_exaggeration,
        voids,
    };
    let description = describe(name, &summary, (heightmap.columns(), heightmap.rows()));
    let mut world = procedural::dress_heightmap(heightmap, seed, &config, progress);
    world.elevation = Some(info);
    Ok(FileWorld { world, config, description, elevation: Some(summary) })
}

/// The reader's advice for the command line, said for the page: it has no `--max-size`.
fn for_the_page(mut error: dem::DemError) -> dem::DemError {
    const ADVICE: &str = "(pass --max-size N to downsample it to N a side)";
    if error.problem.contains(ADVICE) {
        error.problem = error.problem.replace(
            ADVICE,
            &format!("(the page reads up to {MAX_HEIGHTMAP_SIDE} a side; `rayterra terrain --heightmap FILE --max-size N` downsamples larger files)"),
        );
    }
    error
}

/// The page's line about elevation data, e.g. `elevation data N42E001.hgt: Hgt 1201x1623
/// samples (1201x1201 in the file), cell 68.5 m, heights 349 to 3094 m, 7652 voids filled; no
/// sea (the land lies above 0 m)`.
fn describe(name: &str, summary: &ElevationSummary, drawn: (u32, u32)) -> String {
    let (columns, rows) = drawn;
    let mut text = format!("elevation data {name}: {:?} {columns}x{rows} samples", summary.format);
    if summary.source_size != drawn {
        let (c, r) = summary.source_size;
        let why = if c.max(r) > MAX_PAGE_SIDE {
            format!("; the page draws at most {MAX_PAGE_SIDE} a side")
        } else {
            "; resampled for square cells".to_string()
        };
        text += &format!(" ({c}x{r} in the file{why})");
    }
    text += &format!(", cell {:.2} m", summary.cell_size_metres);
    if summary.cell_size_assumed {
        text += " (the file states none: the address's cell-size, or 1 m)";
    }
    let (low, high) = summary.range_metres;
    text += &format!(", heights {low:.0} to {high:.0} m");
    if summary.voids > 0 {
        text += &format!(", {} voids filled", summary.voids);
    }
    if summary.vertical_exaggeration != 1.0 {
        text += &format!(", heights x{}", summary.vertical_exaggeration);
    }
    text += &match (summary.water_level, summary.sea) {
        (WaterLevel::Metres(level), true) => format!("; sea at {level} m"),
        (WaterLevel::Metres(level), false) => format!("; no sea (the land lies above {level} m)"),
        (WaterLevel::None, _) => "; no sea (water-level=none)".to_string(),
    };
    text
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    /// A shared elevation model's bytes, or `None` after a loud skip (a failure under CI).
    fn shared(name: &str) -> Option<Vec<u8>> {
        let dir =
            test_skips::shared_data(Path::new(env!("CARGO_MANIFEST_DIR")), "terrain-dem", "the page's DEMs")?;
        Some(std::fs::read(dir.join(name)).unwrap_or_else(|error| panic!("{name}: {error}")))
    }

    /// The page's world of a DEM is the native program's: same heights, same scene.
    #[test]
    fn elevation_data_builds_the_native_programs_world() {
        for name in
            ["vinschgau_f32_lzw_utm32n_nodata.tif", "N42E001.hgt", "frontrange_srtmgl3_geographic.asc"]
        {
            let Some(bytes) = shared(name) else { return };
            let page =
                world_from_file(&bytes, name, 1, &ElevationOptions::default(), &mut |_| {}).expect(name);
            let native = dem::load_bytes(&bytes, name, &dem::LoadOptions::default()).expect(name);
            assert_eq!(page.config, native.scene.config, "{name}");
            assert_eq!(page.world.heightmap, native.scene.heightmap, "{name}");
            assert_eq!(page.world.elevation.as_ref(), Some(&native.scene.info), "{name}");
            let summary = page.elevation.expect("elevation");
            assert!(!summary.sea && !page.config.sea, "{name}: these lie above 0 m");
            assert_ne!(page.config.camera_start, SceneConfig::default().camera_start);
            assert!(
                page.description.starts_with(&format!("elevation data {name}: ")),
                "{}",
                page.description
            );
        }
        let Some(bytes) = shared("vinschgau_f32_lzw_utm32n_nodata.tif") else { return };
        let page = world_from_file(&bytes, "v.tif", 1, &ElevationOptions::default(), &mut |_| {})
            .expect("vinschgau");
        assert_eq!(
            page.description,
            "elevation data v.tif: GeoTiff 252x194 samples, cell 250.00 m, heights 388 to 3863 m, 445 voids filled; no sea (the land lies above 0 m)"
        );
    }

    #[test]
    fn ground_below_the_water_gets_a_sea() {
        let text = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n-5 0 20\n-2 4 30\n";
        let page =
            world_from_file(text.as_bytes(), "coast.asc", 1, &ElevationOptions::default(), &mut |_| {})
                .expect("grid");
        assert!(page.config.sea);
        assert!(page.description.ends_with("; sea at 0 m"), "{}", page.description);
        assert!(page.description.contains("cell 10.00 m, heights -5 to 30 m"), "{}", page.description);
    }

    /// The address's water level, exaggeration and cell size reach the data as the command
    /// line's do.
    #[test]
    fn the_addresses_options_place_the_data_as_the_command_lines() {
        let Some(bytes) = shared("vinschgau_f32_lzw_utm32n_nodata.tif") else { return };
        let place = dem::PlaceOptions { water_level: WaterLevel::Metres(1500.0), vertical_exaggeration: 2.0 };
        let options = ElevationOptions { cell_size: None, place };
        let page = world_from_file(&bytes, "v.tif", 1, &options, &mut |_| {}).expect("vinschgau");
        let native_options = dem::LoadOptions { place, ..dem::LoadOptions::default() };
        let native = dem::load_bytes(&bytes, "v.tif", &native_options).expect("vinschgau");
        assert_eq!(page.config, native.scene.config);
        assert_eq!(page.world.heightmap, native.scene.heightmap);
        assert!(page.config.sea);
        assert!(page.description.ends_with(", heights x2; sea at 1500 m"), "{}", page.description);
        let none = ElevationOptions {
            place: dem::PlaceOptions { water_level: WaterLevel::None, ..place },
            ..options
        };
        let page = world_from_file(&bytes, "v.tif", 1, &none, &mut |_| {}).expect("vinschgau");
        assert!(!page.config.sea && page.description.ends_with("; no sea (water-level=none)"));
        // An OpenEXR image states no spacing: the address's cell size is taken.
        let image = image::Rgb32FImage::from_fn(4, 3, |x, y| image::Rgb([(x * 10 + y) as f32; 3]));
        let mut exr = std::io::Cursor::new(Vec::new());
        image::DynamicImage::ImageRgb32F(image).write_to(&mut exr, image::ImageFormat::OpenExr).expect("exr");
        let sized = ElevationOptions { cell_size: Some(25.0), ..ElevationOptions::default() };
        let page = world_from_file(exr.get_ref(), "h.exr", 1, &sized, &mut |_| {}).expect("exr");
        assert_eq!(page.world.elevation.as_ref().map(|info| info.cell_size_metres), Some(25.0));
        assert!(page.description.contains("cell 25.00 m (the file states none"), "{}", page.description);
    }

    #[test]
    fn images_keep_the_courses_scene() {
        let image = image::GrayImage::from_fn(5, 4, |x, y| image::Luma([(x * 40 + y * 10) as u8]));
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, image::ImageFormat::Png).expect("png");
        let page =
            world_from_file(bytes.get_ref(), "hills.png", 2, &ElevationOptions::default(), &mut |_| {})
                .expect("image");
        assert_eq!(page.config, SceneConfig::default());
        assert_eq!(page.description, "heightmap hills.png, 5x4");
        assert!(page.elevation.is_none() && page.world.elevation.is_none());
    }

    /// Data larger than the page's limit is downsampled to it; larger than the engine's, refused
    /// before it is decoded, with advice that fits a page.
    #[test]
    fn large_data_is_fitted_or_refused() {
        let grid = |columns: u32| {
            let mut text = format!("ncols {columns}\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 5\n");
            for row in 0..2 {
                let line: Vec<String> = (0..columns).map(|column| (column % 50 + row).to_string()).collect();
                text += &line.join(" ");
                text += "\n";
            }
            text
        };
        let wide = grid(MAX_PAGE_SIDE + 103);
        let page = world_from_file(wide.as_bytes(), "wide.asc", 1, &ElevationOptions::default(), &mut |_| {})
            .expect("downsampled");
        assert_eq!((page.world.heightmap.columns(), page.world.heightmap.rows()), (MAX_PAGE_SIDE, 2));
        assert!(
            page.description.contains("samples (4200x2 in the file; the page draws at most 4097 a side)"),
            "{}",
            page.description
        );
        let cell = page.world.elevation.as_ref().map(|info| info.cell_size_metres).expect("elevation");
        assert!((cell - 5.0 * 4200.0 / 4097.0).abs() < 1e-9, "{cell}");
        let huge = grid(MAX_HEIGHTMAP_SIDE + 1);
        let error =
            world_from_file(huge.as_bytes(), "huge.asc", 1, &ElevationOptions::default(), &mut |_| {})
                .expect_err("too large");
        assert!(error.starts_with("huge.asc: 8194x2 samples is more than"), "{error}");
        assert!(error.contains("the page reads up to 8193 a side; `rayterra terrain"), "{error}");
    }

    #[test]
    fn broken_files_are_named() {
        let mut tiff = b"II*\0".to_vec();
        tiff.extend([0xff; 40]);
        for (bytes, name, says) in [
            (tiff, "cut.tif", "cut.tif: "),
            (vec![0; 1000], "N10E010.hgt", "N10E010.hgt: an SRTM .hgt tile is"),
            (b"ncols 2\nnrows 2\ncellsize 1\n1 2\n3 five\n".to_vec(), "bad.asc", "bad.asc: line 5"),
            (b"\x89PNG\r\n\x1a\nbroken".to_vec(), "broken.png", "broken.png is not a readable image"),
        ] {
            let error =
                world_from_file(&bytes, name, 1, &ElevationOptions::default(), &mut |_| {}).expect_err(name);
            assert!(error.contains(says), "{name}: {error}");
        }
    }
}
