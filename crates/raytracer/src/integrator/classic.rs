//! The classic shading model of the course template (spec section 5), exactly: ambient, diffuse
//! and the view-independent `(N.L)^20` highlight, hard and soft shadows, mirror and glossy
//! reflection, refraction with total internal reflection and Beer absorption, every result
//! clamped to 1 at every depth, and a depth limit of 10.
//!
//! It is not physically based (no fall-off, no Fresnel, per-depth clamping): it is what the course's
//! users expect their scene files to look like.
//!
//! The same recursion is the gathering pass of the course's photon mapper (spec section 10): its
//! camera rays are traced exactly so (mirror, glossy, refraction, visible light shapes), but the
//! local light of a diffuse hit comes from the photon map instead of shadow rays, and only the
//! primary ray's result is clamped. [`Classic::with_photons`] makes that variant.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::base::sampler::{PixelRng, Siblings, Strata, hash_values, mix64};
use crate::geometry::Ray;
use crate::integrator::course_lobes::GlossyLobe;
pub use crate::integrator::course_lobes::{MAX_DEPTH, SPEC_POWER, refract};
use crate::integrator::photon_map::PhotonEstimate;
use crate::light::Light;
use crate::prepare::{Hit, Interaction, PreparedScene};

/// Glossy reflection is sampled only at depths up to this; deeper it is a perfect mirror.
pub const MAX_GLOSSY_DEPTH: u32 = 2;
/// Samples per quality unit: an area light takes `16 * shade_quality` shadow samples and a glossy
/// reflection `16 * drefl_quality` directions.
pub const SAMPLES_PER_QUALITY: u32 = 16;

/// Per-path mutable state: the pixel's random numbers, the ray count and the noise estimate.
pub struct TraceContext<'a> {
    /// The pixel's generator.
    pub rng: &'a mut PixelRng,
    /// Rays traced so far (camera, secondary and shadow rays).
    pub rays: u64,
    /// Estimated variance of the colour (per channel, the largest), summed over the sampled
    /// estimates (area-light shadows, glossy reflections) met along the tagged part of the path:
    /// the adaptive sampler refines pixels whose estimate is visibly noisy.
    pub variance: f64,
    /// Photon-map lookups made (irradiance estimates).
    pub lookups: u64,
}

impl TraceContext<'_> {
    /// A context for one pixel's samples.
    pub fn new(rng: &mut PixelRng) -> TraceContext<'_> {
        TraceContext { rng, rays: 0, variance: 0.0, lookups: 0 }
    }
}

/// Where the local light of a hit comes from.
enum LocalLight<'s> {
    /// Every light, through shadow rays (the classic model, spec 5.2 and 5.3).
    Direct,
    /// The photon map's irradiance estimate (the course's photon mapper, spec section 10).
    Photons(PhotonEstimate<'s>),
}

/// The classic integrator over a prepared scene.
pub struct Classic<'s> {
    scene: &'s PreparedScene,
    local: LocalLight<'s>,
    shadow_strata: Strata,
    glossy_strata: Strata,
}

/// Purpose codes that keep the per-pixel stratum shifts of different estimates independent.
const GLOSSY_PURPOSE: u64 = u64::MAX;

impl<'s> Classic<'s> {
    /// The integrator for `scene`, with its camera's quality settings.
    pub fn new(scene: &'s PreparedScene) -> Classic<'s> {
        let cam = &scene.scene.camera;
        Classic {
            scene,
            local: LocalLight::Direct,
            shadow_strata: Strata::for_count(SAMPLES_PER_QUALITY * cam.shade_quality),
            glossy_strata: Strata::for_count(SAMPLES_PER_QUALITY * cam.drefl_quality),
        }
    }

    /// The gathering pass of the course's photon mapper (spec section 10): the local light of a
    /// hit with `diff > 0` is `color * diff * (background + E)` with `E` the photon map's
    /// irradiance estimate (no highlight, no shadow rays), and only the primary ray's result is
    /// clamped to 1.
    pub fn with_photons(scene: &'s PreparedScene, estimate: PhotonEstimate<'s>) -> Classic<'s> {
        Classic { local: LocalLight::Photons(estimate), ..Classic::new(scene) }
    }

