//! The world to draw, as plain data: a heightmap, the terrain's colour and detail maps, the sky box
//! faces and the water texture. It comes from the course's asset folder ([`assets`]), from any
//! heightmap image with generated textures, or entirely from noise ([`procedural`]).
//!
//! Nothing here touches the GPU: every function is pure and unit-tested.

pub mod assets;
pub mod atmosphere;
pub mod chunk;
pub mod dem;
pub mod erosion;
pub mod export;
pub mod ground;
pub mod heightfield;
pub mod heightmap;
pub mod mesh;
pub mod occlusion;
pub mod procedural;
pub mod quadtree;
pub mod splat;

use std::path::{Path, PathBuf};

use glam::DVec3;
use image::{DynamicImage, RgbaImage};

pub use heightfield::Heightfield;
pub use heightmap::{Heightmap, HeightmapError, MAX_HEIGHTMAP_SIDE};
pub use mesh::TerrainMesh;

/// Why a world could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    /// A file could not be opened or read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A file is not an image this program can decode (corrupt, truncated or of an unknown format).
    #[error("{} is not a readable image: {source}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// What the decoder said.
        source: image::ImageError,
    },
    /// An image decoded but is not a usable heightmap.
    #[error("{} is not a usable heightmap: {problem}", path.display())]
    BadHeightmap {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: HeightmapError,
    },
    /// An asset folder lacks some of the course's files.
    #[error(
        "the asset folder {} lacks {} (expected the course's layout: {})",
        dir.display(),
        missing.join(", "),
        assets::ASSET_FILES.join(", ")
    )]
    MissingAssets {
        /// The folder.
        dir: PathBuf,
        /// The files not found in it.
        missing: Vec<String>,
    },
    /// An image too large to load, found from its header before decoding.
    #[error(
        "{} is {width}x{height} pixels, larger than the {MAX_IMAGE_SIDE} pixels a side an image may have",
        path.display()
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
    },
    /// An image with no pixels (a width or a height of 0).
    #[error("{} is an empty image ({width}x{height} pixels)", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// Its width in pixels.
        width: u32,
        /// Its height in pixels.
        height: u32,
    },
    /// The asset path is not a folder.
    #[error("{} is not a folder", path.display())]
    NotAFolder {
        /// The path given.
        path: PathBuf,
    },
}

/// The sky box's five faces, as seen from inside the box.
///
/// Sides go around the box in order, each joining the next along its right edge: `sides[0]` faces
/// the camera at start (the -z wall), then the +x, +z and -x walls. An image's top row is the top of
/// the wall, its bottom row the horizon (y = 0). The top face is seen from below with its bottom
/// row along the -z wall and its left column along the -x wall (the course's `SkyBox0..4`).
#[derive(Debug, Clone, PartialEq)]
pub struct SkyBox {
    /// The four walls: -z, +x, +z, -x.
    pub sides: [RgbaImage; 4],
    /// The ceiling.
    pub top: RgbaImage,
}

/// One face of the sky box.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkyFace {
    /// The -z wall, ahead of the camera at start (`SkyBox0`).
    Front,
    /// The +x wall (`SkyBox1`).
    Right,
    /// The +z wall (`SkyBox2`).
    Back,
    /// The -x wall (`SkyBox3`).
    Left,
    /// The ceiling (`SkyBox4`).
    Top,
}

impl SkyFace {
    /// All faces: the four walls in order around the box, then the top. A face's position in
    /// this list is its index (layer) in [`SkyBox::faces`].
    pub const ALL: [SkyFace; 5] =
        [SkyFace::Front, SkyFace::Right, SkyFace::Back, SkyFace::Left, SkyFace::Top];

    /// The point of this face shown at texture coordinates (`u`, `v`) (0..1, v down the image),
    /// for a box of `size` (x width, y height, z depth) standing on y = 0, centred on the y axis.
    pub fn point(self, u: f64, v: f64, size: DVec3) -> DVec3 {
        let (hx, hz) = (size.x / 2.0, size.z / 2.0);
        let y = size.y * (1.0 - v);
        match self {
            SkyFace::Front => DVec3::new(-hx + 2.0 * hx * u, y, -hz),
            SkyFace::Right => DVec3::new(hx, y, -hz + 2.0 * hz * u),
            SkyFace::Back => DVec3::new(hx - 2.0 * hx * u, y, hz),
            SkyFace::Left => DVec3::new(-hx, y, hz - 2.0 * hz * u),
            SkyFace::Top => DVec3::new(-hx + 2.0 * hx * u, size.y, hz - 2.0 * hz * v),
        }
    }
}

