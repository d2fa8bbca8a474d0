//! Stochastic progressive photon mapping (Hachisuka and Jensen 2009, as pbrt-v4 computes it),
//! over the path tracer's camera walk, the shared lights and lobes, and the [`PhotonMap`].
//!
//! Each pass:
//! 1. *Camera pass.* Every pixel traces one camera path (its own random stream: seed, pixel,
//!    pass) exactly as the path tracer does, except that at each surface vertex the path picks
//!    the diffuse lobe with its sampling probability `p`: it then estimates the direct light
//!    there by next-event estimation (weight `1 / p`), leaves a *visible point* and stops;
//!    otherwise it goes on through the glossy and specular lobes (weight `1 / (1 - p)`). Lights
//!    seen along the way and direct light count as in the path tracer.
//! 2. *Photon pass.* `photons` photons leave the lights and the environment in proportion to
//!    their power (photon `i` of pass `j` has its own stream: seed, pass, index) and scatter by
//!    the same lobes, with Russian roulette. Every hit of a surface with a diffuse lobe after at
//!    least one bounce (or the first hit of an environment photon, whose light next-event
//!    estimation does not sample) is stored with its power and depth.
//! 3. *Update.* Each visible point gathers the stored photons within its radius `r` that arrived
//!    on its side and whose whole path (camera segments plus photon segments) is at most
//!    `max_depth` segments long: `Phi` = the sum of their powers, `M` their count. Then, with
//!    `gamma` the radius reduction (`reduction=`, default 2/3):
//!    `N' = N + gamma M`, `r' = r sqrt(N' / (N + M))`, `tau' = (tau + beta f Phi) r'^2 / r^2`,
//!    where `beta` is the camera path's throughput and `f = diff c / pi` the visible point's
//!    Lambertian lobe.
//!
//! After `P` passes of `N` photons a pixel is `direct / P + tau / (P N pi r^2)`. The initial
//! radius is `sample_dist=` in a file that chooses progressive photon mapping itself
//! (`algorithm= PPM` or `SPPM`, as students' progressive renderers read it); otherwise it is
//! [`AUTO_RADIUS_PIXELS`] pixel footprints at the pixel's first visible point (the camera path's
//! length times the angle of a pixel), at most `sample_dist=` (which the course's photon mapper
//! reads as its largest gathering radius).
//!
//! Photons are traced in batches of [`BATCH`] (a photon map each), so memory stays bounded
//! whatever the count; the statistics of a pass sum over its batches. Everything is
//! deterministic: pixels and photons draw from their own streams, photons are stored in index
//! order, and every pixel sums its photons in the map's fixed order, so the image does not depend
//! on the thread count, and any set of rows renders to the same values on its own.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::base::rows::Rows;
use crate::base::sampler::{PixelRng, stream};
use crate::camera::Camera;
use crate::integrator::bsdf::{Bsdf, Transport, class};
use crate::integrator::lights::Lights;
use crate::integrator::path::{Vertex, walk};
use crate::integrator::photon_map::{MapEntry, PhotonMap};
pub use crate::integrator::report::SppmStats;
use crate::prepare::PreparedScene;
use crate::scene::{Diagnostic, PhotonSettings, Severity};

/// Photons traced into one photon map.
pub const BATCH: u64 = 1 << 18;
/// Photons a worker traces in one go.
const CHUNK: u64 = 1 << 10;
/// The initial radius, in pixel footprints, when the scene sets no `sample_dist=`.
pub const AUTO_RADIUS_PIXELS: f64 = 2.0;
/// Photon depth from which Russian roulette may end a photon's path.
const PHOTON_RR_DEPTH: u32 = 3;

/// An SPPM photon as stored: where it landed, its direction of travel, its power and the number of
/// segments of its path from the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppmPhoton {
    /// Hit point, world space.
    pub position: Vec3,
    /// Unit direction of travel when it arrived.
    pub direction: Vec3,
    /// Power, linear RGB.
    pub power: Vec3,
    /// Segments from the light to here (1 for a photon that arrives straight from a light).
    pub depth: u32,
}

