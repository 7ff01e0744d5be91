//! glTF files as whole scenes (`caustic render scene.glb`, issue 37): the camera, punctual
//! lights in Blender's units, emissive surfaces as lights, and what caustic cannot honour
//! listed rather than dropped.

use crate::common::{GltfFile, caustic, out_dir, render_films_with, render_scene, whitted};
use caustic::camera::Camera;
use caustic::desc::{LightShape, MaterialDesc};
use caustic::error::Loc;
use caustic::io::gltf::scene::{View, describe_scene};
use caustic::scene::build::build_scene;
use glam::{Vec3, vec3};
use std::path::Path;

/// A 4 × 4 floor at y = 0 facing up, as a glTF buffer: positions accessor 0, indices 1.
fn floor() -> GltfFile {
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[
            -2.0, 0.0, -2.0, 2.0, 0.0, -2.0, 2.0, 0.0, 2.0, -2.0, 0.0, 2.0,
        ],
    );
    // Counter-clockwise seen from above.
    f.indices(5125, &[0, 2, 1, 0, 3, 2]);
    f
}

fn describe(path: &Path, view: &View) -> caustic::desc::SceneDesc {
    describe_scene(path, view, caustic::budget::Budget::machine_default()).unwrap()
}

/// Returns the error reading `path` as a scene seen from `camera` gives.
fn describe_err(path: &Path, camera: Option<&str>) -> String {
    let v = View {
        camera: camera.map(str::to_owned),
        ..view()
    };
    describe_scene(path, &v, caustic::budget::Budget::machine_default())
        .unwrap_err()
        .to_string()
}

fn view() -> View {
    View {
        output: "x.png".into(),
        ..View::default()
    }
}

/// A matte material of reflectance `kd`, set on the scene's geometry node, so that a pixel
/// is a closed form.
fn matte(desc: &mut caustic::desc::SceneDesc, kd: f32) {
    desc.materials.push(MaterialDesc {
        kd: Vec3::splat(kd),
        ks: Vec3::ZERO,
        shininess: 0.0,
        transparency: 0.0,
        ior: 1.0,
        absorption: Vec3::ZERO,
        roughness: 0.0,
        perlin_scale: 0.0,
        texture: None,
        bump: None,
        loc: Loc::internal(),
    });
    let id = caustic::desc::MaterialId(desc.materials.len() as u32 - 1);
    for n in &mut desc.nodes {
        if n.kind.is_geometry() {
            n.material = Some(id);
        }
    }
}

/// The camera node looks down its −Z with +Y up, the image takes the camera's aspect ratio,
/// and a point light of I candela is I/683 W/sr: a matte floor's pixel straight under it is
/// `kd/π · I/683 / d²`, within float rounding.
#[test]
fn camera_and_point_light_follow_the_file_in_blender_units() {
    let dir = out_dir("gltf-scene-camera-light");
    let f = floor();
    // The camera 3 above the floor looking straight down (a rotation of −90° about x), the
    // light 2 above the floor at (0.5, 2, 0.25).
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let rest = format!(
        r#""scene":0,"scenes":[{{"nodes":[0,1,2]}}],
        "nodes":[{{"mesh":0}},
          {{"name":"Top","camera":0,"translation":[0,3,0],"rotation":[{},0,0,{s}]}},
          {{"translation":[0.5,2,0.25],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":0.8,"aspectRatio":2.0,"znear":0.1}}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","color":[1,0.5,0.25],"intensity":683}}]}}}},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]"#,
        -s
    );
    let path = f.write_glb(&dir, "room", &rest);
    let mut desc = describe(&path, &view());
    let r = desc.renders[0].clone();
    assert_eq!((r.width, r.height), (800, 400));
    assert!((r.camera.eye - vec3(0.0, 3.0, 0.0)).length() < 1e-6);
    assert!(
        (r.camera.view - vec3(0.0, -1.0, 0.0)).length() < 1e-6,
        "{}",
        r.camera.view
    );
    assert!(
        (r.camera.up - vec3(0.0, 0.0, -1.0)).length() < 1e-6,
        "{}",
        r.camera.up
    );
    assert!((r.camera.fov_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    let light = &desc.lights[0];
    assert_eq!(light.shape, LightShape::Point);
    let pi = std::f32::consts::PI;
    assert!((light.colour - vec3(1.0, 0.5, 0.25) / pi).length() < 1e-6);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);

    // Render with the file's view at --size 64 32 and a matte floor of kd 0.5.
    let sized = describe(
        &path,
        &View {
            size: Some((64, 32)),
            ..view()
        },
    );
    assert_eq!((sized.renders[0].width, sized.renders[0].height), (64, 32));
    matte(&mut desc, 0.5);
    let mut r = desc.renders[0].clone();
    (r.width, r.height) = (64, 32);
    let mut scene = build_scene(&desc, &r).unwrap();
    let camera = Camera::new(&r.camera, r.width, r.height);
    let film = render_scene(&mut scene, &camera, r.width, r.height, &whitted());
    // The pixel whose centre ray meets the floor nearest (0.5, 0, 0.25): find it by the
    // camera's own rays, then the closed form at the point it meets.
    let mut best = (f32::INFINITY, 0, 0, Vec3::ZERO);
    for y in 0..r.height {
        for x in 0..r.width {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let t = -ray.origin.y / ray.dir.y;
            let p = Vec3::from(ray.at(t));
            let d = (p - vec3(0.5, 0.0, 0.25)).length();
            if d < best.0 {
                best = (d, x, y, p);
            }
        }
    }
    let (_, x, y, p) = best;
    let to_light = vec3(0.5, 2.0, 0.25) - p;
    let (d2, cos) = (to_light.length_squared(), to_light.normalize().y);
    // Course units: kd · rgb · cos / d², rgb = (colour · 683 / 683) / π.
    let expected = vec3(1.0, 0.5, 0.25) * 0.5 / pi * cos / d2;
    let got = Vec3::from(film.get(x, y));
    assert!(
        (got - expected).abs().max_element() < 1e-4 * expected.max_element(),
        "pixel ({x}, {y}): {got} against {expected}"
    );
}

