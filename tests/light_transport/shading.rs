//! The first renderer against closed forms: Phong direct light with falloff, shadows, ambient,
//! the background, and the look of the course's simple.lua.

use crate::common;

use crate::common::{a4_assets, render_corpus_script, render_films};
use caustic::integrator::eye::background;
use glam::Vec3A;
use std::path::Path;

/// A floor (top face y = 0) under a light at (0, 10, 0), with a ball at (0, 5, 0) shadowing the
/// point below it. Camera looks down at the floor.
const FLOOR_SCENE: &str = r#"
floor_mat = gr.material({0.5, 0.25, 1.0}, {0, 0, 0}, 0)
root = gr.node('root')
floor = gr.cube('floor')
floor:set_material(floor_mat)
floor:scale(40, 1, 40)
floor:translate(-20, -1, -20)
root:add_child(floor)
ball = gr.nh_sphere('ball', {0, 5, 0}, 1)
ball:set_material(floor_mat)
root:add_child(ball)
light = gr.light({0, 10, 0}, {0.9, 0.8, 0.7}, {1, 0.1, 0.01})
gr.render(root, 'floor.png', 64, 48, {0, 12, 12}, {0, -1, -1}, {0, 1, 0}, 60, {0.2, 0.3, 0.1}, {light})
"#;

#[test]
fn floor_pixels_match_phong_with_falloff_and_shadow_exactly() {
    let films = render_films(FLOOR_SCENE.as_bytes(), "floor.lua", Path::new(".")).unwrap();
    let (_, camera, film) = &films[0];
    let kd = Vec3A::new(0.5, 0.25, 1.0);
    let ambient = Vec3A::new(0.2, 0.3, 0.1);
    let intensity = Vec3A::new(0.9, 0.8, 0.7);
    let light = Vec3A::new(0.0, 10.0, 0.0);
    let (mut lit, mut shadowed) = (0, 0);
    for y in 0..film.height {
        for x in 0..film.width {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            if ray.dir.y >= 0.0 {
                continue;
            }
            let t = -ray.origin.y / ray.dir.y;
            let p = ray.at(t);
            if p.x.abs() > 19.0 || p.z.abs() > 19.0 {
                continue;
            }
            // Skip pixels that see the ball rather than the floor.
            let to_ball = Vec3A::new(0.0, 5.0, 0.0) - ray.origin;
            if (to_ball - ray.dir * to_ball.dot(ray.dir)).length() < 1.05 {
                continue;
            }
            // The ball's shadow: the segment p → light passes within radius 1 of (0, 5, 0).
            let to_light = light - p;
            let c = Vec3A::new(0.0, 5.0, 0.0) - p;
            let s = (c.dot(to_light) / to_light.length_squared()).clamp(0.0, 1.0);
            let dist = (c - to_light * s).length();
            if (dist - 1.0).abs() < 0.02 {
                continue; // too close to the shadow's edge to call
            }
            let mut expected = ambient * kd;
            if dist > 1.0 {
                let d = to_light.length();
                let cos = to_light.y / d;
                expected += intensity * kd * cos / (1.0 + 0.1 * d + 0.01 * d * d);
                lit += 1;
            } else {
                shadowed += 1;
            }
            let got = film.get(x, y);
            assert!(
                (got - expected).abs().max_element() < 2e-4,
                "pixel ({x}, {y}) at {p}: got {got}, want {expected}"
            );
        }
    }
    assert!(
        lit > 1000 && shadowed > 10,
        "lit {lit}, shadowed {shadowed}"
    );
}

#[test]
fn sphere_facing_the_light_head_on_has_radiance_kd_times_intensity() {
    let src = r#"
        m = gr.material({0.5, 0.4, 0.3}, {0, 0, 0}, 0)
        s = gr.sphere('s')
        s:set_material(m)
        gr.render(s, 'x.png', 33, 33, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 30, {0, 0, 0},
                  {gr.light({0, 0, 10}, {1, 1, 1}, {1, 0, 0})})
    "#;
    let films = render_films(src.as_bytes(), "s.lua", Path::new(".")).unwrap();
    let (_, camera, film) = &films[0];
    // The centre pixel sees (0, 0, 1) with n = l = +z: kd · 1 · cos 0.
    let c = film.get(16, 16);
    assert!(
        (c - Vec3A::new(0.5, 0.4, 0.3)).abs().max_element() < 1e-5,
        "{c}"
    );
    // Off-centre pixels: kd · (n · l) with the hit point computed analytically.
    for (x, y) in [(12, 16), (16, 20), (13, 19)] {
        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
        let b = ray.origin.dot(ray.dir);
        let t = -b - (b * b - ray.origin.length_squared() + 1.0).sqrt();
        let p = ray.at(t);
        let l = (Vec3A::new(0.0, 0.0, 10.0) - p).normalize();
        let want = Vec3A::new(0.5, 0.4, 0.3) * p.dot(l);
        let got = film.get(x, y);
        assert!(
            (got - want).abs().max_element() < 1e-4,
            "({x}, {y}): {got} vs {want}"
        );
    }
    // The corner sees the background gradient.
    let corner = film.get(0, 0);
    assert!(
        (corner - background(camera, camera.ray(0.5, 0.5).dir))
            .abs()
            .max_element()
            < 1e-6
    );
}

