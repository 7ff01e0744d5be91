//! The render-ready scene: world-space [`Instance`]s of one primitive enum ([`Shape`]), the
//! meshes and CSG trees they place, materials, lights and the top-level BVH. The hit records the
//! queries return ([`crate::geometry::hit`]) live below, beside the shapes.
//!
//! # Two-level BVH
//! The top level ([`Scene::tlas`]) is a BVH over instances' world-space boxes. An analytic shape
//! is intersected in its object space (the ray is transformed, not renormalised, so `t` carries
//! over); a mesh instance transforms the ray and traverses the mesh's own BVH (the bottom level,
//! [`MeshGeom`]). A 1M-triangle mesh instanced 10 times thus costs one mesh of memory plus ten
//! instances.

use crate::accel::mesh::MeshGeom;
use crate::accel::{Bounds, Bvh};
use crate::desc::NodeId;
use crate::geometry::Analytic;
use crate::geometry::csg::{CsgNode, CsgTree};
use crate::light::Light;
use crate::material::Material;
use glam::{Affine3A, Mat3A, Vec3A};
use std::time::Duration;

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
    /// The instances that can shade with a transparent material, with their world bounds: with
    /// fewer than two, no two transparent solids can touch and [`Scene::touching`] is skipped;
    /// otherwise it runs only at hits inside another one's bounds.
    pub transparent: Vec<(u32, Bounds)>,
    /// Whether every light lies outside the world bounds of every transparent instance. Then a
    /// point inside a transparent solid sees no light directly: a shadow ray from it must cross
    /// the solid's boundary, which blocks it (the light through it is the caustic map's), so
    /// the eye path casts none ([`Scene::lights_clear_of_media`]).
    pub lights_clear_of_media: bool,
    /// Whether some transparent material absorbs ([`Material::absorption`]): without one, the
    /// per-segment Beer–Lambert factor is 1 and the paths skip it ([`Scene::kept_along`]).
    pub absorbing: bool,
    /// The media the camera is in (under water, inside a glass ball): where camera rays start
    /// ([`Scene::media_at`]).
    pub eye_media: crate::scene::media::Media,
    /// The media each light is in, by light index: where its photons start.
    pub light_media: Vec<crate::material::medium::MediumStack>,
    /// What of its materials and lights the passes simulate: the effect plan's choice, applied
    /// by [`Scene::apply`] before any pass runs; [`Features::GENERAL`] until then.
    pub features: Features,
    /// What the scene holds, charged to the command's memory budget and given back when the
    /// scene is dropped ([`crate::budget`]).
    pub account: crate::budget::Account,
}

/// The parts of shading the effect plan can leave out ([`mod@crate::integrator::plan`]). Each hit is
/// shaded by a kernel compiled for these flags ([`Scene::interaction`]), so the code of an effect
/// that is off is not reached at all, rather than skipped by a check at every ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// Colour maps replace `kd`, and glTF textures give `kd`, `ks` and the roughness.
    pub textures: bool,
    /// Bump and normal maps bend the shading normal.
    pub normal_maps: bool,
    /// Perlin noise bends the shading normal.
    pub noise: bool,
    /// Transparent materials refract (else they are opaque: `t = 0`).
    pub refraction: bool,
    /// Area and sphere lights are sampled over their surface (else at their centre: hard
    /// shadows).
    pub soft_shadows: bool,
    /// Deepest chain of specular bounces an eye path splits deterministically over; deeper, it
    /// goes on by Russian roulette ([`crate::integrator::eye`]).
    pub specular_depth: u32,
}

/// Deepest chain of reflections and refractions an eye path follows by deterministic splitting
/// by default ([`Features::specular_depth`]); deeper paths go on by Russian roulette. The plan
/// deepens it for scenes of many nested dielectric layers ([`mod@crate::integrator::plan`]).
pub const MAX_DEPTH: u32 = 12;

impl Features {
    /// Everything on, at the fixed depth: the kernel that handles any material.
    pub const GENERAL: Features = Features {
        textures: true,
        normal_maps: true,
        noise: true,
        refraction: true,
        soft_shadows: true,
        specular_depth: MAX_DEPTH,
    };
}

impl Scene {
    /// Makes the passes simulate `features` (the plan's): an effect turned off is removed from
    /// the materials that had it (their textures, maps, noise or transparency), so every query
    /// sees the same scene, and the hits are shaded by the kernel without its code. Removal
    /// cannot be undone: a scene rendered with an effect disabled keeps it disabled.
    pub fn apply(&mut self, features: Features) {
        for m in &mut self.materials {
            if !features.textures {
                m.texture = None;
                m.metal_rough = None;
            }
            if !features.normal_maps {
                m.bump = None;
            }
            if !features.noise {
                m.perlin_scale = 0.0;
            }
            if !features.refraction {
                m.transparency = 0.0;
            }
        }
        if !features.refraction {
            self.transparent.clear();
        }
        self.features = features;
    }

    /// Returns the materials the placed instances can shade with (each once, in index order).
    pub fn placed_materials(&self) -> Vec<&Material> {
        let mut ids: Vec<u32> = self
            .instances
            .iter()
            .flat_map(|inst| self.instance_materials(inst))
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids.iter().map(|&m| &self.materials[m as usize]).collect()
    }

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
}
