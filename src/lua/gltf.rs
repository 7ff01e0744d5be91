//! `gr.gltf(name, file [, {lights = true}])`: a glTF file's default scene as a `gr.node`
//! hierarchy that a script can transform and instance like any node.
//!
//! ```lua
//! room, lights = gr.gltf('room', 'room.glb', {lights = true})
//! room:translate(0, 1, 0)
//! scene:add_child(room)
//! gr.render(scene, 'room.png', 256, 256, eye, view, up, 50, {0, 0, 0}, lights)
//! ```
//!
//! The design, and why: the returned group (named `name`) holds one group per root glTF node,
//! each glTF node a `gr.node` named after it (`node N` without a name) carrying its local TRS or
//! matrix transform, its children below it. A node's glTF mesh is a mesh child of that group,
//! named after the mesh (`mesh N`): each glTF mesh is read once, alone and in its own frame
//! (`MeshSource::File::part`), by the loader `gr.mesh` uses, so materials, textures, roughness,
//! transmission, volume and emissive surfaces (lights wherever they are placed) are the same;
//! nodes sharing a mesh share its triangles. Only the file's JSON is read here (its hierarchy,
//! [`crate::io::gltf::hierarchy`]); buffers and images are read when a scene is built. Since
//! every mesh reads the whole file, the meshes times the file's bytes (buffers included) are
//! bounded ([`MAX_REREAD_BYTES`]): past it the script line is an error that names `gr.mesh`.
//!
//! The node `gr.gltf` returns is a group: `set_material` on it is an error, as on any
//! `gr.node`; the mesh children keep the file's materials.
//!
//! Punctual lights (`KHR_lights_punctual`) are ignored unless `{lights = true}`; then they are
//! converted as `caustic render file.glb` converts them ([`crate::io::gltf::scene`]) and returned
//! as a second value, a table of lights for `gr.render`'s light list. `gr.render` takes its
//! lights explicitly and lights live in world space (not in the node graph), so these are placed
//! where the file's own hierarchy puts them, in the file's frame: they do not follow later
//! transforms of the returned node or its instances. Without the option the second value is an
//! empty table.

use super::State;
use super::gr::{charge, input_fault, link, mesh_part_at};
use crate::desc::{LightDesc, LightId, MeshFormat, NodeDesc, NodeId, NodeKind};
use crate::error::Fault;
use crate::io::gltf::hierarchy::read_tree;
use crate::lua::args::{Args, LightRef, NodeRef};
use mlua::{Lua, MultiValue, Value};

/// Most bytes `gr.gltf` lets the scene build read for one file: its distinct meshes times what
/// reading the file once takes (each mesh is read alone, the whole file each time).
pub const MAX_REREAD_BYTES: u64 = 4 << 30;

/// The option keys `gr.gltf` takes, in its message's order.
const OPTIONS: &[&str] = &["lights"];

/// `gr.gltf(name, file [, options])`: returns the file's hierarchy as a node and a table of
/// its punctual lights (empty without `{lights = true}`).
pub(super) fn gr_gltf(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<MultiValue> {
    let name = a.string(1)?;
    let given = a.string(2)?;
    let lights = options(a)?;
    let path = s
        .resolve_input("glTF file", &given)
        .map_err(|m| a.fault(input_fault(&m), m))?;
    if MeshFormat::from_path(&path) != Some(MeshFormat::Gltf) {
        return Err(a.bad(2, format!("'{given}' is not a .gltf or .glb file")));
    }
    let tree = read_tree(&path, lights, &a.loc)
        .map_err(|e| a.fault(Fault::MeshLoad, format!("cannot load glTF '{given}': {e}")))?;
    // Each distinct mesh is read alone, the whole file each time: bound the work, so that a
    // file of a thousand meshes over a large buffer cannot keep the scene build reading for
    // hours.
    let meshes: std::collections::BTreeSet<u32> = tree
        .nodes
        .iter()
        .filter_map(|n| n.mesh.as_ref().map(|m| m.0))
        .collect();
    let work = (meshes.len() as u64).saturating_mul(tree.read_bytes);
    if work > MAX_REREAD_BYTES {
        return Err(a.fault(
            Fault::MeshLoad,
            format!(
                "glTF '{given}': its {} meshes would each read the file's {} bytes again (over                  {} GiB in all); gr.mesh reads it once, with the node transforms baked in",
                meshes.len(),
                tree.read_bytes,
                MAX_REREAD_BYTES >> 30
            ),
        ));
    }
    let root = add_node(s, a, name, NodeKind::Group)?;
    let mut ids: Vec<NodeId> = Vec::with_capacity(tree.nodes.len());
    for node in &tree.nodes {
        let id = add_node(s, a, node.name.clone(), NodeKind::Group)?;
        s.desc.nodes[id.0 as usize].transform = node.parent_from_node;
        // The file's matrix is the same in either dialect: one call, which both orders read
        // alike, so the legacy check ([`super::legacy`]) never counts it for either.
        if let Some(w) = &mut s.watch {
            w.compose(id, node.parent_from_node);
        }
        if let Some((index, mesh_name)) = &node.mesh {
            let mesh = mesh_part_at(s, a, &given, path.clone(), Some(*index))?;
            let child = add_node(s, a, mesh_name.clone(), NodeKind::Mesh(mesh))?;
            link(s, a, id, child)?;
        }
        ids.push(id);
    }
    for (node, &id) in tree.nodes.iter().zip(&ids) {
        for &c in &node.children {
            link(s, a, id, ids[c])?;
        }
    }
    for &r in &tree.roots {
        link(s, a, root, ids[r])?;
    }
    let table = lua.create_table()?;
    for light in tree.lights {
        charge(s, a, size_of::<LightDesc>(), "a light")?;
        let id = LightId(s.desc.lights.len() as u32);
        s.desc.lights.push(light);
        table.raw_push(lua.create_userdata(LightRef(id))?)?;
    }
    let node = Value::UserData(lua.create_userdata(NodeRef(root))?);
    Ok(MultiValue::from_iter([node, Value::Table(table)]))
}

/// Returns whether argument 3, the options table, asks for the file's punctual lights; an
/// unknown key, a non-boolean `lights` or a non-table is an error at the script line.
fn options(a: &Args) -> mlua::Result<bool> {
    let table = match a.get(3) {
        None | Some(Value::Nil) => return Ok(false),
        Some(Value::Table(t)) => t,
        Some(_) => return Err(a.bad(3, "options table expected, like {lights = true}")),
    };
    let mut lights = false;
    for pair in table.pairs::<Value, Value>() {
        let (key, value) = pair?;
        match (key.to_string().ok().as_deref(), value) {
            (Some("lights"), Value::Boolean(b)) => lights = b,
            (Some("lights"), _) => return Err(a.bad(3, "option 'lights' must be a boolean")),
            (key, _) => {
                return Err(a.bad(
                    3,
                    format!(
                        "unknown option '{}' (gr.gltf takes {})",
                        key.unwrap_or("?"),
                        OPTIONS.join(", ")
                    ),
                ));
            }
        }
    }
    Ok(lights)
}

/// Adds a node of `kind` named `name` made at `a`'s line, charged to the budget.
fn add_node(s: &mut State, a: &Args, name: String, kind: NodeKind) -> mlua::Result<NodeId> {
    let what = format!("a node named by {} bytes", name.len());
    charge(s, a, size_of::<NodeDesc>() + name.len(), &what)?;
    Ok(s.desc.add_node(name, kind, a.loc.clone()))
}
