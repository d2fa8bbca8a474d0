//! The ground materials' weights on the CPU (a "splat map"), for other tools: the same shares the
//! modern look's terrain shader works out per vertex (`vs_lit` in `render/grid_modern.wgsl`),
//! from the same inputs: the shape map of [`super::ground::ground_map`] (normal, curvature) and
//! the detail map's green channel (broad patches), both sampled bilinearly as the GPU does, the
//! height, and the ground settings' rock slope, snow line and sand line ([`GroundLines`]).
//!
//! Five materials, in this order: rock (cliffs), scree (moderately steep hollows), grass (and
//! soil: the rest), sand (shores), snow (high up, least on steep slopes). At each heightmap
//! sample the five weights are at least 0 and sum to 1 (the shader's blend divides by their sum
//! too). The shader then blends them by their relief (noise at a much finer scale than a
//! sample); the splat map holds the weights before that.
//!
//! Conventions: y-up; row 0 is the far (-z, northern) row, as the heightmap's.

use glam::Vec3;
use image::RgbaImage;
use rayon::prelude::*;

use super::ground::ground_map;
use super::procedural::smoothstep_f32;
use super::{Heightfield, World};
use crate::config::SceneConfig;

/// The materials' names, in the order of their weights.
pub const MATERIALS: [&str; 5] = ["rock", "scree", "grass", "sand", "snow"];

/// Where the materials start, in world units (as the shader's `scene.ground` uniform holds them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundLines {
    /// The rock's slope as `1 - cos(angle)` (the slope measure is `1 - normal.y`).
    pub rock_slope: f32,
    /// The snow line's height (world y).
    pub snow_line: f32,
    /// The shore's sand line (world y; far below the land without a sea).
    pub sand_line: f32,
    /// The land's highest point above the water (world y, at least 0.001).
    pub top: f32,
}

impl GroundLines {
    /// The lines for a scene laid out by `config` (as `render::lighting` sets them) from the
    /// ground settings' rock slope (degrees), snow line and sand line (shares of the land's
    /// highest point).
    pub fn new(rock_slope_degrees: f32, snow_line: f32, sand_line: f32, config: &SceneConfig) -> Self {
        let top = config.height_of_level(255.0).max(1e-3);
        Self {
            rock_slope: 1.0 - rock_slope_degrees.to_radians().cos(),
            snow_line: snow_line * top,
            sand_line: if config.sea { sand_line * top } else { -1e4 },
            top,
        }
    }
}

/// The five weights ([`MATERIALS`]' order) at a point with the unit `normal` (y-up), the
/// `curvature` (-1 ridge to 1 hollow, the shape map's scale), the world `height`, and `broad`
/// (the detail map's green, 0 to 1): the shader's shares, grass taking the rest, normalised to
/// sum to 1.
pub fn weights(normal: Vec3, curvature: f32, height: f32, broad: f32, lines: &GroundLines) -> [f32; 5] {
    let slope = 1.0 - normal.y;
    let (rs, top) = (lines.rock_slope, lines.top);
    let rock = smoothstep_f32(rs * 0.85, rs * 1.15, slope + 0.12 * rs * (broad - 0.5));
    let scree =
        smoothstep_f32(rs * 0.35, rs * 0.7, slope) * smoothstep_f32(-0.05, 0.35, curvature) * (1.0 - rock);
    let band = 0.3 * lines.sand_line.abs() + 1e-4;
    let sand =
        (1.0 - smoothstep_f32(
            lines.sand_line - band,
            lines.sand_line + band,
            height + 0.02 * top * (broad - 0.5),
        )) * (1.0 - smoothstep_f32(0.1, 0.25, slope));
    let line = lines.snow_line + 0.12 * top * normal.z + 0.08 * top * (broad - 0.5);
    let snow = smoothstep_f32(line - 0.03 * top, line + 0.03 * top, height)
        * (1.0 - smoothstep_f32(rs * 1.1, rs * 1.6, slope));
    let rock = rock * (1.0 - snow);
    let scree = scree * (1.0 - snow);
    let sand = sand * (1.0 - rock) * (1.0 - snow);
    let grass = (1.0 - rock - scree - sand - snow).max(0.0);
    let total = rock + scree + grass + sand + snow;
    [rock, scree, grass, sand, snow].map(|w| w / total)
}

