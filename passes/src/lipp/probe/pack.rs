//! The probe resources' words for a scene: `env.prefiltered` and `env.sh`
//! (layouts in the module comment of [`super`]).

use super::prefilter::{Level, prefilter};
use super::sh::project_sh;
use super::{LEVELS, PI, level_size};
use strandgraph_assets::Scene;

/// The levels as `env.prefiltered`'s words.
pub fn words(levels: &[Level]) -> Vec<u32> {
    debug_assert_eq!(levels.len(), LEVELS as usize);
    levels
        .iter()
        .flat_map(|l| &l.texels)
        .flat_map(|c| [c[0], c[1], c[2], 1.0])
        .map(f32::to_bits)
        .collect()
}

/// The environment's radiance scale: `color × intensity`.
fn env_scale(scene: &Scene) -> Option<[f32; 3]> {
    let e = scene.desc.environment.as_ref()?;
    Some(e.color.map(|c| c * e.intensity))
}

/// The [`LEVELS`] levels of a constant radiance `c`.
pub fn constant_levels(c: [f32; 3]) -> Vec<Level> {
    (0..LEVELS)
        .map(|k| {
            let (w, h) = level_size(k);
            Level {
                width: w,
                height: h,
                texels: vec![c; (w * h) as usize],
            }
        })
        .collect()
}

/// `env.prefiltered` for a scene (see the module comment).
pub fn prefiltered_words(scene: &Scene) -> Vec<u32> {
    let levels = match (env_scale(scene), &scene.environment_map) {
        (Some(s), Some(map)) => prefilter(map, s),
        (Some(s), None) => constant_levels(s),
        (None, _) => constant_levels([0.0; 3]),
    };
    words(&levels)
}

/// `env.sh`: 9 × (rgb, pad) L2 SH radiance coefficients for a scene.
pub fn sh_words(scene: &Scene) -> Vec<u32> {
    let mut sh = [[0f32; 3]; 9];
    match (env_scale(scene), &scene.environment_map) {
        (Some(s), Some(map)) => sh = project_sh(map, s),
        // A constant radiance c has only L00 = c · 4π · Y00.
        (Some(s), None) => sh[0] = s.map(|c| c * 4.0 * PI * 0.282_095),
        (None, _) => {}
    }
    sh.iter()
        .flat_map(|c| [c[0], c[1], c[2], 0.0])
        .map(f32::to_bits)
        .collect()
}
