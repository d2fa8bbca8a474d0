//! Hydraulic erosion by water droplets (after Hans Theobald Beyer's "Implementation of a method
//! for hydraulic erosion", 2015): each droplet starts at a random point, runs down the gradient
//! with some inertia, picks up sediment up to a capacity that grows with its speed, water and
//! the drop, leaves sediment where it slows or climbs, and evaporates. Soil is moved, never made
//! or lost: what a droplet still carries when it stops is left where it stops.
//!
//! A [`Tile`] is a rectangle of the grid in cell units (heights divided by the cell size, the
//! spacing between samples is 1); droplets stay inside their tile.

use super::random::SplitMix64;

/// The droplets' parameters (heights in cell units: a drop of 1 is one cell size).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DropletParams {
    /// How much of its direction a droplet keeps at each step (0: follows the gradient, up to
    /// less than 1).
    pub inertia: f32,
    /// Sediment a droplet can carry per unit of drop, speed and water.
    pub capacity: f32,
    /// Least capacity, so that droplets on flat ground still carry a little.
    pub min_capacity: f32,
    /// Fraction of the free capacity taken from the ground per step (0 to 1).
    pub erode_rate: f32,
    /// Fraction of the excess sediment left per step (0 to 1).
    pub deposit_rate: f32,
    /// Fraction of the water evaporating per step (0 to less than 1).
    pub evaporation: f32,
    /// Acceleration of a droplet per unit of drop.
    pub gravity: f32,
    /// Steps a droplet lives at most (each step moves one cell).
    pub max_steps: u32,
    /// Radius of the brush a droplet erodes with, in cells (1 to 8).
    pub radius: u32,
}

impl Default for DropletParams {
    /// Gentle droplets, many of which are needed: each takes and leaves little, so their paths
    /// gather into channels that deepen (rather than each one planing the slope it runs down).
    fn default() -> Self {
        Self {
            inertia: 0.05,
            capacity: 2.0,
            min_capacity: 0.01,
            erode_rate: 0.05,
            deposit_rate: 0.05,
            evaporation: 0.02,
            gravity: 4.0,
            max_steps: 80,
            radius: 2,
        }
    }
}

/// A rectangle of heights (cell units) that droplets run on, with where it lies in its grid.
#[derive(Debug, Clone)]
pub struct Tile {
    width: usize,
    height: usize,
    heights: Vec<f32>,
    /// Column and row of the tile's first sample in the grid.
    origin: (u32, u32),
    /// The grid's columns and rows.
    grid: (u32, u32),
    /// The largest column and row coordinates in the tile (`width - 1`, `height - 1`).
    limit: (f32, f32),
}

/// A droplet that reached the edge of its tile (not the grid's) and goes on in another tiling:
/// where it is (grid coordinates, in cells), where it heads, its speed, water and sediment, and
/// the steps it has left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carried {
    /// Column coordinate in the grid (cells).
    pub x: f32,
    /// Row coordinate in the grid (cells).
    pub y: f32,
    dir_x: f32,
    dir_y: f32,
    speed: f32,
    water: f32,
    sediment: f32,
    steps_left: u32,
}

/// A droplet's state as it runs.
#[derive(Debug, Clone, Copy)]
struct State {
    x: f32,
    y: f32,
    dir_x: f32,
    dir_y: f32,
    speed: f32,
    water: f32,
    sediment: f32,
}

impl Tile {
    /// A tile of `heights` alone (a whole grid: droplets stop at its edges).
    pub fn new(width: usize, height: usize, heights: Vec<f32>) -> Self {
        assert_eq!(heights.len(), width * height, "tile size");
        let limit = (width.saturating_sub(1) as f32, height.saturating_sub(1) as f32);
        Self { width, height, heights, origin: (0, 0), grid: (width as u32, height as u32), limit }
    }

