//! Materials through the renderer: textures replace kd at the right texture coordinates on every
//! primitive kind, normal maps act in the surface's tangent frame, and the corpus's textured
//! scenes render with their images.

use crate::common;

use crate::common::{out_dir, render_films};
use caustic::film::Film;
use caustic::geometry::Ray;
use caustic::material::texture::Texture;
use glam::Vec3A;
use std::path::Path;

/// Writes a 4×4 texture whose every texel has a different colour.
fn write_texture(dir: &Path) {
    let img = image::RgbImage::from_fn(4, 4, |x, y| {
        image::Rgb([(x * 60 + 10) as u8, (y * 60 + 10) as u8, 200])
    });
    img.save(dir.join("tex.png")).unwrap();
}

/// Renders `body` (which adds nodes to `root`) lit only by an ambient light of 1, so each pixel
/// is exactly its diffuse colour; returns the film and a function giving each pixel's surface.
fn ambient_render(
    dir: &Path,
    body: &str,
) -> (Film, Vec<Option<caustic::scene::build::SurfaceHit>>) {
    let src = format!(
        "tex = gr.material({{1,1,1}}, {{0,0,0}}, 0, 0, 1, 0, 'tex.png')\nroot = gr.node('root')\n{body}\n\
         gr.render(root, 'x.png', 40, 40, {{0,0,6}}, {{0,0,-1}}, {{0,1,0}}, 40, {{1,1,1}}, {{gr.light({{0,0,-50}}, {{0,0,0}}, {{1,0,0}})}})"
    );
    let d = common::run_lua_in(&src, dir).unwrap();
    let r = &d.renders[0];
    let mut scene = caustic::scene::build::build_scene(&d, r).unwrap();
    let camera = caustic::camera::Camera::new(&r.camera, r.width, r.height);
    let film = common::render_scene(&mut scene, &camera, r.width, r.height, &common::whitted());
    let surfaces = (0..r.width * r.height)
        .map(|i| {
            let ray: Ray = camera.ray((i % r.width) as f32 + 0.5, (i / r.width) as f32 + 0.5);
            scene.intersect(&ray).map(|h| scene.surface(&ray, &h))
        })
        .collect();
    (film, surfaces)
}

#[test]
fn textures_replace_kd_at_the_hit_coordinates_on_every_primitive() {
    let dir = out_dir("materials-textures");
    write_texture(&dir);
    let texture = Texture::load(&dir.join("tex.png"), &caustic::Loc::internal()).unwrap();
    let bodies = [
        "s = gr.sphere('s'); s:set_material(tex); s:rotate('y', 30); root:add_child(s)",
        "b = gr.cube('b'); b:set_material(tex); b:translate(-0.5, -0.5, -0.5); b:rotate('y', 35); b:rotate('x', 20); root:add_child(b)",
        "c = gr.cylinder('c'); c:set_material(tex); c:rotate('x', -60); root:add_child(c)",
        "k = gr.cone('k'); k:set_material(tex); k:translate(0, 0, -0.5); k:rotate('x', -120); root:add_child(k)",
        "m = gr.mesh('m', {{-1,-1,0}, {1,-1,0}, {0,1,0}}, {{0, 1, 2}}); m:set_material(tex); root:add_child(m)",
        "a = gr.sphere('a'); a:set_material(tex); b = gr.cube('b'); b:set_material(tex); b:scale(2, 2, 2); b:translate(-1, -1, 0)\n\
         d = gr.difference('d', a, b); d:rotate('x', 30); root:add_child(d)",
    ];
    for body in bodies {
        let (film, surfaces) = ambient_render(&dir, body);
        let mut checked = 0;
        let mut colours = std::collections::HashSet::new();
        for (i, s) in surfaces.iter().enumerate() {
            let Some(s) = s else { continue };
            let want = texture.colour(s.uv);
            let got = film.pixels[i];
            assert!(
                (got - want).abs().max_element() < 1e-5,
                "{body}: pixel {i} uv {} got {got} want {want}",
                s.uv
            );
            colours.insert(format!("{:.3}", got));
            checked += 1;
        }
        assert!(
            checked > 100 && colours.len() > 8,
            "{body}: {checked} pixels, {} colours",
            colours.len()
        );
    }
}

