//! Surfaces through the whole pipeline: world-space points, normals and texture coordinates at
//! known places on each primitive kind, transformed and inside CSG.

use crate::common::run_lua;
use caustic::geometry::Ray;
use caustic::scene::build::{SurfaceHit, build_scene};
use glam::{Vec2, Vec3A};

/// Returns the surface the ray from `o` along `d` sees in the scene of `body` (root `root`).
fn look(body: &str, o: Vec3A, d: Vec3A) -> SurfaceHit {
    let src = format!(
        "m = gr.material({{1,1,1}}, {{0,0,0}}, 0)\nroot = gr.node('root')\n{body}\n\
         gr.render(root, 'x.png', 4, 4, {{0,0,5}}, {{0,0,-1}}, {{0,1,0}}, 50, {{0,0,0}}, {{gr.light({{0,0,9}}, {{1,1,1}}, {{1,0,0}})}})"
    );
    let d0 = run_lua(&src).unwrap();
    let scene = build_scene(&d0, &d0.renders[0]).unwrap();
    let ray = Ray::new(o, d);
    let hit = scene.intersect(&ray).expect("the ray must hit");
    scene.surface(&ray, &hit)
}

fn close(a: Vec2, b: Vec2) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn texture_coordinates_at_known_points() {
    // nh_box corner (1, 1, 1), size 2: the +z face at world (1.5, 2.5, 3) is face point (0.25, 0.75).
    let s = look(
        "b = gr.nh_box('b', {1, 1, 1}, 2); b:set_material(m); root:add_child(b)",
        Vec3A::new(1.5, 2.5, 9.0),
        -Vec3A::Z,
    );
    assert!((s.p - Vec3A::new(1.5, 2.5, 3.0)).length() < 1e-5 && (s.ng - Vec3A::Z).length() < 1e-6);
    assert!(close(s.uv, Vec2::new(0.25, 0.25)), "{}", s.uv);
    // A sphere turned 90° about y: its object +z (u = ½) now faces world +x.
    let s = look(
        "s = gr.sphere('s'); s:set_material(m); s:rotate('y', 90); root:add_child(s)",
        Vec3A::new(5.0, 0.0, 0.0),
        -Vec3A::X,
    );
    assert!(close(s.uv, Vec2::new(0.5, 0.5)), "{}", s.uv);
    assert!((s.ns - Vec3A::X).length() < 1e-5);
    // Cylinder cap at z = 1 (centre) and side; cone side.
    let s = look(
        "c = gr.cylinder('c'); c:set_material(m); root:add_child(c)",
        Vec3A::new(0.0, 0.0, 5.0),
        -Vec3A::Z,
    );
    assert!(close(s.uv, Vec2::new(0.5, 0.5)) && (s.ng - Vec3A::Z).length() < 1e-6);
    let s = look(
        "c = gr.cylinder('c'); c:set_material(m); root:add_child(c)",
        Vec3A::new(5.0, 0.0, 0.5),
        -Vec3A::X,
    );
    assert!(close(s.uv, Vec2::new(0.5, 0.25)), "{}", s.uv);
    let s = look(
        "k = gr.cone('k'); k:set_material(m); root:add_child(k)",
        Vec3A::new(5.0, 0.0, 0.5),
        -Vec3A::X,
    );
    assert!(
        (s.p.x - 0.5).abs() < 1e-5 && close(s.uv, Vec2::new(0.5, 0.5)),
        "{} {}",
        s.p,
        s.uv
    );
    // Inside CSG a boundary keeps its operand's mapping: the sphere part of a union.
    let s = look(
        "a = gr.sphere('a'); a:set_material(m); b = gr.cube('b'); b:set_material(m); b:translate(3, 0, 0)\n\
         u = gr.union('u', a, b); u:rotate('y', 90); root:add_child(u)",
        Vec3A::new(5.0, 0.5, -3.5),
        -Vec3A::X,
    );
    // The cube (moved +3 along x, then turned) spans world x in [0, 1], z in [-4, -3].
    assert!(
        (s.p.x - 1.0).abs() < 1e-5 && close(s.uv, Vec2::new(0.5, 0.5)),
        "{} {}",
        s.p,
        s.uv
    );
    let s2 = look(
        "a = gr.sphere('a'); a:set_material(m); b = gr.cube('b'); b:set_material(m); b:translate(3, 0, 0)\n\
         u = gr.union('u', a, b); u:rotate('y', 90); root:add_child(u)",
        Vec3A::new(5.0, 0.0, 0.0),
        -Vec3A::X,
    );
    assert!(close(s2.uv, Vec2::new(0.5, 0.5)), "sphere part: {}", s2.uv);
    // A mesh without texture coordinates reports its barycentrics.
    let s = look(
        "t = gr.mesh('t', {{0,0,0}, {1,0,0}, {0,1,0}}, {{0, 1, 2}}); t:set_material(m); root:add_child(t)",
        Vec3A::new(0.25, 0.5, 3.0),
        -Vec3A::Z,
    );
    assert!(close(s.uv, Vec2::new(0.25, 0.5)), "{}", s.uv);
}
