//! Mitsuba 3's physically based BSDFs (issue 27), evaluated at one surface point: the math of
//! Mitsuba's `src/bsdfs/*.cpp`, `microfacet.h` and `fresnel.h`, one module per plugin.
//!
//! A [`PhysicalBsdf`] is built from a [`Material`] with every parameter already evaluated at the
//! point (textures are resolved by the caller), and works in the local shading frame:
//! - +z is the shading normal as the shape defines it (not turned towards the viewer), +x the
//!   first tangent (the direction of `alpha_u`), +y the second;
//! - `wo` (towards the viewer, or the previous vertex) and `wi` (towards the light, or the next
//!   vertex) are unit vectors pointing away from the surface;
//! - values are linear RGB; `eval` is `f(wo, wi)` without the cosine factor; radiance transport
//!   (Mitsuba's `TransportMode::Radiance`): radiance refracted into a medium of relative index
//!   `eta` is scaled by `1 / eta^2`.
//!
//! One-sided plugins (`diffuse`, `conductor`, `roughconductor`, `plastic`, `roughplastic`) are
//! black when `wo.z <= 0` or `wi.z <= 0`; the dielectrics work from both sides, and so do
//! `principled` (seen from the back: its specular reflection and transmission only) and
//! `principledthin` (the same from both sides). The wrappers
//! (`twosided`, `mask`, `blendbsdf`) are flattened into at most [`MAX_COMPONENTS`] weighted
//! components (see [`wrappers`]).
//!
//! ```
//! use glam::DVec3;
//! use raytracer::integrator::bsdfs::PhysicalBsdf;
//! use raytracer::material::{Interface, Material, Param};
//!
//! // Mitsuba's default `dielectric`: BK7 glass in air.
//! let glass = Material::Dielectric(Interface {
//!     int_ior: 1.5046,
//!     ext_ior: 1.000277,
//!     specular_reflectance: Param::scalar(1.0),
//!     specular_transmittance: Param::scalar(1.0),
//! });
//! // Constants only here; a renderer looks textures up at the hit point.
//! let bsdf = PhysicalBsdf::new(&glass, &mut |p| match p {
//!     Param::Constant(v) => *v,
//!     Param::Texture(_) => unreachable!("no textures in this example"),
//! });
//! let wo = DVec3::new(0.0, 0.6, 0.8); // towards the viewer, 36.9 degrees off the normal
//! // u_lobe = 0.9 > F (about 0.04): refraction into the glass, radiance scaled by 1 / eta^2.
//! let s = bsdf.sample(wo, 0.9, 0.5, 0.5).expect("glass scatters");
//! assert!(s.delta && s.wi.z < 0.0);
//! assert!((s.eta - 1.5046 / 1.000277).abs() < 1e-12);
//! assert!((s.weight.x - 1.0 / (s.eta * s.eta)).abs() < 1e-12);
//! assert_eq!(bsdf.eval(wo, s.wi), DVec3::ZERO); // a delta lobe has no density
//! assert!(!bsdf.has_smooth()); // nothing for next-event estimation
//! ```

pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fresnel;
pub mod microfacet;
pub mod plastic;
pub mod principled;
pub mod principledthin;
pub mod roughdielectric;
pub mod roughplastic;
pub mod special;
pub mod wrappers;

#[cfg(test)]
mod tests;

use glam::DVec3;
use smallvec::SmallVec;

use crate::material::{Material, Param};
use conductor::{Conductor, RoughConductor};
use dielectric::{Dielectric, ThinDielectric};
use diffuse::Diffuse;
use plastic::Plastic;
use roughdielectric::RoughDielectric;
use roughplastic::RoughPlastic;
pub use wrappers::{Component, MAX_COMPONENTS, Side, component_count};

/// A direction drawn by [`PhysicalBsdf::sample`], in the local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalSample {
    /// The sampled direction (unit, pointing away from the surface).
    pub wi: DVec3,
    /// `f(wo, wi) |wi.z| / pdf` for a non-delta outcome; for a delta outcome, the factor the
    /// path throughput is multiplied by (e.g. the tint, `F / P(reflect)` ...).
    pub weight: DVec3,
    /// The solid-angle density of `wi` for a non-delta outcome (the one
    /// [`PhysicalBsdf::pdf`] returns); for a delta outcome, the discrete probability of the
    /// chosen delta lobe.
    pub pdf: f64,
    /// Whether `wi` comes from a delta lobe (mirror, smooth refraction, null pass-through).
    pub delta: bool,
    /// The relative index of refraction crossed (`eta` of the side entered over the side left;
    /// 1 for reflection and pass-through): Russian roulette divides the throughput's
    /// `eta^2` scaling back out with it.
    pub eta: f64,
}

