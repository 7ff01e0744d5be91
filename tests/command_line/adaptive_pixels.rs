//! Adaptive pixels and the error map on the command line: `--noise-target`, `--max-spp` and
//! `--error-map` write what they say, print the estimate, and refuse what they cannot do with a
//! usage error naming the flag.

use crate::common::{caustic, out_dir, run_ok};

/// A floor under an area light behind a sphere: a soft shadow (noisy at 4 samples a pixel)
/// beside hard-lit floor, the sky above.
const SCENE: &str = "
    m = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    floor = gr.cube('floor'); floor:set_material(m); floor:scale(10, 1, 10); floor:translate(-5, -1, -8)
    ball = gr.nh_sphere('ball', {0, 0.6, -3}, 0.6); ball:set_material(m)
    root = gr.node('root'); root:add_child(floor); root:add_child(ball)
    gr.render(root, 'p.png', 48, 36, {0, 1.5, 2}, {0, -0.4, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
              {gr.area_light({-0.5, 3, -3.5}, {2, 2, 2}, {1, 0, 0}, nil, nil, {1, 0, 0}, {0, 0, 1})})
";

fn setup(name: &str) -> std::path::PathBuf {
    let dir = out_dir(name);
    std::fs::write(dir.join("p.lua"), SCENE).unwrap();
    dir
}

/// `--error-map` writes the map at the image's size (the PNG with its legend strip beneath),
/// and the render says the estimated relative RMSE; with `--noise-target` it also says how
/// the samples went, and the ray-count map shows more rays in the shadow than in the sky.
#[test]
fn error_maps_and_the_estimate_are_written() {
    let dir = setup("cli_error_map");
    let out = run_ok(caustic().current_dir(&dir).args([
        "render",
        "p.lua",
        "--gi",
        "off",
        "--error-map",
        "err.png",
        "-o",
        "plain.png",
    ]));
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("estimated relative RMSE 0."), "{said}");
    let png = image::open(dir.join("err.png")).unwrap();
    assert_eq!((png.width(), png.height()), (48, 36 + 56));
    let out = run_ok(caustic().current_dir(&dir).args([
        "render",
        "p.lua",
        "--gi",
        "off",
        "--noise-target",
        "0.05",
        "--max-spp",
        "64",
        "--error-map",
        "err.exr",
        "--aa-map",
        "rays.png",
        "-o",
        "adaptive.png",
    ]));
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("adaptive pixels to 0.05"), "{said}");
    assert!(said.contains("(4 to 64)"), "{said}");
    let exr = image::open(dir.join("err.exr")).unwrap().into_rgb32f();
    assert_eq!((exr.width(), exr.height()), (48, 36));
    assert!(
        exr.pixels()
            .all(|p| p.0.iter().all(|c| c.is_finite() && *c >= 0.0))
    );
    // The sky (top row) is a smooth gradient: next to no error and the fewest rays; the soft
    // shadow below, more of both.
    let sky_error = exr.get_pixel(24, 0).0[0];
    let most = exr.pixels().map(|p| p.0[0]).fold(0.0, f32::max);
    assert!(most > 10.0 * sky_error, "sky {sky_error}, most {most}");
    let rays = image::open(dir.join("rays.png")).unwrap().into_luma8();
    let sky = rays.get_pixel(24, 0).0[0];
    assert!(
        rays.pixels().any(|p| p.0[0] > sky),
        "no pixel took more rays than the sky"
    );
}

/// Each flag out of range or in a combination it cannot serve is a usage error naming it, and
/// so is a map written where the image or another map goes.
#[test]
fn bad_noise_flags_are_usage_errors() {
    let dir = setup("cli_noise_flags");
    for (args, says) in [
        (
            &["--noise-target", "0"][..],
            "--noise-target must be in (0, 10]",
        ),
        (
            &["--noise-target", "NaN"],
            "--noise-target must be in (0, 10]",
        ),
        (
            &["--noise-target", "0.1", "--spp", "1"],
            "--noise-target needs --spp 2",
        ),
        (
            &["--noise-target", "0.1", "--adaptive"],
            "cannot be combined with --adaptive",
        ),
        (
            &["--noise-target", "0.1", "--integrator", "progressive"],
            "cannot be combined with --integrator progressive",
        ),
        (
            &["--noise-target", "0.1", "--max-spp", "2"],
            "--max-spp must be in [--spp, 65536]",
        ),
        (
            &["--noise-target", "0.1", "--max-spp", "70000"],
            "--max-spp must be in",
        ),
        (&["--max-spp", "64"], "--max-spp bounds adaptive pixels"),
        (
            &["--error-map", "e.jpg"],
            "--error-map e.jpg: the map is written as .png or .exr",
        ),
        (
            &["--error-map", "e.png", "--spp", "1"],
            "--error-map: one sample a pixel",
        ),
        (
            &["--error-map", "./p.png"],
            "--error-map and the image would both be written to ./p.png",
        ),
        (
            &["--aa-map", "m.png", "--error-map", "m.png"],
            "--error-map and --aa-map would both be written to m.png",
        ),
        (
            &["--error-map", "e.png", "--adaptive"],
            "--error-map: --adaptive's corner rays",
        ),
        (
            &["--error-map", "e.png", "--integrator", "progressive"],
            "--error-map: the progressive integrator",
        ),
    ] {
        let out = caustic()
            .current_dir(&dir)
            .args(["render", "p.lua", "-q"])
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}
