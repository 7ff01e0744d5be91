//! Media: the camera inside transparent solids, indices relative to the solid around, and
//! absorption, each against a closed form along one centre ray (issue 35: the camera was always
//! in air, an index below 1 rendered as 1, nothing absorbed).
//!
//! Each scene looks at a large area light straight on through the solids, with nothing else to
//! see, and is compared with the same scene without them: the ratio of the centre pixels is then
//! a product of Fresnel factors, the radiance scale `n²` of the change of medium (radiance over
//! `n²` is what is conserved) and the Beer–Lambert transmittance, summed over the reflections
//! between parallel faces. The splitting of eye paths makes those pixels exact up to the cut of
//! weak branches (weights under 1e-3 of the pixel's), hence the tolerances.

use crate::common;

use caustic::camera::Camera;
use glam::Vec3A;

/// Fresnel reflectance at normal incidence between indices `a` and `b`.
fn r0(a: f32, b: f32) -> f32 {
    ((a - b) / (a + b)).powi(2)
}

/// Renders the one render of `src` with centre rays and no photon maps; returns the film's
/// pixels, width and camera.
fn render(src: &str) -> (Vec<Vec3A>, u32, Camera) {
    let films = common::render_films_with(
        src.as_bytes(),
        "media.lua",
        std::path::Path::new("."),
        &common::whitted(),
    )
    .unwrap();
    let (r, camera, film) = films.into_iter().next().unwrap();
    (film.pixels, r.width, camera)
}

/// The centre pixel of a `size × size` image.
fn centre(pixels: &[Vec3A], size: u32) -> Vec3A {
    pixels[(size / 2 * size + size / 2) as usize]
}

/// Lua for the black sphere of radius 1000 round every scene here, so that no ray reaches the
/// background (whose gradient is not black).
const ENCLOSURE: &str = "black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
enclosure = gr.sphere('enclosure'); enclosure:set_material(black); enclosure:scale(1000, 1000, 1000)
root:add_child(enclosure)";

/// A scene: the objects of `objects` (Lua adding to `root`), an area light 40 wide at z = −20
/// facing +z, the camera at `eye` looking along −z, all in [`ENCLOSURE`].
fn facing_light(objects: &str, eye: [f32; 3]) -> String {
    format!(
        "root = gr.node('root')
{ENCLOSURE}
{objects}
light = gr.area_light({{0, 0, -20}}, {{1, 1, 1}}, {{1, 0, 0}}, nil, nil, {{40, 0, 0}}, {{0, 40, 0}})
gr.render(root, 'out.png', 9, 9, {{{}, {}, {}}}, {{0, 0, -1}}, {{0, 1, 0}}, 20, {{0, 0, 0}}, {{light}})
",
        eye[0], eye[1], eye[2]
    )
}

/// The eye at the centre of a glass ball (index 1.5) sees the light through its wall at normal
/// incidence: transmitted `1 − R`, raised by the radiance scale 1.5² of glass over air, the
/// reflections across the centre (which see the black behind) summed as `1/(1 − R²)`. Before the
/// camera's medium was found, the image was the scene's without the ball (ratio 1).
#[test]
fn a_camera_inside_a_glass_ball_sees_out_through_it() {
    let ball = "glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
b = gr.sphere('ball'); b:set_material(glass); root:add_child(b)";
    let (inside, size, _) = render(&facing_light(ball, [0.0, 0.0, 0.0]));
    let (bare, _, _) = render(&facing_light("", [0.0, 0.0, 0.0]));
    let r = r0(1.0, 1.5);
    let want = (1.0 - r) * 1.5 * 1.5 / (1.0 - r * r);
    let ratio = centre(&inside, size) / centre(&bare, size);
    assert!(centre(&bare, size).x > 0.0);
    assert!(
        (ratio - Vec3A::splat(want)).abs().max_element() < 2e-3 * want,
        "ratio {ratio}, want {want}"
    );
}

