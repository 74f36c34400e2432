//! RON scene files: resolution, camera, lights, environment, meshes, grooms and the render
//! graph to run. Paths inside a scene are relative to the scene file.
//!
//! Scenes are parsed with the RON extensions `unwrap_variant_newtypes` and `implicit_some`,
//! so a procedural source reads `Procedural(style: Long, strands: 40000)` and optional
//! values need no `Some(..)`.

mod load;

use serde::{Deserialize, Serialize};

use crate::hairmesh::HairMeshParams;
use crate::loaders::Units;
use crate::procedural::{BodyParams, GroomParams, HeadParams};
use crate::transform::Transform;

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
    /// Kulikov's "fedora culling" shapes around a hat, in world space.
    #[serde(default)]
    pub fedora: Option<Fedora>,
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

/// Hair appearance: melanin concentration or a colour, and roughness. The
/// cuticle tilt is the shading pass's parameter (`kulikov.shade`'s `shift`;
/// Chiang's fixed α in `lipp.shade`), not the material's: a key nothing read
/// would be accepted and do nothing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Eumelanin concentration (0 = white, about 1.3 = black). Ignored when `color` is set.
    pub melanin: Option<f32>,
    /// A direct linear RGB colour instead of melanin.
    pub color: Option<[f32; 3]>,
    /// Longitudinal roughness in [0, 1].
    pub roughness: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            melanin: Some(0.6),
            color: None,
            roughness: 0.3,
        }
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
