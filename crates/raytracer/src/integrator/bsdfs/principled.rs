//! `principled` (Mitsuba 3's `principled.cpp` and `principledhelpers.h`): the Disney BSDF
//! (Burley 2012, 2015) as Mitsuba defines it, from both sides.
//!
//! With `brdf = (1 - metallic)(1 - spec_trans)`, `bsdf = (1 - metallic) spec_trans`, `h` the
//! half vector (the generalised one for refraction, turned up) and `F` the dielectric Fresnel
//! reflectance at `wo . h` for the relative index `eta`, Mitsuba's lobes are (here written as `f`,
//! without the cosine of `wi`):
//! - main specular reflection (GGX, both sides): `F_p D G / (4 |cos_o| |cos_i|)` where, seen from
//!   the front, `F_p = (1 - metallic)(1 - spec_tint) F + metallic Schlick(base_color)
//!   + (1 - metallic) spec_tint Schlick(R0(eta) base_color / lum)`, and from the back
//!   `F_p = bsdf F`;
//! - specular transmission (GGX, both sides): Walter's BTDF times `sqrt(base_color) bsdf`, without
//!   the `eta^2` factor (Mitsuba's formula in radiance mode, whose `1 / eta^2` cancels it);
//! - clearcoat (front only): `0.25 clearcoat F_schlick(0.04) D_GTR1 G_cc` with Smith GGX masking
//!   of `alpha = 0.25` and no `1 / (4 cos cos)` (as Mitsuba);
//! - diffuse (front only): `brdf base_color / pi` times the Disney diffuse with retro-reflection,
//!   blended towards the Hanrahan-Krueger fake subsurface by `flatness`;
//! - sheen (front only, where `brdf > 0`): `sheen (1 - metallic) Schlick weight(cos_d)`, tinted.
//!
//! Sampling chooses the diffuse (cosine), clearcoat (GTR1 normals), transmission or reflection
//! (GGX visible normals) lobe with Mitsuba's probabilities (the sampling rates); the pdf is the
//! mixture's, so the weight is `f cos / pdf`.

use std::f64::consts::{FRAC_1_PI, PI, TAU};

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::{MicrofacetDistribution, cosine_pdf, cosine_sample};
use crate::base::color::luminance;
use crate::material::Distribution;

/// A `principled` BSDF with its parameters evaluated at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    /// Base colour, linear RGB.
    pub base_color: DVec3,
    /// `roughness` as given (the retro-reflection reads it).
    pub roughness: f64,
    /// Metal weight.
    pub metallic: f64,
    /// Transmission weight of the dielectric.
    pub spec_trans: f64,
    /// Base-colour tint of the dielectric reflection.
    pub spec_tint: f64,
    /// Sheen weight.
    pub sheen: f64,
    /// Base-colour tint of the sheen.
    pub sheen_tint: f64,
    /// Diffuse to fake-subsurface blend.
    pub flatness: f64,
    /// Clearcoat weight.
    pub clearcoat: f64,
    /// Clearcoat glossiness.
    pub clearcoat_gloss: f64,
    /// Relative index of refraction, inside over outside.
    pub eta: f64,
    /// The main specular lobes' GGX distribution (visible normals).
    pub distr: MicrofacetDistribution,
    /// `main_specular_sampling_rate`.
    pub specular_rate: f64,
    /// `clearcoat_sampling_rate`.
    pub clearcoat_rate: f64,
    /// `diffuse_reflectance_sampling_rate`.
    pub diffuse_rate: f64,
}

/// The probabilities of choosing each lobe (diffuse, clearcoat, transmission, reflection), for
/// a viewing direction on the front (or not) and the Fresnel reflectance `f` of the facet.
#[derive(Clone, Copy, Debug)]
struct LobeChoice {
    diffuse: f64,
    clearcoat: f64,
    transmit: f64,
    reflect: f64,
}