/// One physically based lobe set (a Mitsuba plugin other than the wrappers), local frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Lobe {
    /// `diffuse`.
    Diffuse(Diffuse),
    /// `dielectric`.
    Dielectric(Dielectric),
    /// `thindielectric`.
    ThinDielectric(ThinDielectric),
    /// `roughdielectric`.
    RoughDielectric(RoughDielectric),
    /// `conductor`.
    Conductor(Conductor),
    /// `roughconductor`.
    RoughConductor(RoughConductor),
    /// `plastic`.
    Plastic(Plastic),
    /// `roughplastic`.
    RoughPlastic(RoughPlastic),
    /// `principled`.
    Principled(principled::Principled),
    /// `principledthin`.
    PrincipledThin(principledthin::PrincipledThin),
    /// The pass-through of `mask`: `wi = -wo`, weight 1.
    Null,
}

impl Lobe {
    /// `f(wo, wi)` without the cosine; 0 for delta lobes.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        match self {
            Lobe::Diffuse(l) => l.eval(wo, wi),
            Lobe::RoughDielectric(l) => l.eval(wo, wi),
            Lobe::RoughConductor(l) => l.eval(wo, wi),
            Lobe::Plastic(l) => l.eval(wo, wi),
            Lobe::RoughPlastic(l) => l.eval(wo, wi),
            Lobe::Principled(l) => l.eval(wo, wi),
            Lobe::PrincipledThin(l) => l.eval(wo, wi),
            Lobe::Dielectric(_) | Lobe::ThinDielectric(_) | Lobe::Conductor(_) | Lobe::Null => DVec3::ZERO,
        }
    }

    /// The solid-angle density of the lobe's non-delta outcomes.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        match self {
            Lobe::Diffuse(l) => l.pdf(wo, wi),
            Lobe::RoughDielectric(l) => l.pdf(wo, wi),
            Lobe::RoughConductor(l) => l.pdf(wo, wi),
            Lobe::Plastic(l) => l.pdf(wo, wi),
            Lobe::RoughPlastic(l) => l.pdf(wo, wi),
            Lobe::Principled(l) => l.pdf(wo, wi),
            Lobe::PrincipledThin(l) => l.pdf(wo, wi),
            Lobe::Dielectric(_) | Lobe::ThinDielectric(_) | Lobe::Conductor(_) | Lobe::Null => 0.0,
        }
    }

    /// Draws a direction: `u` chooses among the lobe's parts, `u1`, `u2` the direction.
    pub fn sample(&self, wo: DVec3, u: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        match self {
            Lobe::Diffuse(l) => l.sample(wo, u1, u2),
            Lobe::Dielectric(l) => l.sample(wo, u),
            Lobe::ThinDielectric(l) => l.sample(wo, u),
            Lobe::RoughDielectric(l) => l.sample(wo, u, u1, u2),
            Lobe::Conductor(l) => l.sample(wo),
            Lobe::RoughConductor(l) => l.sample(wo, u1, u2),
            Lobe::Plastic(l) => l.sample(wo, u, u1, u2),
            Lobe::RoughPlastic(l) => l.sample(wo, u, u1, u2),
            Lobe::Principled(l) => l.sample(wo, u, u1, u2),
            Lobe::PrincipledThin(l) => l.sample(wo, u, u1, u2),
            Lobe::Null => Some(LocalSample { wi: -wo, weight: DVec3::ONE, pdf: 1.0, delta: true, eta: 1.0 }),
        }
    }

    /// Whether the lobe has a non-delta part.
    pub fn has_smooth(&self) -> bool {
        matches!(
            self,
            Lobe::Diffuse(_)
                | Lobe::RoughDielectric(_)
                | Lobe::RoughConductor(_)
                | Lobe::Plastic(_)
                | Lobe::RoughPlastic(_)
                | Lobe::Principled(_)
                | Lobe::PrincipledThin(_)
        )
    }

    /// A denoiser albedo: the diffuse reflectance (the base's for plastics), the metal's colour
    /// at normal incidence, the transmission tint of dielectrics, 1 for the pass-through.
    pub fn albedo(&self) -> DVec3 {
        match self {
            Lobe::Diffuse(l) => l.reflectance,
            Lobe::Dielectric(l) => l.transmit_tint,
            Lobe::ThinDielectric(l) => l.transmit_tint,
            Lobe::RoughDielectric(l) => l.transmit_tint,
            Lobe::Conductor(l) => l.albedo(),
            Lobe::RoughConductor(l) => l.metal.albedo(),
            Lobe::Plastic(l) => l.diffuse,
            Lobe::RoughPlastic(l) => l.base,
            Lobe::Principled(l) => l.base_color,
            Lobe::PrincipledThin(l) => l.base_color,
            Lobe::Null => DVec3::ONE,
        }
    }
}

