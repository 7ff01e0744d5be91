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
        let mut bsdf = self.kernel(needs)(material, &surf, wo);
        // Only where a second transparent solid exists can one touch this surface.
        if material.transparency > 0.0 && self.transparent.len() > 1 {
            bsdf.touching = self.touching(ray, hit);
        }
        if let (Some(clock), Some(start)) = (clock, start) {
            *clock += start.elapsed().as_nanos() as u64;
        }
        Interaction { surf, bsdf }
    }

    /// Returns the BSDF kernel for hits that need `needs`, compiled without the shading effects
    /// the plan left out ([`crate::scene::Features`]): one choice per hit among eight
    /// instances, instead of a check per effect.
    fn kernel<'a>(&self, needs: Needs) -> Kernel<'a> {
        let f = self.features;
        let bend = needs == Needs::Full;
        macro_rules! pick {
            ($($t:literal, $b:literal, $n:literal);*) => {
                match (f.textures, bend && f.normal_maps, bend && f.noise) {
                    $(($t, $b, $n) => Bsdf::kernel::<$t, $b, $n>,)*
                }
            };
        }
        pick!(true, true, true; true, true, false; true, false, true; true, false, false;
              false, true, true; false, true, false; false, false, true; false, false, false)
    }
}

/// A BSDF kernel ([`Bsdf::kernel`]).
type Kernel<'a> = fn(&'a crate::material::Material, &SurfaceHit, glam::Vec3A) -> Bsdf<'a>;
