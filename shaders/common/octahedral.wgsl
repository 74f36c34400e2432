// Octahedral unit vectors (assets/src/octahedral.rs; Cigolle et al. 2014).
// Composed with naga_oil:
//   #import strandgraph::octahedral::unpack_unit_vector
#define_import_path strandgraph::octahedral

fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

// assets/src/octahedral.rs: unpack_unit_vector (two snorm16, x low, y high).
// unpack2x16snorm clamps at -1 like unsnorm16.
fn unpack_unit_vector(bits: u32) -> vec3<f32> {
    let e = unpack2x16snorm(bits);
    let z = 1.0 - abs(e.x) - abs(e.y);
    var xy = e;
    if z < 0.0 {
        xy = (vec2<f32>(1.0) - abs(e.yx)) * sign_not_zero(e);
    }
    let n = vec3<f32>(xy, z);
    let len2 = dot(n, n);
    if len2 > 0.0 {
        return n * inverseSqrt(len2);
    }
    return vec3<f32>(0.0);
}