/// A square facing the camera with a normal map, lit from the upper right; `turn` rotates the
/// square and the light together about the view axis.
fn normal_mapped(dir: &Path, bump: &str, turn: f32) -> Film {
    let src = format!(
        "m = gr.material({{0.8,0.8,0.8}}, {{0,0,0}}, 0, 0, 1, 0, nil, '{bump}')\nroot = gr.node('root')\n\
         q = gr.cube('q'); q:set_material(m); q:translate(-0.5, -0.5, -1); q:scale(2, 2, 1); q:rotate('z', {turn}); root:add_child(q)\n\
         pos = {{3 * math.cos(math.rad(30 + {turn})), 3 * math.sin(math.rad(30 + {turn})), 1}}\n\
         gr.render(root, 'x.png', 32, 32, {{0,0,4}}, {{0,0,-1}}, {{0,1,0}}, 22, {{0,0,0}}, {{gr.light(pos, {{1,1,1}}, {{1,0,0}})}})"
    );
    let films = render_films(src.as_bytes(), "n.lua", dir).unwrap();
    films.into_iter().next().unwrap().2
}

#[test]
fn flat_normal_map_changes_nothing_and_tilted_maps_turn_with_their_object() {
    let dir = out_dir("materials-normal-maps");
    image::RgbImage::from_pixel(8, 8, image::Rgb([128, 128, 255]))
        .save(dir.join("flat.png"))
        .unwrap();
    image::RgbImage::from_pixel(8, 8, image::Rgb([200, 128, 230]))
        .save(dir.join("tilt.png"))
        .unwrap();
    let src_plain = "m = gr.material({0.8,0.8,0.8}, {0,0,0}, 0)\nroot = gr.node('root')\n\
        q = gr.cube('q'); q:set_material(m); q:translate(-0.5, -0.5, -1); q:scale(2, 2, 1); root:add_child(q)\n\
        pos = {3 * math.cos(math.rad(30)), 3 * math.sin(math.rad(30)), 1}\n\
        gr.render(root, 'x.png', 32, 32, {0,0,4}, {0,0,-1}, {0,1,0}, 22, {0,0,0}, {gr.light(pos, {1,1,1}, {1,0,0})})";
    let plain = render_films(src_plain.as_bytes(), "p.lua", &dir)
        .unwrap()
        .remove(0)
        .2;
    let flat = normal_mapped(&dir, "flat.png", 0.0);
    assert_eq!(
        plain.pixels, flat.pixels,
        "a flat normal map must leave the image unchanged"
    );
    // The tilted map changes the shading...
    let tilted = normal_mapped(&dir, "tilt.png", 0.0);
    let diff = tilted
        .pixels
        .iter()
        .zip(&plain.pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f32::max);
    assert!(
        diff > 0.05,
        "the tilted map must change the shading ({diff})"
    );
    // ... and turning square and light by 90° about the view axis turns the image by 90°:
    // the map acts in the surface's frame, not in world space.
    let turned = normal_mapped(&dir, "tilt.png", 90.0);
    let n = tilted.width;
    for y in 0..n {
        for x in 0..n {
            // Image rotated 90° counter-clockwise: (x, y) -> (y, n - 1 - x).
            let a = tilted.get(x, y);
            let b = turned.get(y, n - 1 - x);
            assert!((a - b).abs().max_element() < 1e-3, "({x}, {y}): {a} vs {b}");
        }
    }
}