impl Principled {
    /// A principled BSDF; `roughness` and `anisotropic` give the GGX roughness as Mitsuba's
    /// `calc_dist_params`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        base_color: DVec3,
        roughness: f64,
        anisotropic: f64,
        metallic: f64,
        spec_trans: f64,
        spec_tint: f64,
        sheen: f64,
        sheen_tint: f64,
        flatness: f64,
        clearcoat: f64,
        clearcoat_gloss: f64,
        eta: f64,
        rates: [f64; 3],
    ) -> Principled {
        Principled {
            base_color,
            roughness,
            metallic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            eta,
            distr: ggx(anisotropic, roughness),
            specular_rate: rates[0],
            clearcoat_rate: rates[1],
            diffuse_rate: rates[2],
        }
    }

    fn brdf(&self) -> f64 {
        (1.0 - self.metallic) * (1.0 - self.spec_trans)
    }

    fn bsdf(&self) -> f64 {
        (1.0 - self.metallic) * self.spec_trans
    }

    /// Mitsuba's lobe probabilities, normalised (all 0 when they sum to 0).
    fn choice(&self, front: bool, f: f64) -> LobeChoice {
        let bsdf = self.bsdf();
        let c = if front {
            LobeChoice {
                diffuse: self.brdf() * self.diffuse_rate,
                clearcoat: 0.25 * self.clearcoat * self.clearcoat_rate,
                transmit: self.specular_rate * bsdf * (1.0 - f),
                reflect: self.specular_rate * (1.0 - bsdf * (1.0 - f)),
            }
        } else {
            LobeChoice { diffuse: 0.0, clearcoat: 0.0, transmit: 1.0 - f, reflect: f }
        };
        let total = c.diffuse + c.clearcoat + c.transmit + c.reflect;
        if total.is_nan() || total <= 0.0 || !total.is_finite() {
            return LobeChoice { diffuse: 0.0, clearcoat: 0.0, transmit: 0.0, reflect: 0.0 };
        }
        LobeChoice {
            diffuse: c.diffuse / total,
            clearcoat: c.clearcoat / total,
            transmit: c.transmit / total,
            reflect: c.reflect / total,
        }
    }

    /// The half vector of `wo`, `wi` (Mitsuba's), turned to +z, with the relative index of the
    /// path (`eta` from the front, `1 / eta` from the back); `None` when it is undefined.
    fn half_vector(&self, wo: DVec3, wi: DVec3) -> Option<(DVec3, f64)> {
        let eta_path = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let reflected = wo.z * wi.z > 0.0;
        let h = (wo + wi * if reflected { 1.0 } else { eta_path }).normalize_or_zero();
        if h == DVec3::ZERO {
            return None;
        }
        Some((if h.z < 0.0 { -h } else { h }, eta_path))
    }

    /// `f(wo, wi)` without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        let (ci, co) = (wo.z, wi.z);
        if ci == 0.0 || co == 0.0 {
            return DVec3::ZERO;
        }
        let Some((h, eta_path)) = self.half_vector(wo, wi) else { return DVec3::ZERO };
        let front = ci > 0.0;
        let reflected = ci * co > 0.0;
        let (brdf, bsdf) = (self.brdf(), self.bsdf());
        let oh = wo.dot(h);
        let ih = wi.dot(h);
        let fr = fresnel_dielectric(oh, self.eta).r;
        let compatible = mac_mic_compatible(h, wo, wi, reflected);
        let d = self.distr.d(h);
        let g = self.distr.g(wo, wi, h);
        // Mitsuba's value includes |cos wi|; divided out at the end.
        let mut value = DVec3::ZERO;
        if reflected && compatible && fr > 0.0 {
            let f = if front {
                let lum = luminance(self.base_color);
                let tint = if lum > 0.0 { self.base_color / lum } else { DVec3::ONE };
                let eta_it = if oh >= 0.0 { self.eta } else { 1.0 / self.eta };
                let metal = self.metallic * schlick(self.base_color, oh, self.eta);
                let tinted =
                    (1.0 - self.metallic) * self.spec_tint * schlick(tint * schlick_r0(eta_it), oh, self.eta);
                DVec3::splat((1.0 - self.metallic) * (1.0 - self.spec_tint) * fr) + metal + tinted
            } else {
                DVec3::splat(bsdf * fr)
            };
            value += f * (d * g / (4.0 * ci.abs()));
        }
        if !reflected && compatible && bsdf > 0.0 && fr < 1.0 {
            let denom = oh + eta_path * ih;
            let t = ((1.0 - fr) * d * g * oh * ih / (ci * denom * denom)).abs();
            value += self.base_color.max(DVec3::ZERO).powf(0.5) * (bsdf * t);
        }
        if reflected && compatible && front && self.clearcoat > 0.0 {
            let fcc = schlick(DVec3::splat(0.04), oh, self.eta).x;
            let dcc = gtr1_d(h, clearcoat_alpha(self.clearcoat_gloss));
            let gcc = smith_ggx1(wo, h, 0.25) * smith_ggx1(wi, h, 0.25);
            value += DVec3::splat(0.25 * self.clearcoat * fcc * dcc * gcc * co.abs());
        }
        if reflected && front && brdf > 0.0 {
            let (diffuse, cos_d) =
                disney_diffuse(ci.abs(), co.abs(), h.dot(wi), self.roughness, self.flatness);
            value += self.base_color * (brdf * co.abs() * FRAC_1_PI * diffuse);
            if self.sheen > 0.0 && 1.0 - self.metallic > 0.0 {
                let sheen = sheen_colour(self.base_color, self.sheen_tint);
                value +=
                    sheen * (self.sheen * (1.0 - self.metallic) * schlick_weight(cos_d.abs()) * co.abs());
            }
        }
        (value / co.abs()).max(DVec3::ZERO)
    }

    /// The density of [`Principled::sample`].
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        let (ci, co) = (wo.z, wi.z);
        if ci == 0.0 || co == 0.0 {
            return 0.0;
        }
        let front = ci > 0.0;
        // Seen from the back without transmission, nothing is sampled (Mitsuba's `sample`;
        // its `pdf` is not 0 there, where its `eval` is).
        if !front && (self.bsdf().is_nan() || self.bsdf() <= 0.0) {
            return 0.0;
        }
        let Some((h, eta_path)) = self.half_vector(wo, wi) else { return 0.0 };
        let reflected = ci * co > 0.0;
        let oh = wo.dot(h);
        let ih = wi.dot(h);
        let p = self.choice(front, fresnel_dielectric(oh, self.eta).r);
        let dh_dwi = if reflected {
            (1.0 / (4.0 * ih)).abs()
        } else {
            let denom = oh + eta_path * ih;
            (eta_path * eta_path * ih / (denom * denom)).abs()
        };
        if !dh_dwi.is_finite() {
            return 0.0;
        }
        let compatible = mac_mic_compatible(h, wo, wi, reflected);
        let wo_up = if front { wo } else { -wo };
        let mut pdf = 0.0;
        if reflected {
            pdf += p.diffuse * cosine_pdf(wi);
            if compatible {
                pdf += p.reflect * self.distr.pdf(wo_up, h) * dh_dwi;
                if p.clearcoat > 0.0 {
                    pdf += p.clearcoat * gtr1_pdf(h, clearcoat_alpha(self.clearcoat_gloss)) * dh_dwi;
                }
            }
        } else if compatible {
            pdf += p.transmit * self.distr.pdf(wo_up, h) * dh_dwi;
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Draws `wi`: `u` chooses the lobe, `u1`, `u2` the direction (and the GGX normal that
    /// sets the Fresnel split between reflection and transmission, as Mitsuba).
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        let ci = wo.z;
        if ci == 0.0 {
            return None;
        }
        let front = ci > 0.0;
        if !front && (self.bsdf().is_nan() || self.bsdf() <= 0.0) {
            return None;
        }
        let wo_up = if front { wo } else { -wo };
        let (m, _) = self.distr.sample(wo_up, u1, u2);
        let fr = fresnel_dielectric(wo.dot(m), self.eta);
        let p = self.choice(front, fr.r);
        let mut eta = 1.0;
        let wi = if u < p.diffuse {
            cosine_sample(u1, u2)
        } else if u < p.diffuse + p.clearcoat {
            let mcc = gtr1_sample(clearcoat_alpha(self.clearcoat_gloss), u1, u2);
            let wi = reflect(wo, mcc);
            if !(ci * wi.z > 0.0 && mac_mic_compatible(mcc, wo, wi, true)) {
                return None;
            }
            wi
        } else if u < p.diffuse + p.clearcoat + p.transmit {
            let wi = refract(wo, m, fr.cos_t, fr.eta_ti);
            if !(ci * wi.z < 0.0 && mac_mic_compatible(m, wo, wi, false)) {
                return None;
            }
            eta = fr.eta_it;
            wi
        } else {
            let wi = reflect(wo, m);
            if !(ci * wi.z > 0.0 && mac_mic_compatible(m, wo, wi, true)) {
                return None;
            }
            wi
        };
        if !(wi.z * ci != 0.0) || !wi.is_finite() {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z.abs() / pdf;
        Some(LocalSample { wi, weight, pdf, delta: false, eta })
    }
}

/// The GGX distribution of `roughness` and `anisotropic` (Mitsuba's `calc_dist_params`:
/// `alpha = roughness^2`, stretched by `sqrt(1 - 0.9 anisotropic)`, at least 0.001), sampling
/// visible normals.
pub(super) fn ggx(anisotropic: f64, roughness: f64) -> MicrofacetDistribution {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).max(0.0).sqrt();
    let (ax, ay) = if aspect > 0.0 { (r2 / aspect, r2 * aspect) } else { (r2, r2) };
    let clamp = |a: f64| if a.is_nan() { 0.001 } else { a.max(0.001) };
    MicrofacetDistribution::new(Distribution::Ggx, clamp(ax), clamp(ay), true)
}

