//! Triangle meshes in object space: the plain data every loader produces.
//!
//! A [`MeshData`] is shared by every node that instances it (`Arc`), so a mesh
//! placed ten times is stored once. Vertex attributes are indexed by one index
//! per corner (loaders unify `v/vt/vn` triples into single vertices).

use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// A triangle mesh as loaded from a file, in the object space of its node.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions; every entry is finite (loaders reject NaN and infinity).
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, parallel to `positions`, or empty when the file has none.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, parallel to `positions`, or empty when the file has none.
    pub uvs: Vec<Vec2>,
    /// Triangles as indices into `positions` (always in range).
    pub triangles: Vec<[u32; 3]>,
    /// The file this mesh was read from, for messages.
    pub source: PathBuf,
}

impl MeshData {
    /// Returns the number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}
