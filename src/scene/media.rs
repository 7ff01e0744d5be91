//! Which media a point lies in, and what a medium absorbs along a segment.
//!
//! A path starts in the medium of its origin: a camera under water sees the water's surface from
//! below (Snell's window, total internal reflection), and a lamp in a pool sends its photons out
//! through the water. [`Scene::media_at`] finds the stack ([`MediumStack`]) of a point, which the
//! build stores for the camera ([`Scene::eye_media`]) and for each light
//! ([`Scene::light_media`]).
//!
//! # How a point's media are found
//! For each transparent instance whose box holds the point, probe rays in [`PROBES`] fixed
//! directions are cast from it against that instance alone. A probe whose first hit on the
//! instance leaves it (crosses with the outward normal, the side a ray there would pop the solid
//! off its stack by) votes inside; one that enters it or meets nothing votes outside. The
//! majority decides; a split vote (a point on the surface, a solid left open) is reported as
//! doubtful, so `caustic info` and the render can say so instead of guessing silently. The
//! stack is then entered from air in the order a ray would have to: absolute indices first,
//! relative ones (below 1, [`crate::material::medium`]) after, larger boxes before smaller ones.
//!
//! # Absorption
//! [`Scene::transmittance`] is Beer–Lambert along a segment in the winning medium:
//! `exp(−σ·d)` per channel, with `σ` the material's [`Material::absorption`] (per unit of world
//! length); 1 in air and in clear solids.

use super::Scene;
use crate::geometry::Ray;
use crate::material::Material;
use crate::material::medium::MediumStack;
use glam::Vec3A;

/// Probe rays per transparent instance whose box holds the point.
pub const PROBES: usize = 7;

/// The media a point lies in ([`Scene::media_at`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Media {
    /// The stack a path starting at the point carries.
    pub stack: MediumStack,
    /// The instances (TLAS order) the point is inside, outermost first.
    pub inside: Vec<u32>,
    /// Instances whose probes split their vote: the point lies on their surface or they are not
    /// closed, so whether it is inside is a guess.
    pub doubtful: Vec<u32>,
}

/// Returns the `k`-th of [`PROBES`] directions spread over the sphere (a golden-angle spiral,
/// turned so that none lies along an axis or a diagonal of the cube faces).
fn probe(k: usize) -> Vec3A {
    let z = 1.0 - (2.0 * k as f32 + 1.0) / PROBES as f32;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 0.3 + k as f32 * 2.399_963_2;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z).normalize()
}

impl Scene {
    /// Returns the media point `p` lies in (module docs).
    pub fn media_at(&self, p: Vec3A) -> Media {
        let mut media = Media::default();
        // (instance, material of a surface left, relative index, box volume)
        let mut found: Vec<(u32, u32, bool, f32)> = Vec::new();
        for &(i, b) in &self.transparent {
            if !(p.cmpge(b.min) & p.cmple(b.max)).all() {
                continue;
            }
            let mut votes = 0;
            let mut material = None;
            for k in 0..PROBES {
                let ray = Ray::new(p, probe(k));
                let Some(h) = self.hit_instance(i as usize, &ray) else {
                    continue;
                };
                let m = &self.materials[h.material as usize];
                if m.transparency > 0.0 && !self.enters(i as usize, &ray, &h) {
                    votes += 1;
                    material.get_or_insert(h.material);
                }
            }
            if votes != 0 && votes != PROBES {
                media.doubtful.push(i);
            }
            if let Some(m) = material.filter(|_| 2 * votes > PROBES) {
                let d = b.max - b.min;
                let relative = self.materials[m as usize].ior < 1.0;
                found.push((i, m, relative, d.x * d.y * d.z));
            }
        }
        found.sort_by(|a, b| a.2.cmp(&b.2).then(b.3.total_cmp(&a.3)));
        for &(i, m, _, _) in &found {
            let ior = self.materials[m as usize].ior;
            media.stack = media.stack.cross(m, ior, true).after;
            media.inside.push(i);
        }
        media
    }

    /// Returns the fraction of light per channel a segment of world length `distance` keeps in
    /// the medium of `media` (Beer–Lambert; 1 in air and clear solids, 0 over an infinite
    /// distance in an absorbing channel).
    pub fn transmittance(&self, media: &MediumStack, distance: f32) -> Vec3A {
        match media.winner().filter(|_| self.absorbing) {
            None => Vec3A::ONE,
            Some(id) => beer_lambert(&self.materials[id as usize], distance),
        }
    }

    /// [`Scene::transmittance`] along `ray` from its origin to parameter `t` (in units of its
    /// direction), the length taken only in a scene that absorbs: the paths' per-segment call.
    pub fn kept_along(&self, media: &MediumStack, ray: &Ray, t: f32) -> Vec3A {
        if !self.absorbing {
            return Vec3A::ONE;
        }
        self.transmittance(media, t * ray.dir.length())
    }
}

/// Returns `exp(−σ·d)` per channel for `material`'s absorption `σ`, exactly 1 where `σ = 0`
/// (also over an infinite distance).
pub fn beer_lambert(material: &Material, distance: f32) -> Vec3A {
    let s = material.absorption;
    if s == Vec3A::ZERO {
        return Vec3A::ONE;
    }
    let channel = |s: f32| if s > 0.0 { (-s * distance).exp() } else { 1.0 };
    Vec3A::new(channel(s.x), channel(s.y), channel(s.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probes_are_unit_and_spread() {
        let dirs: Vec<Vec3A> = (0..PROBES).map(probe).collect();
        for d in &dirs {
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.abs().max_element() < 0.99, "{d} lies along an axis");
        }
        // Spread: their mean is near the centre, so a half-open solid splits the vote.
        let mean = dirs.iter().sum::<Vec3A>() / PROBES as f32;
        assert!(mean.length() < 0.2, "{mean}");
    }

    #[test]
    fn beer_lambert_is_exp_of_minus_sigma_d() {
        let mut m = Material::fallback();
        assert_eq!(beer_lambert(&m, f32::INFINITY), Vec3A::ONE);
        m.absorption = Vec3A::new(0.0, 0.5, 2.0);
        let t = beer_lambert(&m, 2.0);
        assert_eq!(t.x, 1.0);
        assert!((t.y - (-1.0f32).exp()).abs() < 1e-6 && (t.z - (-4.0f32).exp()).abs() < 1e-6);
        assert_eq!(beer_lambert(&m, f32::INFINITY), Vec3A::new(1.0, 0.0, 0.0));
    }
}
