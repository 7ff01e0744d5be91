//! The Lua layer: runs a CS488 scene script on an embedded Lua 5.4 and fills a [`SceneDesc`].
//!
//! Nothing below this layer knows Lua exists: a script run yields plain data, and `gr.render`
//! hands the description as it stands to a [`RenderHook`] (the CLI builds and renders the scene
//! there). The layer's parts:
//! - `sandbox.rs` (with `sandbox.lua`): the Lua state, built from what a scene needs (no
//!   processes, native code, bytecode or writes; reads confined to the scene's folders), its
//!   time budget and the command line's watchdog (`docs/security.md`);
//! - `gr.rs`: the `gr` table, built from one list of (name, call kind, function);
//! - `inline.rs`: the inline form of `gr.mesh`, its vertex and face tables checked element by
//!   element;
//! - `gltf.rs`: `gr.gltf`, a glTF file's node hierarchy rebuilt as `gr.node`s;
//! - `generated.rs`: meshes a script generates (`gr.water_mesh`), cached as files;
//! - [`settings`]: a scene's own render settings (`gr.settings`);
//! - [`args`]: argument checks with lauxlib's messages and the calling script line;
//! - `legacy/`: the course's legacy API ([`Dialect`], `--dialect`): the transform order, the
//!   built-in `readobj`, the Lua 5.1 names, and the warning when a modern run looks legacy.
//! - [`globals`]: the globals set before the script runs (`-D NAME=VALUE`).
//!
//! This module owns what a run shares: the description being filled (and the memory budget it
//! is charged to, [`crate::budget`]), path resolution and warnings. Paths (meshes, textures,
//! output images, `require`d modules) resolve against the working directory first, as the course
//! does, then against the script's folder, so a corpus scene runs both from its own folder and
//! by path from anywhere; what they name must lie in the scene's folders
//! ([`sandbox::Folders`]), and an image `gr.render` names must be written inside the script's
//! folder or the working directory ([`check_scene_output`]). Files are only resolved here;
//! the scene build reads them. `gr.gltf` reads a glTF file's JSON here (its node
//! hierarchy, which the script gets back as nodes; buffers and images wait for the build). Two
//! legacy cases read files here: `readobj`, whose tables the
//! script needs at once, and the legacy warning's check, which reads mesh files' vertices for
//! their boxes (once per run, only when the transform order matters).
//!
//! ```lua
//! m = gr.material({0.7, 0.6, 1.0}, {0.5, 0.4, 0.8}, 25)
//! s = gr.sphere('s'); s:set_material(m)
//! root = gr.node('root'); root:add_child(s)
//! gr.render(root, 'out.png', 256, 256, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50,
//!           {0.3, 0.3, 0.3}, {gr.light({0, 10, 10}, {1, 1, 1}, {1, 0, 0})})
//! ```

pub mod args;
mod generated;
pub mod globals;
mod gltf;
mod gr;
mod inline;
mod legacy;
mod lights;
pub mod sandbox;
pub mod settings;

pub use legacy::Dialect;

use crate::desc::{MeshId, RenderDesc, SceneDesc};
use crate::error::{Error, Loc, Result};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Called by every `gr.render`: receives the description as it stands and the render call.
pub type RenderHook = Box<dyn FnMut(&SceneDesc, &RenderDesc) -> Result<()>>;

/// Largest image `gr.render` accepts, in pixels (about 8k × 8k).
pub use crate::film::MAX_PIXELS;

