//! The time planner (`--time-budget`, `--target-error` for the photon-map integrator): a
//! target error is met, the printed expected error is close to the measured one, the flags the
//! user typed stay, and what the planner cannot honour is a usage error naming the flag.

use crate::common::{caustic, out_dir, run_ok};

/// A photon-mapped box under an area light, with a glass ball's caustic on the floor: every
/// part of the planner's model (camera noise, maps' noise, their blur) is there.
const BOX: &str = "
    white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    red = gr.material({0.7, 0.1, 0.1}, {0, 0, 0}, 0)
    glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
    root = gr.node('root')
    floor = gr.cube('floor'); floor:set_material(white); floor:scale(4, 0.1, 4); floor:translate(-2, -1.1, -6)
    back = gr.cube('back'); back:set_material(white); back:scale(4, 4, 0.1); back:translate(-2, -1, -6.1)
    left = gr.cube('left'); left:set_material(red); left:scale(0.1, 4, 4); left:translate(-2.1, -1, -6)
    ceil = gr.cube('ceil'); ceil:set_material(white); ceil:scale(4, 0.1, 4); ceil:translate(-2, 3, -6)
    ball = gr.nh_sphere('ball', {0.3, -0.4, -4}, 0.6); ball:set_material(glass)
    for _, n in ipairs({floor, back, left, ceil, ball}) do root:add_child(n) end
    gr.render(root, 'b.png', 40, 40, {0, 1, 1.5}, {0, -0.2, -1}, {0, 1, 0}, 55, {0, 0, 0},
              {gr.area_light({0, 2.8, -4}, {6, 6, 6}, {1, 0, 0}, nil, 200000, {0.5, 0, 0}, {0, 0, 0.5})})
";

/// Returns the number after `key` in `text` (up to the next space, comma or parenthesis).
fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no {key:?} in {text}"))
        + key.len();
    let tail: String = text[at..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == 'e' || *c == '-')
        .collect();
    tail.parse()
        .unwrap_or_else(|_| panic!("{key:?} then {tail:?}"))
}

/// `--target-error 0.05`: against two independent long renders (64 samples, 16 times the
/// photons and cache rays; `caustic diff --second`, so the references' noise drops out) the
/// image's relative RMSE is at most 1.5 times the target, and the error the planner printed is
/// within 1.5 times of the measured one. The same for `--time-budget 0.01`, a budget too short
/// for any pilot (the planner's short-budget plan, whose maps' part comes from one difference:
/// 0.263 expected against 0.193 measured when written).
#[test]
fn target_error_is_met_and_the_expected_error_is_close() {
    let dir = out_dir("time_planner_target");
    std::fs::write(dir.join("b.lua"), BOX).unwrap();
    let render = |args: &[&str]| {
        let out = run_ok(
            caustic()
                .current_dir(&dir)
                .arg("render")
                .arg("b.lua")
                .args(args),
        );
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    for (seed, name) in [("1", "r1.exr"), ("2", "r2.exr")] {
        let long = [
            "--spp",
            "64",
            "--photon-scale",
            "16",
            "--cache-rays",
            "4096",
        ];
        render(&[&long[..], &["--seed", seed, "-q", "-o", name]].concat());
    }
    let measure = |said: &str| {
        let expected = number_after(said, "expected relative RMSE");
        let diff = run_ok(
            caustic()
                .current_dir(&dir)
                .args(["diff", "t.exr", "r1.exr", "--second", "r2.exr"]),
        );
        let diff = String::from_utf8_lossy(&diff.stdout).to_string();
        let measured = number_after(&diff, "relative RMSE");
        let ratio = expected / measured;
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "expected {expected}, measured {measured}: {said}"
        );
        measured
    };
    let said = render(&["--target-error", "0.05", "-q", "-o", "t.exr"]);
    let measured = measure(&said);
    assert!(measured <= 1.5 * 0.05, "measured {measured}: {said}");
    let said = render(&["--time-budget", "0.01", "-o", "t.exr"]);
    assert!(said.contains("too short for a pilot"), "{said}");
    measure(&said);
}

