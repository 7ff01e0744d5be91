//! The photon-mapping integrator (Jensen): caustics and indirect diffuse light from photon maps.
//!
//! Phases ([`render`]): the prepass ([`prepass`], which makes a [`Prepass`]: trace and build the
//! global map, then the caustic map, then the map of precomputation points, together
//! [`Prepass::build_with`]; estimate those points; the irradiance cache), then the camera pass
//! with the maps as the eye path's diffuse term. A prepass can be saved to a file and read
//! back instead of made ([`super::maps_file`], which owns those files).
//! [`Prepass::diffuse`] answers what a diffuse surface receives other than directly from the lights:
//! - caustics: a density estimate of the caustic map at the point;
//! - indirect diffuse light, in one of two modes ([`Indirect`]):
//!   - `Gather` (the default; Jensen's final gathering): `rays` cosine-distributed rays from the
//!     point; where each lands on a diffuse lobe, the global map's radiance estimate (all its
//!     photons) is the incoming radiance. Where one lands on a mirror or a dielectric it
//!     continues by the BSDF's roulette over the specular lobes (radiance scaled by
//!     `(n_from/n_to)²` where it refracts), for up to [`MAX_GATHER_SPECULAR`] bounces: light
//!     arriving diffuse → specular → diffuse is in neither the caustic map nor the direct term.
//!     Emitters seen by gather rays count nothing (that light is the direct term or the caustic
//!     map's). Points reached after more than [`MAX_GATHER_DEPTH`] specular bounces use the
//!     direct mode.
//!
//!     By default that estimate is not made afresh for every gather ray. Following Christensen
//!     (*Faster photon map global illumination*, JGT 1999), the irradiance is estimated at a
//!     pseudo-random one in [`PRECOMPUTE_STRIDE`] global photons, all up front when there are
//!     no more of them than the image's pixels ([`Prepass::precompute_for`]), else each the first
//!     time a gather ray reads it ([`Precomputed`]), and a gather ray takes the value of the nearest
//!     such point whose normal is within 25° of the surface's (one 1-nearest query instead of a
//!     50-nearest estimate). The point must also be one the query point can see along the
//!     surface, as Christensen's and pbrt's estimators require: it passes the side test
//!     (`on_one_surface`: not across a wall from the query point, which a normal test alone
//!     cannot tell when both faces of a thin wall face the same way, as a box's inside floor and
//!     the floor outside it do), and the query point lies within the radius the point's own
//!     estimate gathered over (a point estimated from a dense patch inside a sealed box stands
//!     for that patch only). Where no point passes it falls back to the estimate, whose photons
//!     pass the normal and disc tests (issue 35: a light sealed in a box lit its outside). Why: a frame has tens of millions of gather
//!     rays but only ~10^6 photons, so estimating at the photons is far cheaper, and the
//!     gathered values are averaged over 64 rays, which hides the piecewise-constant lookup
//!     (on `room2.lua`: render 32.6 s -> 8.2 s, mean pixel value within 1.3%; pbrt's closed
//!     sphere stays within 2.5% in both modes, `tests/photons/closed_forms.rs`).
//!     `GiSettings::precompute` (`--gather-lookup estimate`) turns it off.
//!
//!     And by default most points do not gather at all: they interpolate the records of an
//!     irradiance cache made before the camera pass ([`super::irradiance_cache`]; the final
//!     scene: render 72 s -> 37 s at 1024²). Where a record serves a point, eye paths too weak
//!     to be gathered use it as well.
//!   - `Direct`: the global map's estimate at the point itself, from photons that made at least
//!     one diffuse bounce (direct light and caustics come from shadow rays and the caustic map).
//!     Fast and blotchy: the original project's method.
//!
//! Estimates use the `k` nearest photons within a maximum radius, reject photons whose stored
//! normal disagrees with the surface's (light leaking round corners and through thin walls) or
//! that lie off the surface's side (`on_one_surface`: a parallel face across a wall, whose
//! normal agrees), and weight them with a [`Filter`] that integrates to one.
//!
//! # A pixel's samples share caustic estimates
//! The caustic map is read at every diffuse point an eye path reaches, a `k`-nearest search
//! each: on the final scene at 1024², 5.65M searches, the camera pass's largest cost. A pixel's
//! samples land close together (on the final scene's floor, a pixel is about a third of the
//! caustic estimate's radius wide), and the estimates of two points a fraction of the radius
//! apart are nearly the same photons. So within one round of a pixel's samples (a
//! [`crate::render::scope`], on one thread), a sample whose point lies within
//! [`REUSE_FRACTION`] (a quarter) of an earlier sample's estimate radius, on a surface facing
//! the same way, takes that estimate instead of searching (up to eight estimates a round are
//! kept: a water pixel's reflection and refraction reach different surfaces, and the time
//! planner's pilot traces each sample through four prepasses, each with estimates of its own). What each
//! sample does with it (its texture's `kd`, its weight) stays its own.
//!
//! What it costs: a sample's estimate is centred up to a quarter radius from its point, which
//! widens the kernel's blur by about that (its bias, a quarter radius against the kernel's own
//! radius), and the samples of a pixel no longer average independent estimates, which they
//! barely were (the discs overlap by more than 80%). On the final scene at 1024² the relative
//! RMSE against the long references of `tools/accuracy/final_budget.sh` went from 0.08365 to
//! 0.08372 and the block bias stayed 0.0213, while 46% of the estimates were reused and the
//! camera pass took 0.64–0.68 of its time; the validation table against Mitsuba 3 moved by at
//! most 0.0002 in any region's mean (at 96², few samples share). Nothing is shared between
//! pixels, prepasses or passes (the round's scope and the prepass key the estimates), so tiles
//! stay bit-identical to the full frame; the progressive integrator's fixed-radius estimates
//! never share (its convergence is analysed per estimate).

