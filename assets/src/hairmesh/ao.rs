//! Baked ambient occlusion per hair-mesh vertex (Lipp §3.5: "pre-bake an ambient occlusion
//! value in each vertex of the hair mesh proxy"). Strand density is splatted into a voxel
//! grid; a vertex's AO is the mean transmittance along six axis directions.

use glam::{IVec3, Vec3};

use super::HairMesh;

const RES: i32 = 32;

impl HairMesh {
    /// Bakes AO into every layer vertex. `extinction` is optical depth per (strand count
    /// per voxel); larger values darken the groom's interior faster.
    pub fn bake_ao(&mut self, extinction: f32) {
        let b = self.bounds();
        if b.is_empty() {
            return;
        }
        let size = b.size().max(Vec3::splat(1e-4));
        let cell = size / RES as f32;
        let idx = |p: Vec3| -> IVec3 {
            ((p - b.min) / cell)
                .floor()
                .as_ivec3()
                .clamp(IVec3::ZERO, IVec3::splat(RES - 1))
        };
        let flat = |c: IVec3| (c.x + RES * (c.y + RES * c.z)) as usize;
        let mut density = vec![0f32; (RES * RES * RES) as usize];
        // Each bundle's strands are spread over its layers' quads.
        for bd in &self.bundles {
            let layers =
                &self.layers[bd.first_layer as usize..(bd.first_layer + bd.layer_count) as usize];
            let per = bd.strands as f32 / (layers.len() * 4) as f32;
            for l in layers {
                for p in l.positions {
                    density[flat(idx(p))] += per;
                }
            }
        }
        let max = density.iter().copied().fold(0.0, f32::max).max(1e-6);
        density.iter_mut().for_each(|d| *d /= max);
        let dirs = [
            IVec3::X,
            IVec3::NEG_X,
            IVec3::Y,
            IVec3::NEG_Y,
            IVec3::Z,
            IVec3::NEG_Z,
        ];
        for l in &mut self.layers {
            for k in 0..4 {
                let start = idx(l.positions[k]);
                let mut sum = 0.0;
                for d in dirs {
                    let mut c = start + d;
                    let mut depth = 0.0;
                    while c.cmpge(IVec3::ZERO).all() && c.cmplt(IVec3::splat(RES)).all() {
                        depth += density[flat(c)];
                        c += d;
                    }
                    sum += (-extinction * depth).exp();
                }
                l.ao[k] = sum / dirs.len() as f32;
            }
        }
    }
}
