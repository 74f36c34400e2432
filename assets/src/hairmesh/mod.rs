//! Hair meshes, the input of the Lipp pipeline. Lipp §2 (after Bhokare et al. 2024 and
//! Yuksel et al. 2009): "Each bundle is formed by a set of L layers, with the first and
//! last layers placed at the hair roots and tips respectively. Each layer i is defined as
//! a polygonal shape (in our case, we use quads) with vertices v^i and associated
//! per-vertex tangents t^i and uvw coordinates." Lipp §3.5 adds a baked AO value per vertex.

pub mod ao;
pub mod fit;
pub mod procedural;
pub mod strandgen;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::bounds::Aabb;
use crate::transform::Transform;

pub use strandgen::StrandStyle;

/// One layer of a bundle: a quad. Corner k has (u, v) = `[(0,0), (1,0), (1,1), (0,1)][k]`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Layer {
    pub positions: [Vec3; 4],
    /// Unit tangents along the bundle (root to tip).
    pub tangents: [Vec3; 4],
    /// (u, v) of the corner and w = layer / (L - 1).
    pub uvw: [Vec3; 4],
    /// Baked ambient occlusion, 1 = unoccluded (Lipp §3.5).
    pub ao: [f32; 4],
}

/// The (u, v) of the four quad corners.
pub const CORNER_UV: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

/// A bundle: a stack of layers and the number of strands it generates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bundle {
    pub first_layer: u32,
    pub layer_count: u32,
    pub strands: u32,
    pub style: StrandStyle,
}

/// A groom as bundles of layered quads.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HairMesh {
    pub bundles: Vec<Bundle>,
    pub layers: Vec<Layer>,
    pub transform: Transform,
}

/// How to build a hair mesh for a groom in a scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HairMeshParams {
    pub bundles: u32,
    pub layers: u32,
    #[serde(default)]
    pub style: StrandStyle,
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_seed() -> u64 {
    1
}

/// The most bundles a hair mesh may ask for (Lipp's 127k-strand groom has 1,024).
pub const MAX_BUNDLES: u32 = 65_536;
/// The most layers a bundle may ask for.
pub const MAX_LAYERS: u32 = 64;

impl HairMeshParams {
    /// What is wrong with the parameters, if anything; the message names the
    /// field. Bounds what building the mesh allocates (bundles × layers quads).
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=MAX_BUNDLES).contains(&self.bundles) {
            return Err(format!(
                "bundles = {} must be in 1..={MAX_BUNDLES}",
                self.bundles
            ));
        }
        if !(2..=MAX_LAYERS).contains(&self.layers) {
            return Err(format!(
                "layers = {} must be in 2..={MAX_LAYERS}",
                self.layers
            ));
        }
        let s = &self.style;
        if ![s.curl_radius, s.curl_turns, s.twist, s.noise]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err("style: every number must be finite".into());
        }
        Ok(())
    }

    /// What a groom that declares no hair mesh is fitted with: a bundle per
    /// 128 strands (Lipp's 127k-strand groom has 1,024), 16 to 1,024 of
    /// them, and 8 layers.
    pub fn fitted_default(strands: usize) -> HairMeshParams {
        HairMeshParams {
            bundles: (strands / 128).clamp(16, 1024) as u32,
            layers: 8,
            style: StrandStyle::default(),
            seed: default_seed(),
        }
    }
}

impl HairMesh {
    pub fn bundle_count(&self) -> usize {
        self.bundles.len()
    }
    pub fn layer_count(&self) -> usize {
        self.layers.len()
    }
    pub fn strand_count(&self) -> usize {
        self.bundles.iter().map(|b| b.strands as usize).sum()
    }
    pub fn bundle_layers(&self, b: usize) -> &[Layer] {
        let bd = &self.bundles[b];
        &self.layers[bd.first_layer as usize..(bd.first_layer + bd.layer_count) as usize]
    }
    pub fn bounds(&self) -> Aabb {
        self.layers
            .iter()
            .flat_map(|l| l.positions)
            .fold(Aabb::EMPTY, Aabb::grow)
    }
    pub fn memory_bytes(&self) -> usize {
        self.layers.len() * std::mem::size_of::<Layer>()
            + self.bundles.len() * std::mem::size_of::<Bundle>()
    }

    /// Appends a bundle from per-layer corner positions; tangents and uvw are derived.
    pub fn push_bundle(&mut self, corners: &[[Vec3; 4]], strands: u32, style: StrandStyle) {
        let l = corners.len();
        if l < 2 {
            return;
        }
        let first = self.layers.len() as u32;
        for i in 0..l {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(l - 1));
            let w = i as f32 / (l - 1) as f32;
            let mut layer = Layer {
                positions: corners[i],
                ao: [1.0; 4],
                ..Default::default()
            };
            for k in 0..4 {
                layer.tangents[k] = (corners[b][k] - corners[a][k]).normalize_or_zero();
                layer.uvw[k] = Vec3::new(CORNER_UV[k][0], CORNER_UV[k][1], w);
            }
            self.layers.push(layer);
        }
        self.bundles.push(Bundle {
            first_layer: first,
            layer_count: l as u32,
            strands,
            style,
        });
    }

    /// Checks the invariants: layer ranges in bounds, two or more layers, finite data.
    pub fn validate(&self) -> Result<(), String> {
        for (i, b) in self.bundles.iter().enumerate() {
            if b.layer_count < 2 {
                return Err(format!("bundle {i} has fewer than 2 layers"));
            }
            if (b.first_layer + b.layer_count) as usize > self.layers.len() {
                return Err(format!("bundle {i} layers out of range"));
            }
        }
        if self.layers.iter().any(|l| {
            l.positions
                .iter()
                .chain(&l.tangents)
                .any(|p| !p.is_finite())
        }) {
            return Err("non-finite layer data".into());
        }
        Ok(())
    }
}
