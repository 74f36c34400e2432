//! The GPU data layout every backend shares: the `frame` uniform, per-model
//! records, lights and mesh triangles. WGSL mirrors these structs in
//! `shaders/common/layout.wgsl`; CPU kernels decode them from words.

use bytemuck::{Pod, Zeroable};

/// `frame`: camera and screen, one per frame (64 words).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct FrameData {
    /// Column-major world → clip.
    pub view_proj: [f32; 16],
    pub inv_view_proj: [f32; 16],
    /// xyz, 1.
    pub camera_pos: [f32; 4],
    /// width, height, 1/width, 1/height.
    pub screen: [f32; 4],
    pub near: f32,
    pub far: f32,
    pub model_count: u32,
    pub light_count: u32,
    /// Pixels per world unit at view depth 1 (`proj[1][1] * height / 2`).
    pub pixels_per_unit: f32,
    /// Seconds since the animation's start, and since the last frame (0 for
    /// a still image): the simulation's time step.
    pub time: f32,
    pub delta_time: f32,
    /// 1: the simulation starts over from the rest pose this frame (the
    /// first frame of a sequence, every frame of a still image).
    pub sim_reset: u32,
    pub _pad: [u32; 16],
}

/// `models`: one hair model (groom) each (64 words).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct ModelData {
    /// Column-major groom local → world.
    pub world: [f32; 16],
    /// World-space bounds (w unused).
    pub bounds_min: [f32; 4],
    pub bounds_max: [f32; 4],
    pub strand_first: u32,
    pub strand_count: u32,
    pub points_per_strand: u32,
    pub vertex_first: u32,
    /// First segment of this model in the global segment numbering
    /// (`strand_count * (points_per_strand - 1)` per model).
    pub segment_first: u32,
    /// 1 when roots follow triangles of `mesh.triangles` (Kulikov skinning).
    pub skinned: u32,
    pub triangle_first: u32,
    /// Bit 0: LOD enabled; bit 1: facial hair.
    pub flags: u32,
    /// Parent mesh local → world rotation (rows of a 3×3, w unused), for bind frames.
    pub mesh_rotation: [[f32; 4]; 3],
    /// Linear RGB base colour, roughness.
    pub color: [f32; 4],
    /// Fedora exclusion box (w of `fedora_min` is 1 when enabled).
    pub fedora_min: [f32; 4],
    pub fedora_max: [f32; 4],
    /// Inclusion sphere centre and radius.
    pub fedora_sphere: [f32; 4],
    /// Never draw fewer than this fraction of strands (scene LOD setting).
    pub min_fraction: f32,
    /// Cuticle tilt α in radians (the material's `highlight_shift_deg`).
    pub highlight_shift: f32,
    /// Strand thickness in metres (the groom's first vertex's): the width
    /// `lipp.filter` converts its opacity estimate to (`true_width`).
    pub thickness: f32,
    pub _pad: u32,
}

pub const MODEL_LOD_ENABLED: u32 = 1;
pub const MODEL_FACIAL_HAIR: u32 = 2;

/// `lights`: 16 words each.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct LightData {
    /// xyz and w = 0 for a direction the light travels, w = 1 for a point light position.
    pub position_or_direction: [f32; 4],
    /// Linear RGB × intensity.
    pub radiance: [f32; 4],
    pub _pad: [u32; 8],
}

/// `mesh.triangles`: three world-space corners (16 words). Each corner's `w`
/// holds its smooth vertex normal, octahedral-packed (`pack_unit_vector`),
/// as raw bits.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct TriangleData {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    /// Index of the mesh in the scene.
    pub mesh: u32,
    /// Each corner's albedo (see [`pack_albedo`]); 0 = the pass's albedo.
    pub albedo: [u32; 3],
}

/// A linear albedo as 8-bit square roots (a gamma of 2, so dark tones keep
/// their precision), alpha 255 marking it set. WGSL decodes with
/// `unpack4x8unorm` and squares: the same numbers on every backend.
pub fn pack_albedo(c: [f32; 3]) -> u32 {
    let q = |x: f32| (x.clamp(0.0, 1.0).sqrt() * 255.0).round() as u32;
    q(c[0]) | q(c[1]) << 8 | q(c[2]) << 16 | 255 << 24
}

/// [`pack_albedo`] inverted; `None` for 0 (not set).
pub fn unpack_albedo(w: u32) -> Option<[f32; 3]> {
    if w == 0 {
        return None;
    }
    let c = |k: u32| {
        let x = ((w >> (8 * k)) & 0xFF) as f32 / 255.0;
        x * x
    };
    Some([c(0), c(1), c(2)])
}

/// Words of a `Pod` value, for uploads.
pub fn words_of<T: Pod>(v: &[T]) -> Vec<u32> {
    bytemuck::cast_slice::<T, u32>(v).to_vec()
}

/// Decodes a `Pod` record at record index `i` from a binding's words.
pub fn read<T: Pod>(words: &crate::kernel::Words<'_>, i: usize) -> T {
    let n = std::mem::size_of::<T>() / 4;
    let raw: Vec<u32> = (0..n).map(|k| words.load(i * n + k)).collect();
    bytemuck::pod_read_unaligned(bytemuck::cast_slice(&raw))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_sizes_match_the_graph_declarations() {
        assert_eq!(std::mem::size_of::<FrameData>(), 256);
        assert_eq!(std::mem::size_of::<ModelData>(), 256);
        assert_eq!(std::mem::size_of::<LightData>(), 64);
        assert_eq!(std::mem::size_of::<TriangleData>(), 64);
    }
}
