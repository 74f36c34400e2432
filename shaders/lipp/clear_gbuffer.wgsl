// lipp.clear_gbuffer (ours): every G-buffer layer cleared over the runs of
// 64 pixels the groom's screen rectangle touches, the runs lipp.shade
// shades, a workgroup a block of runs (lipp::rect::Rect::run_dispatch).
// Port of passes/src/lipp/clear.rs.

#import strandgraph::lipp_rect::{ARGS_RECT_LO, ARGS_RECT_HI, RUN, rect_from_args, rect_runs, group_runs, touches_run}

struct ClearParams {
    width: u32,
    height: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: ClearParams;
@group(0) @binding(1) var<storage, read> raster_args: array<u32>;
@group(0) @binding(2) var<storage, read_write> gbuffer: array<vec2<u32>>;

@compute @workgroup_size(64)
fn clear_gbuffer(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let pixels = max(params.width * params.height, 1u);
    let rect = rect_from_args(raster_args[ARGS_RECT_LO], raster_args[ARGS_RECT_HI]);
    let runs = rect_runs(rect, params.width);
    let layers = arrayLength(&gbuffer) / pixels;
    // This workgroup's block of the runs (rect::Rect::runs_of_group).
    let block = group_runs(runs.y, wg.x, groups.x);
    for (var k = block.x; k < block.y; k++) {
        let run = runs.x + k;
        let i = run * RUN + lane;
        if touches_run(rect, run * RUN, RUN, params.width) && i < pixels {
            for (var layer = 0u; layer < layers; layer++) {
                gbuffer[layer * pixels + i] = vec2<u32>(0xFFFFFFFFu);
            }
        }
    }
}