#[test]
fn simple_lua_spheres_are_lit_towards_the_lights_and_dark_away_from_them() {
    if common::skip_without_corpus(
        "simple_lua_spheres_are_lit_towards_the_lights_and_dark_away_from_them",
    ) {
        return;
    }
    let films = render_corpus_script(&a4_assets().join("simple.lua"));
    assert_eq!(films.len(), 1);
    let (r, camera, film) = &films[0];
    assert_eq!((r.width, r.height), (256, 256));
    let sample = |p: Vec3A| {
        let (x, y) = camera.project(p).unwrap();
        film.get(x as u32, y as u32)
    };
    // s1: centre (0, 0, -400), radius 100. The point facing the white light at (-100, 150, 400)...
    let centre = Vec3A::new(0.0, 0.0, -400.0);
    let towards_white = (Vec3A::new(-100.0, 150.0, 400.0) - centre).normalize();
    let lit = sample(centre + towards_white * 100.0);
    // ... and a visible point whose normal faces away from both lights (worked out by hand:
    // n·(white − c) < 0, n·(magenta − c) < 0, n·(eye − p) > 0).
    let away = Vec3A::new(-0.1, -0.95, 0.15).normalize();
    let dark = sample(centre + away * 100.0);
    // Lit: at least kd·I·cos ≈ 0.9·(0.7, 1.0, 0.7) above the unlit side in every channel but
    // for the highlights and reflections both share.
    assert!(
        lit.y > dark.y + 0.5 && lit.x > dark.x + 0.3,
        "lit {lit} vs dark {dark}"
    );
    // The unlit side still gets the ambient term kd · ambient = (0.21, 0.3, 0.21).
    assert!(dark.cmpge(Vec3A::new(0.2, 0.29, 0.2)).all(), "dark {dark}");
    // The top row sees no object: the background gradient, varying down the image.
    for x in [0, 100, 255] {
        let want = background(camera, camera.ray(x as f32 + 0.5, 0.5).dir);
        assert!((film.get(x, 0) - want).abs().max_element() < 1e-6);
    }
    assert!(
        film.get(0, 0) != film.get(0, 60),
        "background must not be constant"
    );
}

#[test]
fn area_light_irradiance_matches_quadrature_and_casts_soft_shadows() {
    // A 1×1 area light 2 units above a floor, facing down; physical falloff {0, 0, 1}.
    let src = r#"
        m = gr.material({1, 1, 1}, {0, 0, 0}, 0)
        root = gr.node('root')
        floor = gr.cube('floor'); floor:set_material(m); floor:scale(40, 1, 40); floor:translate(-20, -1, -20)
        root:add_child(floor)
        blocker = gr.nh_box('blocker', {-3.2, 0.8, -0.5}, 1); blocker:set_material(m); root:add_child(blocker)
        l = gr.area_light({0, 2, 0}, {1, 1, 1}, {0, 0, 1}, nil, nil, {1, 0, 0}, {0, 0, 1})  -- u × v = -y
        gr.render(root, 'x.png', 48, 48, {0, 6, 0.01}, {0, -1, 0}, {0, 0, -1}, 80, {0, 0, 0}, {l})
    "#;
    let d = common::run_lua(src).unwrap();
    let r = &d.renders[0];
    let mut scene = caustic::scene::build::build_scene(&d, r).unwrap();
    let camera = caustic::camera::Camera::new(&r.camera, r.width, r.height);
    let settings = caustic::integrator::Settings {
        light_samples: 1024,
        ..common::whitted()
    };
    let film = common::render_scene(&mut scene, &camera, r.width, r.height, &settings);
    // Irradiance at floor point p from the light (radiance I/A = 1), by a 200×200 midpoint rule.
    let quadrature = |p: Vec3A| {
        let n = 200;
        let mut e = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let y = Vec3A::new(
                    -0.5 + (i as f32 + 0.5) / n as f32,
                    2.0,
                    -0.5 + (j as f32 + 0.5) / n as f32,
                );
                let w = y - p;
                let d2 = w.length_squared();
                let cos = w.y / d2.sqrt();
                e += (cos * cos / d2) as f64 / (n * n) as f64;
            }
        }
        e as f32
    };
    // The camera looks down on the light's back: black, and it hides the floor below it.
    assert_eq!(film.get(24, 24), Vec3A::ZERO);
    for (x, y) in [(30, 20), (36, 36), (12, 30), (32, 29)] {
        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
        let p = ray.at(-ray.origin.y / ray.dir.y);
        if p.x < -2.0 {
            continue; // near the blocker
        }
        let want = quadrature(p);
        let got = film.get(x, y).x;
        assert!(
            (got - want).abs() < 0.02 * want,
            "pixel ({x}, {y}) at {p}: {got} vs quadrature {want}"
        );
    }
    // The blocker's shadow is soft: along a line through it, values rise from the umbra through
    // intermediate penumbra values to full light, never jumping straight from dark to lit.
    let row: Vec<f32> = (0..48).map(|x| film.get(x, 24).x).collect();
    let lit = row.iter().cloned().fold(0.0, f32::max);
    let partial = row
        .iter()
        .filter(|&&v| v > 0.1 * lit && v < 0.6 * lit)
        .count();
    assert!(partial >= 2, "no penumbra in {row:?}");
}

