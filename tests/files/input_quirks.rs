//! Input that real tools write and numbers that are accepted but would render wrong: byte-order
//! marks and CRLF line ends in every text format, the inline `gr.mesh` form's argument errors,
//! and the numeric ranges the renderer enforces (each proved safe by a render at its edge).

use crate::common;

use crate::common::{GltfFile, assert_same_mesh, out_dir};
use caustic::io::gltf::load_gltf;
use caustic::io::obj::load_obj;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// The UTF-8 byte-order mark.
const BOM: &str = "\u{FEFF}";

/// Writes `text` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Returns `text` with every `\n` turned into `\r\n`, as Windows tools write it.
fn crlf(text: &str) -> String {
    text.replace('\n', "\r\n")
}

// ---- byte-order marks and CRLF ----

/// A quad whose first vertex matters: losing it shifts every face onto other vertices.
const QUAD_OBJ: &str = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
                        mtllib quad.mtl\nusemtl red\nf 1/1/1 2/2/1 3/2/1\nf 1/1/1 3/2/1 4/1/1\n";
const QUAD_MTL: &str = "newmtl red\nKd 0.8 0.1 0.1\nKs 0.2 0.2 0.2\nNs 10\n";

#[test]
fn obj_and_mtl_with_a_byte_order_mark_and_crlf_load_like_plain_files() {
    let dir = out_dir("quirks-obj-bom");
    write(&dir, "quad.mtl", QUAD_MTL);
    let plain = load_obj(&write(&dir, "plain.obj", QUAD_OBJ)).unwrap();
    assert_eq!(plain.positions[0], Vec3::ZERO);
    assert_eq!(plain.materials[0].kd, Vec3::new(0.8, 0.1, 0.1));
    let variants = [
        format!("{BOM}{QUAD_OBJ}"),
        crlf(QUAD_OBJ),
        format!("{BOM}{}", crlf(QUAD_OBJ)),
    ];
    for (i, text) in variants.iter().enumerate() {
        // The MTL gets the same treatment as its OBJ: a BOM would hide its `newmtl`.
        let sub = dir.join(format!("v{i}"));
        std::fs::create_dir_all(&sub).unwrap();
        let mtl = if text.starts_with(BOM) {
            format!("{BOM}{}", crlf(QUAD_MTL))
        } else {
            crlf(QUAD_MTL)
        };
        write(&sub, "quad.mtl", &mtl);
        let mesh = load_obj(&write(&sub, "quad.obj", text)).unwrap();
        assert_same_mesh(&mesh, &plain);
        assert_eq!(mesh.materials[0].name, "red", "variant {i}");
    }
}