/// Writes `dir/panel.glb`: a 0.5 × 0.5 quad at the origin in the plane y = 0, counter-clockwise
/// seen from below (it faces down), as mesh 0, with `rest` of the JSON (nodes, materials, meshes).
fn write_panel(dir: &Path, rest: &str) {
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[
            -0.25, 0.0, -0.25, 0.25, 0.0, -0.25, 0.25, 0.0, 0.25, -0.25, 0.0, 0.25,
        ],
    );
    f.indices(5125, &[0, 1, 2, 0, 2, 3]);
    f.write_glb(dir, "panel", rest);
}

/// An emissive quad is an area light: a floor lit by a glTF panel of radiance L renders as
/// the one lit by `gr.area_light` of the same square and `rgb = L·A/π`, and the camera sees
/// the panel's radiance.
#[test]
fn an_emissive_quad_lights_as_the_area_light_of_its_shape() {
    let dir = out_dir("gltf-scene-emitter");
    let rest = r#""nodes":[{"mesh":0}],
        "extensionsUsed":["KHR_materials_emissive_strength"],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1]},
          "emissiveFactor":[1,0.8,0.6],
          "extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":8}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#;
    write_panel(&dir, rest);
    let data = caustic::io::gltf::load_gltf(&dir.join("panel.glb")).unwrap();
    // A surface as well as a light: it hides what is behind it and reflects by its material.
    assert_eq!(
        data.triangles.len(),
        2,
        "an emissive surface is still geometry"
    );
    assert_eq!(data.emitters.len(), 1);
    assert_eq!(data.emitters[0].radiance, vec3(8.0, 6.4, 4.8));
    let render = |lamp: &str| {
        let script = format!(
            r#"
            matte = gr.material({{0.6, 0.6, 0.6}}, {{0, 0, 0}}, 0)
            root = gr.node('root')
            floor = gr.cube('floor'); floor:set_material(matte)
            floor:scale(40, 0.1, 40); floor:translate(-20, -1.1, -20); root:add_child(floor)
            {lamp}
            gr.render(root, 'x.png', 48, 48, {{0, 0.5, 3}}, {{0, -0.6, -3}}, {{0, 1, 0}}, 50,
                      {{0, 0, 0}}, lights)
        "#
        );
        let mut settings = whitted();
        settings.light_samples = 64;
        let films = render_films_with(script.as_bytes(), "lamp.lua", &dir, &settings).unwrap();
        films.into_iter().next().unwrap().2
    };
    let mesh = render(
        "panel = gr.mesh('panel', 'panel.glb'); panel:translate(0, 0.5, 0); root:add_child(panel)
         lights = {gr.light({0, -50, 0}, {0, 0, 0}, {1, 0, 0})}",
    );
    // rgb = L·A/π with A = 0.25.
    let pi = std::f32::consts::PI;
    let rgb = vec3(8.0, 6.4, 4.8) * 0.25 / pi;
    let area = render(&format!(
        "lights = {{gr.area_light({{0, 0.5, 0}}, {{{}, {}, {}}}, {{0, 0, 1}}, nil, nil,
                                   {{0.5, 0, 0}}, {{0, 0, 0.5}})}}",
        rgb.x, rgb.y, rgb.z
    ));
    let mean = |film: &caustic::film::Film| {
        let mut sum = glam::Vec3A::ZERO;
        for y in 24..film.height {
            for x in 0..film.width {
                sum += film.get(x, y);
            }
        }
        sum / (24 * film.width) as f32
    };
    let (a, b) = (mean(&mesh), mean(&area));
    assert!(a.x > 0.01, "the floor is lit: {a}");
    assert!(
        ((a - b) / b).abs().max_element() < 0.01,
        "floor under the glTF panel {a} against the area light {b}"
    );
}

