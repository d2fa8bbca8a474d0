//! Bezier surfaces of revolution (`primitive bezier`): a Bezier curve in the plane of (height
//! along an axis, distance from it), revolved about the axis. Hit exactly, not through a
//! tessellation.
//!
//! A point of the surface is `base + z(s) axis + r(s) (cos phi e1 + sin phi e2)` for the curve
//! parameter `s` in [0, 1] and the angle `phi`. Along a ray `o + t d`, in the axis's frame, the
//! height `h(t)` is linear and the squared distance from the axis `rho2(t)` quadratic in `t`, so
//! a hit solves `h(t) = z(s)`, `rho2(t) = r(s)^2` for `(s, t)`: Newton's method on those two
//! equations, started from a safe guess. The guesses come from the curve's convex hull: the
//! curve is split (de Casteljau) into pieces, each bounded by the box of its control points in
//! the (height, radius) plane, an annulus slab in space. The ray's stretch inside a piece's
//! annulus (split where its distance from the axis stops falling, so that stretch is monotone)
//! brackets the roots there; Newton starts from its middle, and a piece where it fails to
//! converge inside the bracket is split again, down to pieces of 2^-14 of the curve. Every
//! root of every piece is found (two near-coincident roots at a silhouette may come out as one),
//! and the nearest wins.

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};

use super::{Bounds, Ray, ShapeHit, ShapePart, course_perpendicular};
use crate::base::error::GeometryError;

/// Pieces tested together behind their common hull.
const GROUP: usize = 4;
/// Pieces the curve is split into up front, per degree.
const PIECES_PER_DEGREE: usize = 8;
/// Deepest further split of a piece, while looking for a root.
const MAX_SPLIT_DEPTH: u32 = 10;
/// Newton iterations at most.
const NEWTON_STEPS: u32 = 16;
/// Most control points (`P=` lines).
pub const MAX_CONTROL_POINTS: usize = 32;

/// One piece of the profile curve: its parameter range, its own control points (in the
/// (height, radius) plane) and their bounds.
#[derive(Clone, Debug, PartialEq)]
struct Piece {
    s0: f64,
    s1: f64,
    control: Vec<DVec2>,
    /// `(z_min, z_max, r_min, r_max)` of the convex hull, `r` as a distance (its absolute value).
    hull: [f64; 4],
}

impl Piece {
    fn new(s0: f64, s1: f64, control: Vec<DVec2>) -> Piece {
        let mut hull = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
        for p in &control {
            hull[0] = hull[0].min(p.x);
            hull[1] = hull[1].max(p.x);
            hull[2] = hull[2].min(p.y.abs());
            hull[3] = hull[3].max(p.y.abs());
        }
        if control.iter().any(|p| p.y < 0.0) && control.iter().any(|p| p.y > 0.0) {
            hull[2] = 0.0;
        }
        Piece { s0, s1, control, hull }
    }

    /// The two halves (de Casteljau at the middle).
    fn split(&self) -> (Piece, Piece) {
        let (left, right) = de_casteljau(&self.control, 0.5);
        let mid = 0.5 * (self.s0 + self.s1);
        (Piece::new(self.s0, mid, left), Piece::new(mid, self.s1, right))
    }
}

/// A Bezier surface of revolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Bezier {
    /// Where the axis starts (`O1=`; the point of `center=` at height 0).
    pub base: DVec3,
    /// Unit axis (towards `O2=`; +z for the `center=` form).
    pub axis: DVec3,
    /// The profile's control points `(z, r)`: height along the axis from `base` and distance from
    /// the axis.
    pub profile: Vec<DVec2>,
    /// Unit vector perpendicular to the axis where the texture's `v = 0` seam lies (as for
    /// cylinders).
    seam: DVec3,
    /// `axis x seam`.
    seam2: DVec3,
    /// The curve in the power basis, `sum c_k s^k` (Horner's rule is faster than de Casteljau,
    /// and exact enough on [0, 1] for the degrees allowed).
    power: Vec<DVec2>,
    /// The derivative in the power basis.
    power_derivative: Vec<DVec2>,
    pieces: Vec<Piece>,
    /// Runs of [`GROUP`] consecutive pieces with the union of their hulls, tested before the
    /// pieces in them.
    groups: Vec<(usize, usize, [f64; 4])>,
    /// The hull of the whole profile, as a piece's.
    hull: [f64; 4],
    bounds: Bounds,
    /// The size of the surface and its distance from the origin.
    magnitude: f64,
}