impl MapEntry for SppmPhoton {
    #[inline]
    fn position(&self) -> Vec3 {
        self.position
    }
}

/// The settings of an SPPM render.
#[derive(Clone, Debug, PartialEq)]
pub struct SppmSettings {
    /// Passes (`iterations=`, or `--passes`).
    pub passes: u64,
    /// Photons each pass (`emit_photons=`, or `--photons`).
    pub photons: u64,
    /// Radius reduction `gamma` (`reduction=`), in (0, 1].
    pub reduction: f64,
    /// Initial radius (`sample_dist=` in a file with `algorithm= PPM|SPPM`); `None`:
    /// [`AUTO_RADIUS_PIXELS`] pixel footprints, at most `max_radius`.
    pub initial_radius: Option<f64>,
    /// The largest automatic initial radius (`sample_dist=`).
    pub max_radius: f64,
    /// Deepest light path, in segments.
    pub max_depth: u32,
    /// Seed of all random streams.
    pub seed: u64,
}

impl SppmSettings {
    /// The settings a scene's photon keys give, with a render's overrides. `progressive` says
    /// whether the file chose progressive photon mapping itself (`algorithm= PPM|SPPM`), which
    /// makes `sample_dist=` the initial radius.
    pub fn new(
        photons: &PhotonSettings,
        progressive: bool,
        passes: Option<u64>,
        max_depth: u32,
        seed: u64,
    ) -> SppmSettings {
        let set = photons.location_of("sample_dist").is_some();
        SppmSettings {
            passes: passes.unwrap_or(photons.iterations),
            photons: photons.emit_photons,
            reduction: photons.reduction,
            initial_radius: (progressive && set).then_some(photons.sample_dist),
            max_radius: if set { photons.sample_dist } else { f64::INFINITY },
            max_depth,
            seed,
        }
    }
}

/// Bytes of memory an SPPM render keeps for each pixel.
pub const BYTES_PER_PIXEL: u64 =
    (std::mem::size_of::<PixelState>() + std::mem::size_of::<VisiblePoint>()) as u64;
/// Bytes of the photon maps of a batch, at most (photons of the batch times their depth limit).
pub fn batch_bytes(max_depth: u32) -> u64 {
    BATCH * max_depth.max(1) as u64 * (std::mem::size_of::<SppmPhoton>() as u64 + 2)
}

/// Refuses an SPPM render of `pixels` pixels that `max_hitpoints=` does not allow (SPPM keeps one
/// visible point a pixel), or whose memory would exceed `limit` bytes, before anything is
/// allocated.
pub fn check_memory(
    photons: &PhotonSettings,
    pixels: u64,
    max_depth: u32,
    limit: u64,
) -> Result<(), Diagnostic> {
    if let Some(max) = photons.max_hitpoints
        && pixels > max
    {
        return Err(Diagnostic {
            severity: Severity::Error,
            message: format!(
                "SPPM keeps one visible point a pixel: {pixels} pixels, but `max_hitpoints= {max}` allows fewer"
            ),
            location: photons.location_of("max_hitpoints").cloned(),
            notes: vec!["raise `max_hitpoints=` or render a smaller image (`--size`)".into()],
        });
    }
    let bytes = pixels.saturating_mul(BYTES_PER_PIXEL).saturating_add(batch_bytes(max_depth));
    if bytes > limit {
        return Err(Diagnostic {
            severity: Severity::Error,
            message: format!(
                "an SPPM render of {pixels} pixels would need {} of memory, over the limit of {}",
                crate::base::memory::format_bytes(bytes),
                crate::base::memory::format_bytes(limit)
            ),
            location: None,
            notes: vec![format!("{BYTES_PER_PIXEL} bytes a pixel; render a smaller image (`--size`)")],
        });
    }
    Ok(())
}

/// The state of one pixel across passes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct PixelState {
    /// Sum over passes of the light the camera paths gathered directly.
    direct: DVec3,
    /// The accumulated, radius-scaled flux.
    tau: DVec3,
    /// The photon count `N` of the estimate.
    n: f64,
    /// The squared radius; 0 until the pixel's first visible point sets it.
    r2: f64,
}

