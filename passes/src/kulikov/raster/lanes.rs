//! Lane utilisation of the rasterization loop, as a GPU would execute it.
//!
//! Kulikov, "Divergence": "Only 45% of lanes are active on average ... Nested
//! loops with divergent bounds". A subgroup runs in lock step: with nested
//! loops every column costs as many steps as the lane with the tallest slice
//! of that column; flattened, the subgroup costs as many steps as its lane
//! with the most pixels. The CPU kernel computes the schedule from each
//! lane's column heights and counts active lanes per step.

/// `(active lane-steps, total lane-steps)` of one subgroup of `width` lanes;
/// `heights[lane][column]` is the number of pixels the lane visits in that column.
pub fn utilisation(heights: &[Vec<u32>], width: usize, flattened: bool) -> (u64, u64) {
    if flattened {
        let totals: Vec<u64> = heights
            .iter()
            .map(|h| h.iter().map(|&x| u64::from(x)).sum())
            .collect();
        let steps = totals.iter().copied().max().unwrap_or(0);
        (totals.iter().sum(), steps * width as u64)
    } else {
        let columns = heights.iter().map(Vec::len).max().unwrap_or(0);
        let (mut active, mut steps) = (0u64, 0u64);
        for k in 0..columns {
            let col: Vec<u64> = heights
                .iter()
                .map(|h| u64::from(h.get(k).copied().unwrap_or(0)))
                .collect();
            // A column costs at least one step (the loop test) while any lane is still in it.
            let lanes_here = heights.iter().filter(|h| h.len() > k).count() as u64;
            let tallest = col
                .iter()
                .copied()
                .max()
                .unwrap_or(0)
                .max(u64::from(lanes_here > 0));
            steps += tallest;
            active += col.iter().sum::<u64>();
        }
        (active, steps * width as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flattening_removes_slope_divergence() {
        // Two lanes: one steep (tall columns), one shallow (short columns), same pixel count.
        let lanes = vec![vec![4, 4], vec![1, 1, 1, 1, 1, 1, 1, 1]];
        let (a_n, t_n) = utilisation(&lanes, 2, false);
        let (a_f, t_f) = utilisation(&lanes, 2, true);
        assert_eq!((a_n, a_f), (16, 16));
        assert_eq!(t_n, 2 * (4 + 4 + 6));
        assert_eq!(t_f, 2 * 8);
        assert!(a_f as f64 / t_f as f64 > a_n as f64 / t_n as f64);
    }
}
