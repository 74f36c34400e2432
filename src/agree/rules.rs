//! Where a GPU output may differ from the CPU's, and why. Everything not
//! listed here compares under [`default_rule`]: buffers bit-exact, float
//! images within a few ULPs. Every exception states what differs and the
//! measurement behind its bound; `outliers` is the fraction of elements
//! allowed outside the rule (0: none).

use super::compare::{Rule, default_rule};
use crate::runner::Backend;
use strandgraph_graph::schema::ResourceDecl;

/// How one output is judged.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Judgement {
    pub rule: Rule,
    /// Fraction of elements allowed outside `rule`.
    pub outliers: f64,
    /// Why it is looser than the resource's default, if it is.
    pub why: Option<&'static str>,
}

/// The judgement for output `binding` of a pass of `kind` on `backend`:
/// the exception listed for that backend if there is one, else the one
/// listed for every backend, else the resource's default.
pub fn rule(kind: &str, binding: &str, decl: &ResourceDecl, backend: Backend) -> Judgement {
    let listed = |on: On| {
        EXCEPTIONS
            .iter()
            .find(|e| e.kind == kind && e.binding == binding && e.on == on)
    };
    let own = match backend {
        Backend::Wgpu => listed(On::Wgpu),
        _ => None,
    };
    own.or_else(|| listed(On::Every)).map_or(
        Judgement {
            rule: default_rule(decl),
            outliers: 0.0,
            why: None,
        },
        |e| Judgement {
            rule: e.rule,
            outliers: e.outliers,
            why: Some(e.why),
        },
    )
}

/// Which GPU backends an exception covers.
#[derive(Debug, Clone, Copy, PartialEq)]
enum On {
    /// Every GPU backend.
    Every,
    /// wgpu alone: wgpu-hal writes the SPIR-V, and strandgraph cannot mark
    /// its float operations `NoContraction` as the ash backend does
    /// (passes/src/spirv.rs), so the driver may fuse `a * b + c` into an FMA
    /// the CPU does not compute: results round differently.
    Wgpu,
}

struct Exception {
    kind: &'static str,
    binding: &'static str,
    on: On,
    rule: Rule,
    outliers: f64,
    why: &'static str,
}

