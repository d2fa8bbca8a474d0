//! A whole render that hands out its image as it goes ([`render_watched`]): the path model
//! after every batch of samples, SPPM after every pass, the classic and photon models after
//! every block of rows. The watcher may stop it between two of them. Its finished image is the
//! very image of [`super::render`] (same bytes): the path tracer's samples are summed exactly
//! whatever the batches, SPPM resumes from its state between passes as a checkpoint does, and
//! the classic and photon models give the same pixels for any split into rows.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::DVec3;

use super::{
    Progress, RenderError, RenderSettings, RenderStats, Rendered, Rows, camera_for, check_settings, run_seed,
    thread_pool,
};
use crate::base::image_io::Image;
use crate::base::sampler::ExactSum;
use crate::integrator::Model;
use crate::integrator::adaptive::{self, PixelSampling};
use crate::integrator::sppm::{self, SppmSettings, SppmState};
use crate::integrator::{path, photon};
use crate::prepare::PreparedScene;

/// What a [`Snapshot`]'s `done` and `total` count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// Samples a pixel (path model; every run's samples together).
    Samples,
    /// Passes of SPPM (in the current run).
    Passes,
    /// Rows of the image (classic and photon models; in the current run).
    Rows,
}

/// The image of a render so far, handed to the watcher of [`render_watched`].
#[derive(Clone, Copy, Debug)]
pub struct Snapshot<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The pixels so far, linear RGB, row by row from the top. Pixels not rendered yet are the
    /// mean of the runs finished before (black in the first run).
    pub pixels: &'a [[f32; 3]],
    /// What `done` and `total` count.
    pub work: Work,
    /// Units done.
    pub done: u64,
    /// Units in all (of the current run for [`Work::Passes`] and [`Work::Rows`]).
    pub total: u64,
    /// The run being rendered (from 0) of [`RenderSettings::runs`].
    pub run: u32,
    /// What the render did so far (rays, samples).
    pub stats: RenderStats,
    /// Whether this is the finished image.
    pub finished: bool,
}

/// Longest a batch of the path tracer's samples should take, so that a watcher stopping the
/// render is heard soon.
const BATCH_SECONDS: f64 = 0.25;

/// Renders every row and run of `scene` as [`super::render`] does, calling `watch` with the
/// image so far after every batch of samples (path), pass (sppm) or block of rows (classic,
/// photon), and once with the finished image. `watch` returning [`ControlFlow::Break`] stops the
/// render there: the result is then `Ok(None)`. The path tracer's first batch is one sample a
/// pixel, then batches grow while they take under a quarter of a second. `progress` is called
/// from worker threads as work finishes.
pub fn render_watched(
    scene: &PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(Progress) + Sync),
    watch: &mut (dyn FnMut(&Snapshot<'_>) -> ControlFlow<()> + Send),
) -> Result<Option<Rendered>, RenderError> {
    let rows = Rows::full(settings.width, settings.height);
    check_settings(scene, settings, &rows, &(0..settings.runs))?;
    let pool = thread_pool(settings)?;
    pool.install(|| {
        let mut watcher = Watcher {
            settings,
            stats: RenderStats { threads: rayon::current_num_threads(), ..RenderStats::default() },
            runs: RunSums::new(rows.len()),
            watch,
        };
        let pixels = match settings.model {
            Model::Path => watch_path(scene, settings, &rows, progress, &mut watcher),
            Model::Sppm => watch_runs(&mut watcher, |watcher, run| {
                watch_sppm_run(scene, settings, &rows, run, progress, watcher)
            }),
            Model::Classic | Model::Photon => watch_runs(&mut watcher, |watcher, run| {
                watch_rows_run(scene, settings, &rows, run, progress, watcher)
            }),
        };
        let Some(pixels) = pixels else { return Ok(None) };
        let stats = watcher.stats;
        let flow = (watcher.watch)(&Snapshot {
            width: settings.width,
            height: settings.height,
            pixels: &pixels,
            work: match settings.model {
                Model::Path => Work::Samples,
                Model::Sppm => Work::Passes,
                Model::Classic | Model::Photon => Work::Rows,
            },
            done: 1,
            total: 1,
            run: settings.runs - 1,
            stats,
            finished: true,
        });
        // The image is finished either way.
        let _ = flow;
        Ok(Some(Rendered { image: Image::new(settings.width, settings.height, pixels), stats }))
    })
}

/// The state shared by the models' loops: the settings, the work so far, the finished runs.
struct Watcher<'w> {
    settings: &'w RenderSettings,
    stats: RenderStats,
    runs: RunSums,
    watch: &'w mut (dyn FnMut(&Snapshot<'_>) -> ControlFlow<()> + Send),
}

