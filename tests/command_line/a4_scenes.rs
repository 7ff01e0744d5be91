//! The standard A4 scenes of the course render, from their own folder and by path, at the size
//! their scripts ask for, and look like what they describe.

use crate::common;

use crate::common::{a4_assets, caustic, out_dir, run_ok};
use std::path::Path;

/// Every A4 scene, with the image size its `gr.render` call asks for.
const SCENES: [(&str, u32, u32); 7] = [
    ("simple", 256, 256),
    ("nonhier", 512, 512),
    ("nonhier2", 256, 256),
    ("hier", 256, 256),
    ("instance", 256, 256),
    ("simple-cows", 256, 256),
    ("macho-cows", 256, 256),
];

/// Checks a written image's size and that it shows more than a blank background.
fn check_image(path: &Path, w: u32, h: u32) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    assert_eq!((img.width(), img.height()), (w, h), "{}", path.display());
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 200,
        "{}: only {} distinct colours",
        path.display(),
        colours.len()
    );
}

#[test]
fn every_a4_scene_renders_from_its_own_folder() {
    if common::skip_without_corpus("every_a4_scene_renders_from_its_own_folder") {
        return;
    }
    let out = out_dir("a4-from-folder");
    for (name, w, h) in SCENES {
        let png = out.join(format!("{name}.png"));
        run_ok(
            caustic()
                .current_dir(a4_assets())
                .args(["render", &format!("{name}.lua"), "-o"])
                .arg(&png),
        );
        check_image(&png, w, h);
    }
}

#[test]
fn every_a4_scene_renders_by_path_from_the_repository_root() {
    if common::skip_without_corpus("every_a4_scene_renders_by_path_from_the_repository_root") {
        return;
    }
    let out = out_dir("a4-by-path");
    for (name, w, h) in SCENES {
        let png = out.join(format!("{name}.png"));
        let script = Path::new("../shared/corpus/cs488/shraacha__cs488/A4/Assets")
            .join(format!("{name}.lua"));
        run_ok(
            caustic()
                .current_dir(env!("CARGO_MANIFEST_DIR"))
                .arg("render")
                .arg(&script)
                .arg("-o")
                .arg(&png),
        );
        check_image(&png, w, h);
    }
}

#[test]
fn without_o_the_image_lands_in_the_working_directory_and_meshes_beside_the_script() {
    if common::skip_without_corpus(
        "without_o_the_image_lands_in_the_working_directory_and_meshes_beside_the_script",
    ) {
        return;
    }
    let out = out_dir("a4-default-output");
    let scenes = out.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    for f in ["nonhier.lua", "smstdodeca.obj"] {
        std::fs::copy(a4_assets().join(f), scenes.join(f)).unwrap();
    }
    run_ok(
        caustic()
            .current_dir(&out)
            .args(["render", "scenes/nonhier.lua"]),
    );
    check_image(&out.join("nonhier.png"), 512, 512);
    assert!(!scenes.join("nonhier.png").exists());
}

#[test]
fn scale_option_resizes_the_image() {
    if common::skip_without_corpus("scale_option_resizes_the_image") {
        return;
    }
    let out = out_dir("a4-scale");
    let png = out.join("n.png");
    run_ok(
        caustic()
            .current_dir(a4_assets())
            .args(["render", "nonhier.lua", "--scale", "0.25", "-o"])
            .arg(&png),
    );
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (128, 128));
}

