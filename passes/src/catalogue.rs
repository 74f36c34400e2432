//! Every pass kind, with the paper section that specifies it.

/// A registered pass kind.
#[derive(Debug, Clone, Copy)]
pub struct PassKind {
    /// Registry key, `pipeline.pass`.
    pub name: &'static str,
    pub summary: &'static str,
    /// Where the algorithm comes from.
    pub source: &'static str,
}

const fn kind(name: &'static str, summary: &'static str, source: &'static str) -> PassKind {
    PassKind {
        name,
        summary,
        source,
    }
}

pub static KINDS: &[PassKind] = &[
    // Shared by every pipeline.
    kind(
        "common.clear",
        "fill buffers or images with a constant (all-ones for atomicMin targets)",
        "strandgraph",
    ),
    kind(
        "scene.depth_prepass",
        "rasterize opaque meshes (heads, bodies) into scene depth",
        "strandgraph",
    ),
    kind(
        "scene.opaque",
        "shade opaque meshes, including hair shadows on skin",
        "Kulikov 2025, 'Hair shadows on skin'",
    ),
    // Kulikov 2025, SIGGRAPH Advances: Indiana Jones strand hair.
    kind(
        "kulikov.lod",
        "per-model strand count: asset cap, segments per 64x64 tile, 2M-segment budget, thickness compensation",
        "Kulikov 2025, 'LODs'",
    ),
    kind(
        "kulikov.skin",
        "skin roots to triangles (hairRootSkinningInfo_t) and cache post-transform positions",
        "Kulikov 2025, 'Skinning'",
    ),
    kind(
        "kulikov.density",
        "splat drawn segments' projected area into a 48^3 density grid per model (atomicAdd)",
        "Kulikov 2025, 'Simulation' (density output), 'Hair volumetric shadows'",
    ),
    kind(
        "kulikov.depth_downsample",
        "1/16 downscaled max depth for segment occlusion culling",
        "Kulikov 2025, 'Culling'",
    ),
    kind(
        "kulikov.cull",
        "frustum, occlusion and fedora culling; visibility bits, screen bounds and sort bins",
        "Kulikov 2025, 'Culling', 'L2 cache is your friend'",
    ),
    kind(
        "kulikov.tile_alloc",
        "allocate 64x64 atlas tiles per model from screen bounds, downscaling until they fit",
        "Kulikov 2025, 'Visibility buffer: tile allocation, downscale'",
    ),
    kind(
        "kulikov.sort_scan",
        "prefix sum over sort buckets; writes the raster's indirect dispatch",
        "Kulikov 2025, 'Sort everything!'",
    ),
    kind(
        "kulikov.sort",
        "global counting sort of visible segments by screen bucket",
        "Kulikov 2025, 'Sort everything!'",
    ),
    kind(
        "kulikov.raster",
        "conservative software rasterizer into a 3-layer 32-bit visibility atlas plus additive coverage",
        "Kulikov 2025, 'Rasterization', 'Divergence', 'Pixel request stack'",
    ),
    kind(
        "kulikov.debug_resolve",
        "resolve the visibility atlas to screen: coverage over the opaque image, layer depths",
        "Kulikov 2025, 'Visibility buffer' (debug view)",
    ),
    kind(
        "kulikov.shade_sort",
        "re-sort visible segments to natural order for strand-space shading",
        "Kulikov 2025, 'Strand-space shading needs different segment order'",
    ),
    kind(
        "kulikov.shade",
        "per-vertex Marschner (Karis 2016 R, TT, TRT, multiple scattering), self-shadowing: none, voxel march, baked SH",
        "Kulikov 2025, 'Shading', 'Self-shadowing'",
    ),
    kind(
        "kulikov.compose",
        "per-model quad, back to front: coverage reconstruction, weighted lighting, Poisson-disk atlas sampling, hair depth (motion: kulikov.pixel_motion)",
        "Kulikov 2025, 'Composition', 'Motion vectors'",
    ),
    kind(
        "kulikov.pixel_motion",
        "per-pixel motion: the front hair segment's interpolated vertex motion where composition wrote its depth, else the depth reprojected with last frame's camera",
        "Kulikov 2025, 'Composition', 'Motion vectors'",
    ),
    kind(
        "kulikov.skin_shadow",
        "hair shadows and AO on opaque pixels: march the density grids towards each light (6 steps) and along the normal (2 steps), into a per-pixel mask scene.opaque reads",
        "Kulikov 2025, 'Hair volumetric shadows'",
    ),
    kind(
        "kulikov.store_history",
        "compress this frame's post-transform NDC (clamped UNORM16 x, y) for next frame's motion vectors",
        "Kulikov 2025, 'Motion vectors'",
    ),
    kind(
        "kulikov.motion",
        "per-vertex screen motion from last frame's compressed NDC (none where either frame skipped the vertex)",
        "Kulikov 2025, 'Motion vectors'",
    ),
    // Lipp et al., deferred software rasterization of hair meshes.
    kind(
        "lipp.lod",
        "per-bundle LOD: screen AABB (Eq. 3), L (Eq. 2), N_LOD (Eq. 1), control points (Eq. 4-5), indirect args",
        "Lipp §3.2",
    ),
    kind(
        "lipp.raster",
        "cooperative strand assembly (Code 1) and DDA line rasterization into centre and conservative 64-bit G-buffers",
        "Lipp §3.1, Appendix B Code 1",
    ),
    kind(
        "lipp.dom_depth",
        "deep opacity map per light, stage 1: first-hit depth of the drawn strands in the light's view",
        "Lipp §3.4; Yuksel and Keyser 2008",
    ),
    kind(
        "lipp.dom_opacity",
        "deep opacity map per light, stage 2: strand opacity per layer behind the first hit (density-compensated for LOD)",
        "Lipp §3.2.3, §3.4; Yuksel and Keyser 2008",
    ),
    kind(
        "lipp.shade",
        "deferred shading: Chiang 2016 R/TT/TRT, Kajiya-Kay multiple scattering, DOM shadows, probe lighting",
        "Lipp §3.4",
    ),
    kind(
        "lipp.filter",
        "reconnection and opacity reconstruction filter over centre and conservative layers",
        "Lipp §3.3, Appendix B Code 2",
    ),
    // Roofline references for `strandgraph bench` (scenes/graphs/roofline.ron).
    kind(
        "bench.atomic_min32",
        "random-address 32-bit atomicMin into a visibility-atlas-sized buffer (roofline)",
        "strandgraph bench; Kulikov 2025 'Rasterization' (the operation measured)",
    ),
    kind(
        "bench.atomic_min64",
        "random-address 64-bit atomicMin, result unused, into a screen-sized 64-bit buffer (roofline)",
        "strandgraph bench; Lipp §3.1 (the operation measured)",
    ),
    kind(
        "bench.copy",
        "buffer-to-buffer copy in a compute shader (bandwidth roofline)",
        "strandgraph bench",
    ),
    // Scheuermann 2004, ATI: polygonal hair, the baseline.
    kind(
        "scheuermann.sort",
        "approximate back-to-front sort of hair patches",
        "Scheuermann 2004, 'Approximate depth sorting'",
    ),
    kind(
        "scheuermann.draw",
        "Kajiya-Kay/Marschner-mix shading of hair polygons; opaque, back-facing and front-facing passes",
        "Scheuermann 2004, 'Rendering scheme'",
    ),
];
