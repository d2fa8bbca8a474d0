//! Rays and the closed set of shapes the scene language can describe.
//!
//! Conventions: the world is **z-up** and right-handed; distances are unitless (scenes use sizes of
//! about 0.1 to 10, but walls are often spheres of radius 1e5), so everything is computed in `f64`.
//! A shape reports hits as a ray parameter `t` plus the [`ShapePart`] that was hit; the surface
//! frame (point, outward normal) and texture coordinates are computed afterwards, for the nearest
//! hit only.

mod bounds;
mod cylinder;
mod plane;
mod ray;
mod sphere;
mod square;

pub use bounds::Bounds;
pub use cylinder::Cylinder;
pub use plane::Plane;
pub use ray::{Ray, offset_origin};
pub use sphere::Sphere;
pub use square::Square;

use glam::DVec3;

/// Which part of a shape a ray hit; only cylinders have more than one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapePart {
    /// The only surface of a sphere, plane or square, or the curved side of a cylinder.
    Main,
    /// The cap disc of a cylinder at `O1` (normal `-axis`).
    BottomCap,
    /// The cap disc of a cylinder at `O2` (normal `+axis`).
    TopCap,
}

/// A hit of a ray on a shape: the ray parameter and the part hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeHit {
    /// Ray parameter of the hit; the point is `origin + t * dir` (`dir` is a unit vector, so `t`
    /// is also the distance).
    pub t: f64,
    /// The part of the shape that was hit.
    pub part: ShapePart,
}

/// The closed set of geometric shapes (pbrt's tagged union, as a Rust enum).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere (`primitive sphere`).
    Sphere(Sphere),
    /// An infinite plane (`primitive plane`).
    Plane(Plane),
    /// A parallelogram (`primitive square`).
    Square(Square),
    /// A closed cylinder with both caps (`primitive cylinder`).
    Cylinder(Cylinder),
}

impl Shape {
    /// The nearest hit with `t_min < t < t_max`, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_min, t_max),
            Shape::Plane(s) => s.intersect(ray, t_min, t_max),
            Shape::Square(s) => s.intersect(ray, t_min, t_max),
            Shape::Cylinder(s) => s.intersect(ray, t_min, t_max),
        }
    }

    /// The unit normal pointing out of the shape at `point` on `part` (for a plane or square, the
    /// normal given in the scene file).
    #[inline]
    pub fn outward_normal(&self, point: DVec3, part: ShapePart) -> DVec3 {
        match self {
            Shape::Sphere(s) => s.outward_normal(point),
            Shape::Plane(s) => s.normal,
            Shape::Square(s) => s.normal,
            Shape::Cylinder(s) => s.outward_normal(point, part),
        }
    }

    /// Texture coordinates `(u, v)` of `point` on `part` (spec section 5.6). `u` selects the
    /// texture row (counted from the bottom), `v` the column; both wrap.
    pub fn texture_coordinates(&self, point: DVec3, part: ShapePart) -> (f64, f64) {
        match self {
            Shape::Sphere(s) => s.texture_coordinates(point),
            Shape::Plane(s) => s.texture_coordinates(point),
            Shape::Square(s) => s.texture_coordinates(point),
            Shape::Cylinder(s) => s.texture_coordinates(point, part),
        }
    }

    /// An axis-aligned box around the shape, or `None` for an unbounded shape (a plane).
    pub fn bounds(&self) -> Option<Bounds> {
        match self {
            Shape::Sphere(s) => Some(s.bounds()),
            Shape::Plane(_) => None,
            Shape::Square(s) => Some(s.bounds()),
            Shape::Cylinder(s) => Some(s.bounds()),
        }
    }

    /// The size of the shape and its distance from the origin, whichever is larger: the
    /// magnitude that rounding errors of its intersections scale with.
    pub fn magnitude(&self) -> f64 {
        match self {
            Shape::Sphere(s) => s.centre.abs().max_element() + s.radius,
            Shape::Plane(s) => s.offset.abs(),
            Shape::Square(s) => s.centre.abs().max_element() + s.dx.length() + s.dy.length(),
            Shape::Cylinder(s) => s.base.abs().max_element().max(s.top.abs().max_element()) + s.radius,
        }
    }
}

