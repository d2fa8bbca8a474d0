//! Axis-aligned bounding boxes.

use glam::DVec3;

use super::ray::Ray;

/// An axis-aligned box `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Bounds {
    /// The empty box (the identity of [`Bounds::union`]).
    pub const EMPTY: Bounds =
        Bounds { min: DVec3::splat(f64::INFINITY), max: DVec3::splat(f64::NEG_INFINITY) };

    /// The smallest box holding both boxes.
    pub fn union(self, other: Bounds) -> Bounds {
        Bounds { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// The smallest box holding this box and a point.
    pub fn include(self, p: DVec3) -> Bounds {
        Bounds { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The centre of the box.
    pub fn centroid(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area (the SAH cost only needs relative areas).
    pub fn half_area(&self) -> f64 {
        let d = (self.max - self.min).max(DVec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Whether the ray's segment `t_min < t < t_max` passes through the box. `inv_dir` is the
    /// component-wise inverse of the ray direction (infinite components are fine).
    #[inline]
    pub fn hit(&self, ray: &Ray, inv_dir: DVec3, t_min: f64, t_max: f64) -> bool {
        let t0 = (self.min - ray.origin) * inv_dir;
        let t1 = (self.max - ray.origin) * inv_dir;
        // NaN (0 * inf on a slab boundary) compares false in min/max and is dropped.
        let near = t0.min(t1).max_element().max(t_min);
        let far = t0.max(t1).min_element().min(t_max);
        near <= far
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_through_box_hits_and_beside_it_misses() {
        let b = Bounds { min: DVec3::splat(-1.0), max: DVec3::splat(1.0) };
        let ray = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        assert!(b.hit(&ray, ray.dir.recip(), 0.0, f64::INFINITY));
        assert!(!b.hit(&ray, ray.dir.recip(), 0.0, 3.0), "segment ends before the box");
        let beside = Ray::new(DVec3::new(-5.0, 2.0, 0.0), DVec3::X);
        assert!(!b.hit(&beside, beside.dir.recip(), 0.0, f64::INFINITY));
    }

    #[test]
    fn union_and_area() {
        let a = Bounds::EMPTY.include(DVec3::ZERO).include(DVec3::ONE);
        assert_eq!(a.half_area(), 3.0);
        assert_eq!(a.union(Bounds::EMPTY), a);
        assert_eq!(a.centroid(), DVec3::splat(0.5));
    }
}
