//! `gr.gltf`: a glTF file's default-scene hierarchy as `gr.node`s, its meshes read one by one in
//! their own frames, drawing what `gr.mesh` of the same file draws; the file's punctual lights
//! on request; errors at the script line.

use crate::common::{GltfFile, out_dir, render_films_with, run_lua_in, whitted};
use caustic::camera::Camera;
use caustic::desc::{NodeKind, RenderDesc};
use caustic::film::Film;
use glam::{Vec3, vec3};
use std::path::Path;

/// Writes `dir/two.glb`: a parent node translated by (0.3, −0.2, −1) holding a child rotated
/// 30° about y that holds a unit quad in its xy plane (a coloured matte glTF material), and,
/// when `light`, a node at (0.5, 2, 0.25) with a point light of colour (1, 0.5, 0.25) and
/// 683 cd.
fn write_two_nodes(dir: &Path, light: bool) {
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[
            -0.5, -0.5, 0.0, 0.5, -0.5, 0.0, 0.5, 0.5, 0.0, -0.5, 0.5, 0.0,
        ],
    );
    f.indices(5125, &[0, 1, 2, 0, 2, 3]);
    let (s, c) = 15f32.to_radians().sin_cos();
    let (roots, light_node, lights) = if light {
        (
            "[0,2]",
            r#",{"translation":[0.5,2,0.25],"extensions":{"KHR_lights_punctual":{"light":0}}}"#,
            r#""extensionsUsed":["KHR_lights_punctual"],
            "extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","color":[1,0.5,0.25],"intensity":683}]}},"#,
        )
    } else {
        ("[0]", "", "")
    };
    let rest = format!(
        r#""scene":0,"scenes":[{{"nodes":{roots}}}],{lights}
        "nodes":[{{"name":"parent","translation":[0.3,-0.2,-1],"children":[1]}},
          {{"name":"child","rotation":[0,{s},0,{c}],"mesh":0}}{light_node}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.3,0.2,1],"metallicFactor":0,"roughnessFactor":1}}}}],
        "meshes":[{{"name":"quad","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}]"#
    );
    f.write_glb(dir, "two", &rest);
}

/// Renders `src` (run in `dir`) with the course's renderer and returns every image.
fn films(src: &str, dir: &Path) -> Vec<(RenderDesc, Camera, Film)> {
    render_films_with(src.as_bytes(), "test.lua", dir, &whitted()).unwrap()
}

/// Returns the largest difference of two films of the same size over every pixel and channel.
fn largest_difference(a: &Film, b: &Film, (w, h): (u32, u32)) -> f32 {
    let mut worst = 0.0f32;
    for y in 0..h {
        for x in 0..w {
            let d = Vec3::from(a.get(x, y)) - Vec3::from(b.get(x, y));
            worst = worst.max(d.abs().max_element());
        }
    }
    worst
}

const RENDER: &str = "gr.render(root, 'x.png', 48, 48, {0, 0, 3}, {0, 0, -1}, {0, 1, 0}, 50, \
                      {0.1, 0.1, 0.1}, {gr.light({1, 2, 4}, {0.8, 0.8, 0.8}, {1, 0, 0})})";

/// The two-node file placed by `gr.gltf` (the hierarchy as nodes, the mesh in its own frame)
/// renders what `gr.mesh` of it (every transform baked into the vertices) renders.
#[test]
fn a_hierarchy_renders_as_the_baked_mesh() {
    let dir = out_dir("gr-gltf-hierarchy");
    write_two_nodes(&dir, false);
    let desc = run_lua_in("n = gr.gltf('two', 'two.glb')", &dir).unwrap();
    let names: Vec<&str> = desc.nodes.iter().map(|n| n.name.as_str()).collect();
    assert_eq!(names, ["two", "parent", "child", "quad"]);
    assert!(matches!(desc.nodes[3].kind, NodeKind::Mesh(_)));
    assert_eq!(desc.nodes[0].children.len(), 1);
    let baked = films(&format!("root = gr.mesh('m', 'two.glb')\n{RENDER}"), &dir);
    let nodes = films(&format!("root = gr.gltf('g', 'two.glb')\n{RENDER}"), &dir);
    let lit = (0..48 * 48)
        .filter(|&i| Vec3::from(baked[0].2.get(i % 48, i / 48)).max_element() > 0.2)
        .count();
    assert!(lit > 100, "the quad covers {lit} pixels");
    let worst = largest_difference(&baked[0].2, &nodes[0].2, (48, 48));
    assert!(worst <= 1e-5, "pixels differ by {worst}");
}

/// The returned node instanced twice under different transforms draws two copies, each the
/// copy `gr.mesh` of the file draws under the same transforms.
#[test]
fn the_returned_node_instances_like_any_node() {
    let dir = out_dir("gr-gltf-instances");
    write_two_nodes(&dir, false);
    let place = |make: &str| {
        format!(
            "n = {make}\n\
             l = gr.node('l'); l:translate(-1, 0, 0); l:add_child(n)\n\
             r = gr.node('r'); r:translate(1, 0.3, 0); r:add_child(n)\n\
             root = gr.node('root'); root:add_child(l); root:add_child(r)\n{RENDER}"
        )
    };
    let baked = films(&place("gr.mesh('m', 'two.glb')"), &dir);
    let nodes = films(&place("gr.gltf('g', 'two.glb')"), &dir);
    let film = &nodes[0].2;
    let lit = |xs: std::ops::Range<u32>| {
        xs.flat_map(|x| (0..48).map(move |y| (x, y)))
            .filter(|&(x, y)| Vec3::from(film.get(x, y)).max_element() > 0.2)
            .count()
    };
    assert!(lit(0..20) > 50 && lit(28..48) > 50, "both copies drawn");
    let worst = largest_difference(&baked[0].2, film, (48, 48));
    assert!(worst <= 1e-5, "pixels differ by {worst}");
}

/// With `{lights = true}` the file's point light comes back as the second value, converted as
/// `caustic render file.glb` converts it (rgb = colour·intensity/(683π)): a matte floor under
/// it shows `kd·rgb·cos/d²`; without the option no light is made and the floor is dark.
#[test]
fn lights_true_returns_the_files_point_light() {
    let dir = out_dir("gr-gltf-lights");
    write_two_nodes(&dir, true);
    let scene = |opts: &str, lights: &str| {
        format!(
            "g, lights = gr.gltf('g', 'two.glb'{opts})\n\
             assert(type(lights) == 'table')\n\
             floor = gr.cube('floor'); floor:scale(4, 0.01, 4); floor:translate(-2, -0.01, -2)\n\
             floor:set_material(gr.material({{0.5, 0.5, 0.5}}, {{0, 0, 0}}, 0))\n\
             root = gr.node('root'); root:add_child(floor)\n\
             gr.render(root, 'x.png', 64, 64, {{0, 3, 0}}, {{0, -1, 0}}, {{0, 0, -1}}, 60, \
             {{0, 0, 0}}, {lights})"
        )
    };
    let with = films(&scene(", {lights = true}", "lights"), &dir);
    let (r, camera, film) = &with[0];
    assert_eq!(r.lights.len(), 1);
    let mut best = (f32::INFINITY, 0, 0, Vec3::ZERO);
    for y in 0..r.height {
        for x in 0..r.width {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let p = Vec3::from(ray.at(-ray.origin.y / ray.dir.y));
            let d = (p - vec3(0.5, 0.0, 0.25)).length();
            if d < best.0 {
                best = (d, x, y, p);
            }
        }
    }
    let (_, x, y, p) = best;
    let to_light = vec3(0.5, 2.0, 0.25) - p;
    let (d2, cos) = (to_light.length_squared(), to_light.normalize().y);
    let expected = vec3(1.0, 0.5, 0.25) / std::f32::consts::PI * 0.5 * cos / d2;
    let got = Vec3::from(film.get(x, y));
    assert!(
        (got - expected).abs().max_element() < 0.01 * expected.max_element(),
        "pixel ({x}, {y}): {got} against {expected}"
    );

    // Without the option the table is empty and no light is made; a black light stands in.
    let without = scene("", "{gr.light({0, 10, 0}, {0, 0, 0}, {1, 0, 0})}");
    let without = without.replace(
        "assert(type(lights) == 'table')",
        "assert(type(lights) == 'table' and #lights == 0)",
    );
    let dark = films(&without, &dir);
    let (r, _, film) = &dark[0];
    assert_eq!(r.lights.len(), 1);
    let brightest = (0..r.width * r.height)
        .map(|i| Vec3::from(film.get(i % r.width, i / r.width)).max_element())
        .fold(0.0f32, f32::max);
    assert_eq!(brightest, 0.0);
}

/// Bad options and a missing file are errors naming the script line (and the file).
#[test]
fn bad_options_and_missing_files_name_the_line() {
    let dir = out_dir("gr-gltf-errors");
    write_two_nodes(&dir, false);
    let err = |src: &str| run_lua_in(src, &dir).unwrap_err().to_string();
    let cases = [
        (
            "\n\nn = gr.gltf('g', 'two.glb', {light = true})",
            "test.lua:3:",
            "unknown option 'light'",
        ),
        (
            "\nn = gr.gltf('g', 'two.glb', {lights = 1})",
            "test.lua:2:",
            "'lights' must be a boolean",
        ),
        (
            "n = gr.gltf('g', 'two.glb', 'lights')",
            "test.lua:1:",
            "options table expected",
        ),
        (
            "\nn = gr.gltf('g', 'missing.glb')",
            "test.lua:2:",
            "missing.glb",
        ),
        (
            "n = gr.gltf('g')",
            "test.lua:1:",
            "bad argument #2 to 'gltf'",
        ),
    ];
    for (src, line, what) in cases {
        let e = err(src);
        assert!(e.starts_with(line) && e.contains(what), "{src}: {e}");
    }
    // A file that is not glTF names the script line and the file.
    std::fs::write(dir.join("bad.glb"), b"glTF garbage").unwrap();
    let e = err("\n\nn = gr.gltf('g', 'bad.glb')");
    assert!(e.starts_with("test.lua:3:") && e.contains("bad.glb"), "{e}");
}

/// Each mesh gr.gltf places reads the whole file at the scene build, so a file of many meshes
/// over a large buffer is refused at the script line, naming gr.mesh: three meshes over a
/// declared 2 GB buffer (6 GB of reading, over the 4 GiB bound) are an error; the same file
/// declaring a 1 kB buffer is read into nodes. The buffer is never opened at script time.
#[test]
fn many_meshes_over_a_large_buffer_are_refused() {
    let dir = out_dir("gr-gltf-reread");
    let file = |bytes: u64| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,2]}}],
            "nodes":[{{"mesh":0}},{{"mesh":1}},{{"mesh":2}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}},
                      {{"primitives":[{{"attributes":{{"POSITION":0}}}}]}},
                      {{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                           "min":[0,0,0],"max":[1,1,0]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"byteLength":{bytes},"uri":"big.bin"}}]}}"#
        )
    };
    std::fs::write(dir.join("huge.gltf"), file(2_000_000_000)).unwrap();
    std::fs::write(dir.join("small.gltf"), file(1000)).unwrap();
    let err = run_lua_in("n = gr.gltf('huge', 'huge.gltf')", &dir)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(":1") && err.contains("huge.gltf") && err.contains("gr.mesh"),
        "{err}"
    );
    let desc = run_lua_in("n = gr.gltf('small', 'small.gltf')", &dir).unwrap();
    assert!(desc.nodes.iter().filter(|n| n.name == "mesh 2").count() == 1);
}