/// How a script run treats recoverable problems, and what it is given before it runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScriptOptions {
    /// `--missing-textures=warn`: a missing texture or bump image is a warning (once per file) and
    /// the material renders with `kd` instead, rather than an error.
    pub missing_textures_warn: bool,
    /// Most bytes the script's Lua state may hold; `None` for [`sandbox::MAX_LUA_MEMORY`].
    pub memory_limit: Option<usize>,
    /// Most bytes the description and the scenes built from it may take (`--memory-budget`);
    /// `None` for [`crate::budget::default_limit`].
    pub memory_budget: Option<u64>,
    /// `--dialect`: how transforms compose. `None` (no `--dialect`) reads the script the
    /// modern way and warns when it looks legacy (`legacy/`).
    pub dialect: Option<Dialect>,
    /// Globals set before the script runs (`-D NAME=VALUE`; see [`globals`]).
    pub globals: Vec<globals::Global>,
    /// Stop the script with [`Error::Interrupted`] once [`crate::interrupt::requested`] (the
    /// command line's Ctrl-C), rather than let it run to its end.
    pub interruptible: bool,
    /// `--script-time`: how long the script may run, not counting its renders; `None` for
    /// [`sandbox::DEFAULT_SCRIPT_TIME`].
    pub script_time: Option<std::time::Duration>,
    /// `--allow-read`: folders the scene may read besides its own ([`sandbox::Folders`]).
    pub allow_read: Vec<PathBuf>,
    /// `--trusted-script`: the whole Lua standard library, for a script the user trusts.
    pub trusted: bool,
    /// End the process (with the budget's message) when the script overruns its time inside
    /// one library call that the Lua hook cannot stop ([`sandbox::watchdog`]); the command
    /// line sets it, a library caller would rather not be ended.
    pub watchdog: bool,
}

impl ScriptOptions {
    /// Returns a fresh budget of [`ScriptOptions::memory_budget`] bytes.
    pub fn budget(&self) -> crate::budget::Budget {
        self.budget_within(crate::files::ReadScope::any())
    }

    /// Returns a fresh budget of [`ScriptOptions::memory_budget`] bytes for a scene whose files
    /// may name files only in `scope`.
    pub fn budget_within(&self, scope: crate::files::ReadScope) -> crate::budget::Budget {
        let limit = self
            .memory_budget
            .unwrap_or_else(crate::budget::default_limit);
        crate::budget::Budget::scoped(limit, scope)
    }
}

/// Runs the script at `path`, calling `hook` for every `gr.render`; returns the final description.
pub fn run_script(path: &Path, hook: RenderHook) -> Result<SceneDesc> {
    run_script_with(path, hook, ScriptOptions::default())
}

/// Runs the script at `path` with `options`.
pub fn run_script_with(path: &Path, hook: RenderHook, options: ScriptOptions) -> Result<SceneDesc> {
    let source = crate::files::read_regular(path).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!("cannot read script: {e}"),
    })?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    run_source_with(&source, &path.display().to_string(), &dir, hook, options)
}

/// Runs a test's Lua `src` (its renders not run) and returns the scene and the camera of its
/// first `gr.render`, at that render's size.
#[cfg(test)]
pub(crate) fn test_scene(src: &[u8]) -> (crate::scene::Scene, crate::camera::Camera) {
    let no_render = Box::new(|_: &_, _: &_| Ok(()));
    let desc = run_source(src, "t.lua", ".".as_ref(), no_render).unwrap();
    let r = &desc.renders[0];
    let scene = crate::scene::build_scene(&desc, r).unwrap();
    (
        scene,
        crate::camera::Camera::new(&r.camera, r.width, r.height),
    )
}

/// Runs script text named `name` (used in messages), resolving relative paths in the working
/// directory and then in `script_dir`.
pub fn run_source(
    source: &[u8],
    name: &str,
    script_dir: &Path,
    hook: RenderHook,
) -> Result<SceneDesc> {
    run_source_with(source, name, script_dir, hook, ScriptOptions::default())
}

