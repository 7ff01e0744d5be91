//! Coincident and touching faces between different objects: water resting on a floor, glass
//! resting on water, a glass ball touching the water surface, thin walls that meet only along an
//! edge. Each object is watertight alone; the hard part is the tie between two objects' surfaces
//! at the same `t` and the crack along a shared edge.

use crate::common::{render_films_with, run_lua, whitted};
use caustic::camera::Camera;
use caustic::scene::build::build_scene;
use glam::Vec3A;
use std::path::Path;

/// A floor slab and a water box (index 1.33, bottom face at y = 0) standing on it, seen from
/// above at a slant; the floor's top face is at `floor_top`.
fn water_scene(floor_top: f64, size: u32) -> String {
    format!(
        "white = gr.material({{0.7, 0.7, 0.7}}, {{0, 0, 0}}, 0)\n\
         water_m = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.33)\n\
         root = gr.node('root')\n\
         floor = gr.cube('floor'); floor:scale(8, 1, 8); floor:translate(-4, {floor_top} - 1, -4)\n\
         floor:set_material(white); root:add_child(floor)\n\
         water = gr.cube('water'); water:scale(6, 0.5, 6); water:translate(-3, 0, -3)\n\
         water:set_material(water_m); root:add_child(water)\n\
         gr.render(root, 'w.png', {size}, {size}, {{0, 1.5, 0.8}}, {{0, -1.5, -0.5}}, {{0, 1, 0}}, 50,\n\
                   {{0.3, 0.3, 0.3}}, {{gr.light({{0.5, 3, 0.5}}, {{1, 1, 1}}, {{1, 0, 0}})}})\n"
    )
}

/// Returns the `size²` pixels of the first image the script renders (the course's renderer).
fn pixels(src: &str) -> (u32, Vec<Vec3A>) {
    let films = render_films_with(src.as_bytes(), "w.lua", Path::new("."), &whitted()).unwrap();
    let (r, _, film) = films.into_iter().next().unwrap();
    let px = (0..r.height)
        .flat_map(|y| (0..r.width).map(move |x| (x, y)))
        .map(|(x, y)| film.get(x, y))
        .collect();
    (r.width, px)
}

/// The floor seen through water standing exactly on it looks like a floor raised 1e-3 into the
/// water (no tie): every pixel within 0.02 (the coincident faces tie at the same `t`, and
/// whichever won by rounding gave black or white speckle). 48² pixels, one ray each.
#[test]
fn water_on_the_floor_matches_a_floor_just_inside_the_water() {
    let (size, touching) = pixels(&water_scene(0.0, 48));
    let (_, lifted) = pixels(&water_scene(1e-3, 48));
    assert_within(&touching, &lifted, size, "water");
}

/// Asserts that images `a` and `b` (`size²` pixels) differ by at most 0.02 in every channel of
/// every pixel; `what` names the case in the message.
fn assert_within(a: &[Vec3A], b: &[Vec3A], size: u32, what: &str) {
    let bad: Vec<(usize, Vec3A, Vec3A)> = a
        .iter()
        .zip(b)
        .enumerate()
        .filter(|(_, (a, b))| (**a - **b).abs().max_element() > 0.02)
        .map(|(i, (a, b))| (i, *a, *b))
        .collect();
    assert!(
        bad.is_empty(),
        "{what}: {} of {} pixels differ by more than 0.02, e.g. (index, touching, reference) {:?}",
        bad.len(),
        size * size,
        &bad[..bad.len().min(5)]
    );
}