    /// The colour seen along a primary ray, in [0, 1] per channel. `siblings` says how this
    /// pixel sample shares nested estimates with the pixel's other samples. When `tag` is given,
    /// it is mixed with the objects and point lights that decide the colour along the
    /// deterministic part of the path (primitives hit, mirror and refraction chains, lit point
    /// lights), as the template's anti-aliasing hash did: neighbouring pixels with different tags
    /// straddle an edge.
    pub fn radiance(
        &self,
        cx: &mut TraceContext<'_>,
        ray: &Ray,
        siblings: Siblings,
        tag: Option<&mut u64>,
    ) -> DVec3 {
        self.trace(cx, ray, 1, siblings, tag)
    }

    fn trace(
        &self,
        cx: &mut TraceContext<'_>,
        ray: &Ray,
        depth: u32,
        sib: Siblings,
        mut tag: Option<&mut u64>,
    ) -> DVec3 {
        if depth > MAX_DEPTH {
            return DVec3::ZERO;
        }
        cx.rays += 1;
        let scene = &self.scene.scene;
        let (primitive, hit) = match self.scene.closest_hit(ray) {
            Hit::Miss => return scene.background.miss_color(ray.dir).clamp(DVec3::ZERO, DVec3::ONE),
            Hit::Emitter { light, .. } => {
                mix_tag(&mut tag, 1 << 32 | light as u64);
                return scene.lights[light as usize].color().clamp(DVec3::ZERO, DVec3::ONE);
            }
            Hit::Surface { primitive, hit } => (primitive, hit),
        };
        mix_tag(&mut tag, primitive as u64);
        let material = self.scene.course_material(primitive);
        let surface = self.scene.interaction(ray, primitive, hit);
        let (normal, front) = (surface.normal, surface.front);

        let mut color = DVec3::ZERO;
        match &self.local {
            LocalLight::Direct if material.has_local() => {
                let base = self.scene.surface_color(&surface);
                color +=
                    self.local_light(cx, &surface, base, material.diff, material.spec, depth, sib, &mut tag);
            }
            LocalLight::Photons(estimate) if material.diff > 0.0 => {
                let base = self.scene.surface_color(&surface);
                cx.lookups += 1;
                let irradiance = estimate.irradiance(surface.point, surface.normal);
                color += base * material.diff * (scene.background.color + irradiance);
            }
            _ => {}
        }
        if material.refl > 0.0 {
            let reflected = ray.dir - 2.0 * ray.dir.dot(normal) * normal;
            let weight = material.color * material.refl;
            color += weight
                * if material.drefl > 0.0 && depth <= MAX_GLOSSY_DEPTH {
                    self.glossy(
                        cx,
                        &surface,
                        reflected,
                        material.drefl,
                        depth,
                        sib,
                        weight.max_element(),
                        tag.is_some(),
                    )
                } else {
                    self.trace(cx, &surface.spawn(reflected), depth + 1, sib, tag.as_deref_mut())
                };
        }
        if material.refr > 0.0 {
            let n = if front { 1.0 / material.rindex } else { material.rindex };
            let dir = refract(ray.dir, normal, n);
            let mut transmitted = self.trace(cx, &surface.spawn(dir), depth + 1, sib, tag);
            if !front {
                // The ray travelled `t` inside the object before leaving it here.
                transmitted *= (-material.absor * hit.t).exp();
            }
            color += material.refr * transmitted;
        }
        match self.local {
            LocalLight::Photons(_) if depth > 1 => color,
            _ => color.clamp(DVec3::ZERO, DVec3::ONE),
        }
    }

    /// Ambient, diffuse and highlight terms (spec 5.2) with shadows (5.3).
    #[allow(clippy::too_many_arguments)]
    fn local_light(
        &self,
        cx: &mut TraceContext<'_>,
        surface: &Interaction,
        base: DVec3,
        diff: f64,
        spec: f64,
        depth: u32,
        sib: Siblings,
        tag: &mut Option<&mut u64>,
    ) -> DVec3 {
        let scene = &self.scene.scene;
        let mut color = base * scene.background.color * diff;
        for (index, light) in scene.lights.iter().enumerate() {
            let to_light = (light.centre() - surface.point).normalize_or_zero();
            let d = to_light.dot(surface.normal);
            // Lights behind the surface contribute nothing, shadowed or not: skip the shadow rays.
            if d <= 0.0 {
                continue;
            }
            let (shade, shade_variance) = self.shade(cx, light, index, surface, depth, sib, tag.is_some());
            if shade <= 0.0 {
                continue;
            }
            if matches!(light, Light::Point { .. }) {
                mix_tag(tag, 2 << 32 | index as u64);
            }
            let full = base * light.color() * (diff * d + spec * d.powi(SPEC_POWER));
            if tag.is_some() {
                let scale = full.max_element().min(1.0);
                cx.variance += scale * scale * shade_variance;
            }
            color += full * shade;
        }
        color
    }

