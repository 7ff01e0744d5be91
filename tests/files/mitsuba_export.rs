//! `caustic export-mitsuba`: the validation scenes export, the lighting model maps to Mitsuba's
//! units, and everything outside the shared subset is refused with the object and line at fault.

use crate::common;

use crate::common::{caustic, out_dir};
use std::path::Path;

fn export(dir: &Path, src: &str) -> std::process::Output {
    std::fs::write(dir.join("s.lua"), src).unwrap();
    caustic()
        .current_dir(dir)
        .args(["export-mitsuba", "s.lua", "-o", "s.xml"])
        .output()
        .unwrap()
}

const BOX: &str = "white = gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0)
    root = gr.node('root')
    b = gr.cube('b'); b:scale(2, 2, 2); b:translate(-1, -1, -1); b:set_material(white); root:add_child(b)
";

fn render_line(lights: &str) -> String {
    format!(
        "gr.render(root, 'x.png', 8, 8, {{0,0,0.5}}, {{0,0,-1}}, {{0,1,0}}, 60, {{0,0,0}}, {lights})"
    )
}

#[test]
fn every_validation_scene_exports() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = out_dir("export-validation");
    let mut n = 0;
    for entry in std::fs::read_dir(root.join("scenes/validate")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "lua") {
            continue;
        }
        let xml = dir.join(path.file_stem().unwrap()).with_extension("xml");
        common::run_ok(
            caustic()
                .current_dir(root)
                .arg("export-mitsuba")
                .arg(&path)
                .arg("-o")
                .arg(&xml),
        );
        let text = std::fs::read_to_string(&xml).unwrap();
        assert!(
            text.contains("<emitter type=\"area\">") && text.contains("twosided"),
            "{text}"
        );
        n += 1;
    }
    assert!(n >= 5, "scenes/validate has {n} scenes");
}

#[test]
fn lights_map_to_mitsuba_units() {
    let dir = out_dir("export-units");
    // rgb 1 over a 0.5 × 0.5 light: radiance π / 0.25; a point light: intensity π.
    let src = format!(
        "{BOX}{}",
        render_line(
            "{gr.area_light({0,0.9,0}, {1,1,1}, {0,0,1}, nil, nil, {0.5,0,0}, {0,0,0.5}), gr.light({0,0,0}, {1,2,3}, {0,0,1})}"
        )
    );
    let out = export(&dir, &src);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let xml = std::fs::read_to_string(dir.join("s.xml")).unwrap();
    let pi = std::f32::consts::PI;
    assert!(
        xml.contains(&format!(
            "value=\"{}, {}, {}\"",
            pi / 0.25,
            pi / 0.25,
            pi / 0.25
        )),
        "{xml}"
    );
    assert!(
        xml.contains(&format!("value=\"{}, {}, {}\"", pi, 2.0 * pi, 3.0 * pi)),
        "{xml}"
    );
}

/// A spot exports as Mitsuba's `spot` of intensity `π·rgb` aimed along its axis, its outer
/// angle the `cutoff_angle` and its inner the `beam_width` (whose falloff between differs from
/// glTF's, `src/scene/mitsuba.rs`), and a sun as a `directional` emitter of irradiance `π·rgb`
/// along its direction of travel.
#[test]
fn spot_and_directional_lights_map_to_mitsuba_emitters() {
    let dir = out_dir("export-spot-sun");
    let src = format!(
        "{BOX}{}",
        render_line(
            "{gr.spot_light({0, 0.9, 0}, {0, -2, 0}, {1, 2, 3}, 15, 20), gr.directional_light({0, 0, -3}, {0.5, 0.5, 0.5})}"
        )
    );
    let out = export(&dir, &src);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let xml = std::fs::read_to_string(dir.join("s.xml")).unwrap();
    let pi = std::f32::consts::PI;
    let spot = xml
        .lines()
        .find(|l| l.contains("<emitter type=\"spot\">"))
        .unwrap_or_else(|| panic!("no spot in {xml}"));
    for want in [
        "<lookat origin=\"0, 0.9, 0\" target=\"0, -0.100000024, 0\"".to_owned(),
        format!(
            "<rgb name=\"intensity\" value=\"{}, {}, {}\"/>",
            pi,
            2.0 * pi,
            3.0 * pi
        ),
        format!(
            "<float name=\"cutoff_angle\" value=\"{}\"/>",
            20f32.to_radians().to_degrees()
        ),
        format!(
            "<float name=\"beam_width\" value=\"{}\"/>",
            15f32.to_radians().to_degrees()
        ),
    ] {
        assert!(spot.contains(&want), "{want} not in {spot}");
    }
    let sun = format!(
        "<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -1\"/>\
         <rgb name=\"irradiance\" value=\"{0}, {0}, {0}\"/></emitter>",
        0.5 * pi
    );
    assert!(xml.contains(&sun), "{sun} not in {xml}");
}

