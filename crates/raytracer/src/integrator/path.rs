//! The unidirectional path tracer (spec section 11): camera paths with next-event estimation at
//! every vertex with a smooth lobe, combined with BSDF sampling by multiple importance sampling
//! (power heuristic) for square and sphere lights, Russian roulette from [`RR_DEPTH`] segments
//! on, no clamping. The background is an environment light found by escaping rays.
//!
//! Depth counts segments, as in Mitsuba 3 and pbrt: with `max_depth = 1` only lights seen
//! directly appear, `2` adds direct lighting, and so on.
//!
//! The same walk is the camera pass of SPPM ([`crate::integrator::sppm`]), which stops it at a
//! diffuse vertex (see [`walk`] and [`Vertex`]).

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::base::rows::Rows;
use crate::base::sampler::{ExactSum, PixelRng, stream};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrator::bsdf::{Bsdf, Transport, class, power_heuristic};
use crate::integrator::direct::DirectTracer;
use crate::integrator::lights::Lights;
use crate::integrator::physical::PhysicalTracer;
use crate::prepare::{Hit, Interaction, PreparedScene};
use crate::scene::PixelFilter;

/// The path depth (segments) from which Russian roulette may end a path.
pub const RR_DEPTH: u32 = 5;
/// The default deepest path, in segments (`--max-depth`).
pub const DEFAULT_MAX_DEPTH: u32 = 10;
/// Largest survival probability of Russian roulette.
const RR_MAX_SURVIVAL: f64 = 0.95;

/// What to do at a surface vertex of a camera path, decided by the caller of [`walk`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// The lobe classes the path goes on with (see [`class`]); next-event estimation covers the
    /// smooth ones among them.
    pub lobes: u8,
    /// A factor of the path's throughput (for a choice made with some probability).
    pub scale: f64,
    /// Whether the path ends here after next-event estimation (which then takes the full weight:
    /// no BSDF sample follows to share it with).
    pub stop: bool,
}

impl Vertex {
    /// A vertex that goes on with every lobe (the path tracer's).
    pub const CONTINUE: Vertex = Vertex { lobes: class::ALL, scale: 1.0, stop: false };
}

pub use crate::integrator::report::PathResult;

/// Walks the camera path that starts with `ray`, drawing from `rng`, and returns the radiance it
/// gathers. At each surface vertex, `visit(bsdf, at, depth, beta, wo, rng)` chooses what happens
/// (see [`Vertex`]); `depth` is the number of segments up to the vertex and `beta` the throughput
/// up to it.
pub fn walk(
    scene: &PreparedScene,
    lights: &Lights<'_>,
    max_depth: u32,
    mut ray: Ray,
    rng: &mut PixelRng,
    mut visit: impl FnMut(&Bsdf, &Interaction, u32, DVec3, DVec3, &mut PixelRng) -> Vertex,
) -> PathResult {
    let mut out = PathResult::default();
    let mut beta = DVec3::ONE;
    // The previous vertex and the density of its BSDF sample (for MIS); `None` after the camera
    // or a delta lobe, whose emission hits take the full weight.
    let mut previous: Option<(DVec3, f64)> = None;
    let mut eta_scale = 1.0;
    let mut depth = 0u32;
    loop {
        out.rays += 1;
        let (primitive, hit) = match scene.closest_hit(&ray) {
            Hit::Miss => {
                out.radiance += beta * lights.environment(ray.dir);
                break;
            }
            Hit::Emitter { light, t } => {
                let le = lights.emitted(light, &ray, t);
                let weight = match previous {
                    Some((p, bsdf_pdf)) => power_heuristic(bsdf_pdf, lights.pdf(light, p, ray.dir, t)),
                    None => 1.0,
                };
                out.radiance += beta * le * weight;
                break;
            }
            Hit::Surface { primitive, hit } => (primitive, hit),
        };
        let at = scene.interaction(&ray, primitive, hit);
        let material = scene.course_material(primitive);
        if !at.front && material.refr > 0.0 {
            // The segment ran inside the transparent object: Beer's law.
            beta *= (-material.absor * at.t).exp();
        }
        depth += 1;
        if depth >= max_depth {
            break;
        }
        let bsdf = Bsdf::new(material, scene.surface_color(&at), &at);
        let wo = -ray.dir;
        let vertex = visit(&bsdf, &at, depth, beta, wo, rng);
        beta *= vertex.scale;
        let smooth = vertex.lobes & class::SMOOTH;
        if smooth != 0 && bsdf.has(smooth) && lights.any() {
            let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
            if let Some(ls) = lights.sample(at.point, u, u1, u2) {
                let pair = bsdf.local_pair(wo, ls.wi);
                let f = bsdf.eval_pair(&pair, smooth);
                if f != DVec3::ZERO && lights.unoccluded(at.spawn(ls.wi).origin, ls.target, &mut out.rays) {
                    let weight = if ls.delta || vertex.stop {
                        1.0
                    } else {
                        power_heuristic(ls.pdf, bsdf.pdf_pair(&pair, vertex.lobes))
                    };
                    out.radiance += beta * f * ls.radiance * (ls.wi.dot(at.normal).abs() * weight / ls.pdf);
                }
            }
        }
        if vertex.stop {
            break;
        }
        let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
        let Some(s) = bsdf.sample(wo, u, u1, u2, vertex.lobes, Transport::Radiance) else { break };
        beta *= s.weight;
        eta_scale *= s.eta_scale;
        previous = if s.delta { None } else { Some((at.point, s.pdf)) };
        ray = at.spawn(s.wi);
        if depth >= RR_DEPTH {
            let q = (beta.max_element() * eta_scale).min(RR_MAX_SURVIVAL);
            if rng.uniform() >= q {
                break;
            }
            beta /= q;
        }
    }
    out
}