#[test]
fn a_byte_order_mark_does_not_shift_the_faces_of_an_obj() {
    // Before the fix tobj dropped `\u{FEFF}v 0 0 0`, so face 1 2 3 used the old vertices 2, 3, 4.
    let dir = out_dir("quirks-obj-bom-shift");
    let text = format!("{BOM}v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n");
    let mesh = load_obj(&write(&dir, "tri.obj", &text)).unwrap();
    assert_eq!(mesh.positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(mesh.triangles, [[0, 1, 2]]);
    // A bad line is still reported at its own line number.
    let text = format!("{BOM}v 0 0 0\r\nv 1 x 0\r\n");
    let error = load_obj(&write(&dir, "bad.obj", &text)).unwrap_err();
    assert!(
        error
            .to_string()
            .ends_with("bad.obj:2: malformed number `x` in `v` line"),
        "{error}"
    );
}

/// The triangle `(1,0,0), (0,1,0), (0,0,1)` as one glTF node and mesh.
fn gltf_triangle() -> (GltfFile, &'static str) {
    let mut f = GltfFile::default();
    f.floats("VEC3", &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    let rest = r#""scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#;
    (f, rest)
}

#[test]
fn gltf_json_with_a_byte_order_mark_and_crlf_loads() {
    let dir = out_dir("quirks-gltf-bom");
    let (f, rest) = gltf_triangle();
    let plain = load_gltf(&f.write_external(&dir, "plain", rest)).unwrap();
    assert_eq!(plain.positions, [Vec3::X, Vec3::Y, Vec3::Z]);
    // A .gltf saved by a Windows editor: BOM and CRLF around the same JSON.
    let json = f.json(Some("plain.bin"), rest);
    let text = format!("{BOM}{}", crlf(&json));
    let mesh = load_gltf(&write(&dir, "bom.gltf", &text)).unwrap();
    assert_same_mesh(&mesh, &plain);
    // The same inside a GLB's JSON chunk: the chunk rebuilt around the marked JSON.
    let plain_glb = f.glb(rest);
    let old_len = u32::from_le_bytes(plain_glb[12..16].try_into().unwrap()) as usize;
    let mut json = format!("{BOM}{}", f.json(None, rest)).into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    let bin_chunk = &plain_glb[20 + old_len..];
    let total = (12 + 8 + json.len() + bin_chunk.len()) as u32;
    let mut glb = [&b"glTF"[..], &2u32.to_le_bytes(), &total.to_le_bytes()].concat();
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(json);
    glb.extend(bin_chunk);
    std::fs::write(dir.join("bom.glb"), &glb).unwrap();
    let mesh = load_gltf(&dir.join("bom.glb")).unwrap();
    assert_same_mesh(&mesh, &plain);
}

#[test]
fn a_study_curve_saved_as_csv_utf8_with_a_byte_order_mark_reads() {
    let dir = out_dir("quirks-csv-bom");
    let text = format!("{BOM}cpu_s,rel_rmse\r\n1.5,0.25\r\n3,0.125\r\n");
    let curve = caustic::study::Curve::read("other", &write(&dir, "curve.csv", &text)).unwrap();
    assert_eq!(curve.points, [(1.5, 0.25), (3.0, 0.125)]);
}

// ---- the inline form of gr.mesh ----

/// Returns the error of `gr.mesh('m', VERTS, FACES)` at line 2 of `test.lua`.
fn inline_error(verts: &str, faces: &str) -> String {
    common::lua_error(&format!("x = 1\nm = gr.mesh('m', {verts}, {faces})"))
}

const TRI: &str = "{{0,0,0},{1,0,0},{0,1,0}}";

#[test]
fn inline_mesh_faults_name_the_line_the_argument_and_the_element() {
    let bad3 = |detail: &str| format!("test.lua:2: bad argument #3 to 'mesh' ({detail})");
    let bad2 = |detail: &str| format!("test.lua:2: bad argument #2 to 'mesh' ({detail})");
    let cases = [
        (
            TRI,
            "{{1,2,'x'}}",
            bad3("face 1, index 3: integer expected, got string"),
        ),
        (
            TRI,
            "{{0,1,2},{0,1,2.5}}",
            bad3("face 2, index 3: integer expected, got 2.5 (no integer representation)"),
        ),
        (
            TRI,
            "{{0,1,1e300}}",
            bad3("face 1, index 3: integer expected, got 1e300 (beyond 64-bit integers)"),
        ),
        (
            TRI,
            "{{0,1,{}}}",
            bad3("face 1, index 3: integer expected, got table"),
        ),
        (
            TRI,
            "{{0,1,nil,2}}",
            bad3("face 1, index 3: integer expected, got nil"),
        ),
        (
            TRI,
            "{{0,1,5}}",
            bad3("face 1: index 5 out of range (0..3)"),
        ),
        (
            TRI,
            "{{0,1,-1}}",
            bad3("face 1: index -1 out of range (0..3)"),
        ),
        (TRI, "{1}", bad3("face 1 is not a table (got number)")),
        (TRI, "{{0,1}}", bad3("face 1 has fewer than 3 vertices")),
        (TRI, "'faces'", bad3("table of faces expected, got string")),
        (TRI, "nil", bad3("table of faces expected, got nil")),
        (
            "{{0,0,0},{1,0,0},{0,1,'y'}}",
            "{{0,1,2}}",
            bad2("vertex 3, entry 3: number expected, got string"),
        ),
        (
            "{{0,0,0},{1,0},{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got 2 entries"),
        ),
        (
            "{{0,0,0},{1,0,0,1},{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got 4 entries"),
        ),
        (
            "{{0,0,0},7,{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got number"),
        ),
        (
            "{{0,0,0},{1,0,0},{0,0/0,0}}",
            "{{0,1,2}}",
            bad2("vertex 3, entry 2: finite number expected, got NaN"),
        ),
        (
            "{{0,0,0},{1,0,0},{0,1,1e300}}",
            "{{0,1,2}}",
            bad2(
                "vertex 3, entry 3: number within single precision (|x| <= 3.4e38) expected, got 1e300",
            ),
        ),
    ];
    for (verts, faces, want) in cases {
        assert_eq!(inline_error(verts, faces), want, "{verts} {faces}");
    }
}

