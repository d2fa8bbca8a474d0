//! Flow accumulation (D8): every sample drains to its steepest lower neighbour, and a sample's
//! flow is the number of samples (itself included) whose water passes through it. Channels are
//! where it is large.

use rayon::prelude::*;

/// The flow accumulation of `heights` (`columns` x `rows`, row by row), in samples. Samples with
/// no lower neighbour (pits, flats, the lowest edge) keep what reaches them. Ties in height are
/// broken by index, so the result is the same at any thread count.
pub fn accumulation(heights: &[f32], columns: u32, rows: u32) -> Vec<f32> {
    let (w, h) = (columns as isize, rows as isize);
    let receiver: Vec<u32> = (0..heights.len())
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i as isize) % w, (i as isize) / w);
            let here = heights[i];
            let (mut best, mut target) = (0.0f32, i as u32);
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    let (nx, ny) = (x + dx, y + dy);
                    if (dx, dy) == (0, 0) || !(0..w).contains(&nx) || !(0..h).contains(&ny) {
                        continue;
                    }
                    let j = (ny * w + nx) as usize;
                    let distance = if dx != 0 && dy != 0 { std::f32::consts::SQRT_2 } else { 1.0 };
                    let slope = (here - heights[j]) / distance;
                    if slope > best {
                        (best, target) = (slope, j as u32);
                    }
                }
            }
            target
        })
        .collect();
    // Highest first: a sample's flow is complete before it is passed on.
    let mut order: Vec<u32> = (0..heights.len() as u32).collect();
    order.par_sort_unstable_by(|&a, &b| heights[b as usize].total_cmp(&heights[a as usize]).then(a.cmp(&b)));
    let mut flow = vec![1.0f32; heights.len()];
    for &i in &order {
        let target = receiver[i as usize];
        if target != i {
            flow[target as usize] += flow[i as usize];
        }
    }
    flow
}

/// The share of samples (0 to 1) whose flow accumulation exceeds `threshold` samples.
pub fn channel_share(flow: &[f32], threshold: f32) -> f64 {
    flow.iter().filter(|&&f| f > threshold).count() as f64 / flow.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_drains_along_its_fall() {
        // 3 columns, 4 rows, falling toward the last row.
        let heights: Vec<f32> = (0..12).map(|i| 10.0 - (i / 3) as f32).collect();
        let flow = accumulation(&heights, 3, 4);
        assert_eq!(&flow[0..3], &[1.0, 1.0, 1.0]);
        assert_eq!(&flow[9..12], &[4.0, 4.0, 4.0]);
        assert_eq!(flow.iter().sum::<f32>(), 1.0 * 3.0 + 2.0 * 3.0 + 3.0 * 3.0 + 4.0 * 3.0);
        assert!((channel_share(&flow, 2.5) - 0.5).abs() < 1e-12);
    }
}
