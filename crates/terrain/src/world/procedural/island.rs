//! The island's heightmap: warped fractal noise under a radial mask, so that the land rises from
//! a sea floor, has beaches, hills and a few snowy peaks, and the map's border is under water.

use noise::{Fbm, MultiFractal, NoiseFn, Perlin, RidgedMulti};

use super::field::{grid_from_fn_with_progress, layer_seed, smoothstep};
use crate::config::SceneConfig;
use crate::world::heightmap::sixteen_of_level;
use crate::world::{Heightmap, HeightmapError};

/// Distance from the map's centre to the coast, in map half-widths, before the coast's noise.
const COAST_RADIUS: f64 = 0.70;

/// Height of the highest peaks (all but the top 0.05% of the map), in world units.
const PEAK_HEIGHT: f64 = 2.15;
/// Height the summits round off toward, in world units.
const MAX_HEIGHT: f64 = 2.32;
/// Width of the rounding of the summits: heights from `MAX_HEIGHT + SUMMIT_ROUNDING` up are all
/// cut to `MAX_HEIGHT`, flat.
const SUMMIT_ROUNDING: f64 = 0.12;
/// Rank of the highest peaks among the map's samples, as a fraction: all but the top 0.05%.
const PEAK_QUANTILE: f64 = 0.9995;

/// Largest heightmap side generated sample by sample. Larger islands evaluate the island's
/// shape on a grid of this side, resample it bicubically and add finer noise: the shape's noise
/// has no features this grid cannot hold, and the full evaluation would cost 16 times as much at
/// 8193 samples a side (see [`island_heightmap`]).
pub const EXACT_SIDE: u32 = 2049;

/// The noise layers of one island.
struct IslandNoise {
    warp_x: Fbm<Perlin>,
    warp_z: Fbm<Perlin>,
    hills: Fbm<Perlin>,
    ridges: RidgedMulti<Perlin>,
    massifs: Fbm<Perlin>,
    coast: Fbm<Perlin>,
}

impl IslandNoise {
    fn new(seed: u32) -> Self {
        Self {
            warp_x: Fbm::<Perlin>::new(layer_seed(seed, 1)).set_octaves(4),
            warp_z: Fbm::<Perlin>::new(layer_seed(seed, 2)).set_octaves(4),
            hills: Fbm::<Perlin>::new(layer_seed(seed, 3)).set_octaves(5),
            ridges: RidgedMulti::<Perlin>::new(layer_seed(seed, 4)).set_octaves(5),
            massifs: Fbm::<Perlin>::new(layer_seed(seed, 6)).set_octaves(3),
            coast: Fbm::<Perlin>::new(layer_seed(seed, 5)).set_octaves(5),
        }
    }

    /// The island's base height and its mountains' height (before their scaling) at (`px`,
    /// `pz`) in [-1, 1]^2, in world units.
    fn elevation(&self, px: f64, pz: f64) -> (f64, f64) {
        // Domain warp: bends coasts and valleys so they do not look like blobs of noise.
        let qx = px + 0.22 * self.warp_x.get([px * 1.3, pz * 1.3]);
        let qz = pz + 0.22 * self.warp_z.get([px * 1.3 + 5.2, pz * 1.3 + 1.7]);
        // Signed distance to a ragged coast, in map half-widths: positive inland.
        // A squircle rather than a circle: the island fills more of the square map while its
        // border stays under water.
        let radius = (qx.powi(4) + qz.powi(4)).sqrt().sqrt() + 0.20 * self.coast.get([qx * 2.2, qz * 2.2]);
        let inland = COAST_RADIUS - radius;
        let hill = self.hills.get([qx * 2.6, qz * 2.6]);
        let ridge = ((self.ridges.get([qx * 0.9 + 3.1, qz * 0.9 - 2.3]) + 1.0) * 0.5).max(0.0);
        // World height: a slope through the coastline that levels off into rolling lowlands
        // inland and into a sea floor offshore, with ridged mountains further inland.
        let lowland = 0.42 + 0.45 * hill;
        let profile = -smooth_max(-inland * 3.0, -lowland, 0.25);
        let floor = -1.05 + 0.2 * hill;
        let base = smooth_max(profile, floor, 0.3);
        // Mountains rise where a broad noise is high, so they are rounded where it peaks and
        // slope gently where it falls (masks would make flat tops and cliffs); ridged noise
        // only sharpens their crests.
        let uplift = (self.massifs.get([qx * 1.1 + 7.3, qz * 1.1 - 4.1]) + 0.1).max(0.0);
        let mountains = uplift.powf(2.0) * (0.55 + 0.45 * ridge) * smoothstep(0.0, 0.35, inland);
        (base, mountains)
    }
}

