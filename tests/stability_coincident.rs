//! Coincident and touching faces between different objects: water resting on a floor, thin
//! walls that meet only along an edge. Each object is watertight alone; the hard part is the
//! tie between two objects' surfaces at the same `t` and the crack along a shared edge.

mod common;

use caustic::camera::Camera;
use caustic::scene::build::build_scene;
use common::run_lua;
use glam::Vec3A;

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
