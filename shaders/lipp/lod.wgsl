// lipp.lod: Lipp §3.2, per-bundle LOD (Eq. 1-5), a thread per bundle, in
// the camera's view or each light's deep opacity map. Port of
// passes/src/lipp/lod/{mod,footprint}.rs; lipp.lod_scan (lod_scan.wgsl)
// sums the counts.

// Bindings 1 (frame), 4 (models) and 5 (lights) are declared in dom.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 4
#define LIGHTS_BINDING 5
#import strandgraph::lipp_dom::{frame, models, lights, light_frame}
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::hash::pcg
#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::lipp_rect::{extended_corner, box_pad, screen_rect, pack_tiles}
#import strandgraph::lipp::{LightFrame, light_project, unit, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, LOD_CULLED, LOD_OTHER_GROOM, F32_MAX, F32_MIN}

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
    // 1: measure in each light's map (lod::View::Light).
    light_view: u32,
    map_resolution: u32,
    camera_bound: u32,
    // Ours: C at most lod::groom_cap of the groom's points per strand.
    groom_resolution: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

const ALL_MODELS: u32 = 0xffffffffu;
// lod::LOD_GROUP.
const LOD_GROUP: u32 = 64u;
// dom::MAX_DOM_LIGHTS.
const MAX_DOM_LIGHTS: u32 = 4u;

@group(0) @binding(0) var<uniform> params: LodParams;
@group(0) @binding(2) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(3) var<storage, read> hairmesh_layers: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> lod_choices: array<u32>;

// footprint::Footprint.
struct Footprint {
    lo: vec2<f32>,
    hi: vec2<f32>,
}

fn empty_footprint() -> Footprint {
    return Footprint(vec2<f32>(F32_MAX), vec2<f32>(F32_MIN));
}

fn corner(first_layer: u32, i: u32, k: u32) -> vec3<f32> {
    return hairmesh_layers[(first_layer + i) * LAYER_VEC4S + 2u * k].xyz;
}

// lod::lod_value (Lipp Eq. 2).
fn lod_value(fp: Footprint, height: f32, lambda: f32) -> f32 {
    let dx = fp.hi.x - fp.lo.x;
    let dy = fp.hi.y - fp.lo.y;
    return clamp(sqrt(dx * dx + dy * dy) / height * lambda, 0.0, 1.0);
}

// footprint::light_map: Lipp Eq. 3 in light lf's map.
fn light_map(lf: LightFrame, res: f32, first_layer: u32, layers: u32) -> Footprint {
    var fp = empty_footprint();
    for (var i = 0u; i < layers; i++) {
        for (var k = 0u; k < 4u; k++) {
            let q = light_project(lf, corner(first_layer, i, k));
            let s = vec2<f32>(q.x * res, q.y * res);
            fp = Footprint(min(fp.lo, s), max(fp.hi, s));
        }
    }
    return fp;
}

// lod::groom_cap: 2 (points - 1) + 1 snapped like Eq. 5, C_max for an
// unknown groom (fewer than 2 points).
fn groom_cap(points: u32, c_max: u32) -> u32 {
    if points < 2u {
        return c_max;
    }
    return snap_control_points(2u * (points - 1u) + 1u, c_max);
}

// lod::snap_control_points (Lipp Eq. 5).
fn snap_control_points(c_raw: u32, c_max: u32) -> u32 {
    let x = max(c_raw, 3u) - 1u;
    // next_power_of_two(x) for x >= 2.
    let p = 1u << (32u - countLeadingZeros(x - 1u));
    return min(p + 1u, c_max);
}

