//! `reference.count` and `reference.fill`: each drawn segment into the list
//! of every 8 × 8 screen tile its ribbon may reach (a counting sort by
//! tile, with [`super::scan::SCAN`] between the two).
//!
//! A lane per segment. `count` projects the segment once and stores its
//! ribbon as a record ([`Record`]) that `fill` and the resolve read, so
//! nothing after it walks the models or the post-transform cache again. A
//! tile takes the segment when the ribbon's axis passes within its widest
//! radius of the disk around the tile ([`Ribbon::may_touch`]), so a long
//! diagonal segment is not listed in every tile of its bounding box. `fill`
//! takes slots with an atomicAdd on a second, cleared, per-tile counter; the
//! order within a list is the GPU's arrival order, which the resolve does
//! not depend on (it orders by depth, then segment).

use super::ribbon::{RECORD_WORDS, Record, Ribbon};
use super::{TILE, segment_ribbon, tiles};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::kulikov::Scene;
use crate::lipp::MAX_CONTROL_POINTS;
use crate::params::NoParams;
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;

pub const GROUP: u32 = 256;

crate::gpu_block! {
    /// `BinParams` in shaders/reference/ribbon.wgsl.
    pub struct BinGpu {
        segments: u32,
        width: u32,
        height: u32,
        tiles_x: u32,
    }
}

fn bin_gpu(q: &Quantities) -> BinGpu {
    BinGpu {
        segments: count(q.segments),
        width: q.width,
        height: q.height,
        tiles_x: tiles(q.width, q.height).0,
    }
}

pub static COUNT: PassKind<NoParams, BinGpu> = PassKind {
    kind: "reference.count",
    summary: "per segment, its screen ribbon, counted in every 8x8 tile it may reach",
    source: "ours: the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("segment_visibility"),
        Binding::read("clip_positions"),
        Binding::read("groom.vertices"),
        Binding::atomic("reference_counts"),
        Binding::write("reference_ribbons"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Segments,
        per_group: GROUP,
    },
    shader: Shader::compute("reference/count.wgsl", "count"),
    kernel: |_| Box::new(CountKernel),
    gpu: |_, q| bin_gpu(q),
    raster: None,
};

pub static FILL: PassKind<NoParams, BinGpu> = PassKind {
    kind: "reference.fill",
    summary: "per segment, write it into the list of every tile it was counted in",
    source: "ours: the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("reference_ribbons"),
        Binding::read("reference_offsets"),
        Binding::atomic("reference_cursor"),
        Binding::write("reference_segments"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Segments,
        per_group: GROUP,
    },
    shader: Shader::compute("reference/fill.wgsl", "fill"),
    kernel: |_| Box::new(FillKernel),
    gpu: |_, q| bin_gpu(q),
    raster: None,
};

/// The tiles `ribbon` may reach, row by row.
pub fn reached_tiles(ribbon: &Ribbon, width: u32, height: u32) -> Vec<u32> {
    let [x0, y0, x1, y1] = ribbon.bounds();
    let (x0, y0) = (x0.max(0.0), y0.max(0.0));
    let (x1, y1) = (x1.min(width as f32 - 1.0), y1.min(height as f32 - 1.0));
    if !(x0 <= x1 && y0 <= y1) {
        return Vec::new();
    }
    let tiles_x = tiles(width, height).0;
    let (tx0, ty0, tx1, ty1) = (
        x0 as u32 / TILE,
        y0 as u32 / TILE,
        x1 as u32 / TILE,
        y1 as u32 / TILE,
    );
    let half = 0.5 * TILE as f32;
    let mut out = Vec::new();
    for ty in ty0..=ty1 {
        for tx in tx0..=tx1 {
            let centre = [(tx * TILE) as f32 + half, (ty * TILE) as f32 + half];
            if ribbon.may_touch(centre, half) {
                out.push(ty * tiles_x + tx);
            }
        }
    }
    out
}

