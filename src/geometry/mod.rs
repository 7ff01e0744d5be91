//! Shapes and their ray intersections, in object space, plus the ray and hit types they share.
//!
//! [`Analytic`] is the closed set of analytic primitives (sphere, cube, cylinder, cone): the scene
//! places them as instances (`scene::Shape::Analytic`), CSG trees hold them as leaves, and
//! texture mapping ([`uv`]) dispatches on them, so a new primitive is one new variant that every
//! `match` must handle.
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
pub mod triangle;
pub mod uv;
pub mod water;

pub use ray::{Ray, offset_ray_origin, spawn_offset};

use glam::{Affine3A, Vec3A};

/// Returns, per axis, the size of the terms of `m·p` (`|M|·|p| + |t|`): `f32` rounding moves
/// each coordinate of the transformed point by a few ulps of that, not of the largest
/// coordinate. A slab scaled 10⁴ times thinner puts a far ray's origin at 10⁴ in y, yet its x
/// is as exact as the world's.
pub fn origin_size(m: &Affine3A, p: Vec3A) -> Vec3A {
    let a = m.matrix3;
    let p = p.abs();
    a.x_axis.abs() * p.x + a.y_axis.abs() * p.y + a.z_axis.abs() * p.z + m.translation.abs()
}

/// An analytic primitive in its own object space (the unit shapes of `gr.sphere`, `gr.cube`,
/// `gr.cylinder` and `gr.cone`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Analytic {
    /// Centre (0,0,0), radius 1.
    Sphere,
    /// The axis-aligned unit cube from (0,0,0) to (1,1,1).
    Cube,
    /// Axis z, radius 1, z in [-1, 1], closed by caps.
    Cylinder,
    /// Apex at the origin, axis z, radius 1 at z = 1, closed by a cap at z = 1.
    Cone,
}

impl Analytic {
    /// Returns where the full line `o + t·d` (object space) enters and leaves the primitive;
    /// `o_size` is, per axis, the size of the terms `o` was computed from
    /// ([`origin_size`]), which bounds its rounding error.
    pub fn interval(self, o: Vec3A, d: Vec3A, o_size: Vec3A) -> Option<Interval> {
        match self {
            Analytic::Sphere => sphere::interval(o, d),
            Analytic::Cube => cube::interval(o, d, o_size),
            Analytic::Cylinder => cylinder::interval(o, d),
            Analytic::Cone => cone::interval(o, d),
        }
    }

    /// Returns the primitive's name, as `--stats` prints it.
    pub fn label(self) -> &'static str {
        match self {
            Analytic::Sphere => "sphere",
            Analytic::Cube => "cube",
            Analytic::Cylinder => "cylinder",
            Analytic::Cone => "cone",
        }
    }
}

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