/// The base and mountain heights on a `size` x `size` grid of pixel centres, and the scale that
/// brings the highest peaks (all but the top 0.05% of the map) to `PEAK_HEIGHT`: whatever the
/// seed, every island gets snow-capped summits and none is cut flat.
fn elevations(noise: &IslandNoise, size: u32, progress: &mut dyn FnMut(f32)) -> (Vec<(f64, f64)>, f64) {
    let scale = 2.0 / size as f64;
    let elevations = grid_from_fn_with_progress(
        size,
        size,
        |x, y| {
            // Position in [-1, 1]^2, pixel centres.
            let px = (x as f64 + 0.5) * scale - 1.0;
            let pz = (y as f64 + 0.5) * scale - 1.0;
            noise.elevation(px, pz)
        },
        progress,
    );
    let scale = mountain_scale(&elevations);
    (elevations, scale)
}

/// Generates a `size` x `size` island heightmap for `seed`, in grey levels placed with `config`'s
/// height mapping (the coast is at the level of y = 0). Bit-identical for the same arguments.
///
/// Up to [`EXACT_SIDE`] samples a side, every sample is evaluated from the noise and kept as an
/// `f32` level. Larger maps take the shape from a grid of [`EXACT_SIDE`] samples, resampled
/// bicubically, and add one octave of fine noise per doubling beyond it (rougher on mountains,
/// none at the shore, so beaches stay smooth); they are kept as 16-bit values (2 bytes a
/// sample, steps of 1/257 grey level). `progress` hears the fraction done (0 to 1).
pub fn island_heightmap(
    seed: u32,
    size: u32,
    config: &SceneConfig,
    progress: &mut dyn FnMut(f32),
) -> Result<Heightmap, HeightmapError> {
    island_with_exact_side(seed, size, EXACT_SIDE, config, progress)
}

/// [`island_heightmap`] with the largest exactly evaluated side as a parameter (tests use a small
/// one).
fn island_with_exact_side(
    seed: u32,
    size: u32,
    exact_side: u32,
    config: &SceneConfig,
    progress: &mut dyn FnMut(f32),
) -> Result<Heightmap, HeightmapError> {
    // Reject bad sizes before the work.
    Heightmap::check_size(size, size)?;
    let noise = IslandNoise::new(seed);
    let lowest = config.level_of_height(-1.2) as f64;
    let highest = config.level_of_height(MAX_HEIGHT as f32) as f64;
    let level_of = |height: f64| {
        // Peaks round off just below the top of the height range.
        let height = -smooth_max(-height, -MAX_HEIGHT, SUMMIT_ROUNDING);
        f64::from(config.level_of_height(height as f32)).clamp(lowest, highest) as f32
    };
    if size <= exact_side {
        let (elevations, scale) = elevations(&noise, size, progress);
        let levels =
            elevations.into_iter().map(|(base, mountain)| level_of(base + mountain * scale)).collect();
        return Heightmap::new(size, size, levels);
    }
    // The shape on the coarse grid: a fifth of the work at 4097 samples, a sixteenth at 8193.
    let coarse_share = 0.3;
    let (elevations, scale) = elevations(&noise, exact_side, &mut |done| progress(done * coarse_share));
    let shape = Grid {
        side: exact_side as usize,
        heights: elevations.into_iter().map(|(base, mountain)| base + mountain * scale).collect(),
    };
    let octaves = (size - 1).div_ceil(exact_side - 1).ilog2() as usize;
    let detail = Fbm::<Perlin>::new(layer_seed(seed, 7)).set_octaves(octaves.max(1));
    let to_coarse = exact_side as f64 / size as f64;
    let step = 2.0 / size as f64;
    // Where each column and each row of samples reads the coarse grid: at the sample's centre in
    // the coarse grid's sample coordinates.
    let taps: Vec<Taps> = (0..size).map(|i| shape.taps((i as f64 + 0.5) * to_coarse - 0.5)).collect();
    let values = grid_from_fn_with_progress(
        size,
        size,
        |x, y| {
            // This sample's centre in [-1, 1]^2.
            let (px, pz) = ((x as f64 + 0.5) * step - 1.0, (y as f64 + 0.5) * step - 1.0);
            let height = shape.interpolate(&taps[x as usize], &taps[y as usize]);
            let roughness =
                smoothstep(0.08, 0.3, height.abs()) * (0.012 + 0.04 * smoothstep(0.4, 1.6, height));
            let height = height + roughness * detail.get([px * DETAIL_FREQUENCY, pz * DETAIL_FREQUENCY]);
            sixteen_of_level(level_of(height))
        },
        &mut |done| progress(coarse_share + done * (1.0 - coarse_share)),
    );
    Heightmap::from_sixteen_bit(size, size, values)
}