use super::eye::{DiffuseTerm, PathState, ShadingPoint};
use super::irradiance_cache::{CacheSettings, CacheStats, Gather, IrradianceCache, Probes};
use super::local_radii::LocalRadii;
pub use super::precomputed::{PRECOMPUTE_STRIDE, PointEstimate, Precomputed, is_precompute_point};
use super::{Plan, Settings, View, camera_pass};
use crate::accel::counters::RayKind;
use crate::camera::Camera;
use crate::film::Film;
use crate::geometry::{Ray, offset_ray_origin};
use crate::material::medium::MediumStack;
use crate::photon::estimate::Filter;
use crate::photon::file::CountedMap;
use crate::photon::trace::{LightCounts, MapKind, photon_budget, trace_map_with};
use crate::photon::{PhotonId, PhotonMap};
use crate::progress::{NoProgress, Progress};
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::scene::interaction::Needs;
use crate::stats::{RayCounts, RenderStats};
use glam::Vec3A;
use std::cell::RefCell;
use std::f32::consts::FRAC_1_PI;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Deepest eye-path depth (specular bounces) at which final gathering is used; deeper points
/// see the global map directly. Surfaces seen through a glass ball are at depth 2.
pub const MAX_GATHER_DEPTH: u32 = 3;

/// Least weight an eye path must carry for its diffuse hits to be final-gathered; weaker paths
/// (a Fresnel reflection off water or glass, about 2–10% of the pixel) read the global map
/// directly, as Jensen's renderer does for rays of low importance: its blotches, scaled by
/// that weight, stay below the noise, and the gather rays go where the pixel's light comes from.
pub const GATHER_MIN_WEIGHT: f32 = 0.1;

/// Most specular bounces a final-gather ray follows before it reads the map where it is (a
/// glass ball under water is four interfaces deep).
pub const MAX_GATHER_SPECULAR: u32 = 8;

/// Photons emitted for the global map by default. It is seen only through final gathering,
/// which averages many lookups, so its noise is averaged away before it reaches a pixel.
pub const GLOBAL_PHOTONS: u64 = 200_000;

/// Photons emitted for the caustic map by default. The caustic map is seen directly, one density
/// estimate per pixel, and under water it carries all the direct light: its noise and the blur
/// of its k-nearest kernel at shadow edges (which shrinks as the square root of the count) reach
/// the image unaveraged. Caustic photons stop at their first diffuse hit and are aimed at the
/// specular objects, so they cost a fraction of global ones. See `docs/validation.md` for the
/// measurement that set this count.
pub const CAUSTIC_PHOTONS: u64 = 2_000_000;

/// Smallest cosine between a precomputed point's normal and the surface's for the point to be used.
const PRECOMPUTED_MIN_COS: f32 = 0.9;

/// How far, as a share of their distance, the chord between two points may lean off the plane
/// perpendicular to their mean normal beyond what the angle between their normals allows, for
/// them still to count as one surface ([`on_one_surface`]): 0.05 (2.9°), for float rounding
/// and surfaces that curve both ways between the two points (a bumpy mesh).
const ONE_SURFACE_SLACK: f32 = 0.05;

/// Returns whether two points `offset` apart, of unit geometric normals `n_a` and `n_b` (facing
/// the same way: the callers' normal tests), may lie on one surface: whether the offset's part
/// along their mean normal is at most `sin(θ/2) + ONE_SURFACE_SLACK` of its length, `θ` the
/// angle between the normals. The side test of the photon estimates and the precomputed
/// lookups, with the normal test the "can the point see it along the surface" test of
/// Christensen's and pbrt's estimators without a ray.
///
/// Why that bound: on a circular arc the chord between two points is perpendicular to their
/// mean normal, and across a crease of angle `θ` it leans at most `θ/2` off the plane
/// perpendicular to it (at most when one point is on the crease), so points of one smooth or
/// faceted surface pass. A point on a parallel surface across a wall of thickness `t` (a sealed
/// box's inside floor seen from the floor outside it: both normals up, so the normal test cannot
/// tell) leans `t` over the distance and fails unless it is `t / 0.05` = 20 `t` away.
fn on_one_surface(offset: Vec3A, n_a: Vec3A, n_b: Vec3A) -> bool {
    let cos = n_a.dot(n_b).clamp(-1.0, 1.0);
    let lean = (0.5 * (1.0 - cos)).sqrt() + ONE_SURFACE_SLACK;
    // (offset · m)² with m = (n_a + n_b)/|n_a + n_b| and |n_a + n_b|² = 2 + 2 cos.
    let along = offset.dot(n_a + n_b);
    along * along <= (2.0 + 2.0 * cos) * lean * lean * offset.length_squared()
}

/// How the indirect diffuse term is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Indirect {
    /// Final gathering with this many rays per shaded point.
    Gather { rays: u32 },
    /// The global map's estimate at the point (photons after a diffuse bounce only).
    Direct,
}

/// Where a final gather runs ([`Prepass::gather`]).
#[derive(Clone, Copy, Debug)]
pub struct GatherAt {
    pub p: Vec3A,
    /// The unit geometric normal: rays below the surface it bounds are skipped.
    pub ng: Vec3A,
    /// The media the point lies in.
    pub media: MediumStack,
}

/// Settings of the photon phases and estimates.
#[derive(Clone, Debug, PartialEq)]
pub struct GiSettings {
    pub seed: u64,
    /// Photons emitted for the global map, shared by lights without `num_photons`.
    pub photons: u64,
    /// Photons emitted for the caustic map, shared the same way (see [`CAUSTIC_PHOTONS`]).
    pub caustic_photons: u64,
    /// Multiplies every light's photon count, `num_photons` included (previews, tests).
    pub photon_scale: f64,
    /// Whether [`crate::frame::render_desc`] scales the photon counts with the image: by the
    /// rendered image's pixels over the script's, so a `--scale 0.25` preview traces about a
    /// sixteenth of the photons (the density estimates then span about as many pixels as at
    /// full size). The command line turns it off when `--photons`, `--caustic-photons` or
    /// `--photon-scale` fixes the count.
    pub follow_image: bool,
    /// Nearest photons per estimate.
    pub k: usize,
    /// Largest search radius of the global map as a fraction of the scene's diagonal (the caustic
    /// map uses half of it).
    pub max_radius: f32,
    pub filter: Filter,
    pub indirect: Indirect,
    /// Whether to trace the caustic map (the effect plan turns it off without specular surfaces).
    pub caustics: bool,
    /// Final-gather rays read the irradiance at about one global photon in [`PRECOMPUTE_STRIDE`]
    /// (Christensen 1999), estimated when first read, instead of making a density estimate
    /// where they land.
    pub precompute: bool,
    /// Final gathering interpolates an irradiance cache ([`super::irradiance_cache`]).
    pub cache: CacheSettings,
    /// A pixel's samples share a caustic estimate where their points lie within
    /// [`REUSE_FRACTION`] of its radius (the module doc says why); off only to measure it.
    pub share_caustics: bool,
}

