//! The material lobes of the physically based models (spec section 11, made exact), shared by the
//! path tracer and SPPM.
//!
//! A material's weights `diff`, `spec`, `refl`, `refr` (each taken as at least 0) are divided by
//! their sum when it exceeds 1, so the lobes mix with total weight at most 1; the rest is
//! absorbed. With `c` the surface colour (`color=` times the texture, clamped to [0, 1]):
//! - `diff`: a Lambertian lobe of albedo `diff c` (`f = diff c / pi`);
//! - `spec`: a GGX microfacet reflection lobe (perfectly reflecting facets, separable Smith
//!   shadowing) of roughness [`SPEC_ALPHA`] `= sqrt(2 / (SPEC_POWER + 2))`, the roughness whose
//!   lobe matches a Phong lobe of exponent `SPEC_POWER = 20` (Walter et al. 2007), tinted `spec c`;
//! - `refl`: a perfect mirror tinted `refl c` when `drefl = 0`, otherwise a GGX lobe of roughness
//!   `drefl / 4` ([`DREFL_ALPHA_PER_UNIT`]), about the spread of the course's glossy lobe;
//! - `refr`: a smooth dielectric interface of relative index `rindex` (outside is vacuum), weight
//!   `refr`, untinted: Fresnel reflection `F` and transmission `1 - F` (total internal reflection
//!   past the critical angle); radiance crossing it is scaled by `1 / eta^2`.
//!
//! Every lobe reflects at most what it receives (the GGX lobes lose the energy of facets that
//! shadow each other, as single-scattering microfacet models do), and so does their mix.
//! Surfaces are two-sided: both faces reflect alike, with the normal turned towards the viewer.
//! On a transparent material (`refr > 0`) only the outside face carries the `diff`, `spec` and
//! `refl` lobes: seen from inside, only the dielectric interface acts (weight `refr`), and the
//! rest is absorbed.
//!
//! Directions are world-space unit vectors; `wo` points from the surface towards the viewer (or
//! the previous vertex), `wi` towards where light comes from (or the next vertex).

use std::f64::consts::{FRAC_1_PI, PI};

use glam::DVec3;

use crate::base::color::channel_mean;

use crate::base::sampling::{cosine_hemisphere_pdf, orthonormal_basis};
use crate::material::CourseMaterial;
use crate::prepare::Interaction;

/// GGX roughness of the `spec` lobe: `sqrt(2 / (SPEC_POWER + 2))`.
pub const SPEC_ALPHA: f64 = 0.301_511_344_577_763_6;
/// GGX roughness of a glossy `refl` lobe per unit of `drefl`.
pub const DREFL_ALPHA_PER_UNIT: f64 = 0.25;
/// The smallest GGX roughness (smaller `drefl` values are clamped to it).
pub const MIN_ALPHA: f64 = 1e-3;

/// Which way quantities flow along a path: radiance (camera paths) or importance (photons).
/// Only refraction tells them apart: radiance is scaled by `1 / eta^2` when crossing an
/// interface, importance is not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths.
    Radiance,
    /// Light paths (photons).
    Importance,
}

/// Lobe classes, as a bit set: which lobes a query or a sample may use.
pub mod class {
    /// The Lambertian lobe.
    pub const DIFFUSE: u8 = 1;
    /// The GGX lobes (`spec`, and `refl` with `drefl > 0`).
    pub const GLOSSY: u8 = 2;
    /// The delta lobes (a perfect mirror, the dielectric interface).
    pub const SPECULAR: u8 = 4;
    /// Every lobe.
    pub const ALL: u8 = 7;
    /// The lobes with a density (diffuse and glossy).
    pub const SMOOTH: u8 = DIFFUSE | GLOSSY;
}

/// Index of each lobe in a [`Bsdf`].
const DIFFUSE: usize = 0;
const SPEC: usize = 1;
const REFL: usize = 2;
const REFR: usize = 3;

