//! The detail map: tileable grey noise with mean 128, added signed to the terrain's colour.

use image::RgbaImage;
use noise::{Billow, Fbm, MultiFractal, Perlin};

use super::field::{Tileable, grid_from_fn, layer_seed};

/// Standard deviation of the detail map's grey levels (the course's detail map has about 16).
const DETAIL_SPREAD: f64 = 16.0;

/// Generates a `size` x `size` tileable detail map for `seed`: fine fractal grain over a pebbly
/// billowy pattern, normalised to mean 128 and a spread of 16 grey levels, so ADD_SIGNED leaves
/// the terrain's mean colour unchanged. Bit-identical for the same arguments.
pub fn detail_map(seed: u32, size: u32) -> RgbaImage {
    let grain = Tileable::new(Fbm::<Perlin>::new(layer_seed(seed, 30)).set_octaves(5), 16.0);
    let pebbles = Tileable::new(Billow::<Perlin>::new(layer_seed(seed, 31)).set_octaves(3), 24.0);
    let values = grid_from_fn(size, size, |x, y| {
        let (u, v) = ((x as f64 + 0.5) / size as f64, (y as f64 + 0.5) / size as f64);
        grain.get(u, v) + 0.35 * pebbles.get(u, v)
    });
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt().max(1e-9);
    let mut image = RgbaImage::new(size, size);
    for (pixel, value) in image.pixels_mut().zip(&values) {
        let grey = (128.0 + (value - mean) / spread * DETAIL_SPREAD).round().clamp(0.0, 255.0) as u8;
        pixel.0 = [grey, grey, grey, 255];
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_with_mean_128_and_course_like_spread() {
        let map = detail_map(5, 64);
        let greys: Vec<f64> = map.pixels().map(|p| f64::from(p.0[0])).collect();
        assert!(map.pixels().all(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2] && p.0[3] == 255));
        let mean = greys.iter().sum::<f64>() / greys.len() as f64;
        let spread = (greys.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / greys.len() as f64).sqrt();
        assert!((mean - 128.0).abs() < 0.6, "mean {mean}");
        assert!((spread - 16.0).abs() < 1.0, "spread {spread}");
    }

    #[test]
    fn tiles_seamlessly() {
        // The step across the wrap-around edge is no larger than typical steps inside.
        let map = detail_map(5, 128);
        let grey = |x: u32, y: u32| f64::from(map.get_pixel(x % 128, y % 128).0[0]);
        let inner: f64 = (0..128).map(|y| (grey(64, y) - grey(63, y)).abs()).sum();
        let wrap: f64 = (0..128).map(|y| (grey(0, y) - grey(127, y)).abs()).sum();
        assert!(wrap < inner * 2.0, "wrap {wrap} inner {inner}");
        let wrap_rows: f64 = (0..128).map(|x| (grey(x, 0) - grey(x, 127)).abs()).sum();
        assert!(wrap_rows < inner * 2.0, "wrap {wrap_rows} inner {inner}");
    }

    #[test]
    fn deterministic_per_seed() {
        assert_eq!(detail_map(1, 32), detail_map(1, 32));
        assert_ne!(detail_map(1, 32), detail_map(2, 32));
    }
}
