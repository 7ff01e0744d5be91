//! Progressive photon mapping: the consistent reference integrator. Its image converges to the
//! right one as passes are added, where the photon mapper's keeps the bias of its fixed `k`.
//!
//! # Method
//! Probabilistic progressive photon mapping (Knaus & Zwicker, *Progressive Photon Mapping: A
//! Probabilistic Approach*, TOG 2011), which converges as Hachisuka & Jensen's stochastic
//! progressive photon mapping (SPPM, 2009; pbrt-v4's `SPPMIntegrator`) does. Each pass `i` is
//! an independent photon-mapping frame: fresh photon maps (both, by the plan), a camera pass
//! with one jittered sample per pixel, and estimates that take every photon within a radius
//! `r_i` (one per map), which shrinks from pass to pass as
//!
//! `r_{i+1}² = r_i² · (i + α) / (i + 1)`,
//!
//! so `r_i² ∝ i^(α−1)`. The image is the mean of the passes. A pass's kernel bias is
//! proportional to `r_i²` and its variance to `1/r_i²`; over `N` passes the bias falls as
//! `N^(α−1)` and the variance as `N^(−α)`, and with `α = 2/3` (the default, as pbrt-v4's) both
//! parts of the RMSE fall as `N^(−1/3)`. Direct light (shadow rays), specular paths and pixel
//! area are Monte Carlo terms and converge as `N^(−1/2)`.
//!
//! # Why this design rather than SPPM's per-pixel statistics
//! - **One code path**: a pass runs the photon mapper's phases and the eye path unchanged, so
//!   everything the photon mapper renders (caustics through water and glass, textures, area
//!   lights, final gathering) the reference renders by the same code, and a difference between
//!   the two is a difference of estimates, not of features.
//! - **Bounded memory**: a pass holds its own maps and film and frees them before the next;
//!   what persists is three sums of the image (the mean, and the even and odd passes). Nothing
//!   grows with the number of passes (pbrt-v3's SPPM grew to tens of GB, pbrt-v3#264).
//! - **An error estimate for free**: passes are independent, so the even and the odd passes
//!   make two independent half images whose difference estimates the noise of the mean
//!   ([`Accumulator::estimated_error`]), which `--target-error` stops on.
//! - **Deterministic**: pass `i`'s photon and pixel streams are keyed by `(seed, i)`, so the
//!   image depends on neither the thread count nor the tiling.
//! - **Local radii without per-pixel state**: where SPPM keeps each pixel's radius and photon
//!   count, the first pass's radius here is a field over space set by a pilot map's density
//!   (a disc of about `k` photons where photons are sparser than the median, the median's disc
//!   where they are denser; [`super::local_radii`] says why), shrunk by the schedule above. A
//!   dim caustic gets a larger radius and converges at the relative error a bright one does: on `tests/light_transport/progressive.rs`'s two-mirror scene a caustic ten
//!   times dimmer has 0.35 times the error one radius leaves it, level with the bright one's.
//!   Final-gather rays' ends read one radius per map (the fields' median, shrunk): a gather
//!   averages them. `--local-radii off` gives one radius per map everywhere: the median
//!   distance to the `k`-th nearest photon over up to 1024 photons of the first pass
//!   ([`initial_radius`]); `--radius` sets the median either way.
//!
//! The estimated error counts noise only: the even and odd half images share the kernel's
//! bias. With `α = 2/3` the bias is asymptotically of the same order as the noise, so the true
//! error can be up to about `√2` times the estimate (`docs/accuracy.md` measures it).
//!
//! ```text
//! caustic render scenes/cornell_glass.lua --integrator progressive --passes 256 --write-every 16
//! ```

