//! Rays and the closed set of shapes the scene language can describe.
//!
//! Conventions: the world is **z-up** and right-handed; distances are unitless (scenes use sizes of
//! about 0.1 to 10, but walls are often spheres of radius 1e5), so the analytic shapes are
//! computed in `f64`. Triangle meshes keep their vertices in `f32` (as Embree does) with a
//! watertight test and recompute the hit point in `f64`.
//! A shape reports hits as a ray parameter `t` plus the [`ShapePart`] that was hit (with the
//! triangle and its barycentric weights, or the curve parameter, that the intersection found);
//! the surface frame (point, normals) and texture coordinates are computed afterwards, for the
//! nearest hit only.

pub mod bezier;
mod cylinder;
pub mod mesh;
pub mod mesh_file;
pub mod obj;
mod plane;
pub mod ply;
pub mod serialized;
mod sphere;
mod square;
pub mod triangle;
pub mod triangle_set;

pub use crate::base::bounds::Bounds;
pub use crate::base::ray::{Ray, SPAWN_OFFSET, offset_origin};
pub use bezier::Bezier;
pub use cylinder::Cylinder;
pub use mesh::{MESH_ERROR_SCALE, MeshVertices, TriangleIndices, TriangleMesh};
pub use obj::{MeshFile, MeshTransform};
pub use plane::Plane;
pub use sphere::Sphere;
pub use square::Square;
pub use triangle::Triangle;
pub use triangle_set::{MeshRay, TriangleSet};

use std::sync::Arc;

use glam::DVec3;

/// Which part of a shape a ray hit, with what the intersection found there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapePart {
    /// The only surface of a sphere, plane or square, or the curved side of a cylinder.
    Main,
    /// The cap disc of a cylinder at `O1` (normal `-axis`).
    BottomCap,
    /// The cap disc of a cylinder at `O2` (normal `+axis`).
    TopCap,
    /// A triangle (of a mesh, or a single triangle with `index` 0) at the barycentric weights
    /// `b1`, `b2` of its second and third corners.
    Triangle {
        /// The triangle's index in its mesh.
        index: u32,
        /// Weight of the second corner.
        b1: f32,
        /// Weight of the third corner.
        b2: f32,
    },
    /// A Bezier surface of revolution at curve parameter `s` in [0, 1].
    Profile {
        /// The curve parameter.
        s: f64,
    },
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

