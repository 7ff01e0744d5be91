//! The scene sandbox (`src/lua/sandbox.rs`, `docs/security.md`): every forbidden thing a scene
//! script might reach for is tried and refused at its line, with no side effect; what a scene
//! may do (read its folder, require its modules, load text) still works; the time budget stops
//! loops however they hide; outputs a scene names stay in its folders.

use crate::common::caustic;
use caustic::error::{Error, Fault};
use caustic::lua::{ScriptOptions, run_source_with};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A fresh, empty folder for one test outside any git checkout (a scene inside one may read the
/// whole checkout, so `target/test-output` would not test the folder boundary). Dropping it
/// removes the folder, and the process's parent folder once the last test's is gone, so runs
/// leave nothing in the system's temporary folder.
struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
        // Fails while another test's folder is still there; the last one to go removes it.
        if let Some(parent) = self.0.parent() {
            let _ = std::fs::remove_dir(parent);
        }
    }
}

/// Returns a fresh, empty [`Scratch`] folder named `name` for this test process.
fn out_dir(name: &str) -> Scratch {
    let dir = std::env::temp_dir()
        .join(format!("caustic-sandbox-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// Runs `src` as `test.lua` in `dir` with `options`, without rendering.
fn run_in(src: &[u8], dir: &Path, options: ScriptOptions) -> Result<(), Error> {
    run_source_with(src, "test.lua", dir, Box::new(|_, _| Ok(())), options).map(|_| ())
}

/// Options with a short time budget, so a loop the sandbox fails to stop fails the test fast.
fn quick() -> ScriptOptions {
    ScriptOptions {
        script_time: Some(Duration::from_millis(500)),
        ..ScriptOptions::default()
    }
}

/// Returns the error of a script that must fail, with its fault.
fn refused(src: &str, dir: &Path) -> (Fault, String) {
    match run_in(src.as_bytes(), dir, quick()) {
        Ok(()) => panic!("script was expected to fail:\n{src}"),
        Err(Error::Script { fault, message, .. }) => (fault, message),
        Err(e) => panic!("expected a located fault, got {e}"),
    }
}

#[test]
fn every_forbidden_library_function_is_refused_at_its_line_naming_the_opt_in() {
    let dir = out_dir("sandbox-forbidden");
    for call in [
        "os.execute('true')",
        "os.remove('x')",
        "os.rename('a', 'b')",
        "os.exit(0)",
        "os.getenv('HOME')",
        "os.tmpname()",
        "os.setlocale('C')",
        "io.popen('ls')",
        "io.output('x')",
        "io.input('x')",
        "io.read()",
        "io.tmpfile()",
        "package.loadlib('libc.so.6', '*')",
        "string.dump(function() end)",
        "debug.sethook()",
        "debug.getlocal(1, 1)",
        "debug.getregistry()",
    ] {
        let src = format!("local x = 1\n{call}\n");
        let (fault, message) = refused(&src, &dir);
        let name = call.split('(').next().unwrap();
        assert_eq!(fault, Fault::Sandbox, "{call}: {message}");
        assert!(message.contains(name), "{call}: {message}");
        assert!(message.contains("--trusted-script"), "{call}: {message}");
    }
}

#[test]
fn nothing_forbidden_has_a_side_effect() {
    let dir = out_dir("sandbox-side-effects");
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "keep me").unwrap();
    let marker = dir.join("marker");
    for src in [
        format!("os.execute('touch {}')", marker.display()),
        format!("io.popen('touch {}')", marker.display()),
        "os.remove('victim.txt')".to_string(),
        "os.rename('victim.txt', 'moved.txt')".to_string(),
        "io.open('victim.txt', 'w')".to_string(),
        "io.open('victim.txt', 'a')".to_string(),
        "io.open('victim.txt', 'r+')".to_string(),
        "io.open('new.txt', 'wb')".to_string(),
        "local f = io.open('victim.txt') f:write('x')".to_string(),
    ] {
        assert!(run_in(src.as_bytes(), &dir, quick()).is_err(), "{src}");
    }
    assert!(!marker.exists());
    assert!(!dir.join("moved.txt").exists() && !dir.join("new.txt").exists());
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
}

#[test]
fn collectgarbage_keeps_only_the_options_that_cannot_defeat_limits() {
    let dir = out_dir("sandbox-gc");
    let ok = "collectgarbage() collectgarbage('collect') assert(collectgarbage('count') > 0) \
              collectgarbage('step') assert(collectgarbage('isrunning'))";
    run_in(ok.as_bytes(), &dir, quick()).unwrap();
    for opt in ["stop", "restart", "incremental", "generational", "setpause"] {
        let (fault, message) = refused(&format!("collectgarbage('{opt}')"), &dir);
        assert_eq!(fault, Fault::Sandbox);
        assert!(message.contains(opt), "{message}");
    }
}

/// Returns a real Lua 5.4 binary chunk (what `luac` writes).
fn bytecode() -> Vec<u8> {
    let lua = mlua::Lua::new();
    lua.load("return 1").into_function().unwrap().dump(false)
}

#[test]
fn binary_chunks_are_refused_everywhere_a_chunk_enters() {
    let dir = out_dir("sandbox-bytecode");
    let chunk = bytecode();
    assert!(chunk.starts_with(b"\x1bLua"));
    // As the script itself.
    let e = run_in(&chunk, &dir, quick()).unwrap_err().to_string();
    assert!(e.contains("binary"), "{e}");
    // Through load, as a string and from a reader function.
    std::fs::write(dir.join("chunk.luac"), &chunk).unwrap();
    std::fs::write(dir.join("mod.lua"), &chunk).unwrap();
    let probe = "local s = io.open('chunk.luac', 'rb'):read('a')
                 local f, e = load(s) assert(f == nil and e:find('binary'), e)
                 local f, e = load(s, 'x', 'b') assert(f == nil and e:find('binary'), e)
                 local done = false
                 local f, e = load(function() if done then return nil end done = true return s end)
                 assert(f == nil and e:find('binary'), e)
                 local f, e = loadfile('chunk.luac') assert(f == nil and e:find('binary'), e)
                 assert(not pcall(dofile, 'chunk.luac'))";
    run_in(probe.as_bytes(), &dir, quick()).unwrap();
    // Through require, with a module file that holds bytecode.
    let e = run_in(b"require('mod')", &dir, quick())
        .unwrap_err()
        .to_string();
    assert!(e.contains("binary"), "{e}");
}

#[test]
fn text_chunks_modules_and_files_in_the_scene_folder_still_work() {
    let dir = out_dir("sandbox-allowed");
    std::fs::create_dir_all(dir.join("lib/deep")).unwrap();
    std::fs::write(dir.join("lib/deep/init.lua"), "return {x = 42}").unwrap();
    std::fs::write(
        dir.join("helper.lua"),
        "helper_loaded = (helper_loaded or 0) + 1 return 7",
    )
    .unwrap();
    std::fs::write(dir.join("data.txt"), "first line\r\n3.5 rest\nlast").unwrap();
    let src = "
        assert(require('lib.deep').x == 42)
        assert(require('helper') == 7 and require('helper') == 7 and helper_loaded == 1)
        assert(package.loaded.helper == 7)
        local f = assert(io.open('data.txt'))
        assert(f:read('l') == 'first line\\r')
        assert(f:read('n') == 3.5)
        assert(f:read('l') == ' rest')
        assert(f:read('a') == 'last')
        assert(f:read('l') == nil)
        local n = 0 for line in io.lines('data.txt') do n = n + 1 end assert(n == 3)
        assert(dofile('helper.lua') == 7 and helper_loaded == 2)
        assert(load('return 1 + 1')() == 2)
        local env = {}
        load('y = 5', 'c', 't', env)() assert(env.y == 5 and y == nil)
        assert(io.open('missing.txt') == nil)
        local co = coroutine.wrap(function() coroutine.yield(1) return 2 end)
        assert(co() == 1 and co() == 2)
        assert(os.time() > 0 and os.clock() >= 0 and type(os.date('%Y')) == 'string')
        assert(utf8.len('été') == 3 and string.format('%5.2f', math.pi) == ' 3.14')
        assert(getmetatable(gr.node('n')) == false)
        io.write('')
    ";
    run_in(src.as_bytes(), &dir, quick()).unwrap();
}

#[test]
fn files_outside_the_scene_folder_are_refused_however_they_are_named() {
    let outside = out_dir("sandbox-outside-secret");
    std::fs::write(outside.join("secret.txt"), "password").unwrap();
    std::fs::write(outside.join("secret.lua"), "return 'password'").unwrap();
    std::fs::write(
        outside.join("cube.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let dir = out_dir("sandbox-outside");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(outside.join("secret.txt"), dir.join("link.txt")).unwrap();
        std::os::unix::fs::symlink(&outside, dir.join("linkdir")).unwrap();
    }
    let abs = outside.join("secret.txt").display().to_string();
    let rel = format!(
        "../{}/secret.txt",
        outside.file_name().unwrap().to_string_lossy()
    );
    let mut names = vec![abs.clone(), rel.clone(), format!("sub/../{rel}")];
    if cfg!(unix) {
        names.push("link.txt".into());
        names.push("linkdir/secret.txt".into());
    }
    for name in &names {
        for src in [
            format!("io.open('{name}')"),
            format!("io.lines('{name}')"),
            format!("dofile('{name}')"),
            format!("loadfile('{name}')"),
        ] {
            let (fault, message) = refused(&src, &dir);
            assert_eq!(fault, Fault::Sandbox, "{src}: {message}");
            assert!(message.contains("--allow-read"), "{message}");
        }
    }
    let mesh = outside.join("cube.obj").display().to_string();
    let (fault, message) = refused(&format!("gr.mesh('m', '{mesh}')"), &dir);
    assert_eq!(fault, Fault::Sandbox, "{message}");
    let src = format!("gr.material({{1,1,1}}, {{0,0,0}}, 1, 0, 1, 0, '{abs}')");
    assert_eq!(refused(&src, &dir).0, Fault::Sandbox);
    // Modules: no path syntax in a name, and no module file outside.
    for name in ["../x", "/etc/passwd", "a..b", ""] {
        assert_eq!(
            refused(&format!("require('{name}')"), &dir).0,
            Fault::Sandbox
        );
    }
    // The user can widen the folders: the same mesh then loads.
    let options = ScriptOptions {
        allow_read: vec![outside.to_path_buf()],
        ..quick()
    };
    run_in(format!("gr.mesh('m', '{mesh}')").as_bytes(), &dir, options).unwrap();
}

#[test]
fn the_time_budget_stops_loops_wherever_they_hide() {
    let dir = out_dir("sandbox-time");
    for src in [
        "while true do end",
        "local t = {} for i = 1, math.huge do t[i % 10] = i end",
        "coroutine.wrap(function() while true do end end)()",
        "local co = coroutine.create(function() while true do end end) coroutine.resume(co)",
        "while true do pcall(function() while true do end end) end",
        "local function f() while true do end end \
         while true do xpcall(f, function(e) return e end) end",
        "local function f() return f() end f()",
        "local function f() pcall(f) pcall(f) end while true do f() end",
        "setmetatable({}, {__gc = function() while true do end end}) collectgarbage()",
        "local mt = {} setmetatable({}, mt) mt.__gc = function() while true do end end \
         collectgarbage() while true do end",
        "string.gsub(string.rep('a', 1000), 'a', function() while true do end end)",
        "table.sort({3, 2, 1, 5, 4}, function(a, b) while true do end end)",
        // Loops in C that take no memory: the sandbox answers or refuses them, then loops on.
        "assert(string.rep('', 2^62) == '' and (''):rep(2^62, '') == '') while true do end",
        "assert(not pcall(table.move, {}, 1, 2^62, 2)) while true do end",
    ] {
        let (fault, message) = refused(src, &dir);
        assert_eq!(fault, Fault::Sandbox, "{src}: {message}");
        assert!(
            message.contains("--script-time") || message.contains("__gc"),
            "{src}: {message}"
        );
    }
}

#[test]
fn a_library_call_that_never_returns_ends_the_command_with_the_budget_message() {
    let dir = out_dir("sandbox-watchdog");
    // One string.find call that backtracks for hours: no Lua instruction runs inside it.
    std::fs::write(
        dir.join("pattern.lua"),
        "local s = string.rep('a', 300000)\nprint(string.find(s, '.-.-.-b'))\n",
    )
    .unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["info", "--script-time", "0.5", "pattern.lua"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--script-time") && err.contains("library call"),
        "{err}"
    );
}

#[test]
fn a_script_saved_with_a_byte_order_mark_or_a_shebang_runs_with_its_own_line_numbers() {
    let dir = out_dir("sandbox-header");
    for prefix in [
        "\u{feff}",
        "#!/usr/bin/env lua\n",
        "\u{feff}#!/usr/bin/lua -x\n",
        "# comment\n",
    ] {
        let lines_before = prefix.matches('\n').count();
        let src = format!("{prefix}x = 1\nerror('here')\n");
        let e = run_in(src.as_bytes(), &dir, quick())
            .unwrap_err()
            .to_string();
        let line = lines_before + 2;
        assert!(e.contains(&format!("test.lua:{line}:")), "{prefix:?}: {e}");
    }
    run_in("\u{feff}gr.node('a')".as_bytes(), &dir, quick()).unwrap();
}

#[test]
fn a_trusted_script_gets_the_whole_library() {
    let dir = out_dir("sandbox-trusted");
    let options = ScriptOptions {
        trusted: true,
        ..quick()
    };
    let written = dir.join("w.txt");
    let src = format!(
        "assert(type(os.getenv('PATH')) == 'string') assert(io.open('{}', 'w')):close()",
        written.display()
    );
    run_in(src.as_bytes(), &dir, options).unwrap();
    assert!(written.exists());
}

/// Returns a scene that renders a 4 × 4 image to `output`.
fn tiny_scene(output: &str) -> String {
    format!(
        "s = gr.sphere('s') s:set_material(gr.material({{1, 1, 1}}, {{0, 0, 0}}, 1))
         r = gr.node('r') r:add_child(s)
         gr.render(r, '{output}', 4, 4, {{0, 0, 5}}, {{0, 0, -1}}, {{0, 1, 0}}, 50, {{0.1, 0.1, 0.1}},
                   {{gr.light({{0, 5, 5}}, {{1, 1, 1}}, {{1, 0, 0}})}})"
    )
}

#[test]
fn an_image_a_scene_names_outside_its_folders_is_refused_unless_the_user_names_it() {
    let elsewhere = out_dir("sandbox-output-elsewhere");
    let dir = out_dir("sandbox-output");
    let target: PathBuf = elsewhere.join("victim.png");
    std::fs::write(&target, "keep me").unwrap();
    std::fs::write(dir.join("s.lua"), tiny_scene(&target.display().to_string())).unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["render", "-q", "s.lua"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("-o"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
    // A symlink the scene ships at its output name is not a way out either.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&target, dir.join("out.png")).unwrap();
        std::fs::write(dir.join("t.lua"), tiny_scene("out.png")).unwrap();
        let out = caustic()
            .current_dir(&dir)
            .args(["render", "-q", "t.lua"])
            .output()
            .unwrap();
        assert!(!out.status.success());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
    }
    // The user's -o may name any place; a name inside the folder is written as before.
    let out = caustic()
        .current_dir(&dir)
        .args(["render", "-q", "s.lua", "-o"])
        .arg(elsewhere.join("chosen.png"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::write(dir.join("u.lua"), tiny_scene("inside.png")).unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["render", "-q", "u.lua"])
        .output()
        .unwrap();
    assert!(out.status.success() && dir.join("inside.png").exists());
}

/// Runs `src` in `dir`, building the scene of every `gr.render` (where mesh files are read).
fn build_in(src: &str, dir: &Path) -> Result<(), Error> {
    let hook = Box::new(
        |d: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
            caustic::scene::build::build_scene(d, r).map(|_| ())
        },
    );
    run_source_with(src.as_bytes(), "test.lua", dir, hook, quick()).map(|_| ())
}

#[test]
fn files_a_mesh_names_outside_the_scene_folder_are_refused() {
    let outside = out_dir("sandbox-nested-secret");
    std::fs::write(outside.join("lib.mtl"), "newmtl m\nKd 1 0 0\n").unwrap();
    std::fs::write(outside.join("data.bin"), [0u8; 36]).unwrap();
    let png = outside.join("t.png");
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 10, 10]))
        .save(&png)
        .unwrap();
    let dir = out_dir("sandbox-nested");
    let up = format!("../{}", outside.file_name().unwrap().to_string_lossy());
    std::fs::write(
        dir.join("a.obj"),
        format!("mtllib {up}/lib.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
    )
    .unwrap();
    std::fs::write(
        dir.join("b.mtl"),
        format!("newmtl m\nKd 1 1 1\nmap_Kd {}\n", png.display()),
    )
    .unwrap();
    std::fs::write(dir.join("b.obj"), "mtllib b.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
    std::fs::write(
        dir.join("c.gltf"),
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
            "min":[0,0,0],"max":[0,0,0]}}],"bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"uri":"{up}/data.bin","byteLength":36}}]}}"#
        ),
    )
    .unwrap();
    for mesh in ["a.obj", "b.obj", "c.gltf"] {
        let src = format!(
            "m = gr.mesh('m', '{mesh}') r = gr.node('r') r:add_child(m)
             gr.render(r, 'o.png', 4, 4, {{0, 0, 5}}, {{0, 0, -1}}, {{0, 1, 0}}, 50,
                       {{0, 0, 0}}, {{gr.light({{0, 5, 5}}, {{1, 1, 1}}, {{1, 0, 0}})}})"
        );
        let e = build_in(&src, &dir).unwrap_err().to_string();
        assert!(
            e.contains("outside the folders a scene may read"),
            "{mesh}: {e}"
        );
        // Named by the user, the same folder is readable.
        let options = ScriptOptions {
            allow_read: vec![outside.to_path_buf()],
            ..quick()
        };
        let hook = Box::new(
            |d: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
                caustic::scene::build::build_scene(d, r).map(|_| ())
            },
        );
        run_source_with(src.as_bytes(), "test.lua", &dir, hook, options).unwrap();
    }
}

