//! Profiling traversal for users: `--heatmap nodes|triangles|time` and `--stats`' traversal
//! counts by ray kind. The kinds' ray counts agree with the renderer's own ray counters, the
//! heatmap is black exactly where nothing was traversed, and counting changes no pixel.

use crate::common::{caustic, out_dir, run_ok};

/// A mesh floor (a 16 × 16 grid of quads, x in [-4, 0]) on the left half of the view, the
/// background on the right,
/// one point light: Whitted shading, so every ray is a camera or a shadow ray.
fn scene() -> String {
    let n = 16;
    let mut v = Vec::new();
    let mut f = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                i as f32 / n as f32 * 4.0 - 4.0,
                2.0 - j as f32 / n as f32 * 10.0,
            );
            v.push(format!("{{{x}, 0, {z}}}"));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            f.push(format!(
                "{{{}, {}, {}, {}}}",
                a,
                a + 1,
                a + n + 2,
                a + n + 1
            ));
        }
    }
    format!(
        "m = gr.material({{0.7, 0.7, 0.7}}, {{0, 0, 0}}, 0)
         floor = gr.mesh('floor', {{{}}}, {{{}}}); floor:set_material(m)
         root = gr.node('root'); root:add_child(floor)
         gr.render(root, 'p.png', 40, 30, {{0, 1, 1}}, {{0, -0.3, -1}}, {{0, 1, 0}}, 60, {{0, 0, 0}},
                   {{gr.light({{-2, 4, -2}}, {{1, 1, 1}}, {{1, 0, 0}})}})",
        v.join(", "),
        f.join(", ")
    )
}

/// Returns the number before `word` in `line` (`... 1200 primary ...`).
fn number_before(line: &str, word: &str) -> u64 {
    let at = line
        .find(word)
        .unwrap_or_else(|| panic!("no {word} in {line}"));
    let digits: String = line[..at]
        .trim_end()
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.chars().rev().collect::<String>().parse().unwrap()
}

#[test]
fn traversal_counts_by_kind_agree_with_the_ray_counters_and_change_no_pixel() {
    let dir = out_dir("profiling-kinds");
    std::fs::write(dir.join("p.lua"), scene()).unwrap();
    let plain = ["render", "p.lua", "--spp", "1", "-q", "--gi", "off"];
    run_ok(
        caustic()
            .current_dir(&dir)
            .args(plain)
            .args(["-o", "plain.png"]),
    );
    let out = run_ok(caustic().current_dir(&dir).args(plain).args([
        "-o",
        "counted.png",
        "--stats",
        "--heatmap",
        "triangles",
    ]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rays = stdout.lines().find(|l| l.contains("  rays: ")).unwrap();
    let kinds = stdout
        .lines()
        .find(|l| l.contains("traversal by ray kind"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert_eq!(
        number_before(kinds, "rays, "),
        number_before(rays, "primary"),
        "camera rays: {kinds} / {rays}"
    );
    let shadow = &kinds[kinds.find("shadow").expect("shadow rays")..];
    assert_eq!(
        number_before(shadow, "rays, "),
        number_before(rays, "shadow"),
        "{kinds} / {rays}"
    );
    assert!(
        !kinds.contains("gather") && !kinds.contains("photon"),
        "{kinds}"
    );
    assert_eq!(
        std::fs::read(dir.join("plain.png")).unwrap(),
        std::fs::read(dir.join("counted.png")).unwrap(),
        "counting changed the image"
    );
}

#[test]
fn the_heatmap_is_black_where_nothing_was_traversed_and_has_its_legend() {
    let dir = out_dir("profiling-heatmap");
    std::fs::write(dir.join("p.lua"), scene()).unwrap();
    let out = run_ok(caustic().current_dir(&dir).args([
        "render",
        "p.lua",
        "--spp",
        "1",
        "-q",
        "--gi",
        "off",
        "--heatmap",
        "triangles",
    ]));
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("wrote p.heat-triangles.png (top colour: "),
        "{said}"
    );
    let img = image::open(dir.join("p.heat-triangles.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(
        img.dimensions(),
        (40, 30 + 56),
        "the image and its legend strip"
    );
    let (mut sky, mut floor) = (0, 0);
    for y in 0..30 {
        for x in 0..40 {
            let heat = img.get_pixel(x, y).0;
            // Rays to the right of the view never reach the floor's box (the floor lies at
            // x < 0); rays low on the left land on the floor.
            if x >= 24 {
                assert_eq!(
                    heat,
                    [0, 0, 4],
                    "pixel {x},{y} right of the floor tested triangles"
                );
                sky += 1;
            }
            if x < 16 && y >= 20 {
                assert_ne!(heat, [0, 0, 4], "floor pixel {x},{y} tested no triangle");
                floor += 1;
            }
        }
    }
    assert!(
        sky > 100 && floor > 100,
        "{sky} sky and {floor} floor pixels"
    );
    // The legend's colour bar runs from the scale's black to its yellow.
    let bar_y = 30 + 12;
    assert_eq!(img.get_pixel(4, bar_y).0, [0, 0, 4]);
    assert_eq!(img.get_pixel(35, bar_y).0, [252, 255, 164]);
    let e = caustic()
        .current_dir(&dir)
        .args([
            "render",
            "p.lua",
            "--heatmap",
            "nodes",
            "--integrator",
            "progressive",
        ])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&e.stderr).contains("--heatmap: the progressive"));
}
