// sim.splat / sim.splat_chains: each simulated vertex's velocity and a count
// into its groom's velocity grid, for hair-hair friction. Port of
// passes/src/sim/grid.rs (the method and its citation are there).

#import strandgraph::layout::FrameData
#import strandgraph::sim::{SimModel, includes, point}

struct SplatParams {
    strands: u32,
    enabled: u32,
    // grid::SplatParams::models: 0 Flagged, 1 All, 2 None.
    models: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: SplatParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> sim_models: array<SimModel>;
@group(0) @binding(3) var<storage, read> groom_strands: array<vec2<u32>>;
// position (w = 1 once written), velocity.
@group(0) @binding(4) var<storage, read> sim_state: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> sim_grid: array<atomic<u32>>;

const GRID_RES: u32 = 32u;
const GRID_WORDS: u32 = 131072u;
const VELOCITY_SCALE: f32 = 4096.0;

// grid::fixed.
fn fixed(v: f32) -> u32 {
    return bitcast<u32>(i32(clamp(floor(v * VELOCITY_SCALE + 0.5), -1e9, 1e9)));
}

@compute @workgroup_size(64)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>) {
    let g = gid.x;
    if g >= params.strands || params.enabled == 0u || frame.sim_reset != 0u {
        return;
    }
    var m = 0u;
    loop {
        if m >= frame.model_count {
            return;
        }
        let d = sim_models[m];
        if g >= d.strand_first && g < d.strand_first + d.strand_count {
            break;
        }
        m++;
    }
    let sim = sim_models[m];
    // The other grooms' strands are not read at all.
    if !includes(params.models, sim.flags) {
        return;
    }
    let range = groom_strands[g];
    // A strand the solver has never written is skipped at its root.
    if range.y == 0u || sim_state[2u * range.x].w == 0.0 {
        return;
    }
    let last = f32(GRID_RES);
    // grid::splat_strand: a run of vertices in one cell is added once.
    var run_cell = 0xffffffffu;
    var run = vec4<u32>(0u);
    for (var v = range.x; v < range.x + range.y; v++) {
        let x = sim_state[2u * v];
        if x.w == 0.0 {
            continue;
        }
        let f = (point(sim.inv_world, x.xyz) - sim.grid_min.xyz) * sim.grid_min.w;
        if !(all(f >= vec3<f32>(0.0)) && all(f < vec3<f32>(last))) {
            continue;
        }
        let i = vec3<u32>(f);
        let cell = i.x + GRID_RES * (i.y + GRID_RES * i.z);
        let u = sim_state[2u * v + 1u];
        let add = vec4<u32>(fixed(u.x), fixed(u.y), fixed(u.z), 1u);
        if cell == run_cell {
            run = run + add;
        } else {
            flush(m, run_cell, run);
            run_cell = cell;
            run = add;
        }
    }
    flush(m, run_cell, run);
}

fn flush(m: u32, cell: u32, sum: vec4<u32>) {
    if cell == 0xffffffffu {
        return;
    }
    let o = m * GRID_WORDS + 4u * cell;
    atomicAdd(&sim_grid[o], sum.x);
    atomicAdd(&sim_grid[o + 1u], sum.y);
    atomicAdd(&sim_grid[o + 2u], sum.z);
    atomicAdd(&sim_grid[o + 3u], sum.w);
}
