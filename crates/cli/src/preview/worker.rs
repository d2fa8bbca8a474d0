//! The preview's render thread: renders the scene from the current pose through
//! [`render_watched`], hands every image to the window, writes every finished render as
//! `rayterra render` does, and starts again when the camera moves (a draft at a quarter of the
//! size and one sample a pixel first).

use std::ops::ControlFlow;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use raytracer::integrator::Model;
use raytracer::integrator::aov::{Aovs, DEFAULT_AOV_SAMPLES};
use raytracer::render::{Snapshot, Work, render_watched};
use raytracer::{PreparedScene, RenderSettings, Sampling};

use super::pose::Pose;
use super::pose::pose_note;
use super::{Frame, Job, Shared};

/// The draft's side, as a fraction of the image's.
const DRAFT_DIVISOR: u32 = 4;
/// Photons of a draft of the photon models, at most.
const DRAFT_PHOTONS: u64 = 20_000;
/// Shortest time between two denoised images of an unfinished render.
const DENOISE_EVERY: Duration = Duration::from_secs(1);

/// Renders until the window is gone and the render of the pose it left is written.
pub(super) fn work(shared: &Shared, job: Job<'_>, wake: &(dyn Fn() + Sync)) -> Result<(), ExitCode> {
    let Job { args, scene_name, mut prepared, settings, denoiser, prepare_time, syntax } = job;
    let scene_pose = Pose::of_camera(&prepared.scene.camera);
    let mut pose = scene_pose;
    let mut serial = 0;
    let mut draft = false;
    loop {
        pose.apply(&mut prepared.scene.camera);
        let started = Instant::now();
        let mut denoising = Denoising { aovs: None, last: None };
        let mut publish = |snapshot: &Snapshot<'_>, status: String, scale: u32| {
            serial += 1;
            let pixels = Arc::new(upscale(snapshot, scale, (settings.width, settings.height)));
            let frame = Frame {
                width: settings.width,
                height: settings.height,
                pixels: Arc::clone(&pixels),
                status,
                finished: snapshot.finished && scale == 1,
                serial,
            };
            let show_denoised = shared.lock().show_denoised;
            // Denoising waits for a whole image (no draft, no half-rendered rows).
            let whole = scale == 1 && (snapshot.work != Work::Rows || snapshot.finished);
            let denoised = match &denoiser {
                Some(oidn) if show_denoised && whole && denoising.due(snapshot.finished) => {
                    denoising.denoise(oidn, &prepared, &settings, &pixels).map(|d| (serial, Arc::new(d)))
                }
                _ => None,
            };
            shared.update(|s| {
                s.frame = Some(frame);
                if denoised.is_some() {
                    s.denoised = denoised;
                }
            });
            wake();
        };
        let stopped = |shared: &Shared| {
            if shared.lock().pose.is_some() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        };
        if draft {
            let small = draft_settings(&prepared, &settings);
            let mut watch = |s: &Snapshot<'_>| {
                if s.finished {
                    publish(s, "draft (a quarter of the size, 1 sample a pixel)".into(), DRAFT_DIVISOR);
                }
                stopped(shared)
            };
            render_watched(&prepared, &small, &|_| {}, &mut watch).map_err(|e| fail(&e.to_string()))?;
        }
        let rendered = if stopped(shared).is_break() {
            None
        } else {
            let mut images = 0;
            let mut watch = |s: &Snapshot<'_>| {
                images += 1;
                publish(s, status(s, &settings, images, started.elapsed()), 1);
                stopped(shared)
            };
            render_watched(&prepared, &settings, &|_| {}, &mut watch).map_err(|e| fail(&e.to_string()))?
        };
        let render_time = started.elapsed();
        if let Some(rendered) = rendered {
            crate::render::write_whole(
                args,
                &prepared,
                &settings,
                denoiser.as_ref(),
                rendered.image.pixels().to_vec(),
            )?;
            if !args.quiet {
                crate::render::print_summary(
                    &args.output,
                    &format!("{}x{} pixels", settings.width, settings.height),
                    &settings,
                    &rendered.stats,
                    prepare_time,
                    render_time,
                );
            }
            if pose != scene_pose {
                outln!("{}", pose_note(&pose, syntax, &scene_name, &format!("of {}", args.output.display())));
            }
            // Wait for a new pose or the window's closing; denoise the finished image on `D`.
            loop {
                let state = shared.lock();
                if state.pose.is_some() {
                    break;
                }
                if state.window_gone {
                    return Ok(());
                }
                let latest = state.frame.as_ref().map(|f| (f.serial, Arc::clone(&f.pixels)));
                let wanted = state.show_denoised
                    && latest
                        .as_ref()
                        .is_some_and(|(n, _)| state.denoised.as_ref().is_none_or(|(d, _)| d != n));
                if let (Some(oidn), true, Some((n, pixels))) = (&denoiser, wanted, latest) {
                    drop(state);
                    let denoised = denoising.denoise(oidn, &prepared, &settings, &pixels);
                    shared.update(|s| {
                        s.denoised = Some((n, Arc::new(denoised.unwrap_or_else(|| pixels.to_vec()))))
                    });
                    wake();
                    continue;
                }
                drop(shared.changed.wait(state).unwrap_or_else(|poisoned| poisoned.into_inner()));
            }
        }
        // A new pose: render it, a draft first.
        if let Some(next) = shared.lock().pose.take() {
            pose = next;
            draft = true;
        }
    }
}

