// reference.count: per segment, its ribbon record, and +1 in every 8x8
// screen tile the ribbon may reach. Port of passes/src/reference/bin.rs
// (count) and reference::segment_ribbon.

#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LOD_MODELS_BINDING 3
#define REFERENCE_COUNTS_BINDING 7
#define REFERENCE_RIBBONS_BINDING 8
#import strandgraph::kulikov_segments::{frame, models, lod_models, drawn_segment}
#import strandgraph::kulikov::load_lod
#import strandgraph::reference::{BinParams, Ribbon, ribbon_of}
#import strandgraph::reference_bins::store_ribbon

@group(0) @binding(0) var<uniform> params: BinParams;
@group(0) @binding(4) var<storage, read> segment_visibility: array<u32>;
@group(0) @binding(5) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> groom_vertices: array<vec4<f32>>;
// Bindings 7 (reference_counts) and 8 (reference_ribbons) are bins.wgsl's.

// reference::segment_ribbon: not drawn when culled, dropped by the LOD or
// crossing the near plane; joined to its neighbours but at root and tip.
fn segment_ribbon(id: u32) -> Ribbon {
    var r: Ribbon;
    r.valid = false;
    if (segment_visibility[id / 32u] & (1u << (id % 32u))) == 0u {
        return r;
    }
    let seg = drawn_segment(id);
    if !seg.valid {
        return r;
    }
    let per = models[seg.model].points_per_strand - 1u;
    let lod = load_lod(lod_models[seg.model]);
    let k = seg.local % per;
    let t0 = groom_vertices[seg.va].w * lod.thickness_scale;
    let t1 = groom_vertices[seg.vb].w * lod.thickness_scale;
    return ribbon_of(
        clip_positions[seg.va], clip_positions[seg.vb], t0, t1,
        k > 0u, k + 1u < lod.segments_per_strand, seg.va, seg.vb,
        frame.near, frame.screen.xy, frame.pixels_per_unit,
    );
}

@compute @workgroup_size(256)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x;
    if id >= params.segments {
        return;
    }
    store_ribbon(id, segment_ribbon(id), params.width, params.height, params.tiles_x);
}
