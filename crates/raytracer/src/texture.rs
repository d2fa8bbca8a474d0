//! Textures ready for lookups: images (BMP, PNG, JPEG) decoded within the memory budget, and the
//! project's built-in procedural textures generated ([`crate::procedural`]). How a scene names a
//! texture is part of the scene description ([`crate::scene::texture`]), re-exported here.

use std::io::{BufRead, Seek};
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::base::color::luminance;
use crate::base::diagnostic::{clip, clip_path};
use crate::base::memory::{MemoryBudget, OverBudget};
pub use crate::scene::texture::{BUILTIN_PREFIX, Builtin, MAX_BUILTIN_COUNT, TextureRef, TextureSource};

/// A texture ready for lookups. Rows are counted **from the bottom**, as the course's BMP reader
/// did, so that `u = 0` is the image's bottom edge.
///
/// Texels are 8-bit RGB (a channel byte `b` means `b / 256`, the course's scale) stored in 4 x 4
/// tiles of 4-byte texels, one 64-byte cache line per tile, so the four texels of a bilinear
/// lookup usually share a cache line.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    /// Tiles across.
    tiles_x: u32,
    /// Tiled texels: tile `(tx, ty)` starts at `(ty * tiles_x + tx) * 16`.
    texels: Vec<[u8; 4]>,
}

/// Side of a texel tile.
const TILE: u32 = 4;

/// An image file that could not be used as a texture.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// Not found in any of the folders searched.
    #[error("cannot find texture `{}` (looked in {})", clip(.name), display_paths(.searched))]
    NotFound {
        /// The path as written.
        name: String,
        /// Where it was looked for.
        searched: Vec<std::path::PathBuf>,
    },
    /// The path names a folder.
    #[error("texture `{}` is a directory, not an image file", clip_path(.path))]
    Directory {
        /// The folder.
        path: PathBuf,
    },
    /// The path names a device, a pipe or a socket.
    #[error("texture `{}` is not a regular file", clip_path(.path))]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// The image is wider or taller than [`MAX_TEXTURE_SIDE`] (found from its header, before
    /// decoding).
    #[error(
        "texture `{}` is {width}x{height} pixels, larger than the {MAX_TEXTURE_SIDE} pixels a side a texture may have",
        clip_path(.path)
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
    },
    /// The image has no pixels (a width or a height of 0).
    #[error("texture `{}` is an empty image ({width}x{height} pixels)", clip_path(.path))]
    Empty {
        /// The file.
        path: PathBuf,
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
    },
    /// Decoding and keeping the image would take the scene past its memory budget.
    #[error("texture `{}` ({width}x{height} pixels) {over}", clip_path(.path))]
    OverBudget {
        /// The file.
        path: PathBuf,
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
        /// The budget's numbers.
        over: OverBudget,
    },
    /// Found but unreadable or not a supported image.
    #[error("cannot read texture `{}`: {source}", clip_path(.path))]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: image::ImageError,
    },
}

/// What an image file's header says, read without decoding the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageInfo {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bytes the texture keeps ([`memory_bytes`]).
    pub kept_bytes: u64,
    /// Bytes needed only while decoding: the decoded image, and its conversion to 8-bit RGB.
    pub decoding_bytes: u64,
}

/// Bytes a texture of `width` x `height` texels keeps in memory: 4-byte texels in 4 x 4 tiles.
pub fn memory_bytes(width: u32, height: u32) -> u64 {
    u64::from(width.div_ceil(TILE)) * u64::from(height.div_ceil(TILE)) * u64::from(TILE * TILE * 4)
}

