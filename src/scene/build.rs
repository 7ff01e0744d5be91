//! Turns a [`SceneDesc`] and one of its `gr.render` calls into the render-ready [`Scene`].
//!
//! Flattening walks the DAG from the render's root and emits one [`Instance`] per placement of a
//! geometry node: the same node reached through several parents is placed several times
//! (instancing), but a mesh's triangles and BVH are built once and shared by all its instances.
//!
//! # Two-level BVH
//! The top level ([`Scene::tlas`]) is a BVH over instances' world-space boxes. An analytic shape
//! is intersected in its object space (the ray is transformed, not renormalised, so `t` carries
//! over); a mesh instance transforms the ray and traverses the mesh's own BVH (the bottom level).
//! A 1M-triangle mesh instanced 10 times thus costs one mesh of memory plus ten instances.

use crate::accel::mesh::MeshGeom;
use crate::accel::{Bounds, Bvh};
use crate::desc::{MeshId, NodeId, NodeKind, RenderDesc, SceneDesc};
use crate::error::{Error, Loc, Result};
use crate::geometry::csg::{CsgNode, CsgTree};
pub use crate::geometry::hit::{Hit, SurfaceHit};
use crate::geometry::triangle;
use crate::geometry::uv::{analytic_dpdu, analytic_uv};
use crate::geometry::{Analytic, Interval, Ray};
use crate::light::Light;
use crate::material::Material;
use crate::scene::images::ImageCache;
use crate::scene::meshes::MeshCache;
use glam::{Affine3A, DAffine3, DMat3, DVec3, Mat3A, Vec2, Vec3A};
use std::collections::{HashMap, HashSet};
use std::time::{Duration, Instant};

/// Most node visits flattening may make before it reports a runaway instancing graph.
pub const MAX_NODE_VISITS: usize = 20_000_000;
/// Deepest CSG tree accepted.
const MAX_CSG_DEPTH: usize = 64;

/// What an instance places in the world: the one set of primitives the scene traces. Every
/// `match` on it names each variant, so a new primitive cannot fall into another's arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A unit analytic primitive in the instance's object space.
    Analytic(Analytic),
    /// Index into [`Scene::meshes`].
    Mesh(u32),
    /// Index into [`Scene::csgs`].
    Csg(u32),
}

impl Shape {
    /// Returns the kind's name, as `--stats` prints it.
    pub fn label(&self) -> &'static str {
        match self {
            Shape::Analytic(a) => a.label(),
            Shape::Mesh(_) => "mesh",
            Shape::Csg(_) => "csg",
        }
    }
}

/// One placement of a shape in the world.
#[derive(Clone, Debug)]
pub struct Instance {
    pub shape: Shape,
    pub world_from_object: Affine3A,
    pub object_from_world: Affine3A,
    /// Maps object-space normals to world space (inverse transpose of the linear part).
    pub normal_to_world: Mat3A,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// True when a mesh instance shades each triangle with its file's material
    /// ([`MeshGeom::materials`]) rather than `material`: the script set no material on the node.
    pub mesh_materials: bool,
    /// The geometry node this instance places.
    pub node: NodeId,
    /// World-space bounding box.
    pub bounds: Bounds,
}

/// Counters describing a built scene, for `--stats` and `caustic info`.
#[derive(Clone, Debug, Default)]
pub struct BuildStats {
    /// Instances by [`Shape::label`].
    pub by_kind: std::collections::BTreeMap<&'static str, usize>,
    /// Triangles over all mesh instances.
    pub triangles_placed: usize,
    /// Triangles stored once per distinct mesh.
    pub triangles_stored: usize,
    pub bvh_bytes: usize,
    pub build_time: Duration,
}

/// Everything the renderer traces.
pub struct Scene {
    /// Instances in top-level BVH order: the TLAS leaf index `i` is instance `i`.
    pub instances: Vec<Instance>,
    pub meshes: Vec<MeshGeom>,
    pub csgs: Vec<CsgTree>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub ambient: Vec3A,
    pub tlas: Bvh,
    pub stats: BuildStats,
}

/// A geometry node reached from the root, with its accumulated `world_from_node`.
struct Placement {
    node: NodeId,
    world: DAffine3,
}

