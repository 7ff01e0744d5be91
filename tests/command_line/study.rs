//! `caustic study` and `caustic diff` on a small scene: one CSV row per setting and seed whose
//! errors recompute from the images it wrote, a table row per setting, a plot.

use crate::common::{caustic, out_dir, run_ok};
use caustic::metrics::{Metrics, Region};
use std::path::Path;

/// A diffuse box under a point light with a glass ball: photon maps, a caustic, 24 × 24.
const SCENE: &str = "
white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(white); floor:scale(4, 0.1, 4); floor:translate(-2, -1.1, -2)
root:add_child(floor)
back = gr.cube('back'); back:set_material(white); back:scale(4, 4, 0.1); back:translate(-2, -1.1, -2)
root:add_child(back)
ball = gr.sphere('ball'); ball:set_material(glass); ball:scale(0.4, 0.4, 0.4); ball:translate(0, -0.5, 0)
root:add_child(ball)
gr.render(root, 'box.png', 24, 24, {0, 0, 4}, {0, 0, -1}, {0, 1, 0}, 40, {0, 0, 0},
          {gr.light({0, 1.5, 0.5}, {2, 2, 2}, {0, 0, 1}, nil, 20000)})
";

/// Reads a linear image the study or a render wrote.
fn read(path: &Path) -> caustic::metrics::Image {
    caustic::io::image::read_rgb(path).unwrap()
}

/// The study's CSV has one row per setting and seed (2 × 2 settings, 2 seeds: 8 rows), its
/// times are positive and finite, and its mean ratio, relative RMSE and block error recompute
/// from the image each row names against the reference within 1e-5 relative; the Markdown has
/// a row per setting and the plot is a 900 × 600 PNG.
#[test]
fn study_rows_recompute_from_the_images_it_wrote() {
    let dir = out_dir("study");
    let script = dir.join("box.lua");
    std::fs::write(&script, SCENE).unwrap();
    let reference = dir.join("ref.exr");
    run_ok(caustic().args([
        "render",
        script.to_str().unwrap(),
        "-o",
        reference.to_str().unwrap(),
        "--integrator",
        "progressive",
        "--passes",
        "16",
        "-q",
    ]));
    let study = dir.join("out");
    let out = run_ok(caustic().args([
        "study",
        script.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--sweep",
        "caustic-photons=1e4,4e4",
        "--sweep",
        "gather-rays=2,4",
        "--base=--spp 1",
        "--seeds",
        "2",
        "-o",
        study.to_str().unwrap(),
    ]));
    let csv = std::fs::read_to_string(study.join("study.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| {
            // The setting is quoted and holds no comma.
            l.split(',')
                .map(|c| c.trim_matches('"').to_string())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 8, "{csv}");
    let r = read(&reference);
    let mut settings = std::collections::BTreeSet::new();
    for row in &rows {
        settings.insert(row[col("setting")].clone());
        for t in ["cpu_s", "wall_s"] {
            let v: f64 = row[col(t)].parse().unwrap();
            assert!(v.is_finite() && v > 0.0, "{t} {v}");
        }
        let image = read(&study.join(&row[col("image")]));
        let m = Metrics::against(&image, &r, Region::full(r.width, r.height));
        for (name, want) in [
            ("mean_ratio", m.mean_ratio),
            ("rel_rmse", m.rel_rmse),
            ("block_bias", m.block_bias),
        ] {
            let got: f64 = row[col(name)].parse().unwrap();
            assert!(
                (got - want).abs() <= 1e-5 * want.abs().max(1e-3),
                "{name}: CSV {got}, recomputed {want}"
            );
        }
    }
    assert_eq!(settings.len(), 4, "{settings:?}");
    let md = std::fs::read_to_string(study.join("study.md")).unwrap();
    for s in &settings {
        assert!(md.contains(s.as_str()), "no row for {s} in\n{md}");
    }
    assert!(String::from_utf8_lossy(&out.stdout).contains("| setting |"));
    let png = image::image_dimensions(study.join("study.png")).unwrap();
    assert_eq!(png, (900, 600));
}

/// A study's bad input is a usage error naming what is wrong, before any render: a sweep
/// without values, a flag no render takes, a reference of another size, too many seeds.
#[test]
fn study_input_errors_name_the_fault() {
    let dir = out_dir("study_errors");
    let script = dir.join("box.lua");
    std::fs::write(&script, SCENE).unwrap();
    let small = dir.join("small.exr");
    run_ok(caustic().args([
        "render",
        script.to_str().unwrap(),
        "-o",
        small.to_str().unwrap(),
        "--scale",
        "0.5",
        "--gi",
        "off",
        "-q",
    ]));
    let s = script.to_str().unwrap();
    for (args, want) in [
        (vec!["--sweep", "photons"], "KEY=V1"),
        (vec!["--sweep", "no-such-flag=1,2"], "no-such-flag"),
        (vec!["--sweep", "photons=-5"], "photons=-5"),
        (vec!["--seeds", "1000"], "--seeds"),
        (vec!["--base=-o x.png"], "the study's to set"),
        (vec![], "renders 24x24 but"),
    ] {
        let out = caustic()
            .args(["study", s, "--reference", small.to_str().unwrap()])
            .args(["-o", dir.join("out").to_str().unwrap()])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
