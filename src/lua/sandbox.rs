//! The Lua state scripts run in: a sandbox built from what a scene needs, not the full standard
//! library with dangerous parts taken away (`docs/security.md` is the threat model).
//!
//! A scene script is an untrusted program: scenes are cloned from public repositories, passed
//! between students and submitted to farms. The state is given, by construction:
//! - `string` (less `string.dump`), `table`, `math`, `utf8`, `coroutine` and the base library,
//!   with `load` reading text chunks only (Lua does not verify bytecode: a crafted binary chunk
//!   corrupts memory) and `collectgarbage` limited to `collect`, `count`, `step` and `isrunning`;
//! - `os.time`, `os.clock`, `os.date` and `os.difftime`;
//! - `io.write` (to standard output), and `io.open`, `io.lines`, `dofile` and `loadfile` that
//!   read, never write, files inside the scene's folders ([`Folders`]: the script's folder
//!   tree, or the git checkout it lies in, plus `--allow-read` folders);
//! - `require` of Lua modules (text) inside the scene's folders: the working directory first,
//!   as Lua's `./?.lua` does, then the script's folder, so a course scene's
//!   `require('buckyball')` finds the buckyball.lua beside it however it is run; `package` holds
//!   only `loaded`, `preload` and `searchers` (the built-in `readobj` is one, see
//!   [`super::legacy`]);
//! - `debug.traceback` and `debug.getinfo` (course scripts print tracebacks);
//! - `setmetatable` without `__gc` finalizers (Lua runs them with hooks off, out of the time
//!   budget's reach).
//!
//! Processes, native code (`package.loadlib`, C modules), binary chunks, writing or removing
//! files, the environment, `os.exit` and debug hooks are not there: each such name is a function
//! that fails at the script line saying so and naming `--trusted-script`, which gives a script the
//! whole standard library (as before the sandbox; for a user's own scripts only).
//!
//! ```lua
//! require('buckyball')   -- ./buckyball.lua, else buckyball.lua in the script's folder
//! os.execute('rm -rf ~') -- scene.lua:2: os.execute is not available to scene scripts ...
//! ```
//!
//! Two budgets bound what a script takes, and it cannot remove either: the state may hold at
//! most [`MAX_LUA_MEMORY`] bytes (or the options' limit; an allocation past it fails as a Lua
//! memory error, reported at the line the script was running), and the script may run for at
//! most its time budget ([`ScriptClock`], `--script-time`), not counting the renders its
//! `gr.render` calls make. The hook that enforces time is a global one (coroutines inherit it),
//! and once the budget is spent it fires on every instruction, so no `pcall` can swallow the
//! stop. Time spent inside one C library call (a pathological string pattern) is bounded by the
//! command line's watchdog ([`watchdog`]), which ends the process with the same message.
//!
//! ```lua
//! while true do end   -- scene.lua:1: the script ran for more than its 300 s budget (--script-time)
//! ```

use crate::error::{Error, Fault, Loc};
use mlua::chunk::ChunkMode;
use mlua::{Function, HookTriggers, Lua, LuaOptions, MultiValue, StdLib, Table, Value, VmState};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Most memory one script's Lua state may hold: 4 GiB, far more than any scene description
/// needs, and less than the machines caustic runs on can give before the system kills it.
pub const MAX_LUA_MEMORY: usize = 4 << 30;

/// The default time a script may run (`--script-time`), not counting its renders: five
/// minutes, a thousand times what the course's largest scenes take.
pub const DEFAULT_SCRIPT_TIME: Duration = Duration::from_secs(300);

/// The largest file `io.open`, `dofile`, `loadfile` or `require` reads: 256 MiB.
pub const MAX_READ: u64 = 256 << 20;

/// VM instructions between two samples of the running script line and the clock.
const LINE_SAMPLE: u32 = 1000;

/// The chunk name of the sandbox's own Lua, which error locations skip.
pub(super) const PRELUDE_NAME: &str = "=caustic sandbox";

/// The flag that lifts the sandbox, named in every refusal.
const TRUSTED_FLAG: &str = "--trusted-script";

/// How a script's state is limited.
#[derive(Clone, Debug)]
pub(super) struct Limits {
    /// Most bytes the state may hold.
    pub memory: usize,
    /// Stop with [`Error::Interrupted`] on Ctrl-C ([`crate::interrupt::requested`]).
    pub interruptible: bool,
    /// The whole standard library, for a script its user trusts.
    pub trusted: bool,
}

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

