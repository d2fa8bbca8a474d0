//! The terrain's colour map, derived from a heightmap: sand on the shore, grass on the lowlands,
//! rock on steep slopes and high up, snow on the peaks, with hill shading from the sun baked in.

use glam::DVec3;
use image::RgbaImage;
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

use super::SUN_DIRECTION;
use super::field::{grid_from_fn_with_progress, layer_seed, mix, smoothstep, to_pixel};
use crate::config::SceneConfig;
use crate::world::{Heightfield, Heightmap};

const SEABED: [f64; 3] = [0.50, 0.46, 0.34];
const WET_SAND: [f64; 3] = [0.62, 0.55, 0.38];
const SAND: [f64; 3] = [0.84, 0.77, 0.56];
const GRASS_LIGHT: [f64; 3] = [0.45, 0.58, 0.20];
const GRASS_DARK: [f64; 3] = [0.17, 0.34, 0.10];
const FOREST: [f64; 3] = [0.10, 0.24, 0.08];
const ROCK_LIGHT: [f64; 3] = [0.56, 0.52, 0.46];
const ROCK_DARK: [f64; 3] = [0.34, 0.31, 0.28];
const SNOW: [f64; 3] = [0.95, 0.96, 0.99];

/// Colour-map texels per heightmap sample along each side (the course has 512 texels over 256
/// samples), up to [`MAX_COLOUR_MAP_SIDE`].
const TEXELS_PER_SAMPLE: u32 = 2;

/// Longest side of a generated colour map, in texels.
pub const MAX_COLOUR_MAP_SIDE: u32 = 2048;

/// Size of the colour map generated for a heightmap of `columns` x `rows` samples: twice the
/// samples, scaled down to at most [`MAX_COLOUR_MAP_SIDE`] on the longer side (at least 1 texel).
pub fn colour_map_size(columns: u32, rows: u32) -> (u32, u32) {
    let longest = columns.max(rows) * TEXELS_PER_SAMPLE;
    let scale = (MAX_COLOUR_MAP_SIDE as f64 / longest as f64).min(1.0);
    let side = |samples: u32| ((samples * TEXELS_PER_SAMPLE) as f64 * scale).round().max(1.0) as u32;
    (side(columns), side(rows))
}

/// Paints the colour map of `heightmap` (placed with `config`) for `seed`. Bit-identical for the
/// same arguments.
pub fn colour_map(heightmap: &Heightmap, config: &SceneConfig, seed: u32) -> RgbaImage {
    colour_maps(heightmap, config, seed, &mut |_| {}).0
}

