// What the reference's counting passes (reference.count for a groom,
// lipp.reference_strands for hair meshes) do with a segment's ribbon: store
// its record and count it in every 8x8 tile it may reach
// (passes/src/reference/bin.rs, `Record::store` and `reached_tiles`). The
// importer places the two bindings:
//   #define REFERENCE_COUNTS_BINDING 7
//   #define REFERENCE_RIBBONS_BINDING 8
//   #import strandgraph::reference_bins::store_ribbon
#define_import_path strandgraph::reference_bins

#import strandgraph::reference::{Ribbon, ribbon_pack, ribbon_tiles, ribbon_reaches_tile}

@group(0) @binding(#{REFERENCE_COUNTS_BINDING}) var<storage, read_write> reference_counts: array<atomic<u32>>;
@group(0) @binding(#{REFERENCE_RIBBONS_BINDING}) var<storage, read_write> reference_ribbons: array<vec4<u32>>;

// Record `id` of `reference_ribbons` (or "not drawn"), and +1 per reached
// tile of a screen `width` x `height` whose tile rows are `tiles_x` long.
fn store_ribbon(id: u32, r: Ribbon, width: u32, height: u32, tiles_x: u32) {
    let words = ribbon_pack(r);
    reference_ribbons[3u * id] = words[0];
    reference_ribbons[3u * id + 1u] = words[1];
    reference_ribbons[3u * id + 2u] = words[2];
    if !r.valid {
        return;
    }
    let t = ribbon_tiles(r, width, height);
    for (var ty = t.y; ty <= t.w; ty++) {
        for (var tx = t.x; tx <= t.z; tx++) {
            if ribbon_reaches_tile(r, tx, ty) {
                atomicAdd(&reference_counts[ty * tiles_x + tx], 1u);
            }
        }
    }
}