/// The lobes of a material at one surface point, in the local frame of the normal facing the
/// viewer.
#[derive(Clone, Debug)]
pub struct Bsdf {
    /// The normal on the viewer's side and two tangents: the local frame `(t, b, n)`.
    n: DVec3,
    t: DVec3,
    b: DVec3,
    /// Each lobe's weight times its tint (the dielectric's is grey).
    tint: [DVec3; 4],
    /// The `refl` lobe's GGX roughness; 0 for a perfect mirror.
    refl_alpha: f64,
    /// Refractive index of the far side over the near side (`rindex` entering, `1 / rindex`
    /// leaving).
    eta: f64,
    /// Relative probability of choosing each lobe when sampling (its mean tint).
    choose: [f64; 4],
    /// The class of each lobe ([`class`]); 0 for a lobe that does not scatter.
    classes: [u8; 4],
}

/// A direction sampled from a [`Bsdf`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit direction, world space.
    pub wi: DVec3,
    /// `f cos / pdf`: the factor the path's throughput takes.
    pub weight: DVec3,
    /// The density the direction was drawn with (per steradian; 0 for a delta lobe).
    pub pdf: f64,
    /// Whether a delta lobe (mirror, dielectric) produced it.
    pub delta: bool,
    /// Whether it crossed the surface (refraction).
    pub transmitted: bool,
    /// `eta^2` when the direction was refracted, 1 otherwise (for Russian roulette).
    pub eta_scale: f64,
}

/// Two directions in a [`Bsdf`]'s local frame (see [`Bsdf::local_pair`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalPair {
    /// The direction towards the viewer.
    o: DVec3,
    /// The direction towards the light.
    i: DVec3,
}

/// The class of each lobe, given whether the mirror is rough.
#[inline]
fn class_of(lobe: usize, rough_mirror: bool) -> u8 {
    match lobe {
        DIFFUSE => class::DIFFUSE,
        SPEC => class::GLOSSY,
        REFL if rough_mirror => class::GLOSSY,
        _ => class::SPECULAR,
    }
}

impl Bsdf {
    /// The lobes of `material` with surface colour `colour` (texture applied) at `at`.
    pub fn new(material: &CourseMaterial, colour: DVec3, at: &Interaction) -> Bsdf {
        let mut w = [material.diff, material.spec, material.refl, material.refr].map(|w| w.max(0.0));
        let sum: f64 = w.iter().sum();
        if sum > 1.0 {
            w = w.map(|x| x / sum);
        }
        if !at.front && w[REFR] > 0.0 {
            // Inside a transparent object only the interface acts.
            w = [0.0, 0.0, 0.0, w[REFR]];
        }
        let c = colour.clamp(DVec3::ZERO, DVec3::ONE);
        let tint = [c * w[DIFFUSE], c * w[SPEC], c * w[REFL], DVec3::splat(w[REFR])];
        let eta = if material.refr > 0.0 && material.rindex > 0.0 {
            if at.front { material.rindex } else { 1.0 / material.rindex }
        } else {
            1.0
        };
        let refl_alpha = if material.drefl > 0.0 {
            (material.drefl * DREFL_ALPHA_PER_UNIT).clamp(MIN_ALPHA, 1.0)
        } else {
            0.0
        };
        let (t, b) = orthonormal_basis(at.normal);
        let choose = tint.map(channel_mean);
        let classes =
            std::array::from_fn(|l| if choose[l] > 0.0 { class_of(l, refl_alpha > 0.0) } else { 0 });
        Bsdf { n: at.normal, t, b, tint, refl_alpha, eta, choose, classes }
    }

    /// Whether any lobe of the classes `set` can scatter light.
    #[inline]
    pub fn has(&self, set: u8) -> bool {
        self.classes.iter().any(|c| c & set != 0)
    }

    /// The albedo of the diffuse lobe (`diff c`, normalised).
    #[inline]
    pub fn diffuse_albedo(&self) -> DVec3 {
        self.tint[DIFFUSE]
    }

    /// The reflectance of the lobes with a density (diffuse and glossy): the sum of their tints
    /// (weight times colour), each channel in [0, 1]. A denoiser's albedo at this surface.
    #[inline]
    pub fn smooth_albedo(&self) -> DVec3 {
        (0..4)
            .filter(|&l| self.in_set(l, class::SMOOTH))
            .map(|l| self.tint[l])
            .sum::<DVec3>()
            .clamp(DVec3::ZERO, DVec3::ONE)
    }