/// Area and sphere lights are seen by camera rays, in mirrors and through glass, with the
/// radiance of the lighting model (`I_phys/A = π·rgb/A` on an area light's emitting side, black
/// on its back, `rgb/R²` on a sphere light), and nowhere counted twice with direct light.
#[test]
fn emitters_are_seen_with_their_radiance_directly_in_mirrors_and_through_glass() {
    let render = |body: &str, eye: &str, view: &str| {
        let src = format!(
            "root = gr.node('root')\n{body}\n\
             gr.render(root, 'x.png', 9, 9, {eye}, {view}, {{1, 0, 0}}, 10, {{0, 0, 0}}, lights)"
        );
        let films =
            common::render_films_with(src.as_bytes(), "e.lua", Path::new("."), &common::whitted())
                .unwrap();
        films[0].2.get(4, 4)
    };
    // A 2 × 0.5 light (area 1) at y = 3 emitting downwards, rgb (0.5, 1, 2).
    let light = "lights = {gr.area_light({0, 3, 0}, {0.5, 1, 2}, {0, 0, 1}, nil, nil, {2, 0, 0}, {0, 0, 0.5})}";
    let pi = std::f32::consts::PI;
    let want = Vec3A::new(0.5, 1.0, 2.0) * pi;
    let below = render(light, "{0, 0, 0}", "{0, 1, 0}");
    assert!(
        (below - want).abs().max_element() < 1e-4 * want.max_element(),
        "{below}"
    );
    let above = render(light, "{0, 6, 0}", "{0, -1, 0}");
    assert_eq!(above, Vec3A::ZERO, "the back of an area light is black");
    // Straight down into a mirror (ks 0.8, no highlight) below the light, and straight up
    // through a glass slab of index 1.5.
    let seen = render(
        &format!(
            "{light}\nm = gr.material({{0, 0, 0}}, {{0.8, 0.8, 0.8}}, 0)\n\
             s = gr.cube('s'); s:scale(4, 0.1, 4); s:translate(-2, -1.1, -2); s:set_material(m); root:add_child(s)"
        ),
        "{0, 0, 0}",
        "{0, -1, 0}",
    );
    assert!(
        (seen - 0.8 * want).abs().max_element() < 1e-3 * want.max_element(),
        "{seen}"
    );
    let slab = |light: &str| {
        render(
            &format!(
                "{light}\ng = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)\n\
                 s = gr.cube('s'); s:scale(4, 0.5, 4); s:translate(-2, 1, -2); s:set_material(g); root:add_child(s)"
            ),
            "{0, 0, 0}",
            "{0, 1, 0}",
        )
    };
    // What the slab shows of the light alone: the same view with a black light subtracted (the
    // 4% reflected down at each face sees the background).
    let dark = light.replace("{0.5, 1, 2}", "{0, 0, 0}");
    let glass = slab(light) - slab(&dark);
    // Two interfaces at normal incidence transmit (1 − R)² with R = 0.04, the light bouncing
    // between them (1 + R² + R⁴ …), and the n² factors of entering and leaving cancel.
    let t = (1.0f32 - 0.04).powi(2) / (1.0 - 0.04 * 0.04);
    assert!(
        (glass - t * want).abs().max_element() < 1e-3 * want.max_element(),
        "{glass} vs {}",
        t * want
    );
    // A sphere light of radius 0.5 and rgb 1 has radiance rgb / R² = 4.
    let sphere = render(
        "lights = {gr.sphere_light({0, 3, 0}, {1, 1, 1}, {0, 0, 1}, nil, nil, 0.5)}",
        "{0, 0, 0}",
        "{0, 1, 0}",
    );
    assert!(
        (sphere - Vec3A::splat(4.0)).abs().max_element() < 1e-4,
        "{sphere}"
    );
}
