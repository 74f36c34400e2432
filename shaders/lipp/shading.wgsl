// Lipp §3.4's shading of one strand point, shared by lipp.shade (per
// G-buffer sample, shade.wgsl) and lipp.reference_shade (per strand point of
// the ground truth, reference_shade.wgsl). Port of passes/src/lipp/shade.rs
// (shade_point): the compact Chiang 2016 R/TT/TRT of chiang.wgsl,
// Kajiya-Kay-like multiple scattering, deep-opacity-map shadows looked up
// `delta` layers nearer the light (Lipp Eq. 8), probe lighting with baked
// AO (L2 SH irradiance and a prefiltered GGX lookup for R + TRT, probe.wgsl).
// Composed with naga_oil; the importer places the bindings:
//   #define FRAME_BINDING 1
//   #define MODELS_BINDING 2
//   #define LIGHTS_BINDING 3
//   #define ENV_SH_BINDING 4
//   #define DOM_DEPTH_BINDING 7
//   #define DOM_LAYERS_BINDING 8
//   #define ENV_PREFILTERED_BINDING 10
//   #import strandgraph::lipp_shading::{ShadeParams, shading_of, shade_point, depth_correction}
#define_import_path strandgraph::lipp_shading

#import strandgraph::lipp_dom
#import strandgraph::lipp_dom::{frame, models, light_frame, NO_HIT, OPACITY_SCALE}
#import strandgraph::hash::pcg
#import strandgraph::lipp::{LightFrame, light_project, unit, safe_normalize, PI}
#import strandgraph::chiang::{chiang, fibre_paths, FibrePaths}
#import strandgraph::probe::{PROBE_LEVELS, latlong_uv, probe_alpha_lod, probe_taps, probe_blend, view_facing_normal, probe_lobe}

