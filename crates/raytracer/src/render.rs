//! The render driver: pixels in parallel, adaptive anti-aliasing, progress and statistics.
//!
//! Adaptive mode (the default) improves on the template's edge resampling: every pixel first takes
//! one sample at its centre, recording a tag of what it saw (objects along the mirror and
//! refraction chain, lit point lights) and an estimate of its own noise (from the spread of its
//! area-light shadow rays and glossy directions). Then:
//! - every pixel whose tag differs from a neighbour's (a geometry or shadow edge) or whose colour
//!   differs from a neighbour's by more than [`CONTRAST_THRESHOLD`] (a texture or lighting edge)
//!   is re-rendered with a jittered `REFINE_GRID x REFINE_GRID` grid of samples, which replaces
//!   its first sample;
//! - every other pixel whose estimated error exceeds [`NOISE_THRESHOLD`] (a penumbra or a busy
//!   glossy reflection) keeps its first sample and adds a small `NOISE_GRID x NOISE_GRID` grid
//!   whose shadow and glossy samples bring the total to as many as its error estimate asks for
//!   (up to [`MAX_NESTED_FACTOR`] times the first pass's), the two averaged by their sample counts.
//!
//! (The template used a fixed 3 x 3 grid, on tag edges only.) Uniform mode takes the same number
//! of stratified samples in every pixel.
//!
//! Rows are rendered in parallel, but each pixel's random numbers come from its own coordinates,
//! so the image is the same bit for bit whatever the number of threads.
//!
//! The physically based models are driven here too. The path tracer renders any rectangle of
//! pixels over any range of sample indices ([`path_sums`]): every sample draws from its own stream
//! (seed, pixel, sample index) and a pixel's samples are summed exactly ([`ExactSum`]), so a
//! render split into tiles (pixel rectangles) and passes (sample ranges) merges into the same
//! bytes as one render: a pixel of `N` samples is `sum / N` whatever the grouping of its sums.
//! SPPM renders any rectangle of pixels ([`crate::integrator::sppm::render`]): its photons draw
//! from streams of (seed, pass, photon index), the same for every rectangle.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::image_io::Image;
use crate::integrator::classic::TraceContext;
use crate::integrator::path::{DEFAULT_MAX_DEPTH, PathTracer};
use crate::integrator::photon::{self, PhotonEstimate, PhotonStats};
use crate::integrator::sppm::{self, SppmSettings, SppmStats};
use crate::integrator::{Classic, Model};
use crate::prepare::{Hit, PreparedScene};
use crate::sampler::{ExactSum, PixelRng, Siblings, Strata, stream};
use crate::scene::{Algorithm, Diagnostic, PhotonSettings, check_image_size};

/// Side of the sample grid of a refined pixel in adaptive mode (16 samples).
pub const REFINE_GRID: u32 = 4;
/// Side of the sample grid a pixel refined for noise alone adds to its first sample (4 samples,
/// enough to spread the extra nested samples over the pixel's area).
pub const NOISE_GRID: u32 = 2;
/// Largest per-channel colour difference between neighbours that does not trigger refinement.
pub const CONTRAST_THRESHOLD: f64 = 0.1;
/// Largest estimated standard error of a pixel's first-pass colour that does not trigger
/// refinement (two 8-bit steps).
pub const NOISE_THRESHOLD: f64 = 2.0 / 255.0;
/// Most nested samples (shadow rays, glossy directions) a refined pixel takes, as a multiple of a
/// first-pass pixel's.
pub const MAX_NESTED_FACTOR: u32 = 4;
/// Largest `--spp`.
pub const MAX_SPP: u32 = 1 << 20;
/// Samples a pixel of the path tracer when none are asked for.
pub const DEFAULT_PATH_SPP: u32 = 64;
/// Deepest path `--max-depth` accepts.
pub const MAX_DEPTH_LIMIT: u32 = 1000;
/// The memory a render may use for its photon map unless told otherwise, in bytes (4 GiB).
pub const DEFAULT_MEMORY_LIMIT: u64 = 4 << 30;

/// How pixels are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One sample per pixel, then `REFINE_GRID^2` samples where an edge or a contrast is found.
    Adaptive,
    /// This many stratified samples in every pixel (`--spp N`).
    Uniform(u32),
}

