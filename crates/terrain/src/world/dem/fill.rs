//! Filling voids (nodata samples) from their neighbours, deterministically.

/// Fills the `NaN` samples of a `columns` x `rows` grid from their neighbours, front by front:
/// each void next to known samples takes the mean of its known neighbours (of the eight around
/// it, weighting the four edge neighbours twice as much as the corners), where "known" means known
/// before this front, so the result does not depend on any order. Returns the filled grid and the
/// mask of the voids (`true` where a sample was filled), or `None` when every sample is a void.
pub fn fill_voids(columns: u32, rows: u32, mut heights: Vec<f32>) -> Option<(Vec<f32>, Vec<bool>)> {
    let (w, h) = (columns as usize, rows as usize);
    debug_assert_eq!(heights.len(), w * h);
    let voids: Vec<bool> = heights.iter().map(|v| !v.is_finite()).collect();
    let void_count = voids.iter().filter(|&&v| v).count();
    if void_count == 0 {
        return Some((heights, voids));
    }
    if void_count == heights.len() {
        return None;
    }
    let mut known: Vec<bool> = voids.iter().map(|&v| !v).collect();
    let neighbours = |index: usize| {
        let (x, y) = ((index % w) as isize, (index / w) as isize);
        const OFFSETS: [(isize, isize, f32); 8] = [
            (-1, 0, 2.0),
            (1, 0, 2.0),
            (0, -1, 2.0),
            (0, 1, 2.0),
            (-1, -1, 1.0),
            (1, -1, 1.0),
            (-1, 1, 1.0),
            (1, 1, 1.0),
        ];
        OFFSETS.into_iter().filter_map(move |(dx, dy, weight)| {
            let (nx, ny) = (x + dx, y + dy);
            (nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h)
                .then(|| (ny as usize * w + nx as usize, weight))
        })
    };
    // The first front: voids touching a known sample, in index order.
    let mut queued = vec![false; heights.len()];
    let mut front: Vec<usize> = Vec::new();
    for index in 0..heights.len() {
        if !known[index] && neighbours(index).any(|(n, _)| known[n]) {
            queued[index] = true;
            front.push(index);
        }
    }
    let mut values = Vec::new();
    while !front.is_empty() {
        values.clear();
        values.extend(front.iter().map(|&index| {
            let (sum, weight) =
                neighbours(index).filter(|&(n, _)| known[n]).fold((0.0f64, 0.0f64), |(s, t), (n, wgt)| {
                    (s + f64::from(heights[n]) * f64::from(wgt), t + f64::from(wgt))
                });
            (sum / weight) as f32
        }));
        for (&index, &value) in front.iter().zip(&values) {
            heights[index] = value;
            known[index] = true;
        }
        let mut next = Vec::new();
        for &index in &front {
            for (n, _) in neighbours(index) {
                if !known[n] && !queued[n] {
                    queued[n] = true;
                    next.push(n);
                }
            }
        }
        next.sort_unstable();
        front = next;
    }
    Some((heights, voids))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_void_takes_its_neighbours_mean() {
        let nan = f32::NAN;
        let (filled, mask) =
            fill_voids(3, 3, vec![1.0, 1.0, 1.0, 1.0, nan, 1.0, 1.0, 1.0, 13.0]).expect("some data");
        // Edge neighbours 1 (weight 2 each), corners 1, 1, 1 and 13 (weight 1 each).
        assert!((filled[4] - (8.0 + 16.0) / 12.0).abs() < 1e-6, "{}", filled[4]);
        assert_eq!(mask, vec![false, false, false, false, true, false, false, false, false]);
    }

    #[test]
    fn large_voids_fill_from_their_edges_without_spikes() {
        let mut heights: Vec<f32> = (0..100).map(|i| 100.0 + (i % 10) as f32).collect();
        for y in 2..8 {
            for x in 0..6 {
                heights[y * 10 + x] = f32::NAN;
            }
        }
        let (filled, mask) = fill_voids(10, 10, heights).expect("some data");
        assert_eq!(mask.iter().filter(|&&m| m).count(), 36);
        assert!(filled.iter().all(|h| (100.0..=109.0).contains(h)), "{filled:?}");
    }

    #[test]
    fn all_voids_is_none() {
        assert!(fill_voids(2, 2, vec![f32::NAN; 4]).is_none());
    }
}
