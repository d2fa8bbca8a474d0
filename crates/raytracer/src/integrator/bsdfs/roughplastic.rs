//! `roughplastic` (Mitsuba 3's `roughplastic.cpp`): a diffuse base under a rough dielectric
//! coating, one-sided, isotropic.
//!
//! As Mitsuba, the diffuse term is weighted by the coating's rough transmittance `T(cos)` in
//! both directions, tabulated once per (distribution, alpha, eta) over 64 cosines and
//! interpolated linearly, and the base's albedo is divided by `1 - R_int` (or `1 - d R_int`
//! with `nonlinear`), `R_int` the coating's hemispherical internal reflectance. Both are
//! integrals of the microfacet model computed here as Mitsuba computes them
//! (`eval_transmittance`, `eval_reflectance`: Gauss-Legendre quadrature over the visible-normal
//! sample space, 32 x 32 nodes, 128 x 128 when the index ratio is below 1), and cached for
//! the process.

use std::collections::HashMap;
use std::f64::consts::FRAC_1_PI;
use std::sync::{Arc, OnceLock, RwLock};

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::{MicrofacetDistribution, cosine_pdf, cosine_sample};
use super::plastic::sampling_weight;
use crate::material::Distribution;

/// Number of cosines of the transmittance table (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TABLE_RES: usize = 64;

/// The coating's precomputed integrals.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatingTable {
    /// Rough transmittance from outside at the cosines `max(1e-6, i / 63)`.
    pub external_transmittance: [f64; TABLE_RES],
    /// Hemispherical (cosine-weighted) reflectance of the coating from inside.
    pub internal_reflectance: f64,
}

impl CoatingTable {
    /// Computes the table for a distribution (visible-normal sampling is always used for the
    /// integration) and a relative index `eta`.
    pub fn compute(kind: Distribution, alpha: f64, eta: f64) -> CoatingTable {
        let distr = MicrofacetDistribution::new(kind, alpha, alpha, true);
        let mut external_transmittance = [0.0; TABLE_RES];
        let mut internal = 0.0;
        let outside = Quadrature::for_eta(eta);
        let inside = Quadrature::for_eta(1.0 / eta);
        for (i, t) in external_transmittance.iter_mut().enumerate() {
            let mu = (i as f64 / (TABLE_RES - 1) as f64).max(1e-6);
            let wi = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            *t = coating_transmittance(&distr, wi, eta, &outside);
            internal += coating_reflectance(&distr, wi, 1.0 / eta, &inside) * mu;
        }
        CoatingTable { external_transmittance, internal_reflectance: internal * 2.0 / TABLE_RES as f64 }
    }

    /// The external transmittance at the cosine `mu`, linearly interpolated.
    pub fn transmittance(&self, mu: f64) -> f64 {
        let x = mu.clamp(0.0, 1.0) * (TABLE_RES - 1) as f64;
        let i = (x as usize).min(TABLE_RES - 2);
        let w = x - i as f64;
        (1.0 - w) * self.external_transmittance[i] + w * self.external_transmittance[i + 1]
    }

    /// The table for these parameters, from the process's cache (computed on first use; a
    /// table depends only on its parameters, so sharing it between threads and renders changes
    /// no value). Renders create their own thread pools, so a per-thread cache would compute
    /// every table again for each one.
    pub fn cached(kind: Distribution, alpha: f64, eta: f64) -> Arc<CoatingTable> {
        type Key = (u8, u64, u64);
        static CACHE: OnceLock<RwLock<HashMap<Key, Arc<CoatingTable>>>> = OnceLock::new();
        let cache = CACHE.get_or_init(Default::default);
        let key = (kind as u8, alpha.to_bits(), eta.to_bits());
        if let Some(t) = cache.read().ok().and_then(|c| c.get(&key).cloned()) {
            return t;
        }
        let table = Arc::new(CoatingTable::compute(kind, alpha, eta));
        if let Ok(mut c) = cache.write() {
            // Bounded: a textured roughness would otherwise fill it without end.
            if c.len() >= 256 {
                c.clear();
            }
            c.entry(key).or_insert_with(|| Arc::clone(&table));
        }
        table
    }
}

/// A Gauss-Legendre rule on [0, 1]: nodes and weights.
#[derive(Clone, Debug)]
pub struct Quadrature(Vec<(f64, f64)>);

impl Quadrature {
    /// Mitsuba's resolution for an index ratio `eta`: 32 nodes above 1, 128 otherwise (total
    /// internal reflection makes the integrand steeper).
    pub fn for_eta(eta: f64) -> Quadrature {
        Quadrature(gauss_legendre(if eta > 1.0 { 32 } else { 128 }))
    }
}

/// Gauss-Legendre nodes and weights on [0, 1].
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Newton on P_n from Tricomi's initial guess.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (x + 1.0), 0.5 * w));
    }
    out
}

