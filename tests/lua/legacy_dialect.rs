//! Scripts written for the course's legacy API (before Fall 2015) render correctly with
//! `--dialect legacy`: node transforms post-multiply, so a legacy copy of a scene (each node's
//! calls in the reverse order, as the two eras' copies of the course's scenes are) renders,
//! value for value, the image of its modern copy;
//! `require('readobj')` gets a built-in OBJ reader, modules load from the script's folder, and
//! the Lua 5.1 names work.

use crate::common;

use crate::common::{a4_assets, caustic, legacy_copy, out_dir, reverse_transform_calls, run_ok};
use caustic::Fault;
use caustic::desc::{MeshSource, NodeId, SceneDesc};
use caustic::lua::{Dialect, ScriptOptions, run_source_with};
use glam::{DAffine3, DVec3};
use std::path::{Path, PathBuf};

/// Runs script text named `test.lua` in `dialect` (paths resolve in `dir`) without rendering.
fn run_in(src: &str, dir: &Path, dialect: Option<Dialect>) -> Result<SceneDesc, caustic::Error> {
    let options = ScriptOptions {
        dialect,
        ..ScriptOptions::default()
    };
    run_source_with(
        src.as_bytes(),
        "test.lua",
        dir,
        Box::new(|_, _| Ok(())),
        options,
    )
}

/// Returns the linear pixels of an EXR the command line wrote.
fn exr_pixels(path: &Path) -> Vec<f32> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb32f()
        .into_raw()
}

/// The repository's legacy scene pair.
fn desk(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/legacy")
        .join(name)
}

#[test]
fn legacy_dialect_post_multiplies_each_nodes_transforms() {
    let src = "n = gr.node('n'); n:translate(1, 2, 3); n:rotate('z', 90); n:scale(2, 2, 2)";
    let t = DAffine3::from_translation(DVec3::new(1.0, 2.0, 3.0));
    let r = DAffine3::from_rotation_z(90f64.to_radians());
    let s = DAffine3::from_scale(DVec3::splat(2.0));
    let cases = [
        (Some(Dialect::Legacy), t * r * s, DVec3::new(1.0, 4.0, 3.0)),
        (Some(Dialect::Modern), s * r * t, DVec3::new(-4.0, 4.0, 6.0)),
        (None, s * r * t, DVec3::new(-4.0, 4.0, 6.0)),
    ];
    for (dialect, expected, x_lands_at) in cases {
        let desc = run_in(src, Path::new("."), dialect).unwrap();
        let m = desc.node(NodeId(0)).transform;
        assert!(m.abs_diff_eq(expected, 1e-12), "{dialect:?}: {m:?}");
        // Legacy: scaled, rotated, then moved; modern: moved, rotated, then scaled.
        let p = m.transform_point3(DVec3::X);
        assert!(p.abs_diff_eq(x_lands_at, 1e-12), "{dialect:?}: {p}");
    }
}

#[test]
fn the_legacy_desk_renders_the_modern_desks_image_value_for_value() {
    let out = out_dir("legacy-desk");
    let render = |script: &str, flags: &[&str], exr: &str| {
        let run = run_ok(
            caustic()
                .arg("render")
                .arg(desk(script))
                .args(["--scale", "0.5", "-q", "-o"])
                .arg(out.join(exr))
                .args(flags),
        );
        (
            exr_pixels(&out.join(exr)),
            String::from_utf8_lossy(&run.stderr).into_owned(),
        )
    };
    let (modern, quiet) = render("desk.lua", &[], "modern.exr");
    let (legacy, quiet_too) = render("desk_legacy.lua", &["--dialect", "legacy"], "legacy.exr");
    let (wrong, warned) = render("desk_legacy.lua", &[], "wrong.exr");
    assert_eq!(modern.len(), 64 * 48 * 3);
    assert!(modern == legacy, "the two copies render different images");
    let changed = modern.iter().zip(&wrong).filter(|(a, b)| a != b).count();
    assert!(
        changed > modern.len() / 10,
        "the legacy copy read the modern way changed only {changed} values"
    );
    assert!(!quiet.contains("--dialect") && !quiet_too.contains("--dialect"));
    assert!(warned.contains("--dialect legacy"), "{warned}");
}

