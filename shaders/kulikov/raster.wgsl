// kulikov.raster: the conservative software rasterizer into the tiled
// visibility atlas. Port of passes/src/kulikov/raster/{mod,geometry}.rs.
//
// Each lane takes one segment, rasterizes it as a trapezoid (positions and
// half widths snapped to 1/256 pixel, coverage = exact area of trapezoid ∩
// pixel from its edges, or by Sutherland-Hodgman clipping with
// analytic_coverage off), depth-tests every covered pixel
// against the scene depth at the pixel centre, and writes a 32-bit payload
// (depth10 << 22 | segment) into 3 ordered layers with chained atomicMin,
// plus atomicAdd(coverage, round(coverage * 1024)).
//
// The GPU-only optimisations, switched by the uniform parameters:
// - loop_flattening: Kulikov's single loop (a lane moves to its next column
//   on its own) instead of nested column/row loops run in lock step;
// - depth_test_stack, pixel_request_stack: the two LDS request stacks
//   ("Shipped with 2 stacks - for depth test and actual pixel writes").
//   Each subgroup owns 2 x subgroup_size entries of each stack (its
//   `subgroup_id` selects them; 256 lanes need 2 x 256 entries for any
//   subgroup size that divides 256, up to MAX_SUBGROUP). Requests are
//   pushed with subgroupExclusiveAdd and flushed, one per lane, when a
//   subgroup's worth is queued; lanes whose segment is done keep flushing
//   for the others. Only subgroup barriers are needed. Entries pack the
//   atlas texel (21 bits) with the coverage increment (11 bits); an atlas
//   layer larger than 2^21 texels disables the stacks;
// - last_layer_cull: skip the layer atomics when the last layer, read with
//   a plain atomicLoad, already holds something nearer;
// - morton_sort: a counting sort of the workgroup's segments by Morton code
//   of their midpoint, in workgroup memory (256 buckets over the group's
//   key range; the scan reuses the stack memory).
// None of them changes which writes happen: results are the CPU kernel's.
// With both stacks off the pass runs the entry `raster_no_stacks`, where
// they are compiled out (measured on an H100 at the 1080p close view: raster
// 0.78 ms with them off by the uniform, 0.61 ms compiled out).

// Bindings 2..=4 (frame, models, lod_models) are declared in segments.wgsl.
#define FRAME_BINDING 2
#define MODELS_BINDING 3
#define LOD_MODELS_BINDING 4
#import strandgraph::kulikov_segments::{frame, models, lod_models, drawn_segment}
#import strandgraph::layout::{ModelLod, ModelTiles}
#import strandgraph::kulikov::{TILE, TILE_TEXELS, EMPTY, LAYERS, COVERAGE_SCALE, round_away, model_trapezoid, load_lod, load_tiles, quantize_depth, pack_payload, linear_depth, Poly, poly_range, Trapezoid, trapezoid_column, quad_columns, quad_column_span, column_coverage, quad_pixel_coverage, trapezoid_depth_at, morton_code}