/// The time a script has run, paused while its `gr.render` calls render, shared with the
/// command line's [`watchdog`] thread.
#[derive(Debug)]
pub struct ScriptClock {
    budget: Duration,
    state: Mutex<ClockState>,
}

#[derive(Debug)]
struct ClockState {
    /// Time run before the current stretch.
    used: Duration,
    /// When the current stretch began; `None` while paused or finished.
    since: Option<Instant>,
    /// The line last sampled, for the watchdog's message.
    line: Option<Loc>,
    /// The script's name, for a message before any line was sampled.
    name: String,
    /// The stop the hook raised (budget spent, Ctrl-C), which ends the run even when the
    /// script caught it.
    stop: Option<Error>,
}

impl ScriptClock {
    /// Returns a running clock with `budget` for the script `name`.
    pub fn start(budget: Duration, name: &str) -> Arc<ScriptClock> {
        Arc::new(ScriptClock {
            budget,
            state: Mutex::new(ClockState {
                used: Duration::ZERO,
                since: Some(Instant::now()),
                line: None,
                name: name.to_string(),
                stop: None,
            }),
        })
    }

    /// Returns the time run so far.
    pub fn used(&self) -> Duration {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.used + s.since.map_or(Duration::ZERO, |t| t.elapsed())
    }

    /// Returns whether the clock is running (the script, not a render, has the thread).
    fn running(&self) -> bool {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.since.is_some()
    }

    /// Stops counting until [`ScriptClock::resume`].
    pub fn pause(&self) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(t) = s.since.take() {
            s.used += t.elapsed();
        }
    }

    /// Counts again after [`ScriptClock::pause`].
    pub fn resume(&self) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if s.since.is_none() {
            s.since = Some(Instant::now());
        }
    }

    /// Returns the stop the hook raised, if it did: the run fails with it even when the
    /// script caught it (`pcall`, `coroutine.resume`) and ran to its end.
    pub fn stop(&self) -> Option<Error> {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.stop.clone()
    }

    /// Records the stop the hook raises.
    fn record_stop(&self, e: &Error) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.stop.get_or_insert_with(|| e.clone());
    }

    /// Records the line the script runs.
    fn saw(&self, loc: &Loc) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.line = Some(loc.clone());
    }

    /// Returns the message of a script past its budget, `near` the line it ran.
    fn overrun(&self, near: Option<&Loc>) -> String {
        let at = near.map_or(String::new(), |l| format!(" (last seen at {l})"));
        format!(
            "the script ran for more than its budget of {} s{at}; a scene script that loops \
             for ever is stopped here (raise the budget with --script-time SECONDS)",
            self.budget.as_secs_f64()
        )
    }
}

/// The folders a scene may read: the script's folder and every folder below it (or, inside a
/// git checkout, the checkout's tree: [`project_root`]), and those the user names with
/// `--allow-read`. Paths resolve against the working directory first, as the
/// course does, then against the script's folder; what they name must lie in one of these
/// folders once symlinks and `..` are resolved.
#[derive(Clone, Debug)]
pub struct Folders {
    /// The script's folder (the empty path for a script in the working directory).
    pub script_dir: PathBuf,
    /// The readable trees, canonical.
    roots: Vec<PathBuf>,
}

/// Returns the tree a script in the canonical folder `dir` may read: the nearest folder at or
/// above `dir` that holds `.git` (a cloned scene repository keeps shared textures and meshes in
/// sibling folders, `scenes/gallery/../textures/`), else `dir` itself. The search stops below
/// the user's home folder and the file system's root, which are never a scene's tree.
fn project_root(dir: &Path) -> PathBuf {
    let home = std::env::var_os("HOME").and_then(|h| std::fs::canonicalize(h).ok());
    let mut at = Some(dir);
    while let Some(d) = at {
        if d.parent().is_none() || home.as_deref() == Some(d) {
            break;
        }
        if d.join(".git").exists() {
            return d.to_path_buf();
        }
        at = d.parent();
    }
    dir.to_path_buf()
}

/// Why a path a scene names cannot be read.
#[derive(Clone, Debug, PartialEq)]
pub enum Unreadable {
    /// Nothing by that name in the working directory or the script's folder.
    NotFound,
    /// The file exists, at this canonical path, outside the scene's folders.
    Outside(PathBuf),
}

