//! Fitting a hair mesh to a strand groom: cluster strands into bundles by k-means on root
//! positions and the strands' direction, then fit each bundle's layers to the strands' cross-sections (centre and
//! principal axes of the points at each w).

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{HairMesh, HairMeshParams};
use crate::groom::{Groom, stable_permutation};

/// k-means (Lloyd) on points, seeded; centroids found on a subsample of at most
/// `sample` points, then every point is assigned. Returns the cluster of each point.
pub fn kmeans(points: &[Vec3], k: usize, iterations: usize, seed: u64, sample: usize) -> Vec<u32> {
    let k = k.clamp(1, points.len().max(1));
    if points.is_empty() {
        return Vec::new();
    }
    let order = stable_permutation(points.len(), seed);
    let sub: Vec<Vec3> = order
        .iter()
        .take(sample.max(k))
        .map(|&i| points[i as usize])
        .collect();
    let mut centroids: Vec<Vec3> = sub.iter().take(k).copied().collect();
    let nearest = |p: Vec3, c: &[Vec3]| -> u32 {
        let mut best = (f32::INFINITY, 0u32);
        for (j, q) in c.iter().enumerate() {
            let d = p.distance_squared(*q);
            if d < best.0 {
                best = (d, j as u32);
            }
        }
        best.1
    };
    for _ in 0..iterations {
        let assign: Vec<u32> = sub.par_iter().map(|&p| nearest(p, &centroids)).collect();
        let mut sum = vec![(Vec3::ZERO, 0u32); centroids.len()];
        for (p, &a) in sub.iter().zip(&assign) {
            sum[a as usize].0 += *p;
            sum[a as usize].1 += 1;
        }
        for (c, (s, n)) in centroids.iter_mut().zip(sum) {
            if n > 0 {
                *c = s / n as f32;
            }
        }
    }
    points.par_iter().map(|&p| nearest(p, &centroids)).collect()
}

impl HairMesh {
    /// Fits `params.bundles` bundles of `params.layers` layers to a groom.
    pub fn fit(groom: &Groom, params: &HairMeshParams) -> HairMesh {
        let layers = params.layers.max(2) as usize;
        let resampled = groom.resampled(layers);
        // Cluster on the root and the point a third of the way along: strands
        // planted side by side but combed apart (at a parting) land in
        // different bundles, so no bundle spans both ways.
        let features: Vec<Vec3> = (0..resampled.strand_count())
            .map(|s| {
                let p = resampled.strand(s);
                (p[0] + p[p.len() / 3]) * 0.5
            })
            .collect();
        let assign = kmeans(&features, params.bundles as usize, 10, params.seed, 20_000);
        let k = assign.iter().copied().max().map_or(0, |m| m as usize + 1);
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); k];
        for (s, &a) in assign.iter().enumerate() {
            members[a as usize].push(s);
        }
        let fitted: Vec<Option<Vec<[Vec3; 4]>>> = members
            .par_iter()
            .map(|m| fit_bundle(&resampled, m, layers))
            .collect();
        let mut mesh = HairMesh {
            transform: groom.transform,
            ..Default::default()
        };
        for (corners, m) in fitted.iter().zip(&members) {
            if let Some(c) = corners {
                mesh.push_bundle(c, m.len() as u32, params.style);
            }
        }
        mesh.bake_ao(2.0);
        mesh
    }
}

