//! Closed cylinders (`primitive cylinder`): the curved side and both cap discs.

use std::f64::consts::TAU;

use glam::DVec3;

use super::{Bounds, Ray, ShapeHit, ShapePart, course_perpendicular, solve_quadratic};
use crate::base::error::GeometryError;

/// A closed cylinder from the bottom cap centre `base` (`O1=`) to the top cap centre `top`
/// (`O2=`) with radius `radius` (`R=`).
#[derive(Clone, Debug, PartialEq)]
pub struct Cylinder {
    /// Bottom cap centre (`O1=`).
    pub base: DVec3,
    /// Top cap centre (`O2=`).
    pub top: DVec3,
    /// Radius (`R=`), positive.
    pub radius: f64,
    /// Unit axis from `base` to `top`.
    pub axis: DVec3,
    /// `|top - base|`.
    pub height: f64,
    /// Unit vector perpendicular to the axis where the side texture's `v = 0` seam lies (the
    /// course's `GetAnVerticalVector`: `unit(axis x z)`, or `x` when the axis is vertical).
    seam: DVec3,
    /// `axis x seam`: completes the right-handed frame `(seam, seam2, axis)`.
    seam2: DVec3,
    /// Centre of the smallest sphere around the cylinder (for a quick rejection).
    bound_centre: DVec3,
    /// Squared radius of that sphere.
    bound_radius_sq: f64,
}

impl Cylinder {
    /// The cylinder from `base` to `top` with radius `radius`.
    pub fn new(base: DVec3, top: DVec3, radius: f64) -> Result<Cylinder, GeometryError> {
        if !radius.is_finite() || radius <= 0.0 {
            return Err(GeometryError::NonPositiveRadius(radius));
        }
        let along = top - base;
        let height = along.length();
        if along == DVec3::ZERO {
            return Err(GeometryError::ZeroAxis);
        }
        if !height.is_finite() {
            return Err(GeometryError::AxisTooLong);
        }
        if height == 0.0 {
            return Err(GeometryError::AxisTooShort);
        }
        let axis = along / height;
        let seam = course_perpendicular(axis);
        Ok(Cylinder {
            base,
            top,
            radius,
            axis,
            height,
            seam,
            seam2: axis.cross(seam),
            bound_centre: (base + top) * 0.5,
            bound_radius_sq: (height * 0.5).powi(2) + radius * radius,
        })
    }

