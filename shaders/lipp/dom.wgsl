// What the deep opacity map's writers (lipp.dom_depth, lipp.dom_opacity in
// dom_maps.wgsl) and its reader (lipp.shade) share: the map's constants and
// the light frames, with the scene bindings those read (frame, models,
// lights) declared once. Composed with naga_oil:
//   #define FRAME_BINDING 1
//   #define MODELS_BINDING 2
//   #define LIGHTS_BINDING 3
//   #import strandgraph::lipp_dom::{frame, models, lights, light_frame, NO_HIT, OPACITY_SCALE}
// Each pass numbers its bindings in the order of its definition's
// bindings() (passes/tests/wgsl_bindings.rs checks it), so the importing shader
// says where these three sit with the defines above.
// naga_oil renames every token that spells an imported name, struct members
// included: an importer must not use these names for anything else (or
// must reach the item qualified, as lipp/shade.wgsl does with `lights`).
#define_import_path strandgraph::lipp_dom

#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::lipp::{LightFrame, light_frame_of}

@group(0) @binding(#{FRAME_BINDING}) var<storage, read> frame: FrameData;
@group(0) @binding(#{MODELS_BINDING}) var<storage, read> models: array<ModelData>;
@group(0) @binding(#{LIGHTS_BINDING}) var<storage, read> lights: array<LightData>;

// dom::{NO_HIT, OPACITY_SCALE}.
const NO_HIT: u32 = 0xFFFFFFFFu;
const OPACITY_SCALE: f32 = 1024.0;

// dom::LightFrame::new over every model's bounds.
fn light_frame(l: u32) -> LightFrame {
    var lo = vec3<f32>(3.40282347e38);
    var hi = vec3<f32>(-3.40282347e38);
    let count = min(frame.model_count, arrayLength(&models));
    for (var m = 0u; m < count; m++) {
        lo = min(lo, models[m].bounds_min.xyz);
        hi = max(hi, models[m].bounds_max.xyz);
    }
    if count == 0u {
        lo = vec3<f32>(-1.0);
        hi = vec3<f32>(1.0);
    }
    return light_frame_of(lo, hi, lights[l].position_or_direction);
}
