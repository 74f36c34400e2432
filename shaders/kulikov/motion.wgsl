// kulikov.store_history and kulikov.motion: motion vectors from the
// post-transform cache (Kulikov, "Motion vectors"). CPU kernels:
// passes/src/kulikov/motion.rs, which documents the packing.
//
// Bindings (group 0): 0 = HistoryParams, then the pass's bindings() in
// order. store_history: 1 = frame, 2 = prev_frame.
// motion: 1 = frame, 2 = clip_positions, 3 = prev_clip_positions (read,
// then overwritten for the next frame), 4 = vertex_motion.
#import strandgraph::layout::FrameData
#import strandgraph::kulikov::round_away

struct HistoryParams {
    vertices: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const UNORM_MAX: f32 = 65534.0;
// Codes are stored plus one; 0 (a History buffer's first contents) is
// "not transformed" (motion::NOT_TRANSFORMED).
const NOT_TRANSFORMED: u32 = 0u;

@group(0) @binding(0) var<uniform> params: HistoryParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> prev_frame: FrameData;
@group(0) @binding(3) var<storage, read_write> prev_clip_positions: array<u32>;
@group(0) @binding(4) var<storage, read_write> vertex_motion: array<vec2<f32>>;

fn compress(ndc: f32) -> u32 {
    return u32(round_away((clamp(ndc, -1.0, 1.0) * 0.5 + 0.5) * UNORM_MAX));
}

fn decompress(code: u32) -> f32 {
    return f32(code) / UNORM_MAX * 2.0 - 1.0;
}

// motion::pack.
fn pack(c: vec4<f32>) -> u32 {
    if c.w > frame.near {
        return (compress(c.x / c.w) + 1u) | ((compress(c.y / c.w) + 1u) << 16u);
    }
    return NOT_TRANSFORMED;
}

@compute @workgroup_size(256)
fn store_history(@builtin(local_invocation_index) lane: u32) {
    // Binding 0 is every pass's parameter block; this entry needs none.
    _ = params.vertices;
    if lane == 0u {
        prev_frame = frame;
    }
}

@compute @workgroup_size(256)
fn motion(@builtin(global_invocation_id) id: vec3<u32>) {
    let v = id.x;
    if v >= params.vertices {
        return;
    }
    let c = clip_positions[v];
    let prev = prev_clip_positions[v];
    var m = vec2<f32>(0.0);
    if prev != NOT_TRANSFORMED && c.w > frame.near {
        let p = vec2<f32>(decompress((prev & 0xFFFFu) - 1u), decompress((prev >> 16u) - 1u));
        let n = vec2<f32>(c.x / c.w, c.y / c.w);
        m = vec2<f32>((n.x - p.x) * 0.5 * frame.screen.x, (p.y - n.y) * 0.5 * frame.screen.y);
    }
    vertex_motion[v] = m;
    prev_clip_positions[v] = pack(c);
}
