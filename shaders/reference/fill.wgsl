// reference.fill and reference.fill_strands: each drawn segment into the
// list of every tile its count pass counted it in, taking slots with an
// atomicAdd on a second, cleared, per-tile counter. Port of
// passes/src/reference/bin.rs (fill).

#import strandgraph::reference::{BinParams, Ribbon, ribbon_unpack, ribbon_tiles, ribbon_reaches_tile}

@group(0) @binding(0) var<uniform> params: BinParams;
@group(0) @binding(1) var<storage, read> reference_ribbons: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> reference_offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> reference_cursor: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> reference_segments: array<u32>;

// lipp::MAX_CONTROL_POINTS: record slots per strand in fill_strands.
const STRAND_SLOTS: u32 = 129u;

fn fill_record(id: u32) {
    let r = ribbon_unpack(reference_ribbons[3u * id], reference_ribbons[3u * id + 1u], reference_ribbons[3u * id + 2u]);
    if !r.valid {
        return;
    }
    let t = ribbon_tiles(r, params.width, params.height);
    let capacity = arrayLength(&reference_segments);
    for (var ty = t.y; ty <= t.w; ty++) {
        for (var tx = t.x; tx <= t.z; tx++) {
            if ribbon_reaches_tile(r, tx, ty) {
                let tile = ty * params.tiles_x + tx;
                let slot = reference_offsets[tile] + atomicAdd(&reference_cursor[tile], 1u);
                // Past the capacity the list is cut; the host reports it.
                if slot < capacity {
                    reference_segments[slot] = id;
                }
            }
        }
    }
}

// A lane per segment (`params.segments` records).
@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < params.segments {
        fill_record(gid.x);
    }
}

// A lane per strand (`params.segments` strands), each with STRAND_SLOTS
// record slots of which the first C - 1 hold its segments.
@compute @workgroup_size(64)
fn fill_strands(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.segments {
        return;
    }
    // The graph sizes reference_ribbons for every strand's slots. Not
    // arrayLength: on the H100 (driver 580) it reads 0 records of the
    // crowd's 2.7 GB binding, past 2 GiB, and nothing was filled.
    let first = gid.x * STRAND_SLOTS;
    for (var id = first; id < first + STRAND_SLOTS - 1u; id++) {
        fill_record(id);
    }
}
