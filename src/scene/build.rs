//! Turns a [`SceneDesc`] and one of its `gr.render` calls into the render-ready [`Scene`].
//!
//! Flattening walks the DAG from the render's root and emits one [`Instance`] per placement of a
//! geometry node: the same node reached through several parents is placed several times
//! (instancing), but a mesh's file is read once per build ([`MeshCache`]) and its triangles and
//! BVH are built once and shared by all its instances. Textures are loaded the same way
//! ([`ImageCache`]). Bad input found here (cycles, singular or overflowing transforms, broken
//! mesh files, non-finite vertices, geometry placed outside the coordinate range of
//! [`crate::range`]) is an error naming the script line, and so is a scene over the memory
//! budget ([`crate::budget`]): placements are counted over the DAG, and CSG trees over their
//! operands, before either is expanded; instances, meshes and textures are charged before they
//! are made.
//!
//! ```lua
//! root = gr.node('root')
//! for i = 1, 4 do
//!     n = gr.node('inst' .. i); n:translate(3 * i, 0, 0); n:add_child(cow); root:add_child(n)
//! end
//! gr.render(root, ...)   -- build_scene: four instances of one mesh
//! ```

use crate::accel::mesh::MeshGeom;
use crate::accel::{self, Bounds, Bvh};
use crate::budget::{Account, At, bytes_of};
use crate::desc::{MeshId, NodeDesc, NodeId, NodeKind, RenderDesc, SceneDesc};
use crate::error::{Error, Fault, Loc, Result};
use crate::geometry::Analytic;
use crate::geometry::csg::{CsgNode, CsgTree};
pub use crate::geometry::hit::{Hit, SurfaceHit};
use crate::light::Light;
use crate::material::Material;
use crate::scene::images::ImageCache;
use crate::scene::meshes::MeshCache;
use crate::scene::types::{BuildStats, Instance, Scene, Shape};
use glam::{Affine3A, DAffine3, DMat3, DVec3, Mat3A, Vec3A};
use std::collections::{HashMap, HashSet};
use std::time::Instant;

/// Most node visits flattening may make before it reports a runaway instancing graph.
pub const MAX_NODE_VISITS: usize = 20_000_000;
/// Deepest CSG tree accepted.
const MAX_CSG_DEPTH: usize = 64;
/// Bytes the top-level BVH build takes per instance, beyond the instance and its box: obvhs's
/// boxes and binary nodes while it builds, and the 8-wide nodes kept (measured: 48 B kept).
const TLAS_BYTES_PER_INSTANCE: u64 = 128;
/// Bytes a traceable mesh adds per triangle to the data its loader charged (which it shares):
/// its share of a 160-byte block of four, BVH nodes, leaves and order (24.3 B measured on a
/// 33.5M-triangle surface), a material index, and headroom; the builder's 32-byte references
/// are freed before the blocks are made.
const MESH_BYTES_PER_TRIANGLE: u64 = 72;
/// Bytes a traceable mesh adds per vertex: the smooth normal Perlin noise may ask for.
const MESH_BYTES_PER_VERTEX: u64 = 16;

/// A geometry node reached from the root, with its accumulated `world_from_node`.
struct Placement {
    node: NodeId,
    world: DAffine3,
}

