//! Which lane rasterizes which segment, as the WGSL assigns them.
//!
//! Kulikov: "sort according to Morton curve within each group". The WGSL's
//! `morton_sort` is a counting sort in workgroup memory: 256 buckets over
//! the group's key range, a lane's rank within its bucket from an
//! `atomicAdd` (here: invocation order, one order the GPU may produce), and
//! the valid segments packed to the front, so idle lanes gather in the last
//! subgroups. Without it every invocation keeps its own segment and one
//! that projects to nothing leaves an idle lane in its subgroup.

use super::GROUP;

/// Morton code of a point (16 bits per axis, x in the even bits).
pub fn morton(x: u32, y: u32) -> u32 {
    let spread = |mut v: u32| {
        v &= 0xFFFF;
        v = (v | (v << 8)) & 0x00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// The WGSL's bucket of `key` among keys `lo..=hi`: 256 buckets, the span
/// shifted down to 8 bits when it needs more.
pub fn bucket(key: u32, lo: u32, hi: u32) -> u32 {
    let span = hi - lo;
    let shift = if span >= GROUP {
        // firstLeadingBit(span) + 1 - 8
        32 - span.leading_zeros() - 8
    } else {
        0
    };
    (key - lo) >> shift
}

/// The workgroup's lanes after the counting sort: valid segments by bucket,
/// in invocation order within one, then the idle lanes.
pub fn morton_sort<T>(lanes: Vec<Option<T>>, key: impl Fn(&T) -> u32) -> Vec<Option<T>> {
    let keys = lanes.iter().flatten().map(&key);
    let (lo, hi) = keys.fold((u32::MAX, 0), |(lo, hi), k| (lo.min(k), hi.max(k)));
    let n = lanes.len();
    let mut valid: Vec<T> = lanes.into_iter().flatten().collect();
    // A stable sort: equal buckets keep invocation order.
    valid.sort_by_key(|l| bucket(key(l), lo, hi));
    let mut out: Vec<Option<T>> = valid.into_iter().map(Some).collect();
    out.resize_with(n, || None);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_cover_the_range_in_256() {
        assert_eq!(bucket(300, 100, 355), 200);
        assert_eq!(bucket(355, 100, 356), 127);
        assert_eq!(bucket(u32::MAX, 0, u32::MAX), 255);
        assert_eq!(bucket(7, 7, 7), 0);
    }

    #[test]
    fn sort_packs_valid_lanes_by_bucket_keeping_order_within_one() {
        // Span 1000: shift 2, so keys 0..3 share a bucket.
        let lanes = vec![Some(1000), None, Some(3), Some(0), None, Some(2)];
        let sorted = morton_sort(lanes, |k| *k);
        assert_eq!(
            sorted,
            vec![Some(3), Some(0), Some(2), Some(1000), None, None]
        );
    }
}