impl Folders {
    /// Returns the folders of a script in `script_dir`, plus `allow_read` (given by the user).
    pub fn new(script_dir: &Path, allow_read: &[PathBuf]) -> Folders {
        let dir = if script_dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            script_dir
        };
        let own = std::fs::canonicalize(dir).ok().map(|d| project_root(&d));
        let roots = own
            .into_iter()
            .chain(
                allow_read
                    .iter()
                    .filter_map(|d| std::fs::canonicalize(d).ok()),
            )
            .collect();
        Folders {
            script_dir: script_dir.to_path_buf(),
            roots,
        }
    }

    /// Returns the scope the scene's own files (meshes' libraries, buffers, images) are read in.
    pub fn read_scope(&self) -> crate::files::ReadScope {
        crate::files::ReadScope::within(self.roots.clone())
    }

    /// Returns whether the existing file `path` lies in one of the readable trees.
    pub fn contains(&self, path: &Path) -> Result<(), Unreadable> {
        let real = std::fs::canonicalize(path).map_err(|_| Unreadable::NotFound)?;
        if self.roots.iter().any(|r| real.starts_with(r)) {
            Ok(())
        } else {
            Err(Unreadable::Outside(real))
        }
    }

    /// Returns the readable file `given` names: as given (working directory), else in the
    /// script's folder; it must lie in the scene's folders.
    pub fn resolve(&self, given: &str) -> Result<PathBuf, Unreadable> {
        let p = Path::new(given);
        let q = self.script_dir.join(p);
        let found = if p.is_file() {
            p.to_path_buf()
        } else if p.is_relative() && q.is_file() {
            q
        } else {
            return Err(Unreadable::NotFound);
        };
        self.contains(&found)?;
        Ok(found)
    }

    /// Returns the message for `what` named `given` resolving to a file outside the folders.
    pub fn outside_message(&self, what: &str, given: &str, real: &Path) -> String {
        let roots: Vec<String> = self.roots.iter().map(|r| r.display().to_string()).collect();
        format!(
            "{what} '{given}' is {}, outside the folders a scene may read ({}); a scene reads \
             only files in its own folder and below it (docs/security.md): copy the file there, \
             or name its folder with --allow-read DIR",
            real.display(),
            roots.join(", ")
        )
    }
}

/// Returns a fresh Lua state for a script in `folders`, limited by `limits`, with the tracker of
/// its running line; `clock` stops the script once its budget is spent.
pub(super) fn new_lua(
    limits: &Limits,
    folders: &Rc<Folders>,
    clock: &Arc<ScriptClock>,
) -> mlua::Result<(Lua, LineTracker)> {
    let lua = if limits.trusted {
        // SAFETY: the user asked for the whole library (`--trusted-script`); the `debug`
        // functions that can corrupt mlua's invariants are still removed below.
        unsafe { Lua::unsafe_new_with(StdLib::ALL, LuaOptions::new()) }
    } else {
        let libs = StdLib::STRING
            | StdLib::TABLE
            | StdLib::MATH
            | StdLib::UTF8
            | StdLib::COROUTINE
            | StdLib::OS
            | StdLib::DEBUG;
        // SAFETY: `debug` is cut down to `traceback` and `getinfo` before any script runs, and
        // neither `package` nor `io` is opened (no C modules, no file handles).
        unsafe { Lua::unsafe_new_with(libs, LuaOptions::new()) }
    };
    lua.set_memory_limit(limits.memory)?;
    let tracker = LineTracker::default();
    install_hook(&lua, limits.interruptible, &tracker, clock)?;
    if limits.trusted {
        trim_debug_for_mlua(&lua)?;
        add_script_dir_to_path(&lua, &folders.script_dir)?;
    } else {
        confine(&lua, folders)?;
    }
    Ok((lua, tracker))
}

