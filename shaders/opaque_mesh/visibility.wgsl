// scene.visibility: opaque meshes (heads, bodies) into a 64-bit visibility
// buffer, rasterized in compute. Port of passes/src/opaque_mesh/visibility.rs.
//
// One lane per triangle walks its clipped bounding box with exact integer
// edge functions; with `cooperative_above` > 0 (off by default, see the
// Rust side), larger boxes are queued and walked by the whole workgroup,
// one pixel per lane. Each covered pixel
// keeps (depth bits << 32 | triangle) with one atomicMin: the nearest
// triangle, ties to the lower index, whatever the order.
//
// Bindings (group 0): 0 = parameters, 1 = frame, 2 = mesh.triangles,
// 3 = scene.visibility (cleared to all-ones by common.clear).
//
#import strandgraph::layout::{FrameData, TriangleData}
#import strandgraph::opaque_setup::{Setup, setup_world, box_pixels, edges, step_x, covers, depth_at}

struct VisibilityParams {
    triangles: u32,
    // 0: every lane rasterizes its own triangle.
    cooperative_above: u32,
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: VisibilityParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> mesh_triangles: array<TriangleData>;
@group(0) @binding(3) var<storage, read_write> scene_visibility: array<atomic<u64>>;

const GROUP: u32 = 64u;

var<workgroup> queue: array<u32, GROUP>;
var<workgroup> queued: atomic<u32>;
var<workgroup> queued_total: u32;

fn setup_of(t: u32) -> Setup {
    let tri = mesh_triangles[t];
    return setup_world(tri.a.xyz, tri.b.xyz, tri.c.xyz, frame.view_proj, frame.near, params.width, params.height);
}

fn write(x: u32, y: u32, z: f32, t: u32) {
    // Depth clipping, as hardware discards fragments outside [0, 1].
    if z >= 0.0 && z <= 1.0 {
        atomicMin(&scene_visibility[y * params.width + x], (u64(bitcast<u32>(z)) << 32u) | u64(t));
    }
}

// The lane's own triangle, row by row, stepping edge functions exactly.
fn rasterize_alone(s: Setup, t: u32) {
    let dx = step_x(s);
    for (var y = s.bounds.y; y <= s.bounds.w; y++) {
        var e = edges(s, s.bounds.x, y);
        for (var x = s.bounds.x; x <= s.bounds.z; x++) {
            if covers(s, e) {
                write(x, y, depth_at(s, e), t);
            }
            e += dx;
        }
    }
}

@compute @workgroup_size(64)
fn rasterize(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane == 0u {
        atomicStore(&queued, 0u);
    }
    workgroupBarrier();
    let count = min(params.triangles, arrayLength(&mesh_triangles));
    let t = wg.x * GROUP + lane;
    if t < count {
        let s = setup_of(t);
        if s.valid {
            if params.cooperative_above > 0u && box_pixels(s) > params.cooperative_above {
                queue[atomicAdd(&queued, 1u)] = t;
            } else {
                rasterize_alone(s, t);
            }
        }
    }
    workgroupBarrier();
    if lane == 0u {
        queued_total = atomicLoad(&queued);
    }
    let n = workgroupUniformLoad(&queued_total);
    for (var q = 0u; q < n; q++) {
        let tq = queue[q];
        let s = setup_of(tq);
        let width = s.bounds.z - s.bounds.x + 1u;
        let total = box_pixels(s);
        for (var k = lane; k < total; k += GROUP) {
            let x = s.bounds.x + k % width;
            let y = s.bounds.y + k / width;
            let e = edges(s, x, y);
            if covers(s, e) {
                write(x, y, depth_at(s, e), tq);
            }
        }
    }
}