/// A legacy script of two parts for the Mitsuba subset (diffuse, physical falloff), and its modern
/// copy (each node's calls reversed).
const TWO_PARTS: &str = "white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
root = gr.node('root')
c = gr.cube('c'); c:set_material(white); root:add_child(c)
c:translate(1, 0, 0); c:rotate('y', 30); c:scale(2, 1, 1)
s = gr.sphere('s'); s:set_material(white); root:add_child(s)
s:translate(-1, 0.5, 0); s:scale(0.5, 0.5, 0.5)
gr.render(root, 'two.png', 16, 16, {0, 0, 8}, {0, 0, -1}, {0, 1, 0}, 50, {0.2, 0.2, 0.2},
          {gr.light({0, 5, 5}, {1, 1, 1}, {0, 0, 1})})
";

#[test]
fn every_command_that_runs_a_script_takes_the_dialect() {
    let out = out_dir("legacy-commands");
    let legacy = out.join("two_legacy.lua");
    let modern = out.join("two.lua");
    std::fs::write(&legacy, TWO_PARTS).unwrap();
    let (reversed, runs) = reverse_transform_calls(TWO_PARTS);
    assert_eq!(runs, 2);
    std::fs::write(&modern, reversed).unwrap();
    let photons = out.join("photons.png");
    let xml = out.join("scene.xml");
    let commands: [&[&str]; 3] = [
        &["info"],
        &[
            "photons",
            "--photons",
            "1000",
            "--caustic-photons",
            "1000",
            "-q",
            "-o",
        ],
        &["export-mitsuba", "-o"],
    ];
    for (command, target) in commands.iter().zip([None, Some(&photons), Some(&xml)]) {
        let runs = [
            (&[][..], true),
            (&["--dialect", "modern"][..], false),
            (&["--dialect", "legacy"][..], false),
        ];
        for (flags, warns) in runs {
            let mut cmd = caustic();
            cmd.arg(command[0]).arg(&legacy).args(&command[1..]);
            if let Some(t) = target {
                cmd.arg(t);
            }
            let run = run_ok(cmd.args(flags));
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert_eq!(
                stderr.contains("--dialect legacy"),
                warns,
                "{command:?} {flags:?}: {stderr}"
            );
        }
    }
    // The last export read the legacy script the legacy way: it places what the modern copy does.
    let modern_xml = out.join("modern.xml");
    run_ok(
        caustic()
            .arg("export-mitsuba")
            .arg(&modern)
            .arg("-o")
            .arg(&modern_xml),
    );
    let shapes = |p: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(p).unwrap();
        text.lines()
            .filter(|l| l.contains("<shape"))
            .map(String::from)
            .collect()
    };
    assert_eq!(shapes(&xml).len(), 2);
    assert_eq!(shapes(&xml), shapes(&modern_xml));
    let bad = caustic()
        .args(["info", "x.lua", "--dialect", "old"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success());
    assert!(
        stderr.contains("--dialect") && stderr.contains("legacy"),
        "{stderr}"
    );
}