    /// The `w` x `h` rectangle at column `x`, row `y` of a grid of `columns` x `rows` samples.
    /// Droplets stop at the grid's edges; at the tile's other edges they are handed on
    /// ([`Carried`]).
    pub fn copy_from(grid: &[f32], (columns, rows): (u32, u32), x: u32, y: u32, w: u32, h: u32) -> Self {
        let mut heights = Vec::with_capacity(w as usize * h as usize);
        for row in y..y + h {
            let start = row as usize * columns as usize + x as usize;
            heights.extend_from_slice(&grid[start..start + w as usize]);
        }
        Self { origin: (x, y), grid: (columns, rows), ..Self::new(w as usize, h as usize, heights) }
    }

    /// The heights, row by row.
    pub fn into_heights(self) -> Vec<f32> {
        self.heights
    }

    /// Runs `count` droplets, their start points drawn from `random`, [`LANES`] at a time (a
    /// step of each in turn; a lane that frees takes the next droplet). A droplet that is (or
    /// gets) below `sea` (cell units; `f32::NEG_INFINITY` for no sea) erodes no more: its
    /// sediment settles on the seabed over its next steps, as a river's does off its mouth.
    /// Returns, in the order they left, the droplets that reached an edge of the tile inside
    /// the grid.
    pub fn run(
        &mut self,
        count: u64,
        params: &DropletParams,
        sea: f32,
        random: &mut SplitMix64,
    ) -> Vec<Carried> {
        let mut carried = Vec::new();
        if self.width < 2 || self.height < 2 {
            return carried;
        }
        let brush = Brush::new(params.radius, self.width);
        let (span_x, span_y) = ((self.width - 1) as f32, (self.height - 1) as f32);
        let mut left = count;
        let next = || {
            left = left.checked_sub(1)?;
            let (x, y) = (random.unit() * span_x, random.unit() * span_y);
            let start = State { x, y, dir_x: 0.0, dir_y: 0.0, speed: 1.0, water: 1.0, sediment: 0.0 };
            Some((start, params.max_steps))
        };
        self.run_lanes(next, params, sea, &brush, Some(&mut carried));
        carried
    }

    /// Runs on, [`LANES`] at a time as [`Tile::run`] does, droplets handed on from another
    /// tiling (in grid coordinates, inside this tile); those that reach this tile's edge too
    /// stop there and leave their sediment.
    pub fn resume(&mut self, droplets: &[Carried], params: &DropletParams, sea: f32) {
        if self.width < 2 || self.height < 2 {
            return;
        }
        let brush = Brush::new(params.radius, self.width);
        let (ox, oy) = (self.origin.0 as f32, self.origin.1 as f32);
        let (limit_x, limit_y) = ((self.width - 1) as f32, (self.height - 1) as f32);
        let mut droplets = droplets.iter();
        let next = || {
            let d = droplets.next()?;
            let start = State {
                x: (d.x - ox).clamp(0.0, limit_x),
                y: (d.y - oy).clamp(0.0, limit_y),
                dir_x: d.dir_x,
                dir_y: d.dir_y,
                speed: d.speed,
                water: d.water,
                sediment: d.sediment,
            };
            Some((start, d.steps_left))
        };
        self.run_lanes(next, params, sea, &brush, None);
    }

    /// Runs the droplets `next` gives (a start and the steps it may take) in [`LANES`] lanes,
    /// a step of each busy lane in turn, until `next` gives no more and every lane is done. The
    /// droplets that reach an edge of the tile inside the grid go to `carried` in the order
    /// they leave; without `carried` they stop there.
    fn run_lanes(
        &mut self,
        mut next: impl FnMut() -> Option<(State, u32)>,
        p: &DropletParams,
        sea: f32,
        brush: &Brush,
        mut carried: Option<&mut Vec<Carried>>,
    ) {
        let mut lanes: [Option<Running>; LANES] = [None; LANES];
        let mut more = true;
        loop {
            let mut busy = false;
            for lane in &mut lanes {
                if lane.is_none() && more {
                    match next() {
                        Some((state, steps)) => {
                            *lane = Some(Running { here: self.spot(state.x, state.y), state, step: 0, steps })
                        }
                        None => more = false,
                    }
                }
                let Some(droplet) = lane else { continue };
                busy = true;
                if !self.step(droplet, p, sea, brush, &mut carried) {
                    *lane = None;
                }
            }
            if !busy {
                break;
            }
        }
    }