#[test]
fn inline_mesh_accepts_integral_floats_and_numeric_strings_as_lua_does() {
    let d = common::run_lua(&format!("m = gr.mesh('m', {TRI}, {{{{0.0, '1', 2}}}})")).unwrap();
    let meshes = caustic::scene::meshes::load_meshes(&d).unwrap();
    assert_eq!(meshes[0].triangles, [[0, 1, 2]]);
}

// ---- numeric ranges: refused outside, safe at the edge ----

/// A light list, a root and a camera around `body`, which places nodes under `root` with the
/// materials `edge` (reflectances at their largest) and `dim`.
fn ranged_scene(body: &str, lights: &str, eye: &str, ambient: &str) -> String {
    format!(
        "edge = gr.material({{10, 10, 10}}, {{10, 10, 10}}, 20)\n\
         dim = gr.material({{0.5, 0.5, 0.5}}, {{0, 0, 0}}, 0)\n\
         root = gr.node('root')\n{body}\n\
         gr.render(root, 'edge.png', 12, 12, {eye}, {{0, 0, -1}}, {{0, 1, 0}}, 90, {ambient}, {{{lights}}})\n"
    )
}

/// Renders every image of `script` with photon maps where its lights ask for them, and asserts
/// every pixel is finite, no sample was dropped as NaN or infinite, and something was lit.
fn assert_renders_finite(script: &str) {
    let dir = out_dir("quirks-edge");
    let frames = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let sink = std::rc::Rc::clone(&frames);
    caustic::lua::run_source(
        script.as_bytes(),
        "edge.lua",
        &dir,
        Box::new(move |desc, r| {
            let settings = common::centre_ray();
            let progress = caustic::progress::NoProgress;
            let frame = caustic::frame::render_desc(desc, r, 1.0, None, &settings, &progress)?;
            sink.borrow_mut().push(frame);
            Ok(())
        }),
    )
    .unwrap();
    for frame in frames.borrow().iter() {
        let pixels = &frame.film.pixels;
        assert!(pixels.iter().all(|p| p.is_finite()), "{script}");
        assert_eq!(frame.stats.render.nonfinite_samples, 0, "{script}");
        assert!(pixels.iter().any(|p| p.max_element() > 0.0), "{script}");
        assert!(
            frame.stats.photons.is_some(),
            "the lights ask for photon maps"
        );
    }
}

