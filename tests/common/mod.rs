//! Helpers shared by the integration tests: corpus paths, running scripts, rendering films.
#![allow(dead_code)]

use caustic::camera::Camera;
use caustic::desc::{RenderDesc, SceneDesc};
use caustic::film::{Film, Window};
use caustic::integrator::{GiMode, Settings};
use caustic::lua::run_source;
use caustic::progress::NoProgress;
use caustic::scene::Scene;
use caustic::scene::build::build_scene;
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::rc::Rc;

/// Returns true, after printing one line naming the test and the missing folder, when the
/// shared corpus is not beside the checkout (a fresh clone): the test then skips. Under
/// `CI=true`, where the corpus is always present, a missing corpus fails the test instead.
pub fn skip_without_corpus(test: &str) -> bool {
    let root = corpus("");
    if root.is_dir() {
        return false;
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{test}: the shared corpus {} is missing (CI=true requires it)",
        root.display()
    );
    // Straight to stderr: the test harness captures print! but not the stream itself.
    let line = format!("skipped {test}: no shared corpus at {}\n", root.display());
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    true
}

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

/// Returns the folder tests share for `gr.water_mesh`'s generated meshes (`CAUSTIC_CACHE`): kept
/// between runs, so the final scene's 2M-triangle water is generated once per checkout.
pub fn mesh_cache() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-mesh-cache")
}

/// Copies every file under `from` that a scene reads (all but `.lua` scripts and hidden entries
/// such as a `.cache/` of generated meshes) to the same place under `to`.
pub fn copy_assets(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap();
        if name.to_string_lossy().starts_with('.') {
            continue;
        }
        if path.is_dir() {
            copy_assets(&path, &to.join(name));
        } else if path.extension().is_none_or(|e| e != "lua") {
            std::fs::copy(&path, to.join(name)).unwrap();
        }
    }
}

/// Returns a command running the built `caustic` binary, its generated meshes in
/// [`mesh_cache`].
pub fn caustic() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustic"));
    cmd.env("CAUSTIC_CACHE", mesh_cache());
    cmd
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

/// Runs a script, rendering every `gr.render` call into a film with the command line's default
/// settings (photon maps where a light asks for them); nothing is written to disk.
pub fn render_films(
    src: &[u8],
    name: &str,
    dir: &Path,
) -> Result<Vec<(RenderDesc, Camera, Film)>, caustic::Error> {
    render_films_with(src, name, dir, &centre_ray())
}

/// The settings the closed-form tests are written for: one ray through each pixel's centre (the
/// course's sampling, so a pixel is the value along one known ray), with the per-pixel light and
/// gather counts of the library defaults.
pub fn centre_ray() -> Settings {
    let d = Settings::default();
    let spp = match d.sampling {
        caustic::render::Sampling::Stratified { spp }
        | caustic::render::Sampling::Jittered { spp }
        | caustic::render::Sampling::Noise { spp, .. } => spp,
        caustic::render::Sampling::Adaptive { .. } => 1,
    };
    let mut photons = d.photons.clone();
    if let caustic::integrator::photon_map::Indirect::Gather { rays } = &mut photons.indirect {
        *rays *= spp;
    }
    Settings {
        sampling: caustic::render::Sampling::Stratified { spp: 1 },
        light_samples: d.light_samples * spp,
        photons,
        ..d
    }
}

/// [`render_films`] with `settings`.
pub fn render_films_with(
    src: &[u8],
    name: &str,
    dir: &Path,
    settings: &Settings,
) -> Result<Vec<(RenderDesc, Camera, Film)>, caustic::Error> {
    let films = Rc::new(RefCell::new(Vec::new()));
    let sink = Rc::clone(&films);
    let settings = settings.clone();
    run_source(
        src,
        name,
        dir,
        Box::new(move |desc: &SceneDesc, r: &RenderDesc| {
            let mut scene = build_scene(desc, r)?;
            let camera = Camera::new(&r.camera, r.width, r.height);
            let film = render_scene(&mut scene, &camera, r.width, r.height, &settings);
            sink.borrow_mut().push((r.clone(), camera, film));
            Ok(())
        }),
    )?;
    Ok(Rc::try_unwrap(films).ok().unwrap().into_inner())
}

/// Returns the frame settings of the course's renderer: one centre ray per pixel, no photon maps.
pub fn whitted() -> Settings {
    Settings {
        gi: GiMode::Off,
        ..centre_ray()
    }
}

/// Renders the whole `width × height` image of `scene` through the one frame call.
pub fn render_scene(
    scene: &mut Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    settings: &Settings,
) -> Film {
    render_frame(
        scene,
        camera,
        Window::full(width, height),
        settings,
        &NoProgress,
    )
    .0
}

