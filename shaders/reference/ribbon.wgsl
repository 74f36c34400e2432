// The reference's segments as camera-facing ribbons of their thickness with
// round joins (passes/src/reference/ribbon.rs, whose arithmetic this
// repeats in the same order), their 12-word records, the stratified sample
// pattern, and the tiles a ribbon may reach. Composed with naga_oil:
//   #import strandgraph::reference::{Ribbon, ribbon_covers, ...}
#define_import_path strandgraph::reference

#import strandgraph::clip::{clip_to_screen, near_clip, clip_at}

// reference::TILE: the lists' screen tile edge.
const REFERENCE_TILE: u32 = 8u;

// BinGpu (count, fill).
struct BinParams {
    segments: u32,
    width: u32,
    height: u32,
    tiles_x: u32,
}

// ribbon::Ribbon, and the segment's end vertices (ribbon::Record).
struct Ribbon {
    valid: bool,
    a: vec2<f32>,
    b: vec2<f32>,
    ha: f32,
    hb: f32,
    wa: f32,
    wb: f32,
    join_a: bool,
    join_b: bool,
    va: u32,
    vb: u32,
    // The parameters of a and b along the segment (Ribbon::range).
    range: vec2<f32>,
}

// Ribbon::new: the part in front of the near plane (near_clip) of the
// segment from clip position c0 to c1 with world thicknesses t0, t1 and end
// vertices va, vb; a cut end has no join.
fn ribbon_of(c0_in: vec4<f32>, c1_in: vec4<f32>, t0_in: f32, t1_in: f32, join_a: bool, join_b: bool, va: u32, vb: u32, near: f32, screen: vec2<f32>, pixels_per_unit: f32) -> Ribbon {
    var r: Ribbon;
    let part = near_clip(c0_in, c1_in, near);
    r.valid = part.valid;
    if !r.valid {
        return r;
    }
    let c0 = part.a;
    let c1 = part.b;
    let t0 = clip_at(t0_in, t1_in, part.ta);
    let t1 = clip_at(t0_in, t1_in, part.tb);
    r.a = clip_to_screen(c0, screen.x, screen.y).xy;
    r.b = clip_to_screen(c1, screen.x, screen.y).xy;
    r.ha = 0.5 * t0 * pixels_per_unit / c0.w;
    r.hb = 0.5 * t1 * pixels_per_unit / c1.w;
    r.wa = c0.w;
    r.wb = c1.w;
    r.join_a = join_a && part.ta == 0.0;
    r.join_b = join_b && part.tb == 1.0;
    r.va = va;
    r.vb = vb;
    r.range = vec2<f32>(part.ta, part.tb);
    return r;
}

// Record::store: three words of four (RECORD_WORDS = 12).
fn ribbon_pack(r: Ribbon) -> array<vec4<u32>, 3> {
    if !r.valid {
        return array<vec4<u32>, 3>(vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u));
    }
    // The near plane cuts at most one end.
    let cut_a = r.range.x != 0.0;
    let cut_b = r.range.y != 1.0;
    let flags = 1u | (u32(r.join_a) << 1u) | (u32(r.join_b) << 2u) | (u32(cut_a) << 3u) | (u32(cut_b) << 4u);
    let cut = select(select(0.0, r.range.y, cut_b), r.range.x, cut_a);
    return array<vec4<u32>, 3>(
        bitcast<vec4<u32>>(vec4<f32>(r.a, r.b)),
        bitcast<vec4<u32>>(vec4<f32>(r.ha, r.hb, r.wa, r.wb)),
        vec4<u32>(r.va, r.vb, flags, bitcast<u32>(cut)),
    );
}

// Record::load.
fn ribbon_unpack(w0: vec4<u32>, w1: vec4<u32>, w2: vec4<u32>) -> Ribbon {
    let p = bitcast<vec4<f32>>(w0);
    let h = bitcast<vec4<f32>>(w1);
    let cut = bitcast<f32>(w2.w);
    let range = vec2<f32>(select(0.0, cut, (w2.z & 8u) != 0u), select(1.0, cut, (w2.z & 16u) != 0u));
    return Ribbon((w2.z & 1u) != 0u, p.xy, p.zw, h.x, h.y, h.z, h.w, (w2.z & 2u) != 0u, (w2.z & 4u) != 0u, w2.x, w2.y, range);
}

// Ribbon::axis.
fn ribbon_axis(r: Ribbon, p: vec2<f32>) -> f32 {
    let dx = r.b.x - r.a.x;
    let dy = r.b.y - r.a.y;
    let len2 = dx * dx + dy * dy;
    if len2 > 1e-12 {
        return ((p.x - r.a.x) * dx + (p.y - r.a.y) * dy) / len2;
    }
    return 0.0;
}

