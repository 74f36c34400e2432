// sim.follow_layers: hair-mesh layers from the simulated bundle chains. Port
// of passes/src/sim/follow.rs (the method and its reasons are there), with
// glam's operation order.

#import strandgraph::layout::ModelData
#import strandgraph::sim::{dot3, normalize3, point}

struct FollowParams {
    bundles: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: FollowParams;
@group(0) @binding(1) var<storage, read> models: array<ModelData>;
@group(0) @binding(2) var<storage, read> hairmesh_bundles: array<u32>;
// Per chain point: simulated and rest positions, rest tangent (groom local).
@group(0) @binding(3) var<storage, read> sim_chain_points: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> sim_chain_rest: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> sim_chain_tangents: array<vec4<f32>>;
// Per layer corner: (position, AO), (tangent, uvw.w).
@group(0) @binding(6) var<storage, read_write> hairmesh_layers: array<vec4<f32>>;

const GROUP: u32 = 64u;
const MAX_LAYERS: u32 = 16u;
const BUNDLE_WORDS: u32 = 16u;
const CORNERS: u32 = 4u;

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// follow::turn.
fn turn(t: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let c = dot3(a, b);
    let zero = vec3<f32>(0.0);
    if all(a == zero) || all(b == zero) || c <= -0.9999 {
        return t;
    }
    let v = cross3(a, b);
    return t * c + cross3(v, t) + v * (dot3(v, t) * (1.0 / (1.0 + c)));
}

fn rest_direction(first: u32, l: u32, n: u32) -> vec3<f32> {
    let ahead = sim_chain_rest[first + min(l + 1u, n - 1u)].xyz;
    let behind = sim_chain_rest[first + max(l, 1u) - 1u].xyz;
    return normalize3(ahead - behind);
}

fn point_direction(first: u32, l: u32, n: u32) -> vec3<f32> {
    let ahead = sim_chain_points[first + min(l + 1u, n - 1u)].xyz;
    let behind = sim_chain_points[first + max(l, 1u) - 1u].xyz;
    return normalize3(ahead - behind);
}

@compute @workgroup_size(64)
fn follow(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let b = wg.x * (GROUP / MAX_LAYERS) + lane / MAX_LAYERS;
    let l = lane % MAX_LAYERS;
    if b >= params.bundles {
        return;
    }
    let o = b * BUNDLE_WORDS;
    let first_layer = hairmesh_bundles[o];
    let n = hairmesh_bundles[o + 1u];
    if l >= n {
        return;
    }
    let world = models[hairmesh_bundles[o + 3u]].world;
    let layer = first_layer + l;
    for (var c = 0u; c < CORNERS; c++) {
        let first = CORNERS * first_layer + c * n;
        let t_local = turn(sim_chain_tangents[first + l].xyz, rest_direction(first, l, n), point_direction(first, l, n));
        let p_local = sim_chain_points[first + l].xyz;
        let p = point(world, p_local);
        // glam's Mat3 * Vec3: column by column.
        let t = normalize3(world[0].xyz * t_local.x + world[1].xyz * t_local.y + world[2].xyz * t_local.z);
        let i = 2u * (4u * layer + c);
        hairmesh_layers[i] = vec4<f32>(p, hairmesh_layers[i].w);
        hairmesh_layers[i + 1u] = vec4<f32>(t, hairmesh_layers[i + 1u].w);
    }
}
