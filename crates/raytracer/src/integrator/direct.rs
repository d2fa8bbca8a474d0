//! Direct lighting of physically based scenes (Mitsuba's `direct` integrator): at the surface a
//! camera ray meets, `emitter_samples` emitter samples and `bsdf_samples` BSDF samples, combined
//! by the power heuristic over both counts, as Mitsuba 3.9.1's `direct.cpp` combines them.
//!
//! With `n_e` emitter and `n_b` BSDF samples (`n = n_e + n_b`), an emitter sample of density
//! `p_e` (its emitter's choice included) towards a direction the BSDF samples with density
//! `p_b` weighs `w(p_e n_e / n, p_b n_b / n) / n_e`, a BSDF sample that meets an emitter weighs
//! `w(p_b n_b / n, p_e n_e / n) / n_b`, with `w(a, b) = a^2 / (a^2 + b^2)` (0 where `a` is 0).
//! Emitters are chosen uniformly, as Mitsuba chooses them ([`Emitters::uniform`]), so that the
//! strategies' weights and noise are Mitsuba's. Only strategies with samples count: with `n_b = 0` emitter samples take the full weight,
//! and with `n_e = 0` BSDF samples do. As in Mitsuba, an emitter sample of a delta emitter (a
//! point, a spot, a projector, a directional light) weighs 1, not `1 / n_e`: with `n_e > 1`
//! such lights count `n_e` times (Mitsuba 3.9.1 renders them so); BSDF samples of a delta lobe
//! (a mirror) meeting an emitter weigh `1 / n_b`. Emitter samples are drawn only where the BSDF
//! has a smooth lobe. Emitters seen directly add their radiance unless `hide_emitters`.

use glam::DVec3;

use crate::base::sampler::PixelRng;
use crate::geometry::Ray;
use crate::integrator::bsdfs::PhysicalBsdf;
use crate::integrator::emitters::Emitters;
use crate::integrator::physical::Frame;
use crate::integrator::report::PathResult;
use crate::prepare::PreparedScene;
use crate::scene::DirectSamples;

/// Mitsuba's `direct` integrator over a physically based prepared scene.
#[derive(Debug)]
pub struct DirectTracer<'s> {
    scene: &'s PreparedScene,
    emitters: Emitters<'s>,
    samples: DirectSamples,
    hide_emitters: bool,
}

/// Mitsuba's `direct.cpp` `mis_weight`: the power heuristic, 0 where `a` is 0 (and where the
/// ratio is not finite).
#[inline]
fn mis_weight(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a > 0.0 {
        let w = a2 / (a2 + b2);
        if w.is_finite() { w } else { 0.0 }
    } else {
        0.0
    }
}

impl<'s> DirectTracer<'s> {
    /// The integrator of `scene` with `samples` per surface point; `hide_emitters` as the scene
    /// says.
    pub fn new(scene: &'s PreparedScene, samples: DirectSamples) -> DirectTracer<'s> {
        DirectTracer {
            scene,
            emitters: Emitters::uniform(scene),
            samples,
            hide_emitters: scene.scene.render.hide_emitters,
        }
    }

    /// The radiance arriving along the camera ray `ray` (one sample), drawing from `rng`.
    pub fn radiance(&self, ray: Ray, rng: &mut PixelRng) -> PathResult {
        let scene = self.scene;
        let mut out = PathResult { rays: 1, ..PathResult::default() };
        let Some((primitive, hit)) = scene.closest_surface(&ray) else {
            if !self.hide_emitters {
                out.radiance += self.emitters.environment(ray.dir);
            }
            return out;
        };
        let at = scene.interaction(&ray, primitive, hit);
        if !self.hide_emitters
            && let Some(emitter) = scene.emitter_of(primitive)
        {
            out.radiance += self.emitters.emitted(emitter, &at);
        }
        let (n_e, n_b) = (self.samples.emitter_samples, self.samples.bsdf_samples);
        let total = (n_e + n_b) as f64;
        let (frac_e, frac_b) = (n_e as f64 / total, n_b as f64 / total);
        let bsdf = PhysicalBsdf::new(scene.material(at.primitive), &mut |p| scene.param(p, &at));
        let frame = Frame::at(scene, &at);
        let wo = frame.to_local(-ray.dir);

        // Emitter sampling.
        if bsdf.has_smooth() {
            for _ in 0..n_e {
                let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
                let Some(ls) = self.emitters.sample(at.point, u, u1, u2) else { continue };
                if !frame.admits(ls.wi) || ls.pdf <= 0.0 {
                    continue;
                }
                let wi = frame.to_local(ls.wi);
                let f = bsdf.eval(wo, wi);
                if f == DVec3::ZERO || !self.emitters.unoccluded(at.spawn(ls.wi).origin, &ls, &mut out.rays) {
                    continue;
                }
                let weight = if ls.delta {
                    1.0
                } else {
                    mis_weight(ls.pdf * frac_e, bsdf.pdf(wo, wi) * frac_b) / n_e as f64
                };
                out.radiance += f * ls.radiance * (wi.z.abs() * weight / ls.pdf);
            }
        }

        // BSDF sampling.
        for _ in 0..n_b {
            let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
            let Some(s) = bsdf.sample(wo, u, u1, u2) else { continue };
            let wi = frame.to_world(s.wi);
            if s.weight == DVec3::ZERO || !frame.admits(wi) {
                continue;
            }
            let next = at.spawn(wi);
            out.rays += 1;
            let (le, emitter_pdf) = match scene.closest_surface(&next) {
                None => {
                    let le = self.emitters.environment(wi);
                    let pdf =
                        if s.delta || le == DVec3::ZERO { 0.0 } else { self.emitters.environment_pdf(wi) };
                    (le, pdf)
                }
                Some((p, h)) => match scene.emitter_of(p) {
                    None => continue,
                    Some(emitter) => {
                        let there = scene.interaction(&next, p, h);
                        let le = self.emitters.emitted(emitter, &there);
                        let pdf = if s.delta || le == DVec3::ZERO {
                            0.0
                        } else {
                            self.emitters.area_pdf(emitter, at.point, wi, there.t, there.geometric)
                        };
                        (le, pdf)
                    }
                },
            };
            if le == DVec3::ZERO {
                continue;
            }
            // A delta lobe's "density" is a probability: it is weighed against no emitter sample.
            let weight = if s.delta { 1.0 } else { mis_weight(s.pdf * frac_b, emitter_pdf * frac_e) };
            out.radiance += s.weight * le * (weight / n_b as f64);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weights_follow_mitsubas_power_heuristic_over_the_counts() {
        assert_eq!(mis_weight(0.0, 1.0), 0.0);
        assert_eq!(mis_weight(2.0, 0.0), 1.0);
        assert!((mis_weight(1.0, 1.0) - 0.5).abs() < 1e-15);
        assert!((mis_weight(3.0, 1.0) - 0.9).abs() < 1e-15);
        // Two weighted densities of one direction: their weights add up to 1.
        let (pe, pb, fe, fb) = (0.7, 2.3, 0.25, 0.75);
        assert!((mis_weight(pe * fe, pb * fb) + mis_weight(pb * fb, pe * fe) - 1.0).abs() < 1e-15);
    }
}
