//! Spawned rays never re-hit the surface they leave, on every primitive kind (CSG and instanced
//! meshes included) and at scene scales from 1e-3 to 1e5.

use crate::common::run_lua;
use caustic::geometry::Analytic;
use caustic::geometry::{Ray, offset_ray_origin};
use caustic::scene::build::build_scene;
use caustic::scene::{Scene, Shape};
use glam::Vec3A;

/// A small deterministic random stream (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn direction(&mut self) -> Vec3A {
        let z = 1.0 - 2.0 * self.next();
        let phi = std::f32::consts::TAU * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// One of every primitive kind, spread over about 10 units, then scaled by `scale` and moved
/// 3·scale away from the origin (so coordinates are not all near zero).
fn scene_at(scale: f64) -> Scene {
    let src = format!(
        "m = gr.material({{1,1,1}}, {{0,0,0}}, 0)\n\
         root = gr.node('root')\n\
         s = gr.nh_sphere('s', {{-3, 0, 0}}, 1.3); s:set_material(m); root:add_child(s)\n\
         b = gr.cube('b'); b:set_material(m); b:rotate('y', 30); b:translate(0, -0.5, -3); root:add_child(b)\n\
         c = gr.cylinder('c'); c:set_material(m); c:rotate('x', 70); c:translate(3, 0, 0); root:add_child(c)\n\
         k = gr.cone('k'); k:set_material(m); k:scale(1.5, 1.5, 2); k:rotate('x', -100); k:translate(0, -3, 0); root:add_child(k)\n\
         k1 = gr.cube('k1'); k1:set_material(m); k1:translate(-0.5, -0.5, -0.5); k1:scale(1.6, 1.6, 1.6)\n\
         k2 = gr.sphere('k2'); k2:set_material(m)\n\
         csg = gr.difference('csg', k1, k2); csg:translate(0, 0, 3); root:add_child(csg)\n\
         octa = gr.mesh('octa', {{{{1,0,0}}, {{-1,0,0}}, {{0,1,0}}, {{0,-1,0}}, {{0,0,1}}, {{0,0,-1}}}},\n\
           {{{{0,2,4}}, {{2,1,4}}, {{1,3,4}}, {{3,0,4}}, {{2,0,5}}, {{1,2,5}}, {{3,1,5}}, {{0,3,5}}}})\n\
         octa:set_material(m)\n\
         for i = 0, 1 do\n\
           n = gr.node('inst' .. i); n:rotate('z', 20 + 40 * i); n:translate(-2 + 4 * i, 3, 0)\n\
           n:add_child(octa); root:add_child(n)\n\
         end\n\
         root:scale({scale}, {scale}, {scale}); root:translate({t}, {t}, {t})\n\
         gr.render(root, 'x.png', 4, 4, {{0,0,0}}, {{0,0,-1}}, {{0,1,0}}, 50, {{0,0,0}}, {{gr.light({{0,0,0}}, {{1,1,1}}, {{1,0,0}})}})",
        t = 3.0 * scale
    );
    let d = run_lua(&src).unwrap();
    build_scene(&d, &d.renders[0]).unwrap()
}

/// Spawns two rays from each of `primaries` hits (one to each side) and returns (spawned, re-hits).
///
/// A re-hit is a hit on the same surface (instance, triangle, face and normal) within 1e-4 of the
/// scene's scale: leaving a surface near an edge may legitimately hit the *other* face at once.
fn spawn_from_hits(scale: f32, primaries: usize, seed: u64) -> (usize, usize) {
    let scene = scene_at(scale as f64);
    let centre = Vec3A::splat(3.0 * scale);
    let mut rng = Rng(seed);
    let (mut spawned, mut rehits) = (0, 0);
    let mut kinds = [0usize; 6];
    for _ in 0..primaries {
        // From a sphere of radius 20 around the scene towards a random point inside it.
        let origin = centre + rng.direction() * 20.0 * scale;
        let target = centre
            + Vec3A::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 10.0 * scale;
        let ray = Ray::new(origin, (target - origin).normalize());
        let Some(hit) = scene.intersect(&ray) else {
            continue;
        };
        let surf = scene.surface(&ray, &hit);
        kinds[match scene.instances[hit.instance as usize].shape {
            Shape::Analytic(Analytic::Sphere) => 0,
            Shape::Analytic(Analytic::Cube) => 1,
            Shape::Analytic(Analytic::Cylinder) => 2,
            Shape::Mesh(_) => 3,
            Shape::Csg(_) => 4,
            Shape::Analytic(Analytic::Cone) => 5,
        }] += 1;
        for side in [1.0f32, -1.0] {
            let mut w = rng.direction();
            if w.dot(surf.ng) * side < 0.0 {
                w = -w;
            }
            let spawn = Ray::new(offset_ray_origin(surf.p, surf.ng, w), w);
            spawned += 1;
            if let Some(h2) = scene.intersect(&spawn)
                && h2.instance == hit.instance
                && h2.prim == hit.prim
                && h2.face == hit.face
                && scene.surface(&spawn, &h2).ng.dot(surf.ng) > 0.999
                && h2.t < 1e-4 * scale
            {
                rehits += 1;
            }
        }
    }
    assert!(
        kinds.iter().all(|&k| k > primaries / 100),
        "every kind must be hit often: {kinds:?}"
    );
    (spawned, rehits)
}

#[test]
fn spawned_rays_never_rehit_their_surface_at_any_scale() {
    let mut total = 0;
    for (k, scale) in [1e-3f32, 1.0, 1e5].into_iter().enumerate() {
        let (spawned, rehits) = spawn_from_hits(scale, 900_000, 17 + k as u64);
        assert_eq!(
            rehits, 0,
            "scale {scale}: {rehits} of {spawned} spawned rays re-hit their surface"
        );
        total += spawned;
    }
    assert!(total >= 1_000_000, "only {total} rays spawned");
}