/// The path tracer over a prepared scene.
#[derive(Debug)]
pub struct PathTracer<'s> {
    scene: &'s PreparedScene,
    lights: Lights<'s>,
    max_depth: u32,
}

impl<'s> PathTracer<'s> {
    /// The path tracer of `scene` with paths of at most `max_depth` segments.
    pub fn new(scene: &'s PreparedScene, max_depth: u32) -> PathTracer<'s> {
        PathTracer { scene, lights: Lights::new(scene), max_depth }
    }

    /// The radiance arriving along `ray` (one sample), drawing from `rng`.
    #[inline]
    pub fn radiance(&self, ray: Ray, rng: &mut PixelRng) -> PathResult {
        walk(self.scene, &self.lights, self.max_depth, ray, rng, |_, _, _, _, _, _| Vertex::CONTINUE)
    }
}

/// The path tracer a scene needs: the course's materials and lights, or the physically based
/// ones of Mitsuba scenes.
enum Tracer<'s> {
    Course(PathTracer<'s>),
    Physical(PhysicalTracer<'s>),
    /// Mitsuba's `direct` integrator, where the scene asks for it.
    Direct(DirectTracer<'s>),
}

impl<'s> Tracer<'s> {
    fn new(scene: &'s PreparedScene, max_depth: u32) -> Tracer<'s> {
        if scene.is_physical()
            && let Some(samples) = scene.scene.render.direct
        {
            Tracer::Direct(DirectTracer::new(scene, samples))
        } else if scene.is_physical() {
            Tracer::Physical(PhysicalTracer::new(scene, max_depth))
        } else {
            Tracer::Course(PathTracer::new(scene, max_depth))
        }
    }

    #[inline]
    fn radiance(&self, ray: Ray, rng: &mut PixelRng) -> PathResult {
        match self {
            Tracer::Course(t) => t.radiance(ray, rng),
            Tracer::Physical(t) => t.radiance(ray, rng),
            Tracer::Direct(t) => t.radiance(ray, rng),
        }
    }
}

/// Where in its pixel a sample goes, `(0, 0)` the top-left corner of pixel `pixel` of an image
/// of `size` pixels: drawn from the reconstruction filter's own density around the pixel's
/// centre (filter importance sampling), restricted to the image as Mitsuba's film restricts its
/// samples, so every sample weighs 1 and the pixel's mean converges to the filtered image
/// Mitsuba's weighted splatting converges to. The box filter draws exactly as the course's
/// sampler did.
#[inline]
pub fn filter_offset(
    filter: PixelFilter,
    rng: &mut PixelRng,
    pixel: (u32, u32),
    size: (f64, f64),
) -> (f64, f64) {
    let inside = |dx: f64, dy: f64| {
        (0.0..size.0).contains(&(pixel.0 as f64 + dx)) && (0.0..size.1).contains(&(pixel.1 as f64 + dy))
    };
    match filter {
        PixelFilter::Box => (rng.uniform(), rng.uniform()),
        PixelFilter::Tent { radius } => {
            let tent = |u: f64| {
                if u < 0.5 {
                    radius * ((2.0 * u).sqrt() - 1.0)
                } else {
                    radius * (1.0 - (2.0 - 2.0 * u).sqrt())
                }
            };
            loop {
                let (dx, dy) = (0.5 + tent(rng.uniform()), 0.5 + tent(rng.uniform()));
                if inside(dx, dy) {
                    return (dx, dy);
                }
            }
        }
        PixelFilter::Gaussian { stddev } => {
            // Mitsuba's filter is `g(x) - g(R)` on [-R, R], R = 4 stddev, per axis: Gaussian pairs
            // (Box-Muller), kept with probability (g(x) - g(R)) (g(y) - g(R)) / (g(x) g(y)).
            let radius = 4.0 * stddev;
            let g = |x: f64| (-x * x / (2.0 * stddev * stddev)).exp();
            let floor = g(radius);
            loop {
                let (u1, u2, keep) = (rng.uniform(), rng.uniform(), rng.uniform());
                let r = stddev * (-2.0 * (1.0 - u1).ln()).sqrt();
                let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
                let (x, y) = (r * c, r * s);
                if x.abs() < radius
                    && y.abs() < radius
                    && keep * g(x) * g(y) < (g(x) - floor) * (g(y) - floor)
                    && inside(0.5 + x, 0.5 + y)
                {
                    return (0.5 + x, 0.5 + y);
                }
            }
        }
    }
}

/// The exact sums of the path tracer's samples `samples` (sample indices) of every pixel of
/// `rows` (in the order of [`Rows::ys`]) seen through `camera`, and the rays traced: the path
/// model's row loop. Sample `s` of pixel `(x, y)` draws from its own stream (`seed`, pixel, `s`),
/// so sums of disjoint sample ranges and rows merge ([`ExactSum::merge`]) into exactly the sums of
/// one render. `progress(done)` reports samples finished (pixels times samples) from worker
/// threads.
pub fn render_sums(
    scene: &PreparedScene,
    camera: &Camera,
    seed: u64,
    max_depth: u32,
    rows: &Rows,
    samples: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<ExactSum>, u64) {
    let tracer = Tracer::new(scene, max_depth);
    let filter = scene.scene.render.filter;
    let image_size = camera.image_size();
    let width = rows.width() as usize;
    let ys: Vec<u32> = rows.ys().collect();
    let mut sums = vec![ExactSum::default(); rows.len()];
    let rays = AtomicU64::new(0);
    let done = AtomicU64::new(0);
    let per_row = width as u64 * (samples.end.saturating_sub(samples.start));
    if width > 0 {
        sums.par_chunks_mut(width).enumerate().for_each(|(row, sums)| {
            let y = ys[row];
            let mut row_rays = 0;
            for (x, sum) in sums.iter_mut().enumerate() {
                let x = x as u32;
                for s in samples.clone() {
                    let mut rng = PixelRng::for_sample(seed, stream::PATH, x, y, s);
                    let (dx, dy) = filter_offset(filter, &mut rng, (x, y), image_size);
                    let lens = if camera.has_lens() { (rng.uniform(), rng.uniform()) } else { (0.0, 0.0) };
                    let result = tracer.radiance(camera.ray(x as f64 + dx, y as f64 + dy, lens), &mut rng);
                    sum.add(result.radiance);
                    row_rays += result.rays;
                }
            }
            rays.fetch_add(row_rays, Ordering::Relaxed);
            progress(done.fetch_add(per_row, Ordering::Relaxed) + per_row);
        });
    }
    (sums, rays.load(Ordering::Relaxed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SourceFile, parse};

    fn scene(text: &str) -> PreparedScene {
        let parsed = parse(&SourceFile::from_text("t.txt", None, text.to_owned())).expect("parses");
        PreparedScene::new(parsed.scene, &Default::default()).expect("prepares")
    }

    /// The mean radiance of `n` paths along `ray`.
    fn mean(tracer: &PathTracer<'_>, ray: Ray, n: u64) -> DVec3 {
        (0..n).map(|i| tracer.radiance(ray, &mut PixelRng::for_sample(0, 1, 0, 0, i)).radiance).sum::<DVec3>()
            / n as f64
    }

    #[test]
    fn a_point_light_on_a_diffuse_plane_gives_the_analytic_radiance_exactly() {
        // L = albedo / pi * I cos / d^2, with albedo = colour * diff; one light, no
        // environment: every path gives exactly this value.
        let s = scene(
            "light point\n O= 1 0 2\n color= 3 3 3\nend\n\
             primitive plane\n N= 0 0 1\n R= 0\n color= 0.8 0.6 0.4\n diff= 0.9\nend\n",
        );
        let tracer = PathTracer::new(&s, DEFAULT_MAX_DEPTH);
        for target in [DVec3::ZERO, DVec3::new(0.5, 0.3, 0.0), DVec3::new(-2.0, 1.0, 0.0)] {
            let eye = DVec3::new(0.2, -3.0, 1.5);
            let ray = Ray::new(eye, target - eye);
            let to_light = DVec3::new(1.0, 0.0, 2.0) - target;
            let d2 = to_light.length_squared();
            let cos = to_light.z / d2.sqrt();
            let expect = DVec3::new(0.8, 0.6, 0.4) * 0.9 / std::f64::consts::PI * 3.0 * cos / d2;
            for i in 0..16 {
                let got = tracer.radiance(ray, &mut PixelRng::for_sample(7, 1, 0, 0, i)).radiance;
                assert!(
                    (got - expect).abs().max_element() < 1e-12 * expect.max_element(),
                    "{got} vs {expect}"
                );
            }
        }
    }

    #[test]
    fn depth_counts_segments_as_mitsuba_does() {
        let text = "light sphere\n O= 0 0 3\n R= 0.5\n color= 4 4 4\nend\n\
                    primitive plane\n N= 0 0 1\n R= 0\n color= 1 1 1\n diff= 0.5\nend\n";
        let s = scene(text);
        let at_light = Ray::new(DVec3::new(0.0, -1.0, 3.0), DVec3::Y);
        let at_floor = Ray::new(DVec3::new(0.0, -1.0, 1.0), DVec3::new(0.0, 1.0, -1.0));
        let one = PathTracer::new(&s, 1);
        assert_eq!(mean(&one, at_light, 4), DVec3::splat(4.0), "depth 1: lights seen directly");
        assert_eq!(mean(&one, at_floor, 4), DVec3::ZERO);
        let two = PathTracer::new(&s, 2);
        assert!(mean(&two, at_floor, 64).x > 0.0, "depth 2: direct light");
    }

    #[test]
    fn the_white_furnace_is_white_at_every_depth_limit() {
        // A diffuse sphere of albedo 1 in a uniform environment of radiance 0.5 looks exactly
        // like the environment once paths are deep enough; Russian roulette keeps it unbiased.
        let s = scene(
            "background\n color= 0.5 0.5 0.5\nend\nprimitive sphere\n O= 0 0 0\n R= 1\n color= 1 1 1\n diff= 1\nend\n",
        );
        let ray = Ray::new(DVec3::new(0.3, -4.0, 0.2), DVec3::Y);
        for max_depth in [2, 3, 10] {
            // Convex: every bounce escapes, so two segments are enough.
            let got = mean(&PathTracer::new(&s, max_depth), ray, 64);
            assert!((got - DVec3::splat(0.5)).abs().max_element() < 1e-12, "depth {max_depth}: {got}");
        }
    }
}
