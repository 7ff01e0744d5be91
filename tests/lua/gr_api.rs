//! The `gr` API's semantics: transform order, instancing, argument checks, optional extended
//! arguments, and error messages that name the script line.

use crate::common;

use crate::common::{lua_error, out_dir, run_lua, run_lua_in};
use caustic::Fault;
use caustic::desc::{CsgOp, LightShape, NodeKind};
use caustic::scene::build::{build_scene, count_placements};
use caustic::scene::meshes::load_meshes;
use glam::DVec3;

#[test]
fn transforms_pre_multiply_in_call_order() {
    let d = run_lua(
        "a = gr.node('a'); a:scale(2, 2, 2); a:translate(1, 0, 0)\n\
         b = gr.node('b'); b:translate(1, 0, 0); b:scale(2, 2, 2)\n\
         c = gr.node('c'); c:rotate('Z', 90)\n\
         d = gr.node('d'); gr.translate(d, 0, 0, 5)",
    )
    .unwrap();
    let apply = |i: usize, p: DVec3| d.nodes[i].transform.transform_point3(p);
    // scale then translate: M = T·S, so (1,0,0) -> (3,0,0); the other order gives (4,0,0).
    assert!((apply(0, DVec3::X) - DVec3::new(3.0, 0.0, 0.0)).length() < 1e-12);
    assert!((apply(1, DVec3::X) - DVec3::new(4.0, 0.0, 0.0)).length() < 1e-12);
    // Right-handed rotation in degrees, upper-case axis accepted: x -> y.
    assert!((apply(2, DVec3::X) - DVec3::Y).length() < 1e-12);
    // gr doubles as the node metatable: gr.translate(n, ...) is n:translate(...).
    assert!((apply(3, DVec3::ZERO) - DVec3::new(0.0, 0.0, 5.0)).length() < 1e-12);
}

#[test]
fn instancing_places_a_shared_subtree_once_per_parent() {
    if common::skip_without_corpus("instancing_places_a_shared_subtree_once_per_parent") {
        return;
    }
    let dir = common::a4_assets();
    let src = "
        m = gr.material({1, 1, 1}, {0, 0, 0}, 0)
        cow = gr.mesh('cow', 'cow.obj'); cow:set_material(m)
        again = gr.mesh('again', 'cow.obj'); again:set_material(m)
        root = gr.node('root')
        for i = 1, 4 do
            n = gr.node('inst' .. i); n:translate(3 * i, 0, 0); n:add_child(cow); root:add_child(n)
        end
        root:add_child(again)
        gr.render(root, 'x.png', 8, 8, {0, 0, 30}, {0, 0, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
                  {gr.light({0, 10, 10}, {1, 1, 1}, {1, 0, 0})})
    ";
    let d = run_lua_in(src, &dir).unwrap();
    // Both gr.mesh calls read the same file: one mesh, shared.
    assert_eq!(d.meshes.len(), 1);
    let counts = count_placements(&d, d.renders[0].root).unwrap();
    assert_eq!(counts.by_kind["mesh"], 5);
    assert_eq!(counts.triangles, 5 * 5804);
    let scene = build_scene(&d, &d.renders[0]).unwrap();
    assert_eq!(scene.stats.triangles_placed, 5 * 5804);
    assert_eq!(
        scene.stats.triangles_stored, 5804,
        "instances must share one mesh"
    );
    // Each instance sits 3 units further along x.
    let mut xs: Vec<f32> = scene
        .instances
        .iter()
        .map(|i| i.world_from_object.translation.x)
        .collect();
    xs.sort_by(f32::total_cmp);
    assert_eq!(xs, vec![0.0, 3.0, 6.0, 9.0, 12.0]);
}

#[test]
fn every_gr_render_call_renders_at_that_moment() {
    let src = "
        m = gr.material({1, 1, 1}, {0, 0, 0}, 0)
        s = gr.sphere('s'); s:set_material(m)
        root = gr.node('root'); root:add_child(s)
        l = gr.light({0, 10, 10}, {1, 1, 1}, {1, 0, 0})
        gr.render(root, 'a.png', 4, 3, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0}, {l})
        s:translate(1, 0, 0)
        root:render('b.png', 5, 2, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0}, {l, l})
    ";
    let films = common::render_films(src.as_bytes(), "two.lua", std::path::Path::new(".")).unwrap();
    assert_eq!(films.len(), 2);
    assert_eq!(
        (films[0].0.width, films[0].0.height, films[0].0.lights.len()),
        (4, 3, 1)
    );
    assert_eq!(
        (films[1].0.width, films[1].0.height, films[1].0.lights.len()),
        (5, 2, 2)
    );
    assert_eq!(films[1].0.loc.line, 8);
}