impl Bezier {
    /// The surface of revolution about the axis from `base` along `axis` (any length but zero)
    /// of the Bezier curve with control points `profile` (`(z, r)`: height along the axis from
    /// `base`, distance from the axis), of degree `profile.len() - 1` (1 to 31).
    pub fn new(base: DVec3, axis: DVec3, profile: Vec<DVec2>) -> Result<Bezier, GeometryError> {
        let axis = axis.try_normalize().ok_or(GeometryError::ZeroAxis)?;
        if profile.len() < 2 || profile.len() > MAX_CONTROL_POINTS {
            return Err(GeometryError::ControlPoints(profile.len()));
        }
        if profile.iter().all(|p| p.y == 0.0) || profile.windows(2).all(|w| w[0] == w[1]) {
            return Err(GeometryError::Degenerate(
                "the profile has no extent: every control point is on the axis or they all coincide",
            ));
        }
        let power = power_basis(&profile);
        let power_derivative: Vec<DVec2> =
            power.iter().enumerate().skip(1).map(|(k, c)| *c * k as f64).collect();
        let n = profile.len() - 1;
        let count = PIECES_PER_DEGREE * n;
        let mut pieces = Vec::with_capacity(count);
        let mut rest = profile.clone();
        let mut s0 = 0.0;
        for i in 0..count {
            let s1 = (i + 1) as f64 / count as f64;
            if i + 1 == count {
                pieces.push(Piece::new(s0, 1.0, rest.clone()));
            } else {
                // Split the remaining curve [s0, 1] at s1.
                let local = (s1 - s0) / (1.0 - s0);
                let (left, right) = de_casteljau(&rest, local);
                pieces.push(Piece::new(s0, s1, left));
                rest = right;
            }
            s0 = s1;
        }
        let seam = course_perpendicular(axis);
        let seam2 = axis.cross(seam);
        let z = profile.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x), b.max(p.x)));
        let r = profile.iter().fold(0.0f64, |a, p| a.max(p.y.abs()));
        // Box of the bounding cylinder.
        let (bottom, top) = (base + axis * z.0, base + axis * z.1);
        let spread = DVec3::new(
            r * (1.0 - axis.x * axis.x).max(0.0).sqrt(),
            r * (1.0 - axis.y * axis.y).max(0.0).sqrt(),
            r * (1.0 - axis.z * axis.z).max(0.0).sqrt(),
        );
        let bounds = Bounds { min: bottom.min(top) - spread, max: bottom.max(top) + spread };
        let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element();
        if !magnitude.is_finite() {
            return Err(GeometryError::Degenerate("the profile is not finite"));
        }
        let hull = Piece::new(0.0, 1.0, profile.clone()).hull;
        let groups = (0..pieces.len())
            .step_by(GROUP)
            .map(|start| {
                let end = (start + GROUP).min(pieces.len());
                let h = pieces[start..end].iter().fold(
                    [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY],
                    |a, p| {
                        [a[0].min(p.hull[0]), a[1].max(p.hull[1]), a[2].min(p.hull[2]), a[3].max(p.hull[3])]
                    },
                );
                (start, end, h)
            })
            .collect();
        Ok(Bezier {
            groups,
            base,
            axis,
            profile,
            seam,
            seam2,
            power,
            power_derivative,
            pieces,
            hull,
            bounds,
            magnitude,
        })
    }

    /// The point of the profile at `s`: `(z, r)`.
    pub fn profile_at(&self, s: f64) -> DVec2 {
        horner(&self.power, s)
    }

    /// The derivative of the profile at `s`: `(z', r')`.
    fn derivative_at(&self, s: f64) -> DVec2 {
        horner(&self.power_derivative, s)
    }

    /// The nearest hit with `t_min < t < t_max`.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<ShapeHit> {
        let o = ray.origin - self.base;
        let local_o = DVec3::new(o.dot(self.seam), o.dot(self.seam2), o.dot(self.axis));
        let d = ray.dir;
        let local_d = DVec3::new(d.dot(self.seam), d.dot(self.seam2), d.dot(self.axis));
        let eq = RayEquations::new(local_o, local_d);
        // Tolerance on the hull boxes: rounding of the local coordinates.
        let pad = 1e-12 * (self.magnitude + o.abs().max_element());
        let mut best: Option<(f64, f64)> = None;
        let mut limit = t_max;
        // Most rays pass the whole surface by: test its hull first.
        let [z0, z1, _, r1] = self.hull;
        if eq.annulus_intervals(z0 - pad, z1 + pad, 0.0, r1 + pad, t_min, limit).is_empty() {
            return None;
        }
        for &(start, end, [z0, z1, r0, r1]) in &self.groups {
            if eq
                .annulus_intervals(z0 - pad, z1 + pad, (r0 - pad).max(0.0), r1 + pad, t_min, limit)
                .is_empty()
            {
                continue;
            }
            for piece in &self.pieces[start..end] {
                self.search(piece, &eq, t_min, &mut limit, pad, 0, &mut best);
            }
        }
        best.map(|(t, s)| ShapeHit { t, part: ShapePart::Profile { s } })
    }

    /// Finds the roots on `piece` nearer than `limit`, keeping the nearest in `best`.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        piece: &Piece,
        eq: &RayEquations,
        t_min: f64,
        limit: &mut f64,
        pad: f64,
        depth: u32,
        best: &mut Option<(f64, f64)>,
    ) {
        let [z0, z1, r0, r1] = piece.hull;
        for (ta, tb) in eq.annulus_intervals(z0 - pad, z1 + pad, (r0 - pad).max(0.0), r1 + pad, t_min, *limit)
        {
            let split = match self.newton(piece, eq, ta, tb) {
                Newton::Root(t, s) if t > t_min && t < *limit => {
                    *limit = t;
                    *best = Some((t, s));
                    // A piece may hold two roots on one stretch (near a silhouette): look for a
                    // nearer one in the halves, unless this one is at the stretch's start.
                    t > ta + 1e-6 * (tb - ta)
                }
                // A root out of reach, or of another piece: that piece finds it.
                Newton::Root(..) | Newton::Elsewhere => false,
                Newton::Diverged => true,
            };
            if split && depth < MAX_SPLIT_DEPTH {
                let (left, right) = piece.split();
                self.search(&left, eq, t_min, limit, pad, depth + 1, best);
                self.search(&right, eq, t_min, limit, pad, depth + 1, best);
            }
        }
    }

    /// Newton's method on `(s, t)` from the middle of the ray's stretch `[ta, tb]` and the
    /// point of the piece's chord nearest to it in the (height, radius) plane.
    fn newton(&self, piece: &Piece, eq: &RayEquations, ta: f64, tb: f64) -> Newton {
        let mut t = 0.5 * (ta + tb);
        let (c0, c1) = (piece.control[0], piece.control[piece.control.len() - 1]);
        let at = DVec2::new(eq.oz + eq.dz * t, (eq.a * t * t + 2.0 * eq.b * t + eq.c).max(0.0).sqrt());
        let chord = c1 - c0;
        let f = if chord.length_squared() > 0.0 {
            ((at - c0).dot(chord) / chord.length_squared()).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let width = piece.s1 - piece.s0;
        let mut s = piece.s0 + f * width;
        let t_scale = tb.abs().max(ta.abs()).max(self.magnitude * 1e-3);
        let mut converged = false;
        for _ in 0..NEWTON_STEPS {
            let p = self.profile_at(s);
            let dp = self.derivative_at(s);
            let f1 = eq.oz + eq.dz * t - p.x;
            let f2 = eq.a * t * t + 2.0 * eq.b * t + eq.c - p.y * p.y;
            // Jacobian of (f1, f2) by (s, t).
            let (j11, j12) = (-dp.x, eq.dz);
            let (j21, j22) = (-2.0 * p.y * dp.y, 2.0 * (eq.a * t + eq.b));
            let det = j11 * j22 - j12 * j21;
            if det == 0.0 || !det.is_finite() {
                return Newton::Diverged;
            }
            let ds = (f1 * j22 - f2 * j12) / det;
            let dt = (j11 * f2 - j21 * f1) / det;
            s -= ds;
            t -= dt;
            if !s.is_finite() || !t.is_finite() || !(-0.5..=1.5).contains(&s) {
                return Newton::Diverged;
            }
            if dt.abs() <= 1e-14 * t_scale && ds.abs() <= 1e-13 {
                converged = true;
                break;
            }
        }
        // Converged to an actual root?
        let p = self.profile_at(s);
        let f1 = eq.oz + eq.dz * t - p.x;
        let rho = (eq.a * t * t + 2.0 * eq.b * t + eq.c).max(0.0).sqrt();
        let f2 = rho - p.y.abs();
        let tol = 1e-9 * (self.magnitude + t.abs());
        if !(f1.abs() <= tol && f2.abs() <= tol) {
            return if converged { Newton::Elsewhere } else { Newton::Diverged };
        }
        let slack_t = 1e-9 * (tb - ta) + 1e-12 * t_scale;
        let inside = s >= piece.s0 - 1e-9 * width
            && s <= piece.s1 + 1e-9 * width
            && (0.0..=1.0).contains(&s)
            && t >= ta - slack_t
            && t <= tb + slack_t;
        if inside { Newton::Root(t, s.clamp(0.0, 1.0)) } else { Newton::Elsewhere }
    }

    /// The unit outward normal at curve parameter `s` and point `point`: the profile's normal
    /// `(-r', z')` in the (height, radius) plane, turned about the axis; it points away from the
    /// axis where the curve climbs.
    pub fn outward_normal(&self, point: DVec3, s: f64) -> DVec3 {
        let radial = self.radial(point);
        let mut dp = self.derivative_at(s);
        if dp.length_squared() == 0.0 {
            // A cusp (repeated control points): the direction just beside it.
            let nudge = if s < 0.5 { 1e-7 } else { -1e-7 };
            dp = self.derivative_at(s + nudge);
        }
        let r = self.profile_at(s).y;
        let sign = if r < 0.0 { -1.0 } else { 1.0 };
        (radial * dp.x * sign - self.axis * dp.y * sign).normalize_or(self.axis)
    }

    /// The unit direction from the axis to `point` (the seam direction on the axis).
    fn radial(&self, point: DVec3) -> DVec3 {
        let p = point - self.base;
        (p - self.axis * p.dot(self.axis)).try_normalize().unwrap_or(self.seam)
    }

    /// Texture coordinates (spec section 9): `u = s` along the curve, `v` the angle around the
    /// axis from the seam over 2 pi (as on a cylinder's side).
    pub fn texture_coordinates(&self, point: DVec3, s: f64) -> (f64, f64) {
        let p = point - self.base;
        let angle = p.dot(self.seam2).atan2(p.dot(self.seam)).rem_euclid(TAU);
        (s, angle / TAU)
    }

    /// The directions in which `u` and `v` grow at curve parameter `s` and `point`.
    pub fn texture_tangents(&self, point: DVec3, s: f64) -> (DVec3, DVec3) {
        let radial = self.radial(point);
        let dp = self.derivative_at(s);
        let r = self.profile_at(s).y;
        (self.axis * dp.x + radial * dp.y, self.axis.cross(radial) * (TAU * r))
    }

    /// The bounding box.
    pub fn bounds(&self) -> Bounds {
        self.bounds
    }

    /// The size of the surface and its distance from the origin, whichever is larger.
    pub fn magnitude(&self) -> f64 {
        self.magnitude
    }
}

