//! The Kulikov-style pipeline (Indiana Jones strand hair, SIGGRAPH 2025
//! Advances): LOD, skinning, culling, tile atlas, sort, software raster and
//! a debug resolve. Each pass is one file: definition, CPU kernel, citation.

pub mod compose;
pub mod cull;
pub mod debug_resolve;
pub mod density;
pub mod depth_downsample;
pub mod lod;
pub mod motion;
pub mod payload;
pub mod raster;
pub mod shade;
pub mod shade_sort;
pub mod skin;
pub mod skin_shadow;
pub mod sort;
pub mod tile_alloc;

use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, ModelData, read};

/// Atlas tile edge in texels (Kulikov: "64x64 pixel tiles").
pub const TILE: u32 = 64;
/// Texels per atlas tile.
pub const TILE_TEXELS: u32 = TILE * TILE;

/// `lod_models`: the LOD pass's decision per model (8 words).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ModelLod {
    pub strands: u32,
    /// 1, or 2 when every other vertex is skipped.
    pub vertex_step: u32,
    pub thickness_scale: f32,
    /// Segments drawn per strand (after vertex skipping).
    pub segments_per_strand: u32,
    /// Drawn strands of all earlier models (for the skinning dispatch).
    pub strand_prefix: u32,
    /// Linear view depth range of the model's bounds, for payload depth.
    pub depth_near: f32,
    pub depth_far: f32,
    /// Drawn segments of all earlier models (for the dispatches over drawn
    /// segments: [`Scene::nth_drawn`]).
    pub segment_prefix: u32,
}

impl ModelLod {
    pub const WORDS: usize = 8;

    pub fn load(w: &Words<'_>, m: usize) -> Self {
        let b = m * Self::WORDS;
        Self {
            strands: w.load(b),
            vertex_step: w.load(b + 1).max(1),
            thickness_scale: w.load_f32(b + 2),
            segments_per_strand: w.load(b + 3),
            strand_prefix: w.load(b + 4),
            depth_near: w.load_f32(b + 5),
            depth_far: w.load_f32(b + 6),
            segment_prefix: w.load(b + 7),
        }
    }

    pub fn store(&self, w: &Words<'_>, m: usize) {
        let b = m * Self::WORDS;
        w.store(b, self.strands);
        w.store(b + 1, self.vertex_step);
        w.store_f32(b + 2, self.thickness_scale);
        w.store(b + 3, self.segments_per_strand);
        w.store(b + 4, self.strand_prefix);
        w.store_f32(b + 5, self.depth_near);
        w.store_f32(b + 6, self.depth_far);
        w.store(b + 7, self.segment_prefix);
    }

    /// Segments this model draws.
    pub fn drawn(&self) -> u32 {
        self.strands * self.segments_per_strand
    }

    /// The two vertex indices (within the strand) of drawn segment `k`.
    pub fn segment_vertices(&self, points: u32, k: u32) -> (u32, u32) {
        let v0 = k * self.vertex_step;
        (v0, (v0 + self.vertex_step).min(points - 1))
    }
}

/// Drawn segments per strand of `points` points at a vertex step.
pub fn drawn_segments(points: u32, step: u32) -> u32 {
    (points.saturating_sub(1)).div_ceil(step.max(1))
}

/// Per-frame data every Kulikov kernel reads, decoded once per workgroup.
pub struct Scene {
    pub frame: FrameData,
    pub models: Vec<ModelData>,
}

impl Scene {
    pub fn load(ctx: &Ctx<'_>) -> Self {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let models_w = ctx.words("models");
        let models = (0..frame.model_count as usize)
            .map(|m| read(&models_w, m))
            .collect();
        Self { frame, models }
    }

    /// The model owning global segment `id` (full numbering) and the local
    /// index. Models number their segments in order (`upload.rs`), so this
    /// is a binary search for the last model starting at or before `id`, as
    /// `segments.wgsl` does it. With the crowd's 28 grooms the linear
    /// search it replaces cost `kulikov.cull` 0.71 → 0.48 ms on an H100.
    pub fn segment_model(&self, id: u32) -> Option<(usize, u32)> {
        let m = self
            .models
            .partition_point(|md| md.segment_first <= id)
            .checked_sub(1)?;
        let md = &self.models[m];
        let count = md.strand_count * md.points_per_strand.saturating_sub(1);
        (id < md.segment_first + count).then(|| (m, id - md.segment_first))
    }

    /// The LOD pass's decisions (`lod_models`), one per model.
    pub fn lods(&self, ctx: &Ctx<'_>) -> Vec<ModelLod> {
        let w = ctx.words("lod_models");
        (0..self.models.len())
            .map(|m| ModelLod::load(&w, m))
            .collect()
    }

    /// The tile allocation (`atlas_tiles`), one per model.
    pub fn tiles(&self, ctx: &Ctx<'_>) -> Vec<tile_alloc::ModelTiles> {
        let w = ctx.words("atlas_tiles");
        (0..self.models.len())
            .map(|m| tile_alloc::ModelTiles::load(&w, m))
            .collect()
    }

    pub fn width(&self) -> u32 {
        self.frame.screen[0] as u32
    }
    pub fn height(&self) -> u32 {
        self.frame.screen[1] as u32
    }
}

/// Column-major 4×4 times a point.
pub fn transform(m: &[f32; 16], p: [f32; 4]) -> [f32; 4] {
    let mut out = [0.0; 4];
    for (r, o) in out.iter_mut().enumerate() {
        *o = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r] * p[3];
    }
    out
}

/// Clip space to screen pixels (y down), and NDC depth.
pub fn clip_to_screen(c: [f32; 4], width: f32, height: f32) -> [f32; 3] {
    let iw = 1.0 / c[3];
    [
        (c[0] * iw * 0.5 + 0.5) * width,
        (0.5 - c[1] * iw * 0.5) * height,
        c[2] * iw,
    ]
}

/// World position of a post-transform cache entry: `inv_view_proj × clip`, divided by w.
pub fn world_of_clip(inv_view_proj: &[f32; 16], c: [f32; 4]) -> [f32; 3] {
    let p = transform(inv_view_proj, c);
    let iw = 1.0 / p[3];
    [p[0] * iw, p[1] * iw, p[2] * iw]
}

#[cfg(test)]
mod segment_model_tests {
    use super::*;
    use bytemuck::Zeroable;

    fn model(segment_first: u32, strand_count: u32, points: u32) -> ModelData {
        ModelData {
            segment_first,
            strand_count,
            points_per_strand: points,
            ..ModelData::zeroed()
        }
    }

    #[test]
    fn finds_the_model_holding_each_segment() {
        // 4 x 3 segments, an empty model, 2 x 1 segments, 5 x 2 segments.
        let scene = Scene {
            frame: FrameData::zeroed(),
            models: vec![
                model(0, 4, 4),
                model(12, 0, 4),
                model(12, 2, 2),
                model(14, 5, 3),
            ],
        };
        let linear = |id: u32| {
            scene.models.iter().enumerate().find_map(|(m, md)| {
                let count = md.strand_count * md.points_per_strand.saturating_sub(1);
                (id >= md.segment_first && id < md.segment_first + count)
                    .then(|| (m, id - md.segment_first))
            })
        };
        for id in 0..30 {
            assert_eq!(scene.segment_model(id), linear(id), "segment {id}");
        }
        assert_eq!(scene.segment_model(12), Some((2, 0)));
        assert_eq!(scene.segment_model(24), None);
        let empty = Scene {
            frame: FrameData::zeroed(),
            models: vec![],
        };
        assert_eq!(empty.segment_model(0), None);
    }
}
