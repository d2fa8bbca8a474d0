//! The built-in world, made from noise: an island heightmap, its colour map (from height and
//! slope), detail noise, a sky and a water texture. Everything is deterministic: the same seed and
//! sizes give bit-identical images on every run.

mod colour;
mod detail;
mod field;
mod island;
mod sky;
mod water;
mod waves;

pub use colour::{MAX_COLOUR_MAP_SIDE, colour_map, colour_map_size, colour_maps};
pub use detail::detail_map;
pub use field::smoothstep_f32;
pub use island::{EXACT_SIDE, island_heightmap};
pub use sky::{sky_box, sky_boxes};
pub use water::water_texture;
pub use waves::{WAVE_MAP_SIZE, wave_map};

use super::{Heightmap, HeightmapError, UnlitLayers, World};
use crate::config::SceneConfig;

/// Direction toward the sun (y-up, not normalised): 25 degrees high, ahead and to the left of the
/// starting view. The sky's sun and the colour map's hill shading both use it.
pub const SUN_DIRECTION: [f64; 3] = [-0.742, 0.423, -0.520];

/// Side of the generated detail map, in texels.
pub const DETAIL_MAP_SIZE: u32 = 512;
/// Side of each generated sky face, in texels.
pub const SKY_FACE_SIZE: u32 = 512;
/// Side of the generated water texture, in texels.
pub const WATER_TEXTURE_SIZE: u32 = 256;

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProceduralOptions {
    /// Seed of every noise layer.
    pub seed: u32,
    /// Side of the island's square heightmap, in samples.
    pub heightmap_size: u32,
}

impl Default for ProceduralOptions {
    fn default() -> Self {
        Self { seed: 1, heightmap_size: 512 }
    }
}

/// A part of the world being generated, reported to progress callbacks as it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The island's heightmap.
    Heightmap,
    /// The colour map derived from the heightmap.
    ColourMap,
    /// The detail map.
    DetailMap,
    /// The five sky faces.
    Sky,
    /// The water texture.
    Water,
}

impl Stage {
    /// All stages, in the order they run.
    pub const ALL: [Stage; 5] =
        [Stage::Heightmap, Stage::ColourMap, Stage::DetailMap, Stage::Sky, Stage::Water];

    /// A short description, e.g. for a progress line.
    pub fn describe(self) -> &'static str {
        match self {
            Stage::Heightmap => "island heightmap",
            Stage::ColourMap => "colour map",
            Stage::DetailMap => "detail map",
            Stage::Sky => "sky",
            Stage::Water => "water",
        }
    }
}

/// How far generation has got: the stage under way and the fraction of it done (0 when it
/// starts, 1 when it ends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// The part being generated.
    pub stage: Stage,
    /// Fraction of the stage done, 0 to 1.
    pub done: f32,
}

impl Progress {
    /// The fraction of all stages done (each stage counted as an equal part), 0 to 1.
    pub fn overall(&self) -> f32 {
        let index = Stage::ALL.iter().position(|&s| s == self.stage).unwrap_or(0);
        (index as f32 + self.done.clamp(0.0, 1.0)) / Stage::ALL.len() as f32
    }
}

/// Generates the whole procedural world, calling `progress` as each [`Stage`] starts and as it
/// advances.
pub fn generate(
    options: ProceduralOptions,
    config: &SceneConfig,
    progress: &mut dyn FnMut(Progress),
) -> Result<World, HeightmapError> {
    progress(Progress { stage: Stage::Heightmap, done: 0.0 });
    let heightmap = island_heightmap(options.seed, options.heightmap_size, config, &mut |done| {
        progress(Progress { stage: Stage::Heightmap, done })
    })?;
    Ok(dress_heightmap(heightmap, options.seed, config, progress))
}

/// A world around a given heightmap: the heightmap as is, with a colour map painted from its
/// heights and slopes and generated detail, sky and water textures. Calls `progress` as each
/// [`Stage`] after [`Stage::Heightmap`] starts and advances.
pub fn dress_heightmap(
    heightmap: Heightmap,
    seed: u32,
    config: &SceneConfig,
    progress: &mut dyn FnMut(Progress),
) -> World {
    progress(Progress { stage: Stage::ColourMap, done: 0.0 });
    let (colour_map, albedo_map) = colour_maps(&heightmap, config, seed, &mut |done| {
        progress(Progress { stage: Stage::ColourMap, done })
    });
    progress(Progress { stage: Stage::DetailMap, done: 0.0 });
    let detail_map = detail_map(seed, DETAIL_MAP_SIZE);
    progress(Progress { stage: Stage::Sky, done: 0.0 });
    let (sky, clear_sky) = sky_boxes(seed, SKY_FACE_SIZE, config);
    progress(Progress { stage: Stage::Water, done: 0.0 });
    let water = water_texture(seed, WATER_TEXTURE_SIZE);
    progress(Progress { stage: Stage::Water, done: 1.0 });
    let unlit = Some(UnlitLayers { albedo_map, sky: clear_sky });
    World { heightmap, colour_map, detail_map, sky, water, unlit, elevation: None, erosion: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generate_reports_every_stage_in_order() {
        let mut seen = Vec::new();
        let mut overall = Vec::new();
        let options = ProceduralOptions { seed: 1, heightmap_size: 16 };
        let world = generate(options, &SceneConfig::default(), &mut |progress| {
            if progress.done == 0.0 {
                seen.push(progress.stage);
            }
            overall.push(progress.overall());
        })
        .expect("valid size");
        assert_eq!(seen, Stage::ALL);
        assert!(overall.windows(2).all(|w| w[0] <= w[1]), "{overall:?}");
        assert_eq!(overall.last(), Some(&1.0));
        assert_eq!(world.heightmap.columns(), 16);
        assert_eq!(world.colour_map.dimensions(), (32, 32));
        assert_eq!(world.sky.top.dimensions(), (SKY_FACE_SIZE, SKY_FACE_SIZE));
    }

    #[test]
    fn bad_sizes_are_errors() {
        let options = ProceduralOptions { seed: 1, heightmap_size: 0 };
        assert!(generate(options, &SceneConfig::default(), &mut |_| {}).is_err());
    }
}