/// `record` (or "not drawn") at `id` of `records`, and +1 in `counts` for
/// every tile it reaches: what both counting passes do with a segment
/// (`reference.count`, `lipp.reference_strands`; shaders/reference/bins.wgsl).
pub fn store_ribbon(
    record: Option<&Record>,
    id: u32,
    records: &Words<'_>,
    counts: &Words<'_>,
    width: u32,
    height: u32,
) {
    Record::store(record, records, id as usize);
    for t in record.map_or_else(Vec::new, |r| reached_tiles(&r.ribbon, width, height)) {
        counts.fetch_add(t as usize, 1);
    }
}

/// The segments of workgroup `group` that exist.
fn lanes(group: u32, q: Quantities) -> impl Iterator<Item = u32> {
    let first = group * GROUP;
    let segments = q.segments;
    (first..first + GROUP).take_while(move |&id| u64::from(id) < segments)
}

struct CountKernel;

impl CpuKernel for CountKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let q = ctx.quantities;
        let (counts, records) = (
            ctx.words("reference_counts"),
            ctx.words("reference_ribbons"),
        );
        for id in lanes(group, q) {
            let record = segment_ribbon(&scene, &lods, ctx, id);
            store_ribbon(record.as_ref(), id, &records, &counts, q.width, q.height);
        }
    }
}

/// `fill` of record `id`: into the list of every tile it reaches.
fn fill_record(ctx: &Ctx<'_>, id: u32) {
    let q = ctx.quantities;
    let (records, offsets, cursor, list) = (
        ctx.words("reference_ribbons"),
        ctx.words("reference_offsets"),
        ctx.words("reference_cursor"),
        ctx.words("reference_segments"),
    );
    let Some(record) = Record::load(&records, id as usize) else {
        return;
    };
    for t in reached_tiles(&record.ribbon, q.width, q.height) {
        let taken = cursor.fetch_add(t as usize, 1);
        let slot = offsets.load(t as usize).wrapping_add(taken) as usize;
        // Past the capacity the list is cut; check_lists reports it.
        if slot < list.len() {
            list.store(slot, id);
        }
    }
}

struct FillKernel;

impl CpuKernel for FillKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        for id in lanes(group, ctx.quantities) {
            fill_record(ctx, id);
        }
    }
}

/// Record slots per strand in `fill_strands` (Lipp's strands: at most
/// [`MAX_CONTROL_POINTS`] points, one slot per point, the last unused).
pub const STRAND_SLOTS: u32 = MAX_CONTROL_POINTS;

/// Strands per `fill_strands` workgroup (a lane each).
pub const STRAND_GROUP: u32 = 64;

pub static FILL_STRANDS: PassKind<NoParams, BinGpu> = PassKind {
    kind: "reference.fill_strands",
    summary: "per strand, write each of its segments into the list of every tile it was counted in",
    source: "ours: the ground-truth reference (docs/reference.md)",
    bindings: FILL.bindings,
    workgroup_size: STRAND_GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::MeshStrands,
        per_group: STRAND_GROUP,
    },
    shader: Shader::compute("reference/fill.wgsl", "fill_strands"),
    kernel: |_| Box::new(FillStrandsKernel),
    gpu: |_, q| BinGpu {
        segments: count(q.mesh_strands),
        ..bin_gpu(q)
    },
    raster: None,
};

struct FillStrandsKernel;

impl CpuKernel for FillStrandsKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let strands = ctx.quantities.mesh_strands;
        let records = ctx.words("reference_ribbons").len() / RECORD_WORDS;
        let first = group * STRAND_GROUP;
        for s in (first..first + STRAND_GROUP).take_while(|&s| u64::from(s) < strands) {
            let base = s * STRAND_SLOTS;
            for id in base..(base + STRAND_SLOTS - 1).min(records as u32) {
                fill_record(ctx, id);
            }
        }
    }
}
