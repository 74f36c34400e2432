// kulikov.skin (`skin`): strand roots follow their triangle; every drawn
// vertex goes to clip space (before the division by w) into
// `clip_positions`. kulikov.skin_motion (`skin_motion`): the same, then each
// drawn vertex's motion and vertex history (motion.rs).
// Port of passes/src/kulikov/skin.rs, with glam's operation order:
// p = root_now + sum_i now[i] * dot(p - root_bind, bind[i]).

#import strandgraph::layout::{FrameData, ModelData, ModelLod, TriangleData}
#import strandgraph::clip::transform
#import strandgraph::kulikov::{load_lod, round_away}

// The pass has no parameters; the block keeps binding 0 the same for every pass.
struct SkinParams {
    reserved: u32,
}

@group(0) @binding(0) var<uniform> params: SkinParams;
@group(0) @binding(1) var<storage, read> lod_args: array<u32>;
@group(0) @binding(2) var<storage, read> frame: FrameData;
@group(0) @binding(3) var<storage, read> models: array<ModelData>;
@group(0) @binding(4) var<storage, read> lod_models: array<ModelLod>;
// xyz: rest position in groom space, w: thickness.
@group(0) @binding(5) var<storage, read> groom_vertices: array<vec4<f32>>;
// Per strand: first vertex and vertex count.
@group(0) @binding(6) var<storage, read> groom_strands: array<vec2<u32>>;
// Per strand: triangle, packed barycentrics, octahedral bind normal and tangent.
@group(0) @binding(7) var<storage, read> groom_skinning: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> mesh_triangles: array<TriangleData>;
@group(0) @binding(9) var<storage, read_write> clip_positions: array<vec4<f32>>;
// kulikov.skin_motion only (motion.rs): last frame's LOD, the vertex
// history (read, then this frame's NDC over it) and the motion.
@group(0) @binding(10) var<storage, read> prev_lod_models: array<ModelLod>;
@group(0) @binding(11) var<storage, read_write> prev_clip_positions: array<u32>;
@group(0) @binding(12) var<storage, read_write> vertex_motion: array<vec2<f32>>;

const SKIN_GROUP: u32 = 64u;

// glam Vec3::dot: (x*x' + y*y') + z*z'.
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// glam try_normalize: None (w = 0) unless 1/length is finite and positive.
fn try_normalize(v: vec3<f32>) -> vec4<f32> {
    let rcp = 1.0 / sqrt(dot3(v, v));
    if rcp > 0.0 && rcp <= 3.40282347e38 {
        return vec4<f32>(v * rcp, 1.0);
    }
    return vec4<f32>(0.0);
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    return try_normalize(v).xyz;
}

// glam normalize: v * (1 / length), unguarded.
fn normalize_glam(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(dot3(v, v)));
}

// glam reject_from: v - n * dot(v, n) * (1 / dot(n, n)).
fn reject_from(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / dot3(n, n);
    return v - n * dot3(v, n) * rcp;
}

// glam Mat4::transform_point3: ((x * px + y * py) + z * pz) + w.
fn transform_point3(m: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return (m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]).xyz;
}

// strandgraph_assets::octahedral::unpack_barycentrics.
fn unpack_barycentrics(p: u32) -> vec3<f32> {
    let x = f32(p & 0xffffu) / 65535.0;
    let y = f32(p >> 16u) / 65535.0;
    return vec3<f32>(x, y, max(1.0 - x - y, 0.0));
}

fn unsnorm16(v: u32) -> f32 {
    // (v as u16 as i16) as f32 / 32767, at least -1.
    let s = (bitcast<i32>(v << 16u)) >> 16u;
    return max(f32(s) / 32767.0, -1.0);
}

fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(select(-1.0, 1.0, v.x >= 0.0), select(-1.0, 1.0, v.y >= 0.0));
}

// strandgraph_assets::octahedral::unpack_unit_vector (oct_decode).
fn unpack_unit_vector(p: u32) -> vec3<f32> {
    let e = vec2<f32>(unsnorm16(p & 0xffffu), unsnorm16(p >> 16u));
    let z = 1.0 - abs(e.x) - abs(e.y);
    var xy = e;
    if z < 0.0 {
        xy = (vec2<f32>(1.0) - vec2<f32>(abs(e.y), abs(e.x))) * sign_not_zero(e);
    }
    return normalize_or_zero(vec3<f32>(xy, z));
}

struct RootMotion {
    valid: bool,
    root_bind: vec3<f32>,
    root_now: vec3<f32>,
    now0: vec3<f32>,
    now1: vec3<f32>,
    now2: vec3<f32>,
    bind0: vec3<f32>,
    bind1: vec3<f32>,
    bind2: vec3<f32>,
}

fn rot(m: ModelData, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot3(m.mesh_rotation[0].xyz, v), dot3(m.mesh_rotation[1].xyz, v), dot3(m.mesh_rotation[2].xyz, v));
}

