//! The world to draw, as plain data: a heightmap, the terrain's colour and detail maps, the sky box
//! faces and the water texture. It comes from the course's asset folder ([`assets`]), from any
//! heightmap image with generated textures, or entirely from noise ([`procedural`]).
//!
//! Nothing here touches the GPU: every function is pure and unit-tested.

pub mod assets;
pub mod export;
pub mod heightfield;
pub mod heightmap;
pub mod mesh;
pub mod procedural;
pub mod quadtree;

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
        heights
            + image(&self.colour_map)
            + image(&self.detail_map)
            + sky(&self.sky)
            + image(&self.water)
            + unlit
    }
}

/// Decodes an image file, recognising its format from its content. Errors name the file.
pub fn read_image(path: &Path) -> Result<DynamicImage, WorldError> {
    let reader = image::ImageReader::open(path)
        .map_err(|source| WorldError::Read { path: path.to_path_buf(), source })?;
    let reader = reader
        .with_guessed_format()
        .map_err(|source| WorldError::Read { path: path.to_path_buf(), source })?;
    reader.decode().map_err(|source| WorldError::Decode { path: path.to_path_buf(), source })
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
    fn missing_file_error_names_it() {
        let path = Path::new("/nonexistent/rayterra/heightmap.png");
        let error = read_image(path).expect_err("no such file");
        assert!(matches!(error, WorldError::Read { .. }));
        assert!(error.to_string().contains("/nonexistent/rayterra/heightmap.png"), "{error}");
    }
}