#[test]
fn a_scene_at_the_edge_of_the_coordinate_range_renders_finite_pixels() {
    // A wall 2e8 wide at z = -1e8, a ball and a cube reaching the corners, lights at the far
    // corners with the largest intensity and the strongest falloffs, the eye at z = 1e8.
    let body = "wall = gr.mesh('wall', {{-1e8,-1e8,-1e8},{1e8,-1e8,-1e8},{1e8,1e8,-1e8},{-1e8,1e8,-1e8}}, {{0,1,2,3}})\n\
                wall:set_material(edge); root:add_child(wall)\n\
                ball = gr.nh_sphere('ball', {0, 0, -5e7}, 5e7); ball:set_material(dim); root:add_child(ball)\n\
                box = gr.cube('box'); box:set_material(edge); box:scale(1e8, 1e8, 1e8)\n\
                box:translate(0, -1e8, -1e8); root:add_child(box)";
    let lights = "gr.light({1e8, 1e8, 1e8}, {1e8, 1e8, 1e8}, {1e-6, 0, 0}, 1e30, 2000),\n\
                  gr.light({-1e8, 1e8, 0}, {1e8, 1e8, 1e8}, {0, 0, 1e-6}, 1e30, 2000),\n\
                  gr.area_light({0, 1e8, -5e7}, {1e8, 1e8, 1e8}, {0, 1e-6, 0}, nil, 2000, {1e8, 0, 0}, {0, 0, 1e8}),\n\
                  gr.sphere_light({-1e8, -1e8, 1e8}, {1e8, 1e8, 1e8}, {1e6, 1e6, 1e6}, nil, 2000, 1e8),\n\
                  gr.spot_light({1e8, -1e8, 1e8}, {-1, 1, -1}, {1e8, 1e8, 1e8}, 0, 90, 1e30, 2000),\n\
                  gr.directional_light({1e-30, -1e30, 1}, {1e8, 1e8, 1e8}, 1e30, 2000)";
    assert_renders_finite(&ranged_scene(
        body,
        lights,
        "{0, 0, 1e8}",
        "{1e8, 1e8, 1e8}",
    ));
}

#[test]
fn a_scene_at_the_edge_of_the_light_ranges_renders_finite_pixels() {
    // Unit-sized geometry under the brightest, nearest and smallest emitters: a sphere light of
    // the smallest radius and an area light of the smallest area, both in view.
    let body = "floor = gr.mesh('floor', {{-2,-1,-2},{2,-1,-2},{2,-1,2},{-2,-1,2}}, {{0,1,2,3}})\n\
                floor:set_material(edge); root:add_child(floor)\n\
                ball = gr.sphere('ball'); ball:set_material(edge); ball:scale(0.5, 0.5, 0.5); root:add_child(ball)";
    let lights = "gr.light({0, 1, 0.6}, {1e8, 1e8, 1e8}, {1e-6, 0, 0}, 1e30, 2000),\n\
                  gr.sphere_light({0.5, 0.5, 1}, {1e8, 1e8, 1e8}, {1e-6, 0, 1e-6}, 1, 2000, 1e-6),\n\
                  gr.area_light({-0.5, 0.5, 1}, {1e8, 1e8, 1e8}, {1e-6, 1e-6, 0}, 1, 2000, {1e-6, 0, 0}, {0, 0, 1e-6}),\n\
                  gr.spot_light({0, 0.6, 0}, {0, -1, 0}, {1e8, 1e8, 1e8}, 0, 0, 1, 2000),\n\
                  gr.spot_light({0, 0.6, 0.1}, {0, -1, 0}, {1e8, 1e8, 1e8}, 1e-6, 1e-6, 1, 2000)";
    assert_renders_finite(&ranged_scene(body, lights, "{0, 0, 3}", "{1e8, 1e8, 1e8}"));
}

