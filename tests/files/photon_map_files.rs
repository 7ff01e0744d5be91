//! Photon maps as files (`caustic photons --save`, `caustic render --photon-maps`): a render
//! from a saved file, whole or in tiles, is the render that traces its own maps, byte for byte;
//! a file for another scene, other photon settings, a damaged or truncated file, and flags
//! that cannot use one are refused with an error naming the file or the flag.

use crate::common::{caustic, out_dir, run_ok};
use std::path::Path;

/// A glass ball on a floor under a point light: both maps, final gathering, a caustic.
const SCENE: &str = "
    white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    red = gr.material({0.7, 0.2, 0.2}, {0, 0, 0}, 0)
    glass = gr.material({0, 0, 0}, {0.1, 0.1, 0.1}, 50, 1.0, 1.5)
    root = gr.node('root')
    floor = gr.cube('floor'); floor:set_material(white); floor:scale(6, 0.5, 6); floor:translate(-3, -0.5, -5)
    root:add_child(floor)
    wall = gr.cube('wall'); wall:set_material(red); wall:scale(6, 4, 0.5); wall:translate(-3, 0, -5.5)
    root:add_child(wall)
    ball = gr.nh_sphere('ball', {0, 1, -2.5}, 1); ball:set_material(glass); root:add_child(ball)
    gr.render(root, 'ball.exr', 64, 48, {0, 2, 3}, {0, -0.3, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
              {gr.light({0, 5, -2}, {1, 1, 1}, {1, 0, 0}, nil, 20000)})
";

/// The flags every command below shares: small maps, few gather rays.
const FLAGS: [&str; 8] = [
    "--photons",
    "20000",
    "--caustic-photons",
    "40000",
    "--gather-rays",
    "8",
    "--spp",
    "1",
];

/// Writes the scene to `dir/ball.lua` and returns its path.
fn scene_in(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("ball.lua");
    std::fs::write(&path, SCENE).unwrap();
    path
}

/// Runs `caustic ARGS FLAGS` in `dir`, asserting success.
fn run(dir: &Path, args: &[&str]) -> std::process::Output {
    run_ok(caustic().current_dir(dir).args(args).args(FLAGS).arg("-q"))
}

/// Runs `caustic ARGS FLAGS` in `dir`, asserting failure; returns stderr.
fn fails(dir: &Path, args: &[&str]) -> String {
    let out = caustic()
        .current_dir(dir)
        .args(args)
        .args(FLAGS)
        .arg("-q")
        .output()
        .unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Renders `ball.lua` in `dir` from `maps.bin` to `out`, with `extra` flags, asserting success.
fn render_from_file(dir: &Path, out: &str, extra: &[&str]) {
    let mut args = vec!["render", "ball.lua", "--photon-maps", "maps.bin", "-o", out];
    args.extend_from_slice(extra);
    run(dir, &args);
}

#[test]
fn renders_from_a_saved_map_whole_and_in_tiles_equal_the_render_that_traces_them() {
    let dir = out_dir("photon-map-files");
    scene_in(&dir);
    run(&dir, &["render", "ball.lua", "-o", "traced.exr"]);
    let saved = run(&dir, &["photons", "ball.lua", "--save", "maps.bin"]);
    let said = String::from_utf8_lossy(&saved.stderr);
    assert!(said.contains("wrote maps.bin ("), "{said}");
    assert!(
        !said.contains(" 0 irradiance-cache records"),
        "no cache saved: {said}"
    );
    let read = run(
        &dir,
        &[
            "render",
            "ball.lua",
            "--photon-maps",
            "maps.bin",
            "-o",
            "read.exr",
            "--stats",
        ],
    );
    let stats = String::from_utf8_lossy(&read.stdout);
    assert!(
        stats.contains("photon maps: read from --photon-maps in ")
            && !stats.contains("irradiance cache: "),
        "the maps and the cache are read, not made: {stats}"
    );
    let traced = std::fs::read(dir.join("traced.exr")).unwrap();
    assert!(
        std::fs::read(dir.join("read.exr")).unwrap() == traced,
        "the render from the file differs from the render that traced its maps"
    );
    // Four tiles, each reading the same file, stitched.
    let tiles = ["0,0,64,12", "0,12,64,24", "0,24,64,36", "0,36,64,48"];
    let mut names = Vec::new();
    for (i, crop) in tiles.iter().enumerate() {
        let name = format!("tile{i}.exr");
        render_from_file(&dir, &name, &["--crop", crop]);
        names.push(name);
    }
    let mut stitch = caustic();
    stitch.current_dir(&dir).arg("stitch").args(&names);
    run_ok(stitch.args(["-o", "stitched.exr"]));
    assert!(
        std::fs::read(dir.join("stitched.exr")).unwrap() == traced,
        "the stitched tiles differ from the full render"
    );
}

#[test]
fn a_map_file_for_other_photons_another_scene_or_damaged_is_refused() {
    let dir = out_dir("photon-map-files-refused");
    let script = scene_in(&dir);
    run(&dir, &["photons", "ball.lua", "--save", "maps.bin"]);
    let read = |extra: &[&str]| {
        let mut args = vec!["render", "ball.lua", "-o", "x.exr"];
        args.extend_from_slice(extra);
        fails(&dir, &args)
    };
    // Other photon settings: the message shows both.
    for other in [
        &["--seed", "3"][..],
        &["--photon-scale", "0.5"],
        &["--cache-accuracy", "0.5"],
        &["--scale", "0.5"],
    ] {
        let mut extra = vec!["--photon-maps", "maps.bin"];
        extra.extend_from_slice(other);
        let e = read(&extra);
        assert!(
            e.contains("maps.bin: these photon maps were traced with other settings")
                && e.contains("saved: ")
                && e.contains("this render: "),
            "{other:?}: {e}"
        );
    }
    // The script edited (a comment changes the lines): another scene.
    std::fs::write(&script, format!("-- edited\n{SCENE}")).unwrap();
    let e = read(&["--photon-maps", "maps.bin"]);
    assert!(e.contains("traced for another scene"), "{e}");
    std::fs::write(&script, SCENE).unwrap();
    // One byte changed in the photons, a truncated file, another file, no file.
    let bytes = std::fs::read(dir.join("maps.bin")).unwrap();
    let mut damaged = bytes.clone();
    let at = bytes.len() / 2;
    damaged[at] ^= 0x10;
    std::fs::write(dir.join("damaged.bin"), &damaged).unwrap();
    std::fs::write(dir.join("short.bin"), &bytes[..bytes.len() - 1000]).unwrap();
    std::fs::write(dir.join("other.bin"), b"P6\n1 1\n255\n").unwrap();
    for (file, want) in [
        ("damaged.bin", "the checksum does not match"),
        ("short.bin", "the file ends inside the irradiance cache"),
        ("other.bin", "not a caustic photon-map file"),
        ("missing.bin", "missing.bin: No such file"),
    ] {
        let e = read(&["--photon-maps", file]);
        assert!(
            e.contains(&format!("{file}: ")) && e.contains(want),
            "{file}: {e}"
        );
    }
    // The undamaged file still reads.
    render_from_file(&dir, "ok.exr", &[]);
    // Flags that cannot use a file.
    let e = read(&[
        "--photon-maps",
        "maps.bin",
        "--integrator",
        "progressive",
        "--passes",
        "2",
    ]);
    assert!(
        e.contains("--photon-maps: this frame is rendered progressively"),
        "{e}"
    );
    let e = fails(&dir, &["photons", "ball.lua", "--photon-maps", "maps.bin"]);
    assert!(e.contains("does not read them"), "{e}");
    let e = read(&["--photon-maps", "maps.bin", "--gi", "off"]);
    assert!(
        e.contains("--photon-maps: this frame is rendered without photon maps"),
        "{e}"
    );
}

/// A photon pass split into parts (`caustic photons --part i/N`) and merged (`--merge`) writes
/// the file one `caustic photons --save` writes, byte for byte, whatever the number of parts
/// (one; three, given out of order; seven, more than the light's chunks of photons), and a
/// render from the merged file is the render that traces its own maps.
#[test]
fn a_pass_split_into_parts_merges_into_the_file_one_process_writes() {
    let dir = out_dir("photon-parts");
    let scene = scene_in(&dir);
    let scene = scene.to_str().unwrap();
    run(&dir, &["photons", scene, "--save", "whole.bin"]);
    let whole = std::fs::read(dir.join("whole.bin")).unwrap();
    for n in [1u32, 3, 7] {
        let mut names: Vec<String> = (0..n).map(|i| format!("part{i}of{n}.bin")).collect();
        for (i, name) in names.iter().enumerate() {
            let part = format!("{i}/{n}");
            run(&dir, &["photons", scene, "--part", &part, "--save", name]);
        }
        names.reverse();
        let mut args = vec!["photons", scene, "--merge"];
        args.extend(names.iter().map(String::as_str));
        args.extend(["--save", "merged.bin"]);
        run(&dir, &args);
        let merged = std::fs::read(dir.join("merged.bin")).unwrap();
        assert!(merged == whole, "{n} parts merge into another file");
    }
    run(&dir, &["render", scene, "-o", "traced.exr"]);
    let from = ["--photon-maps", "merged.bin", "-o", "merged.exr"];
    run(&dir, &[&["render", scene][..], &from].concat());
    let traced = std::fs::read(dir.join("traced.exr")).unwrap();
    assert!(std::fs::read(dir.join("merged.exr")).unwrap() == traced);
}

/// A merge refuses, naming the part file: a part missing, a part given twice, a part traced
/// with another seed, a part of another split, a maps file given as a part, and a part whose
/// photon was forged (its power made NaN); a part index out of range is a usage error.
#[test]
fn a_merge_of_parts_that_are_not_one_pass_is_refused() {
    let dir = out_dir("photon-parts-refused");
    let scene = scene_in(&dir);
    let scene = scene.to_str().unwrap();
    for i in 0..3 {
        let (part, name) = (format!("{i}/3"), format!("p{i}.bin"));
        run(&dir, &["photons", scene, "--part", &part, "--save", &name]);
    }
    let other = ["--seed", "5", "--part", "0/3", "--save", "seed5.bin"];
    run(&dir, &[&["photons", scene][..], &other].concat());
    run(
        &dir,
        &["photons", scene, "--part", "0/2", "--save", "half.bin"],
    );
    run(&dir, &["photons", scene, "--save", "whole.bin"]);
    // Four bytes in the middle of the photons made a NaN: a position, code word or power that
    // cannot be, found whichever field they fall in (the checksum fails only after it).
    let mut forged = std::fs::read(dir.join("p1.bin")).unwrap();
    let at = forged.len() / 2;
    forged[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.join("forged.bin"), forged).unwrap();
    let merge = |parts: &[&str]| {
        let mut args = vec!["photons", scene, "--merge"];
        args.extend(parts);
        args.extend(["--save", "out.bin"]);
        fails(&dir, &args)
    };
    let e = merge(&["p0.bin", "p1.bin"]);
    assert!(
        e.contains("p0.bin") && e.contains("2 parts were given"),
        "{e}"
    );
    let e = merge(&["p0.bin", "p1.bin", "p1.bin"]);
    assert!(e.contains("p1.bin") && e.contains("given twice"), "{e}");
    let e = merge(&["seed5.bin", "p1.bin", "p2.bin"]);
    assert!(
        e.contains("seed5.bin") && e.contains("other settings"),
        "{e}"
    );
    let e = merge(&["half.bin", "p1.bin", "p2.bin"]);
    assert!(e.contains("half.bin") && e.contains("part 0/2"), "{e}");
    let e = merge(&["whole.bin"]);
    assert!(
        e.contains("whole.bin") && e.contains("not a caustic photon-pass part"),
        "{e}"
    );
    let e = merge(&["p0.bin", "forged.bin", "p2.bin"]);
    assert!(e.contains("forged.bin"), "{e}");
    let e = fails(
        &dir,
        &["photons", scene, "--part", "3/3", "--save", "x.bin"],
    );
    assert!(e.contains("--part"), "{e}");
    assert!(!dir.join("out.bin").exists());
}