/// Settings of one render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Pixel sampling.
    pub sampling: Sampling,
    /// Worker threads; `None` uses one per core.
    pub threads: Option<usize>,
    /// Seed of all random numbers.
    pub seed: u64,
    /// The light-transport model.
    pub model: Model,
    /// Photons to emit, instead of the scene's `emit_photons=` (`--photons`).
    pub photons: Option<u64>,
    /// Bytes the render's photon map may use at most.
    pub memory_limit: u64,
    /// Deepest light path of the physically based models, in segments (`--max-depth`).
    pub max_depth: u32,
    /// SPPM passes, instead of the scene's `iterations=` (`--passes`).
    pub passes: Option<u64>,
}

impl RenderSettings {
    /// The scene's photon settings with this render's overrides.
    pub fn photon_settings(&self, scene: &PreparedScene) -> PhotonSettings {
        let mut p = scene.scene.camera.photons.clone();
        if let Some(n) = self.photons {
            p.emit_photons = n;
        }
        p
    }

    /// The scene file's image size with adaptive sampling (uniform 16 samples when the camera
    /// has a lens: defocus blur needs samples everywhere, not only on edges), and the model its
    /// `algorithm=` names (see [`crate::integrator::choose_model`]).
    pub fn for_scene(scene: &PreparedScene) -> RenderSettings {
        let cam = &scene.scene.camera;
        RenderSettings {
            width: cam.image_width,
            height: cam.image_height,
            sampling: if cam.aperture > 0.0 { Sampling::Uniform(16) } else { Sampling::Adaptive },
            threads: None,
            seed: 0,
            model: crate::integrator::choose_model(&scene.scene, None).0,
            photons: None,
            memory_limit: DEFAULT_MEMORY_LIMIT,
            max_depth: DEFAULT_MAX_DEPTH,
            passes: None,
        }
    }

    /// The samples a pixel of the path tracer: `--spp`, else [`DEFAULT_PATH_SPP`].
    pub fn path_spp(&self) -> u32 {
        match self.sampling {
            Sampling::Uniform(n) => n,
            Sampling::Adaptive => DEFAULT_PATH_SPP,
        }
    }

    /// The SPPM settings: the scene's photon keys with this render's overrides.
    pub fn sppm_settings(&self, scene: &PreparedScene) -> SppmSettings {
        let progressive = matches!(
            scene.scene.camera.algorithm,
            Some((Algorithm::ProgressivePhotonMapping | Algorithm::StochasticProgressivePhotonMapping, _))
        );
        SppmSettings::new(&self.photon_settings(scene), progressive, self.passes, self.max_depth, self.seed)
    }
}

/// The stage a progress report is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Tracing photons from the lights (photon model; units are photons).
    TracingPhotons,
    /// Building the photon map's search tree (one unit).
    BuildingPhotonMap,
    /// Tracing every pixel.
    Tracing,
    /// Re-rendering the pixels on edges (adaptive mode).
    Refining,
    /// Path tracing (units are samples: pixels times samples a pixel).
    Sampling,
    /// SPPM passes (units are passes).
    Passes,
}

/// A progress report: `done` of `total` units (rows while tracing, pixels while refining, samples
/// while path tracing, passes of SPPM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The stage.
    pub stage: Stage,
    /// Units finished.
    pub done: u64,
    /// Units in the stage.
    pub total: u64,
}

/// Counts of the work a render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Rays traced: camera, reflected, refracted, glossy and shadow rays.
    pub rays: u64,
    /// Camera samples taken.
    pub camera_samples: u64,
    /// Pixels re-rendered by adaptive anti-aliasing.
    pub refined_pixels: u64,
    /// Worker threads used.
    pub threads: usize,
    /// Photon-map irradiance estimates (photon model).
    pub lookups: u64,
    /// The photon map's making (photon model).
    pub photons: Option<PhotonStats>,
    /// The passes and photons of an SPPM render.
    pub sppm: Option<SppmStats>,
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image, linear RGB.
    pub image: Image,
    /// What it took.
    pub stats: RenderStats,
}

/// Why a render could not start.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// An image size that is empty or too large.
    #[error("{0}")]
    ImageSize(String),
    /// A sample count out of range.
    #[error("the number of samples per pixel must be from 1 to {MAX_SPP}, not {0}")]
    SampleCount(u32),
    /// A path depth out of range.
    #[error("the path depth must be from 1 to {MAX_DEPTH_LIMIT}, not {0}")]
    Depth(u32),
    /// Settings the scene cannot be rendered with (for example a photon map over the memory
    /// limit), with where in the scene file.
    #[error("{0}")]
    Settings(Box<Diagnostic>),
    /// The worker threads could not be started.
    #[error("cannot start {threads} worker threads: {source}")]
    Threads {
        /// Threads asked for.
        threads: usize,
        /// Why not.
        #[source]
        source: rayon::ThreadPoolBuildError,
    },
}

