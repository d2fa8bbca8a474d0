//! Rays and the rule for where secondary rays start.

use glam::DVec3;

/// A ray `origin + t * dir` with a unit direction, so `t` is a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
}

impl Ray {
    /// A ray from `origin` towards `dir`, which is normalised here (it must not be zero).
    #[inline]
    pub fn new(origin: DVec3, dir: DVec3) -> Ray {
        Ray { origin, dir: dir.normalize() }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// Relative size of the offset that moves a secondary ray's origin off the surface it starts on.
///
/// Hit points are computed in `f64` with an error of a few ulps of the scene's magnitudes (the
/// shape's size and distance from the origin, and the point's coordinates); `1e-9` of that
/// magnitude is millions of ulps, so the offset point is always on the intended side, yet it stays
/// far below anything visible: 1e-4 for a wall sphere of radius 1e5, 1e-12 for a sphere of
/// radius 1e-3 at the origin.
pub const SPAWN_OFFSET: f64 = 1e-9;

/// The start point of a secondary ray leaving `point` towards the side `side` points to (the
/// facing normal for reflected and shadow rays, its negation for transmitted rays). `magnitude` is
/// the larger of the hit shape's magnitude and the point's largest coordinate.
#[inline]
pub fn offset_origin(point: DVec3, side: DVec3, magnitude: f64) -> DVec3 {
    point + side * (SPAWN_OFFSET * magnitude.max(f64::MIN_POSITIVE))
}
