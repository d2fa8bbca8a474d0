//! What the ground's materials are chosen from (modern look), as images for the GPU: the land's
//! shape at (up to) the heightmap's resolution, and a small tileable texture of procedural noise
//! that gives each material its grain and its height for blending.
//!
//! The shape map ([`ground_map`]) holds per sample, as RGBA bytes: the surface normal's x and z
//! (y-up, `n * 0.5 + 0.5`), the curvature (128 level; above, a hollow or valley; below, a ridge)
//! and the erosion's flow (0 without erosion; 255 where 4 x 2^10 or more samples drain through).
//! The noise ([`material_noise`]) holds fine grain (red), patches (green), strata banded along its
//! second axis (blue) and pebbles (alpha), each tileable. Everything is the project's own, made
//! here; nothing is read from files.

use image::{Rgba, RgbaImage};
use rayon::prelude::*;

use super::Heightmap;
use super::erosion::ErosionMaps;
use super::heightfield::Heightfield;
use crate::config::SceneConfig;

/// The shape map's largest side: larger heightmaps are sampled every few samples.
pub const GROUND_MAP_MAX_SIDE: u32 = 2048;

/// Side of the material noise texture, in texels.
pub const NOISE_SIDE: u32 = 256;

/// The curvature (change of slope across the span it is measured over, a 128th of the map's
/// side) that reaches the shape map's extremes.
const CURVATURE_RANGE: f32 = 0.25;

/// The land's shape for its materials: normals, curvature and the erosion's flow (see the
/// module's documentation), one texel every `stride` samples where the heightmap is larger than
/// [`GROUND_MAP_MAX_SIDE`].
pub fn ground_map(heightmap: &Heightmap, config: &SceneConfig, erosion: Option<&ErosionMaps>) -> RgbaImage {
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    let stride = columns.max(rows).div_ceil(GROUND_MAP_MAX_SIDE).max(1);
    let (width, height) = (columns.div_ceil(stride), rows.div_ceil(stride));
    let sample_cell = Heightfield::cell_size_of(heightmap, config);
    let cell = sample_cell * stride as f32;
    // Curvature over a span of about a 128th of the map, whatever its resolution.
    let reach = (columns.max(rows) / 128).max(stride).max(1);
    let span = sample_cell * reach as f32;
    let at = |column: i64, row: i64| {
        let c = column.clamp(0, i64::from(columns) - 1) as u32;
        let r = row.clamp(0, i64::from(rows) - 1) as u32;
        config.height_of_level(heightmap.level(r, c))
    };
    let flow = erosion.filter(|maps| maps.columns == columns && maps.rows == rows);
    let mut bytes = vec![0u8; width as usize * height as usize * 4];
    bytes.par_chunks_mut(width as usize * 4).enumerate().for_each(|(y, row_bytes)| {
        let row = i64::from(y as u32 * stride);
        let s = i64::from(stride);
        for (x, texel) in row_bytes.chunks_exact_mut(4).enumerate() {
            let column = i64::from(x as u32 * stride);
            let centre = at(column, row);
            let (left, right) = (at(column - s, row), at(column + s, row));
            let (up, down) = (at(column, row - s), at(column, row + s));
            let normal =
                glam::Vec3::new(-(right - left) / (2.0 * cell), 1.0, -(down - up) / (2.0 * cell)).normalize();
            let r = i64::from(reach);
            let around =
                at(column - r, row) + at(column + r, row) + at(column, row - r) + at(column, row + r);
            let curvature = (around - 4.0 * centre) / span;
            let accumulated = flow.map_or(0.0, |maps| {
                // The largest flow in the block the texel stands for (channels are thin).
                let mut most = 0.0f32;
                for r in row..(row + s).min(i64::from(rows)) {
                    for c in column..(column + s).min(i64::from(columns)) {
                        most = most.max(maps.flow[(r as usize) * columns as usize + c as usize]);
                    }
                }
                most
            });
            let flow_byte = ((accumulated / 4.0).max(1.0).log2() / 10.0).clamp(0.0, 1.0);
            texel.copy_from_slice(&[
                unit_byte(normal.x * 0.5 + 0.5),
                unit_byte(normal.z * 0.5 + 0.5),
                unit_byte(0.5 + 0.5 * (curvature / CURVATURE_RANGE).clamp(-1.0, 1.0)),
                unit_byte(flow_byte),
            ]);
        }
    });
    // The sizes came from the heightmap's, which are within the engine's limits.
    RgbaImage::from_raw(width, height, bytes).unwrap_or_else(|| RgbaImage::new(1, 1))
}

