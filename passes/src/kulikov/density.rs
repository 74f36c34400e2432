//! `kulikov.density`: splat the drawn hair into a per-model density grid.
//!
//! Kulikov, "Simulation": "We also output voxel density grids for each
//! simulation. We need that for hair collision and for hair shadow
//! calculations" (48x48x48 for shadows on skin). We have no simulation, so
//! this pass builds the grid from the post-transform cache: every drawn
//! segment adds its projected area (thickness × length, in units of
//! [`AREA_UNIT`] m²) to the voxel of its midpoint with `atomicAdd`, over the
//! model's world bounds. Divided by the voxel volume that is an extinction
//! coefficient: optical depth along a ray is the expected number of strands
//! it crosses, the quantity `kulikov.shade`'s `VoxelMarch` and the baked SH
//! both count ("number of scattering events").

use super::cull::{GROUP, drawn_segment};
use super::{Scene, world_of_clip};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::layout::ModelData;
use crate::params::{Invalid, PassParams};
use strandgraph_graph::schema::Quantity;

/// Largest grid edge; `density_grid` holds `MAX_RESOLUTION³` words per model.
pub const MAX_RESOLUTION: u32 = 48;
/// Words per model in `density_grid`.
pub const GRID_WORDS: u32 = MAX_RESOLUTION * MAX_RESOLUTION * MAX_RESOLUTION;
/// Fixed-point unit of the splatted area: 1e-9 m² (0.001 mm²).
pub const AREA_UNIT: f32 = 1e-9;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DensityParams {
    /// Grid edge (1..=48).
    pub resolution: u32,
}

impl Default for DensityParams {
    fn default() -> Self {
        Self {
            resolution: MAX_RESOLUTION,
        }
    }
}

impl PassParams for DensityParams {
    fn validate(&self) -> Result<(), Invalid> {
        check_resolution(self.resolution)
    }
}

/// Checks a `resolution` parameter (1..=48), for every pass that reads the grid.
pub fn check_resolution(r: u32) -> Result<(), Invalid> {
    if r == 0 || r > MAX_RESOLUTION {
        return Err(Invalid::new(
            "resolution",
            format!(
                "expected 1..={MAX_RESOLUTION} (density_grid holds {MAX_RESOLUTION}³ voxels per model), got {r}"
            ),
        ));
    }
    Ok(())
}

crate::gpu_block! {
    /// The WGSL `DensityParams` block (binding 0).
    pub struct DensityGpu {
        resolution: u32,
        /// Scene quantity: segments in the full numbering.
        segments: u32,
    }
}

pub static DENSITY: PassKind<DensityParams, DensityGpu> = PassKind {
    kind: "kulikov.density",
    summary: "splat drawn segments' projected area into a 48^3 density grid per model (atomicAdd)",
    source: "Kulikov 2025, 'Simulation' (density output), 'Hair volumetric shadows'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("clip_positions"),
        Binding::read("groom.vertices"),
        Binding::atomic("density_grid"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Segments,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/density.wgsl", "density"),
    kernel: |p| {
        Box::new(DensityKernel {
            resolution: p.resolution,
        })
    },
    gpu: |p, q| DensityGpu {
        resolution: p.resolution,
        segments: count(q.segments),
    },
    raster: None,
};

/// A model's grid: its world bounds split into `resolution³` voxels.
#[derive(Debug, Clone, Copy)]
pub struct Grid {
    pub min: [f32; 3],
    pub size: [f32; 3],
    pub resolution: u32,
}

impl Grid {
    pub fn of(m: &ModelData, resolution: u32) -> Self {
        let min = [m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]];
        let size = [0, 1, 2].map(|a| (m.bounds_max[a] - m.bounds_min[a]).max(1e-6));
        Self {
            min,
            size,
            resolution,
        }
    }
    /// The voxel (index within the model's block) holding world point `p`.
    pub fn voxel(&self, p: [f32; 3]) -> Option<u32> {
        let r = self.resolution as f32;
        let mut idx = [0u32; 3];
        for a in 0..3 {
            let f = (p[a] - self.min[a]) / self.size[a] * r;
            // Written so NaN is rejected too.
            if !(f >= 0.0 && f < r) {
                return None;
            }
            idx[a] = f as u32;
        }
        Some((idx[2] * self.resolution + idx[1]) * self.resolution + idx[0])
    }
    pub fn voxel_volume(&self) -> f32 {
        let r = self.resolution as f32;
        self.size[0] * self.size[1] * self.size[2] / (r * r * r)
    }
    /// Extinction (strands crossed per metre) of a voxel holding `units`.
    pub fn sigma(&self, units: u32) -> f32 {
        units as f32 * AREA_UNIT / self.voxel_volume()
    }
}

struct DensityKernel {
    resolution: u32,
}