#[test]
fn extended_arguments_are_optional_and_stored() {
    let d = run_lua(
        "a = gr.material({1, 0, 0}, {0, 0, 0}, 10)\n\
         b = gr.material({0.2, 0.2, 0.35}, {0.7, 0.7, 0.7}, 25, 0.7, 1.33, 1.05)\n\
         c = gr.material({1, 1, 1}, {0, 0, 0}, 0, 0, 0, 0)\n\
         l1 = gr.light({0, 1, 0}, {1, 1, 1}, {1, 0, 0})\n\
         l2 = gr.light({0, 1, 0}, {1, 1, 1}, {1, 0, 0}, 10000)\n\
         l3 = gr.light({0, 1, 0}, {1, 1, 1}, {1, 0, 0}, 50, 200000)\n\
         cyl = gr.cylinder('c')\n\
         ring = gr.difference('ring', cyl, gr.sphere('s'))\n\
         j = gr.joint('j', {0, 0, 90}, {-10, 0, 10})",
    )
    .unwrap();
    let m = &d.materials;
    assert_eq!(
        (m[0].transparency, m[0].ior, m[0].perlin_scale),
        (0.0, 1.0, 0.0)
    );
    assert_eq!(
        (m[1].transparency, m[1].ior, m[1].perlin_scale),
        (0.7, 1.33, 1.05)
    );
    assert_eq!(m[1].loc.line, 2);
    let l = &d.lights;
    assert_eq!((l[0].power, l[0].photons), (None, None));
    assert_eq!((l[1].power, l[1].photons), (Some(10000.0), None));
    assert_eq!((l[2].power, l[2].photons), (Some(50.0), Some(200000)));
    assert_eq!(d.nodes[0].kind, NodeKind::Cylinder);
    assert!(matches!(
        d.nodes[2].kind,
        NodeKind::Csg {
            op: CsgOp::Difference,
            ..
        }
    ));
    assert_eq!(d.nodes[3].kind, NodeKind::Group, "a joint is a plain node");
}

