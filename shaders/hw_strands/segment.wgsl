// The payload bits of a segment (hw_strands::Segment's bits_a and bits_b),
// shared by hw_strands.assemble (assemble.wgsl, which stores them in a
// record) and hw_strands.mesh (mesh.wgsl, which emits them as flat vertex
// outputs). Port of passes/src/hw_strands/assemble.rs's `record`.
// Composed with naga_oil:
//   #import strandgraph::hw_strands_segment::segment_bits
#define_import_path strandgraph::hw_strands_segment

#import strandgraph::lipp::{lerp_vec, safe_normalize, oct_encode, quantize}
#import strandgraph::lipp_assembly::ControlPoint

// payload::pack's layout: bits_a (x) is the low payload word at end a
// (tangent y, u, v, w, AO); bits_b (y) the tangent's x with end b's w
// (bits 8-13) and AO (bits 14-19). The tangent is the middle one, packed
// once per segment as lipp.raster packs it with `segment_payload` on.
fn segment_bits(a: ControlPoint, ta: vec3<f32>, b: ControlPoint, tb: vec3<f32>, uv: vec2<f32>) -> vec2<u32> {
    let e = oct_encode(safe_normalize(lerp_vec(ta, tb, 0.5)));
    let bits_a = (quantize(e.y * 0.5 + 0.5, 255.0) << 24u)
        | (quantize(uv.x, 63.0) << 18u)
        | (quantize(uv.y, 63.0) << 12u)
        | (quantize(a.w, 63.0) << 6u)
        | quantize(a.ao, 63.0);
    let bits_b = quantize(e.x * 0.5 + 0.5, 255.0)
        | (quantize(b.w, 63.0) << 8u)
        | (quantize(b.ao, 63.0) << 14u);
    return vec2<u32>(bits_a, bits_b);
}
