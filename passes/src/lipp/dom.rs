//! `lipp.dom_depth` and `lipp.dom_opacity`: deep opacity maps (Yuksel and
//! Keyser 2008) per light, which Lipp §3.4 uses for volumetric shadows from
//! point lights, "which we query using the depth-correction described in
//! Section 3.2" (Eq. 8, applied in `lipp.shade`).
//!
//! Both passes rasterize the drawn (LOD-reduced) strands once more, in the
//! light's view: the strand is assembled once per workgroup (Code 1, shared
//! with `lipp.raster`) and projected per light ("Strand assembly is performed
//! only once, while projection is executed per view", Lipp §5). The light's
//! view is orthographic along its direction (a point light: from the light to
//! the hair's bounds centre), fitted to the bounds of every model.
//! 1. `dom_depth`: the first-hit depth per texel (atomicMin on the f32 bits of
//!    a depth in [0, 1], which order like the floats).
//! 2. `dom_opacity`: each strand texel adds `strand_opacity` (fixed point,
//!    1/1024) to the layer its depth behind the first hit falls in; layers
//!    are `layer_thickness` metres deep.
//!
//! Which strands: the paper builds its maps from "the full geometry set"
//! (Fig. 4) and shifts the lookups of the strands the camera's LOD kept (Eq.
//! 8, in `lipp.shade`). Here the maps receive the strands of their own LOD
//! decision (`shadow_lod`: `lipp.lod` with `view: Light`, footprints in the
//! map), each strand's opacity scaled by N / N_LOD of its bundle
//! (`density_compensation`, stochastic simplification's "thicken the
//! remaining ones"), so the optical depth of the whole groom is preserved in
//! expectation and the maps stand for the full geometry set, as the paper's
//! do, at a fraction of the strands.
//!
//! Assembly once for both maps (ours, `shared_points`, after Lipp §5):
//! `dom_depth` keeps the world-space control points it assembles in
//! `dom_points`, and `dom_opacity` walks those rather than assemble each
//! strand again (at the full geometry on the H200, 0.654 → 0.548 ms; README,
//! "Lipp: one assembly for both deep opacity maps"). The points are the same
//! bits, so the maps are the same. The buffer's size sets the room a strand
//! has ([`points_room`]); a strand of more points is assembled by both.

use super::assemble::{Assembly, Strands, assemble};
use super::strand::ControlPoint;
use super::walk::Dda;
use super::{MAX_CONTROL_POINTS, RASTER_GROUP, cross, dot, frame, normalize, scale, sub};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{LightData, ModelData, read};
use crate::params::{Invalid, PassParams, in_range};
use strandgraph_graph::Quantities;

/// Fixed-point scale of the opacity layers.
pub const OPACITY_SCALE: f32 = 1024.0;
/// A texel no strand reached (the clear value).
pub const NO_HIT: u32 = u32::MAX;
/// Lights with a deep opacity map (the rest are unshadowed).
pub const MAX_DOM_LIGHTS: usize = 4;
/// Words of `dom_points` before the kept points: word 0 is the room per
/// strand `dom_depth` kept this frame (0: none), then padding.
pub const POINTS_HEADER: usize = 4;

/// Points of room per strand that `words` of `dom_points` give `total`
/// strands: strand s's point k is at words `POINTS_HEADER + (s · room + k)
/// · 3` (x, y, z as f32 bits).
pub fn points_room(words: usize, total: u32) -> u32 {
    if words <= POINTS_HEADER || total == 0 {
        return 0;
    }
    ((words - POINTS_HEADER) / 3 / total as usize).min(MAX_CONTROL_POINTS as usize) as u32
}

/// Which map pass a [`DomParams`] is for.
pub trait MapPass: Copy + Default + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    /// The map the pass writes; `Depth` alone takes `test_first`.
    const STAGE: Stage;
}

/// `lipp.dom_depth`'s [`MapPass`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DepthMap;
/// `lipp.dom_opacity`'s [`MapPass`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OpacityMap;

impl MapPass for DepthMap {
    const STAGE: Stage = Stage::Depth;
}
impl MapPass for OpacityMap {
    const STAGE: Stage = Stage::Opacity;
}

