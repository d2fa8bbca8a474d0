//! The course's asset folder: `heightmap.bmp`, `terrain-texture3.bmp`, `detail.bmp` and
//! `SkyBox0.bmp` .. `SkyBox5.bmp` (four sky walls, the sky top, then the water texture).

use std::path::{Path, PathBuf};

use super::{Heightmap, SkyBox, World, WorldError, read_rgba};

/// The files of a course asset folder, in the order [`load_course_folder`] reads them.
pub const ASSET_FILES: [&str; 9] = [
    "heightmap.bmp",
    "terrain-texture3.bmp",
    "detail.bmp",
    "SkyBox0.bmp",
    "SkyBox1.bmp",
    "SkyBox2.bmp",
    "SkyBox3.bmp",
    "SkyBox4.bmp",
    "SkyBox5.bmp",
];

/// Loads a world from a folder laid out like the course's.
///
/// File names are matched without regard to case, and the sky files may also sit in a `SkyBox`
/// subfolder (as in some course repositories). When files are missing the error lists all of them.
pub fn load_course_folder(dir: &Path) -> Result<World, WorldError> {
    let metadata =
        std::fs::metadata(dir).map_err(|source| WorldError::Read { path: dir.to_path_buf(), source })?;
    if !metadata.is_dir() {
        return Err(WorldError::NotAFolder { path: dir.to_path_buf() });
    }
    let mut found = Vec::with_capacity(ASSET_FILES.len());
    let mut missing = Vec::new();
    for name in ASSET_FILES {
        match find_asset(dir, name)? {
            Some(path) => found.push(path),
            None => missing.push(name.to_string()),
        }
    }
    if !missing.is_empty() {
        return Err(WorldError::MissingAssets { dir: dir.to_path_buf(), missing });
    }
    // Every file was found: `found[i]` is the path of `ASSET_FILES[i]`.
    let path = |i: usize| found[i].as_path();
    Ok(World {
        heightmap: Heightmap::load(path(0))?,
        colour_map: read_rgba(path(1))?,
        detail_map: read_rgba(path(2))?,
        sky: SkyBox {
            sides: [read_rgba(path(3))?, read_rgba(path(4))?, read_rgba(path(5))?, read_rgba(path(6))?],
            top: read_rgba(path(7))?,
        },
        water: read_rgba(path(8))?,
        unlit: None,
        elevation: None,
        erosion: None,
    })
}

/// Finds `name` in `dir` (or, for sky files, in `dir/SkyBox`), ignoring case.
fn find_asset(dir: &Path, name: &str) -> Result<Option<PathBuf>, WorldError> {
    if let Some(path) = find_ignoring_case(dir, name)? {
        return Ok(Some(path));
    }
    if name.to_ascii_lowercase().starts_with("skybox")
        && let Some(sub) = find_ignoring_case(dir, "SkyBox")?
        && sub.is_dir()
    {
        return find_ignoring_case(&sub, name);
    }
    Ok(None)
}

fn find_ignoring_case(dir: &Path, name: &str) -> Result<Option<PathBuf>, WorldError> {
    let exact = dir.join(name);
    if exact.exists() {
        return Ok(Some(exact));
    }
    let entries =
        std::fs::read_dir(dir).map_err(|source| WorldError::Read { path: dir.to_path_buf(), source })?;
    Ok(entries.filter_map(Result::ok).map(|entry| entry.path()).find(|path| {
        path.file_name().and_then(|file| file.to_str()).is_some_and(|file| file.eq_ignore_ascii_case(name))
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rayterra-assets-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    fn write_bmp(path: &Path, width: u32, height: u32, grey: u8) {
        image::RgbImage::from_pixel(width, height, image::Rgb([grey; 3]))
            .save_with_format(path, image::ImageFormat::Bmp)
            .expect("write bmp");
    }

    #[test]
    fn lists_every_missing_file() {
        let dir = scratch("missing");
        write_bmp(&dir.join("heightmap.bmp"), 4, 4, 120);
        let error = load_course_folder(&dir).expect_err("incomplete");
        match &error {
            WorldError::MissingAssets { missing, .. } => {
                assert_eq!(missing.len(), 8);
                assert_eq!(missing[0], "terrain-texture3.bmp");
            }
            other => panic!("unexpected error {other}"),
        }
        assert!(error.to_string().contains("SkyBox5.bmp"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn loads_mixed_case_names_and_a_skybox_subfolder() {
        let dir = scratch("layout");
        write_bmp(&dir.join("HeightMap.BMP"), 6, 5, 200);
        write_bmp(&dir.join("terrain-texture3.bmp"), 8, 8, 90);
        write_bmp(&dir.join("detail.bmp"), 8, 8, 128);
        std::fs::create_dir(dir.join("SkyBox")).expect("subfolder");
        for i in 0..6 {
            write_bmp(&dir.join("SkyBox").join(format!("SkyBox{i}.bmp")), 4, 4, 10 * i as u8);
        }
        let world = load_course_folder(&dir).expect("complete folder");
        assert_eq!((world.heightmap.columns(), world.heightmap.rows()), (6, 5));
        assert_eq!(world.heightmap.level(2, 3), 200.0);
        assert_eq!(world.sky.sides[3].get_pixel(0, 0).0, [30, 30, 30, 255]);
        assert_eq!(world.water.get_pixel(1, 1).0, [50, 50, 50, 255]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn corrupt_file_error_names_it() {
        let dir = scratch("corrupt");
        for name in ASSET_FILES {
            write_bmp(&dir.join(name), 4, 4, 100);
        }
        std::fs::write(dir.join("detail.bmp"), b"BM this is not a bitmap").expect("write");
        let error = load_course_folder(&dir).expect_err("corrupt");
        assert!(matches!(error, WorldError::Decode { .. }), "{error}");
        assert!(error.to_string().contains("detail.bmp"), "{error}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_is_not_a_folder() {
        let dir = scratch("file");
        let file = dir.join("heightmap.bmp");
        write_bmp(&file, 4, 4, 1);
        assert!(matches!(load_course_folder(&file), Err(WorldError::NotAFolder { .. })));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