/// Whether the facet of normal `m` (turned to +z) lets `wo` reach `wi` (Mitsuba's
/// `mac_mic_compatibility`): both on the facet's side of `wo` for a reflection, on opposite
/// sides for a transmission.
pub(super) fn mac_mic_compatible(m: DVec3, wo: DVec3, wi: DVec3, reflection: bool) -> bool {
    let m = if wo.z >= 0.0 { m } else { -m };
    wo.dot(m) > 0.0 && if reflection { wi.dot(m) > 0.0 } else { wi.dot(-m) > 0.0 }
}

/// Schlick's weight `(1 - cos)^5`, `cos` clamped to [0, 1].
pub(super) fn schlick_weight(cos: f64) -> f64 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// Schlick's reflectance at normal incidence for a relative index `eta`.
pub(super) fn schlick_r0(eta: f64) -> f64 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// Schlick's approximation `R0 + (1 - R0) (1 - cos)^5` at the cosine `cos_i` on the side of
/// relative index `eta` (Mitsuba's `calc_schlick`: the transmitted cosine is used where the
/// ray enters the optically thinner side).
pub(super) fn schlick(r0: DVec3, cos_i: f64, eta: f64) -> DVec3 {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let cos_t_sqr = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
        schlick_weight(cos_t_sqr.max(0.0).sqrt())
    };
    r0 + (DVec3::ONE - r0) * w
}

