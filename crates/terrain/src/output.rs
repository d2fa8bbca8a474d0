//! Writing images safely: to a temporary file in the destination's folder, then renamed into
//! place, so a failure never leaves a half-written file under the requested name.

use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageFormat};

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The file system refused (missing folder, no permission, disk full...).
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file name's extension names no image format this program writes.
    #[error("cannot tell which image format to write for {}: use .png, .bmp or .jpg", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The encoder failed (e.g. an image too large for the format).
    #[error("cannot encode {}: {source}", path.display())]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// What the encoder said.
        source: image::ImageError,
    },
}

/// The image format for `path`'s extension: PNG, BMP or JPEG.
pub fn format_for(path: &Path) -> Result<ImageFormat, SaveError> {
    match ImageFormat::from_path(path) {
        Ok(format @ (ImageFormat::Png | ImageFormat::Bmp | ImageFormat::Jpeg)) => Ok(format),
        _ => Err(SaveError::UnknownFormat { path: path.to_path_buf() }),
    }
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
    let io_error = |source| SaveError::Io { path: path.to_path_buf(), source };
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().map_or_else(|| "image".into(), |name| name.to_string_lossy().into_owned());
    let temporary = folder.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let file = std::fs::File::create(&temporary).map_err(io_error)?;
        let mut writer = std::io::BufWriter::new(file);
        image
            .write_to(&mut writer, format)
            .map_err(|source| SaveError::Encode { path: path.to_path_buf(), source })?;
        let file = writer.into_inner().map_err(|error| io_error(error.into_error()))?;
        file.sync_all().map_err(io_error)?;
        std::fs::rename(&temporary, path).map_err(io_error)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result
}

/// Writes `bytes` to `path`, atomically like [`save_image`].
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), SaveError> {
    let io_error = |source| SaveError::Io { path: path.to_path_buf(), source };
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().map_or_else(|| "file".into(), |name| name.to_string_lossy().into_owned());
    let temporary = folder.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = std::fs::write(&temporary, bytes).and_then(|()| std::fs::rename(&temporary, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result.map_err(io_error)
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
