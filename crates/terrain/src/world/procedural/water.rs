//! The water texture: a tileable teal sea with the bright, thin lines of caustics.

use image::RgbaImage;
use noise::{Fbm, MultiFractal, Perlin};

use super::field::{Tileable, image_from_fn, layer_seed, mix, smoothstep, to_pixel};

const DEEP: [f64; 3] = [0.16, 0.36, 0.48];
const SHALLOW: [f64; 3] = [0.26, 0.50, 0.58];
const CAUSTIC: [f64; 3] = [0.78, 0.92, 0.93];

/// Generates a `size` x `size` tileable water texture for `seed`. Bit-identical for the same
/// arguments.
pub fn water_texture(seed: u32, size: u32) -> RgbaImage {
    let tint = Tileable::new(Fbm::<Perlin>::new(layer_seed(seed, 50)).set_octaves(3), 3.0);
    let ripples_a = Tileable::new(Fbm::<Perlin>::new(layer_seed(seed, 51)).set_octaves(3), 5.0);
    let ripples_b = Tileable::new(Fbm::<Perlin>::new(layer_seed(seed, 52)).set_octaves(3), 7.0);
    image_from_fn(size, size, |x, y| {
        let (u, v) = ((x as f64 + 0.5) / size as f64, (y as f64 + 0.5) / size as f64);
        // Caustics: where the noise crosses zero, a thin bright line; two layers interleave.
        let line = |n: f64| (1.0 - (n.abs() * 9.0).min(1.0)).powi(3);
        let caustic = (line(ripples_a.get(u, v)) + 0.7 * line(ripples_b.get(u, v))).min(1.0);
        let base = mix(DEEP, SHALLOW, smoothstep(-0.4, 0.4, tint.get(u, v)));
        to_pixel(mix(base, CAUSTIC, 0.75 * caustic))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sea_coloured_and_tileable() {
        let water = water_texture(2, 64);
        let n = 64.0 * 64.0;
        let mean: Vec<f64> =
            (0..3).map(|c| water.pixels().map(|p| f64::from(p.0[c])).sum::<f64>() / n).collect();
        // Blue-green: blue and green above red, like the course's SkyBox5.
        assert!(mean[2] > mean[0] + 30.0 && mean[1] > mean[0] + 30.0, "{mean:?}");
        let grey = |x: u32, y: u32| f64::from(water.get_pixel(x % 64, y % 64).0[1]);
        let inner: f64 = (0..64).map(|y| (grey(32, y) - grey(31, y)).abs()).sum();
        let wrap: f64 = (0..64).map(|y| (grey(0, y) - grey(63, y)).abs()).sum();
        assert!(wrap < inner * 2.0 + 64.0, "wrap {wrap} inner {inner}");
    }

    #[test]
    fn deterministic_per_seed() {
        assert_eq!(water_texture(4, 32), water_texture(4, 32));
        assert_ne!(water_texture(4, 32), water_texture(5, 32));
    }
}