/// An emissive surface is a surface too (glTF's and Mitsuba's model): a black emissive panel
/// between a point light and the floor shades the floor under it, which then receives the
/// panel's light alone, as if the point light were off (within 0.5%). Before, the panel was a
/// light only and the point light shone through it.
#[test]
fn an_emissive_panel_casts_the_shadow_of_the_surface_it_is() {
    let dir = out_dir("gltf-scene-emitter-shadow");
    let rest = r#""nodes":[{"mesh":0}],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1],"metallicFactor":0},
          "emissiveFactor":[1,1,1]}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#;
    write_panel(&dir, rest);
    let render = |point: f32| {
        // The camera sits under the panel looking straight down at the floor's middle, all of
        // it in the panel's shadow from the point light above.
        let script = format!(
            r#"
            matte = gr.material({{0.6, 0.6, 0.6}}, {{0, 0, 0}}, 0)
            root = gr.node('root')
            floor = gr.cube('floor'); floor:set_material(matte)
            floor:scale(40, 0.1, 40); floor:translate(-20, -1.1, -20); root:add_child(floor)
            panel = gr.mesh('panel', 'panel.glb'); panel:translate(0, 0.5, 0); root:add_child(panel)
            gr.render(root, 'x.png', 8, 8, {{0, 0, 0}}, {{0, -1, 0}}, {{0, 0, -1}}, 20,
                      {{0, 0, 0}}, {{gr.light({{0, 2, 0}}, {{{point}, {point}, {point}}}, {{0, 0, 1}})}})
        "#
        );
        let mut settings = whitted();
        settings.light_samples = 64;
        let films = render_films_with(script.as_bytes(), "shadow.lua", &dir, &settings).unwrap();
        let film = &films.into_iter().next().unwrap().2;
        film.pixels.iter().map(|p| p.x).sum::<f32>() / film.pixels.len() as f32
    };
    let (lit, panel_only) = (render(5.0), render(0.0));
    // The point light alone would add kd·I·cos/d² = 0.6·5/9 = 0.33 under it.
    assert!(
        panel_only > 0.01,
        "the panel lights the floor: {panel_only}"
    );
    assert!(
        (lit / panel_only - 1.0).abs() < 0.005,
        "under the panel with the point light on {lit}, off {panel_only}"
    );
}