fn unit_byte(value: f32) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// A hash of a lattice point to 0..1 (deterministic, platform independent).
fn hash(x: u32, y: u32, seed: u32) -> f32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_215.0
}

/// Value noise with `period` lattice cells across the tile, wrapping at the tile's edges, at
/// (u, v) in 0..1.
fn value_noise(u: f32, v: f32, period: u32, seed: u32) -> f32 {
    let (x, y) = (u * period as f32, v * period as f32);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    let wrap = |i: f32| (i as i64).rem_euclid(i64::from(period)) as u32;
    let (ix0, iy0, ix1, iy1) = (wrap(x0), wrap(y0), wrap(x0 + 1.0), wrap(y0 + 1.0));
    let top = hash(ix0, iy0, seed) * (1.0 - sx) + hash(ix1, iy0, seed) * sx;
    let bottom = hash(ix0, iy1, seed) * (1.0 - sx) + hash(ix1, iy1, seed) * sx;
    top * (1.0 - sy) + bottom * sy
}

/// Fractal value noise: `octaves` octaves from `period` cells across, halving in strength.
fn fractal(u: f32, v: f32, period: u32, octaves: u32, seed: u32) -> f32 {
    let (mut sum, mut weight, mut amplitude) = (0.0, 0.0, 1.0);
    for octave in 0..octaves {
        sum += amplitude * value_noise(u, v, period << octave, seed + octave);
        weight += amplitude;
        amplitude *= 0.5;
    }
    sum / weight
}

/// Pebbles: 1 at the centre of a cell's pebble, falling to 0 at its rim (cellular noise with
/// `cells` cells across the tile, wrapping).
fn pebbles(u: f32, v: f32, cells: u32, seed: u32) -> f32 {
    let (x, y) = (u * cells as f32, v * cells as f32);
    let (cx, cy) = (x.floor() as i64, y.floor() as i64);
    let mut nearest = f32::MAX;
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (gx, gy) = (cx + dx, cy + dy);
            let (wx, wy) = (gx.rem_euclid(i64::from(cells)) as u32, gy.rem_euclid(i64::from(cells)) as u32);
            let px = gx as f32 + 0.15 + 0.7 * hash(wx, wy, seed);
            let py = gy as f32 + 0.15 + 0.7 * hash(wx, wy, seed + 1);
            nearest = nearest.min((px - x).hypot(py - y));
        }
    }
    (1.0 - nearest * 1.6).clamp(0.0, 1.0).sqrt()
}

