//! The course's legacy API (before Fall 2015): how caustic reads it.
//!
//! Legacy scripts differ from modern ones in four ways (`cs488_lua_api.md` §0):
//! - **transform order**: each node's calls compose by post-multiplication, `M ← M·T`, so
//!   `n:translate(..); n:rotate(..)` rotates the geometry first (each call in the node's own
//!   frame), where the modern starter pre-multiplies, `M ← T·M` (each call in the parent's frame,
//!   in call order). `--dialect legacy` reads scripts the legacy way; [`Dialect::compose`] is the
//!   one place the order becomes a matrix;
//! - **inline meshes**: `gr.mesh(name, {{x,y,z}, ...}, {{i,j,k,...}, ...})`, accepted in both
//!   dialects;
//! - **OBJ files read in Lua** by `readobj.lua`: `require('readobj')`, then
//!   `gr.mesh('cow', readobj('cow.obj'))`; [`readobj`] is the built-in that serves it;
//! - **Lua 5.1 names**: `unpack`, `string.gfind` and `table.getn`, aliased (`sandbox.rs`) in both
//!   dialects.
//!
//! ```lua
//! require('readobj')
//! cow = gr.mesh('cow', readobj('cow.obj'))
//! cow:translate(0, 1, 0); cow:scale(2, 2, 2)  -- legacy: scaled, then moved up by 1
//! ```

mod readobj;

use crate::lua::State;
use glam::DAffine3;
use mlua::Lua;
use std::cell::RefCell;
use std::rc::Rc;

/// Which era of the course's API a script is written for; it decides how transforms compose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dialect {
    /// Fall 2015 onwards: each call pre-multiplies, `M ← T·M`, and acts in the parent's frame in
    /// call order.
    #[default]
    Modern,
    /// Before Fall 2015: each call post-multiplies, `M ← M·T`, and acts in the node's own frame,
    /// so the last call touches the geometry first.
    Legacy,
}

impl Dialect {
    /// Returns node matrix `m` with the transform `t` of one more call composed in.
    pub fn compose(self, m: DAffine3, t: DAffine3) -> DAffine3 {
        match self {
            Dialect::Modern => t * m,
            Dialect::Legacy => m * t,
        }
    }
}

/// Sets the built-in `readobj` module in `lua` ([`readobj`]).
pub(in crate::lua) fn install(lua: &Lua, state: &Rc<RefCell<State>>) -> mlua::Result<()> {
    readobj::install(lua, state)
}