/// Builds the scene that `render` draws from `desc`.
pub fn build_scene(desc: &SceneDesc, render: &RenderDesc) -> Result<Scene> {
    // The worker threads with the stacks eye paths need, unless the caller started them.
    let _ = crate::accel::start_workers(None);
    let start = Instant::now();
    // What the scene keeps is charged to `account`, given back when the scene is dropped; what
    // only the build uses (placements, the files' data) to `scratch`, given back on return.
    let account = desc.budget.account();
    let scratch = desc.budget.account();
    let placements = flatten(desc, render.root, &scratch)?;
    let per_instance =
        2 * bytes_of::<Instance>(1) + bytes_of::<Bounds>(1) + TLAS_BYTES_PER_INSTANCE;
    let what = format!("the {} instances it places", placements.len());
    account.charge(
        (placements.len() as u64).saturating_mul(per_instance),
        what,
        At::Script(&render.loc),
    )?;
    let mut images = ImageCache::with_account(desc.missing_textures_warn, account.clone());
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
        account: account.clone(),
        mesh_files: MeshCache::with_account(scratch),
        csg_sizes: HashMap::new(),
        meshes: Vec::new(),
        warned_empty: HashSet::new(),
        mesh_index: HashMap::new(),
        csgs: Vec::new(),
        instances: Vec::new(),
        bounds: Vec::new(),
        stats: BuildStats::default(),
        mesh_lights: Vec::new(),
        emitter_triangles: 0,
    };
    for p in &placements {
        b.place(p)?;
    }
    let tlas = Bvh::build_with(&b.bounds, tlas_builder(&b.bounds));
    let mut instances: Vec<Instance> = tlas
        .order()
        .iter()
        .map(|&i| b.instances[i as usize].clone())
        .collect();
    instances.shrink_to_fit();
    let mut stats = b.stats;
    stats.bvh_bytes = tlas.bytes() + b.meshes.iter().map(|m| m.bvh.bytes()).sum::<usize>();
    stats.triangles_stored = b.meshes.iter().map(|m| m.len()).sum();
    stats.build_time = start.elapsed();
    let mut scene = Scene {
        instances,
        lights: lights(desc, render, &b.bounds, b.mesh_lights),
        meshes: b.meshes,
        csgs: b.csgs,
        materials: b.materials,
        ambient: render.ambient.into(),
        tlas,
        stats,
        transparent: Vec::new(),
        lights_clear_of_media: false,
        absorbing: false,
        eye_media: Default::default(),
        light_media: Vec::new(),
        features: super::types::Features::GENERAL,
        account,
    };
    scene.transparent = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, inst)| {
            scene
                .instance_materials(inst)
                .iter()
                .any(|&m| scene.materials[m as usize].transparency > 0.0)
        })
        .map(|(i, inst)| (i as u32, inst.bounds))
        .collect();
    scene.lights_clear_of_media = scene.lights.iter().all(|light| {
        let b = light_bounds(light);
        scene
            .transparent
            .iter()
            .all(|(_, t)| (b.max.cmplt(t.min) | b.min.cmpgt(t.max)).any())
    });
    find_media(desc, render, &mut scene);
    Ok(scene)
}

/// Returns the lights of `render`, then the placed meshes' `mesh_lights`, in a scene of
/// instances whose boxes are `boxes` (all of them are where a directional light's photons must
/// reach).
fn lights(
    desc: &SceneDesc,
    render: &RenderDesc,
    boxes: &[Bounds],
    mesh_lights: Vec<Light>,
) -> Vec<Light> {
    let world = boxes.iter().fold(Bounds::EMPTY, |a, &x| a.union(x));
    render
        .lights
        .iter()
        .map(|l| Light::from_desc(&desc.lights[l.0 as usize], world))
        .chain(mesh_lights)
        .collect()
}

/// Finds whether any medium absorbs and the media the camera and each light are in
/// ([`Scene::media_at`]), warning at the render's line when the eye lies on a solid's surface,
/// and about solids hidden inside denser ones ([`warn_hidden_solids`]).
fn find_media(desc: &SceneDesc, render: &RenderDesc, scene: &mut Scene) {
    scene.absorbing = scene
        .materials
        .iter()
        .any(|m| m.transparency > 0.0 && m.absorption != glam::Vec3A::ZERO);
    scene.eye_media = scene.media_at(render.camera.eye.into());
    for &i in &scene.eye_media.doubtful {
        let node = desc.node(scene.instances[i as usize].node);
        let inside = scene.eye_media.inside.contains(&i);
        eprintln!(
            "{}: warning: the camera lies on the surface of node '{}' ({}), or the node is not closed; taking it to be {} it",
            render.loc,
            node.name,
            node.loc,
            if inside { "inside" } else { "outside" }
        );
    }
    let mut budget = ProbeBudget(MAX_MEDIA_PROBES);
    let mut unknown = 0usize;
    scene.light_media = scene
        .lights
        .iter()
        .map(|light| {
            let b = light_bounds(light);
            let p = (b.min + b.max) * 0.5;
            if !budget.take(scene, p) {
                unknown += 1;
                return crate::material::medium::MediumStack::air();
            }
            scene.media_at(p).stack
        })
        .collect();
    if unknown > 0 {
        eprintln!(
            "{}: warning: {unknown} lights lie inside more transparent solids than caustic checks ({MAX_MEDIA_PROBES} boxes round lights in all); their photons start as if in air",
            render.loc
        );
    }
    warn_hidden_solids(desc, scene, &mut budget);
}