/// `export-mitsuba` writes an emissive surface as Mitsuba has one: its shape, with its BSDF
/// and an `area` emitter of its radiance (`emissiveFactor × emissiveStrength`), once; no
/// second, coincident light shape over the same triangles.
#[test]
fn an_emissive_surface_exports_as_one_emitting_shape() {
    let dir = out_dir("gltf-scene-emitter-export");
    let rest = r#""nodes":[{"mesh":0}],
        "extensionsUsed":["KHR_materials_emissive_strength"],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1],"metallicFactor":0,
          "roughnessFactor":1},
          "emissiveFactor":[1,0.5,0.25],
          "extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#;
    write_panel(&dir, rest);
    let out = caustic()
        .current_dir(&dir)
        .args(["export-mitsuba", "panel.glb", "-o", "panel.xml"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let xml = std::fs::read_to_string(dir.join("panel.xml")).unwrap();
    assert_eq!(xml.matches("<emitter type=\"area\">").count(), 1, "{xml}");
    let shape = xml
        .lines()
        .find(|l| l.contains("<emitter type=\"area\">"))
        .unwrap();
    assert!(
        shape.contains("<rgb name=\"radiance\" value=\"4, 2, 1\"/>")
            && shape.contains("panel_mesh0_material")
            && shape.contains("roughconductor"),
        "the panel's shape, BSDF and radiance: {shape}"
    );
    assert!(!xml.contains("_light"), "no separate light shape: {xml}");
}

/// Renders the floor of `desc` (made matte, kd 0.5) seen from the file's camera at 96 × 96,
/// one ray through each pixel's centre, course's renderer; returns each pixel that sees the
/// floor well inside its edges, with the point it sees and its value.
fn floor_pixels(desc: &mut caustic::desc::SceneDesc) -> Vec<(Vec3, Vec3)> {
    matte(desc, 0.5);
    let mut r = desc.renders[0].clone();
    (r.width, r.height) = (96, 96);
    let mut scene = build_scene(desc, &r).unwrap();
    let camera = Camera::new(&r.camera, r.width, r.height);
    let film = render_scene(&mut scene, &camera, r.width, r.height, &whitted());
    let mut out = Vec::new();
    for y in 0..r.height {
        for x in 0..r.width {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let p = Vec3::from(ray.at(-ray.origin.y / ray.dir.y));
            if ray.dir.y < 0.0 && p.x.abs() < 1.95 && p.z.abs() < 1.95 {
                out.push((p, Vec3::from(film.get(x, y))));
            }
        }
    }
    out
}

/// A file's spot light in Blender's units: `intensity` cd is `intensity/683` W/sr down its
/// node's −Z, with glTF's cone falloff (`t = clamp((cos θ − cos outer)/(cos inner − cos
/// outer), 0, 1)`, intensity times `t²`). On a matte floor of kd 0.5 every pixel is the closed
/// form `kd/π · I/683 · t² · cos θ / d²` to 1% on the axis and in the ramp between the cones,
/// and exactly 0 beyond the outer cone.
#[test]
fn a_spot_light_lights_the_floor_as_the_closed_form_and_nothing_beyond_its_cone() {
    let dir = out_dir("gltf-scene-spot");
    let f = floor();
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // The camera 4 above the floor and the spot 1.5 above (0.3, 0, −0.2), both looking down
    // (−90° about x); the spot's I/683 is π W/sr, so its rgb is its colour.
    let (inner, outer) = (0.35f64, 0.5f64);
    let rest = format!(
        r#""nodes":[{{"mesh":0}},
          {{"camera":0,"translation":[0,4,0],"rotation":[{m},0,0,{s}]}},
          {{"translation":[0.3,1.5,-0.2],"rotation":[{m},0,0,{s}],
            "extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":1.2,"znear":0.1}}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"spot","name":"Lamp",
          "color":[1,0.5,0.25],"intensity":{i},
          "spot":{{"innerConeAngle":{inner},"outerConeAngle":{outer}}}}}]}}}},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]"#,
        m = -s,
        i = 683.0 * std::f64::consts::PI,
    );
    let path = f.write_glb(&dir, "spot", &rest);
    let mut desc = describe(&path, &view());
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let light = &desc.lights[0];
    let LightShape::Spot {
        direction,
        inner: i,
        outer: o,
    } = light.shape
    else {
        panic!("not a spot: {:?}", light.shape)
    };
    assert!(
        (direction - vec3(0.0, -1.0, 0.0)).length() < 1e-6,
        "{direction}"
    );
    assert_eq!((i, o), (inner as f32, outer as f32));
    assert!((light.colour - vec3(1.0, 0.5, 0.25)).length() < 1e-5);
    // The spot's photon share is its flux: π·rgb·∫t² dω, summed over the channels.
    let w = inner.cos() - outer.cos();
    let weighted = std::f64::consts::TAU * (1.0 - outer.cos() - 2.0 * w / 3.0);
    let flux = std::f64::consts::PI * weighted * 1.75;
    assert!((f64::from(light.power.unwrap()) / flux - 1.0).abs() < 1e-5);

    let spot = vec3(0.3, 1.5, -0.2);
    let (mut on_axis, mut ramp, mut dark) = (0, 0, 0);
    for (p, got) in floor_pixels(&mut desc) {
        let to = spot - p;
        let d = f64::from(to.length());
        let cos = f64::from(to.y) / d;
        let t = ((cos - outer.cos()) / w).clamp(0.0, 1.0);
        let want = vec3(1.0, 0.5, 0.25) * (0.5 * t * t * cos / (d * d)) as f32;
        if cos < outer.cos() - 1e-4 {
            assert_eq!(got, Vec3::ZERO, "{p}: beyond the outer cone");
            dark += 1;
        } else if cos > outer.cos() + 1e-4 {
            assert!(
                (got - want).abs().max_element() <= 0.01 * want.max_element(),
                "{p} (cos θ {cos}): {got} against {want}"
            );
            if cos > inner.cos() {
                on_axis += 1;
            } else {
                ramp += 1;
            }
        }
    }
    assert!(
        on_axis > 100 && ramp > 100 && dark > 1000,
        "{on_axis} on the axis, {ramp} in the ramp, {dark} dark"
    );
}

