//! The plain scene description a script fills in: no Lua types, every entry tagged with the script
//! line that made it.
//!
//! This is the bottom floor: it imports nothing of geometry, the BVH or file loading. Files are
//! named here (resolved paths of meshes, textures and output images), never read; `scene` reads
//! them when it builds a scene. Tests can fill a description in Rust without Lua.
//!
//! Index spaces ([`NodeId`], [`MaterialId`], [`LightId`], [`MeshId`]) are positions in the vectors
//! of [`SceneDesc`]. Entries are only ever appended, so an id stays valid for the whole script, and
//! an image rendered mid-script sees the description as it stands at that moment.
//!
//! Transforms follow the course's convention (pre-multiplication): each `translate`, `rotate` or
//! `scale` call on a node computes `M ← T·M`, so calls act on the geometry in call order, each in
//! the parent's frame, and `world_from_object = M_root · … · M_parent · M_node`. Scripts read with
//! `--dialect legacy` compose `M ← M·T` instead (`lua::Dialect`); either way a node holds one
//! `parent_from_node` matrix, and nothing below the Lua layer knows which order made it.

use crate::budget::Budget;
use crate::error::Loc;
use glam::{DAffine3, DVec3, Vec3};
use std::path::{Path, PathBuf};

/// Index of a node in [`SceneDesc::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);
/// Index of a material in [`SceneDesc::materials`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaterialId(pub u32);
/// Index of a light in [`SceneDesc::lights`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightId(pub u32);
/// Index of a mesh in [`SceneDesc::meshes`]; nodes made from the same file share one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshId(pub u32);

/// The boolean operation of a CSG node: `a ∪ b`, `a ∩ b` or `a − b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    Union,
    Intersection,
    Difference,
}

/// What a node is: a transform-only group or one kind of geometry, in its own model frame.
#[derive(Clone, Debug, PartialEq)]
pub enum NodeKind {
    /// `gr.node` and `gr.joint`: a transform with children and no geometry.
    Group,
    /// `gr.sphere`: centre (0,0,0), radius 1.
    Sphere,
    /// `gr.cube`: the axis-aligned unit cube from (0,0,0) to (1,1,1).
    Cube,
    /// `gr.nh_sphere`: a sphere with its own centre and radius in the node's frame.
    NhSphere { center: DVec3, radius: f64 },
    /// `gr.nh_box`: the cube from `corner` to `corner + size` on every axis.
    NhBox { corner: DVec3, size: f64 },
    /// `gr.cylinder`: axis z, radius 1, z in [-1, 1], closed by caps at z = ±1.
    Cylinder,
    /// `gr.cone`: apex at the origin, axis z, radius 1 at z = 1, closed by a cap at z = 1.
    Cone,
    /// `gr.mesh`: a triangle mesh shared with every other node loaded from the same file.
    Mesh(MeshId),
    /// `gr.union`, `gr.intersection`, `gr.difference`: operands evaluated in this node's frame.
    Csg { op: CsgOp, a: NodeId, b: NodeId },
}

impl NodeKind {
    /// Returns true for every kind that `set_material` accepts (geometry and CSG nodes).
    pub fn is_geometry(&self) -> bool {
        !matches!(self, NodeKind::Group)
    }

    /// Returns the kind's name as `caustic info` prints it.
    pub fn label(&self) -> &'static str {
        match self {
            NodeKind::Group => "group",
            NodeKind::Sphere | NodeKind::NhSphere { .. } => "sphere",
            NodeKind::Cube | NodeKind::NhBox { .. } => "cube",
            NodeKind::Cylinder => "cylinder",
            NodeKind::Cone => "cone",
            NodeKind::Mesh(_) => "mesh",
            NodeKind::Csg { .. } => "csg",
        }
    }
}