impl SkyBox {
    /// The five images in [`SkyFace::ALL`] order.
    pub fn faces(&self) -> [&RgbaImage; 5] {
        [&self.sides[0], &self.sides[1], &self.sides[2], &self.sides[3], &self.top]
    }
}

/// Everything the renderer draws, as images and heights.
#[derive(Debug, Clone, PartialEq)]
pub struct World {
    /// Heights of the terrain.
    pub heightmap: Heightmap,
    /// Colour of the whole terrain, stretched once over it (top row at -z).
    pub colour_map: RgbaImage,
    /// Grey detail (mean 128), repeated over the terrain and added signed to the colour.
    pub detail_map: RgbaImage,
    /// The sky box faces.
    pub sky: SkyBox,
    /// The water texture, repeated over the sea; it should tile seamlessly.
    pub water: RgbaImage,
    /// The colour map without its baked hill shading and the sky without its painted sun, for
    /// the modern look, which lights the scene itself (the procedural world has them; images
    /// from elsewhere are used as they are).
    pub unlit: Option<UnlitLayers>,
    /// What the world keeps of the elevation data it was made from (metres, water, the mask of
    /// the samples the file had no data for), for worlds made from a DEM ([`dem`]).
    pub elevation: Option<dem::place::ElevationInfo>,
    /// The flow and deposition maps of the erosion that shaped the heights, for the ground
    /// materials; `None` when the heights were not eroded ([`erosion`]).
    pub erosion: Option<erosion::ErosionMaps>,
}

/// Layers of a world without the light painted into them.
#[derive(Debug, Clone, PartialEq)]
pub struct UnlitLayers {
    /// The colour map's albedo: its colours before hill shading.
    pub albedo_map: RgbaImage,
    /// The sky box without the sun's disc and glow.
    pub sky: SkyBox,
}

impl World {
    /// The colour map the modern look lights: the albedo where there is one.
    pub fn albedo_map(&self) -> &RgbaImage {
        self.unlit.as_ref().map_or(&self.colour_map, |unlit| &unlit.albedo_map)
    }

    /// The sky the modern look grades for its sun: the one without a painted sun where there is
    /// one.
    pub fn clear_sky(&self) -> &SkyBox {
        self.unlit.as_ref().map_or(&self.sky, |unlit| &unlit.sky)
    }

    /// Bytes of memory the world's data takes (heightmap and images).
    pub fn memory_bytes(&self) -> usize {
        let image = |image: &RgbaImage| image.as_raw().len();
        let sky = |sky: &SkyBox| sky.faces().iter().map(|face| image(face)).sum::<usize>();
        let heights = self.heightmap.levels().len() * self.heightmap.bytes_per_sample();
        let unlit = self.unlit.as_ref().map_or(0, |u| image(&u.albedo_map) + sky(&u.sky));
        let voids = self.elevation.as_ref().map_or(0, |e| e.voids.len());
        let erosion = self.erosion.as_ref().map_or(0, erosion::ErosionMaps::memory_bytes);
        heights
            + image(&self.colour_map)
            + image(&self.detail_map)
            + sky(&self.sky)
            + image(&self.water)
            + unlit
            + voids
            + erosion
    }
}

/// Largest side of any image the world loads, in pixels (sky faces and colour maps; heightmaps
/// have their own, smaller limit, [`MAX_HEIGHTMAP_SIDE`]).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// An image file's decoder, its format recognised from the content, with its header read and
/// nothing decoded yet.
fn open_decoder(path: &Path) -> Result<impl image::ImageDecoder, WorldError> {
    let read = |source| WorldError::Read { path: path.to_path_buf(), source };
    // Never waits on a named pipe; a folder or device is refused.
    let file = atomic_file::open_regular(path).map_err(read)?;
    header_decoder(image::ImageReader::new(std::io::BufReader::new(file)), path)
}

/// The decoder of an image read from `reader` (`path` names it in messages), as
/// [`open_decoder`].
fn header_decoder<'a, R: std::io::BufRead + std::io::Seek + 'a>(
    reader: image::ImageReader<R>,
    path: &Path,
) -> Result<impl image::ImageDecoder + use<'a, R>, WorldError> {
    let read = |source| WorldError::Read { path: path.to_path_buf(), source };
    let mut reader = reader.with_guessed_format().map_err(read)?;
    // The header only: no size limit yet, so that the size can be named in the message.
    let mut limits = image::Limits::no_limits();
    limits.max_alloc = Some(64 << 20);
    reader.limits(limits);
    reader.into_decoder().map_err(|source| WorldError::Decode { path: path.to_path_buf(), source })
}

