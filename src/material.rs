//! Surface materials as the renderer uses them.
//!
//! `gr.material(kd, ks, p [, t [, ior [, s [, texture [, bump]]]]])` means: diffuse reflectance
//! `kd` (which also multiplies the ambient light), a Phong highlight `ks·(r·v)^p`, mirror
//! reflection weighted by `ks`, and, when `t > 0`, refraction into a medium of index `ior` with
//! weight `t`. Textures, normal maps and Perlin-noise normals are parsed and validated but not yet
//! simulated by the first renderer (see the materials issue).

pub mod fresnel;
pub mod medium;
pub mod perlin;
pub mod texture;

use crate::geometry::mesh::MeshMaterial;
use crate::scene::desc::MaterialDesc;
use glam::Vec3A;

/// A material ready for shading.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub kd: Vec3A,
    pub ks: Vec3A,
    pub shininess: f32,
    pub transparency: f32,
    pub ior: f32,
}

impl Material {
    /// Returns the material a script described.
    pub fn from_desc(d: &MaterialDesc) -> Material {
        Material {
            kd: d.kd.into(),
            ks: d.ks.into(),
            shininess: d.shininess,
            transparency: d.transparency,
            ior: d.ior,
        }
    }

    /// Returns the material a mesh file defined (its texture is not used yet).
    pub fn from_mesh(m: &MeshMaterial) -> Material {
        Material {
            kd: m.kd.into(),
            ks: m.ks.into(),
            shininess: m.shininess,
            transparency: m.transparency,
            ior: m.ior,
        }
    }

    /// Returns the matte grey used for geometry that never got a material.
    pub fn fallback() -> Material {
        Material {
            kd: Vec3A::splat(0.6),
            ks: Vec3A::ZERO,
            shininess: 0.0,
            transparency: 0.0,
            ior: 1.0,
        }
    }

    /// Returns true when the surface reflects like a mirror (any `ks` channel above 0).
    pub fn is_reflective(&self) -> bool {
        self.ks.max_element() > 0.0
    }
}