/// The colour map of [`colour_map`] and its albedo (the same colours before the hill shading), in
/// one pass, calling `progress` with the fraction done (0 to 1) as it goes.
pub fn colour_maps(
    heightmap: &Heightmap,
    config: &SceneConfig,
    seed: u32,
    progress: &mut dyn FnMut(f32),
) -> (RgbaImage, RgbaImage) {
    let field = Heights { map: heightmap, config };
    let (width, height) = colour_map_size(heightmap.columns(), heightmap.rows());
    let patches = Fbm::<Perlin>::new(layer_seed(seed, 20)).set_octaves(5);
    let grain = Fbm::<Perlin>::new(layer_seed(seed, 21)).set_octaves(4);
    let bands = Perlin::new(layer_seed(seed, 22));
    let sun = DVec3::from(SUN_DIRECTION).normalize();
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    let cell = f64::from(Heightfield::cell_size_of(heightmap, config));
    let texels = grid_from_fn_with_progress(
        width,
        height,
        |x, y| {
            // This texel's centre in sample coordinates (sample centres at whole numbers).
            let column = (x as f64 + 0.5) / width as f64 * columns as f64 - 0.5;
            let row = (y as f64 + 0.5) / height as f64 * rows as f64 - 0.5;
            let h = sample(&field, column, row);
            let slope_x =
                (sample(&field, column + 1.0, row) - sample(&field, column - 1.0, row)) / (2.0 * cell);
            let slope_z =
                (sample(&field, column, row + 1.0) - sample(&field, column, row - 1.0)) / (2.0 * cell);
            let normal = DVec3::new(-slope_x, 1.0, -slope_z).normalize();
            let steepness = 1.0 - normal.y; // 0 flat, ~0.3 at 45 degrees
            // Noise in map coordinates (u, v in 0..1), independent of the map's resolution.
            let (u, v) = (x as f64 / width as f64, y as f64 / height as f64);
            let patch = patches.get([u * 9.0, v * 9.0]);
            let fine = grain.get([u * 60.0, v * 60.0]);
            let band = bands.get([h * 2.5, u * 4.0, v * 4.0]);

            // Lowland: grass of varying shade, with darker woods in patches.
            let grass = mix(GRASS_LIGHT, GRASS_DARK, smoothstep(-0.5, 0.6, patch + 0.3 * fine));
            let mut colour =
                mix(grass, FOREST, smoothstep(0.15, 0.45, patch) * (1.0 - smoothstep(1.0, 1.5, h)));
            // Rock on steep ground and above the tree line, banded like strata.
            let rock = mix(ROCK_LIGHT, ROCK_DARK, smoothstep(-0.6, 0.6, band + 0.5 * fine));
            let rockiness =
                smoothstep(0.06, 0.16, steepness + 0.03 * fine).max(smoothstep(1.25, 1.6, h + 0.15 * patch));
            colour = mix(colour, rock, rockiness);
            // Snow on the peaks, sliding off the steepest faces.
            let snow = smoothstep(1.75, 1.95, h + 0.12 * patch + 0.05 * fine)
                * (1.0 - smoothstep(0.20, 0.35, steepness));
            colour = mix(colour, SNOW, snow);
            // Beach: sand just above the water, wet sand at the waterline, seabed below.
            let shore = 0.10 + 0.06 * patch;
            let sand = mix(WET_SAND, SAND, smoothstep(0.0, 0.05, h));
            colour = mix(sand, colour, smoothstep(shore, shore + 0.08, h));
            colour = mix(SEABED, colour, smoothstep(-0.15, 0.0, h));

            // Hill shading from the sun, plus a little grain so flat areas are not uniform.
            let light = 0.58 + 0.62 * normal.dot(sun).max(0.0) + 0.04 * fine;
            (to_pixel(colour.map(|c| c * light)), to_pixel(colour.map(|c| c * (0.96 + 0.04 * fine))))
        },
        progress,
    );
    let (shaded, albedo): (Vec<[u8; 4]>, Vec<[u8; 4]>) = texels.into_iter().unzip();
    let image = |texels: Vec<[u8; 4]>| {
        RgbaImage::from_raw(width, height, texels.into_iter().flatten().collect())
            .expect("buffer sized width * height * 4")
    };
    (image(shaded), image(albedo))
}

/// World heights read straight from a heightmap (no copy of a large map).
struct Heights<'a> {
    map: &'a Heightmap,
    config: &'a SceneConfig,
}

impl Heights<'_> {
    fn columns(&self) -> u32 {
        self.map.columns()
    }

    fn rows(&self) -> u32 {
        self.map.rows()
    }

    /// World height of a sample, computed as [`Heightfield`] stores it.
    fn height(&self, row: u32, column: u32) -> f32 {
        self.config.height_of_level(self.map.level(row, column))
    }
}

