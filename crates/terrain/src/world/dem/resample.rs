//! Resampling a grid of heights to another size (square cells, `--max-size`).

/// Resamples a `columns` x `rows` grid to `new_columns` x `new_rows`, sample centres aligned
/// (the grids cover the same footprint). Where a side shrinks, each new sample is the mean of the
/// source samples under its cell (a box filter, so no detail aliases); where it grows, it is
/// interpolated linearly. The two directions are done one after the other.
pub fn resample(columns: u32, rows: u32, heights: &[f32], new_columns: u32, new_rows: u32) -> Vec<f32> {
    let (w, h) = (columns as usize, rows as usize);
    let (nw, nh) = (new_columns as usize, new_rows as usize);
    // Along rows (x) first.
    let x_weights = weights(w, nw);
    let mut across = vec![0.0f32; nw * h];
    for (out_row, in_row) in across.chunks_mut(nw).zip(heights.chunks(w)) {
        for (out, taps) in out_row.iter_mut().zip(&x_weights) {
            *out = taps.iter().map(|&(i, wt)| f64::from(in_row[i]) * wt).sum::<f64>() as f32;
        }
    }
    let y_weights = weights(h, nh);
    let mut out = vec![0.0f32; nw * nh];
    for (y, taps) in y_weights.iter().enumerate() {
        let row = &mut out[y * nw..(y + 1) * nw];
        for (x, value) in row.iter_mut().enumerate() {
            *value = taps.iter().map(|&(i, wt)| f64::from(across[i * nw + x]) * wt).sum::<f64>() as f32;
        }
    }
    out
}

/// The void mask resampled as [`resample`] resamples heights: a new sample is a void where more
/// than half of what it is made of was.
pub fn resample_mask(columns: u32, rows: u32, mask: &[bool], new_columns: u32, new_rows: u32) -> Vec<bool> {
    let as_numbers: Vec<f32> = mask.iter().map(|&m| if m { 1.0 } else { 0.0 }).collect();
    resample(columns, rows, &as_numbers, new_columns, new_rows).into_iter().map(|v| v > 0.5).collect()
}

/// For each of `n` new samples along a side of `old` samples, the source samples and their
/// weights (summing to 1).
fn weights(old: usize, n: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = old as f64 / n as f64;
    (0..n)
        .map(|i| {
            if scale > 1.0 {
                // Box: the source cells under [i * scale, (i + 1) * scale).
                let (start, end) = (i as f64 * scale, (i as f64 + 1.0) * scale);
                let first = start.floor() as usize;
                let last = (end.ceil() as usize).min(old);
                (first..last)
                    .map(|j| {
                        let overlap = (end.min(j as f64 + 1.0) - start.max(j as f64)).max(0.0);
                        (j, overlap / scale)
                    })
                    .filter(|&(_, wt)| wt > 0.0)
                    .collect()
            } else {
                // Linear between the two nearest source centres.
                let centre = ((i as f64 + 0.5) * scale - 0.5).clamp(0.0, (old - 1) as f64);
                let j = (centre.floor() as usize).min(old.saturating_sub(2));
                let t = centre - j as f64;
                if old == 1 { vec![(0, 1.0)] } else { vec![(j, 1.0 - t), (j + 1, t)] }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_size_is_identity_and_halving_averages() {
        let grid: Vec<f32> = (0..16).map(|i| i as f32).collect();
        assert_eq!(resample(4, 4, &grid, 4, 4), grid);
        let half = resample(4, 4, &grid, 2, 2);
        assert_eq!(half, vec![2.5, 4.5, 10.5, 12.5]);
    }

    #[test]
    fn growing_interpolates_between_centres() {
        let grown = resample(2, 2, &[0.0, 10.0, 0.0, 10.0], 4, 2);
        assert_eq!(grown, vec![0.0, 2.5, 7.5, 10.0, 0.0, 2.5, 7.5, 10.0]);
    }
}
