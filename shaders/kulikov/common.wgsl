// Helpers every Kulikov kernel shares, ported operation for operation from
// passes/src/kulikov/{mod,payload,cull}.rs and raster/geometry.rs, so that
// GPU results can be diffed bit for bit against the CPU kernels. Integer
// work and the order of float operations match; what WGSL cannot pin down
// is FMA contraction and the precision of division and sqrt (Vulkan allows
// 2.5 and 3 ULP). Measured on an H100 (wgpu 30, Vulkan): kulikov.cull is
// bit-identical to the CPU kernel; kulikov.raster differs only in
// coverage rounding (+-1..3 of 1024 per texel) and in pixels whose exact
// coverage is ~0 (the shoelace area of a sliver is cancellation noise, so
// `coverage > 0` flips; those texels get coverage 0 or 1/1024).
//   #import strandgraph::kulikov::{...}
#define_import_path strandgraph::kulikov
// (naga_oil: identifiers of a composable module must not end in a digit.)

#import strandgraph::layout::{ModelData, ModelLod, ModelTiles}
#import strandgraph::clip::{clip_to_screen, near_clip, clip_at}

// Atlas tile edge in texels (kulikov::TILE) and texels per tile.
const TILE: u32 = 64u;
const TILE_TEXELS: u32 = 4096u;
// Payload: depth10 << 22 | segment (kulikov::payload).
const SEGMENT_BITS: u32 = 22u;
const SEGMENT_MASK: u32 = 0x3FFFFFu;
const MAX_SEGMENTS_PER_MODEL: u32 = 0x400000u;
const DEPTH_LEVELS: u32 = 1024u;
// An empty visibility texel (the clear value).
const EMPTY: u32 = 0xFFFFFFFFu;
const COVERAGE_SCALE: f32 = 1024.0;
// Ordered visibility layers.
const LAYERS: u32 = 3u;
// Density grid words per model (48^3, one per voxel) and the fixed-point
// unit of projected area (kulikov::density::{GRID_WORDS, AREA_UNIT}).
const GRID_WORDS: u32 = 110592u;
const AREA_UNIT: f32 = 1e-9;
// Sub-pixel snap grid (raster::geometry::SNAP).
const SNAP: f32 = 256.0;
// f32::MAX and f32::MIN.
const F32_MAX: f32 = 3.40282347e38;
const F32_MIN: f32 = -3.40282347e38;

// Rust's f32::round: halves away from zero (WGSL's round() goes to even).
// x - trunc(x) is exact, so this is exact for every finite x.
fn round_away(x: f32) -> f32 {
    let t = trunc(x);
    if abs(x - t) >= 0.5 {
        return t + sign(x);
    }
    return t;
}

// ModelLod::load (a vertex step of 0 reads as 1).
fn load_lod(l: ModelLod) -> ModelLod {
    var out = l;
    out.vertex_step = max(l.vertex_step, 1u);
    return out;
}

// ModelTiles::load (a downscale of 0 reads as 1).
fn load_tiles(t: ModelTiles) -> ModelTiles {
    var out = t;
    out.downscale = max(t.downscale, 1u);
    return out;
}

// Drawn segments per strand of `points` points at a vertex step.
fn drawn_segments(points: u32, step: u32) -> u32 {
    let s = max(step, 1u);
    let n = select(0u, points - 1u, points >= 1u);
    return (n + s - 1u) / s;
}

// Scene::segment_model: whether global segment `id` belongs to model `m`.
fn segment_in_model(m: ModelData, id: u32) -> bool {
    let per = select(0u, m.points_per_strand - 1u, m.points_per_strand >= 1u);
    let count = m.strand_count * per;
    return id >= m.segment_first && id < m.segment_first + count;
}

// cull::DrawnSegment: both vertices' global indices and the model-local index.
struct DrawnSegment {
    valid: bool,
    model: u32,
    local: u32,
    // Global vertex indices of the two ends.
    va: u32,
    vb: u32,
}

// cull::drawn_segment for a segment already known to lie in model `model`.
fn drawn_in_model(md: ModelData, lod: ModelLod, model: u32, id: u32) -> DrawnSegment {
    var out = DrawnSegment(false, model, id - md.segment_first, 0u, 0u);
    let per = md.points_per_strand - 1u;
    let strand = out.local / per;
    let k = out.local % per;
    if strand >= lod.strands || k >= lod.segments_per_strand {
        return out;
    }
    // ModelLod::segment_vertices.
    let a = k * lod.vertex_step;
    let b = min(a + lod.vertex_step, md.points_per_strand - 1u);
    let base = md.vertex_first + strand * md.points_per_strand;
    out.valid = true;
    out.va = base + a;
    out.vb = base + b;
    return out;
}

