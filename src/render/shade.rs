//! Whitted-style shading: what one eye ray sees.
//!
//! At a hit with material `(kd, ks, p, t, ior)` the radiance is
//! `kd·ambient + Σ_visible lights att(d)·I·(kd·max(0, n·l) + ks·max(0, r·v)^p)`
//! plus `ks` times the mirror-reflected radiance, all blended with the refracted radiance by the
//! transparency `t` (Snell's law; total internal reflection reflects). Normals are flipped to face
//! the incoming ray, so both sides of a surface shade alike.

use super::RayCounts;
use crate::camera::Camera;
use crate::geometry::{Ray, offset_ray_origin};
use crate::scene::Scene;
use glam::Vec3A;

/// Deepest chain of reflections and refractions followed.
pub const MAX_DEPTH: u32 = 8;
/// Contributions weighted below this are not traced.
const MIN_WEIGHT: f32 = 1e-3;

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
    depth: u32,
    counts: &mut RayCounts,
) -> Vec3A {
    let Some(hit) = scene.intersect(ray) else {
        return background(camera, ray.dir);
    };
    let surf = scene.surface(ray, &hit);
    let mat = &scene.materials[surf.material as usize];
    let wo = -ray.dir.normalize();
    // Face the viewer: both sides of a surface shade alike.
    let (n, ng) = if surf.ng.dot(wo) < 0.0 {
        (-surf.ns, -surf.ng)
    } else {
        (surf.ns, surf.ng)
    };

    let mut colour = scene.ambient * mat.kd;
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
        let r = 2.0 * cos * n - wi;
        let rv = r.dot(wo);
        let spec = if rv > 0.0 && mat.shininess > 0.0 {
            mat.ks * rv.powf(mat.shininess)
        } else {
            Vec3A::ZERO
        };
        colour += light.colour * light.attenuation(d) * (mat.kd * cos + spec);
    }

    if depth >= MAX_DEPTH {
        return colour;
    }
    let mut out = colour;
    if mat.is_reflective() && mat.ks.max_element() > MIN_WEIGHT {
        out += mat.ks * trace_reflection(scene, camera, surf.p, ng, n, wo, depth, counts);
    }
    if mat.transparency > 0.0 {
        let refracted = trace_refraction(
            scene, camera, surf.p, surf.ng, surf.ns, wo, mat.ior, depth, counts,
        );
        out = out * (1.0 - mat.transparency) + refracted * mat.transparency;
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn trace_reflection(
    scene: &Scene,
    camera: &Camera,
    p: Vec3A,
    ng: Vec3A,
    n: Vec3A,
    wo: Vec3A,
    depth: u32,
    counts: &mut RayCounts,
) -> Vec3A {
    let wr = 2.0 * n.dot(wo) * n - wo;
    let ray = Ray::new(offset_ray_origin(p, ng, wr), wr);
    counts.secondary += 1;
    radiance(scene, camera, &ray, depth + 1, counts)
}

/// Returns the radiance seen through a refracting surface; `ng`/`ns` are the surface's own
/// (outward) normals and `ior` the index inside it.
#[allow(clippy::too_many_arguments)]
fn trace_refraction(
    scene: &Scene,
    camera: &Camera,
    p: Vec3A,
    ng: Vec3A,
    ns: Vec3A,
    wo: Vec3A,
    ior: f32,
    depth: u32,
    counts: &mut RayCounts,
) -> Vec3A {
    let entering = ng.dot(wo) > 0.0;
    let (n, eta) = if entering {
        (ns, 1.0 / ior)
    } else {
        (-ns, ior)
    };
    let cos_i = n.dot(wo).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    let wt = if sin2_t >= 1.0 {
        // Total internal reflection.
        2.0 * cos_i * n - wo
    } else {
        let cos_t = (1.0 - sin2_t).sqrt();
        -wo * eta + n * (eta * cos_i - cos_t)
    };
    let ray = Ray::new(offset_ray_origin(p, ng, wt), wt);
    counts.secondary += 1;
    radiance(scene, camera, &ray, depth + 1, counts)
}