/// A file's directional light in Blender's units: `intensity` lx is `intensity/683` W/m²
/// travelling down its node's −Z, with no falloff: a matte floor of kd 0.5 is `kd/π · E ·
/// cos θ` everywhere, and the photon share is the flux through the disc over the file.
#[test]
fn a_directional_light_lights_the_floor_as_e_kd_over_pi_cos() {
    let dir = out_dir("gltf-scene-sun");
    let f = floor();
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // −60° about x: the light travels along (0, −cos 30°, −sin 30°); E/683 = π·colour.
    let rest = format!(
        r#""nodes":[{{"mesh":0}},
          {{"camera":0,"translation":[0,4,0],"rotation":[{m},0,0,{s}]}},
          {{"translation":[5,5,5],"rotation":[-0.5,0,0,0.8660254037844386],
            "extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":1.2,"znear":0.1}}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"directional",
          "color":[0.2,0.4,0.6],"intensity":{i}}}]}}}},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]"#,
        m = -s,
        i = 683.0 * std::f64::consts::PI,
    );
    let path = f.write_glb(&dir, "sun", &rest);
    let mut desc = describe(&path, &view());
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let light = &desc.lights[0];
    let LightShape::Directional { direction } = light.shape else {
        panic!("not directional: {:?}", light.shape)
    };
    let cos = 30f32.to_radians().cos();
    assert!(
        (direction - vec3(0.0, -cos, -0.5)).length() < 1e-6,
        "{direction}"
    );
    assert!((light.colour - vec3(0.2, 0.4, 0.6)).length() < 1e-6);
    // The flux through the disc over the 4 × 4 floor's sphere (radius √8 and a hundredth):
    // E·πR², E = π·rgb.
    let r = 8f32.sqrt() * 1.01;
    let pi = std::f32::consts::PI;
    let flux = pi * pi * r * r * 1.2;
    assert!((light.power.unwrap() / flux - 1.0).abs() < 1e-3, "{flux}");
    let pixels = floor_pixels(&mut desc);
    assert!(pixels.len() > 4000, "{}", pixels.len());
    let want = vec3(0.2, 0.4, 0.6) * 0.5 * cos;
    for (p, got) in pixels {
        assert!(
            (got - want).abs().max_element() < 1e-5,
            "{p}: {got} against {want}"
        );
    }
}

