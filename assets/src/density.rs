//! A voxel grid of strand density for baked ambient occlusion, shared by hair meshes
//! (Lipp §3.5) and hair patches (Scheuermann 2004: "Ambient occlusion to approximate
//! self-shadowing - Per vertex"). Strand points are splatted into the grid; a vertex's
//! occlusion comes from the optical depth marched out of it through the grid.

use glam::{IVec3, Vec3};

use crate::bounds::Aabb;

/// Density on `dims` cells spanning a box; cell `c` covers `min + c * cell .. + cell`.
#[derive(Debug, Clone, PartialEq)]
pub struct DensityGrid {
    min: Vec3,
    cell: Vec3,
    dims: IVec3,
    data: Vec<f32>,
}

impl DensityGrid {
    /// `dims` cells per axis over `bounds` (each side at least 0.1 mm, so a flat or
    /// one-point groom still gets a grid). `None` for an empty or non-finite box.
    pub fn new(bounds: Aabb, dims: IVec3) -> Option<DensityGrid> {
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return None;
        }
        let dims = dims.max(IVec3::ONE);
        let size = bounds.size().max(Vec3::splat(1e-4));
        Some(DensityGrid {
            min: bounds.min,
            cell: size / dims.as_vec3(),
            dims,
            data: vec![0.0; (dims.x * dims.y * dims.z) as usize],
        })
    }

    /// Cubic cells, `res` of them along the longest side of `bounds`: a march of one cell
    /// is then the same length in every direction.
    pub fn cubic(bounds: Aabb, res: i32) -> Option<DensityGrid> {
        if bounds.is_empty() {
            return None;
        }
        let size = bounds.size().max(Vec3::splat(1e-4));
        let edge = size.max_element() / res.max(1) as f32;
        let dims = (size / edge)
            .ceil()
            .as_ivec3()
            .clamp(IVec3::ONE, IVec3::splat(res.max(1)));
        let mut g = DensityGrid::new(bounds, dims)?;
        g.cell = Vec3::splat(edge);
        Some(g)
    }

    pub fn dims(&self) -> IVec3 {
        self.dims
    }
    /// The cell's edge lengths.
    pub fn cell_size(&self) -> Vec3 {
        self.cell
    }
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// `p` in continuous cell coordinates (cell `c` spans `c .. c + 1`).
    pub fn to_grid(&self, p: Vec3) -> Vec3 {
        (p - self.min) / self.cell
    }
    /// The cell holding `p`, clamped into the grid. (Truncating instead of flooring
    /// differs only below 0, which clamps to 0 either way, and skips a libm call.)
    pub fn cell_of(&self, p: Vec3) -> IVec3 {
        self.to_grid(p).as_ivec3().clamp(IVec3::ZERO, self.dims - 1)
    }
    fn flat(&self, c: IVec3) -> usize {
        (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize
    }

    /// Adds `w` to the cell holding `p` (clamped into the grid).
    pub fn add(&mut self, p: Vec3, w: f32) {
        let i = self.flat(self.cell_of(p));
        self.data[i] += w;
    }
    /// Adds another grid of the same shape cell by cell (for parallel splatting).
    pub fn merge(mut self, other: &DensityGrid) -> DensityGrid {
        if self.dims == other.dims {
            self.data
                .iter_mut()
                .zip(&other.data)
                .for_each(|(a, b)| *a += b);
        }
        self
    }
    /// An empty grid of the same shape.
    pub fn cleared(&self) -> DensityGrid {
        DensityGrid {
            data: vec![0.0; self.data.len()],
            ..*self
        }
    }
    pub fn scale(&mut self, s: f32) {
        self.data.iter_mut().for_each(|d| *d *= s);
    }
    /// Scales the densest cell to 1.
    pub fn normalize_max(&mut self) {
        let max = self.data.iter().copied().fold(0.0, f32::max).max(1e-6);
        self.data.iter_mut().for_each(|d| *d /= max);
    }

    /// Trilinear density at continuous cell coordinates `q` (cell values sit at cell
    /// centres, clamped at the border). At a cell centre it is exactly that cell's value.
    pub fn sample(&self, q: Vec3) -> f32 {
        let q = q - 0.5;
        let c0 = floor(q);
        self.trilinear(c0, q - c0.as_vec3())
    }

    /// Trilinear interpolation between the cells `c0 + {0,1}³` with weights `f`.
    fn trilinear(&self, c0: IVec3, f: Vec3) -> f32 {
        let v: [f32; 8] = if c0.cmpge(IVec3::ZERO).all() && (c0 + 1).cmplt(self.dims).all() {
            let i = self.flat(c0);
            let (y, z) = (self.dims.x as usize, (self.dims.x * self.dims.y) as usize);
            let d = &self.data;
            [
                d[i],
                d[i + 1],
                d[i + y],
                d[i + y + 1],
                d[i + z],
                d[i + z + 1],
                d[i + z + y],
                d[i + z + y + 1],
            ]
        } else {
            std::array::from_fn(|k| {
                let o = IVec3::new(k as i32 & 1, (k as i32 >> 1) & 1, k as i32 >> 2);
                self.data[self.flat((c0 + o).clamp(IVec3::ZERO, self.dims - 1))]
            })
        };
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(v[0], v[1], f.x);
        let x10 = lerp(v[2], v[3], f.x);
        let x01 = lerp(v[4], v[5], f.x);
        let x11 = lerp(v[6], v[7], f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z)
    }

    /// A read-only view for marching rays, with the grid's empty regions indexed.
    pub fn marcher(&self) -> Marcher<'_> {
        let d = self.dims;
        let mut occupied = vec![false; self.data.len()];
        // Cell c is marked when any of the eight cells a trilinear sample based at c reads
        // (c + {0,1}³, clamped) holds density; a sample based on an unmarked cell is 0.
        for z in 0..d.z {
            for y in 0..d.y {
                for x in 0..d.x {
                    let c = IVec3::new(x, y, z);
                    if self.data[self.flat(c)] != 0.0 {
                        for k in 0..8 {
                            let o = IVec3::new(k & 1, (k >> 1) & 1, k >> 2);
                            let base = (c - o).max(IVec3::ZERO);
                            occupied[self.flat(base)] = true;
                        }
                    }
                }
            }
        }
        Marcher {
            grid: self,
            occupied,
        }
    }
}