/// Sets the global hook that samples the running line every [`LINE_SAMPLE`] instructions and
/// stops the script on Ctrl-C or past its time budget.
fn install_hook(
    lua: &Lua,
    interruptible: bool,
    tracker: &LineTracker,
    clock: &Arc<ScriptClock>,
) -> mlua::Result<()> {
    let seen = Rc::clone(&tracker.0);
    let clock = Arc::clone(clock);
    // A global hook: Lua copies it into every coroutine the script creates, and mlua calls the
    // same function there (a per-thread hook would be dropped in a new coroutine).
    lua.set_global_hook(
        HookTriggers::new().every_nth_instruction(LINE_SAMPLE),
        move |lua, debug| {
            // Inside the sandbox's own Lua (a wrapper such as string.rep), the script line is
            // the one that called it.
            let here = match (debug.current_line(), debug.source().source) {
                (_, Some(source)) if source == PRELUDE_NAME => {
                    Some(super::args::caller_loc(lua)).filter(|l| l.line > 0)
                }
                (Some(line), Some(source)) => Some(Loc {
                    file: source.strip_prefix('@').unwrap_or(&source).into(),
                    line: line as u32,
                }),
                _ => None,
            };
            if let Some(here) = here {
                let mut seen = seen.borrow_mut();
                match seen.as_mut() {
                    Some(loc) if loc.file == here.file => loc.line = here.line,
                    _ => *seen = Some(here),
                }
                if let Some(loc) = seen.as_ref() {
                    clock.saw(loc);
                }
            }
            let stop = if interruptible && crate::interrupt::requested() {
                let at = seen
                    .borrow()
                    .as_ref()
                    .map_or(String::new(), |l| format!(" near {l}"));
                Some(Error::Interrupted(format!(
                    "the script stopped{at}; no later gr.render ran"
                )))
            } else if clock.used() > clock.budget {
                Some(Error::fault_at(
                    Fault::Sandbox,
                    &seen.borrow().clone().unwrap_or_else(|| Loc {
                        file: "<script>".into(),
                        line: 0,
                    }),
                    clock.overrun(None),
                ))
            } else {
                None
            };
            match stop {
                None => Ok(VmState::Continue),
                Some(e) => {
                    clock.record_stop(&e);
                    // From now on every instruction fails, so a `pcall` that catches this
                    // error cannot run on: the next instruction after it fails again.
                    let fatal = e.clone();
                    lua.set_global_hook(
                        HookTriggers::new().every_nth_instruction(1),
                        move |_, _| Err(mlua::Error::external(fatal.clone())),
                    )?;
                    Err(mlua::Error::external(e))
                }
            }
        },
    )
}

/// Removes the `debug` functions that could break mlua's userdata and registry invariants (a
/// trusted script keeps the rest).
fn trim_debug_for_mlua(lua: &Lua) -> mlua::Result<()> {
    let debug: Table = lua.globals().get("debug")?;
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
        "sethook",
    ] {
        debug.raw_set(f, Value::Nil)?;
    }
    Ok(())
}

/// Adds the script's folder to a trusted script's `package.path`.
fn add_script_dir_to_path(lua: &Lua, script_dir: &Path) -> mlua::Result<()> {
    // Lua's path templates cannot quote `;` or `?`: a folder holding one is not searched.
    let dir = script_dir.to_string_lossy();
    if !dir.is_empty() && !dir.contains([';', '?']) {
        let package: Table = lua.globals().get("package")?;
        let path: String = package.get("path")?;
        let sep = std::path::MAIN_SEPARATOR;
        let dir = dir.trim_end_matches(sep);
        package.set(
            "path",
            format!("{path};{dir}{sep}?.lua;{dir}{sep}?{sep}init.lua"),
        )?;
    }
    Ok(())
}

/// Returns a function that fails with the sandbox's refusal of `name`.
fn refusal(lua: &Lua, name: &'static str, why: &'static str) -> mlua::Result<Function> {
    lua.create_function(move |lua, _: MultiValue| -> mlua::Result<()> {
        Err(mlua::Error::external(Error::fault_at(
            Fault::Sandbox,
            &super::args::caller_loc(lua),
            format!(
                "{name} is not available to scene scripts ({why}); caustic runs scenes in a \
                 sandbox (docs/security.md): give a script you trust the whole Lua library with \
                 {TRUSTED_FLAG}"
            ),
        )))
    })
}

/// A standard library the sandbox rebuilds: the functions it keeps, and those it refuses
/// with the reason each refusal gives (see the module doc).
struct Kept {
    name: &'static str,
    kept: &'static [&'static str],
    refused: &'static [(&'static str, &'static str)],
}