// cull::screen_bin: the 64x64 screen tile of the segment's midpoint.
fn screen_bin(w: f32, h: f32, sa: vec3<f32>, sb: vec3<f32>) -> u32 {
    let x = u32(clamp(0.5 * (sa.x + sb.x), 0.0, w - 1.0));
    let y = u32(clamp(0.5 * (sa.y + sb.y), 0.0, h - 1.0));
    return y / TILE * ((u32(w) + TILE - 1u) / TILE) + x / TILE;
}

// ModelTiles::texel: the atlas texel of screen pixel (x, y), or EMPTY.
fn tile_texel(t: ModelTiles, x: u32, y: u32) -> u32 {
    if t.valid == 0u {
        return EMPTY;
    }
    let u = x / t.downscale;
    let v = y / t.downscale;
    if u < t.origin_x * TILE || v < t.origin_y * TILE {
        return EMPTY;
    }
    let uu = u - t.origin_x * TILE;
    let vv = v - t.origin_y * TILE;
    let tx = uu / TILE;
    let ty = vv / TILE;
    if tx >= t.grid_w || ty >= t.grid_h {
        return EMPTY;
    }
    return (t.first_tile + ty * t.grid_w + tx) * TILE * TILE + (vv % TILE) * TILE + uu % TILE;
}

// payload::quantize_depth: linear view depth normalised to the model's range, 10 bits.
fn quantize_depth(view_depth: f32, near: f32, far: f32) -> u32 {
    let t = clamp((view_depth - near) / max(far - near, 1e-6), 0.0, 1.0);
    return min(u32(round_away(t * f32(DEPTH_LEVELS - 1u))), DEPTH_LEVELS - 1u);
}

fn pack_payload(depth_q: u32, segment: u32) -> u32 {
    return (depth_q << SEGMENT_BITS) | (segment & SEGMENT_MASK);
}

fn depth_of(payload: u32) -> u32 {
    return payload >> SEGMENT_BITS;
}

// payload::total_coverage: Kulikov's quadratic fit from additive coverage.
fn total_coverage(additive: u32) -> f32 {
    let x = f32(additive) / COVERAGE_SCALE;
    return clamp(x - 0.5 * x * clamp(0.5 * x, 0.0, 1.0), 0.0, 1.0);
}

// payload::linear_depth: view depth from NDC depth of perspective_rh.
fn linear_depth(z_ndc: f32, near: f32, far: f32) -> f32 {
    return near * far / (far - z_ndc * (far - near));
}

// raster::geometry::snap.
fn snap(x: f32) -> f32 {
    return round_away(x * SNAP) / SNAP;
}

// raster::geometry::Poly: a convex polygon of at most 8 vertices.
struct Poly {
    pts: array<vec2<f32>, 8>,
    n: u32,
}

// Poly::clip: keeps sign * (p[axis] - at) >= 0 (one Sutherland-Hodgman plane).
fn poly_clip(src: Poly, axis: u32, at: f32, sign: f32) -> Poly {
    var s = src;
    var out: Poly;
    out.n = 0u;
    for (var i = 0u; i < s.n; i++) {
        let a = s.pts[i];
        let b = s.pts[(i + 1u) % s.n];
        let ia = sign * (a[axis] - at) >= 0.0;
        let ib = sign * (b[axis] - at) >= 0.0;
        if ia && out.n < 8u {
            out.pts[out.n] = a;
            out.n += 1u;
        }
        if ia != ib && out.n < 8u {
            let t = (at - a[axis]) / (b[axis] - a[axis]);
            out.pts[out.n] = vec2<f32>(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y));
            out.n += 1u;
        }
    }
    return out;
}

// Poly::strip: the part within lo <= p[axis] <= hi.
fn poly_strip(p: Poly, axis: u32, lo: f32, hi: f32) -> Poly {
    return poly_clip(poly_clip(p, axis, lo, 1.0), axis, hi, -1.0);
}

// Poly::area (shoelace, summed in vertex order).
fn poly_area(src: Poly) -> f32 {
    var p = src;
    var twice = 0.0;
    for (var i = 0u; i < p.n; i++) {
        let a = p.pts[i];
        let b = p.pts[(i + 1u) % p.n];
        twice += a.x * b.y - b.x * a.y;
    }
    return 0.5 * abs(twice);
}

// Poly::range: (min, max) of one coordinate.
fn poly_range(src: Poly, axis: u32) -> vec2<f32> {
    var p = src;
    var r = vec2<f32>(F32_MAX, F32_MIN);
    for (var i = 0u; i < p.n; i++) {
        r = vec2<f32>(min(r.x, p.pts[i][axis]), max(r.y, p.pts[i][axis]));
    }
    return r;
}

