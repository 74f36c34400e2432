// kulikov.tile_alloc: 64x64 atlas tiles for each model's visible screen
// bounds, at the smallest power-of-two downscale that fits.
// Port of passes/src/kulikov/tile_alloc.rs (`allocate`), one invocation.

#import strandgraph::layout::{FrameData, ModelTiles}
#import strandgraph::kulikov::TILE

struct TileParams {
    atlas_tiles: u32,
    max_downscale: u32,
    // Scene quantity: hair models.
    models: u32,
}

@group(0) @binding(0) var<uniform> params: TileParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> screen_bounds: array<u32>;
@group(0) @binding(3) var<storage, read_write> atlas_tiles: array<ModelTiles>;

// tile_alloc::visible_bounds: (x0, y0, x1, y1), or x0 > x1 when nothing is visible.
fn visible_bounds(m: u32) -> vec4<u32> {
    return vec4<u32>(screen_bounds[4u * m], screen_bounds[4u * m + 1u], ~screen_bounds[4u * m + 2u], ~screen_bounds[4u * m + 3u]);
}

fn is_visible(b: vec4<u32>) -> bool {
    return b.x <= b.z && b.y <= b.w;
}

// (origin x, origin y, grid w, grid h) in tiles of TILE * d pixels.
fn grid(b: vec4<u32>, d: u32) -> vec4<u32> {
    let span = TILE * d;
    return vec4<u32>(b.x / span, b.y / span, b.z / span - b.x / span + 1u, b.w / span - b.y / span + 1u);
}

@compute @workgroup_size(1)
fn allocate() {
    _ = frame.model_count;
    let count = params.models;
    let max_downscale = max(params.max_downscale, 1u);
    var d = 1u;
    loop {
        var need = 0u;
        for (var m = 0u; m < count; m++) {
            let b = visible_bounds(m);
            if is_visible(b) {
                let g = grid(b, d);
                need += g.z * g.w;
            }
        }
        if need <= params.atlas_tiles || d >= max_downscale {
            break;
        }
        d *= 2u;
    }
    var next = 0u;
    for (var m = 0u; m < count; m++) {
        let b = visible_bounds(m);
        if !is_visible(b) {
            atlas_tiles[m] = ModelTiles(0u, 0u, 0u, 0u, 0u, d, 0u, 0u);
            continue;
        }
        let g = grid(b, d);
        let fits = next + g.z * g.w <= params.atlas_tiles;
        atlas_tiles[m] = ModelTiles(next, g.z, g.w, g.x, g.y, d, select(0u, 1u, fits), 0u);
        if fits {
            next += g.z * g.w;
        }
    }
}
