//! The course's ray tracer (Whitted 1980): direct light by shadow rays, the ambient term
//! `ambient·kd` for everything else a diffuse surface receives, mirror reflection and Fresnel
//! refraction by deterministic splitting ([`super::eye`]).
//!
//! Phases: the camera pass, nothing before it.

use super::eye::DiffuseTerm;
use super::{Settings, camera_pass};
use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::stats::RenderStats;

/// Renders `window` of the image of `scene` through `camera`.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    window: Window,
    settings: &Settings,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    let diffuse = DiffuseTerm::Ambient(scene.ambient);
    camera_pass(scene, camera, diffuse, window, settings, progress)
}
