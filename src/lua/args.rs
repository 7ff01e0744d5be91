//! Argument checks for the `gr` functions, with lauxlib's messages and the calling script line.
//!
//! The course's C++ reads fixed argument positions with `luaL_check*`, so extra arguments are
//! ignored and messages read `bad argument #3 to 'nh_sphere' (number expected, got nil)`. We keep
//! those messages, prefix them with `script:line:`, and additionally reject NaN, infinity and
//! numbers beyond single precision (the renderer's `f32`: `|x| > 3.4e38` would become infinite).
//! Points, lengths, light colours and reflectances are further held to the ranges the renderer
//! can use ([`crate::range`]).
//! This module also owns the Lua-side handles of description entries ([`NodeRef`],
//! [`MaterialRef`], [`LightRef`]) and how a caustic error crosses the Lua boundary.
//!
//! ```lua
//! s = gr.nh_sphere('s', {0, 0, 0})   -- test.lua:1: bad argument #3 to 'nh_sphere' (number expected, got no value)
//! s:translate(1, 0/0, 0)             -- bad argument #2 to 'translate' (finite number expected, got NaN)
//! s:translate(1e300, 0, 0)           -- bad argument #1 to 'translate' (number within single precision (|x| <= 3.4e38) expected, got 1e300)
//! ```

use crate::desc::{LightId, MaterialId, NodeId};
use crate::error::{Error, Fault, Loc};
use crate::range;
use glam::{DVec3, Vec3};
use mlua::{Lua, MultiValue, Value};

/// A `gr.node` value on the Lua side: a handle to a node of the description.
#[derive(Clone, Copy, Debug)]
pub struct NodeRef(pub NodeId);
/// A `gr.material` value on the Lua side.
#[derive(Clone, Copy, Debug)]
pub struct MaterialRef(pub MaterialId);
/// A `gr.light` value on the Lua side.
#[derive(Clone, Copy, Debug)]
pub struct LightRef(pub LightId);

/// Returns the location of the innermost Lua function on the call stack.
pub fn caller_loc(lua: &Lua) -> Loc {
    for level in 1..32 {
        let found = lua.inspect_stack(level, |d| {
            let line = d.current_line()?;
            let source = d.source().source?.into_owned();
            Some((source, line))
        });
        match found {
            None => break,
            Some(None) => continue,
            // The sandbox's own Lua (`sandbox.lua`) is not where a script went wrong.
            Some(Some((source, _))) if source == super::sandbox::PRELUDE_NAME => continue,
            Some(Some((source, line))) => {
                let file = source.strip_prefix('@').unwrap_or(&source).to_string();
                return Loc {
                    file: file.into(),
                    line: line as u32,
                };
            }
        }
    }
    Loc {
        file: "<script>".into(),
        line: 0,
    }
}

/// Wraps a caustic error so it crosses the Lua boundary intact.
pub fn lua_err(e: Error) -> mlua::Error {
    mlua::Error::external(e)
}

/// The arguments of one `gr` call, with what is needed to report a bad one.
pub struct Args<'a> {
    lua: &'a Lua,
    vals: Vec<Value>,
    /// The function name used in messages (`'nh_sphere'`).
    pub fname: &'static str,
    /// The calling script line.
    pub loc: Loc,
    /// True when called as `n:method(...)`: lauxlib then numbers arguments from the first after self.
    method_call: bool,
}