    /// The unshadowed fraction of `light` seen from the surface point, in [0, 1] (spec 5.3), and
    /// the estimated variance of that fraction (when `track_noise`; 0 otherwise).
    #[allow(clippy::too_many_arguments)]
    fn shade(
        &self,
        cx: &mut TraceContext<'_>,
        light: &Light,
        index: usize,
        surface: &Interaction,
        depth: u32,
        sib: Siblings,
        track_noise: bool,
    ) -> (f64, f64) {
        let origin = surface.shadow_origin();
        let visible = |cx: &mut TraceContext<'_>, target: DVec3| -> bool {
            cx.rays += 1;
            let to = target - origin;
            let dist = to.length();
            dist.is_nan() || dist <= 0.0 || !self.scene.occluded(&Ray { origin, dir: to / dist }, dist)
        };
        let strata = self.shadow_strata;
        let total = strata.count();
        let sampled = |cx: &mut TraceContext<'_>, point_at: &dyn Fn(f64, f64) -> DVec3| -> (f64, f64) {
            let k = sib.share(total);
            let shift = hash_values(&[cx.rng.key(), depth as u64, index as u64]);
            let mut unblocked = 0u32;
            let mut errors = StratumErrors::new(strata, track_noise);
            for j in 0..k {
                let s = sib.stratum(j, total, shift);
                let (a, b) = strata.sample(s, cx.rng);
                let v = visible(cx, point_at(a, b));
                unblocked += v as u32;
                errors.record(s, DVec3::splat(if v { 1.0 } else { 0.0 }));
            }
            (unblocked as f64 / k as f64, errors.variance_of_mean(k))
        };
        match light {
            Light::Point { position, .. } => (if visible(cx, *position) { 1.0 } else { 0.0 }, 0.0),
            // Stratified over the light's area (the spec's jittered 4x4 grid, refined for higher
            // quality).
            Light::Square { shape, .. } => sampled(cx, &|a, b| shape.point_at(2.0 * a - 1.0, 2.0 * b - 1.0)),
            // Stratified uniformly over the sphere's surface (equal-area cells in z and angle).
            Light::Sphere { shape, .. } => sampled(cx, &|a, b| {
                let z = 1.0 - 2.0 * a;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = TAU * b;
                shape.centre + shape.radius * DVec3::new(r * phi.cos(), r * phi.sin(), z)
            }),
        }
    }

    /// Glossy reflection (spec 5.4): the mean of directions `R + drefl (x b1 + y b2)` with
    /// `(x, y) = rho (cos theta, sin theta)`, `rho = 2^xi - 1`, `theta = 2 pi xi'` (the `exp`
    /// distribution), traced at depth + 2 without anti-aliasing bookkeeping.
    ///
    /// When `track_noise` is set, the variance of the mean, scaled by `weight` (the reflection's
    /// weight in the colour), is added to the context's estimate.
    #[allow(clippy::too_many_arguments)]
    fn glossy(
        &self,
        cx: &mut TraceContext<'_>,
        surface: &Interaction,
        reflected: DVec3,
        drefl: f64,
        depth: u32,
        sib: Siblings,
        weight: f64,
        track_noise: bool,
    ) -> DVec3 {
        let lobe = GlossyLobe::new(reflected, drefl);
        let strata = self.glossy_strata;
        let total = strata.count();
        let k = sib.share(total);
        let shift = hash_values(&[cx.rng.key(), depth as u64, GLOSSY_PURPOSE]);
        let mut sum = DVec3::ZERO;
        let mut errors = StratumErrors::new(strata, track_noise);
        for j in 0..k {
            let s = sib.stratum(j, total, shift);
            let (xi, xi2) = strata.sample(s, cx.rng);
            let dir = lobe.direction(xi, xi2);
            let c = self.trace(cx, &surface.spawn(dir), depth + 2, sib.nested(k, j), None);
            sum += c;
            errors.record(s, c);
        }
        if track_noise {
            cx.variance += weight * weight * errors.variance_of_mean(k);
        }
        sum / k as f64
    }
}

