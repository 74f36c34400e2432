// lipp.occlusion (ours): bundles behind the opaque depth's Hi-Z draw no
// strand. A thread per bundle copies lipp.lod's decisions, flagging those
// hidden. Port of
// passes/src/lipp/lod/occlusion.rs (the bounds and why they hold are there).

#import strandgraph::layout::FrameData
#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::kulikov::HIZ_FACTOR
#import strandgraph::lipp::{BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, LOD_OCCLUDED, BOX_BITS_SHIFT, F32_MAX, F32_MIN}

struct OcclusionParams {
    enabled: u32,
    // Scene quantity: bundles packed.
    bundles: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: OcclusionParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(3) var<storage, read> hairmesh_layers: array<vec4<f32>>;
@group(0) @binding(4) var hiz: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> lod_choices: array<u32>;
@group(0) @binding(6) var<storage, read_write> lod_visible: array<u32>;

// occlusion.rs constants.
const GROUP: u32 = 64u;
const TWIST_REACH: f32 = 0.25;
const HERMITE_BULGE: f32 = 0.3;
const NOISE_REACH: f32 = 1.75;
const MAX_BLOCKS: u32 = 1024u;
const DEPTH_MARGIN: f32 = 1e-5;

// occlusion::extended_corner.
fn extended_corner(layer: u32, k: u32) -> vec3<f32> {
    let base = layer * LAYER_VEC4S;
    let c0 = hairmesh_layers[base].xyz;
    let c1 = hairmesh_layers[base + 2u].xyz;
    let c2 = hairmesh_layers[base + 4u].xyz;
    let c3 = hairmesh_layers[base + 6u].xyz;
    let lo = -TWIST_REACH;
    let hi = 1.0 + TWIST_REACH;
    let u = select(lo, hi, k == 1u || k == 2u);
    let v = select(lo, hi, k >= 2u);
    let bottom = c0 + (c1 - c0) * u;
    let top = c3 + (c2 - c3) * u;
    return bottom + (top - bottom) * v;
}

// occlusion::box_hidden.
fn box_hidden(lo: vec3<f32>, hi: vec3<f32>) -> bool {
    let w = frame.screen.x;
    let h = frame.screen.y;
    var s_lo = vec2<f32>(F32_MAX);
    var s_hi = vec2<f32>(F32_MIN);
    var nearest = F32_MAX;
    for (var i = 0u; i < 8u; i++) {
        let p = select(lo, hi, vec3<bool>((i & 1u) != 0u, (i & 2u) != 0u, (i & 4u) != 0u));
        let c = transform(frame.view_proj, vec4<f32>(p, 1.0));
        if c.w <= frame.near {
            return false;
        }
        let s = clip_to_screen(c, w, h);
        s_lo = min(s_lo, s.xy);
        s_hi = max(s_hi, s.xy);
        nearest = min(nearest, s.z);
    }
    // One pixel wider: the rasterizer snaps ends to 1/256 pixel.
    let r_lo = s_lo - vec2<f32>(1.0);
    let r_hi = s_hi + vec2<f32>(1.0);
    if r_hi.x < 0.0 || r_hi.y < 0.0 || r_lo.x >= w || r_lo.y >= h {
        return true;
    }
    let size = vec2<f32>(w, h) - vec2<f32>(1.0);
    let b_lo = vec2<u32>(clamp(r_lo, vec2<f32>(0.0), size)) / HIZ_FACTOR;
    let b_hi = vec2<u32>(clamp(r_hi, vec2<f32>(0.0), size)) / HIZ_FACTOR;
    if (b_hi.x - b_lo.x + 1u) * (b_hi.y - b_lo.y + 1u) > MAX_BLOCKS {
        return false;
    }
    for (var by = b_lo.y; by <= b_hi.y; by++) {
        for (var bx = b_lo.x; bx <= b_hi.x; bx++) {
            if textureLoad(hiz, vec2<u32>(bx, by), 0).x + DEPTH_MARGIN >= nearest {
                return false;
            }
        }
    }
    return true;
}

// occlusion::bundle_boxes' box j (pieces between layers j and j + 1).
struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

fn piece_box(first: u32, j: u32, style: f32) -> Box {
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(F32_MIN);
    var chord = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let p = extended_corner(first + j, k);
        for (var l = 0u; l < 4u; l++) {
            let q = extended_corner(first + j + 1u, l);
            chord = max(chord, distance(p, q));
            lo = min(lo, min(p, q));
            hi = max(hi, max(p, q));
        }
    }
    let pad = vec3<f32>(style + HERMITE_BULGE * chord);
    return Box(lo - pad, hi + pad);
}

// occlusion::hidden_flags for bundle b at c control points.
fn hidden_flags(b: u32, c: u32) -> u32 {
    let o = b * BUNDLE_WORDS;
    let first = hairmesh_bundles[o];
    let n = clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS);
    let style = abs(bitcast<f32>(hairmesh_bundles[o + 4u])) + NOISE_REACH * abs(bitcast<f32>(hairmesh_bundles[o + 7u]));
    if c < n {
        // Fewer control points than layers: one box, the union.
        var all = Box(vec3<f32>(F32_MAX), vec3<f32>(F32_MIN));
        for (var j = 0u; j + 1u < n; j++) {
            let bx = piece_box(first, j, style);
            all = Box(min(all.lo, bx.lo), max(all.hi, bx.hi));
        }
        return select(0u, LOD_OCCLUDED, box_hidden(all.lo, all.hi));
    }
    var mask = 0u;
    for (var j = 0u; j + 1u < n; j++) {
        let bx = piece_box(first, j, style);
        if box_hidden(bx.lo, bx.hi) {
            mask |= 1u << j;
        }
    }
    if mask == 0u {
        return 0u;
    }
    if mask == (1u << (n - 1u)) - 1u {
        // Hidden whole only with the chords across each layer.
        var whole = true;
        for (var j = 0u; j + 2u < n && whole; j++) {
            let a = piece_box(first, j, style);
            let bx = piece_box(first, j + 1u, style);
            whole = box_hidden(min(a.lo, bx.lo), max(a.hi, bx.hi));
        }
        if whole {
            return LOD_OCCLUDED;
        }
    }
    return mask << BOX_BITS_SHIFT;
}

@compute @workgroup_size(64)
fn occlusion(@builtin(global_invocation_id) id: vec3<u32>) {
    let count = min(min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS), min(arrayLength(&lod_choices), arrayLength(&lod_visible)) / LOD_WORDS);
    let b = id.x;
    if b >= count {
        return;
    }
    let o = b * LOD_WORDS;
    var flags = lod_choices[o + 3u];
    if params.enabled != 0u && flags == 0u && lod_choices[o] > 0u {
        flags |= hidden_flags(b, lod_choices[o + 1u]);
    }
    lod_visible[o] = lod_choices[o];
    lod_visible[o + 1u] = lod_choices[o + 1u];
    lod_visible[o + 2u] = lod_choices[o + 2u];
    lod_visible[o + 3u] = flags;
}
