//! The effect plan: which integrator a frame uses and which parts of light transport it
//! simulates, decided from its scene and settings before any pass runs. The passes read the
//! plan; `caustic info` prints it and `--stats` prints it with the phases' times.
//!
//! A render simulates only what its scene calls for:
//! - **photon maps** (global illumination) when, with `--gi auto` (the default), any of the
//!   render's lights was given the extended project's `power` or `num_photons` (scenes written for
//!   a photon mapper). Otherwise the course's ambient term stands in for indirect light, so the A4
//!   scenes keep their look.
//! - a **caustic map** only when photon maps are on and some placed surface is specular (a mirror
//!   or a dielectric): without one no photon path light → specular → diffuse exists.
//! - **final gathering** when photon maps are on and `--indirect gather` (the default); with
//!   `--indirect direct` the global map is seen directly.
//! - soft shadows only for area and sphere lights (reported; the lights decide it).
//! - photon counts that follow the image ([`crate::frame::render_desc`], see
//!   `GiSettings::follow_image`): a preview at a quarter of the script's size traces a sixteenth
//!   of its photons, unless the command line fixes a count; the reason joins the plan's notes.
//!
//! `--force EFFECT` and `--disable EFFECT` overrule the decisions for the effects in
//! [`Effect::OVERRIDABLE`]; `--gi on|off` is `--force`/`--disable photon-maps`. A forced effect
//! the scene cannot have is planned on and says why it will do nothing (a caustic map without a
//! specular surface stays empty).
//!
//! Each decision is data ([`Decision`]: the effect, on or off, and a typed [`Why`]) rendered as
//! text by `Display`, so tests and tools read the plan without parsing sentences.

use super::Integrator;
use crate::photon::trace::specular_targets;
use crate::scene::Scene;
use std::fmt;

/// What `--gi` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GiMode {
    Auto,
    On,
    Off,
}

/// A part of light transport the plan decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Effect {
    PhotonMaps,
    Caustics,
    FinalGathering,
    SoftShadows,
}

impl Effect {
    /// The effects `--force` and `--disable` take.
    pub const OVERRIDABLE: [Effect; 3] =
        [Effect::PhotonMaps, Effect::Caustics, Effect::FinalGathering];

    /// The effect's name on the command line and in the plan.
    pub fn name(self) -> &'static str {
        match self {
            Effect::PhotonMaps => "photon-maps",
            Effect::Caustics => "caustics",
            Effect::FinalGathering => "final-gathering",
            Effect::SoftShadows => "soft-shadows",
        }
    }

    /// Returns the overridable effect called `name`.
    pub fn parse(name: &str) -> Option<Effect> {
        Effect::OVERRIDABLE.into_iter().find(|e| e.name() == name)
    }
}

/// The user's overrides of the plan (`--force`, `--disable`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    pub force: Vec<Effect>,
    pub disable: Vec<Effect>,
}

impl Overrides {
    fn get(&self, e: Effect) -> Option<bool> {
        if self.disable.contains(&e) {
            Some(false)
        } else if self.force.contains(&e) {
            Some(true)
        } else {
            None
        }
    }
}

/// Why an effect is on or off.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Why {
    /// `--force` (or `--gi on`).
    Forced,
    /// `--disable` (or `--gi off`).
    Disabled,
    /// Forced, but the scene cannot have it: the reason it will do nothing.
    ForcedInVain(&'static str),
    /// `--integrator progressive`, which is photon mapping.
    Progressive,
    /// A light has `power` or `num_photons`.
    LightAsks,
    /// No light has `power` or `num_photons`.
    NoLightAsks,
    /// This many placed objects are specular or refractive.
    Specular(usize),
    NoSpecular,
    /// It needs photon maps, which are off.
    NoPhotonMaps,
    /// `--indirect gather`.
    Gather,
    /// `--indirect direct`.
    DirectVisualisation,
    /// This many area or sphere lights.
    AreaLights(usize),
    PointLightsOnly,
}

/// One decision of the plan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decision {
    pub effect: Effect,
    pub on: bool,
    pub why: Why,
}

impl fmt::Display for Decision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let state = if self.on { "on" } else { "off" };
        let why = match &self.why {
            Why::Forced => "--force".to_string(),
            Why::Disabled => "--disable".to_string(),
            Why::ForcedInVain(what) => format!("--force, but {what}"),
            Why::Progressive => "--integrator progressive".to_string(),
            Why::LightAsks => "a light has power or num_photons".to_string(),
            Why::NoLightAsks => {
                "no light has power or num_photons; ambient term instead".to_string()
            }
            Why::Specular(n) => format!("{n} specular or refractive objects"),
            Why::NoSpecular => "no specular or refractive surface".to_string(),
            Why::NoPhotonMaps => "photon maps are off".to_string(),
            Why::Gather => "--indirect gather".to_string(),
            Why::DirectVisualisation => "--indirect direct: the global map seen directly".into(),
            Why::AreaLights(n) => format!("{n} area or sphere lights"),
            Why::PointLightsOnly => "point lights only".to_string(),
        };
        write!(f, "{}: {state} ({why})", self.effect.name())
    }
}

