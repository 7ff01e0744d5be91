//! The effect plan (issue 14): decided from the scene and the settings before any pass runs, as
//! typed decisions the passes read, overruled by --force and --disable, printed by `info`.

use crate::common;

use crate::common::caustic;
use caustic::integrator::photon_map::{GiSettings, Indirect};
use caustic::integrator::plan::{Decision, Effect, Overrides, Why, plan_with};
use caustic::integrator::{GiMode, Integrator, Settings};
use caustic::scene::Scene;
use caustic::scene::build::build_scene;
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
    let mut glass = scene("scenes/validate/cornell_glass.lua");
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
    let mut render = |s: &Settings| {
        let w = caustic::film::Window::full(12, 12);
        crate::common::render_frame(&mut glass, &camera, w, s, &caustic::progress::NoProgress)
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

/// A photon-mapped scene without refraction, textures, normal maps, noise or area lights: a
/// mirror ball against a red wall on a white floor under a point light.
const PLAIN: &str = "white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    red = gr.material({0.7, 0.2, 0.2}, {0, 0, 0}, 0)
    mirror = gr.material({0, 0, 0}, {0.9, 0.9, 0.9}, 0)
    root = gr.node('root')
    f = gr.cube('floor'); f:set_material(white); f:scale(4, 0.1, 4); f:translate(-2, -1.1, -2); root:add_child(f)
    w = gr.cube('wall'); w:set_material(red); w:scale(4, 4, 0.1); w:translate(-2, -1, -2); root:add_child(w)
    b = gr.nh_sphere('ball', {0, -0.5, -0.5}, 0.5); b:set_material(mirror); root:add_child(b)
    gr.render(root, 'x.png', 16, 16, {0, 0, 3}, {0, -0.2, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
              {gr.light({0, 1.5, 1}, {1, 1, 1}, {1, 0, 0}, nil, 3000)})";

/// A scene with every effect: a glass ball, a textured and normal-mapped floor, a noisy red
/// wall, under an area light.
fn rich() -> String {
    let tex = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures");
    let t = |name: &str| format!("'{}'", tex.join(name).display());
    format!(
        "floor = gr.material({{0.7, 0.7, 0.7}}, {{0, 0, 0}}, 0, 0, 1, 0, {}, {})
        red = gr.material({{0.7, 0.2, 0.2}}, {{0, 0, 0}}, 0, 0, 1, 2)
        glass = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)
        root = gr.node('root')
        f = gr.cube('floor'); f:set_material(floor); f:scale(4, 0.1, 4); f:translate(-2, -1.1, -2); root:add_child(f)
        w = gr.cube('wall'); w:set_material(red); w:scale(4, 4, 0.1); w:translate(-2, -1, -2); root:add_child(w)
        b = gr.nh_sphere('ball', {{0, -0.5, -0.5}}, 0.5); b:set_material(glass); root:add_child(b)
        light = gr.area_light({{0, 1.5, 0}}, {{1, 1, 1}}, {{1, 0, 0}}, 1, 3000, {{0.6, 0, 0}}, {{0, 0, 0.6}})
        gr.render(root, 'x.png', 16, 16, {{0, 0, 3}}, {{0, -0.2, -1}}, {{0, 1, 0}}, 50, {{0.1, 0.1, 0.1}},
                  {{light}})",
        t("tiles_red.png"),
        t("tiles_norm.png")
    )
}

/// Renders the script `src` through the frame call with `overrides` (few photons, the same
/// seed every time); returns the pixels, the plan and the features the scene was shaded with.
fn render_src(
    src: &str,
    overrides: Overrides,
) -> (
    Vec<glam::Vec3A>,
    caustic::integrator::Plan,
    caustic::scene::Features,
) {
    let d = common::run_lua(src).unwrap();
    let settings = Settings {
        overrides,
        photons: GiSettings {
            photons: 3000,
            caustic_photons: 3000,
            follow_image: false,
            ..GiSettings::default()
        },
        ..Settings::default()
    };
    let f = caustic::frame::render_desc(
        &d,
        &d.renders[0],
        1.0,
        None,
        &settings,
        &caustic::progress::NoProgress,
    )
    .unwrap();
    (f.film.pixels, f.stats.plan, f.scene.features)
}

fn forcing(e: Effect) -> Overrides {
    Overrides {
        force: vec![e],
        ..Overrides::default()
    }
}

fn disabling(e: Effect) -> Overrides {
    Overrides {
        disable: vec![e],
        ..Overrides::default()
    }
}

/// What the plan skips was not needed: on a scene without refraction, soft shadows, textures,
/// normal maps or noise, the plan leaves each out (the hits are shaded by the kernel compiled
/// without it), and the image equals, bit for bit with the same seed, the render with that
/// effect forced on (the general kernel). Caustics likewise on a box with no specular surface.
#[test]
fn a_ruled_out_effect_forced_on_changes_no_pixel() {
    let (auto, plan, features) = render_src(PLAIN, Overrides::default());
    assert_eq!(plan.integrator, Integrator::PhotonMap);
    assert_eq!(
        (features.textures, features.normal_maps, features.noise),
        (false, false, false),
        "the specialised kernel shades the plain scene"
    );
    assert!(!features.refraction && !features.soft_shadows);
    assert!(auto.iter().any(|p| p.max_element() > 0.01), "a lit image");
    for e in [
        Effect::Refraction,
        Effect::SoftShadows,
        Effect::Textures,
        Effect::NormalMaps,
        Effect::Noise,
    ] {
        let d = plan.decision(e).unwrap();
        assert!(!d.on, "{d}");
        let (forced, fplan, ffeatures) = render_src(PLAIN, forcing(e));
        let fd = fplan.decision(e).unwrap();
        assert!(fd.on && matches!(fd.why, Why::ForcedInVain(_)), "{fd}");
        assert_ne!(
            features,
            ffeatures,
            "forcing {} changes the kernel",
            e.name()
        );
        assert!(auto == forced, "forcing {} on changed the image", e.name());
    }
    let box_src = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/validate/cornell_diffuse.lua"),
    )
    .unwrap()
    .replace(
        "dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\\\])') or '') .. 'lib/box.lua')",
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/validate/lib/box.lua"),
        )
        .unwrap(),
    );
    let (auto, plan, _) = render_src(&box_src, Overrides::default());
    assert!(!plan.caustics, "{:?}", plan.decision(Effect::Caustics));
    let (forced, fplan, _) = render_src(&box_src, forcing(Effect::Caustics));
    assert!(fplan.caustics);
    assert!(auto == forced, "an empty caustic map changed the image");
}

