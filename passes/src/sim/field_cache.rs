//! Head collision fields on disk, baked once per head and placement like
//! the self-shadowing bake ([`strandgraph_bake::blob`] files under
//! [`strandgraph_bake::cache_dir`]): a content hash of the mesh, the
//! groom's placement on it, the region and the padding names the file.
//! A file that cannot be trusted is logged and baked over; without a cache
//! directory every field is baked.

use glam::Mat4;
use std::path::Path;
use strandgraph_assets::Aabb;
use strandgraph_assets::mesh::TriMesh;
use strandgraph_assets::mesh_sdf::{MeshSdf, SDF_RES};
use strandgraph_bake::blob::Kind;

/// Version 1: `MeshSdf::bake` as of the first simulation (BVH closest
/// point, sign from the interpolated vertex normal).
const FILES: Kind = Kind {
    magic: b"SGHDSDF1",
    version: 1,
    name: "head_sdf",
};

/// The distances, then the grid's origin (3) and spacing (1).
const FLOATS: usize = SDF_RES * SDF_RES * SDF_RES + 4;

fn key(mesh: &TriMesh, to_mesh: Mat4, region: &Aabb, padding: f32) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"strandgraph head sdf");
    h.update(&(SDF_RES as u64).to_le_bytes());
    let floats = to_mesh
        .to_cols_array()
        .into_iter()
        .chain(region.min.to_array())
        .chain(region.max.to_array())
        .chain([padding])
        .chain(mesh.positions.iter().flat_map(|p| p.to_array()));
    for f in floats {
        h.update(&f.to_bits().to_le_bytes());
    }
    h.update(&(mesh.triangles.len() as u64).to_le_bytes());
    for t in mesh.triangles.iter().flatten() {
        h.update(&t.to_le_bytes());
    }
    *h.finalize().as_bytes()
}

/// [`MeshSdf::bake`] through the cache in `dir`.
pub fn bake(
    mesh: &TriMesh,
    to_mesh: Mat4,
    region: Aabb,
    padding: f32,
    dir: Option<&Path>,
) -> Option<MeshSdf> {
    let Some(dir) = dir else {
        return MeshSdf::bake(mesh, to_mesh, region, padding);
    };
    let key = key(mesh, to_mesh, &region, padding);
    let file = FILES.path(dir, &key);
    match FILES.read(&file, &key, 1, FLOATS) {
        Ok(Some(f)) => {
            let n = FLOATS - 4;
            return Some(MeshSdf {
                min: glam::Vec3::new(f[n], f[n + 1], f[n + 2]),
                voxel: f[n + 3],
                values: f[..n].to_vec(),
            });
        }
        Ok(None) => {}
        Err(why) => {
            tracing::error!(path = %file.display(), "unusable head collision field, baking again: {why}")
        }
    }
    let field = MeshSdf::bake(mesh, to_mesh, region, padding)?;
    let mut floats = field.values.clone();
    floats.extend(field.min.to_array());
    floats.push(field.voxel);
    if let Err(e) = FILES.write(&file, &key, 1, &floats) {
        tracing::error!(path = %file.display(), "could not cache the head collision field: {e}");
    }
    Some(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use strandgraph_assets::procedural::head::star_mesh;

    /// A second bake reads the first's file and gets the same field; a
    /// damaged file is baked over.
    #[test]
    fn fields_come_back_from_the_cache() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = star_mesh(|_| 0.1, 16);
        let region = mesh.bounds();
        let first = bake(&mesh, Mat4::IDENTITY, region, 0.01, Some(dir.path())).unwrap();
        let files: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(files.len(), 1);
        let file = files[0].as_ref().unwrap().path();
        let again = bake(&mesh, Mat4::IDENTITY, region, 0.01, Some(dir.path())).unwrap();
        assert_eq!(again, first);
        let mut bytes = std::fs::read(&file).unwrap();
        bytes[strandgraph_bake::blob::HEADER + 9] ^= 0x40;
        std::fs::write(&file, &bytes).unwrap();
        let key = key(&mesh, Mat4::IDENTITY, &region, 0.01);
        assert!(FILES.read(&file, &key, 1, FLOATS).is_err());
        let repaired = bake(&mesh, Mat4::IDENTITY, region, 0.01, Some(dir.path())).unwrap();
        assert_eq!(repaired, first);
        assert!(FILES.read(&file, &key, 1, FLOATS).unwrap().is_some());
    }
}