/// `gr.spot_light(pos, dir, rgb, inner, outer [, power [, num_photons]])` and
/// `gr.directional_light(dir, rgb [, power [, num_photons]])`: angles in degrees stored in
/// radians, directions normalised, physical falloff; bad angles, zero directions and NaN are
/// errors at the line, numbered like lauxlib's.
#[test]
fn spot_and_directional_lights_are_described_and_checked() {
    let d = run_lua(
        "s = gr.spot_light({0, 2, 0}, {0, -3, 0}, {1, 0.5, 0.25}, 15, 20)\n\
         t = gr.spot_light({0, 2, 0}, {1, 0, 0}, {1, 1, 1}, 0, 90, 7, 1000)\n\
         u = gr.directional_light({0, 0, -2}, {0.3, 0.3, 0.3})\n\
         v = gr.directional_light({1, -1, 0}, {0.3, 0.3, 0.3}, nil, 500)",
    )
    .unwrap();
    let l = &d.lights;
    assert_eq!(
        l[0].shape,
        LightShape::Spot {
            direction: glam::Vec3::NEG_Y,
            inner: 15f64.to_radians() as f32,
            outer: 20f64.to_radians() as f32,
        }
    );
    assert_eq!(
        (l[0].position, l[0].falloff, l[0].power, l[0].photons),
        (glam::vec3(0.0, 2.0, 0.0), [0.0, 0.0, 1.0], None, None)
    );
    assert_eq!((l[1].power, l[1].photons), (Some(7.0), Some(1000)));
    assert_eq!(
        l[2].shape,
        LightShape::Directional {
            direction: glam::Vec3::NEG_Z
        }
    );
    assert_eq!(l[2].colour, glam::Vec3::splat(0.3));
    assert_eq!(
        (l[3].power, l[3].photons, l[3].loc.line),
        (None, Some(500), 4)
    );
    for (script, want) in [
        (
            "s = gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 30, 20)",
            "test.lua:1: bad argument #5 to 'spot_light' (spot angles must satisfy 0 <= inner <= outer <= 90 degrees, got inner 30 and outer 20)",
        ),
        (
            "s = gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 10, 95)",
            "test.lua:1: bad argument #5 to 'spot_light' (spot angles must satisfy 0 <= inner <= outer <= 90 degrees, got inner 10 and outer 95)",
        ),
        (
            "s = gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, -1, 20)",
            "test.lua:1: bad argument #5 to 'spot_light' (spot angles must satisfy 0 <= inner <= outer <= 90 degrees, got inner -1 and outer 20)",
        ),
        (
            "s = gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 0/0, 20)",
            "test.lua:1: bad argument #4 to 'spot_light' (finite number expected, got NaN)",
        ),
        (
            "s = gr.spot_light({0, 2, 0}, {0, 0, 0}, {1, 1, 1}, 10, 20)",
            "test.lua:1: bad argument #2 to 'spot_light' (direction must not be zero)",
        ),
        (
            "s = gr.directional_light({0, 0/0, 0}, {1, 1, 1})",
            "test.lua:1: bad argument #1 to 'directional_light' (entry 2: finite number expected, got NaN)",
        ),
        (
            "s = gr.directional_light({0, 0, 0}, {1, 1, 1})",
            "test.lua:1: bad argument #1 to 'directional_light' (direction must not be zero)",
        ),
        (
            "s = gr.directional_light({0, -1, 0}, {-1, 1, 1})",
            "test.lua:1: bad argument #2 to 'directional_light' (colour components must be >= 0, got {-1, 1, 1})",
        ),
    ] {
        assert_eq!(lua_error(script), want, "{script}");
    }
}

#[test]
fn textures_resolve_like_meshes_and_missing_ones_are_located_errors() {
    let dir = out_dir("lua-textures");
    image::RgbImage::new(2, 2).save(dir.join("t.png")).unwrap();
    let d = run_lua_in(
        "m = gr.material({1,1,1}, {0,0,0}, 0, 0, 1, 0, 't.png')",
        &dir,
    )
    .unwrap();
    assert_eq!(
        d.materials[0].texture.as_deref(),
        Some(dir.join("t.png").as_path())
    );
    let e = run_lua_in(
        "\nm = gr.material({1,1,1}, {0,0,0}, 0, 0, 1, 0, 't.png', 'nope.png')",
        &dir,
    )
    .unwrap_err();
    assert_eq!(e.fault(), Some(Fault::NotFound), "{e}");
    assert!(
        e.to_string()
            .starts_with("test.lua:2: bump map 'nope.png' not found"),
        "{e}"
    );
}

#[test]
fn tuple_and_number_checks_follow_lauxlib() {
    assert_eq!(
        lua_error("s = gr.nh_sphere('s', {1, 2}, 3)"),
        "test.lua:1: bad argument #2 to 'nh_sphere' (N-tuple expected)"
    );
    assert_eq!(
        lua_error("\n\ns = gr.nh_sphere('s', {1, 2, 'x'}, 3)"),
        "test.lua:3: bad argument #2 to 'nh_sphere' (entry 3: number expected, got string)"
    );
    assert_eq!(
        lua_error("s = gr.nh_sphere('s', {0, 0, 0})"),
        "test.lua:1: bad argument #3 to 'nh_sphere' (number expected, got no value)"
    );
    assert_eq!(
        lua_error("s = gr.nh_sphere('s', {0, 0, 0}, nil)"),
        "test.lua:1: bad argument #3 to 'nh_sphere' (number expected, got nil)"
    );
    // Numeric strings and trailing commas are numbers and tuples; leading zeros are fine.
    let d = run_lua("s = gr.nh_sphere(7, {0, '-085', 0,}, '10')").unwrap();
    assert_eq!(d.nodes[0].name, "7");
    assert_eq!(
        d.nodes[0].kind,
        NodeKind::NhSphere {
            center: DVec3::new(0.0, -85.0, 0.0),
            radius: 10.0
        }
    );
    // NaN and infinity are rejected.
    assert_eq!(
        lua_error("s = gr.nh_sphere('s', {0, 0, 0}, 0/0)"),
        "test.lua:1: bad argument #3 to 'nh_sphere' (finite number expected, got NaN)"
    );
    assert_eq!(
        lua_error("s = gr.nh_box('b', {0, math.huge, 0}, 1)"),
        "test.lua:1: bad argument #2 to 'nh_box' (entry 2: finite number expected, got inf)"
    );
}

