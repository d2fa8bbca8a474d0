//! The sky box: a gradient from a pale horizon to a deep zenith, a sun with its glow, and a
//! layer of clouds seen in perspective, painted onto the five faces so that they join without
//! seams (each texel is coloured by the direction it is seen in from the box's centre).

use glam::DVec3;
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

use super::SUN_DIRECTION;
use image::RgbaImage;

use super::field::{grid_from_fn, layer_seed, mix, smoothstep, to_pixel};
use crate::config::SceneConfig;
use crate::world::{SkyBox, SkyFace};

const ZENITH: [f64; 3] = [0.13, 0.32, 0.70];
const HORIZON: [f64; 3] = [0.70, 0.82, 0.94];
const SUN: [f64; 3] = [1.0, 0.96, 0.84];
const CLOUD_LIT: [f64; 3] = [1.0, 0.99, 0.97];
const CLOUD_SHADE: [f64; 3] = [0.62, 0.67, 0.76];

/// Generates the five faces, each `size` x `size`, for `seed`, matching the box of `config`.
/// Bit-identical for the same arguments.
pub fn sky_box(seed: u32, size: u32, config: &SceneConfig) -> SkyBox {
    sky_boxes(seed, size, config).0
}

/// The sky of [`sky_box`] and the same sky without the sun's disc and glow (for a renderer that
/// draws its own sun), in one pass.
pub fn sky_boxes(seed: u32, size: u32, config: &SceneConfig) -> (SkyBox, SkyBox) {
    let sky = Sky::new(seed);
    let box_size = config.sky_box_size.as_dvec3();
    let paint = |face: SkyFace| {
        let texels = grid_from_fn(size, size, |x, y| {
            let u = (x as f64 + 0.5) / size as f64;
            let v = (y as f64 + 0.5) / size as f64;
            let (with_sun, clear) = sky.colours(face.point(u, v, box_size).normalize());
            (to_pixel(with_sun), to_pixel(clear))
        });
        let (with_sun, clear): (Vec<[u8; 4]>, Vec<[u8; 4]>) = texels.into_iter().unzip();
        let image = |texels: Vec<[u8; 4]>| {
            RgbaImage::from_raw(size, size, texels.into_iter().flatten().collect())
                .expect("buffer sized size * size * 4")
        };
        (image(with_sun), image(clear))
    };
    let [front, right, back, left, top] =
        [SkyFace::Front, SkyFace::Right, SkyFace::Back, SkyFace::Left, SkyFace::Top].map(paint);
    (
        SkyBox { sides: [front.0, right.0, back.0, left.0], top: top.0 },
        SkyBox { sides: [front.1, right.1, back.1, left.1], top: top.1 },
    )
}

/// The sky as a function of the viewing direction.
struct Sky {
    clouds: Fbm<Perlin>,
    sun: DVec3,
}

impl Sky {
    fn new(seed: u32) -> Self {
        Self {
            clouds: Fbm::<Perlin>::new(layer_seed(seed, 40)).set_octaves(6).set_persistence(0.55),
            sun: DVec3::from(SUN_DIRECTION).normalize(),
        }
    }

    /// Colour seen in unit direction `d` (d.y >= 0 above the horizon), with the sun and
    /// without it.
    fn colours(&self, d: DVec3) -> ([f64; 3], [f64; 3]) {
        let elevation = d.y.max(0.0);
        let clear = mix(HORIZON, ZENITH, elevation.powf(0.5));
        // Sun: a bright disc inside a wide glow.
        let facing = d.dot(self.sun).max(0.0);
        let glow = 0.35 * facing.powi(8) + 0.6 * facing.powi(64) + smoothstep(0.9993, 0.9997, facing);
        let colour = mix(clear, SUN, glow.min(1.0));
        // Clouds on a flat layer above: density from noise at the point the ray meets the layer,
        // thinning toward the horizon where the layer's far parts would only add noise.
        let reach = 1.0 / (elevation + 0.06);
        let (cx, cz) = (d.x * reach * 1.1, d.z * reach * 1.1);
        let density = self.cloud_density(cx, cz);
        if density <= 0.0 {
            return (colour, clear);
        }
        // Lit from the sun's side: thinner toward the sun means a brighter edge.
        let toward_sun = self.cloud_density(cx + self.sun.x * 0.08, cz + self.sun.z * 0.08);
        let light = (0.65 + 2.5 * (density - toward_sun)).clamp(0.0, 1.0);
        let cloud = mix(CLOUD_SHADE, CLOUD_LIT, light);
        let sunlit_cloud = mix(cloud, SUN, 0.3 * facing.powi(16));
        let cover = density * smoothstep(0.0, 0.25, elevation);
        (mix(colour, sunlit_cloud, cover), mix(clear, cloud, cover))
    }