/// Snell's window: from 1 under a calm water surface (index 1.33, a box 200 wide and 10 deep
/// with a black floor in it 5 down) looking straight up at a light that covers the sky, the rays
/// within the critical angle `asin(1/1.33)` = 48.75° of the vertical see the light, at the
/// centre `(1 − R)·1.33²` of it; those beyond it are reflected totally, down to the black floor:
/// exactly 0. Before, every pixel saw the light as if the water were not there.
#[test]
fn under_water_the_sky_shrinks_to_snells_window() {
    let size = 61;
    let scene = |water: &str| {
        format!(
            "root = gr.node('root')
{ENCLOSURE}
{water}
light = gr.area_light({{0, 3, 0}}, {{1, 1, 1}}, {{1, 0, 0}}, nil, nil, {{400, 0, 0}}, {{0, 0, 400}})
gr.render(root, 'out.png', {size}, {size}, {{0, -1, 0}}, {{0, 1, 0}}, {{0, 0, -1}}, 120, {{0, 0, 0}}, {{light}})
"
        )
    };
    let water = "w = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)
pool = gr.cube('pool'); pool:set_material(w); pool:scale(200, 10, 200); pool:translate(-100, -10, -100)
root:add_child(pool)
floor = gr.cube('floor'); floor:set_material(black); floor:scale(190, 1, 190); floor:translate(-95, -6, -95)
root:add_child(floor)";
    let (under, _, camera) = render(&scene(water));
    let (sky, _, _) = render(&scene(""));
    let critical = (1.0f32 / 1.33).asin().to_degrees();
    let (mut inside, mut outside) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let i = (y * size + x) as usize;
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let angle = ray.dir.normalize().dot(Vec3A::Y).acos().to_degrees();
            assert!(sky[i].x > 0.0, "the light covers the whole view");
            if angle > critical + 0.5 {
                outside += 1;
                assert_eq!(
                    under[i],
                    Vec3A::ZERO,
                    "pixel {x},{y} at {angle}° beyond the window"
                );
            } else if angle < critical - 3.0 {
                inside += 1;
                assert!(
                    under[i].x > 0.0,
                    "pixel {x},{y} at {angle}° inside the window is dark"
                );
            }
        }
    }
    assert!(
        inside > 500 && outside > 500,
        "{inside} pixels inside, {outside} outside"
    );
    let want = (1.0 - r0(1.0, 1.33)) * 1.33 * 1.33;
    let ratio = centre(&under, size as u32) / centre(&sky, size as u32);
    assert!(
        (ratio - Vec3A::splat(want)).abs().max_element() < 2e-3 * want,
        "ratio {ratio}, want {want}"
    );
}

/// The water box of the bubble tests: 200 wide, the camera 5 inside it; `bubble` is Lua adding
/// objects inside it.
fn in_water(bubble: &str) -> String {
    facing_light(
        &format!(
            "water = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.33)
pool = gr.cube('pool'); pool:set_material(water); pool:scale(200, 200, 10); pool:translate(-100, -100, -5)
root:add_child(pool)
{bubble}"
        ),
        [0.0, 0.0, 4.0],
    )
}

/// An air bubble in water written as the relative index `ior = 0.75` (air in water): the centre
/// ray crosses two water–air faces at normal incidence, `(1 − R)²/(1 − R²)` with
/// `R = r0(1.33, 0.75·1.33)`, the radiance scales cancelling. Before, an index below 1 rendered
/// as 1 and the bubble was invisible (ratio 1).
#[test]
fn an_air_bubble_of_relative_index_below_one_refracts() {
    let bubble = "air = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 0.75)
b = gr.sphere('bubble'); b:set_material(air); root:add_child(b)";
    let (with, size, _) = render(&in_water(bubble));
    let (without, _, _) = render(&in_water(""));
    let r = r0(1.33, 0.75 * 1.33);
    let want = (1.0 - r) * (1.0 - r) / (1.0 - r * r);
    let ratio = centre(&with, size) / centre(&without, size);
    assert!(
        (ratio - Vec3A::splat(want)).abs().max_element() < 1e-3,
        "ratio {ratio}, want {want}"
    );
}

