//! Subgroup operations emulated over explicit lanes.
//!
//! A CPU kernel runs a subgroup's lanes as arrays indexed by lane, with an
//! active mask where control flow diverges. These helpers give the results
//! the WGSL built-ins give (`subgroupExclusiveAdd`, `subgroupBallot`, ...).

/// `subgroupAdd` over active lanes.
pub fn add(values: &[u32], active: &[bool]) -> u32 {
    values
        .iter()
        .zip(active)
        .filter(|(_, a)| **a)
        .map(|(v, _)| *v)
        .fold(0u32, u32::wrapping_add)
}

/// `subgroupExclusiveAdd`: per lane, the sum over active lanes below it.
pub fn exclusive_add(values: &[u32], active: &[bool]) -> Vec<u32> {
    let mut sum = 0u32;
    values
        .iter()
        .zip(active)
        .map(|(v, a)| {
            let before = sum;
            if *a {
                sum = sum.wrapping_add(*v);
            }
            before
        })
        .collect()
}

/// `subgroupMax` over active lanes (0 when none is active).
pub fn max(values: &[u32], active: &[bool]) -> u32 {
    values
        .iter()
        .zip(active)
        .filter(|(_, a)| **a)
        .map(|(v, _)| *v)
        .max()
        .unwrap_or(0)
}

/// `subgroupElect`: the lowest active lane.
pub fn elect(active: &[bool]) -> Option<usize> {
    active.iter().position(|a| *a)
}

/// Number of active lanes (`WaveActiveCountBits(true)`).
pub fn count(active: &[bool]) -> u32 {
    active.iter().filter(|a| **a).count() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scans_skip_inactive_lanes() {
        let v = [1, 2, 3, 4];
        let a = [true, false, true, true];
        assert_eq!(add(&v, &a), 8);
        assert_eq!(exclusive_add(&v, &a), vec![0, 1, 1, 4]);
        assert_eq!(max(&v, &a), 4);
        assert_eq!(elect(&[false, true, true]), Some(1));
        assert_eq!(count(&a), 3);
    }
}
