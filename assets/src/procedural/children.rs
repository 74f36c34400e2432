//! Child strands interpolated around guides, as groom tools make them: each
//! child follows its nearest guide at its root's offset, transported along the
//! guide's bends and pulled in towards the guide by the clump profile; then
//! waves and curls (in phase within a clump, so clumps form ringlets), frizz
//! growing to the tip, and a few strays that leave their clump.

use glam::{Quat, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::guides::{Path, SKIN_MARGIN};
use super::styles::Resolved;
use super::surface::Surface;

/// A guide: its path and the phase its clump's waves and curls share.
pub struct Guide {
    pub path: Path,
    pub phase: f32,
}

/// Guide roots bucketed in a uniform grid, for nearest-guide queries.
pub struct RootGrid {
    cell: f32,
    buckets: std::collections::HashMap<[i32; 3], Vec<u32>>,
    roots: Vec<Vec3>,
}

impl RootGrid {
    pub fn new(roots: Vec<Vec3>, cell: f32) -> RootGrid {
        let mut buckets = std::collections::HashMap::<_, Vec<u32>>::new();
        for (i, r) in roots.iter().enumerate() {
            buckets
                .entry(Self::key(*r, cell))
                .or_default()
                .push(i as u32);
        }
        RootGrid {
            cell,
            buckets,
            roots,
        }
    }
    fn key(p: Vec3, cell: f32) -> [i32; 3] {
        (p / cell).floor().as_ivec3().to_array()
    }
    /// The nearest root to `p`: the 27 cells around it, else every root.
    pub fn nearest(&self, p: Vec3) -> Option<u32> {
        let [x, y, z] = Self::key(p, self.cell);
        let nearest_of = |ids: &mut dyn Iterator<Item = u32>| {
            ids.map(|i| (self.roots[i as usize].distance_squared(p), i))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        let mut near = (-1..=1).flat_map(|dz| {
            (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| [x + dx, y + dy, z + dz]))
        });
        let mut ids = near
            .by_ref()
            .filter_map(|k| self.buckets.get(&k))
            .flatten()
            .copied();
        let best = nearest_of(&mut ids).or_else(|| nearest_of(&mut (0..self.roots.len() as u32)));
        best.map(|(_, i)| i)
    }
}

/// Smooth pseudo-random displacement: two sines along random directions.
struct Frizz {
    dirs: [Vec3; 2],
    freq: [f32; 2],
    phase: [f32; 2],
}

impl Frizz {
    fn new(rng: &mut Pcg64Mcg) -> Frizz {
        let mut dir = || Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
        let dirs = [dir(), dir()];
        Frizz {
            dirs,
            freq: [
                60.0 + 80.0 * rng.random::<f32>(),
                15.0 + 20.0 * rng.random::<f32>(),
            ],
            phase: [rng.random::<f32>() * 6.3, rng.random::<f32>() * 6.3],
        }
    }
    fn at(&self, s: f32) -> Vec3 {
        self.dirs[0] * (self.freq[0] * s + self.phase[0]).sin() * 0.4
            + self.dirs[1] * (self.freq[1] * s + self.phase[1]).sin()
    }
}

/// Grows the child rooted at `root` around `guide` into `out` (first point =
/// the root exactly).
pub fn grow(
    surface: &Surface,
    r: &Resolved,
    guide: &Guide,
    root: Vec3,
    rng: &mut Pcg64Mcg,
    out: &mut [Vec3],
) {
    let n = out.len();
    let guide_len = guide.path.length().max(1e-5);
    let own = r.strands_per_guide <= 1;
    let length = if own {
        guide_len
    } else {
        guide_len * (1.0 - r.length_variation * rng.random::<f32>())
    };
    let stray = rng.random::<f32>() < r.stray_fraction;
    let clump = if stray {
        0.0
    } else {
        r.clump * (0.75 + 0.25 * rng.random::<f32>())
    };
    let frizz_amount = if stray { r.frizz * 5.0 } else { r.frizz };
    let frizz = Frizz::new(rng);
    let phase = guide.phase
        + if own {
            0.0
        } else {
            0.6 * (rng.random::<f32>() - 0.5)
        };
    let depth = r.volume * 0.3 * rng.random::<f32>();
    let (root_pos, root_tangent) = guide.path.sample(0.0);
    let offset0 = root - root_pos;
    let (b1_0, b2_0) = root_tangent.any_orthonormal_pair();
    out[0] = root;
    for (i, o) in out.iter_mut().enumerate().skip(1) {
        let t = i as f32 / (n - 1) as f32;
        let s = t * length;
        let (gp, gt) = guide.path.sample(s);
        // Transport the root offset and frame along the guide's bends.
        let rot = Quat::from_rotation_arc(root_tangent, gt);
        let pull = clump * (s / guide_len).powf(r.clump_profile);
        let mut p = gp + rot * offset0 * (1.0 - pull);
        let (b1, b2) = (rot * b1_0, rot * b2_0);
        // Styling ramps in over the first centimetres so roots stay planted.
        let ramp = (s / 0.02).min(1.0);
        if r.wave_amplitude > 0.0 {
            let a = std::f32::consts::TAU * r.wave_frequency * s + phase;
            p += b1 * (r.wave_amplitude * a.sin() * ramp);
        }
        if r.curl_radius > 0.0 {
            let a = std::f32::consts::TAU * r.curl_frequency * s + phase;
            p += (b1 * a.cos() + b2 * a.sin()) * (r.curl_radius * ramp);
        }
        p += frizz.at(s) * (frizz_amount * t * t);
        *o = surface.push_out(p, SKIN_MARGIN + depth * ramp);
    }
    // A level cut (bob) trims the child too: its offset from the guide may
    // carry it lower than the guide's own cut.
    if let Some(h) = r.cut_height {
        let cut = Path::new(out.to_vec())
            .cut_below(h + surface.center.y + 0.003 * (rng.random::<f32>() - 0.5));
        for (o, p) in out.iter_mut().zip(cut.resampled(n)).skip(1) {
            *o = surface.push_out(p, SKIN_MARGIN);
        }
    }
}

/// Root-to-tip thickness: constant over most of the strand, tapering over
/// the last third (hair is cut or worn thin only at the ends).
pub fn thickness(r: &Resolved, t: f32) -> f32 {
    let x = ((t - 0.66) / 0.34).clamp(0.0, 1.0);
    let taper = x * x * (3.0 - 2.0 * x);
    r.root_thickness + (r.tip_thickness - r.root_thickness) * taper
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_root_matches_brute_force() {
        let roots: Vec<Vec3> = (0..500)
            .map(|i| {
                let a = i as f32 * 0.618;
                Vec3::new(a.sin(), (a * 1.3).cos(), (a * 0.7).sin()) * 0.1
            })
            .collect();
        let grid = RootGrid::new(roots.clone(), 0.01);
        for k in 0..200 {
            let p = Vec3::new((k as f32 * 0.37).sin(), (k as f32 * 0.11).cos(), 0.3) * 0.12;
            let brute = (0..roots.len())
                .min_by(|&a, &b| roots[a].distance(p).total_cmp(&roots[b].distance(p)))
                .unwrap();
            let found = grid.nearest(p).unwrap() as usize;
            // Within the 27 cells the nearest is exact; beyond, the grid may
            // return a root no farther than one cell more.
            assert!(roots[found].distance(p) <= roots[brute].distance(p) + 0.01 * 1.8);
        }
    }

    #[test]
    fn thickness_tapers_only_at_the_tip() {
        let r = super::super::styles::Style::Long.defaults();
        assert_eq!(thickness(&r, 0.0), r.root_thickness);
        assert_eq!(thickness(&r, 0.5), r.root_thickness);
        assert!((thickness(&r, 1.0) - r.tip_thickness).abs() < 1e-9);
    }
}