/// A physically based BSDF at one surface point, every parameter already evaluated (no
/// textures here): up to [`MAX_COMPONENTS`] weighted [`Lobe`]s kept inline (no heap
/// allocation, except the first use of a `roughplastic` table on a thread). Local frame and
/// conventions: see the module documentation.
///
/// A path keeps one and refills it at every vertex ([`PhysicalBsdf::rebuild`]): the slots are
/// neither cleared nor copied, only the components a material has are written.
#[derive(Clone, Debug, Default)]
pub struct PhysicalBsdf {
    components: SmallVec<[Component; MAX_COMPONENTS]>,
}

impl PhysicalBsdf {
    /// Builds the BSDF of `material`, `param` evaluating a [`Param`] at this point (RGB; scalar
    /// parameters take the `.x` of what it returns). A [`Material::Course`] has no physically
    /// based BSDF and gives a black one (the course's lobes are `integrator::bsdf`'s).
    pub fn new(material: &Material, param: &mut dyn FnMut(&Param) -> DVec3) -> PhysicalBsdf {
        let mut bsdf = PhysicalBsdf::default();
        bsdf.rebuild(material, param);
        bsdf
    }

    /// Makes this the BSDF of `material`, as [`PhysicalBsdf::new`] builds it, in place.
    pub fn rebuild(&mut self, material: &Material, param: &mut dyn FnMut(&Param) -> DVec3) {
        let components = &mut self.components;
        components.clear();
        wrappers::flatten(material, param, &mut |c| {
            if components.len() < MAX_COMPONENTS {
                components.push(c);
            }
        });
    }

    /// The components (weighted lobes) of the BSDF.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// `f(wo, wi)` without the cosine factor, per RGB channel; 0 for delta components.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for c in self.components() {
            if let Some((o, i)) = c.localise(wo, wi) {
                sum += c.weight * c.lobe.eval(o, i);
            }
        }
        sum
    }

    /// The solid-angle density with which [`PhysicalBsdf::sample`] draws `wi` as a non-delta
    /// outcome.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        let mut sum = 0.0;
        for c in self.components() {
            if let Some((o, i)) = c.localise(wo, wi) {
                sum += c.weight * c.lobe.pdf(o, i);
            }
        }
        sum
    }

    /// Draws `wi` for `wo`: `u_lobe` chooses the component (with probability its weight) and
    /// the part of it (Fresnel reflection or refraction, specular or diffuse ...), `u1`, `u2`
    /// the direction; all uniform in [0, 1). `None` when nothing is scattered (the direction
    /// fell below the surface, or `wo` sees a one-sided surface's back).
    ///
    /// For a non-delta outcome the weight and pdf are those of the whole mixture
    /// (`weight = eval * |wi.z| / pdf`), so that multiple importance sampling sees one density.
    pub fn sample(&self, wo: DVec3, u_lobe: f64, u1: f64, u2: f64) -> Option<LocalSample> {
        let mut valid = 0;
        let mut start = 0.0;
        let mut chosen = None;
        for c in self.components() {
            if !c.side.admits(wo) {
                continue;
            }
            valid += 1;
            if chosen.is_none() && u_lobe < start + c.weight {
                let u = ((u_lobe - start) / c.weight).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
                chosen = Some((c, u));
            }
            start += c.weight;
        }
        let (c, u) = chosen?;
        let o = c.to_lobe(wo);
        let mut s = c.lobe.sample(o, u, u1, u2)?;
        s.wi = c.to_lobe(s.wi);
        if s.delta {
            s.pdf *= c.weight;
            return Some(s);
        }
        if valid == 1 && c.weight == 1.0 {
            return Some(s);
        }
        let pdf = self.pdf(wo, s.wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        s.weight = self.eval(wo, s.wi) * s.wi.z.abs() / pdf;
        s.pdf = pdf;
        Some(s)
    }

    /// Whether any component has a non-delta part (next-event estimation is worth it).
    pub fn has_smooth(&self) -> bool {
        self.components().iter().any(|c| c.lobe.has_smooth())
    }

    /// A denoiser albedo: the weighted [`Lobe::albedo`]s of the components seen from the front.
    pub fn albedo(&self) -> DVec3 {
        self.components().iter().filter(|c| c.side != Side::Back).map(|c| c.weight * c.lobe.albedo()).sum()
    }
}

