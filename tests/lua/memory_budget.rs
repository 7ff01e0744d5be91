//! The memory budget: what a scene creates (description entries, instances, CSG trees, mesh
//! triangles, textures, photon maps) is charged where it is made, and a scene over the budget is
//! an error naming the script line or file and the amount, never an allocation abort; the
//! top-level BVH stays near-linear on stacked instances.

use crate::common;

use crate::common::{caustic, out_dir};
use caustic::desc::{CameraDesc, NodeKind, RenderDesc, SceneDesc};
use caustic::lua::{ScriptOptions, run_source_with};
use caustic::scene::build::build_scene;
use caustic::{Error, Loc};
use glam::{DAffine3, DVec3, Vec3};
use std::path::Path;

const MIB: u64 = 1 << 20;

/// Runs `src` as `test.lua` in `dir` under a budget of `budget` bytes, building the scene of
/// every `gr.render`; returns the first error's message.
fn build_error(src: &str, dir: &Path, budget: u64) -> String {
    let options = ScriptOptions {
        memory_budget: Some(budget),
        ..ScriptOptions::default()
    };
    let hook = Box::new(|desc: &SceneDesc, r: &RenderDesc| build_scene(desc, r).map(drop));
    match run_source_with(src.as_bytes(), "test.lua", dir, hook, options) {
        Ok(_) => panic!("the scene was expected to go over its budget:\n{src}"),
        Err(e) => e.to_string(),
    }
}

const RENDER: &str = "gr.render(root, 'x.png', 8, 8, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, \
                      {0, 0, 0}, {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0})})";

/// A CSG node whose operands are the same node, 40 levels deep, stands for a tree of 2^41 - 1
/// nodes: it was expanded node by node until the allocation failed (SIGABRT after 5 s and
/// 2.2 GB); now it is refused before expansion, at the line that made it, with the count.
#[test]
fn a_csg_dag_is_refused_before_it_is_expanded() {
    let src = format!(
        "m = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0)
         s = gr.sphere('s'); s:set_material(m); c = s
         for i = 1, 40 do c = gr.union('u' .. i, c, c) end
         root = gr.node('root'); root:add_child(c)
         {RENDER}"
    );
    let e = build_error(&src, Path::new("."), 1 << 30);
    assert_eq!(
        e,
        "test.lua:3: CSG node 'u40' expands to a tree of 2199023255551 nodes for each instance, \
         which would take 256.0 TiB, more than the 1024.0 MiB left of the memory budget of \
         1.0 GiB (--memory-budget GIB raises it)"
            .replace("1024.0 MiB", &left(&e)),
    );
}

/// Returns the "left" amount of a budget message (what the description itself took varies
/// with the platform's struct sizes only in the last digit).
fn left(message: &str) -> String {
    let (_, tail) = message.split_once("more than the ").unwrap();
    tail.split(" left").next().unwrap().to_string()
}

/// A DAG of nodes, each added as a child twice, 40 levels deep, stands for 2^40 placements: it
/// is refused before a placement is made, at the root's line (the old code gave up after 20
/// million node visits and 1 GB). At 22 levels, 4 Mi coincident spheres whose top-level BVH the
/// old `caustic info` was still building after 10 minutes, a 256 MiB budget refuses it the
/// same way.
#[test]
fn a_node_dag_is_refused_before_it_is_flattened() {
    for (levels, count, amount) in [(40, 1u64 << 40, "104.0 TiB"), (22, 1 << 22, "416.0 MiB")] {
        let src = format!(
            "m = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0)
             s = gr.sphere('s'); s:set_material(m); root = s
             for i = 1, {levels} do
                 local n = gr.node('n' .. i); n:add_child(root); n:add_child(root); root = n
             end
             {RENDER}"
        );
        let e = build_error(&src, Path::new("."), 256 * MIB);
        let want = format!(
            "test.lua:4: the scene under this node expands to {count} placements, which would \
             take {amount}, more than the"
        );
        assert!(e.starts_with(&want), "{e}");
        assert!(e.ends_with("of the memory budget of 256.0 MiB (--memory-budget GIB raises it)"));
    }
}