// lod::choose for bundle b: (N_LOD, C, screen rectangle, flags).
fn choose(b: u32) -> vec4<u32> {
    let o = b * BUNDLE_WORDS;
    if params.model != ALL_MODELS && hairmesh_bundles[o + 3u] != params.model {
        return vec4<u32>(0u, 3u, 0u, LOD_OTHER_GROOM);
    }
    let first_layer = hairmesh_bundles[o];
    let layers = clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS);
    let n = hairmesh_bundles[o + 2u];
    let seed = hairmesh_bundles[o + 8u];
    let w = frame.screen.x;
    let h = frame.screen.y;
    // footprint::screen (Lipp Eq. 3), and in the same pass over the layers
    // rect::bundle_box (the camera's view only).
    var fp = empty_footprint();
    var behind = false;
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(F32_MIN);
    var chord = 0.0;
    var prev_c = vec3<f32>(0.0);
    var prev_r = 0.0;
    for (var i = 0u; i < layers; i++) {
        var q: array<vec3<f32>, 4>;
        for (var k = 0u; k < 4u; k++) {
            q[k] = corner(first_layer, i, k);
            let c = transform(frame.view_proj, vec4<f32>(q[k], 1.0));
            if c.w <= frame.near {
                behind = true;
                continue;
            }
            let s = clip_to_screen(c, w, h);
            fp = Footprint(min(fp.lo, s.xy), max(fp.hi, s.xy));
        }
        if params.light_view == 0u {
            var e: array<vec3<f32>, 4>;
            for (var k = 0u; k < 4u; k++) {
                e[k] = extended_corner(q[0], q[1], q[2], q[3], k);
            }
            let centre = (e[0] + e[1] + e[2] + e[3]) * 0.25;
            var r = 0.0;
            for (var k = 0u; k < 4u; k++) {
                lo = min(lo, e[k]);
                hi = max(hi, e[k]);
                r = max(r, distance(e[k], centre));
            }
            if i > 0u {
                chord = max(chord, distance(centre, prev_c) + r + prev_r);
            }
            prev_c = centre;
            prev_r = r;
        }
    }
    // The groom's own strength multiplies the pass's.
    let groom_lambda = bitcast<f32>(hairmesh_bundles[o + 9u]);
    let lambda = params.lambda * groom_lambda;
    var camera_l = 1.0;
    if !behind {
        camera_l = lod_value(fp, h, lambda);
    }
    var culled = false;
    var measured = camera_l;
    if params.light_view == 0u {
        let outside = !(fp.lo.x <= fp.hi.x) || fp.hi.x < 0.0 || fp.lo.x > w || fp.hi.y < 0.0 || fp.lo.y > h;
        culled = params.frustum_cull != 0u && outside && !behind;
    } else {
        let res = f32(params.map_resolution);
        let n_lights = min(min(frame.light_count, MAX_DOM_LIGHTS), arrayLength(&lights));
        var l = 0.0;
        for (var li = 0u; li < n_lights; li++) {
            l = max(l, lod_value(light_map(light_frame(li), res, first_layer, layers), res, lambda));
        }
        if params.camera_bound != 0u {
            l = min(l, camera_l);
        }
        measured = l;
        culled = n_lights == 0u;
    }
    // 0: the groom has LOD off.
    var l = measured;
    if params.enabled == 0u || groom_lambda <= 0.0 {
        l = 1.0;
    }
    let delta = select(0.0, unit(pcg(seed)), params.random_delta != 0u);
    // Lipp Eq. 1.
    // A culled bundle keeps its N_LOD for β (lipp.lod_scan draws none).
    var strands = n;
    if params.strand_lod != 0u && n > 0u {
        strands = clamp(u32(ceil(l * (f32(n) + delta))), 1u, n);
    }
    // Lipp Eq. 4-5.
    let l_res = select(1.0, l, params.resolution_lod != 0u);
    let c_raw = max(u32(floor(sqrt(l_res) * f32(params.max_control_points))), layers);
    var c_max = params.max_control_points;
    if params.groom_resolution != 0u {
        c_max = groom_cap(hairmesh_bundles[o + 10u], c_max);
    }
    let c = snap_control_points(c_raw, c_max);
    var rect = 0u;
    if params.light_view == 0u && !culled {
        let pad = box_pad(bitcast<f32>(hairmesh_bundles[o + 4u]), bitcast<f32>(hairmesh_bundles[o + 7u]), chord);
        let r = screen_rect(frame.view_proj, frame.screen.xy, frame.near, lo - pad, hi + pad);
        rect = pack_tiles(r, u32(w), u32(h));
    }
    return vec4<u32>(strands, c, rect, select(0u, LOD_CULLED, culled));
}

@compute @workgroup_size(64)
fn lod(@builtin(global_invocation_id) id: vec3<u32>) {
    let count = min(min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS), arrayLength(&lod_choices) / LOD_WORDS);
    let b = id.x;
    if b >= count {
        return;
    }
    let d = choose(b);
    lod_choices[b * LOD_WORDS] = d.x;
    lod_choices[b * LOD_WORDS + 1u] = d.y;
    lod_choices[b * LOD_WORDS + 2u] = d.z;
    lod_choices[b * LOD_WORDS + 3u] = d.w;
}
