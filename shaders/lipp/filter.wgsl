// lipp.filter: Lipp §3.3 and Appendix B Code 2, the single-pass elliptical
// bilateral reconnection filter with opacity reconstruction, blended over
// `output`. Port of passes/src/lipp/filter.rs (see its deviations).
// `output` is Rgba16Float, read and written: a read_write storage texture.

#import strandgraph::layout::{FrameData, ModelData}
#import strandgraph::clip::transform
#import strandgraph::lipp::{safe_normalize, is_empty, unpack_payload, world_position, linear_depth, Sample, EMPTY_WORD}

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
    front_threshold: f32,
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
}

@group(0) @binding(0) var<uniform> params: FilterParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> gbuffer: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> shaded: array<vec4<f32>>;
@group(0) @binding(4) var output: texture_storage_2d<rgba16float, read_write>;
// NDC depth (f32 bits) the next groom's rasterizer is tested against.
@group(0) @binding(5) var<storage, read_write> hair_depth: array<u32>;
@group(0) @binding(6) var<storage, read> models: array<ModelData>;
// lipp.shade's tiles with hair and their count (lipp::tiles).
@group(0) @binding(7) var<storage, read> filter_tiles: array<u32>;
@group(0) @binding(8) var<storage, read> filter_args: array<u32>;

// lipp::tiles::TILE, this pass's workgroup size.
const TILE: u32 = 64u;

fn payload(layer: u32, i: u32) -> vec2<u32> {
    return gbuffer[layer * params.width * params.height + i];
}

// lipp::gbuffer_layers.
fn layer_count() -> u32 {
    let pixels = max(params.width * params.height, 1u);
    return max(min(arrayLength(&gbuffer), arrayLength(&shaded)) / pixels, 2u);
}

fn color(layer: u32, i: u32) -> vec4<f32> {
    return shaded[layer_count() * i + layer];
}

