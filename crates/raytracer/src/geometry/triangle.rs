//! Single triangles (`primitive triangle`) and the watertight ray-triangle test they share with
//! meshes.
//!
//! The test is the one of Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT
//! 2013): the triangle is moved into a frame where the ray starts at the origin and runs along
//! +z, and the signs of three 2-D edge functions decide inside or outside. Two triangles sharing an
//! edge compute that edge's function from the same numbers with opposite signs, so a ray through
//! the edge (or a shared vertex) hits one of them, never neither.

use glam::DVec3;

use super::{Bounds, Ray, ShapeHit, ShapePart};
use crate::base::error::GeometryError;

/// A ray in the frame of the watertight test: `kz` is the axis where the direction is largest,
/// `kx`, `ky` the other two (swapped to keep the winding), and the shear that maps the direction
/// to +z.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// Axis permutation `(kx, ky, kz)`.
    pub k: [usize; 3],
    /// Shear `(sx, sy, sz)`: `x' = x - sx z`, `y' = y - sy z`, `z' = sz z`.
    pub shear: [f64; 3],
    /// The ray's origin.
    pub origin: DVec3,
}

impl WatertightRay {
    /// The frame of `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> WatertightRay {
        let d = ray.dir;
        let [kx, ky, kz] = axis_permutation([d.x, d.y, d.z]);
        WatertightRay {
            k: [kx, ky, kz],
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
            origin: ray.origin,
        }
    }

    /// The hit of the ray on the triangle `p0 p1 p2` with `t_min < t < t_max`, as
    /// `(t, b1, b2)` where `b1`, `b2` are the barycentric weights of `p1` and `p2`. Both faces are
    /// hit; a degenerate (zero-area) triangle is never hit.
    #[inline]
    pub fn intersect(&self, p: [DVec3; 3], t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let a = p[0] - self.origin;
        let b = p[1] - self.origin;
        let c = p[2] - self.origin;
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        let t_scaled = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
        let t = t_scaled / det;
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some((t, v / det, w / det))
    }
}

/// The axes `(kx, ky, kz)` of the watertight test's frame for a ray direction `d`: `kz` where `d`
/// is largest in magnitude, `kx` and `ky` the next two, swapped when `d[kz]` is negative so the
/// triangles' winding is kept. (Also used by meshes, whose rays are single-precision.)
#[inline]
pub fn axis_permutation(d: [f64; 3]) -> [usize; 3] {
    let a = d.map(f64::abs);
    let kz = if a[0] > a[1] {
        if a[0] > a[2] { 0 } else { 2 }
    } else if a[1] > a[2] {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if d[kz] < 0.0 { [ky, kx, kz] } else { [kx, ky, kz] }
}

/// A triangle with corners `p0`, `p1`, `p2` (`P0= P1= P2=` or `O1= O2= O3=`). Both faces are
/// hit; its front faces `(p1 - p0) x (p2 - p0)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    /// The corners.
    pub corners: [DVec3; 3],
    /// Unit normal `unit((p1 - p0) x (p2 - p0))`.
    pub normal: DVec3,
}

impl Triangle {
    /// The triangle with the given corners; an error if they are collinear (no area).
    pub fn new(p0: DVec3, p1: DVec3, p2: DVec3) -> Result<Triangle, GeometryError> {
        let cross = (p1 - p0).cross(p2 - p0);
        let scale = (p1 - p0).length() * (p2 - p0).length();
        let area = cross.length();
        if area.is_nan() || area <= 1e-12 * scale || !area.is_finite() {
            return Err(GeometryError::Degenerate("the three corners are collinear"));
        }
        Ok(Triangle { corners: [p0, p1, p2], normal: cross / area })
    }

