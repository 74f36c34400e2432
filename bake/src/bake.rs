//! The bake itself: for every packed hair vertex, rays over the whole sphere,
//! each ray's scattering-event count, projected to clamped L1 SH (Kulikov,
//! "Precomputed self-shadowing": "Trace visibility rays for each hair vertex
//! offline, bake results to a spherical function").

use crate::bvh::Occluders;
use crate::sh::{Projection, biased, fibonacci_sphere, random_rotation};
use crate::{BakeError, BakeInput, BakeSettings, ShadowSh};
use glam::Vec3A;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::time::Instant;

/// Vertices per parallel work item (and per progress-bar tick).
const CHUNK: usize = 512;

/// Bakes the SH of every vertex of `input`, with a progress bar on stderr
/// (hidden when stderr is not a terminal).
pub fn bake(input: &BakeInput<'_>, settings: &BakeSettings) -> Result<Vec<ShadowSh>, BakeError> {
    let bar = ProgressBar::new(input.vertices.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "baking hair self-shadowing {bar:40} {pos}/{len} vertices, {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let out = bake_with_progress(input, settings, &bar);
    bar.finish_and_clear();
    out
}

/// [`bake`], ticking `bar` once per probe vertex.
pub fn bake_with_progress(
    input: &BakeInput<'_>,
    settings: &BakeSettings,
    bar: &ProgressBar,
) -> Result<Vec<ShadowSh>, BakeError> {
    settings.check()?;
    input.check()?;
    let t0 = Instant::now();
    let occluders = Occluders::new(input, settings);
    let built = t0.elapsed();
    // Probe vertices: every `vertex_stride`-th of each strand, and its tip.
    let k = settings.vertex_stride.max(1);
    let probes: Vec<u32> = input
        .strands
        .iter()
        .flat_map(|&[first, count]| {
            (0..count)
                .filter(move |&i| i % k == 0 || i + 1 == count)
                .map(move |i| first + i)
        })
        .collect();
    bar.set_length(probes.len() as u64);
    let dirs = fibonacci_sphere(settings.rays);
    let mut probe_sh = vec![[0.0f32; 4]; probes.len()];
    probe_sh
        .par_chunks_mut(CHUNK)
        .zip(probes.par_chunks(CHUNK))
        .for_each(|(out, ids)| {
            for (sh, &v) in out.iter_mut().zip(ids) {
                *sh = probe(&occluders, &dirs, input.vertices[v as usize], v, settings);
            }
            bar.inc(ids.len() as u64);
        });
    // Vertices between probes interpolate linearly along the strand (SH
    // coefficients are linear in the function they encode).
    let mut out = vec![[0.0f32; 4]; input.vertices.len()];
    let mut at = 0;
    for &[first, count] in input.strands {
        let n = (0..count).filter(|&i| i % k == 0 || i + 1 == count).count();
        let (ids, shs) = (&probes[at..at + n], &probe_sh[at..at + n]);
        at += n;
        for w in 0..n {
            out[ids[w] as usize] = shs[w];
            if w + 1 < n {
                let (a, b) = (ids[w], ids[w + 1]);
                for v in a + 1..b {
                    let t = (v - a) as f32 / (b - a) as f32;
                    out[v as usize] =
                        std::array::from_fn(|c| shs[w][c] + (shs[w + 1][c] - shs[w][c]) * t);
                }
            }
        }
        debug_assert!(n == 0 || ids[0] == first);
    }
    let secs = t0.elapsed().as_secs_f64();
    let rays = probes.len() as f64 * f64::from(settings.rays);
    tracing::info!(
        vertices = input.vertices.len(),
        probes = probes.len(),
        segments = occluders.segments.len(),
        triangles = occluders.triangles.len(),
        rays_per_vertex = settings.rays,
        bvh_ms = built.as_secs_f64() * 1e3,
        seconds = secs,
        mrays_per_s = rays / secs.max(1e-9) / 1e6,
        "baked hair self-shadowing"
    );
    Ok(out)
}

/// The SH of one probe vertex: every direction of the (per-vertex rotated)
/// lattice, its event count biased where it escaped, projected.
fn probe(occ: &Occluders, dirs: &[Vec3A], p: [f32; 4], v: u32, s: &BakeSettings) -> ShadowSh {
    let origin = Vec3A::new(p[0], p[1], p[2]);
    if !origin.is_finite() {
        return [0.0; 4];
    }
    let rot = random_rotation(s.seed, u64::from(v));
    let mut proj = Projection::default();
    for &d in dirs {
        let d = rot * d;
        let events = occ.events(origin, d, s.max_distance, v, s.max_scatter_events);
        proj.add(d, biased(events, s.max_scatter_events));
    }
    proj.finish()
}