/// And what the plan keeps is needed: on a scene with each effect, the plan includes it, and
/// disabling it changes the image.
#[test]
fn an_effect_the_scene_has_is_planned_and_disabling_it_changes_the_image() {
    let src = rich();
    let (auto, plan, features) = render_src(&src, Overrides::default());
    assert_eq!(
        features,
        caustic::scene::Features {
            specular_depth: features.specular_depth,
            ..caustic::scene::Features::GENERAL
        }
    );
    for e in [
        Effect::Caustics,
        Effect::Refraction,
        Effect::SoftShadows,
        Effect::Textures,
        Effect::NormalMaps,
        Effect::Noise,
        Effect::FinalGathering,
    ] {
        let d = plan.decision(e).unwrap();
        assert!(
            d.on && !matches!(d.why, Why::Forced | Why::ForcedInVain(_)),
            "{d}"
        );
        let (off, oplan, _) = render_src(&src, disabling(e));
        assert_eq!(oplan.decision(e).unwrap().why, Why::Disabled);
        let changed = auto.iter().zip(&off).filter(|(a, b)| a != b).count();
        println!(
            "--disable {}: {changed} of {} pixels change",
            e.name(),
            auto.len()
        );
        assert!(changed > 0, "disabling {} changed nothing", e.name());
    }
}

/// Global illumination asked off (`--gi off` on a photon-mapped scene) rules out the caustic map
/// and final gathering: forced on, each says it does nothing, and no pixel changes.
#[test]
fn effects_of_global_illumination_asked_off_change_nothing_when_forced() {
    let off = |mut o: Overrides| {
        o.disable.push(Effect::PhotonMaps);
        o
    };
    let (auto, plan, _) = render_src(PLAIN, off(Overrides::default()));
    assert_eq!(plan.integrator, Integrator::Whitted);
    for e in [Effect::Caustics, Effect::FinalGathering] {
        let (forced, fplan, _) = render_src(PLAIN, off(forcing(e)));
        assert!(
            matches!(fplan.decision(e).unwrap().why, Why::ForcedInVain(_)),
            "{:?}",
            fplan.decision(e)
        );
        assert!(auto == forced, "forcing {} changed the image", e.name());
    }
}

/// Whether a course scene gets global illumination is a choice of lighting model, not an
/// absence: an A4 scene (no power or num_photons) is planned without photon maps, and forcing
/// them on replaces its ambient term with photon-mapped light, so the image changes.
#[test]
fn global_illumination_on_an_a4_scene_is_a_lighting_model() {
    let a4 = PLAIN.replace("nil, 3000", "");
    let a4 = a4.replace("{1, 0, 0}, )", "{1, 0, 0})");
    let (ambient, plan, _) = render_src(&a4, Overrides::default());
    assert_eq!(
        plan.decision(Effect::PhotonMaps).unwrap().why,
        Why::NoLightAsks
    );
    let (photons, fplan, _) = render_src(&a4, forcing(Effect::PhotonMaps));
    assert_eq!(fplan.integrator, Integrator::PhotonMap);
    assert!(ambient != photons);
}