/// Builds the scene that `render` draws from `desc`.
pub fn build_scene(desc: &SceneDesc, render: &RenderDesc) -> Result<Scene> {
    let start = Instant::now();
    let placements = flatten(desc, render.root)?;
    let mut images = ImageCache::new(desc.missing_textures_warn);
    let mut materials: Vec<Material> = desc
        .materials
        .iter()
        .map(|m| images.material(m))
        .collect::<Result<_>>()?;
    let fallback = materials.len() as u32;
    materials.push(Material::fallback());

    let mut b = Builder {
        desc,
        fallback,
        materials,
        images,
        mesh_files: MeshCache::new(),
        meshes: Vec::new(),
        warned_empty: HashSet::new(),
        mesh_index: HashMap::new(),
        csgs: Vec::new(),
        instances: Vec::new(),
        bounds: Vec::new(),
        stats: BuildStats::default(),
    };
    for p in &placements {
        b.place(p)?;
    }
    let tlas = Bvh::build(&b.bounds);
    let mut instances: Vec<Instance> = tlas
        .order()
        .iter()
        .map(|&i| b.instances[i as usize].clone())
        .collect();
    instances.shrink_to_fit();
    let mut stats = b.stats;
    stats.bvh_bytes = tlas.bytes() + b.meshes.iter().map(|m| m.bvh.bytes()).sum::<usize>();
    stats.triangles_stored = b.meshes.iter().map(|m| m.triangles.len()).sum();
    stats.build_time = start.elapsed();
    Ok(Scene {
        instances,
        meshes: b.meshes,
        csgs: b.csgs,
        materials: b.materials,
        lights: render
            .lights
            .iter()
            .map(|l| Light::from_desc(&desc.lights[l.0 as usize]))
            .collect(),
        ambient: render.ambient.into(),
        tlas,
        stats,
    })
}

/// What a render's root places in the world, by kind, without building anything.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PlacementCounts {
    /// Placed geometry nodes by [`NodeKind::label`].
    pub by_kind: std::collections::BTreeMap<&'static str, usize>,
    /// Triangles over all placed meshes.
    pub triangles: usize,
}

/// Counts the geometry placed under `root` (instancing included), as `caustic info` prints it.
///
/// Reads the mesh files placed, to count their triangles.
pub fn count_placements(desc: &SceneDesc, root: NodeId) -> Result<PlacementCounts> {
    let mut counts = PlacementCounts::default();
    let mut meshes = MeshCache::new();
    for p in flatten(desc, root)? {
        let kind = &desc.node(p.node).kind;
        *counts.by_kind.entry(kind.label()).or_default() += 1;
        if let NodeKind::Mesh(m) = kind {
            counts.triangles += meshes.get(desc, *m)?.triangles.len();
        }
    }
    Ok(counts)
}

/// Returns every geometry node reachable from `root` with its world transform, in DAG order.
fn flatten(desc: &SceneDesc, root: NodeId) -> Result<Vec<Placement>> {
    enum Step {
        Enter(NodeId, DAffine3, Option<Loc>),
        Leave(NodeId),
    }
    let mut out = Vec::new();
    let mut on_path = vec![false; desc.nodes.len()];
    let mut stack = vec![Step::Enter(root, DAffine3::IDENTITY, None)];
    let mut visits = 0usize;
    while let Some(step) = stack.pop() {
        let (id, parent, via) = match step {
            Step::Leave(id) => {
                on_path[id.0 as usize] = false;
                continue;
            }
            Step::Enter(id, parent, via) => (id, parent, via),
        };
        let node = desc.node(id);
        if on_path[id.0 as usize] {
            let loc = via.unwrap_or_else(|| node.loc.clone());
            return Err(Error::at(
                &loc,
                format!(
                    "node '{}' (made at {}) is its own ancestor: add_child made a cycle",
                    node.name, node.loc
                ),
            ));
        }
        visits += 1;
        if visits > MAX_NODE_VISITS {
            return Err(Error::at(
                &desc.node(root).loc,
                format!(
                    "the scene under '{}' expands to more than {MAX_NODE_VISITS} node placements; is the instancing nested too deep?",
                    desc.node(root).name
                ),
            ));
        }
        let world = parent * node.transform;
        if node.kind.is_geometry() {
            out.push(Placement { node: id, world });
        }
        on_path[id.0 as usize] = true;
        stack.push(Step::Leave(id));
        for (child, loc) in node.children.iter().rev() {
            stack.push(Step::Enter(*child, world, Some(loc.clone())));
        }
    }
    Ok(out)
}

struct Builder<'a> {
    desc: &'a SceneDesc,
    fallback: u32,
    /// The script's materials, the fallback, then each built mesh's file materials.
    materials: Vec<Material>,
    images: ImageCache,
    /// Mesh files read so far by this build.
    mesh_files: MeshCache,
    meshes: Vec<MeshGeom>,
    mesh_index: HashMap<MeshId, u32>,
    /// Mesh nodes already reported as having no triangles.
    warned_empty: HashSet<NodeId>,
    csgs: Vec<CsgTree>,
    instances: Vec<Instance>,
    bounds: Vec<Bounds>,
    stats: BuildStats,
}

