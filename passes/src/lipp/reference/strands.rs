//! `lipp.reference_strands`: the ground truth's strands (see the module
//! above). One workgroup per kept strand, dispatched like `lipp.raster`
//! from `raster_args`; the strand is assembled by the same code
//! ([`assemble`], Lipp Code 1, styling included), so the reference draws the
//! curve the pipeline draws, at the LOD pass's control points.
//!
//! Each segment becomes a ribbon of the groom's thickness (hair meshes
//! carry none; the groom generated from the same mesh has one, the
//! model's `thickness`), unsnapped, joined to its neighbours but at root
//! and tip, counted in every tile it may reach.

use super::{PointRecord, SLOTS};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::kulikov::transform;
use crate::layout::{FrameData, ModelData, read};
use crate::lipp::assemble::{Assembly, Strands, assemble};
use crate::lipp::payload::quantize;
use crate::lipp::strand::{ControlPoint, strand_uv};
use crate::lipp::{MAX_CONTROL_POINTS, RASTER_GROUP, frame};
use crate::params::{Invalid, PassParams};
use crate::reference::bin::store_ribbon;
use crate::reference::ribbon::{Record, Ribbon};
use crate::reference::tiles;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StrandsParams {
    /// Curl, twist and noise, as `lipp.raster`'s `styling`.
    pub styling: bool,
}

impl Default for StrandsParams {
    fn default() -> Self {
        Self { styling: true }
    }
}

impl PassParams for StrandsParams {
    fn validate(&self) -> Result<(), Invalid> {
        Ok(())
    }
}

crate::gpu_block! {
    /// `StrandsParams` in shaders/lipp/reference_strands.wgsl.
    pub struct StrandsGpu {
        bundles: u32,
        width: u32,
        height: u32,
        tiles_x: u32,
        styling: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static STRANDS: PassKind<StrandsParams, StrandsGpu> = PassKind {
    kind: "lipp.reference_strands",
    summary: "the ground truth's strands: Lipp's assembly at the LOD's control points, every point and every segment's ribbon, counted per 8x8 tile",
    source: "ours: the ground-truth reference (docs/reference.md), assembly after Lipp Appendix B Code 1",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("raster_args"),
        Binding::read("bundle_lod"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::read("models"),
        Binding::atomic("reference_counts"),
        Binding::write("reference_ribbons"),
        Binding::write("reference_points"),
    ]),
    workgroup_size: RASTER_GROUP,
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: 0,
    },
    shader: Shader::compute("lipp/reference_strands.wgsl", "reference_strands"),
    kernel: |p| Box::new(StrandsKernel(*p)),
    gpu: |p, q| StrandsGpu {
        bundles: count(q.bundles),
        width: q.width,
        height: q.height,
        tiles_x: tiles(q.width, q.height).0,
        styling: flag(p.styling),
        ..StrandsGpu::default()
    },
    raster: None,
};

/// What one strand's points and segments are written with.
struct Writer<'a> {
    f: &'a FrameData,
    width: u32,
    height: u32,
    counts: Words<'a>,
    records: Words<'a>,
    points: Words<'a>,
}

impl Writer<'_> {
    fn point(&self, slot: u32, p: &ControlPoint, tangent: [f32; 3], template: &PointRecord) {
        let record = PointRecord {
            pos: p.pos,
            ao: p.ao,
            tangent,
            ..*template
        };
        record.store(&self.points, slot as usize);
    }

    /// Segment `m` of a strand of `c` points, between slots `slot` and
    /// `slot + 1`: its ribbon, counted in its tiles.
    fn segment(
        &self,
        slot: u32,
        a: &ControlPoint,
        b: &ControlPoint,
        m: u32,
        c: u32,
        thickness: f32,
    ) {
        let clip =
            |p: &ControlPoint| transform(&self.f.view_proj, [p.pos[0], p.pos[1], p.pos[2], 1.0]);
        let record = Ribbon::new(
            self.f,
            clip(a),
            clip(b),
            thickness,
            thickness,
            m > 0,
            m + 2 < c,
        )
        .map(|ribbon| Record {
            ribbon,
            vertices: [slot, slot + 1],
        });
        store_ribbon(
            record.as_ref(),
            slot,
            &self.records,
            &self.counts,
            self.width,
            self.height,
        );
    }
}

/// The strand thickness of `model` (`ModelData::thickness`, the groom's).
fn thickness(ctx: &Ctx<'_>, model: u32) -> f32 {
    let m: ModelData = read(&ctx.words("models"), model as usize);
    m.thickness
}

struct StrandsKernel(StrandsParams);