// skin::root_motion.
fn root_motion(m: ModelData, root_local: vec3<f32>, info: vec4<u32>) -> RootMotion {
    var out: RootMotion;
    out.valid = false;
    let t = mesh_triangles[m.triangle_first + info.x];
    let a = t.a.xyz;
    let b = t.b.xyz;
    let c = t.c.xyz;
    let w = unpack_barycentrics(info.y);
    let n4 = try_normalize(cross3(b - a, c - a));
    if n4.w == 0.0 {
        return out;
    }
    let n = n4.xyz;
    let tan4 = try_normalize(reject_from(b - a, n));
    if tan4.w == 0.0 {
        return out;
    }
    let tan = tan4.xyz;
    let nb = normalize_glam(rot(m, unpack_unit_vector(info.z)));
    let tb = normalize_glam(rot(m, unpack_unit_vector(info.w)));
    out.valid = true;
    out.root_bind = transform_point3(m.world, root_local);
    out.root_now = a * w.x + b * w.y + c * w.z;
    out.now0 = tan;
    out.now1 = n;
    out.now2 = cross3(n, tan);
    out.bind0 = tb;
    out.bind1 = nb;
    out.bind2 = cross3(nb, tb);
    return out;
}

// RootMotion::apply.
fn apply(mo: RootMotion, p_bind: vec3<f32>) -> vec3<f32> {
    let d = p_bind - mo.root_bind;
    let sum = vec3<f32>(0.0) + mo.now0 * dot3(d, mo.bind0) + mo.now1 * dot3(d, mo.bind1) + mo.now2 * dot3(d, mo.bind2);
    return mo.root_now + sum;
}

// motion.rs: UNORM16 NDC codes, stored plus one; 0 is "not transformed"
// (also a History buffer's first contents).
const UNORM_MAX: f32 = 65534.0;
const NOT_TRANSFORMED: u32 = 0u;

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

// motion::motion: screen motion in pixels (y down), zero where either
// frame did not transform the vertex.
fn screen_motion(prev: u32, c: vec4<f32>) -> vec2<f32> {
    if prev == NOT_TRANSFORMED || !(c.w > frame.near) {
        return vec2<f32>(0.0);
    }
    let p = vec2<f32>(decompress((prev & 0xFFFFu) - 1u), decompress((prev >> 16u) - 1u));
    let n = vec2<f32>(c.x / c.w, c.y / c.w);
    return vec2<f32>((n.x - p.x) * 0.5 * frame.screen.x, (p.y - n.y) * 0.5 * frame.screen.y);
}

// motion::drawn_at: whether a strand of `count` points draws vertex `v` at
// a vertex step.
fn drawn_at(v: u32, step: u32, count: u32) -> bool {
    return v % max(step, 1u) == 0u || v + 1u == count;
}

// A kept strand after skinning: its model, index among the model's kept
// strands, first vertex, point count and vertex step.
struct Skinned {
    found: bool,
    model: u32,
    kept: u32,
    first: u32,
    count: u32,
    step: u32,
}

// Kept strand g (global kept index): its drawn vertices to clip space.
fn skin_strand(g: u32) -> Skinned {
    var out = Skinned(false, 0u, 0u, 0u, 0u, 1u);
    var mi = 0u;
    for (; mi < frame.model_count; mi++) {
        let l = lod_models[mi];
        if g >= l.strand_prefix && g < l.strand_prefix + l.strands {
            out.found = true;
            break;
        }
    }
    if !out.found {
        return out;
    }
    let model = models[mi];
    let lod = load_lod(lod_models[mi]);
    let kept = g - lod.strand_prefix;
    let strand = model.strand_first + kept;
    let fc = groom_strands[strand];
    let first = fc.x;
    let count = fc.y;
    let info = groom_skinning[strand];
    var motion: RootMotion;
    motion.valid = false;
    if model.skinned != 0u {
        motion = root_motion(model, groom_vertices[first].xyz, info);
    }
    var v = 0u;
    loop {
        var p = transform_point3(model.world, groom_vertices[first + v].xyz);
        if motion.valid {
            p = apply(motion, p);
        }
        clip_positions[first + v] = transform(frame.view_proj, vec4<f32>(p, 1.0));
        if v + 1u >= count {
            break;
        }
        v = min(v + lod.vertex_step, count - 1u);
    }
    out.model = mi;
    out.kept = kept;
    out.first = first;
    out.count = count;
    out.step = lod.vertex_step;
    return out;
}

@compute @workgroup_size(64)
fn skin(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    _ = params.reserved;
    let g = wg.x * SKIN_GROUP + lane;
    if g < lod_args[3] {
        skin_strand(g);
    }
}

// kulikov.skin_motion: skinning, then each drawn vertex's motion against
// last frame's history and this frame's NDC over it (motion.rs). Last frame
// transformed the vertex when its LOD kept the strand (kept strands are a
// prefix) and drew that vertex: no cleared cache is needed to tell.
@compute @workgroup_size(64)
fn skin_motion(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    _ = params.reserved;
    let g = wg.x * SKIN_GROUP + lane;
    if g >= lod_args[3] {
        return;
    }
    let s = skin_strand(g);
    if !s.found {
        return;
    }
    let prev = prev_lod_models[s.model];
    let had = s.kept < prev.strands;
    var v = 0u;
    loop {
        let i = s.first + v;
        let c = clip_positions[i];
        var last = NOT_TRANSFORMED;
        if had && drawn_at(v, prev.vertex_step, s.count) {
            last = prev_clip_positions[i];
        }
        vertex_motion[i] = screen_motion(last, c);
        prev_clip_positions[i] = pack(c);
        if v + 1u >= s.count {
            break;
        }
        v = min(v + s.step, s.count - 1u);
    }
}