/// Most (point, transparent box holding it) pairs whose media the build probes
/// ([`Scene::media_at`]: 7 rays each, about a second's work on 2 cores), over the lights' media
/// and the hidden-solid check together: a scene of thousands of lights or solids inside
/// thousands of nested shells cannot stall the build.
const MAX_MEDIA_PROBES: usize = 1 << 16;

/// What is left of [`MAX_MEDIA_PROBES`].
struct ProbeBudget(usize);

impl ProbeBudget {
    /// Takes the probes of point `p` (one per transparent box holding it) and returns true, or
    /// returns false when they are more than what is left.
    fn take(&mut self, scene: &Scene, p: glam::Vec3A) -> bool {
        let boxes = scene
            .transparent
            .iter()
            .filter(|(_, t)| (p.cmpge(t.min) & p.cmple(t.max)).all())
            .count();
        let ok = boxes <= self.0;
        if ok {
            self.0 -= boxes;
        }
        ok
    }
}

/// Most transparent instances [`warn_hidden_solids`] looks at (each looks for the others that
/// hold it, a pass over all of them), besides the probes it takes from the [`ProbeBudget`].
const MAX_HIDDEN_CHECK: usize = 4096;

/// Warns, at the node's script line, about a transparent solid of absolute index placed inside
/// a denser one (an air bubble of `ior = 1` in water): where solids overlap the denser medium
/// wins ([`crate::material::medium`]), so the inner one would vanish without a word. An index
/// below 1, relative to the container, is what makes such a solid.
fn warn_hidden_solids(desc: &SceneDesc, scene: &Scene, budget: &mut ProbeBudget) {
    if scene.transparent.len() > MAX_HIDDEN_CHECK {
        return;
    }
    for &(a, bounds) in &scene.transparent {
        let inst = &scene.instances[a as usize];
        let ior = scene.materials[inst.material as usize].ior;
        if inst.mesh_materials || ior < 1.0 {
            continue;
        }
        let centre = (bounds.min + bounds.max) * 0.5;
        if !budget.take(scene, centre) {
            return;
        }
        let media = scene.media_at(centre);
        let holder = media.inside.iter().find(|&&b| {
            let outer = scene.transparent.iter().find(|t| t.0 == b).map(|t| t.1);
            b != a
                && outer.is_some_and(|o| (o.min.cmple(bounds.min) & o.max.cmpge(bounds.max)).all())
        });
        let Some(&b) = holder else { continue };
        let outer = &scene.instances[b as usize];
        let outer_ior = scene.materials[outer.material as usize].ior;
        if outer_ior > ior {
            let (node, around) = (desc.node(inst.node), desc.node(outer.node));
            eprintln!(
                "{}: warning: node '{}' (ior {ior}) lies inside node '{}' (ior {outer_ior}): where transparent solids overlap the denser one wins, so '{}' is invisible there; for air in it give ior = {:.4} (an ior below 1 is relative to the solid around)",
                node.loc,
                node.name,
                around.name,
                node.name,
                ior / outer_ior
            );
        }
    }
}

/// Most instances whose centres share one cell of a 1024³ grid over the scene that the top-level
/// BVH is built for with obvhs's PLOC. Its build time grows with the square of the instances
/// stacked on one spot and beyond (measured on coincident spheres: 2,000 in 0.2 s, 8,000 in
/// 1.9 s, 32,000 in 43 s; 8,000 concentric ones in 3.8 s), where the binned SAH builder halves
/// such a range by position and stays near-linear. Every other scene keeps the PLOC tree, so its
/// pictures do not change.
const MAX_STACKED_FOR_PLOC: usize = 256;

/// Returns the builder of the top-level BVH over `boxes`: PLOC, unless more than
/// [`MAX_STACKED_FOR_PLOC`] instances are centred on one spot.
fn tlas_builder(boxes: &[Bounds]) -> accel::Builder {
    if boxes.len() <= MAX_STACKED_FOR_PLOC {
        return accel::Builder::Ploc;
    }
    let centre = |b: &Bounds| (b.min + b.max) * 0.5;
    let (lo, hi) = boxes
        .iter()
        .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(centre(b)), hi.max(centre(b)))
        });
    let scale = Vec3A::splat(1023.0) / (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
    let mut cells: Vec<u32> = boxes
        .iter()
        .map(|b| {
            let c = ((centre(b) - lo) * scale)
                .min(Vec3A::splat(1023.0))
                .as_uvec3();
            c.x | c.y << 10 | c.z << 20
        })
        .collect();
    cells.sort_unstable();
    let most = cells
        .chunk_by(|a, b| a == b)
        .map(<[u32]>::len)
        .max()
        .unwrap_or(0);
    if most > MAX_STACKED_FOR_PLOC {
        accel::Builder::BinnedSah
    } else {
        accel::Builder::Ploc
    }
}

