//! `kulikov.cull`: frustum, occlusion and fedora culling per segment, with a
//! visibility bit, per-model screen bounds and sort-bin counts as output.
//!
//! Kulikov, "Culling": "Occlusion cull against downscaled depth ... Fedora
//! culling: exclusion box, inclusion sphere ... atomically raise a visibility
//! bit ... utilize wave intrinsics and only do actual atomic write once per
//! wave. ... compute real screen boundaries for each hair model". The sort
//! bins are filled here too ("Populate sorting bins in visibility culling pass").

use super::{ModelLod, Scene, TILE, clip_to_screen, transform};
use crate::common::clip::near_clip;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::layout::ModelData;
use crate::params::PassParams;
use std::collections::BTreeMap;

pub const GROUP: u32 = 256;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct CullParams {
    pub frustum: bool,
    pub occlusion: bool,
    pub fedora: bool,
    /// One atomic per subgroup and target instead of one per lane.
    pub wave_aggregated_atomics: bool,
}

impl Default for CullParams {
    fn default() -> Self {
        Self {
            frustum: true,
            occlusion: true,
            fedora: true,
            wave_aggregated_atomics: true,
        }
    }
}

impl PassParams for CullParams {}

crate::gpu_block! {
    /// `CullParams`: the four switches, then the segment count.
    pub struct CullGpu {
        frustum: u32,
        occlusion: u32,
        fedora: u32,
        wave_aggregated_atomics: u32,
        /// Scene quantity: segments in the full numbering.
        segments: u32,
    }
}

pub static CULL: PassKind<CullParams, CullGpu> = PassKind {
    kind: "kulikov.cull",
    summary: "frustum, occlusion and fedora culling; visibility bits, screen bounds and sort bins",
    source: "Kulikov 2025, 'Culling', 'L2 cache is your friend'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("clip_positions"),
        Binding::read("hiz"),
        Binding::atomic("segment_visibility"),
        Binding::atomic("screen_bounds"),
        Binding::atomic("sort_bins"),
        Binding::read("lod_args"),
    ]),
    workgroup_size: GROUP,
    // Over the drawn segments only ([`nth_drawn`]).
    dispatch: Dispatch::Indirect {
        binding: "lod_args",
        word: 4,
    },
    shader: Shader::compute("kulikov/cull.wgsl", "cull"),
    kernel: |p| Box::new(CullKernel(*p)),
    gpu: |p, q| CullGpu {
        frustum: flag(p.frustum),
        occlusion: flag(p.occlusion),
        fedora: flag(p.fedora),
        wave_aggregated_atomics: flag(p.wave_aggregated_atomics),
        segments: count(q.segments),
    },
    raster: None,
};

struct CullKernel(CullParams);

/// A drawn segment: its model, both vertices' global indices, its local index.
#[derive(Debug, Clone, Copy)]
pub struct DrawnSegment {
    /// Its global id (full numbering).
    pub id: u32,
    pub model: usize,
    pub local: u32,
    pub v0: u32,
    pub v1: u32,
}

/// Maps a global segment id to its drawn vertices, or `None` when LOD dropped it.
pub fn drawn_segment(scene: &Scene, lods: &[ModelLod], id: u32) -> Option<DrawnSegment> {
    let (m, local) = scene.segment_model(id)?;
    drawn_in_model(scene, lods, m, local)
}

/// Drawn segment `d` of the LOD's compact numbering (models in order, each
/// model's kept strands, each strand's drawn segments), `None` past the
/// last. The passes that visit drawn segments only (cull, sort) launch
/// `lod_args`' second dispatch and map each invocation through this, as
/// `segments.wgsl`'s `nth_drawn` does; their outputs stay in the full
/// numbering. Kulikov: LOD "reduces the amount of rendered strands", so at
/// a distance most of the full numbering is not drawn.
pub fn nth_drawn(scene: &Scene, lods: &[ModelLod], d: u32) -> Option<DrawnSegment> {
    // The last model whose drawn segments start at or before `d`.
    let m = lods
        .partition_point(|l| l.segment_prefix <= d)
        .checked_sub(1)?;
    let lod = lods.get(m).filter(|_| m < scene.models.len())?;
    let local = d - lod.segment_prefix;
    if local >= lod.drawn() {
        return None;
    }
    let per = scene.models[m].points_per_strand - 1;
    let (strand, k) = (
        local / lod.segments_per_strand,
        local % lod.segments_per_strand,
    );
    drawn_in_model(scene, lods, m, strand * per + k)
}