/// Renders `window` of `scene` through `camera` with `settings` as a frame does: plans it once
/// (applying the plan to the scene, [`caustic::frame::plan`]) and runs the plan's passes.
pub fn render_frame(
    scene: &mut Scene,
    camera: &Camera,
    window: Window,
    settings: &Settings,
    progress: &dyn caustic::progress::Progress,
) -> (Film, caustic::frame::Stats) {
    let plan = caustic::frame::plan(scene, settings);
    caustic::frame::render(scene, camera, window, settings, plan, progress)
}

/// [`render_frame`] with no progress, on a pool of `threads` threads.
pub fn render_on_threads(
    threads: usize,
    scene: &mut Scene,
    camera: &Camera,
    window: Window,
    settings: &Settings,
) -> (Film, caustic::frame::Stats) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| render_frame(scene, camera, window, settings, &NoProgress))
}

/// Asserts that `part`, a render of `window` alone, equals that window of the full frame `full`
/// bit for bit.
pub fn assert_window_of(part: &Film, full: &Film, window: Window) {
    let (w, h) = window.size();
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x + window.x0, y + window.y0);
            assert_eq!(part.get(x, y), full.get(fx, fy), "window pixel ({x}, {y})");
        }
    }
}

/// Renders a corpus script as if run from its own folder.
pub fn render_corpus_script(path: &Path) -> Vec<(RenderDesc, Camera, Film)> {
    let src = std::fs::read(path).unwrap();
    render_films(&src, &path.display().to_string(), path.parent().unwrap()).unwrap()
}