/// The error estimate of a stratified mean, from the samples' second differences along the rows
/// of the stratum grid: for three neighbouring cells, `(f0 - 2 f1 + f2)^2 / 6` estimates the
/// variance of one sample about its cell's mean, free of any linear trend across the cells. The
/// mean of `k` samples then has variance `sigma^2 / k`. Unlike the plain sample variance, the
/// estimate stays small for a smooth integrand (whose error stratification removes) and grows where
/// the integrand jumps inside the pattern (a shadow or object edge).
struct StratumErrors {
    strata: Strata,
    /// Sample value of each stratum, when recording.
    values: Vec<Option<f64>>,
}

impl StratumErrors {
    /// Records samples of `strata` when `enabled`; otherwise costs nothing.
    fn new(strata: Strata, enabled: bool) -> StratumErrors {
        let len = if enabled { strata.count() as usize } else { 0 };
        StratumErrors { strata, values: vec![None; len] }
    }

    /// Records the value (largest channel) of the sample taken in stratum `s`.
    #[inline]
    fn record(&mut self, s: u32, value: DVec3) {
        if let Some(slot) = self.values.get_mut(s as usize) {
            *slot = Some(value.max_element());
        }
    }

    /// The estimated variance of the mean of the `k` samples recorded.
    fn variance_of_mean(&self, k: u32) -> f64 {
        let nx = self.strata.nx as usize;
        let (mut sum, mut triples) = (0.0, 0u32);
        for row in self.values.chunks(nx) {
            for w in row.windows(3) {
                if let [Some(a), Some(b), Some(c)] = *w {
                    sum += (a - 2.0 * b + c).powi(2) / 6.0;
                    triples += 1;
                }
            }
        }
        if triples == 0 { 0.0 } else { sum / triples as f64 / k as f64 }
    }
}