    /// Where (`x`, `y`) lies: the cell (the last one for a point on the far edges) and the
    /// point's offsets in it. `x` and `y` are inside the tile (0 to width - 1, 0 to height - 1).
    #[inline]
    fn spot(&self, x: f32, y: f32) -> Spot {
        // Inside the tile, so the conversions neither saturate nor see NaN.
        let column = (x as i32).min(self.width as i32 - 2);
        let row = (y as i32).min(self.height as i32 - 2);
        Spot {
            index: row as usize * self.width + column as usize,
            column,
            row,
            u: x - column as f32,
            v: y - row as f32,
        }
    }

    /// The heights at the four corners of the cell whose north-west corner is sample `index`:
    /// north-west, north-east, south-west, south-east.
    #[inline]
    fn corners(&self, index: usize) -> [f32; 4] {
        let w = self.width;
        let (north, south) = (&self.heights[index..index + 2], &self.heights[index + w..index + w + 2]);
        [north[0], north[1], south[0], south[1]]
    }

    /// Height at a spot, bilinear over its cell.
    #[inline]
    fn height(&self, Spot { index, u, v, .. }: Spot) -> f32 {
        let [nw, ne, sw, se] = self.corners(index);
        let (north, south) = (nw + (ne - nw) * u, sw + (se - sw) * u);
        north + (south - north) * v
    }

    /// Height and gradient at a spot, bilinear over its cell.
    #[inline]
    fn sample(&self, Spot { index, u, v, .. }: Spot) -> (f32, f32, f32) {
        let [nw, ne, sw, se] = self.corners(index);
        // Along the north and south edges, then between them: the slope across is the
        // difference of the edges' heights, the slope along blends the edges' slopes.
        let (along_north, along_south) = (ne - nw, se - sw);
        let (north, south) = (nw + along_north * u, sw + along_south * u);
        let gy = south - north;
        (north + gy * v, along_north + (along_south - along_north) * v, gy)
    }

    /// Adds `amount` at a spot, shared bilinearly among its cell's four corners.
    #[inline]
    fn deposit(&mut self, Spot { index, u, v, .. }: Spot, amount: f32) {
        let w = self.width;
        let nw = amount * (1.0 - u) * (1.0 - v);
        let ne = amount * u * (1.0 - v);
        let sw = amount * (1.0 - u) * v;
        // The last corner takes what the others left, so that exactly `amount` is added.
        let se = amount - nw - ne - sw;
        let north = &mut self.heights[index..index + 2];
        north[0] += nw;
        north[1] += ne;
        let south = &mut self.heights[index + w..index + w + 2];
        south[0] += sw;
        south[1] += se;
    }

    /// The highest of the four samples around the spot (no corner of its cell rises above the
    /// water by what settles there while this stays below it).
    #[inline]
    fn highest_corner(&self, Spot { index, .. }: Spot) -> f32 {
        let w = self.width;
        let (north, south) = (&self.heights[index..index + 2], &self.heights[index + w..index + w + 2]);
        at_least(at_least(north[0], north[1]), at_least(south[0], south[1]))
    }

