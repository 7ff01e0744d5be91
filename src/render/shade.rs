//! Shading: what one eye ray sees.
//!
//! A material `(kd, ks, p, t, ior)` is a mix of two surfaces, weighted by the transparency `t`
//! (see [`crate::material`]):
//! - with weight `1 − t`, an opaque surface: ambient `kd·ambient` (only without global
//!   illumination), direct light from every light by shadow rays
//!   `Σ att(d)·I(θ)·(kd·max(0, n·l) + ks·max(0, r·v)^p)` (area and sphere lights averaged over
//!   `light_samples` stratified samples: soft shadows), `ks` times the mirror-reflected radiance,
//!   and, with photon maps, caustics and indirect diffuse light ([`crate::render::gi`]);
//! - with weight `t`, a clear dielectric interface: Fresnel reflectance `F` of the reflected ray
//!   and `1 − F` of the refracted one, between the media on either side.
//!
//! Rays carry a [`MediumStack`], so nested and touching dielectrics refract with the ratio of the
//! two media at each interface, and the boundary of a solid inside a denser one (a water surface
//! inside a glass ball) is passed through untouched. Normals are flipped to face the incoming ray
//! for the opaque part, so both sides of a surface shade alike.

use super::RayCounts;
use super::gi::Gi;
use crate::camera::Camera;
use crate::geometry::{Ray, offset_ray_origin};
use crate::material::fresnel;
use crate::material::medium::{Crossing, MediumStack};
use crate::sampling::{Rng, stratified_2d};
use crate::scene::Scene;
use crate::scene::build::SurfaceHit;
use glam::Vec3A;

/// Deepest chain of reflections and refractions followed.
pub const MAX_DEPTH: u32 = 12;
/// Paths whose weight falls below this are not traced further.
const MIN_WEIGHT: f32 = 1e-3;

/// Where an eye path stands: how deep, how much it still matters, which medium it is in.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub depth: u32,
    /// Largest channel of the product of weights so far.
    pub weight: f32,
    pub media: MediumStack,
}

impl PathState {
    /// Returns the state of a camera ray (in air).
    pub fn camera() -> PathState {
        PathState {
            depth: 0,
            weight: 1.0,
            media: MediumStack::air(),
        }
    }

    fn child(&self, weight: f32, media: MediumStack) -> PathState {
        PathState {
            depth: self.depth + 1,
            weight: self.weight * weight,
            media,
        }
    }
}

/// Returns the background seen along `dir`: a vertical gradient in the camera's frame, so objects
/// stand out against it wherever they are.
pub fn background(camera: &Camera, dir: Vec3A) -> Vec3A {
    let s = (0.5 * (dir.normalize().dot(camera.v) + 1.0)).clamp(0.0, 1.0);
    let bottom = Vec3A::new(0.02, 0.02, 0.08);
    let top = Vec3A::new(0.30, 0.42, 0.75);
    bottom + (top - bottom) * s
}

/// Everything shading needs besides the ray: the scene, the camera (for the background), and
/// the photon maps when global illumination is on.
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// Shadow-ray samples per area or sphere light at each shaded point.
    pub light_samples: u32,
    /// Photon maps and how to use them; `None` renders as the course does (ambient term).
    pub gi: Option<&'a Gi>,
}

