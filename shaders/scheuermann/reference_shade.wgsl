// scheuermann.reference_shade: Scheuermann 2004's shading (shading.wgsl, the
// same as scheuermann.hair's stages) at every vertex of the groom's own
// strands, into `vertex_lighting` for reference.resolve to interpolate.
// Port of passes/src/scheuermann/reference_shade.rs.
//
// Bindings (group 0): 0 = parameters, 1 = frame, 2 = models, 3 = lights,
// 4 = groom.vertices, 5 = scheuermann.strand_shading (per vertex:
// octahedral world normal, AO, texture u, texture v), 6 = patches.texture,
// 7 = vertex_lighting.
#import strandgraph::scheuermann_shading::{params, models, sample_level, hair_lighting_at}
#import strandgraph::octahedral::unpack_unit_vector
#import strandgraph::half::pack_radiance

@group(0) @binding(4) var<storage, read> groom_vertices: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> scheuermann_strand_shading: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read_write> vertex_lighting: array<vec2<u32>>;

fn world_of(m: u32, v: u32) -> vec3<f32> {
    return (models[m].world * vec4<f32>(groom_vertices[v].xyz, 1.0)).xyz;
}

@compute @workgroup_size(256)
fn reference_shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = gid.x;
    if v >= min(arrayLength(&groom_vertices), arrayLength(&scheuermann_strand_shading)) {
        return;
    }
    // reference_shade::model_of: the last model starting at or before v.
    var m = 0u;
    for (var k = 1u; k < arrayLength(&models); k++) {
        if models[k].vertex_first <= v && models[k].strand_count > 0u {
            m = k;
        }
    }
    let n = max(models[m].points_per_strand, 2u);
    let i = (v - models[m].vertex_first) % n;
    let world = world_of(m, v);
    let before = world_of(m, v - min(i, 1u));
    let after = world_of(m, v + select(1u, 0u, i + 1u >= n));
    let s = scheuermann_strand_shading[v];
    let tex = sample_level(0u, bitcast<vec2<f32>>(s.zw));
    let lit = hair_lighting_at(world, after - before, unpack_unit_vector(s.x), bitcast<f32>(s.y), tex, m);
    vertex_lighting[v] = pack_radiance(lit.rgb);
}