/// The first drawn-segment index of each [`GROUP`]-wide block workgroup
/// `group` visits in the dispatch `lod_args` holds at word 4 (one block,
/// or more where the dispatch was capped: the WGSL's stride loop).
pub fn drawn_blocks(ctx: &Ctx<'_>, group: u32) -> impl Iterator<Item = u32> {
    let args = ctx.words("lod_args");
    blocks(args.load(4), args.load(7), group)
}

/// [`drawn_blocks`] of a dispatch of `groups` workgroups over `drawn` segments.
fn blocks(groups: u32, drawn: u32, group: u32) -> impl Iterator<Item = u32> {
    let stride = u64::from(groups.max(1)) * u64::from(GROUP);
    (0..)
        .map(move |round| round * stride + u64::from(group * GROUP))
        .take_while(move |&first| first < u64::from(drawn))
        .map(|first| first as u32)
}

/// Segment `local` of model `m` (full numbering), if the LOD draws it.
fn drawn_in_model(scene: &Scene, lods: &[ModelLod], m: usize, local: u32) -> Option<DrawnSegment> {
    let md = &scene.models[m];
    let per = md.points_per_strand - 1;
    let (strand, k) = (local / per, local % per);
    let lod = &lods[m];
    if strand >= lod.strands || k >= lod.segments_per_strand {
        return None;
    }
    let (a, b) = lod.segment_vertices(md.points_per_strand, k);
    let base = md.vertex_first + strand * md.points_per_strand;
    Some(DrawnSegment {
        id: md.segment_first + local,
        model: m,
        local,
        v0: base + a,
        v1: base + b,
    })
}

/// The sort bucket of a segment: the 64×64 screen tile of its midpoint.
pub fn screen_bin(w: f32, h: f32, s0: [f32; 3], s1: [f32; 3]) -> u32 {
    let x = (0.5 * (s0[0] + s1[0])).clamp(0.0, w - 1.0) as u32;
    let y = (0.5 * (s0[1] + s1[1])).clamp(0.0, h - 1.0) as u32;
    y / TILE * (w as u32).div_ceil(TILE) + x / TILE
}

/// Kulikov's fedora test: inside the exclusion box and outside the inclusion sphere.
pub fn fedora_culls(m: &ModelData, p: [f32; 3]) -> bool {
    if m.fedora_min[3] == 0.0 {
        return false;
    }
    let in_box = (0..3).all(|a| p[a] >= m.fedora_min[a] && p[a] <= m.fedora_max[a]);
    let d2: f32 = (0..3).map(|a| (p[a] - m.fedora_sphere[a]).powi(2)).sum();
    in_box && d2 > m.fedora_sphere[3] * m.fedora_sphere[3]
}

/// What a visible segment contributes.
struct Visible {
    id: u32,
    model: usize,
    bounds: [u32; 4],
    bin: u32,
}