impl GiSettings {
    /// Returns each light's photon count for the `kind` map: its `num_photons` or its share of
    /// `photons` (global) or `caustic_photons` ([`photon_budget`]), times `photon_scale`.
    pub fn budget(&self, lights: &[crate::light::Light], kind: MapKind) -> Vec<u64> {
        let total = match kind {
            MapKind::Global => self.photons,
            MapKind::Caustic => self.caustic_photons,
        };
        photon_budget(lights, total)
            .into_iter()
            .map(|n| (n as f64 * self.photon_scale).round() as u64)
            .collect()
    }
}

impl Default for GiSettings {
    fn default() -> GiSettings {
        GiSettings {
            seed: 0,
            photons: GLOBAL_PHOTONS,
            caustic_photons: CAUSTIC_PHOTONS,
            photon_scale: 1.0,
            follow_image: true,
            k: 50,
            max_radius: 0.05,
            filter: Filter::Epanechnikov,
            indirect: Indirect::Gather {
                rays: super::DEFAULT_GATHER_RAYS,
            },
            caustics: true,
            precompute: true,
            cache: CacheSettings::default(),
            share_caustics: true,
        }
    }
}

/// Counters of the photon phases, for `--stats`.
#[derive(Clone, Debug, Default)]
pub struct GiStats {
    /// Photons emitted and stored per light, for each map.
    pub global: Vec<LightCounts>,
    pub caustic: Vec<LightCounts>,
    /// Bytes each map owns ([`PhotonMap::bytes`]).
    pub global_bytes: usize,
    pub caustic_bytes: usize,
    /// Tracing and kd-tree building of both maps.
    pub trace_time: Duration,
    pub build_time: Duration,
    /// Of those, the caustic map's tracing and building.
    pub caustic_time: Duration,
    /// Time to make the map of precomputation points (zero without), and how many it holds.
    pub precompute_time: Duration,
    pub precomputed_points: usize,
    /// How many of those points were estimated because a gather ray read them (filled in
    /// after the camera pass, [`Precomputed`]).
    pub precomputed_evaluated: usize,
    /// The irradiance cache's record pass, when there was one.
    pub cache: Option<CacheStats>,
    /// The time to read the maps when they came from a file (`--photon-maps`) instead of
    /// being traced, and the irradiance-cache records the file held.
    pub read_time: Option<Duration>,
    pub read_records: usize,
    /// What the time planner chose, for a render with a time budget or a target error.
    pub planned: Option<super::planner::Planned>,
}

/// What the photon-map prepass makes for one frame, and how shading reads it: the maps with
/// their per-light counts (in `stats`), the precomputation points and the irradiance cache.
/// Made by [`prepass`], or read from a file by [`super::maps_file::load`]; consumed by the
/// camera pass ([`super::eye::DiffuseTerm::Photons`]).
#[derive(Debug)]
pub struct Prepass {
    pub global: PhotonMap,
    pub caustic: Option<PhotonMap>,
    /// Irradiance at a subset of the global photons, each estimated when first read or up
    /// front ([`Prepass::precompute_for`]; see [`GiSettings::precompute`]).
    pub precomputed: Option<Precomputed>,
    /// Records of final gathers that shading points interpolate ([`Prepass::with_cache`]).
    pub cache: Option<IrradianceCache>,
    pub settings: GiSettings,
    global_r2: f32,
    caustic_r2: f32,
    /// Whether estimates take every photon within the maps' radii (the progressive
    /// integrator's fixed radii, [`Prepass::with_fixed_radii`]) rather than the `k` nearest.
    fixed_radii: bool,
    /// With fixed radii, radii that vary over space ([`Prepass::with_local_radii`]): the fields
    /// and the factors (global, caustic) their values are scaled by.
    local: Option<(Arc<LocalRadii>, (f32, f32))>,
    pub stats: GiStats,
}

thread_local! {
    static FOUND: RefCell<Vec<(f32, PhotonId)>> = const { RefCell::new(Vec::new()) };
    /// The caustic estimates of the open pixel scope's samples so far ([`Prepass::caustic_at`]).
    static MEMO: RefCell<Memos> = const { RefCell::new(Memos::EMPTY) };
}

/// A sample's point may take an earlier sample's caustic estimate when it lies within this
/// fraction of that estimate's radius of it (the module doc says why and what it costs).
pub const REUSE_FRACTION: f32 = 0.25;

/// Smallest cosine between the normals of two points that share a caustic estimate.
const REUSE_MIN_COS: f32 = 0.99;

/// The most caustic estimates a pixel round keeps for each prepass and `k` (the pilot's
/// samples are traced through up to eight pairs of them).
const MEMO_EACH: usize = 8;

/// A caustic estimate that later samples of the same pixel round may take.
#[derive(Clone, Copy)]
struct Memo {
    /// The address of the prepass it was made with and the photons it took (the planner's
    /// pilot traces each sample through several prepasses, and with fewer photons: see
    /// [`Prepass::caustic_diffuse`]).
    prepass: usize,
    k: usize,
    p: Vec3A,
    n: Vec3A,
    irradiance: Vec3A,
    /// Squared distance within which a point takes it.
    reuse_d2: f32,
}

