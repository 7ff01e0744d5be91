//! Loads the meshes a description names, once per file per scene build.
//!
//! The description holds what `gr.mesh` was given (a resolved path, or the legacy inline vertex
//! and face lists); reading the file happens here, when a scene is built, through the loaders of
//! [`crate::io`]. A file that cannot be read or parsed is an error naming the `gr.mesh` line and
//! the file's own line:
//!
//! ```text
//! scene.lua:12: cannot load mesh 'cow.obj': cow.obj:88: face index 9 out of range (file has 8 vertices)
//! ```
//!
//! ```lua
//! cow  = gr.mesh('cow', 'cow.obj')
//! quad = gr.mesh('quad', {{0,0,0}, {1,0,0}, {1,1,0}, {0,1,0}}, {{0, 1, 2, 3}})
//! ```

use crate::budget::{Account, At};
use crate::desc::{MeshDesc, MeshFormat, MeshId, MeshSource, SceneDesc};
use crate::error::{Error, Fault, Result};
use crate::geometry::mesh::MeshData;
use crate::io::{gltf, obj};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// Meshes loaded so far by one scene build: each file read once, each mesh id resolved once.
#[derive(Default)]
pub struct MeshCache {
    by_id: HashMap<MeshId, Arc<MeshData>>,
    /// Keyed by the file and the glTF mesh read alone (`None`: the whole file).
    by_path: HashMap<(PathBuf, Option<u32>), Arc<MeshData>>,
    /// Where the loaders charge what they read; `None` draws on each description's budget.
    account: Option<Account>,
}

impl MeshCache {
    /// Returns an empty cache charging each description's own budget.
    pub fn new() -> MeshCache {
        MeshCache::default()
    }

    /// Returns an empty cache whose loaders charge `account`.
    pub fn with_account(account: Account) -> MeshCache {
        MeshCache {
            account: Some(account),
            ..MeshCache::default()
        }
    }

    /// Returns the data of mesh `id` of `desc`, reading its file on first use.
    pub fn get(&mut self, desc: &SceneDesc, id: MeshId) -> Result<Arc<MeshData>> {
        if let Some(data) = self.by_id.get(&id) {
            return Ok(Arc::clone(data));
        }
        let mesh = &desc.meshes[id.0 as usize];
        let account = self
            .account
            .get_or_insert_with(|| desc.budget.account())
            .clone();
        let load_mesh = |mesh| load_mesh(mesh, &account);
        let data = match &mesh.source {
            MeshSource::File { path, part, .. } => match self.by_path.get(&(path.clone(), *part)) {
                Some(data) => Arc::clone(data),
                None => {
                    let data = Arc::new(load_mesh(mesh)?);
                    self.by_path
                        .insert((path.clone(), *part), Arc::clone(&data));
                    data
                }
            },
            MeshSource::Inline { .. } => Arc::new(load_mesh(mesh)?),
        };
        self.by_id.insert(id, Arc::clone(&data));
        Ok(data)
    }
}

/// Returns the triangles of `mesh`: its file read by the loader of its format, or its inline
/// faces fanned into triangles; what is read is charged to `account` before it is allocated.
pub fn load_mesh(mesh: &MeshDesc, account: &Account) -> Result<MeshData> {
    match &mesh.source {
        MeshSource::File {
            given,
            path,
            format,
            part,
        } => {
            let cannot = |e: &dyn std::fmt::Display| {
                Error::fault_at(
                    Fault::MeshLoad,
                    &mesh.loc,
                    format!("cannot load mesh '{given}': {e}"),
                )
            };
            match format {
                MeshFormat::Obj => obj::load_obj_with(path, account).map_err(|e| cannot(&e)),
                MeshFormat::Gltf => {
                    gltf::load_gltf_mesh_with(path, *part, account).map_err(|e| cannot(&e))
                }
            }
        }
        MeshSource::Inline { positions, faces } => {
            let triangles: usize = faces.iter().map(|f| f.len().saturating_sub(2)).sum();
            let bytes = (positions.len() * size_of::<glam::Vec3>()
                + triangles * size_of::<[u32; 3]>()) as u64;
            let what = format!("the inline mesh's {triangles} triangles");
            account.charge(bytes, what, At::Script(&mesh.loc))?;
            let mut data = MeshData {
                source: PathBuf::from(format!("{} (inline mesh)", mesh.loc)),
                positions: positions.iter().map(|p| p.as_vec3()).collect(),
                ..Default::default()
            };
            for face in faces {
                for j in 1..face.len().saturating_sub(1) {
                    data.triangles.push([face[0], face[j], face[j + 1]]);
                }
            }
            Ok(data)
        }
    }
}

/// Returns the data of every mesh of `desc`, in [`SceneDesc::meshes`] order (for `caustic info`).
pub fn load_meshes(desc: &SceneDesc) -> Result<Vec<Arc<MeshData>>> {
    let mut cache = MeshCache::new();
    (0..desc.meshes.len() as u32)
        .map(|i| cache.get(desc, MeshId(i)))
        .collect()
}
