//! Lipp Eq. 3, a bundle's footprint: the axis-aligned box of its layer
//! quads' corners projected into a view, in that view's pixels. The camera's
//! screen gives the paper's LOD; a light's deep opacity map gives the shadow
//! LOD (ours, [`super::View::Light`]): the map is a view of its own, with its
//! own resolution, and how much of a bundle it can resolve does not depend on
//! where the camera is.

use super::super::dom::LightFrame;
use super::super::{BundleRecord, Corner, transform};
use crate::kernel::Words;
use crate::layout::FrameData;

/// A footprint: the box's corners (pixels of its view).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    pub lo: [f32; 2],
    pub hi: [f32; 2],
}

impl Footprint {
    fn empty() -> Self {
        Self {
            lo: [f32::MAX; 2],
            hi: [f32::MIN; 2],
        }
    }

    fn add(&mut self, s: [f32; 2]) {
        self.lo = [self.lo[0].min(s[0]), self.lo[1].min(s[1])];
        self.hi = [self.hi[0].max(s[0]), self.hi[1].max(s[1])];
    }

    /// Whether any corner was added.
    pub fn is_some(&self) -> bool {
        self.lo[0] <= self.hi[0]
    }
}

/// Calls `visit` with every layer corner of bundle `b` (world space).
fn corners(layers: &Words<'_>, b: &BundleRecord, visit: &mut dyn FnMut([f32; 3])) {
    for i in 0..b.layers() {
        for k in 0..4 {
            visit(Corner::load(layers, (b.first_layer + i) as usize, k).position);
        }
    }
}

/// Lipp Eq. 3 on the camera's screen: the footprint of the corners in front
/// of the near plane, and whether a corner lies behind it.
pub fn screen(f: &FrameData, layers: &Words<'_>, b: &BundleRecord) -> (Footprint, bool) {
    let mut fp = Footprint::empty();
    let mut behind = false;
    corners(layers, b, &mut |p| {
        let clip = transform(&f.view_proj, [p[0], p[1], p[2], 1.0]);
        if clip[3] <= f.near {
            behind = true;
            return;
        }
        let s = crate::kulikov::clip_to_screen(clip, f.screen[0], f.screen[1]);
        fp.add([s[0], s[1]]);
    });
    (fp, behind)
}

/// Lipp Eq. 3 in a light's deep opacity map of `res` texels per side: the
/// light's orthographic view ([`LightFrame`]) scaled to texels.
pub fn light_map(lf: &LightFrame, res: f32, layers: &Words<'_>, b: &BundleRecord) -> Footprint {
    let mut fp = Footprint::empty();
    corners(layers, b, &mut |p| {
        let q = lf.project(p);
        fp.add([q[0] * res, q[1] * res]);
    });
    fp
}
