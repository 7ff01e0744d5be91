//! The course's ray tracer (Whitted 1980): direct light by shadow rays, the ambient term
//! `ambient·kd` for everything else a diffuse surface receives, mirror reflection and Fresnel
//! refraction by deterministic splitting ([`super::eye`]).
//!
//! Phases: the camera pass, nothing before it.

use super::eye::DiffuseTerm;
use super::{Settings, View, camera_pass};
use crate::film::Film;
use crate::progress::Progress;
use crate::stats::RenderStats;

/// Renders `view`.
pub fn render(view: View, settings: &Settings, progress: &dyn Progress) -> (Film, RenderStats) {
    let diffuse = DiffuseTerm::Ambient(view.scene.ambient);
    camera_pass(view, diffuse, settings, progress)
}