// Bounds are the largest measured on lavapipe (CI) and on an NVIDIA H100
// (driver 580.159.04) with some headroom; README's "Per-pass agreement"
// lists what each backend measured. Where the H100 exceeds a bound the
// README says so: the bound is what CI enforces, not what every GPU meets.
static EXCEPTIONS: &[Exception] = &[
    Exception {
        kind: "scene.opaque",
        binding: "output",
        on: On::Every,
        rule: Rule::F16 { ulps: 2 },
        outliers: 0.00001,
        why: "perspective-correct barycentrics divide by a varying sum and the normal is normalised (Vulkan allows OpFDiv 2.5 ULP, inverseSqrt 2 ULP): lavapipe stays within 1 half-ULP; on the H100 at 1080p 10 of 4.1M words (crowd, wgpu) move further",
    },
    Exception {
        kind: "kulikov.compose",
        binding: "output",
        on: On::Every,
        rule: Rule::F16 { ulps: 2 },
        outliers: 0.002,
        why: "the reconstruction weights use pow, and the lighting interpolation and layer coverage divide by varying values, whose GPU precision Vulkan leaves to the implementation; f16 stores round the difference to 1-2 ULP (lavapipe at 250x140: 23% of words 1 ULP apart, none beyond 2; as a fragment shader it had 0.07% outliers on lavapipe, 0.025% on the H100)",
    },
    Exception {
        kind: "kulikov.skin_shadow",
        binding: "skin_shadow",
        on: On::Every,
        rule: Rule::Unorm8 { steps: 1 },
        outliers: 0.02,
        why: "each texel marches the density grid from a world position rebuilt from depth with a division (Vulkan allows OpFDiv 2.5 ULP): a step landing on a voxel boundary changes the mask (lavapipe 0.65%, H100 1.56% of texels)",
    },
    Exception {
        kind: "kulikov.shade",
        binding: "vertex_lighting",
        on: On::Every,
        rule: Rule::F16 { ulps: 1 },
        outliers: 0.0,
        why: "f32 lighting packed to halves: exp and pow differ in their last f32 bits on a GPU, which moves a value on a half's rounding boundary by one half-ULP",
    },
    Exception {
        kind: "kulikov.skin_motion",
        binding: "prev_clip_positions",
        on: On::Every,
        rule: Rule::Unorm16 { steps: 1 },
        outliers: 0.0,
        why: "NDC positions packed as 16-bit UNORM come from x / w: a GPU may divide as x · rcp(w) (Vulkan allows OpFDiv 2.5 ULP), which moves a position on a code's rounding boundary by one code (H100: 0.016% of words)",
    },
    Exception {
        kind: "kulikov.sort",
        binding: "sorted_segments",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "segments take their slot in a bin with an atomicAdd, so the order within a bin is the GPU's arrival order; the raster reads a bin's segments in any order",
    },
    Exception {
        kind: "reference.fill",
        binding: "reference_segments",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "as kulikov.sort: a segment takes its slot in a tile's list with an atomicAdd, so the order within a list is arrival order; the resolve keeps, per sample, the nearest fragment whatever the order",
    },
    Exception {
        kind: "lipp.shade",
        binding: "filter_tiles",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "a tile with hair takes its slot in the list with an atomicAdd, so the order is arrival order; lipp.filter filters each listed tile on its own",
    },
    Exception {
        kind: "reference.fill_strands",
        binding: "reference_segments",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "as reference.fill: list order is atomic arrival order",
    },
    Exception {
        kind: "lipp.reference_shade",
        binding: "vertex_lighting",
        on: On::Every,
        rule: Rule::F16 { ulps: 16 },
        outliers: 0.0,
        why: "lipp.shade's shading (its rule: relative error ≤ 4e-3 from acos, exp and sqrt), packed to halves: 4e-3 is 4 half ULPs, and a value on a rounding boundary one more",
    },
    Exception {
        kind: "kulikov.shade_sort",
        binding: "shading_segments",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "as kulikov.sort: the order within a bin is atomic arrival order, and shading is per segment",
    },
    Exception {
        kind: "lipp.dom_depth",
        binding: "dom_depth",
        on: On::Every,
        rule: Rule::Near { max: 16 },
        outliers: 0.001,
        why: "light-space depth (f32 bits, atomicMin) comes from a perspective division: Mesa lowers a / b to a · rcp(b), one rounding more than the CPU (lavapipe 0.025% of texels, ≤ 8 ULP)",
    },
    Exception {
        kind: "lipp.raster",
        binding: "gbuffer",
        on: On::Every,
        rule: Rule::Exact,
        outliers: 0.001,
        why: "each layer packs the fragment's f32 depth above its id: the depth comes from a division (a · rcp(b) on Mesa), so a few layers hold depths one rounding apart (lavapipe 0.025% of words)",
    },
    Exception {
        kind: "lipp.shade",
        binding: "shaded",
        on: On::Every,
        rule: Rule::Rgb9e5Records {
            rel: 8e-3,
            abs: 1e-5,
        },
        outliers: 0.0,
        why: "Chiang's lobes chain acos, exp and sqrt, whose GPU precision Vulkan leaves to the implementation, through azimuthal terms that cancel (relative error ≤ 4e-3 before packing, lavapipe ≤ 16051 ULP of f32); RGB9E5 then rounds either way by a step of 2^-9 of the brightest channel",
    },
    Exception {
        kind: "kulikov.raster",
        binding: "coverage_atlas",
        on: On::Wgpu,
        rule: Rule::Near { max: 8 },
        outliers: 0.0,
        why: "contracted trapezoid geometry moves a pixel's coverage across a 1/1024 quantisation step (lavapipe ±7 on 0.01% of texels)",
    },
    Exception {
        kind: "lipp.dom_depth",
        binding: "dom_depth",
        on: On::Wgpu,
        rule: Rule::F32 {
            ulps: 262_144,
            abs: 0.0,
        },
        outliers: 0.001,
        why: "contracted light projection: 18.6% of texels differ, by ≤ 122423 ULP of depth (1.5%), and a strand's edge moves into or out of a few texels (lavapipe)",
    },
    Exception {
        kind: "lipp.dom_depth",
        binding: "dom_points",
        on: On::Wgpu,
        rule: Rule::F32 {
            ulps: 256,
            abs: 1e-5,
        },
        outliers: 0.0,
        why: "the strands' world-space points, assembled with the Hermite and styling arithmetic contracted (as lipp.reference_strands' reference_points)",
    },
    Exception {
        kind: "lipp.dom_depth",
        binding: "dom_points",
        on: On::Every,
        rule: Rule::F32 {
            ulps: 16,
            abs: 1e-6,
        },
        outliers: 0.0,
        why: "the strands' world-space points: the GPU's sin and cos of the curl, twist and noise are not the CPU's",
    },
    Exception {
        kind: "lipp.dom_opacity",
        binding: "dom_layers",
        on: On::Wgpu,
        rule: Rule::Exact,
        outliers: 0.001,
        why: "contracted light projection moves a strand sample into the neighbouring layer or texel (lavapipe 0.019% of words)",
    },
    Exception {
        kind: "lipp.dom_opacity",
        binding: "dom_layers",
        on: On::Every,
        rule: Rule::Exact,
        outliers: 0.00002,
        why: "without contraction the light projection still divides (Vulkan allows OpFDiv 2.5 ULP): a sample on a texel or layer boundary lands in its neighbour (lavapipe: 2 of 2,097,152 words with the groomed hair meshes; H100: 0.19%, outside)",
    },
    Exception {
        kind: "lipp.raster",
        binding: "gbuffer",
        on: On::Wgpu,
        rule: Rule::Exact,
        outliers: 0.06,
        why: "contracted projection changes the packed depth bits of 4% of the layers on lavapipe",
    },
    Exception {
        kind: "lipp.reference_strands",
        binding: "reference_points",
        on: On::Wgpu,
        rule: Rule::F32 {
            ulps: 256,
            abs: 4e-3,
        },
        outliers: 0.00001,
        why: "as lipp.raster on wgpu: naga's SPIR-V lets the driver contract the Hermite and styling arithmetic into fused multiply-adds, which moves positions by a few ULPs; a tangent is a finite difference of positions a millimetre or less apart (the beard's curls), normalised, so its components move by up to 3e-3, and 32 of 8,256,000 words (tangent y, where the neighbours nearly coincide) by up to 1.3e-2 (lavapipe; the G-buffer's octahedral tangent has steps of 8e-3)",
    },
    Exception {
        kind: "lipp.reference_strands",
        binding: "reference_ribbons",
        on: On::Wgpu,
        rule: Rule::F32 {
            ulps: 256,
            abs: 1e-5,
        },
        outliers: 0.0,
        why: "the contracted positions, projected: screen ends, radii and depths a few ULPs apart",
    },
    Exception {
        kind: "lipp.reference_strands",
        binding: "reference_counts",
        on: On::Wgpu,
        rule: Rule::Near { max: 4 },
        outliers: 0.0,
        why: "a ribbon whose reach touches a tile's corner by a contracted ULP is counted there or not",
    },
    // Scheuermann's stages draw through the hardware rasterizer: the same
    // snapped coverage, but depth and attributes interpolated by the GPU's
    // own arithmetic (the CPU's in f64), and highlights of sin^180 that turn
    // a last-bit difference in a varying into several f16 ULPs.
    Exception {
        kind: "scheuermann.prime_depth",
        binding: "depth_buffer",
        on: On::Every,
        rule: Rule::F32 { ulps: 4, abs: 1e-6 },
        outliers: 0.0002,
        why: "an interpolated uv on the alpha test's threshold (opaque_alpha) or a depth tie flips which patch primes a pixel (lavapipe, showcase at 250x140: 3 of 35,000 texels)",
    },
    Exception {
        kind: "scheuermann.opaque",
        binding: "output",
        on: On::Every,
        rule: Rule::F16 { ulps: 8 },
        outliers: 0.005,
        why: "the highlights raise sin(T, H) to the 180th and 24th power, so a last-bit difference in an interpolated tangent is several f16 ULPs; isolated, the pass tests depth Equal against the CPU's primed depth, which the GPU's own interpolation misses on some texels (in a frame each backend primes its own): lavapipe, showcase at 250x140, 241 of 70,000 words",
    },
    Exception {
        kind: "scheuermann.reference_shade",
        binding: "vertex_lighting",
        on: On::Every,
        rule: Rule::F16 { ulps: 8 },
        outliers: 0.0,
        why: "as scheuermann.opaque's highlights (sin(T, H) to the 180th power), at strand vertices with no rasterization: lavapipe, two grooms, 190 of 224,000 words one half-ULP apart",
    },
    Exception {
        kind: "scheuermann.back_faces",
        binding: "output",
        on: On::Every,
        rule: Rule::F16 { ulps: 8 },
        outliers: 0.001,
        why: "as scheuermann.opaque, blended: a fragment whose alpha crosses the discard threshold or whose depth ties the primed depth blends on one side only (lavapipe: 41 of 70,000 words)",
    },
    Exception {
        kind: "scheuermann.front_faces",
        binding: "output",
        on: On::Every,
        rule: Rule::F16 { ulps: 8 },
        outliers: 0.001,
        why: "as scheuermann.back_faces (lavapipe: 40 of 70,000 words)",
    },
    Exception {
        kind: "scheuermann.front_faces",
        binding: "depth_buffer",
        on: On::Every,
        rule: Rule::F32 { ulps: 4, abs: 1e-6 },
        outliers: 0.002,
        why: "as scheuermann.prime_depth, for the blended texels' depth writes (lavapipe: 29 of 35,000 texels)",
    },
    // The hardware strands: the assembly places each strand's records where
    // its atomicAdd lands, and the raster's quads go through the GPU's own
    // vertex arithmetic and rasterizer.
    Exception {
        kind: "hw_strands.assemble",
        binding: "hw_segments",
        on: On::Every,
        rule: Rule::Multiset,
        outliers: 0.0,
        why: "a strand's records sit where its workgroup's atomicAdd on the draw's vertex count lands, which depends on the order workgroups run; the raster draws them in any order to the same G-buffer",
    },
    Exception {
        kind: "hw_strands.assemble",
        binding: "hw_segments",
        on: On::Wgpu,
        rule: Rule::Multiset,
        outliers: 0.3,
        why: "as on every backend, and 8 of a record's 10 words are clip coordinates from a matrix product the driver contracts into FMAs (exact on ash): lavapipe, two grooms at 160x90: 2,290,289 of 10,240,000 words, the written ones' last bits",
    },
    Exception {
        kind: "hw_strands.raster",
        binding: "gbuffer",
        on: On::Every,
        rule: Rule::Exact,
        outliers: 0.0075,
        why: "the vertex stage expands each segment into a quad with the GPU's own square root and division, and the rasterizer interpolates depth with its own arithmetic: a sample on a half-pixel-wide quad's edge is covered on one side only, or its 24-bit depth differs in the last bit (lavapipe, two grooms at 160x90: 930 of 230,400 words; the H100, the showcase's 60k-strand groom at 320x180: 5,859 of 921,600, benches/results/agree-h100/hw_strands_raster.txt)",
    },
    Exception {
        kind: "hw_strands.mesh",
        binding: "gbuffer",
        on: On::Every,
        rule: Rule::Exact,
        outliers: 0.0075,
        why: "hw_strands.raster's quads and fragment shader, emitted by mesh shaders: the same GPU square root, division and depth interpolation decide a quad edge's samples (the H100, the showcase's 60k-strand groom at 320x180: 6,245 of 921,600 words on wgpu, 6,136 on ash, benches/results/agree-h100/hw_mesh.txt)",
    },
    Exception {
        kind: "hw_strands.mesh",
        binding: "strand_depth",
        on: On::Every,
        rule: Rule::F32 { ulps: 4, abs: 1e-6 },
        outliers: 0.001,
        why: "as hw_strands.raster's: a sample on a quad's edge is written on one side only",
    },
    Exception {
        kind: "hw_strands.raster",
        binding: "strand_depth",
        on: On::Every,
        rule: Rule::F32 { ulps: 4, abs: 1e-6 },
        outliers: 0.001,
        why: "as its G-buffer: a sample on a quad's edge is written on one side only (lavapipe: 2 of 14,400 texels)",
    },
];
