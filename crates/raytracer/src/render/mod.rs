//! The render driver: a model's runs over a set of rows, checkpoints, the thread pool and the
//! settings. Each model renders its rows itself (the classic and photon models through the
//! adaptive sampler of [`crate::integrator::adaptive`], the path tracer with
//! [`crate::integrator::path::render_sums`], SPPM with [`crate::integrator::sppm::render_from`]).
//!
//! The path tracer renders any set of rows
//! ([`Rows`]) over any range of sample indices ([`path_sums`]): every sample draws from its own
//! stream (seed, pixel, sample index) and a pixel's samples are summed exactly ([`ExactSum`]), so
//! a render split into tiles (sets of rows) and passes (sample ranges) merges into the same bytes
//! as one render: a pixel of `N` samples is `sum / N` whatever the grouping of its sums. SPPM
//! renders any set of rows ([`crate::integrator::sppm::render_from`]): its photons draw from streams
//! of (seed, pass, photon index), the same for every set. [`render_portion`] renders some rows
//! and some runs of a render ([`RenderSettings::runs`]); [`checkpoint`] keeps its finished work.

use std::ops::Range;

pub mod checkpoint;
mod run;
mod watch;

pub use crate::base::memory::DEFAULT_MEMORY_LIMIT;
pub use crate::base::rows::Rows;
use checkpoint::{Checkpoint, CheckpointError, Estimate};
pub use run::{path_sums, run_seed};
use run::{render_rows_run, render_sppm_run};
pub use watch::{Snapshot, Work, render_watched};

use crate::base::image_io::Image;
use crate::base::sampler::ExactSum;
use crate::camera::Camera;
use crate::integrator::Model;
pub use crate::integrator::adaptive::{
    CONTRAST_THRESHOLD, MAX_NESTED_FACTOR, NOISE_GRID, NOISE_THRESHOLD, REFINE_GRID, Sampling,
};
use crate::integrator::path::DEFAULT_MAX_DEPTH;
use crate::integrator::photon;
pub use crate::integrator::report::{Progress, RenderStats, Stage};
use crate::integrator::sppm::{self, SppmSettings};
use crate::prepare::{Hit, PreparedScene};
use crate::scene::{Algorithm, Diagnostic, PhotonSettings, check_image_size};

