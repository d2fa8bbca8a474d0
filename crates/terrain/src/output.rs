//! Writing images safely: to a temporary file created exclusively in the destination's folder,
//! then renamed into place (the `atomic-file` crate, shared with the ray tracer), so a failure
//! never leaves a half-written file under the requested name and a planted file or symlink is
//! never followed.

use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageFormat};

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The file system refused to make a folder for the file.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file or folder being written.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file could not be written (missing folder, no permission, disk full, encoder error).
    #[error(transparent)]
    File(#[from] atomic_file::WriteError<image::ImageError>),
    /// The file name's extension names no image format this program writes.
    #[error("cannot tell which image format to write for {}: use .png, .bmp or .jpg", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// The image format for `path`'s extension: PNG, BMP or JPEG.
pub fn format_for(path: &Path) -> Result<ImageFormat, SaveError> {
    match ImageFormat::from_path(path) {
        Ok(format @ (ImageFormat::Png | ImageFormat::Bmp | ImageFormat::Jpeg)) => Ok(format),
        _ => Err(SaveError::UnknownFormat { path: path.to_path_buf() }),
    }
}

/// Checks, before rendering, that a frame can be written to `path`: its extension names a
/// format and its folder exists and takes a new file. Nothing is left behind.
pub fn check_output(path: &Path) -> Result<ImageFormat, SaveError> {
    let format = format_for(path)?;
    atomic_file::check_writable(path)?;
    Ok(format)
}

/// Writes a rendered frame to `path` in the format its extension names (PNG keeps the alpha
/// channel; BMP and JPEG are written as RGB), atomically.
pub fn save_frame(frame: &image::RgbaImage, path: &Path) -> Result<(), SaveError> {
    let format = format_for(path)?;
    let image = DynamicImage::ImageRgba8(frame.clone());
    let image = match format {
        ImageFormat::Png => image,
        _ => DynamicImage::ImageRgb8(image.into_rgb8()),
    };
    save_image(&image, path, format)
}

/// Writes `image` to `path` in `format`, atomically: the image is encoded into a temporary file
/// beside `path`, which is then renamed over it.
pub fn save_image(image: &DynamicImage, path: &Path, format: ImageFormat) -> Result<(), SaveError> {
    atomic_file::write_atomically(path, |writer| image.write_to(writer, format))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = std::env::temp_dir().join(format!("rayterra-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let image = DynamicImage::ImageRgba8(image::RgbaImage::from_pixel(3, 2, image::Rgba([1, 2, 3, 255])));
        let path = dir.join("shot.png");
        save_image(&image, &path, ImageFormat::Png).expect("writable");
        let back = image::open(&path).expect("readable").into_rgba8();
        assert_eq!(back.get_pixel(2, 1).0, [1, 2, 3, 255]);
        // Only the image is left in the folder: no temporary file.
        let names: Vec<_> = std::fs::read_dir(&dir).expect("dir").filter_map(Result::ok).collect();
        assert_eq!(names.len(), 1);
        // A folder that does not exist is an error naming the file.
        let missing = dir.join("no-such-folder").join("shot.png");
        let error = save_image(&image, &missing, ImageFormat::Png).expect_err("no folder");
        assert!(error.to_string().contains("no-such-folder"), "{error}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_planted_symlink_is_not_followed() {
        let dir = tempfile::tempdir().expect("temp dir");
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"precious").expect("write");
        // The name the terrain's writer used to make up from the target and the process id.
        let planted = dir.path().join(format!(".shot.png.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).expect("symlink");
        let image = DynamicImage::ImageRgba8(image::RgbaImage::from_pixel(2, 2, image::Rgba([9, 9, 9, 255])));
        save_image(&image, &dir.path().join("shot.png"), ImageFormat::Png).expect("writable");
        assert_eq!(std::fs::read(&victim).expect("read"), b"precious");
        assert!(std::fs::symlink_metadata(&planted).expect("still there").file_type().is_symlink());
    }

    #[test]
    fn output_is_checked_before_rendering() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("no-such-folder/shot.png");
        let error = check_output(&missing).expect_err("no folder").to_string();
        assert!(error.contains("shot.png") && error.contains("does not exist"), "{error}");
        assert!(matches!(check_output(&dir.path().join("a.gif")), Err(SaveError::UnknownFormat { .. })));
        assert_eq!(check_output(&dir.path().join("a.jpg")).ok(), Some(ImageFormat::Jpeg));
        assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 0, "nothing left behind");
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(format_for(Path::new("a.bmp")).ok(), Some(ImageFormat::Bmp));
        assert_eq!(format_for(Path::new("a.PNG")).ok(), Some(ImageFormat::Png));
        assert_eq!(format_for(Path::new("a.jpeg")).ok(), Some(ImageFormat::Jpeg));
        assert!(matches!(format_for(Path::new("a")), Err(SaveError::UnknownFormat { .. })));
        assert!(matches!(format_for(Path::new("a.txt")), Err(SaveError::UnknownFormat { .. })));
    }

    #[test]
    fn frames_are_written_in_the_extensions_format() {
        let dir = std::env::temp_dir().join(format!("rayterra-frames-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let frame = image::RgbaImage::from_pixel(4, 3, image::Rgba([200, 100, 50, 255]));
        for name in ["f.png", "f.bmp", "f.jpg"] {
            save_frame(&frame, &dir.join(name)).expect("writable");
            let back = image::open(dir.join(name)).expect("readable").into_rgb8();
            let pixel = back.get_pixel(1, 1).0;
            assert!((i32::from(pixel[0]) - 200).abs() < 8, "{name}: {pixel:?}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
