//! The bench's rows: each pipeline's published configuration and its
//! ablations, one published (or our own) optimisation switched off at a time.

use strandgraph::runner::{Barriers, LoopCounters};
use strandgraph_graph::alias::Aliasing;

/// One row of the table: a pipeline configuration.
#[derive(Debug, Clone, Copy)]
pub struct Variant {
    pub pipeline: &'static str,
    pub name: &'static str,
    /// The graph, relative to the repository root.
    pub graph: &'static str,
    /// `PASS.PARAM=VALUE` overrides, as `render --param`.
    pub overrides: &'static [&'static str],
    /// The raster passes: their time goes in parentheses, their atomics are
    /// compared with the roofline.
    pub raster: &'static [&'static str],
    /// The roofline pass whose rate is the raster's ceiling.
    pub ceiling: &'static str,
    /// The GPU backends' settings: [`DEFAULTS`] in every row but those
    /// that measure them.
    pub backend: RowBackend,
}

/// A row's settings of the GPU backends (`runner::OpenOptions`) and of the
/// memory plan they bind.
#[derive(Debug, Clone, Copy)]
pub struct RowBackend {
    /// Which passes' shaders get naga's loop counters.
    pub loop_counters: LoopCounters,
    /// How ash separates a queue's passes with barriers.
    pub barriers: Barriers,
    /// Which transients share bytes (the plan's `aliasing`).
    pub aliasing: Aliasing,
}

/// As the graph says and as the backends do by default.
pub const DEFAULTS: RowBackend = RowBackend {
    loop_counters: LoopCounters::Graph,
    barriers: Barriers::Levels,
    aliasing: Aliasing::FirstFit,
};

const KULIKOV: &str = "scenes/graphs/kulikov.ron";

