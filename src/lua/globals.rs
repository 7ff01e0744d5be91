//! Globals set before a script runs: the command line's `-D NAME=VALUE` (Mitsuba 3's `-D`), so one
//! script renders variants without being edited.
//!
//! A value is a Lua integer when it reads as one (`3`, `-2`), else a float when it reads as a
//! finite number (`0.5`, `1e-3`), `true` and `false` are booleans, and anything else is a string
//! (`-D out=big.png`, `-D name=` for the empty string). A script reads them as ordinary globals and
//! may give a default for a global left unset:
//!
//! ```lua
//! -- caustic render scene.lua -D size=512 -D glass=true
//! size = size or 256
//! if glass then ball:set_material(gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)) end
//! ```
//!
//! Refused, each with a message naming the definition: a form without `=` or without a name, a
//! name that is not a Lua identifier or is a keyword, more than [`MAX_GLOBALS`] definitions, a
//! name given twice, names and values longer than [`MAX_NAME_LEN`] and [`MAX_VALUE_LEN`] bytes, a
//! number too large to be finite (`1e999`), and a name the script environment already defines
//! (`gr`, `math`, `print`, …), which the definition would hide.

use crate::error::{Error, Result};
use mlua::{Lua, Value};

/// Most globals one script run may be given.
pub const MAX_GLOBALS: usize = 256;

/// Longest global name, in bytes.
pub const MAX_NAME_LEN: usize = 64;

/// Longest global value, in bytes.
pub const MAX_VALUE_LEN: usize = 4096;

/// Lua 5.4's reserved words, which cannot name a global.
const KEYWORDS: [&str; 22] = [
    "and", "break", "do", "else", "elseif", "end", "false", "for", "function", "goto", "if", "in",
    "local", "nil", "not", "or", "repeat", "return", "then", "true", "until", "while",
];

/// The value of a global set before a script runs.
#[derive(Clone, Debug, PartialEq)]
pub enum GlobalValue {
    Integer(i64),
    Number(f64),
    Boolean(bool),
    String(String),
}

/// A global `name = value` set before a script runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Global {
    pub name: String,
    pub value: GlobalValue,
}

impl Global {
    /// Returns the global `NAME=VALUE` defines, or a message saying what is wrong with it.
    pub fn parse(text: &str) -> std::result::Result<Global, String> {
        let Some((name, value)) = text.split_once('=') else {
            return Err(format!("'{text}' has no '=': expected NAME=VALUE"));
        };
        check_name(name)?;
        if value.len() > MAX_VALUE_LEN {
            return Err(format!(
                "the value of {name} is {} bytes long, more than {MAX_VALUE_LEN}",
                value.len()
            ));
        }
        let value = parse_value(value).map_err(|e| format!("{name}={value}: {e}"))?;
        Ok(Global {
            name: name.to_string(),
            value,
        })
    }

    /// Returns the definition as it would be written on the command line, for messages.
    fn text(&self) -> String {
        let value = match &self.value {
            GlobalValue::Integer(i) => i.to_string(),
            GlobalValue::Number(x) => x.to_string(),
            GlobalValue::Boolean(b) => b.to_string(),
            GlobalValue::String(s) => s.clone(),
        };
        format!("{}={value}", self.name)
    }
}

/// Returns an error unless `name` may name a global: a Lua identifier of at most
/// [`MAX_NAME_LEN`] bytes that is not a keyword.
fn check_name(name: &str) -> std::result::Result<(), String> {
    if name.is_empty() {
        return Err("the name before '=' is empty: expected NAME=VALUE".into());
    }
    if name.len() > MAX_NAME_LEN {
        return Err(format!(
            "the name is {} bytes long, more than {MAX_NAME_LEN}",
            name.len()
        ));
    }
    let mut chars = name.chars();
    let first_ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !first_ok || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "'{name}' is not a Lua name (letters, digits and '_', not starting with a digit)"
        ));
    }
    if KEYWORDS.contains(&name) {
        return Err(format!("'{name}' is a Lua keyword, not a name"));
    }
    if name == "gr" {
        return Err("'gr' is the scene API; a global of that name would hide it".into());
    }
    Ok(())
}