#[test]
fn node_methods_check_their_arguments_and_number_them_like_lauxlib() {
    // Method calls number arguments after self, as lauxlib does.
    assert_eq!(
        lua_error("n = gr.node('n')\nn:rotate('Q', 30)"),
        "test.lua:2: bad argument #1 to 'rotate' (Axis must be x, y or z)"
    );
    assert_eq!(
        lua_error("n = gr.node('n')\ngr.rotate(n, 'xy', 30)"),
        "test.lua:2: bad argument #2 to 'rotate' (Single character expected)"
    );
    assert_eq!(
        lua_error("n = gr.node('n')\nm = gr.material({1,1,1}, {0,0,0}, 0)\nn:set_material(m)"),
        "test.lua:3: calling 'set_material' on bad self (Geometry node expected)"
    );
    assert_eq!(
        lua_error("n = gr.node('n')\nm = gr.material({1,1,1}, {0,0,0}, 0)\ngr.set_material(n, m)"),
        "test.lua:3: bad argument #1 to 'set_material' (Geometry node expected)"
    );
    assert_eq!(
        lua_error("m = gr.material({1,1,1}, {0,0,0}, 0)\ngr.add_child(m, gr.node('x'))"),
        "test.lua:2: bad argument #1 to 'add_child' (gr.node expected, got gr.material)"
    );
    assert_eq!(
        lua_error("n = gr.node('n')\nn:translate(1, 2)"),
        "test.lua:2: bad argument #3 to 'translate' (number expected, got no value)"
    );
    assert_eq!(
        lua_error("n = gr.node('n')\nn:frobnicate()"),
        "test.lua:2: gr.node has no method 'frobnicate'"
    );
}

#[test]
fn unknown_functions_and_lua_errors_name_the_line() {
    let e = lua_error("x = 1\ntorus = gr.torus('t', 0.5)");
    assert!(
        e.starts_with("test.lua:2: unknown function gr.torus"),
        "{e}"
    );
    let e = lua_error("x = 1\n\nx = = 2");
    assert!(e.starts_with("test.lua:3:"), "{e}");
    let e = lua_error("error('boom')");
    assert!(e.starts_with("test.lua:1: boom"), "{e}");
    // The sandbox's library is there, with the Lua 5.1 names (tests/lua/legacy_dialect.rs calls
    // them); what it refuses is a function that fails (tests/lua/sandbox.rs).
    run_lua(
        "assert(io and os and string and math and table and debug and coroutine and utf8)\n\
             assert(unpack and string.gfind and table.getn)\n\
             assert(not pcall(debug.getregistry) and debug.traceback ~= nil)",
    )
    .unwrap();
}