/// The size of an image file in pixels, read from its header without decoding it.
pub fn image_size(path: &Path) -> Result<(u32, u32), WorldError> {
    open_decoder(path).map(|decoder| image::ImageDecoder::dimensions(&decoder))
}

/// Decodes an image file, recognising its format from its content. The size is checked from
/// the header first (at most [`MAX_IMAGE_SIDE`] a side), and the decoder may allocate no more
/// than the picture needs. Errors name the file.
pub fn read_image(path: &Path) -> Result<DynamicImage, WorldError> {
    decode_checked(open_decoder(path)?, path)
}

/// Checks the size a decoder's header gives, then decodes behind limits.
fn decode_checked(mut decoder: impl image::ImageDecoder, path: &Path) -> Result<DynamicImage, WorldError> {
    let decode = |source| WorldError::Decode { path: path.to_path_buf(), source };
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(WorldError::TooLarge { path: path.to_path_buf(), width, height });
    }
    if width == 0 || height == 0 {
        return Err(WorldError::Empty { path: path.to_path_buf(), width, height });
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    limits.max_alloc = Some(image::ImageDecoder::total_bytes(&decoder).saturating_add(64 << 20));
    image::ImageDecoder::set_limits(&mut decoder, limits).map_err(decode)?;
    DynamicImage::from_decoder(decoder).map_err(decode)
}

/// Decodes an image file into 8-bit RGBA. Errors name the file.
pub fn read_rgba(path: &Path) -> Result<RgbaImage, WorldError> {
    read_image(path).map(DynamicImage::into_rgba8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_faces_meet_at_their_edges() {
        let size = DVec3::new(200.0, 200.0, 280.0);
        // Each wall's right edge is the next wall's left edge.
        for i in 0..4 {
            let (wall, next) = (SkyFace::ALL[i], SkyFace::ALL[(i + 1) % 4]);
            for v in [0.0, 0.3, 1.0] {
                assert_eq!(wall.point(1.0, v, size), next.point(0.0, v, size));
            }
        }
        // The top's bottom row runs along the front wall's top, its left column along the left wall's.
        assert_eq!(SkyFace::Top.point(0.25, 1.0, size), SkyFace::Front.point(0.25, 0.0, size));
        assert_eq!(SkyFace::Top.point(0.0, 0.25, size), SkyFace::Left.point(0.25, 0.0, size));
        assert_eq!(SkyFace::Front.point(0.5, 1.0, size), DVec3::new(0.0, 0.0, -140.0));
    }

    #[test]
    fn huge_images_are_refused_from_their_header_with_their_size() {
        // A BMP header claiming 20000x20000 pixels, 24-bit, and no pixels.
        let mut bmp = b"BM".to_vec();
        bmp.extend(54u32.to_le_bytes()); // file size (ignored)
        bmp.extend([0; 4]);
        bmp.extend(54u32.to_le_bytes()); // pixel data offset
        bmp.extend(40u32.to_le_bytes()); // BITMAPINFOHEADER
        bmp.extend(20_000i32.to_le_bytes());
        bmp.extend(20_000i32.to_le_bytes());
        bmp.extend(1u16.to_le_bytes());
        bmp.extend(24u16.to_le_bytes());
        bmp.extend([0; 24]);
        let path = std::env::temp_dir().join(format!("rayterra-huge-{}.bmp", std::process::id()));
        std::fs::write(&path, &bmp).expect("write");
        let error = read_image(&path).expect_err("too large").to_string();
        assert!(error.contains("is 20000x20000 pixels, larger than the 16384 pixels a side"), "{error}");
        assert_eq!(image_size(&path).ok(), Some((20_000, 20_000)));
        let error = Heightmap::load(&path).expect_err("too large").to_string();
        assert!(
            error.contains("a heightmap may have at most 8193 samples per side, this one is 20000x20000"),
            "{error}"
        );
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn empty_images_are_refused() {
        let path = std::env::temp_dir().join(format!("rayterra-empty-{}.hdr", std::process::id()));
        std::fs::write(&path, b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 8\n").expect("write");
        let error = read_image(&path).expect_err("empty");
        assert!(matches!(error, WorldError::Empty { width: 8, height: 0, .. }), "{error}");
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn missing_file_error_names_it() {
        let path = Path::new("/nonexistent/rayterra/heightmap.png");
        let error = read_image(path).expect_err("no such file");
        assert!(matches!(error, WorldError::Read { .. }));
        assert!(error.to_string().contains("/nonexistent/rayterra/heightmap.png"), "{error}");
    }
}
