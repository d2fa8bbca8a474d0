//! The island's heightmap: warped fractal noise under a radial mask, so that the land rises from
//! a sea floor, has beaches, hills and a few snowy peaks, and the map's border is under water.

use noise::{Fbm, MultiFractal, NoiseFn, Perlin, RidgedMulti};

use super::field::{grid_from_fn, layer_seed, smoothstep};
use crate::config::SceneConfig;
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

/// Generates a `size` x `size` island heightmap for `seed`, in grey levels placed with `config`'s
/// height mapping (the coast is at the level of y = 0). Bit-identical for the same arguments.
pub fn island_heightmap(seed: u32, size: u32, config: &SceneConfig) -> Result<Heightmap, HeightmapError> {
    // Reject bad sizes before the work.
    Heightmap::check_size(size, size)?;
    let warp_x = Fbm::<Perlin>::new(layer_seed(seed, 1)).set_octaves(4);
    let warp_z = Fbm::<Perlin>::new(layer_seed(seed, 2)).set_octaves(4);
    let hills = Fbm::<Perlin>::new(layer_seed(seed, 3)).set_octaves(5);
    let ridges = RidgedMulti::<Perlin>::new(layer_seed(seed, 4)).set_octaves(5);
    let massifs = Fbm::<Perlin>::new(layer_seed(seed, 6)).set_octaves(3);
    let coast = Fbm::<Perlin>::new(layer_seed(seed, 5)).set_octaves(5);
    let lowest = config.level_of_height(-1.2) as f64;
    let highest = config.level_of_height(MAX_HEIGHT as f32) as f64;
    let scale = 2.0 / size as f64;
    let elevations = grid_from_fn(size, size, |x, y| {
        // Position in [-1, 1]^2, pixel centres.
        let px = (x as f64 + 0.5) * scale - 1.0;
        let pz = (y as f64 + 0.5) * scale - 1.0;
        // Domain warp: bends coasts and valleys so they do not look like blobs of noise.
        let qx = px + 0.22 * warp_x.get([px * 1.3, pz * 1.3]);
        let qz = pz + 0.22 * warp_z.get([px * 1.3 + 5.2, pz * 1.3 + 1.7]);
        // Signed distance to a ragged coast, in map half-widths: positive inland.
        // A squircle rather than a circle: the island fills more of the square map while its
        // border stays under water.
        let radius = (qx.powi(4) + qz.powi(4)).sqrt().sqrt() + 0.20 * coast.get([qx * 2.2, qz * 2.2]);
        let inland = COAST_RADIUS - radius;
        let hill = hills.get([qx * 2.6, qz * 2.6]);
        let ridge = ((ridges.get([qx * 0.9 + 3.1, qz * 0.9 - 2.3]) + 1.0) * 0.5).max(0.0);
        // World height: a slope through the coastline that levels off into rolling lowlands
        // inland and into a sea floor offshore, with ridged mountains further inland.
        let lowland = 0.42 + 0.45 * hill;
        let profile = -smooth_max(-inland * 3.0, -lowland, 0.25);
        let floor = -1.05 + 0.2 * hill;
        let base = smooth_max(profile, floor, 0.3);
        // Mountains rise where a broad noise is high, so they are rounded where it peaks and
        // slope gently where it falls (masks would make flat tops and cliffs); ridged noise
        // only sharpens their crests.
        let uplift = (massifs.get([qx * 1.1 + 7.3, qz * 1.1 - 4.1]) + 0.1).max(0.0);
        let mountains = uplift.powf(2.0) * (0.55 + 0.45 * ridge) * smoothstep(0.0, 0.35, inland);
        (base, mountains)
    });
    let scale = mountain_scale(&elevations);
    let levels = elevations
        .into_iter()
        .map(|(base, mountain)| {
            let height = base + mountain * scale;
            // Peaks round off just below the top of the height range.
            let height = -smooth_max(-height, -MAX_HEIGHT, SUMMIT_ROUNDING);
            f64::from(config.level_of_height(height as f32)).clamp(lowest, highest) as f32
        })
        .collect();
    Heightmap::new(size, size, levels)
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
    heights.sort_by(f64::total_cmp);
    let (base_at_top, mountain_at_top) = elevations
        .iter()
        .copied()
        .find(|&(base, mountain)| base + mountain == heights[rank])
        .unwrap_or((0.0, 1.0));
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
        let a = island_heightmap(3, 64, &config).expect("valid size");
        let b = island_heightmap(3, 64, &config).expect("valid size");
        let c = island_heightmap(4, 64, &config).expect("valid size");
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn an_island_with_a_shore_in_a_sea() {
        let config = SceneConfig::default();
        for seed in [1, 2, 3, 42] {
            let map = island_heightmap(seed, 128, &config).expect("valid size");
            let sea_level = config.level_of_height(0.0);
            let levels = map.levels();
            let under = levels.iter().filter(|&&l| l < sea_level).count() as f32 / levels.len() as f32;
            assert!((0.25..0.8).contains(&under), "seed {seed}: {under} of the map under water");
            // The whole border is sea.
            let n = map.columns();
            for i in 0..n {
                for (row, column) in [(0, i), (n - 1, i), (i, 0), (i, n - 1)] {
                    assert!(map.level(row, column) < sea_level, "seed {seed}: border above water");
                }
            }
            // The centre region holds land that rises well above the shore.
            let highest = levels.iter().copied().fold(f32::MIN, f32::max);
            assert!(config.height_of_level(highest) > 1.0, "seed {seed}: flat island");
        }
    }

    #[test]
    fn no_seed_cuts_its_summits_flat() {
        // At most the top 0.05% of the map may reach the flat cut at the top of the height
        // range; seed 3 (the README's example) had 1% of its samples there, 9 and 11 a quarter.
        let config = SceneConfig::default();
        let top = config.level_of_height(MAX_HEIGHT as f32);
        for seed in 1..=12 {
            let map = island_heightmap(seed, 256, &config).expect("valid size");
            let flat = map.levels().iter().filter(|&&l| l >= top - 1e-3).count();
            let fraction = flat as f64 / map.levels().len() as f64;
            assert!(
                fraction <= 1.0 - PEAK_QUANTILE,
                "seed {seed}: {:.3}% of the map is cut flat",
                100.0 * fraction
            );
            let highest = map.levels().iter().copied().fold(f32::MIN, f32::max);
            assert!(
                config.height_of_level(highest) > PEAK_HEIGHT as f32 - 0.05,
                "seed {seed}: no snowy peaks"
            );
        }
    }

    #[test]
    fn rejects_sizes_a_heightmap_cannot_have() {
        let config = SceneConfig::default();
        assert!(matches!(island_heightmap(1, 1, &config), Err(HeightmapError::TooSmall { .. })));
        assert!(matches!(island_heightmap(1, 100_000, &config), Err(HeightmapError::TooLarge { .. })));
    }
}