/// Builds a leaf lobe (no wrapper) from its material, evaluating its parameters.
pub(crate) fn leaf_lobe(material: &Material, param: &mut dyn FnMut(&Param) -> DVec3) -> Option<Lobe> {
    use microfacet::MicrofacetDistribution;
    let distr = |mf: &crate::material::Microfacet, param: &mut dyn FnMut(&Param) -> DVec3| {
        let au = param(&mf.alpha_u).x;
        let av = param(&mf.alpha_v).x;
        MicrofacetDistribution::new(mf.distribution, au, av, mf.sample_visible)
    };
    Some(match material {
        Material::Diffuse { reflectance } => Lobe::Diffuse(Diffuse { reflectance: param(reflectance) }),
        Material::Dielectric(i) => Lobe::Dielectric(Dielectric {
            eta: i.int_ior / i.ext_ior,
            reflect_tint: param(&i.specular_reflectance),
            transmit_tint: param(&i.specular_transmittance),
        }),
        Material::ThinDielectric(i) => Lobe::ThinDielectric(ThinDielectric {
            eta: i.int_ior / i.ext_ior,
            reflect_tint: param(&i.specular_reflectance),
            transmit_tint: param(&i.specular_transmittance),
        }),
        Material::RoughDielectric { interface: i, microfacet } => Lobe::RoughDielectric(RoughDielectric {
            eta: i.int_ior / i.ext_ior,
            reflect_tint: param(&i.specular_reflectance),
            transmit_tint: param(&i.specular_transmittance),
            distr: distr(microfacet, param),
        }),
        Material::Conductor(m) => {
            Lobe::Conductor(Conductor { eta: m.eta, k: m.k, tint: param(&m.specular_reflectance) })
        }
        Material::RoughConductor { metal: m, microfacet } => Lobe::RoughConductor(RoughConductor {
            metal: Conductor { eta: m.eta, k: m.k, tint: param(&m.specular_reflectance) },
            distr: distr(microfacet, param),
        }),
        Material::Plastic(c) => Lobe::Plastic(Plastic::new(
            c.int_ior / c.ext_ior,
            param(&c.diffuse_reflectance),
            param(&c.specular_reflectance),
            c.nonlinear,
        )),
        Material::RoughPlastic { coating: c, microfacet } => {
            let d = distr(microfacet, param);
            // Isotropic, as Mitsuba (which refuses anisotropic roughness here): alpha_u.
            let d = MicrofacetDistribution::new(d.kind, d.alpha_u, d.alpha_u, d.sample_visible);
            Lobe::RoughPlastic(RoughPlastic::new(
                c.int_ior / c.ext_ior,
                param(&c.diffuse_reflectance),
                param(&c.specular_reflectance),
                c.nonlinear,
                d,
            ))
        }
        Material::Principled(p) => {
            let base = param(&p.base_color);
            let mut s = |q: &Param| param(q).x;
            Lobe::Principled(principled::Principled::new(
                base,
                s(&p.roughness),
                s(&p.anisotropic),
                s(&p.metallic),
                s(&p.spec_trans),
                s(&p.spec_tint),
                s(&p.sheen),
                s(&p.sheen_tint),
                s(&p.flatness),
                s(&p.clearcoat),
                s(&p.clearcoat_gloss),
                p.eta,
                [p.specular_sampling_rate, p.clearcoat_sampling_rate, p.diffuse_sampling_rate],
            ))
        }
        Material::PrincipledThin(p) => {
            let base = param(&p.base_color);
            let mut s = |q: &Param| param(q).x;
            Lobe::PrincipledThin(principledthin::PrincipledThin::new(
                base,
                s(&p.roughness),
                s(&p.anisotropic),
                s(&p.spec_trans),
                s(&p.eta),
                s(&p.spec_tint),
                s(&p.sheen),
                s(&p.sheen_tint),
                s(&p.flatness),
                s(&p.diff_trans),
                [
                    p.specular_reflectance_sampling_rate,
                    p.specular_transmittance_sampling_rate,
                    p.diffuse_reflectance_sampling_rate,
                    p.diffuse_transmittance_sampling_rate,
                ],
            ))
        }
        Material::Course(_)
        | Material::TwoSided { .. }
        | Material::Mask { .. }
        | Material::Blend { .. }
        | Material::Perturbed { .. } => {
            return None;
        }
    })
}