/// Samples an image's channel bilinearly at texture coordinates `(u, v)` as a GPU's linear filter
/// does (texel centres at `(i + 0.5) / size`), clamping to the edge or wrapping around.
fn bilinear(image: &RgbaImage, channel: usize, u: f32, v: f32, wrap: bool) -> f32 {
    let (width, height) = (image.width() as i64, image.height() as i64);
    let (x, y) = (u * width as f32 - 0.5, v * height as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i64, j: i64| {
        let (i, j) = if wrap {
            (i.rem_euclid(width), j.rem_euclid(height))
        } else {
            (i.clamp(0, width - 1), j.clamp(0, height - 1))
        };
        f32::from(image.get_pixel(i as u32, j as u32).0[channel]) / 255.0
    };
    let (i, j) = (x0 as i64, y0 as i64);
    let top = texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx;
    let bottom = texel(i, j + 1) * (1.0 - fx) + texel(i + 1, j + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The materials' weights at every heightmap sample of a world.
#[derive(Debug, Clone, PartialEq)]
pub struct SplatMap {
    /// Samples per row (the heightmap's).
    pub columns: u32,
    /// Rows (the heightmap's), row 0 the far (-z) one.
    pub rows: u32,
    /// Five weights a sample ([`MATERIALS`]' order), row by row.
    pub weights: Vec<[f32; 5]>,
}

/// The weights of `world`'s ground (placed with `config`, with the ground's `lines`) at each of its
/// heightmap samples, from the same shape map (with the erosion's maps when the world has them)
/// and detail map the shader reads. Deterministic: the same world gives the same weights at any
/// thread count.
pub fn splat_map(world: &World, config: &SceneConfig, lines: &GroundLines) -> SplatMap {
    let heightmap = &world.heightmap;
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    let shape = ground_map(heightmap, config, world.erosion.as_ref());
    let field = Heightfield::new(heightmap, config);
    let weights = (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| {
            let (shape, detail, field, lines) = (&shape, &world.detail_map, &field, &lines);
            (0..columns).map(move |column| {
                // The sample's texture coordinates, as the shader's `uv`: texel centres of a
                // shape map as large as the heightmap.
                let u = (column as f32 + 0.5) / columns as f32;
                let v = (row as f32 + 0.5) / rows as f32;
                let (a, b) = (bilinear(shape, 0, u, v, false), bilinear(shape, 1, u, v, false));
                let (nx, nz) = (a * 2.0 - 1.0, b * 2.0 - 1.0);
                let normal = Vec3::new(nx, (1.0 - nx * nx - nz * nz).max(0.0).sqrt(), nz).normalize();
                let curvature = bilinear(shape, 2, u, v, false) * 2.0 - 1.0;
                let repeat = config.detail_repeat;
                let broad = bilinear(detail, 1, u * repeat, v * repeat, true);
                weights(normal, curvature, field.height(row, column), broad, lines)
            })
        })
        .collect();
    SplatMap { columns, rows, weights }
}

impl SplatMap {
    /// The weights as bytes that sum to exactly 255 at each sample (the largest remainders
    /// rounded up, ties to the earlier material), five a sample.
    pub fn bytes(&self) -> Vec<[u8; 5]> {
        self.weights.par_iter().map(quantise).collect()
    }

    /// The weights as two RGBA images, as splat maps are laid out for other tools (four layers an
    /// image): the first holds rock, scree, grass and sand in red, green, blue and alpha, the
    /// second snow in red (green, blue and alpha 0). Each sample's eight bytes sum to 255.
    pub fn images(&self) -> [RgbaImage; 2] {
        let bytes = self.bytes();
        let first = bytes.iter().flat_map(|b| [b[0], b[1], b[2], b[3]]).collect();
        let second = bytes.iter().flat_map(|b| [b[4], 0, 0, 0]).collect();
        let image =
            |raw| RgbaImage::from_raw(self.columns, self.rows, raw).unwrap_or_else(|| RgbaImage::new(1, 1));
        [image(first), image(second)]
    }
}

/// Weights summing to 1 as bytes summing to 255.
fn quantise(weights: &[f32; 5]) -> [u8; 5] {
    let scaled = weights.map(|w| w.clamp(0.0, 1.0) * 255.0);
    let mut bytes = scaled.map(|s| s.floor() as u8);
    let given: u32 = bytes.iter().map(|&b| u32::from(b)).sum();
    let mut order = [0usize, 1, 2, 3, 4];
    // Largest remainder first; a stable sort keeps ties in material order.
    order.sort_by(|&a, &b| (scaled[b] - scaled[b].floor()).total_cmp(&(scaled[a] - scaled[a].floor())));
    for &i in order.iter().take(255u32.saturating_sub(given) as usize) {
        bytes[i] = bytes[i].saturating_add(1);
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::GroundSettings;

    fn lines() -> GroundLines {
        GroundSettings::default().lines(&SceneConfig::default())
    }

    fn strongest(w: [f32; 5]) -> &'static str {
        let best = (0..5).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
        MATERIALS[best]
    }

    #[test]
    fn cliffs_give_rock_high_ground_snow_and_shores_sand() {
        let lines = lines();
        let up = Vec3::Y;
        let cliff = Vec3::new(0.8, 0.6, 0.0).normalize();
        // A cliff halfway up.
        let w = weights(cliff, 0.0, 0.4 * lines.top, 0.5, &lines);
        assert_eq!(strongest(w), "rock", "{w:?}");
        assert!(w[0] > 0.9, "{w:?}");
        // Flat ground near the top: snow.
        let w = weights(up, 0.0, 0.95 * lines.top, 0.5, &lines);
        assert_eq!(strongest(w), "snow", "{w:?}");
        // Flat ground just above the water: sand.
        let w = weights(up, 0.0, 0.2 * lines.sand_line, 0.5, &lines);
        assert_eq!(strongest(w), "sand", "{w:?}");
        // Flat ground halfway up: grass.
        let w = weights(up, 0.0, 0.4 * lines.top, 0.5, &lines);
        assert_eq!(strongest(w), "grass", "{w:?}");
        assert!((w[2] - 1.0).abs() < 1e-6, "{w:?}");
        // A moderately steep hollow: scree.
        let hollow = Vec3::new(0.0, 1.0 - 0.65 * lines.rock_slope, 0.0);
        let hollow = Vec3::new((1.0 - hollow.y * hollow.y).sqrt(), hollow.y, 0.0);
        let w = weights(hollow, 0.6, 0.4 * lines.top, 0.5, &lines);
        assert_eq!(strongest(w), "scree", "{w:?}");
        // A steep slope high up sheds its snow.
        let w = weights(cliff, 0.0, 0.95 * lines.top, 0.5, &lines);
        assert_eq!(strongest(w), "rock", "{w:?}");
    }

    #[test]
    fn the_shader_still_works_the_shares_out_as_ported_here() {
        // `weights` is a port of these lines of the terrain shader: when they change, change it.
        let shader: String = include_str!("../render/grid_modern.wgsl").split_whitespace().collect();
        for line in [
            "let rock = smoothstep(rock_slope * 0.85, rock_slope * 1.15, slope + 0.12 * rock_slope * (broad - 0.5));",
            "let scree = smoothstep(rock_slope * 0.35, rock_slope * 0.7, slope) * smoothstep(-0.05, 0.35, curvature) * (1.0 - rock);",
            "let band = 0.3 * abs(scene.ground.w) + 1e-4;",
            "let sand = (1.0 - smoothstep(scene.ground.w - band, scene.ground.w + band, height + 0.02 * top * (broad - 0.5))) * (1.0 - smoothstep(0.1, 0.25, slope));",
            "let line = scene.ground.z + 0.12 * top * normal.z + 0.08 * top * (broad - 0.5);",
            "let snow = smoothstep(line - 0.03 * top, line + 0.03 * top, height) * (1.0 - smoothstep(rock_slope * 1.1, rock_slope * 1.6, slope));",
            "out.shares = vec4<f32>(rock * (1.0 - snow), scree * (1.0 - snow), sand * (1.0 - rock) * (1.0 - snow), snow);",
            "let w_grass = max(1.0 - w_rock - w_scree - w_sand - w_snow, 0.0);",
            "let broad = textureSampleLevel(detail_map, wrap, out.uv * grid.detail_repeat, 0.0).g;",
            "let normal = normalize(vec3<f32>(nxz.x, sqrt(max(1.0 - dot(nxz, nxz), 0.0)), nxz.y));",
            "let curvature = shape.b * 2.0 - 1.0;",
        ] {
            let line: String = line.split_whitespace().collect();
            assert!(
                shader.contains(&line),
                "the shader no longer has `{line}`: port the change to `weights`"
            );
        }
        // And `GroundLines::new` of these lines of the uniforms.
        let uniforms: String = include_str!("../render/lighting.rs").split_whitespace().collect();
        for line in [
            "let top = config.height_of_level(255.0).max(1e-3);",
            "1.0 - ground.rock_slope_degrees.to_radians().cos(), ground.snow_line * top,",
            "if config.sea { ground.sand_line * top } else { -1e4 },",
            "ground_scale: [1.0 / (ground.texture_size * config.terrain_length), ground.detail, top, 0.0],",
        ] {
            let line: String = line.split_whitespace().collect();
            assert!(uniforms.contains(&line), "lighting.rs no longer has `{line}`: port the change");
        }
    }

    #[test]
    fn without_a_sea_there_is_no_shore() {
        let config = SceneConfig { sea: false, ..SceneConfig::default() };
        let lines = GroundSettings::default().lines(&config);
        let w = weights(Vec3::Y, 0.0, 0.001, 0.5, &lines);
        assert_eq!(w[3], 0.0, "{w:?}");
    }

    #[test]
    fn weights_are_shares_that_sum_to_one_and_bytes_to_255() {
        let lines = lines();
        for i in 0..2000 {
            let t = i as f32 / 2000.0;
            let normal =
                Vec3::new((t * 37.0).sin(), 0.3 + 0.7 * (t * 11.0).cos().abs(), (t * 23.0).cos()).normalize();
            let w = weights(normal, (t * 7.0).sin(), (t * 3.0 - 0.5) * lines.top, (t * 13.0).fract(), &lines);
            assert!(w.iter().all(|&x| (0.0..=1.0 + 1e-6).contains(&x)), "{w:?}");
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
            let bytes = quantise(&w);
            assert_eq!(bytes.iter().map(|&b| u32::from(b)).sum::<u32>(), 255, "{w:?} {bytes:?}");
            for (b, x) in bytes.iter().zip(w) {
                assert!((f32::from(*b) - x * 255.0).abs() < 1.0, "{w:?} {bytes:?}");
            }
        }
    }

    #[test]
    fn bilinear_sampling_matches_texel_centres_and_wraps() {
        let image = RgbaImage::from_fn(4, 2, |x, y| image::Rgba([(x * 60 + y) as u8, 0, 0, 0]));
        // A texel's centre gives the texel.
        assert_eq!(bilinear(&image, 0, 2.5 / 4.0, 0.5 / 2.0, false), 120.0 / 255.0);
        // Halfway between two texels, their mean.
        assert!((bilinear(&image, 0, 2.0 / 4.0, 0.25, false) - 90.0 / 255.0).abs() < 1e-6);
        // Past the edge: clamped, or wrapped to the other side.
        assert_eq!(bilinear(&image, 0, 0.0, 0.25, false), 0.0);
        assert!((bilinear(&image, 0, 0.0, 0.25, true) - 90.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn the_island_has_every_material_and_the_same_map_at_any_thread_count() {
        let config = SceneConfig::default();
        let options = crate::world::procedural::ProceduralOptions { seed: 1, heightmap_size: 128 };
        let world = crate::world::procedural::generate(options, &config, &mut |_| {}).expect("valid");
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            pool.install(|| splat_map(&world, &config, &GroundSettings::default().lines(&config)))
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one, two);
        assert_eq!((one.columns, one.rows, one.weights.len()), (128, 128, 128 * 128));
        for (m, name) in MATERIALS.iter().enumerate() {
            let most = one.weights.iter().map(|w| w[m]).fold(0.0f32, f32::max);
            assert!(most > 0.5, "{name} is nowhere the main material (at most {most})");
        }
        let [first, second] = one.images();
        assert_eq!(first.dimensions(), (128, 128));
        for (a, b) in first.pixels().zip(second.pixels()) {
            let sum: u32 = a.0.iter().chain(&b.0).map(|&x| u32::from(x)).sum();
            assert_eq!(sum, 255);
        }
    }
}