/// World height at fractional sample coordinates, clamped to the grid, interpolated bilinearly.
fn sample(field: &Heights<'_>, column: f64, row: f64) -> f64 {
    let column = column.clamp(0.0, f64::from(field.columns() - 1));
    let row = row.clamp(0.0, f64::from(field.rows() - 1));
    let (c0, r0) =
        ((column.floor() as u32).min(field.columns() - 2), (row.floor() as u32).min(field.rows() - 2));
    let (fx, fz) = (column - f64::from(c0), row - f64::from(r0));
    let at = |r: u32, c: u32| f64::from(field.height(r, c));
    let top = at(r0, c0) + (at(r0, c0 + 1) - at(r0, c0)) * fx;
    let bottom = at(r0 + 1, c0) + (at(r0 + 1, c0 + 1) - at(r0 + 1, c0)) * fx;
    top + (bottom - top) * fz
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(level: f32) -> Heightmap {
        Heightmap::new(8, 8, vec![level; 64]).expect("valid")
    }

    fn mean(image: &RgbaImage) -> [f64; 3] {
        let n = (image.width() * image.height()) as f64;
        let mut sum = [0.0; 3];
        for p in image.pixels() {
            for (total, &channel) in sum.iter_mut().zip(&p.0) {
                *total += f64::from(channel) / 255.0 / n;
            }
        }
        sum
    }

    #[test]
    fn sizes_follow_the_heightmap() {
        assert_eq!(colour_map_size(256, 256), (512, 512));
        assert_eq!(colour_map_size(300, 7), (600, 14));
        assert_eq!(colour_map_size(2049, 2049), (2048, 2048));
        assert_eq!(colour_map_size(4000, 2), (2048, 1));
    }

    #[test]
    fn colours_follow_height() {
        let config = SceneConfig::default();
        let at = |height: f32| mean(&colour_map(&flat(config.level_of_height(height)), &config, 1));
        let beach = at(0.04);
        let lowland = at(0.6);
        let peak = at(2.2);
        // Sand is yellowish (red above blue), grass is green, snow is bright and neutral.
        assert!(beach[0] > beach[2] + 0.15, "beach {beach:?}");
        assert!(lowland[1] > lowland[0] && lowland[1] > lowland[2], "lowland {lowland:?}");
        assert!(peak.iter().all(|&c| c > 0.6), "peak {peak:?}");
    }

    #[test]
    fn steep_ground_is_rock() {
        let config = SceneConfig::default();
        // 8 x 64 samples span 20 units along z: cells of 0.3125 units. A ramp along x rising 20
        // levels (0.3 units) per sample is about 44 degrees steep.
        let levels = (0..8 * 64).map(|i| 110.0 + 20.0 * (i % 8) as f32).collect();
        let ramp = Heightmap::new(8, 64, levels).expect("valid");
        let rock = mean(&colour_map(&ramp, &config, 1));
        let spread =
            rock.iter().copied().fold(f64::MIN, f64::max) - rock.iter().copied().fold(f64::MAX, f64::min);
        assert!(spread < 0.12, "rock should be greyish: {rock:?}");
    }

    #[test]
    fn the_albedo_is_the_colour_without_hill_shading() {
        let config = SceneConfig::default();
        // A ridge: one slope faces the sun, the other faces away.
        let levels = (0..32 * 32).map(|i| 200.0 - 6.0 * ((i % 32) as f32 - 16.0).abs()).collect();
        let ridge = Heightmap::new(32, 32, levels).expect("valid");
        let (shaded, albedo) = colour_maps(&ridge, &config, 1, &mut |_| {});
        assert_eq!(shaded, colour_map(&ridge, &config, 1));
        let brightness = |image: &RgbaImage, x: u32| -> f64 {
            (8..56).map(|y| image.get_pixel(x, y).0[..3].iter().map(|&c| f64::from(c)).sum::<f64>()).sum()
        };
        // The shaded map tells the slopes apart much more than the albedo.
        let shaded_contrast = (brightness(&shaded, 12) / brightness(&shaded, 52)).ln().abs();
        let albedo_contrast = (brightness(&albedo, 12) / brightness(&albedo, 52)).ln().abs();
        assert!(shaded_contrast > 3.0 * albedo_contrast, "{shaded_contrast} vs {albedo_contrast}");
    }

    #[test]
    fn deterministic_per_seed() {
        let config = SceneConfig::default();
        let levels = (0..256).map(|i| (i % 200) as f32).collect();
        let map = Heightmap::new(16, 16, levels).expect("valid");
        assert_eq!(colour_map(&map, &config, 9), colour_map(&map, &config, 9));
        assert_ne!(colour_map(&map, &config, 9), colour_map(&map, &config, 10));
    }
}