    /// The probability that [`Bsdf::sample`] over `set` picks a lobe of the classes `of`.
    pub fn class_probability(&self, set: u8, of: u8) -> f64 {
        let total = self.choice_total(set);
        if total <= 0.0 {
            return 0.0;
        }
        (0..4).filter(|&l| self.in_set(l, set & of)).map(|l| self.choose[l]).sum::<f64>() / total
    }

    #[inline]
    fn in_set(&self, lobe: usize, set: u8) -> bool {
        self.classes[lobe] & set != 0
    }

    #[inline]
    fn choice_total(&self, set: u8) -> f64 {
        (0..4).filter(|&l| self.in_set(l, set)).map(|l| self.choose[l]).sum()
    }

    #[inline]
    fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    #[inline]
    fn to_world(&self, v: DVec3) -> DVec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }

    /// The BSDF value `f(wo, wi)` of the lobes of `set` with a density (delta lobes give 0).
    pub fn eval(&self, wo: DVec3, wi: DVec3, set: u8) -> DVec3 {
        self.eval_local(self.to_local(wo), self.to_local(wi), set)
    }

    /// [`Bsdf::eval`] of the local directions `o` and `i`.
    #[inline]
    fn eval_local(&self, o: DVec3, i: DVec3, set: u8) -> DVec3 {
        if o.z <= 0.0 || i.z <= 0.0 {
            return DVec3::ZERO;
        }
        let mut f = DVec3::ZERO;
        if self.in_set(DIFFUSE, set) {
            f += self.tint[DIFFUSE] * FRAC_1_PI;
        }
        if self.in_set(SPEC, set) {
            f += self.tint[SPEC] * ggx_f(o, i, SPEC_ALPHA);
        }
        if self.refl_alpha > 0.0 && self.in_set(REFL, set) {
            f += self.tint[REFL] * ggx_f(o, i, self.refl_alpha);
        }
        f
    }

    /// The pair of directions `wo`, `wi` in the BSDF's local frame, for [`Bsdf::eval_pair`] and
    /// [`Bsdf::pdf_pair`]: next-event estimation asks for both at the same pair.
    #[inline]
    pub fn local_pair(&self, wo: DVec3, wi: DVec3) -> LocalPair {
        LocalPair { o: self.to_local(wo), i: self.to_local(wi) }
    }

    /// [`Bsdf::eval`] at a pair of directions made by [`Bsdf::local_pair`] (the same value).
    #[inline]
    pub fn eval_pair(&self, pair: &LocalPair, set: u8) -> DVec3 {
        self.eval_local(pair.o, pair.i, set)
    }

    /// [`Bsdf::pdf`] at a pair of directions made by [`Bsdf::local_pair`] (the same value).
    #[inline]
    pub fn pdf_pair(&self, pair: &LocalPair, set: u8) -> f64 {
        self.pdf_local(pair.o, pair.i, set, self.choice_total(set))
    }

    /// The density with which [`Bsdf::sample`] over `set` draws `wi` (per steradian; delta lobes
    /// are not counted).
    pub fn pdf(&self, wo: DVec3, wi: DVec3, set: u8) -> f64 {
        self.pdf_local(self.to_local(wo), self.to_local(wi), set, self.choice_total(set))
    }

    /// [`Bsdf::pdf`] of the local directions `o` and `i`, with `total = choice_total(set)`.
    #[inline]
    fn pdf_local(&self, o: DVec3, i: DVec3, set: u8, total: f64) -> f64 {
        if total <= 0.0 || o.z <= 0.0 || i.z <= 0.0 {
            return 0.0;
        }
        let mut pdf = 0.0;
        if self.in_set(DIFFUSE, set) {
            pdf += self.choose[DIFFUSE] * cosine_hemisphere_pdf(i.z);
        }
        if self.in_set(SPEC, set) {
            pdf += self.choose[SPEC] * ggx_pdf(o, i, SPEC_ALPHA);
        }
        if self.refl_alpha > 0.0 && self.in_set(REFL, set) {
            pdf += self.choose[REFL] * ggx_pdf(o, i, self.refl_alpha);
        }
        pdf / total
    }

    /// Draws a direction from the lobes of `set`: a lobe chosen with probability proportional
    /// to its mean tint (by `u_lobe`), then a direction from it (by `u1`, `u2`). A direction of
    /// a lobe with a density is weighted against the mixture of all lobes of `set` with one (the
    /// one-sample model); a delta lobe's by its choice probability. `None` when the set has no
    /// lobe or the direction falls below the surface.
    pub fn sample(
        &self,
        wo: DVec3,
        u_lobe: f64,
        u1: f64,
        u2: f64,
        set: u8,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let total = self.choice_total(set);
        let o = self.to_local(wo);
        if total <= 0.0 || o.z <= 0.0 {
            return None;
        }
        let mut target = u_lobe * total;
        let mut lobe = REFR;
        let mut last = None;
        for l in 0..4 {
            if self.in_set(l, set) {
                last = Some(l);
                if target < self.choose[l] {
                    lobe = l;
                    last = None;
                    break;
                }
                target -= self.choose[l];
            }
        }
        if let Some(l) = last {
            lobe = l; // rounding left `target` at the end
        }
        let p_lobe = self.choose[lobe] / total;
        let i = match lobe {
            DIFFUSE => cosine_local(u1, u2),
            SPEC => ggx_sample(o, SPEC_ALPHA, u1, u2),
            REFL if self.refl_alpha > 0.0 => ggx_sample(o, self.refl_alpha, u1, u2),
            REFL => {
                let wi = self.to_world(DVec3::new(-o.x, -o.y, o.z));
                let weight = self.tint[REFL] / p_lobe;
                return Some(BsdfSample {
                    wi,
                    weight,
                    pdf: 0.0,
                    delta: true,
                    transmitted: false,
                    eta_scale: 1.0,
                });
            }
            _ => return Some(self.sample_dielectric(o, u1, p_lobe, mode)),
        };
        if i.z <= 0.0 {
            return None;
        }
        let wi = self.to_world(i);
        // As `pdf(wo, wi, set)` and `eval(wo, wi, set)`, sharing their local frame work.
        let back = self.to_local(wi);
        let pdf = self.pdf_local(o, back, set, total);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval_local(o, back, set) * (i.z / pdf);
        Some(BsdfSample { wi, weight, pdf, delta: false, transmitted: false, eta_scale: 1.0 })
    }

    /// Reflection with probability `F`, refraction otherwise, by `u`.
    fn sample_dielectric(&self, o: DVec3, u: f64, p_lobe: f64, mode: Transport) -> BsdfSample {
        let f = fresnel_dielectric(o.z, self.eta);
        let weight = self.tint[REFR] / p_lobe;
        if u < f {
            return BsdfSample {
                wi: self.to_world(DVec3::new(-o.x, -o.y, o.z)),
                weight,
                pdf: 0.0,
                delta: true,
                transmitted: false,
                eta_scale: 1.0,
            };
        }
        let cos_t = refracted_cos(o.z, self.eta).unwrap_or(0.0);
        let i = DVec3::new(-o.x / self.eta, -o.y / self.eta, -cos_t);
        let scale = match mode {
            Transport::Radiance => 1.0 / (self.eta * self.eta),
            Transport::Importance => 1.0,
        };
        BsdfSample {
            wi: self.to_world(i).normalize(),
            weight: weight * scale,
            pdf: 0.0,
            delta: true,
            transmitted: true,
            eta_scale: self.eta * self.eta,
        }
    }
}

