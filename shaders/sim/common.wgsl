// What the simulation's passes share (mirrors passes/src/sim/mod.rs).
// Composed with naga_oil:
//   #import strandgraph::sim::{SimModel, includes, dot3, normalize3, point}
#define_import_path strandgraph::sim

// passes/src/sim/mod.rs: SimModel, 128 bytes.
// sim::SIM_SIMULATE: the scene marks the groom `simulate: true`.
const SIM_SIMULATE: u32 = 1u;

// pbd::Simulated::includes: whether a pass's `models` (0 Flagged, 1 All,
// 2 None) simulates a groom with SimModel `flags`.
fn includes(models: u32, flags: u32) -> bool {
    if models == 0u {
        return (flags & SIM_SIMULATE) != 0u;
    }
    return models == 1u;
}

struct SimModel {
    inv_world: mat4x4<f32>,
    rest_down: vec4<f32>,
    // xyz: grid point 0 (groom local); w: grid points per unit.
    sdf_min: vec4<f32>,
    scale: f32,
    flags: u32,
    // The groom's strands in the pass's numbering (groom_strands).
    strand_first: u32,
    strand_count: u32,
    // The velocity grid's corner (groom local) and cells per unit (w).
    grid_min: vec4<f32>,
}

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// sim::normalize: one reciprocal; zero for a zero vector.
fn normalize3(v: vec3<f32>) -> vec3<f32> {
    let len = sqrt(dot3(v, v));
    if len > 0.0 {
        return v * (1.0 / len);
    }
    return vec3<f32>(0.0);
}

// glam's Mat4::transform_point3: column by column.
fn point(m: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return (m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]).xyz;
}