impl CullKernel {
    fn test(
        &self,
        scene: &Scene,
        hiz: &Words<'_>,
        seg: &DrawnSegment,
        c0: [f32; 4],
        c1: [f32; 4],
    ) -> Option<([u32; 4], u32)> {
        let f = &scene.frame;
        // Only the part in front of the near plane is drawn (the raster's
        // segment_trapezoid clips the same way).
        let part = near_clip(c0, c1, f.near)?;
        let (c0, c1) = (part.a, part.b);
        if self.0.frustum {
            let out = |axis: usize, sign: f32| sign * c0[axis] > c0[3] && sign * c1[axis] > c1[3];
            if out(0, 1.0)
                || out(0, -1.0)
                || out(1, 1.0)
                || out(1, -1.0)
                || out(2, 1.0)
                || (c0[2] < 0.0 && c1[2] < 0.0)
            {
                return None;
            }
        }
        if self.0.fedora {
            let world = |c: [f32; 4]| {
                let p = transform(&f.inv_view_proj, c);
                [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
            };
            let m = &scene.models[seg.model];
            if fedora_culls(m, world(c0)) && fedora_culls(m, world(c1)) {
                return None;
            }
        }
        let (w, h) = (f.screen[0], f.screen[1]);
        let (s0, s1) = (clip_to_screen(c0, w, h), clip_to_screen(c1, w, h));
        let clampx = |x: f32| x.clamp(0.0, w - 1.0) as u32;
        let clampy = |y: f32| y.clamp(0.0, h - 1.0) as u32;
        let bounds = [
            clampx(s0[0].min(s1[0])),
            clampy(s0[1].min(s1[1])),
            clampx(s0[0].max(s1[0])),
            clampy(s0[1].max(s1[1])),
        ];
        // Long segments span many blocks and are not tested (`farthest`).
        if self.0.occlusion {
            let farthest = super::depth_downsample::farthest(hiz, w as u32, bounds);
            if farthest.is_some_and(|far| s0[2].min(s1[2]) > far) {
                return None;
            }
        }
        Some((bounds, screen_bin(w, h, s0, s1)))
    }
}

impl CpuKernel for CullKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let (clip, hiz) = (ctx.words("clip_positions"), ctx.words("hiz"));
        let (bits, bounds, bins) = (
            ctx.words("segment_visibility"),
            ctx.words("screen_bounds"),
            ctx.words("sort_bins"),
        );
        let total = ctx.quantities.segments;
        let width = ctx.subgroup_width.max(1);
        let mut local = CounterValues::default();
        for (first, sub) in drawn_blocks(ctx, group)
            .flat_map(|first| (0..GROUP.div_ceil(width)).map(move |sub| (first, sub)))
        {
            let lanes = sub * width..((sub + 1) * width).min(GROUP);
            let visible: Vec<Visible> = lanes
                .filter_map(|l| nth_drawn(&scene, &lods, first + l))
                .filter(|seg| u64::from(seg.id) < total)
                .filter_map(|seg| {
                    let (c0, c1) = (
                        clip.load_vec4(seg.v0 as usize),
                        clip.load_vec4(seg.v1 as usize),
                    );
                    let (b, bin) = self.test(&scene, &hiz, &seg, c0, c1)?;
                    Some(Visible {
                        id: seg.id,
                        model: seg.model,
                        bounds: b,
                        bin,
                    })
                })
                .collect();
            local.atomics += self.publish(&visible, &bits, &bounds, &bins);
        }
        if ctx.instrument {
            ctx.counters.add(&local);
        }
    }
}