#[test]
fn script_values_outside_the_ranges_are_refused_at_their_line() {
    let light = |args: &str| format!("l = gr.light({args})");
    let render = |eye: &str, ambient: &str| {
        format!(
            "r = gr.node('r')\ngr.render(r, 'x.png', 4, 4, {eye}, {{0,0,-1}}, {{0,1,0}}, 50, {ambient}, {{gr.light({{0,0,5}}, {{1,1,1}}, {{1,0,0}})}})"
        )
    };
    let bad = |line: u32, n: u32, f: &str, detail: &str| {
        format!("test.lua:{line}: bad argument #{n} to '{f}' ({detail})")
    };
    let cases = [
        (
            "m = gr.material({1e30, 1, 1}, {0, 0, 0}, 0)".to_owned(),
            bad(1, 1, "material", "reflectance 1e30 is outside [0, 10]"),
        ),
        (
            "m = gr.material({1, 1, 1}, {0, 11, 0}, 0)".to_owned(),
            bad(1, 2, "material", "reflectance 11 is outside [0, 10]"),
        ),
        (
            light("{0, 0, 0}, {1e9, 1, 1}, {1, 0, 0}"),
            bad(1, 2, "light", "colour component 1e9 is outside [0, 1e8]"),
        ),
        (
            light("{0, 0, 0}, {1, 1, 1}, {1e-30, 0, 0}"),
            bad(1, 3, "light", "falloff coefficient 1e-30 must be 0 or in [1e-6, 1e6]"),
        ),
        (
            light("{0, 0, 0}, {1, 1, 1}, {1, 0, 1e7}"),
            bad(1, 3, "light", "falloff coefficient 1e7 must be 0 or in [1e-6, 1e6]"),
        ),
        (
            light("{0, 0, 0}, {1, 1, 1}, {1, 0, 0}, 1e35"),
            bad(1, 4, "light", "power must be in [0, 1e30], got 1e35"),
        ),
        (
            light("{0, 0, 2e8}, {1, 1, 1}, {1, 0, 0}"),
            bad(1, 1, "light", "coordinate 2e8 is outside the renderer's range [-1e8, 1e8]"),
        ),
        (
            "l = gr.spot_light({0, 0, 0}, {0, -1, 0}, {1e9, 1, 1}, 10, 20)".to_owned(),
            bad(1, 3, "spot_light", "colour component 1e9 is outside [0, 1e8]"),
        ),
        (
            "l = gr.directional_light({0, -1, 0}, {1, 1, 1}, 1e35)".to_owned(),
            bad(1, 3, "directional_light", "power must be in [0, 1e30], got 1e35"),
        ),
        (
            "l = gr.sphere_light({0, 0, 0}, {1, 1, 1}, {1, 0, 0}, nil, nil, 1e-30)".to_owned(),
            bad(1, 6, "sphere_light", "radius 1e-30 is smaller than 1e-6"),
        ),
        (
            "l = gr.area_light({0, 0, 0}, {1, 1, 1}, {1, 0, 0}, nil, nil, {1e-7, 0, 0}, {0, 0, 1e-7})"
                .to_owned(),
            bad(1, 7, "area_light", "the edges u and v must span a parallelogram of area at least 1e-12 (not zero or parallel)"),
        ),
        (
            "l = gr.area_light({0, 0, 0}, {1, 1, 1}, {1, 0, 0}, nil, nil, {1e9, 0, 0}, {0, 0, 1})"
                .to_owned(),
            bad(1, 6, "area_light", "coordinate 1e9 is outside the renderer's range [-1e8, 1e8]"),
        ),
        (
            "s = gr.nh_sphere('s', {0, 0, 0}, 1e30)".to_owned(),
            bad(1, 3, "nh_sphere", "radius 1e30 is longer than 1e8"),
        ),
        (
            "b = gr.nh_box('b', {-3e8, 0, 0}, 1)".to_owned(),
            bad(1, 2, "nh_box", "coordinate -3e8 is outside the renderer's range [-1e8, 1e8]"),
        ),
        (
            "m = gr.mesh('m', {{0,0,0},{1,0,0},{0,1e30,0}}, {{0,1,2}})".to_owned(),
            bad(1, 2, "mesh", "vertex 3: coordinate 1e30 is outside the renderer's range [-1e8, 1e8]"),
        ),
        (
            render("{0, 0, 1e30}", "{0, 0, 0}"),
            bad(2, 5, "render", "coordinate 1e30 is outside the renderer's range [-1e8, 1e8]"),
        ),
        (
            render("{0, 0, 5}", "{1e9, 0, 0}"),
            bad(2, 9, "render", "colour component 1e9 is outside [0, 1e8]"),
        ),
    ];
    for (script, want) in cases {
        assert_eq!(common::lua_error(&script), want, "{script}");
    }
}