/// What Newton's method found on a piece.
enum Newton {
    /// A root `(t, s)` on the piece and the ray's stretch.
    Root(f64, f64),
    /// A root, but on another piece or outside the stretch.
    Elsewhere,
    /// No convergence.
    Diverged,
}

/// The ray in the axis's frame: `rho2(t) = a t^2 + 2 b t + c`, `h(t) = oz + dz t`.
struct RayEquations {
    a: f64,
    b: f64,
    c: f64,
    oz: f64,
    dz: f64,
    /// `rho2` at the ray's closest approach to the axis, `c - b^2 / a` (when `a > 1e-300`).
    closest: f64,
    /// Where the closest approach is, `-b / a` (when `a > 0`).
    t_closest: f64,
}

impl RayEquations {
    /// The equations of the ray from `o` along `d`, both in the axis's frame (z along the axis).
    /// What every hull test of the ray needs is worked out once here (a ray meets up to dozens).
    fn new(o: DVec3, d: DVec3) -> RayEquations {
        let a = d.x * d.x + d.y * d.y;
        let b = o.x * d.x + o.y * d.y;
        let c = o.x * o.x + o.y * o.y;
        RayEquations {
            a,
            b,
            c,
            oz: o.z,
            dz: d.z,
            closest: if a > 1e-300 { c - b * b / a } else { 0.0 },
            t_closest: if a > 0.0 { -b / a } else { f64::NAN },
        }
    }