    /// Takes up to `amount` from the cells of the brush around the sample nearest the spot,
    /// never more from a cell than would dig it below `floor`; returns what was taken.
    #[inline]
    fn erode(&mut self, here: Spot, amount: f32, floor: f32, brush: &Brush) -> f32 {
        let (cx, cy) = (here.column + i32::from(here.u >= 0.5), here.row + i32::from(here.v >= 0.5));
        let (w, h) = (self.width as i32, self.height as i32);
        let r = brush.reach;
        let mut taken = 0.0;
        if cx >= r && cy >= r && cx + r < w && cy + r < h {
            // The whole brush is inside the tile (nearly always): its shares are known, and its
            // rows are runs of neighbouring samples.
            let centre = (cy * w + cx) as usize;
            match brush.side {
                1 => return self.erode_square::<1>(centre, &brush.square, amount, floor),
                3 => return self.erode_square::<3>(centre, &brush.square, amount, floor),
                5 => return self.erode_square::<5>(centre, &brush.square, amount, floor),
                7 => return self.erode_square::<7>(centre, &brush.square, amount, floor),
                _ => {}
            }
            for &(offset, ref shares) in &brush.rows {
                let first = centre.wrapping_add_signed(offset);
                let cells = &mut self.heights[first..first + shares.len()];
                for (cell, &share) in cells.iter_mut().zip(shares) {
                    let take = at_most(amount * share, at_least(*cell - floor, 0.0));
                    *cell -= take;
                    taken += take;
                }
            }
            return taken;
        }
        let inside =
            |&&(dx, dy, _): &&(i32, i32, f32)| (0..w).contains(&(cx + dx)) && (0..h).contains(&(cy + dy));
        let total: f32 = brush.cells.iter().filter(inside).map(|c| c.2).sum();
        for &(dx, dy, weight) in brush.cells.iter().filter(inside) {
            let cell = &mut self.heights[((cy + dy) * w + cx + dx) as usize];
            let take = at_most(amount * weight / total, at_least(*cell - floor, 0.0));
            *cell -= take;
            taken += take;
        }
        taken
    }

    /// [`Tile::erode`] with a brush whose cells all lie in the `S` x `S` square around
    /// `centre` (a sample at least `S / 2` from the tile's edges), its `shares` row by row (0 for
    /// a corner outside the brush): rows of a size known here, which the compiler unrolls.
    #[inline(always)]
    fn erode_square<const S: usize>(
        &mut self,
        centre: usize,
        shares: &[f32],
        amount: f32,
        floor: f32,
    ) -> f32 {
        let Ok(rows) = <&[[f32; S]; S]>::try_from(shares.as_chunks::<S>().0) else { return 0.0 };
        let w = self.width;
        let first = centre - (S / 2) * (w + 1);
        let mut taken = 0.0;
        for (r, shares) in rows.iter().enumerate() {
            let start = first + r * w;
            let Some(Ok(cells)) = self.heights.get_mut(start..start + S).map(<&mut [f32; S]>::try_from)
            else {
                continue;
            };
            for (cell, &share) in cells.iter_mut().zip(shares) {
                let take = at_most(amount * share, at_least(*cell - floor, 0.0));
                *cell -= take;
                taken += take;
            }
        }
        taken
    }