#[inline]
fn mix_tag(tag: &mut Option<&mut u64>, value: u64) {
    if let Some(t) = tag {
        **t = mix64(**t ^ value.wrapping_mul(0x2545_f491_4f6c_dd1d));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::TextureSearch;
    use crate::scene::{SourceFile, parse};

    fn scene(text: &str) -> PreparedScene {
        let parsed = parse(&SourceFile::from_text("test.txt", None, text.to_owned())).expect("valid scene");
        PreparedScene::new(parsed.scene, &TextureSearch::default()).expect("prepared")
    }

    /// The colour along one ray, with its ray count and tag.
    fn shoot(scene: &PreparedScene, origin: DVec3, dir: DVec3) -> (DVec3, u64, u64) {
        let mut rng = PixelRng::new(0, 0, 0, 0);
        let mut cx = TraceContext::new(&mut rng);
        let mut tag = 0;
        let c =
            Classic::new(scene).radiance(&mut cx, &Ray::new(origin, dir), Siblings::ALONE, Some(&mut tag));
        (c, cx.rays, tag)
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).abs().max_element() < 1e-12
    }

    const FLOOR: &str = "primitive plane\n N= 0 0 1\n R= 0\n color= 0.5 0.4 0.3\n diff= 0.8\nend\n";

    #[test]
    fn point_light_straight_above_a_diffuse_plane_gives_color_light_diff() {
        let s = scene(&format!("light point\n O= 0 0 5\n color= 0.9 0.9 0.9\nend\n{FLOOR}"));
        let (c, rays, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        assert!(close(c, DVec3::new(0.5, 0.4, 0.3) * 0.9 * 0.8), "{c}");
        assert_eq!(rays, 2, "one camera ray, one shadow ray");
    }

    #[test]
    fn ambient_term_is_color_background_diff() {
        let s = scene(&format!("background\n color= 0.2 0.1 0.0\nend\n{FLOOR}"));
        let (c, _, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        assert!(close(c, DVec3::new(0.5 * 0.2, 0.4 * 0.1, 0.0) * 0.8), "{c}");
    }

    #[test]
    fn highlight_is_spec_times_n_dot_l_to_the_twentieth() {
        // Light at 60 degrees from the normal: N.L = 0.5.
        let text = "light point\n O= 0 0 0\n color= 1 1 1\nend\n\
                    primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n spec= 0.5\nend\n";
        let light = DVec3::new(3f64.sqrt(), 0.0, 1.0) * 2.0;
        let s = scene(&text.replace("O= 0 0 0", &format!("O= {} {} {}", light.x, light.y, light.z)));
        // Seen from anywhere: the highlight does not depend on the view.
        for eye in [DVec3::new(0.0, 0.0, 1.0), DVec3::new(-3.0, 1.0, 0.5)] {
            let (c, _, _) = shoot(&s, eye, -eye);
            assert!(close(c, DVec3::splat(0.5 * 0.5f64.powi(20))), "{c}");
        }
    }

    #[test]
    fn shadowed_point_keeps_only_the_ambient_term() {
        let text = format!(
            "background\n color= 0.5 0.5 0.5\nend\nlight point\n O= 0 0 5\n color= 1 1 1\nend\n{FLOOR}\
             primitive sphere\n O= 0 0 2.5\n R= 0.5\n refr= 1\n rindex= 1\nend\n"
        );
        let s = scene(&text);
        let (c, _, lit_tag) = shoot(&s, DVec3::new(2.0, 0.0, 1.0), DVec3::new(-2.0, 0.0, -1.0));
        assert!(close(c, DVec3::new(0.5, 0.4, 0.3) * 0.5 * 0.8), "transparent objects block fully: {c}");
        // A lit point of the same surface has another tag: the shadow border is an edge.
        let (_, _, shadow_tag) = shoot(&s, DVec3::new(2.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -1.0));
        assert_ne!(lit_tag, shadow_tag);
    }

    #[test]
    fn light_behind_the_surface_gives_nothing() {
        let s = scene(&format!("light point\n O= 0 0 -5\n color= 1 1 1\nend\n{FLOOR}"));
        let (c, rays, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        assert_eq!(c, DVec3::ZERO);
        assert_eq!(rays, 1, "no shadow ray for a light behind the surface");
    }

    #[test]
    fn colours_clamp_at_one() {
        let s = scene(&format!("light point\n O= 0 0 5\n color= 10 10 10\nend\n{FLOOR}"));
        let (c, _, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        assert_eq!(c, DVec3::ONE);
    }

    #[test]
    fn mirror_reflects_the_background_times_refl_and_color() {
        let text = "background\n color= 0.2 0.4 0.8\nend\n\
                    primitive plane\n N= 0 0 1\n R= 0\n color= 1 0.5 0.25\n refl= 0.5\nend\n";
        let (c, rays, _) = shoot(&scene(text), DVec3::new(-1.0, 0.0, 1.0), DVec3::new(1.0, 0.0, -1.0));
        assert!(close(c, DVec3::new(0.2, 0.2, 0.2) * 0.5), "{c}");
        assert_eq!(rays, 2);
    }

    #[test]
    fn glossy_reflection_of_a_uniform_sky_is_the_mirror_image() {
        let text = "background\n color= 0.2 0.4 0.8\nend\ncamera\n drefl_quality= 2\nend\n\
                    primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n refl= 1\n drefl= 0.3\nend\n";
        let (c, rays, _) = shoot(&scene(text), DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.1, 0.0, -1.0));
        assert!(close(c, DVec3::new(0.2, 0.4, 0.8)), "{c}");
        assert_eq!(rays, 1 + 32, "16 * drefl_quality glossy rays");
    }

    #[test]
    fn glass_ball_absorbs_along_its_diameter() {
        let text = "background\n color= 1 1 1\nend\n\
                    primitive sphere\n O= 0 0 0\n R= 1\n refr= 1\n rindex= 1.5\n absor= 1 0 0.5\nend\n";
        let (c, rays, _) = shoot(&scene(text), DVec3::new(0.0, -5.0, 0.0), DVec3::Y);
        assert!((c - DVec3::new((-2.0f64).exp(), 1.0, (-1.0f64).exp())).abs().max_element() < 1e-9, "{c}");
        assert_eq!(rays, 3, "in, out, background");
    }

    #[test]
    fn total_internal_reflection_keeps_the_ray_inside() {
        // A ray inside a glass ball (index 2, critical angle 30 degrees) hitting the surface at 45
        // degrees reflects; its path runs around the ball until the depth limit.
        let text = "background\n color= 1 1 1\nend\n\
                    primitive sphere\n O= 0 0 0\n R= 1\n refr= 1\n rindex= 2\nend\n";
        let s = scene(text);
        let start = DVec3::new(-(0.5f64).sqrt(), -(0.5f64).sqrt(), 0.0) * 0.999;
        let (c, rays, _) = shoot(&s, start, DVec3::X);
        assert_eq!(c, DVec3::ZERO, "trapped light never reaches the sky");
        assert_eq!(rays, MAX_DEPTH as u64);
    }

    #[test]
    fn two_facing_mirrors_stop_at_the_depth_limit() {
        let text = "background\n color= 1 1 1\nend\n\
                    primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n refl= 1\nend\n\
                    primitive plane\n N= 0 0 -1\n R= -1\n color= 1 1 1\n refl= 1\nend\n";
        let (c, rays, _) = shoot(&scene(text), DVec3::new(0.0, 0.0, 0.5), DVec3::Z);
        assert_eq!(c, DVec3::ZERO);
        assert_eq!(rays, MAX_DEPTH as u64);
    }

    #[test]
    fn fully_visible_area_light_equals_a_point_light_at_its_centre() {
        let area = scene(&format!(
            "light area\n O= 0 0 5\n Dx= 1 0 0\n Dy= 0 1 0\n color= 0.9 0.9 0.9\nend\n{FLOOR}"
        ));
        let point = scene(&format!("light point\n O= 0 0 5\n color= 0.9 0.9 0.9\nend\n{FLOOR}"));
        let eye = DVec3::new(0.3, 0.2, 1.0);
        let (a, rays, _) = shoot(&area, eye, DVec3::new(0.1, -0.3, -1.0));
        let (p, _, _) = shoot(&point, eye, DVec3::new(0.1, -0.3, -1.0));
        assert!(close(a, p), "{a} vs {p}");
        assert_eq!(rays, 1 + 16 * 4, "16 * shade_quality shadow rays (default quality 4)");
    }

    #[test]
    fn half_covered_area_light_gives_half_the_light() {
        // A blocker over x < 0 hides exactly half of the stratified light from the origin.
        let text = format!(
            "camera\n shade_quality= 1\nend\nlight square\n O= 0 0 5\n Dx= 1 0 0\n Dy= 0 1 0\n color= 1 1 1\nend\n{FLOOR}\
             primitive square\n O= -10 0 2.5\n Dx= 10 0 0\n Dy= 0 10 0\nend\n"
        );
        let s = scene(&text);
        let (c, _, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        let d = 5.0 / (5.0f64 * 5.0).sqrt();
        assert!(close(c, DVec3::new(0.5, 0.4, 0.3) * 0.8 * d * 0.5), "{c}");
    }

    #[test]
    fn sphere_light_is_visible_and_does_not_shadow_itself() {
        let text = format!("light sphere\n O= 0 0 5\n R= 1\n color= 2 0.5 0.9\nend\n{FLOOR}");
        let s = scene(&text);
        let (seen, rays, _) =
            shoot(&s, DVec3::new(0.0, 0.0, 10.0), DVec3::new(0.0, 0.0, 1.0).reflect(DVec3::Z).normalize());
        assert_eq!(seen, DVec3::new(1.0, 0.5, 0.9), "the light's colour, clamped");
        assert_eq!(rays, 1);
        let (lit, _, _) = shoot(&s, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z);
        assert!(
            close(lit, (DVec3::new(0.5, 0.4, 0.3) * DVec3::new(2.0, 0.5, 0.9) * 0.8).min(DVec3::ONE)),
            "{lit}"
        );
    }

    #[test]
    fn refraction_obeys_snell_and_reflects_past_the_critical_angle() {
        let n = DVec3::Z;
        let v = DVec3::new(0.6, 0.0, -0.8);
        let t = refract(v, n, 1.0 / 1.5);
        assert!((t.length() - 1.0).abs() < 1e-12);
        let sin_t = t.x;
        assert!((sin_t - 0.6 / 1.5).abs() < 1e-12, "sin t = {sin_t}");
        // From glass to air at 53 degrees: beyond the critical angle (41.8 degrees).
        let steep = DVec3::new(0.8, 0.0, -0.6);
        let tir = refract(steep, n, 1.5);
        assert!((tir - DVec3::new(0.8, 0.0, 0.6)).length() < 1e-12);
        // Straight through at normal incidence.
        assert!((refract(-DVec3::Z, n, 1.7) + DVec3::Z).length() < 1e-12);
    }
}
