//! Texture coordinates of the analytic primitives, in object space.
//!
//! Images are indexed with v = 0 at the top row (the original project's convention), so every
//! mapping puts v = 0 at the "top" of its surface:
//! - sphere: u = ½ + atan2(x, z)/2π around the y axis (u = ½ faces +z), v = acos(y)/π from the
//!   north pole (+y) to the south pole;
//! - cube face `2·axis + side`: the face's other two coordinates, both in [0, 1]; ±x faces use
//!   (z, 1 − y), ±y faces (x, z), ±z faces (x, 1 − y);
//! - cylinder side: u = ½ + atan2(y, x)/2π around z, v = (1 − z)/2; caps: u = (x + 1)/2,
//!   v = (1 − y)/2;
//! - cone side: u as the cylinder's, v = 1 − z (apex at the bottom row); cap as the cylinder's.

use crate::geometry::Analytic;
use glam::{Vec2, Vec3A};
use std::f32::consts::{PI, TAU};

/// Returns the texture coordinates of object-space point `p` on face `face` of `shape`.
pub fn analytic_uv(shape: Analytic, p: Vec3A, face: u8) -> Vec2 {
    let around_z = || 0.5 + p.y.atan2(p.x) / TAU;
    let disc = || Vec2::new((p.x + 1.0) * 0.5, (1.0 - p.y) * 0.5);
    let uv = match shape {
        Analytic::Sphere => {
            let n = p.normalize_or_zero();
            Vec2::new(0.5 + n.x.atan2(n.z) / TAU, n.y.clamp(-1.0, 1.0).acos() / PI)
        }
        Analytic::Cube => match face / 2 {
            0 => Vec2::new(p.z, 1.0 - p.y),
            1 => Vec2::new(p.x, p.z),
            _ => Vec2::new(p.x, 1.0 - p.y),
        },
        Analytic::Cylinder => match face {
            0 => Vec2::new(around_z(), (1.0 - p.z) * 0.5),
            _ => disc(),
        },
        Analytic::Cone => match face {
            0 => Vec2::new(around_z(), 1.0 - p.z),
            _ => disc(),
        },
    };
    uv.clamp(Vec2::ZERO, Vec2::ONE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec2, b: Vec2) -> bool {
        (a - b).length() < 1e-6
    }

    #[test]
    fn known_points_map_to_known_coordinates() {
        assert!(close(
            analytic_uv(Analytic::Sphere, Vec3A::Y, 0),
            Vec2::new(0.5, 0.0)
        ));
        assert!(close(
            analytic_uv(Analytic::Sphere, Vec3A::Z, 0),
            Vec2::new(0.5, 0.5)
        ));
        assert!(close(
            analytic_uv(Analytic::Sphere, Vec3A::X, 0),
            Vec2::new(0.75, 0.5)
        ));
        // At the poles u is arbitrary; v is 0 at the north pole and 1 at the south.
        assert!((analytic_uv(Analytic::Sphere, -Vec3A::Y, 0).y - 1.0).abs() < 1e-6);
        // Cube +z face (face 5): x across, y up with v = 0 at the top.
        assert!(close(
            analytic_uv(Analytic::Cube, Vec3A::new(0.25, 0.9, 1.0), 5),
            Vec2::new(0.25, 0.1)
        ));
        assert!(close(
            analytic_uv(Analytic::Cube, Vec3A::new(0.0, 0.3, 0.6), 0),
            Vec2::new(0.6, 0.7)
        ));
        assert!(close(
            analytic_uv(Analytic::Cube, Vec3A::new(0.2, 1.0, 0.6), 3),
            Vec2::new(0.2, 0.6)
        ));
        // Cylinder side at angle 0 (the +x side), half way up; cap centre.
        assert!(close(
            analytic_uv(Analytic::Cylinder, Vec3A::new(1.0, 0.0, 0.0), 0),
            Vec2::new(0.5, 0.5)
        ));
        assert!(close(
            analytic_uv(Analytic::Cylinder, Vec3A::new(0.0, 0.0, 1.0), 2),
            Vec2::new(0.5, 0.5)
        ));
        assert!(close(
            analytic_uv(Analytic::Cone, Vec3A::new(0.0, -0.5, 0.5), 0),
            Vec2::new(0.25, 0.5)
        ));
    }
}

/// Returns the object-space tangent `∂p/∂u` (not normalised; it may vanish at poles and apexes)
/// of the mapping [`analytic_uv`] uses, at `p` on face `face` of `shape`.
pub fn analytic_dpdu(shape: Analytic, p: Vec3A, face: u8) -> Vec3A {
    match (shape, face) {
        (Analytic::Sphere, _) => Vec3A::new(p.z, 0.0, -p.x),
        (Analytic::Cube, f) if f / 2 == 0 => Vec3A::Z,
        (Analytic::Cube, _) => Vec3A::X,
        (Analytic::Cylinder | Analytic::Cone, 0) => Vec3A::new(-p.y, p.x, 0.0),
        (Analytic::Cylinder | Analytic::Cone, _) => Vec3A::X,
    }
}

#[cfg(test)]
mod dpdu_tests {
    use super::*;

    /// The tangent points where u grows: a small step along it increases u.
    #[test]
    fn tangents_follow_increasing_u() {
        let cases = [
            (Analytic::Sphere, Vec3A::new(0.6, 0.0, 0.8), 0u8),
            (Analytic::Cube, Vec3A::new(0.0, 0.3, 0.4), 0),
            (Analytic::Cube, Vec3A::new(0.3, 1.0, 0.4), 3),
            (Analytic::Cube, Vec3A::new(0.3, 0.2, 1.0), 5),
            (Analytic::Cylinder, Vec3A::new(0.6, 0.8, 0.1), 0),
            (Analytic::Cylinder, Vec3A::new(0.2, 0.3, 1.0), 2),
            (Analytic::Cone, Vec3A::new(0.3, 0.4, 0.5), 0),
        ];
        for (shape, p, face) in cases {
            let t = analytic_dpdu(shape, p, face).normalize();
            let u0 = analytic_uv(shape, p, face).x;
            let u1 = analytic_uv(shape, p + t * 1e-3, face).x;
            assert!(u1 > u0, "{shape:?} face {face}: u {u0} -> {u1}");
        }
    }
}
