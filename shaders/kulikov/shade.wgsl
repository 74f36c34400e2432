// kulikov.shade: per-vertex hair lighting in strand space, one lane per
// visible segment of shading_segments. Marschner R, TT, TRT after Karis 2016
// ("Physically Based Hair Shading in Unreal"; Tafuri 2019's TT/TRT forms are
// not reproduced, Karis's are used for all three lobes), Karis's multiple
// scattering fake, per-lobe artist scalars, self-shadowing None (0),
// VoxelMarch (1) through density_grid, or Baked (2): Kulikov's precomputed
// self-shadowing, clamped L1 SH of scattering events per vertex
// (groom_shadow_sh, baked offline by strandgraph-bake).
// Port of passes/src/kulikov/shade/{mod,karis}.rs.

// Bindings 2..=4 (frame, models, lod_models) are declared in segments.wgsl.
#define FRAME_BINDING 2
#define MODELS_BINDING 3
#define LOD_MODELS_BINDING 4
#import strandgraph::kulikov_segments::{frame, models, lod_models, drawn_segment, world_of_clip}
#import strandgraph::layout::{ModelData, LightData}
#import strandgraph::kulikov::{load_lod, GRID_WORDS, AREA_UNIT, F32_MAX}
#import strandgraph::half::pack_radiance

struct ShadeParams {
    // r, tt, trt scales; scatter (0 = no multiple scattering).
    lobes: vec4<f32>,
    // 0 None, 1 VoxelMarch, 2 Baked.
    self_shadow: u32,
    absorption: f32,
    resolution: u32,
    march_steps: u32,
    ambient: f32,
}

@group(0) @binding(0) var<uniform> params: ShadeParams;
@group(0) @binding(1) var<storage, read> shade_args: array<u32>;
@group(0) @binding(5) var<storage, read> lights: array<LightData>;
@group(0) @binding(6) var<storage, read> shading_segments: array<u32>;
@group(0) @binding(7) var<storage, read> segment_visibility: array<u32>;
@group(0) @binding(8) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> density_grid: array<u32>;
// Per vertex: L1 SH coefficients (Y00, Y1-1 (y), Y10 (z), Y11 (x)) of the
// scattering-event count, biased by -HAIR_MAX_SCATTER_EVENTS where rays missed.
@group(0) @binding(10) var<storage, read> groom_shadow_sh: array<vec4<f32>>;
// rgba16f per vertex: r | g << 16, b | a << 16.
@group(0) @binding(11) var<storage, read_write> vertex_lighting: array<vec2<u32>>;

const GROUP: u32 = 64u;
const PI: f32 = 3.14159265;

// Karis 2016: longitudinal Gaussian and Schlick Fresnel (n = 1.55).
fn hair_g(b: f32, theta: f32) -> f32 {
    return exp(-0.5 * theta * theta / (b * b)) / (sqrt(2.0 * PI) * b);
}

fn hair_f(cos_theta: f32) -> f32 {
    let r = (1.0 - 1.55) / (1.0 + 1.55);
    let f0 = r * r;
    return f0 + (1.0 - f0) * pow(1.0 - cos_theta, 5.0);
}

