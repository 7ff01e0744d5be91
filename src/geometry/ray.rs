//! Rays and the offset that keeps a spawned ray from re-hitting the surface it leaves.

use glam::Vec3A;

/// A ray `origin + t·dir` for `t` in `(tmin, tmax)`; `dir` need not be unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3A,
    pub dir: Vec3A,
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    /// Returns the ray from `origin` along `dir` with `t` in `(0, ∞)`.
    pub fn new(origin: Vec3A, dir: Vec3A) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// Returns the same ray limited to `t < tmax`.
    pub fn with_tmax(self, tmax: f32) -> Ray {
        Ray { tmax, ..self }
    }

    /// Returns the point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }
}

/// Relative size of the spawn offset: about 64 ulps of the hit point's largest coordinate.
const OFFSET_REL: f32 = 1.0 / (1 << 17) as f32;
/// Smallest spawn offset, for hit points at the origin.
const OFFSET_ABS: f32 = 1e-9;

/// Returns the distance a spawned ray's origin is moved off a surface at a point whose largest
/// coordinate has magnitude `size`.
pub fn spawn_offset(size: f32) -> f32 {
    size * OFFSET_REL + OFFSET_ABS
}

/// Returns a ray origin moved off the surface at `p` (geometric normal `ng`) to the side `w` points to.
///
/// The offset scales with the magnitude of `p`'s coordinates, because the error of a computed hit
/// point does too (pbrt-v4's `OffsetRayOrigin`, with a constant bound in place of tracked errors).
pub fn offset_ray_origin(p: Vec3A, ng: Vec3A, w: Vec3A) -> Vec3A {
    let eps = spawn_offset(p.abs().max_element());
    let n = if ng.dot(w) < 0.0 { -ng } else { ng };
    p + n * eps
}
