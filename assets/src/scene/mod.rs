//! RON scene files: resolution, camera, lights, environment, meshes, grooms and the render
//! graph to run. Paths inside a scene are relative to the scene file.
//!
//! Scenes are parsed with the RON extensions `unwrap_variant_newtypes` and `implicit_some`,
//! so a procedural source reads `Procedural(style: Long, strands: 40000)` and optional
//! values need no `Some(..)`.

mod animation;
mod check;
mod load;

use serde::{Deserialize, Serialize};

use crate::hairmesh::HairMeshParams;
use crate::hairpatch::PatchParams;
use crate::loaders::Units;
use crate::procedural::{BodyParams, GroomParams, HeadParams};
use crate::transform::Transform;

pub use animation::{Animation, CameraKey, Joint, JointKey, Pose};
pub use check::{MAX_BODY_RESOLUTION, MAX_RESOLUTION};
pub use load::{Scene, SceneCounts, SceneGroom, SceneMesh};

/// The scene file's contents, before anything is loaded or generated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneDesc {
    /// Output size in pixels (width, height).
    pub resolution: (u32, u32),
    pub camera: Camera,
    #[serde(default)]
    pub lights: Vec<Light>,
    #[serde(default)]
    pub environment: Option<Environment>,
    #[serde(default)]
    pub meshes: Vec<MeshDesc>,
    #[serde(default)]
    pub grooms: Vec<GroomDesc>,
    /// The render graph to run, relative to the scene file (e.g. "graphs/kulikov.ron").
    pub graph: String,
    /// Joints and a camera path ([`Scene::pose_at`]); a scene without one is still.
    #[serde(default)]
    pub animation: Option<Animation>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Camera {
    LookAt {
        position: [f32; 3],
        target: [f32; 3],
        fov_deg: f32,
    },
    /// A camera on a sphere about `target`: yaw about +y from +z, pitch up from the horizon.
    Orbit {
        target: [f32; 3],
        distance: f32,
        yaw_deg: f32,
        pitch_deg: f32,
        fov_deg: f32,
    },
}

