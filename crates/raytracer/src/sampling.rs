//! Warps from uniform numbers in [0, 1) to directions and points, shared by the light-transport
//! models. Directions are unit vectors in world space (z-up); each warp states its density.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// A direction uniform over the whole sphere (density `1 / (4 pi)` per steradian).
#[inline]
pub fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (TAU * u2).sin_cos();
    DVec3::new(r * cos, r * sin, z)
}

/// A direction in the hemisphere around the unit vector `n`, with density `cos / pi` per steradian
/// (the angle measured from `n`), by Malley's method: a uniform point of the unit disc lifted to
/// the hemisphere.
#[inline]
pub fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let (sin, cos) = (TAU * u2).sin_cos();
    let (x, y) = (r * cos, r * sin);
    let z = (1.0 - u1).max(0.0).sqrt();
    let (t, b) = orthonormal_basis(n);
    t * x + b * y + n * z
}

/// The density of [`cosine_hemisphere`] for a direction whose cosine with `n` is `cos`.
#[inline]
pub fn cosine_hemisphere_pdf(cos: f64) -> f64 {
    if cos > 0.0 { cos / PI } else { 0.0 }
}

/// Two unit vectors that make a right-handed orthonormal basis `(t, b, n)` with the unit vector
/// `n` (Duff et al. 2017: continuous, no normalisation).
#[inline]
pub fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), DVec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// A point uniform over the sphere of `centre` and `radius`, with its outward unit normal
/// (density `1 / area`).
#[inline]
pub fn uniform_sphere_point(centre: DVec3, radius: f64, u1: f64, u2: f64) -> (DVec3, DVec3) {
    let n = uniform_sphere(u1, u2);
    (centre + radius * n, n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::test_util::TestRng;

    #[test]
    fn bases_are_orthonormal_and_right_handed() {
        let mut rng = TestRng::new(4);
        for _ in 0..1000 {
            let n = rng.unit_vector();
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
        for n in [DVec3::Z, -DVec3::Z, DVec3::X] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.cross(b) - n).length() < 1e-12, "{n}");
        }
    }

    #[test]
    fn cosine_directions_stay_in_the_hemisphere_with_mean_cosine_two_thirds() {
        let mut rng = TestRng::new(8);
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let count = 200_000;
        let mut sum = 0.0;
        for _ in 0..count {
            let d = cosine_hemisphere(n, rng.uniform(), rng.uniform());
            assert!((d.length() - 1.0).abs() < 1e-12);
            let c = d.dot(n);
            assert!(c >= 0.0);
            sum += c;
        }
        // E[cos] under cos/pi is 2/3.
        assert!((sum / count as f64 - 2.0 / 3.0).abs() < 3e-3, "{}", sum / count as f64);
    }

    #[test]
    fn uniform_sphere_directions_have_no_preferred_side() {
        let mut rng = TestRng::new(2);
        let count = 200_000;
        let mut mean = DVec3::ZERO;
        let mut z2 = 0.0;
        for _ in 0..count {
            let d = uniform_sphere(rng.uniform(), rng.uniform());
            assert!((d.length() - 1.0).abs() < 1e-12);
            mean += d;
            z2 += d.z * d.z;
        }
        assert!((mean / count as f64).length() < 6e-3);
        // E[z^2] over the sphere is 1/3.
        assert!((z2 / count as f64 - 1.0 / 3.0).abs() < 3e-3);
    }
}
