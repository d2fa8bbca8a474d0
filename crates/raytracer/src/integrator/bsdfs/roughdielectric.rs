//! `roughdielectric` (Mitsuba 3's `roughdielectric.cpp`): a rough interface between two
//! dielectrics (Walter et al. 2007), reflection and transmission, from both sides.

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::MicrofacetDistribution;

/// A rough dielectric interface of relative index `eta` (inside over outside).
///
/// With `eta_t` the index ratio of `wi`'s side over `wo`'s and `h` the generalised half vector
/// (`normalize(wo + eta_t wi)` for transmission, `normalize(wo + wi)` for reflection, turned
/// up):
/// - reflection: `F(wo.h) D(h) G / (4 |cos_o| |cos_i|)`, tinted by `specular_reflectance`;
/// - transmission (radiance): `(1 - F) D G |wo.h| |wi.h| / (|cos_o| |cos_i| (wo.h + eta_t wi.h)^2)`,
///   tinted by `specular_transmittance`: Walter's BTDF times `1 / eta_t^2`, the scaling of
///   radiance crossing into the other medium (Mitsuba's radiance mode).
///
/// Sampling draws `h` from the distribution seen from `wo` turned up (visible normals, or
/// all normals with Walter's roughness widening `1.2 - 0.2 sqrt|cos_o|` when
/// `sample_visible` is off), then reflects with probability `F(wo.h)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// `int_ior / ext_ior`.
    pub eta: f64,
    /// Tint of reflection.
    pub reflect_tint: DVec3,
    /// Tint of transmission.
    pub transmit_tint: DVec3,
    /// The microfacets.
    pub distr: MicrofacetDistribution,
}

impl RoughDielectric {
    /// The distribution sampling uses for the viewing cosine `cos_o`.
    fn sampling_distr(&self, cos_o: f64) -> MicrofacetDistribution {
        if self.distr.sample_visible { self.distr } else { self.distr.scaled(1.2 - 0.2 * cos_o.abs().sqrt()) }
    }

    /// The half vector of the pair, turned up, and the index ratio `eta_t` of `wi`'s side over
    /// `wo`'s (1 for reflection). `None` for degenerate pairs.
    fn half_vector(&self, wo: DVec3, wi: DVec3) -> Option<(DVec3, bool, f64)> {
        let (co, ci) = (wo.z, wi.z);
        if co == 0.0 || ci == 0.0 {
            return None;
        }
        let reflected = co * ci > 0.0;
        let eta_t = if reflected {
            1.0
        } else if co > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let h = wo + wi * eta_t;
        let len = h.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let h = h / len;
        let h = if h.z < 0.0 { -h } else { h };
        // Both directions must see the facet's front from their own side.
        if wo.dot(h) * co <= 0.0 || wi.dot(h) * ci <= 0.0 {
            return None;
        }
        Some((h, reflected, eta_t))
    }

    /// `f(wo, wi)` without the cosine (radiance mode).
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        let Some((h, reflected, eta_t)) = self.half_vector(wo, wi) else {
            return DVec3::ZERO;
        };
        let d = self.distr.d(h);
        if d == 0.0 {
            return DVec3::ZERO;
        }
        let f = fresnel_dielectric(wo.dot(h), self.eta).r;
        let g = self.distr.g(wo, wi, h);
        let (co, ci) = (wo.z.abs(), wi.z.abs());
        if reflected {
            self.reflect_tint * (f * d * g / (4.0 * co * ci))
        } else {
            let (oh, ih) = (wo.dot(h), wi.dot(h));
            let denom = oh + eta_t * ih;
            let value = (1.0 - f) * d * g * (oh * ih).abs() / (co * ci * denom * denom);
            self.transmit_tint * value
        }
    }

    /// The density of [`RoughDielectric::sample`] per steradian of `wi`.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        let Some((h, reflected, eta_t)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let pm = self.sampling_distr(wo.z).pdf(wo_up, h);
        let f = fresnel_dielectric(wo.dot(h), self.eta).r;
        let ih = wi.dot(h);
        if reflected {
            pm * f / (4.0 * ih.abs())
        } else {
            let denom = wo.dot(h) + eta_t * ih;
            pm * (1.0 - f) * eta_t * eta_t * ih.abs() / (denom * denom)
        }
    }

    /// A direction reflected or refracted about a sampled microfacet normal; `u` chooses
    /// between them with probabilities `F` and `1 - F`.
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let (m, _) = self.sampling_distr(wo.z).sample(wo_up, u1, u2);
        // A facet turned away from wo (possible without visible-normal sampling) scatters
        // nothing (its masking is 0).
        if wo_up.dot(m) <= 0.0 {
            return None;
        }
        let fr = fresnel_dielectric(wo.dot(m), self.eta);
        let reflected = u < fr.r;
        let (wi, eta) =
            if reflected { (reflect(wo, m), 1.0) } else { (refract(wo, m, fr.cos_t, fr.eta_ti), fr.eta_it) };
        // A reflection must stay on wo's side, a refraction cross (else the facet is hidden).
        if (wi.z * wo.z > 0.0) != reflected {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z.abs() / pdf;
        Some(LocalSample { wi, weight, pdf, delta: false, eta })
    }
}
