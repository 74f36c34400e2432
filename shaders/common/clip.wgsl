// Clip-space helpers every pipeline uses (the CPU kernels' kulikov::transform
// and kulikov::clip_to_screen, which the Lipp kernels call too, and
// common::clip::near_clip). Composed with naga_oil:
//   #import strandgraph::clip::{transform, clip_to_screen, near_clip}
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

// common::clip::NearClipped: the part of a segment with w > near, its ends
// and their parameters along the original segment.
struct NearClipped {
    valid: bool,
    a: vec4<f32>,
    b: vec4<f32>,
    ta: f32,
    tb: f32,
}

// common::clip::near_clip: the cut end is the lerp where w reaches near
// (clip space is linear along the segment), with w = near exactly.
fn near_clip(c0: vec4<f32>, c1: vec4<f32>, near: f32) -> NearClipped {
    var out = NearClipped(false, c0, c1, 0.0, 1.0);
    let d0 = c0.w - near;
    let d1 = c1.w - near;
    let in0 = d0 > 0.0;
    let in1 = d1 > 0.0;
    if in0 && in1 {
        out.valid = true;
        return out;
    }
    if !in0 && !in1 {
        return out;
    }
    let t = d0 / (d0 - d1);
    if !(t >= 0.0 && t <= 1.0) {
        return out;
    }
    var cut = c0 + t * (c1 - c0);
    cut.w = near;
    out.valid = true;
    if in0 {
        out.b = cut;
        out.tb = t;
    } else {
        out.a = cut;
        out.ta = t;
    }
    return out;
}

// common::clip::at: v0 + t (v1 - v0), exact at t = 0 and t = 1, so an end
// near_clip did not cut keeps its attributes bit for bit.
fn clip_at(v0: f32, v1: f32, t: f32) -> f32 {
    if t == 0.0 {
        return v0;
    }
    if t == 1.0 {
        return v1;
    }
    return v0 + t * (v1 - v0);
}

fn clip_at3(v0: vec3<f32>, v1: vec3<f32>, t: f32) -> vec3<f32> {
    return vec3<f32>(clip_at(v0.x, v1.x, t), clip_at(v0.y, v1.y, t), clip_at(v0.z, v1.z, t));
}