use super::eye::DiffuseTerm;
use super::local_radii::{LocalRadii, RadiusField};
use super::photon_map::{GiSettings, GiStats, Prepass};
use super::{Partial, Plan, Settings, Stats, View, camera_pass};
use crate::film::{Film, Window};
use crate::photon::PhotonMap;
use crate::progress::{Progress, StopOnly};
use crate::render::Sampling;
use crate::scene::Scene;
use crate::stats::RenderStats;
use glam::Vec3A;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Radius reduction parameter α by default (pbrt-v4's, the optimum of Knaus & Zwicker).
pub const DEFAULT_ALPHA: f32 = 2.0 / 3.0;

/// Passes by default when neither `--target-error` nor `--time-budget` stops the render.
pub const DEFAULT_PASSES: u32 = 64;

/// Most passes one render may run (`--passes`, and the bound under `--target-error`).
pub const MAX_PASSES: u32 = 1 << 20;

/// Global-map photons per pass by default: a pass is about a quarter of a default photon-mapped
/// frame (one camera sample per pixel instead of four), so a quarter of its photons.
pub const PASS_GLOBAL_PHOTONS: u64 = super::photon_map::GLOBAL_PHOTONS / 4;

/// Caustic-map photons per pass by default (a quarter of the photon mapper's, as above).
pub const PASS_CAUSTIC_PHOTONS: u64 = super::photon_map::CAUSTIC_PHOTONS / 4;

/// Fewest passes before `--target-error` may stop: the noise estimate needs two of each half.
pub const MIN_PASSES_FOR_ESTIMATE: u32 = 4;

/// Photons at which [`initial_radius`] measures the distance to the `k`-th nearest.
const RADIUS_PROBES: usize = 1024;

/// What shapes a progressive render besides the photon mapper's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgressiveSettings {
    /// Passes to run at most.
    pub passes: u32,
    /// Radius reduction α in (0, 1): larger shrinks the radii more slowly.
    pub alpha: f32,
    /// First pass's radius of the global map as a fraction of the scene's diagonal (the caustic
    /// map's is half of it); `None` sets both from the first pass's photon density.
    pub initial_radius: Option<f32>,
    /// Stop once the estimated relative RMSE is at most this.
    pub target_error: Option<f64>,
    /// Stop before a pass that would end after this much time.
    pub time_budget: Option<Duration>,
    /// Report the running image to [`Progress::snapshot`] every this many passes.
    pub snapshot_every: Option<u32>,
    /// The index of the first pass to run (`--first-pass`): a render farm runs passes `P` to
    /// `P + passes - 1` in one process and others elsewhere, and `caustic merge` adds them up
    /// ([`super::passes_file`]). Each pass's streams and radius are those pass `i` has in one
    /// process running them all.
    pub first_pass: u32,
    /// Radii that vary over space with a pilot map's photon density ([`super::local_radii`])
    /// rather than one per map for the whole image.
    pub local_radii: bool,
}

impl Default for ProgressiveSettings {
    fn default() -> ProgressiveSettings {
        ProgressiveSettings {
            passes: DEFAULT_PASSES,
            alpha: DEFAULT_ALPHA,
            initial_radius: None,
            target_error: None,
            time_budget: None,
            snapshot_every: None,
            first_pass: 0,
            local_radii: true,
        }
    }
}

/// Why a progressive render stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// It ran the passes it was given.
    Passes,
    /// The estimated error reached the target.
    TargetError,
    /// Another pass would have ended after the time budget.
    TimeBudget,
    /// The render was asked to stop ([`Progress::should_stop`]): the pass under way is
    /// dropped, unless it is the first.
    Interrupted,
}

/// What a progressive render reports, for `--stats`.
#[derive(Clone, Debug)]
pub struct ProgressiveStats {
    pub passes: u32,
    pub stop: Stop,
    /// The mean's relative RMSE estimated from the even and odd passes (noise only; `None`
    /// before two passes or on a black image).
    pub estimated_error: Option<f64>,
    /// The global and caustic maps' radii at the first and at the last pass.
    pub first_radii: (f32, f32),
    pub last_radii: (f32, f32),
    /// Whether the radii varied over space (then the radii above are the fields' medians).
    pub local_radii: bool,
    pub time: Duration,
    /// The sums the film is the mean of, for a pass file ([`super::passes_file`]).
    pub sums: Accumulator,
}

