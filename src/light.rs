//! Lights as the renderer uses them.
//!
//! A point light of colour `I` and falloff `(c0, c1, c2)` delivers `I / (c0 + c1·d + c2·d²)` to a
//! point at distance `d`, as the course specifies; attenuation applies to direct light only, never
//! to the ambient term.

use crate::scene::desc::LightDesc;
use glam::Vec3A;

/// A point light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    pub position: Vec3A,
    pub colour: Vec3A,
    pub falloff: [f32; 3],
}

impl PointLight {
    /// Returns the light a script described.
    pub fn from_desc(d: &LightDesc) -> PointLight {
        PointLight {
            position: d.position.into(),
            colour: d.colour.into(),
            falloff: d.falloff,
        }
    }

    /// Returns the attenuation factor `1 / (c0 + c1·d + c2·d²)` at distance `d`.
    pub fn attenuation(&self, d: f32) -> f32 {
        let [c0, c1, c2] = self.falloff;
        1.0 / (c0 + c1 * d + c2 * d * d)
    }
}