/// One node of the scene DAG.
#[derive(Clone, Debug)]
pub struct NodeDesc {
    /// The name the script gave; not unique.
    pub name: String,
    pub kind: NodeKind,
    /// `parent_from_node`, composed in the script's dialect (see the module doc).
    pub transform: DAffine3,
    /// Set by `set_material`; the last call wins. Not inherited by children.
    pub material: Option<MaterialId>,
    /// Children in `add_child` order, each with the line of its `add_child` call.
    pub children: Vec<(NodeId, Loc)>,
    /// Where the node was created.
    pub loc: Loc,
}

/// A material as `gr.material(kd, ks, p [, t [, ior [, s [, texture [, bump]]]]])` gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// Diffuse reflectance (also multiplies the ambient light).
    pub kd: Vec3,
    /// Specular colour: Phong highlight and mirror reflection weight.
    pub ks: Vec3,
    /// Phong exponent.
    pub shininess: f32,
    /// Transparency in [0, 1]; above 0 the surface refracts.
    pub transparency: f32,
    /// Refractive index of the material's interior (meaningful when `transparency > 0`):
    /// absolute from 1 up, relative to the containing medium below 1.
    pub ior: f32,
    /// Absorption coefficient per channel per unit length of the interior (`gr.absorption`).
    pub absorption: Vec3,
    /// GGX roughness of the mirror lobe in `[0, 1]` (`gr.roughness`; 0: smooth).
    pub roughness: f32,
    /// Scale of the Perlin-noise normal perturbation; 0 means none.
    pub perlin_scale: f32,
    /// Texture image replacing `kd`, resolved to a readable path.
    pub texture: Option<PathBuf>,
    /// Normal-map image ("bump" in the original project), resolved to a readable path.
    pub bump: Option<PathBuf>,
    pub loc: Loc,
}

/// The emitting shape of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightShape {
    /// `gr.light`.
    Point,
    /// `gr.area_light`: a one-sided parallelogram centred at the position with edges `u`, `v`,
    /// emitting on the side of `u × v`.
    Area { u: Vec3, v: Vec3 },
    /// `gr.sphere_light`.
    Sphere { radius: f32 },
    /// `gr.spot_light`, glTF's `spot`: at the position, shining along `direction` (non-zero),
    /// full within `inner` and dark beyond `outer` (radians, `0 ≤ inner ≤ outer ≤ π/2`), with
    /// glTF's falloff between ([`crate::light::spot`]).
    Spot {
        direction: Vec3,
        inner: f32,
        outer: f32,
    },
    /// `gr.directional_light`, glTF's `directional`: light travelling along `direction`
    /// (non-zero) from beyond the scene; the colour is its irradiance over π on a surface facing
    /// it, and the position is not used ([`crate::light::directional`]).
    Directional { direction: Vec3 },
}

/// A light as `gr.light(pos, rgb, falloff [, power [, num_photons]])`, `gr.area_light`,
/// `gr.sphere_light`, `gr.spot_light` or `gr.directional_light` gives it (or a glTF file's
/// punctual light).
#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    pub shape: LightShape,
    /// World-space position (lights are not part of the scene graph); the centre of area lights.
    pub position: Vec3,
    /// Intensity per channel.
    pub colour: Vec3,
    /// Attenuation `1 / (c0 + c1·d + c2·d²)`, all coefficients ≥ 0 and not all 0.
    pub falloff: [f32; 3],
    /// The extended project's light power (photon energy); `None` when the script gives none.
    pub power: Option<f32>,
    /// Photons this light emits; `None` lets the renderer decide.
    pub photons: Option<u64>,
    pub loc: Loc,
}

/// The file formats `gr.mesh` reads, told apart by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront `.obj` (with its `.mtl` libraries).
    Obj,
    /// glTF 2.0, `.gltf` (JSON) or `.glb` (binary).
    Gltf,
}

impl MeshFormat {
    /// Returns the format of `path` by its extension (any case), or `None` for one caustic does
    /// not read.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(MeshFormat::Obj),
            "gltf" | "glb" => Some(MeshFormat::Gltf),
            _ => None,
        }
    }
}