#[test]
fn anything_outside_the_subset_is_refused_with_its_line() {
    let dir = out_dir("export-refused");
    let light = "{gr.light({0,0,0}, {1,1,1}, {0,0,1})}";
    for (body, line, what) in [
        (
            "c = gr.cylinder('c'); c:set_material(white); root:add_child(c)\n",
            4,
            "cylinder",
        ),
        (
            "p = gr.material({1,1,1}, {0.5,0.5,0.5}, 20)\nq = gr.sphere('q'); q:set_material(p); root:add_child(q)\n",
            4,
            "Phong",
        ),
        (
            "h = gr.material({1,1,1}, {0,0,0}, 0, 0.5, 1.5)\nq = gr.sphere('q'); q:set_material(h); root:add_child(q)\n",
            4,
            "partly transparent",
        ),
        (
            "e = gr.sphere('e'); e:scale(1, 2, 1); e:set_material(white); root:add_child(e)\n",
            4,
            "non-uniformly scaled",
        ),
    ] {
        let out = export(&dir, &format!("{BOX}{body}{}", render_line(light)));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(&format!("s.lua:{line}:")) && err.contains(what),
            "{body}: {err}"
        );
    }
    let out = export(
        &dir,
        &format!(
            "{BOX}{}",
            render_line("{gr.light({0,0,0}, {1,1,1}, {1,0,0})}")
        ),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("falloff"), "{err}");
}

/// Media export (issue 35): an absorbing dielectric becomes a `homogeneous` medium of
/// `sigma_t = −ln(colour)/distance` (written over its largest channel, at that `scale`, since
/// Mitsuba reads RGB `sigma_t` as a reflectance) that is the solid's `interior`, the `exterior`
/// of a bubble in it and the sensor's medium when the eye is in it, under `volpath`; the bubble's
/// relative index 0.75 becomes the absolute `int_ior` 0.75·1.33 against `ext_ior` 1.33.
#[test]
fn absorbing_media_and_relative_indices_export() {
    let dir = out_dir("export-media");
    let out = export(
        &dir,
        &format!(
            "water = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.33)
    gr.absorption(water, {{0.5, 0.25, 1}}, 2)
    air = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 0.75)
    root = gr.node('root')
    w = gr.cube('w'); w:scale(4, 4, 4); w:translate(-2, -2, -2); w:set_material(water); root:add_child(w)
    b = gr.sphere('b'); b:scale(0.2, 0.2, 0.2); b:translate(0, 0, -1); b:set_material(air); root:add_child(b)
    {}",
            render_line("{gr.area_light({0, 1.9, 0}, {1, 1, 1}, {0, 0, 1}, nil, nil, {0.5, 0, 0}, {0, 0, 0.5})}")
        ),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("s.xml")).unwrap();
    let sigma = [0.5f32.ln() / -2.0, 0.25f32.ln() / -2.0, 0.0];
    let scale = sigma[1];
    let medium = format!(
        "<medium type=\"homogeneous\" id=\"medium0\"><rgb name=\"sigma_t\" value=\"{}, 1, 0\"/><float name=\"scale\" value=\"{scale}\"/>",
        sigma[0] / scale
    );
    for want in [
        "<integrator type=\"volpath\">",
        medium.as_str(),
        "<ref id=\"medium0\"/></sensor>",
        "<ref name=\"interior\" id=\"medium0\"/>",
        "<float name=\"int_ior\" value=\"0.99750006\"/><float name=\"ext_ior\" value=\"1.33\"/></bsdf><ref name=\"exterior\" id=\"medium0\"/>",
    ] {
        assert!(text.contains(want), "missing {want} in:\n{text}");
    }
}

/// A rough mirror exports as Mitsuba's `roughconductor` with GGX of `alpha = roughness²`, and
/// rough glass as `roughdielectric`.
#[test]
fn rough_mirrors_export_as_rough_conductors() {
    let dir = out_dir("export-rough");
    let out = export(
        &dir,
        &format!(
            "metal = gr.material({{0, 0, 0}}, {{0.9, 0.6, 0.5}}, 0)
    gr.roughness(metal, 0.5)
    root = gr.node('root')
    b = gr.sphere('b'); b:set_material(metal); root:add_child(b)
    glass = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)
    gr.roughness(glass, 0.3)
    g = gr.sphere('g'); g:scale(0.5, 0.5, 0.5); g:translate(0, 0, -3); g:set_material(glass); root:add_child(g)
    {}",
            render_line(
                "{gr.area_light({0, 1.9, 0}, {1, 1, 1}, {0, 0, 1}, nil, nil, {0.5, 0, 0}, {0, 0, 0.5})}"
            )
        ),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("s.xml")).unwrap();
    let want = "<bsdf type=\"roughconductor\"><string name=\"material\" value=\"none\"/><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.25\"/><rgb name=\"specular_reflectance\" value=\"0.9, 0.6, 0.5\"/>";
    assert!(text.contains(want), "missing {want} in:\n{text}");
    let alpha = 0.3f32 * 0.3;
    let glass = format!(
        "<bsdf type=\"roughdielectric\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"{alpha}\"/><float name=\"int_ior\" value=\"1.5\"/><float name=\"ext_ior\" value=\"1\"/>"
    );
    assert!(text.contains(&glass), "missing {glass} in:\n{text}");
}
