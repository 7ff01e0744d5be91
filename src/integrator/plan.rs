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
//! - **refraction** (Fresnel splitting and media tracking) only when a placed material is
//!   transparent; **textures**, **normal maps** (bump and normal maps) and **noise** (Perlin
//!   normals) only when a placed material has one. The hits are shaded by a kernel compiled
//!   without the effects that are off ([`crate::scene::Features`], `Scene::interaction`): their
//!   code is not reached, rather than skipped by a check at every ray. Disabling one that the
//!   scene has removes it from the materials ([`Scene::apply`]).
//! - **soft shadows** only for area and sphere lights; disabled, those are sampled at their
//!   centre (hard shadows; their photons still leave the whole surface).
//! - **adaptive** refinement when `--adaptive` asks (reported: the sampler refines only where
//!   neighbouring corners differ).
//! - the **specular depth** eye paths split over: 0 without a specular surface, else the
//!   default [`super::eye::MAX_DEPTH`], deepened to `2·L + 2` for `L` dielectric layers nested
//!   one inside another (a ray crosses each layer twice on the way through); beyond it paths go
//!   on by Russian roulette, so the depth trades noise for time, never bias.
//! - photon counts that follow the image ([`crate::frame::render_desc`], see
//!   `GiSettings::follow_image`): a preview at a quarter of the script's size traces a sixteenth
//!   of its photons, unless the command line fixes a count; the reason joins the plan's notes.
//!
//! `--force EFFECT` and `--disable EFFECT` overrule the decisions for the effects in
//! [`Effect::OVERRIDABLE`]; `--gi on|off` is `--force`/`--disable photon-maps`. A forced effect
//! the scene cannot have is planned on and says why it will do nothing (a caustic map without a
//! specular surface stays empty; the general shading kernel finds no texture). Forcing is how
//! the plan is checked: a scene without an effect renders bit for bit the same with the effect
//! forced on (tests/light_transport/effect_plan.rs), so what the plan skips was not needed.
//!
//! Each decision is data ([`Decision`]: the effect, on or off, and a typed [`Why`]) rendered as
//! text by `Display`, so tests and tools read the plan without parsing sentences.

use super::Integrator;
use crate::scene::MAX_DEPTH;
use crate::scene::{Features, Scene};
use std::fmt;

/// Deepest specular depth the plan chooses for nested dielectrics (32 layers).
pub const MAX_SPECULAR_DEPTH: u32 = 66;
/// Most transparent instances whose nesting the plan measures (the measure is quadratic);
/// with more, the default depth stands.
const MAX_NESTING_INSTANCES: usize = 4096;

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
    Refraction,
    SoftShadows,
    Textures,
    NormalMaps,
    Noise,
    Adaptive,
}

impl Effect {
    /// The effects `--force` and `--disable` take.
    pub const OVERRIDABLE: [Effect; 8] = [
        Effect::PhotonMaps,
        Effect::Caustics,
        Effect::FinalGathering,
        Effect::Refraction,
        Effect::SoftShadows,
        Effect::Textures,
        Effect::NormalMaps,
        Effect::Noise,
    ];

    /// The effect's name on the command line and in the plan.
    pub fn name(self) -> &'static str {
        match self {
            Effect::PhotonMaps => "photon-maps",
            Effect::Caustics => "caustics",
            Effect::FinalGathering => "final-gathering",
            Effect::Refraction => "refraction",
            Effect::SoftShadows => "soft-shadows",
            Effect::Textures => "textures",
            Effect::NormalMaps => "normal-maps",
            Effect::Noise => "noise",
            Effect::Adaptive => "adaptive",
        }
    }

    /// What a material has when it calls for this effect, for the plan's text.
    fn material_noun(self) -> &'static str {
        match self {
            Effect::Textures => "with a texture",
            Effect::NormalMaps => "with a bump or normal map",
            Effect::Noise => "with Perlin noise",
            _ => "calling for it",
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
    /// This many placed materials call for the effect (transparent, textured, ...).
    Materials(usize),
    /// No placed material calls for it.
    NoMaterial,
    /// `--adaptive`.
    AdaptiveAsked,
    /// `--noise-target`: rounds of samples where a pixel's noise is above it.
    NoiseTarget,
    /// The time planner chose rounds of samples where the pixels' noise is above a target.
    PlannedRounds,
    /// A fixed number of samples per pixel.
    FixedSamples,
}

