// kulikov.debug_resolve: the visibility atlas resolved to screen. Blends each
// model's reconstructed coverage in its colour over `output` and writes the
// three layers' 10-bit depths (R, G, B: brighter is nearer) and the total
// coverage (A) to `debug_layers`.
// Port of passes/src/kulikov/debug_resolve.rs. `output` is Rgba16Float and
// both read and written: a read_write storage texture (wgpu needs
// TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES for rgba16float read_write).

#import strandgraph::layout::{FrameData, ModelData, ModelTiles}
#import strandgraph::kulikov::{load_tiles, tile_texel, round_away, total_coverage, depth_of, EMPTY, LAYERS}

struct ResolveParams {
    // Scene quantities: screen width and pixel count.
    width: u32,
    pixels: u32,
}

@group(0) @binding(0) var<uniform> params: ResolveParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read> atlas_tiles: array<ModelTiles>;
@group(0) @binding(4) var<storage, read> vis_atlas: array<u32>;
@group(0) @binding(5) var<storage, read> coverage_atlas: array<u32>;
@group(0) @binding(6) var output: texture_storage_2d<rgba16float, read_write>;
@group(0) @binding(7) var debug_layers: texture_storage_2d<rgba8unorm, write>;

const GROUP: u32 = 256u;

@compute @workgroup_size(256)
fn resolve(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let i = wg.x * GROUP + lane;
    if i >= params.pixels {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    let stride = arrayLength(&vis_atlas) / LAYERS;
    var color = textureLoad(output, vec2<u32>(x, y));
    var debug = 0u;
    for (var m = 0u; m < frame.model_count; m++) {
        let texel = tile_texel(load_tiles(atlas_tiles[m]), x, y);
        if texel == EMPTY {
            continue;
        }
        let alpha = total_coverage(coverage_atlas[texel]);
        if alpha <= 0.0 {
            continue;
        }
        let c = models[m].color;
        color = vec4<f32>(
            color.x * (1.0 - alpha) + c.x * alpha,
            color.y * (1.0 - alpha) + c.y * alpha,
            color.z * (1.0 - alpha) + c.z * alpha,
            color.w * (1.0 - alpha) + alpha,
        );
        if debug == 0u {
            var d = vec3<u32>(0u);
            for (var l = 0u; l < LAYERS; l++) {
                let p = vis_atlas[texel + l * stride];
                d[l] = select(255u - depth_of(p) / 4u, 0u, p == EMPTY);
            }
            debug = d.x | (d.y << 8u) | (d.z << 16u) | (u32(round_away(alpha * 255.0)) << 24u);
        }
    }
    textureStore(output, vec2<u32>(x, y), color);
    // Rgba8Unorm: byte k / 255 stores back as byte k.
    textureStore(debug_layers, vec2<u32>(x, y), unpack4x8unorm(debug));
}