/// The closed set of geometric shapes (pbrt's tagged union, as a Rust enum). The larger shapes
/// are boxed so that a scene of many small ones (spheres) stays compact.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere (`primitive sphere`).
    Sphere(Sphere),
    /// An infinite plane (`primitive plane`).
    Plane(Plane),
    /// A parallelogram (`primitive square`).
    Square(Box<Square>),
    /// A closed cylinder with both caps (`primitive cylinder`).
    Cylinder(Box<Cylinder>),
    /// A single triangle (`primitive triangle`).
    Triangle(Box<Triangle>),
    /// A Bezier surface of revolution (`primitive bezier`).
    Bezier(Box<Bezier>),
    /// A triangle mesh, loaded (the triangles of one material of a mesh file).
    Mesh(Arc<TriangleMesh>),
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
            Shape::Triangle(s) => s.intersect(ray, t_min, t_max),
            Shape::Bezier(s) => s.intersect(ray, t_min, t_max),
            // Meshes start their rays at the origin (every caller's `t_min` is 0; a mesh hit is
            // only trusted beyond its rounding error anyway).
            Shape::Mesh(m) => m.intersect(ray, t_max),
        }
    }

    /// Whether the shape lies on the ray with `0 < t < t_max` (for shadow rays; faster than
    /// [`Shape::intersect`] for meshes).
    #[inline]
    pub fn occludes(&self, ray: &Ray, t_max: f64) -> bool {
        match self {
            Shape::Mesh(m) => m.occluded(ray, t_max),
            _ => self.intersect(ray, 0.0, t_max).is_some(),
        }
    }

    /// The hit point: `ray.at(t)`, except on a triangle, where it is recomputed from the
    /// barycentric weights in double precision so that it lies on the triangle's plane.
    #[inline]
    pub fn hit_point(&self, ray: &Ray, hit: &ShapeHit) -> DVec3 {
        match (self, hit.part) {
            (Shape::Mesh(m), ShapePart::Triangle { index, b1, b2 }) => m.point_at(index, b1, b2),
            (Shape::Triangle(t), ShapePart::Triangle { b1, b2, .. }) => {
                // The single-precision weights are a start; the plane is exact in double precision.
                let p = t.point_at(b1 as f64, b2 as f64);
                let q = ray.at(hit.t);
                q - t.normal * (q - p).dot(t.normal)
            }
            _ => ray.at(hit.t),
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
            Shape::Triangle(s) => s.normal,
            Shape::Bezier(s) => match part {
                ShapePart::Profile { s: at } => s.outward_normal(point, at),
                _ => s.axis,
            },
            Shape::Mesh(m) => match part {
                ShapePart::Triangle { index, .. } => m.face_normal(index),
                _ => DVec3::Z,
            },
        }
    }

    /// The unit normal to shade with, on the outward side: the interpolated vertex normal of a
    /// smooth mesh, `None` where it equals the outward normal (every other shape).
    #[inline]
    pub fn shading_normal(&self, part: ShapePart) -> Option<DVec3> {
        match (self, part) {
            (Shape::Mesh(m), ShapePart::Triangle { index, b1, b2 }) => m.shading_normal(index, b1, b2),
            _ => None,
        }
    }

    /// The directions in which the texture coordinates `u` and `v` grow at `point` (not unit
    /// vectors; for tangent-space normal maps).
    pub fn texture_tangents(&self, point: DVec3, part: ShapePart) -> (DVec3, DVec3) {
        match self {
            Shape::Sphere(s) => {
                // u runs from the -pole to the +pole, v around the pole.
                let i = (point - s.centre).normalize_or(s.pole());
                let around = s.pole().cross(i);
                let up = i.cross(around);
                (up, around)
            }
            Shape::Plane(p) => match p.texture_axes.as_deref() {
                Some(&(u, v)) => (u, v),
                None => any_tangents(p.normal),
            },
            Shape::Square(s) => (s.dx, s.dy),
            Shape::Cylinder(c) => match part {
                ShapePart::Main => (c.axis, c.axis.cross(c.outward_normal(point, part))),
                _ => any_tangents(c.axis),
            },
            Shape::Triangle(t) => t.texture_tangents(),
            Shape::Bezier(b) => match part {
                ShapePart::Profile { s } => b.texture_tangents(point, s),
                _ => any_tangents(b.axis),
            },
            Shape::Mesh(m) => match part {
                ShapePart::Triangle { index, .. } => m.texture_tangents(index),
                _ => any_tangents(DVec3::Z),
            },
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
            Shape::Triangle(s) => match part {
                ShapePart::Triangle { b1, b2, .. } => (b1 as f64, b2 as f64),
                _ => s.texture_coordinates(point),
            },
            Shape::Bezier(s) => match part {
                ShapePart::Profile { s: at } => s.texture_coordinates(point, at),
                _ => (0.0, 0.0),
            },
            Shape::Mesh(m) => match part {
                ShapePart::Triangle { index, b1, b2 } => m.texture_coordinates(index, b1, b2),
                _ => (0.0, 0.0),
            },
        }
    }

    /// Whether the shape has a box around it ([`Shape::bounds`] is `Some`): all but a plane and
    /// an empty mesh.
    pub fn is_bounded(&self) -> bool {
        match self {
            Shape::Plane(_) => false,
            Shape::Mesh(m) => !m.is_empty(),
            _ => true,
        }
    }

    /// An axis-aligned box around the shape, or `None` for an unbounded shape (a plane).
    pub fn bounds(&self) -> Option<Bounds> {
        match self {
            Shape::Sphere(s) => Some(s.bounds()),
            Shape::Plane(_) => None,
            Shape::Square(s) => Some(s.bounds()),
            Shape::Cylinder(s) => Some(s.bounds()),
            Shape::Triangle(s) => Some(s.bounds()),
            Shape::Bezier(s) => Some(s.bounds()),
            Shape::Mesh(m) => (!m.is_empty()).then(|| m.bounds()),
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
            Shape::Triangle(s) => s.corners.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max),
            Shape::Bezier(s) => s.magnitude(),
            // Single-precision vertices: rounding errors are larger (see `MESH_ERROR_SCALE`).
            Shape::Mesh(m) => m.magnitude() * MESH_ERROR_SCALE,
        }
    }
}

/// Two directions perpendicular to `n` (tangents for a surface without texture axes).
fn any_tangents(n: DVec3) -> (DVec3, DVec3) {
    let a = n.any_orthonormal_vector();
    (a, n.cross(a))
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
            let point = shape.hit_point(&ray, &hit);
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