/// Returns `parent_from_object` for the primitive a geometry kind stands for.
fn local_transform(kind: &NodeKind) -> DAffine3 {
    match kind {
        NodeKind::NhSphere { center, radius } => {
            DAffine3::from_translation(*center) * DAffine3::from_scale(DVec3::splat(*radius))
        }
        NodeKind::NhBox { corner, size } => {
            DAffine3::from_translation(*corner) * DAffine3::from_scale(DVec3::splat(*size))
        }
        NodeKind::Group
        | NodeKind::Sphere
        | NodeKind::Cube
        | NodeKind::Cylinder
        | NodeKind::Cone
        | NodeKind::Mesh(_)
        | NodeKind::Csg { .. } => DAffine3::IDENTITY,
    }
}

/// Returns the analytic primitive a node kind places, or `None` for groups, meshes and CSG nodes.
fn analytic_of(kind: &NodeKind) -> Option<Analytic> {
    match kind {
        NodeKind::Sphere | NodeKind::NhSphere { .. } => Some(Analytic::Sphere),
        NodeKind::Cube | NodeKind::NhBox { .. } => Some(Analytic::Cube),
        NodeKind::Cylinder => Some(Analytic::Cylinder),
        NodeKind::Cone => Some(Analytic::Cone),
        NodeKind::Group | NodeKind::Mesh(_) | NodeKind::Csg { .. } => None,
    }
}

/// Returns the object-space box of a unit analytic primitive.
fn analytic_bounds(shape: Analytic) -> Bounds {
    match shape {
        Analytic::Cube => Bounds {
            min: Vec3A::ZERO,
            max: Vec3A::ONE,
        },
        Analytic::Cone => Bounds {
            min: Vec3A::new(-1.0, -1.0, 0.0),
            max: Vec3A::ONE,
        },
        Analytic::Sphere | Analytic::Cylinder => Bounds {
            min: Vec3A::NEG_ONE,
            max: Vec3A::ONE,
        },
    }
}

fn to_f32(m: DAffine3) -> Affine3A {
    Affine3A::from_cols_array(&m.to_cols_array().map(|x| x as f32))
}

fn normal_matrix(m: &DMat3) -> Mat3A {
    Mat3A::from(m.inverse().transpose().as_mat3())
}

/// Returns the box holding `b` after transform `m`.
fn transform_bounds(m: &DAffine3, b: Bounds) -> Bounds {
    let mut out = Bounds::EMPTY;
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x } as f64,
            if k & 2 == 0 { b.min.y } else { b.max.y } as f64,
            if k & 4 == 0 { b.min.z } else { b.max.z } as f64,
        );
        out = out.grow(Vec3A::from(m.transform_point3(c).as_vec3()));
    }
    out
}

/// Returns true when the linear part of `m` and its inverse both fit single precision and `m`
/// does not flatten space (a zero or vanishing scale).
fn is_invertible(m: &DAffine3) -> bool {
    let fits = |a: &DMat3| a.to_cols_array().iter().all(|x| x.abs() < f32::MAX as f64);
    let det = m.matrix3.determinant();
    let scale = m
        .matrix3
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, x| a.max(x.abs()));
    det.is_finite()
        && det != 0.0
        && det.abs() > (scale * 1e-7).powi(3)
        && fits(&m.matrix3)
        && fits(&m.matrix3.inverse())
}

