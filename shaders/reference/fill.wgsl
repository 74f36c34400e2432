// reference.fill: each drawn segment into the list of every tile
// reference.count counted it in, taking slots with an atomicAdd on a
// second, cleared, per-tile counter. Port of passes/src/reference/bin.rs
// (fill).

#import strandgraph::reference::{BinParams, Ribbon, ribbon_unpack, ribbon_tiles, ribbon_reaches_tile}

@group(0) @binding(0) var<uniform> params: BinParams;
@group(0) @binding(1) var<storage, read> reference_ribbons: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> reference_offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> reference_cursor: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> reference_segments: array<u32>;

@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x;
    if id >= params.segments {
        return;
    }
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
