// lipp.lod: Lipp §3.2, per-bundle LOD (Eq. 1-5), prefix sum of N_LOD and the
// rasterizer's indirect dispatch arguments. Port of passes/src/lipp/lod.rs:
// one workgroup of 256 threads, each owning a contiguous run of bundles; the
// per-thread sums are scanned in workgroup memory (the deviation from the
// paper's one-thread-per-bundle pass that lod.rs explains).

#import strandgraph::layout::FrameData
#import strandgraph::hash::pcg
#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::lipp::{unit, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, MAX_GROUPS_X, LOD_CULLED, LOD_OTHER_GROOM, F32_MAX, F32_MIN}

// LodParams (booleans as 0/1).
struct LodParams {
    enabled: u32,
    lambda: f32,
    random_delta: u32,
    max_control_points: u32,
    frustum_cull: u32,
    strand_lod: u32,
    resolution_lod: u32,
    // Scene quantity: bundles packed.
    bundles: u32,
    // Only this groom's bundles (the per-model block); ALL_MODELS: every groom.
    model: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const ALL_MODELS: u32 = 0xffffffffu;

// Whether bundle b belongs to the groom(s) this pass decides for.
fn included(b: u32) -> bool {
    return params.model == ALL_MODELS || hairmesh_bundles[b * BUNDLE_WORDS + 3u] == params.model;
}

@group(0) @binding(0) var<uniform> params: LodParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(3) var<storage, read> hairmesh_layers: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> bundle_lod: array<u32>;
@group(0) @binding(5) var<storage, read_write> raster_args: array<u32>;

const LOD_GROUP: u32 = 256u;

var<workgroup> sums: array<u32, 256>;
var<workgroup> full_sums: array<u32, 256>;

// lod::snap_control_points (Lipp Eq. 5).
fn snap_control_points(c_raw: u32, c_max: u32) -> u32 {
    let x = max(c_raw, 3u) - 1u;
    // next_power_of_two(x) for x >= 2.
    let p = 1u << (32u - countLeadingZeros(x - 1u));
    return min(p + 1u, c_max);
}

// lod::choose for bundle b: (N_LOD, C, culled flag).
fn choose(b: u32) -> vec3<u32> {
    if !included(b) {
        return vec3<u32>(0u, 3u, LOD_OTHER_GROOM);
    }
    let o = b * BUNDLE_WORDS;
    let first_layer = hairmesh_bundles[o];
    let layers = clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS);
    let n = hairmesh_bundles[o + 2u];
    let seed = hairmesh_bundles[o + 8u];
    let w = frame.screen.x;
    let h = frame.screen.y;
    // Lipp Eq. 3: AABB of the projected layer quads.
    var lo = vec2<f32>(F32_MAX);
    var hi = vec2<f32>(F32_MIN);
    var behind = false;
    for (var i = 0u; i < layers; i++) {
        for (var k = 0u; k < 4u; k++) {
            let p = hairmesh_layers[(first_layer + i) * LAYER_VEC4S + 2u * k].xyz;
            let c = transform(frame.view_proj, vec4<f32>(p, 1.0));
            if c.w <= frame.near {
                behind = true;
                continue;
            }
            let s = clip_to_screen(c, w, h);
            lo = vec2<f32>(min(lo.x, s.x), min(lo.y, s.y));
            hi = vec2<f32>(max(hi.x, s.x), max(hi.y, s.y));
        }
    }
    let any_in_front = lo.x <= hi.x;
    let outside = !any_in_front || hi.x < 0.0 || lo.x > w || hi.y < 0.0 || lo.y > h;
    let culled = params.frustum_cull != 0u && outside && !behind;
    // Lipp Eq. 2.
    // The groom's own strength multiplies the pass's (0: the groom has LOD off).
    let groom_lambda = bitcast<f32>(hairmesh_bundles[o + 9u]);
    var l = 1.0;
    if params.enabled != 0u && !behind && groom_lambda > 0.0 {
        let dx = hi.x - lo.x;
        let dy = hi.y - lo.y;
        l = clamp(sqrt(dx * dx + dy * dy) / h * (params.lambda * groom_lambda), 0.0, 1.0);
    }
    let delta = select(0.0, unit(pcg(seed)), params.random_delta != 0u);
    // Lipp Eq. 1.
    var strands = n;
    if culled {
        strands = 0u;
    } else if params.strand_lod != 0u && n > 0u {
        strands = clamp(u32(ceil(l * (f32(n) + delta))), 1u, n);
    }
    // Lipp Eq. 4-5.
    let l_res = select(1.0, l, params.resolution_lod != 0u);
    let c_raw = max(u32(floor(sqrt(l_res) * f32(params.max_control_points))), layers);
    let c = snap_control_points(c_raw, params.max_control_points);
    return vec3<u32>(strands, c, select(0u, LOD_CULLED, culled));
}

@compute @workgroup_size(256)
fn lod(@builtin(local_invocation_index) lane: u32) {
    let count = min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS);
    let per = (count + LOD_GROUP - 1u) / LOD_GROUP;
    let begin = min(lane * per, count);
    let end = min(begin + per, count);
    var sum = 0u;
    var full = 0u;
    for (var b = begin; b < end; b++) {
        if included(b) {
            full += hairmesh_bundles[b * BUNDLE_WORDS + 2u];
        }
        let d = choose(b);
        bundle_lod[b * LOD_WORDS] = d.x;
        bundle_lod[b * LOD_WORDS + 1u] = d.y;
        bundle_lod[b * LOD_WORDS + 3u] = d.z;
        sum += d.x;
    }
    sums[lane] = sum;
    full_sums[lane] = full;
    workgroupBarrier();
    if lane == 0u {
        var acc = 0u;
        var acc_full = 0u;
        for (var i = 0u; i < LOD_GROUP; i++) {
            acc_full += full_sums[i];
            let s = sums[i];
            sums[i] = acc;
            acc += s;
        }
        raster_args[0] = min(acc, MAX_GROUPS_X);
        raster_args[1] = 1u;
        raster_args[2] = 1u;
        raster_args[3] = acc;
        // β of Lipp Eq. 8 is word 3 / word 4.
        raster_args[4] = acc_full;
    }
    workgroupBarrier();
    var first = sums[lane];
    for (var b = begin; b < end; b++) {
        bundle_lod[b * LOD_WORDS + 2u] = first;
        first += bundle_lod[b * LOD_WORDS];
    }
}
