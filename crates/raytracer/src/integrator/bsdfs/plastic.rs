//! `plastic` (Mitsuba 3's `plastic.cpp`): a diffuse base under a smooth dielectric coating,
//! with the coating's internal reflections (Weidlich and Wilkie's layered model as Mitsuba
//! simplifies it), one-sided.

use std::f64::consts::FRAC_1_PI;

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance, reflect_z};
use super::microfacet::{cosine_pdf, cosine_sample};

/// A smooth plastic: specular reflection `F(cos_o) specular_reflectance` (a delta lobe) and a
/// diffuse term
/// `f = d / (1 - fdr_int') (1 - F(cos_o)) (1 - F(cos_i)) / (pi eta^2)`, with `d` the base's
/// albedo and `fdr_int' = fdr_int` (or `d fdr_int` when `nonlinear`), `fdr_int` the coating's
/// diffuse internal reflectance [`fresnel_diffuse_reflectance`]`(1 / eta)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// `int_ior / ext_ior` of the coating.
    pub eta: f64,
    /// The base's albedo (`diffuse_reflectance`).
    pub diffuse: DVec3,
    /// The coating's tint (`specular_reflectance`).
    pub specular: DVec3,
    /// `nonlinear`.
    pub nonlinear: bool,
    /// `fresnel_diffuse_reflectance(1 / eta)`.
    pub fdr_int: f64,
    /// The share of samples the specular lobe gets before Fresnel weighting:
    /// `mean(specular) / (mean(diffuse) + mean(specular))`.
    pub specular_sampling_weight: f64,
}

impl Plastic {
    /// A plastic of relative index `eta` with its derived constants.
    pub fn new(eta: f64, diffuse: DVec3, specular: DVec3, nonlinear: bool) -> Plastic {
        Plastic {
            eta,
            diffuse,
            specular,
            nonlinear,
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
            specular_sampling_weight: sampling_weight(diffuse, specular),
        }
    }

    /// The base's albedo as the coating scatters it: `d / (1 - fdr_int')`.
    pub fn effective_diffuse(&self, internal_reflectance: f64) -> DVec3 {
        let denom = if self.nonlinear {
            DVec3::ONE - self.diffuse * internal_reflectance
        } else {
            DVec3::splat(1.0 - internal_reflectance)
        };
        self.diffuse / denom.max(DVec3::splat(1e-12))
    }

    /// The probability of choosing the specular lobe at the viewing cosine `cos_o`.
    fn prob_specular(&self, f_o: f64) -> f64 {
        let s = f_o * self.specular_sampling_weight;
        let d = (1.0 - f_o) * (1.0 - self.specular_sampling_weight);
        if s + d > 0.0 { s / (s + d) } else { 0.0 }
    }

    /// `f(wo, wi)` of the diffuse term without the cosine (the specular term is a delta).
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return DVec3::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let f_i = fresnel_dielectric(wi.z, self.eta).r;
        self.effective_diffuse(self.fdr_int) * ((1.0 - f_o) * (1.0 - f_i) * FRAC_1_PI / (self.eta * self.eta))
    }

    /// The density of the diffuse outcomes of [`Plastic::sample`].
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        (1.0 - self.prob_specular(f_o)) * cosine_pdf(wi)
    }

    /// The mirror direction (probability proportional to `F specular_sampling_weight`) or a
    /// cosine-distributed one.
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let p_spec = self.prob_specular(f_o);
        if u < p_spec {
            let weight = self.specular * (f_o / p_spec);
            return Some(LocalSample { wi: reflect_z(wo), weight, pdf: p_spec, delta: true, eta: 1.0 });
        }
        let wi = cosine_sample(u1, u2);
        let pdf = (1.0 - p_spec) * cosine_pdf(wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z / pdf;
        Some(LocalSample { wi, weight, pdf, delta: false, eta: 1.0 })
    }
}

/// `mean(specular) / (mean(diffuse) + mean(specular))` (one half when both are black).
pub fn sampling_weight(diffuse: DVec3, specular: DVec3) -> f64 {
    let d = diffuse.max(DVec3::ZERO).element_sum() / 3.0;
    let s = specular.max(DVec3::ZERO).element_sum() / 3.0;
    if d + s > 0.0 { s / (d + s) } else { 0.5 }
}
