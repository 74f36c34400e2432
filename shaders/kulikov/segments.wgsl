// The scene bindings every per-segment Kulikov pass reads (frame, models,
// lod_models), declared once with the helpers that read them. Composed
// with naga_oil:
//   #define FRAME_BINDING 1
//   #define MODELS_BINDING 2
//   #define LOD_MODELS_BINDING 3
//   #import strandgraph::kulikov_segments::{frame, models, lod_models, drawn_segment, world_of_clip}
// Each pass numbers its bindings in the order of its definition's
// bindings() (passes/tests/wgsl_bindings.rs checks it), so the importing shader
// says where these three sit with the defines above; naga_oil substitutes
// them into this module when it composes that shader.
// naga_oil renames every token that spells an imported name, struct members
// included: an importer must not use these names for anything else (or
// must reach the item qualified, as lipp/shade.wgsl does with `lights`).
#define_import_path strandgraph::kulikov_segments

#import strandgraph::layout::{FrameData, ModelData, ModelLod}
#import strandgraph::clip::transform
#import strandgraph::kulikov::{load_lod, segment_in_model, drawn_in_model, DrawnSegment}

@group(0) @binding(#{FRAME_BINDING}) var<storage, read> frame: FrameData;
@group(0) @binding(#{MODELS_BINDING}) var<storage, read> models: array<ModelData>;
@group(0) @binding(#{LOD_MODELS_BINDING}) var<storage, read> lod_models: array<ModelLod>;

// The last model whose first segment is at or before `key` (binary
// search: models number their segments in order). `drawn`: first segments
// of the LOD's compact numbering (ModelLod::segment_prefix), else of the
// full numbering (ModelData::segment_first). Callers pass a constant.
fn last_model_at_or_before(key: u32, drawn: bool) -> u32 {
    var m = 0u;
    var n = frame.model_count;
    loop {
        if n <= 1u {
            break;
        }
        let half = n / 2u;
        var start = models[m + half].segment_first;
        if drawn {
            start = lod_models[m + half].segment_prefix;
        }
        if start <= key {
            m += half;
        }
        n -= half;
    }
    return m;
}

// cull::drawn_segment: the model holding `id` (Scene::segment_model's
// binary search), then its LOD.
fn drawn_segment(id: u32) -> DrawnSegment {
    let m = last_model_at_or_before(id, false);
    if frame.model_count > 0u {
        let md = models[m];
        if segment_in_model(md, id) {
            return drawn_in_model(md, load_lod(lod_models[m]), m, id);
        }
    }
    return DrawnSegment(false, 0u, 0u, 0u, 0u);
}

// cull::nth_drawn: drawn segment `d` of the LOD's compact numbering (models
// in order, each model's kept strands, each strand's drawn segments);
// invalid past the last. Its global id is the model's segment_first + local.
fn nth_drawn(d: u32) -> DrawnSegment {
    let m = last_model_at_or_before(d, true);
    if frame.model_count > 0u {
        let lod = load_lod(lod_models[m]);
        let local = d - lod.segment_prefix;
        if d >= lod.segment_prefix && local < lod.strands * lod.segments_per_strand {
            let md = models[m];
            let strand = local / lod.segments_per_strand;
            let k = local % lod.segments_per_strand;
            return drawn_in_model(md, lod, m, md.segment_first + strand * (md.points_per_strand - 1u) + k);
        }
    }
    return DrawnSegment(false, 0u, 0u, 0u, 0u);
}

// kulikov::world_of_clip.
fn world_of_clip(c: vec4<f32>) -> vec3<f32> {
    let p = transform(frame.inv_view_proj, c);
    let iw = 1.0 / p.w;
    return vec3<f32>(p.x * iw, p.y * iw, p.z * iw);
}
