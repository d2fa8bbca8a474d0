//! Fresnel equations (Mitsuba 3's `fresnel.h`): unpolarised reflectance of a dielectric
//! interface and of a conductor, and the diffuse Fresnel reflectance of a dielectric.
//!
//! Angles are given by cosines measured from the interface's normal (+z of the local frame);
//! `eta` is a relative index of refraction, inside over outside (the inside being below the
//! surface, -z).

use glam::DVec3;

/// The result of [`fresnel_dielectric`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricFresnel {
    /// Unpolarised reflectance `F` in [0, 1] (1 under total internal reflection).
    pub r: f64,
    /// Cosine of the transmitted direction, of the sign opposite to `cos_i` (0 under total
    /// internal reflection).
    pub cos_t: f64,
    /// Relative index of the side entered over the side left (`eta` from outside, `1/eta` from
    /// inside).
    pub eta_it: f64,
    /// Its reciprocal.
    pub eta_ti: f64,
}

/// Fresnel reflectance of a smooth dielectric interface of relative index `eta` (inside over
/// outside) for an incident direction of cosine `cos_i` (positive outside, negative inside).
/// As Mitsuba: `eta = 1` reflects nothing, grazing incidence (`cos_i = 0`) reflects everything.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> DielectricFresnel {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i);
    let ci = cos_i.abs();
    let ct = cos_t_sqr.max(0.0).sqrt();
    let r = if eta == 1.0 {
        0.0
    } else if ci == 0.0 {
        1.0
    } else {
        let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    let cos_t = if cos_i >= 0.0 { -ct } else { ct };
    DielectricFresnel { r, cos_t, eta_it, eta_ti }
}

/// A complex number, only as much as the conductor's Fresnel equations need.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn add(self, o: Complex) -> Complex {
        Complex { re: self.re + o.re, im: self.im + o.im }
    }
    fn sub(self, o: Complex) -> Complex {
        Complex { re: self.re - o.re, im: self.im - o.im }
    }
    fn mul(self, o: Complex) -> Complex {
        Complex { re: self.re * o.re - self.im * o.im, im: self.re * o.im + self.im * o.re }
    }
    fn scale(self, s: f64) -> Complex {
        Complex { re: self.re * s, im: self.im * s }
    }
    fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Complex) -> Complex {
        let d = o.norm();
        Complex { re: (self.re * o.re + self.im * o.im) / d, im: (self.im * o.re - self.re * o.im) / d }
    }
    /// The principal square root.
    fn sqrt(self) -> Complex {
        let r = self.norm().sqrt();
        if r == 0.0 {
            return Complex { re: 0.0, im: 0.0 };
        }
        let re = (0.5 * (r + self.re)).max(0.0).sqrt();
        let im = (0.5 * (r - self.re)).max(0.0).sqrt().copysign(self.im);
        Complex { re, im }
    }
}

/// Unpolarised Fresnel reflectance of a conductor of complex relative index `eta + i k` for one
/// channel, at an incident cosine `cos_i` (clamped to [0, 1]). Exact (the complex Fresnel
/// equations, as Mitsuba's `fresnel_conductor`).
pub fn fresnel_conductor_channel(cos_i: f64, eta: f64, k: f64) -> f64 {
    let ci = cos_i.clamp(0.0, 1.0);
    let n = Complex { re: eta, im: k };
    let sin2_i = 1.0 - ci * ci;
    // sin^2 t = sin^2 i / n^2, cos t = sqrt(1 - sin^2 t)
    let n2 = n.mul(n);
    let sin2_t = Complex { re: sin2_i, im: 0.0 }.div(n2);
    let cos_t = Complex { re: 1.0, im: 0.0 }.sub(sin2_t).sqrt();
    let ci_c = Complex { re: ci, im: 0.0 };
    let r_parl = n.scale(ci).sub(cos_t).div(n.scale(ci).add(cos_t));
    let r_perp = ci_c.sub(n.mul(cos_t)).div(ci_c.add(n.mul(cos_t)));
    let r = 0.5 * (r_parl.norm() + r_perp.norm());
    if r.is_finite() { r.clamp(0.0, 1.0) } else { 1.0 }
}

/// [`fresnel_conductor_channel`] for the three RGB channels.
pub fn fresnel_conductor(cos_i: f64, eta: DVec3, k: DVec3) -> DVec3 {
    DVec3::new(
        fresnel_conductor_channel(cos_i, eta.x, k.x),
        fresnel_conductor_channel(cos_i, eta.y, k.y),
        fresnel_conductor_channel(cos_i, eta.z, k.z),
    )
}

/// Diffuse Fresnel reflectance `F_dr(eta)`: the fraction of uniform (cosine-weighted) incident
/// light a smooth interface of relative index `eta` reflects. Mitsuba's fits: Egan and
/// Hilgeman (1973) for `eta < 1`, d'Eon and Irving (2011) otherwise (errors below 0.6% for
/// indices up to 2).
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 * inv
    } else {
        0.919_317 + inv * (-3.4793 + inv * (6.753_35 + inv * (-7.809_89 + inv * (4.985_54 - 1.368_81 * inv))))
    }
}

