//! The path tracer of physically based scenes (Mitsuba's `path` integrator): the same walk as
//! [`super::path`], over Mitsuba's BSDFs ([`super::bsdfs`]) and emitters ([`super::emitters`]).
//!
//! At every vertex with a smooth lobe, next-event estimation samples an emitter and is combined
//! with BSDF sampling by multiple importance sampling (power heuristic); surfaces that emit add
//! their radiance when a path meets their front face; rays that escape meet the environment.
//! Russian roulette starts at the scene's `rr_depth`, with Mitsuba's survival probability
//! `min(max(throughput) eta^2, 0.95)`. Depth counts segments, as in Mitsuba: `max_depth = 1`
//! shows only what emits.

use glam::DVec3;

use crate::base::sampler::PixelRng;
use crate::geometry::Ray;
use crate::integrator::bsdf::power_heuristic;
use crate::integrator::bsdfs::PhysicalBsdf;
use crate::integrator::emitters::Emitters;
use crate::integrator::report::PathResult;
use crate::prepare::{Interaction, PreparedScene};

/// Largest survival probability of Russian roulette (Mitsuba's).
const RR_MAX_SURVIVAL: f64 = 0.95;

/// The local shading frame at a surface point: `n` the shading normal as the shape defines it
/// (not turned towards the viewer), or as a `normalmap` / `bumpmap` perturbs it, `t` and `b`
/// tangents.
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame {
    t: DVec3,
    b: DVec3,
    n: DVec3,
    /// The unperturbed shading normal, when the frame is perturbed.
    base: Option<DVec3>,
}

impl Frame {
    pub(super) fn at(scene: &PreparedScene, at: &Interaction) -> Frame {
        let (t, b, n) = scene.shading_frame(at);
        match scene.perturbed_frame(at, (t, b, n)) {
            Some((t2, b2, n2)) => Frame { t: t2, b: b2, n: n2, base: Some(n) },
            None => Frame { t, b, n, base: None },
        }
    }

    /// Whether the world direction `w` towards a light is on the same side of the perturbed and
    /// of the unperturbed normal (Mitsuba's `normalmap` and `bumpmap` scatter nothing else).
    #[inline]
    pub(super) fn admits(self, w: DVec3) -> bool {
        match self.base {
            Some(n0) => n0.dot(w) * self.n.dot(w) > 0.0,
            None => true,
        }
    }

    #[inline]
    pub(super) fn to_local(self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    #[inline]
    pub(super) fn to_world(self, v: DVec3) -> DVec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// The path tracer over a physically based prepared scene.
#[derive(Debug)]
pub struct PhysicalTracer<'s> {
    scene: &'s PreparedScene,
    emitters: Emitters<'s>,
    max_depth: u32,
    rr_depth: u32,
    hide_emitters: bool,
}

impl<'s> PhysicalTracer<'s> {
    /// The tracer of `scene` with paths of at most `max_depth` segments; Russian roulette and
    /// hidden emitters as the scene says ([`crate::scene::SceneRender`]).
    pub fn new(scene: &'s PreparedScene, max_depth: u32) -> PhysicalTracer<'s> {
        let render = &scene.scene.render;
        PhysicalTracer {
            scene,
            emitters: Emitters::new(scene),
            max_depth,
            rr_depth: render.rr_depth,
            hide_emitters: render.hide_emitters,
        }
    }

    /// Makes `bsdf` the BSDF of the primitive at `at`, its parameters looked up there.
    #[inline]
    pub fn bsdf_at(&self, at: &Interaction, bsdf: &mut PhysicalBsdf) {
        let material = self.scene.material(at.primitive);
        bsdf.rebuild(material, &mut |p| self.scene.param(p, at));
    }

    /// The radiance arriving along `ray` (one sample), drawing from `rng`.
    pub fn radiance(&self, mut ray: Ray, rng: &mut PixelRng) -> PathResult {
        let scene = self.scene;
        let mut out = PathResult::default();
        let mut beta = DVec3::ONE;
        // The previous vertex and its BSDF sample's density, for MIS; `None` after the camera or
        // a delta lobe.
        let mut previous: Option<(DVec3, f64)> = None;
        let mut eta = 1.0;
        let mut depth = 0u32;
        // One BSDF for the whole path, refilled at every vertex.
        let mut bsdf = PhysicalBsdf::default();
        loop {
            out.rays += 1;
            let seen = !(depth == 0 && self.hide_emitters);
            let Some((primitive, hit)) = scene.closest_surface(&ray) else {
                if seen {
                    let le = self.emitters.environment(ray.dir);
                    if le != DVec3::ZERO {
                        let weight = match previous {
                            Some((_, pdf)) => power_heuristic(pdf, self.emitters.environment_pdf(ray.dir)),
                            None => 1.0,
                        };
                        out.radiance += beta * le * weight;
                    }
                }
                break;
            };
            let at = scene.interaction(&ray, primitive, hit);
            if seen && let Some(emitter) = scene.emitter_of(primitive) {
                let le = self.emitters.emitted(emitter, &at);
                if le != DVec3::ZERO {
                    let weight = match previous {
                        Some((p, pdf)) => power_heuristic(
                            pdf,
                            self.emitters.area_pdf(emitter, p, ray.dir, at.t, at.geometric),
                        ),
                        None => 1.0,
                    };
                    out.radiance += beta * le * weight;
                }
            }
            depth += 1;
            if depth >= self.max_depth {
                break;
            }
            self.bsdf_at(&at, &mut bsdf);
            let frame = Frame::at(scene, &at);
            let wo = frame.to_local(-ray.dir);
            let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
            if bsdf.has_smooth()
                && let Some(ls) = self.emitters.sample(at.point, u, u1, u2)
                && frame.admits(ls.wi)
            {
                let wi = frame.to_local(ls.wi);
                let f = bsdf.eval(wo, wi);
                if f != DVec3::ZERO && self.emitters.unoccluded(at.spawn(ls.wi).origin, &ls, &mut out.rays) {
                    let weight = if ls.delta { 1.0 } else { power_heuristic(ls.pdf, bsdf.pdf(wo, wi)) };
                    out.radiance += beta * f * ls.radiance * (wi.z.abs() * weight / ls.pdf);
                }
            }
            let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
            let Some(s) = bsdf.sample(wo, u, u1, u2) else { break };
            let wi = frame.to_world(s.wi);
            if !frame.admits(wi) {
                break;
            }
            beta *= s.weight;
            if beta == DVec3::ZERO || !beta.is_finite() {
                break;
            }
            eta *= s.eta;
            previous = if s.delta { None } else { Some((at.point, s.pdf)) };
            ray = at.spawn(wi);
            if depth >= self.rr_depth {
                let q = (beta.max_element() * eta * eta).min(RR_MAX_SURVIVAL);
                if rng.uniform() >= q {
                    break;
                }
                beta /= q;
            }
        }
        out
    }
}
