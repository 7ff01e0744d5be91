//! Surface materials as the renderer uses them; what a material does at one hit, for eye rays,
//! gather rays and photons alike, is its [`bsdf::Bsdf`].
//!
//! `gr.material(kd, ks, p [, t [, ior [, s [, texture [, bump]]]]])` means:
//! - `kd`: diffuse reflectance, which also multiplies the ambient light; a `texture` replaces it
//!   (looked up at the hit's texture coordinates, [`texture`]);
//! - `ks`, `p`: a Phong highlight `ks·(r·v)^p` from each light, and mirror reflection weighted by
//!   `ks`;
//! - `t`, `ior`: with weight `t` the surface is a clear dielectric interface into a solid of index
//!   `ior` (Fresnel reflection and refraction, [`fresnel`], with media tracked by [`medium`]);
//!   the opaque behaviour above has weight `1 − t`;
//! - `gr.absorption(material, colour, distance)`: the solid's interior keeps `colour` of the
//!   light that crosses `distance` of it (Beer–Lambert, glTF's `KHR_materials_volume`):
//!   [`Material::absorption`] `σ = −ln(colour)/distance`;
//! - `s`: Perlin-noise bending of the shading normal ([`perlin`]);
//! - `bump`: an RGB tangent-space normal map or a grey height map ([`texture::BumpMap`]).
//!
//! A glTF mesh's material may carry textures of glTF's own model instead ([`pbr`]): base colour,
//! metallic and roughness looked up per hit, which give `kd`, `ks` and the roughness there
//! ([`Material::reflectance`]); its normal texture is a `bump` map.

pub mod bsdf;
pub mod fresnel;
pub mod medium;
pub mod microfacet;
pub mod pbr;
pub mod perlin;
pub mod texture;

use crate::desc::MaterialDesc;
use crate::geometry::mesh::MeshMaterial;
use glam::{Vec2, Vec3A};
use pbr::{MetalRough, Reflectance};
use std::sync::Arc;
use texture::{BumpMap, Texture};

/// The weights of a material's behaviours ([`Material::lobes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobes {
    pub diffuse: Vec3A,
    pub mirror: Vec3A,
    pub dielectric: f32,
}

impl Lobes {
    /// Returns the largest channel of the lobes' sum, `(kd + ks)·(1 − t) + t`: the share of the
    /// light arriving that the surface sends on in its brightest channel, above 1
    /// ([`crate::range::MAX_ALBEDO`]) for a surface that reflects more than it receives.
    pub fn total(&self) -> f32 {
        (self.diffuse + self.mirror + Vec3A::splat(self.dielectric)).max_element()
    }
}

/// A material ready for shading.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub kd: Vec3A,
    pub ks: Vec3A,
    pub shininess: f32,
    pub transparency: f32,
    /// Index of refraction of the interior: absolute from 1 up, relative to the containing
    /// medium below 1 ([`medium`]).
    pub ior: f32,
    /// Absorption coefficient `σ` per channel, per unit of world length, of the interior of a
    /// transparent solid (Beer–Lambert, [`crate::scene::media`]); zero for clear.
    pub absorption: Vec3A,
    /// GGX roughness of the mirror lobe (`gr.roughness`): 0 is the smooth mirror, above 0 the
    /// rough conductor of [`microfacet`] (`alpha = roughness²`) replaces the mirror and the Phong
    /// highlight.
    pub roughness: f32,
    /// Scale of the Perlin-noise normal perturbation; 0 for none.
    pub perlin_scale: f32,
    /// Colour map replacing `kd`.
    pub texture: Option<Arc<Texture>>,
    /// glTF base colour and metallic-roughness textures: where present, `kd`, `ks` and
    /// `roughness` at a hit come from them ([`MetalRough::at`]), and the fields above hold the
    /// factors' values.
    pub metal_rough: Option<Arc<MetalRough>>,
    /// Normal or height map.
    pub bump: Option<Arc<BumpMap>>,
    /// Radiance the surface emits (a glTF emissive material; zero otherwise). Its light is a
    /// mesh light over the same triangles ([`crate::scene::emitters`]), which is what shading
    /// reads; the surface keeps it so that exporters write it as the emitter it is.
    pub emission: Vec3A,
}

