//! The inline form of `gr.mesh`: vertex and face tables given in the script itself (the legacy
//! course's form, and what `readobj` returns), checked element by element.
//!
//! Every fault is lauxlib's bad-argument error at the calling line, naming the element:
//! `scene.lua:3: bad argument #3 to 'mesh' (face 1, index 3: integer expected, got string)`.
//! Vertices are 3-tuples of numbers within the renderer's coordinate range
//! ([`crate::range::MAX_COORDINATE`]); faces are sequences of at least three 0-based
//! integer indices into the vertices, convex and fanned into triangles when the scene is built.
//! Tables are read by their raw length, so a hole (`{0, 1, nil, 2}`) is an element that is
//! `nil`, reported as such rather than cutting the face short.
//!
//! ```lua
//! quad = gr.mesh('quad', {{0,0,0}, {1,0,0}, {1,1,0}, {0,1,0}}, {{0, 1, 2, 3}})
//! ```

use super::State;
use super::args::{Args, type_name};
use crate::desc::{MeshDesc, MeshId, MeshSource};
use glam::DVec3;
use mlua::{Table, Value};

/// Reads `gr.mesh(name, vertices, faces)`'s tables (arguments 2 and 3) into a new mesh.
pub(super) fn inline_mesh(s: &mut State, a: &Args) -> mlua::Result<MeshId> {
    let Some(Value::Table(verts)) = a.get(2) else {
        return Err(a.bad(2, "table of vertices expected"));
    };
    let Some(Value::Table(face_table)) = a.get(3) else {
        let got = a.get(3).map_or("no value".to_owned(), type_name);
        return Err(a.bad(3, format!("table of faces expected, got {got}")));
    };
    let positions = vertices(a, verts)?;
    let faces = faces(a, face_table, positions.len())?;
    let corners: usize = faces.iter().map(Vec::len).sum();
    let bytes = size_of::<MeshDesc>()
        + positions.len() * size_of::<DVec3>()
        + faces.len() * size_of::<Vec<u32>>()
        + corners * size_of::<u32>();
    super::gr::charge(s, a, bytes, "an inline mesh's vertices and faces")?;
    let id = MeshId(s.desc.meshes.len() as u32);
    s.desc.meshes.push(MeshDesc {
        source: MeshSource::Inline { positions, faces },
        loc: a.loc.clone(),
    });
    Ok(id)
}

/// Returns the positions of the vertex table, argument 2.
fn vertices(a: &Args, verts: &Table) -> mlua::Result<Vec<DVec3>> {
    let n = verts.raw_len();
    let mut positions = Vec::with_capacity(n);
    for k in 1..=n {
        let t = match verts.raw_get::<Value>(k)? {
            Value::Table(t) if t.raw_len() == 3 => t,
            Value::Table(t) => {
                let message = format!("vertex {k}: 3-tuple expected, got {} entries", t.raw_len());
                return Err(a.bad(2, message));
            }
            other => {
                let message = format!("vertex {k}: 3-tuple expected, got {}", type_name(&other));
                return Err(a.bad(2, message));
            }
        };
        let mut p = [0.0; 3];
        for (j, slot) in p.iter_mut().enumerate() {
            let element = format!("vertex {k}, entry {}", j + 1);
            *slot = a.element_number(2, &element, t.raw_get(j + 1)?)?;
        }
        if let Err(e) = crate::range::coordinate(p) {
            return Err(a.bad(2, format!("vertex {k}: {e}")));
        }
        positions.push(DVec3::from_array(p));
    }
    Ok(positions)
}

/// Returns the faces of the face table, argument 3, as indices below `nv`.
fn faces(a: &Args, face_table: &Table, nv: usize) -> mlua::Result<Vec<Vec<u32>>> {
    let n = face_table.raw_len();
    let mut faces = Vec::with_capacity(n);
    for k in 1..=n {
        let f = match face_table.raw_get::<Value>(k)? {
            Value::Table(f) => f,
            other => {
                let got = type_name(&other);
                return Err(a.bad(3, format!("face {k} is not a table (got {got})")));
            }
        };
        let corners = f.raw_len();
        if corners < 3 {
            return Err(a.bad(3, format!("face {k} has fewer than 3 vertices")));
        }
        let mut idx = Vec::with_capacity(corners);
        for j in 1..=corners {
            let element = format!("face {k}, index {j}");
            let i = a.element_integer(3, &element, f.raw_get(j)?)?;
            if !(0..nv as i64).contains(&i) {
                return Err(a.bad(3, format!("face {k}: index {i} out of range (0..{nv})")));
            }
            idx.push(i as u32);
        }
        faces.push(idx);
    }
    Ok(faces)
}