/// Runs script text with `options` (see [`run_source`]).
pub fn run_source_with(
    source: &[u8],
    name: &str,
    script_dir: &Path,
    hook: RenderHook,
    options: ScriptOptions,
) -> Result<SceneDesc> {
    let folders = Rc::new(sandbox::Folders::new(script_dir, &options.allow_read));
    let budget = options.script_time.unwrap_or(sandbox::DEFAULT_SCRIPT_TIME);
    let clock = sandbox::ScriptClock::start(budget, name);
    // The script's clock stops while gr.render renders: only the script's own time counts.
    let mut inner = hook;
    let paused = std::sync::Arc::clone(&clock);
    let hook: RenderHook = Box::new(move |desc, render| {
        paused.pause();
        let result = inner(desc, render);
        paused.resume();
        result
    });
    let state = Rc::new(RefCell::new(State {
        desc: SceneDesc {
            missing_textures_warn: options.missing_textures_warn,
            budget: options.budget_within(folders.read_scope()),
            ..SceneDesc::default()
        },
        warned_images: HashSet::new(),
        warned_albedo: HashSet::new(),
        script_dir: script_dir.to_path_buf(),
        folders: Rc::clone(&folders),
        hook,
        mesh_cache: HashMap::new(),
        dialect: options.dialect.unwrap_or_default(),
        watch: options.dialect.is_none().then(legacy::Watch::default),
    }));
    // The Lua state takes part of the same memory: never more than the command's budget.
    let limit = options.memory_limit.unwrap_or_else(|| {
        let budget = state.borrow().desc.budget.limit();
        sandbox::MAX_LUA_MEMORY.min(usize::try_from(budget).unwrap_or(usize::MAX))
    });
    let limits = sandbox::Limits {
        memory: limit,
        interruptible: options.interruptible,
        trusted: options.trusted,
    };
    let (lua, lines) = sandbox::new_lua(&limits, &folders, &clock).map_err(convert_error)?;
    gr::install(&lua, &state).map_err(convert_error)?;
    legacy::install(&lua, &state).map_err(convert_error)?;
    globals::set(&lua, &options.globals)?;
    let _watchdog = options.watchdog.then(|| sandbox::watchdog(&clock));
    lua.load(&*sandbox::strip_script_header(source))
        .set_name(format!("@{name}"))
        .set_mode(mlua::chunk::ChunkMode::Text)
        .exec()
        .and_then(|()| match clock.stop() {
            // A stop the script caught still ends the run.
            Some(e) => Err(mlua::Error::external(e)),
            None => Ok(()),
        })
        .map_err(|e| match (clock.stop(), memory_error(&e)) {
            (Some(stop), _) => stop,
            (None, Some(message)) => {
                let loc = lines.last().unwrap_or_else(|| Loc {
                    file: name.into(),
                    line: 0,
                });
                Error::at(
                    &loc,
                    format!("{message}: the script's Lua state reached its limit of {limit} bytes"),
                )
            }
            (None, None) => convert_error(e),
        })?;
    clock.pause();
    drop(lua);
    let state = Rc::try_unwrap(state)
        .map_err(|_| Error::Lua("internal: scene state still borrowed".into()))?
        .into_inner();
    Ok(state.desc)
}

/// Returns an error unless `output`, an image the script at `script` names in `gr.render`, is
/// written inside the script's folder tree or the working directory's tree (only in the folder
/// itself when that is the home folder or the root), once its folder's and its own symlinks are
/// followed: a scene may not choose to overwrite files elsewhere (a user's `-o` may). A folder
/// that does not exist is left to the write to report.
pub fn check_scene_output(script: &Path, output: &Path) -> std::result::Result<(), String> {
    let Ok((target, _)) = crate::files::check_output(output) else {
        return Ok(());
    };
    let folder = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(folder) = std::fs::canonicalize(&folder) else {
        return Ok(());
    };
    let script_dir = match script.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let trees: Vec<PathBuf> = [script_dir, PathBuf::from(".")]
        .iter()
        .filter_map(|d| std::fs::canonicalize(d).ok())
        .collect();
    // The home folder and the root are never a scene's tree: run from there, a scene writes in
    // that folder itself, not anywhere below it (`~/Pictures/…`).
    let home = std::env::var_os("HOME").and_then(|h| std::fs::canonicalize(h).ok());
    let whole_tree = |t: &Path| t.parent().is_some() && home.as_deref() != Some(t);
    if trees
        .iter()
        .any(|t| folder == *t || (whole_tree(t) && folder.starts_with(t)))
    {
        return Ok(());
    }
    let shown: Vec<String> = trees.iter().map(|t| t.display().to_string()).collect();
    Err(format!(
        "gr.render names the output '{}', which would be written in {}, outside the scene's \
         folder and the working directory ({}); a scene writes images only inside those \
         (docs/security.md): name the output with -o to write it elsewhere",
        output.display(),
        folder.display(),
        shown.join(", ")
    ))
}