impl Material {
    /// Returns the material a script described, with its images already loaded (or `None`).
    pub fn from_desc(
        d: &MaterialDesc,
        texture: Option<Arc<Texture>>,
        bump: Option<Arc<BumpMap>>,
    ) -> Material {
        Material {
            kd: d.kd.into(),
            ks: d.ks.into(),
            shininess: d.shininess,
            transparency: d.transparency,
            ior: d.ior,
            absorption: d.absorption.into(),
            roughness: d.roughness,
            perlin_scale: d.perlin_scale,
            texture,
            metal_rough: None,
            bump,
            emission: Vec3A::ZERO,
        }
    }

    /// Returns the material a mesh file defined, with its `kd` texture already loaded (or
    /// `None`); the caller adds the glTF textures ([`Material::metal_rough`], `bump`).
    pub fn from_mesh(m: &MeshMaterial, texture: Option<Arc<Texture>>) -> Material {
        Material {
            kd: m.kd.into(),
            ks: m.ks.into(),
            shininess: m.shininess,
            transparency: m.transparency,
            ior: m.ior,
            absorption: m.absorption.into(),
            roughness: m.roughness,
            perlin_scale: 0.0,
            texture,
            metal_rough: None,
            bump: None,
            emission: m.emission.into(),
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
            absorption: Vec3A::ZERO,
            roughness: 0.0,
            perlin_scale: 0.0,
            texture: None,
            metal_rough: None,
            bump: None,
            emission: Vec3A::ZERO,
        }
    }

    /// Returns true when the surface can reflect like a mirror: any `ks` channel above 0, or
    /// glTF textures, whose texels give `ks` at each hit.
    pub fn is_reflective(&self) -> bool {
        self.ks.max_element() > 0.0 || self.metal_rough.is_some()
    }

    /// Returns true when a texture varies the surface's colours ([`Material::reflectance`]).
    pub fn is_textured(&self) -> bool {
        self.texture.is_some() || self.metal_rough.is_some()
    }

    /// Returns `kd`, `ks` and the roughness at texture coordinates `uv`: the glTF textures'
    /// ([`MetalRough::at`]), else the colour map in place of `kd`, else the material's own.
    pub fn reflectance(&self, uv: Vec2) -> Reflectance {
        if let Some(p) = &self.metal_rough {
            return p.at(uv);
        }
        Reflectance {
            kd: self.texture.as_ref().map_or(self.kd, |t| t.colour(uv)),
            ks: self.ks,
            roughness: self.roughness,
        }
    }

    /// Returns the weights of the material's three behaviours for a surface of diffuse colour
    /// `kd` and mirror colour `ks` (the material's, or its textures' at a hit): Lambertian
    /// `(1 − t)·kd`, mirror `(1 − t)·ks` and dielectric `t` (Fresnel then splits the last into
    /// reflection and refraction). Eye rays weight their terms by these, and photons choose
    /// among them with these probabilities.
    pub fn lobes(&self, kd: Vec3A, ks: Vec3A) -> Lobes {
        let opaque = 1.0 - self.transparency;
        Lobes {
            diffuse: kd * opaque,
            mirror: ks * opaque,
            dielectric: self.transparency,
        }
    }

    /// Returns true when the surface can scatter light specularly (a caustic caster).
    pub fn is_specular(&self) -> bool {
        self.transparency > 0.0 || (self.transparency < 1.0 && self.is_reflective())
    }

    /// Returns the shading normal at a hit: `ns` bent by the bump map (in the frame of `dpdu`)
    /// and by Perlin noise at world point `p`, never tilted past the surface's geometric
    /// hemisphere (`ng`, same side as `ns`), so a surface never looks lit from behind.
    pub fn shading_normal(&self, ns: Vec3A, ng: Vec3A, p: Vec3A, uv: Vec2, dpdu: Vec3A) -> Vec3A {
        self.shading_normal_with::<true, true>(ns, ng, p, uv, dpdu)
    }