/// Writes `bomb.gltf` into `dir`: 60 KB whose 1,000 nodes each place one mesh of 100
/// triangle-strip primitives, all sharing one 30,000-index accessor: 3·10⁹ triangles. The old
/// loader read every primitive in full and aborted (SIGABRT under a 4 GB limit after 5 s).
fn write_gltf_bomb(dir: &Path) {
    let mut buf: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    buf.extend(std::iter::repeat_n(0u8, 30_000));
    let data = base64_encode(&buf);
    let prims = vec![r#"{"attributes":{"POSITION":0},"indices":1,"mode":5}"#; 100].join(",");
    let nodes = vec![r#"{"mesh":0}"#; 1000].join(",");
    let roots: Vec<String> = (0..1000).map(|i| i.to_string()).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":30000}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5121,"count":30000,"type":"SCALAR"}}],
        "meshes":[{{"primitives":[{prims}]}}],
        "nodes":[{nodes}],
        "scenes":[{{"nodes":[{}]}}],"scene":0}}"#,
        buf.len(),
        roots.join(",")
    );
    assert!(
        json.len() < 64_000,
        "the file stays tiny: {} bytes",
        json.len()
    );
    std::fs::write(dir.join("bomb.gltf"), json).unwrap();
}

/// Returns standard base64 of `bytes` (with padding).
fn base64_encode(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The glTF bomb is charged per primitive before it is read: with 64 MiB, primitive 79 of the
/// first node does not fit (each takes 840 KB: 3 vertices, 30,000 indices and 29,998
/// triangles, read and merged).
#[test]
fn gltf_primitives_sharing_one_accessor_are_charged_before_they_are_read() {
    let dir = out_dir("budget-gltf-bomb");
    write_gltf_bomb(&dir);
    let src = format!(
        "m = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0)
         root = gr.mesh('bomb', 'bomb.gltf'); root:set_material(m)
         {RENDER}"
    );
    let e = build_error(&src, &dir, 64 * MIB);
    let file = dir.join("bomb.gltf");
    let want = format!(
        "test.lua:2: cannot load mesh 'bomb.gltf': {}: mesh 0 primitive 79 under node 0: \
         3 vertices and 30000 indices, which would take 820.5 KiB, more than the",
        file.display()
    );
    assert!(e.starts_with(&want), "{e}");
}

/// 1,024,000 instances (just under the legacy check's 2^20 placements) of a CSG tree of 1,023
/// nodes: each instance expands its own tree, 128 GB in all, which the old build did until it
/// aborted (SIGABRT at 12 GB after 30 s). Now the instances and their placements are charged
/// first, then each tree, and the tree that does not fit is named at its line.
#[test]
fn a_million_instances_each_holding_a_csg_tree_are_refused() {
    let src = format!(
        "m = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0)
         s = gr.sphere('s'); s:set_material(m); c = s
         for i = 1, 9 do c = gr.union('u' .. i, c, c) end
         root = gr.node('root')
         for i = 1, 1024 do
             local r = gr.node('r'); r:translate(i, 0, 0); root:add_child(r)
             for j = 1, 1000 do
                 local k = gr.node('k'); k:translate(0, j, 0); k:add_child(c); r:add_child(k)
             end
         end
         {RENDER}"
    );
    let e = build_error(&src, Path::new("."), 1 << 30);
    assert!(
        e.starts_with(
            "test.lua:3: CSG node 'u9' expands to a tree of 1023 nodes for each instance, \
             which would take 127.9 KiB, more than the"
        ),
        "{e}"
    );
}

/// A 1 MiB name given to a million nodes was copied into each node's entry (1 TB: the old
/// code aborted); the copies are charged, so with `--memory-budget 0.0625` (64 MiB) the node
/// that does not fit is named at its line, through the command line's flag.
#[test]
fn a_long_name_copied_into_many_nodes_is_refused() {
    let dir = out_dir("budget-names");
    std::fs::write(
        dir.join("names.lua"),
        "name = string.rep('x', 1048576)\nroot = gr.node('root')\n\
         for i = 1, 1000000 do root:add_child(gr.node(name)) end\n",
    )
    .unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["info", "names.lua", "--memory-budget", "0.0625"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with(
            "error: names.lua:3: a node named by 1048576 bytes would take 1.0 MiB, more than the"
        ),
        "{stderr}"
    );
    assert!(
        stderr.contains("of the memory budget of 64.0 MiB"),
        "{stderr}"
    );
}

/// Returns a description of `n` spheres placed at the origin, the `k`-th scaled by
/// `1 + k·grow` (0: all coincident; above: concentric), under one root, with its render.
fn stacked_spheres(n: usize, grow: f64) -> (SceneDesc, RenderDesc) {
    let mut desc = SceneDesc::default();
    let loc = Loc::internal();
    let root = desc.add_node("root", NodeKind::Group, loc.clone());
    for k in 0..n {
        let s = desc.add_node("s", NodeKind::Sphere, loc.clone());
        desc.nodes[s.0 as usize].transform =
            DAffine3::from_scale(DVec3::splat(1.0 + k as f64 * grow));
        desc.nodes[root.0 as usize].children.push((s, loc.clone()));
    }
    let render = RenderDesc {
        root,
        output: "x.png".into(),
        width: 8,
        height: 8,
        camera: CameraDesc {
            eye: Vec3::new(0.0, 0.0, 5.0),
            view: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_deg: 50.0,
        },
        ambient: Vec3::ZERO,
        lights: Vec::new(),
        loc,
        settings: Vec::new(),
    };
    (desc, render)
}

/// 65,536 coincident spheres, and 65,536 concentric ones: obvhs's PLOC built their top-level
/// BVH in time growing with the square of the stack (32,000 coincident took 43 s, 8,000
/// concentric 3.8 s: minutes here); the stacked scenes are now built by the binned SAH builder.
/// The tree is right: a ray down the axis meets the smallest sphere at t = 4, or the largest
/// (radius 1 + 65535·10⁻⁵) at t = 5 − r.
#[test]
fn stacked_instances_build_a_correct_top_level_bvh() {
    for (grow, radius) in [(0.0, 1.0), (1e-5, 1.0 + 65535.0 * 1e-5)] {
        let (desc, render) = stacked_spheres(65_536, grow);
        let scene = build_scene(&desc, &render).unwrap();
        assert_eq!(scene.instances.len(), 65_536);
        let ray =
            caustic::geometry::ray::Ray::new(glam::Vec3A::new(0.0, 0.0, 5.0), -glam::Vec3A::Z);
        let hit = scene.intersect(&ray).expect("the stack is hit");
        assert!(
            (hit.t - (5.0 - radius as f32)).abs() < 1e-4,
            "t = {}",
            hit.t
        );
        assert!(scene.account.held() > 65_536 * 400, "{:?}", scene.account);
    }
}

/// Writes a `size × size` black PNG to `path`.
fn write_png(path: &Path, size: u32) {
    let img = image::RgbImage::new(size, size);
    img.save(path).unwrap();
}

/// A texture is charged from its header before it is decoded: a 4096² RGB PNG takes 48 MiB
/// decoded and 48 MiB kept, more than a 64 MiB budget holds. One file named by two spellings
/// (`t.png`, `./t.png`) is decoded once, so a 128 MiB budget holds a scene naming it twice.
#[test]
fn textures_are_charged_from_their_header_and_decoded_once_per_file() {
    let dir = out_dir("budget-texture");
    write_png(&dir.join("t.png"), 4096);
    let src = format!(
        "a = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0, 0, 1, 0, 't.png')
         b = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0, 0, 1, 0, './t.png')
         root = gr.sphere('s'); root:set_material(a)
         {RENDER}"
    );
    let e = build_error(&src, &dir, 64 * MIB);
    let want = format!(
        "test.lua:1: texture {} (4096x4096 pixels decoded) would take 96.0 MiB, more than the",
        dir.join("t.png").display()
    );
    assert!(e.starts_with(&want), "{e}");
    let options = ScriptOptions {
        memory_budget: Some(128 * MIB),
        ..ScriptOptions::default()
    };
    let hook = Box::new(|desc: &SceneDesc, r: &RenderDesc| {
        let scene = build_scene(desc, r)?;
        assert!(scene.account.held() >= 96 * MIB && scene.account.held() < 100 * MIB);
        Ok(())
    });
    run_source_with(src.as_bytes(), "test.lua", &dir, hook, options).unwrap();
}