#[test]
fn corpus_textured_scenes_render_with_their_images() {
    if common::skip_without_corpus("corpus_textured_scenes_render_with_their_images") {
        return;
    }
    let project = common::corpus("tengyucai__Computer-Graphics/Project");
    for name in ["texture", "bump", "perlin"] {
        let src = std::fs::read(project.join(format!("Assets/{name}.lua"))).unwrap();
        // Run as the project does, from Project/, so 'Assets/dirt.png' resolves. Textures are the
        // subject, so without photon maps (which would cost minutes at 512²).
        let films =
            common::render_films_with(&src, &format!("{name}.lua"), &project, &common::whitted())
                .unwrap();
        let (_, _, film) = &films[0];
        // The floor is the bottom-centre of the image; its kd is flat green (0.1, 0.7, 0.1) and
        // its look must come from the texture or the noise instead: many distinct colours.
        let mut colours = std::collections::HashSet::new();
        for y in (film.height * 85 / 100)..film.height {
            for x in (film.width * 40 / 100)..(film.width * 60 / 100) {
                let c = film.get(x, y);
                colours.insert([
                    (c.x * 255.0) as u8,
                    (c.y * 255.0) as u8,
                    (c.z * 255.0) as u8,
                ]);
            }
        }
        assert!(
            colours.len() > 20,
            "{name}: floor shows {} colours",
            colours.len()
        );
        if name != "perlin" {
            // Dirt, not the green kd: the floor's mean is not green-dominated.
            let mean: Vec3A = (0..film.width)
                .map(|x| film.get(x, film.height - 1))
                .sum::<Vec3A>()
                / film.width as f32;
            assert!(
                mean.y < mean.x * 1.5,
                "{name}: floor mean {mean} still looks like kd"
            );
        }
    }
}

/// A rough mirror (`gr.roughness`, GGX) lit by a point light in the mirror direction of the
/// camera's centre ray: that pixel is the rough conductor's BRDF in the course's units,
/// `ks·π·f·cos θi` with `f = D(n)·G2/(4 cos θo cos θi)`, `D(n) = 1/(π α²)` and
/// `G2 = 1/(1 + 2Λ(45°))`, `Λ(45°) = (√(1 + α²) − 1)/2` (α = roughness² = 0.25: 2.744 for
/// ks = 0.5), within 1e-3. Everything sits in a black sphere, so the glossy reflection the eye
/// path follows finds nothing. Before, roughness did not exist and the surface was a mirror.
#[test]
fn a_rough_mirror_reflects_a_point_light_by_the_ggx_brdf() {
    let src = "black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
metal = gr.material({0, 0, 0}, {0.5, 0.5, 0.5}, 0)
gr.roughness(metal, 0.5)
root = gr.node('root')
enclosure = gr.sphere('enclosure'); enclosure:set_material(black); enclosure:scale(100, 100, 100)
root:add_child(enclosure)
plane = gr.cube('plane'); plane:set_material(metal); plane:scale(20, 1, 20); plane:translate(-10, -1, -10)
root:add_child(plane)
gr.render(root, 'rough.png', 9, 9, {0, 1, 1}, {0, -1, -1}, {0, 1, 0}, 20, {0, 0, 0},
          {gr.light({0, 1, -1}, {1, 1, 1}, {1, 0, 0})})
";
    let films = common::render_films_with(
        src.as_bytes(),
        "rough.lua",
        Path::new("."),
        &common::whitted(),
    )
    .unwrap();
    let film = &films[0].2;
    let centre = film.pixels[4 * 9 + 4];
    let alpha = 0.25f32;
    let lambda = ((1.0 + alpha * alpha).sqrt() - 1.0) / 2.0;
    let g2 = 1.0 / (1.0 + 2.0 * lambda);
    let cos = std::f32::consts::FRAC_1_SQRT_2;
    let f = g2 / (std::f32::consts::PI * alpha * alpha) / (4.0 * cos * cos);
    let want = 0.5 * std::f32::consts::PI * f * cos;
    assert!(
        (centre - Vec3A::splat(want)).abs().max_element() < 1e-3 * want,
        "centre {centre}, closed form {want}"
    );
}