/// Returns a box holding every point of `light` (an area light's with room to spare); a
/// directional light's is the centre of the disc its photons leave, outside the sphere that
/// holds every instance (so it is in no medium).
fn light_bounds(light: &Light) -> Bounds {
    use crate::light::Shape;
    let (centre, half) = match light.shape {
        Shape::Point { position } | Shape::Spot { position, .. } => (position, Vec3A::ZERO),
        Shape::Directional { dir, sphere } => (sphere.centre - dir * sphere.radius, Vec3A::ZERO),
        Shape::Area { centre, u, v, .. } => (centre, u.abs() + v.abs()),
        Shape::Sphere { centre, radius } => (centre, Vec3A::splat(radius)),
        Shape::Mesh(ref m) => ((m.min + m.max) / 2.0, (m.max - m.min) / 2.0),
    };
    Bounds {
        min: centre - half,
        max: centre + half,
    }
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
    let scratch = desc.budget.account();
    let mut meshes = MeshCache::with_account(scratch.clone());
    for p in flatten(desc, root, &scratch)? {
        let kind = &desc.node(p.node).kind;
        *counts.by_kind.entry(kind.label()).or_default() += 1;
        if let NodeKind::Mesh(m) = kind {
            counts.triangles += meshes.get(desc, *m)?.triangles.len();
        }
    }
    Ok(counts)
}

/// Returns how many geometry placements the DAG under `root` expands to (saturating), or `None`
/// when it has a cycle (which [`flatten`] reports). Linear in the DAG's nodes and edges.
fn count_expanded(desc: &SceneDesc, root: NodeId) -> Option<u64> {
    // 0: not seen, 1: on the path, 2: counted in `count`.
    let mut state = vec![0u8; desc.nodes.len()];
    let mut count = vec![0u64; desc.nodes.len()];
    let mut stack = vec![(root, false)];
    while let Some((id, leaving)) = stack.pop() {
        let i = id.0 as usize;
        let node = desc.node(id);
        if leaving {
            let own = u64::from(node.kind.is_geometry());
            count[i] = node
                .children
                .iter()
                .fold(own, |n, (c, _)| n.saturating_add(count[c.0 as usize]));
            state[i] = 2;
            continue;
        }
        match state[i] {
            1 => return None,
            2 => continue,
            _ => {}
        }
        state[i] = 1;
        stack.push((id, true));
        for (child, _) in &node.children {
            match state[child.0 as usize] {
                1 => return None,
                2 => {}
                _ => stack.push((*child, false)),
            }
        }
    }
    Some(count[root.0 as usize])
}

/// Returns every geometry node reachable from `root` with its world transform, in DAG order;
/// the placements are charged to `account` before any is made.
fn flatten(desc: &SceneDesc, root: NodeId, account: &Account) -> Result<Vec<Placement>> {
    if let Some(n) = count_expanded(desc, root) {
        let what = format!("the scene under this node expands to {n} placements, which");
        account.charge(
            bytes_of::<Placement>(n),
            what,
            At::Script(&desc.node(root).loc),
        )?;
    }
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
    /// Where what the scene keeps is charged.
    account: Account,
    /// Nodes in each CSG node's expanded tree, by node, once counted.
    csg_sizes: HashMap<NodeId, u64>,
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
    /// The lights placed meshes' emissive surfaces make ([`super::emitters`]), and how many
    /// triangles they have in all.
    mesh_lights: Vec<Light>,
    emitter_triangles: usize,
}