/// Cycles per map half-width of the first octave of fine noise large maps add (then twice as
/// many per octave): 80 is about 13 samples a cycle at [`EXACT_SIDE`] samples, finer than the
/// shape's own noise.
const DETAIL_FREQUENCY: f64 = 80.0;

/// A square grid of heights, sampled between its points.
struct Grid {
    side: usize,
    heights: Vec<f64>,
}

impl Grid {
    /// The four samples along one axis that interpolation at coordinate `t` reads (clamped to the
    /// grid) and their Catmull-Rom weights: the same for a whole row or column of a resampling,
    /// so worked out once for it.
    fn taps(&self, t: f64) -> Taps {
        let last = self.side as isize - 1;
        let t0 = t.floor();
        let f = t - t0;
        let first = t0 as isize - 1;
        let (f2, f3) = (f * f, f * f * f);
        Taps {
            samples: [0, 1, 2, 3].map(|i| (first + i).clamp(0, last) as usize),
            weights: [
                -0.5 * f3 + f2 - 0.5 * f,
                1.5 * f3 - 2.5 * f2 + 1.0,
                -1.5 * f3 + 2.0 * f2 + 0.5 * f,
                0.5 * f3 - 0.5 * f2,
            ],
        }
    }

    /// Catmull-Rom bicubic interpolation between the samples of `columns` x `rows` (the taps of
    /// sample coordinates x and y, sample centres at whole numbers), the grid's border extended
    /// outward.
    fn interpolate(&self, columns: &Taps, rows: &Taps) -> f64 {
        (0..4)
            .map(|j| {
                let line = &self.heights[rows.samples[j] * self.side..][..self.side];
                let row: f64 = (0..4).map(|i| columns.weights[i] * line[columns.samples[i]]).sum();
                rows.weights[j] * row
            })
            .sum()
    }
}

/// Where a bicubic interpolation reads along one axis ([`Grid::taps`]).
struct Taps {
    /// The four samples' indices along the axis, clamped to the grid.
    samples: [usize; 4],
    /// Their weights.
    weights: [f64; 4],
}

