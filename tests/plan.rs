//! The effect plan (issue 14): decided from the scene and the settings before any pass runs, as
//! typed decisions the passes read, overruled by --force and --disable, printed by `info`.

mod common;

use caustic::integrator::photon_map::{GiSettings, Indirect};
use caustic::integrator::plan::{Decision, Effect, Overrides, Why, plan_with};
use caustic::integrator::{GiMode, Integrator, Settings};
use caustic::scene::Scene;
use caustic::scene::build::build_scene;
use common::caustic;
use std::path::Path;

fn desc(path: &str) -> caustic::desc::SceneDesc {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    caustic::lua::run_script(&path, Box::new(|_: &_, _: &_| Ok(()))).unwrap()
}

/// A course A4 scene: a mirror ball and a floor under a point light, no power or num_photons.
fn a4() -> Scene {
    let d = common::run_lua(
        "m = gr.material({0.7, 0.7, 0.7}, {0.5, 0.5, 0.5}, 25)
         mirror = gr.material({0, 0, 0}, {0.9, 0.9, 0.9}, 0)
         root = gr.node('root')
         f = gr.cube('f'); f:set_material(m); f:scale(4, 0.1, 4); f:translate(-2, -1, -2); root:add_child(f)
         b = gr.nh_sphere('b', {0, 0, 0}, 0.5); b:set_material(mirror); root:add_child(b)
         gr.render(root, 'x.png', 8, 8, {0, 0, 4}, {0, 0, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
                   {gr.light({2, 3, 3}, {1, 1, 1}, {1, 0, 0})})",
    )
    .unwrap();
    build_scene(&d, &d.renders[0]).unwrap()
}

fn scene(path: &str) -> Scene {
    let d = desc(path);
    build_scene(&d, &d.renders[0]).unwrap()
}

fn decision(p: &caustic::integrator::Plan, e: Effect) -> Decision {
    p.decisions.iter().find(|d| d.effect == e).unwrap().clone()
}

/// Each effect is on exactly when the scene calls for it, with the typed reason: a glass ball
/// under an area light with power asks for all four; a diffuse box needs no caustic map; the
/// course's A4 scenes (no power, point lights) need none of them.
#[test]
fn the_plan_follows_the_scene() {
    let none = Overrides::default();
    let glass = plan_with(
        &scene("scenes/validate/cornell_glass.lua"),
        GiMode::Auto,
        &none,
        true,
    );
    assert_eq!(glass.integrator, Integrator::PhotonMap);
    assert_eq!(decision(&glass, Effect::PhotonMaps).why, Why::LightAsks);
    assert_eq!(decision(&glass, Effect::Caustics).why, Why::Specular(1));
    assert_eq!(decision(&glass, Effect::FinalGathering).why, Why::Gather);
    assert_eq!(
        decision(&glass, Effect::SoftShadows).why,
        Why::AreaLights(1)
    );
    assert!(glass.caustics && glass.final_gathering);
    let diffuse = plan_with(
        &scene("scenes/validate/cornell_diffuse.lua"),
        GiMode::Auto,
        &none,
        true,
    );
    assert_eq!(decision(&diffuse, Effect::Caustics).why, Why::NoSpecular);
    assert!(!diffuse.caustics);
    let a4 = plan_with(&a4(), GiMode::Auto, &none, true);
    assert_eq!(a4.integrator, Integrator::Whitted);
    assert_eq!(decision(&a4, Effect::PhotonMaps).why, Why::NoLightAsks);
    assert_eq!(decision(&a4, Effect::Caustics).why, Why::NoPhotonMaps);
    assert_eq!(decision(&a4, Effect::SoftShadows).why, Why::PointLightsOnly);
    let direct = plan_with(
        &scene("scenes/validate/cornell_glass.lua"),
        GiMode::Auto,
        &none,
        false,
    );
    assert_eq!(
        decision(&direct, Effect::FinalGathering).why,
        Why::DirectVisualisation
    );
}

/// --disable turns an effect off whatever the scene; --force turns it on, and a forced effect the
/// scene cannot have says why it does nothing instead of pretending.
#[test]
fn overrides_overrule_the_plan() {
    let glass = scene("scenes/validate/cornell_glass.lua");
    let off = Overrides {
        disable: vec![Effect::Caustics, Effect::FinalGathering],
        ..Overrides::default()
    };
    let p = plan_with(&glass, GiMode::Auto, &off, true);
    assert!(!p.caustics && !p.final_gathering);
    assert_eq!(decision(&p, Effect::Caustics).why, Why::Disabled);
    let on = Overrides {
        force: vec![Effect::Caustics],
        ..Overrides::default()
    };
    let p = plan_with(
        &scene("scenes/validate/cornell_diffuse.lua"),
        GiMode::Auto,
        &on,
        true,
    );
    assert!(matches!(
        decision(&p, Effect::Caustics).why,
        Why::ForcedInVain(_)
    ));
    let p = plan_with(&a4(), GiMode::Auto, &on, true);
    assert!(!p.caustics, "no caustic map without photon maps");
    assert!(matches!(
        decision(&p, Effect::Caustics).why,
        Why::ForcedInVain(_)
    ));
}

/// The passes read the plan: with caustics disabled no caustic photon is traced, and with final
/// gathering disabled the frame is the global map seen directly, bit for bit.
#[test]
fn the_passes_follow_the_plan() {
    let glass = scene("scenes/validate/cornell_glass.lua");
    let d = desc("scenes/validate/cornell_glass.lua");
    let camera = caustic::camera::Camera::new(&d.renders[0].camera, 12, 12);
    let base = Settings {
        photons: GiSettings {
            photons: 2000,
            caustic_photons: 2000,
            ..GiSettings::default()
        },
        ..Settings::default()
    };
    let render = |s: &Settings| {
        let w = caustic::film::Window::full(12, 12);
        caustic::frame::render(&glass, &camera, w, s, &caustic::progress::NoProgress)
    };
    let disabled = Settings {
        overrides: Overrides {
            disable: vec![Effect::Caustics, Effect::FinalGathering],
            ..Overrides::default()
        },
        ..base.clone()
    };
    let (film, stats) = render(&disabled);
    let photons = stats.photons.unwrap();
    assert_eq!(photons.caustic.iter().map(|c| c.emitted).sum::<u64>(), 0);
    assert_eq!(
        photons.precomputed_points, 0,
        "no gathering, no precomputation"
    );
    let direct = Settings {
        overrides: Overrides {
            disable: vec![Effect::Caustics],
            ..Overrides::default()
        },
        photons: GiSettings {
            indirect: Indirect::Direct,
            ..base.photons.clone()
        },
        ..base.clone()
    };
    let (want, _) = render(&direct);
    assert_eq!(film.pixels, want.pixels);
}

/// `caustic info` prints each render's plan and photon budgets; an unknown effect is a usage
/// error naming the effects there are.
#[test]
fn info_prints_the_plan_and_bad_effects_are_named() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = caustic()
        .current_dir(root)
        .args(["info", "scenes/validate/glass_in_water.lua"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    for want in [
        "photon-maps: on (a light has power or num_photons)",
        "caustics: on (2 specular or refractive objects)",
        "final-gathering: on (--indirect gather)",
        "soft-shadows: on (1 area or sphere lights)",
        "caustic photons: 2000000",
    ] {
        assert!(text.contains(want), "missing '{want}' in:\n{text}");
    }
    let out = caustic()
        .current_dir(root)
        .args([
            "render",
            "scenes/validate/cornell_glass.lua",
            "--force",
            "glossy",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains(
            "unknown effect 'glossy'; the effects are photon-maps, caustics, final-gathering"
        ),
        "{err}"
    );
}
