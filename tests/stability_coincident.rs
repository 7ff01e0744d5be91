//! Coincident and touching faces between different objects: water resting on a floor, thin
//! walls that meet only along an edge. Each object is watertight alone; the hard part is the
//! tie between two objects' surfaces at the same `t` and the crack along a shared edge.

mod common;

use caustic::camera::Camera;
use caustic::scene::build::build_scene;
use common::{render_films_with, run_lua, whitted};
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
    let bad: Vec<(usize, Vec3A, Vec3A)> = touching
        .iter()
        .zip(&lifted)
        .enumerate()
        .filter(|(_, (a, b))| (**a - **b).abs().max_element() > 0.02)
        .map(|(i, (a, b))| (i, *a, *b))
        .collect();
    assert!(
        bad.is_empty(),
        "{} of {} pixels differ by more than 0.02, e.g. (index, touching, lifted) {:?}",
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