/// The parameters of both map passes; `M` tells `lipp.dom_depth`'s, which
/// alone takes `test_first`, from `lipp.dom_opacity`'s, which rejects it
/// ([`DomDepthParams`], [`DomOpacityParams`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default, bound = "")]
pub struct DomParams<M: MapPass> {
    /// Texels per side of each light's map (16..=4096).
    pub resolution: u32,
    /// Opacity layers behind the first hit (1..=8).
    pub layers: u32,
    /// Metres per opacity layer.
    pub layer_thickness: f32,
    /// Opacity one strand adds to a texel it crosses.
    pub strand_opacity: f32,
    pub density_compensation: bool,
    pub cooperative_assembly: bool,
    pub styling: bool,
    /// Ours: `dom_opacity` walks the points `dom_depth` assembled rather
    /// than assemble each strand again (set it on both passes).
    pub shared_points: bool,
    /// `dom_depth` only (ours): a plain load of the texel before its
    /// atomicMin, which most strand texels behind the first hit then skip;
    /// off, every texel an atomicMin whose result nobody waits for.
    /// `dom_opacity` has no such load, and an error names the key.
    #[serde(
        deserialize_with = "crate::params::some",
        serialize_with = "crate::params::plain",
        skip_serializing_if = "Option::is_none"
    )]
    pub test_first: Option<bool>,
    #[serde(skip)]
    pass: std::marker::PhantomData<M>,
}

/// `lipp.dom_depth`'s parameters.
pub type DomDepthParams = DomParams<DepthMap>;
/// `lipp.dom_opacity`'s parameters.
pub type DomOpacityParams = DomParams<OpacityMap>;

impl<M: MapPass> Default for DomParams<M> {
    fn default() -> Self {
        Self {
            resolution: 512,
            layers: 4,
            layer_thickness: 0.02,
            strand_opacity: 0.02,
            density_compensation: true,
            cooperative_assembly: true,
            styling: true,
            shared_points: true,
            test_first: matches!(M::STAGE, Stage::Depth).then_some(true),
            pass: std::marker::PhantomData,
        }
    }
}