/// Marches rays through a [`DensityGrid`], skipping empty space cheaply.
pub struct Marcher<'a> {
    grid: &'a DensityGrid,
    occupied: Vec<bool>,
}

impl Marcher<'_> {
    /// Optical depth in cell lengths × density: the sum of the densities sampled at
    /// `from + dir * k` (cell coordinates, `dir` normalized there) for k = 1, 2, ... while
    /// the sample's cell is inside the grid, stopping early once it exceeds `limit`.
    /// Starting one cell out keeps a vertex from occluding itself with the strands it
    /// stands for.
    pub fn optical_depth(&self, from: Vec3, dir: Vec3, limit: f32) -> f32 {
        let g = self.grid;
        let dir = dir.normalize_or_zero();
        if dir == Vec3::ZERO || !from.is_finite() {
            return 0.0;
        }
        // The steps whose samples can lie in the grid (slab test, a step of margin
        // either side); the per-sample test below stays the exact one.
        let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
        for a in 0..3 {
            let (o, d, n) = (from[a], dir[a], g.dims[a] as f32);
            if d == 0.0 {
                if !(0.0..n).contains(&o) {
                    return 0.0;
                }
                continue;
            }
            let (t1, t2) = ((0.0 - o) / d, (n - o) / d);
            lo = lo.max(t1.min(t2));
            hi = hi.min(t1.max(t2));
        }
        if lo > hi {
            return 0.0;
        }
        let first = (lo.floor() - 1.0).max(1.0) as usize;
        let last = (hi.ceil() + 1.0).min((g.dims.x + g.dims.y + g.dims.z) as f32 * 2.0) as usize;
        let mut depth = 0.0;
        for k in first..=last {
            let q = from + dir * k as f32;
            // The sample's cell is in the grid (compared without flooring).
            if !(q.cmpge(Vec3::ZERO).all() && q.cmplt(g.dims.as_vec3()).all()) {
                continue;
            }
            // As `sample(q)`, with the empty-space test on the base cell in between.
            let q = q - 0.5;
            let c0 = floor(q);
            if self.occupied[g.flat(c0.clamp(IVec3::ZERO, g.dims - 1))] {
                depth += g.trilinear(c0, q - c0.as_vec3());
                if depth > limit {
                    break;
                }
            }
        }
        depth
    }
}

