//! Flow accumulation (D8): every sample drains to its steepest lower neighbour, and a sample's
//! flow is the number of samples (itself included) whose water passes through it. Channels are
//! where it is large.

use rayon::prelude::*;

/// The flow accumulation of `heights` (`columns` x `rows`, row by row), in samples. Samples with
/// no lower neighbour (pits, flats, the lowest edge) keep what reaches them. The result is the
/// same at any thread count.
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
    // A sample passes its flow on once every sample draining into it has passed on theirs (a
    // sample drains only to a lower one, so there are no cycles): no sorting by height. The
    // flows are whole numbers of samples, exact in f32 (below 2^24), so the order of the sums
    // cannot change them.
    let mut donors = vec![0u8; heights.len()];
    for (i, &target) in receiver.iter().enumerate() {
        if target as usize != i {
            donors[target as usize] += 1;
        }
    }
    let mut ready: Vec<u32> = (0..heights.len() as u32).filter(|&i| donors[i as usize] == 0).collect();
    let mut flow = vec![1.0f32; heights.len()];
    while let Some(i) = ready.pop() {
        let target = receiver[i as usize];
        if target != i {
            flow[target as usize] += flow[i as usize];
            donors[target as usize] -= 1;
            if donors[target as usize] == 0 {
                ready.push(target);
            }
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

    #[test]
    fn the_same_flow_as_passing_it_on_from_the_highest_sample_down() {
        // Bumpy ground with pits, ridges, flats and equal heights.
        let (columns, rows) = (61u32, 47u32);
        let heights: Vec<f32> = (0..columns * rows)
            .map(|i| {
                let (x, y) = ((i % columns) as f32, (i / columns) as f32);
                ((x * 0.37).sin() * 3.0 + (y * 0.23).cos() * 4.0 + (x * y * 0.01).sin() - y * 0.1).round()
            })
            .collect();
        let flow = accumulation(&heights, columns, rows);
        // The reference: every sample in order of height, highest first, hands its flow on.
        let receiver: Vec<u32> = (0..heights.len())
            .map(|i| {
                let (w, h) = (columns as isize, rows as isize);
                let (x, y) = ((i as isize) % w, (i as isize) / w);
                let (mut best, mut target) = (0.0f32, i as u32);
                for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1isize).map(move |dx| (dx, dy))) {
                    let (nx, ny) = (x + dx, y + dy);
                    if (dx, dy) != (0, 0) && (0..w).contains(&nx) && (0..h).contains(&ny) {
                        let j = (ny * w + nx) as usize;
                        let distance = if dx != 0 && dy != 0 { std::f32::consts::SQRT_2 } else { 1.0 };
                        let slope = (heights[i] - heights[j]) / distance;
                        if slope > best {
                            (best, target) = (slope, j as u32);
                        }
                    }
                }
                target
            })
            .collect();
        let mut order: Vec<usize> = (0..heights.len()).collect();
        order.sort_by(|&a, &b| heights[b].total_cmp(&heights[a]).then(a.cmp(&b)));
        let mut expected = vec![1.0f32; heights.len()];
        for i in order {
            if receiver[i] as usize != i {
                expected[receiver[i] as usize] += expected[i];
            }
        }
        assert_eq!(flow, expected);
        assert!(flow.iter().any(|&f| f > 50.0), "no channels in the test ground");
    }
}