impl<M: MapPass> PassParams for DomParams<M> {
    fn validate(&self) -> Result<(), Invalid> {
        if M::STAGE == Stage::Opacity && self.test_first.is_some() {
            return Err(Invalid::new(
                "test_first",
                "is lipp.dom_depth's: dom_opacity loads no texel before its atomics",
            ));
        }
        in_range("resolution", self.resolution, 16..=4096)?;
        in_range("layers", self.layers, 1..=8)?;
        if !(self.layer_thickness.is_finite() && self.layer_thickness > 0.0) {
            return Err(Invalid::new("layer_thickness", "must be positive"));
        }
        if !(self.strand_opacity.is_finite() && self.strand_opacity >= 0.0) {
            return Err(Invalid::new("strand_opacity", "must be >= 0"));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `DomParams` in shaders/lipp/dom_maps.wgsl.
    pub struct DomGpu {
        resolution: u32,
        layers: u32,
        layer_thickness: f32,
        strand_opacity: f32,
        density_compensation: u32,
        cooperative_assembly: u32,
        styling: u32,
        bundles: u32,
        shared_points: u32,
        test_first: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

impl<M: MapPass> DomParams<M> {
    /// The WGSL `DomParams` block.
    pub fn uniform(&self, q: &Quantities) -> DomGpu {
        DomGpu {
            resolution: self.resolution,
            layers: self.layers,
            layer_thickness: self.layer_thickness,
            strand_opacity: self.strand_opacity,
            density_compensation: flag(self.density_compensation),
            cooperative_assembly: flag(self.cooperative_assembly),
            styling: flag(self.styling),
            bundles: count(q.bundles),
            shared_points: flag(self.shared_points),
            test_first: flag(self.test_first == Some(true)),
            ..Default::default()
        }
    }
}

/// An orthographic light view fitted to the hair's bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightFrame {
    pub right: [f32; 3],
    pub up: [f32; 3],
    pub forward: [f32; 3],
    /// Minimum of (u, v, w) over the bounds.
    pub lo: [f32; 3],
    /// 1 / extent of (u, v, w).
    pub inv: [f32; 3],
    /// Extent of w in metres.
    pub depth_extent: f32,
}

impl LightFrame {
    /// The view of `light` over the union of `models`' bounds.
    pub fn new(light: &LightData, models: &[ModelData]) -> Self {
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for m in models {
            for a in 0..3 {
                lo[a] = lo[a].min(m.bounds_min[a]);
                hi[a] = hi[a].max(m.bounds_max[a]);
            }
        }
        if models.is_empty() {
            (lo, hi) = ([-1.0; 3], [1.0; 3]);
        }
        let pd = light.position_or_direction;
        let forward = if pd[3] == 0.0 {
            normalize([pd[0], pd[1], pd[2]])
        } else {
            let c = scale([lo[0] + hi[0], lo[1] + hi[1], lo[2] + hi[2]], 0.5);
            normalize(sub(c, [pd[0], pd[1], pd[2]]))
        };
        let forward = if dot(forward, forward) > 0.0 {
            forward
        } else {
            [0.0, -1.0, 0.0]
        };
        let up0 = if forward[1].abs() > 0.99 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let right = normalize(cross(forward, up0));
        let up = cross(right, forward);
        let (mut plo, mut phi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for i in 0..8 {
            let p = [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let q = [dot(p, right), dot(p, up), dot(p, forward)];
            for a in 0..3 {
                plo[a] = plo[a].min(q[a]);
                phi[a] = phi[a].max(q[a]);
            }
        }
        let mut inv = [0.0; 3];
        for a in 0..3 {
            let pad = ((phi[a] - plo[a]) * 0.01).max(1e-3);
            plo[a] -= pad;
            phi[a] += pad;
            inv[a] = 1.0 / (phi[a] - plo[a]);
        }
        Self {
            right,
            up,
            forward,
            lo: plo,
            inv,
            depth_extent: phi[2] - plo[2],
        }
    }

    /// (u, v, depth) in [0, 1]³ for points inside the bounds.
    pub fn project(&self, p: [f32; 3]) -> [f32; 3] {
        [
            (dot(p, self.right) - self.lo[0]) * self.inv[0],
            (dot(p, self.up) - self.lo[1]) * self.inv[1],
            (dot(p, self.forward) - self.lo[2]) * self.inv[2],
        ]
    }
}

/// The views of the lights with a deep opacity map: the first
/// [`MAX_DOM_LIGHTS`] lights the `lights` buffer holds, and of those only as
/// many as `room` = (texels per side, words of the maps) has maps for
/// (`None`: no limit from the maps).
pub fn light_frames(ctx: &Ctx<'_>, room: Option<(u32, usize)>) -> Vec<LightFrame> {
    let f = frame(ctx);
    let mw = ctx.words("models");
    let models: Vec<ModelData> = (0..f.model_count as usize).map(|m| read(&mw, m)).collect();
    let lw = ctx.words("lights");
    let held = lw.len() * 4 / std::mem::size_of::<LightData>();
    let fit = room.map_or(usize::MAX, |(res, maps)| {
        maps / ((res * res) as usize).max(1)
    });
    let n = (f.light_count as usize)
        .min(held)
        .min(fit)
        .min(MAX_DOM_LIGHTS);
    (0..n)
        .map(|l| LightFrame::new(&read::<LightData>(&lw, l), &models))
        .collect()
}

/// A conservative DDA walk over the texels segment (a, b) crosses (pixel
/// coordinates, depth), the conservative half of `lipp.raster`'s walk
/// ([`Dda`]), clipped to the map; `visit(x, y, depth)` with the depth at the
/// middle of the segment's part in the column.
pub fn walk(a: [f32; 3], b: [f32; 3], res: u32, visit: &mut dyn FnMut(u32, u32, f32)) {
    let dda = Dda::new([a[0], a[1]], [b[0], b[1]]);
    let limit = res as f32;
    dda.columns(limit, |col, t0, t1| {
        let (r0, r1) = dda.rows(t0, t1);
        let tm = 0.5 * (t0 + t1);
        let z = a[2] + (b[2] - a[2]) * tm;
        // Rows as floats, clipped to the map, as `dom_segment_depth` in
        // shaders/lipp/dom_maps.wgsl walks them.
        let mut row = r0.max(0.0);
        while row <= r1.min(limit - 1.0) {
            let (x, y) = dda.pixel(col, row);
            visit(x as u32, y as u32, z);
            row += 1.0;
        }
    });
}

fn snap(v: f32) -> f32 {
    (v * super::raster::SNAP + 0.5).floor() / super::raster::SNAP
}

/// Which map a pass writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    Depth,
    Opacity,
}

/// A stage's bindings: what both stages read (the drawn strands, and the
/// models and lights the light views are fitted to), then the stage's maps.
macro_rules! dom_bindings {
    ($($map:expr),+ $(,)?) => {
        &[
            Binding::read("frame"),
            Binding::read("raster_args"),
            Binding::read("bundle_lod"),
            Binding::read("hairmesh.bundles"),
            Binding::read("hairmesh.layers"),
            Binding::read("models"),
            Binding::read("lights"),
            $($map),+
        ]
    };
}

pub static DOM_DEPTH: PassKind<DomDepthParams, DomGpu> = dom_pass(
    "lipp.dom_depth",
    "deep opacity map per light, stage 1: first-hit depth of the drawn strands in the light's view",
    "Lipp §3.4; Yuksel and Keyser 2008",
    dom_bindings!(
        Binding::atomic("dom_depth"),
        Binding::write("dom_points").at_least(POINTS_HEADER as u32),
    ),
);

pub static DOM_OPACITY: PassKind<DomOpacityParams, DomGpu> = dom_pass(
    "lipp.dom_opacity",
    "deep opacity map per light, stage 2: strand opacity per layer behind the first hit (density-compensated for LOD)",
    "Lipp §3.2.3, §3.4; Yuksel and Keyser 2008",
    dom_bindings!(
        Binding::read("dom_depth"),
        Binding::read("dom_points").at_least(POINTS_HEADER as u32),
        Binding::atomic("dom_layers"),
    ),
);

/// A stage's declaration. The two stages differ only in their name, maps,
/// entry point and kernel stage: both walk the drawn strands in each
/// light's view with one workgroup per drawn strand, as the main view's
/// rasterizer, configured by the same parameter block (`M` says which
/// stage; only `dom_depth`'s parameters take `test_first`).
const fn dom_pass<M: MapPass>(
    kind: &'static str,
    summary: &'static str,
    source: &'static str,
    bindings: &'static [Binding],
) -> PassKind<DomParams<M>, DomGpu> {
    PassKind {
        kind,
        summary,
        source,
        bindings: Some(bindings),
        workgroup_size: RASTER_GROUP,
        dispatch: Dispatch::Indirect {
            binding: "raster_args",
            word: 0,
        },
        shader: Shader::compute("lipp/dom_maps.wgsl", M::STAGE.entry()),
        kernel: DomKernel::<M>::boxed,
        gpu: |p, q| p.uniform(q),
        raster: None,
    }
}

impl Stage {
    /// The stage's entry point in shaders/lipp/dom_maps.wgsl.
    const fn entry(self) -> &'static str {
        match self {
            Stage::Depth => "dom_depth_pass",
            Stage::Opacity => "dom_opacity_pass",
        }
    }
}

/// A stage's CPU kernel (`M::STAGE`), configured by checked parameters.
struct DomKernel<M: MapPass> {
    p: DomParams<M>,
}

impl<M: MapPass> DomKernel<M> {
    fn boxed(p: &DomParams<M>) -> Box<dyn CpuKernel> {
        Box::new(DomKernel { p: *p })
    }

    /// One texel (x, y) of light `l`'s maps at normalised depth `z`.
    fn visit(
        &self,
        maps: (&Words<'_>, &Words<'_>),
        l: usize,
        lf: &LightFrame,
        (x, y, z): (u32, u32, f32),
        amount: u32,
    ) {
        let res = self.p.resolution;
        let texel = l * (res * res) as usize + (y * res + x) as usize;
        if !(0.0..=1.0).contains(&z) {
            return;
        }
        match M::STAGE {
            Stage::Depth => {
                // Ours, `test_first`: a plain load first. Most strand texels
                // lie behind the current first hit, and skipping their
                // atomics cuts the contention on the small map (a standard
                // atomicMin filter); but the lane then waits for the load,
                // where an atomicMin alone is fire-and-forget. On the H200
                // neither wins everywhere (README, "Lipp: the maps' lanes,
                // what did not pay, and one switch").
                let bits = z.to_bits();
                if self.p.test_first != Some(true) || bits < maps.0.load(texel) {
                    maps.0.fetch_min(texel, bits);
                }
            }
            Stage::Opacity => {
                let first = maps.0.load(texel);
                if first == NO_HIT {
                    return;
                }
                // Depth behind the first hit, in layers.
                let d = (z - f32::from_bits(first)) * lf.depth_extent / self.p.layer_thickness;
                let k = (d.floor().max(0.0) as u32).min(self.p.layers - 1) as usize;
                let layer = l * self.p.layers as usize + k;
                maps.1.fetch_add(
                    layer * (res * res) as usize + (y * res + x) as usize,
                    amount,
                );
            }
        }
    }
}

impl<M: MapPass> DomKernel<M> {
    /// The room per strand in `dom_points` this frame: `dom_depth` decides
    /// it (and workgroup 0 records it in the header), `dom_opacity` reads it.
    fn room(&self, group: u32, points: &Words<'_>, total: u32) -> u32 {
        if !self.p.shared_points {
            return 0;
        }
        match M::STAGE {
            Stage::Depth => {
                let room = points_room(points.len(), total);
                if group == 0 {
                    points.store(0, room);
                }
                room
            }
            Stage::Opacity => points.load(0),
        }
    }

    /// Segment (a, b) in world space through every light's map.
    fn walk_segment(
        &self,
        maps: (&Words<'_>, &Words<'_>),
        lights: &[LightFrame],
        (a, b): ([f32; 3], [f32; 3]),
        amount: u32,
    ) {
        let res = self.p.resolution;
        let r = res as f32;
        for (l, lf) in lights.iter().enumerate() {
            let (pa, pb) = (lf.project(a), lf.project(b));
            let pa = [snap(pa[0] * r), snap(pa[1] * r), pa[2]];
            let pb = [snap(pb[0] * r), snap(pb[1] * r), pb[2]];
            walk(pa, pb, res, &mut |x, y, z| {
                self.visit(maps, l, lf, (x, y, z), amount);
            });
        }
    }
}

impl<M: MapPass> CpuKernel for DomKernel<M> {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let depth = ctx.words("dom_depth");
        let layers_map = match M::STAGE {
            Stage::Depth => depth,
            Stage::Opacity => ctx.words("dom_layers"),
        };
        let maps = (&depth, &layers_map);
        let points = ctx.words("dom_points");
        let lights = light_frames(ctx, Some((self.p.resolution, depth.len())));
        let strands = Strands::load(ctx);
        let room = self.room(group, &points, strands.total);
        let opts = Assembly::new(ctx, self.p.cooperative_assembly, self.p.styling);
        let stride = ctx.workgroups.max(1);
        let mut s = group;
        while s < strands.total {
            let (lod, rec, k) = strands.strand(s);
            let thinning = if self.p.density_compensation {
                rec.strands as f32 / lod.strands.max(1) as f32
            } else {
                1.0
            };
            let amount = (self.p.strand_opacity * thinning * OPACITY_SCALE + 0.5).floor() as u32;
            let c = lod.control_points.clamp(2, MAX_CONTROL_POINTS);
            // Strand s's slot: point k at words slot + 3k.
            let slot = POINTS_HEADER + s as usize * room as usize * 3;
            let kept = c <= room;
            if M::STAGE == Stage::Opacity && kept {
                let point = |k: usize| {
                    let w = slot + 3 * k;
                    [0, 1, 2].map(|i| f32::from_bits(points.load(w + i)))
                };
                for k in 0..c as usize - 1 {
                    self.walk_segment(maps, &lights, (point(k), point(k + 1)), amount);
                }
            } else {
                let keep = M::STAGE == Stage::Depth && kept;
                let store = |k: usize, p: [f32; 3]| {
                    for (i, v) in p.into_iter().enumerate() {
                        points.store(slot + 3 * k + i, v.to_bits());
                    }
                };
                // Code 1 draws a strand's segments in order, so segment n
                // ends at point n + 1.
                let mut n = 0;
                let mut draw = |a: &ControlPoint, _: [f32; 3], b: &ControlPoint, _: [f32; 3]| {
                    if keep {
                        if n == 0 {
                            store(0, a.pos);
                        }
                        store(n + 1, b.pos);
                    }
                    n += 1;
                    self.walk_segment(maps, &lights, (a.pos, b.pos), amount);
                };
                assemble(&strands.layers, &rec, &lod, k, &opts, &mut draw);
            }
            s += stride;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    /// `test_first` is `dom_depth`'s alone: `dom_opacity` names it as an
    /// error rather than ignore it, and only `dom_depth`'s defaults (the
    /// viewer's widgets) list it, as a plain boolean.
    #[test]
    fn only_dom_depth_takes_test_first() {
        use crate::contract::PassDef;
        let key = || ron::Value::String("test_first".into());
        let set = |v: bool| ron::Value::Map([(key(), ron::Value::Bool(v))].into_iter().collect());
        let depth = DOM_DEPTH.params(&set(false)).unwrap();
        assert_eq!(depth.test_first, Some(false));
        let none = ron::Value::Map(ron::Map::new());
        assert_eq!(DOM_DEPTH.params(&none).unwrap().test_first, Some(true));
        let e = DOM_OPACITY.check_params(&set(true)).unwrap_err();
        assert_eq!(e.param, "test_first");
        assert!(e.message.contains("dom_depth"), "{}", e.message);
        let listed = |d: ron::Value| match d {
            ron::Value::Map(m) => m.get(&key()).cloned(),
            _ => None,
        };
        assert_eq!(
            listed(DOM_DEPTH.param_defaults()),
            Some(ron::Value::Bool(true))
        );
        assert_eq!(listed(DOM_OPACITY.param_defaults()), None);
    }

    #[test]
    fn light_frame_maps_the_bounds_into_the_unit_cube_along_the_light() {
        let mut m = ModelData::zeroed();
        m.bounds_min = [-0.2, 1.0, -0.1, 0.0];
        m.bounds_max = [0.2, 1.8, 0.1, 0.0];
        let mut light = LightData::zeroed();
        light.position_or_direction = [0.0, -1.0, 0.0, 0.0];
        let lf = LightFrame::new(&light, &[m]);
        // Straight down: depth grows downwards, the top is nearest the light.
        let top = lf.project([0.0, 1.8, 0.0]);
        let bottom = lf.project([0.0, 1.0, 0.0]);
        assert!(top[2] < bottom[2] && top[2] > 0.0 && bottom[2] < 1.0);
        assert!(
            (lf.depth_extent - 0.8 * 1.02).abs() < 1e-3,
            "{}",
            lf.depth_extent
        );
        for c in [[-0.2, 1.0, -0.1], [0.2, 1.8, 0.1]] {
            let q = lf.project(c);
            assert!(q.iter().all(|v| (0.0..=1.0).contains(v)), "{q:?}");
        }
    }

    #[test]
    fn walk_visits_every_crossed_texel_once() {
        let mut seen = Vec::new();
        walk([0.5, 0.5, 0.0], [3.5, 1.5, 1.0], 8, &mut |x, y, _| {
            seen.push((x, y))
        });
        assert_eq!(seen, vec![(0, 0), (1, 0), (1, 1), (2, 1), (3, 1)]);
        let mut n = 0;
        walk([-5.0, 2.0, 0.0], [20.0, 2.0, 0.0], 8, &mut |_, _, _| n += 1);
        assert_eq!(n, 8, "clipped to the map");
    }

    #[test]
    fn points_room_fits_every_strand_in_the_buffer() {
        // The graphs' size: 65 points of each of N strands after the header.
        let words = |n: usize| POINTS_HEADER + n * 65 * 3;
        assert_eq!(points_room(words(1000), 1000), 65);
        assert_eq!(points_room(words(1000), 2000), 32);
        assert_eq!(points_room(words(1000), 10), MAX_CONTROL_POINTS);
        assert_eq!(points_room(words(1000), 0), 0);
        assert_eq!(points_room(POINTS_HEADER, 5), 0);
        for total in [1, 7, 1000, 130_000] {
            let room = points_room(words(1000), total) as usize;
            assert!(POINTS_HEADER + total as usize * room * 3 <= words(1000));
        }
    }

    #[test]
    fn bad_params_are_errors() {
        for bad in [
            r#"{"resolution": 8}"#,
            r#"{"layers": 0}"#,
            r#"{"layer_thickness": 0.0}"#,
        ] {
            let v: ron::Value = ron::from_str(bad).unwrap();
            assert!(DOM_DEPTH.params(&v).is_err(), "{bad}");
        }
    }
}
