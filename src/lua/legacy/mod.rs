//! The course's legacy API (before Fall 2015): reading it, and noticing it.
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
//! - **Lua 5.1 names**: `unpack`, `string.gfind` and `table.getn`, aliased to `table.unpack`,
//!   `string.gmatch` and the length operator in both dialects.
//!
//! A script run without `--dialect` is read the modern way and watched ([`Watch`]). At the first
//! `gr.render` whose scene the two orders place differently, it prints one warning naming
//! `--dialect legacy` when the script has shown a legacy sign (one of the last three forms
//! above) and its layout does not speak for the modern order, or, with no sign, when its layout
//! reads legacy ([`order`] says how, and what was measured). A scene whose every node has at
//! most one transform, or only commuting ones, renders the same either way and is never warned
//! about. With `--dialect` given, either way, nothing is watched.
//!
//! ```lua
//! require('readobj')
//! cow = gr.mesh('cow', readobj('cow.obj'))    -- test.lua:2: warning: this script looks written
//! cow:translate(0, 1, 0); cow:scale(2, 2, 2)  -- for the course's legacy API ... --dialect legacy
//! ```

mod bounds;
mod order;
mod readobj;

use crate::desc::{NodeId, RenderDesc, SceneDesc};
use crate::error::Loc;
use crate::lua::State;
use crate::lua::args::caller_loc;
use glam::DAffine3;
use mlua::{Function, Lua, MultiValue, Table, Value};
use std::cell::{Cell, RefCell};
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

/// A form only legacy scripts use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sign {
    /// `gr.mesh(name, verts, faces)`.
    InlineMesh,
    /// `readobj(file)`.
    Readobj,
    /// A Lua 5.1 name: `unpack`, `string.gfind` or `table.getn`.
    Lua51(&'static str),
}

impl Sign {
    /// Returns how the warning names the sign.
    fn describe(self) -> String {
        match self {
            Sign::InlineMesh => "gr.mesh with inline vertex and face tables".into(),
            Sign::Readobj => "readobj".into(),
            Sign::Lua51(name) => format!("the Lua 5.1 name {name}"),
        }
    }
}

/// What a script run without `--dialect` has shown of the legacy API so far.
#[derive(Default)]
pub(in crate::lua) struct Watch {
    /// Each node's transform calls as the legacy order reads them, by node id; a node past the
    /// end has had none.
    calls: Vec<order::Calls>,
    /// The first use of each sign, with its line, in the order seen.
    signs: Vec<(Sign, Loc)>,
    /// Whether the warning was printed (it is printed once per script run).
    warned: bool,
    /// The boxes of the meshes the geometric check has read.
    mesh_boxes: bounds::MeshBoxes,
}

impl Watch {
    /// Records the transform `t` of a call on `node`.
    pub(in crate::lua) fn compose(&mut self, node: NodeId, t: DAffine3) {
        let i = node.0 as usize;
        if self.calls.len() <= i {
            self.calls.resize(i + 1, order::Calls::default());
        }
        self.calls[i].push(t);
    }

    /// Records a use of `sign` at `loc` (the first of each is kept).
    pub(in crate::lua) fn saw(&mut self, sign: Sign, loc: &Loc) {
        if !self.signs.iter().any(|(s, _)| *s == sign) {
            self.signs.push((sign, loc.clone()));
        }
    }

    /// Returns where and why to warn that the scene `render` draws looks legacy, or `None`:
    /// when both orders place it alike, when it shows no legacy sign and its layouts do not make
    /// the case ([`order::Verdict::looks_legacy`]), or when they speak for the modern order.
    fn judge(&mut self, desc: &SceneDesc, render: &RenderDesc) -> Option<(Loc, String)> {
        let orders = order::Orders {
            desc,
            calls: &self.calls,
        };
        if !order::orders_differ(&orders, render.root) {
            return None;
        }
        let verdict = order::compare(&orders, render.root, &mut self.mesh_boxes);
        let Some((_, first)) = self.signs.first() else {
            return verdict
                .looks_legacy()
                .then(|| (render.loc.clone(), verdict.describe()));
        };
        if verdict.rules_out_legacy() {
            return None;
        }
        let signs: Vec<String> = self
            .signs
            .iter()
            .map(|(sign, loc)| {
                if loc.file == first.file {
                    format!("{} (line {})", sign.describe(), loc.line)
                } else {
                    format!("{} ({loc})", sign.describe())
                }
            })
            .collect();
        let why = format!(
            "this script looks written for the course's legacy API (before Fall 2015): it uses {}",
            signs.join(", ")
        );
        Some((first.clone(), why))
    }
}

/// Warns, once per run, when the scene `render` draws looks written for the legacy API and the
/// legacy order would place it differently; does nothing under an explicit `--dialect`.
pub(in crate::lua) fn before_render(s: &mut State, render: &RenderDesc) {
    let State {
        watch: Some(watch),
        desc,
        ..
    } = s
    else {
        return;
    };
    if watch.warned {
        return;
    }
    let Some((loc, why)) = watch.judge(desc, render) else {
        return;
    };
    watch.warned = true;
    s.warn(
        &loc,
        format!(
            "{why}. Legacy scripts compose each node's transforms the other way round \
             (post-multiplied), and that places this scene differently: rerun with --dialect \
             legacy, or give --dialect modern to keep this order and silence the warning"
        ),
    );
}

/// Sets the Lua 5.1 names and the built-in `readobj` in `lua`; each 5.1 name records its use
/// in the run's [`Watch`].
pub(in crate::lua) fn install(lua: &Lua, state: &Rc<RefCell<State>>) -> mlua::Result<()> {
    let g = lua.globals();
    let table: Table = g.get("table")?;
    let string: Table = g.get("string")?;
    let length = lua.create_function(|_, t: Table| Ok(t.raw_len()))?;
    let aliases: [(&Table, &str, &'static str, Function); 3] = [
        (&g, "unpack", "unpack", table.get("unpack")?),
        (&string, "gfind", "string.gfind", string.get("gmatch")?),
        (&table, "getn", "table.getn", length),
    ];
    for (owner, key, name, target) in aliases {
        if !owner.raw_get::<Value>(key)?.is_nil() {
            continue;
        }
        let st = Rc::clone(state);
        let recorded = Cell::new(false);
        let alias = lua.create_function(move |lua, args: MultiValue| {
            // Only the first use is kept, so later calls skip the stack walk. (The state is
            // borrowed only while a gr function runs, and those call no Lua.)
            if !recorded.get()
                && let Ok(mut s) = st.try_borrow_mut()
            {
                s.saw(Sign::Lua51(name), &caller_loc(lua));
                recorded.set(true);
            }
            target.call::<MultiValue>(args)
        })?;
        owner.raw_set(key, alias)?;
    }
    readobj::install(lua, state)
}