impl CpuKernel for DensityKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let (clip, verts, grid) = (
            ctx.words("clip_positions"),
            ctx.words("groom.vertices"),
            ctx.words("density_grid"),
        );
        let inv = scene.frame.inv_view_proj;
        for lane in 0..GROUP {
            let id = group * GROUP + lane;
            if u64::from(id) >= ctx.quantities.segments {
                break;
            }
            let Some(seg) = drawn_segment(&scene, &lods, id) else {
                continue;
            };
            let g = Grid::of(&scene.models[seg.model], self.resolution);
            let a = world_of_clip(&inv, clip.load_vec4(seg.v0 as usize));
            let b = world_of_clip(&inv, clip.load_vec4(seg.v1 as usize));
            let mid = [0, 1, 2].map(|k| 0.5 * (a[k] + b[k]));
            let Some(voxel) = g.voxel(mid) else { continue };
            let len = ((0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f32>()).sqrt();
            let thick = 0.5
                * (verts.load_f32(4 * seg.v0 as usize + 3)
                    + verts.load_f32(4 * seg.v1 as usize + 3))
                * lods[seg.model].thickness_scale;
            let units = (thick * len / AREA_UNIT).round();
            if units >= 1.0 && units.is_finite() {
                grid.fetch_add(
                    (seg.model as u32 * GRID_WORDS + voxel) as usize,
                    units.min(1e6) as u32,
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use crate::kulikov::ModelLod;
    use crate::layout::{FrameData, words_of};
    use bytemuck::Zeroable;
    use strandgraph_graph::Quantities;

    /// Two strands of 3 points, 1 cm segments, 100 µm thick, one LOD-dropped:
    /// the grid holds the drawn segments' projected area, at their midpoints.
    #[test]
    fn splats_drawn_segments_projected_area() {
        let mut f = FrameData::zeroed();
        let id = glam::Mat4::IDENTITY.to_cols_array();
        (f.view_proj, f.inv_view_proj, f.model_count) = (id, id, 1);
        let mut m = ModelData::zeroed();
        (m.strand_count, m.points_per_strand) = (2, 3);
        m.bounds_min = [0.0, 0.0, 0.0, 0.0];
        m.bounds_max = [0.048, 0.048, 0.048, 0.0];
        let lod = ModelLod {
            strands: 1,
            vertex_step: 1,
            thickness_scale: 2.0,
            segments_per_strand: 2,
            ..Default::default()
        };
        let mut lod_words = vec![0u32; 8];
        {
            let atoms: Vec<_> = lod_words
                .iter()
                .map(|&w| std::sync::atomic::AtomicU32::new(w))
                .collect();
            let oob = std::sync::atomic::AtomicU64::new(0);
            lod.store(&crate::kernel::Words::new(&atoms, &oob), 0);
            lod_words = atoms
                .iter()
                .map(|a| a.load(std::sync::atomic::Ordering::Relaxed))
                .collect();
        }
        let (mut clip, mut verts) = (Vec::new(), Vec::new());
        for s in 0..2 {
            for k in 0..3 {
                let p = [0.0105 + 0.02 * s as f32, 0.0105 + 0.01 * k as f32, 0.0105];
                clip.extend([p[0], p[1], p[2], 1.0].map(f32::to_bits));
                verts.extend([p[0], p[1], p[2], 1e-4].map(f32::to_bits));
            }
        }
        let mut hs = Harness::new(Quantities {
            segments: 4,
            vertices: 6,
            models: 1,
            ..Default::default()
        });
        hs.buffer("frame", words_of(&[f]))
            .buffer("models", words_of(&[m]))
            .buffer("lod_models", lod_words)
            .buffer("clip_positions", clip)
            .buffer("groom.vertices", verts)
            .buffer("density_grid", vec![0; GRID_WORDS as usize]);
        let k = crate::PassDef::cpu_kernel(&DENSITY, &ron::Value::Unit).unwrap();
        hs.run(k.as_ref(), 1, GROUP);
        assert_eq!(hs.out_of_bounds(), 0);
        let grid = hs.read("density_grid");
        // 2e-4 m (thickness × LOD scale) × 0.01 m = 2e-6 m² = 2000 units per segment.
        let filled: Vec<(usize, u32)> = grid
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, u)| *u > 0)
            .collect();
        let g = Grid::of(&m, MAX_RESOLUTION);
        let at = |y: f32| g.voxel([0.0105, y, 0.0105]).unwrap() as usize;
        assert_eq!(filled, vec![(at(0.0155), 2000), (at(0.0255), 2000)]);
        // One voxel is 1 mm³: 2000 units there are 2 strands crossed per mm.
        assert!((g.sigma(2000) - 2000.0).abs() < 1.0, "{}", g.sigma(2000));
    }

    #[test]
    fn voxels_cover_the_bounds() {
        let mut m: ModelData = bytemuck::Zeroable::zeroed();
        m.bounds_min = [0.0, 0.0, 0.0, 0.0];
        m.bounds_max = [1.0, 2.0, 4.0, 0.0];
        let g = Grid::of(&m, 4);
        assert_eq!(g.voxel([0.1, 0.1, 0.1]), Some(0));
        assert_eq!(g.voxel([0.9, 1.9, 3.9]), Some(63));
        assert_eq!(g.voxel([1.0, 0.0, 0.0]), None);
        assert_eq!(g.voxel([f32::NAN, 0.0, 0.0]), None);
        assert!((g.voxel_volume() - 8.0 / 64.0).abs() < 1e-6);
        assert!(
            DENSITY
                .params(&ron::from_str("{\"resolution\": 64}").unwrap())
                .is_err()
        );
    }
}
