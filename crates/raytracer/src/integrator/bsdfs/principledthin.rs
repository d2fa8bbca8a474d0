//! `principledthin` (Mitsuba 3's `principledthin.cpp`): the Disney BSDF of a thin sheet
//! (Burley 2015), the same seen from both sides (a direction below is handled as its mirror
//! image above).
//!
//! With `wo` on the front, `h` the half vector of `wo` and `wi` mirrored to the front, `F` the
//! dielectric Fresnel reflectance at `wo . h` for the sheet's index `eta`, `st = spec_trans` and
//! `dt = diff_trans / 2`, Mitsuba's lobes are (`f`, without the cosine of `wi`):
//! - specular reflection (GGX of `roughness`): `st F_t D G / (4 cos_o cos_i)`, `F_t` blended from
//!   `F` towards a tinted Schlick reflectance by `spec_tint`;
//! - specular transmission (GGX of `(0.65 eta - 0.35) roughness`, the mirrored direction
//!   continuing through the sheet unbent): `st base_color (1 - F) D G / (4 cos_o |cos_i|)`;
//! - diffuse reflection: `(1 - st)(1 - dt) base_color / pi` times the Disney diffuse with
//!   retro-reflection and fake subsurface (`flatness`), plus the sheen;
//! - diffuse transmission: `(1 - st) dt base_color / pi`.
//!
//! Sampling picks the lobe with probabilities proportional to `st / 2`, `st / 2`,
//! `(1 - st)(1 - dt)`, `(1 - st) dt` times the sampling rates.

use std::f64::consts::FRAC_1_PI;

use glam::DVec3;

use super::LocalSample;
use super::fresnel::{fresnel_dielectric, reflect};
use super::microfacet::{MicrofacetDistribution, cosine_pdf, cosine_sample};
use super::principled::{
    disney_diffuse, ggx, mac_mic_compatible, schlick, schlick_r0, schlick_weight, sheen_colour,
};
use crate::base::color::luminance;

/// A `principledthin` BSDF with its parameters evaluated at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    /// Base colour, linear RGB.
    pub base_color: DVec3,
    /// `roughness` as given.
    pub roughness: f64,
    /// Weight of the specular lobes.
    pub spec_trans: f64,
    /// The sheet's relative index of refraction.
    pub eta: f64,
    /// Base-colour tint of the specular reflection.
    pub spec_tint: f64,
    /// Sheen weight.
    pub sheen: f64,
    /// Base-colour tint of the sheen.
    pub sheen_tint: f64,
    /// Diffuse to fake-subsurface blend.
    pub flatness: f64,
    /// Diffuse transmission, `diff_trans / 2` (in [0, 1]).
    pub diff_trans: f64,
    /// The reflection's GGX distribution.
    pub reflect_distr: MicrofacetDistribution,
    /// The transmission's GGX distribution (roughness scaled by `0.65 eta - 0.35`).
    pub transmit_distr: MicrofacetDistribution,
    /// Sampling rates: specular reflection, specular transmission, diffuse reflection, diffuse
    /// transmission.
    pub rates: [f64; 4],
}

