//! Spheres (`primitive sphere`, and the visible shape of `light sphere`).

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::{Bounds, Ray, ShapeHit, ShapePart, order};
use crate::base::error::{GeometryError, unit_direction};

/// A sphere with a texture frame.
///
/// 40 bytes: the texture frame is kept apart, and only when it is not the default one (pole +z,
/// seam +y), as few spheres have another; a scene of a million spheres would otherwise carry 48
/// bytes a sphere for it.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    /// Centre (`O=`).
    pub centre: DVec3,
    /// Radius (`R=`), positive.
    pub radius: f64,
    /// `[pole, seam]` when they are not `[+z, +y]`; see [`Sphere::pole`] and [`Sphere::seam`].
    frame: Option<Box<[DVec3; 2]>>,
}

impl Sphere {
    /// A sphere with the default texture frame (pole +z, seam +y).
    pub fn new(centre: DVec3, radius: f64) -> Result<Sphere, GeometryError> {
        Sphere::with_frame(centre, radius, DVec3::Z, DVec3::Y)
    }

    /// A sphere with the texture frame `pole` (`De=`) and `seam` (`Dc=`). Both are normalised and
    /// `seam` is made perpendicular to `pole` (for the usual perpendicular unit inputs this
    /// changes nothing).
    pub fn with_frame(centre: DVec3, radius: f64, pole: DVec3, seam: DVec3) -> Result<Sphere, GeometryError> {
        if !radius.is_finite() || radius <= 0.0 {
            return Err(GeometryError::NonPositiveRadius(radius));
        }
        if (pole, seam) == (DVec3::Z, DVec3::Y) {
            return Ok(Sphere { centre, radius, frame: None });
        }
        let pole = unit_direction(pole, "De")?;
        let seam = unit_direction(seam, "Dc")?;
        let seam =
            (seam - seam.dot(pole) * pole).try_normalize().ok_or(GeometryError::ParallelAxes("Dc", "De"))?;
        let frame = ((pole, seam) != (DVec3::Z, DVec3::Y)).then(|| Box::new([pole, seam]));
        Ok(Sphere { centre, radius, frame })
    }

    /// Unit pole direction of the texture frame (`De=`, default +z): `u = 0` at `-pole`, `u = 1`
    /// at `+pole`.
    #[inline]
    pub fn pole(&self) -> DVec3 {
        self.frame.as_ref().map_or(DVec3::Z, |f| f[0])
    }

    /// Unit direction, perpendicular to the pole, where the texture's `v = 0` seam lies (`Dc=`,
    /// default +y).
    #[inline]
    pub fn seam(&self) -> DVec3 {
        self.frame.as_ref().map_or(DVec3::Y, |f| f[1])
    }

    /// Bytes the texture frame takes apart from the sphere (0 for the default frame).
    pub fn frame_memory(&self) -> usize {
        self.frame.as_ref().map_or(0, |_| std::mem::size_of::<[DVec3; 2]>())
    }