/// The albedo and normal images of the current pose (rendered once, when first needed) and when
/// the last denoised image was made.
struct Denoising {
    aovs: Option<Aovs>,
    last: Option<Instant>,
}

impl Denoising {
    /// Whether an unfinished image is due to be denoised (a finished one always is).
    fn due(&self, finished: bool) -> bool {
        finished || self.last.is_none_or(|t| t.elapsed() >= DENOISE_EVERY)
    }

    /// `pixels` denoised; `None` (and a note) when OIDN fails.
    fn denoise(
        &mut self,
        oidn: &crate::oidn::Oidn,
        prepared: &PreparedScene,
        settings: &RenderSettings,
        pixels: &[[f32; 3]],
    ) -> Option<Vec<[f32; 3]>> {
        self.last = Some(Instant::now());
        if self.aovs.is_none() {
            match raytracer::render::render_aovs(prepared, settings, DEFAULT_AOV_SAMPLES) {
                Ok(aovs) => self.aovs = Some(aovs),
                Err(e) => {
                    errln!("warning: the preview cannot denoise: {e}");
                    return None;
                }
            }
        }
        let aovs = self.aovs.as_ref()?;
        oidn.denoise(settings.width, settings.height, pixels, &aovs.albedo, &aovs.normal, settings.threads)
            .map_err(|e| errln!("warning: the preview cannot denoise: {e}"))
            .ok()
    }
}

/// The settings of a draft: a quarter of the size, one sample a pixel, one run, one SPPM pass,
/// few photons.
fn draft_settings(scene: &PreparedScene, settings: &RenderSettings) -> RenderSettings {
    let photons = settings.photon_settings(scene).emit_photons.min(DRAFT_PHOTONS);
    RenderSettings {
        width: settings.width.div_ceil(DRAFT_DIVISOR),
        height: settings.height.div_ceil(DRAFT_DIVISOR),
        sampling: Sampling::Uniform(1),
        runs: 1,
        passes: Some(1),
        photons: Some(photons.max(1)),
        ..settings.clone()
    }
}

/// The snapshot's pixels at `scale` times its size (nearest pixel), cut to `size`.
fn upscale(snapshot: &Snapshot<'_>, scale: u32, (width, height): (u32, u32)) -> Vec<[f32; 3]> {
    if scale == 1 {
        return snapshot.pixels.to_vec();
    }
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let row = ((y / scale).min(snapshot.height - 1) * snapshot.width) as usize;
        out.extend((0..width).map(|x| snapshot.pixels[row + (x / scale).min(snapshot.width - 1) as usize]));
    }
    out
}

