// lipp.lod: Lipp §3.2, per-bundle LOD (Eq. 1-5), in the camera's view or
// each light's deep opacity map. Port of passes/src/lipp/lod/{mod,footprint}.rs
// and rect.rs; lipp.lod_scan (lod_scan.wgsl) sums the counts.
//
// The CPU kernel takes a bundle's layers one after another, as the paper's
// thread per bundle would. Here a lane takes one layer (16 lanes a bundle,
// four bundles a workgroup), and the bundle's footprints and box are
// reduced in workgroup memory: min and max are exact, so the decisions are
// the same bits, and a thread no longer waits on 16 layers' loads in a row
// (lod.rs says what it measured).

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
// lod::LOD_GROUP lanes: lod::LOD_BUNDLES bundles, a lane per layer.
const LOD_GROUP: u32 = 64u;
const LOD_BUNDLES: u32 = 4u;
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

// A bundle's layer as one lane sees it, and the reduction's slots: camera
// footprint (lo.xy, hi.xy); box lo.xyz and w = 1 if a corner is behind the
// near plane; box hi.xyz and w = the chord bound; extended-quad centre and
// radius; each light's map footprint.
var<workgroup> fp_red: array<vec4<f32>, LOD_GROUP>;
var<workgroup> lo_red: array<vec4<f32>, LOD_GROUP>;
var<workgroup> hi_red: array<vec4<f32>, LOD_GROUP>;
var<workgroup> centre_red: array<vec4<f32>, LOD_GROUP>;
var<workgroup> light_red: array<vec4<f32>, 256>;
var<workgroup> light_frames: array<LightFrame, MAX_DOM_LIGHTS>;

const EMPTY_FP: vec4<f32> = vec4<f32>(F32_MAX, F32_MAX, F32_MIN, F32_MIN);

fn merge_fp(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(min(a.xy, b.xy), max(a.zw, b.zw));
}

fn to_footprint(v: vec4<f32>) -> Footprint {
    return Footprint(v.xy, v.zw);
}

// The lights with maps (dom::light_frames).
fn map_lights() -> u32 {
    return min(min(frame.light_count, MAX_DOM_LIGHTS), arrayLength(&lights));
}

// Lane `lane`'s layer of its bundle into the reduction slots (identities
// where the lane has no layer).
fn layer_slots(lane: u32, first_layer: u32, i: u32, has_layer: bool) {
    var fp = EMPTY_FP;
    var lo = vec4<f32>(vec3<f32>(F32_MAX), 0.0);
    var hi = vec4<f32>(vec3<f32>(F32_MIN), 0.0);
    var centre = vec4<f32>(0.0);
    for (var l = 0u; l < MAX_DOM_LIGHTS; l++) {
        light_red[lane * MAX_DOM_LIGHTS + l] = EMPTY_FP;
    }
    if has_layer {
        var q: array<vec3<f32>, 4>;
        // footprint::screen (Lipp Eq. 3).
        for (var k = 0u; k < 4u; k++) {
            q[k] = corner(first_layer, i, k);
            let c = transform(frame.view_proj, vec4<f32>(q[k], 1.0));
            if c.w <= frame.near {
                lo.w = 1.0;
                continue;
            }
            let s = clip_to_screen(c, frame.screen.x, frame.screen.y);
            fp = merge_fp(fp, vec4<f32>(s.xy, s.xy));
        }
        if params.light_view == 0u {
            // rect::bundle_box's part of one layer.
            var e: array<vec3<f32>, 4>;
            for (var k = 0u; k < 4u; k++) {
                e[k] = extended_corner(q[0], q[1], q[2], q[3], k);
            }
            let c = (e[0] + e[1] + e[2] + e[3]) * 0.25;
            var r = 0.0;
            for (var k = 0u; k < 4u; k++) {
                lo = vec4<f32>(min(lo.xyz, e[k]), lo.w);
                hi = vec4<f32>(max(hi.xyz, e[k]), 0.0);
                r = max(r, distance(e[k], c));
            }
            centre = vec4<f32>(c, r);
        } else {
            // footprint::light_map: Lipp Eq. 3 in each light's map.
            let res = f32(params.map_resolution);
            for (var l = 0u; l < map_lights(); l++) {
                var m = EMPTY_FP;
                for (var k = 0u; k < 4u; k++) {
                    let p = light_project(light_frames[l], q[k]);
                    let s = vec2<f32>(p.x * res, p.y * res);
                    m = merge_fp(m, vec4<f32>(s, s));
                }
                light_red[lane * MAX_DOM_LIGHTS + l] = m;
            }
        }
    }
    fp_red[lane] = fp;
    lo_red[lane] = lo;
    hi_red[lane] = hi;
    centre_red[lane] = centre;
}

