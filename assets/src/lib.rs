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
//! - [`procedural::GroomParams::generate`] grows straight, wavy, curly, long, short,
//!   ponytail, beard, eyebrow and fur grooms on a [`procedural::Surface`].
//! - [`HairMesh`]: `procedural`, `fit` (k-means bundles), `to_groom`, and
//!   [`hairmesh::strandgen::strand_point`], the (bundle, uv, w) -> point function (Lipp §2).
//! - [`skinning::bake`]: `hairRootSkinningInfo_t` records for strand roots (Kulikov).

#![forbid(unsafe_code)]

pub mod bounds;
pub mod error;
pub mod groom;
pub mod hairmesh;
pub mod loaders;
pub mod mesh;
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
