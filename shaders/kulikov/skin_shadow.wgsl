// kulikov.skin_shadow: hair shadows and ambient occlusion on opaque pixels,
// marched through every hair model's density grid (Kulikov, "Hair
// volumetric shadows": 6 steps per light, 1 ray with 2 steps for AO).
// Port of passes/src/kulikov/skin_shadow.rs; one invocation per pixel.
// Mask word: bytes 0-2 the visibility of lights 0-2, byte 3 the AO.

#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::kulikov::{GRID_WORDS, AREA_UNIT, F32_MAX}

// SkinShadowParams::uniform.
struct SkinShadowParams {
    width: u32,
    height: u32,
    resolution: u32,
    steps: u32,
    ao_steps: u32,
    ao_distance: f32,
    absorption: f32,
    ao_absorption: f32,
    // Ours: march only the grids a ray from the workgroup's pixels can reach.
    tile_cull: u32,
}

@group(0) @binding(0) var<uniform> params: SkinShadowParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read> lights: array<LightData>;
@group(0) @binding(4) var<storage, read> density_grid: array<u32>;
@group(0) @binding(5) var scene_depth: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> skin_shadow: array<u32>;

const GROUP: u32 = 64u;
const MASK_LIGHTS: u32 = 3u;
const LIT: u32 = 0xFFFFFFFFu;

// skin_shadow/tile.rs: the workgroup's world box (order-preserving bits)
// and which models' grids its rays can reach.
const MARGIN: f32 = 1e-3;
const MASKED_MODELS: u32 = 256u;
var<workgroup> box_lo: array<atomic<u32>, 3>;
var<workgroup> box_hi: array<atomic<u32>, 3>;
var<workgroup> reached: array<atomic<u32>, 8>;

fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b >> 31u) == 1u);
}

fn unordered(u: u32) -> f32 {
    return select(bitcast<f32>(~u), bitcast<f32>(u & 0x7FFFFFFFu), (u >> 31u) == 1u);
}

fn overlap(alo: vec3<f32>, ahi: vec3<f32>, blo: vec3<f32>, bhi: vec3<f32>) -> bool {
    return all(alo <= bhi) && all(blo <= ahi);
}

// tile::slab: does p + t dir, t >= 0, meet [lo, hi]?
fn slab(p: vec3<f32>, dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    var enter = 0.0;
    var exit = F32_MAX;
    for (var a = 0u; a < 3u; a++) {
        if abs(dir[a]) > 1e-8 {
            let t0 = (lo[a] - p[a]) / dir[a];
            let t1 = (hi[a] - p[a]) / dir[a];
            enter = max(enter, min(t0, t1));
            exit = min(exit, max(t0, t1));
        } else if p[a] < lo[a] || p[a] > hi[a] {
            return false;
        }
    }
    return enter <= exit;
}

// tile::TileBox::reaches.
fn tile_reaches(m: u32, tlo: vec3<f32>, thi: vec3<f32>, light_count: u32) -> bool {
    let md = models[m];
    var gmax = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        gmax[a] = md.bounds_min[a] + max(md.bounds_max[a] - md.bounds_min[a], 1e-6);
    }
    let lo = md.bounds_min.xyz - vec3<f32>(MARGIN);
    let hi = gmax + vec3<f32>(MARGIN);
    if params.ao_steps > 0u {
        let d = vec3<f32>(params.ao_distance);
        if overlap(tlo, thi, lo - d, hi + d) {
            return true;
        }
    }
    for (var l = 0u; l < light_count; l++) {
        let light = lights[l].position_or_direction;
        if light.w == 0.0 {
            let d = light.xyz;
            let dir = select(vec3<f32>(0.0), -normalize(d), length(d) > 0.0);
            let h = (thi - tlo) * 0.5;
            if slab((tlo + thi) * 0.5, dir, lo - h, hi + h) {
                return true;
            }
        } else if overlap(min(tlo, light.xyz), max(thi, light.xyz), lo, hi) {
            return true;
        }
    }
    return false;
}

// The workgroup's mask, complete after the barrier that follows the tile
// test. Read from workgroup memory: a private copy indexed at run time
// would live in local memory.
fn is_reached(m: u32) -> bool {
    return m >= MASKED_MODELS || (atomicLoad(&reached[m / 32u]) & (1u << (m % 32u))) != 0u;
}

struct Hit {
    hit: bool,
    world: vec3<f32>,
}

