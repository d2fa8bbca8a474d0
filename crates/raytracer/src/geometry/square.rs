//! Parallelograms (`primitive square`, and the visible shape of `light square`).

use glam::DVec3;

use super::{Bounds, Ray, ShapeHit, ShapePart};
use crate::base::error::{GeometryError, usable_length_squared};

/// The parallelogram `centre + a * dx + b * dy` for `a, b` in `[-1, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Square {
    /// Centre (`O=`).
    pub centre: DVec3,
    /// First half axis (`Dx=`).
    pub dx: DVec3,
    /// Second half axis (`Dy=`).
    pub dy: DVec3,
    /// Unit normal `unit(dx x dy)`; the side it points to is the front.
    pub normal: DVec3,
    /// Dual axes: for a point `p` in the plane, `a = (p - centre) . dual_x`, `b = ... . dual_y`.
    dual_x: DVec3,
    dual_y: DVec3,
    /// For a square whose normal and dual axes each lie along a coordinate axis (every wall of a
    /// box): which one each lies along, so that [`Square::intersect`] multiplies one component
    /// instead of three (see [`Aligned`]).
    aligned: Option<Aligned>,
}

/// The coordinate axes of an axis-aligned square's normal (`k`) and dual axes (`i`, `j`): their
/// other components are exactly zero.
///
/// The test of such a square gives the generic test's results bit for bit: a dot product with
/// a vector of one non-zero component `v` is `(±0 + ±0) + x v`, which is `x v` exactly whenever
/// that is not zero (and when it is, both tests see a zero: a ray parallel to the plane, a
/// distance of 0, or a coordinate of 0, with the same verdict); rays with a non-finite component
/// miss in both.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Aligned {
    /// The normal along `K`, `dual_x` along `I`, `dual_y` along `J`, as const parameters of
    /// [`Square::intersect_aligned`].
    Xyz,
    Xzy,
    Yxz,
    Yzx,
    Zxy,
    Zyx,
}

impl Aligned {
    /// The axis-aligned form of a normal and dual axes, if they have one.
    fn of(normal: DVec3, dual_x: DVec3, dual_y: DVec3) -> Option<Aligned> {
        let axis = |v: DVec3| {
            let nonzero: Vec<usize> = (0..3).filter(|&a| v[a] != 0.0).collect();
            (nonzero.len() == 1 && v[nonzero[0]].is_finite()).then(|| nonzero[0])
        };
        match (axis(normal)?, axis(dual_x)?, axis(dual_y)?) {
            (0, 1, 2) => Some(Aligned::Xyz),
            (0, 2, 1) => Some(Aligned::Xzy),
            (1, 0, 2) => Some(Aligned::Yxz),
            (1, 2, 0) => Some(Aligned::Yzx),
            (2, 0, 1) => Some(Aligned::Zxy),
            (2, 1, 0) => Some(Aligned::Zyx),
            _ => None,
        }
    }
}

impl Square {
    /// The parallelogram with centre `centre` and half axes `dx`, `dy` (not parallel, not zero).
    pub fn new(centre: DVec3, dx: DVec3, dy: DVec3) -> Result<Square, GeometryError> {
        usable_length_squared(dx, "Dx")?;
        usable_length_squared(dy, "Dy")?;
        let cross = dx.cross(dy);
        let area = cross.length();
        if !area.is_finite() {
            return Err(GeometryError::TooLarge("Dx"));
        }
        if area == 0.0 && dx.normalize().cross(dy.normalize()).length() > 1e-12 {
            return Err(GeometryError::TooSmall("Dx"));
        }
        if area <= 1e-12 * dx.length() * dy.length() {
            return Err(GeometryError::ParallelAxes("Dx", "Dy"));
        }
        let normal = cross / area;
        let (dual_x, dual_y) = (dy.cross(normal) / area, normal.cross(dx) / area);
        Ok(Square { centre, dx, dy, normal, dual_x, dual_y, aligned: Aligned::of(normal, dual_x, dual_y) })
    }

    /// The coordinates `(a, b)` of a point of the square's plane: `p = centre + a dx + b dy`.
    #[inline]
    pub fn plane_coordinates(&self, point: DVec3) -> (f64, f64) {
        let p = point - self.centre;
        (p.dot(self.dual_x), p.dot(self.dual_y))
    }

