//! The samples of a pixel share its weak branches (`caustic::render::Share`): of four samples,
//! one follows a reflection that carries less than a tenth of the sample, at four times its
//! weight, and the others skip it. Checked on a mirror that reflects only the background, so
//! every pixel's value is known: `ks` times the background along the reflected ray.

use crate::common;

use glam::Vec3A;

/// A camera looking down at a large mirror (no diffuse part, one black light) inside a diffuse
/// sphere lit only by the ambient term (`kd · ambient` = 0.5 everywhere) when `sky` is set, or
/// under the open background otherwise. With the sphere, every pixel is `ks · 0.5`.
fn mirror_scene(ks: f32, sky: bool) -> String {
    let sky = if sky {
        "sky = gr.sphere('sky'); sky:set_material(gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0))
sky:scale(30, 30, 30); root:add_child(sky)"
    } else {
        ""
    };
    format!(
        "m = gr.material({{0, 0, 0}}, {{{ks}, {ks}, {ks}}}, 0)
root = gr.node('root')
floor = gr.cube('mirror'); floor:set_material(m)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)
{sky}
gr.render(root, 'out.pfm', 48, 48, {{0, 2, 0}}, {{0, -1, -0.6}}, {{0, 1, 0}}, 40,
          {{1, 1, 1}}, {{gr.light({{0, 100, 0}}, {{0, 0, 0}}, {{1, 0, 0}})}})
"
    )
}

/// What `--stats` counted: primary and secondary rays, and the weak branches' surfaces left
/// unshaded.
struct Counts {
    primary: u64,
    secondary: u64,
    unshaded: u64,
}

/// Renders the mirror at `spp`; returns the pixels and the counts.
fn render(ks: f32, sky: bool, spp: u32, name: &str) -> (Vec<Vec3A>, Counts) {
    let dir = common::out_dir(name);
    std::fs::write(dir.join("scene.lua"), mirror_scene(ks, sky)).unwrap();
    let spp = spp.to_string();
    let out = common::run_ok(common::caustic().current_dir(&dir).args([
        "render",
        "scene.lua",
        "-q",
        "--stats",
        "--spp",
        &spp,
    ]));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let line = |start: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(start))
            .map(|l| {
                l.split([' ', ',', ';'])
                    .filter(|w| !w.is_empty())
                    .map(str::to_owned)
                    .collect::<Vec<_>>()
            })
    };
    let rays = line("rays:").unwrap_or_else(|| panic!("no rays line in {text}"));
    let count = |kind: &str| -> u64 {
        let at = rays.iter().position(|w| w == kind).unwrap();
        rays[at - 1].parse().unwrap()
    };
    // "weak branches (under 10% of a sample): N surfaces left unshaded, ..."
    let unshaded = line("weak branches").map_or(0, |w| {
        let at = w.iter().position(|x| x == "surfaces").unwrap();
        w[at - 1].parse().unwrap()
    });
    let bytes = std::fs::read(dir.join("out.pfm")).unwrap();
    let (w, h, pixels) = caustic::io::pfm::decode(&bytes, 1 << 20).unwrap();
    assert_eq!((w, h), (48, 48));
    let counts = Counts {
        primary: count("primary"),
        secondary: count("secondary"),
        unshaded,
    };
    (pixels, counts)
}

fn mean(pixels: &[Vec3A]) -> Vec3A {
    pixels.iter().copied().sum::<Vec3A>() / pixels.len() as f32
}

const PIXELS: u64 = 48 * 48;

#[test]
fn one_sample_in_four_shades_a_weak_reflection_and_every_pixel_keeps_its_value() {
    // ks = 0.05 is weak: of four samples per pixel each traces the reflection, and exactly one
    // shades the sphere it meets, at four times the weight.
    let (pixels, c) = render(0.05, true, 4, "weak-sky");
    assert_eq!((c.primary, c.secondary), (4 * PIXELS, 4 * PIXELS));
    assert_eq!(
        c.unshaded,
        3 * PIXELS,
        "three samples in four leave the sphere unshaded"
    );
    // Every pixel is ks · kd · ambient = 0.025 exactly, as before sharing.
    for (i, p) in pixels.iter().enumerate() {
        let err = (*p / 0.025 - Vec3A::ONE).abs().max_element();
        assert!(err < 1e-5, "pixel {i} is {p}, not 0.025");
    }
    // A strong mirror (ks = 0.5) is shaded by every sample.
    let (pixels, c) = render(0.5, true, 4, "strong-sky");
    assert_eq!((c.secondary, c.unshaded), (4 * PIXELS, 0));
    assert!((mean(&pixels) / 0.25 - Vec3A::ONE).abs().max_element() < 1e-5);
}

#[test]
fn what_a_weak_reflection_sees_before_a_surface_counts_in_every_sample() {
    // Under the open background the reflections meet no surface: nothing is left unshaded and
    // every sample counts the background it reflects, so the 4-sample image agrees with 16
    // samples pixel by pixel within the gradient's change across a pixel, and in the mean.
    let (four, c4) = render(0.05, false, 4, "weak-open");
    assert_eq!((c4.secondary, c4.unshaded), (4 * PIXELS, 0));
    let (many, c16) = render(0.05, false, 16, "weak-open-16");
    assert_eq!(c16.unshaded, 0);
    let (a, b) = (mean(&four), mean(&many));
    assert!(
        (a / b - Vec3A::ONE).abs().max_element() < 1e-3,
        "mean {a} against {b}"
    );
    let worst = four
        .iter()
        .zip(&many)
        .map(|(s, m)| ((*s - *m).abs() / *m).max_element())
        .fold(0.0f32, f32::max);
    assert!(
        worst < 0.02,
        "a pixel differs by {worst} from its 16-sample value"
    );
}