/// Renders the box in a folder of its own (`name`) with `args`, and returns what it printed.
fn render_box(name: &str, args: &[&str]) -> String {
    let dir = out_dir(name);
    std::fs::write(dir.join("b.lua"), BOX).unwrap();
    let out = run_ok(
        caustic()
            .current_dir(&dir)
            .args(["render", "b.lua"])
            .args(args),
    );
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// A pilot whose prepasses are cheap (a thousandth of the photons, typed, and one cache ray a
/// record) is still too long for 20 ms: its pixels (1296 of them, 12 samples each through four
/// prepasses) are most of it, and the planner times them before it starts (0.13 s predicted,
/// 0.15 s taken, when written). It used to count the prepasses only, run the pilot and report
/// the budget spent.
#[test]
fn a_pilot_whose_pixels_outlast_the_budget_is_skipped() {
    let said = render_box(
        "time_planner_pixels",
        &[
            "--time-budget",
            "0.02",
            "--photon-scale",
            "0.001",
            "--cache-rays",
            "1",
            "-o",
            "x.png",
        ],
    );
    assert!(said.contains("too short for a pilot"), "{said}");
}

/// The box at 64² with a target error the planner reaches in about a second.
const SMALL_TARGET: [&str; 7] = [
    "--scale",
    "1.6",
    "--target-error",
    "0.05",
    "-q",
    "-o",
    "x.png",
];

/// The pilot measures the irradiance cache's interpolation bias and counts it in the expected
/// error (`DiffuseTerm::Unbiased` in `src/integrator/eye.rs`, the pilot in
/// `src/integrator/planner.rs`). On the box at 64² (`--target-error 0.05`): none without a
/// cache; with records ten times further apart than the default's reach (`--cache-accuracy
/// 1`), a bias at least four times the one at `--cache-accuracy 0.1` (with gradients the
/// interpolation's error is second order in the distance: a hundred times, in the square).
#[test]
fn the_pilot_measures_the_caches_interpolation_bias() {
    let bias = |name: &str, args: &[&str]| {
        let said = render_box(name, &[&SMALL_TARGET[..], args].concat());
        (number_after(&said, "the cache's interpolation"), said)
    };
    let (off, said) = bias("time_planner_cache_off", &["--irradiance-cache", "off"]);
    assert_eq!(off, 0.0, "{said}");
    let (fine, _) = bias("time_planner_cache_fine", &["--cache-accuracy", "0.1"]);
    let (coarse, said) = bias("time_planner_cache_coarse", &["--cache-accuracy", "1"]);
    assert!(
        coarse > 0.0 && coarse >= 4.0 * fine,
        "{coarse} against {fine}: {said}"
    );
}

/// The plan counts what more precomputation points cost the cache (`lazy_growth` in
/// `src/integrator/planner.rs`): it says from how many points a gather ray costs more (the
/// larger of the pilot's and the image's 64² pixels), how many an effort makes, and the
/// prepass's seconds as expected and as taken. With the photons typed no effort adds points,
/// and the plan says nothing of them.
#[test]
fn the_plan_counts_the_points_the_cache_reads() {
    let said = render_box("time_planner_points", &SMALL_TARGET);
    let from = number_after(&said, "a record up to");
    let per_effort = number_after(&said, "precomputation points (");
    assert!(from >= 64.0 * 64.0 && per_effort > 0.0, "{said}");
    let expected = number_after(&said, "the prepass expected");
    let took = number_after(&said, "of cache, took");
    assert!(expected > 0.0 && took > 0.0, "{said}");
    let typed = [&SMALL_TARGET[..], &["--photon-scale", "0.5"]].concat();
    let said = render_box("time_planner_points_typed", &typed);
    assert!(!said.contains("precomputation points"), "{said}");
    assert!(said.contains("the prepass expected"), "{said}");
}

/// The flags typed on the command line stay as typed; the planner moves the rest.
#[test]
fn typed_flags_stay() {
    let said = render_box(
        "time_planner_typed",
        &[
            "--time-budget",
            "3",
            "--spp",
            "3",
            "--photon-scale",
            "0.5",
            "-q",
            "-o",
            "x.png",
        ],
    );
    assert!(said.contains(": 3 spp,"), "{said}");
    assert!(said.contains("photon scale 0.5000"), "{said}");
    // Cache rays were not typed: they move with the effort, whatever it is.
    assert!(said.contains("cache rays a record"), "{said}");
}

/// What the planner cannot honour is a usage error naming the flag, before any work.
#[test]
fn planner_flags_are_checked() {
    let dir = out_dir("time_planner_flags");
    std::fs::write(dir.join("b.lua"), BOX).unwrap();
    for (args, flag) in [
        (vec!["--time-budget", "0"], "--time-budget"),
        (vec!["--time-budget", "inf"], "--time-budget"),
        (vec!["--time-budget", "nan"], "--time-budget"),
        (vec!["--target-error", "0"], "--target-error"),
        (
            vec!["--time-budget", "5", "--target-error", "0.1"],
            "--target-error",
        ),
        (
            vec!["--time-budget", "5", "--noise-target", "0.1"],
            "--noise-target",
        ),
        (vec!["--target-error", "0.1", "--adaptive"], "--adaptive"),
        (
            vec!["--time-budget", "5", "--photon-maps", "m.maps"],
            "--photon-maps",
        ),
    ] {
        let out = caustic()
            .current_dir(&dir)
            .args(["render", "b.lua", "-o", "x.png"])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}

/// A floor under a large area light with a thin post: the camera's noise is all in the post's
/// penumbra (the frame where adaptive rounds pay; the planner chose them in every run tried).
const PENUMBRA: &str = "
    white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
    root = gr.node('root')
    floor = gr.cube('floor'); floor:set_material(white); floor:scale(8, 0.1, 8); floor:translate(-4, -1.1, -8)
    post = gr.cube('post'); post:set_material(white); post:scale(0.05, 1.5, 0.05); post:translate(0, -1, -4)
    root:add_child(floor) root:add_child(post)
    gr.render(root, 'p.png', 40, 40, {0, 1, 1.5}, {0, -0.4, -1}, {0, 1, 0}, 55, {0, 0, 0},
      {gr.area_light({0, 2.8, -4}, {6, 6, 6}, {1, 0, 0}, nil, 200000, {2, 0, 0}, {0, 0, 2})})
";

/// Writes the box (`b.lua`) and the penumbra (`p.lua`) into a folder of its own (`name`) and
/// returns a renderer of them: `--stats` with `args`, what it printed (standard output, then
/// standard error).
fn stats_renderer(name: &str) -> impl Fn(&str, &[&str]) -> String {
    let dir = out_dir(name);
    std::fs::write(dir.join("b.lua"), BOX).unwrap();
    std::fs::write(dir.join("p.lua"), PENUMBRA).unwrap();
    move |script: &str, args: &[&str]| {
        let out = run_ok(
            caustic()
                .current_dir(&dir)
                .args(["render", script, "--stats", "-o", "x.png"])
                .args(args),
        );
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr)
    }
}

/// The first round's samples of a plan line that takes rounds ("N spp then rounds"); None
/// without rounds.
fn first_round(planned: &str) -> Option<f64> {
    let (head, _) = planned.split_once(" spp then rounds")?;
    head.rsplit(' ').next()?.parse().ok()
}

/// The effect plan `--stats` prints says what sampling the frame had: `--noise-target` and a
/// budget's rounds are adaptive, and a budget's rounds are really taken exactly when the budget
/// line says so, whichever the planner chose: every pixel takes at least the first round, and
/// the pixels' samples vary unless every pixel met the target in it (which the gate saw once
/// on the penumbra, its first round 256 samples); without rounds every pixel takes the same.
/// On the box (even noise) and on the penumbra (rounds).
#[test]
fn the_plan_reports_the_sampling_the_frame_had() {
    let stats = stats_renderer("time_planner_rounds");
    let noise = stats("b.lua", &["--noise-target", "0.05"]);
    assert!(noise.contains("adaptive: on (--noise-target)"), "{noise}");
    let fixed = stats("b.lua", &["--spp", "4"]);
    assert!(fixed.contains("adaptive: off"), "{fixed}");
    for script in ["b.lua", "p.lua"] {
        let planned = stats(script, &["--time-budget", "1"]);
        let rounds = planned.contains("spp then rounds to a noise target");
        let line = planned
            .lines()
            .find(|l| l.contains("camera rays per pixel"))
            .unwrap_or_default()
            .to_string();
        let mean = number_after(&line, "mean");
        let (lo, hi) = (number_after(&line, "min"), number_after(&line, "max"));
        assert!(mean >= lo && mean <= hi, "{line}");
        match rounds {
            true => {
                assert!(
                    planned.contains("adaptive: on (the time planner's rounds)"),
                    "{planned}"
                );
                let first =
                    first_round(&planned).unwrap_or_else(|| panic!("no first round in {planned}"));
                assert!(
                    lo >= first,
                    "a pixel took fewer than the first round: {line}"
                );
                // Rounds vary the pixels' samples, unless every pixel met the target after the
                // first round (the penumbra's few pixels that would go on sometimes do not).
                assert!(
                    hi > lo || hi == first,
                    "rounds planned but every pixel took {lo}, not the first round's {first}: {line}"
                );
            }
            false => {
                assert!(planned.contains("adaptive: off"), "{planned}");
                assert_eq!(lo, hi, "{line}");
            }
        }
    }
}

/// A target error's plan always ends in rounds to at most the camera's share of the target
/// (`target_rounds` in `src/integrator/planner.rs` says why: the pilot's pixels miss rare
/// fireflies, and a uniform plan cannot see them afterwards). On the box (even noise: the plan
/// was 4 uniform samples) and the penumbra (1 uniform sample) with `--target-error 0.1`: the
/// plan line says "spp then rounds" with a first round of at least 2 samples and a noise
/// target at most 0.1, the frame was adaptive, and no pixel took fewer than the first round.
#[test]
fn a_target_errors_plan_ends_in_rounds() {
    let stats = stats_renderer("time_planner_target_rounds");
    for script in ["b.lua", "p.lua"] {
        let said = stats(script, &["--target-error", "0.1"]);
        let line = said
            .lines()
            .find(|l| l.contains("planned --target-error"))
            .unwrap_or_else(|| panic!("no plan in {said}"));
        let first =
            first_round(line).unwrap_or_else(|| panic!("{script}: no rounds planned: {line}"));
        assert!(first >= 2.0, "{script}: {line}");
        let target = number_after(line, "noise target of");
        assert!(target > 0.0 && target <= 0.1, "{script}: {line}");
        assert!(
            said.contains("adaptive: on (the time planner's rounds)"),
            "{script}: {said}"
        );
        let rays = said
            .lines()
            .find(|l| l.contains("camera rays per pixel"))
            .unwrap_or_default();
        assert!(number_after(rays, "min") >= first, "{script}: {rays}");
    }
}

/// The pilot makes its caches only near its pixels (`src/integrator/planner.rs` says why). On
/// the box at 512² with the pilot's 36 × 36 grid of pixels: the records such a cache estimates
/// a whole build would make are within 15% of what the whole build made (3296 against 3490
/// when written); at the pixels' centre rays it serves as many points as the whole cache
/// (within 2% of them) with the same light (means within 2%; 0.04% when written); and it
/// makes at most 60% of the whole cache's records (49%).
#[test]
fn a_cache_near_the_pilots_pixels_serves_them_as_the_whole_one_does() {
    use caustic::integrator::Settings;
    use caustic::integrator::irradiance_cache::Probes;
    use caustic::integrator::photon_map::{Prepass, planned};
    use std::cell::RefCell;
    use std::rc::Rc;
    let src = BOX.replace("40, 40,", "512, 512,");
    let dir = out_dir("planner_near_cache");
    // (whole records, estimated whole records, near records, served [whole, near], sums)
    let found = Rc::new(RefCell::new(None));
    let sink = Rc::clone(&found);
    caustic::lua::run_source(
        src.as_bytes(),
        "near.lua",
        &dir,
        Box::new(move |desc, r| {
            let mut scene = caustic::scene::build::build_scene(desc, r)?;
            let camera = caustic::camera::Camera::new(&r.camera, r.width, r.height);
            let settings = Settings::default();
            let plan = caustic::frame::plan(&mut scene, &settings);
            let gi = planned(&settings.photons, &plan);
            let no = &caustic::progress::NoProgress;
            // Built twice: the maps are a function of the scene and the seed.
            let maps = || Prepass::build(&scene, &gi).precompute_for(&camera);
            let cols = 36;
            let grid: Vec<(u32, u32)> = (0..cols)
                .flat_map(|j| (0..cols).map(move |i| (i, j)))
                .map(|(i, j)| {
                    (
                        (2 * i + 1) * 512 / (2 * cols),
                        (2 * j + 1) * 512 / (2 * cols),
                    )
                })
                .collect();
            let near = maps().with_cache_over(&scene, &camera, Probes::Near(&grid), no);
            let whole = maps().with_cache(&scene, &camera, no);
            let (ws, ns) = (
                whole.stats.cache.clone().unwrap(),
                near.stats.cache.clone().unwrap(),
            );
            let (mut served, mut sums) = ([0u32; 2], [0.0f64; 2]);
            for &(x, y) in &grid {
                let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                let Some(hit) = scene.intersect(&ray) else {
                    continue;
                };
                let s = scene.surface(&ray, &hit);
                let caches = [&whole, &near].map(|p| p.cache.as_ref().unwrap());
                let e = caches.map(|c| c.lookup(s.p, s.ng, s.ns));
                for (k, e) in e.iter().enumerate() {
                    served[k] += u32::from(e.is_some());
                }
                if let [Some(a), Some(b)] = e {
                    sums[0] += f64::from(a.element_sum());
                    sums[1] += f64::from(b.element_sum());
                }
            }
            *sink.borrow_mut() = Some((ws.records, ns.whole_records, ns.records, served, sums));
            Ok(())
        }),
    )
    .unwrap();
    let (whole, estimated, near, served, sums) = found.borrow().unwrap();
    println!(
        "records: whole {whole}, near {near} (estimating {estimated:.0} for the whole); served \
         {served:?} of the grid's centre rays; light {:.4} / {:.4}",
        sums[1], sums[0]
    );
    assert!((estimated / whole as f64 - 1.0).abs() < 0.15);
    assert!(near as f64 <= 0.6 * whole as f64);
    assert!(served[0] > 600 && served[1] as f64 >= 0.98 * served[0] as f64);
    assert!((sums[1] / sums[0] - 1.0).abs() < 0.02);
}