/// Returns at most the first 40 characters of a name, for messages: a script may give a node a
/// name of any length.
fn short(name: &str) -> String {
    match name.char_indices().nth(40) {
        Some((end, _)) => format!("{}...", &name[..end]),
        None => name.to_string(),
    }
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

/// Returns an error at `node`'s script line when its transform `m` (linear part or translation)
/// does not fit single precision: each number fits alone (the script's arguments are checked),
/// but scales and translations compose into products and sums that may not.
fn check_fits_f32(node: &NodeDesc, m: &DAffine3) -> Result<()> {
    let fits = m.to_cols_array().iter().all(|x| x.abs() < f32::MAX as f64);
    if fits {
        return Ok(());
    }
    Err(Error::at(
        &node.loc,
        format!(
            "node '{}' is transformed beyond single precision (its scales or translations compose past {:.1e})",
            node.name,
            f32::MAX
        ),
    ))
}

/// Returns an error at `node`'s script line when its world-space box leaves the renderer's
/// coordinate range ([`crate::range::MAX_COORDINATE`]): every number of the transforms fits, but
/// their composition may place the geometry where intersection and shading overflow.
fn check_in_range(node: &NodeDesc, bounds: &Bounds) -> Result<()> {
    let corners = [bounds.min, bounds.max].map(|c| crate::range::coordinate(c.to_array()));
    match corners.into_iter().find_map(Result::err) {
        Some(e) => Err(Error::at(
            &node.loc,
            format!(
                "node '{}' is placed out of range by its transforms: {e}",
                node.name
            ),
        )),
        None => Ok(()),
    }
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
        check_fits_f32(node, &world)?;
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
                let data = self.mesh_files.get(self.desc, *id)?;
                let lights =
                    super::emitters::place(&data, &world, node, &mut self.emitter_triangles)?;
                self.mesh_lights.extend(lights);
                let mesh = &self.meshes[index as usize];
                if mesh.is_empty() {
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
                self.stats.triangles_placed += mesh.len();
                (Shape::Mesh(index), mesh.bounds)
            }
            NodeKind::Csg { .. } => {
                let size = self.csg_size(p.node, 0);
                let what = format!(
                    "CSG node '{}' expands to a tree of {size} nodes for each instance, which",
                    short(&node.name)
                );
                let bytes = bytes_of::<CsgNode>(size);
                self.account.charge(bytes, what, At::Script(&node.loc))?;
                let mut nodes = Vec::new();
                let material = self.desc.node(p.node).material.map(|m| m.0);
                let (root, bounds) =
                    self.csg_node(p.node, DAffine3::IDENTITY, material, &mut nodes, 0)?;
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
        check_in_range(node, &bounds)?;
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
            return Err(Error::fault_at(
                Fault::MeshLoad,
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
            return Err(Error::fault_at(
                Fault::MeshLoad,
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
        let bytes = (data.triangles.len() as u64)
            .saturating_mul(MESH_BYTES_PER_TRIANGLE)
            .saturating_add((data.positions.len() as u64).saturating_mul(MESH_BYTES_PER_VERTEX));
        let what = format!(
            "mesh {} ({} triangles) with its BVH",
            data.source.display(),
            data.triangles.len()
        );
        self.account.charge(bytes, what, At::Script(&desc.loc))?;
        let geom = MeshGeom::new(std::sync::Arc::clone(&data), first_material);
        self.meshes.push(geom);
        let index = self.meshes.len() as u32 - 1;
        self.mesh_index.insert(id, index);
        Ok(index)
    }

    /// Returns the nodes [`Builder::csg_node`] makes for the CSG subtree of `id` (saturating);
    /// below [`MAX_CSG_DEPTH`] it stops counting, as the expansion stops with an error there.
    fn csg_size(&mut self, id: NodeId, depth: usize) -> u64 {
        if let Some(&n) = self.csg_sizes.get(&id) {
            return n;
        }
        let n = match self.desc.node(id).kind {
            NodeKind::Csg { a, b, .. } if depth <= MAX_CSG_DEPTH => {
                let (a, b) = (self.csg_size(a, depth + 1), self.csg_size(b, depth + 1));
                a.saturating_add(b).saturating_add(1)
            }
            _ => 1,
        };
        self.csg_sizes.insert(id, n);
        n
    }

    /// Appends the CSG subtree of `id`, `depth` below the tree's root, to `nodes`; `frame` is
    /// `csg_from_parent`. Returns the subtree's index and its bounds in the CSG frame.
    fn csg_node(
        &mut self,
        id: NodeId,
        frame: DAffine3,
        inherited: Option<u32>,
        nodes: &mut Vec<CsgNode>,
        depth: usize,
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
        let m = if depth == 0 {
            frame
        } else {
            frame * node.transform
        };
        if let NodeKind::Csg { op, a, b } = &node.kind {
            let material = node.material.map(|m| m.0).or(inherited);
            let (ia, ba) = self.csg_node(*a, m, material, nodes, depth + 1)?;
            let (ib, bb) = self.csg_node(*b, m, material, nodes, depth + 1)?;
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
        check_fits_f32(node, &m)?;
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