/// Frosted glass under a lamp: a rough dielectric floor (`gr.roughness(glass, 0.3)`, GGX
/// `alpha = 0.09`, index 1.5, its inside absorbing everything that enters) reflects a square
/// area light of radiance `L` towards a camera in the light's mirror direction. Each pixel is
/// `∫ f_r(wo, wi)·cos θi·L·cos θl / d² dA` over the light, the Walter et al. reflection lobe
/// integrated here by a 400 × 400 midpoint rule (the field of view is 0.5°, so every pixel sees
/// the centre's integral to 1e-3). With the lights sampled at the interface and weighed against
/// the path's own draw (multiple importance sampling, `caustic::integrator::mis`) the mean over
/// the 81 pixels is within 2% of it and the pixels' spread is under half that of the draw alone
/// (`light_samples = 0`), whose mean is within three standard errors. Before, the draw alone
/// was all there was.
#[test]
fn frosted_glass_reflects_a_lamp_by_the_walter_lobe_with_less_noise_under_mis() {
    use caustic::material::microfacet::{Ggx, RoughDielectric};
    let src = "black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
gr.roughness(glass, 0.3)
gr.absorption(glass, {0.001, 0.001, 0.001}, 0.01)
root = gr.node('root')
enclosure = gr.sphere('enclosure'); enclosure:set_material(black); enclosure:scale(100, 100, 100)
root:add_child(enclosure)
slab = gr.cube('slab'); slab:set_material(glass); slab:scale(20, 1, 20); slab:translate(-10, -1, -10)
root:add_child(slab)
lamp = gr.area_light({0, 1, -1}, {2, 2, 2}, {0, 0, 1}, nil, nil, {0.5, 0, 0}, {0, 0, 0.5})
gr.render(root, 'frosted.png', 9, 9, {0, 1, 1}, {0, -1, -1}, {0, 1, 0}, 0.5, {0, 0, 0}, {lamp})
";
    let render = |light_samples: u32| {
        let mut settings = common::whitted();
        settings.light_samples = light_samples;
        let films =
            common::render_films_with(src.as_bytes(), "frosted.lua", Path::new("."), &settings)
                .unwrap();
        let film = &films[0].2;
        let values: Vec<f32> = film.pixels.iter().map(|p| p.x).collect();
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / values.len() as f32;
        (mean, var.sqrt())
    };
    // The closed form: L = π·rgb/A on the lamp (caustic's units), the lobe in a frame whose z
    // is the floor's normal +y.
    let lobe = RoughDielectric {
        ggx: Ggx::from_roughness(0.3),
        eta: 1.0 / 1.5,
    };
    let local = |v: Vec3A| Vec3A::new(v.x, v.z, v.y);
    let wo = Vec3A::new(0.0, 1.0, 1.0).normalize();
    let radiance = std::f32::consts::PI * 2.0 / 0.25;
    let n = 400;
    let mut want = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let y = Vec3A::new(
                -0.25 + 0.5 * (i as f32 + 0.5) / n as f32,
                1.0,
                -1.25 + 0.5 * (j as f32 + 0.5) / n as f32,
            );
            let d2 = y.length_squared();
            let wi = y / d2.sqrt();
            let f = lobe.eval(local(wo), local(wi));
            let cos_light = wi.y;
            let da = 0.25 / (n * n) as f32;
            want += (f * wi.y * radiance * cos_light / d2 * da) as f64;
        }
    }
    let want = want as f32;
    let (mis, mis_spread) = render(16);
    let (drawn, drawn_spread) = render(0);
    assert!(
        (mis / want - 1.0).abs() < 0.02,
        "with MIS {mis}, closed form {want}"
    );
    // Unbiased too, within three standard errors of its 81 pixels.
    assert!(
        (drawn - want).abs() < 3.0 * drawn_spread / 9.0,
        "the draw alone {drawn} (spread {drawn_spread}), closed form {want}"
    );
    assert!(
        mis_spread < 0.5 * drawn_spread,
        "spread with MIS {mis_spread}, of the draw alone {drawn_spread}"
    );
}
