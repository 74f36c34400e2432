//! Triangle meshes (heads, bodies) with a BVH for closest-point queries.

use glam::Vec3;

use crate::bounds::Aabb;
use crate::transform::Transform;

/// An indexed triangle mesh in metres.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub transform: Transform,
    /// Linear RGB albedo per vertex (painted skin, lips, eyes), or empty:
    /// then the opaque pass's `albedo` parameter shades the whole mesh.
    pub colors: Vec<Vec3>,
}

/// The closest point on a mesh to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestHit {
    pub triangle: u32,
    /// Barycentric weights of the triangle's three vertices.
    pub barycentric: Vec3,
    pub point: Vec3,
    pub distance_squared: f32,
}

impl TriMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * 12 + self.triangles.len() * 12
    }
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }
    /// Unit face normal (counter-clockwise winding faces outward).
    pub fn face_normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.corners(t);
        (b - a).cross(c - a).normalize_or_zero()
    }
    pub fn face_area(&self, t: usize) -> f32 {
        let [a, b, c] = self.corners(t);
        0.5 * (b - a).cross(c - a).length()
    }
    /// Area-weighted vertex normals.
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|i| self.positions[i as usize]);
            let f = (b - a).cross(c - a);
            for &i in tri {
                n[i as usize] += f;
            }
        }
        n.iter().map(|v| v.normalize_or_zero()).collect()
    }
    /// Checks that indices are in range and positions are finite.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.positions.len() as u32;
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i >= n))
        {
            return Err(format!("triangle {t} has a vertex index out of range"));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} is not finite"));
        }
        Ok(())
    }
    /// Signed volume (positive for a closed, outward-facing mesh).
    pub fn signed_volume(&self) -> f32 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }
    /// Whether `p` is inside the closed mesh (ray parity along +x, jittered direction).
    pub fn contains(&self, p: Vec3) -> bool {
        let dir = Vec3::new(1.0, 0.000_123, 0.000_371).normalize();
        let mut hits = 0;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            // Möller–Trumbore.
            let e1 = b - a;
            let e2 = c - a;
            let h = dir.cross(e2);
            let det = e1.dot(h);
            if det.abs() < 1e-12 {
                continue;
            }
            let f = 1.0 / det;
            let s = p - a;
            let u = f * s.dot(h);
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(e1);
            let v = f * dir.dot(q);
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            if f * e2.dot(q) > 0.0 {
                hits += 1;
            }
        }
        hits % 2 == 1
    }
}

/// Closest point on triangle (a, b, c) to p, as barycentric weights (Ericson, RTCD §5.1.5).
pub fn closest_barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return Vec3::X;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return Vec3::Y;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return Vec3::new(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return Vec3::Z;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return Vec3::new(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return Vec3::new(0.0, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    Vec3::new(1.0 - v - w, v, w)
}

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Triangle count for leaves, 0 for inner nodes.
    count: u32,
}

/// A bounding volume hierarchy over a mesh's triangles (median splits).
pub struct Bvh<'m> {
    mesh: &'m TriMesh,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl<'m> Bvh<'m> {
    pub fn new(mesh: &'m TriMesh) -> Self {
        let mut order: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
        let centroids: Vec<Vec3> = (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (a + b + c) / 3.0
            })
            .collect();
        let mut nodes = vec![Node {
            bounds: Aabb::EMPTY,
            start: 0,
            count: order.len() as u32,
        }];
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let (start, count) = (nodes[ni].start as usize, nodes[ni].count as usize);
            let tris = &mut order[start..start + count];
            let bounds = tris.iter().fold(Aabb::EMPTY, |b, &t| {
                let [a, bb, c] = mesh.corners(t as usize);
                b.grow(a).grow(bb).grow(c)
            });
            nodes[ni].bounds = bounds;
            if count <= 4 {
                continue;
            }
            let cb = tris
                .iter()
                .fold(Aabb::EMPTY, |b, &t| b.grow(centroids[t as usize]));
            let axis = cb.size().max_position();
            let mid = count / 2;
            tris.select_nth_unstable_by(mid, |&x, &y| {
                centroids[x as usize][axis].total_cmp(&centroids[y as usize][axis])
            });
            let left = nodes.len();
            nodes.push(Node {
                bounds: Aabb::EMPTY,
                start: start as u32,
                count: mid as u32,
            });
            nodes.push(Node {
                bounds: Aabb::EMPTY,
                start: (start + mid) as u32,
                count: (count - mid) as u32,
            });
            nodes[ni].start = left as u32;
            nodes[ni].count = 0;
            stack.push(left);
            stack.push(left + 1);
        }
        Bvh { mesh, nodes, order }
    }

    /// The closest point on the mesh to `p`; `None` for an empty mesh.
    pub fn closest(&self, p: Vec3) -> Option<ClosestHit> {
        let mut best: Option<ClosestHit> = None;
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let node = self.nodes.get(ni)?;
            let bound = best.map_or(f32::INFINITY, |b| b.distance_squared);
            if node.bounds.is_empty() || node.bounds.distance_squared(p) > bound {
                continue;
            }
            if node.count == 0 {
                let (l, r) = (node.start as usize, node.start as usize + 1);
                let dl = self.nodes[l].bounds.distance_squared(p);
                let dr = self.nodes[r].bounds.distance_squared(p);
                if dl < dr {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
                continue;
            }
            for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                let [a, b, c] = self.mesh.corners(t as usize);
                let bary = closest_barycentric(p, a, b, c);
                let q = a * bary.x + b * bary.y + c * bary.z;
                let d = q.distance_squared(p);
                if best.is_none_or(|b| d < b.distance_squared) {
                    best = Some(ClosestHit {
                        triangle: t,
                        barycentric: bary,
                        point: q,
                        distance_squared: d,
                    });
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            transform: Transform::IDENTITY,
            colors: Vec::new(),
        }
    }

    #[test]
    fn closed_mesh_volume_and_containment() {
        let m = tetra();
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-6);
        assert!(m.contains(Vec3::splat(0.1)));
        assert!(!m.contains(Vec3::splat(0.5)));
        m.validate().unwrap();
    }

    #[test]
    fn bvh_matches_brute_force() {
        let m = crate::procedural::head::HeadParams::default().build();
        let bvh = Bvh::new(&m);
        for i in 0..50 {
            let p = Vec3::new(
                (i as f32 * 0.37).sin(),
                (i as f32 * 0.91).cos(),
                (i as f32 * 0.13).sin(),
            ) * 0.2;
            let hit = bvh.closest(p).unwrap();
            let brute = (0..m.triangle_count())
                .map(|t| {
                    let [a, b, c] = m.corners(t);
                    let w = closest_barycentric(p, a, b, c);
                    (a * w.x + b * w.y + c * w.z).distance_squared(p)
                })
                .fold(f32::INFINITY, f32::min);
            assert!((hit.distance_squared - brute).abs() < 1e-9);
        }
    }
}