/// Every camera ray of a 256² image from inside a room of thin wall slabs that touch only along
/// their edges hits a wall (rays aimed at a shared edge fell between the two slabs by rounding:
/// each slab's own slab test put the point just outside it). Three placements of the room, from
/// unit size at the origin to size 100 at an offset of 1e3.
#[test]
fn thin_walls_touching_along_an_edge_leave_no_crack() {
    for (scale, offset) in [
        (1.0, [0.0; 3]),
        (0.01, [0.3, -0.2, 0.1]),
        (100.0, [1e3, -500.0, 300.0]),
    ] {
        let [ox, oy, oz] = offset;
        let src = format!(
            "m = gr.material({{0.7, 0.7, 0.7}}, {{0, 0, 0}}, 0)\n\
             room = gr.node('room')\n\
             function slab(name, sx, sy, sz, tx, ty, tz)\n\
               local s = gr.cube(name); s:scale(sx, sy, sz); s:translate(tx, ty, tz)\n\
               s:set_material(m); room:add_child(s)\n\
             end\n\
             -- Floor, ceiling, back, left and right: each meets its neighbours along one edge only.\n\
             slab('floor', 2, 0.1, 2, -1, -1.1, -1)\n\
             slab('ceiling', 2, 0.1, 2, -1, 1, -1)\n\
             slab('back', 2, 2, 0.1, -1, -1, -1.1)\n\
             slab('left', 0.1, 2, 2, -1.1, -1, -1)\n\
             slab('right', 0.1, 2, 2, 1, -1, -1)\n\
             root = gr.node('root'); root:add_child(room)\n\
             room:scale({scale}, {scale}, {scale}); room:translate({ox}, {oy}, {oz})\n\
             gr.render(root, 'r.png', 256, 256, {{{cx}, {cy}, {cz}}}, {{0, 0, -1}}, {{0, 1, 0}}, 40,\n\
                       {{0, 0, 0}}, {{gr.light({{0, 0, 0}}, {{1, 1, 1}}, {{1, 0, 0}})}})\n",
            cx = ox,
            cy = oy,
            cz = oz + 3.5 * scale,
        );
        let desc = run_lua(&src).unwrap();
        let r = &desc.renders[0];
        let scene = build_scene(&desc, r).unwrap();
        let camera = Camera::new(&r.camera, r.width, r.height);
        let misses: Vec<(u32, u32)> = (0..r.height)
            .flat_map(|y| (0..r.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                // Rays through the open front (the plane z = 1 in the room's frame) must hit a wall.
                let s = (oz as f32 + scale as f32 - ray.origin.z) / ray.dir.z;
                let q = (ray.at(s) - Vec3A::new(ox as f32, oy as f32, 0.0)) / scale as f32;
                q.x.abs() < 1.0 && q.y.abs() < 1.0 && scene.intersect(&ray).is_none()
            })
            .collect();
        assert!(
            misses.is_empty(),
            "room at scale {scale}, offset {offset:?}: {} of 65536 camera rays see the background, e.g. {:?}",
            misses.len(),
            &misses[..misses.len().min(5)]
        );
    }
}

/// A white floor, a water box (index 1.33, top face at y = 0.5) standing on it and `glass`
/// (a Lua snippet making the node `glass` of index 1.5), seen from above at a slant through the
/// point (0, 0.5, 0) on the water's top with a field of view of `fov` degrees.
fn glass_and_water_scene(glass: &str, fov: f64) -> String {
    format!(
        "white = gr.material({{0.7, 0.7, 0.7}}, {{0, 0, 0}}, 0)\n\
         water_m = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.33)\n\
         glass_m = gr.material({{0, 0, 0}}, {{0, 0, 0}}, 0, 1, 1.5)\n\
         root = gr.node('root')\n\
         floor = gr.cube('floor'); floor:scale(8, 1, 8); floor:translate(-4, -1, -4)\n\
         floor:set_material(white); root:add_child(floor)\n\
         water = gr.cube('water'); water:scale(6, 0.5, 6); water:translate(-3, 0, -3)\n\
         water:set_material(water_m); root:add_child(water)\n\
         {glass}\n\
         glass:set_material(glass_m); root:add_child(glass)\n\
         gr.render(root, 'g.png', 48, 48, {{0, 2.2, 2.0}}, {{0, -1.7, -2.0}}, {{0, 1, 0}}, {fov},\n\
                   {{0.3, 0.3, 0.3}}, {{gr.light({{0.5, 4, 0.5}}, {{1, 1, 1}}, {{1, 0, 0}})}})\n"
    )
}

/// Asserts that the 48² images of `glass` placed by `touching` and by `reference` (a Lua
/// snippet each) differ by at most 0.02 in every pixel, at each field of view in `fovs`.
fn assert_same_images(touching: &str, reference: &str, fovs: &[f64]) {
    for &fov in fovs {
        let (size, a) = pixels(&glass_and_water_scene(touching, fov));
        let (_, b) = pixels(&glass_and_water_scene(reference, fov));
        assert_within(&a, &b, size, &format!("field of view {fov}"));
    }
}

/// A glass cube resting on a water box's top face looks like the cube sunk 1e-4 into the water:
/// every one of 48² pixels within 0.02 (both faces tie at the same `t`; a ray leaving one was
/// spawned past the other, so it saw glass to air, total reflection, or glass going on under
/// water: 352 pixels differed).
#[test]
fn glass_cube_resting_on_water_matches_a_cube_sunk_just_into_it() {
    let cube = |sink: f64| {
        format!(
            "glass = gr.cube('glass'); glass:translate(-0.5, {}, -0.5)",
            0.5 - sink
        )
    };
    assert_same_images(&cube(0.0), &cube(1e-4), &[50.0]);
}

/// A glass ball under water touching the water surface from below looks like the ball 1e-4
/// lower: 48² pixels within 0.02, once for the whole scene and once for a 1° view of the point
/// of contact (where the film of water between the surfaces is thinner than the spawn offset:
/// 8 of its pixels differed).
#[test]
fn glass_ball_touching_the_water_surface_from_below_matches_a_ball_just_under_it() {
    let ball = |sink: f64| {
        format!(
            "glass = gr.nh_sphere('glass', {{0, {}, 0}}, 0.4)",
            0.1 - sink
        )
    };
    assert_same_images(&ball(0.0), &ball(1e-4), &[50.0, 1.0]);
}
