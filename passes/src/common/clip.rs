//! Near-plane clipping of a segment in clip space, shared by every strand
//! pipeline (WGSL: `near_clip` in `shaders/common/clip.wgsl`).
//!
//! A camera a few centimetres from a face puts strands across the near
//! plane. Dropping them leaves holes right where the viewer looks, so each
//! pipeline draws the part in front, as a GPU's clipper does for a triangle
//! edge: clip space is linear along the segment, so the cut is the lerp at
//! the parameter where `w` reaches `near` (for `perspective_rh`, Vulkan's
//! `z = 0` clip plane).

/// The part of a segment in front of the near plane: its clip-space ends
/// and their parameters along the original segment (0 at `c0`, 1 at `c1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearClipped {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub ta: f32,
    pub tb: f32,
}

impl NearClipped {
    /// An attribute that is `v0` at `c0` and `v1` at `c1` (linear in clip
    /// space), at the clipped part's two ends. An end that was not cut keeps
    /// its value bit for bit.
    pub fn ends(&self, v0: f32, v1: f32) -> [f32; 2] {
        [at(v0, v1, self.ta), at(v0, v1, self.tb)]
    }
}

/// `v0 + t (v1 - v0)`, exact at `t = 0` and `t = 1`.
pub fn at(v0: f32, v1: f32, t: f32) -> f32 {
    if t == 0.0 {
        v0
    } else if t == 1.0 {
        v1
    } else {
        v0 + t * (v1 - v0)
    }
}

/// The part of `c0`–`c1` with `w > near`; `None` when no part is (or a
/// coordinate is NaN). Ends already in front are returned bit for bit; a
/// cut end has `w = near` exactly.
pub fn near_clip(c0: [f32; 4], c1: [f32; 4], near: f32) -> Option<NearClipped> {
    let (d0, d1) = (c0[3] - near, c1[3] - near);
    let (in0, in1) = (d0 > 0.0, d1 > 0.0);
    if in0 && in1 {
        return Some(NearClipped {
            a: c0,
            b: c1,
            ta: 0.0,
            tb: 1.0,
        });
    }
    if !in0 && !in1 {
        return None;
    }
    let t = d0 / (d0 - d1);
    if !(0.0..=1.0).contains(&t) {
        return None;
    }
    let mut cut = [0.0; 4];
    for (k, c) in cut.iter_mut().enumerate() {
        *c = c0[k] + t * (c1[k] - c0[k]);
    }
    cut[3] = near;
    Some(if in0 {
        NearClipped {
            a: c0,
            b: cut,
            ta: 0.0,
            tb: t,
        }
    } else {
        NearClipped {
            a: cut,
            b: c1,
            ta: t,
            tb: 1.0,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_front_is_unchanged_and_behind_is_dropped() {
        let (a, b) = ([0.1, 0.2, 0.3, 1.0], [0.4, -0.2, 0.5, 2.0]);
        assert_eq!(
            near_clip(a, b, 0.5),
            Some(NearClipped {
                a,
                b,
                ta: 0.0,
                tb: 1.0
            })
        );
        assert_eq!(
            near_clip([0.0, 0.0, 0.0, 0.1], [1.0, 0.0, 0.0, -3.0], 0.5),
            None
        );
        // Touching the plane is not in front.
        assert_eq!(near_clip([0.0; 4], [1.0, 0.0, 0.0, 0.5], 0.5), None);
        assert_eq!(near_clip([f32::NAN; 4], b, 0.5), None);
    }

    #[test]
    fn crossing_is_cut_at_the_plane_from_either_end() {
        // From w = -1 to w = 3, x from 0 to 4: w = 0.5 at t = 3/8.
        let (behind, front) = ([0.0, 1.0, 0.0, -1.0], [4.0, 1.0, 2.0, 3.0]);
        let c = near_clip(behind, front, 0.5).unwrap();
        assert_eq!((c.ta, c.tb, c.b), (0.375, 1.0, front));
        assert_eq!(c.a, [1.5, 1.0, 0.75, 0.5]);
        let r = near_clip(front, behind, 0.5).unwrap();
        assert_eq!((r.a, r.ta, r.tb), (front, 0.0, 0.625));
        assert_eq!(r.b, [1.5, 1.0, 0.75, 0.5]);
        // An attribute from 10 at `behind` to 20 at `front`, at the two ends.
        assert_eq!(c.ends(10.0, 20.0), [13.75, 20.0]);
        // Uncut ends keep their values exactly (0.1 + (0.3 - 0.1) is not 0.3).
        let whole = near_clip(front, [0.0, 0.0, 0.0, 1.0], 0.5).unwrap();
        assert_eq!(whole.ends(0.1, 0.3), [0.1, 0.3]);
    }
}
