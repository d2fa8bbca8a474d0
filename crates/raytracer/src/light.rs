//! Lights: the course's (spec section 3, `light` blocks; the classic model has no distance
//! fall-off) and the physically based emitters of Mitsuba scenes ([`Emitter`]), which only the
//! path model reads.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DMat3, DVec3};

use crate::geometry::{Shape, Sphere, Square};

/// The closed set of lights.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// `light point`: a point at `position`.
    Point {
        /// Position (`O=`).
        position: DVec3,
        /// Colour (`color=`), may exceed 1.
        color: DVec3,
    },
    /// `light square` (alias `area`): a parallelogram `O + a Dx + b Dy`, `a, b` in [-1, 1]. Also
    /// a visible object.
    Square {
        /// The emitting parallelogram.
        shape: Square,
        /// Colour (`color=`), may exceed 1.
        color: DVec3,
    },
    /// `light sphere`: a sphere. Also a visible object.
    Sphere {
        /// The emitting sphere.
        shape: Sphere,
        /// Colour (`color=`), may exceed 1.
        color: DVec3,
    },
}

impl Light {
    /// The light's colour.
    #[inline]
    pub fn color(&self) -> DVec3 {
        match self {
            Light::Point { color, .. } | Light::Square { color, .. } | Light::Sphere { color, .. } => *color,
        }
    }

    /// The light's visible shape: `None` for a point light.
    pub fn shape(&self) -> Option<Shape> {
        match self {
            Light::Point { .. } => None,
            Light::Square { shape, .. } => Some(Shape::Square(Box::new(shape.clone()))),
            Light::Sphere { shape, .. } => Some(Shape::Sphere(shape.clone())),
        }
    }

    /// The light's centre: the point the classic model takes the light direction `L` towards.
    #[inline]
    pub fn centre(&self) -> DVec3 {
        match self {
            Light::Point { position, .. } => *position,
            Light::Square { shape, .. } => shape.centre,
            Light::Sphere { shape, .. } => shape.centre,
        }
    }
}

/// The physically based emitters (Mitsuba 3's), in Mitsuba's units: radiance in W m^-2 sr^-1,
/// intensity in W sr^-1, irradiance in W m^-2, per linear RGB channel. World space is the scene
/// file's own.
#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// `area`: primitive `primitive` emits `radiance` from its front face (the side its normal
    /// points to). The primitive is a triangle mesh or a sphere, drawn and sampled by area.
    Area {
        /// Index into the scene's primitives.
        primitive: u32,
        /// Emitted radiance.
        radiance: DVec3,
    },
    /// `point`: light from a point.
    Point {
        /// Where.
        position: DVec3,
        /// Radiant intensity.
        intensity: DVec3,
    },
    /// `spot`: a point light limited to a cone, with Mitsuba's smooth fall-off between
    /// `beam_width` and `cutoff_angle`.
    Spot {
        /// Where.
        position: DVec3,
        /// Unit direction of the cone's axis.
        axis: DVec3,
        /// Radiant intensity on the axis.
        intensity: DVec3,
        /// Cosine of the half-angle of full intensity (`beam_width`, default 20 degrees).
        cos_beam: f64,
        /// Cosine of the half-angle beyond which nothing is emitted (`cutoff_angle`, default
        /// 30 degrees).
        cos_cutoff: f64,
        /// The spot's `texture`, projected through the cone: it multiplies the intensity of
        /// the direction `d` (in the spot's frame) by its value at
        /// `(0.5 + 0.5 d.x / (d.z tan(cutoff)), 0.5 + 0.5 d.y / (d.z tan(cutoff)))`.
        texture: Option<Arc<crate::material::TextureSpec>>,
        /// World directions to the spot's frame (the inverse of `to_world`'s linear part).
        to_local: DMat3,
    },
    /// `directional`: light arriving along one direction from infinitely far.
    Directional {
        /// Unit direction the light travels in.
        direction: DVec3,
        /// Irradiance on a surface facing it.
        irradiance: DVec3,
    },
    /// `constant`: the same radiance from every direction that escapes the scene.
    Constant {
        /// Radiance.
        radiance: DVec3,
    },
    /// `envmap`: an environment map in latitude-longitude layout, sampled in proportion to its
    /// luminance.
    Environment {
        /// The image file (EXR, HDR, or an 8-bit image decoded from sRGB), resolved.
        file: PathBuf,
        /// Where the scene names it (for messages).
        location: crate::base::diagnostic::Location,
        /// Factor on the image's values (`scale`).
        scale: f64,
        /// Rotation from the map's frame to the world (`to_world`, its linear part; the map's
        /// `+y` is up, as in Mitsuba).
        to_world: DMat3,
    },
}