/// Largest `--spp`.
pub const MAX_SPP: u32 = 1 << 20;
/// Most independent runs of a render ([`RenderSettings::runs`]).
pub const MAX_RUNS: u32 = 1 << 16;
/// Samples a pixel of the path tracer when none are asked for.
pub const DEFAULT_PATH_SPP: u32 = 64;
/// Deepest path `--max-depth` accepts.
pub const MAX_DEPTH_LIMIT: u32 = 1000;

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
    /// Independent runs of the render, averaged (at least 1): what `--pass K/N` splits a render
    /// into. Classic, photon and sppm: run `k` draws every random number (pixels, photons) from
    /// streams of its own seed ([`run_seed`]) and counts as one estimate of each pixel. Path: run
    /// `k` takes the samples `k * spp .. (k + 1) * spp` of every pixel, so `N` runs of `spp`
    /// samples are exactly a render of `N * spp` samples.
    pub runs: u32,
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
    /// `algorithm=` names (see [`crate::integrator::choose_model`]); for a scene that states its
    /// render settings (a Mitsuba scene's sampler and integrator), its samples and depth (an
    /// unbounded depth is [`MAX_DEPTH_LIMIT`]).
    pub fn for_scene(scene: &PreparedScene) -> RenderSettings {
        let cam = &scene.scene.camera;
        let stated = &scene.scene.render;
        let sampling = match stated.samples {
            Some(n) => Sampling::Uniform(n),
            None if cam.aperture > 0.0 => Sampling::Uniform(16),
            None => Sampling::Adaptive,
        };
        RenderSettings {
            width: cam.image_width,
            height: cam.image_height,
            sampling,
            threads: None,
            seed: 0,
            model: crate::integrator::choose_model(&scene.scene, None).0,
            photons: None,
            memory_limit: DEFAULT_MEMORY_LIMIT,
            max_depth: stated.max_depth.map_or(DEFAULT_MAX_DEPTH, |d| d.min(MAX_DEPTH_LIMIT)),
            passes: None,
            runs: 1,
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
    /// Runs out of range.
    #[error("runs {}..{} asked for of a render of {total} runs", .runs.start, .runs.end)]
    Runs {
        /// The runs asked for.
        runs: Range<u32>,
        /// The runs of the render.
        total: u32,
    },
    /// A path depth out of range.
    #[error("the path depth must be from 1 to {MAX_DEPTH_LIMIT}, not {0}")]
    Depth(u32),
    /// Settings the scene cannot be rendered with (for example a photon map over the memory
    /// limit), with where in the scene file.
    #[error("{0}")]
    Settings(Box<Diagnostic>),
    /// The checkpoint could not be saved.
    #[error(transparent)]
    Checkpoint(CheckpointError),
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

/// Renders `scene` with the settings' model: every row, every run. `progress` is called from
/// worker threads as work finishes.
pub fn render(
    scene: &PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Rendered, RenderError> {
    let rows = Rows::full(settings.width, settings.height);
    let portion = render_portion(scene, settings, &rows, 0..settings.runs, progress)?;
    let pixels = match portion.pixels {
        PortionPixels::Final(pixels) => pixels,
        PortionPixels::Sums { .. } => unreachable!("every run was rendered"),
    };
    Ok(Rendered { image: Image::new(settings.width, settings.height, pixels), stats: portion.stats })
}

/// What [`render_portion`] computed for its rows, pixel by pixel in the order of [`Rows::ys`].
#[derive(Clone, Debug, PartialEq)]
pub enum PortionPixels {
    /// The pixels' final values: every run of the render was in the portion.
    Final(Vec<[f32; 3]>),
    /// Exact sums of the portion's estimates and their count: a run (or some runs) of several,
    /// to be added to the others' and divided by the total count ([`ExactSum::mean`]).
    Sums {
        /// One sum a pixel.
        sums: Vec<ExactSum>,
        /// The estimates in each sum (the same for every pixel).
        count: u64,
    },
}

/// Some rows and runs of a render.
#[derive(Clone, Debug)]
pub struct Portion {
    /// The pixels.
    pub pixels: PortionPixels,
    /// What they took.
    pub stats: RenderStats,
}

/// Renders the pixels of `rows` in the runs `runs` of the settings' `runs` (see
/// [`RenderSettings::runs`]). Any split of a render into rows and runs gives, pixel for pixel, the
/// values of the whole render: every random number comes from a stream keyed by the pixel (or
/// photon) and the run, the adaptive sampler looks at the same neighbours, and runs are summed
/// exactly. `progress` is called from worker threads as work finishes.
pub fn render_portion(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    runs: Range<u32>,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Portion, RenderError> {
    render_portion_resumable(scene, settings, rows, runs, progress, None)
}

/// [`render_portion`] keeping its finished work in `checkpoint` as it goes, and taking from it
/// what an earlier, interrupted render of the same portion finished: the pixels are the same bit
/// for bit either way (see [`checkpoint`]).
pub fn render_portion_resumable(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    runs: Range<u32>,
    progress: &(dyn Fn(Progress) + Sync),
    mut checkpoint: Option<&mut Checkpoint>,
) -> Result<Portion, RenderError> {
    check_settings(scene, settings, rows, &runs)?;
    let pool = thread_pool(settings)?;
    let whole = runs.start == 0 && runs.end == settings.runs;
    pool.install(|| {
        let mut stats = RenderStats { threads: rayon::current_num_threads(), ..RenderStats::default() };
        let mut total: Option<Vec<ExactSum>> = None;
        let mut count = 0;
        for run in runs {
            let (estimate, run_stats) = match settings.model {
                Model::Sppm => {
                    render_sppm_run(scene, settings, rows, run, progress, checkpoint.as_deref_mut())?
                }
                _ => render_rows_run(scene, settings, rows, run, progress, checkpoint.as_deref_mut())?,
            };
            stats.add(&run_stats);
            let (sums, n) = match estimate {
                // A lone run keeps its values as they are.
                Estimate::Colors(colors) if whole && settings.runs == 1 => {
                    return Ok(Portion {
                        pixels: PortionPixels::Final(colors.iter().map(|c| c.as_vec3().to_array()).collect()),
                        stats,
                    });
                }
                // A run's image counts as one estimate, as stored in an image (32-bit floats).
                Estimate::Colors(colors) => (
                    colors
                        .iter()
                        .map(|c| {
                            let mut sum = ExactSum::default();
                            sum.add(c.as_vec3().as_dvec3());
                            sum
                        })
                        .collect(),
                    1,
                ),
                Estimate::Sums(sums, n) => (sums, n),
            };
            count += n;
            match &mut total {
                None => total = Some(sums),
                Some(t) => t.iter_mut().zip(&sums).for_each(|(a, b)| a.merge(b)),
            }
        }
        let sums = total.unwrap_or_default();
        let pixels = if whole {
            PortionPixels::Final(sums.iter().map(|s| s.mean(count).as_vec3().to_array()).collect())
        } else {
            PortionPixels::Sums { sums, count }
        };
        Ok(Portion { pixels, stats })
    })
}

/// Refuses settings a render of `rows` and `runs` cannot start with.
fn check_settings(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    runs: &Range<u32>,
) -> Result<(), RenderError> {
    check_image_size(settings.width, settings.height).map_err(RenderError::ImageSize)?;
    if let Sampling::Uniform(n) = settings.sampling
        && !(1..=MAX_SPP).contains(&n)
    {
        return Err(RenderError::SampleCount(n));
    }
    if !(1..=MAX_DEPTH_LIMIT).contains(&settings.max_depth) {
        return Err(RenderError::Depth(settings.max_depth));
    }
    if !(1..=MAX_RUNS).contains(&settings.runs) || runs.is_empty() || runs.end > settings.runs {
        return Err(RenderError::Runs { runs: runs.clone(), total: settings.runs });
    }
    if rows.width() != settings.width || rows.blocks().last().is_some_and(|b| b.end > settings.height) {
        return Err(RenderError::ImageSize(format!(
            "the rows asked for do not fit a {}x{} image",
            settings.width, settings.height
        )));
    }
    match settings.model {
        Model::Photon => photon::check_memory(&settings.photon_settings(scene), settings.memory_limit),
        Model::Sppm => sppm::check_memory(
            &settings.photon_settings(scene),
            settings.width as u64 * settings.height as u64,
            settings.max_depth,
            settings.memory_limit,
        ),
        Model::Classic | Model::Path => Ok(()),
    }
    .map_err(|d| RenderError::Settings(Box::new(d)))?;
    Ok(())
}

/// The worker threads of a render.
fn thread_pool(settings: &RenderSettings) -> Result<rayon::ThreadPool, RenderError> {
    let threads = settings.threads.unwrap_or(0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|source| RenderError::Threads { threads, source })
}

/// The auxiliary images (albedo, normal, depth; see [`crate::integrator::aov`]) of the render
/// `settings` describe (its size, camera and seed, on `settings.threads` threads), each pixel the
/// mean of `samples` camera rays. The same bytes at any thread count.
pub fn render_aovs(
    scene: &PreparedScene,
    settings: &RenderSettings,
    samples: u32,
) -> Result<crate::integrator::aov::Aovs, RenderError> {
    check_image_size(settings.width, settings.height).map_err(RenderError::ImageSize)?;
    let threads = settings.threads.unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|source| RenderError::Threads { threads, source })?;
    let camera = camera_for(scene, settings);
    Ok(pool.install(|| {
        crate::integrator::aov::render_aovs(
            scene,
            &camera,
            settings.width,
            settings.height,
            settings.seed,
            samples,
        )
    }))
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