/// Fits the quads of one bundle to its strands (all with `layers` points).
fn fit_bundle(g: &Groom, strands: &[usize], layers: usize) -> Option<Vec<[Vec3; 4]>> {
    if strands.is_empty() {
        return None;
    }
    let at = |s: usize, i: usize| g.positions[s * layers + i];
    let centers: Vec<Vec3> = (0..layers)
        .map(|i| strands.iter().map(|&s| at(s, i)).sum::<Vec3>() / strands.len() as f32)
        .collect();
    let mut out = Vec::with_capacity(layers);
    let mut prev_axis: Option<Vec3> = None;
    for i in 0..layers {
        let (a, b) = (i.saturating_sub(1), (i + 1).min(layers - 1));
        let mut t = (centers[b] - centers[a]).normalize_or_zero();
        if t == Vec3::ZERO {
            t = Vec3::Y;
        }
        let (e1, e2) = t.any_orthonormal_pair();
        // Principal axis of the cross-section in the plane perpendicular to t.
        let proj: Vec<Vec2> = strands
            .iter()
            .map(|&s| {
                let d = at(s, i) - centers[i];
                Vec2::new(d.dot(e1), d.dot(e2))
            })
            .collect();
        let (mut cxx, mut cyy, mut cxy) = (0.0, 0.0, 0.0);
        for p in &proj {
            cxx += p.x * p.x;
            cyy += p.y * p.y;
            cxy += p.x * p.y;
        }
        let theta = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        let mut ax1 = e1 * theta.cos() + e2 * theta.sin();
        // Keep the frame from twisting between layers.
        if let Some(p) = prev_axis {
            let p = p.reject_from(t).normalize_or_zero();
            if p != Vec3::ZERO {
                ax1 = if ax1.dot(p) < 0.0 { -ax1 } else { ax1 };
            }
        }
        prev_axis = Some(ax1);
        let ax2 = t.cross(ax1);
        let (mut h1, mut h2) = (0.0005f32, 0.0005f32);
        for &s in strands {
            let d = at(s, i) - centers[i];
            h1 = h1.max(d.dot(ax1).abs());
            h2 = h2.max(d.dot(ax2).abs());
        }
        let c = centers[i];
        out.push([
            c - ax1 * h1 - ax2 * h2,
            c + ax1 * h1 - ax2 * h2,
            c + ax1 * h1 + ax2 * h2,
            c - ax1 * h1 + ax2 * h2,
        ]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::surface::{Shape, Surface};
    use crate::procedural::{GroomParams, HeadParams, Style};

    #[test]
    fn kmeans_separates_clusters() {
        let mut pts = Vec::new();
        for c in [Vec3::ZERO, Vec3::X * 10.0, Vec3::Y * 10.0] {
            for i in 0..30 {
                pts.push(c + Vec3::splat(i as f32 * 0.01));
            }
        }
        let a = kmeans(&pts, 3, 10, 7, 1000);
        for c in 0..3 {
            let first = a[c * 30];
            assert!(a[c * 30..c * 30 + 30].iter().all(|&x| x == first));
        }
        assert_ne!(a[0], a[30]);
        assert_ne!(a[30], a[60]);
    }

    #[test]
    fn fitted_mesh_regenerates_the_groom() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        let g = GroomParams {
            style: Style::Straight,
            strands: 6000,
            points: 16,
            ..Default::default()
        }
        .generate(&head)
        .groom;
        let params = HairMeshParams {
            bundles: 200,
            layers: 8,
            style: Default::default(),
            seed: 3,
        };
        let m = HairMesh::fit(&g, &params);
        m.validate().unwrap();
        assert!(m.bundle_count() > 150 && m.bundle_count() <= 200);
        assert_eq!(m.strand_count(), 6000);
        assert!(
            m.layers
                .iter()
                .all(|l| l.ao.iter().all(|a| (0.0..=1.0).contains(a)))
        );
        // AO varies: some vertices are more occluded than others.
        let (lo, hi) = m
            .layers
            .iter()
            .flat_map(|l| l.ao)
            .fold((1f32, 0f32), |(a, b), x| (a.min(x), b.max(x)));
        assert!(hi - lo > 0.05, "{lo}..{hi}");
        let regen = m.to_groom(16, 1e-4);
        assert_eq!(regen.strand_count(), 6000);
        // Bundles average the lengths of their strands, so allow 10% of the groom's size.
        let (a, b) = (g.bounds(), regen.bounds());
        let tol = 0.1 * a.size().max_element();
        assert!((a.min - b.min).abs().max_element() < tol, "{a:?} vs {b:?}");
        assert!((a.max - b.max).abs().max_element() < tol, "{a:?} vs {b:?}");
        // Each regenerated root lies within its bundle's root quad's reach of an original root.
        let bvh_pts = g.roots();
        for r in regen.roots().iter().step_by(97) {
            let d = bvh_pts
                .iter()
                .map(|p| p.distance(*r))
                .fold(f32::INFINITY, f32::min);
            assert!(d < 0.02, "{d}");
        }
    }
}