    /// Cloud density (0..1) at a point of the cloud layer.
    fn cloud_density(&self, x: f64, z: f64) -> f64 {
        let n = self.clouds.get([x * 0.9, z * 0.9]);
        smoothstep(0.02, 0.45, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_sky(seed: u32) -> SkyBox {
        sky_box(seed, 32, &SceneConfig::default())
    }

    fn distance(a: &image::Rgba<u8>, b: &image::Rgba<u8>) -> f64 {
        (0..3).map(|c| (f64::from(a.0[c]) - f64::from(b.0[c])).abs()).sum::<f64>() / 3.0
    }

    /// Mean colour step between neighbouring columns inside a face: what a seam must not exceed.
    fn inner_step(face: &image::RgbaImage) -> f64 {
        let n = face.width();
        let steps: f64 =
            (0..n).map(|y| distance(face.get_pixel(n / 2, y), face.get_pixel(n / 2 - 1, y))).sum();
        steps / f64::from(n)
    }

    #[test]
    fn sides_join_without_seams() {
        let n = 96;
        let sky = sky_box(3, n, &SceneConfig::default());
        for i in 0..4 {
            let (left, right) = (&sky.sides[i], &sky.sides[(i + 1) % 4]);
            let seam: f64 =
                (0..n).map(|y| distance(left.get_pixel(n - 1, y), right.get_pixel(0, y))).sum::<f64>()
                    / f64::from(n);
            let inner = inner_step(left).max(inner_step(right));
            assert!(seam < 2.0 * inner + 1.0, "sides {i}/{}: seam {seam}, inner {inner}", (i + 1) % 4);
        }
    }

    #[test]
    fn top_joins_the_sides() {
        let n = 96;
        let sky = sky_box(3, n, &SceneConfig::default());
        let top = &sky.top;
        let last = n - 1;
        // Which top texel touches texel x of each side's top row (see `SkyBox`).
        let edges: [&dyn Fn(u32) -> (u32, u32); 4] =
            [&|x| (x, last), &|x| (last, last - x), &|x| (last - x, 0), &|x| (0, x)];
        for (i, edge) in edges.iter().enumerate() {
            let seam: f64 = (0..n)
                .map(|x| {
                    let (tx, ty) = edge(x);
                    distance(sky.sides[i].get_pixel(x, 0), top.get_pixel(tx, ty))
                })
                .sum::<f64>()
                / f64::from(n);
            let inner = inner_step(&sky.sides[i]).max(inner_step(top));
            assert!(seam < 2.0 * inner + 1.0, "side {i} / top: seam {seam}, inner {inner}");
        }
    }

    #[test]
    fn blue_above_and_paler_at_the_horizon() {
        let sky = small_sky(1);
        // Averaged over the four sides, the horizon row is paler (higher red) than the top row.
        let mean_row = |y: u32| {
            let mut sum = [0.0; 3];
            for side in &sky.sides {
                for x in 0..32 {
                    for (total, &channel) in sum.iter_mut().zip(&side.get_pixel(x, y).0) {
                        *total += f64::from(channel) / 128.0;
                    }
                }
            }
            sum
        };
        let (high, low) = (mean_row(0), mean_row(31));
        assert!(high[2] > high[0], "sky top should be blue: {high:?}");
        assert!(low[0] > high[0], "horizon {low:?} should be paler than {high:?}");
    }

    #[test]
    fn the_clear_sky_has_no_sun() {
        let (with_sun, clear) = sky_boxes(2, 64, &SceneConfig::default());
        assert_eq!(with_sun, sky_box(2, 64, &SceneConfig::default()));
        // The front wall faces the sun (ahead and to the left at start): brighter with it.
        let total = |image: &image::RgbaImage| image.pixels().map(|p| u64::from(p.0[0])).sum::<u64>();
        assert!(total(&with_sun.sides[0]) > total(&clear.sides[0]) + 64 * 64 * 5);
        // Away from the sun the two hardly differ.
        let behind = total(&with_sun.sides[2]).abs_diff(total(&clear.sides[2]));
        assert!(behind < 64 * 64 * 2, "{behind}");
    }

    #[test]
    fn deterministic_per_seed() {
        assert_eq!(small_sky(8), small_sky(8));
        assert_ne!(small_sky(8).top, small_sky(9).top);
    }
}
