//! Progressive passes rendered apart (`caustic render --integrator progressive --first-pass P
//! --save-passes FILE`) and merged (`caustic merge`): the merged image is the image of one
//! process running every pass, to the rounding of the sums, with the same error estimate; parts
//! of another render, with a gap or an overlap, or forged, are refused naming the file.

use crate::common::{GLASS_BALL, caustic, out_dir, run_ok};
use std::path::Path;

/// The flags every render below shares: progressive, small passes.
const FLAGS: [&str; 7] = [
    "--integrator",
    "progressive",
    "--photons",
    "5000",
    "--caustic-photons",
    "5000",
    "-q",
];

/// Runs `caustic ARGS` in `dir`, asserting success; returns stderr.
fn run(dir: &Path, args: &[&str]) -> String {
    let out = run_ok(caustic().current_dir(dir).args(args));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Renders passes `first` to `first + passes - 1` of the scene in `dir` to `name.exr`, saving
/// them to `name.pass`; returns stderr.
fn render(dir: &Path, name: &str, first: u32, passes: u32, extra: &[&str]) -> String {
    let (first, passes) = (first.to_string(), passes.to_string());
    let (exr, pass) = (format!("{name}.exr"), format!("{name}.pass"));
    let mut args = vec![
        "render",
        "ball.lua",
        "--passes",
        &passes,
        "--first-pass",
        &first,
    ];
    args.extend(["-o", &exr, "--save-passes", &pass]);
    args.extend(FLAGS);
    args.extend(extra);
    run(dir, &args)
}

/// Returns the estimated relative RMSE a command printed (`... RMSE 0.1234`).
fn estimate(stderr: &str) -> f64 {
    let at = stderr.rfind("RMSE ").expect("an estimated error");
    let word = stderr[at + 5..].split_whitespace().next().unwrap();
    word.trim_end_matches(|c: char| !c.is_ascii_digit())
        .parse()
        .unwrap()
}

/// Ten passes rendered as 0–2, 3–3 and 4–9 in three processes and merged (given in any order)
/// are the ten passes of one process: every pixel within 1e-5 of it relatively (the sums are
/// added in another order; f32 rounding over ten passes is about 1e-6), and the same estimated
/// error to the printed digits.
#[test]
fn passes_rendered_apart_merge_into_the_render_of_all_of_them() {
    let dir = out_dir("progressive-parts");
    std::fs::write(dir.join("ball.lua"), GLASS_BALL).unwrap();
    let one = render(&dir, "one", 0, 10, &["--stats"]);
    render(&dir, "a", 0, 3, &[]);
    render(&dir, "b", 3, 1, &[]);
    render(&dir, "c", 4, 6, &[]);
    let merged = run(
        &dir,
        &["merge", "c.pass", "a.pass", "b.pass", "-o", "merged.exr"],
    );
    assert!(merged.contains("passes 0 to 9 from 3 files"), "{merged}");
    let (a, b) = (
        caustic::io::image::read_rgb(&dir.join("merged.exr")).unwrap(),
        caustic::io::image::read_rgb(&dir.join("one.exr")).unwrap(),
    );
    assert_eq!((a.width, a.height), (b.width, b.height));
    let worst = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| ((*x - *y).abs() / y.abs().max(glam::Vec3A::splat(1e-6))).max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "a pixel differs by {worst} relatively");
    assert!(b.pixels.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(estimate(&merged), estimate(&one), "{merged}\n{one}");
}

/// A merge refuses, naming the file: parts with a gap, an overlap, another seed or another
/// window (a crop), and a part whose sums were forged to NaN.
#[test]
fn passes_that_are_not_one_render_are_refused() {
    let dir = out_dir("progressive-parts-refused");
    std::fs::write(dir.join("ball.lua"), GLASS_BALL).unwrap();
    render(&dir, "a", 0, 2, &[]);
    render(&dir, "b", 2, 2, &[]);
    render(&dir, "c", 3, 2, &[]);
    render(&dir, "d", 5, 1, &[]);
    render(&dir, "seed", 2, 2, &["--seed", "9"]);
    render(&dir, "crop", 2, 2, &["--crop", "0,0,20,30"]);
    let mut forged = std::fs::read(dir.join("b.pass")).unwrap();
    let at = forged.len() - 4 - 40;
    forged[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.join("forged.pass"), forged).unwrap();
    let fails = |parts: &[&str]| {
        let out = caustic()
            .current_dir(&dir)
            .arg("merge")
            .args(parts)
            .args(["-o", "out.exr"])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{parts:?} merged");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let e = fails(&["a.pass", "d.pass"]);
    assert!(e.contains("d.pass") && e.contains("missing"), "{e}");
    let e = fails(&["a.pass", "b.pass", "c.pass"]);
    assert!(e.contains("c.pass") && e.contains("given twice"), "{e}");
    let e = fails(&["a.pass", "seed.pass"]);
    assert!(
        e.contains("seed.pass") && e.contains("another render"),
        "{e}"
    );
    let e = fails(&["a.pass", "crop.pass"]);
    assert!(e.contains("crop.pass"), "{e}");
    let e = fails(&["a.pass", "forged.pass"]);
    assert!(e.contains("forged.pass") && e.contains("not finite"), "{e}");
    let e = fails(&["b.pass"]);
    assert!(e.contains("b.pass") && e.contains("missing"), "{e}");
    assert!(!dir.join("out.exr").exists());
}