#[test]
fn render_arguments_are_validated() {
    let pre = "m = gr.material({1,1,1}, {0,0,0}, 0)\nr = gr.node('r')\nl = gr.light({0,0,0}, {1,1,1}, {1,0,0})\n";
    let call = |w: &str, h: &str, view: &str, lights: &str| {
        lua_error(&format!(
            "{pre}gr.render(r, 'x.png', {w}, {h}, {{0,0,0}}, {view}, {{0,1,0}}, 50, {{0,0,0}}, {lights})"
        ))
    };
    assert_eq!(
        call("0", "10", "{0,0,-1}", "{l}"),
        "test.lua:4: bad argument #3 to 'render' (image size must be in [1, 65535] pixels, got 0)"
    );
    assert_eq!(
        call("10", "-5", "{0,0,-1}", "{l}"),
        "test.lua:4: bad argument #4 to 'render' (image size must be in [1, 65535] pixels, got -5)"
    );
    assert_eq!(
        call("10", "10", "{0,0,-1}", "{}"),
        "test.lua:4: bad argument #10 to 'render' (Tuple of lights expected)"
    );
    assert_eq!(
        call("10", "10", "{0,0,-1}", "{m}"),
        "test.lua:4: bad argument #10 to 'render' (Tuple of lights expected (entry 1 is a gr.material))"
    );
    assert_eq!(
        call("10", "10", "{0,3,0}", "{l}"),
        "test.lua:4: bad argument #7 to 'render' (up must not be zero or parallel to the view direction)"
    );
    // C++ int truncation: 10.9 renders 10 pixels wide.
    let d = run_lua(&format!("{pre}gr.render(r, 'x.png', 10.9, 3, {{0,0,0}}, {{0,0,-1}}, {{0,1,0}}, 50, {{0,0,0}}, {{l}})")).unwrap();
    assert_eq!((d.renders[0].width, d.renders[0].height), (10, 3));
}

#[test]
fn missing_and_malformed_meshes_name_the_file_and_line() {
    let dir = out_dir("lua-meshes");
    let e = run_lua_in("\nm = gr.mesh('m', 'nowhere.obj')", &dir).unwrap_err();
    assert_eq!(e.fault(), Some(Fault::NotFound), "{e}");
    let e = e.to_string();
    assert!(
        e.starts_with("test.lua:2: mesh file 'nowhere.obj' not found"),
        "{e}"
    );
    // A file is read when a scene is built (here: as `caustic info` does, to count its triangles);
    // the error still names the gr.mesh line.
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let d = run_lua_in("m = gr.mesh('m', 'bad.obj')", &dir).unwrap();
    let e = load_meshes(&d).unwrap_err();
    assert_eq!(e.fault(), Some(Fault::MeshLoad), "{e}");
    let e = e.to_string();
    assert!(
        e.starts_with("test.lua:1: cannot load mesh 'bad.obj': "),
        "{e}"
    );
    assert!(e.contains("bad.obj:4:"), "the OBJ line must be named: {e}");
    // Through gr.render the error is the same: the gr.mesh line, not the gr.render one.
    let src = "m = gr.mesh('m', 'bad.obj')\nr = gr.node('r'); r:add_child(m)\n\
               gr.render(r, 'x.png', 4, 4, {0,0,5}, {0,0,-1}, {0,1,0}, 50, {0,0,0}, {gr.light({0,0,5}, {1,1,1}, {1,0,0})})";
    let e = common::render_films(src.as_bytes(), "test.lua", &dir).unwrap_err();
    assert_eq!(e.fault(), Some(Fault::MeshLoad), "{e}");
    assert!(
        e.to_string()
            .starts_with("test.lua:1: cannot load mesh 'bad.obj': "),
        "{e}"
    );
}

#[test]
fn add_child_cycles_are_reported_not_followed() {
    let src = "a = gr.node('a')\nb = gr.node('b')\na:add_child(b)\nb:add_child(a)\n\
               gr.render(a, 'x.png', 4, 4, {0,0,5}, {0,0,-1}, {0,1,0}, 50, {0,0,0}, {gr.light({0,0,0}, {1,1,1}, {1,0,0})})";
    let d = run_lua(src).unwrap();
    let e = count_placements(&d, d.renders[0].root)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("test.lua:4: node 'a' (made at test.lua:1) is its own ancestor"),
        "{e}"
    );
    assert_eq!(
        lua_error("a = gr.node('a')\na:add_child(a)"),
        "test.lua:2: bad argument #1 to 'add_child' (a node cannot be its own child)"
    );
}

