//! The erosion itself, on a plain grid of heights: parameters, the droplet batches over tiles,
//! the thermal passes and the maps (see the module above for the conventions).

use rayon::prelude::*;

use super::droplet::{Carried, DropletParams, Tile};
use super::random::SplitMix64;
use super::{flow, thermal};

/// Side of the square tiles the droplets of a batch run on, in samples. A droplet that leaves
/// its tile stops and leaves its sediment where it is; the tiles move between batches so their
/// edges leave no mark.
pub const TILE_SIDE: u32 = 256;

/// Number of batches the droplets are split into (each over its own shifted tiling).
pub const BATCHES: u32 = 8;

/// Largest accepted STRENGTH (droplets and thermal passes scale with it).
pub const MAX_STRENGTH: f32 = 10.0;

/// The STRENGTH the procedural island is eroded with unless told otherwise: enough droplets for
/// their paths to gather into valleys and channels.
pub const ISLAND_STRENGTH: f32 = 4.0;

/// A grid of heights with its horizontal spacing.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// Samples per row.
    pub columns: u32,
    /// Number of rows.
    pub rows: u32,
    /// Distance between neighbouring samples, in the units of the heights.
    pub cell_size: f32,
    /// Heights, row by row from the far (-z) row.
    pub heights: Vec<f32>,
}

/// Why erosion could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ErosionError {
    /// A parameter out of its range.
    #[error("erosion parameter {name} = {value} is out of range: {expected}")]
    BadParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// A grid whose heights do not match its size, or that is too small.
    #[error("cannot erode a {columns}x{rows} grid of {len} heights with cell size {cell_size}")]
    BadGrid {
        /// Samples per row.
        columns: u32,
        /// Rows.
        rows: u32,
        /// Heights given.
        len: usize,
        /// The cell size.
        cell_size: f32,
    },
    /// The eroded heights do not make a heightmap.
    #[error("the eroded heights are not a heightmap: {0}")]
    Heightmap(String),
}

/// Every parameter of [`erode`]. Rates are fractions per droplet step or per thermal pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErosionParams {
    /// Seed of the droplets' random start positions: the same seed gives the same heights.
    pub seed: u64,
    /// Droplets released per grid sample (0 for no hydraulic erosion).
    pub droplets_per_cell: f32,
    /// The droplets' parameters.
    pub droplet: DropletParams,
    /// Thermal passes after the droplets (0 for none).
    pub thermal_passes: u32,
    /// The steepest stable slope, in degrees from the horizontal (0 to 89).
    pub talus_degrees: f32,
    /// Height of the sea (in the units of the heights), where droplets stop eroding and their
    /// sediment settles on the seabed below the water, as rivers' does; `None` for no sea
    /// (droplets run on over ground below any level).
    pub sea_level: Option<f32>,
    /// Fraction of a slope's excess over the talus slope moved per thermal pass (0 to 0.5).
    pub thermal_rate: f32,
}

impl ErosionParams {
    /// The parameters of `--erode STRENGTH`: `strength` (greater than 0, at most
    /// [`MAX_STRENGTH`]) droplets per sample and `strength / 4` thermal passes (rounded up), the
    /// other parameters at their defaults (no sea).
    pub fn with_strength(strength: f32, seed: u64) -> Result<Self, ErosionError> {
        // Written so that NaN is refused too.
        let valid = strength > 0.0 && strength <= MAX_STRENGTH;
        if !valid {
            return Err(ErosionError::BadParameter {
                name: "strength",
                value: f64::from(strength),
                expected: "greater than 0 and at most 10",
            });
        }
        Ok(Self {
            seed,
            droplets_per_cell: strength,
            thermal_passes: (strength / 4.0).ceil() as u32,
            ..Self::default()
        })
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), ErosionError> {
        let check = |name, value: f32, ok: bool, expected| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(ErosionError::BadParameter { name, value: f64::from(value), expected })
            }
        };
        let d = &self.droplet;
        check(
            "droplets_per_cell",
            self.droplets_per_cell,
            (0.0..=100.0).contains(&self.droplets_per_cell),
            "0 to 100",
        )?;
        check("talus_degrees", self.talus_degrees, (0.0..89.0).contains(&self.talus_degrees), "0 to 89")?;
        check("thermal_rate", self.thermal_rate, (0.0..=0.5).contains(&self.thermal_rate), "0 to 0.5")?;
        if let Some(sea) = self.sea_level {
            check("sea_level", sea, true, "a finite height")?;
        }
        check("inertia", d.inertia, (0.0..1.0).contains(&d.inertia), "0 to less than 1")?;
        check("capacity", d.capacity, d.capacity >= 0.0, "0 or more")?;
        check("min_capacity", d.min_capacity, d.min_capacity >= 0.0, "0 or more")?;
        check("erode_rate", d.erode_rate, (0.0..=1.0).contains(&d.erode_rate), "0 to 1")?;
        check("deposit_rate", d.deposit_rate, (0.0..=1.0).contains(&d.deposit_rate), "0 to 1")?;
        check("evaporation", d.evaporation, (0.0..1.0).contains(&d.evaporation), "0 to less than 1")?;
        check("gravity", d.gravity, d.gravity >= 0.0, "0 or more")?;
        let steps = d.max_steps as f32;
        check("max_steps", steps, (1..=1000).contains(&d.max_steps), "1 to 1000")?;
        let radius = d.radius as f32;
        check("radius", radius, (1..=8).contains(&d.radius), "1 to 8")?;
        Ok(())
    }
}

