// lipp.shade: Lipp §3.4, deferred shading of both G-buffer layers, one
// invocation per pixel. Port of passes/src/lipp/shade.rs (compact Chiang 2016
// R/TT/TRT of shaders/lipp/chiang.wgsl, Kajiya-Kay-like multiple scattering, deep-opacity-map shadows
// with Lipp Eq. 8's depth correction, probe lighting with baked AO: L2 SH
// irradiance and a prefiltered GGX lookup for R + TRT, shaders/lipp/probe.wgsl). Writes rgba32f into `shaded`
// (pixel i: vec4 2i centre layer, 2i+1 conservative layer).

// Bindings 1 (frame), 2 (models) and 3 (lights) are declared in dom.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LIGHTS_BINDING 3
// `lights` is also a ShadeParams member, which a plain import would rename
// too (naga_oil decorates every token of an imported name): the binding is
// reached as lipp_dom::lights instead.
#import strandgraph::lipp_dom
#import strandgraph::lipp_dom::{frame, models, light_frame, NO_HIT, OPACITY_SCALE}
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::hash::pcg
#import strandgraph::lipp::{LightFrame, light_frame_of, light_project, unit, safe_normalize, is_empty, unpack_payload, world_position, Sample, PI}
#import strandgraph::chiang::{chiang}
#import strandgraph::probe::{PROBE_LEVELS, probe_alpha_lod, probe_taps, probe_blend, view_facing_normal, probe_lobe}

// ShadeParams (booleans as 0/1).
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
    // The groom shaded (its material), in the per-model block.
    model_index: u32,
    probe_specular: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ShadeParams;
@group(0) @binding(4) var<storage, read> env_sh: array<vec4<f32>, 9>;
@group(0) @binding(5) var<storage, read> gbuffer: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read> raster_args: array<u32>;
@group(0) @binding(7) var<storage, read> dom_depth: array<u32>;
@group(0) @binding(8) var<storage, read> dom_layers: array<u32>;
@group(0) @binding(9) var<storage, read_write> shaded: array<vec4<f32>>;
// probe.rs's layout: 6 lat-long levels of rgba32f, back to back.
@group(0) @binding(10) var<storage, read> env_prefiltered: array<vec4<f32>>;


// shade::depth_correction (Lipp Eq. 8): Δ = −log β.
fn depth_correction(drawn: u32, all: u32) -> f32 {
    if drawn == 0u || all == 0u {
        return 0.0;
    }
    return -log(f32(min(drawn, all)) / f32(all));
}

// shade::Dom::transmittance.
fn dom_transmittance(l: u32, pos: vec3<f32>, delta: f32) -> f32 {
    let res = params.dom_resolution;
    let plane = res * res;
    // dom::light_frames: at most MAX_DOM_LIGHTS (4) lights have maps.
    if l >= min(min(frame.light_count, 4u), arrayLength(&dom_depth) / max(plane, 1u)) {
        return 1.0;
    }
    let lf = light_frame(l);
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
    let d = (q.z - bitcast<f32>(first)) * lf.depth_extent / params.dom_layer_thickness - delta;
    var optical = 0.0;
    for (var k = 0u; k < params.dom_layers; k++) {
        let part = clamp(d - f32(k), 0.0, 1.0);
        let o = dom_layers[(l * params.dom_layers + k) * plane + texel];
        optical += part * f32(o) / OPACITY_SCALE;
    }
    return exp(-optical);
}

const SHADE_GROUP: u32 = 64u;

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

// probe::sample_level.
fn probe_level(k: u32, d: vec3<f32>) -> vec3<f32> {
    let tp = probe_taps(k, d);
    return probe_blend(
        env_prefiltered[tp.texel.x].xyz,
        env_prefiltered[tp.texel.y].xyz,
        env_prefiltered[tp.texel.z].xyz,
        env_prefiltered[tp.texel.w].xyz,
        tp.t,
    );
}

// probe::specular: the R + TRT stand-in lobe's prefiltered radiance, weighted.
fn probe_specular(t: vec3<f32>, v: vec3<f32>, n: vec3<f32>, color: vec3<f32>, roughness: f32, alpha: f32) -> vec3<f32> {
    let lobe = probe_lobe(t, v, n, color, roughness, alpha);
    let lod = probe_alpha_lod(lobe.alpha);
    let k0 = min(u32(floor(lod)), PROBE_LEVELS - 1u);
    let k1 = min(k0 + 1u, PROBE_LEVELS - 1u);
    let a = probe_level(k0, lobe.direction);
    let b = probe_level(k1, lobe.direction);
    return (a + (b - a) * (lod - f32(k0))) * lobe.weight;
}

// shade::shade_sample.
fn shade_sample(s: Sample, x: u32, y: u32) -> vec3<f32> {
    let pos = world_position(frame.inv_view_proj, frame.screen, x, y, s.depth);
    let v = safe_normalize(frame.camera_pos.xyz - pos);
    let t = s.tangent;
    let qu = u32(floor(s.uvw.x * 63.0 + 0.5));
    let qv = u32(floor(s.uvw.y * 63.0 + 0.5));
    let vary = 0.85 + 0.3 * unit(pcg(qu | (qv << 6u)));
    let c = models[params.model_index].color;
    let color = clamp(c.xyz * vary, vec3<f32>(0.0), vec3<f32>(1.0));
    let roughness = c.w;
    let alpha = models[params.model_index].highlight_shift;
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
        if params.dom_shadows != 0u {
            var delta = 0.0;
            if params.lod_depth_correction != 0u {
                delta = depth_correction(raster_args[3], raster_args[4]);
            }
            shadow = dom_transmittance(i, pos, delta);
        }
        let rad = lipp_dom::lights[i].radiance.xyz * atten * shadow;
        var f = chiang(t, l, v, color, roughness, alpha) * params.specular;
        if params.multiple_scattering != 0u {
            let sin_tl = sqrt(max(1.0 - dot(t, l) * dot(t, l), 0.0));
            f += color * (sin_tl / PI);
        }
        out += f * rad;
    }
    if params.probe_lighting != 0u {
        let n = view_facing_normal(t, v);
        let e = max(sh_irradiance(n), vec3<f32>(0.0));
        var spec = vec3<f32>(0.0);
        if params.probe_specular != 0u {
            spec = probe_specular(t, v, n, color, roughness, alpha);
        }
        out += (e / PI * color + spec * params.specular) * s.ao;
    }
    return out;
}

@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pixels = params.width * params.height;
    let i = gid.x;
    if i >= pixels {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    // lipp::gbuffer_layers.
    let layers = max(min(arrayLength(&gbuffer), arrayLength(&shaded)) / max(pixels, 1u), 2u);
    for (var layer = 0u; layer < layers; layer++) {
        let p = gbuffer[layer * pixels + i];
        var c = vec4<f32>(0.0);
        if !is_empty(p) {
            c = vec4<f32>(shade_sample(unpack_payload(p), x, y), 1.0);
        }
        shaded[layers * i + layer] = c;
    }
}