/// Where a mesh's triangles come from, as the script gave them; nothing is read here.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSource {
    /// `gr.mesh(name, 'file')`: the file, read when a scene is built.
    File {
        /// The path as the script wrote it, for messages.
        given: String,
        /// `given` resolved to a readable file (working directory first, then the script's folder).
        path: PathBuf,
        format: MeshFormat,
        /// `gr.gltf`: the one glTF mesh (its index in the file) read alone, in its own frame;
        /// `None`: the whole file, every node's transform baked in (`gr.mesh`).
        part: Option<u32>,
    },
    /// The legacy form `gr.mesh(name, {{x,y,z}, …}, {{i,j,k,…}, …})`.
    Inline {
        /// Vertex positions, every one finite.
        positions: Vec<DVec3>,
        /// Convex faces as 0-based indices into `positions` (all in range), each with at least
        /// three corners.
        faces: Vec<Vec<u32>>,
    },
}

/// A mesh named by `gr.mesh` (or one glTF mesh of a file, by `gr.gltf`); files are deduplicated
/// by canonical path and part, so nodes made from the same file share one.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshDesc {
    pub source: MeshSource,
    /// The `gr.mesh` call that first named it.
    pub loc: Loc,
}

/// The camera of a `gr.render` call, in world space, exactly as the script gave it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub eye: Vec3,
    /// A direction (not a look-at point); not necessarily unit length.
    pub view: Vec3,
    /// Approximately up; need not be perpendicular to `view`.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// One `gr.render` call.
#[derive(Clone, Debug)]
pub struct RenderDesc {
    pub root: NodeId,
    /// Where the image goes, resolved against the working directory or the script's folder.
    pub output: PathBuf,
    pub width: u32,
    pub height: u32,
    pub camera: CameraDesc,
    pub ambient: Vec3,
    pub lights: Vec<LightId>,
    pub loc: Loc,
    /// The `caustic render` flags `gr.settings` had set when this image was asked for, in
    /// order (`["--gather-rays", "4"]`): the defaults the command line's own flags override.
    pub settings: Vec<String>,
}

impl RenderDesc {
    /// Returns where light `l` of a scene built for this render was made: the script's lights
    /// come first, in this render's order; the lights of placed meshes' emissive surfaces
    /// after them are placed by the render itself, so its line stands for them.
    pub fn light_loc<'a>(&'a self, desc: &'a SceneDesc, l: usize) -> &'a Loc {
        self.lights
            .get(l)
            .map_or(&self.loc, |id| &desc.lights[id.0 as usize].loc)
    }
}

/// Everything a script has described so far.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub nodes: Vec<NodeDesc>,
    pub materials: Vec<MaterialDesc>,
    pub lights: Vec<LightDesc>,
    pub meshes: Vec<MeshDesc>,
    /// Every `gr.render` call made so far, in order.
    pub renders: Vec<RenderDesc>,
    /// Warnings issued while running the script (also printed to stderr as they happen).
    pub warnings: Vec<String>,
    /// `--missing-textures=warn`: unreadable images fall back to `kd` with a warning.
    pub missing_textures_warn: bool,
    /// What `gr.settings` has set so far: a setting's name and its flag tokens, in the order
    /// first set.
    pub settings: Vec<(String, Vec<String>)>,
    /// The command's memory budget: the script's entries are charged to it as they are made,
    /// and every scene built from this description draws on it ([`crate::budget`]).
    pub budget: Budget,
}

impl SceneDesc {
    /// Returns the node with id `id`.
    pub fn node(&self, id: NodeId) -> &NodeDesc {
        &self.nodes[id.0 as usize]
    }

    /// Appends a node and returns its id.
    pub fn add_node(&mut self, name: impl Into<String>, kind: NodeKind, loc: Loc) -> NodeId {
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(NodeDesc {
            name: name.into(),
            kind,
            transform: DAffine3::IDENTITY,
            material: None,
            children: Vec::new(),
            loc,
        });
        id
    }
}