/// The sine and cosine of `2 pi u`, in single precision (ample for a sampled direction, and
/// twice as fast).
#[inline]
fn turn(u: f64) -> (f64, f64) {
    let (s, c) = (std::f32::consts::TAU * u as f32).sin_cos();
    (s as f64, c as f64)
}

/// A cosine-distributed direction about +z.
#[inline]
fn cosine_local(u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let (s, c) = turn(u2);
    DVec3::new(r * c, r * s, (1.0 - u1).max(0.0).sqrt())
}

/// The cosine of the refracted direction for incidence cosine `cos_i > 0` and relative index
/// `eta` (far side over near side); `None` on total internal reflection.
#[inline]
fn refracted_cos(cos_i: f64, eta: f64) -> Option<f64> {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    (sin2_t < 1.0).then(|| (1.0 - sin2_t).sqrt())
}

/// The unpolarised Fresnel reflectance of a smooth dielectric interface for incidence cosine
/// `cos_i` (on the near side, positive) and relative index `eta` (far side over near side): the
/// mean of the s and p reflectances; 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let Some(cos_t) = refracted_cos(cos_i, eta) else { return 1.0 };
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The GGX normal distribution `D(m)` for a unit microfacet normal `m` (local frame).
#[inline]
pub fn ggx_d(m: DVec3, alpha: f64) -> f64 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = m.z * m.z * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's shadowing term `G1(w)` for GGX (local frame, `w.z > 0`).
#[inline]
pub fn ggx_g1(w: DVec3, alpha: f64) -> f64 {
    let c2 = w.z * w.z;
    if w.z <= 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - c2).max(0.0) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The GGX reflection lobe (perfectly reflecting facets, separable Smith shadowing):
