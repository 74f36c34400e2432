// common.clear: fill one bound buffer with a 32-bit value.
// The GPU backends dispatch it once per resource the pass writes.

struct ClearParams {
    value: u32,
    words: u32,
}

@group(0) @binding(0) var<uniform> params: ClearParams;
@group(0) @binding(1) var<storage, read_write> target_words: array<u32>;

// clear::WORDS_PER_LANE words per lane a round, 256 apart: a workgroup
// clears 4096 consecutive words a round, and the workgroups stride over
// buffers larger than the 65,535 a dispatch launches.
const WORDS_PER_LANE: u32 = 16u;
const SPAN: u32 = 4096u;

@compute @workgroup_size(256)
fn clear(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    for (var start = wg.x * SPAN; start < params.words; start += groups.x * SPAN) {
        for (var k = 0u; k < WORDS_PER_LANE; k++) {
            let i = start + lane + k * 256u;
            if i < params.words {
                target_words[i] = params.value;
            }
        }
    }
}