struct RasterParams {
    loop_flattening: u32,
    pixel_request_stack: u32,
    depth_test_stack: u32,
    last_layer_cull: u32,
    morton_sort: u32,
    // Kulikov's analytic slice coverage (registers) rather than clipping.
    analytic_coverage: u32,
    // Scene quantities: screen size in pixels.
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: RasterParams;
// Indirect arguments; word 3 is the number of sorted segments.
@group(0) @binding(1) var<storage, read> raster_args: array<u32>;
@group(0) @binding(5) var<storage, read> sorted_segments: array<u32>;
@group(0) @binding(6) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> groom_vertices: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> atlas_tiles: array<ModelTiles>;
@group(0) @binding(9) var scene_depth: texture_2d<f32>;
// LAYERS layers of arrayLength / LAYERS texels each.
@group(0) @binding(10) var<storage, read_write> vis_atlas: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> coverage_atlas: array<atomic<u32>>;

// Segments per workgroup (raster::GROUP).
const GROUP: u32 = 256u;
// Largest subgroup the stacks are laid out for.
const MAX_SUBGROUP: u32 = 128u;
// Stack entries: 2 x subgroup size per subgroup = 2 x GROUP.
const STACK: u32 = 512u;
const TEXEL_BITS: u32 = 21u;
const TEXEL_MASK: u32 = 0x1FFFFFu;

// Depth-test stack: screen pixel (x | y << 16), view depth, texel | coverage << 21, payload.
var<workgroup> depth_pos: array<u32, STACK>;
var<workgroup> depth_view: array<f32, STACK>;
var<workgroup> depth_texcov: array<u32, STACK>;
var<workgroup> depth_payload: array<u32, STACK>;
// Pixel-write stack: texel | coverage << 21, payload.
var<workgroup> write_texcov: array<u32, STACK>;
var<workgroup> write_payload: array<u32, STACK>;
// Morton counting sort.
var<workgroup> sort_count: array<atomic<u32>, GROUP>;
var<workgroup> sort_range: array<atomic<u32>, 2>;
var<workgroup> sort_valid: atomic<u32>;

var<private> sg_size: u32;
var<private> sg_lane: u32;
var<private> stack_base: u32;
var<private> use_depth_stack: bool;
var<private> use_pixel_stack: bool;
// Queued entries of this subgroup (the same value in every lane).
var<private> depth_count: u32;
var<private> write_count: u32;
var<private> layer_stride: u32;

// One lane's segment, projected into its model's atlas grid (raster::Lane).
struct Segment {
    valid: bool,
    trap: Trapezoid,
    local: u32,
    lod: ModelLod,
    tiles: ModelTiles,
    morton: u32,
}

// A covered pixel on its way to the atlas.
struct Request {
    pos: u32,
    view_depth: f32,
    texel: u32,
    payload: u32,
    cov: u32,
}

// RasterKernel::project for sorted segment number `index`.
fn project(index: u32) -> Segment {
    var out: Segment;
    out.valid = false;
    let seg = drawn_segment(sorted_segments[index]);
    if !seg.valid {
        return out;
    }
    let lod = load_lod(lod_models[seg.model]);
    let tiles = load_tiles(atlas_tiles[seg.model]);
    if tiles.valid == 0u {
        return out;
    }
    let trap = model_trapezoid(tiles, lod, clip_positions[seg.va], clip_positions[seg.vb],
        groom_vertices[seg.va].w, groom_vertices[seg.vb].w, frame.screen.xy, frame.pixels_per_unit,
        frame.near);
    if !trap.valid {
        return out;
    }
    let mid = vec2<f32>(0.5 * (trap.a.x + trap.b.x), 0.5 * (trap.a.y + trap.b.y));
    out.valid = true;
    out.trap = trap;
    out.local = seg.local;
    out.lod = lod;
    out.tiles = tiles;
    out.morton = morton_code(u32(max(mid.x, 0.0)), u32(max(mid.y, 0.0)));
    return out;
}

// Everything RasterKernel::write_pixel decides before the depth test.
fn pixel_request(s: Segment, x: i32, y: i32, coverage: f32) -> Request {
    let t = s.tiles;
    let view_depth = trapezoid_depth_at(s.trap.a, s.trap.b, s.trap.wa, s.trap.wb, x, y);
    // Depth test at the screen pixel under this atlas texel's centre.
    let d = t.downscale;
    let ux = u32(x);
    let uy = u32(y);
    let sx = min((t.origin_x * TILE + ux) * d + d / 2u, params.width - 1u);
    let sy = min((t.origin_y * TILE + uy) * d + d / 2u, params.height - 1u);
    let texel = (t.first_tile + (uy / TILE) * t.grid_w + ux / TILE) * TILE_TEXELS + (uy % TILE) * TILE + ux % TILE;
    let payload = pack_payload(quantize_depth(view_depth, s.lod.depth_near, s.lod.depth_far), s.local);
    let cov = u32(round_away(coverage * COVERAGE_SCALE));
    return Request(sx | (sy << 16u), view_depth, texel, payload, cov);
}

fn depth_passes(pos: u32, view_depth: f32) -> bool {
    let z = textureLoad(scene_depth, vec2<u32>(pos & 0xFFFFu, pos >> 16u), 0).x;
    return !(view_depth >= linear_depth(z, frame.near, frame.far));
}

// Kulikov's WritePixelToVisBuffer: last-layer cull, then chained atomicMin
// with the evicted value moving down; additive coverage in any case.
fn write_pixel(texel: u32, payload_in: u32, cov: u32) {
    var payload = payload_in;
    let culled = params.last_layer_cull != 0u && atomicLoad(&vis_atlas[texel + (LAYERS - 1u) * layer_stride]) < payload;
    if !culled {
        for (var layer = 0u; layer < LAYERS; layer++) {
            let prev = atomicMin(&vis_atlas[texel + layer * layer_stride], payload);
            if prev == EMPTY {
                break;
            }
            payload = max(payload, prev);
        }
    }
    atomicAdd(&coverage_atlas[texel], cov);
}

// --- Request stacks. Every function below is called in subgroup-uniform
// control flow: all lanes of the subgroup, with the same counts. ---

fn flush_write(take: u32) {
    subgroupBarrier();
    let top = write_count - take;
    if sg_lane < take {
        let i = stack_base + top + sg_lane;
        let tc = write_texcov[i];
        write_pixel(tc & TEXEL_MASK, write_payload[i], tc >> TEXEL_BITS);
    }
    write_count = top;
    // The entries just read may be overwritten by the next push.
    subgroupBarrier();
}

fn submit_write(has: bool, texel: u32, payload: u32, cov: u32) {
    if use_pixel_stack {
        let want = select(0u, 1u, has);
        let offset = subgroupExclusiveAdd(want);
        let added = subgroupAdd(want);
        if has {
            let i = stack_base + write_count + offset;
            write_texcov[i] = texel | (cov << TEXEL_BITS);
            write_payload[i] = payload;
        }
        write_count += added;
        if write_count >= sg_size {
            flush_write(sg_size);
        }
    } else if has {
        write_pixel(texel, payload, cov);
    }
}

fn flush_depth(take: u32) {
    subgroupBarrier();
    let top = depth_count - take;
    var passed = false;
    var texel = 0u;
    var payload = 0u;
    var cov = 0u;
    if sg_lane < take {
        let i = stack_base + top + sg_lane;
        let tc = depth_texcov[i];
        texel = tc & TEXEL_MASK;
        cov = tc >> TEXEL_BITS;
        payload = depth_payload[i];
        passed = depth_passes(depth_pos[i], depth_view[i]);
    }
    depth_count = top;
    subgroupBarrier();
    submit_write(passed, texel, payload, cov);
}

fn submit(has: bool, r: Request) {
    if use_depth_stack {
        let want = select(0u, 1u, has);
        let offset = subgroupExclusiveAdd(want);
        let added = subgroupAdd(want);
        if has {
            let i = stack_base + depth_count + offset;
            depth_pos[i] = r.pos;
            depth_view[i] = r.view_depth;
            depth_texcov[i] = r.texel | (r.cov << TEXEL_BITS);
            depth_payload[i] = r.payload;
        }
        depth_count += added;
        if depth_count >= sg_size {
            flush_depth(sg_size);
        }
    } else {
        var passed = false;
        if has {
            passed = depth_passes(r.pos, r.view_depth);
        }
        submit_write(passed, r.texel, r.payload, r.cov);
    }
}

// Whatever is still queued once every lane of the subgroup is done.
fn drain() {
    if use_depth_stack && depth_count > 0u {
        flush_depth(depth_count);
    }
    if use_pixel_stack {
        loop {
            if write_count == 0u {
                break;
            }
            flush_write(min(write_count, sg_size));
        }
    }
}

// First and last row of a column's y extent within the grid (empty: first > last).
fn column_rows(span: vec2<f32>, grid_h: i32) -> vec2<i32> {
    if span.x > span.y {
        return vec2<i32>(1, 0);
    }
    return vec2<i32>(max(i32(floor(span.x)), 0), min(i32(floor(span.y)), grid_h - 1));
}

// Cursor::open: column x's rows, from the trapezoid's edges with analytic
// coverage (lane state in registers); else from its slice, kept in `col`
// for the clipper.
fn open_column(seg: Segment, x: i32, grid_h: i32, col: ptr<function, Poly>) -> vec2<i32> {
    if params.analytic_coverage != 0u {
        return column_rows(quad_column_span(seg.trap.quad, x), grid_h);
    }
    *col = trapezoid_column(seg.trap.quad, x);
    if (*col).n < 3u {
        return vec2<i32>(1, 0);
    }
    return column_rows(poly_range(*col, 1u), grid_h);
}

// Counting sort of the workgroup's segments by Morton code; returns the
// segment this invocation rasterizes.
fn morton_sort(seg_in: Segment, index: u32, first: u32) -> Segment {
    var seg = seg_in;
    if index == 0u {
        atomicStore(&sort_range[0], 0xFFFFFFFFu);
        atomicStore(&sort_range[1], 0u);
        atomicStore(&sort_valid, 0u);
    }
    atomicStore(&sort_count[index], 0u);
    workgroupBarrier();
    if seg.valid {
        atomicMin(&sort_range[0], seg.morton);
        atomicMax(&sort_range[1], seg.morton);
        atomicAdd(&sort_valid, 1u);
    }
    workgroupBarrier();
    // 256 buckets over the group's key range.
    let lo = atomicLoad(&sort_range[0]);
    let span = atomicLoad(&sort_range[1]) - lo;
    var shift = 0u;
    if span >= GROUP {
        shift = firstLeadingBit(span) + 1u - 8u;
    }
    var bucket = 0u;
    var rank = 0u;
    if seg.valid {
        bucket = (seg.morton - lo) >> shift;
        rank = atomicAdd(&sort_count[bucket], 1u);
    }
    workgroupBarrier();
    // Exclusive scan of the bucket counts (Hillis-Steele, in the depth stack's memory).
    let own = atomicLoad(&sort_count[index]);
    depth_pos[index] = own;
    workgroupBarrier();
    var from_pos = true;
    for (var offset = 1u; offset < GROUP; offset <<= 1u) {
        if from_pos {
            var v = depth_pos[index];
            if index >= offset {
                v += depth_pos[index - offset];
            }
            depth_texcov[index] = v;
        } else {
            var v = depth_texcov[index];
            if index >= offset {
                v += depth_texcov[index - offset];
            }
            depth_pos[index] = v;
        }
        workgroupBarrier();
        from_pos = !from_pos;
    }
    // 8 rounds: the inclusive sums are back in depth_pos.
    write_payload[index] = depth_pos[index] - own;
    workgroupBarrier();
    if seg.valid {
        write_texcov[write_payload[bucket] + rank] = first + index;
    }
    workgroupBarrier();
    let valid = atomicLoad(&sort_valid);
    var sorted = 0u;
    if index < valid {
        sorted = write_texcov[index];
    }
    // The stacks reuse this memory.
    workgroupBarrier();
    seg.valid = false;
    if index < valid {
        seg = project(sorted);
    }
    return seg;
}

// RasterKernel's Cursor::pixel: the trapezoid's area in pixel (x, y) of the
// open column, from its edges in registers (the talk's analytic coverage)
// or by clipping the column slice.
fn pixel_coverage(seg: Segment, col: Poly, x: i32, y: i32) -> f32 {
    if params.analytic_coverage != 0u {
        return quad_pixel_coverage(seg.trap.quad, x, y);
    }
    return column_coverage(col, y);
}

// A pixel is written when its coverage quantises to at least 1/1024: slivers
// thinner than that are float noise that backends need not agree on.
// round_away, as the CPU kernel's f32::round: WGSL's round() sends exactly
// half a step (a common coverage on the snapped grid) to 0, and dropped those
// fragments on wgpu (tests/diff_wgpu.rs found it).
fn covers(coverage: f32) -> bool {
    return round_away(coverage * COVERAGE_SCALE) >= 1.0;
}

@compute @workgroup_size(256)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_size) subgroup_size: u32,
    @builtin(subgroup_invocation_id) subgroup_invocation_id: u32,
    @builtin(subgroup_id) subgroup_id: u32,
) {
    raster_segments(wg, index, subgroup_size, subgroup_invocation_id, subgroup_id, true);
}