/// What the `gr` functions of one script run share.
struct State {
    desc: SceneDesc,
    script_dir: PathBuf,
    /// The folders the scene may read.
    folders: Rc<sandbox::Folders>,
    hook: RenderHook,
    /// Mesh files named so far, by canonical path and the glTF mesh `gr.gltf` reads alone
    /// (`None`: the whole file).
    mesh_cache: HashMap<(PathBuf, Option<u32>), MeshId>,
    /// Missing images already warned about (`--missing-textures=warn`).
    warned_images: HashSet<String>,
    /// Script lines whose material was warned about for reflecting more than it receives (a
    /// loop making a thousand materials on one line warns once).
    warned_albedo: HashSet<String>,
    /// How transforms compose.
    dialect: Dialect,
    /// The legacy signs seen so far; `None` under an explicit `--dialect`.
    watch: Option<legacy::Watch>,
}

impl State {
    /// Returns the readable file `given` names: as given (working directory), else in the
    /// script's folder, inside the folders the scene may read; else the message saying why not,
    /// naming it as `what`.
    fn resolve_input(&self, what: &str, given: &str) -> std::result::Result<PathBuf, String> {
        self.folders.resolve(given).map_err(|e| match e {
            sandbox::Unreadable::NotFound => self.not_found(what, given),
            sandbox::Unreadable::Outside(real) => self.folders.outside_message(what, given, &real),
        })
    }

    /// Returns where to write `given`: as given when its folder exists, else in the script's folder.
    fn resolve_output(&self, given: &str) -> PathBuf {
        let folder_exists = |q: &Path| match q.parent() {
            None => true,
            Some(d) => d.as_os_str().is_empty() || d.is_dir(),
        };
        let p = Path::new(given);
        let q = self.script_dir.join(p);
        if folder_exists(p) || p.is_absolute() || !folder_exists(&q) {
            p.to_path_buf()
        } else {
            q
        }
    }

    /// Records a use of a legacy form at `loc` when the run is watched.
    fn saw(&mut self, sign: legacy::Sign, loc: &Loc) {
        if let Some(w) = &mut self.watch {
            w.saw(sign, loc);
        }
    }

    /// Prints a warning at `loc` and records it in the description.
    fn warn(&mut self, loc: &Loc, message: String) {
        let text = format!("{loc}: warning: {message}");
        eprintln!("{text}");
        self.desc.warnings.push(text);
    }

    /// Returns the message for a file `given` that resolves nowhere.
    fn not_found(&self, what: &str, given: &str) -> String {
        let cwd = std::env::current_dir().unwrap_or_default();
        // A script named without a folder (`scene.lua`) has the empty path as its folder.
        let dir = if self.script_dir.as_os_str().is_empty() {
            cwd.join("")
        } else {
            self.script_dir.clone()
        };
        if dir == cwd || dir == cwd.join("") {
            return format!(
                "{what} '{given}' not found (looked in the working directory {}, which holds the script)",
                cwd.display()
            );
        }
        format!(
            "{what} '{given}' not found (looked in the working directory {} and in the script's folder {})",
            cwd.display(),
            dir.display()
        )
    }
}

/// Returns the message of a Lua memory error, under any callback layers.
fn memory_error(e: &mlua::Error) -> Option<String> {
    match e {
        mlua::Error::MemoryError(message) => Some(message.clone()),
        mlua::Error::CallbackError { cause, .. } | mlua::Error::WithContext { cause, .. } => {
            memory_error(cause)
        }
        _ => None,
    }
}

/// Turns an mlua error into ours, unwrapping callback layers down to the original cause.
fn convert_error(e: mlua::Error) -> Error {
    match e {
        mlua::Error::CallbackError { cause, .. } => convert_error((*cause).clone()),
        mlua::Error::WithContext { cause, .. } => convert_error((*cause).clone()),
        mlua::Error::ExternalError(inner) => match inner.downcast_ref::<Error>() {
            Some(e) => e.clone(),
            None => Error::Lua(inner.to_string()),
        },
        mlua::Error::SyntaxError { message, .. } => Error::Lua(message),
        mlua::Error::RuntimeError(message) => Error::Lua(message),
        other => Error::Lua(other.to_string()),
    }
}
