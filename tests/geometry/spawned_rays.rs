//! Rays spawned the renderer's way (`offset_ray_origin` from `Scene::surface`, directions from
//! the glass BSDF, shadow rays as `Tracer::direct` builds them) from random hits on every
//! primitive kind — sphere, cube, cylinder, cone, meshes, CSG difference, union and intersection,
//! instanced groups — at scales 1e-3 to 1e5 and 1e6 from the origin (pbrt-v4's `Reintersect`,
//! Mitsuba 3's offset tests), each checked against brute force: point-in-solid tests in double
//! precision along the ray.
//!
//! For one spawned ray the reference is the solid's membership along it: the renderer's first
//! hit must be a real boundary crossing (the side changes within [`tolerance`], over the cosine
//! to the normal, after it, and not before it), and a ray the renderer sees hit nothing must not
//! change side at any of [`MARCH`] points up to the scene's edge. For a convex solid this means:
//! the reflected ray and the shadow ray hit nothing, and the refracted ray leaves through the far
//! side at the distance the bisection of membership gives, within the tolerance. Edges where no
//! offset along the normal can clear both faces are counted and bounded ([`Failure::Edge`]).

use crate::common::run_lua;
use caustic::desc::CsgOp;
use caustic::geometry::csg::{CsgNode, CsgTree};
use caustic::geometry::{Analytic, Ray, offset_ray_origin};
use caustic::material::medium::MediumStack;
use caustic::sampling::uniform_sphere;
use caustic::sampling::{Pass, Rng};
use caustic::scene::build::build_scene;
use caustic::scene::interaction::Needs;
use caustic::scene::{Scene, Shape};
use glam::{Affine3A, DMat3, DVec3, Vec3A};
use std::collections::BTreeMap;

/// Primary hits per kind and placement; each spawns three rays (reflected, refracted, shadow).
const HITS: usize = 8000;
/// Membership samples along a spawned ray that the renderer says hits nothing (or before its hit).
const MARCH: usize = 128;

/// Where each kind is placed: (uniform scale, offset of every coordinate from the origin). At 1e6
/// the spacing of `f32` is 0.0625 and the spawn offset 7.6, so objects there are 1e4 and 1e5
/// across (at 1e3 the offset is 0.8% of the object, and the acute rims of the CSG difference
/// thinner than it are 3% of its cavity: no offset along the normal can clear both faces).
const PLACEMENTS: [(f64, f64); 6] = [
    (1e-3, 0.0),
    (1.0, 0.0),
    (1e3, 0.0),
    (1e5, 0.0),
    (1e4, 1e6),
    (1e5, 1e6),
];
/// Largest share of a placement's primary hits whose spawned rays may meet an edge
/// ([`Failure::Edge`]).
const EDGE_SHARE: f64 = 0.005;

/// The glass every kind is made of (index 1.5: a refracted ray goes inside).
const GLASS: &str = "m = gr.material({0.1, 0.1, 0.1}, {0, 0, 0}, 0, 1, 1.5)\n";

/// Returns the scene of `body` (which builds the node `obj`, about 2 units across around the
/// origin) scaled by `scale` and moved by `offset` along each axis.
fn placed(body: &str, scale: f64, offset: f64) -> Scene {
    let src = format!(
        "{GLASS}{body}\n\
         root = gr.node('root'); root:add_child(obj)\n\
         root:scale({scale}, {scale}, {scale}); root:translate({offset}, {offset}, {offset})\n\
         gr.render(root, 'x.png', 4, 4, {{0, 0, 0}}, {{0, 0, -1}}, {{0, 1, 0}}, 50, {{0, 0, 0}},\n\
                   {{gr.light({{0, 0, 0}}, {{1, 1, 1}}, {{1, 0, 0}})}})"
    );
    let d = run_lua(&src).unwrap_or_else(|e| panic!("{e}\n{src}"));
    build_scene(&d, &d.renders[0]).unwrap()
}

/// Returns `a` in double precision.
fn affine(a: &Affine3A) -> (DMat3, DVec3) {
    let m = a.matrix3;
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.as_dvec3());
    (
        DMat3::from_cols(cols[0], cols[1], cols[2]),
        a.translation.as_dvec3(),
    )
}

