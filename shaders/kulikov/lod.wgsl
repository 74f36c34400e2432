// kulikov.lod: how many strands of each model to draw this frame.
// Port of passes/src/kulikov/lod.rs (`choose`), one workgroup of 64 lanes.
// Needs FLOAT64: the segment budget's proportional reduction is computed in
// f64 exactly as the CPU kernel does (`budget as f64 / total as f64`).

#import strandgraph::layout::{FrameData, ModelData, ModelLod, MODEL_LOD_ENABLED}
#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::kulikov::{drawn_segments, MAX_SEGMENTS_PER_MODEL, F32_MAX, F32_MIN}

// LodParams (booleans as 0/1).
struct LodParams {
    enabled: u32,
    max_strands: u32,
    small_model_strands: u32,
    segments_per_tile: u32,
    tile_size: u32,
    segment_budget: u32,
    thickness_compensation: u32,
    max_thickness_scale: f32,
    skip_vertices_beyond_m: f32,
}

@group(0) @binding(0) var<uniform> params: LodParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read_write> lod_models: array<ModelLod>;
@group(0) @binding(4) var<storage, read_write> lod_args: array<u32>;

// Skinning workgroup size (lod::SKIN_GROUP).
const SKIN_GROUP: u32 = 64u;
// lod::DRAWN_GROUP and contract::MAX_COVER_GROUPS.
const DRAWN_GROUP: u32 = 256u;
const MAX_GROUPS: u32 = 65535u;

// lod::screen_extent: (clamped screen area, near, far).
fn screen_extent(m: ModelData) -> vec3<f32> {
    let w = frame.screen.x;
    let h = frame.screen.y;
    var x0 = F32_MAX;
    var y0 = F32_MAX;
    var x1 = F32_MIN;
    var y1 = F32_MIN;
    var near = F32_MAX;
    var far = 0.0;
    var behind = false;
    for (var i = 0u; i < 8u; i++) {
        let p = vec4<f32>(
            select(m.bounds_min.x, m.bounds_max.x, (i & 1u) != 0u),
            select(m.bounds_min.y, m.bounds_max.y, (i & 2u) != 0u),
            select(m.bounds_min.z, m.bounds_max.z, (i & 4u) != 0u),
            1.0,
        );
        let c = transform(frame.view_proj, p);
        near = min(near, c.w);
        far = max(far, c.w);
        if c.w <= frame.near {
            behind = true;
            continue;
        }
        let s = clip_to_screen(c, w, h);
        x0 = min(x0, s.x);
        y0 = min(y0, s.y);
        x1 = max(x1, s.x);
        y1 = max(y1, s.y);
    }
    if behind {
        x0 = 0.0;
        y0 = 0.0;
        x1 = w;
        y1 = h;
    }
    let area = max(min(x1, w) - max(x0, 0.0), 0.0) * max(min(y1, h) - max(y0, 0.0), 0.0);
    let n = max(near, frame.near);
    return vec3<f32>(area, n, max(far, n + 1e-3));
}

// lod::LOD_LANES: the models are dealt out to the lanes, model mi to lane
// mi % LOD_LANES.
const LOD_LANES: u32 = 64u;

// Each lane's share of the segments wanted (exact: see `choose_model`).
var<workgroup> wg_total: array<f64, 64>;
// One block of 64 models' kept strands and drawn segments, for the prefixes.
var<workgroup> wg_strands: array<u32, 64>;
var<workgroup> wg_drawn: array<u32, 64>;

