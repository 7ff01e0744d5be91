//! Per-ray queries on a built [`Scene`]: the closest hit ([`Scene::intersect`]), any hit
//! ([`Scene::occluded`]) and the world-space surface at a hit ([`Scene::surface`]).
//!
//! Traversal returns values or `Option`, never `Result`: the scene was checked when it was built.
//! A ray reaching an instance is moved into its object space (not renormalised, so `t` carries
//! over) and tested against the instance's [`Shape`]; every `match` names each shape.

use crate::accel::Bounds;
use crate::geometry::csg::CsgNode;
use crate::geometry::hit::{Hit, SurfaceHit};
use crate::geometry::triangle;
use crate::geometry::uv::{analytic_dpdu, analytic_uv};
use crate::geometry::{Analytic, Interval, Ray, spawn_offset};
use crate::material::bsdf::Touching;
use crate::scene::types::{Instance, Scene, Shape};
use glam::{Vec2, Vec3A};

impl Scene {
    /// Returns the closest hit with `t` in the ray's `(tmin, tmax)`.
    ///
    /// Where an opaque surface and a transparent one coincide within rounding (water resting on
    /// a floor, glass against a wall), the opaque one wins: the ray meets the floor through the
    /// water, instead of leaving the water through its bottom face into the floor's interior, or
    /// one or the other by the rounding of each pixel (speckle). A transparent surface's hit is
    /// ranked as if it were [`tie_slack`] further away.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        crate::accel::counters::ray();
        let mut best = None;
        let slack = tie_slack(ray);
        self.tlas.closest(ray, |r, i| {
            let Some(h) = self.hit_instance(i, r) else {
                return f32::INFINITY;
            };
            let transparent = self.materials[h.material as usize].transparency > 0.0;
            let rank = if transparent { h.t + slack(h.t) } else { h.t };
            if rank < r.tmax {
                best = Some(h);
                rank
            } else {
                f32::INFINITY
            }
        });
        best
    }

    /// Returns true when anything lies on the ray within `(tmin, tmax)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        crate::accel::counters::ray();
        self.tlas.any(ray, |r, i| {
            let inst = &self.instances[i];
            match inst.shape {
                Shape::Mesh(m) => {
                    let local = object_ray(inst, r);
                    self.meshes[m as usize]
                        .any_hit(&local)
                        .unwrap_or(f32::INFINITY)
                }
                Shape::Analytic(_) | Shape::Csg(_) => {
                    self.hit_instance(i, r).map_or(f32::INFINITY, |h| h.t)
                }
            }
        })
    }

    /// Returns the surface of another transparent solid within the tie slack ([`tie_slack`]) of
    /// `hit` on `ray`, where two transparent solids touch (glass resting on water, a ball
    /// touching the water surface), if any.
    pub fn touching(&self, ray: &Ray, hit: &Hit) -> Option<Touching> {
        let slack = tie_slack(ray)(hit.t);
        let window = Ray {
            tmin: hit.t - slack,
            tmax: hit.t + slack,
            ..*ray
        };
        // The window spans points within `reach` of the hit: no other transparent solid whose
        // bounds, grown by it, miss the hit point can be found (most hits: a water surface far
        // from the glass in it). The margin covers the rounding of the points themselves.
        let p = ray.at(hit.t);
        let reach = slack * ray.dir.length() * 1.01 + 1e-6 * (1.0 + p.abs().max_element());
        let near = |b: &Bounds| {
            (p.cmpge(b.min - Vec3A::splat(reach)) & p.cmple(b.max + Vec3A::splat(reach))).all()
        };
        if !self
            .transparent
            .iter()
            .any(|(i, b)| *i != hit.instance && near(b))
        {
            return None;
        }
        let mut found = None;
        self.tlas.closest(&window, |r, i| {
            if i == hit.instance as usize || !self.transparent.iter().any(|t| t.0 as usize == i) {
                return f32::INFINITY;
            }
            let Some(h) = self.hit_instance(i, r) else {
                return f32::INFINITY;
            };
            let m = &self.materials[h.material as usize];
            if m.transparency <= 0.0 {
                return f32::INFINITY;
            }
            found = Some(Touching {
                material_id: h.material,
                ior: m.ior,
                entering: self.enters(i, r, &h),
            });
            h.t
        });
        found
    }

    /// Returns whether `r` crosses the surface of instance `i` at `h` against its outward normal
    /// (for a mesh, the triangle's winding, as the BSDF's front side is).
    pub(super) fn enters(&self, i: usize, r: &Ray, h: &Hit) -> bool {
        let inst = &self.instances[i];
        let normal = match inst.shape {
            Shape::Mesh(m) => {
                let mesh = &self.meshes[m as usize];
                let [a, b, c] = mesh.corners(h.prim);
                (b - a).cross(c - a)
            }
            Shape::Analytic(_) | Shape::Csg(_) => h.normal,
        };
        // The sign of d·n is the same in object space: normals transform by the inverse transpose.
        inst.object_from_world.transform_vector3a(r.dir).dot(normal) < 0.0
    }

    pub(super) fn hit_instance(&self, i: usize, r: &Ray) -> Option<Hit> {
        let inst = &self.instances[i];
        let local = object_ray(inst, r);
        let analytic = |iv: Option<Interval>| {
            let c = iv?.first_in(r.tmin, r.tmax)?;
            Some(Hit {
                t: c.t as f32,
                instance: i as u32,
                prim: 0,
                b1: 0.0,
                b2: 0.0,
                normal: c.normal,
                material: inst.material,
                face: c.face,
            })
        };
        let hit = match inst.shape {
            Shape::Analytic(a) => {
                let size = crate::geometry::origin_size(&inst.object_from_world, r.origin);
                analytic(a.interval(local.origin, local.dir, size))
            }
            Shape::Mesh(m) => self.meshes[m as usize]
                .intersect(&local)
                .map(|(tri, h)| Hit {
                    material: if inst.mesh_materials {
                        self.meshes[m as usize].materials[tri as usize]
                    } else {
                        inst.material
                    },
                    t: h.t,
                    instance: i as u32,
                    prim: tri,
                    b1: h.b1,
                    b2: h.b2,
                    normal: Vec3A::ZERO,
                    face: 0,
                }),
            Shape::Csg(c) => self.csgs[c as usize]
                .first_hit(local.origin, local.dir, r.tmin, r.tmax)
                .map(|b| Hit {
                    t: b.t as f32,
                    instance: i as u32,
                    prim: b.leaf,
                    b1: 0.0,
                    b2: 0.0,
                    normal: b.normal,
                    material: b.material,
                    face: b.face,
                }),
        }?;
        // Rounding f64 to f32 must not move a hit outside the ray's range.
        (hit.t > r.tmin && hit.t < r.tmax).then_some(hit)
    }

    /// Returns the world-space surface at `hit`, found by `ray`.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let inst = &self.instances[hit.instance as usize];
        let local = object_ray(inst, ray);
        let perlin = self.materials[hit.material as usize].perlin_scale > 0.0;
        let (p_obj, ng_obj, ns_obj, uv, dpdu) = match inst.shape {
            Shape::Mesh(m) => {
                let mesh = &self.meshes[m as usize];
                let idx = mesh.triangle(hit.prim);
                let data = mesh.data();
                let [v0, v1, v2] = idx.map(|i| Vec3A::from(data.positions[i as usize]));
                let w0 = 1.0 - hit.b1 - hit.b2;
                // The hit's barycentric mix of a vertex attribute.
                let mix = |[a, b, c]: [Vec3A; 3]| a * w0 + b * hit.b1 + c * hit.b2;
                let p = mix([v0, v1, v2]);
                let ng = triangle::geometric_normal(v0, v1, v2);
                // Perlin noise needs a continuous base normal: smooth normals when the file has none.
                let ns = if !data.normals.is_empty() {
                    mix(idx.map(|i| Vec3A::from(data.normals[i as usize])))
                } else if perlin {
                    let normals = mesh.smooth_normals();
                    mix(idx.map(|i| normals[i as usize]))
                } else {
                    ng
                };
                let [t0, t1, t2] = if data.uvs.is_empty() {
                    [Vec2::ZERO, Vec2::X, Vec2::Y]
                } else {
                    idx.map(|i| data.uvs[i as usize])
                };
                let uv = t0 * w0 + t1 * hit.b1 + t2 * hit.b2;
                (p, ng, ns, uv, triangle_dpdu([v0, v1, v2], [t0, t1, t2]))
            }
            Shape::Analytic(Analytic::Sphere) => {
                // Re-project onto the sphere: the hit point's error then no longer grows with t.
                let p = local.at(hit.t);
                let p = p / p.length();
                let (uv, dpdu) = (
                    analytic_uv(Analytic::Sphere, p, hit.face),
                    analytic_dpdu(Analytic::Sphere, p, 0),
                );
                (p, p, p, uv, dpdu)
            }
            Shape::Csg(c) => {
                let p = local.at(hit.t);
                let (uv, dpdu) = match &self.csgs[c as usize].nodes[hit.prim as usize] {
                    CsgNode::Leaf {
                        shape,
                        leaf_from_csg,
                        ..
                    } => {
                        let q = leaf_from_csg.transform_point3a(p);
                        let t =
                            leaf_from_csg.matrix3.inverse() * analytic_dpdu(*shape, q, hit.face);
                        (analytic_uv(*shape, q, hit.face), t)
                    }
                    CsgNode::Op { .. } => (Vec2::ZERO, Vec3A::ZERO),
                };
                (p, hit.normal, hit.normal, uv, dpdu)
            }
            Shape::Analytic(leaf @ (Analytic::Cube | Analytic::Cylinder | Analytic::Cone)) => {
                let p = local.at(hit.t);
                let (uv, dpdu) = (
                    analytic_uv(leaf, p, hit.face),
                    analytic_dpdu(leaf, p, hit.face),
                );
                (p, hit.normal, hit.normal, uv, dpdu)
            }
        };
        let p = inst.world_from_object.transform_point3a(p_obj);
        let ng = (inst.normal_to_world * ng_obj).normalize_or_zero();
        let ng = if ng == Vec3A::ZERO {
            -ray.dir.normalize()
        } else {
            ng
        };
        let mut ns = (inst.normal_to_world * ns_obj).normalize_or_zero();
        if ns == Vec3A::ZERO {
            ns = ng;
        } else if ns.dot(ng) < 0.0 {
            // Vertex normals wound against the faces: keep the shading normal on ng's side.
            ns = -ns;
        }
        SurfaceHit {
            p,
            ng,
            ns,
            uv,
            dpdu: inst.world_from_object.transform_vector3a(dpdu),
            material: hit.material,
        }
    }
}

/// Returns, as a function of `t`, how far apart in `t` two surfaces along `ray` may be and still
/// count as one place: twice the spawn offset ([`spawn_offset`]) at the hit point, which bounds
/// the rounding of a computed hit.
fn tie_slack(ray: &Ray) -> impl Fn(f32) -> f32 {
    let (origin, len) = (ray.origin.abs().max_element(), ray.dir.length());
    let reach = ray.dir.abs().max_element();
    move |t| 2.0 * spawn_offset(origin + t * reach) / len
}

fn object_ray(inst: &Instance, r: &Ray) -> Ray {
    Ray {
        origin: inst.object_from_world.transform_point3a(r.origin),
        dir: inst.object_from_world.transform_vector3a(r.dir),
        tmin: r.tmin,
        tmax: r.tmax,
    }
}

/// Returns `∂p/∂u` of a triangle from its corners and texture coordinates (an edge when the
/// texture coordinates are degenerate).
fn triangle_dpdu(p: [Vec3A; 3], t: [Vec2; 3]) -> Vec3A {
    let (dp1, dp2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    if det.abs() < 1e-20 {
        dp1
    } else {
        (dp1 * d2.y - dp2 * d1.y) / det
    }
}
