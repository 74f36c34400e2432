// The Hi-Z test that kulikov.cull and lipp.raster share: the farthest scene
// depth over the 16x16 blocks of kulikov.depth_downsample's `hiz` that a
// pixel box touches. Port of passes/src/kulikov/depth_downsample.rs's
// `farthest`.
// kulikov.depth_downsample and scene.depth_hiz build it with the helpers
// below (one workgroup of 256 lanes per block).
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

// The Hi-Z texel of block `block`, the blocks numbered row by row over a
// screen `width` pixels wide (depth_downsample::block_pixels).
fn hiz_block(block: u32, width: u32) -> vec2<u32> {
    let blocks_x = (width + HIZ_FACTOR - 1u) / HIZ_FACTOR;
    return vec2<u32>(block % blocks_x, block / blocks_x);
}

// Lane `lane`'s pixel of block `block` (it may lie past the screen's edge).
fn hiz_block_pixel(block: u32, lane: u32, width: u32) -> vec2<u32> {
    return hiz_block(block, width) * HIZ_FACTOR + vec2<u32>(lane % HIZ_FACTOR, lane / HIZ_FACTOR);
}

// A depth's bits, ordered as the depths for atomicMax (depth_downsample::
// depth_bits): depths are in [0, 1], and clearing the sign keeps a -0.0
// from ordering above every one of them.
fn hiz_bits(z: f32) -> u32 {
    return bitcast<u32>(z) & 0x7FFFFFFFu;
}