/// Renders `scene` with the settings' model. `progress` is called from worker threads as work
/// finishes.
pub fn render(
    scene: &PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Rendered, RenderError> {
    check_image_size(settings.width, settings.height).map_err(RenderError::ImageSize)?;
    if let Sampling::Uniform(n) = settings.sampling
        && !(1..=MAX_SPP).contains(&n)
    {
        return Err(RenderError::SampleCount(n));
    }
    if !(1..=MAX_DEPTH_LIMIT).contains(&settings.max_depth) {
        return Err(RenderError::Depth(settings.max_depth));
    }
    let threads = settings.threads.unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|source| RenderError::Threads { threads, source })?;
    match settings.model {
        Model::Classic => {
            Ok(pool.install(|| Renderer::new(scene, Classic::new(scene), settings).run(progress)))
        }
        Model::Photon => {
            let photon_settings = settings.photon_settings(scene);
            photon::check_memory(&photon_settings, settings.memory_limit)
                .map_err(|d| RenderError::Settings(Box::new(d)))?;
            Ok(pool.install(|| {
                let report = |done, total| progress(Progress { stage: Stage::TracingPhotons, done, total });
                let (map, stats) = photon::build_photon_map(scene, &photon_settings, settings.seed, &report);
                progress(Progress { stage: Stage::BuildingPhotonMap, done: 1, total: 1 });
                let integrator = Classic::with_photons(scene, PhotonEstimate::new(&map, &photon_settings));
                let mut rendered = Renderer::new(scene, integrator, settings).run(progress);
                rendered.stats.photons = Some(stats);
                rendered
            }))
        }
        Model::Path => Ok(pool.install(|| render_path(scene, settings, progress))),
        Model::Sppm => {
            let sppm_settings = settings.sppm_settings(scene);
            let pixels = settings.width as u64 * settings.height as u64;
            sppm::check_memory(
                &settings.photon_settings(scene),
                pixels,
                settings.max_depth,
                settings.memory_limit,
            )
            .map_err(|d| RenderError::Settings(Box::new(d)))?;
            Ok(pool.install(|| {
                let camera = camera_for(scene, settings);
                let (w, h) = (settings.width, settings.height);
                let total = sppm_settings.passes;
                progress(Progress { stage: Stage::Passes, done: 0, total });
                let report = |done| progress(Progress { stage: Stage::Passes, done, total });
                let (colors, stats) =
                    sppm::render(scene, &camera, &sppm_settings, w, PixelRect::full(w, h), &report);
                Rendered {
                    image: Image::new(w, h, colors.iter().map(|c| c.as_vec3().to_array()).collect()),
                    stats: RenderStats {
                        rays: stats.rays,
                        camera_samples: pixels * stats.passes,
                        threads: rayon::current_num_threads(),
                        sppm: Some(stats),
                        ..RenderStats::default()
                    },
                }
            }))
        }
    }
}

/// The camera of a render: the scene's, at the settings' size, focused at `focal_dist=` or (a
/// lens without it) on the surface seen at the image centre.
pub fn camera_for(scene: &PreparedScene, settings: &RenderSettings) -> Camera {
    let (w, h) = (settings.width, settings.height);
    let cam = &scene.scene.camera;
    let focus = if cam.aperture > 0.0 && cam.focal_distance.is_none() {
        match scene.closest_hit(&Camera::new(cam, w, h, 1.0).central_ray()) {
            Hit::Surface { hit, .. } => hit.t,
            Hit::Emitter { t, .. } => t,
            Hit::Miss => 1.0,
        }
    } else {
        1.0
    };
    Camera::new(cam, w, h, focus)
}

/// A rectangle of pixels of an image: columns `x0..x1`, rows `y0..y1` (0, 0 at the top left).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// The whole `width x height` image.
    pub fn full(width: u32, height: u32) -> PixelRect {
        PixelRect { x0: 0, y0: 0, x1: width, y1: height }
    }

    /// Pixels in the rectangle.
    pub fn len(&self) -> usize {
        (self.x1.saturating_sub(self.x0) as usize) * (self.y1.saturating_sub(self.y0) as usize)
    }

    /// Whether the rectangle holds no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The exact sums of the path tracer's samples `samples` (sample indices) of every pixel of