/// An image decoder for a file or bytes, its format recognised from the content, whose header
/// has been read and checked against [`MAX_TEXTURE_SIDE`]; nothing is decoded yet.
fn open_decoder<'a, R: BufRead + Seek + 'a>(
    reader: image::ImageReader<R>,
    path: &Path,
) -> Result<(impl image::ImageDecoder + use<'a, R>, ImageInfo), TextureError> {
    let unreadable = |source| TextureError::Unreadable { path: path.to_path_buf(), source };
    let mut reader = reader.with_guessed_format().map_err(|e| unreadable(image::ImageError::IoError(e)))?;
    // The header is read without limits on the size, so that a size over the limit can be
    // named; nothing in proportion to the size is allocated before it is checked below.
    let mut limits = image::Limits::no_limits();
    limits.max_alloc = Some(64 << 20);
    reader.limits(limits);
    let mut decoder = reader.into_decoder().map_err(unreadable)?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(TextureError::TooLarge { path: path.to_path_buf(), width, height });
    }
    if width == 0 || height == 0 {
        // Found by fuzzing: a Radiance header may say `-Y 0 +X 8`, and a lookup in an empty
        // texture has no texel to read.
        return Err(TextureError::Empty { path: path.to_path_buf(), width, height });
    }
    let decoded = image::ImageDecoder::total_bytes(&decoder);
    let rgb8 = image::ImageDecoder::color_type(&decoder) == image::ColorType::Rgb8;
    let conversion = if rgb8 { 0 } else { 3 * u64::from(width) * u64::from(height) };
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    // The picture itself, and whatever the decoder needs beside it (palettes, rows, metadata).
    limits.max_alloc = Some(decoded.saturating_add(64 << 20));
    image::ImageDecoder::set_limits(&mut decoder, limits).map_err(unreadable)?;
    let info = ImageInfo {
        width,
        height,
        kept_bytes: memory_bytes(width, height),
        decoding_bytes: decoded + conversion,
    };
    Ok((decoder, info))
}

/// Opens an image file, refusing folders and devices.
fn open_file(path: &Path) -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>, TextureError> {
    let unreadable =
        |e| TextureError::Unreadable { path: path.to_path_buf(), source: image::ImageError::IoError(e) };
    let file = atomic_file::open_regular(path).map_err(|e| match atomic_file::not_regular(&e) {
        Some(atomic_file::NotRegular::Directory) => TextureError::Directory { path: path.to_path_buf() },
        Some(atomic_file::NotRegular::Special) => TextureError::NotAFile { path: path.to_path_buf() },
        None => unreadable(e),
    })?;
    // As `ImageReader::open` does: the format from the extension.
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file));
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    Ok(reader)
}

fn display_paths(paths: &[std::path::PathBuf]) -> String {
    paths.iter().map(|p| format!("`{}`", clip_path(p))).collect::<Vec<_>>().join(", ")
}

/// Largest texture side accepted, in pixels.
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

impl Texture {
    /// A texture from 8-bit RGB texels given **top row first** (the usual image order),
    /// `width * height` of them.
    pub fn from_top_down(width: u32, height: u32, top_down: &[[u8; 3]]) -> Texture {
        assert_eq!(top_down.len(), width as usize * height as usize, "texel count");
        let tiles_x = width.div_ceil(TILE);
        let tiles_y = height.div_ceil(TILE);
        let mut texels = vec![[0u8; 4]; (tiles_x * tiles_y * TILE * TILE) as usize];
        for (i, rgb) in top_down.iter().enumerate() {
            let column = i as u32 % width;
            let row = height - 1 - i as u32 / width;
            texels[tiled_index(tiles_x, row, column)] = [rgb[0], rgb[1], rgb[2], 0];
        }
        Texture { width, height, tiles_x, texels }
    }

    /// Reads an image file's header: its size and the memory it would take, without decoding
    /// it. Folders, devices and images over [`MAX_TEXTURE_SIDE`] a side are refused.
    pub fn probe(path: &Path) -> Result<ImageInfo, TextureError> {
        open_decoder(open_file(path)?, path).map(|(_, info)| info)
    }

    /// Decodes an image file (BMP, PNG or JPEG; palettised, grey or colour) into a texture.
    /// Channels are scaled as the course did: an 8-bit value `b` becomes `b / 256`; 16-bit images
    /// are reduced to their high byte. The size is checked from the header before decoding
    /// (at most [`MAX_TEXTURE_SIDE`] a side), and the decoder may allocate no more than the
    /// picture needs.
    pub fn load(path: &Path) -> Result<Texture, TextureError> {
        Texture::decode(open_file(path)?, path, &MemoryBudget::new(u64::MAX))
    }