/// The estimates of one pixel round: `scope` is its scope's id.
struct Memos {
    scope: u64,
    entries: [Memo; 8 * MEMO_EACH],
    len: usize,
}

impl Memos {
    const EMPTY: Memos = Memos {
        scope: 0,
        entries: [Memo {
            prepass: 0,
            k: 0,
            p: Vec3A::ZERO,
            n: Vec3A::ZERO,
            irradiance: Vec3A::ZERO,
            reuse_d2: 0.0,
        }; 8 * MEMO_EACH],
        len: 0,
    };
}

/// Renders `view` with photon maps: the prepass ([`prepass`]; `read`, when the frame's maps
/// came from a file), then the camera pass with the maps as the eye path's diffuse term.
pub fn render(
    view: View,
    settings: &Settings,
    plan: &Plan,
    read: Option<Prepass>,
    progress: &dyn Progress,
) -> (Film, RenderStats, GiStats) {
    let started = Instant::now();
    let mut photons = planned(&settings.photons, plan);
    let mut settings = std::borrow::Cow::Borrowed(settings);
    let request = settings.budget.filter(|_| read.is_none());
    // The planner may have made the chosen prepass already (its pilot's, or a short budget's).
    let (mut reused, mut timing) = (None, None);
    let mut chosen = request.map(|request| {
        let c = super::planner::choose(view, &settings, &photons, &request, started, progress);
        photons = super::planner::at_effort(&photons, c.planned.effort, &request);
        (reused, timing) = (c.prepass, c.coarse);
        c.planned
    });
    let gi = match reused {
        Some(gi) => gi,
        None => prepass(view.scene, view.camera, &photons, read, progress),
    };
    if let (Some(p), Some(request)) = (&mut chosen, &request) {
        p.prepass_seconds = Some(super::planner::PrepassSeconds::of(&p.model, p.effort, &gi));
        let tracer = super::eye::Tracer {
            scene: view.scene,
            camera: view.camera,
            light_samples: settings.light_samples,
            diffuse: DiffuseTerm::Photons(&gi),
        };
        // With a short budget's timing prepass, the pixels are traced through it too.
        let coarse = timing.as_ref().map(|c| super::eye::Tracer {
            diffuse: DiffuseTerm::Photons(c),
            ..tracer
        });
        let tracers: Vec<_> = std::iter::once(tracer).chain(coarse).collect();
        super::planner::fit_samples(p, view, settings.seed, &tracers, request, started);
        drop(tracers);
        drop(timing.take());
        let s = settings.to_mut();
        s.sampling = match p.adaptive {
            Some(a) => crate::render::Sampling::Noise {
                spp: p.spp,
                max_spp: a.max_spp,
                target: a.target,
            },
            None => crate::render::Sampling::Stratified { spp: p.spp },
        };
        // The half-buffers' estimate of the camera part, printed beside the expected error.
        s.error_estimate |= p.spp >= 2;
    }
    let diffuse = DiffuseTerm::Photons(&gi);
    let (film, stats) = camera_pass(view, diffuse, &settings, progress);
    let evaluated = gi.precomputed.as_ref().map_or(0, Precomputed::evaluated);
    let gi_stats = GiStats {
        precomputed_evaluated: evaluated,
        planned: chosen,
        ..gi.stats
    };
    (film, stats, gi_stats)
}

/// Runs the photon-map prepass of the frame of `scene` through `camera` with `settings`, the
/// phases in turn, each reported to `progress`: trace and build the global map, then the
/// caustic map ([`Prepass::build_with`]; skipped when `read` holds maps read from a file,
/// [`super::maps_file::load`]), estimate the precomputation points ([`Prepass::precompute_for`]),
/// and make the irradiance cache ([`Prepass::with_cache`]; skipped when the file held it). The one
/// chain of these phases: a render and `caustic photons --save` both run it.
pub fn prepass(
    scene: &Scene,
    camera: &Camera,
    settings: &GiSettings,
    read: Option<Prepass>,
    progress: &dyn Progress,
) -> Prepass {
    read.unwrap_or_else(|| Prepass::build_with(scene, settings, progress))
        .precompute_for(camera)
        .with_cache(scene, camera, progress)
}

/// Returns `settings` with the plan's choices: a caustic map or none, final gathering or the
/// global map seen directly.
pub fn planned(settings: &GiSettings, plan: &Plan) -> GiSettings {
    let indirect = match settings.indirect {
        Indirect::Gather { .. } if !plan.final_gathering => Indirect::Direct,
        Indirect::Direct if plan.final_gathering => Indirect::Gather {
            rays: super::DEFAULT_GATHER_RAYS,
        },
        i => i,
    };
    GiSettings {
        caustics: plan.caustics,
        indirect,
        ..settings.clone()
    }
}

/// Phases 1 and 2 for one map: traces the photons of `kind` with each light's share of the
/// budget and builds their kd-tree; returns the map with its per-light counts and the two
/// phases' times. One map is traced and built before the next is traced, so that only one
/// map's photons are ever held in the tracer's form ([`crate::photon::stream`]).
fn trace_and_build(
    scene: &Scene,
    settings: &GiSettings,
    kind: MapKind,
    progress: &dyn Progress,
) -> (CountedMap, Duration, Duration) {
    let start = Instant::now();
    let budget = settings.budget(&scene.lights, kind);
    let traced = trace_map_with(scene, &budget, kind, settings.seed, progress);
    let trace_time = start.elapsed();
    let start = Instant::now();
    let map = CountedMap {
        map: PhotonMap::from_stream(traced.photons),
        per_light: traced.per_light,
    };
    (map, trace_time, start.elapsed())
}

impl Prepass {
    /// Traces and stores the photons of `scene` (both cores) and builds their kd-trees.
    pub fn build(scene: &Scene, settings: &GiSettings) -> Prepass {
        Prepass::build_with(scene, settings, &NoProgress)
    }