impl Builder<'_> {
    fn material_of(&mut self, id: NodeId, inherited: Option<u32>) -> u32 {
        let node = self.desc.node(id);
        match (node.material, inherited) {
            (Some(m), _) => m.0,
            (None, Some(m)) => m,
            (None, None) => {
                eprintln!(
                    "{}: warning: node '{}' has no material; drawing it matte grey",
                    node.loc, node.name
                );
                self.fallback
            }
        }
    }

    fn place(&mut self, p: &Placement) -> Result<()> {
        let node = self.desc.node(p.node);
        let world = p.world * local_transform(&node.kind);
        if !is_invertible(&world) {
            eprintln!(
                "{}: warning: node '{}' has a singular transform (a zero scale?); it is not drawn",
                node.loc, node.name
            );
            return Ok(());
        }
        let analytic = |a: Analytic| (Shape::Analytic(a), analytic_bounds(a));
        let (shape, object_bounds) = match &node.kind {
            NodeKind::Group => return Ok(()),
            NodeKind::Mesh(id) => {
                let index = self.mesh(*id)?;
                let mesh = &self.meshes[index as usize];
                if mesh.triangles.is_empty() {
                    if self.warned_empty.insert(p.node) {
                        let source = self.mesh_files.get(self.desc, *id)?;
                        eprintln!(
                            "{}: warning: mesh '{}' ({}) has no triangles",
                            node.loc,
                            node.name,
                            source.source.display()
                        );
                    }
                    return Ok(());
                }
                self.stats.triangles_placed += mesh.triangles.len();
                (Shape::Mesh(index), mesh.bounds)
            }
            NodeKind::Csg { .. } => {
                let mut nodes = Vec::new();
                let material = self.desc.node(p.node).material.map(|m| m.0);
                let (root, bounds) =
                    self.csg_node(p.node, DAffine3::IDENTITY, material, &mut nodes, 0, true)?;
                self.csgs.push(CsgTree { nodes, root });
                (Shape::Csg(self.csgs.len() as u32 - 1), bounds)
            }
            NodeKind::Sphere | NodeKind::NhSphere { .. } => analytic(Analytic::Sphere),
            NodeKind::Cube | NodeKind::NhBox { .. } => analytic(Analytic::Cube),
            NodeKind::Cylinder => analytic(Analytic::Cylinder),
            NodeKind::Cone => analytic(Analytic::Cone),
        };
        let bounds = transform_bounds(&world, object_bounds);
        if !bounds.is_finite() || !to_f32(world).is_finite() || !to_f32(world.inverse()).is_finite()
        {
            return Err(Error::at(
                &node.loc,
                format!(
                    "node '{}' is placed at a non-finite position (overflowing transform?)",
                    node.name
                ),
            ));
        }
        *self.stats.by_kind.entry(shape.label()).or_default() += 1;
        let mesh_materials = match shape {
            Shape::Mesh(m) => {
                node.material.is_none() && !self.meshes[m as usize].materials.is_empty()
            }
            Shape::Analytic(_) | Shape::Csg(_) => false,
        };
        let material = match shape {
            // A CSG hit takes the material of the operand hit; the instance's is a fallback.
            Shape::Csg(_) => self.fallback,
            // Each triangle takes its file material; the instance's is a fallback.
            Shape::Mesh(_) if mesh_materials => self.fallback,
            Shape::Mesh(_) | Shape::Analytic(_) => self.material_of(p.node, None),
        };
        self.instances.push(Instance {
            shape,
            world_from_object: to_f32(world),
            object_from_world: to_f32(world.inverse()),
            normal_to_world: normal_matrix(&world.matrix3),
            material,
            mesh_materials,
            node: p.node,
            bounds,
        });
        self.bounds.push(bounds);
        Ok(())
    }

    fn mesh(&mut self, id: MeshId) -> Result<u32> {
        if let Some(&i) = self.mesh_index.get(&id) {
            return Ok(i);
        }
        let desc = &self.desc.meshes[id.0 as usize];
        let data = self.mesh_files.get(self.desc, id)?;
        if let Some(bad) = data.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::at(
                &desc.loc,
                format!(
                    "mesh {} has a non-finite vertex (#{})",
                    data.source.display(),
                    bad + 1
                ),
            ));
        }
        let ids = &data.triangle_materials;
        if !ids.is_empty()
            && (ids.len() != data.triangles.len()
                || ids.iter().any(|&m| m as usize >= data.materials.len()))
        {
            return Err(Error::at(
                &desc.loc,
                format!(
                    "mesh {} has per-triangle materials that do not match its triangles or materials",
                    data.source.display()
                ),
            ));
        }
        let first_material = self.materials.len() as u32;
        if !ids.is_empty() {
            for m in &data.materials {
                let material = self.images.mesh_material(m, &desc.loc)?;
                self.materials.push(material);
            }
        }
        let geom = MeshGeom::new(&data, first_material);
        self.meshes.push(geom);
        let index = self.meshes.len() as u32 - 1;
        self.mesh_index.insert(id, index);
        Ok(index)
    }

    /// Appends the CSG subtree of `id` to `nodes`; `frame` is `csg_from_parent`. Returns the
    /// subtree's index and its bounds in the CSG frame.
    fn csg_node(
        &mut self,
        id: NodeId,
        frame: DAffine3,
        inherited: Option<u32>,
        nodes: &mut Vec<CsgNode>,
        depth: usize,
        is_root: bool,
    ) -> Result<(u32, Bounds)> {
        let node = self.desc.node(id);
        if depth > MAX_CSG_DEPTH {
            return Err(Error::at(
                &node.loc,
                format!(
                    "CSG tree under '{}' is deeper than {MAX_CSG_DEPTH} (a cycle?)",
                    node.name
                ),
            ));
        }
        // The root's own transform is already in the instance's world transform.
        let m = if is_root {
            frame
        } else {
            frame * node.transform
        };
        if let NodeKind::Csg { op, a, b } = &node.kind {
            let material = node.material.map(|m| m.0).or(inherited);
            let (ia, ba) = self.csg_node(*a, m, material, nodes, depth + 1, false)?;
            let (ib, bb) = self.csg_node(*b, m, material, nodes, depth + 1, false)?;
            nodes.push(CsgNode::Op {
                op: *op,
                a: ia,
                b: ib,
            });
            return Ok((nodes.len() as u32 - 1, ba.union(bb)));
        }
        let kind = &node.kind;
        let Some(shape) = analytic_of(kind) else {
            return Err(Error::at(
                &node.loc,
                format!(
                    "CSG operand '{}' is a {}; CSG takes spheres, cubes, cylinders and other CSG nodes",
                    node.name,
                    kind.label()
                ),
            ));
        };
        let m = m * local_transform(kind);
        if !is_invertible(&m) {
            return Err(Error::at(
                &node.loc,
                format!("CSG operand '{}' has a singular transform", node.name),
            ));
        }
        let material = self.material_of(id, inherited);
        nodes.push(CsgNode::Leaf {
            shape,
            leaf_from_csg: to_f32(m.inverse()),
            normal_to_csg: normal_matrix(&m.matrix3),
            material,
        });
        Ok((
            nodes.len() as u32 - 1,
            transform_bounds(&m, analytic_bounds(shape)),
        ))
    }
}