// Trapezoid::quad's four corners in order (the ends a and b offset by ±
// their half widths along the normal), as named registers: an array indexed
// at run time lives in local memory on NVIDIA GPUs, and the raster reads
// the corners for every pixel.
struct Quad {
    a_plus: vec2<f32>,
    b_plus: vec2<f32>,
    b_minus: vec2<f32>,
    a_minus: vec2<f32>,
}

// The quad as a Poly, for the clipper.
fn quad_poly(q: Quad) -> Poly {
    var p: Poly;
    p.pts[0] = q.a_plus;
    p.pts[1] = q.b_plus;
    p.pts[2] = q.b_minus;
    p.pts[3] = q.a_minus;
    p.n = 4u;
    return p;
}

// raster::geometry::Trapezoid: a projected segment in raster pixels.
struct Trapezoid {
    valid: bool,
    a: vec2<f32>,
    b: vec2<f32>,
    wa: f32,
    wb: f32,
    quad: Quad,
}

// Trapezoid::new: snapped ends and half widths; invalid when degenerate.
fn trapezoid_new(a_in: vec2<f32>, b_in: vec2<f32>, half_a: f32, half_b: f32, wa: f32, wb: f32) -> Trapezoid {
    var t: Trapezoid;
    t.valid = false;
    t.a = vec2<f32>(snap(a_in.x), snap(a_in.y));
    t.b = vec2<f32>(snap(b_in.x), snap(b_in.y));
    t.wa = wa;
    t.wb = wb;
    let ha = max(snap(half_a), 1.0 / SNAP);
    let hb = max(snap(half_b), 1.0 / SNAP);
    let d = vec2<f32>(t.b.x - t.a.x, t.b.y - t.a.y);
    let len = sqrt(d.x * d.x + d.y * d.y);
    // !(len > 1/SNAP) || !len.is_finite(); NaN fails the first test.
    if !(len > 1.0 / SNAP) || len > F32_MAX {
        return t;
    }
    let n = vec2<f32>(-d.y / len, d.x / len);
    t.quad.a_plus = vec2<f32>(t.a.x + n.x * ha, t.a.y + n.y * ha);
    t.quad.b_plus = vec2<f32>(t.b.x + n.x * hb, t.b.y + n.y * hb);
    t.quad.b_minus = vec2<f32>(t.b.x - n.x * hb, t.b.y - n.y * hb);
    t.quad.a_minus = vec2<f32>(t.a.x - n.x * ha, t.a.y - n.y * ha);
    t.valid = true;
    return t;
}

// compose::segment_trapezoid (and RasterKernel's setup): the part of the
// segment from clip position c0 to c1 in front of the near plane (near_clip)
// as a trapezoid in its model's raster grid, in the CPU's operation order,
// so raster, composition and motion see one shape.
fn model_trapezoid(t: ModelTiles, lod: ModelLod, c0_in: vec4<f32>, c1_in: vec4<f32>, thick_a: f32, thick_b: f32, screen: vec2<f32>, pixels_per_unit: f32, near: f32) -> Trapezoid {
    let clipped = near_clip(c0_in, c1_in, near);
    if !clipped.valid {
        var none: Trapezoid;
        none.valid = false;
        return none;
    }
    let c0 = clipped.a;
    let c1 = clipped.b;
    let d = f32(t.downscale);
    let origin = vec2<f32>(f32(t.origin_x * TILE), f32(t.origin_y * TILE));
    let sa = clip_to_screen(c0, screen.x, screen.y);
    let sb = clip_to_screen(c1, screen.x, screen.y);
    // Strand width in raster pixels: thickness x LOD compensation x projection.
    let ha = 0.5 * clip_at(thick_a, thick_b, clipped.ta) * lod.thickness_scale * pixels_per_unit / c0.w / d;
    let hb = 0.5 * clip_at(thick_a, thick_b, clipped.tb) * lod.thickness_scale * pixels_per_unit / c1.w / d;
    return trapezoid_new(sa.xy / d - origin, sb.xy / d - origin, ha, hb, c0.w, c1.w);
}

// Trapezoid::column: the part over pixel column x (Kulikov's TrapezoidSlice).
fn trapezoid_column(quad: Quad, x: i32) -> Poly {
    return poly_strip(quad_poly(quad), 0u, f32(x), f32(x) + 1.0);
}

// Trapezoid::columns: the first and last pixel column the quad touches.
fn quad_columns(q: Quad) -> vec2<i32> {
    let lo = min(min(q.a_plus.x, q.b_plus.x), min(q.b_minus.x, q.a_minus.x));
    let hi = max(max(q.a_plus.x, q.b_plus.x), max(q.b_minus.x, q.a_minus.x));
    return vec2<i32>(i32(floor(lo)), i32(floor(hi)));
}