/// Renders `view` progressively: passes of photon tracing, map building and a camera pass with
/// shrinking fixed-radius estimates, averaged, until the settings' passes, target error or time
/// budget stop it.
pub fn render(
    view: View,
    settings: &Settings,
    plan: Plan,
    progress: &dyn Progress,
) -> (Film, Stats) {
    let View { scene, window, .. } = view;
    let prog = settings.progressive.clone().unwrap_or_default();
    let start = Instant::now();
    let mut acc = Accumulator::starting_at(window, prog.first_pass);
    let (mut render_stats, mut photon_stats) = (RenderStats::default(), GiStats::default());
    // A pass's phases report nothing (progress counts passes) but stop when asked.
    let inner = StopOnly(progress);
    let (local, mut first_radii, mut radii) = starting_radii(scene, settings, &plan, &inner);
    progress.start("progressive passes", prog.passes as u64);
    // The first pass's rows, when the render is stopped before it ends.
    let mut first_rows = None;
    let stop = loop {
        let pass = prog.first_pass + acc.passes;
        let gi = Prepass::build_with(scene, &pass_photons(settings, &plan, pass), &inner);
        if pass == 0 && local.is_none() {
            first_radii = first_pass_radii(scene, &gi, &prog);
            radii = first_radii;
        }
        let gi = match &local {
            Some(fields) => gi.with_local_radii(fields.clone(), radii),
            None => gi.with_fixed_radii(radii.0, radii.1),
        };
        let pass_settings = Settings {
            seed: pass_seed(settings.seed, pass),
            sampling: jittered(&settings.sampling),
            ..settings.clone()
        };
        let diffuse = DiffuseTerm::Photons(&gi);
        let (film, rs) = camera_pass(view, diffuse, &pass_settings, &inner);
        render_stats.add(&rs);
        add_photon_stats(&mut photon_stats, &gi.stats);
        drop(gi);
        if rs.rows_skipped > 0 {
            // Stopped within this pass: keep the passes finished, or the first pass's rows.
            if acc.passes == 0 {
                first_rows = Some(film);
            }
            break Stop::Interrupted;
        }
        acc.add(&film);
        drop(film);
        crate::mem::release_free_memory();
        progress.advance(1);
        if let Some(k) = prog.snapshot_every
            && acc.passes.is_multiple_of(k)
        {
            progress.snapshot(acc.passes, &acc.mean());
        }
        let elapsed = start.elapsed();
        if let Some(stop) = should_stop(&prog, &acc, elapsed) {
            break stop;
        }
        if progress.should_stop() {
            break Stop::Interrupted;
        }
        radii = shrink(radii, pass + 1, prog.alpha);
    };
    render_stats.time = start.elapsed();
    let progressive = ProgressiveStats {
        passes: acc.passes,
        stop,
        estimated_error: acc.estimated_error(),
        first_radii,
        last_radii: radii,
        local_radii: local.is_some(),
        time: start.elapsed(),
        sums: Accumulator::starting_at(window, prog.first_pass),
    };
    let interrupted = match (&first_rows, stop) {
        (Some(_), _) => Partial::of_rows(&render_stats, window.size().1),
        (None, Stop::Interrupted) => Some(Partial::Passes {
            done: acc.passes,
            planned: prog.passes.min(MAX_PASSES),
        }),
        (None, _) => None,
    };
    let stats = Stats {
        plan,
        render: render_stats,
        photons: Some(photon_stats),
        progressive: Some(progressive),
        interrupted,
    };
    let film = first_rows.unwrap_or_else(|| acc.mean());
    let mut stats = stats;
    if let Some(p) = stats.progressive.as_mut() {
        p.sums = acc;
    }
    (film, stats)
}

/// The global and the caustic map's radii.
type Radii = (f32, f32);

