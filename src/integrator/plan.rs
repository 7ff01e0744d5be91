//! The effect plan: which integrator a frame uses and which parts of light transport it
//! simulates, decided from its scene before any pass runs.
//!
//! A render simulates only what its scene calls for:
//! - **photon maps** (global illumination) when the command line asks (`--gi on`) or, with
//!   `--gi auto` (the default), when any of the render's lights was given the extended project's
//!   `power` or `num_photons` (scenes written for a photon mapper). Otherwise the course's ambient
//!   term stands in for indirect light, so the A4 scenes keep their look.
//! - a **caustic map** only when photon maps are on and some placed surface is specular (a mirror
//!   or a dielectric): without one no photon path light → specular → diffuse exists.
//! - soft shadows only for area and sphere lights; refraction only where `t > 0`; and so on, by
//!   construction of the shading code.
//! - photon counts that follow the image ([`crate::frame::render_desc`], see
//!   `GiSettings::follow_image`): a preview at a quarter of the script's size traces a sixteenth
//!   of its photons, unless the command line fixes a count; the reason joins the plan's.

use super::Integrator;
use crate::photon::trace::specular_targets;
use crate::scene::Scene;

/// What `--gi` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GiMode {
    Auto,
    On,
    Off,
}

/// The effects one render simulates, with the reasons, for `--stats`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// The light-transport method: photon mapping when global illumination is on.
    pub integrator: Integrator,
    /// Whether the photon-mapping integrator traces a caustic map.
    pub caustics: bool,
    pub reasons: Vec<String>,
}

/// Returns the effect plan for `scene` under `mode`.
pub fn plan(scene: &Scene, mode: GiMode) -> Plan {
    let extended = scene
        .lights
        .iter()
        .any(|l| l.power.is_some() || l.photons.is_some());
    let (photon_maps, why) = match mode {
        GiMode::On => (true, "photon maps: on (--gi on)".to_string()),
        GiMode::Off => (false, "photon maps: off (--gi off); ambient term instead".to_string()),
        GiMode::Auto if extended => (true, "photon maps: on (a light has power or num_photons)".to_string()),
        GiMode::Auto => (
            false,
            "photon maps: off (no light has power or num_photons; --gi on forces them); ambient term instead".to_string(),
        ),
    };
    let mut reasons = vec![why];
    let specular = specular_targets(scene).len();
    let caustics = photon_maps && specular > 0;
    if photon_maps {
        reasons.push(if caustics {
            format!("caustic map: on ({specular} specular or refractive objects)")
        } else {
            "caustic map: off (no specular or refractive surface)".to_string()
        });
    }
    let area = scene.lights.iter().filter(|l| l.is_area()).count();
    reasons.push(if area > 0 {
        format!("soft shadows: {area} area or sphere lights")
    } else {
        "soft shadows: off (point lights only)".to_string()
    });
    Plan {
        integrator: if photon_maps {
            Integrator::PhotonMap
        } else {
            Integrator::Whitted
        },
        caustics,
        reasons,
    }
}