impl CullKernel {
    /// Writes one subgroup's results; returns the atomics issued.
    fn publish(
        &self,
        visible: &[Visible],
        bits: &Words<'_>,
        bounds: &Words<'_>,
        bins: &Words<'_>,
    ) -> u64 {
        let bound = |b: &Words<'_>, m: usize, v: [u32; 4]| {
            // Maxima are stored inverted so that all four are atomicMin.
            b.fetch_min(4 * m, v[0]);
            b.fetch_min(4 * m + 1, v[1]);
            b.fetch_min(4 * m + 2, !v[2]);
            b.fetch_min(4 * m + 3, !v[3]);
        };
        if !self.0.wave_aggregated_atomics {
            for v in visible {
                bits.fetch_or((v.id / 32) as usize, 1 << (v.id % 32));
                bound(bounds, v.model, v.bounds);
                bins.fetch_add(v.bin as usize, 1);
            }
            return 6 * visible.len() as u64;
        }
        // subgroupOr / subgroupMin / per-bin counts, then one atomic per target.
        let mut words: BTreeMap<u32, u32> = BTreeMap::new();
        let mut models: BTreeMap<usize, [u32; 4]> = BTreeMap::new();
        let mut counts: BTreeMap<u32, u32> = BTreeMap::new();
        for v in visible {
            *words.entry(v.id / 32).or_default() |= 1 << (v.id % 32);
            let e = models.entry(v.model).or_insert([u32::MAX, u32::MAX, 0, 0]);
            *e = [
                e[0].min(v.bounds[0]),
                e[1].min(v.bounds[1]),
                e[2].max(v.bounds[2]),
                e[3].max(v.bounds[3]),
            ];
            *counts.entry(v.bin).or_default() += 1;
        }
        for (w, mask) in &words {
            bits.fetch_or(*w as usize, *mask);
        }
        for (m, b) in &models {
            bound(bounds, *m, *b);
        }
        for (bin, n) in &counts {
            bins.fetch_add(*bin as usize, *n);
        }
        (words.len() + 4 * models.len() + counts.len()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::FrameData;
    use bytemuck::Zeroable;

    #[test]
    fn a_capped_dispatch_strides_over_every_drawn_segment_once() {
        for (drawn, groups) in [(0, 0), (1, 1), (1000, 4), (5000, 3), (70_000, 1)] {
            let [capped, ..] = super::super::lod::drawn_dispatch(drawn);
            let groups = if groups == 0 {
                capped
            } else {
                groups.min(capped)
            };
            let mut seen: Vec<u32> = (0..groups)
                .flat_map(|g| blocks(groups, drawn, g))
                .flat_map(|first| first..(first + GROUP).min(drawn))
                .collect();
            seen.sort_unstable();
            assert_eq!(
                seen,
                (0..drawn).collect::<Vec<_>>(),
                "{drawn} over {groups}"
            );
        }
        // Past 65,535 workgroups the dispatch is capped and lanes stride.
        let [groups, _, _, n] = super::super::lod::drawn_dispatch(20_000_000);
        assert_eq!((groups, n), (65_535, 20_000_000));
        assert_eq!(blocks(groups, n, 0).count(), 2);
    }

    #[test]
    fn the_drawn_numbering_visits_every_drawn_segment_once_in_order() {
        let model = |segment_first, strand_count, points, vertex_first| ModelData {
            segment_first,
            strand_count,
            points_per_strand: points,
            vertex_first,
            ..ModelData::zeroed()
        };
        // 4 strands of 9 points, an empty model, 3 of 2 points, 5 of 6 points.
        let scene = Scene {
            frame: FrameData::zeroed(),
            models: vec![
                model(0, 4, 9, 0),
                model(32, 0, 4, 36),
                model(32, 3, 2, 36),
                model(35, 5, 6, 42),
            ],
        };
        // Keep 3 strands at every other vertex, none, all, 2 at every vertex.
        let mut lods: Vec<ModelLod> = [(3, 2), (0, 1), (3, 1), (2, 1)]
            .into_iter()
            .zip(&scene.models)
            .map(|((strands, step), m)| ModelLod {
                strands,
                vertex_step: step,
                segments_per_strand: super::super::drawn_segments(m.points_per_strand, step),
                ..ModelLod::default()
            })
            .collect();
        let mut prefix = 0;
        for l in &mut lods {
            l.segment_prefix = prefix;
            prefix += l.drawn();
        }
        let all: Vec<u32> = (0..60)
            .filter_map(|id| drawn_segment(&scene, &lods, id))
            .map(|s| s.id)
            .collect();
        assert_eq!(prefix as usize, all.len());
        let visited: Vec<DrawnSegment> = (0..prefix + 5)
            .map_while(|d| nth_drawn(&scene, &lods, d))
            .collect();
        assert_eq!(visited.iter().map(|s| s.id).collect::<Vec<_>>(), all);
        // The same vertices as the full numbering's lookup.
        for s in &visited {
            let f = drawn_segment(&scene, &lods, s.id).unwrap();
            assert_eq!(
                (s.model, s.local, s.v0, s.v1),
                (f.model, f.local, f.v0, f.v1)
            );
        }
        assert!(nth_drawn(&scene, &lods, prefix).is_none());
        assert!(nth_drawn(&scene, &[], 0).is_none());
    }

    #[test]
    fn fedora_box_culls_except_inside_the_sphere() {
        let mut m: ModelData = bytemuck::Zeroable::zeroed();
        m.fedora_min = [-0.2, 0.1, -0.2, 1.0];
        m.fedora_max = [0.2, 0.4, 0.2, 0.0];
        m.fedora_sphere = [0.0, 0.1, 0.0, 0.12];
        assert!(
            fedora_culls(&m, [0.15, 0.3, 0.0]),
            "inside the box, outside the sphere: culled"
        );
        assert!(
            !fedora_culls(&m, [0.0, 0.15, 0.0]),
            "inside the sphere: kept"
        );
        assert!(!fedora_culls(&m, [0.5, 0.3, 0.0]), "outside the box: kept");
        m.fedora_min[3] = 0.0;
        assert!(!fedora_culls(&m, [0.15, 0.3, 0.0]), "disabled");
    }
}