#[test]
fn transforms_that_place_geometry_out_of_range_are_refused_by_node() {
    let dir = out_dir("quirks-placement");
    let scene = |body: &str| {
        format!(
            "m = gr.material({{1,1,1}}, {{0,0,0}}, 0)\nr = gr.node('r')\n{body}\n\
             gr.render(r, 'x.png', 4, 4, {{0,0,5}}, {{0,0,-1}}, {{0,1,0}}, 50, {{0,0,0}}, {{gr.light({{0,0,5}}, {{1,1,1}}, {{1,0,0}})}})"
        )
    };
    let cases = [
        // Before: a sphere of radius 1e30 rendered as a flat ambient colour around the eye.
        (
            "s = gr.sphere('big'); s:set_material(m); s:scale(1e30, 1e30, 1e30); r:add_child(s)",
            "test.lua:3: node 'big' is placed out of range by its transforms: coordinate -1e30 is outside the renderer's range [-1e8, 1e8]",
        ),
        // A scale inherited from a parent, each number of it within single precision.
        (
            "t = gr.mesh('tri', {{-1,-1,0},{1,-1,0},{0,1,0}}, {{0,1,2}}); t:set_material(m)\n\
             g = gr.node('g'); g:scale(1e20, 1e20, 1e20); g:add_child(t); r:add_child(g)",
            "test.lua:3: node 'tri' is placed out of range by its transforms: coordinate -1e20 is outside the renderer's range [-1e8, 1e8]",
        ),
        (
            "s = gr.sphere('far'); s:set_material(m); s:translate(0, 0, -1e38); r:add_child(s)",
            "test.lua:3: node 'far' is placed out of range by its transforms: coordinate -1e38 is outside the renderer's range [-1e8, 1e8]",
        ),
    ];
    for (body, want) in cases {
        let result = common::render_films(scene(body).as_bytes(), "test.lua", &dir);
        let error = result.map(|_| ()).expect_err(body);
        assert_eq!(error.to_string(), want, "{body}");
    }
}

#[test]
fn mesh_file_values_outside_the_ranges_are_refused_at_their_line_or_accessor() {
    let dir = out_dir("quirks-mesh-ranges");
    let load = |name: &str| {
        caustic::scene::meshes::load_meshes(
            &common::run_lua_in(&format!("m = gr.mesh('m', '{name}')"), &dir).unwrap(),
        )
        .map(|_| ())
        .unwrap_err()
        .to_string()
    };
    write(&dir, "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1e30 0\nf 1 2 3\n");
    assert_eq!(
        load("far.obj"),
        "test.lua:1: cannot load mesh 'far.obj': far.obj:3: vertex coordinate 1e30 is outside the renderer's range [-1e8, 1e8]"
            .replace("far.obj:3", &format!("{}:3", dir.join("far.obj").display()))
    );
    write(&dir, "hot.mtl", "newmtl hot\nKd 1e30 1 1\n");
    write(
        &dir,
        "hot.obj",
        "mtllib hot.mtl\nusemtl hot\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let want = format!(
        "test.lua:1: cannot load mesh 'hot.obj': {}:2: `Kd` value 1e30 is outside [0, 10]",
        dir.join("hot.mtl").display()
    );
    assert_eq!(load("hot.obj"), want);
    let (mut f, rest) = gltf_triangle();
    f.floats("VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -2e9, 0.0]);
    let rest = rest.replace(r#""POSITION":0"#, r#""POSITION":1"#);
    f.write_external(&dir, "far", &rest);
    let want = format!(
        "test.lua:1: cannot load mesh 'far.gltf': {}: mesh 0 primitive 0: position 2 of accessor 1: coordinate -2e9 is outside the renderer's range [-1e8, 1e8]",
        dir.join("far.gltf").display()
    );
    assert_eq!(load("far.gltf"), want);
    let (f, rest) = gltf_triangle();
    let rest = rest.replace(r#"{"mesh":0}"#, r#"{"mesh":0,"scale":[1e30,1,1]}"#);
    f.write_external(&dir, "scaled", &rest);
    let want = format!(
        "test.lua:1: cannot load mesh 'scaled.gltf': {}: mesh 0 primitive 0 under node 0: vertex 0 lands at coordinate 1e30 is outside the renderer's range [-1e8, 1e8]",
        dir.join("scaled.gltf").display()
    );
    assert_eq!(load("scaled.gltf"), want);
}
