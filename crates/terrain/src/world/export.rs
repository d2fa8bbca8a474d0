//! Writes a world as a course asset folder, so its images can be inspected, edited and loaded
//! again with [`super::assets::load_course_folder`].

use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageFormat};

use super::World;
use super::assets::ASSET_FILES;
use super::splat::SplatMap;
use crate::config::SceneConfig;
use crate::output::{SaveError, save_image, write_file};

/// Writes `world` into `dir` (created if needed) under the course's file names, as BMP files.
/// The heightmap is written as 8-bit grey levels (rounded), like the course's. Each file is
/// written whole or not at all. Returns the paths written.
pub fn save_course_folder(world: &World, dir: &Path) -> Result<Vec<PathBuf>, SaveError> {
    std::fs::create_dir_all(dir).map_err(|source| SaveError::Io { path: dir.to_path_buf(), source })?;
    let grey = DynamicImage::ImageLuma16(world.heightmap.to_image()).into_luma8();
    let images = [
        DynamicImage::ImageLuma8(grey),
        world.colour_map.clone().into(),
        world.detail_map.clone().into(),
        world.sky.sides[0].clone().into(),
        world.sky.sides[1].clone().into(),
        world.sky.sides[2].clone().into(),
        world.sky.sides[3].clone().into(),
        world.sky.top.clone().into(),
        world.water.clone().into(),
    ];
    let mut written = Vec::with_capacity(ASSET_FILES.len());
    for (name, image) in ASSET_FILES.iter().zip(images) {
        let path = dir.join(name);
        // BMP stores no alpha worth keeping: the images are opaque.
        let image = match image {
            DynamicImage::ImageLuma8(grey) => DynamicImage::ImageLuma8(grey),
            other => DynamicImage::ImageRgb8(other.into_rgb8()),
        };
        save_image(&image, &path, ImageFormat::Bmp)?;
        written.push(path);
    }
    Ok(written)
}

/// How [`save_heightmap`] writes the heights, from the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightFormat {
    /// `.tif` or `.tiff`: one 32-bit float sample a pixel, the height in metres for elevation
    /// data and in world units (y) otherwise; uncompressed, no geographic tags.
    FloatTiff,
    /// `.png`: 16-bit grey, the heightmap's levels times 257 (`--heightmap` reads it back as the
    /// same levels).
    Png16,
}

impl HeightFormat {
    /// The format `path`'s extension names (case-insensitive), or an error naming the file.
    pub fn for_path(path: &Path) -> Result<Self, SaveError> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("tif" | "tiff") => Ok(Self::FloatTiff),
            Some("png") => Ok(Self::Png16),
            _ => Err(SaveError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other(
                    "a heightmap is written as .tif (32-bit float) or .png (16-bit)",
                ),
            }),
        }
    }
}

impl HeightFormat {
    /// The format for `path` (as [`Self::for_path`]), after checking that its folder takes a new
    /// file: to refuse a bad destination before any work.
    pub fn check(path: &Path) -> Result<Self, SaveError> {
        let format = Self::for_path(path)?;
        atomic_file::check_writable::<image::ImageError>(path)?;
        Ok(format)
    }
}

/// The two files [`save_splat`] writes for `path` (which must end in `.png`, in any case):
/// `path` itself and, beside it, the stem with `_1` (`splat.png` and `splat_1.png`). Checks that
/// the folder takes new files, to refuse a bad destination before any work.
pub fn splat_paths(path: &Path) -> Result<[PathBuf; 2], SaveError> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let stem = path.file_stem().and_then(|s| s.to_str());
    let (Some("png"), Some(stem)) = (extension.as_deref(), stem) else {
        return Err(SaveError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other("a splat map is written as .png (8-bit RGBA)"),
        });
    };
    let second = path.with_file_name(format!("{stem}_1.png"));
    for file in [path, second.as_path()] {
        atomic_file::check_writable::<image::ImageError>(file)?;
    }
    Ok([path.to_path_buf(), second])
}

/// Writes the ground materials' weights `map` as two 8-bit RGBA PNG files (see
/// [`SplatMap::images`]: rock, scree, grass, sand in the first; snow in the second's red), the
/// files [`splat_paths`] names for `path`, each whole or not at all. Returns their paths.
pub fn save_splat(map: &SplatMap, path: &Path) -> Result<[PathBuf; 2], SaveError> {
    let paths = splat_paths(path)?;
    for (image, file) in map.images().into_iter().zip(&paths) {
        save_image(&DynamicImage::ImageRgba8(image), file, ImageFormat::Png)?;
    }
    Ok(paths)
}