    /// The nearest hit with `t_min < t < t_max` on the side (height strictly between the caps)
    /// or on a cap disc (distance to the cap centre at most the radius). A ray inside the
    /// cylinder hits it from the back.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        // Most rays pass far away: reject them against the bounding sphere first (a ray that
        // starts inside it is always tested in full).
        let oc = ray.origin - self.bound_centre;
        let along = oc.dot(ray.dir);
        let c = oc.length_squared() - self.bound_radius_sq;
        if c > 0.0 && (along > 0.0 || (oc - along * ray.dir).length_squared() > self.bound_radius_sq) {
            return None;
        }
        let ob = ray.origin - self.base;
        let mut best: Option<ShapeHit> = None;
        let mut limit = t_max;
        // Side: |t a + b| = R with a = V x u, b = (O - O1) x u (seed report).
        let a = ray.dir.cross(self.axis);
        let b = ob.cross(self.axis);
        let r2 = self.radius * self.radius;
        if let Some((t0, t1)) = solve_quadratic(a.dot(a), a.dot(b), b.dot(b) - r2) {
            for t in [t0, t1] {
                if t > t_min && t < limit {
                    let h = (ob + ray.dir * t).dot(self.axis);
                    if h > 0.0 && h < self.height {
                        best = Some(ShapeHit { t, part: ShapePart::Main });
                        limit = t;
                        break;
                    }
                }
            }
        }
        // Caps: discs in the planes h = 0 and h = height.
        let denom = ray.dir.dot(self.axis);
        if denom.abs() > 1e-12 {
            let h0 = ob.dot(self.axis);
            for (cap_h, part) in [(0.0, ShapePart::BottomCap), (self.height, ShapePart::TopCap)] {
                let t = (cap_h - h0) / denom;
                if t > t_min && t < limit {
                    let p = ob + ray.dir * t - self.axis * cap_h;
                    if p.length_squared() <= r2 {
                        best = Some(ShapeHit { t, part });
                        limit = t;
                    }
                }
            }
        }
        best
    }

    /// Unit outward normal at a point of `part`.
    #[inline]
    pub fn outward_normal(&self, point: DVec3, part: ShapePart) -> DVec3 {
        match part {
            ShapePart::BottomCap => -self.axis,
            ShapePart::TopCap => self.axis,
            _ => {
                let p = point - self.base;
                (p - self.axis * p.dot(self.axis)).normalize()
            }
        }
    }

    /// Texture coordinates (spec 5.6). Side: `u = h / height`, `v` = the angle from the seam
    /// vector to the point's radial direction, turning towards `axis x seam`, over 2 pi (the seed
    /// report's `acos` with the sign of `((C-O1) x axis) . seam`, computed with `atan2`). Caps: the
    /// disc mapped onto the unit square, `u` along the seam vector and `v` along `axis x seam`.
    pub fn texture_coordinates(&self, point: DVec3, part: ShapePart) -> (f64, f64) {
        let p = point - self.base;
        match part {
            ShapePart::Main | ShapePart::Triangle { .. } | ShapePart::Profile { .. } => {
                let h = p.dot(self.axis);
                let angle = p.dot(self.seam2).atan2(p.dot(self.seam)).rem_euclid(TAU);
                (h / self.height, angle / TAU)
            }
            ShapePart::BottomCap | ShapePart::TopCap => {
                let q = if part == ShapePart::TopCap { point - self.top } else { p };
                let scale = 0.5 / self.radius;
                (q.dot(self.seam) * scale + 0.5, q.dot(self.seam2) * scale + 0.5)
            }
        }
    }

    /// The bounding box (exact for the two cap discs).
    pub fn bounds(&self) -> Bounds {
        let extent = (DVec3::ONE - self.axis * self.axis).max(DVec3::ZERO).sqrt() * self.radius;
        Bounds { min: self.base.min(self.top) - extent, max: self.base.max(self.top) + extent }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};

    /// The seed report's textured cylinder: vertical, from z = -2 to -0.8, radius 0.2.
    fn report_cylinder() -> Cylinder {
        Cylinder::new(DVec3::new(2.0, 5.0, -2.0), DVec3::new(2.0, 5.0, -0.8), 0.2).expect("valid")
    }

    fn hit(c: &Cylinder, origin: DVec3, dir: DVec3) -> Option<ShapeHit> {
        c.intersect(&Ray::new(origin, dir), 0.0, f64::INFINITY)
    }

    #[test]
    fn side_hit_from_outside() {
        let c = report_cylinder();
        let h = hit(&c, DVec3::new(2.0, 0.0, -1.0), DVec3::Y).expect("hit");
        assert_eq!(h.part, ShapePart::Main);
        assert!((h.t - 4.8).abs() < 1e-12);
        let p = DVec3::new(2.0, 4.8, -1.0);
        assert!((c.outward_normal(p, h.part) + DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn caps_are_hit_from_above_and_below() {
        let c = report_cylinder();
        let top = hit(&c, DVec3::new(2.05, 5.0, 3.0), -DVec3::Z).expect("top");
        assert_eq!(top.part, ShapePart::TopCap);
        assert!((top.t - 3.8).abs() < 1e-12);
        let bottom = hit(&c, DVec3::new(2.05, 5.0, -4.0), DVec3::Z).expect("bottom");
        assert_eq!(bottom.part, ShapePart::BottomCap);
        assert!((bottom.t - 2.0).abs() < 1e-12);
        assert_eq!(c.outward_normal(DVec3::ZERO, ShapePart::BottomCap), -DVec3::Z);
    }

    #[test]
    fn slanted_ray_through_side_then_cap_takes_the_nearest() {
        let c = report_cylinder();
        // Enters through the top cap, would reach the side's plane later.
        let h = hit(&c, DVec3::new(2.0, 5.0, 0.0), DVec3::new(0.0, 0.1, -1.0)).expect("hit");
        assert_eq!(h.part, ShapePart::TopCap);
    }

    #[test]
    fn rays_from_inside_hit_the_back() {
        let c = report_cylinder();
        let centre = DVec3::new(2.0, 5.0, -1.4);
        let side = hit(&c, centre, DVec3::X).expect("side");
        assert_eq!(side.part, ShapePart::Main);
        assert!((side.t - 0.2).abs() < 1e-12);
        let cap = hit(&c, centre, DVec3::Z).expect("cap");
        assert_eq!(cap.part, ShapePart::TopCap);
        assert!((cap.t - 0.6).abs() < 1e-12);
    }

    #[test]
    fn misses_beside_above_and_along_the_axis_outside() {
        let c = report_cylinder();
        assert!(hit(&c, DVec3::new(2.3, 0.0, -1.0), DVec3::Y).is_none());
        assert!(hit(&c, DVec3::new(2.0, 0.0, -0.5), DVec3::Y).is_none(), "passes above");
        assert!(hit(&c, DVec3::new(2.3, 5.0, 3.0), -DVec3::Z).is_none(), "parallel outside");
        // Tangent to the side.
        assert!(hit(&c, DVec3::new(2.2, 0.0, -1.0), DVec3::Y).is_none());
    }

    #[test]
    fn side_texture_coordinates_follow_the_seed_report() {
        let c = report_cylinder();
        // Vertical axis: seam = (1,0,0) (axis x z = 0), seam2 = z x x = y.
        let (u, v) = c.texture_coordinates(DVec3::new(2.2, 5.0, -2.0 + 0.3), ShapePart::Main);
        assert!((u - 0.25).abs() < 1e-12 && v.abs() < 1e-12, "({u}, {v})");
        let (_, v) = c.texture_coordinates(DVec3::new(2.0, 5.2, -1.0), ShapePart::Main);
        assert!((v - 0.25).abs() < 1e-12, "v = {v}");
        let (_, v) = c.texture_coordinates(DVec3::new(2.0, 4.8, -1.0), ShapePart::Main);
        assert!((v - 0.75).abs() < 1e-12, "v = {v}");
        // The seed report's sign rule: ((C-O1) x axis) . seam < 0 means the angle is negated.
        let p = DVec3::new(2.0, 4.8, -1.0) - c.base;
        assert!(p.cross(c.axis).dot(c.seam) < 0.0);
        let (u, v) = c.texture_coordinates(DVec3::new(2.2, 5.0, -0.8), ShapePart::TopCap);
        assert!((u - 1.0).abs() < 1e-12 && (v - 0.5).abs() < 1e-12, "({u}, {v})");
    }

    #[test]
    fn horizontal_axis_uses_axis_cross_z_as_seam() {
        let c = Cylinder::new(DVec3::ZERO, DVec3::new(0.0, 2.0, 0.0), 1.0).expect("valid");
        // axis = y, seam = y x z = x.
        let (_, v) = c.texture_coordinates(DVec3::new(1.0, 1.0, 0.0), ShapePart::Main);
        assert!(v.abs() < 1e-12);
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert_eq!(Cylinder::new(DVec3::ZERO, DVec3::ZERO, 1.0), Err(GeometryError::ZeroAxis));
        assert!(Cylinder::new(DVec3::ZERO, DVec3::Z, 0.0).is_err());
    }

    #[test]
    fn bounds_contain_the_caps() {
        let c = Cylinder::new(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), 0.5).expect("valid");
        let b = c.bounds();
        let e = 0.5 * (0.5f64).sqrt();
        assert!((b.min - DVec3::new(-e, -e, -0.5)).length() < 1e-12);
        assert!((b.max - DVec3::new(1.0 + e, 1.0 + e, 0.5)).length() < 1e-12);
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(4);
        for scale in SCALES {
            let base = DVec3::new(scale, -scale, 0.5 * scale);
            for dir in [DVec3::Z, DVec3::new(1.0, 2.0, 0.5).normalize()] {
                let c = Cylinder::new(base, base + dir * 2.0 * scale, 0.6 * scale).expect("valid");
                check_reintersection(&Shape::Cylinder(Box::new(c)), base + dir * scale, scale, &mut rng);
            }
        }
    }
}