impl Watcher<'_> {
    /// Hands `pixels` to the watcher as an unfinished image.
    fn show(&mut self, pixels: &[[f32; 3]], work: Work, done: u64, total: u64, run: u32) -> ControlFlow<()> {
        (self.watch)(&Snapshot {
            width: self.settings.width,
            height: self.settings.height,
            pixels,
            work,
            done,
            total,
            run,
            stats: self.stats,
            finished: false,
        })
    }
}

/// The exact sums of the finished runs' images (each counted as one estimate, in 32-bit floats,
/// as [`super::render_portion`] sums them).
struct RunSums {
    sums: Vec<ExactSum>,
    count: u64,
}

impl RunSums {
    fn new(pixels: usize) -> RunSums {
        RunSums { sums: vec![ExactSum::default(); pixels], count: 0 }
    }

    fn add(&mut self, colors: &[DVec3]) {
        for (sum, c) in self.sums.iter_mut().zip(colors) {
            sum.add(c.as_vec3().as_dvec3());
        }
        self.count += 1;
    }

    /// The image so far: the first `done` pixels of the current run's `colors` averaged with the
    /// finished runs, the others the finished runs' mean (black before the first run is done).
    fn preview(&self, colors: &[DVec3], done: usize) -> Vec<[f32; 3]> {
        self.sums
            .iter()
            .enumerate()
            .map(|(i, sum)| {
                if i < done {
                    let mut s = *sum;
                    s.add(colors[i].as_vec3().as_dvec3());
                    s.mean(self.count + 1).as_vec3().to_array()
                } else if self.count > 0 {
                    sum.mean(self.count).as_vec3().to_array()
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }
}

/// Renders every run with `run_once` (its image, or `None` when stopped) and returns the final
/// pixels: a lone run's values as they are, several runs' exact mean.
fn watch_runs(
    watcher: &mut Watcher<'_>,
    mut run_once: impl FnMut(&mut Watcher<'_>, u32) -> Option<Vec<DVec3>>,
) -> Option<Vec<[f32; 3]>> {
    let runs = watcher.settings.runs;
    for run in 0..runs {
        let colors = run_once(watcher, run)?;
        if runs == 1 {
            return Some(colors.iter().map(|c| c.as_vec3().to_array()).collect());
        }
        watcher.runs.add(&colors);
    }
    let count = watcher.runs.count;
    Some(watcher.runs.sums.iter().map(|s| s.mean(count).as_vec3().to_array()).collect())
}

/// The path model: batches of sample indices over every pixel, summed exactly; the final image
/// is the mean of all `runs * spp` samples, as [`super::render`] computes it.
fn watch_path(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    progress: &(dyn Fn(Progress) + Sync),
    watcher: &mut Watcher<'_>,
) -> Option<Vec<[f32; 3]>> {
    let camera = camera_for(scene, settings);
    let total = settings.runs as u64 * settings.path_spp() as u64;
    let pixels = rows.len() as u64;
    let mut sums = vec![ExactSum::default(); rows.len()];
    let (mut done, mut batch) = (0u64, 1u64);
    loop {
        let samples = done..(done + batch).min(total);
        let started = Instant::now();
        let base = done * pixels;
        let report = |n| {
            progress(Progress { stage: super::Stage::Sampling, done: base + n, total: total * pixels });
        };
        let (batch_sums, rays) = path::render_sums(
            scene,
            &camera,
            settings.seed,
            settings.max_depth,
            rows,
            samples.clone(),
            &report,
        );
        sums.iter_mut().zip(&batch_sums).for_each(|(a, b)| a.merge(b));
        let taken = samples.end - samples.start;
        done = samples.end;
        watcher.stats.rays += rays;
        watcher.stats.camera_samples += taken * pixels;
        let mean: Vec<[f32; 3]> = sums.iter().map(|s| s.mean(done).as_vec3().to_array()).collect();
        if done == total {
            return Some(mean);
        }
        watcher
            .show(&mean, Work::Samples, done, total, (done / settings.path_spp() as u64) as u32)
            .continue_value()?;
        batch = next_batch(taken, started.elapsed());
    }
}

/// The next batch of samples a pixel after a batch of `taken` that took `time`: twice as many
/// while that stays under [`BATCH_SECONDS`], fewer when it took longer.
fn next_batch(taken: u64, time: Duration) -> u64 {
    let per_sample = time.as_secs_f64() / taken.max(1) as f64;
    if per_sample <= 0.0 {
        return taken * 2;
    }
    let fits = (BATCH_SECONDS / per_sample).floor() as u64;
    fits.clamp(1, taken * 2)
}

/// Run `run` of SPPM, one pass at a time (resumed from its state, as from a checkpoint).
fn watch_sppm_run(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    run: u32,
    progress: &(dyn Fn(Progress) + Sync),
    watcher: &mut Watcher<'_>,
) -> Option<Vec<DVec3>> {
    let sppm_settings = SppmSettings { seed: run_seed(settings.seed, run), ..settings.sppm_settings(scene) };
    let camera = camera_for(scene, settings);
    let total = sppm_settings.passes;
    let report = |done| progress(Progress { stage: super::Stage::Passes, done, total });
    let mut state = SppmState::new(rows.len());
    let before = watcher.stats;
    loop {
        let mut next = None;
        let mut after_pass = |s: &SppmState| {
            next = Some(s.clone());
            ControlFlow::Break(())
        };
        let (colors, stats) =
            sppm::render_from(scene, &camera, &sppm_settings, rows, state, &mut after_pass, &report);
        let run_stats = RenderStats {
            rays: stats.rays,
            camera_samples: rows.len() as u64 * stats.passes,
            sppm: Some(stats),
            ..RenderStats::default()
        };
        watcher.stats = before;
        watcher.stats.add(&run_stats);
        let Some(next) = next else { return Some(colors) };
        let preview = watcher.runs.preview(&colors, colors.len());
        watcher.show(&preview, Work::Passes, next.passes_done, total, run).continue_value()?;
        state = next;
    }
}

/// Run `run` of the classic or photon model, block of rows by block of rows from the top (the
/// photon map built once, for the first block).
fn watch_rows_run(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    run: u32,
    progress: &(dyn Fn(Progress) + Sync),
    watcher: &mut Watcher<'_>,
) -> Option<Vec<DVec3>> {
    let pixels = PixelSampling {
        camera: camera_for(scene, settings),
        sampling: settings.sampling,
        height: settings.height,
        seed: run_seed(settings.seed, run),
    };
    let photon_settings = settings.photon_settings(scene);
    let mut photon_map = None;
    let (width, height) = (settings.width, settings.height);
    let block = block_rows(height, rayon::current_num_threads());
    let mut colors = Vec::with_capacity(rows.len());
    let mut y = 0;
    while y < height {
        let end = (y + block).min(height);
        let chunk = Rows::from_blocks(width, std::iter::once(y..end).collect());
        let (chunk_colors, stats) = match settings.model {
            Model::Photon => {
                photon::render_rows(scene, &mut photon_map, &photon_settings, &pixels, &chunk, progress)
            }
            _ => adaptive::render_classic(scene, &pixels, &chunk, progress),
        };
        watcher.stats.add(&stats);
        colors.extend(chunk_colors);
        y = end;
        if y < height {
            let preview = watcher.runs.preview(&colors, colors.len());
            watcher.show(&preview, Work::Rows, y as u64, height as u64, run).continue_value()?;
        }
    }
    Some(colors)
}

/// Rows in a block of the classic and photon models: about 24 blocks an image, at least two
/// rows a thread.
fn block_rows(height: u32, threads: usize) -> u32 {
    height.div_ceil(24).max(2 * threads as u32).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TextureSearch;
    use crate::render::{RenderSettings, Sampling, render};
    use crate::scene::{self, SourceFile};

    fn scene() -> PreparedScene {
        let text = include_str!("../../../../scenes/cornell.txt");
        let source = SourceFile::from_text("cornell.txt", None, text.to_owned());
        let parsed = scene::parse(&source).expect("the scene parses");
        PreparedScene::new(parsed.scene, &TextureSearch::default()).expect("the scene prepares")
    }

    /// A snapshot's work, units done and in all, whether finished, and its pixels.
    type Shot = (Work, u64, u64, bool, Vec<[f32; 3]>);

    /// Watches a render to the end: the snapshots, and the finished image.
    fn watched(scene: &PreparedScene, settings: &RenderSettings) -> (Vec<Shot>, Image) {
        let mut shots = Vec::new();
        let mut watch = |s: &Snapshot<'_>| {
            assert_eq!(s.pixels.len(), (s.width * s.height) as usize);
            shots.push((s.work, s.done, s.total, s.finished, s.pixels.to_vec()));
            ControlFlow::Continue(())
        };
        let rendered =
            render_watched(scene, settings, &|_| {}, &mut watch).expect("renders").expect("not stopped");
        (shots, rendered.image)
    }

    fn settings(scene: &PreparedScene, model: Model) -> RenderSettings {
        RenderSettings {
            width: 24,
            height: 18,
            threads: Some(2),
            model,
            photons: Some(2000),
            passes: Some(3),
            ..RenderSettings::for_scene(scene)
        }
    }

    #[test]
    fn every_model_ends_with_the_renders_own_bytes() {
        let scene = scene();
        for model in Model::ALL {
            for runs in [1, 2] {
                let mut s = settings(&scene, model);
                s.runs = runs;
                if model == Model::Path {
                    s.sampling = Sampling::Uniform(5);
                }
                let (shots, image) = watched(&scene, &s);
                let plain = render(&scene, &s, &|_| {}).expect("renders").image;
                assert_eq!(image.pixels(), plain.pixels(), "{model:?}, {runs} runs");
                let last = shots.last().expect("a snapshot");
                assert!(last.3, "the last snapshot is the finished image");
                assert_eq!(last.4, plain.pixels(), "{model:?}");
                // Unfinished images came first, and they differ from the finished one.
                assert!(shots.len() >= 2, "{model:?}: {} snapshots", shots.len());
                assert!(shots[..shots.len() - 1].iter().all(|s| !s.3));
                assert_ne!(shots[0].4, last.4, "{model:?}");
            }
        }
    }

    #[test]
    fn the_watcher_stops_the_render() {
        let scene = scene();
        for model in Model::ALL {
            let mut s = settings(&scene, model);
            s.sampling = Sampling::Uniform(4);
            let mut seen = 0;
            let mut watch = |_: &Snapshot<'_>| {
                seen += 1;
                ControlFlow::Break(())
            };
            let result = render_watched(&scene, &s, &|_| {}, &mut watch).expect("starts");
            assert!(result.is_none(), "{model:?}");
            assert_eq!(seen, 1, "{model:?}");
        }
    }

    #[test]
    fn path_batches_start_small_and_grow_within_the_time() {
        assert_eq!(next_batch(1, Duration::from_millis(1)), 2);
        assert_eq!(next_batch(8, Duration::from_millis(800)), 2);
        assert_eq!(next_batch(4, Duration::from_secs(10)), 1);
        assert_eq!(next_batch(3, Duration::ZERO), 6);
    }
}