    /// The nearest hit with `t_min < t < t_max` (watertight; both faces).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        let (t, b1, b2) = WatertightRay::new(ray).intersect(self.corners, t_min, t_max)?;
        Some(ShapeHit { t, part: ShapePart::Triangle { index: 0, b1: b1 as f32, b2: b2 as f32 } })
    }

    /// The point with barycentric weights `b1`, `b2` of `p1`, `p2`.
    #[inline]
    pub fn point_at(&self, b1: f64, b2: f64) -> DVec3 {
        let [p0, p1, p2] = self.corners;
        p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2
    }

    /// The texture coordinates at a point: the triangle's own barycentric coordinates
    /// `(u, v) = (b1, b2)` (spec section 9), so `p0` is (0, 0), `p1` is (1, 0), `p2` is (0, 1).
    pub fn texture_coordinates(&self, point: DVec3) -> (f64, f64) {
        let [p0, p1, p2] = self.corners;
        let (e1, e2, d) = (p1 - p0, p2 - p0, point - p0);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det)
    }

    /// The directions in which the texture coordinates `u` and `v` grow: `p1 - p0` and `p2 - p0`.
    pub fn texture_tangents(&self) -> (DVec3, DVec3) {
        let [p0, p1, p2] = self.corners;
        (p1 - p0, p2 - p0)
    }

    /// The bounding box.
    pub fn bounds(&self) -> Bounds {
        self.corners.iter().fold(Bounds::EMPTY, |b, p| b.include(*p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};

    fn tri() -> Triangle {
        Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y).expect("valid")
    }

    #[test]
    fn hits_inside_from_both_sides_and_misses_outside() {
        let t = tri();
        let down = Ray::new(DVec3::new(0.25, 0.25, 2.0), -DVec3::Z);
        let hit = t.intersect(&down, 0.0, f64::INFINITY).expect("hit");
        assert!((hit.t - 2.0).abs() < 1e-12);
        let ShapePart::Triangle { b1, b2, .. } = hit.part else { panic!("part {:?}", hit.part) };
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.25).abs() < 1e-6);
        let up = Ray::new(DVec3::new(0.25, 0.25, -2.0), DVec3::Z);
        assert!(t.intersect(&up, 0.0, f64::INFINITY).is_some(), "the back face is hit too");
        let outside = Ray::new(DVec3::new(0.6, 0.6, 2.0), -DVec3::Z);
        assert!(t.intersect(&outside, 0.0, f64::INFINITY).is_none());
        let parallel = Ray::new(DVec3::new(-1.0, 0.2, 0.0), DVec3::X);
        assert!(t.intersect(&parallel, 0.0, f64::INFINITY).is_none());
        assert!(t.intersect(&down, 0.0, 1.5).is_none(), "beyond t_max");
    }

    #[test]
    fn normal_and_texture_coordinates_follow_the_corners() {
        let t = tri();
        assert_eq!(t.normal, DVec3::Z);
        let (u, v) = t.texture_coordinates(DVec3::new(0.25, 0.5, 0.0));
        assert!((u - 0.25).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        let p = t.point_at(0.25, 0.5);
        assert!((p - DVec3::new(0.25, 0.5, 0.0)).length() < 1e-15);
    }

    #[test]
    fn collinear_corners_are_an_error() {
        assert!(Triangle::new(DVec3::ZERO, DVec3::X, DVec3::X * 2.0).is_err());
        assert!(Triangle::new(DVec3::ZERO, DVec3::ZERO, DVec3::Y).is_err());
    }

    /// Rays through a shared edge or the shared vertex of a fan of triangles always hit one of
    /// them: none slips through.
    #[test]
    fn rays_through_shared_edges_and_vertices_never_slip_through() {
        // A fan of 8 triangles around the centre of a regular octagon, in a slanted plane.
        let centre = DVec3::new(0.1, -0.2, 0.3);
        let n = 8;
        let (e1, e2) = (DVec3::new(1.0, 0.0, 0.3), DVec3::new(0.2, 1.0, -0.4));
        let corner = |i: usize| {
            let a = std::f64::consts::TAU * (i % n) as f64 / n as f64;
            centre + e1 * a.cos() + e2 * a.sin()
        };
        let fan: Vec<Triangle> =
            (0..n).map(|i| Triangle::new(centre, corner(i), corner(i + 1)).expect("valid")).collect();
        let mut rng = TestRng::new(9);
        for _ in 0..2000 {
            // A point on a shared edge (or the shared centre).
            let i = (rng.uniform() * n as f64) as usize;
            let s = if rng.uniform() < 0.1 { 0.0 } else { rng.uniform() };
            let target = centre + (corner(i) - centre) * s;
            let origin = target + rng.unit_vector() * 3.0;
            let ray = Ray::new(origin, target - origin);
            let hits = fan.iter().filter(|t| t.intersect(&ray, 0.0, f64::INFINITY).is_some()).count();
            assert!(hits >= 1, "ray {ray:?} slipped through the fan");
        }
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(4);
        for scale in SCALES {
            let o = DVec3::new(scale, -2.0 * scale, scale);
            let shape = Shape::Triangle(Box::new(
                Triangle::new(
                    o - DVec3::X * scale,
                    o + DVec3::Y * scale * 2.0,
                    o + DVec3::new(1.0, -1.0, 0.5) * scale,
                )
                .expect("valid"),
            ));
            check_reintersection(&shape, o, scale, &mut rng);
        }
    }
}