/// A spot's cone angles out of glTF's range (inner above outer, beyond π/2, negative,
/// infinite), an intensity that overflows to infinity, and a spot or sun whose node gives it
/// no direction are errors naming the file and the light.
#[test]
fn bad_spot_and_directional_lights_are_errors_naming_the_light() {
    let dir = out_dir("gltf-scene-bad-lights");
    let f = floor();
    let file = |name: &str, light: &str, node: &str| {
        let rest = format!(
            r#""nodes":[{{"mesh":0}},{{{node}"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
               "extensionsUsed":["KHR_lights_punctual"],
               "extensions":{{"KHR_lights_punctual":{{"lights":[{light}]}}}},
               "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]"#
        );
        f.write_glb(&dir, name, &rest)
    };
    let spot = |inner: &str, outer: &str| {
        format!(
            r#"{{"type":"spot","name":"Lamp","spot":{{"innerConeAngle":{inner},"outerConeAngle":{outer}}}}}"#
        )
    };
    for (name, inner, outer) in [
        ("inner_above_outer", "0.6", "0.5"),
        ("beyond_right_angle", "0.1", "1.6"),
        ("negative", "-0.1", "0.5"),
        ("infinite", "0.1", "1e39"),
    ] {
        let err = describe_err(&file(name, &spot(inner, outer), ""), None);
        assert!(
            err.contains(&format!("{name}.glb"))
                && err.contains("light 'Lamp'")
                && err.contains("0 ≤ inner ≤ outer ≤ π/2"),
            "{err}"
        );
    }
    let err = describe_err(
        &file(
            "overflowing",
            r#"{"type":"directional","intensity":1e39}"#,
            "",
        ),
        None,
    );
    assert!(
        err.contains("overflowing.glb") && err.contains("light 0"),
        "{err}"
    );
    for (name, light) in [
        ("flat_spot", spot("0.1", "0.5")),
        (
            "flat_sun",
            r#"{"type":"directional","name":"Sun"}"#.to_owned(),
        ),
    ] {
        let err = describe_err(&file(name, &light, r#""scale":[0,0,0],"#), None);
        assert!(
            err.contains(&format!("{name}.glb")) && err.contains("no direction"),
            "{err}"
        );
    }
}

/// What caustic cannot honour is listed, one line each, and a file without any light is lit
/// from the camera with a warning rather than rendered black.
#[test]
fn what_the_scene_uses_and_caustic_ignores_is_listed() {
    let dir = out_dir("gltf-scene-ignored");
    let f = floor();
    let rest = r#""nodes":[{"mesh":0}],
        "extensionsUsed":["KHR_materials_clearcoat"],
        "materials":[{"name":"Coated","normalTexture":{"index":0},"alphaMode":"BLEND"}],
        "textures":[{"source":0}],"images":[{"uri":"n.png"}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#;
    let path = f.write_glb(&dir, "ignored", rest);
    let desc = describe(&path, &view());
    let all = desc.warnings.join("\n");
    for want in [
        "extension KHR_materials_clearcoat is not read",
        "material 'Coated': alpha (drawn opaque) not read",
        "the file has no light caustic renders",
    ] {
        assert!(all.contains(want), "missing '{want}' in:\n{all}");
    }
    // The default light sits at the default camera, which frames the floor.
    assert_eq!(desc.lights.len(), 1);
    assert_eq!(desc.lights[0].position, desc.renders[0].camera.eye);
    let eye = desc.renders[0].camera.eye;
    assert!(
        eye.z > 2.0 && eye.y > 0.0,
        "framed from the front, above: {eye}"
    );
}

/// Every way a file can name a bad view or light is an error naming the file: an unknown
/// camera (the message lists the scene's cameras), an orthographic or zero-fov camera, a
/// point light of negative or blinding intensity, more point lights than caustic samples, an
/// emitter brighter than a light may be, and more emissive triangles than caustic tests.
#[test]
fn bad_views_and_emitters_are_errors_naming_the_file() {
    let dir = out_dir("gltf-scene-bad");
    let f = floor();
    let mesh = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}]"#;
    let with = |name: &str, nodes_cameras: &str| {
        f.write_glb(&dir, name, &format!("{nodes_cameras},{mesh}"))
    };
    let cams = with(
        "cams",
        r#""nodes":[{"mesh":0},{"name":"Wide","camera":0}],
           "cameras":[{"name":"WideCam","type":"perspective","perspective":{"yfov":1,"znear":0.1}}]"#,
    );
    let err = describe_err(&cams, Some("Close"));
    assert!(
        err.contains("cams.glb") && err.contains("--camera Close") && err.contains("WideCam"),
        "{err}"
    );
    // Either name picks the camera.
    for name in ["Wide", "WideCam"] {
        let v = View {
            camera: Some(name.into()),
            ..view()
        };
        assert_eq!(
            describe(&cams, &v).renders[0].camera.fov_deg,
            1f32.to_degrees()
        );
    }
    let ortho = with(
        "ortho",
        r#""nodes":[{"mesh":0},{"camera":0}],
           "cameras":[{"name":"Flat","type":"orthographic","orthographic":{"xmag":1,"ymag":1,"zfar":10,"znear":0.1}}]"#,
    );
    let err = describe_err(&ortho, Some("Flat"));
    assert!(
        err.contains("ortho.glb") && err.contains("orthographic"),
        "{err}"
    );
    // Without --camera, the orthographic camera is listed and the scene framed instead.
    let d = describe(&ortho, &view());
    assert!(
        d.warnings
            .iter()
            .any(|w| w.contains("1 orthographic camera")),
        "{:?}",
        d.warnings
    );
    let zero = with(
        "zero",
        r#""nodes":[{"mesh":0},{"camera":0}],
           "cameras":[{"type":"perspective","perspective":{"yfov":0,"znear":0.1}}]"#,
    );
    let err = describe_err(&zero, None);
    assert!(err.contains("zero.glb") && err.contains("yfov"), "{err}");

    // A light of negative intensity, or brighter than a light may be: refused, not dropped.
    let lights = |name: &str, intensity: &str, count: usize| {
        let nodes: Vec<String> = (0..count)
            .map(|_| r#"{"extensions":{"KHR_lights_punctual":{"light":0}}}"#.to_owned())
            .collect();
        let rest = format!(
            r#""nodes":[{{"mesh":0}},{}],"extensionsUsed":["KHR_lights_punctual"],
               "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":{intensity}}}]}}}},{mesh}"#,
            nodes.join(",")
        );
        f.write_glb(&dir, name, &rest)
    };
    for (name, intensity) in [("negative", "-5"), ("blinding", "1e15")] {
        let err = describe_err(&lights(name, intensity, 1), None);
        assert!(
            err.contains(&format!("{name}.glb")) && err.contains("outside [0, 1e8]"),
            "{err}"
        );
    }
    // 1024 lights are read; one more, and the file is refused before any render.
    assert_eq!(
        describe(&lights("many_lights", "1", 1024), &view())
            .lights
            .len(),
        1024
    );
    let err = describe_err(&lights("too_many_lights", "1", 1025), None);
    assert!(err.contains("more than 1024 punctual lights"), "{err}");

    // An emitter of radiance 1e9: over the range of a light's intensity.
    let bright = f.write_glb(
        &dir,
        "bright",
        r#""nodes":[{"mesh":0}],"materials":[{"emissiveFactor":[1,1,1],
            "extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":1e9}}}],
           "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#,
    );
    let err = caustic::io::gltf::load_gltf(&bright)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bright.glb") && err.contains("emitted radiance"),
        "{err}"
    );

    // 5000 emissive triangles (one accessor drawn 2500 times as two triangles): refused.
    let mut many = GltfFile::default();
    many.floats(
        "VEC3",
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0],
    );
    let idx: Vec<u32> = (0..2500).flat_map(|_| [0, 2, 1, 1, 2, 3]).collect();
    many.indices(5125, &idx);
    let path = many.write_glb(
        &dir,
        "many",
        r#""nodes":[{"mesh":0}],"materials":[{"emissiveFactor":[1,1,1]}],
           "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#,
    );
    let err = caustic::io::gltf::load_gltf(&path).unwrap_err().to_string();
    assert!(
        err.contains("many.glb") && err.contains("4096 emissive triangles"),
        "{err}"
    );
}