/// The visible point of a pixel in one pass.
#[derive(Clone, Copy, Debug, Default)]
struct VisiblePoint {
    point: DVec3,
    /// Normal on the viewer's side.
    normal: DVec3,
    /// `beta f`: the camera path's throughput times the Lambertian lobe `diff c / pi`; zero when
    /// the pixel has no visible point this pass.
    weight: DVec3,
    /// Segments of the camera path.
    depth: u32,
    /// The initial radius this point would give (pixel footprints, or `sample_dist=`).
    radius: f64,
    /// Sum of the powers of the photons gathered this pass.
    phi: DVec3,
    /// Photons gathered this pass.
    m: u64,
}

/// The state of an SPPM render of some rows between two passes: all it needs to go on, so that
/// a render resumed from it ([`render_from`]) gives the very values of one that never stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct SppmState {
    /// Passes finished.
    pub passes_done: u64,
    /// Each pixel's state, in the order of [`Rows::ys`].
    pixels: Vec<PixelState>,
    /// What the finished passes did (rays, photons; `mean_radius` is set at the end).
    pub stats: SppmStats,
}

impl SppmState {
    /// Values a pixel holds in [`SppmState::values`].
    pub const VALUES_PER_PIXEL: usize = 8;

    /// The state before the first pass of a render of `pixels` pixels.
    pub fn new(pixels: usize) -> SppmState {
        SppmState { passes_done: 0, pixels: vec![PixelState::default(); pixels], stats: SppmStats::default() }
    }

    /// The pixels' state as [`Self::VALUES_PER_PIXEL`] numbers a pixel (to be saved exactly).
    pub fn values(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.pixels.len() * Self::VALUES_PER_PIXEL);
        for p in &self.pixels {
            out.extend_from_slice(&[
                p.direct.x, p.direct.y, p.direct.z, p.tau.x, p.tau.y, p.tau.z, p.n, p.r2,
            ]);
        }
        out
    }

    /// The state [`Self::values`] saved, after `passes_done` passes that did `stats`.
    pub fn from_values(passes_done: u64, values: &[f64], stats: SppmStats) -> SppmState {
        let pixels = values
            .chunks_exact(Self::VALUES_PER_PIXEL)
            .map(|v| PixelState {
                direct: DVec3::new(v[0], v[1], v[2]),
                tau: DVec3::new(v[3], v[4], v[5]),
                n: v[6],
                r2: v[7],
            })
            .collect();
        SppmState { passes_done, pixels, stats }
    }

    /// The number of pixels.
    pub fn pixels(&self) -> usize {
        self.pixels.len()
    }
}

/// Renders the pixels of `rows` (in the order of [`Rows::ys`]), seen through `camera`, with SPPM.
/// `progress(passes)` is called after each pass.
pub fn render(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &SppmSettings,
    rows: &Rows,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<DVec3>, SppmStats) {
    render_from(
        scene,
        camera,
        settings,
        rows,
        SppmState::new(rows.len()),
        &mut |_| ControlFlow::Continue(()),
        progress,
    )
}

