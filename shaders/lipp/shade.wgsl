// lipp.shade: Lipp §3.4, deferred shading of both G-buffer layers, one
// invocation per pixel. Port of passes/src/lipp/shade.rs; the shading of a
// point is shading.wgsl's (shared with the ground truth's
// reference_shade.wgsl). Writes the `shaded` records (shaded.wgsl: RGB9E5
// radiance, depth and hit flags, planar like the G-buffer), and lists the
// workgroup's 64 pixels for lipp.filter if any has a sample (lipp::tiles).
// A workgroup per run of 64 pixels from the groom's screen rectangle's first
// to its last (lipp::rect, the dispatch lipp.lod_scan wrote); a run the
// rectangle's rows pass by returns at once.

#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LIGHTS_BINDING 3
#define ENV_SH_BINDING 4
#define DOM_DEPTH_BINDING 7
#define DOM_LAYERS_BINDING 8
#define ENV_PREFILTERED_BINDING 10
#import strandgraph::lipp_dom::frame
#import strandgraph::lipp::{is_empty, unpack_payload, world_position, Sample}
#import strandgraph::lipp_shading::{ShadeParams, shading_of, shade_point, depth_correction, share_light_frames}
#import strandgraph::lipp_shaded::{shaded_record, pixel_flags, read_by_filter, HIT}
#import strandgraph::lipp_tiles::filter_groups
#import strandgraph::lipp_rect::{ARGS_RECT_LO, ARGS_RECT_HI, FILTER_RECT_LO, FILTER_RECT_HI, rect_from_args, rect_args, rect_runs, group_runs, touches_run}

@group(0) @binding(0) var<uniform> params: ShadeParams;
@group(0) @binding(5) var<storage, read> gbuffer: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read> raster_args: array<u32>;
@group(0) @binding(9) var<storage, read_write> shaded: array<vec2<u32>>;
@group(0) @binding(11) var<storage, read_write> filter_tiles: array<u32>;
// (workgroups, 1, 1, tiles listed): lipp.filter's indirect dispatch.
@group(0) @binding(12) var<storage, read_write> filter_args: array<atomic<u32>>;

var<workgroup> tile_has_hair: atomic<u32>;

const SHADE_GROUP: u32 = 64u;

// shade::shade_sample: the point at the pixel centre's depth.
fn shade_sample(sm: Sample, x: u32, y: u32) -> vec3<f32> {
    let pos = world_position(frame.inv_view_proj, frame.screen, x, y, sm.depth);
    let strand = vec2<u32>(u32(floor(sm.uvw.x * 63.0 + 0.5)), u32(floor(sm.uvw.y * 63.0 + 0.5)));
    var delta = 0.0;
    if params.lod_depth_correction != 0u {
        delta = depth_correction(raster_args[5], raster_args[4]);
    }
    return shade_point(shading_of(params), pos, sm.tangent, strand, sm.ao, params.model_index, delta);
}

// ShadeKernel::shaded_rect: the groom's screen rectangle (lipp::rect);
// workgroup 0 tells lipp.filter.
fn shaded_rect(wg: u32, lane: u32) -> vec4<u32> {
    let r = rect_from_args(raster_args[ARGS_RECT_LO], raster_args[ARGS_RECT_HI]);
    if wg == 0u && lane == 0u {
        let a = rect_args(r);
        atomicStore(&filter_args[FILTER_RECT_LO], a.x);
        atomicStore(&filter_args[FILTER_RECT_HI], a.y);
    }
    return r;
}

// Two threads a pixel, one per G-buffer layer (every other layer past two):
// a far groom covers few tiles, and its pixels' shading, a long chain of
// dependent loads and transcendentals, set the pass's time (shade.rs).
@compute @workgroup_size(128)
fn shade(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let rect = shaded_rect(wg.x, lane);
    let runs = rect_runs(rect, params.width);
    // A run a workgroup; past 65,535 runs a block (rect::Rect::runs_of_group).
    let block = group_runs(runs.y, wg.x, groups.x);
    // Most of a far or mid groom's runs lie beside its rectangle, on the
    // rows it spans: their workgroups leave before computing the light
    // frames and waiting at the barrier (the same for the whole workgroup;
    // lipp.shade at mid 0.070 -> 0.060 ms on the H200).
    var touched = false;
    for (var k = block.x; k < block.y && !touched; k++) {
        touched = touches_run(rect, (runs.x + k) * SHADE_GROUP, SHADE_GROUP, params.width);
    }
    if !touched {
        return;
    }
    share_light_frames(lane);
    workgroupBarrier();
    for (var k = block.x; k < block.y; k++) {
        let run = runs.x + k;
        // The same for the whole workgroup: it skips the run as one.
        if touches_run(rect, run * SHADE_GROUP, SHADE_GROUP, params.width) {
            shade_run(run, lane);
        }
    }
}

// ShadeKernel::shade_run: run `run`'s 64 pixels, two threads a pixel.
fn shade_run(run: u32, lane: u32) {
    if lane == 0u {
        atomicStore(&tile_has_hair, 0u);
    }
    workgroupBarrier();
    let pixels = params.width * params.height;
    let i = run * SHADE_GROUP + lane % SHADE_GROUP;
    if i < pixels {
        let x = i % params.width;
        let y = i / params.width;
        // lipp::gbuffer_layers: 8 bytes a pixel and layer in both.
        let layers = max(min(arrayLength(&gbuffer), arrayLength(&shaded)) / max(pixels, 1u), 2u);
        let centre = gbuffer[i];
        let flags = pixel_flags(frame.near, frame.far, centre, gbuffer[pixels + i], params.front_threshold);
        for (var layer = lane / SHADE_GROUP; layer < layers; layer += 2u) {
            let p = gbuffer[layer * pixels + i];
            // shaded.rs: the centre layer's record for every pixel (the
            // filter's taps read its flags), the others where a sample is
            // (with read_layers_only, where the filter reads its colour).
            if !is_empty(p) {
                atomicStore(&tile_has_hair, 1u);
                if params.read_layers_only == 0u || read_by_filter(layer, layers, !is_empty(centre), flags) {
                    let c = shade_sample(unpack_payload(p), x, y);
                    shaded[layer * pixels + i] = shaded_record(c, p.y, HIT | flags);
                }
            } else if layer == 0u {
                shaded[i] = shaded_record(vec3<f32>(0.0), 0u, flags);
            }
        }
    }
    workgroupBarrier();
    // tiles::list.
    if lane == 0u && (atomicLoad(&tile_has_hair) != 0u || params.hair_tiles == 0u) {
        let k = atomicAdd(&filter_args[3], 1u);
        filter_tiles[k] = run;
        atomicMax(&filter_args[0], filter_groups(k + 1u, params.filter_lane_budget));
        if k == 0u {
            atomicStore(&filter_args[1], 1u);
            atomicStore(&filter_args[2], 1u);
        }
    }
}
