//! glTF's metallic-roughness material in the terms of the one BSDF, per hit: what the base
//! colour and metallic-roughness textures make of `kd`, `ks` and the GGX roughness at a
//! texture coordinate ([`MetalRough::at`]).
//!
//! With base colour `c`, metallic `m` and roughness `r` (glTF 2.0 §3.9.2; the mapping is in
//! [`mod@crate::io::gltf`]'s doc) a surface is ([`Reflectance::metallic`]):
//! - `kd = c · (1 − m)`: a dielectric keeps its base colour, a metal has no diffuse lobe;
//! - `ks = mix(0.04, c, m)`: the mirror lobe, a rough conductor of GGX roughness `r`.
//!
//! A textured material evaluates this at every hit: `c` is the base colour texture's texel,
//! sRGB-decoded, times `baseColorFactor`; `m` and `r` are the metallic-roughness texture's
//! blue and green channels (linear) times their factors. So the texture keeps
//! `kd = base · (1 − metallic)` texel by texel, and a metal's colour, carried by `ks`, follows
//! the texture too. A material without these textures shades with the values its factors give,
//! stored in [`super::Material`]'s fields, at no cost per hit; only the kernel compiled with
//! textures ([`crate::scene::Features::textures`]) looks here.

use super::texture::Texture;
use glam::{Vec2, Vec3A};
use std::sync::Arc;

/// The dielectric reflectance at normal incidence glTF gives every non-metal (4 %).
pub const DIELECTRIC_F0: f32 = 0.04;

/// What a surface reflects at one point: the three inputs of the BSDF that textures vary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reflectance {
    /// Diffuse reflectance (before the `1 − t` weight).
    pub kd: Vec3A,
    /// Mirror (or rough-conductor) colour.
    pub ks: Vec3A,
    /// GGX roughness of the mirror lobe and of a transparent interface, in `[0, 1]`.
    pub roughness: f32,
}

impl Reflectance {
    /// Returns glTF's surface of base colour `base`, `metallic` and `roughness` (each in
    /// `[0, 1]`): `kd = base·(1 − metallic)`, `ks = mix(0.04, base, metallic)`.
    pub fn metallic(base: Vec3A, metallic: f32, roughness: f32) -> Reflectance {
        Reflectance {
            kd: base * (1.0 - metallic),
            ks: Vec3A::splat(DIELECTRIC_F0).lerp(base, metallic),
            roughness,
        }
    }
}

/// A glTF material's base colour and metallic-roughness textures with their factors.
#[derive(Clone, Debug, PartialEq)]
pub struct MetalRough {
    /// `baseColorFactor` (RGB) in `[0, 1]`.
    pub base_colour: Vec3A,
    /// `metallicFactor` in `[0, 1]`.
    pub metallic: f32,
    /// `roughnessFactor` in `[0, 1]`.
    pub roughness: f32,
    /// The sRGB-encoded base colour texture, multiplied by `base_colour`.
    pub base_colour_texture: Option<Arc<Texture>>,
    /// The linear metallic (blue) and roughness (green) texture, multiplied by the factors.
    pub metallic_roughness_texture: Option<Arc<Texture>>,
}

impl MetalRough {
    /// Returns the surface at texture coordinates `uv`: the textures' texels times the factors,
    /// mapped by [`Reflectance::metallic`].
    pub fn at(&self, uv: Vec2) -> Reflectance {
        let base = match &self.base_colour_texture {
            Some(t) => t.srgb_colour(uv) * self.base_colour,
            None => self.base_colour,
        };
        let (metallic, roughness) = match &self.metallic_roughness_texture {
            Some(t) => {
                let c = t.colour(uv);
                (c.z * self.metallic, c.y * self.roughness)
            }
            None => (self.metallic, self.roughness),
        };
        Reflectance::metallic(base, metallic, roughness)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without textures the surface is the factors'; the base colour texture multiplies the
    /// factor after its sRGB decoding, and the metallic-roughness texture's blue and green
    /// channels scale metallic and roughness, texel by texel.
    #[test]
    fn textures_scale_the_factors_texel_by_texel() {
        let plain = MetalRough {
            base_colour: Vec3A::new(1.0, 0.5, 0.25),
            metallic: 0.5,
            roughness: 0.8,
            base_colour_texture: None,
            metallic_roughness_texture: None,
        };
        let at = plain.at(Vec2::new(0.3, 0.7));
        assert_eq!(at, Reflectance::metallic(plain.base_colour, 0.5, 0.8));
        assert_eq!(at.kd, Vec3A::new(0.5, 0.25, 0.125));
        assert_eq!(at.ks, Vec3A::new(0.52, 0.27, 0.145));
        // sRGB 188 is linear 0.50289; the metallic-roughness texel (_, 51, 255) is roughness
        // 0.2 and metallic 1: a metal of the texture's colour, no diffuse lobe.
        let textured = MetalRough {
            base_colour_texture: Some(Arc::new(Texture::from_rgb(1, 1, vec![[188, 188, 0]]))),
            metallic_roughness_texture: Some(Arc::new(Texture::from_rgb(1, 1, vec![[0, 51, 255]]))),
            metallic: 1.0,
            roughness: 1.0,
            ..plain
        };
        let at = textured.at(Vec2::new(0.3, 0.7));
        assert_eq!(at.kd, Vec3A::ZERO);
        let want = Vec3A::new(0.502_886, 0.251_443, 0.0);
        assert!((at.ks - want).abs().max_element() < 1e-5, "{}", at.ks);
        assert!((at.roughness - 0.2).abs() < 1e-6);
    }
}