/// Writes the heights of `world` (placed with `config`) to `path`, whole or not at all, in the
/// format of its extension ([`HeightFormat`]). Row 0 is the far (-z, northern) row.
pub fn save_heightmap(world: &World, config: &SceneConfig, path: &Path) -> Result<(), SaveError> {
    let map = &world.heightmap;
    match HeightFormat::for_path(path)? {
        HeightFormat::Png16 => save_image(&DynamicImage::ImageLuma16(map.to_image()), path, ImageFormat::Png),
        HeightFormat::FloatTiff => {
            let height = |level: f32| {
                let y = config.height_of_level(level);
                match &world.elevation {
                    // Back to metres: the inverse of `ElevationInfo::world_height`.
                    Some(info) => {
                        (f64::from(y) * info.metres_per_unit / info.vertical_exaggeration + info.base_metres)
                            as f32
                    }
                    None => y,
                }
            };
            let heights: Vec<f32> = map.levels().map(height).collect();
            let mut bytes = std::io::Cursor::new(Vec::new());
            let failed = |error: tiff::TiffError| SaveError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other(error.to_string()),
            };
            tiff::encoder::TiffEncoder::new(&mut bytes)
                .map_err(failed)?
                .write_image::<tiff::encoder::colortype::Gray32Float>(map.columns(), map.rows(), &heights)
                .map_err(failed)?;
            write_file(path, bytes.get_ref())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::SceneConfig;
    use crate::world::assets::load_course_folder;
    use crate::world::procedural::{ProceduralOptions, generate};

    #[test]
    fn round_trips_through_the_course_layout() {
        let options = ProceduralOptions { seed: 2, heightmap_size: 24 };
        let world = generate(options, &SceneConfig::default(), &mut |_| {}).expect("valid");
        let dir = std::env::temp_dir().join(format!("rayterra-export-{}", std::process::id()));
        let written = save_course_folder(&world, &dir).expect("writable");
        assert_eq!(written.len(), 9);
        let back = load_course_folder(&dir).expect("loadable");
        assert_eq!(back.colour_map, world.colour_map);
        assert_eq!(back.sky, world.sky);
        assert_eq!(back.water, world.water);
        for (a, b) in back.heightmap.levels().zip(world.heightmap.levels()) {
            assert!((a - b).abs() <= 0.5 + 1e-3, "{a} vs {b}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn heights_are_written_as_float_tiff_and_sixteen_bit_png() {
        let config = SceneConfig::default();
        let world =
            generate(ProceduralOptions { seed: 2, heightmap_size: 20 }, &config, &mut |_| {}).expect("valid");
        let dir = tempfile::tempdir().expect("temporary folder");
        let png = dir.path().join("h.png");
        save_heightmap(&world, &config, &png).expect("writable");
        let back = crate::world::Heightmap::load(&png).expect("loadable");
        for (a, b) in back.levels().zip(world.heightmap.levels()) {
            assert!((a - b).abs() <= 0.5 / 257.0 + 1e-4, "{a} vs {b}");
        }
        let tif = dir.path().join("h.TIF");
        save_heightmap(&world, &config, &tif).expect("writable");
        let mut decoder =
            tiff::decoder::Decoder::new(std::fs::File::open(&tif).expect("written")).expect("tiff");
        assert_eq!(decoder.dimensions().expect("size"), (20, 20));
        let tiff::decoder::DecodingResult::F32(heights) = decoder.read_image().expect("decodes") else {
            panic!("not float samples");
        };
        let expected: Vec<f32> = world.heightmap.levels().map(|l| config.height_of_level(l)).collect();
        assert_eq!(heights, expected);
        let error = save_heightmap(&world, &config, &dir.path().join("h.jpg")).expect_err("refused");
        assert!(error.to_string().contains("h.jpg"), "{error}");
        let error = HeightFormat::check(&dir.path().join("missing").join("h.tif")).expect_err("refused");
        assert!(error.to_string().contains("missing"), "{error}");
    }

    #[test]
    fn splat_maps_are_two_rgba_pngs_whose_bytes_sum_to_255() {
        let config = SceneConfig::default();
        let world =
            generate(ProceduralOptions { seed: 3, heightmap_size: 40 }, &config, &mut |_| {}).expect("valid");
        let map = crate::world::splat::splat_map(
            &world,
            &config,
            &crate::settings::GroundSettings::default().lines(&config),
        );
        let dir = tempfile::tempdir().expect("temporary folder");
        let paths = save_splat(&map, &dir.path().join("ground.PNG")).expect("writable");
        assert_eq!(paths[1], dir.path().join("ground_1.png"));
        let first = image::open(&paths[0]).expect("a PNG").into_rgba8();
        let second = image::open(&paths[1]).expect("a PNG").into_rgba8();
        assert_eq!((first.dimensions(), second.dimensions()), ((40, 40), (40, 40)));
        assert_eq!([first, second], map.images());
        for bad in ["ground.tif", "ground", "missing/ground.png"] {
            let error = splat_paths(&dir.path().join(bad)).expect_err("refused");
            assert!(error.to_string().contains("ground"), "{error}");
        }
    }
}