impl Default for ErosionParams {
    /// One droplet a sample and one thermal pass at a talus angle of 40 degrees, no sea.
    fn default() -> Self {
        Self {
            seed: 1,
            droplets_per_cell: 1.0,
            droplet: DropletParams::default(),
            thermal_passes: 1,
            talus_degrees: 40.0,
            thermal_rate: 0.5,
            sea_level: None,
        }
    }
}

/// What erosion leaves besides the heights, for the ground materials: one value a sample, in the
/// grid's order.
#[derive(Debug, Clone, PartialEq)]
pub struct ErosionMaps {
    /// Samples per row.
    pub columns: u32,
    /// Number of rows.
    pub rows: u32,
    /// Flow accumulation of the eroded heights: how many samples (itself included) drain through
    /// each sample, following the steepest descent ([`flow::accumulation`]).
    pub flow: Vec<f32>,
    /// Height gained by deposition (eroded minus original height where positive, else 0), in the
    /// units of the heights.
    pub deposition: Vec<f32>,
}

impl ErosionMaps {
    /// Bytes of memory the maps take.
    pub fn memory_bytes(&self) -> usize {
        (self.flow.len() + self.deposition.len()) * std::mem::size_of::<f32>()
    }
}

/// Eroded heights with their maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Eroded {
    /// The new heights (same size and cell size).
    pub grid: HeightGrid,
    /// Flow and deposition.
    pub maps: ErosionMaps,
}

/// Erodes `grid` with `params`: hydraulic erosion by droplets, then thermal erosion, then the
/// flow and deposition maps. Calls `progress` with the fraction done (0 to 1) from the calling
/// thread. The result depends on nothing but the arguments (not on the thread count).
pub fn erode(
    grid: &HeightGrid,
    params: &ErosionParams,
    progress: &mut dyn FnMut(f32),
) -> Result<Eroded, ErosionError> {
    params.validate()?;
    let (columns, rows) = (grid.columns, grid.rows);
    if columns < 2
        || rows < 2
        || grid.heights.len() != columns as usize * rows as usize
        || !(grid.cell_size.is_finite() && grid.cell_size > 0.0)
    {
        return Err(ErosionError::BadGrid {
            columns,
            rows,
            len: grid.heights.len(),
            cell_size: grid.cell_size,
        });
    }
    // The droplets and the talus work in cell units: heights divided by the cell size, so that a
    // slope is the height difference between neighbours.
    let scale = grid.cell_size;
    let mut heights: Vec<f32> = grid.heights.par_iter().map(|&h| h / scale).collect();
    let sea = params.sea_level.map_or(f32::NEG_INFINITY, |level| level / scale);
    // Progress counts batches and passes; the maps at the end are one more.
    let total_steps = (BATCHES + params.thermal_passes + 1) as f32;
    let mut step = 0.0;
    progress(0.0);
    for batch in 0..BATCHES {
        droplet_batch(&mut heights, columns, rows, params, sea, batch);
        step += 1.0;
        progress(step / total_steps);
    }
    let talus = params.talus_degrees.to_radians().tan();
    let mut spare = vec![0.0f32; heights.len()];
    let mut moves = vec![(0.0f32, 0.0f32); heights.len()];
    for _ in 0..params.thermal_passes {
        thermal::pass(&heights, &mut spare, &mut moves, columns, rows, talus, params.thermal_rate);
        std::mem::swap(&mut heights, &mut spare);
        step += 1.0;
        progress(step / total_steps);
    }
    drop((spare, moves));
    heights.par_iter_mut().for_each(|h| *h *= scale);
    let flow = flow::accumulation(&heights, columns, rows);
    let deposition = heights.par_iter().zip(&grid.heights).map(|(&new, &old)| (new - old).max(0.0)).collect();
    progress(1.0);
    Ok(Eroded {
        grid: HeightGrid { columns, rows, cell_size: grid.cell_size, heights },
        maps: ErosionMaps { columns, rows, flow, deposition },
    })
}