#[test]
fn incompatible_dialect_fails_with_a_located_error() {
    if common::skip_without_corpus("incompatible_dialect_fails_with_a_located_error") {
        return;
    }
    let script = common::corpus("WeiqiangYu0528__cs488/A5/Assets/primitive.lua");
    let out = caustic()
        .arg("render")
        .arg(&script)
        .current_dir(out_dir("dialect"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("primitive.lua:1: bad argument #3 to 'material' (number expected, got table)"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn info_summarises_nodes_meshes_and_render_calls() {
    if common::skip_without_corpus("info_summarises_nodes_meshes_and_render_calls") {
        return;
    }
    let out = run_ok(
        caustic()
            .current_dir(a4_assets())
            .args(["info", "macho-cows.lua"]),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    // 3 cow instances of one 5,804-triangle mesh, plus the plane and the buckyball.
    assert!(
        text.contains("render 1 at macho-cows.lua:105: macho-cows.png 256x256"),
        "{text}"
    );
    assert!(
        text.contains("camera: eye (0, 2, 30) view (0, 0, -1) up (0, 1, 0) fov 50°"),
        "{text}"
    );
    assert!(text.contains("lights: 1"), "{text}");
    assert!(
        text.contains("placed: cube 12, mesh 5, sphere 6 (17530 triangles)"),
        "{text}"
    );
}

/// The output format follows the extension: `.png`, `.exr`, `.pfm` and `.hdr` (any case) are written, anything
/// else is refused before rendering with the path in the message, and nothing is written.
/// (`-o out.jpg` used to write PNG bytes under a JPEG name.)
#[test]
fn output_formats_follow_the_extension_and_unknown_ones_are_refused() {
    let dir = out_dir("output-formats");
    std::fs::write(
        dir.join("s.lua"),
        "s = gr.sphere('s'); s:set_material(gr.material({1,1,1}, {0,0,0}, 0))
         gr.render(s, 'x.png', 4, 4, {0,0,5}, {0,0,-1}, {0,1,0}, 50, {0,0,0}, {gr.light({0,0,5}, {1,1,1}, {1,0,0})})",
    )
    .unwrap();
    for name in ["out.jpg", "out.tif", "out"] {
        let out = caustic()
            .current_dir(&dir)
            .args(["render", "s.lua", "-q", "-o", name])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(name), "{name}: {err}");
        assert!(err.contains(".png, .exr, .pfm and .hdr"), "{name}: {err}");
        assert!(!dir.join(name).exists(), "{name} was written");
    }
    common::run_ok(
        caustic()
            .current_dir(&dir)
            .args(["render", "s.lua", "-q", "-o", "ok.EXR"]),
    );
    let exr = image::open(dir.join("ok.EXR")).unwrap();
    assert_eq!((exr.width(), exr.height()), (4, 4));
    common::run_ok(
        caustic()
            .current_dir(&dir)
            .args(["render", "s.lua", "-q", "-o", "ok.png"]),
    );
    let stitched = caustic()
        .current_dir(&dir)
        .args(["stitch", "ok.png", "-o", "all.tif"])
        .output()
        .unwrap();
    assert!(
        !stitched.status.success() && String::from_utf8_lossy(&stitched.stderr).contains("all.tif")
    );
}

/// Flags and script values that set sizes and counts are bounded, with a usage error or one
/// located at the script line, never an abort or a run that does not end: `--threads 100000`
/// started thousands of threads, `--photons 1e12` and `num_photons = 1e12` ran for ever or
/// aborted, and `--scale 16` on a 4096² image tried to allocate 64 GB.
#[test]
fn sizes_and_counts_are_bounded_with_clear_errors() {
    let dir = out_dir("bounded");
    let script = |size: u32, photons: &str| {
        format!(
            "s = gr.sphere('s'); s:set_material(gr.material({{1,1,1}}, {{0,0,0}}, 0))
             gr.render(s, 'x.png', {size}, {size}, {{0,0,5}}, {{0,0,-1}}, {{0,1,0}}, 50, {{0,0,0}},
                       {{gr.light({{0,0,5}}, {{1,1,1}}, {{1,0,0}}, 1, {photons})}})"
        )
    };
    let run = |src: &str, args: &[&str]| {
        std::fs::write(dir.join("s.lua"), src).unwrap();
        let out = caustic()
            .current_dir(&dir)
            .arg("render")
            .arg("s.lua")
            .arg("-q")
            .args(args)
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let small = script(4, "nil");
    for (args, want) in [
        (
            &["--threads", "100000"][..],
            "--threads must be in [1, 1024]",
        ),
        (
            &["--photons", "2000000000"][..],
            "--photons must be at most 1000000000",
        ),
        (
            &["--photon-scale", "1000", "--photons", "10000000"][..],
            "s.lua:3:",
        ),
    ] {
        let (ok, err) = run(&small, args);
        assert!(!ok && err.contains(want), "{args:?}: {err}");
    }
    let (ok, err) = run(&script(4, "1e12"), &[]);
    assert!(
        !ok && err.contains("s.lua:3:") && err.contains("photon count"),
        "{err}"
    );
    let (ok, err) = run(&script(4096, "nil"), &["--scale", "16"]);
    assert!(
        !ok && err.contains("s.lua:2:") && err.contains("65536x65536"),
        "{err}"
    );
}
