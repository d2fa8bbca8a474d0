//! The scene: plain data parsed from a scene file, and the parser with its diagnostics.
//!
//! Conventions: the world is **z-up** and right-handed; colours are linear RGB (material colours in
//! [0, 1], light colours may exceed 1).

pub mod course;
pub mod mitsuba;
pub mod texture;

pub use crate::base::diagnostic::{Diagnostic, Location, Severity};
pub use crate::base::source::{MAX_SCENE_FILE_BYTES, ReadError, SourceFile, Span};
pub use course::{
    MAX_EMITTED_PHOTONS, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, MAX_ITERATIONS, MAX_KEPT_DIAGNOSTICS, MAX_QUALITY,
    MAX_SAMPLE_PHOTONS, MAX_STORED_PHOTONS, Omitted, Parsed, SceneError, aspect_mismatch, check_image_size,
    parse,
};

use std::sync::Arc;

use glam::DVec3;

use crate::geometry::{MeshFile, Shape};
use crate::light::{Emitter, Light};
use crate::material::Material;

/// A whole scene as described by a scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Ambient colour and the colour of rays that hit nothing.
    pub background: Background,
    /// Camera and render-quality settings.
    pub camera: CameraSettings,
    /// The lights, in file order.
    pub lights: Vec<Light>,
    /// The objects, in file order (but for the mesh files, which are in [`Scene::meshes`] until
    /// the scene is prepared).
    pub primitives: Vec<Primitive>,
    /// The mesh files the scene names (`primitive mesh`, `primitive polyhedron`), in file order,
    /// not yet read: [`crate::PreparedScene`] reads each and puts its primitives in its place.
    pub meshes: Vec<MeshPrimitive>,
    /// The physically based emitters (Mitsuba's `<emitter>`s), which only the path model reads;
    /// course files have none (their lights are [`Scene::lights`]).
    pub emitters: Vec<Emitter>,
    /// What the scene file says about rendering it (Mitsuba's integrator, sampler and film);
    /// the defaults for course files.
    pub render: SceneRender,
}

/// The render settings a scene file states (Mitsuba's `<integrator>`, `<sampler>` and
/// `<rfilter>`). Command-line options win over them.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRender {
    /// Samples a pixel (the sampler's `sample_count`), if the file says.
    pub samples: Option<u32>,
    /// Longest path in segments (the integrator's `max_depth`; `-1`, unbounded, is `u32::MAX`),
    /// if the file says.
    pub max_depth: Option<u32>,
    /// The path depth from which Russian roulette may end a path (`rr_depth`, default 5).
    pub rr_depth: u32,
    /// Whether emitters seen directly from the camera are left out (`hide_emitters`).
    pub hide_emitters: bool,
    /// How samples spread over pixels (the film's `rfilter`).
    pub filter: PixelFilter,
    /// Whether 8-bit output is sRGB-encoded by default (Mitsuba's convention); course files
    /// write their values as they are unless `--gamma` is given.
    pub srgb_output: bool,
    /// Mitsuba's `direct` integrator (direct lighting only, with its sample counts) instead of
    /// the path tracer, when the file asks for it.
    pub direct: Option<DirectSamples>,
}

/// The sample counts of Mitsuba's `direct` integrator: at each surface seen from the camera,
/// `emitter_samples` emitter samples and `bsdf_samples` BSDF samples (at least one in all),
/// weighted by Mitsuba's power heuristic over both counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DirectSamples {
    /// Emitter samples (`emitter_samples`, default `shading_samples`, 1).
    pub emitter_samples: u32,
    /// BSDF samples (`bsdf_samples`, default `shading_samples`, 1).
    pub bsdf_samples: u32,
}

impl Default for SceneRender {
    fn default() -> SceneRender {
        SceneRender {
            samples: None,
            max_depth: None,
            rr_depth: 5,
            hide_emitters: false,
            filter: PixelFilter::Box,
            srgb_output: false,
            direct: None,
        }
    }
}