// lod::choose for bundle b from its reduced slots (at lane `lane`):
// (N_LOD, C, screen rectangle, flags).
fn decide(b: u32, lane: u32) -> vec4<u32> {
    let o = b * BUNDLE_WORDS;
    let layers = clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS);
    let n = hairmesh_bundles[o + 2u];
    let seed = hairmesh_bundles[o + 8u];
    let w = frame.screen.x;
    let h = frame.screen.y;
    let fp = to_footprint(fp_red[lane]);
    let behind = lo_red[lane].w != 0.0;
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
        let n_lights = map_lights();
        var l = 0.0;
        for (var li = 0u; li < n_lights; li++) {
            l = max(l, lod_value(to_footprint(light_red[lane * MAX_DOM_LIGHTS + li]), res, lambda));
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
    // The bundle's screen rectangle (rect.rs), which the scan overwrites
    // with its first strand.
    var rect = 0u;
    if params.light_view == 0u && !culled {
        let pad = box_pad(bitcast<f32>(hairmesh_bundles[o + 4u]), bitcast<f32>(hairmesh_bundles[o + 7u]), hi_red[lane].w);
        let r = screen_rect(frame.view_proj, frame.screen.xy, frame.near, lo_red[lane].xyz - pad, hi_red[lane].xyz + pad);
        rect = pack_tiles(r, u32(w), u32(h));
    }
    return vec4<u32>(strands, c, rect, select(0u, LOD_CULLED, culled));
}

@compute @workgroup_size(64)
fn lod(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let count = min(min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS), arrayLength(&lod_choices) / LOD_WORDS);
    if params.light_view != 0u && lane < map_lights() {
        light_frames[lane] = light_frame(lane);
    }
    workgroupBarrier();
    let b = wg.x * LOD_BUNDLES + lane / MAX_LAYERS;
    let i = lane % MAX_LAYERS;
    let o = b * BUNDLE_WORDS;
    let ours = b < count && (params.model == ALL_MODELS || hairmesh_bundles[o + 3u] == params.model);
    var layers = 0u;
    if ours {
        layers = clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS);
    }
    layer_slots(lane, hairmesh_bundles[min(o, arrayLength(&hairmesh_bundles) - 1u)], i, ours && i < layers);
    workgroupBarrier();
    // rect::bundle_box's chord bound between this layer and the one before.
    if ours && i > 0u && i < layers {
        let a = centre_red[lane];
        let p = centre_red[lane - 1u];
        hi_red[lane].w = distance(a.xyz, p.xyz) + a.w + p.w;
    }
    // The bundle's 16 lanes reduced into its first.
    for (var s = MAX_LAYERS / 2u; s > 0u; s >>= 1u) {
        workgroupBarrier();
        if i < s {
            let j = lane + s;
            fp_red[lane] = merge_fp(fp_red[lane], fp_red[j]);
            lo_red[lane] = vec4<f32>(min(lo_red[lane].xyz, lo_red[j].xyz), max(lo_red[lane].w, lo_red[j].w));
            hi_red[lane] = max(hi_red[lane], hi_red[j]);
            for (var l = 0u; l < MAX_DOM_LIGHTS; l++) {
                light_red[lane * MAX_DOM_LIGHTS + l] = merge_fp(light_red[lane * MAX_DOM_LIGHTS + l], light_red[j * MAX_DOM_LIGHTS + l]);
            }
        }
    }
    workgroupBarrier();
    if i != 0u || b >= count {
        return;
    }
    var d = vec4<u32>(0u, 3u, 0u, LOD_OTHER_GROOM);
    if ours {
        d = decide(b, lane);
    }
    lod_choices[b * LOD_WORDS] = d.x;
    lod_choices[b * LOD_WORDS + 1u] = d.y;
    lod_choices[b * LOD_WORDS + 2u] = d.z;
    lod_choices[b * LOD_WORDS + 3u] = d.w;
}
