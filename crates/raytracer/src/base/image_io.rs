//! Rendered images and writing them: PNG (default), BMP, OpenEXR and Radiance HDR, chosen by the
//! file extension. Files are written to a temporary file created exclusively beside the target
//! and renamed into place (the `atomic-file` crate), so a failed write never leaves a half image.

use std::path::{Path, PathBuf};

use image::{ImageFormat, Rgb32FImage, RgbImage};

/// A linear-RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    pixels: Vec<[f32; 3]>,
}

impl Image {
    /// An image from `width * height` pixels, top row first.
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 3]>) -> Image {
        assert_eq!(pixels.len(), width as usize * height as usize, "pixel count");
        Image { width, height, pixels }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixel at column `x`, row `y` (0 at the top).
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// All pixels, top row first.
    pub fn pixels(&self) -> &[[f32; 3]] {
        &self.pixels
    }

    /// 8-bit RGB: `round(clamp(c) * 255)` per channel (the course's look), or sRGB-encoded first
    /// when `gamma` is set.
    pub fn to_rgb8(&self, gamma: bool) -> RgbImage {
        let encode = |c: f32| -> u8 {
            let c = c.clamp(0.0, 1.0);
            let c = if gamma { linear_to_srgb(c) } else { c };
            (c * 255.0).round() as u8
        };
        let raw = self.pixels.iter().flat_map(|p| p.map(encode)).collect();
        RgbImage::from_raw(self.width, self.height, raw).expect("buffer matches the size")
    }

    /// 32-bit float RGB (linear, unclamped).
    pub fn to_rgb32f(&self) -> Rgb32FImage {
        let raw = self.pixels.iter().flatten().copied().collect();
        Rgb32FImage::from_raw(self.width, self.height, raw).expect("buffer matches the size")
    }
}

/// The sRGB transfer function.
fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// Output file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// `.png`: 8-bit RGB.
    Png,
    /// `.bmp`: 24-bit, as the course template wrote.
    Bmp,
    /// `.exr`: OpenEXR, linear 32-bit float.
    Exr,
    /// `.hdr`: Radiance RGBE, linear.
    Hdr,
}

impl OutputFormat {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<OutputFormat, WriteError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(OutputFormat::Png),
            Some("bmp") => Ok(OutputFormat::Bmp),
            Some("exr") => Ok(OutputFormat::Exr),
            Some("hdr") => Ok(OutputFormat::Hdr),
            _ => Err(WriteError::UnknownFormat(path.to_path_buf())),
        }
    }

    /// Whether the format stores linear floating-point values (no 8-bit quantisation, no gamma).
    pub fn is_linear(&self) -> bool {
        matches!(self, OutputFormat::Exr | OutputFormat::Hdr)
    }
}

/// An image that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The extension names no supported format.
    #[error("cannot tell the image format of `{}`: use .png, .bmp, .exr or .hdr", .0.display())]
    UnknownFormat(PathBuf),
    /// The file could not be written (missing folder, no permission, disk full, encoder error);
    /// the message names the target.
    #[error(transparent)]
    File(#[from] atomic_file::WriteError<image::ImageError>),
}

/// Checks, before rendering, that an image can be written to `path`: its extension names a
/// format and its folder exists and takes a new file. Nothing is left behind.
pub fn check_output(path: &Path) -> Result<OutputFormat, WriteError> {
    let format = OutputFormat::from_path(path)?;
    atomic_file::check_writable(path)?;
    Ok(format)
}

/// Writes `image` to `path` in the format its extension names. 8-bit formats are sRGB-encoded
/// when `gamma` is set; linear formats ignore it.
pub fn write_image(image: &Image, path: &Path, gamma: bool) -> Result<(), WriteError> {
    let format = OutputFormat::from_path(path)?;
    atomic_file::write_atomically(path, |out| match format {
        OutputFormat::Png => image.to_rgb8(gamma).write_to(out, ImageFormat::Png),
        OutputFormat::Bmp => image.to_rgb8(gamma).write_to(out, ImageFormat::Bmp),
        OutputFormat::Exr => image.to_rgb32f().write_to(out, ImageFormat::OpenExr),
        OutputFormat::Hdr => image.to_rgb32f().write_to(out, ImageFormat::Hdr),
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> Image {
        Image::new(2, 1, vec![[0.0, 0.5, 1.0], [2.0, -1.0, 0.2]])
    }

    #[test]
    fn eight_bit_rounds_and_clamps() {
        let rgb = tiny().to_rgb8(false);
        assert_eq!(rgb.get_pixel(0, 0).0, [0, 128, 255]);
        assert_eq!(rgb.get_pixel(1, 0).0, [255, 0, 51]);
        let srgb = tiny().to_rgb8(true);
        assert_eq!(srgb.get_pixel(0, 0).0, [0, 188, 255]);
    }

    #[test]
    fn every_format_round_trips_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        for ext in ["png", "bmp", "exr", "hdr"] {
            let path = dir.path().join(format!("out.{ext}"));
            write_image(&tiny(), &path, false).expect("written");
            let back = image::open(&path).expect("readable");
            assert_eq!((back.width(), back.height()), (2, 1), "{ext}");
            if ext == "exr" {
                let f = back.to_rgb32f();
                assert_eq!(f.get_pixel(1, 0).0[0], 2.0, "EXR keeps values above 1");
            }
        }
        let names: Vec<_> =
            std::fs::read_dir(dir.path()).expect("list").map(|e| e.expect("entry").file_name()).collect();
        assert_eq!(names.len(), 4, "{names:?}");
    }

    #[cfg(unix)]
    #[test]
    fn a_full_disk_under_the_exr_encoder_says_so() {
        // /dev/full fails every write with "No space left on device"; the EXR encoder itself
        // calls that "Format error decoding OpenExr".
        let Ok(mut full) = std::fs::File::options().write(true).open("/dev/full") else { return };
        let big = Image::new(64, 64, vec![[0.5; 3]; 64 * 64]);
        let err = atomic_file::encode_into(&mut full, Path::new("out.exr"), |w| {
            big.to_rgb32f().write_to(w, ImageFormat::OpenExr)
        })
        .expect_err("disk full")
        .to_string();
        assert!(err.starts_with("cannot write `out.exr`: No space left on device"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn written_files_get_ordinary_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("out.png");
        write_image(&tiny(), &path, false).expect("written");
        let mode = std::fs::metadata(&path).expect("metadata").permissions().mode() & 0o777;
        assert_eq!(mode & 0o644, 0o644, "readable by all, writable by the owner: {mode:o}");
    }

    #[test]
    fn unknown_extension_and_missing_folder_are_errors_without_output() {
        let dir = tempfile::tempdir().expect("temp dir");
        let err = write_image(&tiny(), &dir.path().join("out.gif"), false).expect_err("gif");
        assert!(err.to_string().contains(".png, .bmp, .exr or .hdr"), "{err}");
        let missing = dir.path().join("no/such/folder/out.png");
        let err = write_image(&tiny(), &missing, false).expect_err("no folder");
        assert!(err.to_string().contains("the folder"), "{err}");
        let err = check_output(&missing).expect_err("no folder");
        assert!(err.to_string().starts_with(&format!("cannot write `{}`", missing.display())), "{err}");
        assert!(check_output(&dir.path().join("out.gif")).is_err());
        assert_eq!(check_output(&dir.path().join("out.EXR")).ok(), Some(OutputFormat::Exr));
        assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 0);
    }
}
