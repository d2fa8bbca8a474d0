//! Helpers shared by the generators: seeds, tileable noise, smooth steps and parallel pixel loops.

use std::f64::consts::TAU;

use image::RgbaImage;
use noise::NoiseFn;
use rayon::prelude::*;

/// A seed for one noise layer, derived from the world's seed and the layer's number, so that the
/// layers of one world are unrelated and every layer changes with the world's seed (splitmix64).
pub fn layer_seed(seed: u32, layer: u32) -> u32 {
    let mut z = (u64::from(seed) << 32 | u64::from(layer)).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) as u32
}

/// A 4-D noise wrapped around a torus: a function of (u, v) with period 1 in both, so an image
/// made of it tiles seamlessly. `cells` is about how many noise features span one period.
pub struct Tileable<N> {
    noise: N,
    radius: f64,
}

impl<N: NoiseFn<f64, 4>> Tileable<N> {
    /// Wraps `noise` so that about `cells` of its features fit in one period.
    pub fn new(noise: N, cells: f64) -> Self {
        Self { noise, radius: cells / TAU }
    }

    /// The noise at (u, v); `get(u + 1, v) == get(u, v + 1) == get(u, v)` up to rounding.
    pub fn get(&self, u: f64, v: f64) -> f64 {
        let (a, b) = (u * TAU, v * TAU);
        let r = self.radius;
        self.noise.get([r * a.cos(), r * a.sin(), r * b.cos(), r * b.sin()])
    }
}

/// Hermite smooth step from 0 at `edge0` to 1 at `edge1`.
pub fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// [`smoothstep`] in single precision, as WGSL's `smoothstep` computes it (edges in either order):
/// for the CPU copies of the shaders' arithmetic (the sky's tables, the ground's splat weights).
pub fn smoothstep_f32(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Linear blend of colours: `a` at t = 0, `b` at t = 1.
pub fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// An opaque 8-bit pixel from a colour with channels in 0..=1 (clamped).
pub fn to_pixel(colour: [f64; 3]) -> [u8; 4] {
    let byte = |c: f64| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    [byte(colour[0]), byte(colour[1]), byte(colour[2]), 255]
}

/// Rows computed between two progress reports by [`grid_from_fn_with_progress`].
const ROWS_PER_BAND: usize = 64;

/// An image whose pixel (x, y) is `pixel(x, y)`, computed row by row in parallel. The result
/// does not depend on the number of threads.
pub fn image_from_fn(width: u32, height: u32, pixel: impl Fn(u32, u32) -> [u8; 4] + Sync) -> RgbaImage {
    image_from_fn_with_progress(width, height, pixel, &mut |_| {})
}

/// [`image_from_fn`], calling `progress` with the fraction of rows done (0 to 1) as it goes.
pub fn image_from_fn_with_progress(
    width: u32,
    height: u32,
    pixel: impl Fn(u32, u32) -> [u8; 4] + Sync,
    progress: &mut dyn FnMut(f32),
) -> RgbaImage {
    let texels = grid_from_fn_with_progress(width, height, pixel, progress);
    let data = texels.into_iter().flatten().collect();
    RgbaImage::from_raw(width, height, data).expect("buffer sized width * height * 4")
}

/// A `width` x `height` grid of values, row by row, computed in parallel.
pub fn grid_from_fn<T: Copy + Default + Send>(
    width: u32,
    height: u32,
    value: impl Fn(u32, u32) -> T + Sync,
) -> Vec<T> {
    grid_from_fn_with_progress(width, height, value, &mut |_| {})
}

/// [`grid_from_fn`], calling `progress` with the fraction of rows done (0 to 1) after each band
/// of rows. Bands are computed one after the other, the rows of a band in parallel (the only
/// place the generators use threads: a single-threaded build would loop here instead).
pub fn grid_from_fn_with_progress<T: Copy + Default + Send>(
    width: u32,
    height: u32,
    value: impl Fn(u32, u32) -> T + Sync,
    progress: &mut dyn FnMut(f32),
) -> Vec<T> {
    let row_length = width as usize;
    let mut data = vec![T::default(); row_length * height as usize];
    let band_length = row_length * ROWS_PER_BAND;
    let bands = data.len().div_ceil(band_length.max(1));
    for (band, rows) in data.chunks_mut(band_length.max(1)).enumerate() {
        let first_row = band * ROWS_PER_BAND;
        rows.par_chunks_mut(row_length).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                *out = value(x as u32, (first_row + y) as u32);
            }
        });
        progress((band + 1) as f32 / bands as f32);
    }
    data
}

#[cfg(test)]
mod tests {
    use noise::Perlin;

    use super::*;

    #[test]
    fn tileable_noise_has_period_one() {
        let noise = Tileable::new(Perlin::new(7), 6.0);
        for (u, v) in [(0.1, 0.2), (0.73, 0.05), (0.5, 0.999)] {
            let here = noise.get(u, v);
            assert!((here - noise.get(u + 1.0, v)).abs() < 1e-9);
            assert!((here - noise.get(u, v - 1.0)).abs() < 1e-9);
        }
        // And it varies.
        assert!((noise.get(0.1, 0.2) - noise.get(0.3, 0.6)).abs() > 1e-3);
    }

    #[test]
    fn grids_are_filled_row_by_row_with_progress() {
        let mut reports = Vec::new();
        let grid = grid_from_fn_with_progress(3, 130, |x, y| x + 10 * y, &mut |done| reports.push(done));
        assert_eq!(grid.len(), 390);
        assert_eq!(grid[3 * 129 + 2], 1292);
        // 130 rows in bands of 64: three reports, the last one complete.
        assert_eq!(reports.len(), 3);
        assert!(reports.windows(2).all(|w| w[0] < w[1]) && reports[2] == 1.0);
        let image = image_from_fn(2, 1, |x, _| [x as u8, 1, 2, 3]);
        assert_eq!(image.as_raw(), &[0, 1, 2, 3, 1, 1, 2, 3]);
    }

    #[test]
    fn layer_seeds_differ() {
        let seeds: Vec<u32> = (0..8).map(|layer| layer_seed(1, layer)).collect();
        for (i, a) in seeds.iter().enumerate() {
            assert!(seeds[i + 1..].iter().all(|b| a != b));
        }
        assert_ne!(layer_seed(1, 0), layer_seed(2, 0));
        assert_eq!(layer_seed(5, 3), layer_seed(5, 3));
    }
}
