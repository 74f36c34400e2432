//! Signed-distance modelling: the primitives and smooth blends the procedural
//! head is sculpted from, and the extraction of a triangle mesh from any signed
//! distance function (Naive Surface Nets, through the `fast-surface-nets` crate).
//!
//! Distances are in metres, negative inside. The smooth blends are Quilez's
//! polynomial smooth minimum; the ellipsoid is his first-order bound. Both keep
//! the functions 1-Lipschitz enough for sphere tracing, push-out and the
//! narrow band below.

use fast_surface_nets::ndshape::{RuntimeShape, Shape as _};
use fast_surface_nets::{SurfaceNetsBuffer, surface_nets};
use glam::Vec3;
use rayon::prelude::*;

use crate::mesh::TriMesh;
use crate::transform::Transform;

/// Polynomial smooth minimum (Quilez): the union of two shapes with a fillet
/// of radius about `k`.
pub fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// Smooth maximum: a filleted intersection (or, with `-b`, a subtraction).
pub fn smax(a: f32, b: f32, k: f32) -> f32 {
    -smin(-a, -b, k)
}

pub fn sphere(p: Vec3, r: f32) -> f32 {
    p.length() - r
}

/// An ellipsoid with semi-axes `r` (Quilez's bound: exact on the surface,
/// slightly underestimating away from it, which keeps blends safe).
pub fn ellipsoid(p: Vec3, r: Vec3) -> f32 {
    let k0 = (p / r).length();
    let k1 = (p / (r * r)).length();
    if k1 < 1e-12 {
        return -r.min_element();
    }
    k0 * (k0 - 1.0) / k1
}

/// A capsule: the segment `a`–`b` thickened by `r`.
pub fn capsule(p: Vec3, a: Vec3, b: Vec3, r: f32) -> f32 {
    let (pa, ba) = (p - a, b - a);
    let h = (pa.dot(ba) / ba.length_squared().max(1e-12)).clamp(0.0, 1.0);
    (pa - ba * h).length() - r
}

/// The outward unit gradient of `sdf` at `p` (central differences, step `h`).
pub fn gradient(sdf: impl Fn(Vec3) -> f32, p: Vec3, h: f32) -> Vec3 {
    let d = |e: Vec3| sdf(p + e) - sdf(p - e);
    Vec3::new(d(Vec3::X * h), d(Vec3::Y * h), d(Vec3::Z * h)).normalize_or_zero()
}

