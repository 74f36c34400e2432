//! The ground-truth reference: what a hair pipeline approximates, rendered
//! without its approximations, so its error can be measured (FLIP and
//! coverage against this image, next to the time).
//!
//! Every strand is the camera-facing ribbon of its own thickness
//! ([`ribbon`]): no level of detail, no thickness compensation, no layer
//! limit, no coverage estimate. Each pixel takes `n × n` stratified samples
//! (64 by default); at each sample every hair fragment covering it is
//! blended front to back (strands are opaque, so the nearest one shows). Shading is the
//! pipeline's own: the passes here read the post-transform cache
//! (`clip_positions`) and per-vertex radiance (`vertex_lighting`) that
//! Kulikov's skinning and strand-space shading write, so against the
//! Kulikov pipeline the reference differs only in visibility, transparency
//! and antialiasing (`scenes/graphs/kulikov_reference.ron`).
//!
//! Four passes, on every backend:
//! 1. [`bin::COUNT`]: per segment, its ribbon (a record the later passes
//!    read) and the 8 × 8 screen tiles it may reach, counted per tile;
//! 2. [`scan::SCAN`]: the tiles' prefix sum, a list range per tile;
//! 3. [`bin::FILL`]: each segment written into the lists of its tiles;
//! 4. [`resolve::RESOLVE`]: per pixel, every segment of the tile's list
//!    tested against every sample, each sample keeping the nearest.
//!
//! The lists hold at most the capacity the graph gives `reference_segments`;
//! the scan records how many entries the frame needed, and [`check_lists`]
//! turns an overflow into an error naming the resource.

pub mod bin;
pub mod resolve;
pub mod ribbon;
pub mod scan;

use crate::kernel::Ctx;
use crate::kulikov::cull::drawn_segment;
use crate::kulikov::{ModelLod, Scene};
use ribbon::{Record, Ribbon};

/// Screen tile edge of the segment lists, in pixels (a resolve workgroup of
/// 64 lanes). A pixel scans its tile's whole list, so the list's length is
/// the resolve's cost, and a smaller tile lists fewer segments that miss
/// the pixel.
pub const TILE: u32 = 8;

/// The screen's tile grid for `width × height` pixels.
pub fn tiles(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// Segment `id`'s ribbon, or `None` when it is not drawn: culled (the
/// fedora), dropped by the LOD, or crossing the near plane. Its ends join
/// the neighbouring segments of the strand, except at the root and tip.
pub(crate) fn segment_ribbon(
    scene: &Scene,
    lods: &[ModelLod],
    ctx: &Ctx<'_>,
    id: u32,
) -> Option<Record> {
    let visible = ctx.words("segment_visibility").load((id / 32) as usize) & (1 << (id % 32));
    if visible == 0 {
        return None;
    }
    let seg = drawn_segment(scene, lods, id)?;
    let md = &scene.models[seg.model];
    let lod = &lods[seg.model];
    let k = seg.local % (md.points_per_strand - 1);
    let (clip, verts) = (ctx.words("clip_positions"), ctx.words("groom.vertices"));
    let thickness = |v: u32| verts.load_f32(4 * v as usize + 3) * lod.thickness_scale;
    let ribbon = Ribbon::new(
        &scene.frame,
        clip.load_vec4(seg.v0 as usize),
        clip.load_vec4(seg.v1 as usize),
        thickness(seg.v0),
        thickness(seg.v1),
        k > 0,
        k + 1 < lod.segments_per_strand,
    )?;
    Some(Record {
        ribbon,
        vertices: [seg.v0, seg.v1],
    })
}

/// Lavapipe (llvmpipe) ends every loop of a shader invocation once the
/// invocation has run this many loop iterations in all
/// (`LP_MAX_TGSI_LOOP_ITERATIONS`): past it a resolve lane silently skips
/// samples.
pub const LLVMPIPE_LOOP_ITERATIONS: u64 = 65_535;

/// What a frame's tile lists must satisfy, checked on the host after it.
#[derive(Debug, Clone, Copy)]
pub struct ListLimits {
    /// Entries `reference_segments` holds.
    pub capacity: usize,
    /// The device's cap on loop iterations per invocation, if it has one.
    pub loop_cap: Option<u64>,
    /// The resolve's `samples_per_axis`.
    pub samples_per_axis: u32,
}

/// `Err` when the frame's lists did not fit their buffer (they were cut
/// short), or when on a device with a loop cap a resolve lane had more list
/// entries to walk than the cap lets it: either way the image is wrong.
/// `offsets` is `reference_offsets` read back after the frame: the tiles'
/// offsets, then the total.
pub fn check_lists(offsets: &[u32], tiles: usize, limits: ListLimits) -> Result<(), String> {
    let needed = offsets.get(tiles).copied().unwrap_or(0) as usize;
    if needed > limits.capacity {
        return Err(format!(
            "reference: the frame needed {needed} tile-list entries but `reference_segments` holds {}; \
             give it more bytes per segment in the graph",
            limits.capacity
        ));
    }
    let Some(cap) = limits.loop_cap else {
        return Ok(());
    };
    let longest = offsets
        .windows(2)
        .take(tiles)
        .map(|w| u64::from(w[1].saturating_sub(w[0])))
        .max()
        .unwrap_or(0);
    // resolve.wgsl: per block of 64 samples, 64 iterations to set up, the
    // list, 64 to finish.
    let samples = u64::from(limits.samples_per_axis).pow(2);
    let iterations = samples.div_ceil(64) * (longest + 128);
    if iterations >= cap {
        return Err(format!(
            "reference: a tile lists {longest} segments, {iterations} loop iterations for a resolve lane \
             at {samples} samples, and this device stops an invocation's loops after {cap} \
             (lavapipe); render at a higher resolution, with fewer samples, or on a GPU"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: ListLimits = ListLimits {
        capacity: 10,
        loop_cap: None,
        samples_per_axis: 8,
    };

    #[test]
    fn lists_that_overflow_or_outrun_the_loop_cap_are_errors() {
        // Two tiles: 4 and 6 entries, 10 in all.
        let offsets = [0, 4, 10];
        assert!(check_lists(&offsets, 2, LIMITS).is_ok());
        let small = ListLimits {
            capacity: 9,
            ..LIMITS
        };
        let e = check_lists(&offsets, 2, small).unwrap_err();
        assert!(e.contains("needed 10") && e.contains("holds 9"), "{e}");
        let capped = ListLimits {
            loop_cap: Some(134),
            ..LIMITS
        };
        let e = check_lists(&offsets, 2, capped).unwrap_err();
        assert!(e.contains("lists 6 segments") && e.contains("134"), "{e}");
        let roomy = ListLimits {
            loop_cap: Some(135),
            ..capped
        };
        assert!(check_lists(&offsets, 2, roomy).is_ok());
    }
}
