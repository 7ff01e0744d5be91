//! The per-hit set-up every path shares: the world-space surface at a hit and its scattering
//! model, built once ([`Scene::interaction`]) for eye rays, final-gather rays and photons alike.

use crate::geometry::Ray;
use crate::geometry::hit::{Hit, SurfaceHit};
use crate::material::bsdf::Bsdf;
use crate::scene::Scene;

/// A ray's hit made ready for scattering.
#[derive(Clone, Copy, Debug)]
pub struct Interaction<'a> {
    /// The surface as the shape gives it (unbent shading normal; the BSDF holds the bent one).
    pub surf: SurfaceHit,
    pub bsdf: Bsdf<'a>,
}

/// How much of the material a caller needs at a hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Needs {
    /// Everything: the shading normal bent by bump map and noise.
    Full,
    /// Only the diffuse reflectance and the geometric normal (photon-map lookups): the costly
    /// normal perturbation is skipped.
    Albedo,
}

impl Scene {
    /// Returns the surface and BSDF where `ray` found `hit`; with `clock`, adds the nanoseconds
    /// spent evaluating the material (textures, bump maps, noise) to it.
    pub fn interaction(
        &self,
        ray: &Ray,
        hit: &Hit,
        needs: Needs,
        clock: Option<&mut u64>,
    ) -> Interaction<'_> {
        let surf = self.surface(ray, hit);
        let material = &self.materials[surf.material as usize];
        let wo = -ray.dir.normalize();
        let start = clock.is_some().then(std::time::Instant::now);
        let mut bsdf = Bsdf::new(material, &surf, wo, needs == Needs::Full);
        // Only where a second transparent solid exists can one touch this surface.
        if material.transparency > 0.0 && self.transparent.len() > 1 {
            bsdf.touching = self.touching(ray, hit);
        }
        if let (Some(clock), Some(start)) = (clock, start) {
            *clock += start.elapsed().as_nanos() as u64;
        }
        Interaction { surf, bsdf }
    }
}
