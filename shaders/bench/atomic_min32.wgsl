// bench.atomic_min32: roofline reference for Kulikov's visibility atlas.
// Each invocation (one per screen pixel) does `ops` 32-bit atomicMin at
// addresses and with values hashed from its global id, the sequence the CPU
// kernel replays (passes/src/bench/roofline.rs).

#import strandgraph::hash::pcg

struct RooflineParams {
    ops: u32,
    invocations: u32,
}

@group(0) @binding(0) var<uniform> params: RooflineParams;
@group(0) @binding(1) var<storage, read_write> atomics_u32: array<atomic<u32>>;

const VALUE_SALT: u32 = 0x9e3779b9u;

@compute @workgroup_size(256)
fn atomic_min32(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x;
    let len = arrayLength(&atomics_u32);
    if id >= params.invocations || len == 0u {
        return;
    }
    for (var k = 0u; k < params.ops; k++) {
        let h = pcg(id * params.ops + k);
        atomicMin(&atomics_u32[h % len], pcg(h ^ VALUE_SALT));
    }
}
