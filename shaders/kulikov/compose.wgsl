// kulikov.compose: every hair model's visibility atlas lit and blended over
// the opaque image, back to front (Kulikov, "Composition"), as one compute
// pass: a lane per screen pixel visits the models in back-to-front order,
// reconstructs each model's radiance and coverage from its 3 layers and the
// additive coverage (Kulikov, "Coverage reconstruction"), blends it
// premultiplied over the pixel (src One, dst OneMinusSrcAlpha, as the talk's
// per-model quads blend), and writes the front layer's depth where the
// coverage reaches depth_threshold and is nearer ("We write hair to depth as
// we render it"), with the pixel's motion: of the segment that wrote the
// depth, else the depth reprojected (compose/motion.rs).
// Why compute rather than the talk's camera-facing quads: Hopper runs pixel
// shaders on few of its SMs, and the quads ran the whole reconstruction twice
// per pixel (colour, then frag_depth); here it runs once, on every SM.
// Port of passes/src/kulikov/compose/{mod,reconstruct}.rs: the CPU kernel is
// the same loop over pixels and models.

#import strandgraph::layout::{FrameData, ModelData, ModelLod, ModelTiles, MODEL_FACIAL_HAIR}
#import strandgraph::half::unpack_radiance
#import strandgraph::kulikov::{load_lod, load_tiles, tile_texel, total_coverage, drawn_in_model, model_trapezoid, quad_pixel_coverage, trapezoid_depth_at, segment_in_model, EMPTY, LAYERS, TILE, SEGMENT_MASK, COVERAGE_SCALE}
#import strandgraph::clip::{near_clip, clip_at3}

struct ComposeParams {
    poisson_samples: u32,
    // 0 Quadratic, 1 Exponential.
    exponential_fit: u32,
    // 0 Exact, 1 Width.
    width_coverage: u32,
    reconstruct_missing: u32,
    depth_threshold: f32,
    facial_hair_bias: f32,
    width: u32,
    height: u32,
    // Skip, per workgroup, models whose tiles cannot reach its pixels.
    workgroup_cull: u32,
    // Atlas layers read, 1..=LAYERS.
    layers: u32,
}

@group(0) @binding(0) var<uniform> params: ComposeParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read> lod_models: array<ModelLod>;
@group(0) @binding(4) var<storage, read> atlas_tiles: array<ModelTiles>;
@group(0) @binding(5) var<storage, read> vis_atlas: array<u32>;
@group(0) @binding(6) var<storage, read> coverage_atlas: array<u32>;
@group(0) @binding(7) var<storage, read> vertex_lighting: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> groom_vertices: array<vec4<f32>>;
@group(0) @binding(10) var scene_depth: texture_2d<f32>;
@group(0) @binding(11) var output: texture_storage_2d<rgba16float, read_write>;
@group(0) @binding(12) var hair_depth: texture_storage_2d<r32float, write>;
@group(0) @binding(13) var<storage, read> prev_frame: FrameData;
// Per vertex: this frame's screen position minus last frame's, pixels.
@group(0) @binding(14) var<storage, read> vertex_motion: array<vec2<f32>>;
@group(0) @binding(15) var<storage, read_write> pixel_motion: array<vec2<f32>>;

const GROUP: u32 = 256u;
// Models whose order fits in workgroup memory; a frame with more takes the
// slow path (each lane ranks the models itself), not a limit.
const MAX_MODELS: u32 = 1024u;
// Back-to-front model order, computed once per workgroup, and per rank
// whether that model's tiles can reach the workgroup's pixels.
var<workgroup> order: array<u32, MAX_MODELS>;
var<workgroup> reaches: array<u32, MAX_MODELS>;

