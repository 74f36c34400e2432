//! Hair assets for strandgraph: the groom data model, loaders for real formats
//! (cyHair, TressFX 2/3/4, OBJ), procedural heads and grooms, hair meshes (Lipp §2),
//! root skinning (Kulikov) and RON scenes.
//!
//! Entry points:
//! - [`Scene::load`] parses a RON scene and builds or loads everything it names;
//!   [`Scene::counts`] gives the totals ([`SceneCounts`]) a render graph is sized by.
//! - [`load_groom`] / [`load_mesh`] read one file (.hair, .tfx 2/3/4, .obj); the
//!   `loaders::*::parse` functions parse bytes and report byte offsets or lines.
//! - [`Groom`]: structure-of-arrays strands; `shuffled` (Kulikov's stable random strand
//!   order), `lod_prefix`, `resampled`, `bounds`, `memory_bytes`.
//! - [`procedural::GroomParams::generate`] grows grooms (guides with gravity and head
//!   collisions, clumped children; straight, wavy, curly, long, bob, short, ponytail,
//!   bun, beard, eyebrows, eyelashes, fur) on a [`procedural::Surface`], such as the
//!   sculpted [`procedural::HeadParams`] head.
//! - [`hair_color`]: melanin and redness to absorption and colour (d'Eon 2011, Chiang 2016).
//! - [`HairMesh`]: `procedural`, `fit` (k-means bundles), `to_groom`, and
//!   [`hairmesh::strandgen::strand_point`], the (bundle, uv, w) -> point function (Lipp §2).
//! - [`hairpatch::HairPatches`]: layered, textured ribbon patches with baked per-vertex
//!   AO in a static inside-to-outside draw order, generated from any groom, and their
//!   procedural [`hairpatch::texture::HairTexture`] (Scheuermann 2004).
//! - [`mesh_sdf::MeshSdf::bake`]: a mesh's signed distance field for hair collisions (Kulikov).
//! - [`skinning::bake`]: `hairRootSkinningInfo_t` records for strand roots (Kulikov).

#![forbid(unsafe_code)]

pub mod bounds;
pub mod density;
pub mod error;
pub mod groom;
pub mod hair_color;
pub mod hairmesh;
pub mod hairpatch;
pub mod loaders;
pub mod mesh;
pub mod mesh_sdf;
pub mod octahedral;
pub mod procedural;
pub mod scene;
pub mod skinning;
pub mod transform;

pub use hairmesh::HairMesh;
pub use scene::{Scene, SceneCounts};

pub use bounds::Aabb;
pub use error::{AssetError, FormatError, FormatErrorKind, Location};
pub use groom::Groom;

pub use loaders::{LoadOptions, Units, load_groom, load_mesh};
pub use mesh::TriMesh;

pub use transform::Transform;

/// Smooth 0 → 1 as `x` goes from `a` to `b` (GLSL's `smoothstep`).
pub(crate) fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