/// A glTF file built by a test: one binary buffer of typed views plus JSON written around it.
#[derive(Default)]
pub struct GltfFile {
    /// The buffer's bytes, every view starting on a 4-byte boundary.
    pub bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl GltfFile {
    /// Appends raw bytes as a buffer view and returns the view's index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
            bytes.len()
        ));
        self.views.len() - 1
    }

    /// Appends a buffer view given as raw JSON (one that may lie outside the buffer); returns
    /// its index.
    pub fn raw_view(&mut self, json: &str) -> usize {
        self.views.push(json.to_owned());
        self.views.len() - 1
    }

    /// Appends an accessor with raw JSON members over a new view of `bytes`; returns its index.
    pub fn accessor(&mut self, bytes: &[u8], members: &str) -> usize {
        let view = self.view(bytes);
        self.accessors
            .push(format!(r#"{{"bufferView":{view},{members}}}"#));
        self.accessors.len() - 1
    }

    /// Appends `FLOAT` data as a `VEC3` or `VEC2` (`kind`) accessor; returns its index.
    pub fn floats(&mut self, kind: &str, values: &[f32]) -> usize {
        let width = if kind == "VEC2" { 2 } else { 3 };
        let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
        let mut members = format!(
            r#""componentType":5126,"count":{},"type":"{kind}""#,
            values.len() / width
        );
        if width == 3 && !values.is_empty() {
            let fold = |f: fn(f32, f32) -> f32| {
                let axis = |k: usize| values.iter().skip(k).step_by(3).copied().reduce(f).unwrap();
                format!("[{},{},{}]", axis(0), axis(1), axis(2))
            };
            members += &format!(r#","min":{},"max":{}"#, fold(f32::min), fold(f32::max));
        }
        self.accessor(&bytes, &members)
    }

    /// Appends indices as `u8` (5121), `u16` (5123) or `u32` (5125) `component`s.
    pub fn indices(&mut self, component: u32, values: &[u32]) -> usize {
        let bytes: Vec<u8> = match component {
            5121 => values.iter().map(|&i| i as u8).collect(),
            5123 => values
                .iter()
                .flat_map(|&i| (i as u16).to_le_bytes())
                .collect(),
            _ => values.iter().flat_map(|&i| i.to_le_bytes()).collect(),
        };
        let members = format!(
            r#""componentType":{component},"count":{},"type":"SCALAR""#,
            values.len()
        );
        self.accessor(&bytes, &members)
    }

    /// Returns the JSON: `rest` holds the other top-level members (scenes, nodes, meshes, …);
    /// `uri` names the buffer's data (`None` for a GLB's BIN chunk).
    pub fn json(&self, uri: Option<&str>, rest: &str) -> String {
        let uri = uri.map_or(String::new(), |u| format!(r#""uri":"{u}","#));
        format!(
            r#"{{"asset":{{"version":"2.0"}},{rest},"buffers":[{{{uri}"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        )
    }

    /// Writes `name.gltf` and `name.bin` into `dir`; returns the `.gltf` path.
    pub fn write_external(&self, dir: &Path, name: &str, rest: &str) -> PathBuf {
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        let json = self.json(Some(&format!("{name}.bin")), rest);
        std::fs::write(&path, json).unwrap();
        path
    }

    /// Writes `name.gltf` with the buffer embedded as a base64 data URI; returns its path.
    pub fn write_embedded(&self, dir: &Path, name: &str, rest: &str) -> PathBuf {
        use base64::Engine;
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let uri = format!("data:application/octet-stream;base64,{data}");
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, self.json(Some(&uri), rest)).unwrap();
        path
    }

    /// Returns the GLB bytes of the file.
    pub fn glb(&self, rest: &str) -> Vec<u8> {
        glb(&self.json(None, rest), &self.bin)
    }

    /// Writes `name.glb` into `dir`; returns its path.
    pub fn write_glb(&self, dir: &Path, name: &str, rest: &str) -> PathBuf {
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, self.glb(rest)).unwrap();
        path
    }
}

/// Returns a GLB container of the glTF `json` and the `bin` chunk, each padded to 4 bytes.
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// The fuzz properties' proptest settings: `PROPTEST_CASES` cases (`default_cases` without it),
/// no failure files.
pub fn proptest_config(default_cases: u32) -> proptest::test_runner::Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default_cases);
    proptest::test_runner::Config {
        cases,
        failure_persistence: None,
        ..proptest::test_runner::Config::default()
    }
}

/// One edit of a byte string, for the fuzz properties' mutations: overwrite a byte, flip a bit,
/// set a 32-bit word, insert, delete or truncate. Each property draws the kinds it wants.
#[derive(Clone, Debug)]
pub enum Edit {
    Set(usize, u8),
    Flip(usize, u8),
    Word(usize, u32),
    Insert(usize, u8),
    Delete(usize),
    Truncate(usize),
}

/// Returns `valid` with `edits` applied, each position taken modulo the length at its turn; an
/// edit that needs more bytes than there are does nothing.
pub fn mutate(valid: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = valid.to_vec();
    for e in edits {
        let n = b.len().max(1);
        match *e {
            Edit::Set(i, v) if !b.is_empty() => b[i % n] = v,
            Edit::Flip(i, bit) if !b.is_empty() => b[i % n] ^= 1 << bit,
            Edit::Word(i, w) if b.len() >= 4 => {
                let at = i % (b.len() - 3);
                b[at..at + 4].copy_from_slice(&w.to_le_bytes());
            }
            Edit::Insert(i, v) => b.insert(i % (b.len() + 1), v),
            Edit::Delete(i) if !b.is_empty() => {
                b.remove(i % n);
            }
            Edit::Truncate(i) => b.truncate(i % (b.len() + 1)),
            _ => {}
        }
    }
    b
}

/// Asserts two meshes hold the same data (every field but `source`).
pub fn assert_same_mesh(
    a: &caustic::geometry::mesh::MeshData,
    b: &caustic::geometry::mesh::MeshData,
) {
    assert_eq!(a.positions, b.positions, "positions");
    assert_eq!(a.normals, b.normals, "normals");
    assert_eq!(a.uvs, b.uvs, "uvs");
    assert_eq!(a.triangles, b.triangles, "triangles");
    assert_eq!(a.materials, b.materials, "materials");
    assert_eq!(
        a.triangle_materials, b.triangle_materials,
        "triangle materials"
    );
}

/// Runs a command, asserting it succeeds (its stderr and stdout in the failure message).
pub fn run_ok(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "command failed: {}\n{}",
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    out
}

/// Returns every `.lua` file under `dir`, sorted.
pub fn lua_scripts(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(lua_scripts(&path));
        } else if path.extension().is_some_and(|e| e == "lua") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// Returns the ```lua blocks of the user guide (`docs/guide.md`).
pub fn guide_examples() -> Vec<String> {
    let guide = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/guide.md"))
        .expect("docs/guide.md");
    let mut out = Vec::new();
    let mut block: Option<String> = None;
    for line in guide.lines() {
        match (&mut block, line.trim()) {
            (None, "```lua") => block = Some(String::new()),
            (Some(_), "```") => out.push(block.take().unwrap()),
            (Some(b), _) => {
                b.push_str(line);
                b.push('\n');
            }
            (None, _) => {}
        }
    }
    out
}

/// Returns a fresh folder under `target/test-output/` holding the files the guide's examples
/// name (`tri.obj`, `tiles.png`, `room.glb`).
pub fn guide_dir(name: &str) -> PathBuf {
    let dir = out_dir(name);
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    // A triangle and a point light above it, each under its own node.
    let mut room = GltfFile::default();
    room.floats("VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    room.write_glb(
        &dir,
        "room",
        r#""scene":0,"scenes":[{"nodes":[0,1]}],
        "nodes":[{"mesh":0},{"translation":[0,2,1],"extensions":{"KHR_lights_punctual":{"light":0}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":100}]}},
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
    );
    let tiles = image::RgbImage::from_fn(8, 8, |x, y| {
        if (x / 4 + y / 4) % 2 == 0 {
            image::Rgb([230, 230, 230])
        } else {
            image::Rgb([40, 60, 90])
        }
    });
    tiles.save(dir.join("tiles.png")).unwrap();
    dir
}

/// Returns a transform call statement's variable (`n` of `n:rotate('y', 30)`), or `None` for any
/// other statement.
fn transform_call(statement: &str) -> Option<&str> {
    let (var, call) = statement.split_once(':')?;
    let is_name = !var.is_empty()
        && var
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.[]".contains(c));
    let is_call = ["translate(", "rotate(", "scale("]
        .iter()
        .any(|f| call.starts_with(f))
        && call.ends_with(')');
    (is_name && is_call).then_some(var)
}

/// Returns `src` with every node's transform calls in the reverse order, and how many runs it
/// reversed: each run of consecutive `v:translate`, `v:rotate` or `v:scale` statements on one
/// variable (one a line, or several separated by `;`, across lines) is reversed in place. This
/// is how the two eras' copies of the course's hier.lua and macho-cows.lua differ: one read in
/// the other's order renders the other's image. Lines holding no reversed call stay as they are.
pub fn reverse_transform_calls(src: &str) -> (String, usize) {
    let lines: Vec<&str> = src.lines().collect();
    let mut statements: Vec<Vec<String>> = lines
        .iter()
        .map(|l| match l.trim() {
            t if t.starts_with("--") => Vec::new(),
            t => t
                .split(';')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
        })
        .collect();
    let slots: Vec<(usize, usize)> = statements
        .iter()
        .enumerate()
        .flat_map(|(i, s)| (0..s.len()).map(move |j| (i, j)))
        .collect();
    let original = statements.clone();
    let var_at = |k: usize| transform_call(&original[slots[k].0][slots[k].1]);
    let (mut k, mut runs) = (0, 0);
    while k < slots.len() {
        let Some(var) = var_at(k) else {
            k += 1;
            continue;
        };
        let mut end = k;
        while end + 1 < slots.len() && var_at(end + 1) == Some(var) {
            end += 1;
        }
        if end > k {
            runs += 1;
            for (slot, from) in (k..=end).zip((k..=end).rev()) {
                let (i, j) = slots[slot];
                let (fi, fj) = slots[from];
                statements[i][j] = original[fi][fj].clone();
            }
        }
        k = end + 1;
    }
    let out: Vec<String> = lines
        .iter()
        .zip(statements.iter().zip(&original))
        .map(|(line, (new, old))| {
            if new == old {
                line.to_string()
            } else {
                let indent = &line[..line.len() - line.trim_start().len()];
                format!("{indent}{}", new.join("; "))
            }
        })
        .collect();
    (out.join("\n") + "\n", runs)
}

/// Returns the legacy copy of a modern course scene: every node's transform calls reversed
/// ([`reverse_transform_calls`]), meshes read by `readobj` (`gr.mesh(n, 'f.obj')` becomes
/// `gr.mesh(n, readobj('f.obj'))` after a `require('readobj')`) and `table.unpack` spelled
/// `unpack`, as scripts of the course before Fall 2015 are written.
pub fn legacy_copy(modern: &str) -> String {
    let (reversed, _) = reverse_transform_calls(modern);
    let mut out = String::from("require('readobj')\n");
    for line in reversed.lines() {
        let mut line = line.replace("table.unpack", "unpack");
        if let Some(start) = line.find("gr.mesh(") {
            // gr.mesh(name, 'file.obj') -> gr.mesh(name, readobj('file.obj'))
            let args = &line[start + "gr.mesh(".len()..];
            if let (Some(comma), Some(close)) = (args.find(','), args.rfind(')')) {
                let file = args[comma + 1..close].trim();
                if file.starts_with('\'') || file.starts_with('"') {
                    let name = &args[..comma];
                    line = format!(
                        "{}gr.mesh({name}, readobj({file})){}",
                        &line[..start],
                        &args[close + 1..]
                    );
                }
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// A glass ball on a floor under a point light, 64x48: both photon maps, a caustic, and an
/// irradiance cache (the photon-map and farm files' tests render it).
pub const GLASS_BALL: &str = "
    white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    glass = gr.material({0, 0, 0}, {0.1, 0.1, 0.1}, 50, 1.0, 1.5)
    root = gr.node('root')
    floor = gr.cube('floor'); floor:set_material(white); floor:scale(6, 0.5, 6); floor:translate(-3, -0.5, -5)
    root:add_child(floor)
    ball = gr.nh_sphere('ball', {0, 1, -2.5}, 1); ball:set_material(glass); root:add_child(ball)
    gr.render(root, 'ball.png', 64, 48, {0, 2, 3}, {0, -0.3, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
              {gr.light({0, 5, -2}, {1, 1, 1}, {1, 0, 0}, nil, 20000)})
";