/// The factor of the mountains that makes, whatever the seed, the highest peaks (all but the top
/// 0.05% of the map) reach about `PEAK_HEIGHT`: every island gets snow-capped summits and none is
/// cut flat.
///
/// A first estimate takes the sample at that rank of the unscaled heights and scales its
/// mountain to reach `PEAK_HEIGHT`. Scaling changes the ranking, though: where the mountains are
/// low at that sample (seed 3), other samples with more mountain and less base rise far past
/// it, and 1% of seed 3's map was cut flat at `MAX_HEIGHT`. When the estimate lifts more than
/// the top 0.05% into the flat cut, the factor is found exactly instead, by bisection on the
/// scaled heights (which rise with the factor, and so does their quantile). Seeds whose estimate
/// cuts nothing flat keep it, and with it their islands.
fn mountain_scale(elevations: &[(f64, f64)]) -> f64 {
    let rank = ((elevations.len() as f64 * PEAK_QUANTILE) as usize).min(elevations.len() - 1);
    let mut heights: Vec<f64> = elevations.iter().map(|&(base, mountain)| base + mountain).collect();
    // The height at that rank, as sorting them all would place it.
    let at_rank = *heights.select_nth_unstable_by(rank, f64::total_cmp).1;
    let (base_at_top, mountain_at_top) =
        elevations.iter().copied().find(|&(base, mountain)| base + mountain == at_rank).unwrap_or((0.0, 1.0));
    let estimate = ((PEAK_HEIGHT - base_at_top) / mountain_at_top.max(1e-3)).clamp(0.0, 10.0);
    let quantile = |scale: f64| {
        let mut scaled: Vec<f64> =
            elevations.iter().map(|&(base, mountain)| base + mountain * scale).collect();
        *scaled.select_nth_unstable_by(rank, f64::total_cmp).1
    };
    if quantile(estimate) < MAX_HEIGHT + SUMMIT_ROUNDING {
        return estimate;
    }
    let (mut low, mut high) = (0.0, estimate);
    for _ in 0..48 {
        let middle = 0.5 * (low + high);
        if quantile(middle) > PEAK_HEIGHT {
            high = middle;
        } else {
            low = middle;
        }
    }
    low
}