/// The reconstruction filter of the path model: the weight a sample at an offset from a pixel's
/// centre (in pixels) has in that pixel. Samples are drawn with the filter's own density
/// (filter importance sampling), so every sample has weight 1 and pixels stay independent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelFilter {
    /// Uniform over the pixel (`box`, radius 0.5): the course's sampling.
    Box,
    /// `tent`: `1 - |x| / radius` per axis (default radius 1).
    Tent {
        /// Radius in pixels.
        radius: f64,
    },
    /// `gaussian`: `exp(-x^2 / (2 stddev^2)) - exp(-radius^2 / (2 stddev^2))` per axis, radius
    /// `4 stddev` (Mitsuba's definition; default `stddev` 0.5).
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f64,
    },
}

/// The `background` block.
#[derive(Clone, Debug, PartialEq)]
pub struct Background {
    /// `color=`: the ambient colour (spec 5.2) and, without a gradient, the colour of rays that
    /// hit nothing.
    pub color: DVec3,
    /// `top=` / `bottom=`: a vertical gradient for rays that hit nothing.
    pub gradient: Option<Gradient>,
}

/// A vertical sky gradient: `t = 0.5 (dir.z + 1)`, colour `bottom (1 - t) + top t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gradient {
    /// Colour straight down (`bottom=`, white when only `top=` is given).
    pub bottom: DVec3,
    /// Colour straight up (`top=`, white when only `bottom=` is given).
    pub top: DVec3,
}

impl Background {
    /// The colour seen along a ray of unit direction `dir` that hits nothing.
    #[inline]
    pub fn miss_color(&self, dir: DVec3) -> DVec3 {
        match self.gradient {
            Some(g) => {
                let t = 0.5 * (dir.z + 1.0);
                g.bottom * (1.0 - t) + g.top * t
            }
            None => self.color,
        }
    }
}

impl Default for Background {
    fn default() -> Background {
        Background { color: DVec3::ZERO, gradient: None }
    }
}

/// The `camera` block: view and quality settings.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSettings {
    /// Eye position (`O=`).
    pub eye: DVec3,
    /// Unit view direction (`N=`, normalised).
    pub dir: DVec3,
    /// Width of the image plane at distance 1 (`lens_W=`).
    pub lens_width: f64,
    /// Height of the image plane at distance 1 (`lens_H=`).
    pub lens_height: f64,
    /// Image width in pixels (`image_W=`).
    pub image_width: u32,
    /// Image height in pixels (`image_H=`).
    pub image_height: u32,
    /// Soft-shadow quality (`shade_quality=`): an area light takes `16 * q` shadow samples.
    pub shade_quality: u32,
    /// Glossy quality (`drefl_quality=`): a glossy reflection takes `16 * q` samples.
    pub drefl_quality: u32,
    /// Lens radius of the thin-lens camera (`aperture=`); 0 is a pinhole.
    pub aperture: f64,
    /// Distance to the plane in focus (`focal_dist=`); `None` focuses on the surface seen at
    /// the image centre.
    pub focal_distance: Option<f64>,
    /// Photon-mapping settings (`max_photons=`, `emit_photons=`, ...), used by the photon models.
    pub photons: PhotonSettings,
    /// The light-transport model the file asks for (`algorithm=`), and where.
    pub algorithm: Option<(Algorithm, Location)>,
    /// The image's up direction (unit, at right angles to `dir`), when the file gives one
    /// (Mitsuba's `lookat`); course files take the world's `+z` ([`crate::camera`]).
    pub up: Option<DVec3>,
    /// A parallel projection (Mitsuba's `orthographic` sensor): every ray goes along `dir`
    /// from the plane through `eye` at right angles to it, and `lens_width` x `lens_height`
    /// is the size of the visible rectangle in scene units. Course cameras are perspective.
    pub orthographic: bool,
    /// Where the image's centre lies on the image plane, off the view direction: `(right, up)`
    /// in the plane's units (those of `lens_width` and `lens_height`; 0 for a centred image,
    /// the course's). A Mitsuba film's crop window renders a part of its film this way.
    pub window_offset: (f64, f64),
}

/// The light-transport model named by the camera key `algorithm=` (students' renderers of the
/// course chose their algorithm there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// `RT`: ray tracing, the classic model.
    RayTracing,
    /// `PM`: the course's photon mapper.
    PhotonMapping,
    /// `PPM`: progressive photon mapping.
    ProgressivePhotonMapping,
    /// `SPPM`: stochastic progressive photon mapping.
    StochasticProgressivePhotonMapping,
}