/// [`render`] from `state` (the state after some passes of the same render, or
/// [`SppmState::new`]), calling `after_pass` with the state after each pass but the last. When
/// `after_pass` breaks, the render stops there and returns the image of the passes done.
///
/// # Panics
/// If `state` is not a state of `rows.len()` pixels.
pub fn render_from(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &SppmSettings,
    rows: &Rows,
    state: SppmState,
    after_pass: &mut dyn FnMut(&SppmState) -> ControlFlow<()>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<DVec3>, SppmStats) {
    let lights = Lights::new(scene);
    let image_width = rows.width();
    let w = image_width as usize;
    let ys: Vec<u32> = rows.ys().collect();
    let pixels = rows.len();
    assert_eq!(state.pixels.len(), pixels, "an SPPM state of another set of rows");
    if pixels == 0 {
        return (Vec::new(), SppmStats::default());
    }
    let SppmState { passes_done, pixels: mut states, mut stats } = state;
    let mut points = vec![VisiblePoint::default(); pixels];
    let rays = AtomicU64::new(stats.rays);
    let cam = &scene.scene.camera;
    let pixel_angle = cam.lens_width / image_width as f64;
    let mut photon_seconds = stats.photon_seconds;
    let mut passes_run = settings.passes;
    for pass in passes_done..settings.passes {
        // 1. Camera pass.
        points.par_chunks_mut(w).zip(states.par_chunks_mut(w)).enumerate().for_each(
            |(row, (points, states))| {
                let y = ys[row];
                let mut row_rays = 0;
                for (i, (vp, state)) in points.iter_mut().zip(states.iter_mut()).enumerate() {
                    let x = i as u32;
                    let mut rng = PixelRng::for_sample(settings.seed, stream::SPPM_CAMERA, x, y, pass);
                    let (dx, dy) = (rng.uniform(), rng.uniform());
                    let lens = if camera.has_lens() { (rng.uniform(), rng.uniform()) } else { (0.0, 0.0) };
                    let ray = camera.ray(x as f64 + dx, y as f64 + dy, lens);
                    *vp = VisiblePoint::default();
                    let mut length = 0.0;
                    let result = walk(
                        scene,
                        &lights,
                        settings.max_depth,
                        ray,
                        &mut rng,
                        |bsdf, at, depth, beta, _, rng| {
                            length += at.t;
                            let p = bsdf.class_probability(class::ALL, class::DIFFUSE);
                            if p > 0.0 && rng.uniform() < p {
                                *vp = VisiblePoint {
                                    point: at.point,
                                    normal: at.normal,
                                    weight: beta / p * bsdf.diffuse_albedo() * std::f64::consts::FRAC_1_PI,
                                    depth,
                                    radius: settings
                                        .initial_radius
                                        .unwrap_or(AUTO_RADIUS_PIXELS * length * pixel_angle),
                                    phi: DVec3::ZERO,
                                    m: 0,
                                };
                                Vertex { lobes: class::DIFFUSE, scale: 1.0 / p, stop: true }
                            } else {
                                Vertex {
                                    lobes: class::GLOSSY | class::SPECULAR,
                                    scale: 1.0 / (1.0 - p),
                                    stop: false,
                                }
                            }
                        },
                    );
                    state.direct += result.radiance;
                    row_rays += result.rays;
                    if vp.weight != DVec3::ZERO && state.r2 == 0.0 {
                        state.r2 = vp.radius * vp.radius;
                    }
                }
                rays.fetch_add(row_rays, Ordering::Relaxed);
            },
        );

        // 2. Photon pass, batch by batch.
        let mut start = 0;
        while start < settings.photons {
            let end = (start + BATCH).min(settings.photons);
            let began = Instant::now();
            let chunks: Vec<(Vec<SppmPhoton>, u64)> = (start..end)
                .step_by(CHUNK as usize)
                .collect::<Vec<u64>>()
                .into_par_iter()
                .map(|from| {
                    let mut out = Vec::new();
                    let mut chunk_rays = 0;
                    for i in from..(from + CHUNK).min(end) {
                        chunk_rays += trace_photon(scene, &lights, settings, pass, i, &mut out);
                    }
                    (out, chunk_rays)
                })
                .collect();
            let mut stored = Vec::with_capacity(chunks.iter().map(|c| c.0.len()).sum());
            for (photons, chunk_rays) in chunks {
                stored.extend_from_slice(&photons);
                rays.fetch_add(chunk_rays, Ordering::Relaxed);
            }
            stats.stored += stored.len() as u64;
            let map = PhotonMap::build(stored);
            photon_seconds += began.elapsed().as_secs_f64();
            if !map.is_empty() {
                points.par_chunks_mut(w).zip(states.par_chunks(w)).for_each(|(points, states)| {
                    for (vp, state) in points.iter_mut().zip(states) {
                        if vp.weight == DVec3::ZERO {
                            continue;
                        }
                        let n = vp.normal.as_vec3();
                        let budget = settings.max_depth.saturating_sub(vp.depth);
                        map.for_each_within(vp.point, state.r2 as f32, |i, _| {
                            let photon = map.photon(i);
                            if photon.direction.dot(n) < 0.0 && photon.depth <= budget {
                                vp.phi += photon.power.as_dvec3();
                                vp.m += 1;
                            }
                        });
                    }
                });
            }
            stats.photons += end - start;
            start = end;
        }

        // 3. Update.
        states.par_iter_mut().zip(points.par_iter()).for_each(|(state, vp)| {
            if vp.m == 0 {
                return;
            }
            let m = vp.m as f64;
            let n_new = state.n + settings.reduction * m;
            let r2_new = state.r2 * n_new / (state.n + m);
            state.tau = (state.tau + vp.weight * vp.phi) * (r2_new / state.r2);
            state.n = n_new;
            state.r2 = r2_new;
        });
        stats.passes += 1;
        progress(pass + 1);
        if pass + 1 < settings.passes {
            let stats = SppmStats { rays: rays.load(Ordering::Relaxed), photon_seconds, ..stats };
            // The pixel states move into the saved state and back: no copy.
            let saved = SppmState { passes_done: pass + 1, pixels: std::mem::take(&mut states), stats };
            let flow = after_pass(&saved);
            states = saved.pixels;
            if flow.is_break() {
                passes_run = pass + 1;
                break;
            }
        }
    }

    let passes = passes_run.max(1) as f64;
    let emitted = (passes_run * settings.photons).max(1) as f64;
    let (mut radius_sum, mut with_radius) = (0.0, 0u64);
    let image = states
        .iter()
        .map(|s| {
            let mut c = s.direct / passes;
            if s.r2 > 0.0 {
                c += s.tau / (emitted * std::f64::consts::PI * s.r2);
                radius_sum += s.r2.sqrt();
                with_radius += 1;
            }
            c
        })
        .collect();
    stats.rays = rays.load(Ordering::Relaxed);
    stats.photon_seconds = photon_seconds;
    stats.mean_radius = if with_radius > 0 { radius_sum / with_radius as f64 } else { 0.0 };
    (image, stats)
}