    /// The hit with `t_min < t < t_max`. Solves for `(a, b)` directly (exact and cheaper than the
    /// seed report's angle sum); the border counts as inside.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        match self.aligned {
            None => self.intersect_any(ray, t_min, t_max),
            Some(Aligned::Xyz) => self.intersect_aligned::<0, 1, 2>(ray, t_min, t_max),
            Some(Aligned::Xzy) => self.intersect_aligned::<0, 2, 1>(ray, t_min, t_max),
            Some(Aligned::Yxz) => self.intersect_aligned::<1, 0, 2>(ray, t_min, t_max),
            Some(Aligned::Yzx) => self.intersect_aligned::<1, 2, 0>(ray, t_min, t_max),
            Some(Aligned::Zxy) => self.intersect_aligned::<2, 0, 1>(ray, t_min, t_max),
            Some(Aligned::Zyx) => self.intersect_aligned::<2, 1, 0>(ray, t_min, t_max),
        }
    }

    /// [`Square::intersect`] of an axis-aligned square: the normal along axis `K`, the dual
    /// axes along `I` and `J` (see [`Aligned`]).
    #[inline(always)]
    fn intersect_aligned<const K: usize, const I: usize, const J: usize>(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<ShapeHit> {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let (c, n) = (self.centre.to_array(), self.normal.to_array());
        let denom = n[K] * d[K];
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = ((c[K] - o[K]) * n[K]) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let a = ((o[I] + d[I] * t) - c[I]) * self.dual_x.to_array()[I];
        let b = ((o[J] + d[J] * t) - c[J]) * self.dual_y.to_array()[J];
        (a.abs() <= 1.0 && b.abs() <= 1.0).then_some(ShapeHit { t, part: ShapePart::Main })
    }

    /// [`Square::intersect`] of any square.
    #[inline(always)]
    fn intersect_any(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        let denom = self.normal.dot(ray.dir);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.centre - ray.origin).dot(self.normal) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let (a, b) = self.plane_coordinates(ray.at(t));
        (a.abs() <= 1.0 && b.abs() <= 1.0).then_some(ShapeHit { t, part: ShapePart::Main })
    }

    /// Texture coordinates (spec 5.6): one copy of the texture over the square, `u` along `dx`
    /// and `v` along `dy`, from 0 at `-d` to 1 at `+d`. (For rectangular squares this is the
    /// spec's `(C-O).Dx/|Dx|^2/2 + 0.5`; for slanted ones it still maps corners to corners.)
    pub fn texture_coordinates(&self, point: DVec3) -> (f64, f64) {
        let (a, b) = self.plane_coordinates(point);
        (a * 0.5 + 0.5, b * 0.5 + 0.5)
    }

    /// A point of the square for `a, b` in `[-1, 1]`.
    #[inline]
    pub fn point_at(&self, a: f64, b: f64) -> DVec3 {
        self.centre + self.dx * a + self.dy * b
    }

    /// The bounding box.
    pub fn bounds(&self) -> Bounds {
        [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .into_iter()
            .fold(Bounds::EMPTY, |b, (x, y)| b.include(self.point_at(x, y)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};

    /// The seed report's square: centre (1,7,-1), axes x and z.
    fn report_square() -> Square {
        Square::new(DVec3::new(1.0, 7.0, -1.0), DVec3::X, DVec3::Z).expect("valid")
    }

    #[test]
    fn axis_aligned_squares_are_hit_exactly_as_by_the_generic_test() {
        // Every orientation of an axis-aligned square (both orders of its axes, both signs),
        // at several scales, against rays from all around, rays along its edges and its plane,
        // and rays starting on it: the same hits, bit for bit.
        let mut rng = TestRng::new(11);
        let axes = [DVec3::X, DVec3::Y, DVec3::Z, -DVec3::X, -DVec3::Y, -DVec3::Z];
        let mut aligned = 0;
        let mut hits = 0;
        for &scale in &SCALES {
            for &u in &axes {
                for &v in &axes {
                    if u.cross(v) == DVec3::ZERO {
                        continue;
                    }
                    let centre = DVec3::new(0.3, -0.2, 0.7) * scale;
                    let square = Square::new(centre, u * scale * 0.8, v * scale * 1.3).expect("valid");
                    assert!(square.aligned.is_some(), "{u} {v}");
                    aligned += 1;
                    let mut rays: Vec<Ray> = (0..400)
                        .map(|_| {
                            let origin = centre + rng.unit_vector() * (3.0 * scale * rng.uniform());
                            let target = centre
                                + (u * 0.8 * (2.0 * rng.uniform() - 1.0)
                                    + v * 1.3 * (2.0 * rng.uniform() - 1.0))
                                    * scale
                                    * 1.2;
                            Ray::new(origin, target - origin)
                        })
                        .collect();
                    // Along an edge, in the plane, from a corner, from the centre.
                    rays.push(Ray::new(centre + u * scale * 0.8 - v * scale * 3.0, v));
                    rays.push(Ray::new(centre - u * scale * 3.0, u));
                    rays.push(Ray::new(centre + (u * 0.8 + v * 1.3) * scale, u.cross(v) + u * 0.1));
                    rays.push(Ray::new(centre, u.cross(v)));
                    for ray in rays {
                        for t_max in [f64::INFINITY, scale] {
                            let got = square.intersect(&ray, 0.0, t_max);
                            assert_eq!(got, square.intersect_any(&ray, 0.0, t_max), "{ray:?}");
                            hits += got.is_some() as u32;
                        }
                    }
                }
            }
        }
        assert_eq!(aligned, 24 * SCALES.len());
        assert!(hits > 10_000, "{hits} hits");
        let slanted = Square::new(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), DVec3::Z).expect("valid");
        assert!(slanted.aligned.is_none());
    }

    #[test]
    fn normal_is_dx_cross_dy() {
        assert_eq!(report_square().normal, -DVec3::Y);
    }

    #[test]
    fn hits_inside_and_misses_outside() {
        let s = report_square();
        let ray = Ray::new(DVec3::new(1.5, 0.0, -0.5), DVec3::Y);
        let hit = s.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        assert!((hit.t - 7.0).abs() < 1e-12);
        let outside = Ray::new(DVec3::new(2.01, 0.0, -0.5), DVec3::Y);
        assert!(s.intersect(&outside, 0.0, f64::INFINITY).is_none());
        let parallel = Ray::new(DVec3::new(1.0, 7.0, -3.0), DVec3::Z);
        assert!(s.intersect(&parallel, 0.0, f64::INFINITY).is_none());
        let from_behind = Ray::new(DVec3::new(1.0, 9.0, -1.0), -DVec3::Y);
        assert!(s.intersect(&from_behind, 0.0, f64::INFINITY).is_some());
    }

    #[test]
    fn slanted_parallelogram_uses_exact_coordinates() {
        let s = Square::new(DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0)).expect("valid");
        // The corner +dx +dy is (2, 1, 0); a point just inside it hits, one just past misses.
        let ray = |x, y| Ray::new(DVec3::new(x, y, 1.0), -DVec3::Z);
        assert!(s.intersect(&ray(1.99, 0.995), 0.0, f64::INFINITY).is_some());
        assert!(s.intersect(&ray(1.0, 1.01), 0.0, f64::INFINITY).is_none());
        let (u, v) = s.texture_coordinates(DVec3::new(2.0, 1.0, 0.0));
        assert!((u - 1.0).abs() < 1e-12 && (v - 1.0).abs() < 1e-12);
    }

    #[test]
    fn texture_coordinates_span_the_square_once() {
        let s = report_square();
        let (u, v) = s.texture_coordinates(DVec3::new(0.0, 7.0, -2.0));
        assert!(u.abs() < 1e-12 && v.abs() < 1e-12);
        let (u, v) = s.texture_coordinates(DVec3::new(1.5, 7.0, -1.0));
        assert!((u - 0.75).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
    }

    #[test]
    fn degenerate_axes_are_errors() {
        assert!(Square::new(DVec3::ZERO, DVec3::ZERO, DVec3::Y).is_err());
        assert!(Square::new(DVec3::ZERO, DVec3::X, DVec3::X * 3.0).is_err());
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(3);
        for scale in SCALES {
            let c = DVec3::new(scale, 2.0 * scale, -scale);
            let dx = DVec3::new(1.0, 0.2, 0.0) * scale;
            let dy = DVec3::new(0.0, 0.3, 1.0) * scale;
            let shape = Shape::Square(Box::new(Square::new(c, dx, dy).expect("valid")));
            check_reintersection(&shape, c, scale, &mut rng);
        }
    }
}