// karis::hair_shading.
fn hair_shading(t: vec3<f32>, v: vec3<f32>, l: vec3<f32>, color: vec3<f32>, roughness: f32, shift: f32, shadow: f32) -> vec3<f32> {
    let rough = clamp(roughness, 1.0 / 255.0, 1.0);
    let vol = dot(v, l);
    let sin_l = clamp(dot(t, l), -1.0, 1.0);
    let sin_v = clamp(dot(t, v), -1.0, 1.0);
    let cos_d = cos(0.5 * abs(asin(sin_v) - asin(sin_l)));
    let lp = l - sin_l * t;
    let vp = v - sin_v * t;
    let cos_phi = dot(lp, vp) / sqrt(dot(lp, lp) * dot(vp, vp) + 1e-4);
    let cos_half_phi = sqrt(clamp(0.5 + 0.5 * cos_phi, 0.0, 1.0));
    let n_prime = 1.19 / cos_d + 0.36 * cos_d;
    let r2 = rough * rough;
    var s = vec3<f32>(0.0);
    // Karis 2016, R lobe.
    {
        let sa = sin(-shift * 2.0);
        let ca = cos(-shift * 2.0);
        let sh = 2.0 * sa * (ca * cos_half_phi * sqrt(1.0 - sin_v * sin_v) + sa * sin_v);
        let mp = hair_g(r2 * sqrt(2.0) * cos_half_phi, sin_l + sin_v - sh);
        let np = 0.25 * cos_half_phi;
        let fp = hair_f(sqrt(clamp(0.5 + 0.5 * vol, 0.0, 1.0)));
        s += vec3<f32>(params.lobes.x * mp * np * fp);
    }
    // Karis 2016, TT lobe.
    {
        let mp = hair_g(r2 / 2.0, sin_l + sin_v - shift);
        let a = 1.0 / n_prime;
        let h = cos_half_phi * (1.0 + a * (0.6 - 0.8 * cos_phi));
        let f = hair_f(cos_d * sqrt(clamp(1.0 - h * h, 0.0, 1.0)));
        let fp = (1.0 - f) * (1.0 - f);
        let tp = pow(color, vec3<f32>(0.5 * sqrt(max(1.0 - (h * a) * (h * a), 0.0)) / cos_d));
        let np = exp(-3.65 * cos_phi - 3.98);
        s += tp * (params.lobes.y * mp * np * fp);
    }
    // Karis 2016, TRT lobe.
    {
        let mp = hair_g(r2 * 2.0, sin_l + sin_v - shift * 4.0);
        let f = hair_f(cos_d * 0.5);
        let fp = (1.0 - f) * (1.0 - f) * f;
        let tp = pow(color, vec3<f32>(0.8 / cos_d));
        let np = exp(17.0 * cos_phi - 16.78);
        s += tp * (params.lobes.z * mp * np * fp);
    }
    s *= shadow;
    // Karis 2016, multiple scattering (KajiyaKayDiffuseAttenuation).
    if params.lobes.w > 0.0 {
        let kajiya = 1.0 - abs(sin_l);
        var fake_n = v - t * sin_v;
        let len = length(fake_n);
        fake_n = select(v, fake_n / len, len > 0.0);
        let nol = clamp((dot(fake_n, l) + 1.0) / 4.0, 0.0, 1.0);
        let diffuse = (1.0 / PI) * (nol + (kajiya - nol) * 0.33) * params.lobes.w;
        let luma = max(dot(color, vec3<f32>(0.3, 0.59, 0.11)), 1e-4);
        let tint = pow(color / luma, vec3<f32>(1.0 - shadow));
        s += sqrt(color) * diffuse * tint * shadow;
    }
    return max(s, vec3<f32>(0.0));
}

// shade::march: strands crossed from p towards the light through the model's grid.
fn march(model: u32, md: ModelData, p: vec3<f32>, dir: vec3<f32>, max_t: f32) -> f32 {
    let res = params.resolution;
    let r = f32(res);
    var size = vec3<f32>(0.0);
    var t_exit = F32_MAX;
    for (var a = 0u; a < 3u; a++) {
        size[a] = max(md.bounds_max[a] - md.bounds_min[a], 1e-6);
        let lo = md.bounds_min[a];
        let hi = lo + size[a];
        if dir[a] > 1e-8 {
            t_exit = min(t_exit, (hi - p[a]) / dir[a]);
        } else if dir[a] < -1e-8 {
            t_exit = min(t_exit, (lo - p[a]) / dir[a]);
        }
    }
    let voxel = min(size.x, min(size.y, size.z)) / r;
    let volume = size.x * size.y * size.z / (r * r * r);
    let t0 = voxel;
    let t1 = min(max(t_exit, 0.0), max_t);
    if t1 <= t0 {
        return 0.0;
    }
    let dt = (t1 - t0) / f32(params.march_steps);
    var crossed = 0.0;
    for (var i = 0u; i < params.march_steps; i++) {
        let q = p + dir * (t0 + (f32(i) + 0.5) * dt);
        var idx = vec3<u32>(0u);
        var inside = true;
        for (var a = 0u; a < 3u; a++) {
            let f = (q[a] - md.bounds_min[a]) / size[a] * r;
            inside = inside && f >= 0.0 && f < r;
            idx[a] = u32(max(f, 0.0));
        }
        if inside {
            let units = density_grid[model * GRID_WORDS + (idx.z * res + idx.y) * res + idx.x];
            crossed += f32(units) * AREA_UNIT / volume * dt;
        }
    }
    return crossed;
}