impl Tracer<'_> {
    /// Returns the radiance arriving along `ray` (towards its origin).
    pub fn radiance(
        &self,
        ray: &Ray,
        state: PathState,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let Some(hit) = self.scene.intersect(ray) else {
            return background(self.camera, ray.dir);
        };
        let mut surf = self.scene.surface(ray, &hit);
        let mat = &self.scene.materials[surf.material as usize];
        let start = counts.timing.then(std::time::Instant::now);
        let kd = mat.diffuse(surf.uv);
        if mat.perturbs_normals() {
            surf.ns = mat.shading_normal(surf.ns, surf.ng, surf.p, surf.uv, surf.dpdu);
        }
        if let Some(start) = start {
            counts.material_nanos += start.elapsed().as_nanos() as u64;
        }
        let wo = -ray.dir.normalize();
        let front = surf.ng.dot(wo) > 0.0;
        let t = mat.transparency;

        let mut out = Vec3A::ZERO;
        if t > 0.0 {
            let crossing = state.media.cross(surf.material, mat.ior, front);
            if crossing.is_false() {
                // The boundary of a solid inside a denser one: no surface here, go straight on.
                if state.depth >= MAX_DEPTH {
                    return Vec3A::ZERO;
                }
                let next = Ray::new(offset_ray_origin(surf.p, surf.ng, ray.dir), ray.dir);
                counts.secondary += 1;
                return self.radiance(&next, state.child(1.0, crossing.after), rng, counts);
            }
            if state.depth < MAX_DEPTH {
                out += t * self.dielectric(&surf, wo, front, crossing, state, rng, counts);
            }
        }
        if t < 1.0 {
            out += (1.0 - t) * self.opaque(&surf, kd, wo, state, rng, counts);
        }
        out
    }

    /// Returns the direct light from every light at `surf` towards `wo`, by shadow rays, for a
    /// surface of diffuse colour `kd` facing the viewer with normals `n` (shading) and `ng`.
    #[allow(clippy::too_many_arguments)]
    pub fn direct(
        &self,
        surf: &SurfaceHit,
        kd: Vec3A,
        n: Vec3A,
        ng: Vec3A,
        wo: Vec3A,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let mat = &self.scene.materials[surf.material as usize];
        let mut colour = Vec3A::ZERO;
        for light in &self.scene.lights {
            let samples = if light.is_area() {
                stratified_2d(rng, self.light_samples)
            } else {
                vec![(0.5, 0.5)]
            };
            let mut sum = Vec3A::ZERO;
            for &u in &samples {
                let ls = light.sample(surf.p, u);
                let to_light = ls.position - surf.p;
                let d = to_light.length();
                if d == 0.0 || ls.intensity == Vec3A::ZERO {
                    continue;
                }
                let wi = to_light / d;
                let cos = n.dot(wi);
                if cos <= 0.0 || ng.dot(wi) <= 0.0 {
                    continue;
                }
                let origin = offset_ray_origin(surf.p, ng, wi);
                let shadow = Ray::new(origin, ls.position - origin).with_tmax(1.0 - 1e-4);
                counts.shadow += 1;
                if self.scene.occluded(&shadow) {
                    continue;
                }
                let rv = fresnel::reflect(wi, n).dot(wo);
                let spec = if rv > 0.0 && mat.shininess > 0.0 {
                    mat.ks * rv.powf(mat.shininess)
                } else {
                    Vec3A::ZERO
                };
                sum += ls.intensity * light.attenuation(d) * (kd * cos + spec);
            }
            colour += sum / samples.len() as f32;
        }
        colour
    }

    /// Returns the light the opaque part of a surface sends towards `wo`.
    fn opaque(
        &self,
        surf: &SurfaceHit,
        kd: Vec3A,
        wo: Vec3A,
        state: PathState,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let mat = &self.scene.materials[surf.material as usize];
        // Face the viewer: both sides of a surface shade alike.
        let (n, ng) = if surf.ng.dot(wo) < 0.0 {
            (-surf.ns, -surf.ng)
        } else {
            (surf.ns, surf.ng)
        };
        let mut colour = self.direct(surf, kd, n, ng, wo, rng, counts);
        match self.gi {
            None => colour += self.scene.ambient * kd,
            Some(gi) => {
                if kd.max_element() > 0.0 {
                    colour += gi.diffuse(self, surf.p, n, ng, kd, state.depth, rng, counts);
                }
            }
        }
        let weight = mat.ks.max_element();
        if mat.is_reflective() && state.depth < MAX_DEPTH && state.weight * weight > MIN_WEIGHT {
            let wr = reflect_above(wo, n, ng);
            let ray = Ray::new(offset_ray_origin(surf.p, ng, wr), wr);
            counts.secondary += 1;
            colour += mat.ks * self.radiance(&ray, state.child(weight, state.media), rng, counts);
        }
        colour
    }

    /// Returns the light a dielectric interface sends towards `wo`: Fresnel-weighted reflection
    /// and refraction between the media on either side of `crossing`.
    #[allow(clippy::too_many_arguments)]
    fn dielectric(
        &self,
        surf: &SurfaceHit,
        wo: Vec3A,
        front: bool,
        crossing: Crossing,
        state: PathState,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        // Normals on the side the ray arrives from.
        let (n, ng) = if front {
            (surf.ns, surf.ng)
        } else {
            (-surf.ns, -surf.ng)
        };
        let eta = crossing.n_from / crossing.n_to;
        let f = fresnel::dielectric(n.dot(wo).max(0.0), eta);
        let mut out = Vec3A::ZERO;
        if f > 0.0 && state.weight * f > MIN_WEIGHT {
            let wr = reflect_above(wo, n, ng);
            let ray = Ray::new(offset_ray_origin(surf.p, ng, wr), wr);
            counts.secondary += 1;
            out += f * self.radiance(&ray, state.child(f, state.media), rng, counts);
        }
        if f < 1.0
            && state.weight * (1.0 - f) > MIN_WEIGHT
            && let Some(wt) = fresnel::refract(wo, n, eta)
            && wt.dot(ng) < 0.0
        {
            let ray = Ray::new(offset_ray_origin(surf.p, ng, wt), wt);
            counts.secondary += 1;
            out +=
                (1.0 - f) * self.radiance(&ray, state.child(1.0 - f, crossing.after), rng, counts);
        }
        out
    }
}

/// Returns `wo` mirrored about the shading normal `n`, or about the geometric normal `ng` when a
/// bent shading normal would send it below the surface.
pub fn reflect_above(wo: Vec3A, n: Vec3A, ng: Vec3A) -> Vec3A {
    let wr = fresnel::reflect(wo, n);
    if wr.dot(ng) > 0.0 {
        wr
    } else {
        fresnel::reflect(wo, ng)
    }
}
