//! Hair assets for strandgraph: the groom data model, loaders for real formats
//! (cyHair, TressFX 2/3/4, OBJ), procedural heads and grooms, hair meshes (Lipp §2),
//! root skinning (Kulikov) and RON scenes.

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