/// A slab of coloured glass 1 thick, keeping `{0.5, 0.7, 0.9}` of the light per unit length
/// (`gr.absorption`): at normal incidence it transmits `T²·a/(1 − R²·a²)` per channel
/// (Beer–Lambert along each crossing, the reflections inside crossing twice more). Before,
/// nothing absorbed.
#[test]
fn coloured_glass_absorbs_by_beer_lambert() {
    let kept = [0.5f32, 0.7, 0.9];
    let slab = format!(
        "glass = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)
gr.absorption(glass, {{{}, {}, {}}}, 1)
s = gr.cube('slab'); s:set_material(glass); s:scale(40, 40, 1); s:translate(-20, -20, -0.5)
root:add_child(s)",
        kept[0], kept[1], kept[2]
    );
    let (through, size, _) = render(&facing_light(&slab, [0.0, 0.0, 5.0]));
    let (bare, _, _) = render(&facing_light("", [0.0, 0.0, 5.0]));
    let r = r0(1.0, 1.5);
    let want = Vec3A::from(kept.map(|a| (1.0 - r) * (1.0 - r) * a / (1.0 - r * r * a * a)));
    let ratio = centre(&through, size) / centre(&bare, size);
    assert!(
        (ratio - want).abs().max_element() < 2e-3,
        "ratio {ratio}, want {want}"
    );
}

/// The camera inside absorbing water looks at the light through 3 of it and then the wall:
/// `a³` times the clear water's picture, per channel.
#[test]
fn a_camera_in_absorbing_water_sees_through_its_colour() {
    let water = |absorb: &str| {
        facing_light(
            &format!(
                "water = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.33)
{absorb}
pool = gr.cube('pool'); pool:set_material(water); pool:scale(200, 200, 10); pool:translate(-100, -100, -8)
root:add_child(pool)"
            ),
            [0.0, 0.0, -5.0],
        )
    };
    let (murky, size, _) = render(&water("gr.absorption(water, {0.8, 0.9, 0.95}, 1)"));
    let (clear, _, _) = render(&water(""));
    let want = Vec3A::new(0.8, 0.9, 0.95).powf(3.0);
    let ratio = centre(&murky, size) / centre(&clear, size);
    assert!(
        (ratio - want).abs().max_element() < 2e-3,
        "ratio {ratio}, want {want}"
    );
}

/// `caustic info` names the camera's medium, and a solid of absolute index 1 inside water (which
/// the denser water hides: where transparent solids overlap the denser wins) is warned about at
/// build time with the relative index that makes it air.
#[test]
fn info_names_the_cameras_medium_and_a_hidden_bubble_is_warned_about() {
    let dir = common::out_dir("media-info");
    let path = dir.join("under.lua");
    let src = in_water(
        "air = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1)
b = gr.sphere('bubble'); b:set_material(air); root:add_child(b)",
    );
    std::fs::write(&path, src).unwrap();
    let out = common::caustic().arg("info").arg(&path).output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stdout}{stderr}");
    assert!(
        stdout.contains("camera medium: inside 'pool'") && stdout.contains("index 1.33"),
        "{stdout}"
    );
    assert!(
        stderr.contains("node 'bubble' (ior 1) lies inside node 'pool' (ior 1.33)")
            && stderr.contains("ior = 0.7519"),
        "{stderr}"
    );
}

/// Finding the lights' media is bounded: 300 point lights at the centre of 300 nested glass
/// shells (90,000 light-shell pairs, 7 probe rays each) build with the first 65,536 pairs'
/// lights placed and the rest warned about by count, instead of tracing every pair.
#[test]
fn many_lights_in_many_shells_are_bounded_and_warned_about() {
    let dir = common::out_dir("media-many-lights");
    let path = dir.join("shells.lua");
    let src = "glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
root = gr.node('root')
for i = 1, 300 do
  local s = gr.sphere('shell' .. i); s:scale(i, i, i); s:set_material(glass); root:add_child(s)
end
lights = {}
for i = 1, 300 do lights[i] = gr.light({0, 0, 0}, {0.01, 0.01, 0.01}, {1, 0, 0}) end
gr.render(root, 'x.png', 8, 8, {0, 0, 0.5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0}, lights)
";
    std::fs::write(&path, src).unwrap();
    let out = common::caustic().arg("info").arg(&path).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // 65,536 pairs hold 218 lights (300 shells each); the other 82 are warned about.
    assert!(
        stderr
            .contains("warning: 82 lights lie inside more transparent solids than caustic checks"),
        "{stderr}"
    );
}
