//! The Lua state scripts run in: Lua 5.4 with its whole standard library, made memory-safe.
//!
//! `debug` is loaded (course scripts use `debug.traceback`) less the functions that could break
//! mlua's userdata and registry invariants: `setmetatable`, `getmetatable`, `setuservalue`,
//! `getuservalue`, `getregistry`, `setupvalue`, `getupvalue`, `upvaluejoin` and `upvalueid`.
//! Lua 5.1 names that legacy scripts call are aliased:
//!
//! ```lua
//! local a, b = unpack({1, 2})             -- table.unpack
//! for w in string.gfind(s, '%a+') do end  -- string.gmatch
//! ```

use mlua::{Lua, LuaOptions, StdLib, Table, Value};

/// Returns a fresh Lua state with the standard library, the unsafe `debug` functions removed and
/// the legacy aliases set.
pub(super) fn new_lua() -> mlua::Result<Lua> {
    // SAFETY: `debug` is the only unsafe library; the functions that can corrupt mlua's
    // userdata or registry invariants are removed before any script runs.
    let lua = unsafe { Lua::unsafe_new_with(StdLib::ALL, LuaOptions::new()) };
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
    let table: Table = g.get("table")?;
    if g.get::<Value>("unpack")?.is_nil() {
        g.set("unpack", table.get::<Value>("unpack")?)?;
    }
    let string: Table = g.get("string")?;
    string.set("gfind", string.get::<Value>("gmatch")?)?;
    Ok(lua)
}