@group(0) @binding(#{ENV_SH_BINDING}) var<storage, read> env_sh: array<vec4<f32>, 9>;
@group(0) @binding(#{DOM_DEPTH_BINDING}) var<storage, read> dom_depth: array<u32>;
@group(0) @binding(#{DOM_LAYERS_BINDING}) var<storage, read> dom_layers: array<u32>;
// probe.rs's layout: 6 lat-long levels of rgba32f, back to back.
@group(0) @binding(#{ENV_PREFILTERED_BINDING}) var<storage, read> env_prefiltered: array<vec4<f32>>;

// shade::ShadeGpu: the parameters of lipp.shade and lipp.reference_shade
// (booleans as 0/1).
struct ShadeParams {
    multiple_scattering: u32,
    probe_lighting: u32,
    specular: f32,
    // Scene quantities.
    width: u32,
    height: u32,
    lights: u32,
    dom_shadows: u32,
    lod_depth_correction: u32,
    dom_resolution: u32,
    dom_layers: u32,
    dom_layer_thickness: f32,
    // lipp.shade: the groom shaded (its material), in the per-model block.
    model_index: u32,
    probe_specular: u32,
    // lipp.reference_shade: the point slots to shade (0 in lipp.shade).
    slots: u32,
    // lipp.shade: list only the tiles with hair (lipp::tiles).
    hair_tiles: u32,
    // lipp.shade: metres a flyaway lies in front (shaded::FRONT), and
    // whether only the samples lipp.filter reads are shaded (shade.rs).
    front_threshold: f32,
    read_layers_only: u32,
    // lipp.shade: the lanes lipp.filter's dispatch is sized for (tiles.rs).
    filter_lane_budget: u32,
    reserved_b: u32,
    reserved_c: u32,
}

// shade::ShadeParams as the shading reads it (booleans as 0/1).
struct Shading {
    multiple_scattering: u32,
    probe_lighting: u32,
    probe_specular: u32,
    specular: f32,
    dom_shadows: u32,
    // The maps' geometry (shade::ShadeParams::dom_*; named apart from the
    // dom_layers binding, which naga_oil would rename with it).
    map_resolution: u32,
    map_layers: u32,
    map_layer_thickness: f32,
}

// The shading's part of the passes' parameters.
fn shading_of(p: ShadeParams) -> Shading {
    return Shading(
        p.multiple_scattering,
        p.probe_lighting,
        p.probe_specular,
        p.specular,
        p.dom_shadows,
        p.dom_resolution,
        p.dom_layers,
        p.dom_layer_thickness,
    );
}

// shade::depth_correction (Lipp Eq. 8): Δ = −log β.
fn depth_correction(drawn: u32, all: u32) -> f32 {
    if drawn == 0u || all == 0u {
        return 0.0;
    }
    return -log(f32(min(drawn, all)) / f32(all));
}

// dom::light_frames of the lights with maps, once per workgroup: each is a
// loop over every model's bounds, which per sample and light (40 models in
// the crowd) cost more than the rest of the lookup.
var<workgroup> dom_frames: array<LightFrame, 4>;

// Lanes 0 to 3 compute the frames; every caller puts a workgroupBarrier
// between this and its first shading.
fn share_light_frames(lane: u32) {
    if lane < min(frame.light_count, 4u) {
        dom_frames[lane] = light_frame(lane);
    }
}

// shade::Dom::transmittance.
fn dom_transmittance(s: Shading, l: u32, pos: vec3<f32>, delta: f32) -> f32 {
    let res = s.map_resolution;
    let plane = res * res;
    // dom::light_frames: at most MAX_DOM_LIGHTS (4) lights have maps.
    if l >= min(min(frame.light_count, 4u), arrayLength(&dom_depth) / max(plane, 1u)) {
        return 1.0;
    }
    let lf = dom_frames[l];
    let q = light_project(lf, pos);
    let x = floor(q.x * f32(res));
    let y = floor(q.y * f32(res));
    if !(x >= 0.0 && y >= 0.0 && x < f32(res) && y < f32(res)) {
        return 1.0;
    }
    let texel = u32(y) * res + u32(x);
    let first = dom_depth[l * plane + texel];
    if first == NO_HIT {
        return 1.0;
    }
    let d = (q.z - bitcast<f32>(first)) * lf.depth_extent / s.map_layer_thickness - delta;
    var optical = 0.0;
    for (var k = 0u; k < s.map_layers; k++) {
        let part = clamp(d - f32(k), 0.0, 1.0);
        let o = dom_layers[(l * s.map_layers + k) * plane + texel];
        optical += part * f32(o) / OPACITY_SCALE;
    }
    return exp(-optical);
}

// shade::sh_irradiance (Ramamoorthi and Hanrahan 2001, Eq. 13).
fn sh_irradiance(n: vec3<f32>) -> vec3<f32> {
    let c1 = 0.429043;
    let c2 = 0.511664;
    let c3 = 0.743125;
    let c4 = 0.886227;
    let c5 = 0.247708;
    let x = n.x;
    let y = n.y;
    let z = n.z;
    return c1 * env_sh[8].xyz * (x * x - y * y) + c3 * env_sh[6].xyz * z * z + c4 * env_sh[0].xyz
        - c5 * env_sh[6].xyz
        + 2.0 * c1 * (env_sh[4].xyz * x * y + env_sh[7].xyz * x * z + env_sh[5].xyz * y * z)
        + 2.0 * c2 * (env_sh[3].xyz * x + env_sh[1].xyz * y + env_sh[2].xyz * z);
}

// probe::sample_level, at lat-long (u, v).
fn probe_level(k: u32, uv: vec2<f32>) -> vec3<f32> {
    let tp = probe_taps(k, uv);
    return probe_blend(
        env_prefiltered[tp.texel.x].xyz,
        env_prefiltered[tp.texel.y].xyz,
        env_prefiltered[tp.texel.z].xyz,
        env_prefiltered[tp.texel.w].xyz,
        tp.t,
    );
}

// probe::specular (specular_lobe): the R + TRT stand-in lobe's prefiltered radiance, weighted.
fn specular_lobe(t: vec3<f32>, v: vec3<f32>, n: vec3<f32>, albedo: vec4<f32>, roughness: f32, alpha: f32) -> vec3<f32> {
    let lobe = probe_lobe(t, v, n, albedo, roughness, alpha);
    let lod = probe_alpha_lod(lobe.alpha);
    let k0 = min(u32(floor(lod)), PROBE_LEVELS - 1u);
    let k1 = min(k0 + 1u, PROBE_LEVELS - 1u);
    let uv = latlong_uv(lobe.direction);
    let a = probe_level(k0, uv);
    let b = probe_level(k1, uv);
    return (a + (b - a) * (lod - f32(k0))) * lobe.weight;
}

// shade::shade_point: radiance towards the camera from `pos` on a strand of
// model `model_index` with tangent `t`, strand (u, v) in 1/63 steps `strand`
// and baked AO `ao`.
fn shade_point(s: Shading, pos: vec3<f32>, t: vec3<f32>, strand: vec2<u32>, ao: f32, model_index: u32, delta: f32) -> vec3<f32> {
    let v = safe_normalize(frame.camera_pos.xyz - pos);
    let vary = 0.85 + 0.3 * unit(pcg(strand.x | (strand.y << 6u)));
    let c = models[model_index].color;
    let color = clamp(c.xyz * vary, vec3<f32>(0.0), vec3<f32>(1.0));
    let roughness = c.w;
    let alpha = models[model_index].highlight_shift;
    // What the fibre's lobes need of the view, for every light and the probe.
    let paths = fibre_paths(dot(t, v), color, roughness);
    var out = vec3<f32>(0.0);
    let count = min(frame.light_count, arrayLength(&lipp_dom::lights));
    for (var i = 0u; i < count; i++) {
        let pd = lipp_dom::lights[i].position_or_direction;
        var l = safe_normalize(-pd.xyz);
        var atten = 1.0;
        if pd.w != 0.0 {
            let d = pd.xyz - pos;
            l = safe_normalize(d);
            atten = 1.0 / max(dot(d, d), 1e-4);
        }
        var shadow = 1.0;
        if s.dom_shadows != 0u {
            shadow = dom_transmittance(s, i, pos, delta);
        }
        let rad = lipp_dom::lights[i].radiance.xyz * atten * shadow;
        var f = chiang(t, l, v, paths, roughness, alpha) * s.specular;
        if s.multiple_scattering != 0u {
            let sin_tl = sqrt(max(1.0 - dot(t, l) * dot(t, l), 0.0));
            f += color * (sin_tl / PI);
        }
        out += f * rad;
    }
    if s.probe_lighting != 0u {
        let n = view_facing_normal(t, v);
        let e = max(sh_irradiance(n), vec3<f32>(0.0));
        var spec = vec3<f32>(0.0);
        if s.probe_specular != 0u {
            spec = specular_lobe(t, v, n, paths.albedo, roughness, alpha);
        }
        out += (e / PI * color + spec * s.specular) * ao;
    }
    return out;
}