// Pixels::world: the world position at a pixel centre; no hit on background.
fn world_at(x: i32, y: i32) -> Hit {
    var out = Hit(false, vec3<f32>(0.0));
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return out;
    }
    let z = textureLoad(scene_depth, vec2<i32>(x, y), 0).x;
    if !(z < 1.0) {
        return out;
    }
    let ndc = vec4<f32>(
        (f32(x) + 0.5) / f32(params.width) * 2.0 - 1.0,
        1.0 - (f32(y) + 0.5) / f32(params.height) * 2.0,
        z,
        1.0,
    );
    let w = frame.inv_view_proj * ndc;
    out.hit = true;
    out.world = w.xyz / w.w;
    return out;
}

// Pixels::normal's choice on one axis: the neighbour with the smaller step.
fn step_towards(p: vec3<f32>, a: Hit, b: Hit) -> vec3<f32> {
    if a.hit && b.hit {
        let da = a.world - p;
        let db = p - b.world;
        if dot(da, da) <= dot(db, db) {
            return da;
        }
        return db;
    }
    if a.hit {
        return a.world - p;
    }
    if b.hit {
        return p - b.world;
    }
    return vec3<f32>(0.0);
}

fn normal_at(x: i32, y: i32, p: vec3<f32>) -> vec3<f32> {
    let dx = step_towards(p, world_at(x + 1, y), world_at(x - 1, y));
    let dy = step_towards(p, world_at(x, y + 1), world_at(x, y - 1));
    let c = cross(dx, dy);
    let len = length(c);
    let e = frame.camera_pos.xyz - p;
    let to_eye = select(vec3<f32>(0.0, 0.0, 1.0), normalize(e), length(e) > 0.0);
    if len == 0.0 {
        return to_eye;
    }
    let n = c / len;
    let d = dot(n, to_eye);
    if d > 0.0 {
        return n;
    } else if d < 0.0 {
        return -n;
    }
    return to_eye;
}

// skin_shadow::voxel: density units of voxel i, zero outside the grid.
fn voxel(m: u32, i: vec3<i32>) -> f32 {
    let res = i32(params.resolution);
    if any(i < vec3<i32>(0)) || any(i >= vec3<i32>(res)) {
        return 0.0;
    }
    return f32(density_grid[m * GRID_WORDS + u32((i.z * res + i.y) * res + i.x)]);
}

// skin_shadow::lerp.
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// skin_shadow::blend: the trilinear blend of a cell's corners, x first,
// then y, then z. `front` holds the corners at z, `back` at z + 1, each
// as (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1).
fn blend(front: vec4<f32>, back: vec4<f32>, t: vec3<f32>) -> f32 {
    let z0 = lerp(lerp(front.x, front.y, t.x), lerp(front.z, front.w, t.x), t.y);
    let z1 = lerp(lerp(back.x, back.y, t.x), lerp(back.z, back.w, t.x), t.y);
    return lerp(z0, z1, t.z);
}

// skin_shadow::trilinear: density units at q, trilinear between voxel
// centres, zero outside the grid. Inside, one base index and seven
// constant offsets; only cells on the border test each corner.
fn trilinear(m: u32, md: ModelData, size: vec3<f32>, q: vec3<f32>) -> f32 {
    let res = i32(params.resolution);
    let f = (q - md.bounds_min.xyz) / size * f32(res) - vec3<f32>(0.5);
    let i0f = floor(f);
    let t = f - i0f;
    let i = vec3<i32>(i0f);
    if all(i >= vec3<i32>(0)) && all(i < vec3<i32>(res - 1)) {
        let r = u32(res);
        let b = m * GRID_WORDS + u32((i.z * res + i.y) * res + i.x);
        let z = b + r * r;
        let front = vec4<f32>(
            f32(density_grid[b]), f32(density_grid[b + 1u]),
            f32(density_grid[b + r]), f32(density_grid[b + r + 1u]),
        );
        let back = vec4<f32>(
            f32(density_grid[z]), f32(density_grid[z + 1u]),
            f32(density_grid[z + r]), f32(density_grid[z + r + 1u]),
        );
        return blend(front, back, t);
    }
    let front = vec4<f32>(
        voxel(m, i), voxel(m, i + vec3<i32>(1, 0, 0)),
        voxel(m, i + vec3<i32>(0, 1, 0)), voxel(m, i + vec3<i32>(1, 1, 0)),
    );
    let back = vec4<f32>(
        voxel(m, i + vec3<i32>(0, 0, 1)), voxel(m, i + vec3<i32>(1, 0, 1)),
        voxel(m, i + vec3<i32>(0, 1, 1)), voxel(m, i + vec3<i32>(1, 1, 1)),
    );
    return blend(front, back, t);
}

