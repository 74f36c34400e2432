//! Baked ambient occlusion per hair-mesh vertex (Lipp §3.5: "pre-bake an ambient occlusion
//! value in each vertex of the hair mesh proxy"). Strand density is splatted into a voxel
//! grid; a vertex's AO is the mean transmittance along six axis directions.

use glam::{IVec3, Vec3};

use super::HairMesh;
use crate::density::DensityGrid;

const RES: i32 = 32;

impl HairMesh {
    /// Bakes AO into every layer vertex. `extinction` is optical depth per (strand count
    /// per voxel); larger values darken the groom's interior faster.
    pub fn bake_ao(&mut self, extinction: f32) {
        let Some(mut density) = DensityGrid::new(self.bounds(), IVec3::splat(RES)) else {
            return;
        };
        // Each bundle's strands are spread over its layers' quads.
        for bd in &self.bundles {
            let layers =
                &self.layers[bd.first_layer as usize..(bd.first_layer + bd.layer_count) as usize];
            let per = bd.strands as f32 / (layers.len() * 4) as f32;
            for l in layers {
                for p in l.positions {
                    density.add(p, per);
                }
            }
        }
        density.normalize_max();
        let marcher = density.marcher();
        let dirs = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        for l in &mut self.layers {
            for k in 0..4 {
                // March from the centre of the vertex's cell, one cell at a time.
                let start = density.cell_of(l.positions[k]).as_vec3() + 0.5;
                let sum: f32 = dirs
                    .iter()
                    .map(|&d| (-extinction * marcher.optical_depth(start, d, f32::INFINITY)).exp())
                    .sum();
                l.ao[k] = sum / dirs.len() as f32;
            }
        }
    }
}
