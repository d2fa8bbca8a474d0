//! `diffuse`: Lambertian reflection (Mitsuba 3's `diffuse.cpp`), one-sided.

use std::f64::consts::FRAC_1_PI;

use glam::DVec3;

use super::LocalSample;
use super::microfacet::{cosine_pdf, cosine_sample};

/// A Lambertian reflector of albedo `reflectance`: `f = reflectance / pi` when `wo` and `wi`
/// are both above the surface, 0 otherwise. Sampled by the cosine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo per RGB channel.
    pub reflectance: DVec3,
}

impl Diffuse {
    /// `f(wo, wi)` without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return DVec3::ZERO;
        }
        self.reflectance * FRAC_1_PI
    }

    /// The density of [`Diffuse::sample`]: `cos(wi) / pi`.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 { 0.0 } else { cosine_pdf(wi) }
    }

    /// A cosine-distributed direction; its weight is the reflectance.
    pub fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_sample(u1, u2);
        let pdf = cosine_pdf(wi);
        if pdf <= 0.0 {
            return None;
        }
        Some(LocalSample { wi, weight: self.reflectance, pdf, delta: false, eta: 1.0 })
    }
}
