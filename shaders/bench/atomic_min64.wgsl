// bench.atomic_min64: roofline reference for Lipp's 64-bit visibility buffer.
// Each invocation (one per screen pixel) does `ops` 64-bit atomicMin with
// the result unused (naga SHADER_INT64_ATOMIC_MIN_MAX allows no more), at
// addresses and with values hashed from its global id, the sequence the CPU
// kernel replays (passes/src/bench/roofline.rs, kernel::wide `fetch_min_u64`).

#import strandgraph::hash::pcg

struct RooflineParams {
    ops: u32,
    invocations: u32,
}

@group(0) @binding(0) var<uniform> params: RooflineParams;
@group(0) @binding(1) var<storage, read_write> atomics_u64: array<atomic<u64>>;

const VALUE_SALT: u32 = 0x9e3779b9u;
const HIGH_SALT: u32 = 0x85ebca6bu;

@compute @workgroup_size(256)
fn atomic_min64(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x;
    let len = arrayLength(&atomics_u64);
    if id >= params.invocations || len == 0u {
        return;
    }
    for (var k = 0u; k < params.ops; k++) {
        let h = pcg(id * params.ops + k);
        let value = (u64(pcg(h ^ HIGH_SALT)) << 32u) | u64(pcg(h ^ VALUE_SALT));
        atomicMin(&atomics_u64[h % len], value);
    }
}
