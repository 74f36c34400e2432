// bench.raster: the graphics roofline, as passes/src/bench/raster.rs.
// `layers` layers of a grid of cell x cell pixel squares, two triangles each
// (cell 0: one square over the whole screen), no vertex buffers, no depth, no
// culling; every fragment writes the RGBA8 bytes of pcg(pixel index), so the
// image does not depend on the order triangles are drawn in.

#import strandgraph::hash::pcg

struct RasterBenchParams {
    cell: u32,
    layers: u32,
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: RasterBenchParams;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
}

// RasterBenchParams::corner, in pixels, then to NDC (y up).
@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    var gx = 1u;
    var gy = 1u;
    var cw = params.width;
    var ch = params.height;
    if params.cell != 0u {
        gx = (params.width + params.cell - 1u) / params.cell;
        gy = (params.height + params.cell - 1u) / params.cell;
        cw = params.cell;
        ch = params.cell;
    }
    let t = vertex / 3u;
    let k = vertex % 3u;
    let square = (t / 2u) % (gx * gy);
    let sx = square % gx;
    let sy = square / gx;
    // 0 top-left, 1 bottom-left, 2 top-right, 3 bottom-right.
    var corner = array<u32, 3>(0u, 1u, 2u)[k];
    if t % 2u == 1u {
        corner = array<u32, 3>(2u, 1u, 3u)[k];
    }
    let px = f32((sx + (corner >> 1u)) * cw);
    let py = f32((sy + (corner & 1u)) * ch);
    var out: VertexOut;
    out.position = vec4<f32>(px / f32(params.width) * 2.0 - 1.0, 1.0 - py / f32(params.height) * 2.0, 0.5, 1.0);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let i = u32(in.position.y) * params.width + u32(in.position.x);
    return unpack4x8unorm(pcg(i));
}
