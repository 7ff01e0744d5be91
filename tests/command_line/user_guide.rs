//! The user guide (`docs/guide.md`) is true to the code: every Lua example in it runs, builds
//! its scenes and renders a tiny image of each, and every CLI flag it names exists.

use crate::common::{caustic, guide_dir, guide_examples, render_films_with};
use caustic::integrator::Settings;
use caustic::render::Sampling;

/// Every Lua example of the guide (at least 5) runs from a folder holding the files it names
/// (`tri.obj`, `tiles.png`), and each of its `gr.render` calls renders (one ray per pixel, few
/// photons) an image with no NaN and some light.
#[test]
fn every_lua_example_in_the_guide_runs_and_renders() {
    let examples = guide_examples();
    assert!(examples.len() >= 5, "{} examples", examples.len());
    let dir = guide_dir("guide");
    let mut settings = Settings {
        sampling: Sampling::Stratified { spp: 1 },
        ..Settings::default()
    };
    settings.photons.photon_scale = 0.05;
    settings.photons.follow_image = false;
    for (i, src) in examples.iter().enumerate() {
        let name = format!("example{i}.lua");
        let films = render_films_with(src.as_bytes(), &name, &dir, &settings)
            .unwrap_or_else(|e| panic!("example {i} of the guide fails: {e}\n{src}"));
        for (r, _, film) in &films {
            assert!(
                film.pixels.iter().all(|p| p.is_finite()),
                "example {i}: NaN in {}",
                r.output.display()
            );
            assert!(
                film.pixels.iter().any(|p| p.max_element() > 0.0),
                "example {i}: {} is black",
                r.output.display()
            );
        }
    }
}

/// Every `--flag` the guide names is accepted by `caustic render --help`, `caustic study
/// --help` or another command's help (no flag documented that does not exist).
#[test]
fn every_flag_in_the_guide_exists() {
    let guide =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/guide.md")).unwrap();
    let mut help = String::new();
    for cmd in [
        "render",
        "study",
        "diff",
        "photons",
        "stitch",
        "export-mitsuba",
        "info",
    ] {
        let out = caustic().args([cmd, "--help"]).output().unwrap();
        help.push_str(&String::from_utf8_lossy(&out.stdout));
    }
    let mut missing = Vec::new();
    for (i, _) in guide.match_indices("--") {
        let flag: String = guide[i + 2..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        if flag.len() < 2 || !flag.chars().next().unwrap().is_ascii_lowercase() {
            continue;
        }
        if !help.contains(&format!("--{flag}")) && !missing.contains(&flag) {
            missing.push(flag);
        }
    }
    assert!(
        missing.is_empty(),
        "flags in the guide that no command takes: {missing:?}"
    );
}