// Ribbon::gap: squared distance to the axis point at t, and the radius there.
fn ribbon_gap(r: Ribbon, p: vec2<f32>, t: f32) -> vec2<f32> {
    let qx = r.a.x + t * (r.b.x - r.a.x);
    let qy = r.a.y + t * (r.b.y - r.a.y);
    let dx = p.x - qx;
    let dy = p.y - qy;
    return vec2<f32>(dx * dx + dy * dy, r.ha + t * (r.hb - r.ha));
}

// Ribbon::covers: the axis parameter, or -1 where the ribbon misses p.
fn ribbon_covers(r: Ribbon, p: vec2<f32>) -> f32 {
    let t0 = ribbon_axis(r, p);
    if (t0 < 0.0 && !r.join_a) || (t0 > 1.0 && !r.join_b) {
        return -1.0;
    }
    let t = clamp(t0, 0.0, 1.0);
    let g = ribbon_gap(r, p, t);
    if g.x < g.y * g.y {
        return t;
    }
    return -1.0;
}

// Ribbon::may_touch: the square of half edge `half` around c.
fn ribbon_may_touch(r: Ribbon, c: vec2<f32>, half: f32) -> bool {
    let t = clamp(ribbon_axis(r, c), 0.0, 1.0);
    let g = ribbon_gap(r, c, t);
    let reach = max(r.ha, r.hb) + half * 1.41421356237;
    return g.x <= reach * reach;
}

// Ribbon::depth_at: view depth, 1/w linear in screen space.
fn ribbon_depth_at(r: Ribbon, t: f32) -> f32 {
    return 1.0 / ((1.0 - t) / r.wa + t / r.wb);
}

// Ribbon::world_t: the perspective-correct parameter along the segment
// (through range where the near plane cut an end).
fn ribbon_world_t(r: Ribbon, t: f32) -> f32 {
    let ia = (1.0 - t) / r.wa;
    let ib = t / r.wb;
    return clip_at(r.range.x, r.range.y, ib / (ia + ib));
}

// bin::reached_tiles: the tile rectangle of the ribbon's bounds, as
// (x0, y0, x1, y1) inclusive; x0 > x1 when it is off screen.
fn ribbon_tiles(r: Ribbon, width: u32, height: u32) -> vec4<u32> {
    let rad = max(r.ha, r.hb);
    let x0 = max(min(r.a.x, r.b.x) - rad, 0.0);
    let y0 = max(min(r.a.y, r.b.y) - rad, 0.0);
    let x1 = min(max(r.a.x, r.b.x) + rad, f32(width) - 1.0);
    let y1 = min(max(r.a.y, r.b.y) + rad, f32(height) - 1.0);
    if !(x0 <= x1 && y0 <= y1) {
        return vec4<u32>(1u, 1u, 0u, 0u);
    }
    return vec4<u32>(u32(x0) / REFERENCE_TILE, u32(y0) / REFERENCE_TILE, u32(x1) / REFERENCE_TILE, u32(y1) / REFERENCE_TILE);
}

// bin::reached_tiles' test for tile (tx, ty).
fn ribbon_reaches_tile(r: Ribbon, tx: u32, ty: u32) -> bool {
    let half = 0.5 * f32(REFERENCE_TILE);
    let c = vec2<f32>(f32(tx * REFERENCE_TILE) + half, f32(ty * REFERENCE_TILE) + half);
    return ribbon_may_touch(r, c, half);
}

// ribbon::hash2.
fn reference_hash2(a: u32, b: u32) -> u32 {
    var h = (a * 0x8da6b343u) ^ (b * 0xd8163841u);
    h ^= h >> 15u;
    h = h * 0x2c1b3c6du;
    h ^= h >> 12u;
    h = h * 0x297a2d39u;
    return h ^ (h >> 15u);
}

// ribbon::sample_position: sample s of pixel (x, y)'s n x n pattern.
fn sample_position(x: u32, y: u32, width: u32, n: u32, s: u32) -> vec2<f32> {
    let h = reference_hash2(y * width + x, s);
    let jx = f32(h & 0xFFFFu) * (1.0 / 65536.0);
    let jy = f32(h >> 16u) * (1.0 / 65536.0);
    let inv = 1.0 / f32(n);
    return vec2<f32>(f32(x) + (f32(s % n) + jx) * inv, f32(y) + (f32(s / n) + jy) * inv);
}