    /// The stretches of `(t_min, t_max)` where the ray lies in the annulus slab
    /// `z0 <= h <= z1`, `r0 <= rho <= r1`, each split where `rho` stops falling (so `rho` is
    /// monotone along each).
    fn annulus_intervals(&self, z0: f64, z1: f64, r0: f64, r1: f64, t_min: f64, t_max: f64) -> Intervals {
        let (mut lo, mut hi) = (t_min, t_max);
        // Height slab.
        if self.dz != 0.0 {
            let (ta, tb) = ((z0 - self.oz) / self.dz, (z1 - self.oz) / self.dz);
            lo = lo.max(ta.min(tb));
            hi = hi.min(ta.max(tb));
        } else if self.oz < z0 || self.oz > z1 {
            return Intervals::default();
        }
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Intervals::default();
        }
        // Inside the outer cylinder: a t^2 + 2 b t + c - r1^2 <= 0.
        match self.roots(r1 * r1) {
            Roots::All => {}
            Roots::None => return Intervals::default(),
            Roots::Between(t0, t1) => {
                lo = lo.max(t0);
                hi = hi.min(t1);
            }
        }
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Intervals::default();
        }
        let mut out = Intervals::default();
        // Outside the inner cylinder: remove (t0, t1).
        match if r0 > 0.0 { self.roots(r0 * r0) } else { Roots::None } {
            Roots::All => return out,
            Roots::None => out.push((lo, hi)),
            Roots::Between(t0, t1) => {
                if lo < t0 {
                    out.push((lo, hi.min(t0)));
                }
                if hi > t1 {
                    out.push((lo.max(t1), hi));
                }
            }
        }
        // Split at the closest approach to the axis.
        if self.a > 0.0 {
            let tc = self.t_closest;
            if let Some(i) = out.as_slice().iter().position(|&(a, b)| a < tc && tc < b) {
                let (a, b) = out.items[i];
                out.items[i] = (a, tc);
                out.insert(i + 1, (tc, b));
            }
        }
        out
    }

    /// Where `rho2(t) <= limit`: everywhere, nowhere, or between two roots.
    fn roots(&self, limit: f64) -> Roots {
        let c = self.c - limit;
        if self.a <= 1e-300 {
            return if c <= 0.0 { Roots::All } else { Roots::None };
        }
        // The discriminant b^2 - a c, computed as a (limit - distance^2 of the closest approach)
        // to keep its precision for rays far from the axis.
        let disc = self.a * (limit - self.closest.max(0.0));
        if disc < 0.0 {
            return Roots::None;
        }
        let q = -(self.b + self.b.signum() * disc.sqrt());
        if q == 0.0 {
            return Roots::Between(0.0, 0.0);
        }
        let (t0, t1) = (q / self.a, c / q);
        Roots::Between(t0.min(t1), t0.max(t1))
    }
}