/// Returns whether the object-space point `q` lies in the closed unit primitive `a`.
fn in_analytic(a: Analytic, q: DVec3) -> bool {
    match a {
        Analytic::Sphere => q.length_squared() <= 1.0,
        Analytic::Cube => q.cmpge(DVec3::ZERO).all() && q.cmple(DVec3::ONE).all(),
        Analytic::Cylinder => q.x * q.x + q.y * q.y <= 1.0 && q.z.abs() <= 1.0,
        Analytic::Cone => q.x * q.x + q.y * q.y <= q.z * q.z && (0.0..=1.0).contains(&q.z),
    }
}

/// Returns whether `q` (the tree's frame) lies in node `id` of a CSG tree.
fn in_csg(tree: &CsgTree, id: u32, q: DVec3) -> bool {
    match &tree.nodes[id as usize] {
        CsgNode::Leaf {
            shape,
            leaf_from_csg,
            ..
        } => {
            let (m, t) = affine(leaf_from_csg);
            in_analytic(*shape, m * q + t)
        }
        CsgNode::Op { op, a, b } => {
            let (a, b) = (in_csg(tree, *a, q), in_csg(tree, *b, q));
            match op {
                CsgOp::Union => a || b,
                CsgOp::Intersection => a && b,
                CsgOp::Difference => a && !b,
            }
        }
    }
}

/// The solid a scene holds, as a point-in-solid test in double precision: every instance's
/// transform (`object_from_world`, the one its rays are moved by) and shape; meshes must be convex.
struct Solid<'a> {
    scene: &'a Scene,
    transforms: Vec<(DMat3, DVec3)>,
    /// Per mesh, a point and an outward normal of each triangle's plane.
    planes: Vec<Vec<(DVec3, DVec3)>>,
}

impl Solid<'_> {
    fn new(scene: &Scene) -> Solid<'_> {
        let planes = scene
            .meshes
            .iter()
            .map(|m| {
                let p: Vec<DVec3> = m.data().positions.iter().map(|v| v.as_dvec3()).collect();
                let centre = p.iter().sum::<DVec3>() / p.len() as f64;
                m.data()
                    .triangles
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|i| p[i as usize]);
                        let n = (b - a).cross(c - a);
                        (a, if n.dot(centre - a) > 0.0 { -n } else { n })
                    })
                    .collect()
            })
            .collect();
        let transforms = scene
            .instances
            .iter()
            .map(|i| affine(&i.object_from_world))
            .collect();
        Solid {
            scene,
            transforms,
            planes,
        }
    }

    /// Returns whether the world-space point `p` lies inside any instance.
    fn contains(&self, p: DVec3) -> bool {
        self.scene
            .instances
            .iter()
            .zip(&self.transforms)
            .any(|(inst, (m, t))| {
                let q = *m * p + *t;
                match inst.shape {
                    Shape::Analytic(a) => in_analytic(a, q),
                    Shape::Mesh(k) => self.planes[k as usize]
                        .iter()
                        .all(|(a, n)| (q - *a).dot(*n) <= 0.0),
                    Shape::Csg(c) => {
                        let tree = &self.scene.csgs[c as usize];
                        in_csg(tree, tree.root, q)
                    }
                }
            })
    }
}

/// Returns how far (world units) a renderer's hit may lie from the true boundary along a ray
/// from `origin`: 2⁻¹⁶ of its largest coordinate (about 128 ulps, twice today's spawn offset)
/// plus 2e-9, fixed here so that a broken offset cannot widen it.
fn tolerance(origin: Vec3A) -> f64 {
    origin.abs().max_element() as f64 / 65536.0 + 2e-9
}

/// Why a spawned ray failed its check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Failure {
    /// Not a failure, but counted and bounded ([`EDGE_SHARE`]): the origin is on the wrong side
    /// yet within the tolerance of the right one, or another boundary is closer than the
    /// tolerance, or the ray grazes a boundary (cosine under 1/8) where the side does not change
    /// within the rounding of a grazing hit. These are edges where the solid is thinner along
    /// the normal than the offset (acute CSG rims) and edges a primary ray only grazed (the
    /// cube's slack, which closes cracks between boxes): no offset along the normal clears both
    /// faces there.
    Edge,
    /// The offset origin is on the wrong side of the surface it leaves, away from any edge.
    WrongSide,
    /// The first hit is the surface the ray left, within the tolerance.
    SelfHit,
    /// The first hit is no boundary: the side does not change there.
    FalseHit,
    /// The renderer missed a boundary the ray crosses (before its hit, or with no hit).
    Missed,
    /// `Scene::occluded` and `Scene::intersect` disagree on a shadow ray.
    AnyHit,
}

