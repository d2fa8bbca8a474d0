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
    /// A vector so long that computing with it overflows (the key's name).
    #[error("`{0}=` is too large to use")]
    TooLarge(&'static str),
    /// A vector not zero but so short that its squared length underflows to zero (the key's name).
    #[error("`{0}=` is too small to use")]
    TooSmall(&'static str),
    /// A cylinder whose axis is too long for its length to be computed.
    #[error("the axis from `O1=` to `O2=` is too long to use")]
    AxisTooLong,
    /// A cylinder whose cap centres differ by so little that the axis's length underflows.
    #[error("the axis from `O1=` to `O2=` is too short to use")]
    AxisTooShort,
}

/// The unit vector along `v` (named `key` in messages), for any finite `v` but zero: it is scaled
/// by its largest component first, so neither huge nor tiny vectors overflow or underflow.
pub(crate) fn unit_direction(v: glam::DVec3, key: &'static str) -> Result<glam::DVec3, GeometryError> {
    let largest = v.abs().max_element();
    if largest == 0.0 {
        return Err(GeometryError::ZeroVector(key));
    }
    if !largest.is_finite() {
        return Err(GeometryError::TooLarge(key));
    }
    Ok((v / largest).normalize())
}

/// The squared length of `v` (named `key` in messages), which must be neither zero nor overflow
/// or underflow.
pub(crate) fn usable_length_squared(v: glam::DVec3, key: &'static str) -> Result<f64, GeometryError> {
    let l2 = v.length_squared();
    if v == glam::DVec3::ZERO {
        Err(GeometryError::ZeroVector(key))
    } else if l2 == 0.0 {
        Err(GeometryError::TooSmall(key))
    } else if !l2.is_finite() {
        Err(GeometryError::TooLarge(key))
    } else {
        Ok(l2)
    }
}
