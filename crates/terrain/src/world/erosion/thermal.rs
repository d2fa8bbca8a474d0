//! Thermal erosion: where the ground between two neighbours is steeper than the talus slope,
//! part of the excess slides down. One pass reads one buffer and writes another (each sample's
//! new height is gathered from its own and its neighbours' old heights), so the result cannot
//! depend on the order the rows run in.
//!
//! Heights in cell units (divided by the cell size): the slope to a side neighbour is the height
//! difference, to a diagonal one the difference over sqrt 2.

use rayon::prelude::*;

/// The eight neighbours: column and row offsets, and distance.
const NEIGHBOURS: [(isize, isize, f32); 8] = [
    (-1, -1, std::f32::consts::SQRT_2),
    (0, -1, 1.0),
    (1, -1, std::f32::consts::SQRT_2),
    (-1, 0, 1.0),
    (1, 0, 1.0),
    (-1, 1, std::f32::consts::SQRT_2),
    (0, 1, 1.0),
    (1, 1, std::f32::consts::SQRT_2),
];

/// Height above the talus slope of sample `from` over its neighbour `to`, `distance` apart.
fn excess(from: f32, to: f32, distance: f32, talus: f32) -> f32 {
    (from - to - talus * distance).max(0.0)
}

/// One pass over `heights` (`columns` x `rows`, cell units) into `out`, with `moves` as scratch:
/// each sample gives `rate` times half its largest excess over the talus slope `talus` (a
/// tangent), shared among its lower neighbours in proportion to their excess.
pub fn pass(
    heights: &[f32],
    out: &mut [f32],
    moves: &mut [(f32, f32)],
    columns: u32,
    rows: u32,
    talus: f32,
    rate: f32,
) {
    let (w, h) = (columns as isize, rows as isize);
    let at = |x: isize, y: isize| heights[(y * w + x) as usize];
    // What each sample gives, and the sum of its neighbours' excesses.
    moves.par_chunks_mut(columns as usize).enumerate().for_each(|(y, row)| {
        let y = y as isize;
        for (x, slot) in row.iter_mut().enumerate() {
            let x = x as isize;
            let here = at(x, y);
            let (mut largest, mut sum) = (0.0f32, 0.0f32);
            for &(dx, dy, distance) in &NEIGHBOURS {
                let (nx, ny) = (x + dx, y + dy);
                if (0..w).contains(&nx) && (0..h).contains(&ny) {
                    let e = excess(here, at(nx, ny), distance, talus);
                    largest = largest.max(e);
                    sum += e;
                }
            }
            *slot = (rate * 0.5 * largest, sum);
        }
    });
    let moves: &[(f32, f32)] = moves;
    out.par_chunks_mut(columns as usize).enumerate().for_each(|(y, row)| {
        let y = y as isize;
        for (x, slot) in row.iter_mut().enumerate() {
            let x = x as isize;
            let here = at(x, y);
            let mut new = here - moves[(y * w + x) as usize].0;
            for &(dx, dy, distance) in &NEIGHBOURS {
                let (nx, ny) = (x + dx, y + dy);
                if (0..w).contains(&nx) && (0..h).contains(&ny) {
                    let (give, sum) = moves[(ny * w + nx) as usize];
                    if give > 0.0 {
                        let e = excess(at(nx, ny), here, distance, talus);
                        new += give * e / sum;
                    }
                }
            }
            *slot = new;
        }
    });
}

/// The largest slope of `heights` (cell units) between neighbours, as a tangent.
pub fn steepest(heights: &[f32], columns: u32, rows: u32) -> f32 {
    let (w, h) = (columns as isize, rows as isize);
    let mut steepest = 0.0f32;
    for y in 0..h {
        for x in 0..w {
            let here = heights[(y * w + x) as usize];
            for &(dx, dy, distance) in &NEIGHBOURS {
                let (nx, ny) = (x + dx, y + dy);
                if (0..w).contains(&nx) && (0..h).contains(&ny) {
                    steepest = steepest.max((here - heights[(ny * w + nx) as usize]).abs() / distance);
                }
            }
        }
    }
    steepest
}
