//! `scheuermann.*`: the stages of Scheuermann 2004's "Optimized Rendering
//! Scheme", one pass kind each, drawn through the hardware rasterizer
//! (`shaders/scheuermann/hair.wgsl`). The graph runs one pass per stage, in
//! the paper's order, so an ablation can drop one:
//!
//! | kind                       | culling     | depth              | colour                 |
//! |----------------------------|-------------|--------------------|------------------------|
//! | `scheuermann.prime_depth`  | none        | `Less`, writes     | off; alpha tested at 1 |
//! | `scheuermann.opaque`       | none        | `Equal`, no writes | replaced               |
//! | `scheuermann.back_faces`   | front faces | `Less`, no writes  | blended                |
//! | `scheuermann.front_faces`  | back faces  | `Less`, writes     | blended                |
//!
//! The four share their parameters (the shading constants) and CPU kernel.
//!
//! "Prime Z buffer with a very simple shader that uses alpha test. Use Z
//! testing instead of alpha testing in subsequent passes for same effect."
//! With `primed: false` the opaque stage is the paper's unoptimized pass 1
//! instead (alpha test at 1, `Less`, writes), for a graph without the prime.
//! Every stage discards fragments with alpha under half an 8-bit step, so
//! the blended stages' fully transparent texels neither blend nor write depth.
//!
//! Draw order is the patches' static inside-to-outside order
//! ([`super::upload`]): the triangles of each stage go in index order. The
//! CPU simulator draws them as the hardware would ([`super::kernel`]).

use super::kernel::HairKernel;
use super::shading::Shading;
use crate::contract::{Binding, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::params::{Invalid, PassParams, in_range};
use crate::raster_state::{
    Blend, ColorLoad, Compare, Cull, DepthLoad, Draw, Geometry, RasterState,
};
use glam::Vec3;
use strandgraph_assets::hairpatch::PATCH_SEGMENTS;
use strandgraph_graph::Quantities;

/// Quads per patch.
pub const SEGMENTS: u32 = PATCH_SEGMENTS as u32;
/// Words per vertex of `patches.vertices`.
pub const VERTEX_WORDS: usize = 8;
/// Bands of rows the CPU kernel rasterizes in parallel.
pub(super) const BANDS: u32 = 64;
/// Fragments less opaque than this are discarded (`MIN_ALPHA` in the WGSL).
pub const MIN_ALPHA: f32 = 0.5 / 255.0;

/// A stage of the optimized rendering scheme (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    PrimeDepth,
    Opaque,
    BackFaces,
    FrontFaces,
}

/// The stages' parameters: the paper's shading constants and two switches.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct HairParams {
    /// False draws nothing: how a bench row drops the prime stage (with
    /// `primed: false` on the opaque stage) without another graph file.
    pub enabled: bool,
    /// `scheuermann.opaque` only: whether a `scheuermann.prime_depth` pass ran before (test `Equal`)
    /// or not (alpha test at `opaque_alpha`, test `Less`, write depth).
    pub primed: bool,
    /// Alpha at which a texel counts as opaque: "alpha test to only pass
    /// opaque pixels". Just under 1, since filtering four texels of 1.0 can
    /// round to 1 − 2⁻²⁴.
    pub opaque_alpha: f32,
    pub primary_shift: f32,
    pub secondary_shift: f32,
    pub shift_scale: f32,
    pub primary_exponent: f32,
    pub secondary_exponent: f32,
    /// Linear RGB of the primary highlight.
    pub primary_colour: [f32; 3],
    pub secondary_strength: f32,
    /// The tweaked diffuse term's lerp floor (0.25 in the paper).
    pub diffuse_floor: f32,
    /// Added to the texture's mip level (negative: sharper, more aliasing).
    pub lod_bias: f32,
}

impl Default for HairParams {
    fn default() -> Self {
        Self {
            enabled: true,
            primed: true,
            opaque_alpha: 0.998,
            primary_shift: -0.06,
            secondary_shift: 0.12,
            shift_scale: 0.3,
            primary_exponent: 180.0,
            secondary_exponent: 24.0,
            primary_colour: [0.25, 0.24, 0.23],
            secondary_strength: 2.0,
            diffuse_floor: 0.25,
            lod_bias: 0.0,
        }
    }
}

impl PassParams for HairParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("opaque_alpha", self.opaque_alpha, 0.5..=1.0)?;
        in_range("primary_shift", self.primary_shift, -2.0..=2.0)?;
        in_range("secondary_shift", self.secondary_shift, -2.0..=2.0)?;
        in_range("shift_scale", self.shift_scale, 0.0..=4.0)?;
        in_range("primary_exponent", self.primary_exponent, 1.0..=4096.0)?;
        in_range("secondary_exponent", self.secondary_exponent, 1.0..=4096.0)?;
        in_range("secondary_strength", self.secondary_strength, 0.0..=16.0)?;
        in_range("diffuse_floor", self.diffuse_floor, 0.0..=1.0)?;
        in_range("lod_bias", self.lod_bias, -4.0..=4.0)?;
        if !self.primary_colour.iter().all(|c| (0.0..=16.0).contains(c)) {
            return Err(Invalid::new(
                "primary_colour",
                format!(
                    "expected three numbers in 0..=16, got {:?}",
                    self.primary_colour
                ),
            ));
        }
        Ok(())
    }
}

impl HairParams {
    pub fn shading(&self) -> Shading {
        Shading {
            primary_shift: self.primary_shift,
            secondary_shift: self.secondary_shift,
            shift_scale: self.shift_scale,
            primary_exponent: self.primary_exponent,
            secondary_exponent: self.secondary_exponent,
            primary: Vec3::from(self.primary_colour),
            secondary_strength: self.secondary_strength,
            diffuse_floor: self.diffuse_floor,
        }
    }
}