    /// The nearest hit with `t_min < t < t_max`. Tangent rays miss.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        // Roots of t^2 + 2 b t + c = 0 with b = oc.V and c = |oc|^2 - r^2. The discriminant
        // b^2 - c is computed as r^2 - |oc - b V|^2 (the squared distance of the ray from the
        // centre), which keeps its precision for huge spheres and distant rays.
        let oc = ray.origin - self.centre;
        let half_b = oc.dot(ray.dir);
        let c = oc.length_squared() - self.radius * self.radius;
        if c > 0.0 && half_b > 0.0 {
            return None; // starts outside, points away
        }
        let disc = self.radius * self.radius - (oc - half_b * ray.dir).length_squared();
        if disc.is_nan() || disc <= 0.0 {
            return None; // a miss, or a tangent ray
        }
        let q = -(half_b + half_b.signum() * disc.sqrt());
        let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { order(q, c / q) };
        let t = if t0 > t_min { t0 } else { t1 };
        (t > t_min && t < t_max).then_some(ShapeHit { t, part: ShapePart::Main })
    }

    /// Unit outward normal at a point on the sphere.
    #[inline]
    pub fn outward_normal(&self, point: DVec3) -> DVec3 {
        (point - self.centre).normalize()
    }

    /// Texture coordinates (spec 5.6): `u` runs from the `-pole` (0) to the `+pole` (1), `v`
    /// around the pole from the seam (0) to the seam again (1).
    pub fn texture_coordinates(&self, point: DVec3) -> (f64, f64) {
        let (pole, seam) = (self.pole(), self.seam());
        let i = (point - self.centre).normalize();
        let a = (-i.dot(pole)).clamp(-1.0, 1.0).acos();
        let sin_a = a.sin();
        let b = if sin_a > 1e-12 { (i.dot(seam) / sin_a).clamp(-1.0, 1.0).acos() } else { 0.0 };
        let u = a / PI;
        let mut v = b / TAU;
        if i.dot(seam.cross(pole)) < 0.0 {
            v = 1.0 - v;
        }
        (u, v)
    }

    /// The bounding box.
    pub fn bounds(&self) -> Bounds {
        Bounds { min: self.centre - DVec3::splat(self.radius), max: self.centre + DVec3::splat(self.radius) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};

    fn unit_sphere() -> Sphere {
        Sphere::new(DVec3::ZERO, 1.0).expect("valid sphere")
    }

    #[test]
    fn the_default_frame_takes_no_room() {
        assert_eq!(std::mem::size_of::<Sphere>(), 40);
        assert_eq!(std::mem::size_of::<Shape>(), 48, "a sphere or a plane, and the tag");
        // The default frame, written unnormalised, is the default frame.
        let long = Sphere::with_frame(DVec3::ZERO, 1.0, DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 2.0, 0.0));
        assert_eq!(long.expect("valid"), unit_sphere());
        let other = Sphere::with_frame(DVec3::ZERO, 1.0, DVec3::X, DVec3::new(1.0, 0.0, 2.0)).expect("valid");
        assert_eq!((other.pole(), other.seam()), (DVec3::X, DVec3::Z), "the seam made perpendicular");
        assert_ne!(other, unit_sphere());
        assert_eq!((unit_sphere().frame_memory(), other.frame_memory()), (0, 48));
        assert_eq!((unit_sphere().pole(), unit_sphere().seam()), (DVec3::Z, DVec3::Y));
    }

    #[test]
    fn hit_from_outside_reports_near_root() {
        let s = unit_sphere();
        let ray = Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y);
        let hit = s.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        assert!((hit.t - 4.0).abs() < 1e-12);
        assert_eq!(s.outward_normal(ray.at(hit.t)), -DVec3::Y);
    }

    #[test]
    fn hit_from_inside_reports_far_root() {
        let s = unit_sphere();
        let ray = Ray::new(DVec3::new(0.0, 0.5, 0.0), DVec3::Y);
        let hit = s.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        assert!((hit.t - 0.5).abs() < 1e-12);
    }

    #[test]
    fn misses_behind_beside_and_beyond_t_max() {
        let s = unit_sphere();
        let away = Ray::new(DVec3::new(0.0, -5.0, 0.0), -DVec3::Y);
        assert!(s.intersect(&away, 0.0, f64::INFINITY).is_none());
        let beside = Ray::new(DVec3::new(1.5, -5.0, 0.0), DVec3::Y);
        assert!(s.intersect(&beside, 0.0, f64::INFINITY).is_none());
        let short = Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y);
        assert!(s.intersect(&short, 0.0, 3.9).is_none());
    }

    #[test]
    fn tangent_ray_misses_and_nearly_tangent_ray_hits() {
        let s = unit_sphere();
        let tangent = Ray::new(DVec3::new(1.0, -5.0, 0.0), DVec3::Y);
        assert!(s.intersect(&tangent, 0.0, f64::INFINITY).is_none());
        let grazing = Ray::new(DVec3::new(1.0 - 1e-9, -5.0, 0.0), DVec3::Y);
        let hit = s.intersect(&grazing, 0.0, f64::INFINITY).expect("grazing hit");
        assert!((hit.t - 5.0).abs() < 1e-3);
    }

    #[test]
    fn huge_sphere_wall_is_exact_near_its_surface() {
        // A Cornell-box wall: radius 1e5, surface at x = -1.
        let s = Sphere::new(DVec3::new(-1e5 - 1.0, 0.0, 0.0), 1e5).expect("valid");
        let ray = Ray::new(DVec3::new(0.0, 0.3, 0.2), -DVec3::X);
        let hit = s.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        // The wall curves away by 0.13 / 2e5 at distance sqrt(0.13) from its closest point.
        let expected = 1.0 + 0.13 / (1e5 + (1e10f64 - 0.13).sqrt());
        // Within 1e-15 of the sphere's magnitude (a few ulps of 1e5).
        assert!((hit.t - expected).abs() < 1e-10, "t = {}, expected {expected}", hit.t);
    }

    #[test]
    fn texture_coordinates_follow_the_course_frame() {
        let s = unit_sphere();
        // South pole u = 0, north pole u = 1, equator u = 0.5.
        assert!((s.texture_coordinates(-DVec3::Z).0).abs() < 1e-9);
        assert!((s.texture_coordinates(DVec3::Z).0 - 1.0).abs() < 1e-9);
        let (u, v) = s.texture_coordinates(DVec3::Y);
        assert!((u - 0.5).abs() < 1e-12 && v.abs() < 1e-12, "seam at +y: ({u}, {v})");
        // Dc x De = y x z = +x: the +x side takes the first half of v.
        let (_, v) = s.texture_coordinates(DVec3::X);
        assert!((v - 0.25).abs() < 1e-12, "v = {v}");
        let (_, v) = s.texture_coordinates(-DVec3::X);
        assert!((v - 0.75).abs() < 1e-12, "v = {v}");
        let (_, v) = s.texture_coordinates(-DVec3::Y);
        assert!((v - 0.5).abs() < 1e-12, "v = {v}");
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(Sphere::new(DVec3::ZERO, 0.0).is_err());
        assert!(Sphere::new(DVec3::ZERO, -1.0).is_err());
        assert!(Sphere::new(DVec3::ZERO, f64::NAN).is_err());
        assert!(Sphere::with_frame(DVec3::ZERO, 1.0, DVec3::ZERO, DVec3::Y).is_err());
        assert!(Sphere::with_frame(DVec3::ZERO, 1.0, DVec3::Z, DVec3::Z * 2.0).is_err());
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(1);
        for scale in SCALES {
            for centre in [DVec3::ZERO, DVec3::new(scale * 3.0, -scale, 2.0 * scale)] {
                let shape = Shape::Sphere(Sphere::new(centre, scale).expect("valid"));
                check_reintersection(&shape, centre, scale, &mut rng);
            }
        }
    }
}
