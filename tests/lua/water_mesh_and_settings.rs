//! Meshes and settings a scene makes for itself: `gr.water_mesh` (a wave surface or a closed body
//! of water, generated once into a cache as glTF) and `gr.settings` (the scene's own defaults
//! for `caustic render`'s quality flags, under the command line's).

use crate::common::{caustic, out_dir, run_lua_in};
use caustic::desc::MeshSource;
use caustic::geometry::water::{WaveParams, close_volume, wave_mesh};
use std::path::{Path, PathBuf};

/// Returns the file the script's only mesh resolved to.
fn mesh_file(src: &str, dir: &Path) -> PathBuf {
    let desc = run_lua_in(src, dir).unwrap();
    match &desc.meshes[0].source {
        MeshSource::File { path, .. } => path.clone(),
        other => panic!("expected a file mesh, got {other:?}"),
    }
}

#[test]
fn water_mesh_writes_the_generator_output_once_per_parameter_set() {
    let dir = out_dir("water-mesh-cache");
    let src = "w = gr.water_mesh('w', {n = 33, seed = 3, size = 2, amplitude = 0.02, depth = 0.5})";
    let path = mesh_file(src, &dir);
    assert!(path.starts_with(dir.join(".cache")), "{}", path.display());
    // The file holds exactly the generator's closed volume, number for number.
    let p = WaveParams {
        n: 33,
        seed: 3,
        size: 2.0,
        amplitude: 0.02,
        ..WaveParams::default()
    };
    let mut expected = wave_mesh(&p);
    close_volume(&mut expected, &p, -0.5);
    let read = caustic::io::gltf::load_gltf(&path).unwrap();
    assert_eq!(read.positions, expected.positions);
    assert_eq!(read.triangles, expected.triangles);
    assert_eq!(read.normals, expected.normals);
    // A second run reuses the file (not rewritten), the same table names the same file, and
    // another table (here one more wave, or no depth) another file.
    let written = std::fs::metadata(&path).unwrap().modified().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    assert_eq!(mesh_file(src, &dir), path);
    assert_eq!(
        std::fs::metadata(&path).unwrap().modified().unwrap(),
        written
    );
    let other = mesh_file(&src.replace("seed = 3", "seed = 3, waves = 9"), &dir);
    let open = mesh_file(&src.replace(", depth = 0.5", ""), &dir);
    assert_ne!(other, path);
    assert_ne!(open, path);
    assert_eq!(
        caustic::io::gltf::load_gltf(&open).unwrap().triangles.len(),
        2 * 32 * 32,
        "without depth the surface stays open"
    );
    let files = std::fs::read_dir(dir.join(".cache")).unwrap().count();
    assert_eq!(files, 3, "one file per distinct table, no temporary left");
}

#[test]
fn water_mesh_rejects_bad_tables_naming_the_key() {
    let dir = out_dir("water-mesh-errors");
    let cases = [
        ("{n = 1}", "'n' must be a whole number in 2..=4097"),
        ("{n = 5000}", "'n' must be a whole number in 2..=4097"),
        ("{n = 2.5}", "'n' must be a whole number"),
        ("{size = -1}", "'size' must be in (0, 1e6]"),
        (
            "{sise = 2}",
            "unknown key 'sise' (the keys are n, seed, size",
        ),
        ("{seed = 'x'}", "'seed' must be a number, got string"),
        (
            "{amplitude = 0.2, depth = 0.1}",
            "'depth' (0.1) must exceed 'amplitude' (0.2)",
        ),
        ("{spread = 4}", "'spread' must be an angle in [0, pi]"),
        ("{n = 0/0}", "'n' must be finite"),
        ("7", "table expected, got number"),
    ];
    for (table, want) in cases {
        let src = format!("w = gr.water_mesh('w', {table})");
        let e = run_lua_in(&src, &dir).unwrap_err().to_string();
        assert!(
            e.starts_with("test.lua:1: bad argument #2 to 'water_mesh'") && e.contains(want),
            "{table}: {e}"
        );
    }
    assert!(!dir.join(".cache").exists(), "no file for a rejected table");
}

/// A small scene whose look depends on the settings `gr.settings` may set.
const SCENE: &str = "
white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
floor = gr.cube('floor'); floor:set_material(white); floor:scale(4, 0.1, 4); floor:translate(-2, -1.1, -2)
ball = gr.nh_sphere('ball', {0, -0.5, 0}, 0.5); ball:set_material(white)
root = gr.node('root'); root:add_child(floor); root:add_child(ball)
SETTINGS
gr.render(root, 'out.png', 24, 16, {0, 0.5, 3}, {0, -0.3, -1}, {0, 1, 0}, 50, {0, 0, 0},
          {gr.area_light({0, 1.5, 0}, {2, 2, 2}, {0, 0, 1}, 1, nil, {0.5, 0, 0}, {0, 0, 0.5})})
";