    /// [`Prepass::build`], reporting each phase to `progress`. The phases: trace and build the
    /// global map, then the caustic map, then the map of precomputation points.
    pub fn build_with(scene: &Scene, settings: &GiSettings, progress: &dyn Progress) -> Prepass {
        let (global, mut trace_time, mut build_time) =
            trace_and_build(scene, settings, MapKind::Global, progress);
        let caustic = settings.caustics.then(|| {
            let (map, trace, build) = trace_and_build(scene, settings, MapKind::Caustic, progress);
            trace_time += trace;
            build_time += build;
            (map, trace + build)
        });
        let caustic_time = caustic.as_ref().map_or(Duration::ZERO, |c| c.1);
        let mut gi = Prepass::of_maps(scene, settings, global, caustic.map(|c| c.0));
        gi.stats.trace_time = trace_time;
        gi.stats.build_time = build_time;
        gi.stats.caustic_time = caustic_time;
        gi
    }

    /// Returns the prepass of maps and an irradiance cache read from a file (`maps`: the
    /// global map, the caustic map and the cache, [`super::maps_file::load`]) in `read`, with
    /// the precomputation points when `settings` asks for them (estimated by
    /// [`Prepass::precompute_for`], as for maps traced here). The cache is the frame's, made over
    /// the whole image when the maps were saved: the cache [`Prepass::with_cache`] would make (the
    /// file's fingerprint holds what it depends on).
    pub fn of_read_maps(
        scene: &Scene,
        settings: &GiSettings,
        (global, caustic, cache): (CountedMap, Option<CountedMap>, Option<IrradianceCache>),
        read: Duration,
    ) -> Prepass {
        let mut gi = Prepass::of_maps(scene, settings, global, caustic);
        gi.stats.read_time = Some(read);
        gi.stats.read_records = cache.as_ref().map_or(0, |c| c.len());
        gi.cache = cache;
        gi
    }

    /// Returns the prepass of these maps and their per-light counts, with the precomputation
    /// points when the settings ask for them.
    fn of_maps(
        scene: &Scene,
        settings: &GiSettings,
        global: CountedMap,
        caustic: Option<CountedMap>,
    ) -> Prepass {
        let extent = scene.extent().max(f32::MIN_POSITIVE);
        let r = settings.max_radius * extent;
        let (caustic_map, caustic_counts) = caustic.map(|c| (c.map, c.per_light)).unzip();
        let mut gi = Prepass {
            stats: GiStats {
                global: global.per_light,
                caustic: caustic_counts.unwrap_or_default(),
                global_bytes: global.map.bytes(),
                caustic_bytes: caustic_map.as_ref().map_or(0, |m| m.bytes()),
                ..GiStats::default()
            },
            global: global.map,
            caustic: caustic_map.filter(|m| !m.is_empty()),
            precomputed: None,
            cache: None,
            settings: settings.clone(),
            global_r2: r * r,
            caustic_r2: 0.25 * r * r,
            fixed_radii: false,
            local: None,
        };
        let gathers = matches!(settings.indirect, Indirect::Gather { .. });
        if settings.precompute && gathers && !gi.global.is_empty() {
            let start = Instant::now();
            let pre = Precomputed::new(&gi.global);
            gi.stats.precompute_time = start.elapsed();
            gi.stats.precomputed_points = pre.points.len();
            gi.precomputed = Some(pre);
        }
        gi
    }

    /// Returns the irradiance at precomputation point `point` (an id of
    /// `precomputed.points`), estimating it now if no gather ray has read it yet; None
    /// without precomputation.
    ///
    /// # Panics
    /// If `point` is not below the number of points.
    pub fn precomputed_irradiance(&self, point: PhotonId) -> Option<Vec3A> {
        let pre = self.precomputed.as_ref()?;
        Some(self.point_irradiance(pre, point).irradiance)
    }

    /// Returns the irradiance at precomputation point `point` of `pre` (at `p`, normal `n`):
    /// its estimate from the global photons that are *not* precomputation points, scaled for the
    /// thinning, with the squared radius of the disc it gathered them over.
    ///
    /// Why the others only: a final-gather ray reads the point nearest to where it lands, and
    /// the nearest of a set of points is most often one with a large empty cell around it, that
    /// is, one where photons happen to be sparse. An estimate that counted the points themselves
    /// would be low exactly where it is read (and one that counted the point it is made at,
    /// which sits where the kernel is largest, high by about 2/(k−1)): the two biases measured
    /// −2.7% and +4% on a Cornell box's ceiling against Mitsuba. The points are an independent
    /// random thinning of the photons, so the points and the other photons are independent
    /// samples of the same density: which point a ray reads says nothing about that point's
    /// estimate, and the others' estimate, scaled by `STRIDE/(STRIDE−1)` for the thinning, is
    /// unbiased.
    fn point_irradiance(&self, pre: &Precomputed, point: PhotonId) -> PointEstimate {
        pre.value(point, || {
            let ph = pre.points.get(point);
            let others = |id: PhotonId| !is_precompute_point(id);
            let thinning = PRECOMPUTE_STRIDE as f32 / (PRECOMPUTE_STRIDE - 1) as f32;
            FOUND.with_borrow_mut(|found| {
                let (map, k, r2) = (&self.global, self.settings.k, self.global_r2);
                let d2 = map.knn_where(ph.position, k, r2, others, found);
                PointEstimate {
                    irradiance: self.kernel_sum(map, found, d2, (ph.position, ph.normal), false)
                        * thinning,
                    r2: d2,
                }
            })
        })
    }

    /// Returns the irradiance at `p` on a surface with normal `n` (facing the side the light
    /// arrives from) estimated from the `kind` map within its radius (zero without a caustic
    /// map); `indirect_only` skips photons that made no diffuse bounce.
    pub fn irradiance(
        &self,
        kind: MapKind,
        p: Vec3A,
        n: Vec3A,
        indirect_only: bool,
        counts: &mut RayCounts,
    ) -> Vec3A {
        self.estimate((kind, self.settings.k), (p, n), indirect_only, true, counts)
            .0
    }