    /// Decodes an image held in memory, as [`Texture::load`] decodes a file, charging `budget`
    /// for the memory the texture keeps (`name` is used in messages).
    pub fn from_bytes(bytes: &[u8], name: &str, budget: &MemoryBudget) -> Result<Texture, TextureError> {
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes));
        Texture::decode(reader, Path::new(name), budget)
    }

    /// Decodes after checking the header and charging `budget` with the texture's memory (the
    /// memory needed while decoding is charged, then given back).
    fn decode<R: BufRead + Seek>(
        reader: image::ImageReader<R>,
        path: &Path,
        budget: &MemoryBudget,
    ) -> Result<Texture, TextureError> {
        let (decoder, info) = open_decoder(reader, path)?;
        let over = |over| TextureError::OverBudget {
            path: path.to_path_buf(),
            width: info.width,
            height: info.height,
            over,
        };
        budget.charge(info.kept_bytes + info.decoding_bytes).map_err(over)?;
        let texture = Texture::decode_checked(decoder, path);
        budget.release(info.decoding_bytes);
        if texture.is_err() {
            budget.release(info.kept_bytes);
        }
        texture
    }

    /// Decodes from a decoder whose header [`open_decoder`] checked.
    fn decode_checked(decoder: impl image::ImageDecoder, path: &Path) -> Result<Texture, TextureError> {
        let img = image::DynamicImage::from_decoder(decoder)
            .map_err(|source| TextureError::Unreadable { path: path.to_path_buf(), source })?;
        Ok(Texture::from_image(img))
    }

    /// Converts a decoded image.
    pub fn from_image(img: impl Into<image::DynamicImage>) -> Texture {
        let rgb = img.into().into_rgb8();
        let (texels, _) = rgb.as_raw().as_chunks::<3>();
        Texture::from_top_down(rgb.width(), rgb.height(), texels)
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel in `row` (counted from the bottom) and `column`, as linear values (`byte / 256`).
    #[inline]
    pub fn texel(&self, row: u32, column: u32) -> [f32; 3] {
        let t = self.texels[tiled_index(self.tiles_x, row, column)];
        [t[0], t[1], t[2]].map(|b| b as f32 / 256.0)
    }

    /// Bilinear lookup at `(u, v)` (spec 5.6): `u` picks the row `frac(u) * height` counted from
    /// the bottom, `v` the column `frac(v) * width`; texel `k` sits at coordinate `k` (as in the
    /// course template) and the filter wraps around both edges.
    #[inline]
    pub fn sample(&self, u: f64, v: f64) -> DVec3 {
        let (r0, r1, fr) = wrap_coordinate(u, self.height);
        let (c0, c1, fc) = wrap_coordinate(v, self.width);
        let t = |r, c| {
            let t = self.texels[tiled_index(self.tiles_x, r, c)];
            DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
        };
        let bottom = t(r0, c0) * (1.0 - fc) + t(r0, c1) * fc;
        let top = t(r1, c0) * (1.0 - fc) + t(r1, c1) * fc;
        (bottom * (1.0 - fr) + top * fr) * (1.0 / 256.0)
    }
}

/// Index of texel (`row`, `column`) in the tiled storage.
#[inline]
fn tiled_index(tiles_x: u32, row: u32, column: u32) -> usize {
    let tile = (row / TILE) * tiles_x + column / TILE;
    (tile * TILE * TILE + (row % TILE) * TILE + column % TILE) as usize
}