/// The libraries the sandbox keeps only parts of.
const KEPT: [Kept; 2] = [
    Kept {
        name: "debug",
        kept: &["traceback", "getinfo"],
        refused: &[
            ("sethook", INTERNALS),
            ("gethook", INTERNALS),
            ("getlocal", INTERNALS),
            ("setlocal", INTERNALS),
            ("getregistry", INTERNALS),
        ],
    },
    Kept {
        name: "os",
        kept: &["time", "clock", "date", "difftime"],
        refused: &[
            ("execute", "it runs a program"),
            ("remove", "it deletes files"),
            ("rename", "it moves files"),
            ("tmpname", "it creates files"),
            ("exit", "it ends the process"),
            ("getenv", "it reads the environment"),
            ("setlocale", "it changes the process's locale"),
        ],
    },
];

/// Why the `debug` functions that are refused are.
const INTERNALS: &str = "it reaches the interpreter's internals";

/// What the sandbox refuses of the libraries it otherwise keeps whole (`io` is the prelude's,
/// with these added), with the reason each refusal gives.
const REFUSED: [(&str, &str, &str); 7] = [
    ("string", "dump", "scenes load text chunks only"),
    ("package", "loadlib", "it loads native code"),
    ("io", "popen", "it runs a program"),
    ("io", "output", "it writes files"),
    ("io", "input", "it opens files"),
    ("io", "read", "it reads standard input"),
    ("io", "tmpfile", "it creates files"),
];

/// Builds the sandbox's globals over the libraries opened: see the module doc.
fn confine(lua: &Lua, folders: &Rc<Folders>) -> mlua::Result<()> {
    let g = lua.globals();
    for Kept {
        name,
        kept,
        refused,
    } in KEPT
    {
        let full: Table = g.get(name)?;
        let lib = lua.create_table()?;
        for f in kept {
            lib.raw_set(*f, full.get::<Value>(*f)?)?;
        }
        for (f, why) in refused {
            lib.raw_set(*f, refusal(lua, leak(format!("{name}.{f}")), why)?)?;
        }
        g.raw_set(name, lib)?;
    }
    g.raw_set(
        "collectgarbage",
        collectgarbage_limited(lua, g.get("collectgarbage")?)?,
    )?;
    g.raw_set("load", load_text(lua)?)?;
    g.raw_set("setmetatable", setmetatable_without_gc(lua)?)?;
    g.raw_set("io", io_in_folders(lua, folders)?)?;
    for (name, f, why) in REFUSED {
        let lib: Table = g.get(name)?;
        lib.raw_set(f, refusal(lua, leak(format!("{name}.{f}")), why)?)?;
    }
    Ok(())
}

/// Returns `collectgarbage` (`gc`) limited to `collect`, `count`, `step` and `isrunning`: no
/// control that could defeat the memory limit's collections.
fn collectgarbage_limited(lua: &Lua, gc: Function) -> mlua::Result<Function> {
    lua.create_function(move |lua, args: MultiValue| {
        let opt = match args.front() {
            None | Some(Value::Nil) => "collect".to_string(),
            Some(v) => v.to_string()?,
        };
        if !matches!(opt.as_str(), "collect" | "count" | "step" | "isrunning") {
            return Err(mlua::Error::external(Error::fault_at(
                Fault::Sandbox,
                &super::args::caller_loc(lua),
                format!(
                    "collectgarbage('{opt}') is not available to scene scripts (only \
                     'collect', 'count', 'step' and 'isrunning' are); caustic runs scenes in \
                     a sandbox (docs/security.md)"
                ),
            )));
        }
        gc.call::<MultiValue>(args)
    })
}

/// Returns the sandbox's `io` table (the prelude's, over `folders`): `write` to standard
/// output, `open` and `lines` that read text files in the scene's folders, and the module
/// finder `require` uses.
fn io_in_folders(lua: &Lua, folders: &Rc<Folders>) -> mlua::Result<Table> {
    let f = Rc::clone(folders);
    let read = lua.create_function(move |lua, given: String| read_file(lua, &f, &given))?;
    let f = Rc::clone(folders);
    let find = lua.create_function(move |lua, name: String| find_module(lua, &f, &name))?;
    let write = lua.create_function(|_, args: MultiValue| {
        use std::io::Write;
        let mut out = std::io::stdout().lock();
        for v in args {
            let text = match v {
                Value::String(s) => s.as_bytes().to_vec(),
                Value::Integer(_) | Value::Number(_) => v.to_string()?.into_bytes(),
                other => {
                    return Err(mlua::Error::runtime(format!(
                        "bad argument to 'write' (string expected, got {})",
                        other.type_name()
                    )));
                }
            };
            let _ = out.write_all(&text);
        }
        Ok(())
    })?;
    let prelude: Function = lua
        .load(PRELUDE)
        .set_name(PRELUDE_NAME)
        .set_mode(ChunkMode::Text)
        .into_function()?;
    prelude.call((write, read, find))
}