/// The Blender-exported scenes in `scenes/gltf/` (`tools/gltf_scenes`) render through the one
/// frame call at the default settings, photon maps and all, to finite images in which the
/// emissive panel or the punctual lights light something: the path `caustic render scene.glb`
/// takes. (Their agreement with Mitsuba 3 is `tools/validate`'s, in docs/validation.md.)
#[test]
fn blender_scenes_render_at_the_defaults() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gltf");
    for name in [
        "glass_of_water",
        "copper_bowl",
        "frosted_sphere",
        "textured_box",
        "spot_and_sun",
    ] {
        let path = dir.join(format!("{name}.glb"));
        let desc = describe(&path, &view());
        // Everything is read; the one stand-in is the textured box's nearest-filtered sampler,
        // looked up bilinearly.
        let unread = desc
            .warnings
            .iter()
            .filter(|w| !w.contains("nearest filtering: looked up bilinearly"));
        assert_eq!(unread.count(), 0, "{name}: {:?}", desc.warnings);
        let r = &desc.renders[0];
        let settings = caustic::integrator::Settings::default();
        let frame = caustic::frame::render_desc(
            &desc,
            r,
            0.1,
            None,
            &settings,
            &caustic::progress::NoProgress,
        )
        .unwrap();
        let film = &frame.film;
        let pixels: Vec<glam::Vec3A> = (0..film.height)
            .flat_map(|y| (0..film.width).map(move |x| film.get(x, y)))
            .collect();
        assert!(
            pixels.iter().all(|p| p.is_finite()),
            "{name}: a non-finite pixel"
        );
        let lit = pixels.iter().filter(|p| p.max_element() > 0.02).count();
        assert!(
            lit > pixels.len() / 2,
            "{name}: {lit} of {} pixels lit",
            pixels.len()
        );
    }
}

