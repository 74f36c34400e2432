// sim.pbd: dynamic follow-the-leader hair (Müller et al. 2012) with head-SDF
// collisions, one lane per strand. Port of passes/src/sim/pbd.rs (the
// algorithm and its citations are there) and passes/src/sim/sdf.rs, with
// glam's operation order.

#import strandgraph::layout::{FrameData, ModelData}
#import strandgraph::sim::{SimModel, includes, dot3, normalize3, point}

struct PbdParams {
    // 0 Flagged, 1 All, 2 None.
    models: u32,
    substeps: u32,
    gravity: f32,
    gravity_preload: u32,
    ftl_damping: f32,
    damping: f32,
    shape_stiffness: f32,
    collision_margin: f32,
    friction: f32,
    strands: u32,
    hair_friction: f32,
    collision_iterations: u32,
}

// position (w = 1 once written), velocity (w: the collision threshold).
struct SimVertex {
    position: vec4<f32>,
    velocity: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: PbdParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read> sim_models: array<SimModel>;
@group(0) @binding(4) var<storage, read> sim_sdf: array<f32>;
// The rest pose: xyz groom local, w thickness.
@group(0) @binding(5) var<storage, read> sim_rest: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> groom_strands: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read_write> sim_state: array<SimVertex>;
// Simulated strands' local positions go here; the others keep their rest pose.
@group(0) @binding(8) var<storage, read_write> groom_vertices: array<vec4<f32>>;
// Per groom, RES^3 cells of (sum of velocity x, y, z as fixed point, count).
@group(0) @binding(9) var<storage, read> sim_grid: array<u32>;

const GROUP: u32 = 64u;
const SDF_RES: u32 = 40u;
const FIELD_WORDS: u32 = 64000u;
const SIM_COLLIDER: u32 = 2u;
const GRID_RES: u32 = 32u;
const GRID_WORDS: u32 = 131072u;
const VELOCITY_SCALE: f32 = 4096.0;

fn direction(m: mat4x4<f32>, v: vec3<f32>) -> vec3<f32> {
    return (m[0] * v.x + m[1] * v.y + m[2] * v.z).xyz;
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// sdf::sample: distance and gradient; inside_grid is false off the grid.
struct Field {
    distance: f32,
    gradient: vec3<f32>,
    inside_grid: bool,
}

fn field_at(base: u32, i: vec3<u32>, dx: u32, dy: u32, dz: u32) -> f32 {
    return sim_sdf[base + i.x + dx + SDF_RES * (i.y + dy + SDF_RES * (i.z + dz))];
}

fn sample_field(m: u32, q: vec3<f32>) -> Field {
    var out: Field;
    out.inside_grid = false;
    let sim = sim_models[m];
    if (sim.flags & SIM_COLLIDER) == 0u {
        return out;
    }
    let last = f32(SDF_RES - 1u);
    let f = (q - sim.sdf_min.xyz) * sim.sdf_min.w;
    if !(f.x >= 0.0 && f.x <= last && f.y >= 0.0 && f.y <= last && f.z >= 0.0 && f.z <= last) {
        return out;
    }
    let i = min(vec3<u32>(floor(f)), vec3<u32>(SDF_RES - 2u));
    let t = f - vec3<f32>(i);
    let base = m * FIELD_WORDS;
    let c000 = field_at(base, i, 0u, 0u, 0u);
    let c100 = field_at(base, i, 1u, 0u, 0u);
    let c010 = field_at(base, i, 0u, 1u, 0u);
    let c110 = field_at(base, i, 1u, 1u, 0u);
    let c001 = field_at(base, i, 0u, 0u, 1u);
    let c101 = field_at(base, i, 1u, 0u, 1u);
    let c011 = field_at(base, i, 0u, 1u, 1u);
    let c111 = field_at(base, i, 1u, 1u, 1u);
    let x00 = lerp(c000, c100, t.x);
    let x10 = lerp(c010, c110, t.x);
    let x01 = lerp(c001, c101, t.x);
    let x11 = lerp(c011, c111, t.x);
    let y0 = lerp(x00, x10, t.y);
    let y1 = lerp(x01, x11, t.y);
    out.distance = lerp(y0, y1, t.z);
    let ex0 = lerp(c100 - c000, c110 - c010, t.y);
    let ex1 = lerp(c101 - c001, c111 - c011, t.y);
    out.gradient = vec3<f32>(lerp(ex0, ex1, t.z), lerp(x10 - x00, x11 - x01, t.z), y1 - y0);
    out.inside_grid = true;
    return out;
}

// grid::sample: the velocity grid's average about groom-local q.
struct Flow {
    found: bool,
    velocity: vec3<f32>,
}

fn grid_word(i: u32) -> f32 {
    return f32(bitcast<i32>(sim_grid[i]));
}

fn sample_flow(m: u32, q: vec3<f32>) -> Flow {
    var out: Flow;
    out.found = false;
    let placement = sim_models[m].grid_min;
    let f = (q - placement.xyz) * placement.w;
    let last = f32(GRID_RES);
    if !(f.x >= 0.0 && f.x < last && f.y >= 0.0 && f.y < last && f.z >= 0.0 && f.z < last) {
        return out;
    }
    let g = clamp(f - vec3<f32>(0.5), vec3<f32>(0.0), vec3<f32>(last - 1.0));
    let fi = min(floor(g), vec3<f32>(last - 2.0));
    let t = g - fi;
    let i = vec3<u32>(fi);
    var velocity = vec3<f32>(0.0);
    var weight = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let dx = corner & 1u;
        let dy = (corner >> 1u) & 1u;
        let dz = corner >> 2u;
        let w = select(1.0 - t.x, t.x, dx == 1u) * select(1.0 - t.y, t.y, dy == 1u) * select(1.0 - t.z, t.z, dz == 1u);
        let c = m * GRID_WORDS + 4u * (i.x + dx + GRID_RES * (i.y + dy + GRID_RES * (i.z + dz)));
        velocity = velocity + vec3<f32>(grid_word(c), grid_word(c + 1u), grid_word(c + 2u)) * w;
        weight = weight + f32(sim_grid[c + 3u]) * w;
    }
    if weight > 0.0 {
        out.found = true;
        out.velocity = velocity * (1.0 / (weight * VELOCITY_SCALE));
    }
    return out;
}

// What a lane knows of its groom.
struct Strand {
    model: u32,
    world: mat4x4<f32>,
    inv_world: mat4x4<f32>,
    scale: f32,
    first: u32,
}

fn rest_local(s: Strand, v: u32) -> vec3<f32> {
    return sim_rest[s.first + v].xyz;
}

// The collision threshold rides in the velocity's w.
fn store(s: Strand, v: u32, x: vec3<f32>, u: vec3<f32>, limit: f32) {
    sim_state[s.first + v] = SimVertex(vec4<f32>(x, 1.0), vec4<f32>(u, limit));
}

// Strand::threshold.
fn threshold(s: Strand, v: u32, margin: f32) -> f32 {
    let f = sample_field(s.model, rest_local(s, v));
    var d = 0.0;
    if f.inside_grid {
        d = f.distance;
    }
    return min(d, margin);
}

// Strand::collide: hit, with the pushed position and world normal, on contact.
struct Contact {
    hit: bool,
    pushed: vec3<f32>,
    normal: vec3<f32>,
}

fn collide(s: Strand, p: vec3<f32>, limit: f32, reach: f32) -> Contact {
    var out: Contact;
    out.hit = false;
    let q = point(s.inv_world, p);
    let f = sample_field(s.model, q);
    if !f.inside_grid || !(f.distance < limit) {
        return out;
    }
    let n = normalize3(f.gradient);
    if all(n == vec3<f32>(0.0)) {
        return out;
    }
    out.hit = true;
    out.pushed = point(s.world, q + n * ((limit - f.distance) * reach));
    out.normal = normalize3(direction(s.world, n));
    return out;
}

// PbdKernel::release: velocity of the held vertex.
fn release(s: Strand, v: u32, x: vec3<f32>, p: vec3<f32>, contact: bool, n: vec3<f32>, limit: f32, d_next: vec3<f32>, dt: f32) {
    let inv_dt = 1.0 / dt;
    var u = (p - x) * inv_dt - d_next * (params.ftl_damping * inv_dt);
    if contact {
        let un = dot3(u, n);
        let tangential = u - n * un;
        u = tangential * (1.0 - params.friction) + n * max(un, 0.0);
    }
    u = u * max(1.0 - params.damping * dt, 0.0);
    store(s, v, p, u, limit);
}

fn substep(s: Strand, count: u32, dt: f32, accel: vec3<f32>) {
    let root = point(s.world, rest_local(s, 0u));
    // The held vertex.
    var hv = 0u;
    var hx = sim_state[s.first].position.xyz;
    var hp = root;
    var hcontact = false;
    var hn = vec3<f32>(0.0);
    var hlimit = 0.0;
    for (var v = 1u; v < count; v++) {
        let state = sim_state[s.first + v];
        let x = state.position.xyz;
        var u = state.velocity.xyz + accel * dt;
        // Hair-hair friction (Petrovic et al. 2005, §3).
        if params.hair_friction > 0.0 {
            let flow = sample_flow(s.model, point(s.inv_world, x));
            if flow.found {
                u = u + (flow.velocity - u) * params.hair_friction;
            }
        }
        var q = x + u * dt;
        let rest_now = point(s.world, rest_local(s, v));
        q = q + (rest_now - q) * params.shape_stiffness;
        let d_rest = rest_local(s, v) - rest_local(s, v - 1u);
        let length = sqrt(dot3(d_rest, d_rest)) * s.scale;
        var fixed = hp + normalize3(q - hp) * length;
        var contact = false;
        var normal = vec3<f32>(0.0);
        let limit = state.velocity.w;
        for (var k = 0u; k < params.collision_iterations; k++) {
            let c = collide(s, fixed, limit, f32(k + 1u));
            if !c.hit {
                break;
            }
            fixed = hp + normalize3(c.pushed - hp) * length;
            contact = true;
            normal = c.normal;
        }
        let last = collide(s, fixed, min(limit, 0.0), 1.0);
        if last.hit {
            fixed = last.pushed;
            contact = true;
            normal = last.normal;
        }
        release(s, hv, hx, hp, hcontact, hn, hlimit, fixed - q, dt);
        hv = v;
        hx = x;
        hp = fixed;
        hcontact = contact;
        hn = normal;
        hlimit = limit;
    }
    release(s, hv, hx, hp, hcontact, hn, hlimit, vec3<f32>(0.0), dt);
}

fn simulate(s: Strand, count: u32) {
    let fresh = sim_state[s.first].position.w == 0.0;
    if frame.sim_reset != 0u || fresh {
        let margin = params.collision_margin * (1.0 / s.scale);
        for (var v = 0u; v < count; v++) {
            store(s, v, point(s.world, rest_local(s, v)), vec3<f32>(0.0), threshold(s, v, margin));
        }
    }
    if !(frame.delta_time > 0.0) {
        return;
    }
    var preload = vec3<f32>(0.0);
    if params.gravity_preload != 0u {
        preload = normalize3(direction(s.world, sim_models[s.model].rest_down.xyz));
    }
    let accel = (vec3<f32>(0.0, -1.0, 0.0) - preload) * params.gravity;
    let dt = frame.delta_time * (1.0 / f32(params.substeps));
    for (var k = 0u; k < params.substeps; k++) {
        substep(s, count, dt, accel);
    }
}

@compute @workgroup_size(64)
fn pbd(@builtin(global_invocation_id) gid: vec3<u32>) {
    let g = gid.x;
    if g >= params.strands {
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
    let range = groom_strands[g];
    let first = range.x;
    let count = range.y;
    // The others keep their rest pose in groom_vertices.
    if !includes(params.models, sim.flags) {
        return;
    }
    let s = Strand(m, models[m].world, sim.inv_world, sim.scale, first);
    simulate(s, count);
    for (var v = 0u; v < count; v++) {
        let l = point(s.inv_world, sim_state[first + v].position.xyz);
        groom_vertices[first + v] = vec4<f32>(l, sim_rest[first + v].w);
    }
}