// raster::geometry::edge_span folded into range r: the y extent of edge
// a-b cut to the column [x0, x0 + 1].
fn edge_span(a: vec2<f32>, b: vec2<f32>, x0: f32, r: vec2<f32>) -> vec2<f32> {
    var p = b;
    var q = a;
    if a.x < b.x {
        p = a;
        q = b;
    }
    let lo = max(p.x, x0);
    let hi = min(q.x, x0 + 1.0);
    if hi < lo {
        return r;
    }
    var ya = p.y;
    var yb = q.y;
    if q.x > p.x {
        let slope = (q.y - p.y) / (q.x - p.x);
        ya = p.y + slope * (lo - p.x);
        yb = p.y + slope * (hi - p.x);
    }
    return vec2<f32>(min(r.x, min(ya, yb)), max(r.y, max(ya, yb)));
}

// Trapezoid::column_span: the quad's y extent over column x, from its
// edges; (F32_MAX, F32_MIN) where no edge reaches the column.
fn quad_column_span(q: Quad, x: i32) -> vec2<f32> {
    let x0 = f32(x);
    var r = vec2<f32>(F32_MAX, F32_MIN);
    r = edge_span(q.a_plus, q.b_plus, x0, r);
    r = edge_span(q.b_plus, q.b_minus, x0, r);
    r = edge_span(q.b_minus, q.a_minus, x0, r);
    return edge_span(q.a_minus, q.a_plus, x0, r);
}

// raster::geometry::edge_area: one edge's clamped height integrated over
// the pixel column, signed by its direction in x.
fn clamped_mean(ya: f32, yb: f32) -> f32 {
    var t0 = 0.0;
    var t1 = 1.0;
    if yb != ya {
        let c0 = clamp(-ya / (yb - ya), 0.0, 1.0);
        let c1 = clamp((1.0 - ya) / (yb - ya), 0.0, 1.0);
        t0 = min(c0, c1);
        t1 = max(c0, c1);
    }
    let d = yb - ya;
    return t0 * clamp(ya + 0.5 * t0 * d, 0.0, 1.0)
        + (t1 - t0) * clamp(ya + 0.5 * (t0 + t1) * d, 0.0, 1.0)
        + (1.0 - t1) * clamp(ya + 0.5 * (t1 + 1.0) * d, 0.0, 1.0);
}

fn edge_area(a: vec2<f32>, b: vec2<f32>, x0: f32, y0: f32) -> f32 {
    var p = a;
    var q = b;
    var sign = 1.0;
    if !(a.x < b.x) {
        p = b;
        q = a;
        sign = -1.0;
    }
    let lo = max(p.x, x0);
    let hi = min(q.x, x0 + 1.0);
    if !(hi > lo) {
        return 0.0;
    }
    let slope = (q.y - p.y) / (q.x - p.x);
    let ya = p.y + slope * (lo - p.x) - y0;
    let yb = p.y + slope * (hi - p.x) - y0;
    return sign * (hi - lo) * clamped_mean(ya, yb);
}

// Trapezoid::pixel_coverage: the quad's exact area inside pixel (x, y) by
// edge integration, in registers (composition's three layers per pixel).
fn quad_pixel_coverage(q: Quad, x: i32, y: i32) -> f32 {
    let x0 = f32(x);
    let y0 = f32(y);
    let s = edge_area(q.a_plus, q.b_plus, x0, y0) + edge_area(q.b_plus, q.b_minus, x0, y0)
        + edge_area(q.b_minus, q.a_minus, x0, y0) + edge_area(q.a_minus, q.a_plus, x0, y0);
    return min(abs(s), 1.0);
}

// Trapezoid::coverage: exact area inside pixel (x, y) of a column slice.
fn column_coverage(column: Poly, y: i32) -> f32 {
    return min(poly_area(poly_strip(column, 1u, f32(y), f32(y) + 1.0)), 1.0);
}

// Trapezoid::depth_at: view depth at the pixel centre projected on the axis.
fn trapezoid_depth_at(a: vec2<f32>, b: vec2<f32>, wa: f32, wb: f32, x: i32, y: i32) -> f32 {
    let p = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let d = vec2<f32>(b.x - a.x, b.y - a.y);
    let t = ((p.x - a.x) * d.x + (p.y - a.y) * d.y) / (d.x * d.x + d.y * d.y);
    let tc = clamp(t, 0.0, 1.0);
    return wa + tc * (wb - wa);
}

// raster::morton: interleaved bits of x (even) and y (odd), 16 bits each.
fn morton_spread(v_in: u32) -> u32 {
    var v = v_in & 0xFFFFu;
    v = (v | (v << 8u)) & 0x00FF00FFu;
    v = (v | (v << 4u)) & 0x0F0F0F0Fu;
    v = (v | (v << 2u)) & 0x33333333u;
    return (v | (v << 1u)) & 0x55555555u;
}

fn morton_code(x: u32, y: u32) -> u32 {
    return morton_spread(x) | (morton_spread(y) << 1u);
}
