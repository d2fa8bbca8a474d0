//! Lights: the course's (spec section 3, `light` blocks; the classic model has no distance
//! fall-off) and the physically based emitters of Mitsuba scenes ([`Emitter`]), which only the
//! path model reads.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3};

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
        /// Emitted radiance: a colour, or a texture over the shape's texture coordinates.
        radiance: crate::material::Param,
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
    /// `projector`: a point light that projects an image (Mitsuba's reciprocal of a perspective
    /// camera), a delta position at `to_world`'s origin looking along its local `+z`.
    ///
    /// A point `p` whose local position `q = to_local p` has `q.z > 0` sees the image at
    /// `u = 0.5 - 0.5 q.x / (q.z tan_x)`, `v = 0.5 - 0.5 aspect q.y / (q.z tan_x)` (outside
    /// `[0, 1]^2` it is dark), where `tan_x` is the tangent of half the horizontal field of view
    /// and `aspect` the texture's width over its height (1 for a constant). It receives
    /// `pi scale E(u, v) / (q.z^2 cos)` from it, `cos` the cosine between `to_world`'s `+z` (as
    /// the matrix maps it, not normalised) and the direction to `p`: a projection of a constant
    /// `E` on a plane facing it at distance 1 gives it the irradiance `pi scale E` (Mitsuba
    /// 3.9.1's `projector.cpp`).
    Projector {
        /// The projected image: irradiance on the image plane at distance 1 (`irradiance`).
        irradiance: crate::material::Param,
        /// Factor on it (`scale`, default 1).
        scale: f64,
        /// Tangent of half the field of view along `fov_axis` (`fov`, or `focal_length` on
        /// 35 mm film along the diagonal; default 50 mm).
        tan_half: f64,
        /// The image axis the field of view spans.
        fov_axis: FovAxis,
        /// The projector's frame to the world (`to_world`).
        to_world: DMat4,
        /// Its inverse.
        to_local: DMat4,
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

/// The image axis a field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// The width (`x`, the default).
    X,
    /// The height (`y`).
    Y,
    /// The diagonal (`diagonal`; a focal length's).
    Diagonal,
    /// The shorter side (`smaller`).
    Smaller,
    /// The longer side (`larger`).
    Larger,
}

impl FovAxis {
    /// The names of the axes as scene files write them, in the order of [`FovAxis::parse`].
    pub const NAMES: [&'static str; 5] = ["x", "y", "diagonal", "smaller", "larger"];

    /// The axis of a name of [`FovAxis::NAMES`].
    pub fn parse(name: &str) -> Option<FovAxis> {
        Some(match name {
            "x" => FovAxis::X,
            "y" => FovAxis::Y,
            "diagonal" => FovAxis::Diagonal,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => return None,
        })
    }

    /// The tangent of half the horizontal field of view, for an image of `aspect` (width over
    /// height) whose field of view along this axis has half-angle tangent `tan_half`.
    pub fn tan_half_x(self, tan_half: f64, aspect: f64) -> f64 {
        let axis = match self {
            FovAxis::Smaller if aspect >= 1.0 => FovAxis::Y,
            FovAxis::Smaller => FovAxis::X,
            FovAxis::Larger if aspect >= 1.0 => FovAxis::X,
            FovAxis::Larger => FovAxis::Y,
            a => a,
        };
        match axis {
            FovAxis::Y => tan_half * aspect,
            FovAxis::Diagonal => tan_half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
            _ => tan_half,
        }
    }
}