/// `D(h) G1(o) G1(i) / (4 cos_o cos_i)`.
#[inline]
fn ggx_f(o: DVec3, i: DVec3, alpha: f64) -> f64 {
    let h = (o + i).normalize();
    ggx_d(h, alpha) * ggx_g1(o, alpha) * ggx_g1(i, alpha) / (4.0 * o.z * i.z)
}

/// The density of [`ggx_sample`]: the visible-normal density `G1(o) max(0, o.h) D(h) / cos_o`
/// times the Jacobian `1 / (4 o.h)` of the reflection.
#[inline]
fn ggx_pdf(o: DVec3, i: DVec3, alpha: f64) -> f64 {
    let h = (o + i).normalize();
    ggx_g1(o, alpha) * ggx_d(h, alpha) / (4.0 * o.z)
}

/// A direction reflected about a microfacet normal drawn from the GGX distribution of normals
/// visible from `o` (Heitz 2018); it may point below the surface.
#[inline]
fn ggx_sample(o: DVec3, alpha: f64, u1: f64, u2: f64) -> DVec3 {
    let m = ggx_visible_normal(o, alpha, u1, u2);
    2.0 * o.dot(m) * m - o
}

/// A microfacet normal drawn from the GGX distribution of normals visible from `o` (local
/// frame, `o.z > 0`): density `G1(o) max(0, o.m) D(m) / cos_o`.
pub fn ggx_visible_normal(o: DVec3, alpha: f64, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * o.x, alpha * o.y, o.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 { DVec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { DVec3::X };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let (s, c) = turn(u2);
    let p1 = r * c;
    let mix = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - mix) * (1.0 - p1 * p1).max(0.0).sqrt() + mix * r * s;
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// The power heuristic (beta = 2) weight of a strategy of density `a` against one of density
/// `b`; the weights of the two strategies sum to 1.
#[inline]
pub fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a2.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::sampling::chi_square::{check, integral};
    use crate::geometry::test_util::TestRng;
    use crate::integrator::classic::SPEC_POWER;

    /// An interaction at the origin whose normal facing the viewer is `n`, on the plane's front
    /// or back.
    pub(crate) fn at(n: DVec3, front: bool) -> Interaction {
        let outward = if front { n } else { -n };
        let text =
            format!("primitive plane\n N= {} {} {}\n R= 0\n diff= 1\nend\n", outward.x, outward.y, outward.z);
        let parsed =
            crate::scene::parse(&crate::scene::SourceFile::from_text("t.txt", None, text)).expect("parses");
        let scene = crate::PreparedScene::new(parsed.scene, &Default::default()).expect("prepares");
        let ray = crate::geometry::Ray::new(n, -n);
        let (primitive, hit) = scene.closest_surface(&ray).expect("hits the plane");
        let at = scene.interaction(&ray, primitive, hit);
        assert_eq!(at.front, front);
        at
    }

    fn material(diff: f64, spec: f64, refl: f64, drefl: f64, refr: f64) -> CourseMaterial {
        CourseMaterial {
            diff,
            spec,
            refl,
            drefl,
            refr,
            rindex: 1.5,
            color: DVec3::ONE,
            ..CourseMaterial::default()
        }
    }

    #[test]
    fn fresnel_matches_known_values() {
        // Normal incidence: ((n - 1) / (n + 1))^2.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-12);
        // 45 degrees into glass: 0.0502 (Rs = 0.0920, Rp = 0.0085).
        assert!((fresnel_dielectric(0.5f64.sqrt(), 1.5) - 0.050_24).abs() < 1e-5);
        // Brewster's angle: Rp vanishes, F = Rs / 2.
        let brewster = 1.5f64.atan().cos();
        assert!((fresnel_dielectric(brewster, 1.5) - 0.073_964).abs() < 1e-5);
        // Grazing incidence reflects everything; past the critical angle (41.8 deg) inside glass too.
        assert!((fresnel_dielectric(1e-9, 1.5) - 1.0).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(43f64.to_radians().cos(), 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric(40f64.to_radians().cos(), 1.0 / 1.5) < 1.0);
        // The index-matched interface reflects nothing.
        assert!(fresnel_dielectric(0.3, 1.0) < 1e-20);
    }

    #[test]
    fn the_spec_roughness_matches_phong_twenty() {
        assert!((SPEC_ALPHA - (2.0 / (SPEC_POWER as f64 + 2.0)).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn ggx_normals_and_visible_normals_integrate_to_one() {
        for alpha in [0.3, 0.6, 0.9] {
            // Projected microfacet area: the integral of D(m) cos(m) over the hemisphere is 1.
            let projected = integral(|m| ggx_d(m, alpha) * m.z.max(0.0));
            assert!((projected - 1.0).abs() < 2e-3, "alpha {alpha}: {projected}");
            let o = DVec3::new(0.6, 0.0, 0.8);
            let visible = integral(|m| ggx_g1(o, alpha) * o.dot(m).max(0.0) * ggx_d(m, alpha) / o.z);
            assert!((visible - 1.0).abs() < 2e-3, "alpha {alpha}: {visible}");
        }
    }

    #[test]
    fn glossy_directions_follow_their_density() {
        let mut rng = TestRng::new(21);
        let n = DVec3::new(0.2, 0.3, 0.9).normalize();
        let wo = DVec3::new(-0.5, 0.4, 0.6).normalize();
        for (name, m) in [
            ("spec", material(0.0, 1.0, 0.0, 0.0, 0.0)),
            ("rough refl", material(0.0, 0.0, 1.0, 0.8, 0.0)),
            ("diff + spec + refl", material(0.5, 0.3, 0.2, 1.6, 0.0)),
            ("diffuse", material(1.0, 0.0, 0.0, 0.0, 0.0)),
        ] {
            let bsdf = Bsdf::new(&m, DVec3::ONE, &at(n, true));
            check(
                name,
                300_000,
                |_| {
                    let s = bsdf.sample(
                        wo,
                        rng.uniform(),
                        rng.uniform(),
                        rng.uniform(),
                        class::ALL,
                        Transport::Radiance,
                    )?;
                    Some(s.wi)
                },
                |wi| bsdf.pdf(wo, wi, class::ALL),
            );
        }
    }

    #[test]
    fn sample_weights_are_f_cos_over_pdf_and_never_create_energy() {
        let mut rng = TestRng::new(5);
        let n = DVec3::Z;
        for m in [
            material(0.7, 0.3, 0.4, 0.3, 0.0),
            material(1.0, 0.0, 0.0, 0.0, 0.0),
            material(0.0, 1.0, 0.0, 0.0, 0.0),
            material(0.2, 0.0, 0.3, 0.0, 0.5),
        ] {
            let bsdf = Bsdf::new(&m, DVec3::new(0.9, 0.5, 1.0), &at(n, true));
            for _ in 0..20 {
                let wo = crate::base::sampling::cosine_hemisphere(n, rng.uniform(), rng.uniform());
                let count = 20_000;
                let mut albedo = DVec3::ZERO;
                for _ in 0..count {
                    let Some(s) = bsdf.sample(
                        wo,
                        rng.uniform(),
                        rng.uniform(),
                        rng.uniform(),
                        class::ALL,
                        Transport::Radiance,
                    ) else {
                        continue;
                    };
                    if !s.delta {
                        let expect = bsdf.eval(wo, s.wi, class::ALL) * s.wi.dot(n) / s.pdf;
                        assert!((expect - s.weight).abs().max_element() < 1e-9);
                    }
                    albedo += s.weight;
                }
                albedo /= count as f64;
                assert!(albedo.max_element() < 1.0 + 0.02, "{m:?} reflects {albedo} at {wo}");
            }
        }
    }

    #[test]
    fn a_white_lambertian_lobe_reflects_everything() {
        let bsdf = Bsdf::new(&material(1.0, 0.0, 0.0, 0.0, 0.0), DVec3::ONE, &at(DVec3::Z, true));
        let mut rng = TestRng::new(1);
        let wo = DVec3::new(0.3, 0.1, 0.9).normalize();
        for _ in 0..1000 {
            let s = bsdf
                .sample(wo, rng.uniform(), rng.uniform(), rng.uniform(), class::ALL, Transport::Radiance)
                .expect("a direction");
            assert!((s.weight - DVec3::ONE).abs().max_element() < 1e-12);
        }
    }

    #[test]
    fn weights_over_one_are_normalised_and_inside_glass_only_the_interface_acts() {
        let m = material(1.0, 0.0, 1.0, 0.0, 0.0);
        let bsdf = Bsdf::new(&m, DVec3::ONE, &at(DVec3::Z, true));
        assert_eq!(bsdf.diffuse_albedo(), DVec3::splat(0.5));
        let glass = material(0.5, 0.0, 0.0, 0.0, 0.5);
        let inside = Bsdf::new(&glass, DVec3::ONE, &at(DVec3::Z, false));
        assert!(!inside.has(class::DIFFUSE) && inside.has(class::SPECULAR));
        let outside = Bsdf::new(&glass, DVec3::ONE, &at(DVec3::Z, true));
        assert!(outside.has(class::DIFFUSE));
    }

    #[test]
    fn refraction_follows_snell_and_fresnel_and_scales_radiance() {
        let bsdf = Bsdf::new(&material(0.0, 0.0, 0.0, 0.0, 1.0), DVec3::ONE, &at(DVec3::Z, true));
        let wo = DVec3::new(0.6, 0.0, 0.8);
        let f = fresnel_dielectric(0.8, 1.5);
        let (mut reflected, n) = (0, 100_000);
        for k in 0..n {
            let u = (k as f64 + 0.5) / n as f64;
            let s = bsdf.sample(wo, 0.5, u, 0.5, class::ALL, Transport::Radiance).expect("always");
            if s.transmitted {
                // sin t = sin i / eta.
                assert!((s.wi.x + 0.6 / 1.5).abs() < 1e-12 && s.wi.z < 0.0);
                assert!((s.weight.x - 1.0 / 2.25).abs() < 1e-12);
                let s = bsdf.sample(wo, 0.5, u, 0.5, class::ALL, Transport::Importance).expect("always");
                assert!((s.weight.x - 1.0).abs() < 1e-12);
            } else {
                reflected += 1;
                assert!((s.wi - DVec3::new(-0.6, 0.0, 0.8)).length() < 1e-12);
            }
        }
        assert!((reflected as f64 / n as f64 - f).abs() < 1e-4);
    }

    #[test]
    fn mis_weights_sum_to_one() {
        let mut rng = TestRng::new(2);
        for _ in 0..1000 {
            let (a, b) = (rng.uniform() * 10.0, rng.uniform() * 0.1);
            assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-12);
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(f64::INFINITY, 1.0), 1.0);
    }
}
