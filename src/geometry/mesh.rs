//! Triangle meshes as plain data in object space ([`MeshData`]), with the materials a mesh file
//! carries ([`MeshMaterial`]) and the images those name or embed ([`ImageSource`]).
//!
//! `MeshData` lives here, among the shapes, because three floors meet on it and all sit above
//! geometry: the loaders in `io` produce it, generators such as [`super::water`] make it, and the
//! BLAS builder ([`crate::accel::mesh::MeshGeom`]) turns it into the traceable form. It holds no
//! BVH and reads no file. Vertex attributes are indexed by one index per corner (loaders unify
//! `v/vt/vn` triples into single vertices). The scene build reads each file once per build and
//! builds one `MeshGeom` from it, shared by every instance of the mesh.

use glam::{Vec2, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

/// A triangle mesh as loaded from a file, in the object space of its node.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions; every entry is finite (loaders reject NaN and infinity).
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, parallel to `positions`, or empty when the file has none.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, parallel to `positions`, or empty when the file has none.
    pub uvs: Vec<Vec2>,
    /// Triangles as indices into `positions` (always in range).
    pub triangles: Vec<[u32; 3]>,
    /// Materials the file defines (OBJ `usemtl`/MTL, glTF materials), used where the script sets none.
    pub materials: Vec<MeshMaterial>,
    /// Per-triangle index into `materials`, parallel to `triangles`, or empty when the file has none.
    pub triangle_materials: Vec<u32>,
    /// The file this mesh was read from, for messages.
    pub source: PathBuf,
    /// Emissive surfaces the file carries (glTF primitives whose material emits): the scene
    /// build makes each placed one a light ([`crate::light::Light::mesh`]); they are not in
    /// `triangles`.
    pub emitters: Vec<MeshEmitter>,
}

/// An emissive surface of a mesh file: one primitive under one node, in the mesh's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshEmitter {
    /// The emitting material's name, for messages.
    pub name: String,
    /// Emitted radiance per channel (glTF `emissiveFactor × emissiveStrength`).
    pub radiance: Vec3,
    /// Triangles, each counter-clockwise seen from the side it emits on.
    pub triangles: Vec<[Vec3; 3]>,
}

/// A material carried by a mesh file, in the terms of `gr.material`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshMaterial {
    /// The file's name for it, for messages.
    pub name: String,
    /// Diffuse colour (OBJ `Kd`, glTF base colour).
    pub kd: Vec3,
    /// Specular colour (OBJ `Ks`; glTF: `mix(0.04, baseColor, metallic)`).
    pub ks: Vec3,
    /// Phong exponent (OBJ `Ns`; glTF: a mirror's, unused: its roughness is a GGX lobe).
    pub shininess: f32,
    /// Transparency in [0, 1] (OBJ `1 - d`, glTF `KHR_materials_transmission`).
    pub transparency: f32,
    /// Index of refraction (OBJ `Ni`, glTF `KHR_materials_ior`, default 1.5 for glTF).
    pub ior: f32,
    /// Absorption coefficient per channel per unit length of the interior (glTF
    /// `KHR_materials_volume`: `−ln(attenuationColor)/attenuationDistance`); zero for clear.
    pub absorption: Vec3,
    /// GGX roughness of the mirror lobe and the dielectric interface in `[0, 1]` (glTF
    /// `roughnessFactor`, `alpha = roughness²`; OBJ: 0, Phong's exponent stands in).
    pub roughness: f32,
    /// Texture replacing `kd` (OBJ `map_Kd`), resolved to a path; glTF's textures are in `pbr`.
    pub texture: Option<PathBuf>,
    /// Radiance emitted (glTF `emissiveFactor × KHR_materials_emissive_strength`; zero for
    /// OBJ): the primitive is also one of [`MeshData::emitters`].
    pub emission: Vec3,
    /// glTF's textures and the factors they scale, looked up per hit; `None` for OBJ materials
    /// and glTF materials without a texture caustic reads.
    pub pbr: Option<MeshPbr>,
}

/// A glTF material's textures with the factors they multiply: what the scene build turns into
/// per-hit lookups ([`crate::material::pbr`]). `kd`, `ks` and `roughness` of the material hold
/// the factors' values, which shading uses wherever a texture is absent or turned off.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPbr {
    /// `baseColorFactor` (RGB), clamped to `[0, 1]`.
    pub base_colour: Vec3,
    /// `metallicFactor` in `[0, 1]`.
    pub metallic: f32,
    /// `roughnessFactor` in `[0, 1]`.
    pub roughness: f32,
    /// `baseColorTexture`: sRGB-encoded, multiplied by `base_colour`.
    pub base_colour_texture: Option<ImageSource>,
    /// `metallicRoughnessTexture`: linear; blue is metallic, green roughness, each multiplied
    /// by its factor.
    pub metallic_roughness_texture: Option<ImageSource>,
    /// `normalTexture`: a linear tangent-space normal map.
    pub normal_texture: Option<ImageSource>,
    /// `normalTexture.scale`: what the map's x and y are multiplied by.
    pub normal_scale: f32,
}

/// Where a mesh file's image is: a file beside it, or encoded bytes inside it.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// An image file (glTF `uri`), resolved against the mesh file's folder.
    File(PathBuf),
    /// Encoded PNG or JPEG bytes the mesh file carries (a GLB buffer view, a buffer, a `data:`
    /// URI): image `image` of `file`.
    Embedded {
        /// The mesh file, for messages.
        file: PathBuf,
        /// The image's index in the file.
        image: usize,
        /// The encoded bytes, shared by every material that uses the image.
        bytes: Arc<[u8]>,
    },
}

impl ImageSource {
    /// Returns the image's name for messages: its path, or "FILE image N".
    pub fn describe(&self) -> String {
        match self {
            ImageSource::File(path) => path.display().to_string(),
            ImageSource::Embedded { file, image, .. } => {
                format!("{} image {image}", file.display())
            }
        }
    }
}

impl MeshData {
    /// Returns the number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}
