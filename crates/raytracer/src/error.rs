//! Typed errors of the library.

use thiserror::Error;

/// An invalid shape parameter, found when a shape is constructed.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum GeometryError {
    /// A radius that is zero, negative or not finite.
    #[error("the radius must be positive, not {0}")]
    NonPositiveRadius(f64),
    /// A direction given as the zero vector (the key's name).
    #[error("`{0}=` must not be the zero vector")]
    ZeroVector(&'static str),
    /// Two directions that must span a plane but are parallel (the keys' names).
    #[error("`{0}=` must not be parallel to `{1}=`")]
    ParallelAxes(&'static str, &'static str),
    /// A cylinder or surface of revolution whose two axis points coincide.
    #[error("the axis from `O1=` to `O2=` has zero length")]
    ZeroAxis,
    /// A shape with no area (collinear triangle corners, a profile on the axis), with why.
    #[error("the shape is degenerate: {0}")]
    Degenerate(&'static str),
    /// A Bezier profile with too few or too many control points (how many).
    #[error("a Bezier profile needs 2 to 32 control points, not {0}")]
    ControlPoints(usize),
}