// strandgraph_bake::sh::visibility. Kulikov, "Visibility function":
// numScatterEvents = max(0, ProjectL1SH(visSH, lightDirection));
// visibility = exp(-absorption * numScatterEvents).
fn baked_visibility(sh: vec4<f32>, l: vec3<f32>) -> f32 {
    let events = sh.x * 0.2820948 + dot(sh.yzw, vec3<f32>(l.y, l.z, l.x)) * 0.4886025;
    return exp(-params.absorption * max(events, 0.0));
}

fn shade_vertex(model: u32, vertex: u32, p: vec3<f32>, t: vec3<f32>) -> vec3<f32> {
    let md = models[model];
    let cam = frame.camera_pos.xyz;
    let to_cam = cam - p;
    let v = select(vec3<f32>(0.0, 0.0, 1.0), normalize(to_cam), length(to_cam) > 0.0);
    let color = md.color.xyz;
    var out = color * params.ambient;
    for (var i = 0u; i < frame.light_count; i++) {
        let light = lights[i];
        var to_light: vec3<f32>;
        var dist = F32_MAX;
        var falloff = 1.0;
        if light.position_or_direction.w == 0.0 {
            let d = light.position_or_direction.xyz;
            to_light = select(vec3<f32>(0.0), -normalize(d), length(d) > 0.0);
        } else {
            let d = light.position_or_direction.xyz - p;
            let d2 = max(dot(d, d), 1e-4);
            dist = sqrt(d2);
            to_light = d / dist;
            falloff = 1.0 / d2;
        }
        var visibility = 1.0;
        if params.self_shadow == 1u {
            visibility = exp(-params.absorption * march(model, md, p, to_light, dist));
        } else if params.self_shadow == 2u {
            visibility = baked_visibility(groom_shadow_sh[vertex], to_light);
        }
        out += light.radiance.xyz * falloff * hair_shading(t, v, to_light, color, md.color.w, md.highlight_shift, visibility);
    }
    return out;
}

fn store_lighting(v: u32, c: vec3<f32>) {
    vertex_lighting[v] = pack_radiance(c);
}

// shade_sort::MAX_SHADE_GROUPS: the dispatch's cap in x, past which lanes stride.
const MAX_SHADE_GROUPS: u32 = 65535u;

@compute @workgroup_size(64)
fn shade(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    for (var i = wg.x * GROUP + lane; i < shade_args[3]; i += MAX_SHADE_GROUPS * GROUP) {
        shade_segment(i);
    }
}

fn shade_segment(i: u32) {
    let id = shading_segments[i];
    let seg = drawn_segment(id);
    if !seg.valid {
        return;
    }
    let p0 = world_of_clip(clip_positions[seg.va]);
    let p1 = world_of_clip(clip_positions[seg.vb]);
    let d = p0 - p1;
    let t = select(vec3<f32>(0.0, 1.0, 0.0), normalize(d), length(d) > 0.0);
    store_lighting(seg.va, shade_vertex(seg.model, seg.va, p0, t));
    let md = models[seg.model];
    let per = md.points_per_strand - 1u;
    let last = seg.local % per + 1u >= load_lod(lod_models[seg.model]).segments_per_strand;
    let next = id + 1u;
    if last || (segment_visibility[next / 32u] & (1u << (next % 32u))) == 0u {
        store_lighting(seg.vb, shade_vertex(seg.model, seg.vb, p1, t));
    }
}