/// The Disney diffuse factor (times `pi / base_color`) with retro-reflection, blended by
/// `flatness` towards Hanrahan-Krueger's fake subsurface; returns it and `cos_d = h . wi`.
/// `cos_a`, `cos_b` are the absolute cosines of the two directions (the factor is symmetric in
/// them).
pub(super) fn disney_diffuse(
    cos_a: f64,
    cos_b: f64,
    cos_d: f64,
    roughness: f64,
    flatness: f64,
) -> (f64, f64) {
    let (cos_o, cos_i) = (cos_a, cos_b);
    let fo = schlick_weight(cos_i);
    let fi = schlick_weight(cos_o);
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    let fss90 = rr / 2.0;
    let fss = (1.0 + (fss90 - 1.0) * fo) * (1.0 + (fss90 - 1.0) * fi);
    let f_ss = 1.25 * (fss * (1.0 / (cos_i + cos_o) - 0.5) + 0.5);
    ((f_diff + f_retro) * (1.0 - flatness) + f_ss * flatness, cos_d)
}

/// The sheen's colour: white tinted towards the base colour's hue by `tint`.
pub(super) fn sheen_colour(base: DVec3, tint: f64) -> DVec3 {
    let lum = luminance(base);
    let c = if lum > 0.0 { base / lum } else { DVec3::ONE };
    DVec3::ONE * (1.0 - tint) + c * tint
}

/// The clearcoat's GTR1 roughness: 0.1 at gloss 0 to 0.001 at gloss 1 (kept inside (0, 1)).
fn clearcoat_alpha(gloss: f64) -> f64 {
    let a = 0.1 * (1.0 - gloss) + 0.001 * gloss;
    if a.is_nan() { 0.1 } else { a.abs().clamp(1e-4, 0.9999) }
}

/// Burley's GTR1 (Berry) distribution of normals (`integral D cos = 1`).
fn gtr1_d(m: DVec3, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let c2 = m.z * m.z;
    let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c2));
    if d * m.z > 1e-20 { d } else { 0.0 }
}

/// The density of [`gtr1_sample`]: `D(m) cos`.
fn gtr1_pdf(m: DVec3, alpha: f64) -> f64 {
    if m.z < 0.0 { 0.0 } else { m.z * gtr1_d(m, alpha) }
}

/// A GTR1 normal (Mitsuba: `u1` the azimuth, `u2` the polar angle).
fn gtr1_sample(alpha: f64, u1: f64, u2: f64) -> DVec3 {
    let a2 = alpha * alpha;
    let (s, c) = (TAU * u1).sin_cos();
    let cos2 = (1.0 - a2.powf(1.0 - u2)) / (1.0 - a2);
    let sin_t = (1.0 - cos2).max(0.0).sqrt();
    DVec3::new(c * sin_t, s * sin_t, cos2.max(0.0).sqrt())
}

/// Smith's GGX masking with a fixed `alpha` (the clearcoat's, Mitsuba's `smith_ggx1`).
fn smith_ggx1(v: DVec3, h: DVec3, alpha: f64) -> f64 {
    if v.dot(h) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}