/// Up to three stretches of a ray (no allocation).
#[derive(Default)]
struct Intervals {
    items: [(f64, f64); 3],
    len: usize,
}

impl Intervals {
    fn push(&mut self, v: (f64, f64)) {
        self.items[self.len] = v;
        self.len += 1;
    }

    fn insert(&mut self, i: usize, v: (f64, f64)) {
        self.items.copy_within(i..self.len, i + 1);
        self.items[i] = v;
        self.len += 1;
    }

    fn as_slice(&self) -> &[(f64, f64)] {
        &self.items[..self.len]
    }

    fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl IntoIterator for Intervals {
    type Item = (f64, f64);
    type IntoIter = std::iter::Take<std::array::IntoIter<(f64, f64), 3>>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.into_iter().take(self.len)
    }
}

enum Roots {
    All,
    None,
    Between(f64, f64),
}

/// The polynomial `sum c_k s^k` at `s` (Horner's rule).
#[inline]
fn horner(c: &[DVec2], s: f64) -> DVec2 {
    c.iter().rev().fold(DVec2::ZERO, |acc, &k| acc * s + k)
}

/// The power-basis coefficients of the Bezier curve with control points `control`:
/// `c_k = C(n, k) sum_i (-1)^(k-i) C(k, i) P_i`.
fn power_basis(control: &[DVec2]) -> Vec<DVec2> {
    let n = control.len() - 1;
    let binomial = |n: usize, k: usize| (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64);
    (0..=n)
        .map(|k| {
            let sum = (0..=k).fold(DVec2::ZERO, |acc, i| {
                let sign = if (k - i) % 2 == 0 { 1.0 } else { -1.0 };
                acc + control[i] * (sign * binomial(k, i))
            });
            sum * binomial(n, k)
        })
        .collect()
}