    /// One step of droplet `d`: it moves one cell downhill, eroding or depositing at the point it
    /// leaves; below `sea` it only lets a share of its sediment settle ([`SEA_SETTLING`]), and
    /// ends there once it carries none. It stops (leaving its sediment where it is) after its
    /// last step, on flat ground, or at the tile's edge, unless there is a `carried` list and the
    /// edge is inside the grid: then it leaves, onto the list. Returns whether it goes on.
    #[inline(always)]
    fn step(
        &mut self,
        d: &mut Running,
        p: &DropletParams,
        sea: f32,
        brush: &Brush,
        carried: &mut Option<&mut Vec<Carried>>,
    ) -> bool {
        if d.step == d.steps {
            return self.stop(d);
        }
        let (height, gx, gy) = self.sample(d.here);
        let in_sea = height < sea;
        if in_sea && d.state.sediment <= 0.0 {
            return false;
        }
        let s = &mut d.state;
        s.dir_x = s.dir_x * p.inertia - gx * (1.0 - p.inertia);
        s.dir_y = s.dir_y * p.inertia - gy * (1.0 - p.inertia);
        let length = (s.dir_x * s.dir_x + s.dir_y * s.dir_y).sqrt();
        if length.is_nan() || length <= 1e-12 {
            return self.stop(d);
        }
        s.dir_x /= length;
        s.dir_y /= length;
        let (next_x, next_y) = (s.x + s.dir_x, s.y + s.dir_y);
        let (limit_x, limit_y) = self.limit;
        if !(0.0..=limit_x).contains(&next_x) || !(0.0..=limit_y).contains(&next_y) {
            let (gx, gy) = (next_x + self.origin.0 as f32, next_y + self.origin.1 as f32);
            let in_grid = (0.0..=(self.grid.0 - 1) as f32).contains(&gx)
                && (0.0..=(self.grid.1 - 1) as f32).contains(&gy);
            if let (Some(carried), true) = (carried, in_grid) {
                let (ox, oy) = (self.origin.0 as f32, self.origin.1 as f32);
                carried.push(Carried {
                    x: s.x + ox,
                    y: s.y + oy,
                    dir_x: s.dir_x,
                    dir_y: s.dir_y,
                    speed: s.speed,
                    water: s.water,
                    sediment: s.sediment,
                    steps_left: d.steps - d.step,
                });
                return false;
            }
            return self.stop(d);
        }
        let next = self.spot(next_x, next_y);
        if in_sea {
            // In still water a droplet carries nothing more: its sediment settles along the
            // seabed as it goes on down it (a fan off the river's mouth), never raising a sample
            // above the water (what does rise above it later, as a delta grows, is the land's
            // deposits). Left all at the waterline, the sediment of every droplet that reached
            // the sea there made a row of mounds along the coast.
            let amount = at_most(s.sediment * SEA_SETTLING, at_least(sea - self.highest_corner(d.here), 0.0));
            self.deposit(d.here, amount);
            s.sediment -= amount;
            (s.x, s.y, d.here) = (next_x, next_y, next);
            d.step += 1;
            return true;
        }
        let drop = height - self.height(next);
        let capacity = at_least(drop * s.speed * s.water * p.capacity, p.min_capacity);
        if drop < 0.0 {
            // Uphill: fill the dip behind it, with no more than it carries.
            let amount = at_most(s.sediment, -drop);
            self.deposit(d.here, amount);
            s.sediment -= amount;
        } else if s.sediment > capacity {
            let amount = (s.sediment - capacity) * p.deposit_rate;
            self.deposit(d.here, amount);
            s.sediment -= amount;
        } else {
            // Never dig deeper than the point it flows to: no pits of its own making.
            let amount = at_most((capacity - s.sediment) * p.erode_rate, drop);
            s.sediment += self.erode(d.here, amount, height - drop, brush);
        }
        s.speed = at_least(s.speed * s.speed + drop * p.gravity, 0.0).sqrt();
        s.water *= 1.0 - p.evaporation;
        (s.x, s.y, d.here) = (next_x, next_y, next);
        d.step += 1;
        true
    }

    /// Ends droplet `d` where it is, leaving its sediment there; returns false (it does not go on).
    #[inline]
    fn stop(&mut self, d: &Running) -> bool {
        if d.state.sediment > 0.0 {
            self.deposit(d.here, d.state.sediment);
        }
        false
    }
}

/// The share of its sediment a droplet in the sea leaves at each step (the rest settles further
/// on: after 20 steps 1% is left, which it leaves where it stops).
const SEA_SETTLING: f32 = 0.2;

/// Droplets a tile runs at once, a step of each in turn. A droplet's step waits on its last
/// (the ground it eroded), but not on another droplet's, so the processor works on the steps
/// of several at the same time. Running them one after another instead gives other (equally
/// likely) heights, as does another number of lanes.
const LANES: usize = 2;

/// A droplet as it runs: its state, its cell, the steps it has taken and may take.
#[derive(Debug, Clone, Copy)]
struct Running {
    state: State,
    here: Spot,
    step: u32,
    steps: u32,
}

/// Where a point lies in a tile: the sample at its cell's north-west corner, and its offsets
/// from it (0 to 1) along the columns and rows.
#[derive(Debug, Clone, Copy)]
struct Spot {
    index: usize,
    column: i32,
    row: i32,
    u: f32,
    v: f32,
}

