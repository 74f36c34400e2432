//! The 32-bit visibility payload and coverage encoding.
//!
//! Kulikov, "Visibility buffer: payload": "22 bit for segment index ... 10 bit
//! for depth. Depth is normalized and linearized. Use model bounds for
//! normalization." Depth sits in the high bits so `atomicMin` keeps the
//! nearest fragment.

/// Bits of the per-model segment index.
pub const SEGMENT_BITS: u32 = 22;
pub const SEGMENT_MASK: u32 = (1 << SEGMENT_BITS) - 1;
/// Largest segment index a model may use (the LOD pass enforces it).
pub const MAX_SEGMENTS_PER_MODEL: u32 = 1 << SEGMENT_BITS;
pub const DEPTH_LEVELS: u32 = 1 << (32 - SEGMENT_BITS);
/// An empty visibility texel (the clear value).
pub const EMPTY: u32 = u32::MAX;
/// Kulikov: `additiveCoverage = coverage * 1024.0f`.
pub const COVERAGE_SCALE: f32 = 1024.0;

/// Linear view depth normalised to the model's depth range, in 10 bits.
pub fn quantize_depth(view_depth: f32, near: f32, far: f32) -> u32 {
    let t = ((view_depth - near) / (far - near).max(1e-6)).clamp(0.0, 1.0);
    ((t * (DEPTH_LEVELS - 1) as f32).round() as u32).min(DEPTH_LEVELS - 1)
}

pub fn pack(depth10: u32, segment: u32) -> u32 {
    (depth10 << SEGMENT_BITS) | (segment & SEGMENT_MASK)
}

pub fn depth_of(payload: u32) -> u32 {
    payload >> SEGMENT_BITS
}

pub fn segment_of(payload: u32) -> u32 {
    payload & SEGMENT_MASK
}

/// Kulikov, "Coverage layer": the shipped quadratic fit from additive to
/// alpha-blended coverage, `saturate(x - 0.5 x saturate(0.5 x))`.
pub fn total_coverage(additive: u32) -> f32 {
    let x = additive as f32 / COVERAGE_SCALE;
    (x - 0.5 * x * (0.5 * x).clamp(0.0, 1.0)).clamp(0.0, 1.0)
}

/// View depth (clip w) from NDC depth of `perspective_rh` (z in [0, 1]).
pub fn linear_depth(z_ndc: f32, near: f32, far: f32) -> f32 {
    near * far / (far - z_ndc * (far - near))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearer_depth_wins_atomic_min() {
        let near = pack(quantize_depth(1.0, 1.0, 2.0), SEGMENT_MASK);
        let far = pack(quantize_depth(1.5, 1.0, 2.0), 0);
        assert!(near < far);
        assert_eq!(segment_of(near), SEGMENT_MASK);
        assert_eq!(depth_of(far), 512);
    }

    #[test]
    fn coverage_fit_saturates() {
        assert_eq!(total_coverage(0), 0.0);
        assert!((total_coverage(512) - 0.4375).abs() < 1e-6); // x = 0.5
        assert_eq!(total_coverage(4096), 1.0);
    }

    #[test]
    fn linear_depth_inverts_the_projection() {
        let (n, f) = (0.02, 500.0);
        let p = glam::Mat4::perspective_rh(1.0, 1.0, n, f);
        let c = p * glam::Vec4::new(0.0, 0.0, -3.0, 1.0);
        assert!((linear_depth(c.z / c.w, n, f) - 3.0).abs() < 1e-3);
    }
}
