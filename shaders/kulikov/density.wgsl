// kulikov.density: every drawn segment adds its projected area (thickness x
// length, in units of AREA_UNIT m^2) to the voxel of its midpoint in its
// model's grid over the model's world bounds, with atomicAdd.
// Port of passes/src/kulikov/density.rs.

// Bindings 1..=3 (frame, models, lod_models) are declared in segments.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LOD_MODELS_BINDING 3
#import strandgraph::kulikov_segments::{frame, models, lod_models, drawn_segment, world_of_clip}
#import strandgraph::layout::ModelData
#import strandgraph::kulikov::{load_lod, round_away, GRID_WORDS, AREA_UNIT}

struct DensityParams {
    // Grid edge (1..=48); density_grid holds 48^3 words per model.
    resolution: u32,
    // Scene quantity: segments in the full numbering.
    segments: u32,
}

@group(0) @binding(0) var<uniform> params: DensityParams;
@group(0) @binding(4) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> groom_vertices: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> density_grid: array<atomic<u32>>;

const GROUP: u32 = 256u;

// density::Grid::voxel: the voxel of p within the model's block, or 0xFFFFFFFF.
fn grid_voxel(md: ModelData, res: u32, p: vec3<f32>) -> u32 {
    let r = f32(res);
    var idx = vec3<u32>(0u);
    for (var a = 0u; a < 3u; a++) {
        let size = max(md.bounds_max[a] - md.bounds_min[a], 1e-6);
        let f = (p[a] - md.bounds_min[a]) / size * r;
        if !(f >= 0.0 && f < r) {
            return 0xFFFFFFFFu;
        }
        idx[a] = u32(f);
    }
    return (idx.z * res + idx.y) * res + idx.x;
}

@compute @workgroup_size(256)
fn density(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let id = wg.x * GROUP + lane;
    if id >= params.segments {
        return;
    }
    let seg = drawn_segment(id);
    if !seg.valid {
        return;
    }
    let md = models[seg.model];
    let a = world_of_clip(clip_positions[seg.va]);
    let b = world_of_clip(clip_positions[seg.vb]);
    let mid = vec3<f32>(0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z));
    let voxel = grid_voxel(md, params.resolution, mid);
    if voxel == 0xFFFFFFFFu {
        return;
    }
    let d = b - a;
    let len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    let thick = 0.5 * (groom_vertices[seg.va].w + groom_vertices[seg.vb].w)
        * load_lod(lod_models[seg.model]).thickness_scale;
    let units = round_away(thick * len / AREA_UNIT);
    if units >= 1.0 && units <= 3.4e38 {
        atomicAdd(&density_grid[seg.model * GRID_WORDS + voxel], u32(min(units, 1e6)));
    }
}
