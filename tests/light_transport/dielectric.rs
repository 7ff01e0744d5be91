//! Refraction through the renderer against closed forms: Fresnel-weighted interfaces summed over
//! all internal reflections, and nested media that refract with the ratio of both indices.

use crate::common::render_films;
use caustic::integrator::eye::background;
use glam::Vec3A;
use std::path::Path;

/// Normal-incidence reflectance between indices `a` and `b`.
fn f0(a: f32, b: f32) -> f32 {
    ((a - b) / (a + b)).powi(2)
}

/// Combines two interfaces or layers (R, T) with all their inter-reflections (incoherent sum).
fn combine((ra, ta): (f32, f32), (rb, tb): (f32, f32)) -> (f32, f32) {
    let k = 1.0 / (1.0 - ra * rb);
    (ra + ta * ta * rb * k, ta * tb * k)
}

/// Diffuse colour of the lit wall behind the camera, which is what reflected rays see.
const WALL: Vec3A = Vec3A::new(1.0, 0.5, 0.25);

/// Renders a 3×3 image looking straight down -z at the origin, with a wall behind the camera lit
/// head-on (radiance `WALL`), and returns the centre pixel and the expected value for an axial
/// stack with total reflectance `r` and transmittance `t`.
fn centre(body: &str) -> (Vec3A, impl Fn((f32, f32)) -> Vec3A) {
    let src = format!(
        "root = gr.node('root')\n{body}\n\
         wall_mat = gr.material({{1, 0.5, 0.25}}, {{0,0,0}}, 0)\n\
         wall = gr.cube('wall'); wall:set_material(wall_mat); wall:scale(40, 40, 1); wall:translate(-20, -20, 15)\n\
         root:add_child(wall)\n\
         gr.render(root, 'x.png', 3, 3, {{0,0,10}}, {{0,0,-1}}, {{0,1,0}}, 10, {{0,0,0}}, {{gr.light({{0,0,12}}, {{1,1,1}}, {{1,0,0}})}})"
    );
    let films = render_films(src.as_bytes(), "d.lua", Path::new(".")).unwrap();
    let (_, camera, film) = films.into_iter().next().unwrap();
    let got = film.get(1, 1);
    let dir = camera.ray(1.5, 1.5).dir;
    assert!((dir - Vec3A::NEG_Z).length() < 1e-6);
    let expect = move |(r, t): (f32, f32)| t * background(&camera, dir) + r * WALL;
    (got, expect)
}

#[test]
fn glass_slab_transmits_one_minus_f_over_one_plus_f() {
    let (got, expect) = centre(
        "glass = gr.material({0,0,0}, {0,0,0}, 0, 1, 1.5)\n\
         s = gr.cube('s'); s:set_material(glass); s:scale(4, 4, 1); s:translate(-2, -2, -0.5); root:add_child(s)",
    );
    let f = f0(1.0, 1.5);
    let (r, t) = combine((f, 1.0 - f), (f, 1.0 - f));
    assert!((t - (1.0 - f) / (1.0 + f)).abs() < 1e-6);
    let want = expect((r, t));
    assert!(
        (got - want).abs().max_element() < 1e-3,
        "got {got}, want {want} (R {r}, T {t})"
    );
}

#[test]
fn glass_inside_water_uses_the_ratio_of_both_indices() {
    let (got, expect) = centre(
        "water = gr.material({0,0,0}, {0,0,0}, 0, 1, 1.33)\n\
         glass = gr.material({0,0,0}, {0,0,0}, 0, 1, 1.5)\n\
         w = gr.cube('w'); w:set_material(water); w:scale(4, 4, 4); w:translate(-2, -2, -2); root:add_child(w)\n\
         g = gr.cube('g'); g:set_material(glass); g:scale(2, 2, 1); g:translate(-1, -1, -0.5); root:add_child(g)",
    );
    let (a, b) = (f0(1.0, 1.33), f0(1.33, 1.5));
    let layer = |f: f32| (f, 1.0 - f);
    let stack = combine(combine(combine(layer(a), layer(b)), layer(b)), layer(a));
    let want = expect(stack);
    assert!(
        (got - want).abs().max_element() < 2e-3,
        "got {got}, want {want}"
    );
    // Treating the glass as if it were in air would reflect noticeably more.
    let wrong = combine(
        combine(combine(layer(a), layer(f0(1.0, 1.5))), layer(f0(1.0, 1.5))),
        layer(a),
    );
    assert!((expect(wrong) - want).abs().max_element() > 1e-2);
}
