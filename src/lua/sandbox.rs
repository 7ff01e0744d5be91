//! The Lua state scripts run in: Lua 5.4 with its whole standard library, made memory-safe.
//!
//! `debug` is loaded (course scripts use `debug.traceback`) less the functions that could break
//! mlua's userdata and registry invariants: `setmetatable`, `getmetatable`, `setuservalue`,
//! `getuservalue`, `getregistry`, `setupvalue`, `getupvalue`, `upvaluejoin` and `upvalueid`.
//! `require` finds modules as paths resolve: in the working directory (Lua's own `./?.lua`),
//! then in the script's folder, so a course scene's `require('buckyball')` finds the
//! buckyball.lua beside it however it is run. (The Lua 5.1 names legacy scripts call are set by
//! [`super::legacy`].)
//!
//! ```lua
//! require('buckyball')   -- ./buckyball.lua, else buckyball.lua in the script's folder
//! ```
//!
//! The state may hold at most [`MAX_LUA_MEMORY`] (or the script options' limit): an allocation
//! past it fails as a Lua memory error, reported at the line the script was running
//! ([`LineTracker`]), instead of the process aborting when the system runs out.
//!
//! ```lua
//! t = {} for i = 1, math.huge do t[i] = i end  -- test.lua:1: not enough memory: ...
//! ```

use crate::error::{Error, Loc};
use mlua::{HookTriggers, Lua, LuaOptions, StdLib, Table, Value, VmState};
use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;

/// Most memory one script's Lua state may hold: 4 GiB, far more than any scene description
/// needs, and less than the machines caustic runs on can give before the system kills it.
pub const MAX_LUA_MEMORY: usize = 4 << 30;

/// VM instructions between two samples of the running script line.
const LINE_SAMPLE: u32 = 1000;

/// The script line a Lua state was last seen running, sampled every [`LINE_SAMPLE`]
/// instructions: a memory error unwinds the Lua stack without a position, so this is where it
/// is reported.
#[derive(Clone, Default)]
pub(super) struct LineTracker(Rc<RefCell<Option<Loc>>>);

impl LineTracker {
    /// Returns the last sampled location, if the script ran long enough to be sampled.
    pub(super) fn last(&self) -> Option<Loc> {
        self.0.borrow().clone()
    }
}

/// Returns a fresh Lua state with the standard library, the unsafe `debug` functions removed,
/// `require` looking in `script_dir` after the working directory and at most `memory_limit`
/// bytes of memory, with the tracker of its running line. When `interruptible`, the script
/// stops with [`Error::Interrupted`] within [`LINE_SAMPLE`] instructions of a Ctrl-C
/// ([`crate::interrupt::requested`]).
pub(super) fn new_lua(
    memory_limit: usize,
    script_dir: &Path,
    interruptible: bool,
) -> mlua::Result<(Lua, LineTracker)> {
    // SAFETY: `debug` is the only unsafe library; the functions that can corrupt mlua's
    // userdata or registry invariants are removed before any script runs.
    let lua = unsafe { Lua::unsafe_new_with(StdLib::ALL, LuaOptions::new()) };
    lua.set_memory_limit(memory_limit)?;
    let tracker = LineTracker::default();
    let seen = Rc::clone(&tracker.0);
    lua.set_hook(
        HookTriggers::new().every_nth_instruction(LINE_SAMPLE),
        move |_, debug| {
            if interruptible && crate::interrupt::requested() {
                let at = seen
                    .borrow()
                    .as_ref()
                    .map_or(String::new(), |l| format!(" near {l}"));
                return Err(mlua::Error::external(Error::Interrupted(format!(
                    "the script stopped{at}; no later gr.render ran"
                ))));
            }
            let (Some(line), Some(source)) = (debug.current_line(), debug.source().source) else {
                return Ok(VmState::Continue);
            };
            let file = source.strip_prefix('@').unwrap_or(&source);
            let mut seen = seen.borrow_mut();
            match seen.as_mut() {
                Some(loc) if &*loc.file == file => loc.line = line as u32,
                _ => {
                    *seen = Some(Loc {
                        file: file.into(),
                        line: line as u32,
                    })
                }
            }
            Ok(VmState::Continue)
        },
    )?;
    let g = lua.globals();
    let debug: Table = g.get("debug")?;
    for f in [
        "setmetatable",
        "getmetatable",
        "setuservalue",
        "getuservalue",
        "getregistry",
        "setupvalue",
        "getupvalue",
        "upvaluejoin",
        "upvalueid",
    ] {
        debug.raw_set(f, Value::Nil)?;
    }
    // Lua's path templates cannot quote `;` or `?`: a folder holding one is not searched.
    let dir = script_dir.to_string_lossy();
    if !dir.is_empty() && !dir.contains([';', '?']) {
        let package: Table = g.get("package")?;
        let path: String = package.get("path")?;
        let sep = std::path::MAIN_SEPARATOR;
        let dir = dir.trim_end_matches(sep);
        package.set(
            "path",
            format!("{path};{dir}{sep}?.lua;{dir}{sep}?{sep}init.lua"),
        )?;
    }
    Ok((lua, tracker))
}