/// Solves `a t^2 + 2 b t + c = 0` (note the halved linear coefficient) for its two real roots in
/// increasing order, using the cancellation-free form. Returns `None` when the discriminant is
/// not positive (no roots, or a double root: a tangent ray, which counts as a miss).
#[inline]
pub(crate) fn solve_quadratic(a: f64, half_b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = half_b * half_b - a * c;
    if disc <= 0.0 || a == 0.0 {
        return None;
    }
    let q = -(half_b + half_b.signum() * disc.sqrt());
    if q == 0.0 {
        return None;
    }
    Some(order(q / a, c / q))
}

/// The pair in increasing order.
#[inline]
pub(crate) fn order(a: f64, b: f64) -> (f64, f64) {
    if a < b { (a, b) } else { (b, a) }
}

/// A unit vector perpendicular to `axis`: `unit(axis x (0,0,1))`, or `(1,0,0)` when `axis` is
/// parallel to z. This is the course template's `GetAnVerticalVector`, which fixes where the seam
/// of a cylinder's texture lies.
pub(crate) fn course_perpendicular(axis: DVec3) -> DVec3 {
    let p = axis.cross(DVec3::Z);
    if p.length_squared() < 1e-24 { DVec3::X } else { p.normalize() }
}

#[cfg(test)]
pub(crate) mod test_util {
    //! Helpers shared by the shape tests.
    use super::*;

    /// Scales over which the re-intersection tests run (spec: 1e-3 .. 1e5).
    pub const SCALES: [f64; 9] = [1e-3, 1e-2, 1e-1, 1.0, 10.0, 1e2, 1e3, 1e4, 1e5];

    /// A small deterministic generator of uniform numbers in [0, 1) for tests.
    pub struct TestRng(u64);
    impl TestRng {
        pub fn new(seed: u64) -> Self {
            TestRng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }
        pub fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        pub fn unit_vector(&mut self) -> DVec3 {
            let z = 2.0 * self.uniform() - 1.0;
            let phi = std::f64::consts::TAU * self.uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        }
    }

    /// Checks the spawn rule on `shape`: a ray leaving a hit point (offset as the integrator
    /// does) to the side it came from must not hit the shape again, and a ray continuing through
    /// the surface must not hit it again at (almost) the same point.
    pub fn check_reintersection(shape: &Shape, aim: DVec3, scale: f64, rng: &mut TestRng) {
        let mut hits = 0;
        for _ in 0..400 {
            let origin = aim + rng.unit_vector() * scale * 3.0;
            let target = aim + rng.unit_vector() * scale * 0.5;
            let ray = Ray::new(origin, target - origin);
            let Some(hit) = shape.intersect(&ray, 0.0, f64::INFINITY) else {
                continue;
            };
            hits += 1;
            let point = ray.at(hit.t);
            let outward = shape.outward_normal(point, hit.part);
            let facing = if ray.dir.dot(outward) < 0.0 { outward } else { -outward };
            let magnitude = shape.magnitude().max(point.abs().max_element());
            // Reflection: back to the side the ray came from.
            let reflected = ray.dir - 2.0 * ray.dir.dot(facing) * facing;
            let back = Ray::new(offset_origin(point, facing, magnitude), reflected);
            if let Some(again) = shape.intersect(&back, 0.0, f64::INFINITY) {
                // Only a concave view of the shape (inside a sphere or cylinder) may be hit
                // again, and then far away from the point.
                assert!(
                    again.t > 1e-6 * scale,
                    "reflected ray re-hit {shape:?} at t={} (scale {scale})",
                    again.t
                );
            }
            // Transmission: straight through the surface.
            let through = Ray::new(offset_origin(point, -facing, magnitude), ray.dir);
            if let Some(again) = shape.intersect(&through, 0.0, f64::INFINITY) {
                assert!(
                    again.t > 1e-6 * scale,
                    "transmitted ray re-hit {shape:?} at t={} (scale {scale})",
                    again.t
                );
            }
        }
        assert!(hits > 50, "too few test rays hit {shape:?}: {hits}");
    }
}