/// Returns a `'static` name for a refusal (a few short strings, made once per state).
fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

/// Returns `setmetatable` refusing a metatable with a `__gc` finalizer: Lua runs finalizers
/// with hooks off, so a finalizer that loops could not be stopped by the time budget (only by
/// the watchdog, which ends the process). A `__gc` field added to a metatable after
/// `setmetatable` is never called (Lua 5.4 marks objects for finalization only here).
fn setmetatable_without_gc(lua: &Lua) -> mlua::Result<Function> {
    let raw: Function = lua.globals().get("setmetatable")?;
    lua.create_function(move |lua, args: MultiValue| {
        if let Some(Value::Table(meta)) = args.get(1)
            && !meta.raw_get::<Value>("__gc")?.is_nil()
        {
            return Err(mlua::Error::external(Error::fault_at(
                Fault::Sandbox,
                &super::args::caller_loc(lua),
                "setmetatable: a __gc finalizer is not available to scene scripts (Lua runs \
                 finalizers where the time budget cannot stop them); caustic runs scenes in a \
                 sandbox (docs/security.md)",
            )));
        }
        raw.call::<MultiValue>(args)
    })
}

/// Returns `load` reading text chunks only: Lua's own, with its mode forced to `'t'`.
fn load_text(lua: &Lua) -> mlua::Result<Function> {
    let raw: Function = lua.globals().get("load")?;
    lua.create_function(move |lua, args: MultiValue| {
        let mut args: Vec<Value> = args.into_iter().collect();
        while args.len() < 3 {
            args.push(Value::Nil);
        }
        // The mode is the third argument; an environment (the fourth) is passed on only when
        // given, since an explicit nil would become the chunk's _ENV.
        args[2] = Value::String(lua.create_string("t")?);
        raw.call::<MultiValue>(MultiValue::from_vec(args))
    })
}

/// `read_scene_file(path)`: the text of a file in the scene's folders, and its chunk name.
fn read_file(lua: &Lua, folders: &Folders, given: &str) -> mlua::Result<MultiValue> {
    let loc = super::args::caller_loc(lua);
    let path = match folders.resolve(given) {
        Ok(p) => p,
        Err(Unreadable::NotFound) => {
            return Ok(MultiValue::from_vec(vec![
                Value::Nil,
                Value::String(lua.create_string(format!("{given}: No such file or directory"))?),
            ]));
        }
        Err(Unreadable::Outside(real)) => {
            return Err(mlua::Error::external(Error::fault_at(
                Fault::Sandbox,
                &loc,
                folders.outside_message("file", given, &real),
            )));
        }
    };
    let bytes = read_bounded(&path).map_err(|e| {
        mlua::Error::external(Error::fault_at(
            Fault::Other,
            &loc,
            format!("cannot read '{given}': {e}"),
        ))
    })?;
    Ok(MultiValue::from_vec(vec![
        Value::String(lua.create_string(bytes)?),
        Value::String(lua.create_string(format!("@{}", path.display()))?),
    ]))
}

/// Returns the bytes of the regular file `path`, at most [`MAX_READ`] of them.
fn read_bounded(path: &Path) -> std::io::Result<Vec<u8>> {
    crate::files::check_regular(path)?;
    let len = std::fs::metadata(path)?.len();
    if len > MAX_READ {
        return Err(std::io::Error::other(format!(
            "the file has {len} bytes; a scene script reads files of at most {MAX_READ} bytes"
        )));
    }
    std::fs::read(path)
}