crate::gpu_block! {
    /// `HairParams` in shaders/scheuermann/hair.wgsl.
    pub struct HairGpu {
        stage: u32,
        primed: u32,
        patches: u32,
        opaque_alpha: f32,
        primary_shift: f32,
        secondary_shift: f32,
        shift_scale: f32,
        primary_exponent: f32,
        secondary_exponent: f32,
        primary_r: f32,
        primary_g: f32,
        primary_b: f32,
        secondary_strength: f32,
        diffuse_floor: f32,
        lod_bias: f32,
        _pad: u32,
    }
}

/// The bindings of every stage.
const BINDINGS: &[Binding] = &[
    Binding::read("frame"),
    Binding::read("models"),
    Binding::read("lights"),
    Binding::read("patches.vertices"),
    Binding::read("patches.models"),
    Binding::read("patches.texture"),
    Binding::write("output"),
    Binding::write("depth_buffer"),
];

const SOURCE: &str = "Scheuermann 2004, 'Optimized Rendering Scheme' and 'Putting it All Together'";

/// The declaration of one stage's kind.
macro_rules! stage_kind {
    ($name:ident, $stage:expr, $kind:literal, $fragment:literal, $summary:literal) => {
        pub static $name: PassKind<HairParams, HairGpu> = PassKind {
            kind: $kind,
            summary: $summary,
            source: SOURCE,
            bindings: Some(BINDINGS),
            workgroup_size: 1,
            // The CPU's bands of rows; the GPUs draw.
            dispatch: Dispatch::Fixed(BANDS),
            shader: Shader {
                file: "scheuermann/hair.wgsl",
                entry: "vs_main",
                fragment: Some($fragment),
            },
            kernel: |p| Box::new(HairKernel::new($stage, *p)),
            gpu: |p, q| gpu_block($stage, p, q),
            raster: Some(|p, q| stage_state($stage, p, q)),
        };
    };
}

stage_kind!(
    PRIME_DEPTH,
    Stage::PrimeDepth,
    "scheuermann.prime_depth",
    "fs_prime",
    "prime the depth buffer with the hair patches' opaque texels (alpha test at 1, no colour)"
);
stage_kind!(
    OPAQUE,
    Stage::Opaque,
    "scheuermann.opaque",
    "fs_opaque",
    "shade the hair patches' opaque texels where the primed depth is equal"
);
stage_kind!(
    BACK_FACES,
    Stage::BackFaces,
    "scheuermann.back_faces",
    "fs_blend",
    "blend the hair patches' back faces, inside to outside, without depth writes"
);
stage_kind!(
    FRONT_FACES,
    Stage::FrontFaces,
    "scheuermann.front_faces",
    "fs_blend",
    "blend the hair patches' front faces, inside to outside, writing depth"
);

/// The WGSL parameter block of `stage`.
pub(super) fn gpu_block(stage: Stage, p: &HairParams, q: &Quantities) -> HairGpu {
    HairGpu {
        stage: stage as u32,
        primed: flag(p.primed),
        patches: count(q.patches),
        opaque_alpha: p.opaque_alpha,
        primary_shift: p.primary_shift,
        secondary_shift: p.secondary_shift,
        shift_scale: p.shift_scale,
        primary_exponent: p.primary_exponent,
        secondary_exponent: p.secondary_exponent,
        primary_r: p.primary_colour[0],
        primary_g: p.primary_colour[1],
        primary_b: p.primary_colour[2],
        secondary_strength: p.secondary_strength,
        diffuse_floor: p.diffuse_floor,
        lod_bias: p.lod_bias,
        _pad: 0,
    }
}

/// The fixed-function state of each stage (the table in the module docs).
pub(super) fn stage_state(stage: Stage, p: &HairParams, q: &Quantities) -> RasterState {
    let draw = |fragment, blend, color_writes, depth_compare, depth_write| Draw {
        fragment,
        blend,
        color_writes,
        depth_compare,
        depth_write,
    };
    let over = Blend::PremultipliedOver;
    let (cull, d) = match stage {
        Stage::PrimeDepth => (
            Cull::None,
            draw("fs_prime", Blend::Replace, false, Compare::Less, true),
        ),
        Stage::Opaque if p.primed => (
            Cull::None,
            draw("fs_opaque", Blend::Replace, true, Compare::Equal, false),
        ),
        Stage::Opaque => (
            Cull::None,
            draw("fs_opaque", Blend::Replace, true, Compare::Less, true),
        ),
        Stage::BackFaces => (
            Cull::Front,
            draw("fs_blend", over, true, Compare::Less, false),
        ),
        Stage::FrontFaces => (
            Cull::Back,
            draw("fs_blend", over, true, Compare::Less, true),
        ),
    };
    RasterState {
        geometry: Geometry::Vertices(if p.enabled { 3 * triangles(q) } else { 0 }),
        cull,
        color_load: ColorLoad::Load,
        depth_load: DepthLoad::Load,
        draws: vec![d],
    }
}

/// Triangles of every patch.
pub fn triangles(q: &Quantities) -> u64 {
    2 * u64::from(SEGMENTS) * q.patches
}

/// Vertex of corner `k` of triangle `t` (`corner_vertex` in the WGSL).
pub fn corner_vertex(t: u32, k: u32) -> u32 {
    let patch = t / (2 * SEGMENTS);
    let q = t % (2 * SEGMENTS);
    let base = patch * 2 * (SEGMENTS + 1) + 2 * (q / 2);
    base + if q.is_multiple_of(2) {
        [0, 1, 2][k as usize]
    } else {
        [1, 3, 2][k as usize]
    }
}
