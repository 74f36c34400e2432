// kulikov.shade_sort: visible segments appended in natural order, one
// atomicAdd per subgroup (Kulikov, "Strand-space shading needs different
// segment order"). shade_args (cleared to 0) ends as [groups, 1, 1, count].
// Port of passes/src/kulikov/shade_sort.rs.

#import strandgraph::subgroup::elected

struct ShadeSortParams {
    wave_aggregated_atomics: u32,
    // Scene quantity: segments in the full numbering.
    segments: u32,
}

@group(0) @binding(0) var<uniform> params: ShadeSortParams;
@group(0) @binding(1) var<storage, read> segment_visibility: array<u32>;
@group(0) @binding(2) var<storage, read_write> shade_args: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> shading_segments: array<u32>;

const GROUP: u32 = 256u;
// kulikov.shade's workgroup size (shade_sort::SHADE_GROUP).
const SHADE_GROUP: u32 = 64u;
// shade_sort::MAX_SHADE_GROUPS: x of the shade dispatch; its lanes stride past it.
const MAX_SHADE_GROUPS: u32 = 65535u;

@compute @workgroup_size(256)
fn shade_sort(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
) {
    let id = wg.x * GROUP + lane;
    // Every lane stays in the subgroup operations (no early return).
    let visible = id < params.segments && (segment_visibility[id / 32u] & (1u << (id % 32u))) != 0u;
    let one = select(0u, 1u, visible);
    if params.wave_aggregated_atomics != 0u {
        let n = subgroupAdd(one);
        let offset = subgroupExclusiveAdd(one);
        var base = 0u;
        if elected(sg_lane) && n > 0u {
            base = atomicAdd(&shade_args[3], n);
            atomicMax(&shade_args[0], min((base + n + SHADE_GROUP - 1u) / SHADE_GROUP, MAX_SHADE_GROUPS));
            atomicStore(&shade_args[1], 1u);
            atomicStore(&shade_args[2], 1u);
        }
        base = subgroupBroadcastFirst(base);
        if visible {
            shading_segments[base + offset] = id;
        }
    } else if visible {
        let slot = atomicAdd(&shade_args[3], 1u);
        shading_segments[slot] = id;
        atomicMax(&shade_args[0], min((slot + 1u + SHADE_GROUP - 1u) / SHADE_GROUP, MAX_SHADE_GROUPS));
        atomicStore(&shade_args[1], 1u);
        atomicStore(&shade_args[2], 1u);
    }
}
