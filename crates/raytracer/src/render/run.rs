//! One run of a model over some rows ([`super::RenderSettings::runs`]): the classic, photon and
//! path models in chunks of rows that a checkpoint keeps, SPPM from a saved state. Every random
//! number is keyed by the run's seed ([`run_seed`]), the pixel or photon, and the sample or pass,
//! so a run's values do not depend on how its rows are grouped or when it was interrupted.

use std::ops::Range;

use super::checkpoint::{self, Checkpoint, Estimate};
use super::{Progress, RenderError, RenderSettings, RenderStats, Rows, Stage, camera_for};
use crate::base::sampler::{ExactSum, hash_values, stream};
use crate::integrator::Model;
use crate::integrator::adaptive::{self, PixelSampling};
use crate::integrator::sppm::{self, SppmSettings, SppmState};
use crate::integrator::{path, photon};
use crate::prepare::PreparedScene;

/// The seed of run `run`: the render's seed for the first run (so that a render of one run is the
/// render as it always was), one derived from it and the run for the others.
pub fn run_seed(seed: u64, run: u32) -> u64 {
    if run == 0 { seed } else { hash_values(&[seed, stream::RUN, run as u64]) }
}

/// Run `run` of the classic, photon or path model over `rows`: in one go, or with a checkpoint in
/// [`checkpoint::CHUNKS`] chunks of rows, each saved as it finishes and taken from the checkpoint
/// when an earlier render saved it.
pub(super) fn render_rows_run(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    run: u32,
    progress: &(dyn Fn(Progress) + Sync),
    mut checkpoint: Option<&mut Checkpoint>,
) -> Result<(Estimate, RenderStats), RenderError> {
    let seed = run_seed(settings.seed, run);
    let chunks = match checkpoint {
        Some(_) => checkpoint::chunk_rows(rows),
        None => vec![rows.clone()],
    };
    let chunked = chunks.len() > 1;
    // A chunk's progress is reported as chunks done, not as its own stages.
    let chunk_progress = |p: Progress| {
        if !chunked || matches!(p.stage, Stage::TracingPhotons | Stage::BuildingPhotonMap) {
            progress(p);
        }
    };
    let photon_settings = settings.photon_settings(scene);
    let pixels = PixelSampling {
        camera: camera_for(scene, settings),
        sampling: settings.sampling,
        height: settings.height,
        seed,
    };
    // The photon map, built when the first chunk that needs it is rendered.
    let mut photon_map = None;
    let mut stats = RenderStats::default();
    let mut estimates = Vec::with_capacity(chunks.len());
    for (i, chunk) in chunks.iter().enumerate() {
        let saved = checkpoint.as_deref().and_then(|c| c.chunk(run, i as u32));
        let estimate = match saved {
            Some(estimate) => estimate.clone(),
            None => {
                let (estimate, chunk_stats) = match settings.model {
                    Model::Path => {
                        // Runs of the path tracer are ranges of sample indices: `--spp` samples each.
                        let spp = settings.path_spp() as u64;
                        let samples = run as u64 * spp..(run as u64 + 1) * spp;
                        let total = chunk.len() as u64 * spp;
                        let report = |done| chunk_progress(Progress { stage: Stage::Sampling, done, total });
                        report(0);
                        let (sums, rays) = path::render_sums(
                            scene,
                            &pixels.camera,
                            settings.seed,
                            settings.max_depth,
                            chunk,
                            samples,
                            &report,
                        );
                        (
                            Estimate::Sums(sums, spp),
                            RenderStats { rays, camera_samples: total, ..RenderStats::default() },
                        )
                    }
                    Model::Photon => {
                        let (colors, chunk_stats) = photon::render_rows(
                            scene,
                            &mut photon_map,
                            &photon_settings,
                            &pixels,
                            chunk,
                            &chunk_progress,
                        );
                        (Estimate::Colors(colors), chunk_stats)
                    }
                    Model::Classic => {
                        let (colors, chunk_stats) =
                            adaptive::render_classic(scene, &pixels, chunk, &chunk_progress);
                        (Estimate::Colors(colors), chunk_stats)
                    }
                    Model::Sppm => unreachable!("SPPM runs are rendered by render_sppm_run"),
                };
                stats.add(&chunk_stats);
                if let Some(c) = checkpoint.as_deref_mut() {
                    c.save_chunk(run, i as u32, estimate.clone()).map_err(RenderError::Checkpoint)?;
                }
                estimate
            }
        };
        if chunked {
            progress(Progress { stage: Stage::Chunks, done: i as u64 + 1, total: chunks.len() as u64 });
        }
        estimates.push(estimate);
    }
    Ok((concatenate(estimates), stats))
}

/// The estimates of consecutive chunks of rows as one.
fn concatenate(estimates: Vec<Estimate>) -> Estimate {
    let mut estimates = estimates.into_iter();
    let Some(mut all) = estimates.next() else {
        return Estimate::Colors(Vec::new());
    };
    for next in estimates {
        match (&mut all, next) {
            (Estimate::Colors(all), Estimate::Colors(more)) => all.extend(more),
            (Estimate::Sums(all, _), Estimate::Sums(more, _)) => all.extend(more),
            _ => unreachable!("the chunks of a run are estimated alike"),
        }
    }
    all
}

/// Run `run` of SPPM over `rows`, from the state a checkpoint saved if there is one, saving its
/// state there after passes.
pub(super) fn render_sppm_run(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    run: u32,
    progress: &(dyn Fn(Progress) + Sync),
    mut checkpoint: Option<&mut Checkpoint>,
) -> Result<(Estimate, RenderStats), RenderError> {
    let sppm_settings = SppmSettings { seed: run_seed(settings.seed, run), ..settings.sppm_settings(scene) };
    let camera = camera_for(scene, settings);
    let total = sppm_settings.passes;
    let start = checkpoint
        .as_deref()
        .and_then(|c| c.sppm_state(run))
        .cloned()
        .unwrap_or_else(|| SppmState::new(rows.len()));
    progress(Progress { stage: Stage::Passes, done: start.passes_done, total });
    let report = |done| progress(Progress { stage: Stage::Passes, done, total });
    let mut failure = None;
    let mut after_pass = |state: &SppmState| {
        if let Some(c) = checkpoint.as_deref_mut()
            && failure.is_none()
        {
            failure = c.save_sppm(run, state).err();
        }
        std::ops::ControlFlow::Continue(())
    };
    let (colors, sppm_stats) =
        sppm::render_from(scene, &camera, &sppm_settings, rows, start, &mut after_pass, &report);
    if let Some(error) = failure {
        return Err(RenderError::Checkpoint(error));
    }
    let stats = RenderStats {
        rays: sppm_stats.rays,
        camera_samples: rows.len() as u64 * sppm_stats.passes,
        sppm: Some(sppm_stats),
        ..RenderStats::default()
    };
    Ok((Estimate::Colors(colors), stats))
}

/// The exact sums of the path tracer's samples `samples` (sample indices) of every pixel of
/// `rows` (in the order of [`Rows::ys`]), and the rays traced: the path model's row loop
/// ([`path::render_sums`]) with the settings' camera, seed and depth.
pub fn path_sums(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    samples: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<ExactSum>, u64) {
    let camera = camera_for(scene, settings);
    path::render_sums(scene, &camera, settings.seed, settings.max_depth, rows, samples, progress)
}