/// Returns a render's local radii (with `--local-radii on`), and its first pass's radii and
/// those of pass `first_pass` as far as they are known before its first pass: both zero when
/// pass 0, run here, will set them from its own maps.
fn starting_radii(
    scene: &Scene,
    settings: &Settings,
    plan: &Plan,
    progress: &dyn Progress,
) -> (Option<Arc<LocalRadii>>, Radii, Radii) {
    let prog = settings.progressive.clone().unwrap_or_default();
    if prog.local_radii {
        let fields = pilot_radii(scene, settings, plan, progress);
        let first = given_radii(scene, &prog).unwrap_or_else(|| fields.medians());
        let now = shrunk_to(first, prog.first_pass, prog.alpha);
        return (Some(Arc::new(fields)), first, now);
    }
    if prog.first_pass > 0 {
        let (first, now) = radii_at(scene, settings, plan, &prog);
        return (None, first, now);
    }
    (None, (0.0, 0.0), (0.0, 0.0))
}

/// Returns the photon settings of pass `pass` of a render with `settings` as `plan` says: the
/// plan's maps, the pass's own seed, no precomputation points (estimates take every photon
/// within the pass's radii).
fn pass_photons(settings: &Settings, plan: &Plan, pass: u32) -> GiSettings {
    GiSettings {
        seed: pass_seed(settings.photons.seed, pass),
        precompute: false,
        ..super::photon_map::planned(&settings.photons, plan)
    }
}

/// Returns the radii `--radius` sets (the global map's that fraction of the scene's diagonal,
/// the caustic map's half of it), or `None` without it.
fn given_radii(scene: &Scene, prog: &ProgressiveSettings) -> Option<(f32, f32)> {
    let extent = scene.extent().max(f32::MIN_POSITIVE);
    prog.initial_radius.map(|f| (f * extent, 0.5 * f * extent))
}

/// Returns the seed of pass `pass`'s streams under `seed`.
pub fn pass_seed(seed: u64, pass: u32) -> u64 {
    crate::sampling::mix64(seed ^ crate::sampling::mix64(0x7072_6f67_0000_0000 | pass as u64))
}

/// Returns a pass's pixel sampling: the frame's count of jittered samples (adaptive sampling has
/// no progressive form; the command line refuses it, the library takes one sample).
fn jittered(sampling: &Sampling) -> Sampling {
    match *sampling {
        Sampling::Stratified { spp } | Sampling::Jittered { spp } | Sampling::Noise { spp, .. } => {
            Sampling::Jittered { spp }
        }
        Sampling::Adaptive { .. } => Sampling::Jittered { spp: 1 },
    }
}

/// Returns the radii after pass `passes` (1-based) given those it used (Knaus & Zwicker's
/// `r_{i+1}² = r_i² (i + α)/(i + 1)`).
pub fn shrink((global, caustic): (f32, f32), passes: u32, alpha: f32) -> (f32, f32) {
    let i = passes as f64;
    let f = ((i + alpha as f64) / (i + 1.0)).sqrt() as f32;
    (global * f, caustic * f)
}

/// Returns the first pass's radii: the settings' fraction of the scene's diagonal, or each map's
/// [`initial_radius`] (no larger than the photon mapper's largest search radius).
fn first_pass_radii(scene: &Scene, gi: &Prepass, prog: &ProgressiveSettings) -> (f32, f32) {
    if let Some(radii) = given_radii(scene, prog) {
        return radii;
    }
    let (max_global, max_caustic) = gi.radii();
    let k = gi.settings.k;
    let global = initial_radius(&gi.global, k, max_global);
    let caustic = gi
        .caustic
        .as_ref()
        .map_or(max_caustic, |c| initial_radius(c, k, max_caustic));
    (global, caustic)
}

/// Returns the median, over up to 1024 photons of `map` spread through it, of the distance to
/// the `k`-th nearest other photon, at most `max` (and `max` for an empty map): a radius that
/// holds about `k` photons where photons typically land.
pub fn initial_radius(map: &PhotonMap, k: usize, max: f32) -> f32 {
    let n = map.len();
    let probes = n.min(RADIUS_PROBES);
    let mut found = Vec::new();
    let r: Vec<f32> = (0..probes)
        .map(|j| {
            let id = crate::photon::PhotonId((j * n / probes) as u32);
            super::local_radii::kth_distance(map, map.position(id), k, max, &mut found)
        })
        .collect();
    super::local_radii::median_or(r, max)
}

