//! Probe lighting for `lipp.shade` (Lipp §3.4: "we use the standard
//! approach of pre-filtered environment maps for specular components (the
//! single scattering hair shading model), and spherical harmonics expansion
//! for more diffuse contributions"): what upload computes from the scene's
//! environment, and the lookup the shader mirrors (`shaders/lipp/probe.wgsl`).
//!
//! **`env.prefiltered`** (Imported, [`BYTES`] = 178,176 B, fixed layout, no
//! header): [`LEVELS`] = 6 latitude-longitude levels, level k is
//! max(128 >> k, 16) × max(64 >> k, 8) texels (128×64, 64×32, 32×16, then
//! 16×8 three times), rgba32f (a = 1), row-major with row 0 at +y, levels
//! back to back from level 0 (texel offsets 0, 8192, 10240, 10752, 10880,
//! 11008; 11,136 texels). The lat-long convention is
//! `strandgraph_assets::loaders::envmap`'s (u = 0.5 looks down −z, u = 0.75
//! down +x). Level k is prefiltered for GGX roughness α_k = r_k², r_k =
//! k / 5 (the perceptual-roughness-linear mip mapping of Karis 2013); level 0
//! (α = 0, a mirror) is the input map resampled to 128 × 64.
//!
//! The prefilter is Karis 2013 ("Real Shading in Unreal Engine 4", the
//! first half of the split sum): with N = V = R assumed, each texel of
//! direction N averages the source over GGX importance samples L of the
//! half vector, weighted by N·L. Each sample reads a box-filtered mip of the
//! source chosen from its pdf (filtered importance sampling, Colbert and
//! Křivánek 2007, "GPU-Based Importance Sampling", GPU Gems 3 ch. 20), so
//! 64 to 256 samples per texel give a noise-free result.
//!
//! **`env.sh`**: the map projected to 9 L2 SH radiance coefficients
//! (Ramamoorthi and Hanrahan 2001) with exact per-row solid angles.
//!
//! The map is scaled by the environment's `color × intensity` (a white map
//! at intensity 1 is the file's radiance). Without a map, the constant
//! colour fills only L00 and every prefiltered texel; without an
//! environment, both are zero.
//!
//! The pieces, one file each: `lookup` (the bilinear lat-long reads the
//! shader mirrors), `lobe` (the GGX lobe standing in for R + TRT),
//! `sh` (the SH projection), `prefilter` (the GGX prefiltered levels)
//! and `pack` (the two resources' words for a scene).

mod lobe;
mod lookup;
mod pack;
mod prefilter;
mod sh;

pub use lobe::{SpecularLobe, specular, specular_lobe, view_facing_normal};
pub use lookup::{latlong_uv, sample, sample_level};
pub use pack::{constant_levels, prefiltered_words, sh_words, words};
pub use prefilter::{Level, prefilter, resample};
pub use sh::{project_sh, sh_basis};

/// Resource name.
pub const PREFILTERED: &str = "env.prefiltered";
/// Prefiltered levels (level 0 = mirror, level 5 = α 1).
pub const LEVELS: u32 = 6;
/// Level 0's size.
pub const WIDTH: u32 = 128;
pub const HEIGHT: u32 = 64;
/// Texels of all levels.
pub const TEXELS: u32 = level_offset(LEVELS);
/// `env.prefiltered`'s size in bytes (rgba32f texels).
pub const BYTES: u64 = TEXELS as u64 * 16;
/// GGX samples per prefiltered texel of the rough levels (fewer for the
/// narrow lobes of levels 1 and 2).
pub const SAMPLES: u32 = 256;

const PI: f32 = std::f32::consts::PI;

/// The smallest level's size: rougher levels stop halving here, since a
/// wide lobe still needs ~20° texels to reconstruct bilinearly (4 × 2
/// texels lost 10% of a spot's energy at α = 1).
pub const MIN_WIDTH: u32 = 16;
pub const MIN_HEIGHT: u32 = 8;

/// Level k's (width, height).
pub const fn level_size(k: u32) -> (u32, u32) {
    let (w, h) = (WIDTH >> k, HEIGHT >> k);
    (
        if w > MIN_WIDTH { w } else { MIN_WIDTH },
        if h > MIN_HEIGHT { h } else { MIN_HEIGHT },
    )
}

/// Level k's first texel.
pub const fn level_offset(k: u32) -> u32 {
    let mut o = 0;
    let mut i = 0;
    while i < k {
        let (w, h) = level_size(i);
        o += w * h;
        i += 1;
    }
    o
}

/// GGX α of level k: r² with r = k / (LEVELS − 1).
pub fn level_alpha(k: u32) -> f32 {
    let r = k as f32 / (LEVELS - 1) as f32;
    r * r
}

/// The fractional level of GGX roughness α (inverse of [`level_alpha`]).
pub fn alpha_lod(alpha: f32) -> f32 {
    alpha.clamp(0.0, 1.0).sqrt() * (LEVELS - 1) as f32
}

/// The words of a test resource, as the kernels' atomics.
#[cfg(test)]
fn atomics(words: &[u32]) -> Vec<std::sync::atomic::AtomicU32> {
    words
        .iter()
        .map(|&w| std::sync::atomic::AtomicU32::new(w))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_fixed_and_documented() {
        assert_eq!(TEXELS, 11_136);
        assert_eq!(BYTES, 178_176);
        assert_eq!(
            (0..=LEVELS).map(level_offset).collect::<Vec<_>>(),
            [0, 8192, 10240, 10752, 10880, 11008, 11136]
        );
        assert_eq!((level_size(3), level_size(5)), ((16, 8), (16, 8)));
        for k in 0..LEVELS {
            assert!((alpha_lod(level_alpha(k)) - k as f32).abs() < 1e-5);
        }
    }
}
