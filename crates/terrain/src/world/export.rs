//! Writes a world as a course asset folder, so its images can be inspected, edited and loaded
//! again with [`super::assets::load_course_folder`].

use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageFormat};

use super::World;
use super::assets::ASSET_FILES;
use crate::output::{SaveError, save_image};

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
}