// lod::choose for model mi, before the budget: its strands, vertex step and
// segments per strand; thickness 1 and the prefixes 0.
fn choose_model(mi: u32) -> ModelLod {
    let enabled = params.enabled != 0u;
    let tile_size = max(params.tile_size, 1u);
    let cam = frame.camera_pos.xyz;
    let m = models[mi];
    let extent = screen_extent(m);
    let area = extent.x;
    let points = max(m.points_per_strand, 2u);
    let centre = vec3<f32>(
        0.5 * (m.bounds_min.x + m.bounds_max.x),
        0.5 * (m.bounds_min.y + m.bounds_max.y),
        0.5 * (m.bounds_min.z + m.bounds_max.z),
    );
    let dc = vec3<f32>(centre.x - cam.x, centre.y - cam.y, centre.z - cam.z);
    let distance = sqrt(dc.x * dc.x + dc.y * dc.y + dc.z * dc.z);
    let lod_on = enabled && (m.flags & MODEL_LOD_ENABLED) != 0u;
    let step = select(1u, 2u, lod_on && distance > params.skip_vertices_beyond_m);
    let per_strand = drawn_segments(points, step);
    var n = m.strand_count;
    if area <= 0.0 {
        n = 0u;
    } else if lod_on {
        if n > params.small_model_strands {
            n = min(n, max(params.max_strands, params.small_model_strands));
        }
        let tile_area = f32(tile_size * tile_size);
        let allowed = u32(ceil(f32(params.segments_per_tile) * area / tile_area / f32(per_strand)));
        let floor_n = max(u32(ceil(clamp(m.min_fraction, 0.0, 1.0) * f32(m.strand_count))), 1u);
        n = min(n, max(allowed, floor_n));
    }
    // The payload has 22 bits of segment index per model.
    n = min(n, MAX_SEGMENTS_PER_MODEL / (points - 1u));
    return ModelLod(n, step, 1.0, per_strand, 0u, extent.y, extent.z, 0u);
}

// One workgroup; lane l decides models l, l + 64, ... The CPU kernel
// decides them in one loop; every sum here is of integers (exact in f64 and
// u32), so the order the lanes add in does not change a bit.
@compute @workgroup_size(64)
fn lod(@builtin(local_invocation_index) lane: u32) {
    let count = frame.model_count;
    // First pass: each model's strands, and the segments they want in all.
    var wanted = 0.0lf;
    for (var mi = lane; mi < count; mi += LOD_LANES) {
        let d = choose_model(mi);
        lod_models[mi] = d;
        // Exact: each product is below 2^22 + 2^22 and the sum far below 2^53.
        wanted += f64(d.strands) * f64(d.segments_per_strand);
    }
    wg_total[lane] = wanted;
    workgroupBarrier();
    var total = 0.0lf;
    for (var i = 0u; i < LOD_LANES; i++) {
        total += wg_total[i];
    }
    // Proportional reduction to the segment budget.
    let reduce = params.enabled != 0u && total > f64(params.segment_budget);
    let factor = f64(params.segment_budget) / total;
    // Second pass, 64 models at a time: the budget, thickness compensation,
    // and the kept strands and drawn segments of the earlier models
    // (lod::drawn_dispatch). Lane l reads back only the models it wrote.
    var prefix = 0u;
    var drawn = 0u;
    for (var base = 0u; base < count; base += LOD_LANES) {
        let mi = base + lane;
        var d = ModelLod(0u, 1u, 1.0, 0u, 0u, 0.0, 0.0, 0u);
        if mi < count {
            d = lod_models[mi];
            if reduce {
                d.strands = u32(floor(f64(d.strands) * factor));
            }
            if params.thickness_compensation != 0u && d.strands > 0u {
                // Coverage is additive: keep strands x thickness constant.
                d.thickness_scale =
                    max(min(f32(models[mi].strand_count) / f32(d.strands), params.max_thickness_scale), 1.0);
            }
        }
        wg_strands[lane] = d.strands;
        wg_drawn[lane] = d.strands * d.segments_per_strand;
        workgroupBarrier();
        var before_strands = prefix;
        var before_drawn = drawn;
        for (var i = 0u; i < LOD_LANES; i++) {
            if i == lane {
                before_strands = prefix;
                before_drawn = drawn;
            }
            prefix += wg_strands[i];
            drawn += wg_drawn[i];
        }
        if mi < count {
            d.strand_prefix = before_strands;
            d.segment_prefix = before_drawn;
            lod_models[mi] = d;
        }
        // The next block overwrites the block's counts.
        workgroupBarrier();
    }
    if lane == 0u {
        // The cull's and the sort's dispatch over drawn segments.
        lod_args[4] = min((drawn + DRAWN_GROUP - 1u) / DRAWN_GROUP, MAX_GROUPS);
        lod_args[5] = 1u;
        lod_args[6] = 1u;
        lod_args[7] = drawn;
        lod_args[0] = (prefix + SKIN_GROUP - 1u) / SKIN_GROUP;
        lod_args[1] = 1u;
        lod_args[2] = 1u;
        lod_args[3] = prefix;
    }
}