// Both stacks off (RasterParams::entry): the stacks' code compiled out, so
// their live values cost this variant no registers.
@compute @workgroup_size(256)
fn raster_no_stacks(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_size) subgroup_size: u32,
    @builtin(subgroup_invocation_id) subgroup_invocation_id: u32,
    @builtin(subgroup_id) subgroup_id: u32,
) {
    raster_segments(wg, index, subgroup_size, subgroup_invocation_id, subgroup_id, false);
}

fn raster_segments(
    wg: vec3<u32>,
    index: u32,
    subgroup_size: u32,
    subgroup_invocation_id: u32,
    subgroup_id: u32,
    stacks: bool,
) {
    sg_size = subgroup_size;
    sg_lane = subgroup_invocation_id;
    layer_stride = arrayLength(&vis_atlas) / LAYERS;
    stack_base = subgroup_id * 2u * subgroup_size;
    let stacks_fit = subgroup_size <= MAX_SUBGROUP && stack_base + 2u * subgroup_size <= STACK
        && layer_stride <= (1u << TEXEL_BITS);
    use_depth_stack = stacks && params.depth_test_stack != 0u && stacks_fit;
    use_pixel_stack = stacks && params.pixel_request_stack != 0u && stacks_fit;
    depth_count = 0u;
    write_count = 0u;

    // No early return: the sort's barriers and the subgroup loops need every invocation.
    let count = raster_args[3];
    let first = wg.x * GROUP;
    var seg: Segment;
    seg.valid = false;
    if first + index < count {
        seg = project(first + index);
    }
    if params.morton_sort != 0u {
        seg = morton_sort(seg, index, first);
    }

    var x = 0;
    var x_end = -1;
    var grid_h = 0;
    if seg.valid {
        let columns = quad_columns(seg.trap.quad);
        x = max(columns.x, 0);
        x_end = min(columns.y, i32(seg.tiles.grid_w * TILE) - 1);
        grid_h = i32(seg.tiles.grid_h * TILE);
    }
    var col: Poly;
    var y = 0;
    var y_end = -1;

    if params.loop_flattening != 0u {
        // Kulikov's flattened loop: a lane that finishes a column opens its
        // next one in the same step; the subgroup loops while any lane has pixels.
        var alive = false;
        loop {
            if x > x_end {
                break;
            }
            let rows = open_column(seg, x, grid_h, &col);
            if rows.x <= rows.y {
                y = rows.x;
                y_end = rows.y;
                alive = true;
                break;
            }
            x += 1;
        }
        loop {
            if !subgroupAny(alive) {
                break;
            }
            var has = false;
            var req: Request;
            if alive {
                let coverage = pixel_coverage(seg, col, x, y);
                if covers(coverage) {
                    has = true;
                    req = pixel_request(seg, x, y, coverage);
                }
                y += 1;
                if y > y_end {
                    alive = false;
                    x += 1;
                    loop {
                        if x > x_end {
                            break;
                        }
                        let rows = open_column(seg, x, grid_h, &col);
                        if rows.x <= rows.y {
                            y = rows.x;
                            y_end = rows.y;
                            alive = true;
                            break;
                        }
                        x += 1;
                    }
                }
            }
            submit(has, req);
        }
    } else {
        // Nested loops: every column of the subgroup costs as many steps as
        // its tallest slice (the lock step the flattened loop removes).
        loop {
            let has_col = x <= x_end;
            if !subgroupAny(has_col) {
                break;
            }
            y = 0;
            y_end = -1;
            if has_col {
                let rows = open_column(seg, x, grid_h, &col);
                y = rows.x;
                y_end = rows.y;
            }
            loop {
                let busy = has_col && y <= y_end;
                if !subgroupAny(busy) {
                    break;
                }
                var has = false;
                var req: Request;
                if busy {
                    let coverage = pixel_coverage(seg, col, x, y);
                    if covers(coverage) {
                        has = true;
                        req = pixel_request(seg, x, y, coverage);
                    }
                    y += 1;
                }
                submit(has, req);
            }
            x += 1;
        }
    }
    drain();
}