    /// [`Prepass::irradiance`] from the `k` nearest photons of the `kind` map (without fixed
    /// radii) at `at` = (point, normal), over the local radii there when
    /// `local` (the eye path's diffuse points; a final-gather ray's end reads the radius the
    /// fields' median shrinks to: gathers average hundreds of such reads, whose noise they
    /// smooth, and a field lookup at each read doubled a gathered frame's time).
    fn estimate(
        &self,
        (kind, k): (MapKind, usize),
        (p, n): (Vec3A, Vec3A),
        indirect_only: bool,
        local: bool,
        counts: &mut RayCounts,
    ) -> (Vec3A, f32) {
        let (map, max_d2) = match (kind, &self.caustic) {
            (MapKind::Global, _) => (&self.global, self.global_r2),
            (MapKind::Caustic, Some(c)) => (c, self.caustic_r2),
            (MapKind::Caustic, None) => return (Vec3A::ZERO, 0.0),
        };
        FOUND.with_borrow_mut(|found| {
            let r2 = if self.fixed_radii {
                let r2 = match self.local.as_ref().filter(|_| local) {
                    Some((fields, (global, caustic))) => {
                        let scale = if kind == MapKind::Caustic {
                            caustic
                        } else {
                            global
                        };
                        (fields.at(kind == MapKind::Caustic, p, n) * scale).powi(2)
                    }
                    None => max_d2,
                };
                map.within(p, r2, found);
                r2
            } else {
                map.knn(p, k, max_d2, found)
            };
            counts.lookups += 1;
            counts.photons_used += found.len() as u64;
            let e = self.kernel_sum(map, found, r2, (p, n), indirect_only);
            (e, r2)
        })
    }

    /// Returns the kernel-weighted power of the `found` photons of `map` within radius² `r2`,
    /// as seen by a surface at `at` = (point, unit geometric normal).
    fn kernel_sum(
        &self,
        map: &PhotonMap,
        found: &[(f32, PhotonId)],
        r2: f32,
        (p, n): (Vec3A, Vec3A),
        indirect_only: bool,
    ) -> Vec3A {
        if found.is_empty() || r2 <= 0.0 {
            return Vec3A::ZERO;
        }
        let mut e = Vec3A::ZERO;
        for &(d2, id) in found {
            let ph = map.get(id);
            // Photons from another surface (round a corner, behind a thin wall: the normal and
            // side tests) do not count.
            if ph.normal.dot(n) < 0.7
                || ph.dir.dot(n) <= 0.0
                || (indirect_only && ph.direct)
                || !on_one_surface(ph.position - p, n, ph.normal)
            {
                continue;
            }
            e += ph.power * self.settings.filter.weight(d2, r2);
        }
        e
    }

    /// Returns these maps with estimates that take every photon within `global` (the global
    /// map) or `caustic` (the caustic map) of the point, kernel-weighted over that disc, instead
    /// of the `k` nearest: the progressive integrator's estimates, whose radii it shrinks from
    /// pass to pass. Precomputed irradiance is dropped (it was made with the `k` nearest).
    pub fn with_fixed_radii(mut self, global: f32, caustic: f32) -> Prepass {
        self.global_r2 = global * global;
        self.caustic_r2 = caustic * caustic;
        self.fixed_radii = true;
        self.precomputed = None;
        self.cache = None;
        self
    }

    /// Returns these maps with the progressive integrator's estimates over radii that vary over
    /// space ([`super::local_radii`]): at `p`, the fields' first-pass radius there scaled by
    /// `radii` over the fields' medians (`radii` are what one global radius would be now).
    pub fn with_local_radii(self, fields: Arc<LocalRadii>, radii: (f32, f32)) -> Prepass {
        let (g, c) = fields.medians();
        let scales = (radii.0 / g, radii.1 / c);
        let mut maps = self.with_fixed_radii(radii.0, radii.1);
        maps.local = Some((fields, scales));
        maps
    }

    /// Returns these maps with every precomputation point estimated now, in kd-tree order, when
    /// there are no more points than `camera`'s image has pixels; else as they are (each point
    /// estimated when first read, [`Precomputed`]).
    ///
    /// Why the image decides: with at most a point per pixel nearly every point is read (the
    /// final scene reads 194k of its 195k), and estimating them in order, each once, costs a
    /// little less than on first read (random order, at times by two threads at once): the
    /// final scene at 1024², points and cache pass together, 9.23 / 9.37 s up front against
    /// 9.90 / 9.45 s lazily (two alternating runs). With more points than pixels (10^7 photons
    /// under a preview) most are never read. The values are the same either way, so this
    /// changes times only, never the image.
    pub fn precompute_for(mut self, camera: &Camera) -> Prepass {
        use rayon::prelude::*;
        let (w, h) = camera.size();
        if let Some(pre) = &self.precomputed
            && pre.points.len() as u64 <= u64::from(w) * u64::from(h)
        {
            let start = Instant::now();
            (0..pre.points.len() as u32)
                .into_par_iter()
                .with_min_len(1024)
                .for_each(|i| {
                    self.point_irradiance(pre, PhotonId(i));
                });
            self.stats.precompute_time += start.elapsed();
        }
        self
    }

    /// Returns these maps with an irradiance cache for the frame of `scene` through `camera`
    /// when final gathering runs and the settings ask for one ([`IrradianceCache::build`]).
    pub fn with_cache(self, scene: &Scene, camera: &Camera, progress: &dyn Progress) -> Prepass {
        self.with_cache_over(scene, camera, Probes::Whole, progress)
    }

    /// [`Prepass::with_cache`] with the cache made only where `probes` says: the planner's
    /// pilot reads it at a grid of pixels, and a cache near them is what those pixels see,
    /// at a fraction of the whole image's records. Such a prepass is not a frame's: before a
    /// render takes it, [`Prepass::with_whole_cache`].
    pub fn with_cache_over(
        mut self,
        scene: &Scene,
        camera: &Camera,
        probes: Probes,
        progress: &dyn Progress,
    ) -> Prepass {
        let gathers = matches!(self.settings.indirect, Indirect::Gather { .. });
        let (w, h) = camera.size();
        let small = w.max(h) < super::irradiance_cache::MIN_IMAGE_SIZE;
        let read = self.cache.is_some();
        if !self.settings.cache.enabled || !gathers || self.global.is_empty() || small || read {
            return self;
        }
        let (cache, stats) = IrradianceCache::build(
            scene,
            camera,
            &self,
            &self.settings.cache,
            (self.settings.seed, probes),
            progress,
        );
        self.cache = Some(cache);
        self.stats.cache = Some(stats);
        self
    }

