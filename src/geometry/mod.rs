//! Shapes and their ray intersections, in object space, plus the ray and hit types they share.
//!
//! Every shape intersects an object-space [`Ray`] and reports `t` in the ray's own parameter, so
//! instances can transform rays without renormalising them. Normals returned here are geometric,
//! unnormalised object-space normals; [`crate::scene`] turns them into world-space shading frames.

pub mod cone;
pub mod csg;
pub mod cube;
pub mod cylinder;
pub mod hit;
pub mod mesh;
pub mod ray;
pub mod sphere;
pub mod tri4;
pub mod triangle;
pub mod uv;
pub mod water;

pub use ray::{Ray, offset_ray_origin};

use glam::Vec3A;

/// A point where a line crosses a shape's boundary, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Line parameter (may be negative: intervals cover the whole line).
    pub t: f64,
    /// Outward geometric normal, object space, not necessarily unit length.
    pub normal: Vec3A,
    /// Which part of the shape was crossed (cube face, cylinder side/cap), for texture mapping.
    pub face: u8,
}

/// Where a line enters and leaves a convex shape: `enter.t <= exit.t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub enter: Crossing,
    pub exit: Crossing,
}

impl Interval {
    /// Returns the first crossing with `t` in `(tmin, tmax)`: the entry, else the exit (ray inside).
    pub fn first_in(&self, tmin: f32, tmax: f32) -> Option<Crossing> {
        let inside = |t: f64| t > tmin as f64 && t < tmax as f64;
        if inside(self.enter.t) {
            Some(self.enter)
        } else if inside(self.exit.t) {
            Some(self.exit)
        } else {
            None
        }
    }
}