/// The two texel indices around `frac(x) * n` and the weight of the second.
#[inline]
fn wrap_coordinate(x: f64, n: u32) -> (u32, u32, f64) {
    let f = if x.is_finite() { x - x.floor() } else { 0.0 };
    let p = f * n as f64;
    let i = (p.floor() as u32).min(n - 1);
    let next = if i + 1 == n { 0 } else { i + 1 };
    (i, next, (p - i as f64).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bitmap_gradients_are_the_bilinear_derivative() {
        // Luminance grows by 0.1 per texel across and 0.02 per texel down.
        let texels =
            (0..4).flat_map(|y| (0..4).map(move |x| [0.1 * x as f32 + 0.02 * y as f32; 3])).collect();
        let b = Bitmap::from_texels(4, 4, texels);
        let (gx, gy) = b.luminance_gradient(0.5, 0.5, crate::material::Wrap::Clamp);
        assert!((gx - 0.1).abs() < 1e-6 && (gy - 0.02).abs() < 1e-6, "{gx} {gy}");
        // Agrees with finite differences of the lookup inside a texel cell.
        let (u, v, h) = (0.4, 0.55, 1e-6);
        let f = |u: f64, v: f64| b.lookup(u, v, false, crate::material::Wrap::Clamp).x;
        let (gx, gy) = b.luminance_gradient(u, v, crate::material::Wrap::Clamp);
        let fd = ((f(u + h, v) - f(u - h, v)) / (2.0 * h), (f(u, v + h) - f(u, v - h)) / (2.0 * h));
        assert!((gx * 4.0 - fd.0).abs() < 1e-4 && (gy * 4.0 - fd.1).abs() < 1e-4, "{gx} {gy} {fd:?}");
    }

    #[test]
    fn builtin_names_parse() {
        assert_eq!(Builtin::parse("marble"), Ok(Builtin::Marble));
        assert_eq!(Builtin::parse("wood"), Ok(Builtin::Wood));
        assert_eq!(Builtin::parse("checker"), Ok(Builtin::Checker(8)));
        assert_eq!(Builtin::parse("checker:20"), Ok(Builtin::Checker(20)));
        assert_eq!(Builtin::parse("stripes:3"), Ok(Builtin::Stripes(3)));
        assert!(Builtin::parse("checker:0").is_err());
        assert!(Builtin::parse("checker:x").is_err());
        assert!(Builtin::parse("marble:2").is_err());
        let err = Builtin::parse("granite").expect_err("unknown");
        assert!(err.contains("`builtin:marble`"), "{err}");
    }

    /// A 2x2 texture: bottom row (0.0, 0.25), top row (0.5, 0.75), given top row first.
    fn tiny() -> Texture {
        let g = |x: u8| [x, x, x];
        Texture::from_top_down(2, 2, &[g(128), g(192), g(0), g(64)])
    }

    #[test]
    fn rows_are_counted_from_the_bottom() {
        let t = tiny();
        assert_eq!(t.texel(0, 0), [0.0; 3]);
        assert_eq!(t.texel(1, 1), [0.75; 3]);
        assert_eq!(t.sample(0.0, 0.0).x, 0.0);
        assert_eq!(t.sample(0.5, 0.0).x, 0.5, "u picks the row");
        assert_eq!(t.sample(0.0, 0.5).x, 0.25, "v picks the column");
    }

    #[test]
    fn lookup_is_bilinear_and_wraps() {
        let t = tiny();
        // Halfway between rows 0 and 1 and columns 0 and 1: the mean of all four.
        assert!((t.sample(0.25, 0.25).x - 0.375).abs() < 1e-9);
        // Past the last row the filter wraps to row 0.
        assert!((t.sample(0.75, 0.0).x - 0.25).abs() < 1e-9);
        // Periodic in both directions, negative coordinates included.
        assert!((t.sample(-0.75, 2.25).x - t.sample(0.25, 0.25).x).abs() < 1e-9);
        assert_eq!(t.sample(f64::NAN, f64::INFINITY).x, 0.0);
    }

    #[test]
    fn eight_bit_values_are_divided_by_256() {
        let img =
            image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(1, 1, image::Rgb([128, 255, 0])));
        let t = Texture::from_image(img);
        assert_eq!(t.texel(0, 0), [0.5, 255.0 / 256.0, 0.0]);
        assert_eq!(t.sample(0.3, 0.7), DVec3::new(0.5, 255.0 / 256.0, 0.0));
    }

    #[test]
    fn empty_images_are_refused() {
        // A Radiance file 8 pixels wide and 0 high (the fuzzer's first crash: the lookup in the
        // empty texture underflowed).
        let hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 8\n";
        let err = Texture::from_bytes(hdr, "empty.hdr", &MemoryBudget::new(1 << 20)).expect_err("empty");
        assert!(matches!(err, TextureError::Empty { width: 8, height: 0, .. }), "{err}");
        assert_eq!(err.to_string(), "texture `empty.hdr` is an empty image (8x0 pixels)");
    }

    #[test]
    fn odd_sizes_keep_every_texel_in_place() {
        // 5 x 7: the tiles do not divide the size.
        let (w, h) = (5u32, 7u32);
        let top_down: Vec<[u8; 3]> = (0..w * h).map(|i| [i as u8, (i * 3) as u8, 7]).collect();
        let t = Texture::from_top_down(w, h, &top_down);
        for i in 0..w * h {
            let (row_from_top, column) = (i / w, i % w);
            let expected = top_down[i as usize].map(|b| b as f32 / 256.0);
            assert_eq!(t.texel(h - 1 - row_from_top, column), expected, "texel {i}");
        }
    }
}

/// A linear-RGB image of the physically based materials and environment maps (Mitsuba's
/// `bitmap` and `envmap`): 32-bit float texels, row 0 at the **top**, as Mitsuba stores them.
/// 8-bit and 16-bit images are decoded from sRGB unless read raw; EXR and HDR images are linear.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    width: u32,
    height: u32,
    texels: Vec<[f32; 3]>,
}

