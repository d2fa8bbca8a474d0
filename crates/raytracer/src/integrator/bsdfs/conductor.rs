//! `conductor` and `roughconductor` (Mitsuba 3's `conductor.cpp`, `roughconductor.cpp`): metal
//! reflection with the complex Fresnel equations per RGB channel, one-sided.

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_conductor, reflect, reflect_z};
use super::microfacet::MicrofacetDistribution;

/// A smooth metal: a perfect mirror weighted by the conductor's Fresnel reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the relative index, per channel.
    pub eta: DVec3,
    /// Imaginary part, per channel.
    pub k: DVec3,
    /// The tint `specular_reflectance`.
    pub tint: DVec3,
}

impl Conductor {
    /// The mirror direction, weight `F(cos) tint`.
    pub fn sample(&self, wo: DVec3) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = self.tint * fresnel_conductor(wo.z, self.eta, self.k);
        Some(LocalSample { wi: reflect_z(wo), weight, pdf: 1.0, delta: true, eta: 1.0 })
    }

    /// The reflectance at normal incidence times the tint (a denoiser albedo).
    pub fn albedo(&self) -> DVec3 {
        self.tint * fresnel_conductor(1.0, self.eta, self.k)
    }
}

/// A rough metal: Cook-Torrance reflection `F(wo.h) D(h) G(wo, wi, h) / (4 cos_o cos_i)`
/// (Smith's separable G), sampled by the distribution (visible normals by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// The metal.
    pub metal: Conductor,
    /// The microfacets.
    pub distr: MicrofacetDistribution,
}

impl RoughConductor {
    /// `f(wo, wi)` without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return DVec3::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.d(h);
        if d == 0.0 {
            return DVec3::ZERO;
        }
        let g = self.distr.g(wo, wi, h);
        let f = fresnel_conductor(wo.dot(h), self.metal.eta, self.metal.k);
        self.metal.tint * f * (d * g / (4.0 * wo.z * wi.z))
    }

    /// The density of [`RoughConductor::sample`] per steradian of `wi`.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let dot = wi.dot(h);
        if dot <= 0.0 {
            return 0.0;
        }
        self.distr.pdf(wo, h) / (4.0 * dot)
    }

    /// Reflects `wo` about a sampled microfacet normal.
    pub fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (m, _) = self.distr.sample(wo, u1, u2);
        if wo.dot(m) <= 0.0 {
            return None;
        }
        let wi = reflect(wo, m);
        if wi.z <= 0.0 || wi.dot(m) <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z / pdf;
        Some(LocalSample { wi, weight, pdf, delta: false, eta: 1.0 })
    }
}