    /// Returns these maps with their cache made afresh over the whole image (a pilot's
    /// prepass, whose cache covered only its pixels, made ready for the frame).
    pub fn with_whole_cache(
        mut self,
        scene: &Scene,
        camera: &Camera,
        progress: &dyn Progress,
    ) -> Prepass {
        self.cache = None;
        self.stats.cache = None;
        self.with_cache(scene, camera, progress)
    }

    /// Returns whether an eye path in `state` final-gathers at a diffuse surface (else it reads
    /// the global map there).
    pub fn gathers(&self, state: &PathState) -> bool {
        matches!(self.settings.indirect, Indirect::Gather { .. })
            && state.depth <= MAX_GATHER_DEPTH
            && state.weight >= GATHER_MIN_WEIGHT
    }

    /// Returns the final gather `g` at `at`: its stratified cosine-distributed rays about its
    /// own axis ([`Gather::directions`]: the shading normal for a point's own gather, `ng` for
    /// an irradiance-cache record), those below the surface skipped, summed ([`Gather`]: the
    /// irradiance, its gradients and `R`).
    pub fn gather(
        &self,
        scene: &Scene,
        at: GatherAt,
        mut g: Gather,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Gather {
        let GatherAt { p, ng, media } = at;
        for (i, d) in g.directions(rng).into_iter().enumerate() {
            if d.dot(ng) <= 0.0 {
                continue;
            }
            counts.secondary += 1;
            let ray = Ray::new(offset_ray_origin(p, ng, d), d);
            let (l, t) = self.gathered_radiance(scene, &ray, media, rng, counts);
            g.add(i, d, l, t);
        }
        g
    }

    /// Returns the global and the caustic map's search radii (the largest, for `k`-nearest
    /// estimates).
    pub fn radii(&self) -> (f32, f32) {
        (self.global_r2.sqrt(), self.caustic_r2.sqrt())
    }

    /// Returns the global map's irradiance estimate at `p` (all photons).
    pub fn global_irradiance(&self, p: Vec3A, n: Vec3A) -> Vec3A {
        self.irradiance(MapKind::Global, p, n, false, &mut RayCounts::default())
    }

    /// Returns the caustic map's irradiance estimate at `p` (zero without a caustic map).
    pub fn caustic_irradiance(&self, p: Vec3A, n: Vec3A) -> Vec3A {
        self.caustic_at(p, n, self.settings.k, &mut RayCounts::default())
    }

    /// Returns the caustic map's estimate from the `k` nearest photons at an eye path's diffuse
    /// point `p` (unit normal `n`), or, within an open pixel scope ([`crate::render::scope`]),
    /// that of an earlier sample of the same round with the same `k` whose point lies within
    /// [`REUSE_FRACTION`] of its estimate's radius of `p` on a surface facing the same way
    /// ([`REUSE_MIN_COS`]). The module doc says why.
    fn caustic_at(&self, p: Vec3A, n: Vec3A, k: usize, counts: &mut RayCounts) -> Vec3A {
        let shares = self.settings.share_caustics && !self.fixed_radii && self.caustic.is_some();
        let Some(scope) = crate::render::scope::current().filter(|_| shares) else {
            return self
                .estimate((MapKind::Caustic, k), (p, n), false, true, counts)
                .0;
        };
        let prepass = std::ptr::from_ref(self) as usize;
        let mine = |e: &Memo| e.prepass == prepass && e.k == k;
        let reused = MEMO.with_borrow_mut(|m| {
            if m.scope != scope {
                m.scope = scope;
                m.len = 0;
            }
            m.entries[..m.len].iter().find_map(|e| {
                let near = (e.p - p).length_squared() <= e.reuse_d2 && e.n.dot(n) >= REUSE_MIN_COS;
                (near && mine(e)).then_some(e.irradiance)
            })
        });
        if let Some(e) = reused {
            counts.reused += 1;
            return e;
        }
        let (irradiance, r2) = self.estimate((MapKind::Caustic, k), (p, n), false, true, counts);
        MEMO.with_borrow_mut(|m| {
            // Each estimator keeps as many as a render's one does, whatever else the pilot's
            // samples are traced through.
            let held = m.entries[..m.len].iter().filter(|e| mine(e)).count();
            if m.scope == scope && m.len < m.entries.len() && held < MEMO_EACH {
                m.entries[m.len] = Memo {
                    prepass,
                    k,
                    p,
                    n,
                    irradiance,
                    reuse_d2: REUSE_FRACTION * REUSE_FRACTION * r2,
                };
                m.len += 1;
            }
        });
        irradiance
    }

    /// Returns the irradiance a final-gather ray finds at `p` (unit geometric normal `n`): the
    /// precomputed value of the nearest precomputation point that may lie on the same surface
    /// (its normal within [`PRECOMPUTED_MIN_COS`] of `n` and [`on_one_surface`] with `p`), when
    /// `p` lies within the disc that point's estimate gathered over; else (no precomputation,
    /// no such point) the global map's estimate at `p`. The module doc says why.
    pub fn gathered_irradiance(&self, p: Vec3A, n: Vec3A, counts: &mut RayCounts) -> Vec3A {
        if let Some(pre) = &self.precomputed {
            counts.lookups += 1;
            let points = &pre.points;
            let found = points.nearest_where(p, self.global_r2, &mut |id| {
                let n_point = points.normal(id);
                n_point.dot(n) >= PRECOMPUTED_MIN_COS
                    && on_one_surface(points.position(id) - p, n, n_point)
            });
            if let Some((d2, id)) = found {
                let point = self.point_irradiance(pre, id);
                if d2 <= point.r2 {
                    counts.photons_used += 1;
                    return point.irradiance;
                }
            }
        }
        let global = (MapKind::Global, self.settings.k);
        self.estimate(global, (p, n), false, false, counts).0
    }

    /// Returns the caustic and indirect light leaving the diffuse lobe of the BSDF at `at`
    /// towards its `wo`.
    pub fn diffuse(
        &self,
        scene: &Scene,
        at: &ShadingPoint,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        self.diffuse_with(scene, at, rng, None, counts)
    }

    /// [`Prepass::diffuse`]; with `unbiased`, a point the cache serves takes, instead of the
    /// cache's value, that value less one serving record's error there: the record (chosen
    /// by its weight, with a stream forked from `rng` by the salt, so that the path's own draws
    /// stay the same) moved to the point, less a gather at the point with the record's own
    /// random numbers. The two gathers see nearly the same light along nearly the same rays,
    /// so their difference is nearly noiseless, and its expectation is the cache's
    /// interpolation bias at the point: the planner's pilot measures it so
    /// ([`super::planner`]).
    pub fn diffuse_with(
        &self,
        scene: &Scene,
        at: &ShadingPoint,
        rng: &mut Rng,
        unbiased: Option<u64>,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let (p, bsdf, state) = (at.p(), at.bsdf(), &at.state);
        let ng = bsdf.ng;
        let mut e = self.caustic_at(p, ng, self.settings.k, counts);
        let gather_at = GatherAt {
            p,
            ng,
            media: state.media,
        };
        // Where a cache record serves the point, its gather stands for the indirect light of
        // every eye path, those too weak to be gathered included (they would read the map
        // directly, blotchier and slower: a 50-nearest estimate against a grid cell's records).
        e += if let Some(cache) = &self.cache
            && let Some(cached) = cache.lookup(p, ng, bsdf.n)
        {
            counts.cached += 1;
            match unbiased.and_then(|salt| cache.pick(p, ng, rng.fork(salt).next_f32())) {
                Some((record, mut stream)) => {
                    let g = Gather::with_translation(ng, self.settings.cache.rays);
                    let fresh = self.gather(scene, gather_at, g, &mut stream, counts);
                    cached - (record.at(p, ng) - fresh.irradiance())
                }
                None => cached,
            }
        } else if let Indirect::Gather { rays } = self.settings.indirect
            && self.gathers(state)
        {
            counts.gathered += 1;
            self.gather(scene, gather_at, Gather::new(bsdf.n, rays), rng, counts)
                .irradiance()
        } else {
            self.irradiance(MapKind::Global, p, ng, true, counts)
        };
        bsdf.kd * FRAC_1_PI * e
    }

    /// Returns the caustic light alone leaving the diffuse lobe of the BSDF at `at` towards its
    /// `wo`, estimated from the `k` nearest caustic photons: the planner's pilot. A `k`-nearest
    /// estimate from `k' = k·F/F'` photons of a map at effort `F` has the radius of one from
    /// `k` photons at `F'`, so pairs of its pilot prepasses read with fewer photons show how a
    /// larger effort's caustic noise spreads over a pixel's samples ([`super::planner`]).
    pub fn caustic_diffuse(&self, at: &ShadingPoint, k: usize, counts: &mut RayCounts) -> Vec3A {
        let bsdf = at.bsdf();
        bsdf.kd * FRAC_1_PI * self.caustic_at(at.p(), bsdf.ng, k, counts)
    }

    /// Returns the radiance a final-gather ray (in `media`) brings back: where it lands on a
    /// diffuse lobe, the global map's estimate of the light leaving it; where it lands on a
    /// mirror or a dielectric, the same read where the path continues, chosen by the one BSDF's
    /// roulette, for up to [`MAX_GATHER_SPECULAR`] specular bounces. Emitters seen along the way
    /// count nothing: light → (specular) → this point is the direct term or the caustic map's.
    /// Also returns the distance to the first surface met, counting false interfaces (infinite
    /// when the ray leaves the scene; the irradiance cache's `R`).
    fn gathered_radiance(
        &self,
        scene: &Scene,
        ray: &Ray,
        mut media: MediumStack,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> (Vec3A, f32) {
        let (mut ray, mut throughput, mut out) = (*ray, Vec3A::ONE, Vec3A::ZERO);
        let (mut bounces, mut first) = (0, None);
        // Every ray of the gather path is a gather ray (its lookups cast none of another kind).
        crate::accel::counters::kind(RayKind::Gather);
        loop {
            let Some(hit) = scene.intersect(&ray) else {
                return (out, first.unwrap_or(f32::INFINITY));
            };
            let t_first = *first.get_or_insert(hit.t * ray.dir.length());
            throughput *= scene.kept_along(&media, &ray, hit.t);
            let specular = scene.materials[hit.material as usize].is_specular();
            let needs = if specular { Needs::Full } else { Needs::Albedo };
            let it = scene.interaction(&ray, &hit, needs, None);
            let (p, bsdf) = (it.surf.p, &it.bsdf);
            let crossing = bsdf.crossing(&media);
            if let Some(c) = crossing
                && c.is_false()
            {
                media = c.after;
                ray = Ray::new(offset_ray_origin(p, it.surf.ng, ray.dir), ray.dir);
                continue;
            }
            let kd = bsdf.lobes().diffuse;
            if kd.max_element() > 0.0 {
                let e = self.gathered_irradiance(p, bsdf.ng, counts);
                out += throughput * kd * FRAC_1_PI * e;
            }
            if !specular || bounces == MAX_GATHER_SPECULAR {
                return (out, t_first);
            }
            let Some(next) = bsdf.sample_specular(crossing.as_ref(), rng) else {
                return (out, t_first);
            };
            throughput *= next.weight * next.radiance_scale;
            if let Some(after) = next.media {
                media = after;
            }
            bounces += 1;
            counts.secondary += 1;
            ray = Ray::new(offset_ray_origin(p, bsdf.ng, next.dir), next.dir);
        }
    }
}
