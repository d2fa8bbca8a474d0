//! Lights (spec section 3, `light` blocks). The classic model has no distance fall-off.

use glam::DVec3;

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
