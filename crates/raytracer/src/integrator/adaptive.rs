//! The pixel sampler of the classic model and the course's photon mapper: one sample a pixel,
//! then refinement where the first pass finds an edge or noise, or a uniform number of stratified
//! samples.
//!
//! It renders any set of whole rows ([`Rows`]): the first pass also traces the rows just above and
//! below each block (when the image has them), so that every pixel of the set compares itself
//! with the same neighbours as in a render of the whole image and comes out the same bit for bit.
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

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::base::rows::Rows;
use crate::base::sampler::{PixelRng, Siblings, Strata};
use crate::camera::Camera;
use crate::integrator::classic::{Classic, TraceContext};
use crate::integrator::report::{Progress, RenderStats, Stage};
use crate::prepare::PreparedScene;

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

/// How pixels are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One sample per pixel, then `REFINE_GRID^2` samples where an edge or a contrast is found.
    Adaptive,
    /// This many stratified samples in every pixel (`--spp N`).
    Uniform(u32),
}

/// What the adaptive sampler needs of a render: its camera, how it samples pixels, the image's
/// height (the rows that have neighbours) and the seed of every pixel's random numbers.
#[derive(Clone, Debug)]
pub struct PixelSampling {
    /// The camera, at the image's size.
    pub camera: Camera,
    /// Adaptive or uniform sampling.
    pub sampling: Sampling,
    /// The image's height in pixels.
    pub height: u32,
    /// The seed of every pixel's random numbers.
    pub seed: u64,
}

/// The classic model's row loop: the colours of the pixels of `rows` (row by row, in the order
/// of [`Rows::ys`]) and what they took.
pub fn render_classic(
    scene: &PreparedScene,
    pixels: &PixelSampling,
    rows: &Rows,
    progress: &(dyn Fn(Progress) + Sync),
) -> (Vec<DVec3>, RenderStats) {
    AdaptiveSampler::new(Classic::new(scene), pixels).run(rows, progress)
}

/// Pass numbers, part of each pixel's random seed.
const FIRST_PASS: u32 = 0;
const REFINE_PASS: u32 = 1;

/// Renders pixels with the classic model's recursion (with or without a photon map).
pub(crate) struct AdaptiveSampler<'s> {
    integrator: Classic<'s>,
    camera: Camera,
    sampling: Sampling,
    height: u32,
    /// The seed of every pixel's random numbers.
    seed: u64,
    rays: AtomicU64,
    lookups: AtomicU64,
}

impl<'s> AdaptiveSampler<'s> {
    /// A sampler of pixels for `integrator`.
    pub(crate) fn new(integrator: Classic<'s>, pixels: &PixelSampling) -> AdaptiveSampler<'s> {
        AdaptiveSampler {
            integrator,
            camera: pixels.camera.clone(),
            sampling: pixels.sampling,
            height: pixels.height,
            seed: pixels.seed,
            rays: AtomicU64::new(0),
            lookups: AtomicU64::new(0),
        }
    }

    /// The colours of the pixels of `rows` (row by row, in the order of [`Rows::ys`]) and what
    /// they took.
    pub(crate) fn run(&self, rows: &Rows, progress: &(dyn Fn(Progress) + Sync)) -> (Vec<DVec3>, RenderStats) {
        let w = rows.width() as usize;
        let (first_samples, track_tags) = match self.sampling {
            Sampling::Adaptive => (1, true),
            Sampling::Uniform(n) => (n, false),
        };
        // The rows the first pass traces: those asked for, and (adaptive) their neighbours.
        let traced: Vec<u32> =
            if track_tags { rows.with_neighbours(self.height) } else { rows.ys().collect() };
        let mut colors = vec![DVec3::ZERO; w * traced.len()];
        let n_tracked = if track_tags { colors.len() } else { 0 };
        let mut traces = vec![PixelTrace::default(); n_tracked];
        let rows_done = AtomicU64::new(0);
        let total_rows = traced.len() as u64;
        let first = Strata::for_count(first_samples);
        // With many samples a pixel, nested estimates are shared among ceil(sqrt(n)) groups of
        // them, so their sample count grows with the square root of the pixel's.
        let first_groups = (first_samples as f64).sqrt().ceil() as u32;
        let trace_row = |j: usize, row: &mut [DVec3], mut row_traces: Option<&mut [PixelTrace]>| {
            let y = traced[j];
            let mut rays = 0;
            for (x, c) in row.iter_mut().enumerate() {
                let trace = row_traces.as_deref_mut().map(|t| &mut t[x]);
                *c = self.pixel(x as u32, y, FIRST_PASS, first, first_groups, trace, &mut rays);
            }
            self.rays.fetch_add(rays, Ordering::Relaxed);
            let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(Progress { stage: Stage::Tracing, done, total: total_rows });
        };
        if track_tags {
            colors
                .par_chunks_mut(w)
                .zip(traces.par_chunks_mut(w))
                .enumerate()
                .for_each(|(j, (row, row_traces))| trace_row(j, row, Some(row_traces)));
        } else {
            colors.par_chunks_mut(w).enumerate().for_each(|(j, row)| trace_row(j, row, None));
        }
        let mut camera_samples = colors.len() as u64 * first_samples as u64;

        let mut refined_pixels = 0;
        if track_tags {
            let band = Band { width: w, height: self.height, rows: &traced };
            let wanted: Vec<usize> = band.positions(rows).collect();
            let flagged = pixels_to_refine(&colors, &traces, &band, &wanted);
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
                            let (x, y) = ((r.index % w) as u32, traced[r.index / w]);
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
            // Keep the rows asked for, dropping the neighbours traced for comparison.
            colors = wanted.iter().map(|&i| colors[i]).collect();
        }

        let stats = RenderStats {
            rays: self.rays.load(Ordering::Relaxed),
            camera_samples,
            refined_pixels,
            threads: rayon::current_num_threads(),
            lookups: self.lookups.load(Ordering::Relaxed),
            ..RenderStats::default()
        };
        (colors, stats)
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
        let mut rng = PixelRng::new(self.seed, x, y, pass);
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

/// A pixel to refine: its index in the traced rows, its camera samples and how their nested
/// estimates are shared (see [`AdaptiveSampler::pixel`]), and the weight its first-pass colour
/// keeps in the result.
struct Refinement {
    index: usize,
    grid: Strata,
    groups: u32,
    first_weight: f64,
}

/// The rows the first pass traced (image rows `rows[j]`, increasing) of an image `height` rows
/// high, stored row after row `width` pixels long.
struct Band<'a> {
    width: usize,
    height: u32,
    rows: &'a [u32],
}

impl Band<'_> {
    /// The positions in the band of the pixels of `wanted`, in its order.
    fn positions<'a>(&'a self, wanted: &'a Rows) -> impl Iterator<Item = usize> + 'a {
        let mut j = 0;
        wanted.ys().flat_map(move |y| {
            while self.rows[j] != y {
                j += 1;
            }
            (j * self.width)..(j + 1) * self.width
        })
    }

    /// The positions of the 4-neighbours of position `i` that the image has (all traced: a band
    /// holds the rows around every row it is asked about).
    fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> {
        let (x, j) = (i % self.width, i / self.width);
        let y = self.rows[j];
        let w = self.width;
        [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| {
                debug_assert_eq!(self.rows[j - 1], y - 1);
                i - w
            }),
            (y + 1 < self.height).then(|| {
                debug_assert_eq!(self.rows[j + 1], y + 1);
                i + w
            }),
        ]
        .into_iter()
        .flatten()
    }
}

