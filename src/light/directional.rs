//! A directional light's geometry: parallel light from beyond a sphere that holds the scene.
//!
//! ```lua
//! gr.directional_light({-0.3, -1, -0.2}, {0.3, 0.3, 0.3})   -- travelling down, E = π·0.3
//! ```
//!
//! The light has no position; the build gives it the sphere round the scene's geometry
//! ([`SceneSphere::holding`]). A shadow ray from a shaded point runs towards the light until it
//! leaves that sphere ([`SceneSphere::exit`]): nothing beyond can cast a shadow. Photons leave
//! a disc of the sphere's radius facing the light's direction, just outside the sphere
//! ([`SceneSphere::disc_point`]): every line of the light's direction that meets the scene
//! crosses the disc, so the disc's flux `E·πR²` is all the light the scene can receive.

use crate::accel::Bounds;
use glam::Vec3A;
use std::f32::consts::TAU;

/// A sphere holding every piece of a scene's geometry, with room for rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSphere {
    pub centre: Vec3A,
    pub radius: f32,
}

impl SceneSphere {
    /// Returns the sphere round `world` (the union of the instances' boxes), grown by a
    /// hundredth and by the coordinates' rounding; the unit sphere when `world` is empty.
    pub fn holding(world: Bounds) -> SceneSphere {
        if !world.is_finite() {
            return SceneSphere {
                centre: Vec3A::ZERO,
                radius: 1.0,
            };
        }
        let centre = (world.min + world.max) * 0.5;
        let half = (world.max - centre).length();
        let rounding = 1e-5 * (1.0 + centre.abs().max_element() + half);
        SceneSphere {
            centre,
            radius: half * 1.01 + rounding,
        }
    }

    /// Returns where the ray from `p` along unit `towards` leaves the sphere, or a point a
    /// little along it when `p` lies outside (nothing there can block it).
    pub fn exit(&self, p: Vec3A, towards: Vec3A) -> Vec3A {
        let oc = p - self.centre;
        let b = oc.dot(towards);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = (b * b - c).max(0.0);
        let t = -b + disc.sqrt();
        p + towards * t.max(1e-3 * self.radius)
    }

    /// Returns the point of `u` in [0, 1)², uniform over the disc of the sphere's radius that
    /// faces unit direction `dir` of travel, centred at `centre − dir·radius`.
    pub fn disc_point(&self, dir: Vec3A, u: (f32, f32)) -> Vec3A {
        let r = self.radius * u.0.sqrt();
        let phi = TAU * u.1;
        let t = dir.any_orthonormal_vector();
        let b = dir.cross(t);
        self.centre - dir * self.radius + (t * phi.cos() + b * phi.sin()) * r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    /// The sphere holds its box; a shadow ray's end lies on it (or beyond, from outside); the
    /// disc's points are uniform over a disc outside the sphere, facing the direction.
    #[test]
    fn the_sphere_holds_the_scene_and_the_disc_covers_it() {
        let b = Bounds {
            min: Vec3A::new(-1.0, 0.0, -2.0),
            max: Vec3A::new(3.0, 1.0, 2.0),
        };
        let s = SceneSphere::holding(b);
        for k in 0..8 {
            let corner = Vec3A::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            assert!((corner - s.centre).length() < s.radius);
        }
        let towards = Vec3A::new(0.2, 1.0, -0.3).normalize();
        let end = s.exit(Vec3A::new(0.5, 0.2, 0.1), towards);
        assert!(((end - s.centre).length() - s.radius).abs() < 1e-5 * s.radius);
        assert!((end - Vec3A::new(0.5, 0.2, 0.1)).dot(towards) > 0.0);
        let outside = s.centre + Vec3A::X * 2.0 * s.radius;
        assert!((s.exit(outside, Vec3A::X) - outside).dot(Vec3A::X) > 0.0);
        let dir = -towards;
        let mut rng = Rng::new(4, Pass::Photon, 0);
        let n = 100_000;
        let mut inner = 0;
        for _ in 0..n {
            let q = s.disc_point(dir, (rng.next_f32(), rng.next_f32()));
            let rel = q - (s.centre - dir * s.radius);
            assert!(rel.dot(dir).abs() < 1e-4 * s.radius);
            assert!(rel.length() <= s.radius * (1.0 + 1e-5));
            inner += u32::from(rel.length() < s.radius / 2.0);
        }
        // Uniform over area: a quarter of the points within half the radius.
        assert!((inner as f32 / n as f32 - 0.25).abs() < 0.005);
        assert_eq!(SceneSphere::holding(Bounds::EMPTY).radius, 1.0);
    }
}
