// Clip-space helpers both pipelines use (the CPU kernels' kulikov::transform
// and kulikov::clip_to_screen, which the Lipp kernels call too). Composed
// with naga_oil:
//   #import strandgraph::clip::{transform, clip_to_screen}
#define_import_path strandgraph::clip

// kulikov::transform: column-major 4x4 times a point, summed in column order.
fn transform(m: mat4x4<f32>, p: vec4<f32>) -> vec4<f32> {
    return m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3] * p.w;
}

// kulikov::clip_to_screen: pixels (y down) and NDC depth.
fn clip_to_screen(c: vec4<f32>, width: f32, height: f32) -> vec3<f32> {
    let iw = 1.0 / c.w;
    return vec3<f32>((c.x * iw * 0.5 + 0.5) * width, (0.5 - c.y * iw * 0.5) * height, c.z * iw);
}