/// The pixels of `wanted` (positions in `band`) to refine, in their order: a tag different from a
/// 4-neighbour's or a colour differing from a 4-neighbour's by more than [`CONTRAST_THRESHOLD`]
/// in some channel (an edge: a `REFINE_GRID` grid of camera samples replaces the first one), or an
/// estimated error above [`NOISE_THRESHOLD`] (noise: more nested samples, as many more as the
/// error says it needs, up to [`MAX_NESTED_FACTOR`] times; an edge pixel takes them in its grid,
/// any other adds them with a `NOISE_GRID` grid to its first sample).
fn pixels_to_refine(
    colors: &[DVec3],
    traces: &[PixelTrace],
    band: &Band,
    wanted: &[usize],
) -> Vec<Refinement> {
    let differs = |a: usize, b: usize| {
        traces[a].tag != traces[b].tag || (colors[a] - colors[b]).abs().max_element() > CONTRAST_THRESHOLD
    };
    wanted
        .iter()
        .filter_map(|&i| {
            let edge = band.neighbours(i).any(|n| differs(i, n));
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
    use crate::render::{RenderSettings, render};

    /// The refinements of a whole `w x h` first pass.
    fn refine_all(colors: &[DVec3], traces: &[PixelTrace], w: usize, h: usize) -> Vec<Refinement> {
        let rows: Vec<u32> = (0..h as u32).collect();
        let band = Band { width: w, height: h as u32, rows: &rows };
        let wanted: Vec<usize> = (0..w * h).collect();
        pixels_to_refine(colors, traces, &band, &wanted)
    }

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
        assert!(refine_all(&colors, &traces, 5, 4).is_empty());
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
            let flagged = refine_all(&colors, &traces, w, h);
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
        assert!(refine_all(&colors, &traces, 3, 3).is_empty());
    }

    #[test]
    fn a_noisy_pixel_gets_as_many_nested_samples_as_its_error_asks_for() {
        let (w, h) = (3, 3);
        // Error ratio to the threshold -> samples needed, as a multiple of the first pass's.
        for (ratio, need) in [(0.99, 1.0f64), (1.2, 1.44), (1.5, 2.25), (1.9, 3.61), (3.0, 9.0)] {
            let (colors, mut traces) = flat(w, h);
            traces[4].error = (ratio * NOISE_THRESHOLD) as f32;
            let flagged = refine_all(&colors, &traces, w, h);
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
        let flagged = refine_all(&colors, &traces, w, h);
        assert_eq!(flagged.len(), 2);
        assert_eq!(shares(&flagged[0]), MAX_NESTED_FACTOR as f64);
        assert_eq!(shares(&flagged[1]), 1.0);
    }

    #[test]
    fn a_band_compares_its_rows_with_the_rows_traced_around_them() {
        // Rows 2 and 3 of an image 6 rows high, traced with rows 1 and 4 around them; an edge
        // between rows 1 and 2 is seen from row 2 only.
        let (w, rows) = (3, [1u32, 2, 3, 4]);
        let band = Band { width: w, height: 6, rows: &rows };
        let (colors, mut traces) = flat(w, rows.len());
        traces[1].tag = 9; // row 1, column 1
        let wanted: Vec<usize> = (w..3 * w).collect();
        let flagged: Vec<usize> =
            pixels_to_refine(&colors, &traces, &band, &wanted).iter().map(|r| r.index).collect();
        assert_eq!(flagged, [w + 1]);
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
