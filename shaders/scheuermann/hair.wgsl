// scheuermann.hair: Scheuermann 2004's polygonal hair, one stage of its
// "Optimized Rendering Scheme" per graph pass. Port of
// passes/src/scheuermann/{hair,shading,texture}.rs; the pipeline state of
// each stage (culling, depth test, blending) is `stage_state` there.
//
// Vertex pulling, no vertex buffers: patch p is a strip of SEGMENTS quads,
// cross-section i holding vertices 2i (left) and 2i + 1 (right); triangle
// t = p * 2 * SEGMENTS + 2i + h has corners (2i, 2i+1, 2i+2) for h = 0 and
// (2i+1, 2i+3, 2i+2) for h = 1, counter-clockwise seen from the patch's
// outward normal.
//
// Bindings (group 0), in the order of the pass's bindings less its
// attachments: 0 = parameters, 1 = frame, 2 = models, 3 = lights,
// 4 = patches.vertices (8 words per vertex: world xyz, AO, octahedral
// tangent, octahedral normal, unorm16 u | v << 16, texels per metre),
// 5 = patches.models (model index per patch), 6 = patches.texture (RGBA8:
// base, alpha, shift, sparkle; mips along u only). Attachments: colour
// `output` (Rgba16Float), depth `depth_buffer` (D32Float).
#import strandgraph::clip::transform
#import strandgraph::octahedral::unpack_unit_vector

#import strandgraph::scheuermann_shading::{HairParams, params, frame, models, lights, SEGMENTS, TEX_LEVELS, MIN_ALPHA, sample_level, hair_lighting_at}

@group(0) @binding(4) var<storage, read> patches_vertices: array<u32>;
@group(0) @binding(5) var<storage, read> patches_models: array<u32>;

struct VertexOut {
    // Invariant: the opaque stage tests depth Equal against the prime stage.
    @invariant @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // AO, texels per metre across the strip, clip w.
    @location(4) ao_density_w: vec3<f32>,
    @location(5) @interpolate(flat) model: u32,
}

// hair.rs: corner_vertex.
fn corner_vertex(t: u32, k: u32) -> u32 {
    let strip = t / (2u * SEGMENTS);
    let q = t % (2u * SEGMENTS);
    let base = strip * 2u * (SEGMENTS + 1u) + 2u * (q / 2u);
    if q % 2u == 0u {
        return base + array<u32, 3>(0u, 1u, 2u)[k];
    }
    return base + array<u32, 3>(1u, 3u, 2u)[k];
}

fn vertex_position(v: u32) -> vec3<f32> {
    let o = 8u * v;
    return vec3<f32>(
        bitcast<f32>(patches_vertices[o]),
        bitcast<f32>(patches_vertices[o + 1u]),
        bitcast<f32>(patches_vertices[o + 2u]),
    );
}

fn clip_of(v: u32) -> vec4<f32> {
    return transform(frame.view_proj, vec4<f32>(vertex_position(v), 1.0));
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // Keeps every binding in use whichever fragment entry a stage draws
    // with (the prime stage's reads neither models nor lights).
    _ = arrayLength(&models);
    _ = arrayLength(&lights);
    let t = index / 3u;
    let v = corner_vertex(t, index % 3u);
    let clip_a = clip_of(corner_vertex(t, 0u));
    let clip_b = clip_of(corner_vertex(t, 1u));
    let clip_c = clip_of(corner_vertex(t, 2u));
    var out: VertexOut;
    // Like the CPU kernel, drop (rather than clip) a triangle with a corner
    // at or behind the near plane: collapsed to a point, it covers nothing.
    if min(clip_a.w, min(clip_b.w, clip_c.w)) <= frame.near {
        out.position = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    let o = 8u * v;
    let clip = clip_of(v);
    out.position = clip;
    out.world = vertex_position(v);
    out.tangent = unpack_unit_vector(patches_vertices[o + 4u]);
    out.normal = unpack_unit_vector(patches_vertices[o + 5u]);
    out.uv = unpack2x16unorm(patches_vertices[o + 6u]);
    out.ao_density_w = vec3<f32>(
        bitcast<f32>(patches_vertices[o + 3u]),
        bitcast<f32>(patches_vertices[o + 7u]),
        clip.w,
    );
    out.model = patches_models[t / (2u * SEGMENTS)];
    return out;
}

// Mips along u only, chosen from the strip's texel density and the view
// depth (texture.rs: lod says why not screen derivatives).
fn sample_hair(uv: vec2<f32>, ao_density_w: vec3<f32>) -> vec4<f32> {
    let texels_per_pixel = ao_density_w.y * ao_density_w.z / frame.pixels_per_unit;
    let lod = clamp(log2(max(texels_per_pixel, 1.0)) + params.lod_bias, 0.0, f32(TEX_LEVELS - 1u));
    let l0 = u32(floor(lod));
    let l1 = min(l0 + 1u, TEX_LEVELS - 1u);
    return mix(sample_level(l0, uv), sample_level(l1, uv), lod - floor(lod));
}

// shading.rs: hair_lighting at a fragment.
fn hair_lighting(in: VertexOut, tex: vec4<f32>) -> vec4<f32> {
    return hair_lighting_at(in.world, in.tangent, in.normal, in.ao_density_w.x, tex, in.model);
}

// Stage PrimeDepth: "simple pixel shader that only returns alpha", alpha
// tested so only opaque texels write depth; colour writes are off.
@fragment
fn fs_prime(in: VertexOut) -> @location(0) vec4<f32> {
    let alpha = sample_hair(in.uv, in.ao_density_w).y;
    if alpha < params.opaque_alpha {
        discard;
    }
    return vec4<f32>(0.0, 0.0, 0.0, alpha);
}

// Stage Opaque: where the prime stage left this fragment's depth (test
// Equal), or alpha tested itself when the graph runs no prime stage.
@fragment
fn fs_opaque(in: VertexOut) -> @location(0) vec4<f32> {
    let tex = sample_hair(in.uv, in.ao_density_w);
    if params.primed == 0u && tex.y < params.opaque_alpha {
        discard;
    }
    return vec4<f32>(hair_lighting(in, tex).rgb, 1.0);
}

// Stages BackFaces and FrontFaces: premultiplied "over".
@fragment
fn fs_blend(in: VertexOut) -> @location(0) vec4<f32> {
    let tex = sample_hair(in.uv, in.ao_density_w);
    if tex.y < MIN_ALPHA {
        discard;
    }
    let lit = hair_lighting(in, tex);
    return vec4<f32>(lit.rgb * lit.a, lit.a);
}