/// The rows. Kulikov's ablations switch one published optimisation off at
/// a time (passes/src/kulikov/raster/mod.rs, sort.rs). Lipp's rows follow
/// its Table 1 (passes/src/lipp/).
pub const VARIANTS: &[Variant] = &[
    Variant {
        pipeline: "Kulikov",
        name: "all optimisations",
        graph: KULIKOV,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        // Kulikov: "2 milliseconds for simulation plus rendering".
        name: "simulating every groom",
        graph: KULIKOV,
        overrides: &["simulate.models=\"All\"", "splat.models=\"All\""],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        // Ours: Petrovic 2005's velocity-grid friction switched off.
        name: "simulating every groom, no hair-hair friction",
        graph: KULIKOV,
        // The grid's splat goes too: the friction is its only reader.
        overrides: &[
            "simulate.models=\"All\"",
            "simulate.hair_friction=0.0",
            "splat.enabled=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours off, both ways (passes/src/loop_counters.rs): every shader
    // compiled with naga's loop counters, as wgpu compiles an untrusted
    // shader; and none, raster and compose included, which kulikov.ron
    // keeps them in.
    Variant {
        pipeline: "Kulikov",
        name: "naga's loop counters in every pass",
        graph: KULIKOV,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: RowBackend {
            loop_counters: LoopCounters::Every,
            ..DEFAULTS
        },
    },
    Variant {
        pipeline: "Kulikov",
        name: "no naga loop counters",
        graph: KULIKOV,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: RowBackend {
            loop_counters: LoopCounters::None,
            ..DEFAULTS
        },
    },
    // Ours off: a pipeline barrier before every pass that has a dependency,
    // in the plan's order (backends/ash/src/record.rs, `levels`).
    Variant {
        pipeline: "Kulikov",
        name: "a barrier before each pass",
        graph: KULIKOV,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: RowBackend {
            barriers: Barriers::PerPass,
            ..DEFAULTS
        },
    },
    // Ours, not yet the default (unmeasured on a GPU): transients share
    // bytes only where the data flow already orders them (graph/src/alias.rs,
    // `Aliasing::NoNewWaits`).
    Variant {
        pipeline: "Kulikov",
        name: "aliasing that adds no wait",
        graph: KULIKOV,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: RowBackend {
            aliasing: Aliasing::NoNewWaits,
            ..DEFAULTS
        },
    },
    Variant {
        pipeline: "Kulikov",
        name: "no loop flattening",
        graph: KULIKOV,
        overrides: &["raster.loop_flattening=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "the talk's request stacks",
        graph: KULIKOV,
        // Kulikov ships both LDS stacks (pixel writes, depth tests); the
        // graph leaves them off, slower on the H100 (scenes/graphs/kulikov.ron).
        overrides: &[
            "raster.pixel_request_stack=true",
            "raster.depth_test_stack=true",
        ],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "no sort",
        graph: KULIKOV,
        overrides: &["sort.enabled=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "no last-layer cull",
        graph: KULIKOV,
        overrides: &["raster.last_layer_cull=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "clipped coverage",
        graph: KULIKOV,
        overrides: &["raster.analytic_coverage=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours, not the talk's: each compose workgroup skips models whose tiles
    // cannot reach its pixels (passes/src/kulikov/compose/mod.rs).
    Variant {
        pipeline: "Kulikov",
        name: "no compose workgroup cull",
        graph: KULIKOV,
        overrides: &["compose.workgroup_cull=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours, shipped off because it measured slower: head triangles with
    // boxes over 64 pixels rasterized by the whole workgroup
    // (passes/src/opaque_mesh/visibility.rs).
    Variant {
        pipeline: "Kulikov",
        name: "cooperative large triangles",
        graph: KULIKOV,
        overrides: &["visibility.cooperative_above=64"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours: each skin-shadow workgroup marches only the density grids its
    // rays can reach (passes/src/kulikov/skin_shadow/tile.rs).
    Variant {
        pipeline: "Kulikov",
        name: "no skin-shadow tile cull",
        graph: KULIKOV,
        overrides: &["skin_shadow.tile_cull=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours: the sort's scatter issues one atomicAdd per subgroup and
    // bucket (passes/src/kulikov/sort.rs).
    Variant {
        pipeline: "Kulikov",
        name: "no sort aggregation",
        graph: KULIKOV,
        overrides: &["sort.wave_aggregated_atomics=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Ours: the shading sort reads a word of visibility bits per lane, not
    // one bit (passes/src/kulikov/shade_sort.rs).
    Variant {
        pipeline: "Kulikov",
        name: "shade sort: a bit per lane",
        graph: KULIKOV,
        overrides: &["shade_sort.word_per_lane=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Quality ablations of the talk's composition (their FLIP against the
    // reference is the point; the raster still writes three layers):
    // one atlas layer instead of three, the random-lines limit 1 - e^-x
    // instead of the shipped quadratic fit, and no reconstruction of the
    // coverage beyond the layers.
    Variant {
        pipeline: "Kulikov",
        name: "one atlas layer",
        graph: KULIKOV,
        overrides: &["compose.layers=1"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "exponential coverage fit",
        graph: KULIKOV,
        overrides: &["compose.coverage_fit=\"Exponential\""],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Kulikov",
        name: "no coverage reconstruction",
        graph: KULIKOV,
        overrides: &["compose.reconstruct_missing=false"],
        raster: &["raster"],
        ceiling: "atomic_min32",
        backend: DEFAULTS,
    },
    // Lipp's Table 1 rows: SWR = software rasterizer, F = reconstruction
    // filter (lipp.filter), L = LOD (lipp.lod), 2/4/8 = MSAA samples (the
    // reference mode, scenes/graphs/lipp_msaa.ron). `filter.enabled=false`
    // composites the centre layer as is; `lod.enabled=false` draws every
    // strand at C_max control points.
    Variant {
        pipeline: "Lipp",
        name: "SWR 1",
        graph: LIPP,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "filter.enabled=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F",
        graph: LIPP,
        overrides: &["lod.enabled=false", "shadow_lod.enabled=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // The filter without §3.3.2's strand connection: conservative-only
    // pixels are not promoted and no flyaway is overlaid (the bilateral
    // filter and the opacity estimate stay). With the paper's alpha it was
    // the only filter setting that beat SWR 1 at every view
    // (benches/results/lipp-filter-sweep-h100.txt).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F, no strand connection",
        graph: LIPP,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "filter.reconnect=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // The filter's opacity as the paper estimates it: the coverage of the
    // centre test's half-pixel lines, not of the groom's strands
    // (`true_width`, passes/src/lipp/filter.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F, paper's alpha",
        graph: LIPP,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "filter.true_width=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+L",
        graph: LIPP,
        overrides: &["filter.enabled=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L (as published)",
        graph: LIPP,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Every groom's bundles simulated (sim.pbd_chains, passes/src/sim/chains.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, simulating every groom",
        graph: LIPP,
        overrides: &["simulate.models=\"All\"", "splat.models=\"All\""],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Ours, each switched off in turn on the published configuration
    // (passes/src/lipp/raster.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, per-sample payload",
        graph: LIPP,
        overrides: &["raster.segment_payload=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, no occlusion culling",
        graph: LIPP,
        overrides: &["raster.occlusion_cull=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, Code 1 strips",
        graph: LIPP,
        overrides: &["raster.strip_rounds=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // C_max points however fine the groom (passes/src/lipp/lod/mod.rs,
    // `groom_resolution`), in the camera's view and the maps'.
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, no groom-resolution cap",
        graph: LIPP,
        overrides: &[
            "lod.groom_resolution=false",
            "shadow_lod.groom_resolution=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // The deep opacity maps' LOD as it was: the camera's, at the camera's λ
    // (passes/src/lipp/lod/mod.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, shadow LOD from the camera",
        graph: LIPP,
        overrides: &["shadow_lod.view=\"Camera\"", "shadow_lod.lambda=1.0"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, shadow LOD not camera-bound",
        graph: LIPP,
        overrides: &["shadow_lod.camera_bound=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Every conservative sample shaded, not only where lipp.filter reads
    // its colour (passes/src/lipp/shade.rs, `read_layers_only`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, every sample shaded",
        graph: LIPP,
        overrides: &["shade.read_layers_only=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // lipp.filter over every tile lipp.shade ran rather than the tiles with
    // hair it lists (passes/src/lipp/tiles.rs): the tiles in the groom's
    // screen rectangle.
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, filter over every tile",
        graph: LIPP,
        overrides: &["shade.hair_tiles=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // lipp.filter with a lane a pixel rather than two or more, each taking
    // every other row of the window (passes/src/lipp/filter.rs, `lanes`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, filter a lane per pixel",
        graph: LIPP,
        overrides: &["filter.lanes=1"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Ours off: lipp.filter's dispatch a workgroup a tile, two lanes a pixel
    // however few the tiles (passes/src/lipp/tiles.rs, `filter_lane_budget`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, filter two lanes a pixel at every size",
        graph: LIPP,
        overrides: &["shade.filter_lane_budget=0"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Ours off: lipp.dom_opacity assembles every strand again rather than
    // walk the points lipp.dom_depth kept (passes/src/lipp/dom.rs,
    // `shared_points`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, each deep opacity map assembles its strands",
        graph: LIPP,
        overrides: &[
            "dom_depth.shared_points=false",
            "dom_opacity.shared_points=false",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Ours off: every shader compiled with naga's loop counters, as wgpu
    // compiles an untrusted shader (passes/src/loop_counters.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, naga's loop counters in every pass",
        graph: LIPP,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: RowBackend {
            loop_counters: LoopCounters::Every,
            ..DEFAULTS
        },
    },
    // Ours off: a pipeline barrier before every pass that has a dependency,
    // in the plan's order (backends/ash/src/record.rs, `levels`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, a barrier before each pass",
        graph: LIPP,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: RowBackend {
            barriers: Barriers::PerPass,
            ..DEFAULTS
        },
    },
    // Ours, not yet the default (unmeasured on a GPU): transients share
    // bytes only where the data flow already orders them (graph/src/alias.rs,
    // `Aliasing::NoNewWaits`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, aliasing that adds no wait",
        graph: LIPP,
        overrides: &[],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: RowBackend {
            aliasing: Aliasing::NoNewWaits,
            ..DEFAULTS
        },
    },
    // Ours: the first-hit map's atomicMin without the plain load before it
    // (passes/src/lipp/dom.rs, `test_first`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, every deep opacity map texel an atomicMin",
        graph: LIPP,
        overrides: &["dom_depth.test_first=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Ours: every tap of the window, not only the band along the tangent
    // (passes/src/lipp/filter.rs, `band`).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, filter over the whole window",
        graph: LIPP,
        overrides: &["filter.band=0.0"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // lipp.shade over every pixel, as the paper's deferred shading, and
    // lipp.clear_gbuffer over the whole G-buffer, rather than the groom's
    // screen rectangle (passes/src/lipp/rect.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, shading every pixel",
        graph: LIPP,
        overrides: &["lod_scan.groom_rect=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // lipp.clear_gbuffer a workgroup per run of 64 pixels, as lipp.shade is
    // dispatched, rather than a block of lod_scan's clear_runs runs
    // (passes/src/lipp/clear.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, G-buffer clear a workgroup per run",
        graph: LIPP,
        overrides: &["lod_scan.clear_runs=1"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // The window of Lipp's Fig. 5 ("a single 7 × 7 kernel pass"), where
    // §3.3.1 says r = 5 (the default) and Code 2 r = 7.
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, 7×7 window (Fig. 5)",
        graph: LIPP,
        overrides: &["filter.radius=3"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Without the camera's LOD but with the maps' own (ours): SWR 1 and
    // SWR 1+F with their deep opacity maps built like SWR 1+F+L's. The rows
    // "SWR 1" and "SWR 1+F" switch the maps' LOD off with the paper's, so
    // their maps receive every strand at full detail, as the paper's built
    // from "the full geometry set" (§3.2.3); against "as published" these
    // two differ in the paper's switches only (README, "What the LOD buys
    // at far").
    Variant {
        pipeline: "Lipp",
        name: "SWR 1, shadow LOD",
        graph: LIPP,
        overrides: &["lod.enabled=false", "filter.enabled=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F, shadow LOD",
        graph: LIPP,
        overrides: &["lod.enabled=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // A filter tap reading both G-buffer layers, then its colour, rather
    // than the neighbour's 8-byte record (passes/src/lipp/shaded.rs).
    Variant {
        pipeline: "Lipp",
        name: "SWR 1+F+L, filter taps from the G-buffer",
        graph: LIPP,
        overrides: &["filter.packed_taps=false"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 2",
        graph: LIPP_MSAA,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "raster.msaa=2",
            "filter.msaa=2",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 4",
        graph: LIPP_MSAA,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "raster.msaa=4",
            "filter.msaa=4",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 8",
        graph: LIPP_MSAA,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "raster.msaa=8",
            "filter.msaa=8",
        ],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 2+L",
        graph: LIPP_MSAA,
        overrides: &["raster.msaa=2", "filter.msaa=2"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 4+L",
        graph: LIPP_MSAA,
        overrides: &["raster.msaa=4", "filter.msaa=4"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Lipp",
        name: "SWR 8+L",
        graph: LIPP_MSAA,
        overrides: &["raster.msaa=8", "filter.msaa=8"],
        raster: &["raster"],
        ceiling: "atomic_min64",
        backend: DEFAULTS,
    },
    // Scheuermann 2004's optimized scheme as published (Z primed), and its
    // unoptimized "Sorted Hair Rendering Scheme" (the opaque pass alpha tests
    // and writes Z itself). Every hair pass goes through the hardware rasterizer.
    Variant {
        pipeline: "Scheuermann",
        name: "Z-primed (as published)",
        graph: SCHEUERMANN,
        overrides: &[],
        raster: &SCHEUERMANN_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "Scheuermann",
        name: "no Z prime",
        graph: SCHEUERMANN,
        overrides: &["prime_depth.enabled=false", "opaque_hair.primed=false"],
        raster: &SCHEUERMANN_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    // Lipp's Table 1 baseline: the same strands through the hardware
    // rasterizer (scenes/graphs/hw_strands.ron), MSAA 1/4/8 without and
    // with LOD. Hopper runs vertex and pixel work on few SMs: the bench's
    // graphics roofline says how few.
    Variant {
        pipeline: "HW strands",
        name: "HW 1",
        graph: HW_STRANDS,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=1",
            "filter.msaa=1",
        ],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW strands",
        name: "HW 4",
        graph: HW_STRANDS,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=4",
            "filter.msaa=4",
        ],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW strands",
        name: "HW 8",
        graph: HW_STRANDS,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=8",
            "filter.msaa=8",
        ],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW strands",
        name: "HW 1+L",
        graph: HW_STRANDS,
        overrides: &["strand_depth.samples=1", "filter.msaa=1"],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW strands",
        name: "HW 4+L",
        graph: HW_STRANDS,
        overrides: &["strand_depth.samples=4", "filter.msaa=4"],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW strands",
        name: "HW 8+L",
        graph: HW_STRANDS,
        overrides: &["strand_depth.samples=8", "filter.msaa=8"],
        raster: &HW_STRANDS_PASSES,
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    // The same quads from mesh shaders (scenes/graphs/hw_mesh.ron): a task
    // workgroup per bundle applying the LOD, strands assembled in mesh
    // workgroups, Bhokare et al.'s pipeline shape. Skipped where the device
    // has no mesh shaders.
    Variant {
        pipeline: "HW mesh",
        name: "MS 1",
        graph: HW_MESH,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=1",
            "filter.msaa=1",
        ],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW mesh",
        name: "MS 4",
        graph: HW_MESH,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=4",
            "filter.msaa=4",
        ],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW mesh",
        name: "MS 8",
        graph: HW_MESH,
        overrides: &[
            "lod.enabled=false",
            "shadow_lod.enabled=false",
            "strand_depth.samples=8",
            "filter.msaa=8",
        ],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW mesh",
        name: "MS 1+L",
        graph: HW_MESH,
        overrides: &["strand_depth.samples=1", "filter.msaa=1"],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW mesh",
        name: "MS 4+L",
        graph: HW_MESH,
        overrides: &["strand_depth.samples=4", "filter.msaa=4"],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
    Variant {
        pipeline: "HW mesh",
        name: "MS 8+L",
        graph: HW_MESH,
        overrides: &["strand_depth.samples=8", "filter.msaa=8"],
        raster: &["mesh"],
        ceiling: "fragments",
        backend: DEFAULTS,
    },
];

const LIPP: &str = "scenes/graphs/lipp.ron";
const LIPP_MSAA: &str = "scenes/graphs/lipp_msaa.ron";
const SCHEUERMANN: &str = "scenes/graphs/scheuermann.ron";
const HW_STRANDS: &str = "scenes/graphs/hw_strands.ron";
const HW_MESH: &str = "scenes/graphs/hw_mesh.ron";
/// Strand generation and rasterization, as Lipp's raster column counts both.
const HW_STRANDS_PASSES: [&str; 2] = ["assemble", "raster"];
/// Its hair passes, all hardware raster.
const SCHEUERMANN_PASSES: [&str; 4] = ["prime_depth", "opaque_hair", "back_faces", "front_faces"];
