//! Infinite planes (`primitive plane`).

use glam::DVec3;

use super::{Ray, ShapeHit, ShapePart};
use crate::base::error::{GeometryError, unit_direction, usable_length_squared};

/// The plane `{P : P . normal = offset}` with optional world-anchored texture axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal (`N=`, normalised on construction); the side it points to is the front.
    pub normal: DVec3,
    /// Signed distance of the plane from the origin along `normal` (`R=`).
    pub offset: f64,
    /// `Dx / |Dx|^2` and `Dy / |Dy|^2` (`Dx=`, `Dy=`): `u = P . tex_u`, so one texture tile spans
    /// `|Dx|` world units. `None` when the file gives no axes (the plane must then be untextured).
    /// Kept apart, only needed to shade: it would make every shape of a scene 48 bytes larger.
    pub texture_axes: Option<Box<(DVec3, DVec3)>>,
}

impl Plane {
    /// A plane with normal `normal` (any length but zero) at signed distance `offset`.
    pub fn new(normal: DVec3, offset: f64) -> Result<Plane, GeometryError> {
        let normal = unit_direction(normal, "N")?;
        Ok(Plane { normal, offset, texture_axes: None })
    }

    /// Sets the texture axes `Dx=`, `Dy=`: their lengths are the world size of one tile.
    pub fn with_texture_axes(mut self, dx: DVec3, dy: DVec3) -> Result<Plane, GeometryError> {
        let inv = |v: DVec3, name| {
            let inverse = v / usable_length_squared(v, name)?;
            if inverse.is_finite() { Ok(inverse) } else { Err(GeometryError::TooSmall(name)) }
        };
        self.texture_axes = Some(Box::new((inv(dx, "Dx")?, inv(dy, "Dy")?)));
        Ok(self)
    }

    /// The hit with `t_min < t < t_max`; rays parallel to the plane miss.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        let denom = self.normal.dot(ray.dir);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.offset - self.normal.dot(ray.origin)) / denom;
        (t > t_min && t < t_max).then_some(ShapeHit { t, part: ShapePart::Main })
    }

    /// Bytes the texture axes take apart from the plane (0 without them).
    pub fn axes_memory(&self) -> usize {
        self.texture_axes.as_ref().map_or(0, |_| std::mem::size_of::<(DVec3, DVec3)>())
    }

    /// Texture coordinates (spec 5.6): `u = P . Dx / |Dx|^2`, `v = P . Dy / |Dy|^2`, anchored in
    /// the world so the texture tiles. (0, 0) without texture axes.
    pub fn texture_coordinates(&self, point: DVec3) -> (f64, f64) {
        match self.texture_axes.as_deref() {
            Some(&(u, v)) => (point.dot(u), point.dot(v)),
            None => (0.0, 0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};

    fn floor() -> Plane {
        Plane::new(DVec3::new(0.0, 0.0, 2.0), -2.0).expect("valid")
    }

    #[test]
    fn normal_is_normalised_and_offset_is_along_it() {
        let p = floor();
        assert_eq!(p.normal, DVec3::Z);
        let ray = Ray::new(DVec3::new(0.3, 0.1, 1.0), -DVec3::Z);
        let hit = p.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        assert!((hit.t - 3.0).abs() < 1e-12);
        assert!((ray.at(hit.t).z + 2.0).abs() < 1e-12);
    }

    #[test]
    fn hit_from_behind_and_misses() {
        let p = floor();
        let below = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
        assert!((p.intersect(&below, 0.0, f64::INFINITY).expect("hit").t - 3.0).abs() < 1e-12);
        let parallel = Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::X);
        assert!(p.intersect(&parallel, 0.0, f64::INFINITY).is_none());
        let away = Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::Z);
        assert!(p.intersect(&away, 0.0, f64::INFINITY).is_none());
        // Grazing but not parallel: hits far away.
        let grazing = Ray::new(DVec3::new(0.0, 0.0, -1.0), DVec3::new(1.0, 0.0, -1e-6));
        let hit = p.intersect(&grazing, 0.0, f64::INFINITY).expect("grazing hit");
        assert!((grazing.at(hit.t).z + 2.0).abs() < 1e-6);
    }

    #[test]
    fn texture_coordinates_tile_with_axis_length() {
        let p = floor()
            .with_texture_axes(DVec3::new(8.0, 0.0, 0.0), DVec3::new(0.0, 8.0, 0.0))
            .expect("valid axes");
        let (u, v) = p.texture_coordinates(DVec3::new(4.0, -2.0, -2.0));
        assert!((u - 0.5).abs() < 1e-12 && (v + 0.25).abs() < 1e-12);
        assert!(floor().with_texture_axes(DVec3::ZERO, DVec3::Y).is_err());
    }

    #[test]
    fn zero_normal_is_an_error() {
        assert_eq!(Plane::new(DVec3::ZERO, 1.0), Err(GeometryError::ZeroVector("N")));
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(2);
        for scale in SCALES {
            let n = DVec3::new(0.3, -0.5, 0.8);
            let shape = Shape::Plane(Plane::new(n, scale).expect("valid"));
            check_reintersection(&shape, n.normalize() * scale, scale, &mut rng);
        }
    }
}