#[test]
fn run_from_the_home_folder_a_scene_writes_only_in_it_not_below_it() {
    let home = out_dir("sandbox-home");
    let pictures = home.join("Pictures");
    std::fs::create_dir_all(&pictures).unwrap();
    std::fs::write(pictures.join("wedding.png"), "keep me").unwrap();
    let scenes = out_dir("sandbox-home-scenes");
    std::fs::write(scenes.join("s.lua"), tiny_scene("Pictures/wedding.png")).unwrap();
    // Renders `script` of the scenes' folder from the home folder, with HOME set to it.
    let render = |script: &str| {
        caustic()
            .current_dir(&home)
            .env("HOME", &*home)
            .args(["render", "-q"])
            .arg(scenes.join(script))
            .output()
            .unwrap()
    };
    let out = render("s.lua");
    assert!(
        !out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(pictures.join("wedding.png")).unwrap(),
        "keep me"
    );
    std::fs::write(scenes.join("t.lua"), tiny_scene("here.png")).unwrap();
    let out = render("t.lua");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(home.join("here.png").exists());
}

/// A test's scratch folder is gone once the test drops it: runs used to leave one
/// `caustic-sandbox-PID` tree in the system's temporary folder each.
#[test]
fn a_scratch_folder_is_removed_when_dropped() {
    let dir = out_dir("sandbox-scratch");
    std::fs::write(dir.join("f.txt"), "x").unwrap();
    let path = dir.to_path_buf();
    assert!(path.join("f.txt").exists());
    drop(dir);
    assert!(!path.exists(), "{} is still there", path.display());
}