impl Scene {
    /// Returns every material index an instance can shade with (its own, its mesh file's, or its
    /// CSG operands').
    pub fn instance_materials(&self, inst: &Instance) -> Vec<u32> {
        match inst.shape {
            Shape::Mesh(m) if inst.mesh_materials => {
                let mut ids = self.meshes[m as usize].materials.clone();
                ids.sort_unstable();
                ids.dedup();
                ids
            }
            Shape::Csg(c) => self.csgs[c as usize]
                .nodes
                .iter()
                .filter_map(|n| match n {
                    CsgNode::Leaf { material, .. } => Some(*material),
                    CsgNode::Op { .. } => None,
                })
                .collect(),
            Shape::Mesh(_) | Shape::Analytic(_) => vec![inst.material],
        }
    }

    /// Returns the diagonal of the box holding every instance (0 for an empty scene).
    pub fn extent(&self) -> f32 {
        let b = self
            .instances
            .iter()
            .fold(Bounds::EMPTY, |a, i| a.union(i.bounds));
        if b.is_finite() {
            (b.max - b.min).length()
        } else {
            0.0
        }
    }

    /// Returns the closest hit with `t` in the ray's `(tmin, tmax)`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best = None;
        self.tlas
            .closest(ray, |r, i| match self.hit_instance(i, r) {
                Some(h) => {
                    best = Some(h);
                    h.t
                }
                None => f32::INFINITY,
            });
        best
    }

    /// Returns true when anything lies on the ray within `(tmin, tmax)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
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

    fn hit_instance(&self, i: usize, r: &Ray) -> Option<Hit> {
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
            Shape::Analytic(a) => analytic(a.interval(local.origin, local.dir)),
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
                let idx = mesh.triangles[hit.prim as usize];
                let [v0, v1, v2] = idx.map(|i| mesh.positions[i as usize]);
                let w0 = 1.0 - hit.b1 - hit.b2;
                let p = v0 * w0 + v1 * hit.b1 + v2 * hit.b2;
                let ng = triangle::geometric_normal(v0, v1, v2);
                // Perlin noise needs a continuous base normal: smooth normals when the file has none.
                let normals = if mesh.normals.is_empty() && perlin {
                    mesh.smooth_normals()
                } else {
                    &mesh.normals
                };
                let ns = if normals.is_empty() {
                    ng
                } else {
                    let [n0, n1, n2] = idx.map(|i| normals[i as usize]);
                    n0 * w0 + n1 * hit.b1 + n2 * hit.b2
                };
                let [t0, t1, t2] = if mesh.uvs.is_empty() {
                    [Vec2::ZERO, Vec2::X, Vec2::Y]
                } else {
                    idx.map(|i| mesh.uvs[i as usize])
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