/// Returns why the render stops after `acc.passes` passes taking `elapsed`, or `None` to go on.
fn should_stop(prog: &ProgressiveSettings, acc: &Accumulator, elapsed: Duration) -> Option<Stop> {
    if acc.passes >= prog.passes.min(MAX_PASSES) {
        return Some(Stop::Passes);
    }
    if let Some(budget) = prog.time_budget {
        let per_pass = elapsed / acc.passes.max(1);
        if elapsed + per_pass > budget {
            return Some(Stop::TimeBudget);
        }
    }
    if let Some(target) = prog.target_error
        && acc.passes >= MIN_PASSES_FOR_ESTIMATE
        && acc.estimated_error().is_some_and(|e| e <= target)
    {
        return Some(Stop::TargetError);
    }
    None
}

/// Returns the radii of the first pass and of pass `prog.first_pass` of a render of `scene`
/// with `settings` as `plan` says: the first pass's from its photon maps (traced again here,
/// without a camera pass) unless `--radius` sets them, then shrunk pass by pass as one process
/// running every pass shrinks them.
fn radii_at(
    scene: &Scene,
    settings: &Settings,
    plan: &Plan,
    prog: &ProgressiveSettings,
) -> ((f32, f32), (f32, f32)) {
    let first = given_radii(scene, prog).unwrap_or_else(|| {
        let gi = Prepass::build(scene, &pass_photons(settings, plan, 0));
        first_pass_radii(scene, &gi, prog)
    });
    (first, shrunk_to(first, prog.first_pass, prog.alpha))
}

/// Returns radii `first` after `passes` passes' shrinking.
fn shrunk_to(first: (f32, f32), passes: u32, alpha: f32) -> (f32, f32) {
    (1..=passes).fold(first, |r, passes| shrink(r, passes, alpha))
}

/// The index whose streams trace the pilot map of [`pilot_radii`]: beyond every pass's.
const PILOT_PASS: u32 = u32::MAX;

/// Returns the local radii of a render of `scene` with `settings` as `plan` says: the fields
/// of a pilot map traced with streams of its own ([`PILOT_PASS`]), each map's radii at most
/// the photon mapper's largest search radius.
fn pilot_radii(
    scene: &Scene,
    settings: &Settings,
    plan: &Plan,
    progress: &dyn Progress,
) -> LocalRadii {
    let gi = Prepass::build_with(scene, &pass_photons(settings, plan, PILOT_PASS), progress);
    let (max_global, max_caustic) = gi.radii();
    let k = gi.settings.k;
    LocalRadii {
        global: RadiusField::new(&gi.global, k, max_global),
        caustic: gi
            .caustic
            .as_ref()
            .map(|c| RadiusField::new(c, k, max_caustic)),
    }
}

/// Adds one pass's photon counters and times to the render's.
fn add_photon_stats(total: &mut GiStats, pass: &GiStats) {
    let add = |t: &mut Vec<_>, p: &[crate::photon::trace::LightCounts]| {
        t.resize(p.len().max(t.len()), Default::default());
        for (t, p) in t.iter_mut().zip(p) {
            let t: &mut crate::photon::trace::LightCounts = t;
            t.emitted += p.emitted;
            t.stored += p.stored;
            t.first_hit_specular += p.first_hit_specular;
        }
    };
    add(&mut total.global, &pass.global);
    add(&mut total.caustic, &pass.caustic);
    total.global_bytes = total.global_bytes.max(pass.global_bytes);
    total.caustic_bytes = total.caustic_bytes.max(pass.caustic_bytes);
    total.trace_time += pass.trace_time;
    total.build_time += pass.build_time;
    total.caustic_time += pass.caustic_time;
}