impl Algorithm {
    /// The values `algorithm=` accepts, as written in scene files.
    pub const NAMES: [&str; 4] = ["RT", "PM", "PPM", "SPPM"];

    /// The algorithm a value of `algorithm=` names (case-insensitive).
    pub fn from_name(name: &str) -> Option<Algorithm> {
        match name.to_ascii_uppercase().as_str() {
            "RT" => Some(Algorithm::RayTracing),
            "PM" => Some(Algorithm::PhotonMapping),
            "PPM" => Some(Algorithm::ProgressivePhotonMapping),
            "SPPM" => Some(Algorithm::StochasticProgressivePhotonMapping),
            _ => None,
        }
    }

    /// The name as scene files write it.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::RayTracing => "RT",
            Algorithm::PhotonMapping => "PM",
            Algorithm::ProgressivePhotonMapping => "PPM",
            Algorithm::StochasticProgressivePhotonMapping => "SPPM",
        }
    }
}

impl Default for CameraSettings {
    /// The course template's defaults.
    fn default() -> CameraSettings {
        CameraSettings {
            eye: DVec3::ZERO,
            dir: DVec3::Y,
            lens_width: 0.88,
            lens_height: 0.88,
            image_width: 420,
            image_height: 420,
            shade_quality: 4,
            drefl_quality: 4,
            aperture: 0.0,
            focal_distance: None,
            photons: PhotonSettings::default(),
            algorithm: None,
            up: None,
            orthographic: false,
            window_offset: (0.0, 0.0),
        }
    }
}

/// Photon-mapping settings of the `camera` block. The classic model does not use them.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Capacity of the photon map (`max_photons=`): photons stored at most.
    pub max_photons: u64,
    /// Photons emitted in all (`emit_photons=`); in the progressive models, photons a pass.
    pub emit_photons: u64,
    /// Photons gathered per estimate (`sample_photons=`).
    pub sample_photons: u64,
    /// Largest gathering radius (`sample_dist=`), in world units; the initial radius of the
    /// progressive models.
    pub sample_dist: f64,
    /// Passes of the progressive models (`iterations=`).
    pub iterations: u64,
    /// Radius reduction `alpha` of the progressive models (`reduction=`), in (0, 1].
    pub reduction: f64,
    /// Most visible points the progressive models keep (`max_hitpoints=`); `None`: no bound
    /// beyond the memory limit.
    pub max_hitpoints: Option<u64>,
    /// The photon keys the file sets, in file order, with where (for diagnostics).
    pub keys: Vec<(&'static str, Location)>,
}

impl PhotonSettings {
    /// The keys of the camera block that only the photon models read.
    pub const KEYS: [&str; 7] = [
        "max_photons",
        "emit_photons",
        "sample_photons",
        "sample_dist",
        "iterations",
        "reduction",
        "max_hitpoints",
    ];

    /// Where the file sets `key=`, if it does.
    pub fn location_of(&self, key: &str) -> Option<&Location> {
        self.keys.iter().find(|(k, _)| *k == key).map(|(_, l)| l)
    }
}

impl Default for PhotonSettings {
    /// The photon mapper's documented defaults.
    fn default() -> PhotonSettings {
        PhotonSettings {
            max_photons: 2_000_000,
            emit_photons: 1_000_000,
            sample_photons: 100,
            sample_dist: 1.0,
            iterations: 64,
            reduction: 2.0 / 3.0,
            max_hitpoints: None,
            keys: Vec::new(),
        }
    }
}

/// An object: a shape and its material.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    /// The geometry.
    pub shape: Shape,
    /// The surface, shared by every primitive with the same material (the parser shares equal
    /// untextured materials; a mesh's triangles all share their mesh's).
    pub material: Arc<Material>,
}

/// A mesh file the scene names (`primitive mesh`, `primitive polyhedron`), before it is read.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPrimitive {
    /// Its place among [`Scene::primitives`]: its triangles go just before the primitive with this
    /// index (after those of earlier mesh files with the same index), one primitive per material
    /// of the file.
    pub index: usize,
    /// The file, as the scene names it, and where its vertices go.
    pub file: MeshFile,
    /// The block's material (a material of the file replaces its colour).
    pub material: Arc<Material>,
}