// skin_shadow::crossed: strands crossed through model m's grid, `steps`
// samples at the centres of equal intervals of the ray inside the box.
fn crossed(m: u32, p: vec3<f32>, dir: vec3<f32>, max_t: f32, steps: u32) -> f32 {
    let md = models[m];
    var size = vec3<f32>(0.0);
    var enter = 0.0;
    var exit = F32_MAX;
    for (var a = 0u; a < 3u; a++) {
        size[a] = max(md.bounds_max[a] - md.bounds_min[a], 1e-6);
        let lo = md.bounds_min[a];
        let hi = lo + size[a];
        if abs(dir[a]) > 1e-8 {
            let t0 = (lo - p[a]) / dir[a];
            let t1 = (hi - p[a]) / dir[a];
            enter = max(enter, min(t0, t1));
            exit = min(exit, max(t0, t1));
        } else if p[a] < lo || p[a] > hi {
            return 0.0;
        }
    }
    let t1 = min(exit, max_t);
    if !(enter < exit) || steps == 0u || t1 <= enter {
        return 0.0;
    }
    let res = params.resolution;
    let r = f32(res);
    let volume = size.x * size.y * size.z / (r * r * r);
    let dt = (t1 - enter) / f32(steps);
    var units = 0.0;
    for (var i = 0u; i < steps; i++) {
        let q = p + dir * (enter + (f32(i) + 0.5) * dt);
        units += trilinear(m, md, size, q);
    }
    return units * AREA_UNIT / volume * dt;
}

fn march(p: vec3<f32>, dir: vec3<f32>, max_t: f32, steps: u32) -> f32 {
    var sum = 0.0;
    for (var m = 0u; m < frame.model_count; m++) {
        if is_reached(m) {
            sum += crossed(m, p, dir, max_t, steps);
        }
    }
    return sum;
}

// skin_shadow::unorm8.
fn unorm8(v: f32) -> u32 {
    return u32(floor(clamp(v, 0.0, 1.0) * 255.0 + 0.5));
}

@compute @workgroup_size(64)
fn march_skin(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane < 3u {
        atomicStore(&box_lo[lane], 0xFFFFFFFFu);
        atomicStore(&box_hi[lane], 0u);
    }
    if lane < 8u {
        atomicStore(&reached[lane], select(0u, 0xFFFFFFFFu, params.tile_cull == 0u));
    }
    workgroupBarrier();
    let i = wg.x * GROUP + lane;
    let x = i32(i % params.width);
    let y = i32(i / params.width);
    var here = Hit(false, vec3<f32>(0.0));
    if i < params.width * params.height {
        here = world_at(x, y);
    }
    if here.hit {
        for (var a = 0u; a < 3u; a++) {
            atomicMin(&box_lo[a], ordered(here.world[a]));
            atomicMax(&box_hi[a], ordered(here.world[a]));
        }
    }
    workgroupBarrier();
    let count = min(min(frame.light_count, arrayLength(&lights)), MASK_LIGHTS);
    // An empty box (no surface pixel) keeps lo > hi: nothing to mark.
    if params.tile_cull != 0u && atomicLoad(&box_lo[0]) <= atomicLoad(&box_hi[0]) {
        var tlo = vec3<f32>(0.0);
        var thi = vec3<f32>(0.0);
        for (var a = 0u; a < 3u; a++) {
            tlo[a] = unordered(atomicLoad(&box_lo[a]));
            thi[a] = unordered(atomicLoad(&box_hi[a]));
        }
        for (var m = lane; m < min(frame.model_count, MASKED_MODELS); m += GROUP) {
            if tile_reaches(m, tlo, thi, count) {
                atomicOr(&reached[m / 32u], 1u << (m % 32u));
            }
        }
    }
    workgroupBarrier();
    if i >= params.width * params.height {
        return;
    }
    if !here.hit {
        skin_shadow[i] = LIT;
        return;
    }
    let p = here.world;
    var mask = LIT;
    for (var l = 0u; l < count; l++) {
        let light = lights[l];
        var dir: vec3<f32>;
        var dist = F32_MAX;
        if light.position_or_direction.w == 0.0 {
            let d = light.position_or_direction.xyz;
            dir = select(vec3<f32>(0.0), -normalize(d), length(d) > 0.0);
        } else {
            let d = light.position_or_direction.xyz - p;
            dir = select(vec3<f32>(0.0), normalize(d), length(d) > 0.0);
            dist = length(d);
        }
        let v = exp(-params.absorption * march(p, dir, dist, params.steps));
        mask = (mask & ~(0xFFu << (8u * l))) | (unorm8(v) << (8u * l));
    }
    if params.ao_steps > 0u {
        let n = normal_at(x, y, p);
        let v = exp(-params.ao_absorption * march(p, n, params.ao_distance, params.ao_steps));
        mask = (mask & 0x00FFFFFFu) | (unorm8(v) << 24u);
    }
    skin_shadow[i] = mask;
}
