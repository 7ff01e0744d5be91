//! The built-in `readobj`: the legacy course's Lua OBJ reader, served by caustic's OBJ parser.
//!
//! Legacy scripts load meshes in Lua: `require('readobj')` defines the global function
//! `readobj(file)`, which returns the vertex and face tables of the inline form of `gr.mesh`.
//! A script's own `readobj.lua` wins (found like any module: the working directory, then the
//! script's folder); without one, `require('readobj')` gets this one, in both dialects. It reads
//! the file with [`crate::io::obj`], so a broken file fails at the `readobj` line with the
//! parser's file and line, and returns vertices `{{x, y, z}, ...}` and faces `{{i, j, k}, ...}`
//! (0-based; n-gons are fanned into triangles, as `gr.mesh` fans an inline n-gon). Like the
//! course's reader it keeps positions and faces only: normals, texture coordinates and
//! materials in the file are dropped.
//!
//! ```lua
//! require('readobj')
//! cow = gr.mesh('cow', readobj('cow.obj'))   -- the triangles of gr.mesh('cow', 'cow.obj')
//! ```

use super::Sign;
use crate::error::Fault;
use crate::lua::State;
use crate::lua::args::Args;
use mlua::{Lua, MultiValue, Table, Value};
use std::cell::RefCell;
use std::rc::Rc;

/// The module name legacy scripts `require`.
const MODULE: &str = "readobj";

/// Appends a searcher to `package.searchers` that serves `require('readobj')` with the built-in
/// when the searchers before it (preloads, then files on `package.path`) found nothing.
pub(in crate::lua) fn install(lua: &Lua, state: &Rc<RefCell<State>>) -> mlua::Result<()> {
    let st = Rc::clone(state);
    let readobj = lua.create_function(move |lua, vals: MultiValue| {
        let args = Args::new(lua, MODULE, vals);
        let mut s = st
            .try_borrow_mut()
            .map_err(|_| args.fail("readobj called while a render is running"))?;
        read(lua, &mut s, &args)
    })?;
    // `require` calls the loader once and caches what it returns (true: the module defines a
    // global, as readobj.lua does).
    let loader = lua.create_function(move |lua, _: MultiValue| {
        lua.globals().set(MODULE, readobj.clone())?;
        Ok(true)
    })?;
    let searcher = lua.create_function(move |lua, name: mlua::LuaString| {
        if name.as_bytes() == MODULE.as_bytes() {
            return Ok(Value::Function(loader.clone()));
        }
        let why = format!("\n\tno built-in module '{}'", name.to_string_lossy());
        Ok(Value::String(lua.create_string(why)?))
    })?;
    let package: Table = lua.globals().get("package")?;
    let searchers: Table = package.get("searchers")?;
    searchers.raw_push(searcher)
}

/// `readobj(file)`: returns the vertex and face tables of an OBJ file.
fn read(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<MultiValue> {
    let given = a.string(1)?;
    s.saw(Sign::Readobj, &a.loc);
    let path = s
        .resolve_input("mesh file", &given)
        .map_err(|m| a.fault(crate::lua::gr::input_fault(&m), m))?;
    let account = s.desc.budget.account();
    let mesh = crate::io::obj::load_obj_with(&path, &account).map_err(|e| {
        a.fault(
            Fault::MeshLoad,
            format!("readobj: cannot load mesh '{given}': {e}"),
        )
    })?;
    let verts = lua.create_table_with_capacity(mesh.positions.len(), 0)?;
    for p in &mesh.positions {
        verts.raw_push(lua.create_sequence_from([p.x as f64, p.y as f64, p.z as f64])?)?;
    }
    let faces = lua.create_table_with_capacity(mesh.triangles.len(), 0)?;
    for t in &mesh.triangles {
        faces.raw_push(lua.create_sequence_from(t.map(i64::from))?)?;
    }
    Ok(MultiValue::from_vec(vec![
        Value::Table(verts),
        Value::Table(faces),
    ]))
}