impl<'a> Args<'a> {
    /// Captures the arguments and the caller's location.
    pub fn new(lua: &'a Lua, fname: &'static str, vals: MultiValue) -> Args<'a> {
        let method_call = lua
            .inspect_stack(0, |d| d.names().name_what == Some("method"))
            .unwrap_or(false);
        Args {
            lua,
            vals: vals.into_vec(),
            fname,
            loc: caller_loc(lua),
            method_call,
        }
    }

    /// Returns the raw value at 1-based position `i`, or `None` when absent.
    pub fn get(&self, i: usize) -> Option<&Value> {
        self.vals.get(i - 1)
    }

    /// Returns an error at the caller's line with a free-form message.
    pub fn fail(&self, message: impl Into<String>) -> mlua::Error {
        self.fault(Fault::Other, message)
    }

    /// Returns an error of kind `fault` at the caller's line.
    pub fn fault(&self, fault: Fault, message: impl Into<String>) -> mlua::Error {
        lua_err(Error::fault_at(fault, &self.loc, message))
    }

    /// Returns lauxlib's `bad argument #i to 'f' (msg)` error.
    pub fn bad(&self, i: usize, msg: impl std::fmt::Display) -> mlua::Error {
        let shown = if self.method_call {
            i as i64 - 1
        } else {
            i as i64
        };
        if shown == 0 {
            return self.fault(
                Fault::BadArgument,
                format!("calling '{}' on bad self ({msg})", self.fname),
            );
        }
        self.fault(
            Fault::BadArgument,
            format!("bad argument #{shown} to '{}' ({msg})", self.fname),
        )
    }

    fn type_error(&self, i: usize, expected: &str) -> mlua::Error {
        let got = match self.get(i) {
            None => "no value".to_string(),
            Some(v) => type_name(v),
        };
        self.bad(i, format!("{expected} expected, got {got}"))
    }

    /// Checks a string argument (numbers are converted, as `luaL_checkstring` does).
    pub fn string(&self, i: usize) -> mlua::Result<String> {
        match self.get(i) {
            Some(v @ (Value::String(_) | Value::Integer(_) | Value::Number(_))) => {
                match self.lua.coerce_string(v.clone())? {
                    Some(s) => Ok(s.to_string_lossy()),
                    None => Err(self.type_error(i, "string")),
                }
            }
            _ => Err(self.type_error(i, "string")),
        }
    }

    /// Checks optional argument `i` with `check`: absent or nil gives `None`.
    fn opt<T>(
        &self,
        i: usize,
        check: impl FnOnce(&Self, usize) -> mlua::Result<T>,
    ) -> mlua::Result<Option<T>> {
        match self.get(i) {
            None | Some(Value::Nil) => Ok(None),
            Some(_) => check(self, i).map(Some),
        }
    }

    /// Checks an optional string argument: absent or nil gives `None`.
    pub fn opt_string(&self, i: usize) -> mlua::Result<Option<String>> {
        self.opt(i, Self::string)
    }

    /// Checks a finite number argument (numeric strings are converted, as `luaL_checknumber` does).
    pub fn number(&self, i: usize) -> mlua::Result<f64> {
        let v = self.get(i).cloned().unwrap_or(Value::Nil);
        let n = match v {
            Value::Integer(_) | Value::Number(_) | Value::String(_) => self.lua.coerce_number(v)?,
            _ => None,
        };
        match n {
            Some(n) => single(n).map_err(|e| self.bad(i, e)),
            None => Err(self.type_error(i, "number")),
        }
    }

    /// Checks an optional number: absent or nil gives `None`.
    pub fn opt_number(&self, i: usize) -> mlua::Result<Option<f64>> {
        self.opt(i, Self::number)
    }

    /// Checks a 3-tuple of finite numbers: a table whose raw length is exactly 3.
    pub fn dvec3(&self, i: usize) -> mlua::Result<DVec3> {
        let Some(Value::Table(t)) = self.get(i) else {
            return Err(self.type_error(i, "table"));
        };
        if t.raw_len() != 3 {
            return Err(self.bad(i, "N-tuple expected"));
        }
        let mut out = [0.0f64; 3];
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = self.element_number(i, &format!("entry {}", k + 1), t.raw_get(k + 1)?)?;
        }
        Ok(DVec3::from_array(out))
    }

    /// Checks `v`, the element of table argument `i` that `element` names (`"vertex 2, entry
    /// 3"`), as a finite single-precision number (numeric strings converted, as Lua does).
    pub fn element_number(&self, i: usize, element: &str, v: Value) -> mlua::Result<f64> {
        let n = match &v {
            Value::Integer(_) | Value::Number(_) | Value::String(_) => {
                self.lua.coerce_number(v.clone())?
            }
            _ => None,
        };
        match n {
            Some(n) => single(n).map_err(|e| self.bad(i, format!("{element}: {e}"))),
            None => {
                let got = type_name(&v);
                Err(self.bad(i, format!("{element}: number expected, got {got}")))
            }
        }
    }

    /// Checks `v`, the element of table argument `i` that `element` names, as an integer: a Lua
    /// integer, a float with an integral value, or a string holding one (as
    /// `luaL_checkinteger` takes them).
    pub fn element_integer(&self, i: usize, element: &str, v: Value) -> mlua::Result<i64> {
        let n = match &v {
            Value::Integer(n) => return Ok(*n),
            Value::Number(_) | Value::String(_) => self.lua.coerce_number(v.clone())?,
            _ => None,
        };
        match n {
            // 2^63 itself does not fit an i64.
            Some(n) if n.fract() == 0.0 && n.abs() < 9.223_372_036_854_776e18 => Ok(n as i64),
            Some(n) if n.fract() == 0.0 => Err(self.bad(
                i,
                format!("{element}: integer expected, got {n:e} (beyond 64-bit integers)"),
            )),
            Some(n) => Err(self.bad(
                i,
                format!("{element}: integer expected, got {n} (no integer representation)"),
            )),
            None => {
                let got = type_name(&v);
                Err(self.bad(i, format!("{element}: integer expected, got {got}")))
            }
        }
    }

    /// Checks a strictly positive number (a radius or a size).
    pub fn positive(&self, i: usize, what: &str) -> mlua::Result<f64> {
        let v = self.number(i)?;
        if v <= 0.0 {
            return Err(self.bad(i, format!("{what} must be positive, got {v}")));
        }
        Ok(v)
    }

    /// Checks an image dimension in pixels, truncated towards zero as C++ `int = double` does.
    pub fn image_size(&self, i: usize) -> mlua::Result<u32> {
        let v = self.number(i)?.trunc();
        if !(1.0..=65535.0).contains(&v) {
            return Err(self.bad(
                i,
                format!("image size must be in [1, 65535] pixels, got {v}"),
            ));
        }
        Ok(v as u32)
    }

    /// Checks three number arguments from position `i` on (`n:translate(x, y, z)`).
    pub fn dvec3_at(&self, i: usize) -> mlua::Result<DVec3> {
        Ok(DVec3::new(
            self.number(i)?,
            self.number(i + 1)?,
            self.number(i + 2)?,
        ))
    }

    /// Checks a 3-tuple and converts it to single precision.
    pub fn vec3(&self, i: usize) -> mlua::Result<Vec3> {
        self.dvec3(i).map(|v| v.as_vec3())
    }

    /// Checks a colour: a 3-tuple with no negative entry.
    pub fn colour(&self, i: usize) -> mlua::Result<Vec3> {
        let c = self.vec3(i)?;
        if c.min_element() < 0.0 {
            return Err(self.bad(
                i,
                format!(
                    "colour components must be >= 0, got {{{}, {}, {}}}",
                    c.x, c.y, c.z
                ),
            ));
        }
        Ok(c)
    }

    /// Checks a light colour or ambient light: a colour within [`range::MAX_INTENSITY`].
    pub fn intensity(&self, i: usize) -> mlua::Result<Vec3> {
        let c = self.colour(i)?;
        let checked = range::within(&c.to_array(), "colour component", range::MAX_INTENSITY);
        checked.map_err(|e| self.bad(i, e))?;
        Ok(c)
    }

    /// Checks a reflectance (`kd`, `ks`): a colour within [`range::MAX_REFLECTANCE`].
    pub fn reflectance(&self, i: usize) -> mlua::Result<Vec3> {
        let c = self.colour(i)?;
        let checked = range::within(&c.to_array(), "reflectance", range::MAX_REFLECTANCE);
        checked.map_err(|e| self.bad(i, e))?;
        Ok(c)
    }

    /// Checks a point or a length vector: a 3-tuple within [`range::MAX_COORDINATE`].
    pub fn point(&self, i: usize) -> mlua::Result<DVec3> {
        let p = self.dvec3(i)?;
        range::coordinate(p.to_array()).map_err(|e| self.bad(i, e))?;
        Ok(p)
    }

    /// Checks a positive length (a radius or a size) no longer than [`range::MAX_COORDINATE`].
    pub fn length(&self, i: usize, what: &str) -> mlua::Result<f64> {
        let v = self.positive(i, what)?;
        if v > range::MAX_COORDINATE {
            let max = range::show(range::MAX_COORDINATE);
            return Err(self.bad(i, format!("{what} {v:e} is longer than {max}")));
        }
        Ok(v)
    }

    /// Checks a `gr.node` argument.
    pub fn node(&self, i: usize) -> mlua::Result<NodeId> {
        if let Some(Value::UserData(ud)) = self.get(i)
            && let Ok(n) = ud.borrow::<NodeRef>()
        {
            return Ok(n.0);
        }
        Err(self.type_error(i, "gr.node"))
    }

    /// Checks a `gr.material` argument.
    pub fn material(&self, i: usize) -> mlua::Result<MaterialId> {
        if let Some(Value::UserData(ud)) = self.get(i)
            && let Ok(m) = ud.borrow::<MaterialRef>()
        {
            return Ok(m.0);
        }
        Err(self.type_error(i, "gr.material"))
    }

    /// Checks a sequence of one or more `gr.light` values.
    pub fn lights(&self, i: usize) -> mlua::Result<Vec<LightId>> {
        let Some(Value::Table(t)) = self.get(i) else {
            return Err(self.type_error(i, "table"));
        };
        let n = t.raw_len();
        if n == 0 {
            return Err(self.bad(i, "Tuple of lights expected"));
        }
        let mut out = Vec::with_capacity(n);
        for k in 1..=n {
            let v: Value = t.raw_get(k)?;
            match &v {
                Value::UserData(ud) if ud.is::<LightRef>() => out.push(ud.borrow::<LightRef>()?.0),
                _ => {
                    let got = type_name(&v);
                    return Err(self.bad(
                        i,
                        format!("Tuple of lights expected (entry {k} is a {got})"),
                    ));
                }
            }
        }
        Ok(out)
    }
}

/// Returns `n` when it is finite in single precision, or the message for an argument that is not.
fn single(n: f64) -> Result<f64, String> {
    if !n.is_finite() {
        Err(format!("finite number expected, got {n}"))
    } else if n.abs() > f32::MAX as f64 {
        Err(format!(
            "number within single precision (|x| <= {:.1e}) expected, got {n:e}",
            f32::MAX
        ))
    } else {
        Ok(n)
    }
}

/// Returns the type name lauxlib would print, with our userdata named by their metatable.
pub fn type_name(v: &Value) -> String {
    match v {
        Value::UserData(ud) if ud.is::<NodeRef>() => "gr.node".into(),
        Value::UserData(ud) if ud.is::<MaterialRef>() => "gr.material".into(),
        Value::UserData(ud) if ud.is::<LightRef>() => "gr.light".into(),
        Value::Integer(_) | Value::Number(_) => "number".into(),
        Value::LightUserData(_) => "userdata".into(),
        other => other.type_name().into(),
    }
}
