// The Hi-Z test that kulikov.cull and lipp.raster share: the farthest scene
// depth over the 16x16 blocks of kulikov.depth_downsample's `hiz` that a
// pixel box touches. Port of passes/src/kulikov/depth_downsample.rs's
// `farthest`.
//   #import strandgraph::hiz::{HIZ_FACTOR, hiz_farthest}
#define_import_path strandgraph::hiz

// Hi-Z block edge in pixels (depth_downsample::FACTOR).
const HIZ_FACTOR: u32 = 16u;
// A box over more blocks than this is not tested (depth_downsample::MAX_BLOCKS):
// long segments are not worth the reads.
const HIZ_MAX_BLOCKS: u32 = 16u;

// The farthest depth of the blocks pixel box `bounds` (x0, y0, x1, y1,
// inclusive, on screen) touches; f32::MAX, which no depth is behind, when
// it touches more than HIZ_MAX_BLOCKS.
fn hiz_farthest(hiz: texture_2d<f32>, bounds: vec4<u32>) -> f32 {
    let t = bounds / HIZ_FACTOR;
    if (t.z - t.x + 1u) * (t.w - t.y + 1u) > HIZ_MAX_BLOCKS {
        return 3.40282347e38;
    }
    var farthest = 0.0;
    for (var ty = t.y; ty <= t.w; ty++) {
        for (var tx = t.x; tx <= t.z; tx++) {
            farthest = max(farthest, textureLoad(hiz, vec2<u32>(tx, ty), 0).x);
        }
    }
    return farthest;
}