// compose::Span: the screen rectangle of a workgroup's pixels.
struct Span {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

fn group_span(group: u32) -> Span {
    let last = params.width * params.height - 1u;
    let i0 = min(group * GROUP, last);
    let i1 = min(i0 + GROUP - 1u, last);
    let y0 = i0 / params.width;
    let y1 = i1 / params.width;
    if y0 == y1 {
        return Span(i0 % params.width, y0, i1 % params.width, y1);
    }
    return Span(0u, y0, params.width - 1u, y1);
}

// compose::reaches: whether any pixel of `s` can sample model `m`'s tiles,
// its Poisson jitter (at most half the downscale) included.
fn model_reaches(m: u32, s: Span) -> bool {
    let t = load_tiles(atlas_tiles[m]);
    if t.valid == 0u {
        return false;
    }
    let span = TILE * t.downscale;
    let margin = t.downscale / 2u + 1u;
    let lo_x = t.origin_x * span;
    let lo_y = t.origin_y * span;
    let hi_x = (t.origin_x + t.grid_w) * span;
    let hi_y = (t.origin_y + t.grid_h) * span;
    return s.x1 + margin >= lo_x && s.x0 < hi_x + margin && s.y1 + margin >= lo_y && s.y0 < hi_y + margin;
}

const POISSON = array<vec2<f32>, 8>(
    vec2<f32>(0.0, 0.0), vec2<f32>(0.62, 0.18), vec2<f32>(-0.45, 0.55), vec2<f32>(0.12, -0.71),
    vec2<f32>(-0.66, -0.32), vec2<f32>(0.38, 0.78), vec2<f32>(0.85, -0.45), vec2<f32>(-0.1, 0.95),
);

// compose::model_order: the sort key, view distance of the bounds' centre plus the facial bias.
fn sort_key(m: u32) -> f32 {
    let md = models[m];
    let c = 0.5 * (md.bounds_min.xyz + md.bounds_max.xyz) - frame.camera_pos.xyz;
    return sqrt(dot(c, c)) + select(0.0, params.facial_hair_bias, (md.flags & MODEL_FACIAL_HAIR) != 0u);
}

// The model at back-to-front rank `rank` (slow path for frames whose order
// does not fit in workgroup memory).
fn model_at(rank: u32) -> u32 {
    for (var m = 0u; m < frame.model_count; m++) {
        if rank_of(m) == rank {
            return m;
        }
    }
    return 0u;
}

// compose::model_order: the back-to-front rank of model `m` (farthest
// first; ties by index).
fn rank_of(m: u32) -> u32 {
    let k = sort_key(m);
    var r = 0u;
    for (var o = 0u; o < frame.model_count; o++) {
        let ko = sort_key(o);
        if ko > k || (ko == k && o < m) {
            r += 1u;
        }
    }
    return r;
}

fn lighting(v: u32) -> vec3<f32> {
    return unpack_radiance(vertex_lighting[v]);
}

fn pixel_hash(x: u32, y: u32) -> u32 {
    var h = (x * 0x8da6b343u) ^ (y * 0xd8163841u);
    h ^= h >> 15u;
    h = h * 0x2c1b3c6du;
    return h ^ (h >> 12u);
}

struct Hair {
    color: vec3<f32>,
    alpha: f32,
    // View depth of the front layer (0 when none).
    front_w: f32,
    // The front layer's segment and where the sample projects on it (motion::Front).
    front_va: u32,
    front_vb: u32,
    front_t: f32,
}

// One pixel of one model: compose::ComposeKernel and reconstruct::reconstruct.
fn compose_pixel(m: u32, x: u32, y: u32) -> Hair {
    var out = Hair(vec3<f32>(0.0), 0.0, 0.0, 0u, 0u, 0.0);
    let t = load_tiles(atlas_tiles[m]);
    let d = t.downscale;
    var sx = x;
    var sy = y;
    if d > 1u && params.poisson_samples > 0u {
        let j = POISSON[pixel_hash(x, y) % params.poisson_samples] * (0.5 * f32(d));
        sx = u32(clamp(f32(x) + 0.5 + j.x, 0.0, f32(params.width) - 1.0));
        sy = u32(clamp(f32(y) + 0.5 + j.y, 0.0, f32(params.height) - 1.0));
    }
    let texel = tile_texel(t, sx, sy);
    if texel == EMPTY {
        return out;
    }
    let additive = coverage_atlas[texel];
    if additive == 0u {
        return out;
    }
    var c_total = total_coverage(additive);
    if params.exponential_fit != 0u {
        c_total = 1.0 - exp(-f32(additive) / COVERAGE_SCALE);
    }
    let u = i32(sx / d - t.origin_x * TILE);
    let v = i32(sy / d - t.origin_y * TILE);
    let md = models[m];
    let lod = load_lod(lod_models[m]);
    let stride = arrayLength(&vis_atlas) / LAYERS;
    var cov = array<f32, 3>(0.0, 0.0, 0.0);
    var lit = array<vec3<f32>, 3>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var n = 0u;
    for (var l = 0u; l < min(params.layers, LAYERS); l++) {
        let p = vis_atlas[texel + l * stride];
        if p == EMPTY {
            break;
        }
        let id = md.segment_first + (p & SEGMENT_MASK);
        if !segment_in_model(md, id) {
            continue;
        }
        let seg = drawn_in_model(md, lod, m, id);
        if !seg.valid {
            continue;
        }
        let c0 = clip_positions[seg.va];
        let c1 = clip_positions[seg.vb];
        let trap = model_trapezoid(t, lod, c0, c1, groom_vertices[seg.va].w, groom_vertices[seg.vb].w,
            frame.screen.xy, frame.pixels_per_unit, frame.near);
        if !trap.valid {
            continue;
        }
        let c = vec2<f32>(f32(u) + 0.5, f32(v) + 0.5);
        let ab = trap.b - trap.a;
        let tt = clamp(dot(c - trap.a, ab) / dot(ab, ab), 0.0, 1.0);
        var coverage = 0.0;
        if params.width_coverage != 0u {
            let w0 = length(trap.quad.a_plus - trap.quad.a_minus);
            let w1 = length(trap.quad.b_plus - trap.quad.b_minus);
            coverage = clamp(w0 + tt * (w1 - w0), 0.0, 1.0);
        } else {
            coverage = quad_pixel_coverage(trap.quad, u, v);
        }
        if n == 0u {
            out.front_w = trapezoid_depth_at(trap.a, trap.b, trap.wa, trap.wb, u, v);
            out.front_va = seg.va;
            out.front_vb = seg.vb;
            out.front_t = tt;
        }
        cov[n] = clamp(coverage, 0.0, 1.0);
        // The vertex lighting at the ends of the part in front of the near plane.
        let part = near_clip(c0, c1, frame.near);
        let la = lighting(seg.va);
        let lb = lighting(seg.vb);
        lit[n] = mix(clip_at3(la, lb, part.ta), clip_at3(la, lb, part.tb), tt);
        n += 1u;
    }
    // Kulikov: C_front by alpha blending; missing lighting as the weighted
    // average with w_i = C_i * 0.25^(3 - i).
    var front = vec3<f32>(0.0);
    var transmit = 1.0;
    var wsum = 0.0;
    var wl = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        front += transmit * cov[i] * lit[i];
        transmit *= 1.0 - cov[i];
        let w = cov[i] * pow(0.25, f32(n - 1u - i));
        wsum += w;
        wl += w * lit[i];
    }
    out.color = front;
    out.alpha = 1.0 - transmit;
    if params.reconstruct_missing != 0u && wsum > 0.0 {
        let c_missing = max(clamp(c_total, 0.0, 1.0) - out.alpha, 0.0);
        out.color = front + c_missing * wl / wsum;
        out.alpha += c_missing;
    }
    return out;
}