/// `x.floor().as_ivec3()` for |x| < 2³¹ without the libm call `floor` becomes on
/// targets without SSE4.1: truncate, then step down where that rounded up (negative
/// non-integers).
fn floor(x: Vec3) -> IVec3 {
    let t = x.as_ivec3();
    t - IVec3::select(x.cmplt(t.as_vec3()), IVec3::ONE, IVec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::from_points(&[Vec3::ZERO, Vec3::ONE])
    }

    #[test]
    fn splat_sample_and_march() {
        let mut g = DensityGrid::new(unit_box(), IVec3::splat(4)).unwrap();
        g.add(Vec3::new(0.6, 0.1, 0.1), 2.0);
        g.add(Vec3::splat(7.0), 1.0); // clamped into the far corner
        assert_eq!(g.data().iter().sum::<f32>(), 3.0);
        // Exact at cell centres, in between halfway.
        assert_eq!(g.sample(Vec3::new(2.5, 0.5, 0.5)), 2.0);
        assert_eq!(g.sample(Vec3::new(3.0, 0.5, 0.5)), 1.0);
        // Along +x from cell 0 the march visits cells 1, 2, 3.
        let m = g.marcher();
        let from = Vec3::splat(0.5);
        assert_eq!(m.optical_depth(from, Vec3::X, f32::INFINITY), 2.0);
        assert_eq!(m.optical_depth(from, Vec3::NEG_X, f32::INFINITY), 0.0);
        assert_eq!(m.optical_depth(from, Vec3::ZERO, f32::INFINITY), 0.0);
        // Skipping empty space changes nothing: compare with sampling everywhere.
        for k in 0..64 {
            let from = Vec3::new(0.3 + k as f32 * 0.05, 1.7, 0.2 + (k % 7) as f32 * 0.5);
            let dir = Vec3::new(1.0, -0.7 + k as f32 * 0.02, 0.3).normalize();
            let unit = dir.normalize_or_zero(); // as optical_depth does
            let all: f32 = (1..40)
                .map(|s| from + unit * s as f32)
                .take_while(|q| q.cmpge(Vec3::ZERO).all() && q.cmplt(Vec3::splat(4.0)).all())
                .map(|q| g.sample(q))
                .sum();
            assert_eq!(m.optical_depth(from, dir, f32::INFINITY), all, "{k}");
        }
        g.normalize_max();
        assert_eq!(g.data().iter().copied().fold(0.0, f32::max), 1.0);
    }

    #[test]
    fn floor_without_libm() {
        for x in [
            -2.5f32,
            -1.0,
            -0.5,
            -0.0,
            0.0,
            1e-9,
            -1e-9,
            0.5,
            1.0,
            3.999_999,
            1e6 + 0.5,
        ] {
            let v = Vec3::new(x, -x, x * 0.5);
            assert_eq!(floor(v), v.floor().as_ivec3(), "{x}");
        }
    }

    #[test]
    fn cubic_cells_and_degenerate_boxes() {
        let b = Aabb::from_points(&[Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0)]);
        let g = DensityGrid::cubic(b, 8).unwrap();
        assert_eq!(g.dims(), IVec3::new(8, 4, 1));
        assert_eq!(g.cell_size(), Vec3::splat(0.25));
        assert!(DensityGrid::cubic(Aabb::EMPTY, 8).is_none());
        let one = DensityGrid::cubic(Aabb::from_points(&[Vec3::ONE]), 8).unwrap();
        assert_eq!(
            one.marcher()
                .optical_depth(Vec3::splat(f32::NAN), Vec3::X, 1.0),
            0.0
        );
    }
}
