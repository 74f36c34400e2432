// lipp.filter: Lipp §3.3 and Appendix B Code 2, the single-pass elliptical
// bilateral reconnection filter with opacity reconstruction, blended over
// `output`. Port of passes/src/lipp/filter.rs (see its deviations).
// `output` is Rgba16Float, read and written: a read_write storage texture.

#import strandgraph::layout::{FrameData, ModelData}
#import strandgraph::clip::transform
#import strandgraph::lipp::{safe_normalize, is_empty, unpack_payload, world_position, linear_depth, Sample, F32_MIN}
#import strandgraph::lipp_shaded::{unpack_rgb9e5, record_depth, HIT, CONS_HIT, FRONT}
#import strandgraph::lipp_rect::{FILTER_RECT_LO, FILTER_RECT_HI, rect_from_args}
#import strandgraph::lipp_tiles::{TILE, FILTER_GROUP, filter_lanes}

// FilterParams (booleans as 0/1).
struct FilterParams {
    enabled: u32,
    reconnect: u32,
    opacity_reconstruction: u32,
    radius: u32,
    s_parallel: f32,
    s_perp: f32,
    sigma_c: f32,
    strip_width: f32,
    depth_threshold: f32,
    // Scene quantities.
    width: u32,
    height: u32,
    // MSAA reference resolve (0: the single-sample filter).
    msaa: u32,
    // Pixels at least this opaque write their hair depth (Lipp §3.5).
    depth_alpha: f32,
    // Ours: convert the hit ratio to the strands' own width (filter.rs).
    true_width: u32,
    // lipp.raster's centre_diameter, pixels.
    centre_diameter: f32,
    model_index: u32,
    // Ours: a tap reads the neighbour's centre-layer record (shaded.rs).
    packed_taps: u32,
    // Ours: pixels; only taps this near the tangent's line (0: every tap).
    band: f32,
    // Ours: the most lanes a pixel (filter.rs `lanes`).
    lanes: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: FilterParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> gbuffer: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> shaded: array<vec2<u32>>;
@group(0) @binding(4) var output: texture_storage_2d<rgba16float, read_write>;
// NDC depth (f32 bits) the next groom's rasterizer is tested against.
@group(0) @binding(5) var<storage, read_write> hair_depth: array<u32>;
@group(0) @binding(6) var<storage, read> models: array<ModelData>;
// lipp.shade's tiles with hair and their count (lipp::tiles).
@group(0) @binding(7) var<storage, read> filter_tiles: array<u32>;
@group(0) @binding(8) var<storage, read> filter_args: array<u32>;

fn payload(layer: u32, i: u32) -> vec2<u32> {
    return gbuffer[layer * params.width * params.height + i];
}

// lipp::gbuffer_layers.
fn layer_count() -> u32 {
    let pixels = max(params.width * params.height, 1u);
    return max(min(arrayLength(&gbuffer), arrayLength(&shaded)) / pixels, 2u);
}

// View::color.
fn color(layer: u32, i: u32) -> vec3<f32> {
    return unpack_rgb9e5(shaded[layer * params.width * params.height + i].x);
}

// View::tap: neighbour q's centre-layer record, or with packed_taps off its
// flags and depth from both G-buffer layers (colour word left 0).
fn tap(q: u32) -> vec2<u32> {
    if params.packed_taps != 0u {
        return shaded[q];
    }
    let g = payload(0u, q);
    let a = payload(1u, q);
    return vec2<u32>(0u, (g.y & 0xFFFFFF00u) | select(0u, HIT, !is_empty(g)) | select(0u, CONS_HIT, !is_empty(a)));
}

// filter::shaded_rect: the pixels lipp.shade wrote records for this frame
// (lipp::rect; filter_args holds them: the binding declares its size); taps
// outside it read no hair.
fn shaded_rect() -> vec4<i32> {
    return vec4<i32>(rect_from_args(filter_args[FILTER_RECT_LO], filter_args[FILTER_RECT_HI]));
}

fn lin(z: f32) -> f32 {
    return linear_depth(frame.near, frame.far, z);
}

// filter::ndc_depth: the NDC depth at linear depth d > 0 (lin's inverse).
fn ndc(d: f32) -> f32 {
    return frame.far * (d - frame.near) / (d * (frame.far - frame.near));
}

// filter::screen_tangent.
fn screen_tangent(x: u32, y: u32, s: Sample) -> vec2<f32> {
    let p = world_position(frame.inv_view_proj, frame.screen, x, y, s.depth);
    let q = p + s.tangent * (0.01 * lin(s.depth));
    let a = transform(frame.view_proj, vec4<f32>(p, 1.0));
    let b = transform(frame.view_proj, vec4<f32>(q, 1.0));
    if a.w <= 0.0 || b.w <= 0.0 {
        return vec2<f32>(1.0, 0.0);
    }
    let dx = (b.x / b.w - a.x / a.w) * frame.screen.x;
    let dy = -(b.y / b.w - a.y / a.w) * frame.screen.y;
    let n = safe_normalize(vec3<f32>(dx, dy, 0.0));
    if n.x == 0.0 && n.y == 0.0 {
        return vec2<f32>(1.0, 0.0);
    }
    return n.xy;
}

// filter::band_span: the taps dx of window row dy within params.band of the
// line along unit tangent tp (lo > hi: none).
fn band_span(dy: f32, tp: vec2<f32>, r: i32) -> vec2<i32> {
    let c = dy * tp.x;
    let band = params.band;
    if band == 0.0 {
        return vec2<i32>(-r, r);
    }
    if abs(tp.y) < 1e-6 {
        return select(vec2<i32>(1, 0), vec2<i32>(-r, r), abs(c) <= band);
    }
    let a = (c - band) / tp.y;
    let b = (c + band) / tp.y;
    return vec2<i32>(max(i32(ceil(min(a, b))), -r), min(i32(floor(max(a, b))), r));
}

// filter::reconstruct: (filtered colour, alpha). With `parts` lanes a
// pixel, lane `part` takes every parts-th row of the window and the lanes
// add their sums (filter.rs, `lanes`).
fn reconstruct(x: u32, y: u32, z_ref: f32, tp: vec2<f32>, cp: vec3<f32>, promoted: bool, part: u32, parts: u32) -> vec4<f32> {
    let r = i32(params.radius);
    let sp = f32(params.radius) * params.s_parallel;
    let sq = f32(params.radius) * params.s_perp;
    // Per pixel, so that a tap divides by nothing (filter::reconstruct).
    let k_par = 1.0 / (sp * sp);
    let k_perp = 1.0 / (sq * sq);
    let k_c = select(1.0 / (params.sigma_c * params.sigma_c), 0.0, promoted);
    let strip2 = params.strip_width * params.strip_width;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    var hc = 0.0;
    var hcons = 0.0;
    let d_ref = lin(z_ref);
    // Within the threshold of the camera, every nearer depth is in the window.
    let near = d_ref - params.depth_threshold;
    let z_near = select(F32_MIN, ndc(near), near > 0.0);
    let z_far = ndc(d_ref + params.depth_threshold);
    let rect = shaded_rect();
    for (var dy = -r + i32(part); dy <= r; dy += i32(parts)) {
        let span = band_span(f32(dy), tp, r);
        for (var dx = span.x; dx <= span.y; dx++) {
            let qx = i32(x) + dx;
            let qy = i32(y) + dy;
            if qx < rect.x || qy < rect.y || qx >= rect.z || qy >= rect.w {
                continue;
            }
            let q = u32(qy) * params.width + u32(qx);
            let fx = f32(dx);
            let fy = f32(dy);
            let dpar = fx * tp.x + fy * tp.y;
            let ox = fx - dpar * tp.x;
            let oy = fy - dpar * tp.y;
            let perp2 = ox * ox + oy * oy;
            let t = tap(q);
            let hit = (t.y & HIT) != 0u;
            if perp2 <= strip2 {
                if hit {
                    hc += 1.0;
                } else if (t.y & CONS_HIT) != 0u {
                    hcons += 1.0;
                }
            }
            if !hit {
                continue;
            }
            let zq = record_depth(t.y);
            if zq < z_near || zq > z_far {
                continue;
            }
            var cq: vec3<f32>;
            if params.packed_taps != 0u {
                cq = unpack_rgb9e5(t.x);
            } else {
                cq = color(0u, q);
            }
            let d = cp - cq;
            let w = exp(-(dpar * dpar) * k_par - perp2 * k_perp - dot(d, d) * k_c);
            sum += cq * w;
            wsum += w;
        }
    }
    // A pixel's lanes are neighbours, aligned to their count, and take the
    // same branches.
    for (var m = 1u; m < parts; m <<= 1u) {
        sum += subgroupShuffleXor(sum, m);
        wsum += subgroupShuffleXor(wsum, m);
        hc += subgroupShuffleXor(hc, m);
        hcons += subgroupShuffleXor(hcons, m);
    }
    var c = cp;
    if wsum > 0.0 {
        c = sum / wsum;
    }
    var alpha = 1.0;
    if params.opacity_reconstruction != 0u && hc + hcons > 0.0 {
        alpha = hc / (hc + hcons);
        if params.true_width != 0u {
            let width = models[params.model_index].thickness * frame.pixels_per_unit / d_ref;
            alpha = true_width_alpha(alpha, params.centre_diameter, width);
        }
    }
    return vec4<f32>(c, alpha);
}

// filter::true_width_alpha.
fn true_width_alpha(f: f32, line: f32, width: f32) -> f32 {
    if f >= 1.0 {
        return 1.0;
    }
    let k = log(1.0 - clamp(width, 0.0, 0.99)) / log(1.0 - line);
    return 1.0 - pow(1.0 - f, k);
}

// The listed tiles' pixels, `parts` neighbouring lanes a pixel as many as
// the dispatch holds (tiles::filter_lanes), within one subgroup for the
// shuffles, FILTER_GROUP / parts pixels a workgroup, striding past 65,535
// workgroups.
@compute @workgroup_size(128)
fn filter_pixels(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let count = min(filter_args[3], arrayLength(&filter_tiles));
    let parts = filter_lanes(groups.x, count, min(params.lanes, sg_size));
    // Two lanes a pixel, the close views' width, as a constant the compiler
    // folds: with `parts` unknown the close view's filter took 0.189 ms on
    // the H200 against 0.187 with this copy.
    if parts == 2u {
        filter_listed(wg.x, groups.x, lane, count, 2u);
    } else {
        filter_listed(wg.x, groups.x, lane, count, parts);
    }
}

fn filter_listed(wg: u32, groups: u32, lane: u32, count: u32, parts: u32) {
    let per = FILTER_GROUP / parts;
    for (var p = wg * per + lane / parts; p < count * TILE; p += max(groups, 1u) * per) {
        filter_pixel(filter_tiles[p / TILE] * TILE + p % TILE, lane % parts, parts);
    }
}

// Lane `part` of `parts` filtering pixel i; part 0 writes.
fn filter_pixel(i: u32, part: u32, parts: u32) {
    if i >= params.width * params.height {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    let g = payload(0u, i);
    let a = payload(1u, i);
    let centre = !is_empty(g);
    let cons = !is_empty(a);
    var out = vec4<f32>(0.0);
    // NDC depth of the nearest sample the colour came from.
    var depth = 1.0;
    if params.msaa > 1u {
        // MSAA reference resolve (Lipp Fig. 5, "MSAA 8").
        var sum = vec3<f32>(0.0);
        var hits = 0u;
        for (var s = 0u; s < min(params.msaa, layer_count()); s++) {
            let q = payload(s, i);
            if !is_empty(q) {
                sum += color(s, i);
                hits += 1u;
                depth = min(depth, unpack_payload(q).depth);
            }
        }
        if hits == 0u {
            return;
        }
        out = vec4<f32>(sum / f32(hits), f32(hits) / f32(params.msaa));
    } else if params.enabled == 0u {
        if !centre {
            return;
        }
        out = vec4<f32>(color(0u, i), 1.0);
        depth = unpack_payload(g).depth;
    } else if centre || (cons && params.reconnect != 0u) {
        let sg = unpack_payload(g);
        let sa = unpack_payload(a);
        // A flyaway in front of the centre hit is blended over it.
        var front = false;
        // lipp.shade's decision (shaded::pixel_flags), which told it to
        // shade the conservative sample.
        if params.reconnect != 0u {
            front = (shaded[i].y & FRONT) != 0u;
        }
        // filter::filter_pixel's reconstructions (the centre sample or a
        // promoted conservative one, §3.3.2, then a flyaway) from one call
        // site in a loop: with one call per branch the window was inlined
        // three times, and on the H100 this one copy took the filter from
        // 64 registers to 56 and 0.398 to 0.316 ms at close (0.082 to 0.061
        // at far; benches/results/lipp-filter-call-site-h100.txt). Promoted
        // and flyaway references borrow colour (w_color = 1).
        var own = vec4<f32>(0.0);
        var over = vec4<f32>(0.0);
        for (var k = 0u; k < select(1u, 2u, front); k++) {
            let borrowed = k == 1u || !centre;
            let z = select(sg.depth, sa.depth, borrowed);
            let t = select(sg.tangent, sa.tangent, borrowed);
            let tp = screen_tangent(x, y, Sample(z, t, sg.uvw, sg.ao));
            let r = reconstruct(x, y, z, tp, color(select(0u, 1u, borrowed), i), borrowed, part, parts);
            if k == 0u {
                own = r;
            } else {
                over = r;
            }
        }
        out = own;
        depth = select(sg.depth, sa.depth, !centre);
        if front {
            let f = over;
            if params.true_width == 0u {
                out = vec4<f32>(f.xyz * f.w + out.xyz * (1.0 - f.w), 1.0);
            } else {
                // Both strands with their own opacity: the flyaway over the centre.
                let a = f.w + out.w * (1.0 - f.w);
                out = vec4<f32>((f.xyz * f.w + out.xyz * out.w * (1.0 - f.w)) / a, a);
            }
            depth = sa.depth;
        }
    } else {
        return;
    }
    if part != 0u {
        return;
    }
    let alpha = out.w;
    // Read only where hair is blended: most of the screen returns above.
    let scene = textureLoad(output, vec2<u32>(x, y));
    textureStore(output, vec2<u32>(x, y), vec4<f32>(out.xyz * alpha + scene.xyz * (1.0 - alpha), alpha + scene.w * (1.0 - alpha)));
    if alpha >= params.depth_alpha {
        hair_depth[i] = bitcast<u32>(min(bitcast<f32>(hair_depth[i]), depth));
    }
}
