//! Numbers finite in double precision (Lua's) but not in single (the renderer's), and radiance
//! that overflows: each is rejected at its script line or handled, and no NaN or infinite value
//! ever reaches the image.

use crate::common::{caustic, lua_error, out_dir, run_lua, run_ok, whitted};
use caustic::frame::{Frame, render_desc};
use caustic::progress::NoProgress;

/// A scene: `{material}` and `{sphere}` replace the material and the sphere's construction,
/// `{view}` the view direction of the 5×5 render.
fn scene(material: &str, sphere: &str, view: &str) -> String {
    format!(
        "m = {material}\n\
         s = {sphere}\n\
         s:set_material(m)\n\
         gr.render(s, 'p.png', 5, 5, {{0, 0, 5}}, {view}, {{0, 1, 0}}, 50, {{0.1, 0.1, 0.1}},\n\
                   {{gr.light({{0, 0, 5}}, {{1, 1, 1}}, {{1, 0, 0}})}})\n"
    )
}

const MATTE: &str = "gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0)";
const SPHERE: &str = "gr.sphere('s')";
const VIEW: &str = "{0, 0, -1}";

/// Renders the first image of `src` with the course's settings.
fn render(src: &str) -> Frame {
    let desc = run_lua(src).unwrap();
    render_desc(&desc, &desc.renders[0], 1.0, None, &whitted(), &NoProgress).unwrap()
}

/// Every number beyond single precision that sets geometry, the camera, a colour or a transform
/// is refused with lauxlib's message at its script line (1e300 became an infinite `f32`, then an
/// all-NaN image with exit status 0). Seven cases, one per argument kind.
#[test]
fn numbers_beyond_single_precision_are_refused_at_their_line() {
    let big = "number within single precision (|x| <= 3.4e38) expected, got 1e300";
    let cases = [
        (
            scene(MATTE, SPHERE, "{0, 0, -1e300}"),
            format!("test.lua:4: bad argument #6 to 'render' (entry 3: {big})").replace("1e300", "-1e300"),
        ),
        (
            scene("gr.material({1e300, 0, 0}, {0, 0, 0}, 0)", SPHERE, VIEW),
            format!("test.lua:1: bad argument #1 to 'material' (entry 1: {big})"),
        ),
        (
            scene("gr.material({1, 1, 1}, {0, 0, 0}, 1e300)", SPHERE, VIEW),
            format!("test.lua:1: bad argument #3 to 'material' ({big})"),
        ),
        (
            scene(MATTE, "gr.nh_sphere('s', {0, 0, 0}, 1e300)", VIEW),
            format!("test.lua:2: bad argument #3 to 'nh_sphere' ({big})"),
        ),
        (
            scene(MATTE, "gr.sphere('s'); s:translate(0, 1e300, 0)", VIEW),
            format!("test.lua:2: bad argument #2 to 'translate' ({big})"),
        ),
        (
            scene(MATTE, "gr.sphere('s'); s:scale(1, 1, -1e300)", VIEW),
            "test.lua:2: bad argument #3 to 'scale' (number within single precision (|x| <= 3.4e38) expected, got -1e300)".into(),
        ),
        (
            "l = gr.light({0, 0, 5}, {1e300, 1, 1}, {1, 0, 0})".into(),
            format!("test.lua:1: bad argument #2 to 'light' (entry 1: {big})"),
        ),
    ];
    for (src, want) in cases {
        assert_eq!(lua_error(&src), want, "script:\n{src}");
    }
}

/// Scales that each fit single precision but compose past it (1e20 · 1e20) are refused when the
/// scene is built, naming the node and its line, instead of an infinite transform.
#[test]
fn transforms_composing_past_single_precision_are_refused() {
    let src = scene(
        MATTE,
        "gr.sphere('s'); s:scale(1e20, 1e20, 1e20)\n\
         g = gr.node('g'); g:scale(1e20, 1e20, 1e20); g:add_child(s)",
        VIEW,
    )
    .replace("gr.render(s,", "gr.render(g,");
    let desc = run_lua(&src).unwrap();
    let err = render_desc(&desc, &desc.renders[0], 1.0, None, &whitted(), &NoProgress)
        .err()
        .expect("the build must fail")
        .to_string();
    assert!(
        err.starts_with("test.lua:2:")
            && err.contains("node 's' is transformed beyond single precision"),
        "{err}"
    );
}

/// A view vector whose square overflows `f32` (1e30) looks the same way as {0, 0, -1}: every
/// one of the 25 pixels equal (it was normalised in single precision: NaN).
#[test]
fn huge_view_vectors_are_normalised_in_double_precision() {
    let want = render(&scene(MATTE, SPHERE, VIEW)).film.pixels;
    let got = render(&scene(MATTE, SPHERE, "{0, 0, -1e30}")).film.pixels;
    assert_eq!(got, want);
}

/// Radiance past the largest `f32` never reaches the image: all 25 pixels are finite, and each
/// sample that overflowed is counted as dropped, black, and printed by `--stats` (they were
/// written as Inf).
#[test]
fn infinite_radiance_is_dropped_and_counted() {
    // Inside a mirror sphere of the largest reflectance (10, see caustic::range), with 32 nested
    // glass shells behind the camera raising the plan's splitting depth to its cap
    // (2·32 + 2 = 66): the split bounces multiply a path by 10 each, 10^66 in all. (Past the
    // splitting depth a mirror above 1 no longer multiplies: caustic::range's note.)
    let src = "m = gr.material({0.5, 0.5, 0.5}, {10, 10, 10}, 0)
root = gr.node('root')
s = gr.sphere('s'); s:scale(10, 10, 10); s:set_material(m); root:add_child(s)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
for i = 1, 32 do
  local g = gr.sphere('g' .. i); g:scale(1 - 0.02 * i, 1 - 0.02 * i, 1 - 0.02 * i)
  g:translate(0, 0, 8); g:set_material(glass); root:add_child(g)
end
gr.render(root, 'p.png', 5, 5, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
          {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0})})
";
    let frame = render(src);
    let pixels = &frame.film.pixels;
    assert!(pixels.iter().all(|p| p.is_finite()), "{pixels:?}");
    let dropped = frame.stats.render.nonfinite_samples;
    let black = pixels.iter().filter(|p| **p == glam::Vec3A::ZERO).count() as u64;
    assert!(
        dropped > 0 && dropped == black,
        "{dropped} dropped, {black} black pixels"
    );

    let dir = out_dir("stability_precision_stats");
    let script = dir.join("p.lua");
    std::fs::write(&script, src).unwrap();
    let out = run_ok(
        caustic()
            .args(["render", "-q", "--gi", "off", "--spp", "1", "--stats", "-o"])
            .arg(dir.join("p.exr"))
            .arg(&script),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = format!("NaN or infinite samples dropped: {dropped}");
    assert!(stdout.contains(&line), "no '{line}' in:\n{stdout}");
}