/// Returns the Lua value `text` stands for: an integer, a finite float, a boolean or a string.
fn parse_value(text: &str) -> std::result::Result<GlobalValue, String> {
    match text {
        "true" => return Ok(GlobalValue::Boolean(true)),
        "false" => return Ok(GlobalValue::Boolean(false)),
        _ => {}
    }
    if let Ok(i) = text.parse::<i64>() {
        return Ok(GlobalValue::Integer(i));
    }
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(GlobalValue::Number(x)),
        // Words Rust reads as numbers (`inf`, `NaN`) stay strings; digits that overflow do not.
        Ok(_) if text.chars().any(|c| c.is_ascii_digit()) => {
            Err("not a finite number (at most about 1.8e308)".into())
        }
        _ => Ok(GlobalValue::String(text.to_string())),
    }
}

/// Sets `globals` in `lua`'s global table, or returns a usage error (naming `-D`, the command
/// line's flag for them) when there are too many, a name is given twice or a name is one the
/// state already defines (`gr`, the standard library).
pub(super) fn set(lua: &Lua, globals: &[Global]) -> Result<()> {
    if globals.len() > MAX_GLOBALS {
        return Err(Error::Usage(format!(
            "-D is given {} times, more than {MAX_GLOBALS}",
            globals.len()
        )));
    }
    let table = lua.globals();
    for (k, g) in globals.iter().enumerate() {
        if globals[..k].iter().any(|other| other.name == g.name) {
            return Err(Error::Usage(format!(
                "-D {}: {} is given twice",
                g.text(),
                g.name
            )));
        }
        let lua_error = |e: mlua::Error| Error::Lua(format!("-D {}: {e}", g.text()));
        if table.contains_key(g.name.as_str()).map_err(lua_error)? {
            return Err(Error::Usage(format!(
                "-D {}: every script already has a global '{}' (gr or Lua's standard library); \
                 a definition would hide it, so choose another name",
                g.text(),
                g.name
            )));
        }
        let value = match &g.value {
            GlobalValue::Integer(i) => Value::Integer(*i),
            GlobalValue::Number(x) => Value::Number(*x),
            GlobalValue::Boolean(b) => Value::Boolean(*b),
            GlobalValue::String(s) => Value::String(lua.create_string(s).map_err(lua_error)?),
        };
        table.raw_set(g.name.as_str(), value).map_err(lua_error)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_read_as_lua_would_type_them() {
        let v = |t: &str| Global::parse(t).map(|g| g.value);
        assert_eq!(v("n=3"), Ok(GlobalValue::Integer(3)));
        assert_eq!(v("n=-2"), Ok(GlobalValue::Integer(-2)));
        assert_eq!(v("x=0.5"), Ok(GlobalValue::Number(0.5)));
        assert_eq!(v("x=1e-3"), Ok(GlobalValue::Number(1e-3)));
        assert_eq!(v("b=true"), Ok(GlobalValue::Boolean(true)));
        assert_eq!(v("b=false"), Ok(GlobalValue::Boolean(false)));
        assert_eq!(v("s=big.png"), Ok(GlobalValue::String("big.png".into())));
        assert_eq!(v("s=a=b"), Ok(GlobalValue::String("a=b".into())));
        assert_eq!(v("s="), Ok(GlobalValue::String(String::new())));
        assert_eq!(v("s=inf"), Ok(GlobalValue::String("inf".into())));
        assert_eq!(v("s=True"), Ok(GlobalValue::String("True".into())));
        assert!(v("x=1e999").unwrap_err().contains("finite"));
    }

    #[test]
    fn bad_forms_and_names_are_refused_with_a_reason() {
        let e = |t: &str| Global::parse(t).unwrap_err();
        assert!(e("foo").contains("no '='"));
        assert!(e("=3").contains("empty"));
        assert!(e("1x=3").contains("not a Lua name"));
        assert!(e("a-b=3").contains("not a Lua name"));
        assert!(e("é=3").contains("not a Lua name"));
        assert!(e("end=3").contains("keyword"));
        assert!(e("gr=3").contains("scene API"));
        assert!(e(&format!("{}=1", "a".repeat(65))).contains("more than 64"));
        assert!(e(&format!("a={}", "v".repeat(4097))).contains("more than 4096"));
        assert!(Global::parse(&format!("{}=1", "a".repeat(64))).is_ok());
        assert!(Global::parse("_under_1=1").is_ok());
    }
}