/// Why the plan chose its specular depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthWhy {
    /// No surface is specular: no path splits.
    NoSpecular,
    /// The default depth covers the scene's nesting of this many dielectric layers.
    Default(u32),
    /// This many dielectric layers nest one inside another.
    Nested(u32),
    /// Too many transparent instances to measure their nesting.
    Unmeasured(usize),
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
            Why::Materials(n) if self.effect == Effect::Refraction => {
                format!("{n} transparent materials")
            }
            Why::Materials(n) => format!("{n} materials {}", self.effect.material_noun()),
            Why::NoMaterial if self.effect == Effect::Refraction => {
                "no transparent material".to_string()
            }
            Why::NoMaterial => format!("no material {}", self.effect.material_noun()),
            Why::AdaptiveAsked => "--adaptive".to_string(),
            Why::NoiseTarget => "--noise-target".to_string(),
            Why::PlannedRounds => "the time planner's rounds".to_string(),
            Why::FixedSamples => "a fixed number of samples per pixel".to_string(),
        };
        write!(f, "{}: {state} ({why})", self.effect.name())
    }
}

impl fmt::Display for DepthWhy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DepthWhy::NoSpecular => write!(f, "no specular surface: no path splits"),
            DepthWhy::Default(l) => write!(
                f,
                "the default; {l} nested dielectric layers need at most {}",
                2 * l + 2
            ),
            DepthWhy::Nested(l) => write!(f, "{l} nested dielectric layers, crossed twice each"),
            DepthWhy::Unmeasured(n) => write!(
                f,
                "the default; {n} transparent instances are too many to measure their nesting"
            ),
        }
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
    /// The shading effects and specular depth the passes simulate ([`Scene::apply`]).
    pub features: Features,
    /// Why the specular depth is `features.specular_depth`.
    pub depth_why: DepthWhy,
    pub decisions: Vec<Decision>,
    /// What else the frame changed and why (photon counts following the image).
    pub notes: Vec<String>,
}

impl Plan {
    /// Turns adaptive sampling on, for `why`: the sampling asked for it, or the time planner
    /// chose rounds after the plan was made ([`crate::frame`] then records it here).
    pub fn adaptive(&mut self, why: Why) {
        if let Some(d) = self
            .decisions
            .iter_mut()
            .find(|d| d.effect == Effect::Adaptive)
        {
            (d.on, d.why) = (true, why);
        }
    }

    /// Returns the decisions and notes as text, one per item.
    pub fn lines(&self) -> Vec<String> {
        let decisions = self.decisions.iter().map(ToString::to_string);
        let depth = format!(
            "specular depth: {} ({})",
            self.features.specular_depth, self.depth_why
        );
        let notes = self.notes.iter().cloned();
        decisions
            .chain(std::iter::once(depth))
            .chain(notes)
            .collect()
    }

