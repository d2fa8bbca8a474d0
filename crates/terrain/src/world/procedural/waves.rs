//! The water's wave maps: tileable noise surfaces stored as their slopes, for the modern look's
//! water to tilt its surface with (two of them, drifting apart, so no pattern repeats visibly).

use image::RgbaImage;
use noise::{Fbm, MultiFractal, Perlin, RidgedMulti};

use super::field::{Tileable, grid_from_fn, layer_seed};

/// Side of each generated wave map, in texels.
pub const WAVE_MAP_SIZE: u32 = 256;

/// A `size` x `size` tileable wave map for `seed`, `cells` noise features across it: red and green
/// hold the surface's slopes along x and z (0.5 is flat; the steepest slope of the map is 0 or
/// 1), blue a foam pattern (0..1, bright in the waves' troughs), alpha 255. Bit-identical for the
/// same arguments.
pub fn wave_map(seed: u32, size: u32, cells: f64) -> RgbaImage {
    let swell = Tileable::new(Fbm::<Perlin>::new(layer_seed(seed, 60)).set_octaves(4), cells);
    let chop = Tileable::new(RidgedMulti::<Perlin>::new(layer_seed(seed, 61)).set_octaves(3), cells * 2.0);
    let heights = grid_from_fn(size, size, |x, y| {
        let (u, v) = (x as f64 / size as f64, y as f64 / size as f64);
        swell.get(u, v) + 0.35 * chop.get(u, v)
    });
    let n = size as usize;
    let at = |x: usize, y: usize| heights[(y % n) * n + (x % n)];
    let slopes: Vec<(f64, f64)> = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            ((at(x + 1, y) - at(x + n - 1, y)) * 0.5, (at(x, y + 1) - at(x, y + n - 1)) * 0.5)
        })
        .collect();
    let steepest = slopes.iter().map(|(sx, sz)| sx.abs().max(sz.abs())).fold(1e-9, f64::max);
    let (low, high) = heights.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    let byte = |value: f64| (value.clamp(0.0, 1.0) * 255.0).round() as u8;
    let mut image = RgbaImage::new(size, size);
    for (i, pixel) in image.pixels_mut().enumerate() {
        let (sx, sz) = slopes[i];
        let trough = 1.0 - (heights[i] - low) / (high - low).max(1e-9);
        pixel.0 =
            [byte(0.5 + 0.5 * sx / steepest), byte(0.5 + 0.5 * sz / steepest), byte(trough * trough), 255];
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slopes_centre_on_flat_and_tile() {
        let map = wave_map(3, 64, 4.0);
        let mean = |c: usize| map.pixels().map(|p| f64::from(p.0[c])).sum::<f64>() / (64.0 * 64.0);
        // Slopes average out over a tileable surface: the mean is flat (128).
        assert!((mean(0) - 127.5).abs() < 4.0 && (mean(1) - 127.5).abs() < 4.0, "{} {}", mean(0), mean(1));
        // The steepest slope uses the whole range.
        assert!(map.pixels().any(|p| p.0[0] == 0 || p.0[0] == 255));
        // Across the wrap-around edge the slope changes no more than inside.
        let red = |x: u32, y: u32| f64::from(map.get_pixel(x % 64, y % 64).0[0]);
        let inner: f64 = (0..64).map(|y| (red(32, y) - red(31, y)).abs()).sum();
        let wrap: f64 = (0..64).map(|y| (red(0, y) - red(63, y)).abs()).sum();
        assert!(wrap < inner * 2.0 + 64.0, "wrap {wrap} inner {inner}");
    }

    #[test]
    fn deterministic_per_seed() {
        assert_eq!(wave_map(4, 32, 3.0), wave_map(4, 32, 3.0));
        assert_ne!(wave_map(4, 32, 3.0), wave_map(5, 32, 3.0));
    }
}