/// A light's photons are charged before they are traced, at its line: 10⁹ photons (the most a
/// light may ask for) take 44.7 GiB at 48 bytes a stored photon. The old code set out to trace
/// them (minutes of tracing, growing towards tens of GB), in a render and in `caustic photons`.
#[test]
fn photon_maps_are_charged_per_light_before_they_are_traced() {
    let src = "m = gr.material({1, 1, 1}, {0, 0, 0}, 0)
        root = gr.cube('floor'); root:set_material(m); root:scale(10, 0.1, 10)
        big = gr.light({0, 5, 0}, {1, 1, 1}, {1, 0, 0}, 100, 1000000000)
        gr.render(root, 'x.png', 8, 8, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0}, {big})";
    let options = ScriptOptions {
        memory_budget: Some(1 << 30),
        ..ScriptOptions::default()
    };
    let hook = Box::new(|desc: &SceneDesc, r: &RenderDesc| {
        let settings = caustic::integrator::Settings::default();
        let progress = caustic::progress::NoProgress;
        caustic::frame::render_desc(desc, r, 1.0, None, &settings, &progress).map(drop)
    });
    let e = run_source_with(src.as_bytes(), "test.lua", Path::new("."), hook, options)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "test.lua:3: this light's 1000000000 photons for the global map would take 44.7 GiB"
        ),
        "{e}"
    );
    // `caustic photons` draws the maps of the scene it builds itself: charged the same way.
    let dir = out_dir("budget-photons");
    std::fs::write(dir.join("test.lua"), src).unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["photons", "test.lua", "--memory-budget", "1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&format!("error: {e}")), "{stderr}");
}