impl CpuKernel for StrandsKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let strands = Strands::load(ctx);
        let model_count = (ctx.words("models").len() / 64).max(1) as u32;
        let widths: Vec<f32> = (0..model_count).map(|m| thickness(ctx, m)).collect();
        let writer = Writer {
            f: &f,
            width: ctx.quantities.width,
            height: ctx.quantities.height,
            counts: ctx.words("reference_counts"),
            records: ctx.words("reference_ribbons"),
            points: ctx.words("reference_points"),
        };
        let opts = Assembly::new(ctx, true, self.0.styling);
        let mut s = group;
        while s < strands.total {
            let (lod, rec, k) = strands.strand(s);
            let c = lod.control_points.clamp(2, MAX_CONTROL_POINTS);
            let uv = strand_uv(k);
            let template = PointRecord {
                pos: [0.0; 3],
                ao: 0.0,
                tangent: [0.0; 3],
                strand: [quantize(uv[0], 63.0), quantize(uv[1], 63.0)],
                model: rec.model.min(model_count - 1),
            };
            let width = widths[template.model as usize];
            let base = s * SLOTS;
            // `assemble` hands the segments over in order, root first.
            let mut m = 0;
            assemble(
                &strands.layers,
                &rec,
                &lod,
                k,
                &opts,
                &mut |a, ta, b, tb| {
                    writer.point(base + m, a, ta, &template);
                    writer.point(base + m + 1, b, tb, &template);
                    writer.segment(base + m, a, b, m, c, width);
                    m += 1;
                },
            );
            s += ctx.workgroups.max(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::PassDef;
    use crate::layout::words_of;
    use crate::lipp::payload::EMPTY;
    use crate::lipp::raster::tests::{frame as test_frame, harness};
    use crate::reference::bin::reached_tiles;
    use crate::reference::ribbon::RECORD_WORDS;
    use bytemuck::Zeroable;
    use std::sync::atomic::{AtomicU32, AtomicU64};

    /// lipp.raster's test bundles (two curly bundles, LOD off: 80 strands
    /// of 127 points), then this pass over the same LOD records.
    #[test]
    fn every_point_and_segment_of_every_strand_lands_where_the_raster_drew() {
        let (mut h, groups) = harness("{}", 32);
        let (w, hgt) = (h.quantities.width, h.quantities.height);
        let slots = (groups * SLOTS) as usize;
        let thickness = 2e-3;
        let model = ModelData {
            thickness,
            ..ModelData::zeroed()
        };
        h.buffer("models", words_of(&[model]))
            .buffer(
                "reference_counts",
                vec![0; (tiles(w, hgt).0 * tiles(w, hgt).1) as usize],
            )
            .buffer("reference_ribbons", vec![0; slots * RECORD_WORDS])
            .buffer(
                "reference_points",
                vec![0; slots * super::super::POINT_WORDS],
            );
        let k = PassDef::cpu_kernel(&STRANDS, &ron::from_str("{}").unwrap()).unwrap();
        h.run(k.as_ref(), groups, RASTER_GROUP);
        assert_eq!(h.out_of_bounds(), 0);
        let gbuffer = h.read("gbuffer");
        let conservative = |x: usize, y: usize| {
            let i = (w * hgt) as usize + y * w as usize + x;
            u64::from(gbuffer[2 * i]) | u64::from(gbuffer[2 * i + 1]) << 32
        };
        let atomics = |name: &str| -> Vec<AtomicU32> {
            h.read(name).into_iter().map(AtomicU32::new).collect()
        };
        let (pw, rw, oob) = (
            atomics("reference_points"),
            atomics("reference_ribbons"),
            AtomicU64::new(0),
        );
        let (points, records) = (Words::new(&pw, &oob), Words::new(&rw, &oob));
        let f = test_frame();
        let mut listed = 0u64;
        for s in 0..groups {
            let base = s * SLOTS;
            let count = (0..SLOTS)
                .filter(|k| PointRecord::load(&points, (base + k) as usize).is_some())
                .count();
            assert_eq!(count, 127, "strand {s}");
            for m in 0..SLOTS {
                let r = Record::load(&records, (base + m) as usize);
                let Some(r) = r else {
                    assert!(m >= 126, "strand {s}: segment {m} not drawn");
                    continue;
                };
                assert!(m < 126, "strand {s}: a record past its last segment");
                assert_eq!(r.vertices, [base + m, base + m + 1]);
                assert_eq!((r.ribbon.join_a, r.ribbon.join_b), (m > 0, m < 125));
                listed += reached_tiles(&r.ribbon, w, hgt).len() as u64;
                // The raster's conservative layer covers the point's pixel.
                let p = PointRecord::load(&points, (base + m) as usize).unwrap();
                let c = transform(&f.view_proj, [p.pos[0], p.pos[1], p.pos[2], 1.0]);
                let sp = crate::kulikov::clip_to_screen(c, w as f32, hgt as f32);
                let (x, y) = (sp[0].floor(), sp[1].floor());
                if x >= 0.0 && y >= 0.0 && x < w as f32 && y < hgt as f32 {
                    assert_ne!(
                        conservative(x as usize, y as usize),
                        EMPTY,
                        "strand {s} point {m}"
                    );
                }
            }
        }
        let counted: u64 = h
            .read("reference_counts")
            .iter()
            .map(|&c| u64::from(c))
            .sum();
        assert_eq!(counted, listed);
    }
}
