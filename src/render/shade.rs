//! Whitted-style shading: what one eye ray sees.
//!
//! A material `(kd, ks, p, t, ior)` is a mix of two surfaces, weighted by the transparency `t`:
//! - with weight `1 − t`, an opaque Phong surface:
//!   `kd·ambient + Σ_visible lights att(d)·I·(kd·max(0, n·l) + ks·max(0, r·v)^p)` plus `ks`
//!   times the mirror-reflected radiance;
//! - with weight `t`, a clear dielectric interface between the medium the ray is in and the
//!   solid's interior of index `ior`: Fresnel reflectance `F` of the reflected ray and `1 − F`
//!   of the refracted one (total internal reflection reflects everything).
//!
//! Rays carry a [`MediumStack`], so nested and touching dielectrics refract with the ratio of the
//! two media at each interface, and the boundary of a solid inside a denser one (a water surface
//! inside a glass ball) is passed through untouched. Normals are flipped to face the incoming ray
//! for the opaque part, so both sides of a surface shade alike.

use super::RayCounts;
use crate::camera::Camera;
use crate::geometry::{Ray, offset_ray_origin};
use crate::material::fresnel;
use crate::material::medium::MediumStack;
use crate::scene::Scene;
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

/// Returns the radiance arriving along `ray` (towards its origin).
pub fn radiance(
    scene: &Scene,
    camera: &Camera,
    ray: &Ray,
    state: PathState,
    counts: &mut RayCounts,
) -> Vec3A {
    let Some(hit) = scene.intersect(ray) else {
        return background(camera, ray.dir);
    };
    let mut surf = scene.surface(ray, &hit);
    let mat = &scene.materials[surf.material as usize];
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
            return continue_straight(
                scene,
                camera,
                surf.p,
                surf.ng,
                ray.dir,
                state,
                crossing.after,
                counts,
            );
        }
        if state.depth < MAX_DEPTH {
            out += t * dielectric(scene, camera, &surf, wo, front, crossing, state, counts);
        }
    }
    if t < 1.0 {
        out += (1.0 - t) * opaque(scene, camera, &surf, kd, wo, state, counts);
    }
    out
}

/// Returns the light the opaque Phong part of a surface sends towards `wo`.
fn opaque(
    scene: &Scene,
    camera: &Camera,
    surf: &crate::scene::build::SurfaceHit,
    kd: Vec3A,
    wo: Vec3A,
    state: PathState,
    counts: &mut RayCounts,
) -> Vec3A {
    let mat = &scene.materials[surf.material as usize];
    // Face the viewer: both sides of a surface shade alike.
    let (n, ng) = if surf.ng.dot(wo) < 0.0 {
        (-surf.ns, -surf.ng)
    } else {
        (surf.ns, surf.ng)
    };
    let mut colour = scene.ambient * kd;
    for light in &scene.lights {
        let to_light = light.position - surf.p;
        let d = to_light.length();
        if d == 0.0 {
            continue;
        }
        let wi = to_light / d;
        let cos = n.dot(wi);
        if cos <= 0.0 || ng.dot(wi) <= 0.0 {
            continue;
        }
        let origin = offset_ray_origin(surf.p, ng, wi);
        let shadow = Ray::new(origin, light.position - origin).with_tmax(1.0 - 1e-4);
        counts.shadow += 1;
        if scene.occluded(&shadow) {
            continue;
        }
        let rv = fresnel::reflect(wi, n).dot(wo);
        let spec = if rv > 0.0 && mat.shininess > 0.0 {
            mat.ks * rv.powf(mat.shininess)
        } else {
            Vec3A::ZERO
        };
        colour += light.colour * light.attenuation(d) * (kd * cos + spec);
    }
    let weight = mat.ks.max_element();
    if mat.is_reflective() && state.depth < MAX_DEPTH && state.weight * weight > MIN_WEIGHT {
        let wr = reflect_above(wo, n, ng);
        let ray = Ray::new(offset_ray_origin(surf.p, ng, wr), wr);
        counts.secondary += 1;
        colour += mat.ks
            * radiance(
                scene,
                camera,
                &ray,
                state.child(weight, state.media),
                counts,
            );
    }
    colour
}

/// Returns the light a dielectric interface sends towards `wo`: Fresnel-weighted reflection and
/// refraction between the media on either side of `crossing`.
#[allow(clippy::too_many_arguments)]
fn dielectric(
    scene: &Scene,
    camera: &Camera,
    surf: &crate::scene::build::SurfaceHit,
    wo: Vec3A,
    front: bool,
    crossing: crate::material::medium::Crossing,
    state: PathState,
    counts: &mut RayCounts,
) -> Vec3A {
    // Normals on the side the ray arrives from.
    let (n, ng) = if front {
        (surf.ns, surf.ng)
    } else {
        (-surf.ns, -surf.ng)
    };
    let eta = crossing.n_from / crossing.n_to;
    let cos_i = n.dot(wo).max(0.0);
    let f = fresnel::dielectric(cos_i, eta);
    let mut out = Vec3A::ZERO;
    if f > 0.0 && state.weight * f > MIN_WEIGHT {
        let wr = reflect_above(wo, n, ng);
        let ray = Ray::new(offset_ray_origin(surf.p, ng, wr), wr);
        counts.secondary += 1;
        out += f * radiance(scene, camera, &ray, state.child(f, state.media), counts);
    }
    if f < 1.0
        && state.weight * (1.0 - f) > MIN_WEIGHT
        && let Some(wt) = fresnel::refract(wo, n, eta)
        && wt.dot(ng) < 0.0
    {
        let ray = Ray::new(offset_ray_origin(surf.p, ng, wt), wt);
        counts.secondary += 1;
        out += (1.0 - f)
            * radiance(
                scene,
                camera,
                &ray,
                state.child(1.0 - f, crossing.after),
                counts,
            );
    }
    out
}

/// Returns `wo` mirrored about the shading normal `n`, or about the geometric normal `ng` when a
/// bent shading normal would send it below the surface.
fn reflect_above(wo: Vec3A, n: Vec3A, ng: Vec3A) -> Vec3A {
    let wr = fresnel::reflect(wo, n);
    if wr.dot(ng) > 0.0 {
        wr
    } else {
        fresnel::reflect(wo, ng)
    }
}

/// Returns the radiance seen by continuing `dir` through a false interface at `p`.
#[allow(clippy::too_many_arguments)]
fn continue_straight(
    scene: &Scene,
    camera: &Camera,
    p: Vec3A,
    ng: Vec3A,
    dir: Vec3A,
    state: PathState,
    media: MediumStack,
    counts: &mut RayCounts,
) -> Vec3A {
    if state.depth >= MAX_DEPTH {
        return Vec3A::ZERO;
    }
    let ray = Ray::new(offset_ray_origin(p, ng, dir), dir);
    counts.secondary += 1;
    radiance(scene, camera, &ray, state.child(1.0, media), counts)
}