/// `integral over the visible-normal sample space of g(m)`, Mitsuba's resolution rule.
fn integrate_visible(
    distr: &MicrofacetDistribution,
    wi: DVec3,
    rule: &Quadrature,
    g: impl Fn(DVec3) -> f64,
) -> f64 {
    let mut sum = 0.0;
    for &(u1, w1) in &rule.0 {
        for &(u2, w2) in &rule.0 {
            let (m, _) = distr.sample(wi, u1, u2);
            sum += w1 * w2 * g(m);
        }
    }
    sum
}

/// Directional albedo of the rough dielectric's reflection (`F D G / (4 cos_i)` integrated),
/// as `E[F(wi.m) G1(wo, m)]` over visible normals (Mitsuba's `eval_reflectance`).
pub fn coating_reflectance(distr: &MicrofacetDistribution, wi: DVec3, eta: f64, rule: &Quadrature) -> f64 {
    integrate_visible(distr, wi, rule, |m| {
        let wo = reflect(wi, m);
        if wo.z <= 0.0 {
            return 0.0;
        }
        fresnel_dielectric(wi.dot(m), eta).r * distr.g1(wo, m)
    })
}

/// Directional transmittance of the rough dielectric (energy, no radiance scaling), as
/// `E[(1 - F(wi.m)) G1(wt, m)]` over visible normals (Mitsuba's `eval_transmittance`).
pub fn coating_transmittance(distr: &MicrofacetDistribution, wi: DVec3, eta: f64, rule: &Quadrature) -> f64 {
    integrate_visible(distr, wi, rule, |m| {
        let f = fresnel_dielectric(wi.dot(m), eta);
        let wt = refract(wi, m, f.cos_t, f.eta_ti);
        if wt.z * wi.z >= 0.0 {
            return 0.0;
        }
        (1.0 - f.r) * distr.g1(wt, m)
    })
}

/// A rough plastic: specular microfacet reflection off the coating
/// `F(wo.h) D G / (4 cos_o cos_i) specular_reflectance`, and the diffuse term
/// `d' T(cos_o) T(cos_i) / (pi eta^2)` with `d' = d / (1 - R_int)` (or `d / (1 - d R_int)`).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlastic {
    /// `int_ior / ext_ior` of the coating.
    pub eta: f64,
    /// The base's albedo as the coating scatters it (`d'`).
    pub diffuse: DVec3,
    /// The base's albedo as given (`d`).
    pub base: DVec3,
    /// The coating's tint.
    pub specular: DVec3,
    /// The coating's microfacets (isotropic).
    pub distr: MicrofacetDistribution,
    /// See [`super::plastic::Plastic::specular_sampling_weight`].
    pub specular_sampling_weight: f64,
    /// The coating's integrals.
    pub table: Arc<CoatingTable>,
}

impl RoughPlastic {
    /// A rough plastic; the table comes from the cache.
    pub fn new(
        eta: f64,
        base: DVec3,
        specular: DVec3,
        nonlinear: bool,
        distr: MicrofacetDistribution,
    ) -> RoughPlastic {
        let table = CoatingTable::cached(distr.kind, distr.alpha_u, eta);
        let r = table.internal_reflectance;
        let denom = if nonlinear { DVec3::ONE - base * r } else { DVec3::splat(1.0 - r) };
        RoughPlastic {
            eta,
            diffuse: base / denom.max(DVec3::splat(1e-12)),
            base,
            specular,
            distr,
            specular_sampling_weight: sampling_weight(base, specular),
            table,
        }
    }

    fn prob_specular(&self, cos_o: f64) -> f64 {
        let t = self.table.transmittance(cos_o);
        let s = (1.0 - t) * self.specular_sampling_weight;
        let d = t * (1.0 - self.specular_sampling_weight);
        if s + d > 0.0 { s / (s + d) } else { 0.0 }
    }

    /// `f(wo, wi)` without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return DVec3::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.d(h);
        let spec = if d > 0.0 {
            let f = fresnel_dielectric(wo.dot(h), self.eta).r;
            f * d * self.distr.g(wo, wi, h) / (4.0 * wo.z * wi.z)
        } else {
            0.0
        };
        let t = self.table.transmittance(wo.z) * self.table.transmittance(wi.z);
        self.specular * spec + self.diffuse * (t * FRAC_1_PI / (self.eta * self.eta))
    }

    /// The density of [`RoughPlastic::sample`].
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p = self.prob_specular(wo.z);
        let h = (wo + wi).normalize();
        let spec = self.distr.pdf(wo, h) / (4.0 * wi.dot(h));
        p * spec + (1.0 - p) * cosine_pdf(wi)
    }

    /// The specular lobe (probability from the coating's reflectance and the sampling weight)
    /// or the cosine-distributed diffuse one.
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u < self.prob_specular(wo.z) {
            let (m, _) = self.distr.sample(wo, u1, u2);
            reflect(wo, m)
        } else {
            cosine_sample(u1, u2)
        };
        if wi.z <= 0.0 {
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
