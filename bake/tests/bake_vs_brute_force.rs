//! The bake against BVH-free brute force: the BVH must find exactly the
//! crossings a test of every segment finds, and the SH must be the L1
//! projection of those counts (Kulikov, "Visibility function").

use glam::Vec3A;
use strandgraph_bake::bvh::Occluders;
use strandgraph_bake::sh::{Projection, biased, eval, fibonacci_sphere, random_rotation};
use strandgraph_bake::{BakeInput, BakeSettings, bake};

struct Groom {
    vertices: Vec<[f32; 4]>,
    strands: Vec<[u32; 2]>,
    triangles: Vec<[[f32; 3]; 3]>,
}

impl Groom {
    fn input(&self) -> BakeInput<'_> {
        BakeInput {
            vertices: &self.vertices,
            strands: &self.strands,
            triangles: &self.triangles,
        }
    }
}

/// A 10 cm "head" (latitude-longitude sphere) with 600 thick strands
/// falling from its upper half: dense enough that most rays cross strands.
fn groom() -> Groom {
    let (nu, nv, r) = (24u32, 16u32, 0.1f32);
    let at = |u: u32, v: u32| {
        let (th, ph) = (
            std::f32::consts::PI * v as f32 / nv as f32,
            std::f32::consts::TAU * u as f32 / nu as f32,
        );
        [
            r * th.sin() * ph.cos(),
            r * th.cos(),
            r * th.sin() * ph.sin(),
        ]
    };
    let mut triangles = Vec::new();
    for v in 0..nv {
        for u in 0..nu {
            let (a, b, c, d) = (at(u, v), at(u + 1, v), at(u, v + 1), at(u + 1, v + 1));
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let mut vertices = Vec::new();
    let mut strands = Vec::new();
    let mut rng = 12345u64;
    let mut rand = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..600 {
        let (th, ph) = (rand() * 1.2, rand() * std::f32::consts::TAU);
        let n = Vec3A::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
        strands.push([vertices.len() as u32, 10]);
        for i in 0..10 {
            let s = i as f32 * 0.012;
            let p = n * (r + 0.002 + s * 0.5) + Vec3A::new(0.0, -s, 0.0);
            vertices.push([p.x, p.y, p.z, 0.003]);
        }
    }
    Groom {
        vertices,
        strands,
        triangles,
    }
}

const PROBES: [usize; 6] = [0, 5, 9, 1234, 3333, 5999];

#[test]
fn bvh_counts_equal_brute_force_counts() {
    let g = groom();
    let s = BakeSettings::default();
    let occ = Occluders::new(&g.input(), &s);
    let (mut total, mut head_rays) = (0.0, 0);
    for &v in &PROBES {
        let p = g.vertices[v];
        let o = Vec3A::new(p[0], p[1], p[2]);
        for (k, d) in fibonacci_sphere(400).into_iter().enumerate() {
            let d = random_rotation(99, k as u64) * d;
            let fast = occ.events(o, d, s.max_distance, v as u32, s.max_scatter_events);
            let slow = occ.events_brute_force(o, d, s.max_distance, v as u32, s.max_scatter_events);
            assert_eq!(fast, slow, "vertex {v}, direction {d}");
            total += slow;
            head_rays += usize::from(occ.head_hit(o, d, s.max_distance).is_some());
        }
    }
    // The comparison means something only if there were crossings to find.
    let rays = (PROBES.len() * 400) as f32;
    assert!(total / rays > 1.0, "mean events per ray {}", total / rays);
    assert!(head_rays > 200, "{head_rays} head hits");
}

#[test]
fn baked_sh_is_the_projection_of_brute_force_counts() {
    let g = groom();
    let s = BakeSettings {
        rays: 64,
        ..BakeSettings::default()
    };
    let sh = bake(&g.input(), &s).unwrap();
    assert_eq!(sh.len(), g.vertices.len());
    let occ = Occluders::new(&g.input(), &s);
    let dirs = fibonacci_sphere(s.rays);
    for &v in &PROBES {
        let p = g.vertices[v];
        let o = Vec3A::new(p[0], p[1], p[2]);
        let rot = random_rotation(s.seed, v as u64);
        let mut proj = Projection::default();
        for &d in &dirs {
            let d = rot * d;
            let e = occ.events_brute_force(o, d, s.max_distance, v as u32, s.max_scatter_events);
            proj.add(d, biased(e, s.max_scatter_events));
        }
        let want = proj.finish();
        for i in 0..4 {
            assert!(
                (sh[v][i] - want[i]).abs() <= 1e-4 * (1.0 + want[i].abs()),
                "vertex {v}: baked {:?}, brute force {want:?}",
                sh[v]
            );
        }
    }
}

/// With many independent rays, the SH reconstruction follows the direct
/// per-direction counts where L1 can: its mean over the sphere is the mean
/// biased count, and the directions it calls most shadowed really are more
/// occluded than the ones it calls lit.
#[test]
fn reconstruction_follows_direct_counts() {
    let g = groom();
    let s = BakeSettings {
        rays: 256,
        ..BakeSettings::default()
    };
    let sh = bake(&g.input(), &s).unwrap();
    let occ = Occluders::new(&g.input(), &s);
    for &v in &PROBES {
        let p = g.vertices[v];
        let o = Vec3A::new(p[0], p[1], p[2]);
        // Independent directions (another seed and count than the bake's).
        let dirs: Vec<Vec3A> = fibonacci_sphere(2000)
            .into_iter()
            .map(|d| random_rotation(7, v as u64) * d)
            .collect();
        let counts: Vec<f32> = dirs
            .iter()
            .map(|&d| {
                let e =
                    occ.events_brute_force(o, d, s.max_distance, v as u32, s.max_scatter_events);
                biased(e, s.max_scatter_events)
            })
            .collect();
        let mean = counts.iter().sum::<f32>() / counts.len() as f32;
        let sh_mean = sh[v][0] * strandgraph_bake::sh::Y0;
        assert!(
            (sh_mean - mean).abs() < 0.1 * (1.0 + mean.abs()),
            "vertex {v}: SH mean {sh_mean}, direct mean {mean}"
        );
        // Rank directions by the reconstruction; compare the direct counts of
        // the top and bottom quarters.
        let mut order: Vec<usize> = (0..dirs.len()).collect();
        order.sort_by(|&a, &b| eval(&sh[v], dirs[a]).total_cmp(&eval(&sh[v], dirs[b])));
        let q = dirs.len() / 4;
        let avg = |ix: &[usize]| ix.iter().map(|&i| counts[i]).sum::<f32>() / ix.len() as f32;
        let (lit, dark) = (avg(&order[..q]), avg(&order[dirs.len() - q..]));
        assert!(
            dark > lit + 1.0,
            "vertex {v}: dark quarter {dark}, lit quarter {lit}"
        );
    }
}

/// Thinned occluders (every 3rd strand, 3× as thick) and segments cut into
/// pieces still agree with brute force over the same occluders, and keep the
/// mean number of crossings of the full set (thickness compensation).
#[test]
fn thinned_occluders_keep_bvh_exact_and_mean_crossings() {
    let g = groom();
    let full = BakeSettings::default();
    let thin = BakeSettings {
        occluder_stride: 3,
        max_piece: 0.003,
        ..full
    };
    let (a, b) = (
        Occluders::new(&g.input(), &full),
        Occluders::new(&g.input(), &thin),
    );
    assert!(b.segments.len() > a.segments.len() / 3, "pieces");
    let (mut sa, mut sb) = (0.0, 0.0);
    for v in (0..g.vertices.len()).step_by(97) {
        let p = g.vertices[v];
        let o = Vec3A::new(p[0], p[1], p[2]);
        for (k, d) in fibonacci_sphere(64).into_iter().enumerate() {
            let d = random_rotation(5, (v * 64 + k) as u64) * d;
            let fast = b.crossings(o, d, 0.15, v as u32) as f32;
            let slow = b.events_brute_force(o, d, 0.15, v as u32, f32::MIN_POSITIVE);
            if b.head_hit(o, d, 0.15).is_none() {
                assert_eq!(fast, slow, "vertex {v}");
            }
            sa += a.crossings(o, d, 0.15, v as u32) as f32;
            sb += fast;
        }
    }
    assert!(sa > 500.0, "{sa} crossings");
    assert!((sb / sa - 1.0).abs() < 0.25, "thinned {sb} vs full {sa}");
}

/// Probes every 4th vertex: those equal the full bake, the ones between are
/// the linear interpolation along the strand.
#[test]
fn vertex_stride_interpolates_between_probes() {
    let g = groom();
    let full = BakeSettings {
        rays: 16,
        ..BakeSettings::default()
    };
    let strided = BakeSettings {
        vertex_stride: 4,
        ..full
    };
    let (a, b) = (
        bake(&g.input(), &full).unwrap(),
        bake(&g.input(), &strided).unwrap(),
    );
    // Strands have 10 vertices: probes at 0, 4, 8 and the tip 9.
    for s in [0usize, 17, 599] {
        let base = s * 10;
        for i in [0, 4, 8, 9] {
            assert_eq!(a[base + i], b[base + i], "strand {s} probe {i}");
        }
        for c in 0..4 {
            let want = a[base + 4][c] + (a[base + 8][c] - a[base + 4][c]) * 0.25;
            assert!((b[base + 5][c] - want).abs() < 1e-4, "strand {s}");
        }
    }
}