/// `rect` (row-major), and the rays traced. Sample `s` of pixel `(x, y)` draws from its own
/// stream (seed, pixel, `s`), so sums of disjoint sample ranges and pixel rectangles merge
/// ([`ExactSum::merge`]) into exactly the sums of one render. `progress(done)` reports samples
/// finished (pixels times samples) from worker threads.
pub fn path_sums(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rect: PixelRect,
    samples: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<ExactSum>, u64) {
    let camera = camera_for(scene, settings);
    let tracer = PathTracer::new(scene, settings.max_depth);
    let width = rect.x1.saturating_sub(rect.x0) as usize;
    let mut sums = vec![ExactSum::default(); rect.len()];
    let rays = AtomicU64::new(0);
    let done = AtomicU64::new(0);
    let per_row = width as u64 * (samples.end.saturating_sub(samples.start));
    if width > 0 {
        sums.par_chunks_mut(width).enumerate().for_each(|(row, sums)| {
            let y = rect.y0 + row as u32;
            let mut row_rays = 0;
            for (i, sum) in sums.iter_mut().enumerate() {
                let x = rect.x0 + i as u32;
                for s in samples.clone() {
                    let mut rng = PixelRng::for_sample(settings.seed, stream::PATH, x, y, s);
                    let (dx, dy) = (rng.uniform(), rng.uniform());
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

/// A whole-image path-traced render: every pixel's samples `0..spp`, averaged.
fn render_path(
    scene: &PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(Progress) + Sync),
) -> Rendered {
    let (w, h) = (settings.width, settings.height);
    let spp = settings.path_spp() as u64;
    let total = w as u64 * h as u64 * spp;
    progress(Progress { stage: Stage::Sampling, done: 0, total });
    let report = |done| progress(Progress { stage: Stage::Sampling, done, total });
    let (sums, rays) = path_sums(scene, settings, PixelRect::full(w, h), 0..spp, &report);
    let pixels = sums.iter().map(|s| s.mean(spp).as_vec3().to_array()).collect();
    Rendered {
        image: Image::new(w, h, pixels),
        stats: RenderStats {
            rays,
            camera_samples: total,
            threads: rayon::current_num_threads(),
            ..RenderStats::default()
        },
    }
}

struct Renderer<'s> {
    integrator: Classic<'s>,
    camera: Camera,
    settings: &'s RenderSettings,
    rays: AtomicU64,
    lookups: AtomicU64,
}

/// Pass numbers, part of each pixel's random seed.
const FIRST_PASS: u32 = 0;
const REFINE_PASS: u32 = 1;

impl<'s> Renderer<'s> {
    fn new(scene: &'s PreparedScene, integrator: Classic<'s>, settings: &'s RenderSettings) -> Renderer<'s> {
        Renderer {
            integrator,
            camera: camera_for(scene, settings),
            settings,
            rays: AtomicU64::new(0),
            lookups: AtomicU64::new(0),
        }
    }

    fn run(&self, progress: &(dyn Fn(Progress) + Sync)) -> Rendered {
        let (w, h) = (self.settings.width as usize, self.settings.height as usize);
        let (first_samples, track_tags) = match self.settings.sampling {
            Sampling::Adaptive => (1, true),
            Sampling::Uniform(n) => (n, false),
        };
        let mut colors = vec![DVec3::ZERO; w * h];
        let n_tracked = if track_tags { w * h } else { 0 };
        let mut traces = vec![PixelTrace::default(); n_tracked];
        let rows_done = AtomicU64::new(0);
        let first = Strata::for_count(first_samples);
        // With many samples a pixel, nested estimates are shared among ceil(sqrt(n)) groups of
        // them, so their sample count grows with the square root of the pixel's.
        let first_groups = (first_samples as f64).sqrt().ceil() as u32;
        let trace_row = |y: usize, row: &mut [DVec3], mut row_traces: Option<&mut [PixelTrace]>| {
            let mut rays = 0;
            for (x, c) in row.iter_mut().enumerate() {
                let trace = row_traces.as_deref_mut().map(|t| &mut t[x]);
                *c = self.pixel(x as u32, y as u32, FIRST_PASS, first, first_groups, trace, &mut rays);
            }
            self.rays.fetch_add(rays, Ordering::Relaxed);
            let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(Progress { stage: Stage::Tracing, done, total: h as u64 });
        };
        if track_tags {
            colors
                .par_chunks_mut(w)
                .zip(traces.par_chunks_mut(w))
                .enumerate()
                .for_each(|(y, (row, row_traces))| trace_row(y, row, Some(row_traces)));
        } else {
            colors.par_chunks_mut(w).enumerate().for_each(|(y, row)| trace_row(y, row, None));
        }
        let mut camera_samples = (w * h) as u64 * first_samples as u64;

        let mut refined_pixels = 0;
        if track_tags {
            let flagged = pixels_to_refine(&colors, &traces, w, h);
            refined_pixels = flagged.len() as u64;
            let done = AtomicU64::new(0);
            let total = flagged.len() as u64;
            progress(Progress { stage: Stage::Refining, done: 0, total });
            const CHUNK: usize = 64;
            let refined: Vec<DVec3> = flagged
                .par_chunks(CHUNK)
                .flat_map_iter(|chunk| {
                    let mut rays = 0;
                    let values: Vec<DVec3> = chunk
                        .iter()
                        .map(|r| {
                            let (x, y) = ((r.index % w) as u32, (r.index / w) as u32);
                            self.pixel(x, y, REFINE_PASS, r.grid, r.groups, None, &mut rays)
                        })
                        .collect();
                    self.rays.fetch_add(rays, Ordering::Relaxed);
                    let finished = done.fetch_add(chunk.len() as u64, Ordering::Relaxed) + chunk.len() as u64;
                    progress(Progress { stage: Stage::Refining, done: finished, total });
                    values
                })
                .collect();
            for (r, c) in flagged.iter().zip(refined) {
                colors[r.index] = colors[r.index] * r.first_weight + c * (1.0 - r.first_weight);
            }
            camera_samples += flagged.iter().map(|r| r.grid.count() as u64).sum::<u64>();
        }

        let pixels = colors.iter().map(|c| c.as_vec3().to_array()).collect();
        Rendered {
            image: Image::new(self.settings.width, self.settings.height, pixels),
            stats: RenderStats {
                rays: self.rays.load(Ordering::Relaxed),
                camera_samples,
                refined_pixels,
                threads: rayon::current_num_threads(),
                lookups: self.lookups.load(Ordering::Relaxed),
                photons: None,
                sppm: None,
            },
        }
    }

    /// The colour of pixel `(x, y)` (0, 0 at the top left) from `strata.count()` camera samples
    /// (at the centre for a single sample, jittered in each cell otherwise), their nested
    /// estimates shared among `groups` groups of samples (see [`Siblings`]): each estimate takes
    /// `groups` times fewer samples than a lone one. With `trace`, records the pixel's tag and
    /// noise estimate. Adds the rays traced to `rays`.
    #[allow(clippy::too_many_arguments)]
    fn pixel(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        strata: Strata,
        groups: u32,
        mut trace: Option<&mut PixelTrace>,
        rays: &mut u64,
    ) -> DVec3 {
        let mut rng = PixelRng::new(self.settings.seed, x, y, pass);
        let n = strata.count();
        let mut sum = DVec3::ZERO;
        let mut cx = TraceContext::new(&mut rng);
        for s in 0..n {
            let (dx, dy) = if n == 1 { (0.5, 0.5) } else { strata.sample(s, cx.rng) };
            let lens = if self.camera.has_lens() { (cx.rng.uniform(), cx.rng.uniform()) } else { (0.0, 0.0) };
            let ray = self.camera.ray(x as f64 + dx, y as f64 + dy, lens);
            let siblings = Siblings { count: groups, index: s % groups };
            let tag = trace.as_deref_mut().map(|t| &mut t.tag);
            sum += self.integrator.radiance(&mut cx, &ray, siblings, tag);
        }
        if let Some(t) = trace {
            t.error = (cx.variance / n as f64).sqrt() as f32;
        }
        *rays += cx.rays;
        if cx.lookups > 0 {
            self.lookups.fetch_add(cx.lookups, Ordering::Relaxed);
        }
        sum / n as f64
    }
}

/// What the first pass records about a pixel for the adaptive sampler.
#[derive(Clone, Copy, Debug, Default)]
struct PixelTrace {
    /// Hash of the objects and lit point lights along the deterministic path.
    tag: u64,
    /// Estimated standard error of the pixel's colour.
    error: f32,
}

/// A pixel to refine: its index, its camera samples and how their nested estimates are shared
/// (see [`Renderer::pixel`]), and the weight its first-pass colour keeps in the result.
struct Refinement {
    index: usize,
    grid: Strata,
    groups: u32,
    first_weight: f64,
}

/// The pixels to refine, in index order: a tag different from a 4-neighbour's or a colour
/// differing from a 4-neighbour's by more than [`CONTRAST_THRESHOLD`] in some channel (an edge:
/// a `REFINE_GRID` grid of camera samples replaces the first one), or an estimated error above
/// [`NOISE_THRESHOLD`] (noise: more nested samples, as many more as the error says it needs, up
/// to [`MAX_NESTED_FACTOR`] times; an edge pixel takes them in its grid, any other adds them with
/// a `NOISE_GRID` grid to its first sample).
fn pixels_to_refine(colors: &[DVec3], traces: &[PixelTrace], w: usize, h: usize) -> Vec<Refinement> {
    let differs = |a: usize, b: usize| {
        traces[a].tag != traces[b].tag || (colors[a] - colors[b]).abs().max_element() > CONTRAST_THRESHOLD
    };
    (0..w * h)
        .filter_map(|i| {
            let (x, y) = (i % w, i / w);
            let edge = (x > 0 && differs(i, i - 1))
                || (x + 1 < w && differs(i, i + 1))
                || (y > 0 && differs(i, i - w))
                || (y + 1 < h && differs(i, i + w));
            // Samples needed to bring the error under the threshold, relative to the first pass.
            let need = (traces[i].error as f64 / NOISE_THRESHOLD).powi(2);
            let factor = if need > 1.0 { (need.ceil() as u32).min(MAX_NESTED_FACTOR) } else { 1 };
            if edge {
                // Replace the first pass: its single centre sample would bias the edge.
                let grid = Strata { nx: REFINE_GRID, ny: REFINE_GRID };
                Some(Refinement { index: i, grid, groups: grid.count().div_ceil(factor), first_weight: 0.0 })
            } else if factor > 1 {
                // Keep the first pass (one share of nested samples) and add `factor - 1` more
                // shares (or the next count the grid divides into), weighting each by its shares.
                let grid = Strata { nx: NOISE_GRID, ny: NOISE_GRID };
                let groups = (grid.count() / (factor - 1)).max(1);
                let shares = grid.count() as f64 / groups as f64;
                Some(Refinement { index: i, grid, groups, first_weight: 1.0 / (1.0 + shares) })
            } else {
                None
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w x h` first pass of one colour and tag with no noise.
    fn flat(w: usize, h: usize) -> (Vec<DVec3>, Vec<PixelTrace>) {
        (vec![DVec3::splat(0.5); w * h], vec![PixelTrace { tag: 7, error: 0.0 }; w * h])
    }

    /// Nested samples of a refinement, in units of the first pass's, first pass included.
    fn shares(r: &Refinement) -> f64 {
        let added = r.grid.count() as f64 / r.groups as f64;
        if r.first_weight > 0.0 { 1.0 + added } else { added }
    }

    #[test]
    fn a_clean_flat_image_needs_no_refinement() {
        let (colors, traces) = flat(5, 4);
        assert!(pixels_to_refine(&colors, &traces, 5, 4).is_empty());
    }

    #[test]
    fn a_tag_or_contrast_edge_replaces_both_sides_with_the_full_grid() {
        let (w, h) = (5, 4);
        for change in ["tag", "contrast"] {
            let (mut colors, mut traces) = flat(w, h);
            let centre = w + 2;
            match change {
                "tag" => traces[centre].tag = 8,
                _ => colors[centre].y += 1.5 * CONTRAST_THRESHOLD,
            }
            let flagged = pixels_to_refine(&colors, &traces, w, h);
            let indices: Vec<usize> = flagged.iter().map(|r| r.index).collect();
            assert_eq!(indices, [2, w + 1, w + 2, w + 3, 2 * w + 2], "{change}");
            for r in &flagged {
                assert_eq!(r.grid, Strata { nx: REFINE_GRID, ny: REFINE_GRID });
                assert_eq!((r.groups, r.first_weight), (r.grid.count(), 0.0), "no extra nested samples");
            }
        }
    }

    #[test]
    fn a_small_contrast_is_not_an_edge() {
        let (mut colors, traces) = flat(3, 3);
        colors[4].x += 0.9 * CONTRAST_THRESHOLD;
        assert!(pixels_to_refine(&colors, &traces, 3, 3).is_empty());
    }

    #[test]
    fn a_noisy_pixel_gets_as_many_nested_samples_as_its_error_asks_for() {
        let (w, h) = (3, 3);
        // Error ratio to the threshold -> samples needed, as a multiple of the first pass's.
        for (ratio, need) in [(0.99, 1.0f64), (1.2, 1.44), (1.5, 2.25), (1.9, 3.61), (3.0, 9.0)] {
            let (colors, mut traces) = flat(w, h);
            traces[4].error = (ratio * NOISE_THRESHOLD) as f32;
            let flagged = pixels_to_refine(&colors, &traces, w, h);
            if need <= 1.0 {
                assert!(flagged.is_empty(), "ratio {ratio}");
                continue;
            }
            let [r] = flagged.as_slice() else { panic!("ratio {ratio}: {} pixels flagged", flagged.len()) };
            assert_eq!((r.index, r.grid), (4, Strata { nx: NOISE_GRID, ny: NOISE_GRID }));
            let total = shares(r);
            assert!(total >= need.min(MAX_NESTED_FACTOR as f64), "ratio {ratio}: {total} shares");
            assert!(total <= 2.0 * MAX_NESTED_FACTOR as f64, "ratio {ratio}: {total} shares");
            // The first pass is weighted by its share of the samples.
            assert!((r.first_weight - 1.0 / total).abs() < 1e-12, "ratio {ratio}");
        }
    }

    #[test]
    fn a_noisy_edge_pixel_takes_its_extra_nested_samples_in_the_full_grid() {
        let (w, h) = (3, 1);
        let (colors, mut traces) = flat(w, h);
        traces[0].tag = 1;
        traces[0].error = (2.0 * NOISE_THRESHOLD) as f32;
        let flagged = pixels_to_refine(&colors, &traces, w, h);
        assert_eq!(flagged.len(), 2);
        assert_eq!(shares(&flagged[0]), MAX_NESTED_FACTOR as f64);
        assert_eq!(shares(&flagged[1]), 1.0);
    }

    /// A rough glossy floor seen from above, reflecting a square light and a ball and lit
    /// through a penumbra: noise everywhere, no geometric edge in view.
    const NOISY_SCENE: &str = "camera\n O= 0 0 2\n N= 0 0.3 -1\n lens_W= 0.8\n lens_H= 0.6\n\
        shade_quality= 1\n drefl_quality= 1\nend\n\
        light square\n O= 0 1.5 2.5\n Dx= 0.8 0 0\n Dy= 0 0.8 0\n color= 1 1 1\nend\n\
        primitive plane\n N= 0 0 1\n R= 0\n color= 0.9 0.8 0.7\n diff= 0.5\n refl= 0.5\n drefl= 0.5\nend\n\
        primitive sphere\n O= 0.2 1.2 1.3\n R= 0.4\n color= 0.2 0.3 0.9\n diff= 0.8\nend\n";

    fn render_noisy(sampling: Sampling) -> Vec<[f32; 3]> {
        use crate::scene::{SourceFile, parse};
        let parsed =
            parse(&SourceFile::from_text("noisy.txt", None, NOISY_SCENE.to_owned())).expect("parses");
        let scene = PreparedScene::new(parsed.scene, &crate::TextureSearch::default()).expect("prepares");
        let settings =
            RenderSettings { width: 48, height: 36, sampling, seed: 3, ..RenderSettings::for_scene(&scene) };
        render(&scene, &settings, &|_| {}).expect("renders").image.pixels().to_vec()
    }

    fn rms(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
        let sum: f64 =
            a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| ((x - y) as f64).powi(2)).sum();
        (sum / (a.len() * 3) as f64).sqrt()
    }

    #[test]
    fn adaptive_sampling_is_closer_to_the_converged_image_than_one_sample_a_pixel() {
        let reference = render_noisy(Sampling::Uniform(256));
        let adaptive = rms(&render_noisy(Sampling::Adaptive), &reference);
        let single = rms(&render_noisy(Sampling::Uniform(1)), &reference);
        // Refinement must remove a large part of the error, not shift it (a bias would).
        assert!(adaptive < 0.7 * single, "adaptive {adaptive:.5} against one sample {single:.5}");
    }
}
