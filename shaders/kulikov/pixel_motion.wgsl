// kulikov.pixel_motion: per-pixel motion vectors of the composed frame
// (Kulikov, "Composition": "Output lighting, depth and motion"). Port of
// passes/src/kulikov/pixel_motion.rs, which says what each pixel gets: the
// front hair segment's interpolated vertex motion where composition wrote
// its depth, else the depth reprojected with last frame's camera.

#import strandgraph::layout::{FrameData, ModelData, ModelLod, ModelTiles}
#import strandgraph::kulikov::{load_lod, load_tiles, tile_texel, segment_in_model, drawn_in_model, model_trapezoid, trapezoid_depth_at, EMPTY, LAYERS, TILE, SEGMENT_MASK}

struct PixelMotionParams {
    width: u32,
    height: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: PixelMotionParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> prev_frame: FrameData;
@group(0) @binding(3) var<storage, read> models: array<ModelData>;
@group(0) @binding(4) var<storage, read> lod_models: array<ModelLod>;
@group(0) @binding(5) var<storage, read> atlas_tiles: array<ModelTiles>;
@group(0) @binding(6) var<storage, read> vis_atlas: array<u32>;
@group(0) @binding(7) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> groom_vertices: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> vertex_motion: array<vec2<f32>>;
// Hair depth over the scene's (NDC, R32Float), written by kulikov.compose.
@group(0) @binding(10) var hair_depth: texture_2d<f32>;
@group(0) @binding(11) var<storage, read_write> pixel_motion: array<vec2<f32>>;

const GROUP: u32 = 64u;
// pixel_motion::DEPTH_MATCH.
const DEPTH_MATCH: f32 = 1e-6;

struct Front {
    found: bool,
    dz: f32,
    motion: vec2<f32>,
}

// Model m's front layer at (x, y): its distance in NDC depth to z and its
// interpolated vertex motion (compose::segment_trapezoid and axis_t).
fn front_layer(m: u32, x: u32, y: u32, z: f32) -> Front {
    var out = Front(false, 0.0, vec2<f32>(0.0));
    let t = load_tiles(atlas_tiles[m]);
    let texel = tile_texel(t, x, y);
    if texel == EMPTY {
        return out;
    }
    let p = vis_atlas[texel];
    if p == EMPTY {
        return out;
    }
    let md = models[m];
    let lod = load_lod(lod_models[m]);
    let id = md.segment_first + (p & SEGMENT_MASK);
    if !segment_in_model(md, id) {
        return out;
    }
    let seg = drawn_in_model(md, lod, m, id);
    if !seg.valid {
        return out;
    }
    let d = t.downscale;
    let trap = model_trapezoid(t, lod, clip_positions[seg.va], clip_positions[seg.vb],
        groom_vertices[seg.va].w, groom_vertices[seg.vb].w, frame.screen.xy, frame.pixels_per_unit,
        frame.near);
    if !trap.valid {
        return out;
    }
    let u = i32(x / d - t.origin_x * TILE);
    let v = i32(y / d - t.origin_y * TILE);
    let w = trapezoid_depth_at(trap.a, trap.b, trap.wa, trap.wb, u, v);
    let ndc = frame.far * (w - frame.near) / (w * (frame.far - frame.near));
    out.dz = abs(ndc - z);
    if out.dz > DEPTH_MATCH {
        return out;
    }
    let c = vec2<f32>(f32(u) + 0.5, f32(v) + 0.5);
    let ab = trap.b - trap.a;
    let s = clamp(dot(c - trap.a, ab) / dot(ab, ab), 0.0, 1.0);
    let ma = vertex_motion[seg.va];
    let mb = vertex_motion[seg.vb];
    out.found = true;
    out.motion = ma + s * (mb - ma);
    return out;
}

// pixel_motion::reprojected; zero without a previous camera.
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

@compute @workgroup_size(64)
fn resolve_motion(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let i = wg.x * GROUP + lane;
    if i >= params.width * params.height {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    let z = textureLoad(hair_depth, vec2<u32>(x, y), 0).x;
    var m = vec2<f32>(0.0);
    if z < 1.0 {
        var best = Front(false, 0.0, vec2<f32>(0.0));
        for (var mi = 0u; mi < frame.model_count; mi++) {
            let f = front_layer(mi, x, y, z);
            if f.found && (!best.found || f.dz < best.dz) {
                best = f;
            }
        }
        if best.found {
            m = best.motion;
        } else {
            m = reprojected(x, y, z);
        }
    }
    pixel_motion[i] = m;
}