/// What the three spawned rays of one kind at one placement did.
#[derive(Default)]
struct Tally {
    spawned: usize,
    /// Refracted rays that passed their check, each with a hit on the far side.
    far_hits: usize,
    /// Rays classified [`Failure::Edge`].
    edges: usize,
    failures: BTreeMap<(Failure, &'static str), usize>,
    example: Option<String>,
}

impl Tally {
    fn note(&mut self, f: Failure, what: &'static str, ray: &Ray) {
        if f == Failure::Edge {
            self.edges += 1;
            return;
        }
        *self.failures.entry((f, what)).or_default() += 1;
        self.example
            .get_or_insert_with(|| format!("{what} {f:?}: {ray:?}"));
    }
}

/// A scene, its solid and the sphere holding it, for spawning and checking rays.
struct Bench<'a> {
    scene: &'a Scene,
    solid: Solid<'a>,
    centre: DVec3,
    radius: f64,
}

impl Bench<'_> {
    /// Returns whether the point `d` units along the unit direction `w` from `o` is inside.
    fn inside_at(&self, o: DVec3, w: DVec3, d: f64) -> bool {
        self.solid.contains(o + w * d)
    }

    /// Returns the distance along `w` from `o` to the first change of side (bisected), if the
    /// ray changes side at one of [`MARCH`] points up to `end`.
    fn first_change(&self, o: DVec3, w: DVec3, start: bool, end: f64) -> Option<f64> {
        let k =
            (1..=MARCH).find(|&k| self.inside_at(o, w, end * k as f64 / MARCH as f64) != start)?;
        let (mut lo, mut hi) = (
            end * (k - 1) as f64 / MARCH as f64,
            end * k as f64 / MARCH as f64,
        );
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.inside_at(o, w, mid) == start {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// Classifies an origin on the wrong side: [`Failure::Edge`] when some point within the
    /// tolerance of it (16 steps along each axis and the normal `ng`, both ways) is on the side
    /// it should be, else [`Failure::WrongSide`].
    fn wrong_side(&self, origin: Vec3A, ng: Vec3A, inside: bool) -> Failure {
        let o = origin.as_dvec3();
        let tol = tolerance(origin);
        let axes = [DVec3::X, DVec3::Y, DVec3::Z, ng.as_dvec3().normalize()];
        let near = axes
            .iter()
            .flat_map(|&a| [a, -a])
            .any(|v| (1..=16).any(|k| self.inside_at(o, v, tol * k as f64 / 16.0) == inside));
        if near {
            Failure::Edge
        } else {
            Failure::WrongSide
        }
    }

    /// Checks one spawned ray whose origin should be inside the solid exactly when `inside`;
    /// `left` names the (instance, prim, face) it leaves and `ng` the normal there. Returns the
    /// distance of its hit, if any, or the failure.
    fn check(
        &self,
        ray: &Ray,
        inside: bool,
        left: (u32, u32, u8),
        ng: Vec3A,
    ) -> Result<Option<f64>, Failure> {
        let o = ray.origin.as_dvec3();
        let len = ray.dir.as_dvec3().length();
        let w = ray.dir.as_dvec3() / len;
        let start = self.solid.contains(o);
        if start != inside {
            return Err(self.wrong_side(ray.origin, ng, inside));
        }
        let end = if ray.tmax.is_finite() {
            ray.tmax as f64 * len
        } else {
            (o - self.centre).length() + self.radius
        };
        let tol = tolerance(ray.origin);
        let reference = self.first_change(o, w, start, end);
        let Some(hit) = self.scene.intersect(ray) else {
            return match reference {
                Some(r) if r < tol => Err(Failure::Edge),
                Some(_) => Err(Failure::Missed),
                None => Ok(None),
            };
        };
        let d = hit.t as f64 * len;
        // Along a grazing ray a boundary is ill-conditioned: its error across the surface over
        // the cosine between the ray and the normal.
        let cos = self
            .scene
            .surface(ray, &hit)
            .ng
            .as_dvec3()
            .normalize()
            .dot(w)
            .abs();
        let reach = tol / cos.max(1e-3);
        // The side must not change before the hit and must change just after it: at one of 64
        // points, else of 4096 (a CSG sliver may be far thinner than the tolerance).
        let changes = |n: usize| {
            (1..=n).any(|k| self.inside_at(o, w, d + reach * k as f64 / n as f64) != start)
        };
        let before = self.inside_at(o, w, (d - reach).max(0.0)) == start;
        if !(before && (changes(64) || changes(4096))) {
            return Err(if (hit.instance, hit.prim, hit.face) == left && d < tol {
                Failure::SelfHit
            } else if cos < 0.125 {
                Failure::Edge
            } else {
                Failure::FalseHit
            });
        }
        if reference.is_some_and(|r| r < d - reach) {
            return Err(Failure::Missed);
        }
        Ok(Some(d))
    }
}

/// Spawns a reflected, a refracted and a shadow ray from each of [`HITS`] primary hits on the
/// scene of `body` at one placement, and tallies their checks.
fn spawn_and_check(body: &str, scale: f64, offset: f64, seed: u64) -> Tally {
    let scene = placed(body, scale, offset);
    let bounds = scene
        .instances
        .iter()
        .fold(caustic::accel::Bounds::EMPTY, |a, i| a.union(i.bounds));
    let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let bench = Bench {
        scene: &scene,
        solid: Solid::new(&scene),
        centre: 0.5 * (lo + hi),
        radius: 0.5 * (hi - lo).length(),
    };
    let mut rng = Rng::new(seed, Pass::Pixel, 0);
    let mut tally = Tally::default();
    let mut hits = 0;
    while hits < HITS {
        // From the sphere of twice the scene's radius towards a random point of its box.
        let u = (rng.next_f32(), rng.next_f32());
        let from = bench.centre + uniform_sphere(u).as_dvec3() * 2.0 * bench.radius;
        let u = DVec3::new(
            rng.next_f32().into(),
            rng.next_f32().into(),
            rng.next_f32().into(),
        );
        let (origin, to) = (from.as_vec3a(), (lo + (hi - lo) * u).as_vec3a());
        let ray = Ray::new(origin, (to - origin).normalize());
        let Some(hit) = scene.intersect(&ray) else {
            continue;
        };
        hits += 1;
        // The directions and origins the eye path uses at glass (`Tracer::dielectric`).
        let left = (hit.instance, hit.prim, hit.face);
        let it = scene.interaction(&ray, &hit, Needs::Full, None);
        let (p, ng) = (it.surf.p, it.bsdf.ng);
        let crossing = it.bsdf.crossing(&MediumStack::air()).unwrap();
        let split = it.bsdf.dielectric(&crossing, (0.0, 0.0));

        let reflected = Ray::new(offset_ray_origin(p, ng, split.reflected), split.reflected);
        if let Err(f) = bench.check(&reflected, false, left, ng) {
            tally.note(f, "reflected", &reflected);
        }
        let wt = split.refracted.expect("air to glass always refracts");
        let refracted = Ray::new(offset_ray_origin(p, ng, wt), wt);
        match bench.check(&refracted, true, left, ng) {
            Err(f) => tally.note(f, "refracted", &refracted),
            Ok(hit) => tally.far_hits += hit.is_some() as usize,
        }

        // A light in the hemisphere the surface faces, one to three scene radii away, and the
        // shadow ray `Tracer::direct` casts to it.
        let mut wi = uniform_sphere((rng.next_f32(), rng.next_f32()));
        if wi.dot(ng) < 0.0 {
            wi = -wi;
        }
        let reach = bench.radius * (1.0 + 2.0 * rng.next_f32() as f64);
        let light = (p.as_dvec3() + wi.as_dvec3() * reach).as_vec3a();
        let from = offset_ray_origin(p, ng, wi);
        let shadow = Ray::new(from, light - from).with_tmax(1.0 - 1e-4);
        match bench.check(&shadow, false, left, ng) {
            Err(f) => tally.note(f, "shadow", &shadow),
            Ok(hit) if hit.is_some() != scene.occluded(&shadow) => {
                tally.note(Failure::AnyHit, "shadow", &shadow)
            }
            Ok(_) => {}
        }
        tally.spawned += 3;
    }
    tally
}

/// Runs every placement of each `(name, body)` kind and asserts that no spawned ray failed, that
/// edges stay under [`EDGE_SHARE`] and that refracted rays hit the far side.
fn assert_kinds(kinds: &[(&str, &str)]) {
    let mut report = Vec::new();
    let mut spawned = 0;
    for (k, (name, body)) in kinds.iter().enumerate() {
        for (j, &(scale, offset)) in PLACEMENTS.iter().enumerate() {
            let t = spawn_and_check(body, scale, offset, (k * 16 + j) as u64);
            spawned += t.spawned;
            let edge_limit = (EDGE_SHARE * HITS as f64) as usize;
            if !t.failures.is_empty() || t.edges > edge_limit || t.far_hits + t.edges < HITS {
                report.push(format!(
                    "{name} at scale {scale}, offset {offset}: {:?}, {} edges (limit {edge_limit}), \
                     {} far hits of {HITS}, {} rays, e.g. {}",
                    t.failures,
                    t.edges,
                    t.far_hits,
                    t.spawned,
                    t.example.unwrap_or_default()
                ));
            }
        }
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
    assert_eq!(spawned, kinds.len() * PLACEMENTS.len() * 3 * HITS);
}

/// A unit sphere, a rotated unit cube, cylinder and cone, each about 2 across around the origin.
const ANALYTIC: [(&str, &str); 4] = [
    ("sphere", "obj = gr.sphere('obj'); obj:set_material(m)"),
    (
        "cube",
        "obj = gr.cube('obj'); obj:set_material(m); obj:translate(-0.5, -0.5, -0.5)\n\
         obj:scale(1.8, 1.8, 1.8); obj:rotate('y', 30); obj:rotate('x', 20)",
    ),
    (
        "cylinder",
        "obj = gr.cylinder('obj'); obj:set_material(m); obj:rotate('x', 70); obj:rotate('z', 15)",
    ),
    (
        "cone",
        "obj = gr.cone('obj'); obj:set_material(m); obj:translate(0, 0, -0.5)\n\
         obj:scale(1, 1, 2); obj:rotate('x', -100); obj:rotate('y', 40)",
    ),
];

/// Reflected, refracted and shadow rays from 8000 hits on each analytic primitive at 6 placements
/// (576k rays) never re-hit their surface, cast no false shadow and leave through the far side
/// where brute force says (convex: the outgoing rays hit nothing): the spawn offset must beat the
/// rounding of hits computed in `f32` world space from `f64` object-space roots.
#[test]
fn analytic_primitives_spawn_rays_without_self_hits() {
    assert_kinds(&ANALYTIC);
}

/// The vertex and face lists of a regular octahedron of radius 1, as `gr.mesh` takes them.
macro_rules! octahedron {
    () => {
        "{{1,0,0}, {-1,0,0}, {0,1,0}, {0,-1,0}, {0,0,1}, {0,0,-1}},\n\
         {{0,2,4}, {2,1,4}, {1,3,4}, {3,0,4}, {2,0,5}, {1,2,5}, {3,1,5}, {0,3,5}}"
    };
}

/// A regular octahedron (slanted faces) and a box of 12 triangles (coplanar pairs meeting along
/// diagonals), both convex.
const MESHES: [(&str, &str); 2] = [
    (
        "octahedron",
        concat!(
            "obj = gr.mesh('obj', ",
            octahedron!(),
            ")\nobj:set_material(m); obj:rotate('z', 25); obj:rotate('x', 10)"
        ),
    ),
    (
        "box mesh",
        "obj = gr.mesh('obj', {{-1,-1,-1}, {1,-1,-1}, {1,1,-1}, {-1,1,-1},\n\
                               {-1,-1,1}, {1,-1,1}, {1,1,1}, {-1,1,1}},\n\
           {{0,2,1}, {0,3,2}, {4,5,6}, {4,6,7}, {0,1,5}, {0,5,4},\n\
            {2,3,7}, {2,7,6}, {1,2,6}, {1,6,5}, {0,4,7}, {0,7,3}})\n\
         obj:set_material(m); obj:scale(0.9, 0.7, 0.8); obj:rotate('y', 35)",
    ),
];

/// Spawned rays from 8000 hits on each of two convex meshes at 6 placements (288k rays) never
/// re-hit their triangle nor miss the far face: a hit is interpolated from the corners, whose
/// plane the offset must clear at every scale, and a ray leaving near an edge must not hit the
/// neighbour (this caught the mesh BVH's absolute slab epsilon at scale 1e5).
#[test]
fn mesh_triangles_spawn_rays_without_self_hits() {
    assert_kinds(&MESHES);
}

/// A box with a spherical cavity that opens through its faces (not convex), two overlapping
/// spheres (not convex) and a box rounded by a sphere (convex), each rotated.
const CSG: [(&str, &str); 3] = [
    (
        "difference",
        "a = gr.cube('a'); a:translate(-0.5, -0.5, -0.5); a:scale(1.6, 1.6, 1.6); a:set_material(m)\n\
         b = gr.sphere('b'); b:set_material(m)\n\
         obj = gr.difference('obj', a, b); obj:rotate('y', 20); obj:rotate('x', 35)",
    ),
    (
        "union",
        "a = gr.nh_sphere('a', {-0.35, 0, 0}, 0.6); a:set_material(m)\n\
         b = gr.nh_sphere('b', {0.35, 0.1, 0}, 0.55); b:set_material(m)\n\
         obj = gr.union('obj', a, b); obj:rotate('z', 30)",
    ),
    (
        "intersection",
        "a = gr.cube('a'); a:translate(-0.5, -0.5, -0.5); a:scale(1.6, 1.6, 1.6); a:set_material(m)\n\
         b = gr.sphere('b'); b:set_material(m)\n\
         obj = gr.intersection('obj', a, b); obj:rotate('y', -25); obj:rotate('z', 10)",
    ),
];

/// Spawned rays from 8000 hits on each CSG operation at 6 placements (432k rays) never re-hit
/// their boundary, and rays into a cavity see its far wall where the membership test does:
/// CSG merges boundaries closer than its own tolerance, which must not swallow a real one.
#[test]
fn csg_solids_spawn_rays_without_self_hits() {
    assert_kinds(&CSG);
}

/// A group of a cylinder and an octahedron placed twice, by a rotation with a non-uniform scale
/// and by a rotation alone.
const INSTANCES: [(&str, &str); 1] = [(
    "instances",
    concat!(
        "g = gr.node('g')\n\
         c = gr.cylinder('c'); c:set_material(m); c:scale(0.3, 0.3, 0.4); c:translate(0, -0.4, 0)\n\
         g:add_child(c)\n\
         o = gr.mesh('o', ",
        octahedron!(),
        ")\n\
         o:set_material(m); o:scale(0.3, 0.3, 0.3); o:translate(0, 0.5, 0); g:add_child(o)\n\
         obj = gr.node('obj')\n\
         a = gr.node('a'); a:scale(1.5, 0.7, 1.2); a:rotate('z', 35); a:translate(-0.6, 0, 0)\n\
         a:add_child(g); obj:add_child(a)\n\
         b = gr.node('b'); b:rotate('x', 60); b:translate(0.6, 0, 0.2); b:add_child(g); obj:add_child(b)"
    ),
)];

/// Spawned rays from 8000 hits on a twice-instanced group at 6 placements (144k rays) never
/// re-hit their surface: the ray is moved into object space by a sheared transform without
/// renormalising, so the offset, chosen in world space, must survive the transform.
#[test]
fn instanced_groups_spawn_rays_without_self_hits() {
    assert_kinds(&INSTANCES);
}

/// The refracted ray that `mesh_triangles_spawn_rays_without_self_hits` found missing the box
/// mesh's far face at scale 1e5 and 1e6 from the origin hits it at the distance of the
/// brute-force triangle test: the mesh BVH's slab test clamped object-space direction components
/// below `f32::EPSILON` (absolute), and an instance scaled by 1e5 has them all below 1e-4.
#[test]
fn box_mesh_far_face_is_hit_from_inside_at_scale_1e5_offset_1e6() {
    let scene = placed(MESHES[1].1, 1e5, 1e6);
    let origin = Vec3A::new(1031488.3, 931773.44, 888073.44);
    let ray = Ray::new(origin, Vec3A::new(-0.29622522, -0.0030437936, 0.9551133));
    let inst = &scene.instances[0];
    let (local, mesh) = (
        Ray::new(
            inst.object_from_world.transform_point3a(ray.origin),
            inst.object_from_world.transform_vector3a(ray.dir),
        ),
        &scene.meshes[0],
    );
    let shear = caustic::geometry::triangle::RayShear::new(&local);
    let brute = (0..mesh.len() as u32)
        .filter_map(|i| {
            let [a, b, c] = mesh.corners(i);
            caustic::geometry::triangle::intersect(&shear, a, b, c, 0.0, f32::INFINITY)
        })
        .map(|h| h.t)
        .fold(f32::INFINITY, f32::min);
    assert!((brute - 227_698.6).abs() < 1.0, "{brute}");
    let hit = scene.intersect(&ray).expect("the far face is missed");
    assert_eq!(hit.t, brute);
}