/// The running sums of a progressive render: all passes, and the even and the odd ones apart.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    pub window: Window,
    /// The index of the first pass added (the parity of a pass's index decides its half).
    pub first: u32,
    pub passes: u32,
    /// Of those, the passes of even index.
    pub even_passes: u32,
    pub sum: Vec<Vec3A>,
    pub even: Vec<Vec3A>,
    pub odd: Vec<Vec3A>,
    pub samples: Vec<u32>,
}

impl Accumulator {
    /// Returns empty sums for `window`.
    pub fn new(window: Window) -> Accumulator {
        Accumulator::starting_at(window, 0)
    }

    /// Returns empty sums for `window` whose first pass will be pass `first`.
    pub fn starting_at(window: Window, first: u32) -> Accumulator {
        let (w, h) = window.size();
        let n = w as usize * h as usize;
        Accumulator {
            window,
            first,
            passes: 0,
            even_passes: 0,
            sum: vec![Vec3A::ZERO; n],
            even: vec![Vec3A::ZERO; n],
            odd: vec![Vec3A::ZERO; n],
            samples: vec![0; n],
        }
    }

    /// Adds one pass's film (of this window).
    pub fn add(&mut self, film: &Film) {
        let even = (self.first + self.passes).is_multiple_of(2);
        self.even_passes += u32::from(even);
        let half = if even { &mut self.even } else { &mut self.odd };
        for (i, &p) in film.pixels.iter().enumerate() {
            self.sum[i] += p;
            half[i] += p;
        }
        for (s, &n) in self.samples.iter_mut().zip(&film.samples) {
            *s = s.saturating_add(n);
        }
        self.passes += 1;
    }

    /// Adds the passes of `other` (of the same window), whatever their indices: their sums,
    /// halves and samples.
    pub fn merge(&mut self, other: &Accumulator) {
        debug_assert_eq!(self.window, other.window);
        for (a, b) in [
            (&mut self.sum, &other.sum),
            (&mut self.even, &other.even),
            (&mut self.odd, &other.odd),
        ] {
            for (x, y) in a.iter_mut().zip(b) {
                *x += *y;
            }
        }
        for (s, &n) in self.samples.iter_mut().zip(&other.samples) {
            *s = s.saturating_add(n);
        }
        self.passes += other.passes;
        self.even_passes += other.even_passes;
    }

    /// Returns the mean of the passes so far as a film (black before the first).
    pub fn mean(&self) -> Film {
        let n = self.passes.max(1) as f32;
        let (width, height) = self.window.size();
        Film {
            width,
            height,
            pixels: self.sum.iter().map(|&p| p / n).collect(),
            samples: self.samples.clone(),
            window: self.window,
        }
    }

    /// Returns the relative RMSE of the mean estimated from the even and odd passes' means `A`
    /// and `B`: with `a` and `b` passes in each, `E[(A − B)²] = σ²(1/a + 1/b)` per channel while
    /// the mean's variance is `σ²/(a + b)`, so the mean's MSE is `mean((A − B)²)·ab/(a + b)²`,
    /// over the mean's mean. `None` before two passes or when the image is black.
    pub fn estimated_error(&self) -> Option<f64> {
        let n = self.passes as f64;
        let a = self.even_passes as f64;
        let b = (self.passes - self.even_passes) as f64;
        if a == 0.0 || b == 0.0 || self.sum.is_empty() {
            return None;
        }
        let (mut d2, mut total) = (0.0f64, 0.0f64);
        for ((&s, &e), &o) in self.sum.iter().zip(&self.even).zip(&self.odd) {
            let d = e / a as f32 - o / b as f32;
            d2 += d.dot(d) as f64;
            total += s.element_sum() as f64;
        }
        let values = 3.0 * self.sum.len() as f64;
        let mean = total / n / values;
        let mse = d2 / values * a * b / (n * n);
        (mean > 0.0).then(|| mse.sqrt() / mean)
    }
}