/// The specular depth follows the scene: none without a specular surface, the default for one
/// glass ball, and two crossings per layer (plus two) for eight nested glass shells.
#[test]
fn the_specular_depth_follows_nested_dielectrics() {
    use caustic::integrator::plan::DepthWhy;
    let none = Overrides::default();
    let diffuse = plan_with(
        &scene("scenes/validate/cornell_diffuse.lua"),
        GiMode::Auto,
        &none,
        true,
    );
    assert_eq!(
        (diffuse.features.specular_depth, diffuse.depth_why),
        (0, DepthWhy::NoSpecular)
    );
    let glass = plan_with(
        &scene("scenes/validate/cornell_glass.lua"),
        GiMode::Auto,
        &none,
        true,
    );
    assert_eq!(
        (glass.features.specular_depth, glass.depth_why),
        (12, DepthWhy::Default(1))
    );
    let mut src = String::from(
        "glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
         root = gr.node('root')\n",
    );
    for k in 0..8 {
        src += &format!(
            "s{k} = gr.nh_sphere('s{k}', {{0, 0, 0}}, {}); s{k}:set_material(glass); root:add_child(s{k})\n",
            1.0 - 0.1 * k as f32
        );
    }
    src += "gr.render(root, 'x.png', 4, 4, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},
              {gr.light({0, 3, 3}, {1, 1, 1}, {1, 0, 0})})";
    let d = common::run_lua(&src).unwrap();
    let shells = plan_with(
        &build_scene(&d, &d.renders[0]).unwrap(),
        GiMode::Auto,
        &none,
        true,
    );
    assert_eq!(
        (shells.features.specular_depth, shells.depth_why),
        (18, DepthWhy::Nested(8))
    );
    let p = plan_with(
        &build_scene(&d, &d.renders[0]).unwrap(),
        GiMode::On,
        &disabling(Effect::Refraction),
        true,
    );
    assert_eq!(
        p.features.specular_depth, 0,
        "opaque black shells: nothing specular"
    );
    assert_eq!(
        p.decision(Effect::Caustics).unwrap().why,
        Why::NoSpecular,
        "no caustic map for glass turned opaque"
    );
}

/// `--stats` prints the plan with the time of the phases each decision ran: the maps' trace
/// and build, the precomputation and cache, the shadow rays, the camera pass, and the global
/// photons' share that met a surface through the lamp's projection map (a point light over a
/// scene it sees in part of its directions). The times are whatever they were; the test reads
/// that each is there and that the counts add up.
#[test]
fn stats_print_the_plan_with_each_decisions_phase() {
    let dir = common::out_dir("plan-stats");
    std::fs::write(dir.join("scene.lua"), PLAIN).unwrap();
    let out = caustic()
        .current_dir(&dir)
        .args(["render", "scene.lua", "-q", "--stats", "--photons", "4000"])
        .args(["--caustic-photons", "4000", "-o", "x.png"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let line = |start: &str| {
        text.lines()
            .map(str::trim)
            .find(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no line '{start}' in:\n{text}"))
            .to_string()
    };
    let seconds = |l: &str, after: &str| -> f64 {
        let rest = &l[l.find(after).unwrap_or_else(|| panic!("{l}")) + after.len()..];
        rest.split_whitespace().next().unwrap().parse().unwrap()
    };
    let global = line("photon-maps: on (a light has power or num_photons)");
    let caustics = line("caustics: on (1 specular or refractive objects)");
    assert!(seconds(&global, "built in ") >= 0.0);
    assert!(seconds(&caustics, "built in ") >= 0.0);
    let gathering = line("final-gathering: on (--indirect gather)");
    assert!(
        gathering.contains("irradiance cache") && gathering.contains("gathers in the camera pass")
    );
    assert_eq!(
        line("soft-shadows: off"),
        "soft-shadows: off (point lights only)"
    );
    assert!(seconds(&line("camera pass: "), "camera pass: ") > 0.0);
    assert_eq!(
        line("specular depth: "),
        "specular depth: 12 (the default; 0 nested dielectric layers need at most 2)"
    );
    let photons = line("global photons: ");
    assert!(
        photons.contains("projection maps kept light 1"),
        "{photons}"
    );
    let met: f64 = photons["global photons: ".len()..]
        .split('%')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(met > 50.0 && met <= 100.0, "{photons}");
}
