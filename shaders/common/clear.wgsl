// common.clear: fill one bound buffer with a 32-bit value.
// The GPU backends dispatch it once per resource the pass writes.

struct ClearParams {
    value: u32,
    words: u32,
}

@group(0) @binding(0) var<uniform> params: ClearParams;
@group(0) @binding(1) var<storage, read_write> target_words: array<u32>;

@compute @workgroup_size(256)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < params.words {
        target_words[id.x] = params.value;
    }
}