/// The Khronos sample models that carry their buffers inline (`scenes/gltf/khronos/`, the
/// `glTF-Embedded` variants) render as whole scenes at the defaults without error and without
/// NaN, and `caustic info`'s one remark on each is the point light at the camera that stands in
/// for the light neither has. Box.gltf (COLLADA2GLTF's, a Y-up root matrix, the glTF default
/// metal of base colour (0.8, 0, 0)) is framed from +Z, fills the middle of the image and
/// shows red only. BoxTextured.gltf (the same box with its base colour a PNG in a `data:` URI,
/// repeating six times along u, sampled with mipmapped minification, which a ray tracer's
/// pixel samples stand in for without remark) shows the texture: the middle of the image is
/// lit, and its logo and background differ by more than a factor of two in brightness.
#[test]
fn khronos_embedded_samples_render_without_nan() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gltf/khronos");
    for name in ["Box.gltf", "BoxTextured.gltf"] {
        let desc = describe(&dir.join(name), &view());
        assert_eq!(desc.warnings.len(), 1, "{name}: {:?}", desc.warnings);
        assert!(desc.warnings[0].contains("lit by a point light at the camera"));
        let settings = caustic::integrator::Settings::default();
        let frame = caustic::frame::render_desc(
            &desc,
            &desc.renders[0],
            0.1,
            None,
            &settings,
            &caustic::progress::NoProgress,
        )
        .unwrap();
        let film = &frame.film;
        let (w, h) = (film.width, film.height);
        let mut centre = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let p = film.get(x, y);
                assert!(p.is_finite(), "{name}: pixel ({x}, {y}) is {p}");
                if (x as f32 / w as f32 - 0.5).abs() < 0.1
                    && (y as f32 / h as f32 - 0.5).abs() < 0.1
                {
                    centre.push(p);
                }
            }
        }
        assert!(!centre.is_empty());
        if name == "Box.gltf" {
            for p in &centre {
                assert!(p.x > 0.0 && p.y == 0.0 && p.z == 0.0, "the box is {p}");
            }
        } else {
            let lum: Vec<f32> = centre.iter().map(|p| p.element_sum()).collect();
            let (lo, hi) = lum
                .iter()
                .fold((f32::MAX, 0.0f32), |(a, b), &l| (a.min(l), b.max(l)));
            assert!(lo > 0.0 && hi > 2.0 * lo, "{name}: brightness {lo} to {hi}");
        }
    }
}

/// A script cannot multiply a small emitter past the scene's bound by instancing it: 2048
/// placements of a two-triangle panel (4096 triangles) build, one more is an error naming
/// the node that placed it.
#[test]
fn instanced_emitters_are_bounded_over_the_scene() {
    let dir = out_dir("gltf-scene-instanced-emitters");
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0],
    );
    f.indices(5125, &[0, 1, 2, 0, 2, 3]);
    f.write_glb(
        &dir,
        "panel",
        r#""nodes":[{"mesh":0}],"materials":[{"emissiveFactor":[1,1,1]}],
           "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#,
    );
    let build = |copies: usize| {
        let script = format!(
            r#"
            panel = gr.mesh('panel', 'panel.glb')
            root = gr.node('root')
            for i = 1, {copies} do
                n = gr.node('copy' .. i); n:translate(i, 0, 0); n:add_child(panel); root:add_child(n)
            end
            gr.render(root, 'x.png', 4, 4, {{0, 5, 0}}, {{0, -1, 0}}, {{0, 0, -1}}, 50, {{0, 0, 0}},
                      {{gr.light({{0, 9, 0}}, {{1, 1, 1}}, {{1, 0, 0}})}})
        "#
        );
        let lights = std::rc::Rc::new(std::cell::Cell::new(0));
        let seen = std::rc::Rc::clone(&lights);
        caustic::lua::run_source(
            script.as_bytes(),
            "copies.lua",
            &dir,
            Box::new(move |desc, r| {
                seen.set(build_scene(desc, r)?.lights.len());
                Ok(())
            }),
        )
        .map(|_| lights.get())
    };
    // The script's light and one mesh light per placement.
    assert_eq!(build(2048).unwrap(), 2049);
    let err = build(2049).unwrap_err().to_string();
    assert!(
        err.contains("copies.lua") && err.contains("more than 4096 triangles"),
        "{err}"
    );
}