/// The material noise texture (see the module's documentation): [`NOISE_SIDE`] texels a side,
/// tileable in both directions.
pub fn material_noise() -> RgbaImage {
    let side = NOISE_SIDE;
    RgbaImage::from_fn(side, side, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / side as f32, (y as f32 + 0.5) / side as f32);
        let grain = fractal(u, v, 32, 3, 1);
        let patches = fractal(u, v, 4, 4, 11);
        // Strata: bands along v, their thickness and their course wobbling.
        let course = v + 0.06 * (fractal(u, v, 4, 2, 21) - 0.5);
        let bands = fractal(0.0, course, 24, 3, 31);
        let strata = (0.65 * bands + 0.35 * fractal(u, v, 16, 2, 41)).clamp(0.0, 1.0);
        let stones = pebbles(u, v, 24, 51);
        Rgba([unit_byte(grain), unit_byte(patches), unit_byte(strata), unit_byte(stones)])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heightmap(side: u32, level: impl Fn(u32, u32) -> f32) -> Heightmap {
        let levels = (0..side * side).map(|i| level(i / side, i % side)).collect();
        Heightmap::new(side, side, levels).expect("valid")
    }

    #[test]
    fn normals_and_curvature_follow_the_land() {
        let config = SceneConfig::default();
        // A slope rising toward +x (east): normals lean toward -x, none in z; no curvature.
        let ramp = ground_map(&heightmap(33, |_, c| 10.0 + c as f32 * 7.0), &config, None);
        let texel = ramp.get_pixel(16, 16).0;
        assert!(texel[0] < 120 && (i32::from(texel[1]) - 128).abs() <= 1, "{texel:?}");
        assert!((i32::from(texel[2]) - 128).abs() <= 1 && texel[3] == 0, "{texel:?}");
        // A valley along z (lowest in the middle column): concave there, convex nowhere.
        let valley =
            ground_map(&heightmap(33, |_, c| 100.0 + (c as f32 - 16.0).powi(2) * 0.9), &config, None);
        assert!(valley.get_pixel(16, 16).0[2] > 140, "{:?}", valley.get_pixel(16, 16));
        // A ridge: convex.
        let ridge = ground_map(&heightmap(33, |_, c| 240.0 - (c as f32 - 16.0).powi(2) * 0.9), &config, None);
        assert!(ridge.get_pixel(16, 16).0[2] < 116, "{:?}", ridge.get_pixel(16, 16));
    }

    #[test]
    fn large_maps_are_sampled_and_flow_is_read() {
        let config = SceneConfig::default();
        let side = GROUND_MAP_MAX_SIDE + 1;
        let flat = Heightmap::new(side, 3, vec![120.0; side as usize * 3]).expect("valid");
        let map = ground_map(&flat, &config, None);
        assert_eq!(map.dimensions(), (side.div_ceil(2), 2));
        let mut flow = vec![1.0f32; 33 * 33];
        flow[16 * 33 + 16] = 4096.0;
        let maps = ErosionMaps { columns: 33, rows: 33, flow, deposition: vec![0.0; 33 * 33] };
        let map = ground_map(&heightmap(33, |_, _| 120.0), &config, Some(&maps));
        assert_eq!(map.get_pixel(16, 16).0[3], 255);
        assert_eq!(map.get_pixel(3, 3).0[3], 0);
    }

    #[test]
    fn the_noise_tiles_and_fills_its_range() {
        let noise = material_noise();
        assert_eq!(noise.dimensions(), (NOISE_SIDE, NOISE_SIDE));
        assert_eq!(noise, material_noise(), "deterministic");
        for channel in 0..4 {
            let values: Vec<u8> = noise.pixels().map(|p| p.0[channel]).collect();
            let (low, high) = (values.iter().min().copied(), values.iter().max().copied());
            assert!(high.unwrap_or(0) - low.unwrap_or(0) > 100, "channel {channel}: {low:?}..{high:?}");
            // Across the tile's seams neighbours differ no more than inside it.
            let jump = |a: (u32, u32), b: (u32, u32)| {
                (i32::from(noise.get_pixel(a.0, a.1).0[channel])
                    - i32::from(noise.get_pixel(b.0, b.1).0[channel]))
                .abs()
            };
            let inside = (0..NOISE_SIDE).map(|y| jump((NOISE_SIDE / 2 - 1, y), (NOISE_SIDE / 2, y))).max();
            let seam = (0..NOISE_SIDE).map(|y| jump((NOISE_SIDE - 1, y), (0, y))).max();
            assert!(seam <= inside.map(|m| m + 24), "channel {channel}: seam {seam:?} inside {inside:?}");
        }
    }
}
