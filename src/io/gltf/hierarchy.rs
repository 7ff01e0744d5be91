//! A glTF file's node hierarchy as plain data, for `gr.gltf` to rebuild as `gr.node`s: each
//! node of the default scene with its name, local transform, mesh and children, and (when asked)
//! the file's punctual lights in the file's world space.
//!
//! Only the JSON (or the GLB's JSON chunk) is read here: no buffer and no image, so a script can
//! describe a large file cheaply and the meshes are read when a scene is built
//! ([`super::load_gltf_mesh_with`], one glTF mesh at a time, in the mesh's own frame). The walk is
//! the mesh loader's own ([`super::placements`]: the default scene, else scene 0, else every root;
//! node cycles and shared children rejected), so a file rebuilt node by node draws what
//! `gr.mesh` of it draws; the node count is that of the file, bounded by its size.
//!
//! ```lua
//! room, lights = gr.gltf('room', 'room.glb', {lights = true})
//! ```

use super::scene::{MAX_LIGHTS, punctual_light, scene_bounds};
use super::{GltfError, placements, read_document};
use crate::desc::LightDesc;
use crate::error::Loc;
use glam::DAffine3;
use std::path::Path;

/// One node of a file's default scene.
#[derive(Clone, Debug, PartialEq)]
pub struct FileNode {
    /// The glTF node's name, or `node N` by its index.
    pub name: String,
    /// The node's TRS or matrix transform: `parent_from_node`.
    pub parent_from_node: DAffine3,
    /// The glTF mesh the node holds, by its index in the file, and its name (or `mesh N`).
    pub mesh: Option<(u32, String)>,
    /// The node's children, as positions in [`FileTree::nodes`].
    pub children: Vec<usize>,
}

/// A file's default scene: its nodes in depth-first order, the roots first among their subtrees.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileTree {
    pub nodes: Vec<FileNode>,
    /// The scene's root nodes, as positions in [`FileTree::nodes`].
    pub roots: Vec<usize>,
    /// The punctual lights the scene places, in the file's world space (empty unless asked).
    pub lights: Vec<LightDesc>,
    /// What reading the file once takes, in bytes: the file and every buffer it declares (its
    /// own binary chunk, external files and `data:` URIs alike, by their `byteLength`).
    pub read_bytes: u64,
}

/// Reads the node hierarchy of the glTF file at `path`, and its punctual lights when `lights`
/// (tagged `loc`, in the units [`super::scene`] gives them); errors name the file, and a bad
/// light its name.
pub fn read_tree(path: &Path, lights: bool, loc: &Loc) -> Result<FileTree, GltfError> {
    let (doc, file_bytes) = read_document(path)?;
    let invalid = |message: String| GltfError::Invalid {
        path: path.to_owned(),
        message,
    };
    let placed = placements(&doc).map_err(invalid)?;
    let mut position = vec![usize::MAX; doc.nodes().len()];
    for (k, (node, _)) in placed.iter().enumerate() {
        position[node.index()] = k;
    }
    let mut tree = FileTree {
        read_bytes: file_bytes
            .saturating_add(doc.buffers().map(|b| b.length() as u64).sum::<u64>()),
        ..FileTree::default()
    };
    let mut is_child = vec![false; placed.len()];
    for (node, _) in &placed {
        let children: Vec<usize> = node.children().map(|c| position[c.index()]).collect();
        for &c in &children {
            is_child[c] = true;
        }
        let mesh = node.mesh().map(|m| {
            let name = m
                .name()
                .map_or(format!("mesh {}", m.index()), str::to_owned);
            (m.index() as u32, name)
        });
        tree.nodes.push(FileNode {
            name: node
                .name()
                .map_or(format!("node {}", node.index()), str::to_owned),
            parent_from_node: super::local_transform(node).map_err(invalid)?,
            mesh,
            children,
        });
    }
    tree.roots = (0..placed.len()).filter(|&k| !is_child[k]).collect();
    if lights {
        let bounds = scene_bounds(&placed);
        for (node, world) in &placed {
            let Some(light) = node.light() else { continue };
            if tree.lights.len() == MAX_LIGHTS {
                return Err(GltfError::Unsupported {
                    path: path.to_owned(),
                    message: format!(
                        "more than {MAX_LIGHTS} punctual lights (node {}); caustic samples \
                         every light at every shaded point",
                        node.index()
                    ),
                });
            }
            tree.lights
                .push(punctual_light(&light, world, bounds, loc).map_err(invalid)?);
        }
    }
    Ok(tree)
}