/// The effects one render simulates, with the reasons.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The light-transport method: photon mapping when global illumination is on.
    pub integrator: Integrator,
    /// Whether the photon-mapping integrator traces a caustic map.
    pub caustics: bool,
    /// Whether the photon-mapping integrator gathers (else it shows the global map directly).
    pub final_gathering: bool,
    pub decisions: Vec<Decision>,
    /// What else the frame changed and why (photon counts following the image).
    pub notes: Vec<String>,
}

impl Plan {
    /// Returns the decisions and notes as text, one per item.
    pub fn lines(&self) -> Vec<String> {
        let decisions = self.decisions.iter().map(ToString::to_string);
        decisions.chain(self.notes.iter().cloned()).collect()
    }
}

/// Returns the effect plan for `scene` under `mode` with no overrides, gathering.
pub fn plan(scene: &Scene, mode: GiMode) -> Plan {
    plan_with(scene, mode, &Overrides::default(), true)
}

/// Returns the effect plan for a frame of `scene` with `settings`: [`plan_with`] its `--gi`,
/// overrides and indirect mode, and with `--integrator progressive` photon maps on (unless
/// disabled) and the progressive integrator.
pub fn plan_for(scene: &Scene, settings: &super::Settings) -> Plan {
    let gather = matches!(
        settings.photons.indirect,
        super::photon_map::Indirect::Gather { .. }
    );
    if settings.progressive.is_none() {
        return plan_with(scene, settings.gi, &settings.overrides, gather);
    }
    let mut plan = plan_with(scene, GiMode::On, &settings.overrides, gather);
    if let Some(d) = plan
        .decisions
        .iter_mut()
        .find(|d| d.effect == Effect::PhotonMaps)
        && d.why == Why::Forced
        && !settings.overrides.force.contains(&Effect::PhotonMaps)
    {
        d.why = Why::Progressive;
    }
    if plan.integrator == Integrator::PhotonMap {
        plan.integrator = Integrator::Progressive;
    }
    plan
}

/// Returns the effect plan for `scene` under `mode` and `overrides`; `gather` is whether the
/// settings ask for final gathering (`--indirect gather`).
pub fn plan_with(scene: &Scene, mode: GiMode, overrides: &Overrides, gather: bool) -> Plan {
    let decide = |effect, auto: (bool, Why)| match overrides.get(effect) {
        Some(true) => (true, Why::Forced),
        Some(false) => (false, Why::Disabled),
        None => auto,
    };
    let mut decisions = Vec::new();
    let extended = scene
        .lights
        .iter()
        .any(|l| l.power.is_some() || l.photons.is_some());
    let auto = match mode {
        GiMode::On => (true, Why::Forced),
        GiMode::Off => (false, Why::Disabled),
        GiMode::Auto if extended => (true, Why::LightAsks),
        GiMode::Auto => (false, Why::NoLightAsks),
    };
    let (photon_maps, why) = decide(Effect::PhotonMaps, auto);
    decisions.push(Decision {
        effect: Effect::PhotonMaps,
        on: photon_maps,
        why,
    });
    let specular = specular_targets(scene).len();
    let auto = match (photon_maps, specular) {
        (false, _) => (false, Why::NoPhotonMaps),
        (true, 0) => (false, Why::NoSpecular),
        (true, n) => (true, Why::Specular(n)),
    };
    let (caustics, mut why) = decide(Effect::Caustics, auto);
    if caustics && why == Why::Forced {
        if !photon_maps {
            why = Why::ForcedInVain("photon maps are off: no caustic map is traced");
        } else if specular == 0 {
            why = Why::ForcedInVain("no surface is specular or refractive: the map stays empty");
        }
    }
    decisions.push(Decision {
        effect: Effect::Caustics,
        on: caustics && photon_maps,
        why,
    });
    let auto = match (photon_maps, gather) {
        (false, _) => (false, Why::NoPhotonMaps),
        (true, true) => (true, Why::Gather),
        (true, false) => (false, Why::DirectVisualisation),
    };
    let (mut final_gathering, mut why) = decide(Effect::FinalGathering, auto);
    if final_gathering && !photon_maps {
        (final_gathering, why) = (
            false,
            Why::ForcedInVain("photon maps are off: there is nothing to gather"),
        );
    }
    decisions.push(Decision {
        effect: Effect::FinalGathering,
        on: final_gathering,
        why,
    });
    let area = scene.lights.iter().filter(|l| l.is_area()).count();
    decisions.push(Decision {
        effect: Effect::SoftShadows,
        on: area > 0,
        why: if area > 0 {
            Why::AreaLights(area)
        } else {
            Why::PointLightsOnly
        },
    });
    Plan {
        integrator: if photon_maps {
            Integrator::PhotonMap
        } else {
            Integrator::Whitted
        },
        caustics: caustics && photon_maps,
        final_gathering,
        decisions,
        notes: Vec::new(),
    }
}
