//! The fixed-function state of raster passes: what a GPU backend needs
//! beyond the shader to draw a pass that has colour or depth attachments.
//!
//! Raster passes draw triangle lists with no vertex buffers (vertex
//! shaders fetch from storage buffers) or generate them in mesh shaders,
//! counter-clockwise front faces, with as many samples per pixel as their
//! attachments have (the graph's `samples`). One pass may issue several
//! draws over the same attachments with different fragment entries and
//! state (say, colour blended, then depth written with the same geometry).
//! The CPU kernels implement the same state in software; each definition's
//! `raster()` documents the pairing.

/// A raster pass's draws and attachment load operations.
#[derive(Debug, Clone, PartialEq)]
pub struct RasterState {
    /// What each draw rasterizes.
    pub geometry: Geometry,
    pub cull: Cull,
    pub color_load: ColorLoad,
    pub depth_load: DepthLoad,
    /// In order; the first one's fragment entry is `Shader::fragment`.
    pub draws: Vec<Draw>,
}

/// Where a raster pass's triangles come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// A non-indexed triangle list of this many vertices (3 per triangle),
    /// from the vertex entry `Shader::entry`.
    Vertices(u64),
    /// The same, with the vertex count an earlier pass wrote.
    Indirect(IndirectDraw),
    /// Mesh shaders (VK_EXT_mesh_shader): `groups` workgroups of the task
    /// entry `task`, each launching the mesh entry `Shader::entry`.
    MeshTasks { task: &'static str, groups: u64 },
}

/// An indirect draw's arguments: Vulkan's `VkDrawIndirectCommand` (vertex
/// count, instance count, first vertex, first instance) at word `word` of
/// the buffer bound as `binding`, which the pass reads as `indirect:`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndirectDraw {
    pub binding: &'static str,
    pub word: usize,
}

/// Which faces the rasterizer drops (front faces are counter-clockwise).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cull {
    None,
    Back,
    Front,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColorLoad {
    Load,
    /// Clear to linear RGBA.
    Clear([f32; 4]),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DepthLoad {
    Load,
    Clear(f32),
}

/// One draw over the pass's attachments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Draw {
    pub fragment: &'static str,
    pub blend: Blend,
    pub color_writes: bool,
    pub depth_compare: Compare,
    pub depth_write: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blend {
    /// The fragment replaces the attachment.
    Replace,
    /// Premultiplied "over", alpha included: colour = src + (1 − src.a) · dst,
    /// alpha = src.a + (1 − src.a) · dst.a (`output`'s alpha is the hair's
    /// coverage, docs/reference.md).
    PremultipliedOver,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    Always,
    Less,
    Equal,
}
