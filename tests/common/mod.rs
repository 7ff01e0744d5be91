//! Helpers shared by the integration tests: corpus paths, running scripts, rendering films.
#![allow(dead_code)]

use caustic::camera::Camera;
use caustic::render::{Film, render};
use caustic::scene::build::build_scene;
use caustic::scene::desc::{RenderDesc, SceneDesc};
use caustic::scene::lua::run_source;
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::rc::Rc;

/// Returns a path inside the read-only CS488 corpus beside the checkout.
pub fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/corpus/cs488")
        .join(rel)
}

/// Returns the folder of the standard A4 scenes.
pub fn a4_assets() -> PathBuf {
    corpus("shraacha__cs488/A4/Assets")
}

/// Returns a fresh, empty folder under `target/test-output/` for one test's files.
pub fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target/test-output")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Returns a command running the built `caustic` binary.
pub fn caustic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_caustic"))
}

/// Runs script text named `test.lua` (paths resolve in `dir`) without rendering.
pub fn run_lua_in(src: &str, dir: &Path) -> Result<SceneDesc, caustic::Error> {
    run_source(src.as_bytes(), "test.lua", dir, Box::new(|_, _| Ok(())))
}

/// Runs script text named `test.lua` without rendering.
pub fn run_lua(src: &str) -> Result<SceneDesc, caustic::Error> {
    run_lua_in(src, Path::new("."))
}

/// Returns the error message a script fails with; panics when it succeeds.
pub fn lua_error(src: &str) -> String {
    match run_lua(src) {
        Ok(_) => panic!("script was expected to fail:\n{src}"),
        Err(e) => e.to_string(),
    }
}

/// Runs a script, rendering every `gr.render` call into a film (nothing is written to disk).
pub fn render_films(
    src: &[u8],
    name: &str,
    dir: &Path,
) -> Result<Vec<(RenderDesc, Camera, Film)>, caustic::Error> {
    let films = Rc::new(RefCell::new(Vec::new()));
    let sink = Rc::clone(&films);
    run_source(
        src,
        name,
        dir,
        Box::new(move |desc: &SceneDesc, r: &RenderDesc| {
            let scene = build_scene(desc, r)?;
            let camera = Camera::new(&r.camera, r.width, r.height);
            let (film, _) = render(&scene, &camera, r.width, r.height);
            sink.borrow_mut().push((r.clone(), camera, film));
            Ok(())
        }),
    )?;
    Ok(Rc::try_unwrap(films).ok().unwrap().into_inner())
}

/// Renders a corpus script as if run from its own folder.
pub fn render_corpus_script(path: &Path) -> Vec<(RenderDesc, Camera, Film)> {
    let src = std::fs::read(path).unwrap();
    render_films(&src, &path.display().to_string(), path.parent().unwrap()).unwrap()
}