    /// Returns the decision about `effect`.
    pub fn decision(&self, effect: Effect) -> Option<&Decision> {
        self.decisions.iter().find(|d| d.effect == effect)
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
    let mut plan = if settings.progressive.is_none() {
        plan_with(scene, settings.gi, &settings.overrides, gather)
    } else {
        progressive_plan(scene, settings, gather)
    };
    let asked = match settings.sampling {
        crate::render::Sampling::Adaptive { .. } => Some(Why::AdaptiveAsked),
        crate::render::Sampling::Noise { .. } => Some(Why::NoiseTarget),
        _ => None,
    };
    if let Some(why) = asked {
        plan.adaptive(why);
    }
    plan
}

/// Returns the plan of a progressive render: photon maps on unless disabled.
fn progressive_plan(scene: &Scene, settings: &super::Settings, gather: bool) -> Plan {
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
/// settings ask for final gathering (`--indirect gather`). Each decision is one function below,
/// in the order the plan lists them.
pub fn plan_with(scene: &Scene, mode: GiMode, overrides: &Overrides, gather: bool) -> Plan {
    let materials = scene.placed_materials();
    let mut d = Decisions {
        overrides,
        list: Vec::new(),
    };
    let photon_maps = photon_maps(&mut d, scene, mode);
    let caustics = caustics(&mut d, scene, &materials, photon_maps);
    let final_gathering = final_gathering(&mut d, photon_maps, gather);
    let soft_shadows = soft_shadows(&mut d, scene);
    let refraction = d.material_effect(
        Effect::Refraction,
        &materials,
        |m| m.transparency > 0.0,
        "no material is transparent: nothing refracts",
    );
    let textures = d.material_effect(
        Effect::Textures,
        &materials,
        |m| m.is_textured(),
        "no material has a texture: the general kernel looks for one and finds none",
    );
    let normal_maps = d.material_effect(
        Effect::NormalMaps,
        &materials,
        |m| m.bump.is_some(),
        "no material has a bump or normal map: the general kernel finds none",
    );
    let noise = d.material_effect(
        Effect::Noise,
        &materials,
        |m| m.perlin_scale > 0.0,
        "no material has Perlin noise: the general kernel finds none",
    );
    d.push(Effect::Adaptive, false, Why::FixedSamples);
    let specular = materials
        .iter()
        .any(|m| m.is_reflective() || (refraction && m.transparency > 0.0));
    let (specular_depth, depth_why) = specular_depth(scene, specular && refraction, specular);
    Plan {
        integrator: if photon_maps {
            Integrator::PhotonMap
        } else {
            Integrator::Whitted
        },
        caustics,
        final_gathering,
        features: Features {
            textures,
            normal_maps,
            noise,
            refraction,
            soft_shadows,
            specular_depth,
        },
        depth_why,
        decisions: d.list,
        notes: Vec::new(),
    }
}

/// The decisions of a plan being made, and the overrides they obey.
struct Decisions<'a> {
    overrides: &'a Overrides,
    list: Vec<Decision>,
}

impl Decisions<'_> {
    /// Returns the decision about `effect`: the override's, if the user gave one, else `auto`.
    fn decide(&self, effect: Effect, auto: (bool, Why)) -> (bool, Why) {
        match self.overrides.get(effect) {
            Some(true) => (true, Why::Forced),
            Some(false) => (false, Why::Disabled),
            None => auto,
        }
    }

    /// Records a decision.
    fn push(&mut self, effect: Effect, on: bool, why: Why) {
        self.list.push(Decision { effect, on, why });
    }

    /// Decides and records a shading effect that `materials` call for when one `has` it; a
    /// forced one that none has says `vain`. Returns whether it is on.
    fn material_effect(
        &mut self,
        effect: Effect,
        materials: &[&crate::material::Material],
        has: impl Fn(&crate::material::Material) -> bool,
        vain: &'static str,
    ) -> bool {
        let n = materials.iter().filter(|m| has(m)).count();
        let auto = if n > 0 {
            (true, Why::Materials(n))
        } else {
            (false, Why::NoMaterial)
        };
        let (on, mut why) = self.decide(effect, auto);
        if on && n == 0 {
            why = Why::ForcedInVain(vain);
        }
        self.push(effect, on, why);
        on
    }
}

/// Decides photon maps: on under `--gi on`, off under `--gi off`, and with `--gi auto` when a
/// light was given the extended project's `power` or `num_photons`.
fn photon_maps(d: &mut Decisions, scene: &Scene, mode: GiMode) -> bool {
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
    let (on, why) = d.decide(Effect::PhotonMaps, auto);
    d.push(Effect::PhotonMaps, on, why);
    on
}

/// Decides the caustic map: on with photon maps when a placed surface is specular as the passes
/// will see it (with refraction disabled a clear glass turns opaque).
fn caustics(
    d: &mut Decisions,
    scene: &Scene,
    materials: &[&crate::material::Material],
    photon_maps: bool,
) -> bool {
    let refracts = d
        .overrides
        .get(Effect::Refraction)
        .unwrap_or_else(|| materials.iter().any(|m| m.transparency > 0.0));
    let specular = scene
        .instances
        .iter()
        .filter(|inst| {
            scene.instance_materials(inst).iter().any(|&m| {
                let m = &scene.materials[m as usize];
                if refracts {
                    m.is_specular()
                } else {
                    m.is_reflective()
                }
            })
        })
        .count();
    let auto = match (photon_maps, specular) {
        (false, _) => (false, Why::NoPhotonMaps),
        (true, 0) => (false, Why::NoSpecular),
        (true, n) => (true, Why::Specular(n)),
    };
    let (caustics, mut why) = d.decide(Effect::Caustics, auto);
    if caustics && why == Why::Forced {
        if !photon_maps {
            why = Why::ForcedInVain("photon maps are off: no caustic map is traced");
        } else if specular == 0 {
            why = Why::ForcedInVain("no surface is specular or refractive: the map stays empty");
        }
    }
    d.push(Effect::Caustics, caustics && photon_maps, why);
    caustics && photon_maps
}

