//! A point inside a transparent solid, with every light outside all of them, casts no shadow
//! rays: each would cross the solid's boundary, which blocks it (that light is the caustic
//! map's). Checked against the same frame with the shortcut off, which traces the rays.

use crate::common;

use caustic::camera::Camera;
use caustic::film::Window;
use caustic::integrator::Settings;
use caustic::scene::build::build_scene;

/// A pool: a diffuse floor and a diffuse block under a closed body of water, a point light
/// above it at `light_y`, a camera looking down through the surface and at a wall above it.
fn pool(light_y: f32) -> String {
    pool_of(light_y, "gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)")
}

/// [`pool`] with the water's material given as Lua.
fn pool_of(light_y: f32, water: &str) -> String {
    format!(
        "stone = gr.material({{0.6, 0.5, 0.4}}, {{0, 0, 0}}, 0)
water = {water}
root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(stone)
floor:scale(4, 0.2, 4); floor:translate(-2, -1.2, -2); root:add_child(floor)
block = gr.cube('block'); block:set_material(stone)
block:scale(0.5, 0.5, 0.5); block:translate(-0.25, -1.0, -0.25); root:add_child(block)
wall = gr.cube('wall'); wall:set_material(stone)
wall:scale(4, 3, 0.2); wall:translate(-2, -1, -2.2); root:add_child(wall)
pool = gr.cube('water'); pool:set_material(water)
pool:scale(3, 0.8, 3); pool:translate(-1.5, -1.0, -1.5); root:add_child(pool)
gr.render(root, 'out.png', 40, 40, {{0, 2, 3}}, {{0, -0.6, -1}}, {{0, 1, 0}}, 50,
          {{0.1, 0.1, 0.1}}, {{gr.light({{0.3, {light_y}, 0.4}}, {{1, 1, 1}}, {{1, 0, 0}})}})
"
    )
}

/// Renders `src` with the course's renderer (centre rays, no photon maps), the shortcut as the
/// scene decides or forced off; returns the pixels and the shadow rays cast.
fn render(src: &str, shortcut: bool) -> (Vec<glam::Vec3A>, u64, bool) {
    let d = common::run_lua(src).unwrap();
    let r = &d.renders[0];
    let mut scene = build_scene(&d, r).unwrap();
    let decided = scene.lights_clear_of_media;
    scene.lights_clear_of_media &= shortcut;
    let camera = Camera::new(&r.camera, r.width, r.height);
    let settings: Settings = common::whitted();
    let (film, stats) = crate::common::render_frame(
        &mut scene,
        &camera,
        Window::full(r.width, r.height),
        &settings,
        &caustic::progress::NoProgress,
    );
    (film.pixels, stats.render.shadow_rays, decided)
}

#[test]
fn points_under_water_cast_no_shadow_rays_and_the_image_is_the_same() {
    let src = pool(2.0);
    let (fast, fast_rays, decided) = render(&src, true);
    let (slow, slow_rays, _) = render(&src, false);
    assert!(decided, "the light is outside the water's bounds");
    // A point light draws no random numbers, so the two frames must agree exactly.
    assert_eq!(fast, slow, "skipping blocked shadow rays changed a pixel");
    // About half the frame looks into the water (922 of 1792 rays are left when written).
    assert!(
        fast_rays * 4 < slow_rays * 3,
        "{fast_rays} shadow rays with the shortcut against {slow_rays} without"
    );
    // The wall above the water is lit, so some rays are still cast and some light arrives.
    assert!(fast_rays > 0);
}

#[test]
fn a_light_inside_the_waters_bounds_keeps_every_shadow_ray() {
    // The light hangs inside the water's box (under its surface): points under water see it.
    let src = pool(-0.5);
    let (fast, fast_rays, decided) = render(&src, true);
    let (slow, slow_rays, _) = render(&src, false);
    assert!(!decided);
    assert_eq!((fast, fast_rays), (slow, slow_rays));
}

#[test]
fn water_that_is_partly_opaque_renders_the_same_frame_with_the_shortcut() {
    // Half-opaque water (t = 0.5, a diffuse kd): paths inside it meet its walls from within and
    // shade their opaque half. Such a point is on the solid's boundary, not inside it; the
    // shortcut leaves it alone (its inward-facing side sees no outside light either way), and
    // the frame must equal the one traced with every shadow ray.
    let src = pool_of(2.0, "gr.material({0.3, 0.5, 0.6}, {0, 0, 0}, 0, 0.5, 1.33)");
    let (fast, fast_rays, decided) = render(&src, true);
    let (slow, slow_rays, _) = render(&src, false);
    assert!(decided);
    assert_eq!(fast, slow, "the shortcut changed a pixel");
    assert!(fast_rays < slow_rays, "{fast_rays} against {slow_rays}");
}
