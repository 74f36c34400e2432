// Triangle setup and coverage of the compute rasterizer behind
// scene.visibility and scene.opaque: a port, operation for operation, of
// passes/src/opaque_mesh/setup.rs (read it for the rules and the bounds that
// keep every integer step inside i32).
//
// Setup vertex order is a, c, b: a front face (counter-clockwise in NDC)
// has negative signed area with y down, and swapping b and c makes it
// positive.
#define_import_path strandgraph::opaque_setup

#import strandgraph::clip::transform

const SUBPIXEL_BITS: u32 = 4u;
const ONE: i32 = 16;
const HALF: i32 = 8;
// (1 << 15) - 64 sub-pixels: setup.rs MAX_EXTENT.
const MAX_EXTENT: i32 = 32704;
const GUARD_BAND: f32 = 524288.0;

struct Setup {
    valid: bool,
    // Snapped corners relative to `origin`, sub-pixels, setup order.
    x: vec3<i32>,
    y: vec3<i32>,
    origin: vec2<i32>,
    area: i32,
    bias: vec3<i32>,
    z: vec3<f32>,
    inv_w: vec3<f32>,
    dz: vec2<f32>,
    // Inclusive pixel bounds clipped to the screen: x0, y0, x1, y1.
    bounds: vec4<u32>,
}

fn min3(v: vec3<i32>) -> i32 {
    return min(min(v.x, v.y), v.z);
}

fn max3(v: vec3<i32>) -> i32 {
    return max(max(v.x, v.y), v.z);
}

// setup.rs Setup::from_clip, with `clip` the corners a, b, c.
fn setup_triangle(clip_a: vec4<f32>, clip_b: vec4<f32>, clip_c: vec4<f32>, near_plane: f32, width: u32, height: u32) -> Setup {
    var s: Setup;
    s.valid = false;
    let near = max(near_plane, 0.0);
    var clip = array<vec4<f32>, 3>(clip_a, clip_c, clip_b);
    var sx = vec3<i32>(0);
    var sy = vec3<i32>(0);
    for (var i = 0u; i < 3u; i++) {
        let c = clip[i];
        // `!(w > near)` also rejects a NaN w, as the CPU's is_nan test does.
        if !(c.w > near) {
            return s;
        }
        let iw = 1.0 / c.w;
        let px = (c.x * iw * 0.5 + 0.5) * f32(width);
        let py = (0.5 - c.y * iw * 0.5) * f32(height);
        if !(abs(px) <= GUARD_BAND && abs(py) <= GUARD_BAND) {
            return s;
        }
        sx[i] = i32(round(px * f32(ONE)));
        sy[i] = i32(round(py * f32(ONE)));
        s.z[i] = c.z * iw;
        s.inv_w[i] = iw;
    }
    s.origin = vec2<i32>(min3(sx), min3(sy));
    if max3(sx) - s.origin.x >= MAX_EXTENT || max3(sy) - s.origin.y >= MAX_EXTENT {
        return s;
    }
    let x = sx - vec3<i32>(s.origin.x);
    let y = sy - vec3<i32>(s.origin.y);
    s.x = x;
    s.y = y;
    s.area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    if s.area <= 0 {
        return s;
    }
    for (var i = 0u; i < 3u; i++) {
        let j = (i + 1u) % 3u;
        let k = (i + 2u) % 3u;
        let dx = x[k] - x[j];
        let dy = y[k] - y[j];
        // Top or left edges keep centres exactly on them.
        s.bias[i] = select(1, 0, dy < 0 || (dy == 0 && dx > 0));
    }
    // `>>` on i32 is an arithmetic shift: floor division by 16.
    let x0 = max((s.origin.x - HALF + ONE - 1) >> SUBPIXEL_BITS, 0);
    let y0 = max((s.origin.y - HALF + ONE - 1) >> SUBPIXEL_BITS, 0);
    let x1 = min((max3(sx) - HALF) >> SUBPIXEL_BITS, i32(width) - 1);
    let y1 = min((max3(sy) - HALF) >> SUBPIXEL_BITS, i32(height) - 1);
    if x1 < x0 || y1 < y0 {
        return s;
    }
    let inv_area = 1.0 / f32(s.area);
    s.dz = vec2<f32>((s.z[1] - s.z[0]) * inv_area, (s.z[2] - s.z[0]) * inv_area);
    s.bounds = vec4<u32>(u32(x0), u32(y0), u32(x1), u32(y1));
    s.valid = true;
    return s;
}

// View::setup: world-space corners a, b, c through `view_proj` (summed in
// column order, as the CPU's kulikov::transform), then setup_triangle.
fn setup_world(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, view_proj: mat4x4<f32>, near_plane: f32, width: u32, height: u32) -> Setup {
    return setup_triangle(
        transform(view_proj, vec4<f32>(a, 1.0)),
        transform(view_proj, vec4<f32>(b, 1.0)),
        transform(view_proj, vec4<f32>(c, 1.0)),
        near_plane,
        width,
        height,
    );
}

fn box_pixels(s: Setup) -> u32 {
    return (s.bounds.z - s.bounds.x + 1u) * (s.bounds.w - s.bounds.y + 1u);
}

// Edge functions at the centre of pixel (px, py), relative to the origin.
fn edges(s: Setup, px: u32, py: u32) -> vec3<i32> {
    let cx = i32(px) * ONE + HALF - s.origin.x;
    let cy = i32(py) * ONE + HALF - s.origin.y;
    var e: vec3<i32>;
    for (var i = 0u; i < 3u; i++) {
        let j = (i + 1u) % 3u;
        let k = (i + 2u) % 3u;
        e[i] = (s.x[k] - s.x[j]) * (cy - s.y[j]) - (s.y[k] - s.y[j]) * (cx - s.x[j]);
    }
    return e;
}

// Per-pixel edge increments along x.
fn step_x(s: Setup) -> vec3<i32> {
    return vec3<i32>(-(s.y[2] - s.y[1]), -(s.y[0] - s.y[2]), -(s.y[1] - s.y[0])) * ONE;
}

fn covers(s: Setup, e: vec3<i32>) -> bool {
    return all(e >= s.bias);
}

// NDC depth at a covered pixel, linear in screen space.
fn depth_at(s: Setup, e: vec3<i32>) -> f32 {
    return s.z[0] + f32(e[1]) * s.dz[0] + f32(e[2]) * s.dz[1];
}

// Perspective-correct barycentrics of the source corners a, b, c.
fn barycentrics(s: Setup, e: vec3<i32>) -> vec3<f32> {
    let q0 = f32(e[0]) * s.inv_w[0];
    let q1 = f32(e[1]) * s.inv_w[1];
    let q2 = f32(e[2]) * s.inv_w[2];
    let sum = q0 + q1 + q2;
    if !(sum > 0.0) {
        return vec3<f32>(1.0, 0.0, 0.0);
    }
    let inv = 1.0 / sum;
    // Setup vertices 0, 1, 2 are corners a, c, b.
    return vec3<f32>(q0 * inv, q2 * inv, q1 * inv);
}