// motion::reprojected: the surface at depth z moved by the camera alone;
// zero without a previous camera or behind its near plane.
fn reprojected(x: u32, y: u32, z: f32) -> vec2<f32> {
    if prev_frame.screen.x <= 0.0 {
        return vec2<f32>(0.0);
    }
    let w = frame.screen.x;
    let h = frame.screen.y;
    let ndc = vec2<f32>((f32(x) + 0.5) / w * 2.0 - 1.0, 1.0 - (f32(y) + 0.5) / h * 2.0);
    let world = frame.inv_view_proj * vec4<f32>(ndc, z, 1.0);
    let c = prev_frame.view_proj * (world / world.w);
    if !(c.w > prev_frame.near) {
        return vec2<f32>(0.0);
    }
    let p = c.xy / c.w;
    return vec2<f32>((ndc.x - p.x) * 0.5 * w, (p.y - ndc.y) * 0.5 * h);
}

@compute @workgroup_size(256)
fn compose(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let models_n = frame.model_count;
    let shared_order = models_n <= MAX_MODELS;
    let span = group_span(wg.x);
    for (var m = lane; shared_order && m < models_n; m += GROUP) {
        let r = rank_of(m);
        order[r] = m;
        reaches[r] = select(1u, u32(model_reaches(m, span)), params.workgroup_cull != 0u);
    }
    workgroupBarrier();
    let i = wg.x * GROUP + lane;
    if i >= params.width * params.height {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    let scene_z = textureLoad(scene_depth, vec2<u32>(x, y), 0).x;
    var z = scene_z;
    var color = textureLoad(output, vec2<u32>(x, y));
    var touched = false;
    // The front layer that wrote the depth, for motion.
    var front = false;
    var front_va = 0u;
    var front_vb = 0u;
    var front_t = 0.0;
    for (var r = 0u; r < models_n; r++) {
        var m = 0u;
        var reach = 1u;
        if shared_order {
            m = order[r];
            reach = reaches[r];
        } else {
            m = model_at(r);
            reach = select(1u, u32(model_reaches(m, span)), params.workgroup_cull != 0u);
        }
        if reach == 0u || load_tiles(atlas_tiles[m]).valid == 0u {
            continue;
        }
        let h = compose_pixel(m, x, y);
        if h.alpha <= 0.0 && h.front_w <= 0.0 {
            continue;
        }
        color = vec4<f32>(h.color + (1.0 - h.alpha) * color.rgb, h.alpha + (1.0 - h.alpha) * color.a);
        touched = true;
        // compose::ndc_depth of the front layer, where nearer.
        if h.alpha >= params.depth_threshold && h.front_w > 0.0 {
            let hz = frame.far * (h.front_w - frame.near) / (h.front_w * (frame.far - frame.near));
            if hz < z {
                z = hz;
                front = true;
                front_va = h.front_va;
                front_vb = h.front_vb;
                front_t = h.front_t;
            }
        }
    }
    var m = vec2<f32>(0.0);
    if front {
        let ma = vertex_motion[front_va];
        m = ma + front_t * (vertex_motion[front_vb] - ma);
    } else if z < 1.0 {
        m = reprojected(x, y, z);
    }
    pixel_motion[i] = m;
    if touched {
        textureStore(output, vec2<u32>(x, y), color);
    }
    textureStore(hair_depth, vec2<u32>(x, y), vec4<f32>(z, 0.0, 0.0, 1.0));
}