/// `find_scene_module(name)`: the loader of module `name` from a `.lua` file in the scene's
/// folders and its path, or nil and where it looked.
fn find_module(lua: &Lua, folders: &Folders, name: &str) -> mlua::Result<MultiValue> {
    let loc = super::args::caller_loc(lua);
    let valid = !name.is_empty()
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-' || b == b'.')
        && !name.split('.').any(str::is_empty);
    if !valid {
        return Err(mlua::Error::external(Error::fault_at(
            Fault::Sandbox,
            &loc,
            format!(
                "require('{name}'): a module name is letters, digits, '_' and '-' in parts \
                 joined by '.' (modules are Lua files in the scene's folders)"
            ),
        )));
    }
    let stem = name.replace('.', std::path::MAIN_SEPARATOR_STR);
    let mut looked = String::new();
    for candidate in [format!("{stem}.lua"), format!("{stem}/init.lua")] {
        match folders.resolve(&candidate) {
            Ok(path) => {
                let bytes = read_bounded(&path).map_err(|e| {
                    mlua::Error::external(Error::fault_at(
                        Fault::Other,
                        &loc,
                        format!("cannot read module '{name}': {e}"),
                    ))
                })?;
                let source = strip_script_header(&bytes);
                let f = lua
                    .load(&*source)
                    .set_name(format!("@{}", path.display()))
                    .set_mode(ChunkMode::Text)
                    .into_function()?;
                return Ok(MultiValue::from_vec(vec![
                    Value::Function(f),
                    Value::String(lua.create_string(path.display().to_string())?),
                ]));
            }
            Err(Unreadable::Outside(real)) => {
                return Err(mlua::Error::external(Error::fault_at(
                    Fault::Sandbox,
                    &loc,
                    folders.outside_message("module", &candidate, &real),
                )));
            }
            Err(Unreadable::NotFound) => looked.push_str(&format!(
                "\n\tno file '{candidate}' in the working directory or the script's folder"
            )),
        }
    }
    Ok(MultiValue::from_vec(vec![
        Value::Nil,
        Value::String(lua.create_string(looked)?),
    ]))
}

/// Returns script text as the stock `lua` reads it: without a UTF-8 byte-order mark, and with a
/// first line starting `#` (a `#!` line) blanked, so line numbers stay those of the file.
pub(super) fn strip_script_header(source: &[u8]) -> std::borrow::Cow<'_, [u8]> {
    let source = source.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(source);
    if source.first() == Some(&b'#') {
        let rest = source
            .iter()
            .position(|&b| b == b'\n')
            .map_or(&[][..], |i| &source[i..]);
        return std::borrow::Cow::Owned(rest.to_vec());
    }
    std::borrow::Cow::Borrowed(source)
}

/// The Lua half of the sandbox: `io`, `require`, `package`, `dofile` and `loadfile` over the
/// two Rust functions that read the scene's folders. Returns the `io` table.
const PRELUDE: &str = include_str!("sandbox.lua");

/// How long past its budget a script stuck inside one library call may run before the
/// [`watchdog`] ends the process.
pub const WATCHDOG_GRACE: Duration = Duration::from_secs(10);

/// The watchdog thread of one script run; dropping it stops the thread.
pub(super) struct Watchdog {
    done: Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.done.store(true, std::sync::atomic::Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

/// Starts a thread that ends the process once `clock`'s script has run [`WATCHDOG_GRACE`] past
/// its budget: the Lua hook stops a script between instructions, and this catches the one case
/// it cannot, a single library call that runs for ever (a string pattern that backtracks over
/// a long subject is quadratic or worse), printing the budget's message.
pub(super) fn watchdog(clock: &Arc<ScriptClock>) -> Watchdog {
    let done = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (clock, stop) = (Arc::clone(clock), Arc::clone(&done));
    let thread = std::thread::Builder::new()
        .name("script-watchdog".into())
        .spawn(move || {
            while !stop.load(std::sync::atomic::Ordering::SeqCst) {
                let left = (clock.budget + WATCHDOG_GRACE).saturating_sub(clock.used());
                if left.is_zero() && clock.running() {
                    let at = {
                        let s = clock.state.lock().unwrap_or_else(|e| e.into_inner());
                        s.line.as_ref().map_or(s.name.clone(), Loc::to_string)
                    };
                    eprintln!(
                        "error: {at}: {}, inside one library call that cannot be stopped \
                         between instructions; caustic ends here",
                        clock.overrun(None)
                    );
                    std::process::exit(1);
                }
                std::thread::park_timeout(
                    left.clamp(Duration::from_millis(50), Duration::from_secs(1)),
                );
            }
        })
        .ok();
    Watchdog { done, thread }
}