/// The larger of `a` and `b`, for numbers that are never NaN (cheaper than `f32::max`, which
/// checks).
#[inline]
fn at_least(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of `a` and `b`, for numbers that are never NaN.
#[inline]
fn at_most(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The cells around a droplet it erodes, weighted by closeness.
struct Brush {
    /// Column and row offsets, and weight.
    cells: Vec<(i32, i32, f32)>,
    /// The radius in whole cells.
    reach: i32,
    /// For a brush wholly inside the tile, its rows from the north: the offset of the row's
    /// first cell from the centre in a tile's samples, and the shares of the whole (all rows'
    /// summing to 1) of the row's cells from the west.
    rows: Vec<(isize, Vec<f32>)>,
    /// Side of the square that holds the brush's cells (`2 x radius - 1`).
    side: usize,
    /// For a brush wholly inside the tile, the shares of the cells of that square, row by row
    /// from the north, west to east (0 where the square's corners are outside the brush).
    square: Vec<f32>,
}

impl Brush {
    /// The brush of `radius` cells for a tile `width` samples wide.
    fn new(radius: u32, width: usize) -> Self {
        let r = radius as i32;
        let mut cells = Vec::new();
        for dy in -r..=r {
            for dx in -r..=r {
                let distance = ((dx * dx + dy * dy) as f32).sqrt();
                if distance < radius as f32 {
                    cells.push((dx, dy, 1.0 - distance / radius as f32));
                }
            }
        }
        let total: f32 = cells.iter().map(|c| c.2).sum();
        // Cells come row by row, west to east, and the cells of a row are contiguous.
        let mut rows: Vec<(i32, isize, Vec<f32>)> = Vec::new();
        for &(dx, dy, weight) in &cells {
            match rows.last_mut() {
                Some((row, _, shares)) if *row == dy => shares.push(weight / total),
                _ => rows.push((dy, dy as isize * width as isize + dx as isize, vec![weight / total])),
            }
        }
        let side = 2 * radius as usize - 1;
        let mut square = vec![0.0; side * side];
        for &(dx, dy, weight) in &cells {
            let (column, row) = ((dx + r - 1) as usize, (dy + r - 1) as usize);
            square[row * side + column] = weight / total;
        }
        let rows = rows.into_iter().map(|(_, offset, shares)| (offset, shares)).collect();
        Self { cells, reach: r, rows, side, square }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cone(side: usize) -> Vec<f32> {
        let c = (side - 1) as f32 / 2.0;
        (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f32 - c, (i / side) as f32 - c);
                40.0 - 0.5 * (x * x + y * y).sqrt() + ((i * 7919 % 13) as f32) * 0.05
            })
            .collect()
    }

    #[test]
    fn droplets_move_soil_without_making_or_losing_any() {
        let side = 96;
        let before = cone(side);
        let mut tile = Tile::new(side, side, before.clone());
        tile.run(20_000, &DropletParams::default(), f32::NEG_INFINITY, &mut SplitMix64::new(3));
        let after = tile.into_heights();
        let sum = |v: &[f32]| v.iter().map(|&h| f64::from(h)).sum::<f64>();
        let moved: f64 = before.iter().zip(&after).map(|(a, b)| f64::from((a - b).abs())).sum();
        assert!(moved > 100.0, "the droplets moved {moved}");
        let change = (sum(&after) - sum(&before)).abs();
        assert!(change < 1e-4 * moved, "mass changed by {change} of {moved} moved");
    }

    #[test]
    fn droplets_leaving_a_tile_inside_the_grid_are_handed_on_with_their_sediment() {
        // A grid of 64 x 16 falling toward +x; a tile of its first 32 columns.
        let (columns, rows) = (64u32, 16u32);
        let grid: Vec<f32> = (0..columns * rows).map(|i| 100.0 - (i % columns) as f32 * 0.8).collect();
        let mut tile = Tile::copy_from(&grid, (columns, rows), 0, 0, 32, rows);
        let before: f64 = tile.heights.iter().map(|&h| f64::from(h)).sum();
        let carried = tile.run(200, &DropletParams::default(), f32::NEG_INFINITY, &mut SplitMix64::new(7));
        assert!(carried.len() > 150, "{} handed on", carried.len());
        assert!(carried.iter().all(|d| d.x >= 30.0 && d.x <= 31.0 && d.steps_left > 0), "{carried:?}");
        // What the tile lost, the handed-on droplets carry.
        let after: f64 = tile.heights.iter().map(|&h| f64::from(h)).sum();
        let carried_soil: f64 = carried.iter().map(|d| f64::from(d.sediment)).sum();
        assert!(carried_soil > 0.0);
        assert!(
            (before - after - carried_soil).abs() < 1e-3 * carried_soil,
            "{before} {after} {carried_soil}"
        );
        // The tile of the grid's last 32 columns takes them on, and they stop at the grid's edge.
        let mut next = Tile::copy_from(&grid, (columns, rows), 30, 0, 34, rows);
        let start: f64 = next.heights.iter().map(|&h| f64::from(h)).sum();
        next.resume(&carried, &DropletParams::default(), f32::NEG_INFINITY);
        let end: f64 = next.heights.iter().map(|&h| f64::from(h)).sum();
        assert!((end - start - carried_soil).abs() < 1e-3 * carried_soil, "{start} {end} {carried_soil}");
        // A tile that is the whole grid hands nothing on.
        let mut whole = Tile::new(columns as usize, rows as usize, grid);
        assert!(
            whole.run(200, &DropletParams::default(), f32::NEG_INFINITY, &mut SplitMix64::new(7)).is_empty()
        );
    }

    #[test]
    fn droplets_end_at_the_sea() {
        // A slope wholly under the sea: droplets end where they start, carrying nothing.
        let heights: Vec<f32> = (0..32 * 32).map(|i| 10.0 - (i % 32) as f32 * 0.5).collect();
        let mut tile = Tile::new(32, 32, heights.clone());
        tile.run(500, &DropletParams::default(), 20.0, &mut SplitMix64::new(2));
        assert_eq!(tile.into_heights(), heights);
        // Above it, they erode.
        let mut tile = Tile::new(32, 32, heights.clone());
        tile.run(500, &DropletParams::default(), -100.0, &mut SplitMix64::new(2));
        assert_ne!(tile.into_heights(), heights);
    }

    #[test]
    fn sediment_settles_offshore() {
        // A slope running down into the sea at height 0 (columns 0..40 land, the rest sea), with
        // a little relief so that droplets gather: what they carry to the sea settles over the
        // seabed, spread offshore, and no soil is made or lost. (Dropped at the waterline as
        // each droplet reached the sea, the same run raised 572 seabed samples, none beyond
        // column 53, and piled a row of mounds along the coast.)
        let side = 64;
        let heights: Vec<f32> = (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f32, (i / side) as f32);
                20.0 - x * 0.5 + 0.3 * (x * 0.7).sin() * (y * 0.9).cos()
            })
            .collect();
        let mut tile = Tile::new(side, side, heights.clone());
        tile.run(4000, &DropletParams::default(), 0.0, &mut SplitMix64::new(7));
        let after = tile.into_heights();
        let total = |h: &[f32]| h.iter().map(|&v| v as f64).sum::<f64>();
        assert!((total(&after) - total(&heights)).abs() < 1e-2 * side as f64, "soil made or lost");
        let (mut raised, mut furthest) = (0, 0);
        for (i, (&a, &b)) in after.iter().zip(&heights).enumerate() {
            if b < -1.0 && a > b + 1e-4 {
                raised += 1;
                furthest = furthest.max(i % side);
            }
        }
        assert!(raised > 900, "only {raised} seabed samples got sediment");
        assert!(furthest >= 58, "sediment stops at column {furthest}");
    }

    #[test]
    fn a_flat_tile_stays_flat() {
        let mut tile = Tile::new(16, 16, vec![5.0; 256]);
        tile.run(1000, &DropletParams::default(), f32::NEG_INFINITY, &mut SplitMix64::new(1));
        assert!(tile.into_heights().iter().all(|&h| h == 5.0));
    }
}