/// Meshes the zero set of `sdf` inside the box `min`–`max` with cells of
/// `cell` metres. The box must enclose the surface with a margin of a few
/// cells. Only cells near the surface are evaluated: a coarse pass with
/// blocks of 4³ cells skips every block whose centre is farther from the
/// surface than the block's half diagonal plus two cells (valid because `sdf` is a distance
/// bound). Triangles are wound outward.
pub fn mesh_sdf(sdf: impl Fn(Vec3) -> f32 + Sync, min: Vec3, max: Vec3, cell: f32) -> TriMesh {
    const BLOCK: u32 = 4;
    let dims = ((max - min) / cell).ceil().as_uvec3() + 1;
    let dims = dims.max(glam::UVec3::splat(3));
    let shape = RuntimeShape::<u32, 3>::new([dims.x, dims.y, dims.z]);
    let far = cell * BLOCK as f32 * 2.0;
    let mut values = vec![far; shape.usize()];
    let blocks = (dims + BLOCK - 1) / BLOCK;
    // Two cells of margin: a cell the surface crosses has every corner within
    // √3 cells of the crossing, so no skipped point is a corner of such a cell.
    let reach = cell * BLOCK as f32 * 0.5 * 3f32.sqrt() + 2.0 * cell;
    let at = |x: u32, y: u32, z: u32| min + Vec3::new(x as f32, y as f32, z as f32) * cell;
    // Each z-slab of blocks is filled by one task; slabs do not overlap.
    let slab = (dims.x * dims.y * BLOCK) as usize;
    values
        .par_chunks_mut(slab)
        .enumerate()
        .for_each(|(bz, chunk)| {
            let z0 = bz as u32 * BLOCK;
            for by in 0..blocks.y {
                for bx in 0..blocks.x {
                    let (x0, y0) = (bx * BLOCK, by * BLOCK);
                    let centre = min
                        + (Vec3::new(x0 as f32, y0 as f32, z0 as f32) + BLOCK as f32 * 0.5) * cell;
                    let d = sdf(centre);
                    if d.abs() > reach {
                        let fill = if d < 0.0 { -far } else { far };
                        for_block(dims, x0, y0, z0, BLOCK, |i, _, _, _| chunk[i] = fill);
                        continue;
                    }
                    for_block(dims, x0, y0, z0, BLOCK, |i, x, y, z| {
                        chunk[i] = sdf(at(x, y, z))
                    });
                }
            }
        });
    let mut buffer = SurfaceNetsBuffer::default();
    surface_nets(&values, &shape, [0; 3], (dims - 1).to_array(), &mut buffer);
    let mut mesh = TriMesh {
        positions: buffer
            .positions
            .iter()
            .map(|p| min + Vec3::from_array(*p) * cell)
            .collect(),
        triangles: buffer
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        transform: Transform::IDENTITY,
        colors: Vec::new(),
    };
    if mesh.signed_volume() < 0.0 {
        mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    mesh
}

/// Calls `f(index within the z-slab, x, y, z)` for every grid point of one
/// block (clipped to the grid), the slab starting at `z0`.
fn for_block(
    dims: glam::UVec3,
    x0: u32,
    y0: u32,
    z0: u32,
    block: u32,
    mut f: impl FnMut(usize, u32, u32, u32),
) {
    for z in z0..(z0 + block).min(dims.z) {
        for y in y0..(y0 + block).min(dims.y) {
            for x in x0..(x0 + block).min(dims.x) {
                let i = ((z - z0) * dims.y * dims.x + y * dims.x + x) as usize;
                f(i, x, y, z);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_mesh_is_closed_outward_and_on_the_surface() {
        let r = 0.1;
        let m = mesh_sdf(
            |p| sphere(p, r),
            Vec3::splat(-0.13),
            Vec3::splat(0.13),
            0.005,
        );
        m.validate().unwrap();
        let volume = 4.0 / 3.0 * std::f32::consts::PI * r * r * r;
        assert!(
            (m.signed_volume() - volume).abs() < 0.02 * volume,
            "{} vs {volume}",
            m.signed_volume()
        );
        for p in &m.positions {
            assert!((p.length() - r).abs() < 0.002, "{p} is off the sphere");
        }
    }

    #[test]
    fn narrow_band_gives_the_same_mesh_as_a_full_evaluation() {
        // A thin shape the coarse pass must not skip.
        let sdf = |p: Vec3| {
            capsule(
                p,
                Vec3::new(-0.05, 0.0, 0.0),
                Vec3::new(0.05, 0.0, 0.0),
                0.004,
            )
        };
        let m = mesh_sdf(sdf, Vec3::splat(-0.07), Vec3::splat(0.07), 0.002);
        assert!(m.triangle_count() > 100);
        for p in &m.positions {
            assert!(sdf(*p).abs() < 0.001);
        }
    }

    #[test]
    fn blends_and_bounds() {
        assert!((smin(1.0, 5.0, 0.1) - 1.0).abs() < 1e-6);
        assert!(smin(1.0, 1.0, 0.1) < 1.0);
        assert!((smax(1.0, 5.0, 0.1) - 5.0).abs() < 1e-6);
        let e = Vec3::new(0.1, 0.05, 0.02);
        assert!(ellipsoid(Vec3::new(0.1, 0.0, 0.0), e).abs() < 1e-6);
        assert!(ellipsoid(Vec3::ZERO, e) < 0.0);
        let g = gradient(|p| sphere(p, 1.0), Vec3::new(2.0, 0.0, 0.0), 1e-3);
        assert!(g.distance(Vec3::X) < 1e-4);
    }
}