/// The control points of the curve's parts before and after `s`.
fn de_casteljau(control: &[DVec2], s: f64) -> (Vec<DVec2>, Vec<DVec2>) {
    let n = control.len();
    let mut p = control.to_vec();
    let mut left = Vec::with_capacity(n);
    let mut right = Vec::with_capacity(n);
    left.push(p[0]);
    right.push(p[n - 1]);
    for k in 1..n {
        for i in 0..n - k {
            p[i] = p[i] + (p[i + 1] - p[i]) * s;
        }
        left.push(p[0]);
        right.push(p[n - 1 - k]);
    }
    right.reverse();
    (left, right)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::test_util::{SCALES, TestRng, check_reintersection};
    use crate::geometry::{Cylinder, Shape};

    fn surface(points: &[(f64, f64)]) -> Bezier {
        Bezier::new(DVec3::ZERO, DVec3::Z, points.iter().map(|&(z, r)| DVec2::new(z, r)).collect())
            .expect("valid")
    }

    /// A profile of collinear points at constant radius is a cylinder (without caps): every
    /// ray agrees with the closed-form cylinder's side.
    #[test]
    fn straight_vertical_profile_is_a_cylinder() {
        let b = Bezier::new(
            DVec3::new(0.5, -1.0, 0.2),
            DVec3::new(1.0, 1.0, 2.0),
            vec![DVec2::new(0.0, 0.7), DVec2::new(0.5, 0.7), DVec2::new(0.9, 0.7), DVec2::new(1.5, 0.7)],
        )
        .expect("valid");
        let axis = DVec3::new(1.0, 1.0, 2.0).normalize();
        let cyl = Cylinder::new(DVec3::new(0.5, -1.0, 0.2), DVec3::new(0.5, -1.0, 0.2) + axis * 1.5, 0.7)
            .expect("valid");
        let mut rng = TestRng::new(21);
        let mut compared = 0;
        for _ in 0..3000 {
            let centre = DVec3::new(0.5, -1.0, 0.2) + axis * 0.75;
            let origin = centre + rng.unit_vector() * 4.0;
            let target = centre + rng.unit_vector() * 1.2 * rng.uniform();
            let ray = Ray::new(origin, target - origin);
            let expected = cyl.intersect(&ray, 0.0, f64::INFINITY).filter(|h| h.part == ShapePart::Main);
            let found = b.intersect(&ray, 0.0, f64::INFINITY);
            // The cylinder's caps may hide its side; compare where the side is nearest.
            match (expected, found) {
                (Some(e), Some(f)) => {
                    assert!((e.t - f.t).abs() < 1e-9, "t {} vs {}", e.t, f.t);
                    let p = ray.at(f.t);
                    let ShapePart::Profile { s } = f.part else { panic!() };
                    assert!(
                        (b.outward_normal(p, s) - cyl.outward_normal(p, ShapePart::Main)).length() < 1e-9
                    );
                    compared += 1;
                }
                (None, Some(f)) => {
                    // The cylinder's cap was hit first, or the ray enters through an open end.
                    let capped =
                        cyl.intersect(&ray, 0.0, f64::INFINITY).is_some_and(|h| h.part != ShapePart::Main);
                    assert!(capped, "hit {f:?} where the cylinder has no side");
                }
                (Some(e), None) => panic!("missed the side at t = {} ({ray:?})", e.t),
                (None, None) => {}
            }
        }
        assert!(compared > 500, "{compared}");
    }

    /// A straight slanted profile is a cone: compare with the cone's closed form.
    #[test]
    fn straight_slanted_profile_is_a_cone() {
        // Apex at height 2 on the z axis, radius 1 at height 0: r = 1 - z/2.
        let b = surface(&[(0.0, 1.0), (0.4, 0.8), (1.2, 0.4)]);
        let mut rng = TestRng::new(22);
        let mut compared = 0;
        for _ in 0..3000 {
            let origin = rng.unit_vector() * 4.0;
            let target = DVec3::new(0.0, 0.0, 0.6) + rng.unit_vector() * rng.uniform();
            let ray = Ray::new(origin, target - origin);
            // Cone x^2 + y^2 = (1 - z/2)^2, 0 <= z <= 1.2.
            let (o, d) = (ray.origin, ray.dir);
            let k = 0.5;
            let a = d.x * d.x + d.y * d.y - k * k * d.z * d.z;
            let bb = o.x * d.x + o.y * d.y + k * (1.0 - k * o.z) * d.z;
            let c = o.x * o.x + o.y * o.y - (1.0 - k * o.z).powi(2);
            let mut expected = None;
            if let Some((t0, t1)) = crate::geometry::solve_quadratic(a, bb, c) {
                for t in [t0, t1] {
                    let z = o.z + t * d.z;
                    if t > 0.0 && (0.0..=1.2).contains(&z) && 1.0 - k * z >= 0.0 {
                        expected = Some(t);
                        break;
                    }
                }
            }
            let found = b.intersect(&ray, 0.0, f64::INFINITY).map(|h| h.t);
            match (expected, found) {
                (Some(e), Some(f)) => {
                    assert!((e - f).abs() < 1e-9, "t {e} vs {f}");
                    compared += 1;
                }
                (None, None) => {}
                (e, f) => {
                    // Only grazing rays may disagree (a double root).
                    let t = e.or(f).expect("one of them");
                    let p = ray.at(t);
                    let n = b.outward_normal(p, (p.z / 1.2).clamp(0.0, 1.0));
                    assert!(n.dot(ray.dir).abs() < 1e-6, "expected {e:?}, found {f:?} for {ray:?}");
                }
            }
        }
        assert!(compared > 500, "{compared}");
    }

    /// A dense grid of rays agrees with a fine tessellation of the same surface wherever the
    /// tessellation is fine enough (away from silhouettes, where the tessellation's error
    /// matters).
    #[test]
    fn agrees_with_a_fine_tessellation() {
        let b = surface(&[(0.0, 0.0), (0.0, 0.9), (0.5, 0.1), (1.0, 1.2), (1.6, 0.5)]);
        // Tessellate: 400 steps along the curve, 400 around.
        let (ns, nphi) = (400, 400);
        let point = |i: usize, j: usize| {
            let p = b.profile_at(i as f64 / ns as f64);
            let phi = TAU * j as f64 / nphi as f64;
            DVec3::new(p.y * phi.cos(), p.y * phi.sin(), p.x)
        };
        let mut tris = Vec::new();
        for i in 0..ns {
            for j in 0..nphi {
                let (a, bb, c, d) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
                tris.push([a, bb, c]);
                tris.push([a, c, d]);
            }
        }
        let mesh: Vec<crate::geometry::Triangle> =
            tris.iter().filter_map(|t| crate::geometry::Triangle::new(t[0], t[1], t[2]).ok()).collect();
        let boxes: Vec<crate::accel::Box32> =
            mesh.iter().map(|t| crate::accel::Box32::from_bounds(&t.bounds())).collect();
        let bvh = crate::accel::wide::WideBvh::build(&boxes, crate::accel::wide::BuildParams::SHAPES);
        let order = bvh.order().to_vec();
        let mut agreed = 0;
        for gy in 0..40 {
            for gx in 0..40 {
                let origin = DVec3::new(-3.0, (gx as f64 - 19.5) / 15.0, (gy as f64) / 22.0 - 0.1);
                let ray = Ray::new(origin, DVec3::new(1.0, 0.05, 0.02));
                let mut tess: Option<(f64, usize)> = None;
                bvh.traverse(&crate::accel::wide::BoxRay::new(&ray), f32::INFINITY, |first, count, limit| {
                    let mut limit = limit;
                    for &i in &order[first as usize..(first + count) as usize] {
                        if let Some(h) = mesh[i as usize].intersect(&ray, 0.0, limit as f64) {
                            limit = h.t as f32;
                            tess = Some((h.t, i as usize));
                        }
                    }
                    limit
                });
                let exact = b.intersect(&ray, 0.0, f64::INFINITY);
                match (tess, exact) {
                    (Some((tt, i)), Some(e)) => {
                        // Where the tessellation faces the ray squarely, it is within its
                        // chordal error of the surface.
                        let n = mesh[i].normal;
                        if n.dot(ray.dir).abs() > 0.2 {
                            assert!((tt - e.t).abs() < 2e-3, "tessellation {tt} vs exact {}", e.t);
                            agreed += 1;
                        }
                    }
                    (None, None) => {}
                    (t, e) => {
                        // Only near a silhouette may one see what the other misses.
                        let t_hit = t.map(|x| x.0).or(e.map(|h| h.t)).expect("one");
                        let p = ray.at(t_hit);
                        let s = match e {
                            Some(ShapeHit { part: ShapePart::Profile { s }, .. }) => s,
                            _ => 0.5,
                        };
                        let grazing = e.is_none() || b.outward_normal(p, s).dot(ray.dir).abs() < 0.2;
                        assert!(grazing, "tessellation {t:?} vs exact {e:?} for {ray:?}");
                    }
                }
            }
        }
        assert!(agreed > 300, "{agreed}");
    }

    #[test]
    fn profile_touching_the_axis_has_no_hole() {
        // A closed bowl: starts on the axis; rays straight down the axis and next to it hit.
        let b = surface(&[(0.0, 0.0), (0.0, 1.0), (1.0, 1.0)]);
        for x in [0.0, 1e-9, 1e-6, 1e-3, 0.1] {
            let ray = Ray::new(DVec3::new(x, 0.0, -2.0), DVec3::Z);
            let hit = b.intersect(&ray, 0.0, f64::INFINITY).unwrap_or_else(|| panic!("missed at x = {x}"));
            let ShapePart::Profile { s } = hit.part else { panic!() };
            // The hit is on the profile: at distance x from the axis, at the profile's height.
            let p = b.profile_at(s);
            assert!((p.y - x).abs() < 1e-6 && (hit.t - 2.0 - p.x).abs() < 1e-9, "t = {} at x = {x}", hit.t);
            let n = b.outward_normal(ray.at(hit.t), s);
            assert!(n.dot(-DVec3::Z) > 0.99, "normal {n}");
        }
    }

    #[test]
    fn texture_coordinates_run_along_and_around() {
        let b = surface(&[(0.0, 1.0), (1.0, 1.0)]);
        let ray = Ray::new(DVec3::new(0.0, 5.0, 0.25), -DVec3::Y);
        let hit = b.intersect(&ray, 0.0, f64::INFINITY).expect("hit");
        let ShapePart::Profile { s } = hit.part else { panic!() };
        let (u, v) = b.texture_coordinates(ray.at(hit.t), s);
        assert!((u - 0.25).abs() < 1e-9, "u = {u}");
        // Seam along x (axis z: course_perpendicular gives z x... = -y x ... ); +y is a quarter turn.
        assert!((0.0..1.0).contains(&v));
    }

    #[test]
    fn invalid_profiles_are_errors() {
        assert!(Bezier::new(DVec3::ZERO, DVec3::Z, vec![DVec2::new(0.0, 1.0)]).is_err());
        assert!(Bezier::new(DVec3::ZERO, DVec3::ZERO, vec![DVec2::ZERO, DVec2::ONE]).is_err());
        assert!(
            Bezier::new(DVec3::ZERO, DVec3::Z, vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0)]).is_err()
        );
    }

    #[test]
    fn reintersection_free_over_all_scales() {
        let mut rng = TestRng::new(23);
        for scale in SCALES {
            let base = DVec3::new(scale, 2.0 * scale, -scale);
            let profile: Vec<DVec2> = [(-1.0, 0.2), (-0.5, 1.4), (0.5, 0.3), (1.0, 0.9)]
                .iter()
                .map(|&(z, r)| DVec2::new(z, r) * scale)
                .collect();
            let shape = Shape::Bezier(Box::new(
                Bezier::new(base, DVec3::new(0.2, 0.1, 1.0), profile).expect("valid"),
            ));
            check_reintersection(&shape, base, scale, &mut rng);
        }
    }
}