/// A maximum of `a` and `b` with a rounded corner of width `k` (polynomial smooth maximum).
fn smooth_max(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (a - b) / k).clamp(0.0, 1.0);
    b + (a - b) * h + k * h * (1.0 - h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_per_seed() {
        let config = SceneConfig::default();
        let a = island_heightmap(3, 64, &config, &mut |_| {}).expect("valid size");
        let b = island_heightmap(3, 64, &config, &mut |_| {}).expect("valid size");
        let c = island_heightmap(4, 64, &config, &mut |_| {}).expect("valid size");
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn an_island_with_a_shore_in_a_sea() {
        let config = SceneConfig::default();
        for seed in [1, 2, 3, 42] {
            let map = island_heightmap(seed, 128, &config, &mut |_| {}).expect("valid size");
            let sea_level = config.level_of_height(0.0);
            let count = map.levels().len();
            let under = map.levels().filter(|&l| l < sea_level).count() as f32 / count as f32;
            assert!((0.25..0.8).contains(&under), "seed {seed}: {under} of the map under water");
            // The whole border is sea.
            let n = map.columns();
            for i in 0..n {
                for (row, column) in [(0, i), (n - 1, i), (i, 0), (i, n - 1)] {
                    assert!(map.level(row, column) < sea_level, "seed {seed}: border above water");
                }
            }
            // The centre region holds land that rises well above the shore.
            let highest = map.levels().fold(f32::MIN, f32::max);
            assert!(config.height_of_level(highest) > 1.0, "seed {seed}: flat island");
        }
    }

    #[test]
    fn large_maps_follow_the_exact_shape_with_finer_detail() {
        let config = SceneConfig::default();
        // As 8193 samples relate to 2049, 513 relate to 129 (the map's shape from 129 samples a side).
        let exact = island_heightmap(5, 129, &config, &mut |_| {}).expect("valid size");
        let mut reports = Vec::new();
        let large =
            island_with_exact_side(5, 513, 129, &config, &mut |done| reports.push(done)).expect("valid size");
        assert_eq!(large.bytes_per_sample(), 2);
        assert!(reports.windows(2).all(|w| w[0] <= w[1]) && reports.last() == Some(&1.0));
        // Sample (i, j) of the coarse map sits at sample coordinates ((i + 0.5) 513 / 129 - 0.5,
        // ...) of the large one: the shapes agree there within the detail's amplitude.
        let large_at = |row: f32, column: f32| {
            let (r, c) = (row.floor() as u32, column.floor() as u32);
            let (fr, fc) = (row - r as f32, column - c as f32);
            let top = large.level(r, c) * (1.0 - fc) + large.level(r, c + 1) * fc;
            let bottom = large.level(r + 1, c) * (1.0 - fc) + large.level(r + 1, c + 1) * fc;
            top * (1.0 - fr) + bottom * fr
        };
        let to_large = |i: u32| (i as f32 + 0.5) * 513.0 / 129.0 - 0.5;
        let mut worst = 0.0f32;
        for i in 4..125 {
            for j in 4..125 {
                worst = worst.max((large_at(to_large(i), to_large(j)) - exact.level(i, j)).abs());
            }
        }
        assert!(worst < 8.0, "the shapes differ by {worst} levels");
        // Two octaves of detail (513 is 4 x 128 + 1) make the large map's land rougher than the
        // same map evaluated sample by sample.
        let full = island_with_exact_side(5, 513, 513, &config, &mut |_| {}).expect("valid size");
        let roughness = |map: &Heightmap| {
            let mut total = 0.0f64;
            for r in 1..512 {
                for c in 1..512 {
                    if config.height_of_level(full.level(r, c)) > 0.6 {
                        let curve = map.level(r, c - 1) - 2.0 * map.level(r, c) + map.level(r, c + 1);
                        total += f64::from(curve.abs());
                    }
                }
            }
            total
        };
        assert!(roughness(&large) > 1.5 * roughness(&full), "{} vs {}", roughness(&large), roughness(&full));
        let again = island_with_exact_side(5, 513, 129, &config, &mut |_| {}).expect("valid size");
        assert_eq!(large, again, "not deterministic");
    }

    #[test]
    fn no_seed_cuts_its_summits_flat() {
        // At most the top 0.05% of the map may reach the flat cut at the top of the height
        // range; seed 3 (the README's example) had 1% of its samples there, 9 and 11 a quarter.
        let config = SceneConfig::default();
        let top = config.level_of_height(MAX_HEIGHT as f32);
        for seed in 1..=12 {
            let map = island_heightmap(seed, 256, &config, &mut |_| {}).expect("valid size");
            let flat = map.levels().filter(|&l| l >= top - 1e-3).count();
            let fraction = flat as f64 / (map.columns() as f64 * map.rows() as f64);
            assert!(
                fraction <= 1.0 - PEAK_QUANTILE,
                "seed {seed}: {:.3}% of the map is cut flat",
                100.0 * fraction
            );
            let highest = map.levels().fold(f32::MIN, f32::max);
            assert!(
                config.height_of_level(highest) > PEAK_HEIGHT as f32 - 0.05,
                "seed {seed}: no snowy peaks"
            );
        }
    }

    #[test]
    fn bicubic_interpolation_meets_the_samples_and_follows_ramps() {
        // 6 x 6 samples on a tilted plane: 3 per column, 5 per row, plus 1.
        let side = 6;
        let heights =
            (0..side * side).map(|i| 1.0 + 3.0 * (i % side) as f64 + 5.0 * (i / side) as f64).collect();
        let grid = Grid { side, heights };
        let at = |x: f64, y: f64| grid.interpolate(&grid.taps(x), &grid.taps(y));
        for (x, y) in [(0.0, 0.0), (2.0, 3.0), (5.0, 1.0)] {
            assert_eq!(at(x, y), 1.0 + 3.0 * x + 5.0 * y);
        }
        // Catmull-Rom reproduces a plane between samples, away from the border.
        for (x, y) in [(1.25, 2.5), (3.75, 1.5), (2.5, 3.125)] {
            assert!((at(x, y) - (1.0 + 3.0 * x + 5.0 * y)).abs() < 1e-12, "({x}, {y})");
        }
        // Beyond the border the border's samples are read.
        assert_eq!(at(-3.0, -3.0), 1.0);
        assert_eq!(at(9.0, 0.0), 16.0);
    }

    #[test]
    fn rejects_sizes_a_heightmap_cannot_have() {
        let config = SceneConfig::default();
        assert!(matches!(island_heightmap(1, 1, &config, &mut |_| {}), Err(HeightmapError::TooSmall { .. })));
        assert!(matches!(
            island_heightmap(1, 100_000, &config, &mut |_| {}),
            Err(HeightmapError::TooLarge { .. })
        ));
    }
}