fn lin(z: f32) -> f32 {
    return linear_depth(frame.near, frame.far, z);
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

// filter::Partial: one lane's share of a window.
struct Partial {
    sum: vec3<f32>,
    wsum: f32,
    hc: f32,
    hcons: f32,
}

// filter::WINDOW_LANES: lanes sharing a pixel's window, a row each in turn.
const WINDOW_LANES: u32 = 8u;

var<workgroup> partials: array<Partial, 64>;

// filter::window_rows: the window's rows -r + k, -r + k + 8, ... of pixel
// (x, y) around a reference sample.
fn window_rows(x: u32, y: u32, d_ref: f32, tp: vec2<f32>, cp: vec4<f32>, promoted: bool, k: u32) -> Partial {
    let r = i32(params.radius);
    let sp = f32(params.radius) * params.s_parallel;
    let sq = f32(params.radius) * params.s_perp;
    var part = Partial(vec3<f32>(0.0), 0.0, 0.0, 0.0);
    for (var dy = -r + i32(k); dy <= r; dy += i32(WINDOW_LANES)) {
        for (var dx = -r; dx <= r; dx++) {
            let qx = i32(x) + dx;
            let qy = i32(y) + dy;
            if qx < 0 || qy < 0 || qx >= i32(params.width) || qy >= i32(params.height) {
                continue;
            }
            let q = u32(qy) * params.width + u32(qx);
            let fx = f32(dx);
            let fy = f32(dy);
            let dpar = fx * tp.x + fy * tp.y;
            let ox = fx - dpar * tp.x;
            let oy = fy - dpar * tp.y;
            let dperp = sqrt(ox * ox + oy * oy);
            let gq = payload(0u, q);
            let aq = payload(1u, q);
            if dperp <= params.strip_width {
                if !is_empty(gq) {
                    part.hc += 1.0;
                } else if !is_empty(aq) {
                    part.hcons += 1.0;
                }
            }
            if is_empty(gq) {
                continue;
            }
            let zq = unpack_payload(gq).depth;
            if abs(lin(zq) - d_ref) > params.depth_threshold {
                continue;
            }
            let cq = color(0u, q);
            let ws = exp(-(dpar * dpar) / (sp * sp) - dperp * dperp / (sq * sq));
            var wc = 1.0;
            if !promoted {
                let d = cp.xyz - cq.xyz;
                wc = exp(-dot(d, d) / (params.sigma_c * params.sigma_c));
            }
            let w = ws * wc;
            part.sum += cq.xyz * w;
            part.wsum += w;
        }
    }
    return part;
}

// filter::reconstruct: (filtered colour, alpha), by the 8 lanes of pixel
// (x, y) together. Every lane of the workgroup calls it (it holds
// barriers); a lane whose pixel needs no reconstruction passes `busy`
// false and gets zero.
fn reconstruct(lane: u32, busy: bool, x: u32, y: u32, z_ref: f32, tp: vec2<f32>, cp: vec4<f32>, promoted: bool) -> vec4<f32> {
    let d_ref = lin(z_ref);
    var part = Partial(vec3<f32>(0.0), 0.0, 0.0, 0.0);
    if busy {
        part = window_rows(x, y, d_ref, tp, cp, promoted, lane % WINDOW_LANES);
    }
    partials[lane] = part;
    workgroupBarrier();
    // The lanes' shares summed in lane order, as filter::reconstruct does.
    let base = lane - lane % WINDOW_LANES;
    var t = Partial(vec3<f32>(0.0), 0.0, 0.0, 0.0);
    for (var k = 0u; k < WINDOW_LANES; k++) {
        let o = partials[base + k];
        t = Partial(t.sum + o.sum, t.wsum + o.wsum, t.hc + o.hc, t.hcons + o.hcons);
    }
    workgroupBarrier();
    var c = cp.xyz;
    if t.wsum > 0.0 {
        c = t.sum / t.wsum;
    }
    var alpha = 1.0;
    if params.opacity_reconstruction != 0u && t.hc + t.hcons > 0.0 {
        alpha = t.hc / (t.hc + t.hcons);
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

// A workgroup per listed tile, striding past 65,535 of them; the tile's
// 64 pixels in 8 batches of 8, each pixel's window shared by 8 lanes.
@compute @workgroup_size(64)
fn filter_pixels(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let count = min(filter_args[3], arrayLength(&filter_tiles));
    for (var t = wg.x; t < count; t += max(groups.x, 1u)) {
        let tile = filter_tiles[t];
        for (var b = 0u; b < TILE / WINDOW_LANES; b++) {
            filter_pixel(tile * TILE + b * WINDOW_LANES + lane / WINDOW_LANES, lane);
        }
    }
}

// filter::filter_pixel for pixel i, with the other lanes of its group.
fn filter_pixel(i: u32, lane: u32) {
    let valid = i < params.width * params.height;
    let writer = valid && lane % WINDOW_LANES == 0u;
    let x = i % params.width;
    let y = i / params.width;
    var g = vec2<u32>(EMPTY_WORD);
    var a = vec2<u32>(EMPTY_WORD);
    if valid {
        g = payload(0u, i);
        a = payload(1u, i);
    }
    let centre = !is_empty(g);
    let cons = !is_empty(a);
    if params.msaa > 1u || params.enabled == 0u {
        if writer {
            resolve_unfiltered(i, x, y, g, centre);
        }
        return;
    }
    let connect = cons && params.reconnect != 0u;
    // The reconstruction around the centre hit, or a promoted
    // conservative-only pixel's (§3.3.2).
    var first = Sample(1.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    var first_colour = vec4<f32>(0.0);
    if centre {
        first = unpack_payload(g);
        first_colour = color(0u, i);
    } else if connect {
        first = unpack_payload(a);
        first_colour = color(1u, i);
    }
    let busy = centre || connect;
    let out_first = reconstruct(lane, busy, x, y, first.depth, screen_tangent(x, y, first), first_colour, !centre);
    // A flyaway in front of the centre hit.
    var front = false;
    var sa = Sample(1.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    var flyaway_colour = vec4<f32>(0.0);
    if centre && connect {
        sa = unpack_payload(a);
        front = lin(sa.depth) <= lin(first.depth) - params.front_threshold;
        flyaway_colour = color(1u, i);
    }
    let f = reconstruct(lane, front, x, y, sa.depth, screen_tangent(x, y, sa), flyaway_colour, true);
    if !writer || !busy {
        return;
    }
    var out = out_first;
    var depth = first.depth;
    if front {
        if params.true_width == 0u {
            out = vec4<f32>(f.xyz * f.w + out.xyz * (1.0 - f.w), 1.0);
        } else {
            // Both strands with their own opacity: the flyaway over the centre.
            let al = f.w + out.w * (1.0 - f.w);
            out = vec4<f32>((f.xyz * f.w + out.xyz * out.w * (1.0 - f.w)) / al, al);
        }
        depth = sa.depth;
    }
    blend(i, x, y, out, depth);
}

// The MSAA reference resolve (Lipp Fig. 5, "MSAA 8") and, with the filter
// off, the centre layer as it is (SWR 1).
fn resolve_unfiltered(i: u32, x: u32, y: u32, g: vec2<u32>, centre: bool) {
    if params.msaa > 1u {
        var sum = vec3<f32>(0.0);
        var hits = 0u;
        var depth = 1.0;
        for (var s = 0u; s < min(params.msaa, layer_count()); s++) {
            let q = payload(s, i);
            if !is_empty(q) {
                sum += color(s, i).xyz;
                hits += 1u;
                depth = min(depth, unpack_payload(q).depth);
            }
        }
        if hits > 0u {
            blend(i, x, y, vec4<f32>(sum / f32(hits), f32(hits) / f32(params.msaa)), depth);
        }
    } else if centre {
        blend(i, x, y, vec4<f32>(color(0u, i).xyz, 1.0), unpack_payload(g).depth);
    }
}

// filter::Hair::over, and the hair depth later grooms test (Lipp §3.5).
fn blend(i: u32, x: u32, y: u32, out: vec4<f32>, depth: f32) {
    let alpha = out.w;
    let scene = textureLoad(output, vec2<u32>(x, y));
    textureStore(output, vec2<u32>(x, y), vec4<f32>(out.xyz * alpha + scene.xyz * (1.0 - alpha), alpha + scene.w * (1.0 - alpha)));
    if alpha >= params.depth_alpha {
        hair_depth[i] = bitcast<u32>(min(bitcast<f32>(hair_depth[i]), depth));
    }
}