/// An OBJ is charged from its faces before tobj parses it: one face of 2^20 corners fans into
/// 1,048,574 triangles, 26 MB of indices, over a 16 MiB budget.
#[test]
fn obj_faces_are_charged_before_they_are_parsed() {
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
    for k in 0..1 << 20 {
        text.push_str([" 1", " 2", " 3"][k % 3]);
    }
    let budget = caustic::budget::Budget::new(16 * MIB);
    let e = caustic::io::obj::parse_obj_with(&text, Path::new("fan.obj"), &budget.account())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("fan.obj: its 1048574 triangles would take"),
        "{e}"
    );
    assert_eq!(budget.used(), 0, "nothing stays charged");
}

/// Every scene in `scenes/` (and its folders) builds under the default budget: `caustic info`
/// builds the scene of each of its renders.
#[test]
fn every_scene_in_scenes_builds_under_the_default_budget() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scripts = common::lua_scripts(&root.join("scenes"));
    assert!(scripts.len() >= 10, "{scripts:?}");
    for script in scripts {
        let out = caustic()
            .current_dir(root)
            .arg("info")
            .arg(&script)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{}: {stderr}", script.display());
        assert!(!stderr.contains("memory budget"), "{stderr}");
    }
}

/// The description's own entries are charged for good: what a script made stays charged after
/// its scenes are dropped, and nothing else does.
#[test]
fn the_description_is_charged_and_scenes_give_their_bytes_back() {
    let src = format!(
        "m = gr.material({{1, 1, 1}}, {{0, 0, 0}}, 0)
         root = gr.sphere('s'); root:set_material(m)
         {RENDER}"
    );
    let options = ScriptOptions {
        memory_budget: Some(64 * MIB),
        ..ScriptOptions::default()
    };
    let hook = Box::new(|desc: &SceneDesc, r: &RenderDesc| {
        let before = desc.budget.used();
        let scene = build_scene(desc, r)?;
        assert!(desc.budget.used() > before);
        drop(scene);
        assert_eq!(desc.budget.used(), before);
        Ok::<(), Error>(())
    });
    let desc = run_source_with(src.as_bytes(), "test.lua", Path::new("."), hook, options).unwrap();
    let entries = size_of::<caustic::desc::MaterialDesc>()
        + size_of::<caustic::desc::NodeDesc>()
        + 1
        + size_of::<caustic::desc::LightDesc>()
        + size_of::<RenderDesc>()
        + size_of::<caustic::desc::LightId>()
        + "x.png".len();
    assert_eq!(desc.budget.used(), entries as u64);
}

/// A script that generates water meshes in a loop writes a file for each: the files are charged,
/// so the loop ends at the budget instead of filling the disk.
#[test]
fn generated_mesh_files_are_charged_so_a_loop_cannot_fill_the_disk() {
    let dir = out_dir("budget-generated");
    let src = "for i = 1, 1000 do
                 gr.water_mesh('w', {n = 65, size = 1, amplitude = 0.001 * i})
               end";
    let options = ScriptOptions {
        memory_budget: Some(1 << 20),
        ..ScriptOptions::default()
    };
    let e = run_source_with(
        src.as_bytes(),
        "test.lua",
        &dir,
        Box::new(|_, _| Ok(())),
        options,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("generated water mesh"), "{e}");
    let written = std::fs::read_dir(dir.join(".cache")).map_or(0, |d| d.count());
    // 65 x 65 x 60 B = 253 KiB each: at most four fit in 1 MiB.
    assert!((1..=4).contains(&written), "{written} files written");
}