impl Bitmap {
    /// Bytes a bitmap of `width` x `height` texels keeps.
    pub fn memory_bytes(width: u32, height: u32) -> u64 {
        u64::from(width) * u64::from(height) * 12
    }

    /// Reads an image file, its size checked from the header and its memory charged to `budget`
    /// before it is decoded. `raw` keeps 8- and 16-bit values as stored (`value / max`).
    pub fn load(path: &Path, raw: bool, budget: &MemoryBudget) -> Result<Bitmap, TextureError> {
        let (decoder, info) = open_decoder(open_file(path)?, path)?;
        let kept = Bitmap::memory_bytes(info.width, info.height);
        let decoding = image::ImageDecoder::total_bytes(&decoder);
        let over = |over| TextureError::OverBudget {
            path: path.to_path_buf(),
            width: info.width,
            height: info.height,
            over,
        };
        budget.charge(kept + decoding).map_err(over)?;
        let decoded = image::DynamicImage::from_decoder(decoder);
        budget.release(decoding);
        let img = decoded.map_err(|source| {
            budget.release(kept);
            TextureError::Unreadable { path: path.to_path_buf(), source }
        })?;
        let linear = matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
        let rgb = img.into_rgb32f();
        let decode = !linear && !raw;
        let texels = rgb
            .as_raw()
            .as_chunks::<3>()
            .0
            .iter()
            .map(|t| if decode { t.map(srgb_to_linear) } else { *t })
            .collect();
        Ok(Bitmap { width: rgb.width(), height: rgb.height(), texels })
    }

    /// A bitmap from texels given top row first, `width * height` of them.
    pub fn from_texels(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Bitmap {
        assert_eq!(texels.len(), width as usize * height as usize, "texel count");
        Bitmap { width, height, texels }
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel at column `x`, row `y` (from the top).
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> DVec3 {
        let t = self.texels[y as usize * self.width as usize + x as usize];
        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
    }

    /// Mitsuba's lookup at texture coordinates `(u, v)`: `u` across from the left, `v` down from
    /// the top, texel centres at half-integers; bilinear unless `nearest`, with `wrap` beyond
    /// the edges.
    #[inline]
    pub fn lookup(&self, u: f64, v: f64, nearest: bool, wrap: crate::material::Wrap) -> DVec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let index = |i: i64, n: i64| wrap_index(i, n, wrap);
        let (x, y) = (u * w as f64, v * h as f64);
        if !x.is_finite() || !y.is_finite() {
            return DVec3::ZERO;
        }
        if nearest {
            return self.texel(index(x.floor() as i64, w), index(y.floor() as i64, h));
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t = |dx: i64, dy: i64| self.texel(index(x0 + dx, w), index(y0 + dy, h));
        (t(0, 0) * (1.0 - fx) + t(1, 0) * fx) * (1.0 - fy) + (t(0, 1) * (1.0 - fx) + t(1, 1) * fx) * fy
    }

    /// The gradient of the luminance of the bilinear [`Bitmap::lookup`] at `(u, v)` in texel
    /// units: `(d/dx, d/dy)` per texel across and down (multiply by the width and height for
    /// the gradient in `(u, v)`); `(0, 0)` where the coordinates are not finite.
    pub fn luminance_gradient(&self, u: f64, v: f64, wrap: crate::material::Wrap) -> (f64, f64) {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = (u * w as f64 - 0.5, v * h as f64 - 0.5);
        if !x.is_finite() || !y.is_finite() {
            return (0.0, 0.0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let f = |dx: i64, dy: i64| {
            luminance(self.texel(wrap_index(x0 + dx, w, wrap), wrap_index(y0 + dy, h, wrap)))
        };
        let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
        let dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        (dx, dy)
    }
}

/// Texel index `i` of a row or column of `n` texels, wrapped as `wrap` says.
fn wrap_index(i: i64, n: i64, wrap: crate::material::Wrap) -> u32 {
    let i = match wrap {
        crate::material::Wrap::Repeat => i.rem_euclid(n),
        crate::material::Wrap::Clamp => i.clamp(0, n - 1),
        crate::material::Wrap::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    };
    i as u32
}

/// The sRGB transfer function undone: an encoded value in [0, 1] to linear.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}