impl PrincipledThin {
    /// A thin principled BSDF; `diff_trans` as given (in [0, 2]), `rates` as in
    /// [`PrincipledThin::rates`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        base_color: DVec3,
        roughness: f64,
        anisotropic: f64,
        spec_trans: f64,
        eta: f64,
        spec_tint: f64,
        sheen: f64,
        sheen_tint: f64,
        flatness: f64,
        diff_trans: f64,
        rates: [f64; 4],
    ) -> PrincipledThin {
        PrincipledThin {
            base_color,
            roughness,
            spec_trans,
            eta,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            diff_trans: diff_trans / 2.0,
            reflect_distr: ggx(anisotropic, roughness),
            transmit_distr: ggx(anisotropic, (0.65 * eta - 0.35) * roughness),
            rates,
        }
    }

    /// The normalised probabilities of the four lobes (all 0 when they sum to 0).
    fn choice(&self) -> [f64; 4] {
        let (st, dt) = (self.spec_trans, self.diff_trans);
        let p = [
            st * self.rates[0] / 2.0,
            st * self.rates[1] / 2.0,
            self.rates[2] * (1.0 - st) * (1.0 - dt),
            self.rates[3] * (1.0 - st) * dt,
        ];
        let total: f64 = p.iter().sum();
        if total.is_nan() || total <= 0.0 || !total.is_finite() {
            return [0.0; 4];
        }
        p.map(|x| x / total)
    }

    /// `(wo, wi)` seen from the front, and the half vector of `wo` and `wi` mirrored to the
    /// front.
    fn frame(wo: DVec3, wi: DVec3) -> Option<(DVec3, DVec3, DVec3)> {
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let (o, i) = (wo * s, wi * s);
        let h = (o + DVec3::new(i.x, i.y, i.z.abs())).normalize_or_zero();
        if h == DVec3::ZERO { None } else { Some((o, i, h)) }
    }

    /// `f(wo, wi)` without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return DVec3::ZERO;
        }
        let Some((o, i, h)) = Self::frame(wo, wi) else { return DVec3::ZERO };
        let (ci, co) = (o.z, i.z);
        let reflected = co > 0.0;
        let (st, dt) = (self.spec_trans, self.diff_trans);
        let mut value = DVec3::ZERO;
        if st > 0.0 && mac_mic_compatible(h, o, i, reflected) {
            let fr = fresnel_dielectric(o.dot(h), self.eta).r;
            if reflected {
                let lum = luminance(self.base_color);
                let tint = if lum > 0.0 { self.base_color / lum } else { DVec3::ONE };
                let f_schlick = schlick(tint * schlick_r0(self.eta), o.dot(h), self.eta);
                let f = DVec3::splat(fr) * (1.0 - self.spec_tint) + f_schlick * self.spec_tint;
                let d = self.reflect_distr.d(h);
                let g = self.reflect_distr.g(o, i, h);
                value += f * (st * d * g / (4.0 * ci));
            } else {
                let d = self.transmit_distr.d(h);
                let g = self.transmit_distr.g(o, i, h);
                value += self.base_color * (st * (1.0 - fr) * d * g / (4.0 * ci));
            }
        }
        if reflected && st < 1.0 && dt < 1.0 {
            let (diffuse, cos_d) = disney_diffuse(ci, co, h.dot(i), self.roughness, self.flatness);
            value += self.base_color * ((1.0 - st) * co * FRAC_1_PI * (1.0 - dt) * diffuse);
            if self.sheen > 0.0 {
                let sheen = sheen_colour(self.base_color, self.sheen_tint);
                value += sheen * (self.sheen * (1.0 - st) * schlick_weight(cos_d.abs()) * (1.0 - dt) * co);
            }
        }
        if !reflected && st < 1.0 && dt > 0.0 {
            value += self.base_color * ((1.0 - st) * dt * FRAC_1_PI * co.abs());
        }
        (value / co.abs()).max(DVec3::ZERO)
    }

    /// The density of [`PrincipledThin::sample`].
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((o, i, h)) = Self::frame(wo, wi) else { return 0.0 };
        let reflected = i.z > 0.0;
        let p = self.choice();
        let mut pdf = 0.0;
        if self.spec_trans > 0.0 && mac_mic_compatible(h, o, i, reflected) {
            let mirrored = DVec3::new(i.x, i.y, i.z.abs());
            let dh_dwi = (1.0 / (4.0 * mirrored.dot(h))).abs();
            if dh_dwi.is_finite() {
                pdf += if reflected {
                    p[0] * self.reflect_distr.pdf(o, h)
                } else {
                    p[1] * self.transmit_distr.pdf(o, h)
                } * dh_dwi;
            }
        }
        pdf += if reflected { p[2] * cosine_pdf(i) } else { p[3] * cosine_pdf(-i) };
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Draws `wi`: `u` chooses the lobe, `u1`, `u2` the direction.
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let o = wo * s;
        let p = self.choice();
        let i = if u < p[0] {
            let (m, _) = self.reflect_distr.sample(o, u1, u2);
            let i = reflect(o, m);
            if !(i.z > 0.0 && mac_mic_compatible(m, o, i, true)) {
                return None;
            }
            i
        } else if u < p[0] + p[1] {
            let (m, _) = self.transmit_distr.sample(o, u1, u2);
            let r = reflect(o, m);
            let i = DVec3::new(r.x, r.y, -r.z);
            if !(i.z < 0.0 && mac_mic_compatible(m, o, i, false)) {
                return None;
            }
            i
        } else if u < p[0] + p[1] + p[2] {
            cosine_sample(u1, u2)
        } else {
            -cosine_sample(u1, u2)
        };
        let wi = i * s;
        if wi.z == 0.0 || !wi.is_finite() {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let weight = self.eval(wo, wi) * wi.z.abs() / pdf;
        Some(LocalSample { wi, weight, pdf, delta: false, eta: 1.0 })
    }
}
