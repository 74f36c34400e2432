// kulikov.shade_sort: visible segments appended in natural order, one
// atomicAdd per subgroup (Kulikov, "Strand-space shading needs different
// segment order"). shade_args (cleared to 0) ends as [groups, 1, 1, count].
// Port of passes/src/kulikov/shade_sort.rs.
//
// word_per_lane (ours): a lane appends the set bits of one 32-bit word of
// visibility bits; off, a workgroup covers the same 8,192 segments in 32
// rounds of one bit per lane.

#import strandgraph::subgroup::elected

struct ShadeSortParams {
    wave_aggregated_atomics: u32,
    word_per_lane: u32,
    // Scene quantity: segments in the full numbering.
    segments: u32,
}

@group(0) @binding(0) var<uniform> params: ShadeSortParams;
@group(0) @binding(1) var<storage, read> segment_visibility: array<u32>;
@group(0) @binding(2) var<storage, read_write> shade_args: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> shading_segments: array<u32>;

const GROUP: u32 = 256u;
// Segments per workgroup (shade_sort::SEGMENTS_PER_GROUP).
const SEGMENTS_PER_GROUP: u32 = 8192u;
// kulikov.shade's workgroup size (shade_sort::SHADE_GROUP).
const SHADE_GROUP: u32 = 64u;
// shade_sort::MAX_SHADE_GROUPS: x of the shade dispatch; its lanes stride past it.
const MAX_SHADE_GROUPS: u32 = 65535u;

// The visibility bits of segments first.. (one bit with `one_bit`), those
// past the scene's segments masked off.
fn lane_bits(first: u32, one_bit: bool) -> u32 {
    if first >= params.segments {
        return 0u;
    }
    var word = segment_visibility[first / 32u];
    if one_bit {
        return (word >> (first % 32u)) & 1u;
    }
    // A whole word (first is a multiple of 32).
    let valid = min(params.segments - first, 32u);
    if valid < 32u {
        word &= (1u << valid) - 1u;
    }
    return word;
}

fn raise_dispatch(end: u32) {
    atomicMax(&shade_args[0], min((end + SHADE_GROUP - 1u) / SHADE_GROUP, MAX_SHADE_GROUPS));
    atomicStore(&shade_args[1], 1u);
    atomicStore(&shade_args[2], 1u);
}

// Appends segments first + b for the set bits b of `bits`, lowest first,
// after those of the subgroup's earlier lanes. Subgroup-uniform control flow.
fn append(bits_in: u32, first: u32, sg_lane: u32) {
    var bits = bits_in;
    let own = countOneBits(bits);
    if params.wave_aggregated_atomics != 0u {
        let n = subgroupAdd(own);
        let offset = subgroupExclusiveAdd(own);
        var base = 0u;
        if elected(sg_lane) && n > 0u {
            base = atomicAdd(&shade_args[3], n);
            raise_dispatch(base + n);
        }
        var slot = subgroupBroadcastFirst(base) + offset;
        while bits != 0u {
            shading_segments[slot] = first + firstTrailingBit(bits);
            slot += 1u;
            bits &= bits - 1u;
        }
    } else {
        while bits != 0u {
            let slot = atomicAdd(&shade_args[3], 1u);
            shading_segments[slot] = first + firstTrailingBit(bits);
            raise_dispatch(slot + 1u);
            bits &= bits - 1u;
        }
    }
}

@compute @workgroup_size(256)
fn shade_sort(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
) {
    let base = wg.x * SEGMENTS_PER_GROUP;
    // Every lane stays in the subgroup operations (no early return).
    if params.word_per_lane != 0u {
        let first = base + 32u * lane;
        append(lane_bits(first, false), first, sg_lane);
    } else {
        for (var round = 0u; round < 32u; round++) {
            let id = base + round * GROUP + lane;
            append(lane_bits(id, true), id, sg_lane);
        }
    }
}