    /// [`Material::shading_normal`] compiled with the bump map's code only when `BUMP` and the
    /// noise's only when `NOISE` ([`crate::scene::Features`]).
    pub fn shading_normal_with<const BUMP: bool, const NOISE: bool>(
        &self,
        ns: Vec3A,
        ng: Vec3A,
        p: Vec3A,
        uv: Vec2,
        dpdu: Vec3A,
    ) -> Vec3A {
        let mut n = ns;
        if BUMP && let Some(b) = &self.bump {
            n = texture::apply_tangent_normal(n, dpdu, b.tangent_normal(uv));
        }
        if NOISE && self.perlin_scale > 0.0 {
            n = perlin::perturb_normal(n, p, self.perlin_scale);
        }
        keep_in_hemisphere(n, ng)
    }
}

/// Returns the absorption coefficient of a volume that keeps `colour` of the light over
/// `distance`: `−ln(colour)/distance` per channel, the colour held to `[MIN_ATTENUATION, 1]`
/// (a black channel absorbs everything within a millionth of the distance, not infinitely).
pub fn absorption(colour: [f32; 3], distance: f32) -> glam::Vec3 {
    if distance == f32::INFINITY {
        return glam::Vec3::ZERO;
    }
    // `ln(1)` is 0, and `−0 / d` is −0: a channel kept whole must read as a plain 0.
    glam::Vec3::from_array(colour.map(|c| {
        let c = c.clamp(MIN_ATTENUATION, 1.0);
        if c == 1.0 { 0.0 } else { -c.ln() / distance }
    }))
}

/// Least fraction of light an absorbing volume keeps over its attenuation distance.
pub const MIN_ATTENUATION: f32 = 1e-6;

/// Smallest cosine allowed between a shading normal and the geometric normal.
const MIN_SHADING_COS: f32 = 0.05;

/// Returns `n` tilted back towards `ng` when it leans past the hemisphere around `ng`.
pub fn keep_in_hemisphere(n: Vec3A, ng: Vec3A) -> Vec3A {
    let c = n.dot(ng);
    if c >= MIN_SHADING_COS {
        n
    } else {
        (n + ng * (2.0 * MIN_SHADING_COS - c)).normalize_or(ng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shading_normals_stay_in_the_geometric_hemisphere() {
        for k in 0..360 {
            let a = (k as f32).to_radians();
            let n = Vec3A::new(a.cos(), 0.3, a.sin()).normalize();
            let kept = keep_in_hemisphere(n, Vec3A::Z);
            assert!(
                kept.dot(Vec3A::Z) > 0.0 && (kept.length() - 1.0).abs() < 1e-5,
                "{n} -> {kept}"
            );
            if n.z >= MIN_SHADING_COS {
                assert_eq!(kept, n);
            }
        }
        // A strong Perlin perturbation on a grazing base normal still faces out.
        let mut m = Material::fallback();
        m.perlin_scale = 50.0;
        for k in 0..200 {
            let p = Vec3A::new(k as f32 * 0.0137, 0.3, 0.0);
            let n = m.shading_normal(Vec3A::Z, Vec3A::Z, p, Vec2::ZERO, Vec3A::X);
            assert!(n.dot(Vec3A::Z) > 0.0);
        }
    }

    #[test]
    fn absorption_keeps_the_colour_over_the_distance() {
        let s = absorption([0.5, 0.25, 1.0], 2.0);
        let kept = (-s * 2.0).exp();
        assert!(
            (kept - glam::Vec3::new(0.5, 0.25, 1.0)).abs().max_element() < 1e-6,
            "{kept}"
        );
        assert_eq!(absorption([0.5; 3], f32::INFINITY), glam::Vec3::ZERO);
        assert!(absorption([0.0; 3], 1e-6).is_finite());
    }
}