/// What a snapshot (the `images`th of its render) holds, for the title: samples (and batches),
/// passes or rows so far, the run, the time and the rays a second.
fn status(s: &Snapshot<'_>, settings: &RenderSettings, images: u64, elapsed: Duration) -> String {
    let runs = settings.runs;
    let run = if runs > 1 { format!(", run {}/{runs}", s.run + 1) } else { String::new() };
    let work = match (s.finished, s.work) {
        (true, _) => match settings.model {
            Model::Path => format!("finished, {} samples a pixel", settings.path_spp() as u64 * runs as u64),
            Model::Sppm => format!("finished, {} passes{run}", settings_passes(s)),
            Model::Classic | Model::Photon => format!("finished{run}"),
        },
        (false, Work::Samples) => {
            let batches = if images == 1 { "batch" } else { "batches" };
            format!("{}/{} samples a pixel in {images} {batches}", s.done, s.total)
        }
        (false, Work::Passes) => format!("pass {}/{}{run}", s.done, s.total),
        (false, Work::Rows) => {
            let sampling = match settings.sampling {
                Sampling::Adaptive => "adaptive sampling".to_owned(),
                Sampling::Uniform(n) => format!("{n} samples a pixel"),
            };
            format!("rows {}/{} ({sampling}){run}", s.done, s.total)
        }
    };
    let seconds = elapsed.as_secs_f64().max(1e-9);
    format!("{work}, {seconds:.1} s, {:.1} M rays/s", s.stats.rays as f64 / seconds / 1e6)
}

/// The SPPM passes a finished snapshot's statistics count.
fn settings_passes(s: &Snapshot<'_>) -> u64 {
    s.stats.sppm.map_or(0, |p| p.passes)
}

/// Prints an error and returns the failure exit code.
fn fail(message: &str) -> ExitCode {
    errln!("error: {message}");
    ExitCode::FAILURE
}

#[cfg(test)]
mod tests {
    use super::*;
    use raytracer::render::RenderStats;

    #[test]
    fn a_draft_is_shown_at_full_size() {
        let pixels = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let s = Snapshot {
            width: 2,
            height: 1,
            pixels: &pixels,
            work: Work::Rows,
            done: 1,
            total: 1,
            run: 0,
            stats: RenderStats::default(),
            finished: true,
        };
        let big = upscale(&s, 2, (3, 2));
        assert_eq!(big.len(), 6);
        assert_eq!(&big[..3], &[pixels[0], pixels[0], pixels[1]]);
        assert_eq!(&big[3..], &big[..3]);
    }

    #[test]
    fn the_status_says_samples_passes_or_rows_time_and_rays() {
        let pixels = [[0.0; 3]];
        let stats = RenderStats { rays: 3_000_000, ..RenderStats::default() };
        let shot = |work, done, total| Snapshot {
            width: 1,
            height: 1,
            pixels: &pixels,
            work,
            done,
            total,
            run: 0,
            stats,
            finished: false,
        };
        let settings = RenderSettings {
            width: 1,
            height: 1,
            sampling: Sampling::Uniform(64),
            threads: None,
            seed: 0,
            model: Model::Path,
            photons: None,
            memory_limit: 1 << 30,
            max_depth: 10,
            passes: None,
            runs: 1,
        };
        let second = Duration::from_secs(2);
        assert_eq!(
            status(&shot(Work::Samples, 3, 64), &settings, 2, second),
            "3/64 samples a pixel in 2 batches, 2.0 s, 1.5 M rays/s"
        );
        assert_eq!(
            status(&shot(Work::Passes, 5, 64), &settings, 5, second),
            "pass 5/64, 2.0 s, 1.5 M rays/s"
        );
        assert_eq!(
            status(&shot(Work::Rows, 96, 384), &settings, 4, second),
            "rows 96/384 (64 samples a pixel), 2.0 s, 1.5 M rays/s"
        );
    }
}