/// Decides final gathering: on with photon maps under `--indirect gather` (`gather`).
fn final_gathering(d: &mut Decisions, photon_maps: bool, gather: bool) -> bool {
    let auto = match (photon_maps, gather) {
        (false, _) => (false, Why::NoPhotonMaps),
        (true, true) => (true, Why::Gather),
        (true, false) => (false, Why::DirectVisualisation),
    };
    let (mut on, mut why) = d.decide(Effect::FinalGathering, auto);
    if on && !photon_maps {
        (on, why) = (
            false,
            Why::ForcedInVain("photon maps are off: there is nothing to gather"),
        );
    }
    d.push(Effect::FinalGathering, on, why);
    on
}

/// Decides soft shadows: on when the scene has area or sphere lights.
fn soft_shadows(d: &mut Decisions, scene: &Scene) -> bool {
    let area = scene.lights.iter().filter(|l| l.is_area()).count();
    let auto = if area > 0 {
        (true, Why::AreaLights(area))
    } else {
        (false, Why::PointLightsOnly)
    };
    let (on, mut why) = d.decide(Effect::SoftShadows, auto);
    if on && area == 0 {
        why = Why::ForcedInVain("point lights only: there is no area to soften shadows over");
    }
    d.push(Effect::SoftShadows, on, why);
    on
}

/// Returns the depth eye paths split over and why: 0 when no surface is specular; else
/// [`MAX_DEPTH`], or `2·L + 2` when `L` transparent instances nest one inside another (by their
/// world boxes) and that is deeper; at most [`MAX_SPECULAR_DEPTH`]. `dielectrics` is whether
/// transparent materials refract.
fn specular_depth(scene: &Scene, dielectrics: bool, specular: bool) -> (u32, DepthWhy) {
    if !specular {
        return (0, DepthWhy::NoSpecular);
    }
    let boxes: Vec<crate::accel::Bounds> = if dielectrics {
        scene.transparent.iter().map(|t| t.1).collect()
    } else {
        Vec::new()
    };
    if boxes.len() > MAX_NESTING_INSTANCES {
        return (MAX_DEPTH, DepthWhy::Unmeasured(boxes.len()));
    }
    let layers = nesting(&boxes);
    let need = (2 * layers + 2).min(MAX_SPECULAR_DEPTH);
    if need > MAX_DEPTH {
        (need, DepthWhy::Nested(layers))
    } else {
        (MAX_DEPTH, DepthWhy::Default(layers))
    }
}

/// Returns the longest chain of boxes each strictly inside the one before.
fn nesting(boxes: &[crate::accel::Bounds]) -> u32 {
    let inside = |a: &crate::accel::Bounds, b: &crate::accel::Bounds| {
        a.min.cmpge(b.min).all() && a.max.cmple(b.max).all() && a != b
    };
    // Larger boxes first: a box can only be inside one that comes before it.
    let mut order: Vec<usize> = (0..boxes.len()).collect();
    let volume =
        |b: &crate::accel::Bounds| (b.max - b.min).max(glam::Vec3A::ZERO).element_product();
    order.sort_by(|&a, &b| volume(&boxes[b]).total_cmp(&volume(&boxes[a])));
    let mut chain = vec![1u32; boxes.len()];
    for i in 0..order.len() {
        for j in 0..i {
            if inside(&boxes[order[i]], &boxes[order[j]]) {
                chain[i] = chain[i].max(chain[j] + 1);
            }
        }
    }
    chain.into_iter().max().unwrap_or(0)
}