/// The tiles of a tiling whose cuts fall `offset` (plus multiples of [`TILE_SIDE`]) from the
/// grid's first column and row: (column, row, width, height) row by row.
fn tiling(columns: u32, rows: u32, (dx, dy): (u32, u32)) -> Vec<(u32, u32, u32, u32)> {
    let starts = |offset: u32, length: u32| -> Vec<(u32, u32)> {
        let mut cuts = vec![0];
        let mut cut = offset;
        while cut < length {
            if cut > 0 {
                cuts.push(cut);
            }
            cut += TILE_SIDE;
        }
        cuts.push(length);
        cuts.windows(2).filter(|w| w[1] > w[0]).map(|w| (w[0], w[1] - w[0])).collect()
    };
    let (xs, ys) = (starts(dx, columns), starts(dy, rows));
    ys.iter().flat_map(|&(y, h)| xs.iter().map(move |&(x, w)| (x, y, w, h))).collect()
}

/// Writes tiles (in `tiles`' order) back into `heights`.
fn write_back(heights: &mut [f32], columns: u32, tiles: &[(u32, u32, u32, u32)], done: &[Vec<f32>]) {
    for (&(x, y, w, _), tile) in tiles.iter().zip(done) {
        for (r, row) in tile.chunks_exact(w as usize).enumerate() {
            let start = (y as usize + r) * columns as usize + x as usize;
            heights[start..start + w as usize].copy_from_slice(row);
        }
    }
}

/// One batch of droplets over a tiling shifted by an offset drawn from the seed and the batch.
/// Each tile is copied out, eroded by its own droplets with its own random stream, and written
/// back in the tiles' order: nothing depends on which thread ran which tile. Droplets that reach
/// a tile's edge go on in a second tiling shifted by half a tile (where they are far from any
/// edge), in the order of their tiles and of their leaving, so that tile edges leave no seams.
fn droplet_batch(heights: &mut [f32], columns: u32, rows: u32, params: &ErosionParams, sea: f32, batch: u32) {
    let mut offsets = SplitMix64::new(params.seed ^ 0x6572_6f73_696f_6e00 ^ u64::from(batch));
    let (dx, dy) = (offsets.below(TILE_SIDE), offsets.below(TILE_SIDE));
    let tiles = tiling(columns, rows, (dx, dy));
    let source: &[f32] = heights;
    let per_batch = params.droplets_per_cell / BATCHES as f32;
    let done: Vec<(Vec<f32>, Vec<Carried>)> = tiles
        .par_iter()
        .enumerate()
        .map(|(index, &(x, y, w, h))| {
            let mut tile = Tile::copy_from(source, (columns, rows), x, y, w, h);
            let droplets = (per_batch * (w * h) as f32).round() as u64;
            let stream =
                params.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (u64::from(batch) << 40) ^ index as u64;
            let mut random = SplitMix64::new(stream);
            let carried = tile.run(droplets, &params.droplet, sea, &mut random);
            (tile.into_heights(), carried)
        })
        .collect();
    let (done, carried): (Vec<Vec<f32>>, Vec<Vec<Carried>>) = done.into_iter().unzip();
    write_back(heights, columns, &tiles, &done);
    // The droplets handed on, each to the tile of the half-shifted tiling it is in.
    let half = TILE_SIDE / 2;
    let shifted = tiling(columns, rows, ((dx + half) % TILE_SIDE, (dy + half) % TILE_SIDE));
    let mut waiting: Vec<Vec<Carried>> = vec![Vec::new(); shifted.len()];
    for droplet in carried.into_iter().flatten() {
        let (cx, cy) = (droplet.x.max(0.0) as u32, droplet.y.max(0.0) as u32);
        let found =
            shifted.iter().position(|&(x, y, w, h)| (x..x + w).contains(&cx) && (y..y + h).contains(&cy));
        if let Some(index) = found {
            waiting[index].push(droplet);
        }
    }
    let busy: Vec<usize> = (0..shifted.len()).filter(|&i| !waiting[i].is_empty()).collect();
    let busy_tiles: Vec<(u32, u32, u32, u32)> = busy.iter().map(|&i| shifted[i]).collect();
    let source: &[f32] = heights;
    let done: Vec<Vec<f32>> = busy
        .par_iter()
        .map(|&index| {
            let (x, y, w, h) = shifted[index];
            let mut tile = Tile::copy_from(source, (columns, rows), x, y, w, h);
            tile.resume(&waiting[index], &params.droplet, sea);
            tile.into_heights()
        })
        .collect();
    write_back(heights, columns, &busy_tiles, &done);
}