/// Renders [`SCENE`] with `settings` in place of `SETTINGS` and `flags`, returning the PNG bytes.
fn render(dir: &Path, name: &str, settings: &str, flags: &[&str]) -> Vec<u8> {
    let script = dir.join(format!("{name}.lua"));
    std::fs::write(&script, SCENE.replace("SETTINGS", settings)).unwrap();
    let png = dir.join(format!("{name}.png"));
    let out = caustic()
        .arg("render")
        .arg(&script)
        .args(["-q", "--photons", "2000", "--caustic-photons", "2000", "-o"])
        .arg(&png)
        .args(flags)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read(&png).unwrap()
}

#[test]
fn scene_settings_are_defaults_the_command_line_overrides() {
    let dir = out_dir("scene-settings");
    let by_flags = render(&dir, "flags", "", &["--spp", "1", "--gather-rays", "2"]);
    let by_scene = render(&dir, "scene", "gr.settings{spp = 1, gather_rays = 2}", &[]);
    assert_eq!(
        by_scene, by_flags,
        "the scene's settings act as the flags do"
    );
    // The command line wins over the scene, flag by flag.
    let plain = render(&dir, "plain", "", &["--gather-rays", "2"]);
    let overridden = render(
        &dir,
        "overridden",
        "gr.settings{spp = 1, gather_rays = 2}",
        &["--spp", "4"],
    );
    assert_eq!(
        overridden, plain,
        "--spp 4 on the command line beats spp = 1"
    );
    assert_ne!(
        by_flags, plain,
        "spp 1 and 4 differ, so the comparisons can fail"
    );
    // Switches: adaptive = true is --adaptive; false leaves it off.
    let adaptive = render(&dir, "adaptive", "gr.settings{adaptive = true}", &[]);
    assert_eq!(adaptive, render(&dir, "adaptive-flag", "", &["--adaptive"]));
    let off = render(&dir, "not-adaptive", "gr.settings{adaptive = false}", &[]);
    assert_eq!(off, render(&dir, "default", "", &[]));
    // Adaptive pixels: noise_target and max_spp are their flags (the soft shadow is noisy at
    // 4 samples, so the target changes the image).
    let noisy = render(
        &dir,
        "noise",
        "gr.settings{noise_target = 0.02, max_spp = 64}",
        &[],
    );
    let noisy_flags = &["--noise-target", "0.02", "--max-spp", "64"];
    assert_eq!(noisy, render(&dir, "noise-flag", "", noisy_flags));
    assert_ne!(noisy, off, "the target changed the image");
}

#[test]
fn bad_scene_settings_are_errors_naming_the_setting() {
    let dir = out_dir("scene-settings-errors");
    let cases = [
        (
            "gr.settings{sp = 1}",
            "test.lua:1: bad argument #1 to 'settings' (unknown setting 'sp' (the settings are spp, adaptive",
        ),
        ("gr.settings{threads = 2}", "unknown setting 'threads'"),
        (
            "gr.settings{adaptive = 1}",
            "'adaptive' is a switch: true or false, got number",
        ),
        (
            "gr.settings{spp = {}}",
            "'spp' must be a finite number or a string, got table",
        ),
        ("gr.settings(3)", "table expected, got number"),
    ];
    for (src, want) in cases {
        let e = run_lua_in(src, &dir).unwrap_err().to_string();
        assert!(e.contains(want), "{src}: {e}");
    }
    // A value the flag's own check refuses is reported at the gr.render line, naming the flag.
    let script = dir.join("bad.lua");
    std::fs::write(&script, SCENE.replace("SETTINGS", "gr.settings{spp = 0}")).unwrap();
    let out = caustic()
        .arg("render")
        .arg(&script)
        .args(["-q", "-o"])
        .arg(dir.join("bad.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("bad.lua:7: gr.settings: --spp must be in [1, 65536], got 0"),
        "{stderr}"
    );
}

/// `caustic info` prints the plan and budgets a render would use: under the scene's
/// `gr.settings` where it has them (it printed the defaults, 200000 and 2000000, for the final
/// scene that asks for 400000 and 4000000).
#[test]
fn info_prints_the_plan_under_the_scenes_settings() {
    let dir = out_dir("scene-settings-info");
    let info = |settings: &str| {
        let script = dir.join("info.lua");
        std::fs::write(&script, SCENE.replace("SETTINGS", settings)).unwrap();
        let out = caustic().arg("info").arg(&script).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let own = info("gr.settings{photons = 1234, caustic_photons = 5678, gi = 'on'}");
    assert!(
        own.contains("plan of render 1 (the scene's gr.settings):"),
        "{own}"
    );
    assert!(own.contains("global photons: 1234"), "{own}");
    let plain = info("");
    assert!(
        plain.contains("plan of render 1 (default settings):"),
        "{plain}"
    );
    assert!(plain.contains("global photons: 200000"), "{plain}");
    let off = info("gr.settings{gi = 'off'}");
    assert!(off.contains("photon-maps: off"), "{off}");
}
