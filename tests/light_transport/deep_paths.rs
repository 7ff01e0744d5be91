//! Paths deeper than any fixed depth: nested glass shells and facing mirrors. Beyond the eye
//! path's splitting depth a path must go on by Russian roulette, never turn silently black.

use crate::common;

use crate::common::{render_films_with, whitted};
use caustic::camera::Camera;
use caustic::film::Film;
use caustic::integrator::Settings;
use caustic::integrator::eye::{MAX_DEPTH, MAX_PATH_DEPTH, background};
use glam::Vec3A;
use std::path::Path;

/// Returns the script of `shells` concentric spherical shells (each a CSG difference of two
/// spheres, of index `ior`) around the origin, seen along -z by a 3×3 image whose centre ray
/// crosses every shell's two faces on the way in and again on the way out. A black wall behind
/// the camera absorbs what the shells reflect, so the centre pixel is the transmitted background.
fn shells_scene(shells: u32, ior: f64) -> String {
    let spacing = 1.0 / shells as f64;
    format!(
        "glass = gr.material({{0,0,0}}, {{0,0,0}}, 0, 1, {ior})\n\
         root = gr.node('root')\n\
         for k = 0, {last} do\n\
           local r = 1 - k * {spacing}\n\
           local outer = gr.sphere('o' .. k); outer:scale(r, r, r)\n\
           local inner = gr.sphere('i' .. k); inner:scale(r - {half}, r - {half}, r - {half})\n\
           local shell = gr.difference('shell' .. k, outer, inner)\n\
           shell:set_material(glass); root:add_child(shell)\n\
         end\n\
         black = gr.material({{0,0,0}}, {{0,0,0}}, 0)\n\
         wall = gr.cube('wall'); wall:set_material(black); wall:scale(40, 40, 1); wall:translate(-20, -20, 15)\n\
         root:add_child(wall)\n\
         gr.render(root, 's.png', 3, 3, {{0,0,10}}, {{0,0,-1}}, {{0,1,0}}, 10, {{0,0,0}},\n\
                   {{gr.light({{0,0,12}}, {{1,1,1}}, {{1,0,0}})}})\n",
        last = shells - 1,
        half = spacing / 2.0,
    )
}

/// Renders `src`'s one image with `settings`; returns its camera and film.
fn render(src: &str, settings: &Settings) -> (Camera, Film) {
    let films = render_films_with(src.as_bytes(), "s.lua", Path::new("."), settings).unwrap();
    let (_, camera, film) = films.into_iter().next().unwrap();
    (camera, film)
}

/// Returns the background the centre ray of the 3×3 image would see with nothing in the way.
fn centre_background(camera: &Camera) -> Vec3A {
    let dir = camera.ray(1.5, 1.5).dir;
    assert!(
        (dir - Vec3A::NEG_Z).length() < 1e-6,
        "the centre ray looks along -z"
    );
    background(camera, dir)
}

/// Shells of index 1 are invisible: the centre pixel through 8 and 100 of them (32 and 400
/// interfaces, far past the splitting depth) equals the background within 1e-5, where a fixed
/// depth cap gave black.
#[test]
fn index_one_shells_are_invisible_at_any_depth() {
    for shells in [8, 100] {
        assert!(4 * shells > MAX_DEPTH);
        let (camera, film) = render(&shells_scene(shells, 1.0), &whitted());
        let (got, want) = (film.get(1, 1), centre_background(&camera));
        assert!(
            (got - want).abs().max_element() < 1e-5,
            "{shells} shells of index 1: centre {got}, background {want}"
        );
    }
}

/// Returns the mean and the standard error of the centre pixel (its one ray along the axis)
/// over `seeds` renders of `src` with different random streams.
fn centre_mean(src: &str, seeds: u64) -> (Vec3A, Vec3A, Vec3A) {
    let mut values = Vec::new();
    let mut bg = Vec3A::ZERO;
    for seed in 0..seeds {
        let (camera, film) = render(src, &Settings { seed, ..whitted() });
        bg = centre_background(&camera);
        values.push(film.get(1, 1));
    }
    let n = seeds as f32;
    let mean = values.iter().sum::<Vec3A>() / n;
    let var = values
        .iter()
        .map(|v| (*v - mean) * (*v - mean))
        .sum::<Vec3A>()
        / (n - 1.0);
    (mean, (var / n).powf(0.5), bg)
}

/// Dielectric shells transmit the closed form of their `m = 4·shells` interfaces with all
/// inter-reflections, `T = (1 − F)/(1 + (m − 1)F)`, within 4 standard errors plus 2%: the path
/// goes on by Russian roulette past the splitting depth (a fixed depth cap gave black). 8 and
/// 100 shells of index 1.05 and 8 of index 1.5; 64 or 256 random streams of the axial ray.
#[test]
fn dielectric_shells_transmit_the_closed_form() {
    for (ior, shells, seeds) in [(1.05f32, 8u32, 64), (1.05, 100, 256), (1.5, 8, 256)] {
        let f = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let m = 4.0 * shells as f32;
        let t = (1.0 - f) / (1.0 + (m - 1.0) * f);
        let (mean, err, bg) = centre_mean(&shells_scene(shells, ior as f64), seeds);
        let want = t * bg;
        println!("{shells} shells of index {ior}: centre {mean} ± {err}, closed form {want}");
        assert!(
            ((mean - want).abs() - 4.0 * err - 0.02 * want).max_element() < 0.0,
            "{shells} shells of index {ior}: centre {mean} ± {err}, closed form {want} (T {t})"
        );
    }
}