#[test]
fn legacy_inline_meshes_are_accepted() {
    let d = run_lua("m = gr.mesh('quad', {{0,0,0}, {1,0,0}, {1,1,0}, {0,1,0}}, {{0, 1, 2, 3}})")
        .unwrap();
    assert_eq!(
        load_meshes(&d).unwrap()[0].triangles,
        vec![[0, 1, 2], [0, 2, 3]]
    );
    let e = lua_error("m = gr.mesh('q', {{0,0,0}, {1,0,0}, {1,1,0}}, {{0, 1, 3}})");
    assert_eq!(
        e,
        "test.lua:1: bad argument #3 to 'mesh' (face 1: index 3 out of range (0..3))"
    );
}

#[test]
fn degenerate_and_extreme_transforms_are_skipped_or_rejected_not_traced() {
    let pre = "m = gr.material({1,1,1}, {0,0,0}, 0)\nr = gr.node('r')\n";
    let post = "\ngr.render(r, 'x.png', 4, 4, {0,0,5}, {0,0,-1}, {0,1,0}, 50, {0,0,0}, {gr.light({0,0,5}, {1,1,1}, {1,0,0})})";
    let build = |body: &str| {
        let d = run_lua(&format!("{pre}{body}{post}")).unwrap();
        build_scene(&d, &d.renders[0]).map(|s| s.instances.len())
    };
    // A zero scale flattens the sphere: nothing to draw, with a warning, not a NaN-filled ray.
    assert_eq!(
        build("s = gr.sphere('s'); s:set_material(m); s:scale(0, 1, 1); r:add_child(s)").unwrap(),
        0
    );
    // A scale too small for single precision to invert is skipped the same way.
    assert_eq!(
        build(
            "s = gr.sphere('s'); s:set_material(m); s:scale(1e-41, 1e-41, 1e-41); r:add_child(s)"
        )
        .unwrap(),
        0
    );
    // A placement that overflows single precision is an error naming the node's line.
    let e =
        build("\ns = gr.sphere('s'); s:set_material(m); s:translate(3e38, 0, 0); s:translate(3e38, 0, 0); r:add_child(s)")
            .unwrap_err()
            .to_string();
    assert!(
        e.starts_with("test.lua:4: node 's' is transformed beyond single precision"),
        "{e}"
    );
    // A placement whose bounds overflow (a sphere of radius 3e38 centred at 3e38) names it too.
    let e =
        build("\ns = gr.sphere('s'); s:set_material(m); s:scale(3e38, 3e38, 3e38); s:translate(3e38, 0, 0); r:add_child(s)")
            .unwrap_err()
            .to_string();
    assert!(
        e.starts_with("test.lua:4: node 's' is placed at a non-finite position"),
        "{e}"
    );
    assert_eq!(
        build("s = gr.sphere('s'); s:set_material(m); r:add_child(s)").unwrap(),
        1
    );
}

#[test]
fn unknown_gr_functions_list_the_functions_that_exist() {
    let fault = |src: &str| run_lua(src).unwrap_err().fault();
    assert_eq!(fault("s = gr.spere('s')"), Some(Fault::UnknownFunction));
    assert_eq!(
        fault("s = gr.sphere('s')\ns:spin()"),
        Some(Fault::UnknownFunction)
    );
    assert_eq!(
        fault("s = gr.nh_sphere('s', {0, 0, 0})"),
        Some(Fault::BadArgument)
    );
    assert_eq!(
        fault("s = gr.sphere('s')\ns:translate(1, 0/0, 0)"),
        Some(Fault::BadArgument)
    );
    // Errors raised by the script itself are Lua's, with no caustic fault.
    assert_eq!(fault("error('stop')"), None);
    assert_eq!(
        lua_error("\ns = gr.spere('s')"),
        "test.lua:2: unknown function gr.spere (caustic has gr.node, gr.joint, gr.sphere, gr.cube, \
         gr.cylinder, gr.cone, gr.nh_sphere, gr.nh_box, gr.mesh, gr.water_mesh, gr.union, \
         gr.intersection, gr.difference, gr.material, gr.absorption, gr.roughness, gr.light, gr.area_light, gr.sphere_light, \
         gr.spot_light, gr.directional_light, gr.settings, gr.render, gr.gltf)"
    );
    assert_eq!(
        lua_error("s = gr.nh_sphere('s', {0, 0, 0})"),
        "test.lua:1: bad argument #3 to 'nh_sphere' (number expected, got no value)"
    );
    assert_eq!(
        lua_error("s = gr.sphere('s')\ns:translate(1, 0/0, 0)"),
        "test.lua:2: bad argument #2 to 'translate' (finite number expected, got NaN)"
    );
}