/// A study of the legacy script against a reference rendered from its modern copy measures no
/// error with `--dialect legacy`, and a large one without; a setting may not choose the dialect.
#[test]
fn study_takes_the_dialect_for_the_whole_study() {
    let out = out_dir("legacy-study");
    let legacy = out.join("two_legacy.lua");
    std::fs::write(&legacy, TWO_PARTS).unwrap();
    let modern = out.join("two.lua");
    std::fs::write(&modern, reverse_transform_calls(TWO_PARTS).0).unwrap();
    let reference = out.join("ref.exr");
    run_ok(
        caustic()
            .arg("render")
            .arg(&modern)
            .args(["--scale", "2", "--spp", "1", "-q", "-o"])
            .arg(&reference),
    );
    let study = |dialect: &[&str], dir: &str| {
        run_ok(
            caustic()
                .arg("study")
                .arg(&legacy)
                .args(dialect)
                .arg("--reference")
                .arg(&reference)
                .arg("--base=--scale 2 --spp 1")
                .arg("-o")
                .arg(out.join(dir)),
        );
        let csv = std::fs::read_to_string(out.join(dir).join("study.csv")).unwrap();
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let column = header.iter().position(|h| *h == "rel_rmse").unwrap();
        let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        row[column].parse::<f64>().unwrap()
    };
    assert_eq!(study(&["--dialect", "legacy"], "legacy"), 0.0);
    assert!(study(&[], "modern") > 0.1);
    let setting = caustic()
        .arg("study")
        .arg(&legacy)
        .arg("--reference")
        .arg(&reference)
        .arg("--base=--dialect legacy")
        .arg("-o")
        .arg(out.join("refused"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&setting.stderr);
    assert!(!setting.status.success());
    assert!(
        stderr.contains("--dialect, -D and --no-partial are the study's to set"),
        "{stderr}"
    );
}

/// The course's A4 scenes whose transform order matters, each with its legacy copy made from it
/// (every node's calls reversed, meshes read by readobj, `unpack`): the copy with `--dialect
/// legacy` renders the original's image value for value (same seed, a quarter of the size), and
/// read the modern way renders another image and warns.
#[test]
fn legacy_copies_of_the_a4_scenes_render_the_originals_images() {
    if common::skip_without_corpus("legacy_copies_of_the_a4_scenes_render_the_originals_images") {
        return;
    }
    let out = out_dir("legacy-a4");
    for name in ["hier", "instance", "simple-cows", "macho-cows"] {
        let original = a4_assets().join(format!("{name}.lua"));
        let copy = out.join(format!("{name}-legacy.lua"));
        std::fs::write(
            &copy,
            legacy_copy(&std::fs::read_to_string(&original).unwrap()),
        )
        .unwrap();
        // From the scenes' folder, where the copy finds the meshes (the working directory first);
        // a script outside that folder reads it only when the user says so (--allow-read).
        let render = |script: &Path, flags: &[&str], exr: &str| {
            let run = run_ok(
                caustic()
                    .current_dir(a4_assets())
                    .arg("render")
                    .arg(script)
                    .arg("--allow-read")
                    .arg(a4_assets())
                    .args(["--scale", "0.25", "--seed", "3", "-q", "-o"])
                    .arg(out.join(exr))
                    .args(flags),
            );
            (
                exr_pixels(&out.join(exr)),
                String::from_utf8_lossy(&run.stderr).into_owned(),
            )
        };
        let (modern, _) = render(&original, &[], &format!("{name}.exr"));
        let (legacy, quiet) = render(
            &copy,
            &["--dialect", "legacy"],
            &format!("{name}-legacy.exr"),
        );
        let (wrong, warned) = render(&copy, &[], &format!("{name}-wrong.exr"));
        assert_eq!(modern.len(), 64 * 64 * 3, "{name}");
        assert!(
            modern == legacy,
            "{name}: the legacy copy renders another image"
        );
        assert!(modern != wrong, "{name}: the order changed nothing");
        // Other warnings (a material brighter than white) are not the dialect's.
        assert!(!quiet.contains("--dialect"), "{name}: {quiet}");
        assert!(warned.contains("--dialect legacy"), "{name}: {warned}");
    }
}

#[test]
fn the_built_in_readobj_reads_what_gr_mesh_reads() {
    let dir = out_dir("legacy-readobj");
    // Comments, a quad, texture coordinates and normals, a negative index.
    let obj = "# a pyramid\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0.5 1 0.5\nvt 0 0\nvn 0 1 0\n\
               f 1/1/1 2/1/1 3/1/1 4/1/1\nf 1 5 2\nf 2 5 3\nf 3 5 4\nf -2 -1 -5\n";
    std::fs::write(dir.join("p.obj"), obj).unwrap();
    let src = "require('readobj')\n\
               a = gr.mesh('a', readobj('p.obj'))\n\
               b = gr.mesh('b', 'p.obj')\n";
    let desc = run_in(src, &dir, None).unwrap();
    let parsed = caustic::io::obj::load_obj(&dir.join("p.obj")).unwrap();
    let MeshSource::Inline { positions, faces } = &desc.meshes[0].source else {
        panic!("readobj made no inline mesh");
    };
    let positions: Vec<glam::Vec3> = positions.iter().map(|p| p.as_vec3()).collect();
    assert_eq!(positions, parsed.positions);
    let triangles: Vec<[u32; 3]> = faces.iter().map(|f| [f[0], f[1], f[2]]).collect();
    assert_eq!(triangles, parsed.triangles);
    assert_eq!(triangles.len(), 6, "the quad fans into two triangles");
    assert!(matches!(desc.meshes[1].source, MeshSource::File { .. }));
}

#[test]
fn readobj_faults_name_the_line_and_the_file() {
    let dir = out_dir("legacy-readobj-faults");
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    let fails = |src: &str| run_in(src, &dir, None).unwrap_err();
    let missing = fails("require('readobj')\nm = gr.mesh('m', readobj('nope.obj'))");
    assert!(matches!(
        missing,
        caustic::Error::Script {
            fault: Fault::NotFound,
            ..
        }
    ));
    let text = missing.to_string();
    assert!(
        text.starts_with("test.lua:2: mesh file 'nope.obj' not found"),
        "{text}"
    );
    let broken = fails("require('readobj')\n\nm = gr.mesh('m', readobj('bad.obj'))").to_string();
    assert!(
        broken.starts_with("test.lua:3: readobj: cannot load mesh 'bad.obj': ")
            && broken.contains("bad.obj:3: "),
        "{broken}"
    );
    let no_name = fails("require('readobj')\nreadobj()").to_string();
    assert_eq!(
        no_name,
        "test.lua:2: bad argument #1 to 'readobj' (string expected, got no value)"
    );
}

/// A script's own readobj.lua (and any module beside it) is found in its folder before the
/// built-in, as the course's scripts found theirs.
#[test]
fn require_finds_modules_in_the_scripts_folder_first() {
    let dir = out_dir("legacy-require");
    std::fs::write(
        dir.join("readobj.lua"),
        "function readobj(f) return {{0,0,0},{1,0,0},{0,1,0}}, {{0,1,2}} end\n",
    )
    .unwrap();
    std::fs::write(dir.join("shapes.lua"), "ball = gr.sphere('ball')\n").unwrap();
    let src = "require('readobj')\nrequire('shapes')\nm = gr.mesh('m', readobj('absent.obj'))";
    let desc = run_in(src, &dir, Some(Dialect::Legacy)).unwrap();
    assert_eq!(desc.nodes[0].name, "ball");
    let MeshSource::Inline { positions, .. } = &desc.meshes[0].source else {
        panic!("no inline mesh");
    };
    assert_eq!(positions.len(), 3, "the script's own readobj ran");
    let missing = run_in("require('nothing_here')", &dir, None)
        .unwrap_err()
        .to_string();
    assert!(
        missing.contains("module 'nothing_here' not found") && missing.contains("no built-in"),
        "{missing}"
    );
}

#[test]
fn lua_51_names_work_in_both_dialects() {
    let src = "local a, b = unpack({1, 2})\n\
               local n = 0\n\
               for w in string.gfind('one two three', '%a+') do n = n + 1 end\n\
               assert(a == 1 and b == 2 and n == 3 and table.getn({4, 5, 6}) == 3)\n\
               assert(table.unpack ~= nil and string.gmatch ~= nil)";
    for dialect in [None, Some(Dialect::Modern), Some(Dialect::Legacy)] {
        run_in(src, Path::new("."), dialect).unwrap_or_else(|e| panic!("{dialect:?}: {e}"));
    }
}
