//! Erosion of a grid of heights: hydraulic erosion by water droplets that carry sediment
//! ([`droplet`]), then thermal erosion that lets slopes steeper than the talus angle slide
//! ([`thermal`]), and the maps the ground materials read afterwards: flow accumulation
//! ([`flow`]) and deposition.
//!
//! Everything is a pure function of the heights, the parameters and the seed, and gives the same
//! heights bit for bit at any number of threads: droplets run in fixed batches over disjoint tiles
//! (each tile with its own random stream, its results written back in a fixed order), and the
//! thermal passes read one buffer and write another.
//!
//! Conventions: y-up; the grid is row by row from the far (-z) row, as [`super::Heightmap`];
//! heights and the cell size are in the same units (world units, or metres).

pub mod droplet;
pub mod flow;
mod random;
mod run;
pub mod thermal;

use rayon::prelude::*;

use super::{Heightfield, Heightmap};
use crate::config::SceneConfig;
pub use run::{
    BATCHES, Eroded, ErosionError, ErosionMaps, ErosionParams, HeightGrid, ISLAND_STRENGTH, MAX_STRENGTH,
    TILE_SIDE, erode,
};

/// Erodes a heightmap placed with `config` (its world heights and cell size), and returns the new
/// heightmap (stored as the original: 16-bit values stay 16-bit, clamped to levels 0..=255) with
/// the maps (in world units).
pub fn erode_heightmap(
    heightmap: &Heightmap,
    config: &SceneConfig,
    params: &ErosionParams,
    progress: &mut dyn FnMut(f32),
) -> Result<(Heightmap, ErosionMaps), ErosionError> {
    let (columns, rows) = (heightmap.columns(), heightmap.rows());
    let grid = HeightGrid {
        columns,
        rows,
        cell_size: Heightfield::cell_size_of(heightmap, config),
        heights: heightmap.levels().map(|level| config.height_of_level(level)).collect(),
    };
    let eroded = erode(&grid, params, progress)?;
    let levels = eroded.grid.heights.par_iter().map(|&h| config.level_of_height(h));
    let heightmap = match heightmap.samples() {
        super::heightmap::StoredSamples::Sixteen(_) => Heightmap::from_sixteen_bit(
            columns,
            rows,
            levels.map(super::heightmap::sixteen_of_level).collect(),
        )
        .map_err(|e| ErosionError::Heightmap(e.to_string()))?,
        super::heightmap::StoredSamples::Levels(_) => Heightmap::new(columns, rows, levels.collect())
            .map_err(|e| ErosionError::Heightmap(e.to_string()))?,
    };
    Ok((heightmap, eroded.maps))
}

#[cfg(test)]
mod tests;
