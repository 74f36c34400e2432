//! Which hair models can shadow a workgroup's pixels (ours, not the talk's).
//!
//! Every skin pixel marches every model's grid towards each light and along
//! its normal; in the crowd that is 28 grids per ray, almost all missed. A
//! workgroup first bounds its pixels' world positions with a box, then keeps
//! the models a ray from anywhere in that box can reach:
//!
//! - a directional light: the ray from the box centre `c` along `dir` hits
//!   the model's box grown by the tile box's half extent `h` (a point
//!   `c + o`, `|o| ≤ h`, reaches box `B` exactly when `c` reaches `B ⊕ h`,
//!   the Minkowski sum);
//! - a point light: the segments from the box to the light lie in the
//!   bounding box of the tile box and the light;
//! - ambient occlusion: the model's box grown by `ao_distance` meets the tile box.
//!
//! The test is conservative (boxes grow by [`MARGIN`] more, so rounding in
//! the per-pixel slab test cannot reach a model the tile dropped): the mask
//! is the same bits with or without it.

use super::super::density::Grid;
use crate::layout::LightData;
use glam::Vec3;

/// Metres every box grows by before the tile test.
pub const MARGIN: f32 = 1e-3;

/// Models a workgroup's mask can name; models past it are always marched.
pub const MASKED_MODELS: usize = 256;

/// An f32 as a u32 that orders like the float (for atomicMin/Max on floats).
pub fn ordered(f: f32) -> u32 {
    let b = f.to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

/// The inverse of [`ordered`].
pub fn unordered(u: u32) -> f32 {
    if u >> 31 == 1 {
        f32::from_bits(u & 0x7FFF_FFFF)
    } else {
        f32::from_bits(!u)
    }
}

/// The world box of a workgroup's surface points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileBox {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl TileBox {
    /// The box of `points`, `None` when there are none: min and max of the
    /// [`ordered`] bits, as the WGSL's workgroup atomics take them.
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Option<Self> {
        let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
        let mut any = false;
        for p in points {
            any = true;
            for a in 0..3 {
                lo[a] = lo[a].min(ordered(p[a]));
                hi[a] = hi[a].max(ordered(p[a]));
            }
        }
        any.then(|| Self {
            lo: Vec3::from(lo.map(unordered)),
            hi: Vec3::from(hi.map(unordered)),
        })
    }

    /// Whether a shadow or AO ray from any point of the box can enter `g`.
    pub fn reaches(&self, g: &Grid, lights: &[LightData], ao_distance: Option<f32>) -> bool {
        let (gmin, gsize) = (Vec3::from(g.min), Vec3::from(g.size));
        let (lo, hi) = (gmin - MARGIN, gmin + gsize + MARGIN);
        if let Some(d) = ao_distance
            && overlap(self.lo, self.hi, lo - d, hi + d)
        {
            return true;
        }
        lights.iter().any(|l| {
            let [x, y, z, kind] = l.position_or_direction;
            if kind == 0.0 {
                let dir = -Vec3::new(x, y, z).normalize_or_zero();
                let (c, h) = ((self.lo + self.hi) * 0.5, (self.hi - self.lo) * 0.5);
                slab(c, dir, lo - h, hi + h)
            } else {
                let light = Vec3::new(x, y, z);
                overlap(self.lo.min(light), self.hi.max(light), lo, hi)
            }
        })
    }
}

fn overlap(alo: Vec3, ahi: Vec3, blo: Vec3, bhi: Vec3) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

/// Whether the ray `p + t·dir`, `t ≥ 0`, meets the box [lo, hi] (a zero
/// direction: whether `p` is inside).
fn slab(p: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let (mut enter, mut exit) = (0.0f32, f32::MAX);
    for a in 0..3 {
        if dir[a].abs() > 1e-8 {
            let (t0, t1) = ((lo[a] - p[a]) / dir[a], (hi[a] - p[a]) / dir[a]);
            enter = enter.max(t0.min(t1));
            exit = exit.min(t0.max(t1));
        } else if p[a] < lo[a] || p[a] > hi[a] {
            return false;
        }
    }
    enter <= exit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_bits_sort_like_the_floats() {
        let v = [-3.5f32, -1e-30, -0.0, 0.0, 1e-30, 2.0, f32::MAX];
        for w in v.windows(2) {
            assert!(ordered(w[0]) <= ordered(w[1]), "{w:?}");
        }
        for f in v {
            assert_eq!(unordered(ordered(f)).to_bits(), f.to_bits());
        }
    }

    fn sun(d: Vec3) -> LightData {
        LightData {
            position_or_direction: [d.x, d.y, d.z, 0.0],
            radiance: [1.0; 4],
            _pad: [0; 8],
        }
    }

    #[test]
    fn a_tile_reaches_the_grids_its_rays_can_enter() {
        let g = Grid {
            min: [-0.5, 1.0, -0.5],
            size: [1.0, 1.0, 1.0],
            resolution: 48,
        };
        // A floor tile under the grid, beside it, and far away.
        let tile = |x: f32| TileBox {
            lo: Vec3::new(x - 0.1, 0.0, -0.1),
            hi: Vec3::new(x + 0.1, 0.0, 0.1),
        };
        let down = [sun(Vec3::NEG_Y)];
        assert!(tile(0.0).reaches(&g, &down, None));
        assert!(!tile(3.0).reaches(&g, &down, None));
        // Light slanting from +x: the tile at x = -2 is in the shadow.
        let slant = [sun(Vec3::new(-1.0, -1.0, 0.0))];
        assert!(tile(-1.5).reaches(&g, &slant, None));
        assert!(!tile(1.5).reaches(&g, &slant, None));
        // Light from below: nothing above shadows the floor.
        assert!(!tile(0.0).reaches(&g, &[sun(Vec3::Y)], None));
        // AO reaches 5 cm: the floor is 1 m under the grid.
        assert!(!tile(0.0).reaches(&g, &[], Some(0.05)));
        assert!(tile(0.0).reaches(&g, &[], Some(1.01)));
        // A point light above the grid: segments from the floor cross it.
        let mut lamp = sun(Vec3::ZERO);
        lamp.position_or_direction = [0.0, 3.0, 0.0, 1.0];
        assert!(tile(0.0).reaches(&g, &[lamp], None));
        lamp.position_or_direction = [5.0, 0.5, 0.0, 1.0];
        assert!(!tile(0.0).reaches(&g, &[lamp], None));
    }
}