impl Camera {
    /// (eye position, target, vertical field of view in degrees).
    pub fn eye_target_fov(&self) -> ([f32; 3], [f32; 3], f32) {
        match *self {
            Camera::LookAt {
                position,
                target,
                fov_deg,
            } => (position, target, fov_deg),
            Camera::Orbit {
                target,
                distance,
                yaw_deg,
                pitch_deg,
                fov_deg,
            } => {
                let (y, p) = (yaw_deg.to_radians(), pitch_deg.to_radians());
                let eye = [
                    target[0] + distance * p.cos() * y.sin(),
                    target[1] + distance * p.sin(),
                    target[2] + distance * p.cos() * y.cos(),
                ];
                (eye, target, fov_deg)
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Light {
    Directional {
        /// The direction the light travels.
        direction: [f32; 3],
        color: [f32; 3],
        intensity: f32,
    },
    Point {
        position: [f32; 3],
        color: [f32; 3],
        intensity: f32,
    },
}

/// Ambient light: a constant colour, optionally an environment map (path relative to the scene).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Environment {
    pub color: [f32; 3],
    pub intensity: f32,
    #[serde(default)]
    pub map: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    pub name: String,
    pub source: MeshSource,
    #[serde(default)]
    pub transform: Transform,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum MeshSource {
    /// The procedural head: a deformed ellipsoid with a neck.
    Head(HeadParams),
    /// The procedural furry body.
    Body(BodyParams),
    /// A Wavefront OBJ file.
    File {
        path: String,
        #[serde(default)]
        units: Units,
    },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroomDesc {
    pub name: String,
    pub source: GroomSource,
    /// The mesh the groom grows on and is skinned to (by name). Procedural grooms need one.
    #[serde(default)]
    pub parent: Option<String>,
    /// Placement relative to the parent mesh (or the world without a parent).
    #[serde(default)]
    pub transform: Transform,
    #[serde(default)]
    pub material: Material,
    #[serde(default)]
    pub lod: LodSettings,
    /// Facial hair (beards, brows) gets a composition sort bias.
    #[serde(default)]
    pub facial_hair: bool,
    /// Build a hair mesh (Lipp §2) for this groom: fitted to the strands, or, for a
    /// `HairMesh` source, generated procedurally.
    #[serde(default)]
    pub hair_mesh: Option<HairMeshParams>,
    /// Scheuermann: how the groom's hair patches are generated (default PatchParams).
    #[serde(default)]
    pub patches: Option<PatchParams>,
    /// Kulikov's "fedora culling" shapes around a hat, in world space.
    #[serde(default)]
    pub fedora: Option<Fedora>,
    /// Simulate the strands (Kulikov: "Enabled per asset by artists"): the
    /// PBD pass moves them with gravity and the parent's joint, against
    /// the parent mesh's signed distance field. Off, they follow the
    /// parent rigidly.
    #[serde(default)]
    pub simulate: bool,
}

/// Kulikov: segments inside the exclusion box are culled unless they are
/// inside the inclusion sphere ("to accommodate area under fedora").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fedora {
    pub box_min: [f32; 3],
    pub box_max: [f32; 3],
    pub sphere_center: [f32; 3],
    pub sphere_radius: f32,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum GroomSource {
    /// Grown on the parent mesh by a generator.
    Procedural(GroomParams),
    /// Strands generated from a procedural hair mesh shaped like the given guide strands
    /// (needs `hair_mesh`); `strands` and `points` of the guide give the groom's size.
    HairMesh(GroomParams),
    /// A groom file (.hair, .tfx).
    File {
        path: String,
        #[serde(default)]
        units: Units,
        /// Overrides the strand thickness (metres).
        #[serde(default)]
        thickness: Option<f32>,
    },
}

/// Hair appearance: pigments (or a colour), roughness and cuticle tilt.
/// Every pipeline takes its colour from [`Material::color`] and its cuticle
/// tilt from `highlight_shift_deg`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Total melanin concentration on Chiang 2016's scale (σa per unit
    /// concentration, see [`crate::hair_color`]): about 0.1 platinum, 0.3
    /// blond, 1.3 brown, 8 black. Ignored when `color` is set.
    pub melanin: Option<f32>,
    /// The fraction of the melanin that is pheomelanin (0 = none, 1 = all):
    /// auburn and red hair.
    pub redness: f32,
    /// A dye's linear RGB colour, added as a second absorber.
    pub dye: Option<[f32; 3]>,
    /// A direct linear RGB colour instead of pigments.
    pub color: Option<[f32; 3]>,
    /// Longitudinal roughness in [0, 1] (also Chiang's βn for the colour).
    pub roughness: f32,
    /// Cuticle scale tilt α in degrees: shifts R's highlight towards the tip by
    /// α, TRT's towards the root by about 1.5α (Marschner 2003, Chiang 2016).
    pub highlight_shift_deg: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            melanin: Some(0.6),
            redness: 0.0,
            dye: None,
            color: None,
            roughness: 0.3,
            highlight_shift_deg: 2.0,
        }
    }
}

impl Material {
    /// The linear RGB colour the shading models take: `color` if set, else
    /// the colour of the pigments' (and dye's) absorption (Chiang 2016 Eq. 9).
    pub fn color(&self) -> [f32; 3] {
        use crate::hair_color::{color_from_sigma_a, sigma_a_from_color, sigma_a_from_melanin};
        if let Some(c) = self.color {
            return c;
        }
        let beta_n = self.roughness.clamp(0.02, 1.0);
        let mut sigma = sigma_a_from_melanin(self.melanin.unwrap_or(0.0), self.redness);
        if let Some(dye) = self.dye {
            let d = sigma_a_from_color(dye, beta_n);
            sigma = [0, 1, 2].map(|i| sigma[i] + d[i]);
        }
        color_from_sigma_a(sigma, beta_n)
    }

    /// What is wrong with the material, if anything.
    pub fn validate(&self) -> Result<(), String> {
        let unit = |x: f32| (0.0..=1.0).contains(&x);
        if self.melanin.is_some_and(|m| !(0.0..=50.0).contains(&m)) {
            return Err("melanin must be in 0..=50".into());
        }
        if !unit(self.redness) {
            return Err("redness must be in 0..=1".into());
        }
        if !unit(self.roughness) {
            return Err("roughness must be in 0..=1".into());
        }
        if !(-10.0..=10.0).contains(&self.highlight_shift_deg) {
            return Err("highlight_shift_deg must be in -10..=10".into());
        }
        for c in self.color.iter().chain(self.dye.iter()) {
            if !c.iter().all(|&x| unit(x)) {
                return Err("colours are linear RGB in 0..=1".into());
            }
        }
        Ok(())
    }
}

/// Level-of-detail settings (Kulikov: prefix of a randomized strand order; Lipp §3.2:
/// per-bundle strand counts with sensitivity lambda).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LodSettings {
    pub enabled: bool,
    /// Seed of the stable random strand order.
    pub shuffle_seed: u64,
    /// Never draw fewer than this fraction of the strands.
    pub min_fraction: f32,
    /// LOD strength (Lipp's λ of Eq. 2, per groom as in Lipp Fig. 1),
    /// multiplying the Lipp graph's `lod.lambda`; 0 draws the groom at full detail.
    pub lambda: f32,
}

impl Default for LodSettings {
    fn default() -> Self {
        LodSettings {
            enabled: true,
            shuffle_seed: 0x5eed,
            min_fraction: 0.05,
            lambda: 1.0,
        }
    }
}