/// Two facing perfect mirrors (reflectance 1) never lose weight, so only the hard cap ends the
/// path: the render finishes, stays finite, and reports the capped paths (the cap is
/// `MAX_PATH_DEPTH` = 1024 bounces, so this also checks the recursion fits the worker's stack).
#[test]
fn facing_perfect_mirrors_stop_at_the_hard_cap() {
    let frame = facing_mirrors(0.0, 1.0, 0.5);
    let pixels = &frame.film.pixels;
    assert!(pixels.iter().all(|p| p.is_finite()), "{pixels:?}");
    assert_eq!(
        frame.stats.render.depth_capped, 9,
        "each of the 9 camera rays bounces until the cap of {MAX_PATH_DEPTH}"
    );
}

/// The command line says when paths hit the cap, without `--stats`: rendering the facing
/// mirrors prints a warning counting the 9 capped paths and naming the image.
#[test]
fn capped_paths_are_reported_on_the_command_line() {
    let dir = common::out_dir("capped_paths");
    let script = dir.join("mirrors.lua");
    std::fs::write(
        &script,
        "mirror = gr.material({0,0,0}, {1,1,1}, 0)\n\
         root = gr.node('root')\n\
         a = gr.cube('a'); a:scale(4000, 4000, 0.1); a:translate(-2000, -2000, -1.1); a:set_material(mirror); root:add_child(a)\n\
         b = gr.cube('b'); b:scale(4000, 4000, 0.1); b:translate(-2000, -2000, 1); b:set_material(mirror); root:add_child(b)\n\
         gr.render(root, 'm.png', 3, 3, {0,0,0}, {0,0,-1}, {0,1,0}, 10, {0,0,0},\n\
                   {gr.light({0,0,0.5}, {1,1,1}, {1,0,0})})\n",
    )
    .unwrap();
    let out = common::run_ok(common::caustic().args([
        "render",
        script.to_str().unwrap(),
        "--spp",
        "1",
        "-q",
    ]));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: 9 eye paths stopped at the 1024-bounce cap")
            && err.contains("m.png"),
        "{err}"
    );
}

/// Renders two facing mirrors 2.1 apart, 4000 wide, of diffuse reflectance `kd` and mirror
/// reflectance `ks`, with the camera between them looking at one and a point light at
/// `z = light_z` on the axis, by the first renderer (no ambient light, no photons).
fn facing_mirrors(kd: f32, ks: f32, light_z: f32) -> caustic::frame::Frame {
    let src = format!(
        "mirror = gr.material({{{kd},{kd},{kd}}}, {{{ks},{ks},{ks}}}, 0)\n\
         root = gr.node('root')\n\
         a = gr.cube('a'); a:scale(4000, 4000, 0.1); a:translate(-2000, -2000, -1.1); a:set_material(mirror); root:add_child(a)\n\
         b = gr.cube('b'); b:scale(4000, 4000, 0.1); b:translate(-2000, -2000, 1); b:set_material(mirror); root:add_child(b)\n\
         gr.render(root, 'm.png', 3, 3, {{0,0,0}}, {{0,0,-1}}, {{0,1,0}}, 10, {{0,0,0}},\n\
                   {{gr.light({{0,0,{light_z}}}, {{1,1,1}}, {{1,0,0}})}})\n"
    );
    let desc = common::run_lua(&src).unwrap();
    caustic::frame::render_desc(
        &desc,
        &desc.renders[0],
        1.0,
        None,
        &whitted(),
        &caustic::progress::NoProgress,
    )
    .unwrap()
}

/// Returns the centre pixel and the dropped samples of the facing mirrors
/// ([`facing_mirrors`]) of diffuse reflectance 0.1 and mirror reflectance `ks`, the light 0.5
/// above the lower mirror.
fn facing_mirrors_centre(ks: f32) -> (Vec3A, u64) {
    let frame = facing_mirrors(0.1, ks, -0.5);
    (frame.film.get(1, 1), frame.stats.render.nonfinite_samples)
}

/// Mirrors brighter than white between each other stay finite: the centre ray of the facing
/// mirrors meets them `MAX_PATH_DEPTH + 1` times on the axis, each hit adding the direct light
/// `kd·I = 0.1`. Split deterministically for the first `MAX_DEPTH` bounces, the path carries
/// `ksⁿ`; beyond, Russian roulette follows a mirror of ks above 1 at ks over its largest
/// channel (weight 1), so with ks = 1.5 the pixel is
/// `0.1·(Σ_{n=0}^{D} 1.5ⁿ + (MAX_PATH_DEPTH − D)·1.5^D)` (D = `MAX_DEPTH`), and with ks = 1 it
/// is `0.1·(MAX_PATH_DEPTH + 1)`, both within 1e-4 (f32 sums of a thousand terms). Unscaled,
/// ks = 1.5 grew as 1.5¹⁰²⁴ and the sample was dropped as infinite.
#[test]
fn facing_mirrors_brighter_than_white_stay_finite() {
    let (white, dropped) = facing_mirrors_centre(1.0);
    let want = 0.1 * (MAX_PATH_DEPTH + 1) as f64;
    assert_eq!(dropped, 0);
    assert!(
        (white.x as f64 / want - 1.0).abs() < 1e-4 && white.x == white.y,
        "ks = 1: centre {white}, closed form {want}"
    );
    let (bright, dropped) = facing_mirrors_centre(1.5);
    let d = MAX_DEPTH as i32;
    let split: f64 = (0..=d).map(|n| 1.5f64.powi(n)).sum();
    let want = 0.1 * (split + (MAX_PATH_DEPTH as f64 - d as f64) * 1.5f64.powi(d));
    println!("ks = 1.5: centre {bright}, closed form {want}, {dropped} dropped");
    assert_eq!(dropped, 0, "ks = 1.5: samples dropped as infinite");
    assert!(
        (bright.x as f64 / want - 1.0).abs() < 1e-4,
        "ks = 1.5: centre {bright}, closed form {want}"
    );
}