/// A missing file named by a script run from its own folder (`caustic render scene.lua`, the
/// script's folder the empty path) says where it looked once, naming the folder, where the
/// message used to end in "the script's folder )".
#[test]
fn not_found_names_the_folder_of_a_script_run_from_its_own_folder() {
    let dir = common::out_dir("not_found_here");
    std::fs::write(dir.join("scene.lua"), "m = gr.mesh('cow', 'cow.obj')\n").unwrap();
    let out = common::caustic()
        .current_dir(&dir)
        .args(["render", "scene.lua"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("mesh file 'cow.obj' not found"), "{err}");
    assert!(!err.contains("folder )"), "{err}");
    let folder = std::fs::canonicalize(&dir).unwrap();
    assert!(err.contains(&folder.display().to_string()), "{err}");
}

/// `-D NAME=VALUE` globals reach the script typed as Lua would read them (integer, float,
/// boolean, string), before its first line runs.
#[test]
fn defined_globals_are_set_before_the_script_runs_with_their_lua_types() {
    use caustic::lua::globals::Global;
    use caustic::lua::{ScriptOptions, run_source_with};
    let globals = ["n=3", "x=0.25", "b=false", "s=big.png", "e="]
        .map(|t| Global::parse(t).unwrap())
        .to_vec();
    let src = "assert(math.type(n) == 'integer' and n == 3)
        assert(math.type(x) == 'float' and x == 0.25)
        assert(b == false and s == 'big.png' and e == '')
        assert(unset == nil)
        gr.node(s .. n)";
    let options = ScriptOptions {
        globals,
        ..ScriptOptions::default()
    };
    let d = run_source_with(
        src.as_bytes(),
        "test.lua",
        std::path::Path::new("."),
        Box::new(|_, _| Ok(())),
        options,
    )
    .unwrap();
    assert_eq!(&*d.nodes[0].name, "big.png3");
}

/// A global that would hide one every script has (`math`, `print`), one given twice, and too
/// many of them are usage errors naming `-D` and the definition.
#[test]
fn defined_globals_may_not_hide_builtins_repeat_or_pile_up() {
    use caustic::lua::globals::{Global, MAX_GLOBALS};
    use caustic::lua::{ScriptOptions, run_source_with};
    let run = |globals: Vec<Global>| {
        let options = ScriptOptions {
            globals,
            ..ScriptOptions::default()
        };
        let no_render = Box::new(|_: &_, _: &_| Ok(()));
        run_source_with(b"", "test.lua", ".".as_ref(), no_render, options)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let g = |t: &str| Global::parse(t).unwrap();
    let e = run(vec![g("math=3")]);
    assert!(e.contains("-D math=3") && e.contains("hide"), "{e}");
    let e = run(vec![g("print=x")]);
    assert!(e.contains("-D print=x"), "{e}");
    let e = run(vec![g("a=1"), g("a=2")]);
    assert!(e.contains("-D a=2") && e.contains("twice"), "{e}");
    let many = (0..=MAX_GLOBALS).map(|i| g(&format!("v{i}=1"))).collect();
    let e = run(many);
    assert!(e.contains("-D") && e.contains("257"), "{e}");
    assert_eq!(run(vec![g("size=512")]), "");
}

/// On the command line, `-D` changes what `caustic info` sees, and a bad form is a usage error
/// naming the flag, before the script runs.
#[test]
fn dash_d_on_the_command_line_sets_globals_and_names_itself_in_errors() {
    let dir = common::out_dir("defines_cli");
    std::fs::write(
        dir.join("scene.lua"),
        "size = size or 16
         gr.render(gr.node('root'), name or 'out.png', size, size, {0, 0, 5}, {0, 0, -1},
                   {0, 1, 0}, 50, {0, 0, 0}, {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0})})\n",
    )
    .unwrap();
    let info = |extra: &[&str]| {
        common::caustic()
            .current_dir(&dir)
            .args(["info", "scene.lua"])
            .args(extra)
            .output()
            .unwrap()
    };
    let out = info(&[]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("16x16"), "{text}");
    let out = info(&["-D", "size=40", "-Dname=big.png"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("40x40") && text.contains("big.png"),
        "{text}"
    );
    for (bad, why) in [
        ("foo", "no '='"),
        ("=3", "empty"),
        ("9lives=1", "not a Lua name"),
        ("while=1", "keyword"),
        ("gr=1", "scene API"),
    ] {
        let out = info(&["-D", bad]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "-D {bad} was accepted");
        assert!(err.contains("-D") && err.contains(why), "-D {bad}: {err}");
    }
    let out = info(&["-D", "table=1"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("-D table=1"), "{err}");
}

/// A material that reflects more than it receives (`(kd + ks)·(1 − t) + t` above 1 in a channel)
/// is warned about once at its script line, naming the total and the channel (issue 35); one
/// that sums to exactly 1 and one of transparency 1 are not; `gr.absorption` checks its colour
/// and distance and warns on an opaque material.
#[test]
fn materials_brighter_than_white_and_absorption_are_checked_at_the_line() {
    let desc = common::run_lua(
        "ok = gr.material({0.7, 0.7, 0.7}, {0.3, 0.3, 0.3}, 10)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
for i = 1, 3 do bright = gr.material({1.2, 0.5, 0.5}, {0.5, 0.5, 0.5}, 10) end
gr.absorption(ok, {0.5, 0.5, 0.5}, 1)",
    )
    .unwrap();
    assert_eq!(desc.warnings.len(), 2, "{:?}", desc.warnings);
    assert!(
        desc.warnings[0].contains("test.lua:3: warning: gr.material: kd + ks reaches 1.7 (red)"),
        "{:?}",
        desc.warnings
    );
    assert!(
        desc.warnings[1].contains("test.lua:4:") && desc.warnings[1].contains("opaque"),
        "{:?}",
        desc.warnings
    );
    // gr.roughness takes [0, 1].
    for (src, want) in [
        (
            "m = gr.material({0, 0, 0}, {1, 1, 1}, 0)\ngr.roughness(m, 1.5)",
            "roughness must be in [0, 1], got 1.5",
        ),
        (
            "m = gr.material({0, 0, 0}, {1, 1, 1}, 0)\ngr.roughness(m, -0.1)",
            "roughness must be in [0, 1]",
        ),
        (
            "m = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)\ngr.roughness(m, 2)",
            "roughness must be in [0, 1], got 2",
        ),
    ] {
        let e = common::lua_error(src);
        assert!(e.contains("test.lua:2") && e.contains(want), "{src}: {e}");
    }
    // An index far outside matter's (its square scales radiance) is refused at its line.
    for ior in ["0.05", "20", "-1"] {
        let e = common::lua_error(&format!(
            "glass = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, {ior})"
        ));
        assert!(
            e.contains("test.lua:1") && e.contains("index of refraction must be in [0.1, 10]"),
            "{ior}: {e}"
        );
    }
    for (args, want) in [
        ("{0, 0.5, 0.5}, 1", "(0, 1]"),
        ("{0.5, 1.5, 0.5}, 1", "(0, 1]"),
        ("{0.5, 0.5, 0.5}, 0", "distance must be positive"),
        ("{0.5, 0.5, 0.5}, 1e-9", "distance must be at least"),
        ("{0.5, 0.5, 0.5}, -1", "distance"),
    ] {
        let e = common::lua_error(&format!(
            "glass = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)\ngr.absorption(glass, {args})"
        ));
        assert!(e.contains("test.lua:2") && e.contains(want), "{args}: {e}");
    }
}