/// The mirror direction of `w` about +z in the local frame.
#[inline]
pub fn reflect_z(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// The mirror direction of `w` about the unit normal `m`.
#[inline]
pub fn reflect(w: DVec3, m: DVec3) -> DVec3 {
    2.0 * w.dot(m) * m - w
}

/// The refracted direction of `w` through the interface of unit normal `m`, given the
/// transmitted cosine `cos_t` and `eta_ti` of [`fresnel_dielectric`] evaluated at `w . m`.
#[inline]
pub fn refract(w: DVec3, m: DVec3, cos_t: f64, eta_ti: f64) -> DVec3 {
    m * (w.dot(m) * eta_ti + cos_t) - w * eta_ti
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_at_normal_incidence_and_brewster() {
        let eta = 1.5;
        let f = fresnel_dielectric(1.0, eta);
        assert!((f.r - 0.04).abs() < 1e-15);
        assert_eq!(f.cos_t, -1.0);
        // Brewster's angle: the p-polarised part vanishes, F = s-part / 2.
        let theta_b = eta.atan();
        let ci = theta_b.cos();
        let f = fresnel_dielectric(ci, eta);
        let ct = (1.0 - (1.0 - ci * ci) / (eta * eta)).sqrt();
        let rs = ((ci - eta * ct) / (ci + eta * ct)).powi(2);
        assert!((f.r - 0.5 * rs).abs() < 1e-15, "{} vs {}", f.r, 0.5 * rs);
        // At Brewster's angle the reflected and transmitted directions are perpendicular.
        assert!((theta_b + ct.acos() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // rs at Brewster for 1.5 is cos^2(2 theta_b) ... = ((n^2-1)/(n^2+1))^2
        let want = ((eta * eta - 1.0) / (eta * eta + 1.0)).powi(2) * 0.5;
        assert!((f.r - want).abs() < 1e-14, "{} vs {want}", f.r);
    }

    #[test]
    fn dielectric_fresnel_from_inside_and_total_internal_reflection() {
        let eta = 1.5;
        // From inside at normal incidence: same reflectance.
        let f = fresnel_dielectric(-1.0, eta);
        assert!((f.r - 0.04).abs() < 1e-15);
        assert_eq!(f.cos_t, 1.0);
        assert_eq!(f.eta_it, 1.0 / eta);
        // Past the critical angle asin(1/1.5) = 41.8 degrees: total.
        let f = fresnel_dielectric(-(50f64.to_radians().cos()), eta);
        assert_eq!(f.r, 1.0);
        // Reciprocity of transmission: T(outside, theta_i) = T(inside, theta_t).
        let ci = 0.6;
        let fo = fresnel_dielectric(ci, eta);
        let fi = fresnel_dielectric(fo.cos_t, eta);
        assert!((fo.r - fi.r).abs() < 1e-14);
        assert!((fi.cos_t - ci).abs() < 1e-14);
        assert_eq!(fresnel_dielectric(0.3, 1.0).r, 0.0);
    }

    #[test]
    fn conductor_fresnel_matches_the_normal_incidence_formula() {
        // Gold at about 600 nm: eta = 0.2, k = 3.0 (normal incidence: ((n-1)^2+k^2)/((n+1)^2+k^2)).
        let (n, k) = (0.2, 3.0);
        let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((fresnel_conductor_channel(1.0, n, k) - want).abs() < 1e-14);
        // Mitsuba's RGB gold (Au): eta = (0.143, 0.374, 1.442), k = (3.983, 2.385, 1.603)
        let eta = DVec3::new(0.143_119, 0.374_957, 1.442_479);
        let kk = DVec3::new(3.983_160, 2.385_721, 1.603_215);
        let f = fresnel_conductor(1.0, eta, kk);
        for c in 0..3 {
            let (n, k) = (eta[c], kk[c]);
            let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            assert!((f[c] - want).abs() < 1e-14);
        }
        assert!(f.x > f.y && f.y > f.z, "gold reflects red most: {f}");
        // With k = 0 it is the dielectric reflectance; at grazing incidence it is 1.
        for ci in [0.1, 0.5, 0.9, 1.0] {
            assert!((fresnel_conductor_channel(ci, 1.5, 0.0) - fresnel_dielectric(ci, 1.5).r).abs() < 1e-14);
        }
        assert!((fresnel_conductor_channel(0.0, 0.2, 3.0) - 1.0).abs() < 1e-12);
        // A perfect conductor (k -> infinity) reflects everything.
        assert!(fresnel_conductor_channel(0.5, 1.0, 1e8) > 1.0 - 1e-7);
    }

    #[test]
    fn diffuse_fresnel_reflectance_matches_integration() {
        // F_dr(eta) = integral over the hemisphere of F(cos) 2 cos d(cos), by quadrature.
        for eta in [1.0 / 1.49, 1.33, 1.49, 1.8] {
            let n = 200_000;
            let mut sum = 0.0;
            for i in 0..n {
                let mu = (i as f64 + 0.5) / n as f64;
                sum += fresnel_dielectric(mu, eta).r * 2.0 * mu / n as f64;
            }
            let fit = fresnel_diffuse_reflectance(eta);
            assert!((fit - sum).abs() / sum < 0.006, "eta {eta}: fit {fit} vs {sum}");
        }
    }
}