/// Traces photon `index` of pass `pass`, appending the photons it stores to `out`; returns the
/// rays traced.
fn trace_photon(
    scene: &PreparedScene,
    lights: &Lights<'_>,
    settings: &SppmSettings,
    pass: u64,
    index: u64,
    out: &mut Vec<SppmPhoton>,
) -> u64 {
    let mut rng = PixelRng::for_photon(settings.seed, stream::SPPM_PHOTON, pass, index);
    let Some(emitted) = lights.emit(&mut rng) else { return 0 };
    let mut ray = emitted.ray;
    let mut beta = emitted.power;
    let mut rays = 0;
    // A photon of `depth` segments is only of use to a camera path of at most
    // `max_depth - depth` segments, which has at least one.
    for depth in 1..settings.max_depth {
        rays += 1;
        let crate::prepare::Hit::Surface { primitive, hit } = scene.closest_hit(&ray) else { break };
        let at = scene.interaction(&ray, primitive, hit);
        let material = scene.course_material(primitive);
        if !at.front && material.refr > 0.0 {
            beta *= (-material.absor * at.t).exp();
        }
        let bsdf = Bsdf::new(material, scene.surface_color(&at), &at);
        if (depth > 1 || emitted.from_environment) && bsdf.has(class::DIFFUSE) {
            out.push(SppmPhoton {
                position: at.point.as_vec3(),
                direction: ray.dir.as_vec3(),
                power: beta.as_vec3(),
                depth,
            });
        }
        let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
        let Some(s) = bsdf.sample(-ray.dir, u, u1, u2, class::ALL, Transport::Importance) else { break };
        let next = beta * s.weight;
        if depth >= PHOTON_RR_DEPTH {
            // Keep the photon with the ratio of its new power to its old: surviving photons
            // keep their power, as a photon map prefers.
            let q = (next.max_element() / beta.max_element()).min(1.0);
            if rng.uniform() >= q {
                break;
            }
            beta = next / q;
        } else {
            beta = next;
        }
        ray = at.spawn(s.wi);
    }
    rays
}
