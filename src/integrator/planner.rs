//! The time planner: `--time-budget S` and `--target-error E` for the photon-map integrator.
//! A short pilot measures what the frame's two kinds of effort cost and how much error each
//! leaves; the planner then spends the user's time where it lowers the error most, says what it
//! chose and why ([`Planned`], printed with the effect plan), and the error it expects.
//!
//! # What a pixel's error is made of
//! A photon-mapped pixel of `s` camera samples, with prepass effort `F` (the frame's photon
//! counts, both maps, times `F`, and the irradiance cache's rays per record times `√F`), has a relative
//! mean squared error (relative to the image's mean brightness `m`, as `caustic study`, `caustic
//! diff` and `--noise-target` count it) of
//!
//! ```text
//! E²(s, F) = V_cam(F) · (4/s)^γ  +  V_map · (F₀/F)^β  +  V_c(F)  +  b² · (F₀/F)²  +  b_c²
//! ```
//!
//! - `V_cam(F) (4/s)^γ`: the camera pass's Monte Carlo noise (pixel position, shadow rays,
//!   gather and glossy rays, Russian roulette): `V_cam` is the variance of a pixel of 4
//!   stratified samples, falling as `s^-γ`, `γ` = 1 for independent samples and up to 2 where
//!   stratification removes a smooth signal's variation across the pixel. (A pixel's *sample*
//!   variance is no measure of it: on the final scene the textures, the ripples and the light's
//!   edge vary 26 times more across a pixel than the pixel's mean does between renders.) It
//!   is `V + K/F`: samples that read coarse maps vary more.
//! - `V_map (F₀/F)^β`: the noise of what the prepass made (the photon maps' density estimates
//!   and the cache's records), the same for every sample of a pixel, so no `s` removes it. A
//!   `k`-nearest estimate's noise falls with photons only once its radius is below a pixel's
//!   footprint (its neighbours then are independent estimates), so `β` lies between 0 and 1
//!   and is measured (clamped to [0.2, 1]), not assumed: 0.37 for the caustic of `glass_in_water` in
//!   `docs/accuracy.md`, near 1 for the diffuse box's global map.
//! - `V_c(F)`: the noise the caustic map's estimates at the eye paths' points make, measured
//!   at four efforts and joined as powers of the effort ([`CausticNoise`]): on the final scene
//!   it falls as effort^-0.9 between a thirty-second and an eighth of the photons and as
//!   effort^-0.36 from an eighth to one, a turn that two efforts cannot see. `V_map` and `β`
//!   are the rest: the cache's records and what they read.
//! - `b (F₀/F)`: the density estimates' blur, the bias that the seed-pair column of
//!   `docs/accuracy.md` shows: proportional to the squared radius, so to `1/F`.
//! - `b_c`: the irradiance cache's interpolation bias, which its accuracy (the records'
//!   spacing) sets, not the effort: the undershoot in a box's concave corners, the largest part
//!   of caustic's converged difference from Mitsuba on the boxes at long budgets.
//!
//! Time is `T(s, F) = c_p·F + c_r·R(F)·G(F) + s·N·τ`: photons (tracing, kd-trees, and the
//! precomputation points' estimates while there are few enough to make them up front) in
//! proportion to the effort, the cache in proportion to its rays per record `R(F)` and to
//! `G(F)`, the growth of a gather ray's cost once the points are estimated as gather rays read
//! them ([`lazy_growth`]), and `N` pixels of `s` samples at `τ` wall seconds a sample. The plan
//! line says the prepass's seconds as expected and as taken.
//!
//! # The pilot
//! Four prepasses of independent seeds, two at `F₀` and two at `4F₀`, each the real chain
//! (maps, precomputation, cache) and timed, except that each cache is made only near the
//! pilot's pixels ([`Probes::Near`]: the lattice points of each level within one stride of
//! them). A cache over the whole image took 70% of the pilot at 1024² on the final scene (four
//! caches of the whole image for 1296 pixels' samples); the records near a pixel are made as
//! a whole build would make them, from the same coarser levels nearby, and the whole build's
//! time is extrapolated from the records each level's probes made
//! ([`super::irradiance_cache::CacheStats::whole_seconds`]). A render that takes a pilot's
//! prepass makes its cache afresh over the whole image. `F₀` is [`PILOT_EFFORT`] for a target error; for a
//! time budget, the effort at which the four take about [`PILOT_SHARE`] of it (at most
//! [`MAX_PILOT_EFFORT`]), so that a long budget measures the maps nearer the efforts it
//! chooses from (the maps' noise on the final scene falls as effort^-1.1 between 1/32 and 1/8
//! of the frame's, as effort^-0.4 from 1/8 to 1). Then up to [`PILOT_GRID`]² pixels spread
//! over the window take four independent stratified sets of [`PILOT_SETS`] samples, every
//! sample traced through all four prepasses with the same random numbers (common random
//! numbers: the four values of a sample differ only by their prepass). Per pixel, running
//! means and variances of the first prepass's value and of three differences give, after
//! subtracting what the samples' own noise adds to each squared mean difference:
//! - `V_cam` at `F₀` and `4F₀` and `γ`: the replicate sets' squared differences (a 2- and a
//!   4-sample pixel's variance);
//! - `V_map` at `F₀` and at `4F₀`: half the squared difference of each pair, less `V_c` there
//!   (so `β`);
//! - `V_c` at `F₀`, at `4F₀` and at about `17F₀` and `33F₀`: the same, of the caustic map's
//!   estimates alone traced through each pair ([`DiffuseTerm::Caustic`], no shadow rays), the
//!   larger pair read also with a quarter and a sixteenth of `k` (at least
//!   [`THINNED_LEAST`]): an estimate from `k' = k·F/F'` photons has the radius `k` photons have
//!   at `F'`, so its pixels' noise, counted `k'/k` times, is `F'`'s. A pair whose mean is
//!   lost in its noise (fewer than two standard errors: a caustic few pilot pixels see)
//!   gives no point;
//! - the bias change between `F₀` and `4F₀`: the squared difference of the two pairs' means,
//!   less their noise (so `b`, as `b(F₀) − b(4F₀) = 3b/4`);
//! - `b_c²`: each sample of the first set traced again through the first pair with the
//!   cache's interpolation error taken out where it serves ([`DiffuseTerm::Unbiased`]: a
//!   record chosen by its weight, moved to the point, less a gather at the point with the
//!   record's own random numbers, so that the difference holds the light's change between the
//!   two points and little noise); per pixel the product of the two prepasses' mean
//!   differences, whose noises are independent, so that only the bias both share is left.
//!   A difference against a fresh gather of independent rays was tried first: its noise
//!   buried the bias, and on the showcase a gather's glimpse of the caustic made it twice
//!   the whole error (`docs/accuracy/budget.md`).
//!
//! and the larger pair's phase times and the samples' time give `c_p`, `c_r` and `τ`. `β` is
//! clamped to [0.2, 1] (1 where the pilot's difference is lost in its noise). A mean of the
//! measured pixels is the image's `m`. Once the chosen prepass is made, the same pixels traced
//! through it alone measure `V_cam` and `τ` at the chosen effort, and the samples are fitted to
//! them ([`fit_samples`]): for a budget, to the time actually left.
//!
//! What the pilot cannot see: error that no two seeds differ by besides the cache's (an
//! estimator's systematic difference from the truth at a fixed `k`, or a difference between
//! caustic and the reference it is measured against), and pixels too rare for its grid (a
//! light's edge, a firefly path): both make the measured error larger than the expected one.
//! `docs/accuracy/budget.md` has the figures.
//!
//! # A budget too short for a pilot
//! The pilot's first prepass is timed before the rest is made. When only its caustic traces
//! would take it above [`PILOT_MOST`] of the time left, it goes without them (`V_c` is then
//! part of `V_map`, as before they were measured). When the rest would take more
//! than [`PILOT_MOST`] of the time left, no plan it finds can win back what it costs: on the
//! final scene at 256² with 2.5 s, a pilot of 1.2 s left a plan of 0.102 where the defaults,
//! their samples fitted to the time, made 0.087. The planner then makes the frame's own
//! prepass, scaled down to fit ([`quick`]), and fits the samples to the time left as after a
//! pilot; the first prepass, of an independent seed at a thirty-second of the effort, gives the
//! maps' part of the expected error by one difference ([`fit_samples`]), with how it falls
//! with effort assumed, not measured, and the plan says so.
//!
//! # The choice
//! With a time budget, over 97 efforts from `F₀/4` to 64 (log-spaced) the planner takes the most
//! samples the time left after the pilot and that prepass allows and keeps the pair of least
//! expected error; with a target error, for each effort the fewest samples that reach it and
//! keeps the pair of least time. `--spp`, `--photons`/`--caustic-photons`/`--photon-scale` and
//! `--cache-rays` typed by the user stay as typed: the choice runs over the others. Efforts
//! are bounded by the photon cap per light and by the memory budget (the extra photons are
//! charged to the scene's account before they are traced).
//!
//! What the planner leaves alone: shadow rays per light (`--light-samples`) and gather rays
//! for points the cache does not serve are re-drawn by every camera sample, so more samples buy
//! the same; `k` changes the estimators' bias in ways the pilot's two effort levels cannot
//! see, and the cache's accuracy (its record spacing) is measured at one value only: its bias
//! counts in the expected error, but choosing it would take the bias at another spacing.
//! `--noise-target` cannot be typed with a budget: the planner sets its own (below).
//!
//! # Adaptive pixels
//! Once the samples are fitted, the planner asks whether the same camera time spent in
//! adaptive rounds ([`crate::render::Sampling::Noise`]: a first round, then rounds doubling a
//! pixel's samples while its standard error is above a target) would leave less error, and
//! for a target error whether fewer samples would reach it; if so the frame is rendered that
//! way ([`fit_adaptive`]). A target error's plan always ends in rounds, to at most the
//! camera's share of the target ([`target_rounds`]): the pilot's pixels miss rare fireflies.
//! The prediction runs the rounds' own test on each pilot pixel, with the variance of a
//! sample from four of its samples, and counts what each pixel then gains with its 4-sample
//! variance from eight others: a pixel's samples vary wherever a texture or an edge crosses
//! it, which stratification removes, so the test's variance is no measure of the gain, and the
//! two come from independent samples so that a pixel picked by luck is not also credited by
//! luck. On the final scene at 1024² the frame's noise is in 0.1–0.4% of the
//! pixels (the caustic under the glass ball, the glass's rim, the water's bright creases):
//! with the defaults' time, rounds took the relative RMSE from the uniform plan's 0.086 to
//! 0.075, below the defaults' 0.084 (`docs/accuracy/budget.md`).
//!
//! A time budget makes the image depend on the machine's speed, as the progressive
//! integrator's does; a target error does too, through the timed pilot's choice between two
//! equally accurate plans, though far less.

use super::eye::{DiffuseTerm, Tracer};
use super::irradiance_cache::Probes;
use super::photon_map::{GiSettings, Prepass};
use super::{Settings, View};
use crate::photon::trace::{MAX_PHOTONS, MapKind};
use crate::progress::{NoProgress, Progress};
use crate::render::noise::{self, Halves};
use crate::render::{Share, WEAK_SHARERS};
use crate::sampling::{Pass, Rng, stratified_2d};
use crate::stats::RayCounts;
use glam::Vec3A;
use std::fmt;
use std::time::{Duration, Instant};

/// What the user asks the planner for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Goal {
    /// The least error in this much wall time from the planner's start (`--time-budget`).
    Time(Duration),
    /// The least time to this relative RMSE (`--target-error`).
    Error(f64),
}

/// A planned render's request: the goal and which of the planner's choices the user fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    pub goal: Goal,
    /// `--spp` was typed: the samples per pixel stay.
    pub fixed_spp: bool,
    /// A photon count or `--photon-scale` was typed: the photon counts stay.
    pub fixed_photons: bool,
    /// `--cache-rays` was typed: the cache's rays per record stay.
    pub fixed_cache_rays: bool,
}

/// The pilot's prepass effort, relative to the frame's own counts (see the module doc).
pub const PILOT_EFFORT: f64 = 1.0 / 32.0;
/// The second pair of pilot prepasses runs at this multiple of the first pair's effort.
pub const PILOT_STEP: f64 = 4.0;
/// The share of a time budget the pilot's prepasses aim to take, and the largest effort of its
/// first pair ([`pilot_effort`]).
pub const PILOT_SHARE: f64 = 0.15;
/// The first pair's largest effort: its larger pair then measures the maps at up to 16 times
/// the frame's photons. It was 0.25 (1 for the larger pair), and long budgets chose 9 to 64
/// times the frame's photons from maps measured at most at 1: on the showcase the pilot's
/// caustic lookups found 1.3 to 2 photons (their radius at its cap, so their noise falling as
/// `1/F`), while at the x40 the plan chose they found 22 on average, the caustic's at `k`
/// where the noise no longer falls, and the expected error came out half the measured. The
/// four prepasses are held at once (`2 + 2·PILOT_STEP` times `F₀`'s photons), so `F₀` is also
/// bounded by what the photon cap and the memory budget allow an effort ([`max_effort`]).
pub const MAX_PILOT_EFFORT: f64 = 4.0;
/// The pilot measures at most this many pixels across and down the window.
pub const PILOT_GRID: u32 = 36;
/// Largest side of the grid of pixels [`fit_samples`] traces through the chosen prepass. The
/// camera's noise is heavy-tailed: on the final scene at 1024², 0.1% of the pixels (the glass
/// ball's focus on the floor, where a pixel's samples straddle a caustic's sharp edge) carry
/// 80% of its variance, and the pilot's 1296 pixels meet one of them about once, so they put
/// the camera's part at a third of what it is. Its samples need one tracer, not four: up to
/// 96² pixels cost a quarter of a sample of every pixel at most ([`FIT_SHARE`]).
const FIT_GRID: u32 = 96;
/// The most pixels [`fit_samples`] traces, as a share of the window's (its 12 samples a pixel
/// are then a quarter of a sample of every pixel).
const FIT_SHARE: f64 = 1.0 / 48.0;
/// A pilot pixel's samples: four independent stratified sets of these sizes, so that each
/// size has two replicates (see [`PixelRun`]).
pub const PILOT_SETS: [u32; 4] = [2, 2, 4, 4];
/// Efforts the planner considers, relative to the frame's own counts.
const MIN_EFFORT: f64 = PILOT_EFFORT / 4.0;
const MAX_EFFORT: f64 = 64.0;
/// Fewest rays per cache record an effort makes.
const MIN_CACHE_RAYS: u32 = 4;
/// Most samples per pixel the planner chooses (`--spp`'s bound).
const MAX_SPP: u32 = 1 << 16;
/// The share of a time budget kept back for what the model does not count (writing the
/// image, the last rows' imbalance).
const RESERVE: f64 = 0.04;
/// The largest share of the time left after the pilot a planned prepass may take.
const PREPASS_SHARE: f64 = 0.6;
/// A plan is judged by the samples it would leave if its prepass took this many times the
/// model's prediction: on the final scene at 1024² the pilot's extrapolation of the photons'
/// seconds per unit effort varied from 5.5 to 7.1 between runs, and a plan that counts on the
/// short end is left with a sample a pixel and twice the error it expected (0.102 against
/// 0.072). A prepass that does take its predicted time leaves the surplus to the camera,
/// whose samples are fitted to the time actually left ([`fit_samples`]).
const PREPASS_MARGIN: f64 = 1.3;
/// Bytes a stored photon takes ([`crate::frame`]'s charge).
const PHOTON_BYTES: f64 = 48.0;

/// What the pilot measured: the model of the module doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    /// The image's mean brightness over the pilot's pixels.
    pub mean: f64,
    /// `V_cam`: the relative variance of a pixel of 4 stratified samples, the part that stays
    /// at any effort and the part that falls as `1/F` (samples reading sparse maps: a gather
    /// ray's or a caustic lookup's value varies more when the maps are coarse).
    pub camera_var: f64,
    pub camera_sparse: f64,
    /// `γ`: a pixel's variance falls as `spp^-γ` (1 for independent samples; up to 2 where
    /// stratification removes the variation of a smooth signal across the pixel).
    pub gamma: f64,
    /// `V_map` at the pilot's effort, and `β`: the maps' noise besides the caustic map's
    /// estimates at the eye paths' points (the cache's records and what they read).
    pub map_var: f64,
    pub beta: f64,
    /// The caustic map's estimates' part of `V_map`, at the efforts the pilot saw it.
    pub caustic: CausticNoise,
    /// `b²` at the pilot's effort.
    pub bias2: f64,
    /// `b_c²`: the irradiance cache's interpolation bias, the same at every effort and sample
    /// count (its accuracy, not its rays, sets the records' spacing).
    pub cache_bias2: f64,
    /// The pilot's effort `F₀`.
    pub pilot_effort: f64,
    /// Prepass seconds per unit of effort spent on photons (tracing, kd-trees, precomputed
    /// points; zero when the photons are fixed) and their fixed seconds otherwise.
    pub photon_per_effort: f64,
    pub photon_fixed: f64,
    /// Seconds per unit of effort the precomputation points' estimates took up front in the
    /// pilot (zero when its points outnumbered the pixels and were estimated as gather rays
    /// read them): an effort whose points outnumber `lazy_from` estimates none up front, and
    /// pays for them in the cache instead ([`lazy_growth`]).
    pub upfront_per_effort: f64,
    /// The irradiance cache's seconds per ray of a record (times its records), and its rays
    /// per record at effort 1 (`fixed_rays`: they do not move).
    pub cache_per_ray: f64,
    pub cache_rays: u32,
    pub fixed_rays: bool,
    /// The precomputation points at effort 1 (zero when the photons are fixed), and the count
    /// from which more points make a gather ray cost more ([`lazy_growth`]): the larger of the
    /// points `cache_per_ray` was measured with and the image's pixels.
    pub points_per_effort: f64,
    pub lazy_from: f64,
    /// Wall seconds of one sample of every pixel of the window.
    pub per_spp: f64,
}

impl Model {
    /// Returns the expected relative error's three parts `(camera, maps, bias)` squared at `s`
    /// samples and effort `f`; the bias is the maps' blur and the cache's interpolation.
    pub fn parts2(&self, s: u32, f: f64) -> (f64, f64, f64) {
        let r = self.pilot_effort / f;
        (
            self.camera_var_at(f) * (4.0 / s as f64).powf(self.gamma),
            self.map_var * r.powf(self.beta) + self.caustic.at(f),
            self.bias2 * r * r + self.cache_bias2,
        )
    }

    /// Returns a 4-sample pixel's relative variance at effort `f`.
    pub fn camera_var_at(&self, f: f64) -> f64 {
        self.camera_var + self.camera_sparse / f
    }

    /// Returns the samples per pixel (at least 1, unbounded) that bring the camera's part at
    /// effort `f` down to `room`.
    pub fn samples_for(&self, f: f64, room: f64) -> f64 {
        (4.0 * (self.camera_var_at(f) / room).powf(1.0 / self.gamma))
            .ceil()
            .max(1.0)
    }

    /// Returns the most samples per pixel (at most [`MAX_SPP`]) a camera pass of `seconds`
    /// takes, or `None` for less than one.
    pub fn samples_in(&self, seconds: f64) -> Option<u32> {
        let most = (seconds / self.per_spp.max(1e-12)).floor();
        (most >= 1.0).then(|| most.min(MAX_SPP as f64) as u32)
    }

    /// Returns the fewest samples per pixel (unbounded) that bring the error at effort `f`
    /// to `target`, or `None` where the maps' parts alone exceed it.
    pub fn samples_to(&self, f: f64, target: f64) -> Option<f64> {
        let (_, m, b) = self.parts2(1, f);
        let room = target * target - m - b;
        (room > 0.0).then(|| self.samples_for(f, room))
    }

    /// Returns the expected relative RMSE at `s` samples and effort `f`.
    pub fn error(&self, s: u32, f: f64) -> f64 {
        let (c, m, b) = self.parts2(s, f);
        (c + m + b).sqrt()
    }

    /// Returns the prepass's expected wall seconds at effort `f`.
    pub fn prepass_time(&self, f: f64) -> f64 {
        let upfront = match self.points_per_effort * f <= self.lazy_from {
            true => self.upfront_per_effort * f,
            false => 0.0,
        };
        self.photon_fixed + self.photon_per_effort * f + upfront + self.cache_time(f)
    }

    /// Returns the irradiance cache's expected wall seconds at effort `f` (the part of the
    /// prepass a pilot's own prepass still takes: its cache covered only the pilot's pixels).
    pub fn cache_time(&self, f: f64) -> f64 {
        let growth = lazy_growth(self.points_per_effort * f, self.lazy_from);
        self.cache_per_ray * cache_rays(self.cache_rays, f, self.fixed_rays) as f64 * growth
    }

    /// Returns the expected wall seconds of prepass and camera pass at `s` and `f`.
    pub fn time(&self, s: u32, f: f64) -> f64 {
        self.prepass_time(f) + s as f64 * self.per_spp
    }
}

impl fmt::Display for CausticNoise {
    /// Writes the measured points (nothing without any): `, and the caustic estimates' 7.2e-3
    /// at x0.031, 2.0e-3 at x0.125`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (effort, var)) in self.points[..self.len].iter().enumerate() {
            let lead = if i == 0 {
                ", and the caustic estimates'"
            } else {
                ","
            };
            write!(f, "{lead} {var:.2e} at x{effort:.3}")?;
        }
        Ok(())
    }
}

/// The pilot's pairs of caustic estimates alone ([`DiffuseTerm::Caustic`]): the first prepass
/// of each pair (with the next), and how many times fewer photons than `k` each estimate takes
/// (`k/t`, at least [`THINNED_LEAST`]): the two pairs at their own `k`, and the larger pair
/// thinned to see larger efforts ([`CausticNoise`]).
const PILOT_CAUSTICS: [(usize, f64); 4] = [(0, 1.0), (2, 1.0), (2, 4.0), (2, 16.0)];

/// The fewest photons a thinned caustic estimate of the pilot takes: fewer make an estimate
/// whose noise no longer scales as its count's.
const THINNED_LEAST: usize = 6;

/// Returns the photons a caustic estimate of the pilot takes, `k/t` (at least
/// [`THINNED_LEAST`], at most `k`).
fn thinned(k: usize, t: f64) -> usize {
    ((k as f64 / t).round() as usize).clamp(THINNED_LEAST.min(k), k.max(1))
}

/// The caustic map's estimates' noise in a pixel (relative variance), measured by the pilot at
/// up to four efforts, and between and past them interpolated as a power of the effort.
///
/// A `k`-nearest estimate's own noise falls as `1/F` only while its radius is capped (it
/// finds fewer than `k` photons); once it holds its `k` it stops falling, and a pixel's noise
/// then falls only as the shrinking radius lets the pixel's samples (or the refracted points
/// of one sample's path) read different photons: on the final scene as effort^-0.36 from an
/// eighth of its photons to one, where between a thirty-second and an eighth it falls as
/// effort^-0.9.
/// A pilot's two efforts cannot see that turn, but an estimate from `k' = k·F/F'` photons of a
/// map at effort `F` has the radius an estimate from `k` has at effort `F'`, so it spreads
/// over the pixel's samples as that one does, with `k/k'` times its count noise: the pilot
/// reads its larger pair with [`PILOT_CAUSTICS`]'s fewer photons and counts each pair's
/// variance `k'/k` times at effort `F'`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CausticNoise {
    /// `(effort, relative variance)` by increasing effort, the variance made non-increasing;
    /// `len` of them are measured.
    pub points: [(f64, f64); PILOT_CAUSTICS.len()],
    pub len: usize,
}

impl CausticNoise {
    /// Returns the curve through `measured` (`(effort, variance)`, any order).
    pub fn new(measured: &[(f64, f64)]) -> CausticNoise {
        let mut c = CausticNoise::default();
        let mut sorted: Vec<(f64, f64)> = measured
            .iter()
            .filter(|(f, v)| *f > 0.0 && f.is_finite() && v.is_finite())
            .copied()
            .take(c.points.len())
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut least = f64::INFINITY;
        for (i, &(f, v)) in sorted.iter().enumerate() {
            least = least.min(v.max(0.0));
            c.points[i] = (f, least);
        }
        c.len = sorted.len();
        c
    }

    /// Returns the variances of the pilot's two pairs at `k` (at `F₀` and `4F₀`, its two
    /// smallest efforts: [`caustic_curve`] makes a curve only with both), or zeros without a
    /// curve.
    fn anchors(&self) -> (f64, f64) {
        match self.len >= 2 {
            true => (self.points[0].1, self.points[1].1),
            false => (0.0, 0.0),
        }
    }

    /// Returns the variance at effort `f`: the measured points joined as powers of the
    /// effort, and before the first and past the last the nearest segment's power clamped to
    /// `[0.2, 1]` (or `1` with one point).
    pub fn at(&self, f: f64) -> f64 {
        let p = &self.points[..self.len];
        let slope = |a: (f64, f64), b: (f64, f64)| match a.1 > 0.0 && b.1 > 0.0 && b.0 > a.0 {
            true => (a.1 / b.1).ln() / (b.0 / a.0).ln(),
            false => 1.0,
        };
        let power = |(f0, v): (f64, f64), s: f64| v * (f0 / f).powf(s);
        match p {
            [] => 0.0,
            [one] => power(*one, 1.0),
            _ if f <= p[0].0 => power(p[0], slope(p[0], p[1]).clamp(0.2, 1.0)),
            _ if f >= p[p.len() - 1].0 => {
                let (a, b) = (p[p.len() - 2], p[p.len() - 1]);
                power(b, slope(a, b).clamp(0.2, 1.0))
            }
            _ => {
                let i = p.iter().position(|q| q.0 > f).unwrap_or(p.len() - 1);
                let (a, b) = (p[i - 1], p[i]);
                match b.1 > 0.0 {
                    true => power(a, slope(a, b)),
                    false => a.1 * (b.0 - f) / (b.0 - a.0),
                }
            }
        }
    }
}

/// Why the planner chose what it did: the effect plan's typed reason for the budget line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Why {
    /// The least expected error the time left after the pilot allows.
    LeastError,
    /// The least expected time to the target.
    LeastTime,
    /// The target is out of reach within the bounds: the plan of least error at the largest
    /// effort and samples considered.
    TargetOutOfReach,
    /// The pilot left too little of the budget for any plan: its own prepass (the larger
    /// pair's), and the fewest samples.
    BudgetSpent,
    /// The pilot found a black image: nothing to plan for; the frame's own settings.
    Black,
    /// The budget is too short for a pilot: the rest of it would take more than
    /// [`PILOT_MOST`] of the time left (`pilot` seconds, as predicted from the first pilot
    /// prepass). The frame's own prepass, scaled down to fit ([`quick`]), and the samples the
    /// time left takes.
    ShortBudget { pilot: f64 },
}

/// Adaptive pixels as the planner chose them: after the plan's samples a pixel takes rounds
/// that double them while its standard error over the image's mean is above `target`, up to
/// `max_spp` ([`crate::render::Sampling::Noise`]; see [`fit_adaptive`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    pub target: f32,
    pub max_spp: u32,
    /// The samples a pixel takes on average, as the pilot's pixels predict, and their time
    /// in samples of every pixel (noisy pixels are often costlier than the average).
    pub mean_spp: f64,
    pub cost: f64,
}

/// A planned prepass's photons' and cache's wall seconds, as expected and as taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrepassSeconds {
    pub expected: (f64, f64),
    pub taken: (f64, f64),
}

impl PrepassSeconds {
    /// Returns the seconds of the prepass `made` at effort `f`, against what `model` expected.
    pub fn of(model: &Model, f: f64, made: &Prepass) -> PrepassSeconds {
        let st = &made.stats;
        let photons = (st.trace_time + st.build_time + st.precompute_time).as_secs_f64();
        let cache = st.cache.as_ref().map_or(0.0, |c| c.whole_seconds());
        let expected_cache = model.cache_time(f);
        PrepassSeconds {
            expected: (model.prepass_time(f) - expected_cache, expected_cache),
            taken: (photons, cache),
        }
    }
}

/// What the planner chose for a frame, with the model it chose by; reported with the plan.
#[derive(Clone, Debug, PartialEq)]
pub struct Planned {
    pub goal: Goal,
    pub why: Why,
    /// The prepass effort chosen, relative to the frame's own counts.
    pub effort: f64,
    /// What the effort makes of the settings: photon scale and cache rays per record.
    pub photon_scale: f64,
    /// Whether the render takes the pilot's own prepass at this effort instead of making one.
    pub pilot_prepass: bool,
    pub cache_rays: u32,
    /// Samples per pixel: all of them, or with `adaptive` the first round's.
    pub spp: u32,
    /// Rounds of samples where the pixels' noise is above a target, when they are expected
    /// to lower the error more than as many samples spread over every pixel.
    pub adaptive: Option<Adaptive>,
    /// The expected relative RMSE and its parts (each the root of its squared share).
    pub expected: f64,
    pub parts: (f64, f64, f64),
    /// The expected wall seconds of the planned prepass and camera pass.
    pub expected_seconds: f64,
    /// The planned prepass's seconds, photons and cache, as the model expected them and as
    /// they were taken (the cache's extrapolated from a pilot's when the render takes its
    /// prepass); `None` until the prepass is made.
    pub prepass_seconds: Option<PrepassSeconds>,
    /// The pilot's wall seconds.
    pub pilot_seconds: f64,
    pub model: Model,
}

impl fmt::Display for Planned {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let goal = match self.goal {
            Goal::Time(t) => format!("--time-budget {:.3} s", t.as_secs_f64()),
            Goal::Error(e) => format!("--target-error {e}"),
        };
        let why = match self.why {
            Why::LeastError => "the least expected error in the time left".to_string(),
            Why::LeastTime => "the least expected time to the target".to_string(),
            Why::TargetOutOfReach => {
                "the target is out of reach; the least error considered".to_string()
            }
            Why::BudgetSpent => "the pilot left too little time; its own prepass".to_string(),
            Why::Black => "a black image; the frame's own settings".to_string(),
            Why::ShortBudget { pilot } => format!(
                "the budget is too short for a pilot (it would take {pilot:.2} s more); the \
                 frame's own prepass, scaled to fit"
            ),
        };
        let (c, m, b) = self.parts;
        let model = &self.model;
        let rounds = match self.adaptive {
            Some(a) => format!(
                " then rounds to a noise target of {} (at most {} spp; {:.2} spp a pixel \
                 expected)",
                a.target, a.max_spp, a.mean_spp
            ),
            None => String::new(),
        };
        let quick = matches!(self.why, Why::ShortBudget { .. });
        let parts = match quick {
            true => format!(
                "camera {c:.4}, maps {m:.4} from the timing prepass, their bias not measured"
            ),
            false => format!("camera {c:.4}, maps {m:.4}, bias {b:.4}"),
        };
        let (v, f0, beta) = (model.map_var, model.pilot_effort, model.beta);
        let maps = match quick {
            true => format!(" maps {v:.2e} at x{f0:.3}, falling as effort^-{beta:.2} assumed;"),
            false => format!(
                " maps {v:.2e} at x{f0:.3} falling as effort^-{beta:.2}{}, bias {:.2e}, the \
                 cache's interpolation {:.2e};",
                model.caustic, model.bias2, model.cache_bias2
            ),
        };
        let growth = match model.points_per_effort > 0.0 {
            true => format!(
                " up to {:.0} precomputation points ({:.0} at effort 1), beyond them times \
                 (points / {:.0})^{LAZY_GROWTH}",
                model.lazy_from, model.points_per_effort, model.lazy_from
            ),
            false => String::new(),
        };
        let upfront = match model.upfront_per_effort > 0.0 {
            true => format!(
                " and {:.3} s more while the points are estimated up front (up to {:.0})",
                model.upfront_per_effort, model.lazy_from
            ),
            false => String::new(),
        };
        let taken = match self.prepass_seconds {
            Some(PrepassSeconds {
                expected: (ep, ec),
                taken: (tp, tc),
            }) => format!(
                "; the prepass expected {ep:.2} s of photons and {ec:.2} s of cache, took {tp:.2} \
                 and {tc:.2} s"
            ),
            None => String::new(),
        };
        write!(
            f,
            "{goal}: {} spp{rounds}, prepass effort x{:.3} (photon scale {:.4}, {} cache rays a \
             record{}): {why}; expected relative RMSE {:.4} ({parts}; lights seen directly left \
             out) in {:.2} s after a {:.2} s {} (measured: camera variance {:.3} a 4-sample \
             pixel at effort 1 falling as spp^-{:.2};{maps} photons {:.3} s per unit effort{upfront}, \
             cache {:.2e} s per ray a record{growth}, {:.4} s a sample of every pixel){taken}",
            self.spp,
            self.effort,
            self.photon_scale,
            self.cache_rays,
            match self.pilot_prepass {
                true => "; the pilot's own",
                false => "",
            },
            self.expected,
            self.expected_seconds,
            self.pilot_seconds,
            match quick {
                true => "timing prepass",
                false => "pilot",
            },
            model.camera_var_at(1.0),
            model.gamma,
            model.photon_per_effort,
            model.cache_per_ray,
            model.per_spp,
        )
    }
}

/// How a gather ray's cost grows with the precomputation points beyond those its cost was
/// measured with: as `(points / from)^LAZY_GROWTH`, where more points than the image's pixels
/// are estimated as gather rays first read them, inside the cache's build.
///
/// Why: the pilot times the cache at `4F₀`, and plans reach 10 to 100 times that effort. With
/// the points all estimated up front (no more of them than pixels) their time is the photons'
/// and grows with the effort; beyond, a gather ray more often reads a point no ray has read
/// yet, and the cache's time grows with the photons at fixed rays. On the diffuse box at 96²
/// with 256 rays a record: 0.263, 0.417, 0.502, 0.728 and 0.994 s at 1/8, 1/2, 1, 2 and 4 times
/// its photons. The pilot's prediction, by its rays alone, was 1.7 to 3.6 times short on the
/// box, the glass in water and the showcase (`docs/accuracy/budget.md`), and a plan that
/// counted on it left the box at `--time-budget 2.5` 2 samples a pixel and 2.4 times the error
/// of the defaults. The exponent that the planned prepasses measured was 0.19 to 0.34 over
/// those scenes and budgets (9 to 75 times the pilot's points); 0.27 is their middle. The
/// final scene at 256², whose points stay below its pixels at the efforts it plans, has none.
pub const LAZY_GROWTH: f64 = 0.27;

/// Returns the factor [`LAZY_GROWTH`] puts on a gather ray's cost at `points` precomputation
/// points, measured at `from` (the larger of the pilot's points and the image's pixels): 1 up
/// to `from`.
pub fn lazy_growth(points: f64, from: f64) -> f64 {
    match from > 0.0 && points > from {
        true => (points / from).powf(LAZY_GROWTH),
        false => 1.0,
    }
}

/// Returns `photons` at prepass effort `f`: photon counts (unless `fixed_photons`) and cache
/// rays per record (unless `fixed_cache_rays`) times `f`.
pub fn at_effort(photons: &GiSettings, f: f64, request: &Request) -> GiSettings {
    let mut s = photons.clone();
    if !request.fixed_photons {
        s.photon_scale *= f;
    }
    s.cache.rays = cache_rays(photons.cache.rays, f, request.fixed_cache_rays);
    s
}

/// Returns the cache's rays per record at effort `f` from `rays` at effort 1: `rays·√f`. The
/// photons take the effort in full; the cache's share of the error is smaller (a grid over
/// `--photon-scale` at the default cache rays beat the same time spent on both alike, on
/// every scene of `docs/accuracy/budget.md`), but a pilot at a thirty-second of the photons
/// with all of the cache's rays would cost as much as the render.
fn cache_rays(rays: u32, f: f64, fixed: bool) -> u32 {
    match fixed {
        true => rays,
        false => (rays as f64 * f.sqrt())
            .round()
            .clamp(MIN_CACHE_RAYS as f64, 65_536.0) as u32,
    }
}

/// What [`choose`] returns: the plan, and the prepasses it made that the render takes.
pub struct Chosen {
    pub planned: Planned,
    /// The frame's prepass, when the planner made it (its pilot's, or a short budget's).
    pub prepass: Option<Prepass>,
    /// A short budget's timing prepass, for [`fit_samples`] to measure the maps' part with.
    pub coarse: Option<Prepass>,
}

/// Runs the pilot for the frame `view` with `settings` (its photon settings `photons`, as the
/// plan made them) and returns the plan for `request`, reporting the pilot's phases to
/// `progress`. `started` is when the budget's clock started. A budget too short for the pilot
/// gets a plan without one ([`quick`]).
pub fn choose(
    view: View,
    settings: &Settings,
    photons: &GiSettings,
    request: &Request,
    started: Instant,
    progress: &dyn Progress,
) -> Chosen {
    let (grid, _) = pilot_grid(view, PILOT_GRID);
    progress.start("planning: pilot prepasses", 4);
    let mut first = pilot_prepass(view, photons, request, &grid, 0, PILOT_EFFORT);
    progress.advance(1);
    if matches!(request.goal, Goal::Time(_)) {
        (first.pixels, first.caustic_pixels, first.per_spp) =
            pixels_seconds(view, settings, &first.prepass);
    }
    let short = quick(view, photons, request, &mut first, started, progress);
    if let Some((mut planned, prepass)) = short {
        planned.spp = given_spp(settings);
        return Chosen {
            planned,
            prepass: Some(prepass),
            coarse: Some(first.prepass),
        };
    }
    let (model, mut prepasses) = pilot(view, settings, photons, request, first, progress);
    let pilot_seconds = started.elapsed().as_secs_f64();
    let max_effort = max_effort(view, photons, request);
    let mut choice = decide(model, request, max_effort, settings, pilot_seconds);
    // Effort 1's photons were charged with the scene; a larger effort charges the rest.
    if choice.effort > 1.0 && !request.fixed_photons {
        let stored: u64 = photon_counts(view.scene, photons).iter().sum();
        let extra = (stored as f64 * (choice.effort - 1.0) * PHOTON_BYTES) as u64;
        if view
            .scene
            .account
            .try_charge(extra, "the planner's photons")
            .is_err()
        {
            choice.effort = 1.0;
        }
    }
    // The pilot's prepass made ready for the frame: its cache covered only the pilot's pixels.
    let reused = (reused_effort(&model, request) == choice.effort).then(|| {
        prepasses
            .swap_remove(2)
            .with_whole_cache(view.scene, view.camera, progress)
    });
    let mut planned = choice.with_settings(photons, request, pilot_seconds);
    planned.pilot_prepass = reused.is_some();
    Chosen {
        planned,
        prepass: reused,
        coarse: None,
    }
}

/// The most of a time budget's time left the rest of the pilot may be expected to take; a
/// budget that short gets the frame's own prepass scaled to fit instead ([`quick`]). On the
/// final scene at 256² a pilot takes 1.2 s, and with 2.5 s the defaults' 5 samples a pixel
/// (relative RMSE 0.0865) beat any plan the 1.3 s left could make (0.1018):
/// `docs/accuracy/budget.md`. It was a quarter: the showcase at 100² and the diffuse box with
/// 2.5 s, whose pilots are predicted at 26% and 27% of the time left, then skipped it by turns
/// and measured 0.038 to 0.061 (the showcase, three runs) where a pilot's plan measured 0.021
/// to 0.029 (five runs), and 0.0164 where it measured 0.0147 to 0.0158. The final scene's, at
/// 61%, is still skipped.
const PILOT_MOST: f64 = 0.35;
/// Without a pilot, the photons may take this share of the time left, and the cache this
/// share of what is left after them: the frame's own balance (at 256² on the final scene,
/// with 4 samples a pixel, the photons take 0.4 s and the cache 1.25 s of the 2.4 s).
const QUICK_PHOTONS: f64 = 0.4;
const QUICK_CACHE: f64 = 0.6;
/// The samples a pixel the camera keeps without a pilot, whatever the cache's share: below
/// 2 a pixel has no two half-buffers for adaptive rounds, and the final scene at 256² with
/// 2.5 s, whose cache took up to 18% more than its share, measured 0.200 at 1 sample a pixel
/// against 0.085 at 2 and rounds (`docs/accuracy/budget.md`). Keeping 2 left it 1 in two
/// runs of seven: what the fitting of the samples and the machine's noise take comes out of
/// the camera's time too, so it keeps 3, and the fit gets 2 where a sample's worth is lost.
const QUICK_SPP: f64 = 3.0;
/// The maps' noise is taken to fall as `effort^-QUICK_BETA` where no pilot measured it
/// ([`fit_samples`]): the value that puts the maps' variance at the geometric middle of what
/// `β` = 0.2 and `β` = 1, the ends of the pilot's range, would make of the same difference, at
/// the efforts a short budget chooses (8 to 32 times [`PILOT_EFFORT`]). Its part of the error
/// is then within a factor 1.4 of either end's at 8 times, 1.85 at 32. The final scene's noise
/// falls as effort^-1.1 from 1/32 to 1/8 of its photons and ^-0.4 from 1/8 to 1, 0.68 over
/// the whole; the glass in water's as ^-0.37 (`docs/accuracy.md`).
const QUICK_BETA: f64 = 0.63;

/// Returns the plan for a budget too short for the pilot, and its prepass made, or `None`
/// when the pilot fits. `first` is the pilot's first prepass, at [`PILOT_EFFORT`]: by its
/// phases' times the rest of the pilot (one more prepass at `F₀` = [`PILOT_EFFORT`], two at
/// `4F₀`, whose photons take 4 times as long and caches twice, with `√4` times the rays)
/// would take `9p + 5c` seconds, `p` the photons' and `c` the rest, and its pixels what
/// [`pixels_seconds`] times; a pilot above [`PILOT_MOST`] of the time left goes without its
/// caustic map's traces, and one above it without them is skipped. The plan then is the frame's own: effort 1,
/// scaled down so that the photons take at most [`QUICK_PHOTONS`] of the time left (their
/// time per unit effort extrapolated from `first` in proportion, which overestimates it:
/// part of a pass's time is fixed), and the cache's rays cut so that it takes at most
/// [`QUICK_CACHE`] of the time left after them ([`fit_samples`] then fits the samples to the
/// rest, and measures the maps' noise against `first`, which the render keeps for it). No
/// pilot measures how the maps' noise falls with effort, nor their bias: the plan says so.
fn quick(
    view: View,
    photons: &GiSettings,
    request: &Request,
    first: &mut Timed,
    started: Instant,
    progress: &dyn Progress,
) -> Option<(Planned, Prepass)> {
    let Goal::Time(budget) = request.goal else {
        return None;
    };
    let budget = budget.as_secs_f64() * (1.0 - RESERVE);
    let stats = &first.prepass.stats;
    let photon_seconds =
        (stats.trace_time + stats.build_time + stats.precompute_time).as_secs_f64();
    let rest = (first.seconds - photon_seconds).max(0.0);
    let pilot = pilot_rest(photon_seconds, rest, request.fixed_photons) + first.pixels;
    let decided = started.elapsed().as_secs_f64();
    let left = budget - decided;
    if let Some(caustics) = pilot_fits(pilot, first.caustic_pixels, left) {
        first.caustic_traces = caustics;
        return None;
    }
    let per_effort = photon_seconds / PILOT_EFFORT;
    let effort = match request.fixed_photons {
        true => 1.0,
        false => (QUICK_PHOTONS * left / per_effort.max(1e-12)).clamp(PILOT_EFFORT, 1.0),
    };
    let mut gi = at_effort(photons, effort, request);
    let prepass = Prepass::build_with(view.scene, &gi, progress).precompute_for(view.camera);
    let first_rays = first.prepass.settings.cache.rays.max(1) as f64;
    let per_ray = stats.cache.as_ref().map_or(0.0, |c| c.whole_seconds()) / first_rays;
    let first_points = stats.precomputed_points as f64;
    let (points_per_effort, lazy_from) = lazy_points(view, first_points, PILOT_EFFORT, request);
    let per_ray = per_ray * lazy_growth(points_per_effort * effort, lazy_from);
    if !request.fixed_cache_rays && per_ray > 0.0 {
        let left = budget - started.elapsed().as_secs_f64();
        let most = (quick_cache(left, first.per_spp) / per_ray)
            .floor()
            .max(MIN_CACHE_RAYS as f64);
        gi.cache.rays = gi.cache.rays.min(most as u32);
    }
    let mut prepass = prepass;
    prepass.settings.cache.rays = gi.cache.rays;
    let prepass = prepass.with_cache(view.scene, view.camera, progress);
    let model = Model {
        mean: 0.0,
        camera_var: 0.0,
        camera_sparse: 0.0,
        gamma: 1.0,
        map_var: 0.0,
        beta: 1.0,
        caustic: CausticNoise::default(),
        bias2: 0.0,
        cache_bias2: 0.0,
        pilot_effort: PILOT_EFFORT,
        // The timing prepass's photons were the frame's when they are fixed.
        photon_per_effort: match request.fixed_photons {
            true => 0.0,
            false => per_effort,
        },
        photon_fixed: match request.fixed_photons {
            true => photon_seconds,
            false => 0.0,
        },
        upfront_per_effort: 0.0,
        // The rays as cut above, at the effort chosen (the growth counted in `per_ray`).
        cache_per_ray: per_ray,
        cache_rays: gi.cache.rays,
        fixed_rays: true,
        points_per_effort: 0.0,
        lazy_from: 0.0,
        per_spp: 0.0,
    };
    let planned = Planned {
        goal: request.goal,
        why: Why::ShortBudget { pilot },
        effort,
        photon_scale: gi.photon_scale,
        pilot_prepass: false,
        cache_rays: gi.cache.rays,
        // `choose` gives the frame's; [`fit_samples`] fits them, unless `--spp` fixed them.
        spp: 1,
        adaptive: None,
        expected: 0.0,
        parts: (0.0, 0.0, 0.0),
        expected_seconds: 0.0,
        prepass_seconds: None,
        pilot_seconds: decided,
        model,
    };
    Some((planned, prepass))
}

/// Returns the seconds a plan without a pilot gives its cache when `left` seconds are left
/// after its photons and a sample of every pixel takes `per_spp`: [`QUICK_CACHE`] of them, but
/// no more than leaves the camera [`QUICK_SPP`] samples a pixel should the cache take
/// [`PREPASS_MARGIN`] times as long.
fn quick_cache(left: f64, per_spp: f64) -> f64 {
    (QUICK_CACHE * left).min((left - QUICK_SPP * per_spp) / PREPASS_MARGIN)
}

/// Returns whether a pilot of `seconds`, and `caustic` more with its caustic map's traces, is
/// taken with `left` seconds left: `Some(true)` with them, `Some(false)` without them (it then
/// measures what it did before them), `None` not at all (above [`PILOT_MOST`] of `left`).
fn pilot_fits(seconds: f64, caustic: f64, left: f64) -> Option<bool> {
    let most = PILOT_MOST * left;
    (seconds <= most).then_some(seconds + caustic <= most)
}

/// The side of the grid of pixels [`pixels_seconds`] times.
const PIXELS_PROBE: u32 = 4;

/// Returns the wall seconds the pilot's pixels are expected to take (their samples through
/// four prepasses like `prepass`) and how many more its caustic map's traces add, from
/// [`PIXELS_PROBE`]² of them traced through it once, and the wall seconds of one sample of
/// every pixel of the window they measure. Where the
/// prepasses are cheap, the pixels are most of a pilot: on a box of 40×40 pixels with a
/// thousandth of its photons, 0.15 s of a 0.02 s budget.
fn pixels_seconds(view: View, settings: &Settings, prepass: &Prepass) -> (f64, f64, f64) {
    let tracer = Tracer {
        scene: view.scene,
        camera: view.camera,
        light_samples: settings.light_samples,
        diffuse: DiffuseTerm::Photons(prepass),
    };
    let (probe, _, _) = pilot_pixels(
        view,
        settings.seed,
        &PilotTracers::only(vec![tracer]),
        PIXELS_PROBE,
        &NoProgress,
    );
    let (pilot, _) = pilot_grid(view, PILOT_GRID);
    let threads = rayon::current_num_threads().max(1) as f64;
    // The four prepasses, and the cache's bias measured through the first two: their gathers
    // cost about as much again (0.6 to 2.6 times on the scenes of docs/accuracy/budget.md).
    // The caustic estimates alone, eight more traces without shadow rays or gathers, cost
    // what two to four whole ones do (on the showcase and on the final scene).
    let (tracers, caustic) = (8.0, if prepass.caustic.is_some() { 3.0 } else { 0.0 });
    let thread_seconds: f64 = probe.iter().map(PixelRun::seconds).sum();
    let per_pixel = thread_seconds / probe.len().max(1) as f64;
    let (w, h) = view.window.size();
    let per_sample = per_pixel / PILOT_SETS.iter().sum::<u32>() as f64;
    let pixels = per_pixel * pilot.len() as f64 / threads;
    (
        pixels * tracers,
        pixels * caustic,
        per_sample * w as f64 * h as f64 / threads,
    )
}

/// Returns the seconds the rest of the pilot is expected to take after its first prepass (at
/// [`PILOT_EFFORT`], `photons` seconds of photons and `rest` of the rest, mostly its cache):
/// one more such, and two at [`PILOT_STEP`] times the effort, whose photons take `PILOT_STEP`
/// times as long (as long, when `fixed_photons`) and caches `√PILOT_STEP` times (their rays
/// per record).
fn pilot_rest(photons: f64, rest: f64, fixed_photons: bool) -> f64 {
    let step = match fixed_photons {
        true => 1.0,
        false => PILOT_STEP,
    };
    (1.0 + 2.0 * step) * photons + (1.0 + 2.0 * PILOT_STEP.sqrt()) * rest
}

/// Returns the maps' relative variance at effort `F` from `d2`, the mean squared difference of
/// pixels traced through prepasses of independent seeds at `F` and at `r·F` (see
/// [`fit_samples`]), with the noise falling as `effort^-QUICK_BETA`.
fn maps_from_difference(d2: f64, r: f64) -> f64 {
    let x = r.powf(QUICK_BETA);
    d2 * x / (1.0 + x)
}

/// Returns the effort whose prepass the pilot has made already and the render may take as its
/// own (the larger pair's first, at [`PILOT_STEP`]`·F₀`; with the photons and the cache's rays
/// both fixed every effort makes the same prepass, and the frame's own effort 1 is it).
fn reused_effort(model: &Model, request: &Request) -> f64 {
    match request.fixed_photons && request.fixed_cache_rays {
        true => 1.0,
        false => PILOT_STEP * model.pilot_effort,
    }
}

/// Measures the camera pass with the planned prepass made (`tracers[0]` reads it): traces the
/// pilot's pixels once more through it alone, for the cost of a sample and the camera's
/// variance at the chosen effort (the pilot's small prepasses measure it through coarser maps),
/// and re-chooses the samples per pixel (unless `--spp` fixed them): for a time budget the most
/// the time left since `started` allows, for a target error the fewest that reach it. The
/// prepass is made, so only the samples can still move; the plan's samples, expected error,
/// time and model are updated.
///
/// A second tracer reads a short budget's timing prepass ([`quick`], no pilot): the pixels are traced
/// through it too, with the same random numbers, for the maps' part of the error, which no
/// pilot measured. Their mean squared difference (less the samples' noise) is
/// `V(F₀) + V(F)` for prepasses of independent seeds at `F₀` ([`PILOT_EFFORT`]) and the
/// plan's `F`; with `V` falling as `F^-β`, `V(F) = D²·r^β / (1 + r^β)`, `r = F₀/F`. Without
/// a second effort `β` is not measured: it is taken as [`QUICK_BETA`]. The difference of the
/// two kernels' blur is counted with the noise.
pub fn fit_samples(
    planned: &mut Planned,
    view: View,
    seed: u64,
    tracers: &[Tracer],
    request: &Request,
    started: Instant,
) {
    if planned.why == Why::Black {
        return;
    }
    let (w, h) = view.window.size();
    let side = ((w as f64 * h as f64 * FIT_SHARE).sqrt() as u32).clamp(PILOT_GRID, FIT_GRID);
    let only = PilotTracers::only(tracers.to_vec());
    let (all, _, samples) = pilot_pixels(view, seed, &only, side, &NoProgress);
    let thread_seconds: f64 = all.iter().map(PixelRun::seconds).sum();
    let runs = lit_pixels(all.clone());
    // Thread seconds over the threads, not the wall time: the pilot's pixels take a tenth of a
    // second, over rows of unequal cost, and its wall time varied from 4.7 to 6.5 s a sample
    // of every pixel between runs on the final scene; the camera pass's rows share the threads
    // evenly.
    let threads = rayon::current_num_threads().max(1) as f64;
    let per_spp = thread_seconds / samples.max(1) as f64 * w as f64 * h as f64 / threads;
    // A pixel's samples share weak branches in groups of up to `WEAK_SHARERS`, and caustic
    // estimates within a round: a sample of a 4-sample set costs 0.66 to 0.88 of one of a
    // 2-sample set (the showcase, the final scene and the diffuse box at 10 s), and the camera
    // pass of a plan of 4 samples or more shares at least as the 4-sample sets do. Timed over
    // all the sets, the showcase at `--time-budget 30` stopped after 21.4 and 21.7 s; timed
    // so, 26.5 and 26.7 s (24.6 with the rounds charged as below). Larger rounds share caustic
    // estimates further (its 512-sample rounds took 0.6 of a 4-sample set's time a sample),
    // which this does not count.
    let shared = sharing_seconds(&all)
        .map_or(per_spp, |t| t * w as f64 * h as f64 / threads)
        .min(per_spp);
    let f = planned.effort;
    let timing = (tracers.len() == 2).then_some(request.fixed_photons);
    let (model, mean) = measured(planned.model, &runs, per_spp, f, timing);
    let (_, maps2, bias2) = model.parts2(1, f);
    // The first round's samples share as the pilot's sets of `WEAK_SHARERS` did when it has as
    // many (`shared` seconds a sample of every pixel; `per_spp` over all the sets). The rounds
    // after it are charged as samples that share little: the pilot pixels predict them short
    // where the noise is heavy-tailed (the final scene at 256² and 10 s: 28.3 samples a pixel
    // taken against 23.2 expected), and the difference is their margin.
    let credit = 1.0 - shared / per_spp.max(1e-300);
    let (spp, need) = match request.goal {
        _ if request.fixed_spp => (planned.spp, None),
        Goal::Time(budget) => {
            let left = budget.as_secs_f64() * (1.0 - RESERVE) - started.elapsed().as_secs_f64();
            let sharing = Model {
                per_spp: shared,
                ..model
            };
            let spp = match sharing.samples_in(left) {
                Some(s) if s >= WEAK_SHARERS => s,
                _ => model.samples_in(left).unwrap_or(1),
            };
            let most = left / per_spp.max(1e-12);
            (spp, Some(Need::Within(most, credit)))
        }
        Goal::Error(target) => {
            let spp = model
                .samples_to(f, target)
                .map_or(planned.spp, |s| s.min(MAX_SPP as f64) as u32);
            let room = target * target - maps2 - bias2;
            (spp, (room > 0.0).then_some(Need::Below(room)))
        }
    };
    let mut camera2 = model.parts2(spp, f).0;
    // The camera pass's time in samples that share little.
    let mut camera_samples = spp as f64 - sharing_credit(spp, credit);
    planned.spp = spp;
    planned.adaptive = None;
    if let Some(need) = need.filter(|_| mean > 0.0) {
        let pixels = PilotPixels::of(&all, mean);
        let fitted = fit_adaptive(&pixels, model.gamma, (spp, camera2), need);
        let fitted = match need {
            Need::Below(room) => Some(target_rounds(&pixels, model.gamma, (spp, room), fitted)),
            Need::Within(..) => fitted,
        };
        if let Some((first, a, c2)) = fitted {
            planned.spp = first;
            planned.adaptive = Some(a);
            camera2 = c2;
            camera_samples = a.cost - sharing_credit(first, credit);
        }
    }
    planned.expected = (camera2 + maps2 + bias2).sqrt();
    planned.parts = (camera2.sqrt(), maps2.sqrt(), bias2.sqrt());
    planned.expected_seconds =
        started.elapsed().as_secs_f64() - planned.pilot_seconds + camera_samples * per_spp;
    planned.model = model;
}

/// Returns `model` with what the pixels `runs` traced through the chosen prepass (at effort
/// `f`) measured: the camera's variance and its fall with samples, and `per_spp`; with a
/// short budget's timing prepass traced beside it (`timing`: whether the photons were typed),
/// the maps' part from their difference ([`maps_from_difference`]). Also returns the pixels'
/// mean.
fn measured(
    model: Model,
    runs: &[PixelRun],
    per_spp: f64,
    f: f64,
    timing: Option<bool>,
) -> (Model, f64) {
    let n = runs.len().max(1) as f64;
    let mean = runs.iter().map(|r| r.mean[0]).sum::<f64>() / n;
    let (v2, v4) = runs.iter().fold((0.0, 0.0), |(a, b), r| {
        let (x, y) = r.set_vars(0);
        (a + x / n, b + y / n)
    });
    let mut model = Model { per_spp, ..model };
    if mean > 0.0 {
        model.camera_var = v4 / (mean * mean);
        model.camera_sparse = 0.0;
        model.gamma = stratification(v2, v4);
        if let Some(fixed_photons) = timing {
            let d2 = (runs.iter().map(|r| r.mean2(1)).sum::<f64>() / n / (mean * mean)).max(0.0);
            let r = match fixed_photons {
                true => 1.0,
                false => (PILOT_EFFORT / f).min(1.0),
            };
            model.map_var = maps_from_difference(d2, r);
            model.pilot_effort = f;
            model.beta = QUICK_BETA;
        }
    }
    (model, mean)
}

/// Returns the samples a plan's first round of `first` saves by sharing, in samples that share
/// little: `credit` (1 less the ratio of the two kinds' times) of them, when the round is one
/// of [`WEAK_SHARERS`] samples or more.
fn sharing_credit(first: u32, credit: f64) -> f64 {
    match first >= WEAK_SHARERS {
        true => credit * first as f64,
        false => 0.0,
    }
}

/// Returns the thread seconds a sample took in the pilot pixels' sets of [`WEAK_SHARERS`]
/// samples or more, through the first tracer (`None` without such sets or time).
fn sharing_seconds(runs: &[PixelRun]) -> Option<f64> {
    let sets = || (0..PILOT_SETS.len()).filter(|&i| PILOT_SETS[i] >= WEAK_SHARERS);
    let count: u32 = sets().map(|i| PILOT_SETS[i]).sum();
    let seconds: f64 = runs
        .iter()
        .map(|r| sets().map(|i| r.set_seconds[i]).sum::<f64>())
        .sum();
    (count > 0 && seconds > 0.0).then(|| seconds / (count as f64 * runs.len() as f64))
}

/// What adaptive rounds must do: stay within this many samples a pixel on average (a time
/// budget), or bring the camera's squared relative error below this (a target error).
#[derive(Clone, Copy, Debug)]
enum Need {
    /// At most this many samples a pixel on average, timed as samples that share little;
    /// plus, for a first round of [`WEAK_SHARERS`] samples or more, this share of the first
    /// round (what its samples save by sharing, as [`fit_samples`] times them).
    Within(f64, f64),
    Below(f64),
}

/// The most samples a planned adaptive pixel may take, as a multiple of the uniform plan's
/// (at least 4): it bounds what a pixel the pilot's grid missed can cost. At 16, if 0.1% of
/// the pixels (the final scene's caustic under the glass and the glass's rim,
/// `docs/accuracy/adaptive.md`) all reach it, they add 1.6% to the camera pass.
const ADAPTIVE_CAP: u32 = 16;

/// Returns the most samples a planned adaptive pixel may take when the uniform plan has `spp`:
/// [`ADAPTIVE_CAP`] times them (at least 4), within [`noise::MAX_SPP`].
fn most_spp(spp: u32) -> u32 {
    (ADAPTIVE_CAP * spp.max(4)).min(noise::MAX_SPP)
}

/// The pilot's pixels as adaptive rounds see them: each one's variance of a single sample as
/// the rounds' test measures it (over its channels, from 4 samples), and, for the pixels the
/// error is counted over (no light seen directly), its 4-sample pixel's variance relative to
/// the squared image mean (from 8 other samples, so that which pixels take more samples and
/// what they would gain are independent estimates).
struct PilotPixels {
    pixels: Vec<(f64, Option<f64>)>,
    /// Each pixel's seconds a sample, relative to the mean over the pixels: the noisy pixels
    /// are often the costly ones (on the diffuse box, the corners the irradiance cache leaves
    /// to fresh gathers: rounds there cost twice a uniform sample's time).
    cost: Vec<f64>,
    /// The image's mean over all the pilot's pixels, lights included, as the rounds' test
    /// divides by ([`crate::render::noise::pilot_mean`]).
    test_mean: f64,
    /// The mean the relative errors are counted against (the pixels that see no light).
    mean: f64,
}

impl PilotPixels {
    fn of(all: &[PixelRun], mean: f64) -> PilotPixels {
        let n = all.len().max(1) as f64;
        let m2 = mean * mean;
        let per_sample: Vec<f64> = all
            .iter()
            .map(|r| r.seconds() / r.n.max(1) as f64)
            .collect();
        let average = per_sample.iter().sum::<f64>() / n;
        PilotPixels {
            cost: per_sample
                .iter()
                .map(|&t| match average > 0.0 {
                    true => t / average,
                    false => 1.0,
                })
                .collect(),
            pixels: all
                .iter()
                .map(|r| {
                    let e = r.noise.sample_error().unwrap_or(0.0) as f64;
                    let var = e * e * r.noise.n as f64;
                    (var, (!r.light).then(|| r.set_vars(0).1 / m2))
                })
                .collect(),
            test_mean: all.iter().map(|r| r.mean[0]).sum::<f64>() / n,
            mean,
        }
    }

    /// Returns the samples a pixel of single-sample variance `var` ends with: `first`, doubled
    /// while its standard error is above `limit`, at most `max` (as
    /// [`crate::render::Sampling::Noise`] samples it).
    fn rounds(var: f64, first: u32, max: u32, limit: f64) -> u32 {
        let mut n = first;
        while n < max && var / n as f64 > limit * limit {
            n = (2 * n).min(max);
        }
        n
    }

    /// Returns what rounds from `first` samples to `target`, at most `max`, are expected to
    /// make, with a pixel's variance falling as `spp^-gamma`: the mean samples a pixel, their
    /// cost in uniform samples a pixel (each pixel's samples weighed by its cost), and the
    /// camera's squared relative error.
    fn predict(&self, first: u32, max: u32, target: f64, gamma: f64) -> (f64, f64, f64) {
        let limit = target * self.test_mean;
        let (mut samples, mut cost, mut error2, mut counted) = (0.0, 0.0, 0.0, 0.0f64);
        for (&(var, v4), &c) in self.pixels.iter().zip(&self.cost) {
            let n = Self::rounds(var, first, max, limit) as f64;
            samples += n;
            cost += n * c;
            if let Some(v4) = v4 {
                error2 += v4 * (4.0 / n).powf(gamma);
                counted += 1.0;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        (samples / n, cost / n, error2 / counted.max(1.0))
    }
}

/// Returns adaptive rounds (the first round's samples, the rounds, and the camera's expected
/// squared relative error) that do better than the uniform plan of `spp` samples and camera
/// error `uniform2`: a lower error within the same samples on average, or fewer samples to the
/// same error; `None` when no candidate does.
///
/// The candidates: first rounds of 2, 4, 8, … samples up to the uniform plan's (a time budget
/// may leave room for a fraction of a sample more than it), and 97 noise targets log-spaced
/// over [10⁻⁴, 10] of the image's mean, rounds up to [`ADAPTIVE_CAP`] times the uniform plan's
/// samples. Each is predicted on
/// the pilot's pixels ([`PilotPixels::predict`]). Adaptive pixels spend samples where a pixel's
/// samples vary, which is not only where its mean does (a texture or an edge across a pixel
/// varies too, and stratification removes most of that): the per-pixel variances of the
/// prediction's error come from replicate pixels, so such a plan is not expected to gain.
fn fit_adaptive(
    pixels: &PilotPixels,
    gamma: f64,
    (spp, uniform2): (u32, f64),
    need: Need,
) -> Option<(u32, Adaptive, f64)> {
    let max = most_spp(spp);
    let firsts = (1..16).map(|k| 1u32 << k).take_while(|&s| s <= spp.max(2));
    let mut best: Option<(f64, u32, Adaptive, f64)> = None;
    for first in firsts {
        for i in 0..97 {
            let target = 10f64.powf(-4.0 + 5.0 * i as f64 / 96.0);
            let (mean_spp, cost, error2) = pixels.predict(first, max, target, gamma);
            let score = match need {
                Need::Within(most, credit)
                    if cost <= most + sharing_credit(first, credit) && error2 < uniform2 =>
                {
                    error2
                }
                Need::Below(room) if error2 <= room && cost < spp as f64 => cost,
                _ => continue,
            };
            if best.as_ref().is_none_or(|b| score < b.0) {
                let a = Adaptive {
                    target: target as f32,
                    max_spp: max,
                    mean_spp,
                    cost,
                };
                best = Some((score, first, a, error2));
            }
        }
    }
    best.map(|(_, first, a, error2)| (first, a, error2))
}

/// Returns the rounds a target error's plan takes: `fitted` ([`fit_adaptive`]'s plan, if any)
/// when its noise target is at most the camera's share of the target, else a first round of
/// its samples (or the uniform plan's `spp`; at least 2, so that each pixel has two
/// half-buffers) with rounds to that share, up to [`most_spp`] (as [`fit_adaptive`]'s).
/// The share is `√room` (`room`: the squared relative error the maps and their bias leave)
/// over the image's mean, in the rounds' test's units (it divides by the mean with the lights,
/// [`PilotPixels::test_mean`]). Where every pixel's standard error ends below it, so does the
/// image's camera part; where the pilot's pixels already were, the rounds cost nothing.
///
/// Why: the pilot's pixels (up to 36 × 36) miss what is rare, and neither a uniform plan nor
/// rounds to a looser target (which [`fit_adaptive`] takes when it costs no more on them) see
/// it afterwards. On the final scene at 1024², `--target-error 0.08` planned 1 or 2 uniform
/// samples on two seeds of three and measured 0.103 and 0.106 against the long references;
/// the renders' own half-buffers said 0.112 (fireflies under the glass ball and on the water's
/// creases). `docs/accuracy/budget.md` has the figures after.
fn target_rounds(
    pixels: &PilotPixels,
    gamma: f64,
    (spp, room): (u32, f64),
    fitted: Option<(u32, Adaptive, f64)>,
) -> (u32, Adaptive, f64) {
    let mean = pixels.mean.max(1e-300);
    let share = room.max(0.0).sqrt() * mean / pixels.test_mean.max(mean);
    if let Some(plan) = fitted.filter(|p| f64::from(p.1.target) <= share) {
        return plan;
    }
    let first = fitted.map_or(spp, |p| p.0).max(2);
    let max_spp = most_spp(spp);
    let (mean_spp, cost, error2) = pixels.predict(first, max_spp, share, gamma);
    let rounds = Adaptive {
        target: share as f32,
        max_spp,
        mean_spp,
        cost,
    };
    (first, rounds, error2)
}

/// The choice before it is turned into settings.
struct Choice {
    why: Why,
    effort: f64,
    spp: u32,
    model: Model,
    goal: Goal,
}

impl Choice {
    fn with_settings(self, photons: &GiSettings, request: &Request, pilot: f64) -> Planned {
        let gi = at_effort(photons, self.effort, request);
        let (c, m, b) = self.model.parts2(self.spp, self.effort);
        Planned {
            goal: self.goal,
            why: self.why,
            effort: self.effort,
            photon_scale: gi.photon_scale,
            pilot_prepass: false,
            cache_rays: gi.cache.rays,
            spp: self.spp,
            adaptive: None,
            expected: (c + m + b).sqrt(),
            parts: (c.sqrt(), m.sqrt(), b.sqrt()),
            expected_seconds: self.model.time(self.spp, self.effort),
            prepass_seconds: None,
            pilot_seconds: pilot,
            model: self.model,
        }
    }
}

/// Returns the largest effort the photon cap per light and the memory budget allow (1 when the
/// photons are fixed: the effort then moves only the cache's rays).
fn max_effort(view: View, photons: &GiSettings, request: &Request) -> f64 {
    if request.fixed_photons {
        return MAX_EFFORT;
    }
    let counts = photon_counts(view.scene, photons);
    let largest = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let total = counts.iter().sum::<u64>().max(1) as f64;
    let budget = view.scene.account.budget();
    let free = budget.limit().saturating_sub(budget.used()) as f64;
    // Effort 1's photons are charged already; the extra is what a larger effort needs.
    let by_memory = 1.0 + free / (total * PHOTON_BYTES);
    // A light's count is rounded after the effort scales it: keep half a photon in hand.
    ((MAX_PHOTONS as f64 - 1.0) / (largest + 0.5))
        .min(by_memory)
        .clamp(MIN_EFFORT, MAX_EFFORT)
}

/// Returns each light's photon count at effort 1 for each map the frame traces: the global
/// map's, and the caustic map's only when the plan traces one (as the scene's account was
/// charged, [`crate::frame::charge_photons`]).
fn photon_counts(scene: &crate::scene::Scene, photons: &GiSettings) -> Vec<u64> {
    let kinds: &[MapKind] = match photons.caustics {
        true => &[MapKind::Global, MapKind::Caustic],
        false => &[MapKind::Global],
    };
    kinds
        .iter()
        .flat_map(|&kind| photons.budget(&scene.lights, kind))
        .collect()
}

/// Returns the efforts considered up to `max`: 97 log-spaced from [`MIN_EFFORT`] to
/// [`MAX_EFFORT`], or the frame's own (1) when neither photons nor cache rays may move.
fn efforts(request: &Request, max: f64) -> Vec<f64> {
    if request.fixed_photons && request.fixed_cache_rays {
        return vec![1.0];
    }
    let (lo, hi) = (MIN_EFFORT.ln(), MAX_EFFORT.ln());
    (0..97)
        .map(|i| (lo + (hi - lo) * i as f64 / 96.0).exp())
        .filter(|&f| f <= max)
        .collect()
}

/// Returns the samples per pixel `settings` give (`--spp`, or the default).
fn given_spp(settings: &Settings) -> u32 {
    match settings.sampling {
        crate::render::Sampling::Stratified { spp } => spp,
        _ => super::DEFAULT_SPP,
    }
}

/// Chooses effort and samples for `request` by `model` (see the module doc).
fn decide(
    model: Model,
    request: &Request,
    max: f64,
    settings: &Settings,
    pilot_seconds: f64,
) -> Choice {
    let given_spp = given_spp(settings);
    let choice = |why, effort, spp| Choice {
        why,
        effort,
        spp,
        model,
        goal: request.goal,
    };
    if model.mean <= 0.0 {
        return choice(Why::Black, 1.0, given_spp);
    }
    let efforts = efforts(request, max);
    // An effort at or below the prepass the pilot made already is that prepass, for the time
    // of its cache over the whole image.
    let reused = Some(reused_effort(&model, request)).filter(|&r| r <= max);
    let made = |f: f64| match reused {
        Some(r) if f <= r => (r, model.cache_time(r)),
        _ => (f, model.prepass_time(f)),
    };
    let fixed_spp = request.fixed_spp.then_some(given_spp);
    // The first plan of least score over the efforts, each with the samples it takes.
    let best =
        |plans: &mut dyn Iterator<Item = (f64, f64, u32)>| plans.min_by(|a, b| a.0.total_cmp(&b.0));
    match request.goal {
        Goal::Time(budget) => {
            let left = budget.as_secs_f64() * (1.0 - RESERVE) - pilot_seconds;
            let mut plans = efforts.iter().filter_map(|&f| {
                let (f, prepass) = made(f);
                // At least 40% of the time left goes to the camera: the prepass's time is
                // extrapolated from the pilot's small efforts and errs on the short side.
                if prepass > PREPASS_SHARE * left {
                    return None;
                }
                let most = model.samples_in(left - PREPASS_MARGIN * prepass)?;
                let s = match fixed_spp {
                    Some(s) => (s <= most).then_some(s)?,
                    None => most,
                };
                Some((model.error(s, f), f, s))
            });
            match best(&mut plans) {
                Some((_, f, s)) => choice(Why::LeastError, f, s),
                None => {
                    let f = reused.unwrap_or(efforts[0]);
                    choice(Why::BudgetSpent, f, fixed_spp.unwrap_or(1))
                }
            }
        }
        Goal::Error(target) => {
            let mut plans = efforts.iter().filter_map(|&f| {
                let (f, prepass) = made(f);
                let s = match fixed_spp {
                    Some(s) => (model.error(s, f) <= target).then_some(s)?,
                    None => model
                        .samples_to(f, target)
                        .filter(|&s| s <= MAX_SPP as f64)? as u32,
                };
                Some((prepass + s as f64 * model.per_spp, f, s))
            });
            match best(&mut plans) {
                Some((_, f, s)) => choice(Why::LeastTime, f, s),
                None => {
                    let f = *efforts.last().unwrap_or(&1.0);
                    choice(Why::TargetOutOfReach, f, fixed_spp.unwrap_or(MAX_SPP))
                }
            }
        }
    }
}

/// Returns `γ` from the variances of pixels of 2 and of 4 stratified samples, `v2 = v4·2^γ`,
/// within [1, 2] (1 when either is zero).
fn stratification(v2: f64, v4: f64) -> f64 {
    match v2 > 0.0 && v4 > 0.0 {
        true => (v2 / v4).log2().clamp(1.0, 2.0),
        false => 1.0,
    }
}

/// Per-pixel running sums over a pilot pixel's samples: count, means and sums of squared
/// deviations (Welford) of the first prepass's value and of the three differences.
#[derive(Clone, Copy, Default)]
struct PixelRun {
    n: u32,
    mean: [f64; QUANTITIES],
    m2: [f64; QUANTITIES],
    /// The means of each stratified set ([`PILOT_SETS`]) of the first prepass's value and of
    /// the third's: two replicates of a 2-sample and of a 4-sample pixel.
    sets: [[f64; 4]; 2],
    /// Whether a sample saw a light directly (the pixel is then left out, see [`lit_pixels`]).
    light: bool,
    /// The first prepass's samples of the first two sets (4 samples, independent of the
    /// 4-sample replicates): their channel variance, as adaptive pixels test it
    /// ([`crate::render::noise::Halves::sample_error`]; see [`fit_adaptive`]).
    noise: Halves,
    /// The thread seconds each set's samples took through the first tracer.
    set_seconds: [f64; 4],
    /// Over the first set's samples: their count, and the sums of the first and of the second
    /// prepass's value less the same with the cache's interpolation error taken out
    /// ([`DiffuseTerm::Unbiased`]), and the thread seconds those traces took.
    unbiased: (u32, [f64; 2]),
    /// The thread seconds of the traces that only measure: the unbiased ones and the caustic
    /// map's alone.
    side_seconds: f64,
}

/// A pilot sample's quantities: the first prepass's value, the differences of the two pairs
/// and of their means, the third prepass's value, and the differences of the caustic map's
/// estimates alone ([`PILOT_CAUSTICS`]).
const QUANTITIES: usize = 5 + PILOT_CAUSTICS.len();

impl PixelRun {
    /// Returns the thread seconds its samples took through the first tracer.
    fn seconds(&self) -> f64 {
        self.set_seconds.iter().sum()
    }

    fn add(&mut self, x: [f64; QUANTITIES]) {
        self.n += 1;
        for (i, &x) in x.iter().enumerate() {
            let d = x - self.mean[i];
            self.mean[i] += d / self.n as f64;
            self.m2[i] += d * (x - self.mean[i]);
        }
    }

    /// Returns an estimate of the squared bias the cache's interpolation leaves in this
    /// pixel: the product of the two prepasses' mean differences. Each difference's noise
    /// (which records serve, and what their own gathers drew) is its prepass's, so only
    /// the bias both share is left in the product's expectation.
    fn cache_bias2(&self) -> f64 {
        let (n, [a, b]) = self.unbiased;
        match n {
            0 => 0.0,
            n => a * b / (n as f64 * n as f64),
        }
    }

    /// Returns the unbiased estimates of the variance of a pixel of 2 and of 4 stratified
    /// samples from the replicates of tracer `t` (0: the first prepass, 1: the third).
    fn set_vars(&self, t: usize) -> (f64, f64) {
        let s = &self.sets[t];
        ((s[0] - s[1]).powi(2) / 2.0, (s[2] - s[3]).powi(2) / 2.0)
    }

    /// Returns the squared standard error of the mean of quantity `i`.
    fn se2(&self, i: usize) -> f64 {
        match self.n {
            0 | 1 => 0.0,
            n => self.m2[i] / ((n - 1) as f64 * n as f64),
        }
    }

    /// Returns the unbiased estimate of the squared mean of quantity `i` (its mean squared,
    /// less the samples' noise in it).
    fn mean2(&self, i: usize) -> f64 {
        self.mean[i] * self.mean[i] - self.se2(i)
    }
}

/// A prepass the planner made, and its wall seconds.
struct Timed {
    prepass: Prepass,
    seconds: f64,
    /// The wall seconds the pilot's pixels are expected to take, and how many more its caustic
    /// estimates alone add ([`pixels_seconds`]; zero until measured).
    pixels: f64,
    caustic_pixels: f64,
    /// Whether the pilot traces the caustic map's estimates alone ([`quick`] drops them when
    /// only they would make the pilot too long).
    caustic_traces: bool,
    /// The wall seconds of one sample of every pixel through it ([`pixels_seconds`]; zero
    /// until measured).
    per_spp: f64,
}

/// Makes the pilot's prepass number `i` (its seed the frame's, mixed with `i`) at effort `f`,
/// its cache made near the pixels of `grid` only, and times it.
fn pilot_prepass(
    view: View,
    photons: &GiSettings,
    request: &Request,
    grid: &[(u32, u32)],
    i: u64,
    f: f64,
) -> Timed {
    let mut gi = at_effort(photons, f, request);
    gi.seed = photons.seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(i + 1));
    let start = Instant::now();
    // The caches are made near the pixels the pilot reads: at 1024² a whole one is most of
    // the pilot's time, and the frame's cost is extrapolated from the records made.
    let prepass = Prepass::build_with(view.scene, &gi, &NoProgress)
        .precompute_for(view.camera)
        .with_cache_over(view.scene, view.camera, Probes::Near(grid), &NoProgress);
    Timed {
        prepass,
        seconds: start.elapsed().as_secs_f64(),
        pixels: 0.0,
        caustic_pixels: 0.0,
        caustic_traces: true,
        per_spp: 0.0,
    }
}

/// Makes the rest of the pilot's four prepasses of independent seeds, two at `F₀` and two at
/// [`PILOT_STEP`]`·F₀` ([`pilot_effort`] chooses `F₀` from `first`, the first one's at
/// [`PILOT_EFFORT`]), and returns them with `F₀`.
fn pilot_prepasses(
    view: View,
    photons: &GiSettings,
    request: &Request,
    first: Timed,
    progress: &dyn Progress,
) -> (Vec<Prepass>, f64) {
    let (grid, _) = pilot_grid(view, PILOT_GRID);
    let f0 = pilot_effort(request, first.seconds, max_effort(view, photons, request));
    let first = match f0 > PILOT_EFFORT {
        true => pilot_prepass(view, photons, request, &grid, 0, f0).prepass,
        false => first.prepass,
    };
    let mut prepasses = vec![first];
    for i in 1..4u64 {
        let f = if i < 2 { f0 } else { PILOT_STEP * f0 };
        prepasses.push(pilot_prepass(view, photons, request, &grid, i, f).prepass);
        progress.advance(1);
    }
    (prepasses, f0)
}

/// The pilot's tracers: through each of its prepasses; through the first two with the cache's
/// interpolation error taken out where it serves ([`DiffuseTerm::Unbiased`]); and the
/// caustic map's estimates alone, pair by pair ([`PILOT_CAUSTICS`]; none without a caustic
/// map).
struct PilotTracers<'a> {
    tracers: Vec<Tracer<'a>>,
    unbiased: Vec<Tracer<'a>>,
    caustic: Vec<Tracer<'a>>,
}

impl<'a> PilotTracers<'a> {
    /// Returns `tracers` alone, without the pilot's side traces.
    fn only(tracers: Vec<Tracer<'a>>) -> PilotTracers<'a> {
        PilotTracers {
            tracers,
            unbiased: Vec::new(),
            caustic: Vec::new(),
        }
    }
}

/// Returns the pilot's tracers through `prepasses` ([`PilotTracers`]), the caustic map's
/// alone only with `caustics`.
fn pilot_tracers<'a>(
    view: View<'a>,
    settings: &Settings,
    prepasses: &'a [Prepass],
    caustics: bool,
) -> PilotTracers<'a> {
    let tracer = |diffuse, light_samples| Tracer {
        scene: view.scene,
        camera: view.camera,
        light_samples,
        diffuse,
    };
    let lights = settings.light_samples;
    let tracers = prepasses
        .iter()
        .map(|p| tracer(DiffuseTerm::Photons(p), lights))
        .collect();
    let unbiased = (0..2)
        .map(|i| {
            tracer(
                DiffuseTerm::Unbiased(&prepasses[i], 0xCAC4E + i as u64),
                lights,
            )
        })
        .collect();
    // A pair's difference holds its caustic estimates' noise alone: the direct light is the
    // same through both, so it is not traced.
    let caustics =
        caustics && prepasses.len() == 4 && prepasses.iter().all(|p| p.caustic.is_some());
    let caustic = PILOT_CAUSTICS
        .iter()
        .filter(|_| caustics)
        .flat_map(|&(i, t)| {
            let k = thinned(prepasses[i].settings.k, t);
            [i, i + 1].map(|i| tracer(DiffuseTerm::Caustic(&prepasses[i], k), 0))
        })
        .collect();
    PilotTracers {
        tracers,
        unbiased,
        caustic,
    }
}

/// Runs the pilot of the module doc and returns its model.
fn pilot(
    view: View,
    settings: &Settings,
    photons: &GiSettings,
    request: &Request,
    first: Timed,
    progress: &dyn Progress,
) -> (Model, Vec<Prepass>) {
    let caustics = first.caustic_traces;
    let (prepasses, f0) = pilot_prepasses(view, photons, request, first, progress);
    let costs = pair_costs(view, photons, request, &prepasses[2..], PILOT_STEP * f0);
    let tracers = pilot_tracers(view, settings, &prepasses, caustics);
    let start = Instant::now();
    let (runs, thread_seconds, samples) =
        pilot_pixels(view, settings.seed, &tracers, PILOT_GRID, progress);
    // The wall time of the four tracers alone: the camera pass shares its threads as they did.
    let side_seconds: f64 = runs.iter().map(|r| r.side_seconds).sum();
    let wall =
        start.elapsed().as_secs_f64() * thread_seconds / (thread_seconds + side_seconds).max(1e-12);
    let runs = lit_pixels(runs);
    let n = runs.len().max(1) as f64;
    let mean = runs.iter().map(|r| r.mean[0]).sum::<f64>() / n;
    let m2 = (mean * mean).max(1e-300);
    let avg = |f: &dyn Fn(&PixelRun) -> f64| runs.iter().map(f).sum::<f64>() / n;
    // V_cam(F) = V + K/F through the two efforts' 4-sample pixels' variances.
    let (a2, c1) = (
        avg(&|r| r.set_vars(0).0) / m2,
        avg(&|r| r.set_vars(0).1) / m2,
    );
    let (b2, c2) = (
        avg(&|r| r.set_vars(1).0) / m2,
        avg(&|r| r.set_vars(1).1) / m2,
    );
    let camera_sparse = ((c1 - c2) / (1.0 / f0 - 1.0 / (PILOT_STEP * f0))).max(0.0);
    let camera_var = (c2 - camera_sparse / (PILOT_STEP * f0)).max(0.0);
    // E[(A − B)²] = 2 V(F₀); E[(C − D)²] = 2 V(4F₀); E[((A + B) − (C + D))²/4] =
    // V(F₀)/2 + V(4F₀)/2 + (b(F₀) − b(4F₀))².
    let v1 = (avg(&|r| r.mean2(1)) / 2.0 / m2).max(0.0);
    let v2 = (avg(&|r| r.mean2(2)) / 2.0 / m2).max(0.0);
    let db2 = (avg(&|r| r.mean2(3)) / m2 - v1 / 2.0 - v2 / 2.0).max(0.0);
    let caustic = match tracers.caustic.is_empty() {
        true => CausticNoise::default(),
        false => {
            let vars: Vec<Option<f64>> = (0..PILOT_CAUSTICS.len())
                .map(|i| significant(runs.iter().map(|r| r.mean2(5 + i) / 2.0 / m2)))
                .collect();
            caustic_curve(prepasses[0].settings.k, f0, &vars)
        }
    };
    // The rest of the maps' noise: the two pairs' less their caustic estimates'.
    let (c1, c2) = caustic.anchors();
    let (v1, v2) = ((v1 - c1).max(0.0), (v2 - c2).max(0.0));
    let beta = if v1 > 0.0 && v2 > 0.0 {
        ((v1 / v2).ln() / PILOT_STEP.ln()).clamp(0.2, 1.0)
    } else {
        1.0
    };
    // b(F₀) − b(sF₀) = b (1 − 1/s).
    let bias2 = db2 / (1.0 - 1.0 / PILOT_STEP).powi(2);
    let measured = runs.iter().filter(|r| r.unbiased.0 > 0);
    let cache_bias2 = (measured.clone().map(PixelRun::cache_bias2).sum::<f64>()
        / measured.count().max(1) as f64
        / m2)
        .max(0.0);
    // The pilot's own parallel efficiency: the camera pass shares its threads the same way.
    let threads = rayon::current_num_threads().max(1) as f64;
    let efficiency = (thread_seconds / (wall * threads).max(1e-12)).clamp(0.25, 1.0);
    let (w, h) = view.window.size();
    let per_sample = thread_seconds / 4.0 / samples.max(1) as f64 / efficiency;
    let model = Model {
        mean,
        camera_var,
        camera_sparse,
        gamma: stratification(a2 + b2, c1 + c2),
        map_var: v1,
        beta,
        caustic,
        bias2,
        cache_bias2,
        pilot_effort: f0,
        photon_per_effort: costs.photon_per_effort,
        photon_fixed: costs.photon_fixed,
        upfront_per_effort: costs.upfront_per_effort,
        cache_per_ray: costs.cache_per_ray,
        cache_rays: photons.cache.rays,
        fixed_rays: request.fixed_cache_rays,
        points_per_effort: costs.points_per_effort,
        lazy_from: costs.lazy_from,
        per_spp: per_sample * w as f64 * h as f64 / threads,
    };
    (model, prepasses)
}

/// Returns the caustic map's noise the pilot measured: `vars[i]`, the relative variance of
/// [`PILOT_CAUSTICS`]'s pair `i` (the first pair at `f0`, the second at [`PILOT_STEP`]` f0`;
/// `None` when lost in its noise), counted `k'/k` times at the effort where the frame's `k`
/// photons have the radius its `k'` have ([`CausticNoise`]). Without both pairs at `k` (the
/// part of the two pairs' whole noise that is the caustic's) no curve: the whole noise is then
/// the rest, as before the caustic was measured apart.
fn caustic_curve(k: usize, f0: f64, vars: &[Option<f64>]) -> CausticNoise {
    let pairs = PILOT_CAUSTICS.iter().zip(vars);
    if !pairs.clone().all(|(&(_, t), v)| t > 1.0 || v.is_some()) {
        return CausticNoise::default();
    }
    let points: Vec<(f64, f64)> = pairs
        .filter_map(|(&(pair, t), v)| {
            let f = if pair == 0 { f0 } else { PILOT_STEP * f0 };
            let kt = thinned(k, t) as f64 / k.max(1) as f64;
            v.map(|v| (f / kt, v * kt))
        })
        .collect();
    CausticNoise::new(&points)
}

/// Returns the mean of `values` (one a pixel) when it lies more than two standard errors above
/// zero, else `None`: a caustic that few of the pilot's pixels see is measured by few, and a
/// mean lost in its noise says nothing about how the noise falls.
fn significant(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut n, mut sum, mut sum2) = (0.0, 0.0, 0.0);
    for v in values {
        (n, sum, sum2) = (n + 1.0, sum + v, sum2 + v * v);
    }
    let mean = sum / f64::max(n, 1.0);
    let var = (sum2 / f64::max(n, 1.0) - mean * mean).max(0.0);
    (n > 1.0 && mean > 2.0 * (var / (n - 1.0)).sqrt()).then_some(mean)
}

/// What a pair of pilot prepasses at effort `f` measured of the prepass's cost ([`Model`]'s
/// fields of the same names).
struct Costs {
    photon_per_effort: f64,
    photon_fixed: f64,
    upfront_per_effort: f64,
    cache_per_ray: f64,
    points_per_effort: f64,
    lazy_from: f64,
}

/// Returns the prepass's costs from `pair`'s phases at effort `f`: the photons' time scales
/// with the effort (unless the photons are fixed), the cache's with its rays and, past the
/// pair's points or the image's pixels, with the points ([`lazy_growth`]).
fn pair_costs(
    view: View,
    photons: &GiSettings,
    request: &Request,
    pair: &[Prepass],
    f: f64,
) -> Costs {
    let n = pair.len().max(1) as f64;
    let (mut photon_seconds, mut precompute, mut cache_seconds, mut points) = (0.0, 0.0, 0.0, 0.0);
    for p in pair {
        let st = &p.stats;
        photon_seconds += (st.trace_time + st.build_time).as_secs_f64() / n;
        precompute += st.precompute_time.as_secs_f64() / n;
        cache_seconds += st.cache.as_ref().map_or(0.0, |c| c.whole_seconds()) / n;
        points += st.precomputed_points as f64 / n;
    }
    let rays = cache_rays(photons.cache.rays, f, request.fixed_cache_rays);
    let (points_per_effort, lazy_from) = lazy_points(view, points, f, request);
    // The pilot's points were estimated up front when they were no more than the pixels.
    let (w, h) = view.camera.size();
    let upfront = points_per_effort > 0.0 && points <= f64::from(w) * f64::from(h);
    let (photon_per_effort, upfront_per_effort, photon_fixed) =
        match (request.fixed_photons, upfront) {
            (true, _) => (0.0, 0.0, photon_seconds + precompute),
            (false, true) => (photon_seconds / f, precompute / f, 0.0),
            (false, false) => ((photon_seconds + precompute) / f, 0.0, 0.0),
        };
    Costs {
        photon_per_effort,
        upfront_per_effort,
        photon_fixed,
        cache_per_ray: cache_seconds / rays.max(1) as f64,
        points_per_effort,
        lazy_from,
    }
}

/// Returns the precomputation points a unit of effort makes (zero when the photons are fixed:
/// no effort adds any) and the count from which more make a gather ray cost more
/// ([`lazy_growth`]), from `points` made at effort `f` and the image's pixels.
fn lazy_points(view: View, points: f64, f: f64, request: &Request) -> (f64, f64) {
    let (w, h) = view.camera.size();
    let per_effort = match request.fixed_photons || f <= 0.0 {
        true => 0.0,
        false => points / f,
    };
    (per_effort, points.max(f64::from(w) * f64::from(h)))
}

/// Returns the pilot's pixels that saw no light directly, which its figures are taken over. A
/// light's own pixels are thousands of times the image's mean (relative to which every error
/// is counted), and their error is its edges' aliasing, the same for every prepass: it would
/// swamp what the plan can change. `docs/accuracy.md` leaves the rows of the ceiling light
/// out of its measures for the same reason; the expected error is the rest of the image's.
fn lit_pixels(runs: Vec<PixelRun>) -> Vec<PixelRun> {
    runs.into_iter().filter(|r| !r.light).collect()
}

/// Returns the radiance along `ray` through each of `tracers`, all drawing the same random
/// numbers (a NaN or infinite value counts as black, as the camera pass drops it); `rng` ends
/// where the last tracer left it. Also returns the seconds the first tracer took.
fn trace_all(
    tracers: &[Tracer],
    ray: &crate::geometry::ray::Ray,
    share: Share,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> (Vec<Vec3A>, f64) {
    let mut last = rng.clone();
    let mut first = None;
    let l = tracers
        .iter()
        .map(|t| {
            let mut r = rng.clone();
            let start = Instant::now();
            let value = crate::render::Radiance::radiance(t, ray, share, &mut r, counts);
            first.get_or_insert(start.elapsed().as_secs_f64());
            last = r;
            match value.is_finite() {
                true => value,
                false => Vec3A::ZERO,
            }
        })
        .collect();
    *rng = last;
    (l, first.unwrap_or(0.0))
}

/// Returns the pilot's smaller effort `F₀`, given that a prepass at [`PILOT_EFFORT`] took
/// `seconds`: for a time budget, the effort at which the pilot's four prepasses (`2 + 2s` times
/// `F₀`'s work, `s` = [`PILOT_STEP`]) take about [`PILOT_SHARE`] of it, so that a longer
/// budget measures the maps nearer the efforts it will choose from; at least
/// [`PILOT_EFFORT`], at most [`MAX_PILOT_EFFORT`] and at most a `2 + 2s`-th of `most`, the
/// largest effort the photon cap and the memory budget allow (the four are held at once). A
/// target error keeps [`PILOT_EFFORT`].
fn pilot_effort(request: &Request, seconds: f64, most: f64) -> f64 {
    let Goal::Time(budget) = request.goal else {
        return PILOT_EFFORT;
    };
    let per_effort = seconds.max(1e-6) / PILOT_EFFORT;
    let work = 2.0 + 2.0 * PILOT_STEP;
    let cap = (most / work).clamp(PILOT_EFFORT, MAX_PILOT_EFFORT);
    (PILOT_SHARE * budget.as_secs_f64() / (work * per_effort)).clamp(PILOT_EFFORT, cap)
}

/// Returns the pilot's pixels (in the full image), row by row: a grid of at most
/// `side`² spread evenly over `view`'s window; and its number of columns.
fn pilot_grid(view: View, side: u32) -> (Vec<(u32, u32)>, u32) {
    let win = view.window;
    let (w, h) = win.size();
    let (cols, rows) = (side.min(w), side.min(h));
    let grid = (0..rows)
        .flat_map(|j| {
            (0..cols).map(move |i| {
                let x = win.x0 + ((2 * i + 1) * w / (2 * cols)).min(w - 1);
                let y = win.y0 + ((2 * j + 1) * h / (2 * rows)).min(h - 1);
                (x, y)
            })
        })
        .collect();
    (grid, cols)
}

/// Traces the pilot's samples: the sets of [`PILOT_SETS`] at each pixel of a grid of at most
/// `side`² over `view`'s window ([`pilot_grid`]), each through every tracer with the same
/// random numbers. Returns each pixel's running sums (with the first tracer's seconds), the
/// thread seconds spent tracing through every tracer and the samples traced per tracer.
fn pilot_pixels(
    view: View,
    seed: u64,
    all: &PilotTracers,
    side: u32,
    progress: &dyn Progress,
) -> (Vec<PixelRun>, f64, u64) {
    use rayon::prelude::*;
    let (tracers, unbiased, caustic) = (&all.tracers, &all.unbiased, &all.caustic);
    let (grid, cols) = pilot_grid(view, side);
    let rows = grid.len() as u32 / cols.max(1);
    progress.start("planning: pilot pixels", rows as u64);
    // The pilot's own streams: keyed like the render's pixels, under another seed.
    let seed = seed ^ 0xD1B5_4A32_D192_ED03;
    let per_row: Vec<(Vec<PixelRun>, f64, u64)> = (0..rows)
        .into_par_iter()
        .map(|j| {
            let mut counts = RayCounts::default();
            let mut runs = Vec::with_capacity(cols as usize);
            let mut seconds = 0.0;
            let mut samples = 0;
            for &(x, y) in &grid[(j * cols) as usize..((j + 1) * cols) as usize] {
                let index = y as u64 * view.window.full_width as u64 + x as u64;
                let mut rng = Rng::new(seed, Pass::Pixel, index);
                let mut run = PixelRun::default();
                for (set, &size) in PILOT_SETS.iter().enumerate() {
                    // A set's samples share caustic estimates as a pixel round's do.
                    let _scope = crate::render::scope::PixelScope::open();
                    let sharers = size.min(WEAK_SHARERS);
                    for (k, (u, v)) in stratified_2d(&mut rng, size).into_iter().enumerate() {
                        let share = match (k as u32).is_multiple_of(sharers) {
                            true => Share::Carry(sharers as f32),
                            false => Share::Skip,
                        };
                        let ray = view.camera.ray(x as f32 + u, y as f32 + v);
                        crate::render::scope::take_light_seen();
                        let start = Instant::now();
                        // The cache's bias from the first set's samples.
                        let before = (set == 0 && !unbiased.is_empty()).then(|| rng.clone());
                        let caustic_rng = rng.clone();
                        let (values, first) =
                            trace_all(tracers, &ray, share, &mut rng, &mut counts);
                        run.light |= crate::render::scope::take_light_seen();
                        seconds += start.elapsed().as_secs_f64();
                        if let Some(mut r) = before {
                            let start = Instant::now();
                            let (u, _) = trace_all(unbiased, &ray, share, &mut r, &mut counts);
                            crate::render::scope::take_light_seen();
                            run.side_seconds += start.elapsed().as_secs_f64();
                            run.unbiased.0 += 1;
                            for (i, u) in u.iter().enumerate().take(2) {
                                run.unbiased.1[i] += ((values[i] - *u).element_sum() / 3.0) as f64;
                            }
                        }
                        run.set_seconds[set] += first;
                        samples += 1;
                        if set < 2 {
                            run.noise.add(values[0]);
                        }
                        let l: Vec<f64> = values
                            .iter()
                            .map(|v| (v.element_sum() / 3.0) as f64)
                            .collect();
                        let mut q = [0.0; QUANTITIES];
                        q[..5].copy_from_slice(&match l[..] {
                            [a, b, c, d] => [a, a - b, c - d, (a + b - c - d) / 2.0, c],
                            [a, b] => [a, a - b, 0.0, 0.0, b],
                            _ => [l[0], 0.0, 0.0, 0.0, 0.0],
                        });
                        if !caustic.is_empty() {
                            let start = Instant::now();
                            let mut r = caustic_rng;
                            let (c, _) = trace_all(caustic, &ray, share, &mut r, &mut counts);
                            crate::render::scope::take_light_seen();
                            run.side_seconds += start.elapsed().as_secs_f64();
                            for (q, pair) in q[5..].iter_mut().zip(c.chunks_exact(2)) {
                                *q = ((pair[0] - pair[1]).element_sum() / 3.0) as f64;
                            }
                        }
                        run.add(q);
                        run.sets[0][set] += q[0] / size as f64;
                        run.sets[1][set] += q[4] / size as f64;
                    }
                }
                runs.push(run);
            }
            progress.advance(1);
            (runs, seconds, samples)
        })
        .collect();
    let mut runs = Vec::new();
    let (mut seconds, mut samples) = (0.0, 0);
    for (r, s, n) in per_row {
        runs.extend(r);
        seconds += s;
        samples += n;
    }
    (runs, seconds, samples)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Model {
        Model {
            mean: 1.0,
            camera_var: 0.01,
            camera_sparse: 0.0,
            gamma: 1.0,
            // 0.0025/F, from a pilot whose own prepass (at 4F₀ = 0.004) is too coarse to take.
            map_var: 2.5,
            beta: 1.0,
            caustic: CausticNoise::default(),
            bias2: 0.0,
            cache_bias2: 0.0,
            pilot_effort: 0.001,
            photon_per_effort: 1.0,
            photon_fixed: 0.0,
            upfront_per_effort: 0.0,
            cache_per_ray: 0.0,
            cache_rays: 256,
            fixed_rays: false,
            points_per_effort: 0.0,
            lazy_from: 0.0,
            per_spp: 0.1,
        }
    }

    fn request(goal: Goal) -> Request {
        Request {
            goal,
            fixed_spp: false,
            fixed_photons: false,
            fixed_cache_rays: false,
        }
    }

    /// With `E² = 0.04/s + 0.0025/F` and `T = F + 0.1 s`, the optimum spends the last second
    /// equally well on either (`0.04/(0.1 s²) = 0.0025/F²`, so `F ≈ 0.079 s`): the planner's
    /// choice is within 2% of the brute-force best over a fine grid of efforts, each judged by
    /// the samples it leaves with the prepass at [`PREPASS_MARGIN`] times its time.
    #[test]
    fn time_goal_matches_brute_force() {
        let m = model();
        let settings = Settings::default();
        let r = request(Goal::Time(Duration::from_secs_f64(10.0)));
        let c = decide(m, &r, MAX_EFFORT, &settings, 0.0);
        let left = 10.0 * (1.0 - RESERVE);
        let mut best = f64::INFINITY;
        for i in 1..100_000 {
            let f = i as f64 * 1e-4 * left;
            let s = ((left - PREPASS_MARGIN * f) / 0.1).floor();
            if s >= 1.0 {
                best = best.min(m.error(s as u32, f));
            }
        }
        let got = m.error(c.spp, c.effort);
        let margin = PREPASS_MARGIN * m.prepass_time(c.effort) + c.spp as f64 * m.per_spp;
        assert!(margin <= left + 1e-9, "{margin} s with the margin");
        assert!(got <= best * 1.02, "planner {got} vs brute force {best}");
    }

    /// A gather ray's cost grows as `(points / from)^LAZY_GROWTH` beyond `from`, and not
    /// below it; without points per effort (the photons fixed) the cache's time is its rays'.
    /// With the diffuse box's pilot figures at `--time-budget 2.5` (`docs/accuracy/budget.md`),
    /// a plan that counts the growth chooses a smaller effort than one that does not and
    /// leaves its prepass the planner's margin, where the other, charged the growth, overruns.
    #[test]
    fn a_plan_counts_what_more_points_cost_the_cache() {
        assert_eq!(lazy_growth(9_000.0, 9_216.0), 1.0);
        assert!((lazy_growth(92_160.0, 9_216.0) - 10f64.powf(LAZY_GROWTH)).abs() < 1e-12);
        assert_eq!(lazy_growth(1e6, 0.0), 1.0);
        let m = Model {
            camera_var: 1e-3,
            map_var: 1.45e-3,
            beta: 0.63,
            cache_bias2: 1.42e-5,
            pilot_effort: 1.0 / 32.0,
            photon_per_effort: 0.293,
            cache_per_ray: 9.14e-4,
            per_spp: 0.0271,
            // The larger pair's points at 4F₀ (the box's 147k at effort 1 over 8), more than
            // its 9216 pixels.
            points_per_effort: 147_220.0,
            lazy_from: 18_403.0,
            ..model()
        };
        let rays = |f: f64| cache_rays(256, f, false) as f64;
        let grown = 9.14e-4 * rays(2.0) * (147_220.0 * 2.0 / 18_403.0f64).powf(LAZY_GROWTH);
        assert!((m.cache_time(2.0) - grown).abs() < 1e-12);
        assert_eq!(m.cache_time(0.1), 9.14e-4 * rays(0.1));
        let flat = Model {
            points_per_effort: 0.0,
            ..m
        };
        assert!((flat.cache_time(2.0) - 9.14e-4 * rays(2.0)).abs() < 1e-12);
        // Points estimated up front in the pilot (its points no more than the pixels) cost
        // the photons' time until an effort's points outnumber the pixels, then none.
        let upfront = Model {
            upfront_per_effort: 0.1,
            lazy_from: 9_216.0,
            ..m
        };
        let below = 9_000.0 / 147_220.0;
        let photons = |f: f64| upfront.prepass_time(f) - upfront.cache_time(f);
        assert!((photons(below) - (0.293 + 0.1) * below).abs() < 1e-12);
        assert!((photons(2.0) - 0.293 * 2.0).abs() < 1e-12);
        let r = request(Goal::Time(Duration::from_secs_f64(2.5)));
        let counted = decide(m, &r, MAX_EFFORT, &Settings::default(), 0.51);
        let uncounted = decide(flat, &r, MAX_EFFORT, &Settings::default(), 0.51);
        assert!(counted.effort < uncounted.effort);
        let left = 2.5 * (1.0 - RESERVE) - 0.51;
        let prepass = m.prepass_time(counted.effort);
        assert!(PREPASS_MARGIN * prepass + counted.spp as f64 * m.per_spp <= left + 1e-9);
        // The plan that did not count it, charged the growth, overruns the time left.
        let over = PREPASS_MARGIN * m.prepass_time(uncounted.effort);
        assert!(over + uncounted.spp as f64 * m.per_spp > left);
    }

    /// With a target, the chosen plan reaches it, and no plan on a fine grid reaches it in
    /// less than 0.98 times the chosen plan's time.
    #[test]
    fn error_goal_is_reached_in_least_time() {
        let m = model();
        let r = request(Goal::Error(0.05));
        let c = decide(m, &r, MAX_EFFORT, &Settings::default(), 0.0);
        assert_eq!(c.why, Why::LeastTime);
        assert!(m.error(c.spp, c.effort) <= 0.05);
        let t = m.time(c.spp, c.effort);
        for i in 1..20_000 {
            let f = i as f64 * 1e-3;
            let room = 0.0025 - m.parts2(1, f).1;
            if room > 0.0 {
                let s = (0.04 / room).ceil();
                assert!(
                    m.time(s as u32, f) >= 0.98 * t,
                    "f {f}: {}",
                    m.time(s as u32, f)
                );
            }
        }
    }

    /// A camera ray that meets an area light before anything else sees it, one that meets the
    /// wall beside it does not, and the pilot's figures leave out pixels that saw a light.
    #[test]
    fn lights_in_view_are_left_out() {
        let src = b"wall = gr.cube('wall') wall:set_material(gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0))
            wall:scale(20, 20, 1) wall:translate(-10, -10, -8)
            root = gr.node('root') root:add_child(wall)
            gr.render(root, 'x.png', 9, 9, {0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60, {0, 0, 0},
              {gr.area_light({0, 0, -5}, {4, 4, 4}, {1, 0, 0}, nil, 1000, {0.5, 0, 0}, {0, 0.5, 0})})";
        let (scene, camera) = crate::lua::test_scene(src);
        let tracer = Tracer {
            scene: &scene,
            camera: &camera,
            light_samples: 1,
            diffuse: DiffuseTerm::Ambient(Vec3A::ZERO),
        };
        let sees = |x: f32, y: f32| {
            let mut rng = Rng::new(1, Pass::Pixel, 0);
            crate::render::scope::take_light_seen();
            let state = super::super::eye::PathState::camera(&scene);
            tracer.radiance(
                &camera.ray(x, y),
                state,
                &mut rng,
                &mut RayCounts::default(),
            );
            crate::render::scope::take_light_seen()
        };
        assert!(sees(4.5, 4.5));
        assert!(!sees(0.5, 0.5));
        let lit = PixelRun {
            light: true,
            ..PixelRun::default()
        };
        let kept = lit_pixels(vec![lit, PixelRun::default(), lit]);
        assert_eq!(kept.len(), 1);
        assert!(!kept[0].light);
    }

    /// A frame without a caustic map counts only the global map's photons towards the memory
    /// an effort needs (the 2M caustic photons by default would otherwise be charged for a
    /// map never traced).
    #[test]
    fn photons_count_only_the_maps_traced() {
        let src = b"s = gr.sphere('s') s:set_material(gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0))
            gr.render(s, 'x.png', 9, 9, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},
              {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0}, 1, 1000)})";
        let (scene, _) = crate::lua::test_scene(src);
        let mut photons = GiSettings {
            photons: 1000,
            caustic_photons: 5000,
            ..GiSettings::default()
        };
        let with = photon_counts(&scene, &photons).iter().sum::<u64>();
        photons.caustics = false;
        let without = photon_counts(&scene, &photons).iter().sum::<u64>();
        assert!(with > without, "{with} {without}");
        let global: u64 = photons.budget(&scene.lights, MapKind::Global).iter().sum();
        assert_eq!(without, global);
    }

    /// `n` pixels of a sample's variance `var` and a 4-sample pixel's variance `var / 4`
    /// (independent samples), relative to an image mean of 1.
    fn flat(n: usize, var: f64) -> Vec<(f64, Option<f64>)> {
        vec![(var, Some(var / 4.0)); n]
    }

    /// Rounds double from the first round and stop at the cap, as the render's do
    /// (`refined_pixel`: 3, 6, 12, then 8 more to 20).
    #[test]
    fn rounds_double_to_the_cap() {
        assert_eq!(PilotPixels::rounds(100.0, 3, 20, 1.0), 20);
        // Uncapped, they stop at the first n with 100 / n ≤ 1: 3, 6, …, 96, 192.
        assert_eq!(PilotPixels::rounds(100.0, 3, 1000, 1.0), 192);
        assert_eq!(PilotPixels::rounds(0.5, 2, 1000, 1.0), 2);
    }

    /// A frame whose noise is in 1% of its pixels: rounds that give those pixels 16 times
    /// the samples within the uniform plan's mean cut the camera's error severalfold. By hand,
    /// with 990 pixels of variance 1 and 10 of 10⁴ (γ = 1): 8 samples everywhere leave
    /// (990·¼ + 10·2500)/1000 · ½ = 12.62; a first round of 4 and the noisy pixels at 128
    /// cost 5.24 samples a pixel and leave (990·¼ + 10·2500·4/128)/1000 = 1.03.
    #[test]
    fn adaptive_rounds_go_where_the_noise_is() {
        let mut pixels = flat(990, 1.0);
        pixels.extend(flat(10, 1e4));
        let pixels = PilotPixels {
            cost: vec![1.0; pixels.len()],
            pixels,
            test_mean: 1.0,
            mean: 1.0,
        };
        let uniform2 = (990.0 * 0.25 + 10.0 * 2500.0) / 1000.0 * 0.5;
        let (first, a, error2) =
            fit_adaptive(&pixels, 1.0, (8, uniform2), Need::Within(8.0, 0.0)).expect("a plan");
        assert!(a.mean_spp <= 8.0, "{a:?}");
        assert!(error2 <= 1.1, "{error2} against {uniform2}");
        assert!(first < 8 && a.max_spp == 128, "{first} {a:?}");
        // The prediction is the rounds' own: recount it by hand.
        let limit = a.target as f64;
        let n: Vec<u32> = pixels
            .pixels
            .iter()
            .map(|p| PilotPixels::rounds(p.0, first, 128, limit))
            .collect();
        let mean = n.iter().sum::<u32>() as f64 / 1000.0;
        assert!((mean - a.mean_spp).abs() < 1e-9);
        assert!((a.cost - a.mean_spp).abs() < 1e-9);
        // Where the noisy pixels' samples cost three times the others' (relative to their
        // mean, 1.02), the same rounds cost (990·4 + 10·128·3)/1020 = 7.65 uniform samples,
        // more than their 5.24 samples a pixel, and still within 8.
        let costly = PilotPixels {
            cost: (0..1000)
                .map(|i| (if i < 990 { 1.0 } else { 3.0 }) / 1.02)
                .collect(),
            ..pixels
        };
        let (_, c, _) =
            fit_adaptive(&costly, 1.0, (8, uniform2), Need::Within(8.0, 0.0)).expect("a plan");
        assert!(c.cost <= 8.0 && (c.cost - 7.65).abs() < 0.01, "{c:?}");
        let pixels = PilotPixels {
            cost: vec![1.0; 1000],
            ..costly
        };
        // A target: the uniform plan's error in fewer samples.
        let (_, b, e2) =
            fit_adaptive(&pixels, 1.0, (8, uniform2), Need::Below(uniform2)).expect("a plan");
        assert!(e2 <= uniform2 && b.mean_spp < 4.0, "{b:?} {e2}");
    }

    /// Noise spread evenly over the image: no rounds beat as many samples everywhere, and a
    /// frame whose samples vary only across each pixel (a texture: a large test variance, no
    /// replicate variance) is not refined either.
    #[test]
    fn even_noise_stays_uniform() {
        let even = PilotPixels {
            pixels: flat(1000, 1.0),
            cost: vec![1.0; 1000],
            test_mean: 1.0,
            mean: 1.0,
        };
        let uniform2 = 0.25 * 0.5;
        assert!(fit_adaptive(&even, 1.0, (8, uniform2), Need::Within(8.0, 0.0)).is_none());
        let mut pixels = flat(990, 1.0);
        pixels.extend(vec![(1e4, Some(0.25)); 10]);
        let textured = PilotPixels {
            pixels,
            cost: vec![1.0; 1000],
            test_mean: 1.0,
            mean: 1.0,
        };
        assert!(fit_adaptive(&textured, 1.0, (8, uniform2), Need::Within(8.0, 0.0)).is_none());
    }

    /// A fixed `--spp` stays; a target out of reach says so; a black pilot keeps the frame's.
    #[test]
    fn fixed_samples_and_unreachable_targets() {
        let m = model();
        let mut r = request(Goal::Time(Duration::from_secs(10)));
        r.fixed_spp = true;
        let settings = Settings {
            sampling: crate::render::Sampling::Stratified { spp: 7 },
            ..Settings::default()
        };
        assert_eq!(decide(m, &r, MAX_EFFORT, &settings, 0.0).spp, 7);
        let r = request(Goal::Error(1e-6));
        let c = decide(m, &r, 2.0, &Settings::default(), 0.0);
        assert_eq!(c.why, Why::TargetOutOfReach);
        assert!(c.effort <= 2.0);
        let black = Model { mean: 0.0, ..m };
        let c = decide(black, &r, 2.0, &Settings::default(), 0.0);
        assert_eq!((c.why, c.effort, c.spp), (Why::Black, 1.0, 4));
        let r = request(Goal::Time(Duration::from_secs(1)));
        let c = decide(m, &r, MAX_EFFORT, &Settings::default(), 5.0);
        assert_eq!(c.why, Why::BudgetSpent);
        // Spent, the render takes the pilot's own prepass, not a coarser one.
        assert_eq!(c.effort, PILOT_STEP * m.pilot_effort);
    }

    /// The pilot's first effort follows the budget (the four prepasses take about
    /// PILOT_SHARE of it), is at most MAX_PILOT_EFFORT, and at most a tenth of the largest
    /// effort memory and the photon cap allow, since its four prepasses are held at once.
    #[test]
    fn the_pilot_effort_follows_the_budget_within_memory() {
        let r = |s: u64| request(Goal::Time(Duration::from_secs(s)));
        // 0.1 s at 1/32: 3.2 s per unit effort, ten F₀'s work in 15 s of a 100 s budget.
        let f = pilot_effort(&r(100), 0.1, MAX_EFFORT);
        assert!((f - 15.0 / 32.0).abs() < 1e-9, "{f}");
        assert_eq!(pilot_effort(&r(100_000), 0.1, MAX_EFFORT), MAX_PILOT_EFFORT);
        assert_eq!(pilot_effort(&r(100_000), 0.1, 10.0), 1.0);
        assert_eq!(pilot_effort(&r(1), 0.1, MAX_EFFORT), PILOT_EFFORT);
        assert_eq!(
            pilot_effort(&request(Goal::Error(0.1)), 0.1, 64.0),
            PILOT_EFFORT
        );
    }

    /// The rest of a pilot whose first prepass took 0.03 s of photons and 0.2 s of cache: one
    /// more (0.23 s) and two at 4 times the effort (0.12 + 0.4 s each), 1.27 s. That is the
    /// final scene at 256²: with 2.5 s it is more than [`PILOT_MOST`] of the time left, with
    /// 10 s it is not. The showcase at 100² with 2.5 s, whose rest was predicted at 0.60 s
    /// with 2.3 s left, takes its pilot (0.021 to 0.029 against 0.038 to 0.061 without).
    #[test]
    fn a_pilot_too_long_for_the_budget_is_predicted() {
        let rest = pilot_rest(0.03, 0.2, false);
        assert!((rest - 1.27).abs() < 1e-12, "{rest}");
        // Photons a user typed are the same in all four: 0.09 + 1 s.
        assert!((pilot_rest(0.03, 0.2, true) - 1.09).abs() < 1e-12);
        assert!(rest > PILOT_MOST * 2.5 * (1.0 - RESERVE));
        assert!(rest <= PILOT_MOST * 10.0 * (1.0 - RESERVE));
        const { assert!(0.60 <= PILOT_MOST * 2.3) };
        // Its caustic traces, 3/8 of its pixels' 0.27 s, still fit; a pilot they would put
        // over goes without them.
        assert_eq!(pilot_fits(0.60, 0.10, 2.3), Some(true));
        assert_eq!(pilot_fits(0.78, 0.10, 2.3), Some(false));
        assert_eq!(pilot_fits(0.85, 0.0, 2.3), None);
    }

    /// Without a pilot the cache takes its share of the time left, less what the camera's
    /// [`QUICK_SPP`] samples need should the cache overrun by [`PREPASS_MARGIN`]: on the final
    /// scene at 256² with 2.5 s (1.6 s left after the photons, 0.23 s a sample), 0.70 s where
    /// its share is 0.96 s; on the glass in water (0.02 s a sample) its share.
    #[test]
    fn without_a_pilot_the_camera_keeps_its_samples() {
        let cache = quick_cache(1.6, 0.23);
        assert!((cache - (1.6 - 0.69) / PREPASS_MARGIN).abs() < 1e-12);
        assert!(1.6 - PREPASS_MARGIN * cache >= QUICK_SPP * 0.23 - 1e-12);
        assert!((quick_cache(1.6, 0.02) - QUICK_CACHE * 1.6).abs() < 1e-12);
    }

    /// Two prepasses of independent seeds at `F` and `rF` differ by `V(F) + V(rF)`: with the
    /// noise falling as `QUICK_BETA` assumes, the split gives `V(F)` back; with `β` at either
    /// end of the pilot's range [0.2, 1] it is off by at most the factors `QUICK_BETA`'s doc
    /// names, in RMS: 1.4 at `r` = 1/8, 1.85 at 1/32.
    #[test]
    fn the_maps_part_from_one_difference() {
        for r in [1.0f64 / 8.0, 1.0 / 32.0] {
            let bound = if r > 0.1 { 1.4 } else { 1.85 };
            for beta in [0.2, QUICK_BETA, 1.0] {
                // Normalised at F: V(F) = 1, V(rF) = r^-β.
                let d2 = 1.0 + r.powf(-beta);
                let got = maps_from_difference(d2, r);
                let ratio = got.sqrt().max(1.0 / got.sqrt());
                match beta == QUICK_BETA {
                    true => assert!((got - 1.0).abs() < 1e-12, "{got}"),
                    false => assert!(ratio <= bound, "r {r} beta {beta}: {got}"),
                }
            }
        }
    }

    /// A sample's time where samples share as a plan of 4 or more will: over the 4-sample sets
    /// only (0.7 s a sample here), not over all of them (0.8).
    #[test]
    fn samples_are_timed_as_they_will_share() {
        let run = PixelRun {
            set_seconds: [2.0, 2.0, 2.8, 2.8],
            ..PixelRun::default()
        };
        let t = sharing_seconds(&[run, run]).unwrap();
        assert!((t - 0.7).abs() < 1e-12, "{t}");
        assert_eq!(sharing_seconds(&[PixelRun::default()]), None);
        // A first round of 8 samples at 0.7 of the unshared time saves 2.4 samples; one of 2
        // shares as the sets of 2 did, which the unshared time counts already.
        assert!((sharing_credit(8, 0.3) - 2.4).abs() < 1e-12);
        assert_eq!(sharing_credit(2, 0.3), 0.0);
    }

    /// A pilot whose larger prepass is what the budget can afford: the plan takes it, for its
    /// cache's time only (none here), and spends the rest on samples (with 0.46 s left, 4
    /// samples of 0.1 s).
    /// The plans that must make a prepass (1.3 s for effort 1.3 and the margin) do not fit.
    #[test]
    fn the_pilot_prepass_is_taken_when_it_is_the_best_affordable() {
        let m = Model {
            pilot_effort: 0.25,
            map_var: 0.01,
            ..model()
        };
        let r = request(Goal::Time(Duration::from_secs(1)));
        let c = decide(m, &r, MAX_EFFORT, &Settings::default(), 0.5);
        assert_eq!((c.why, c.effort, c.spp), (Why::LeastError, 1.0, 4));
        assert_eq!(reused_effort(&m, &r), 1.0);
    }

    /// A glass ball's caustic on a floor, spread over most of the image by a light to the side.
    const CAUSTIC_SCENE: &[u8] = b"
        white = gr.material({0.8, 0.8, 0.8}, {0, 0, 0}, 0)
        glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
        root = gr.node('root')
        floor = gr.cube('floor'); floor:set_material(white); floor:scale(4, 0.1, 4)
        floor:translate(-2, -1.1, -2)
        ball = gr.sphere('ball'); ball:set_material(glass); ball:scale(0.4, 0.4, 0.4)
        ball:translate(0, -0.1, 0)
        root:add_child(floor) root:add_child(ball)
        gr.render(root, 'c.png', 48, 48, {-0.8, 2.5, 2.5}, {0, -3.5, -2.5}, {0, 1, 0}, 12,
          {0, 0, 0}, {gr.area_light({2.5, 3, 0}, {0.6, 0.6, 0.6}, {1, 0, 0}, nil, 100000,
            {0.1, 0, 0}, {0, 0, 0.1})})";

    /// Returns the pilot's pixel variances of caustic estimates alone on [`CAUSTIC_SCENE`]:
    /// pairs of maps (seeds from `seed`) of `photons` caustic photons at efforts 1 and 4, read
    /// with `k` = 48 (effort 1), 48 (effort 4) and 12 (effort 1).
    fn caustic_pairs(seed: u64, scale: f64) -> [f64; 3] {
        let (scene, camera) = crate::lua::test_scene(CAUSTIC_SCENE);
        let (w, h) = camera.size();
        let view = View {
            scene: &scene,
            camera: &camera,
            window: crate::film::Window::full(w, h),
        };
        let map = |i: u64, photon_scale| {
            let gi = GiSettings {
                seed: seed * 8 + i,
                photon_scale: photon_scale * scale,
                k: 48,
                indirect: super::super::photon_map::Indirect::Direct,
                precompute: false,
                ..GiSettings::default()
            };
            Prepass::build_with(&scene, &gi, &NoProgress)
        };
        let maps = [map(0, 1.0), map(1, 1.0), map(2, 4.0), map(3, 4.0)];
        let tracer = |diffuse, light_samples| Tracer {
            scene: &scene,
            camera: &camera,
            light_samples,
            diffuse,
        };
        let caustic = [(0, 48), (1, 48), (2, 48), (3, 48), (0, 12), (1, 12)]
            .map(|(i, k)| tracer(DiffuseTerm::Caustic(&maps[i], k), 0));
        let tracers = PilotTracers {
            tracers: vec![tracer(DiffuseTerm::Ambient(Vec3A::ZERO), 1)],
            unbiased: Vec::new(),
            caustic: caustic.to_vec(),
        };
        let (runs, _, _) = pilot_pixels(view, seed, &tracers, PILOT_GRID, &NoProgress);
        let n = runs.len() as f64;
        [5, 6, 7].map(|i| runs.iter().map(|r| r.mean2(i) / 2.0).sum::<f64>() / n)
    }

    /// A caustic estimate from `k/4` photons reads as far as one from `k` photons of a map with
    /// four times as many: its pixels' noise, counted a quarter, is the larger map's. Brute
    /// force on a glass ball's caustic at two photon counts, four seeds each: the thinned
    /// pair's mean agrees with the pair at four times the photons within 20% (single seeds
    /// 0.85 to 1.22, means 1.00 and 1.07), where the `1/F` that the pilot's two efforts would
    /// assume is 1.3 and 2.2 times too optimistic (the pair at the same photons is 1.3 and 2.2
    /// times the larger, not 4).
    #[test]
    fn a_thinned_caustic_pair_measures_a_larger_effort() {
        for scale in [0.05, 0.25] {
            let (mut thinned, mut fall) = (0.0, 0.0);
            for seed in 1..5 {
                let [same, larger, thin] = caustic_pairs(seed, scale);
                assert!(larger > 0.0, "{scale} {seed}");
                thinned += thin * 12.0 / 48.0 / larger / 4.0;
                fall += same / larger / 4.0;
            }
            assert!((0.8..1.25).contains(&thinned), "{scale}: {thinned}");
            assert!(fall < 3.0, "{scale}: {fall}");
        }
    }

    /// The caustic curve joins its points as powers of the effort, extends the nearest
    /// segment's power (clamped to [0.2, 1]) beyond them, never rises with effort, and falls
    /// linearly to a point measured at zero. Closed forms.
    #[test]
    fn the_caustic_curve_joins_its_points_as_powers() {
        let c = CausticNoise::new(&[(16.0, 0.005), (1.0, 0.04), (4.0, 0.01)]);
        assert_eq!(c.len, 3);
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;
        assert!(close(c.at(1.0), 0.04) && close(c.at(16.0), 0.005));
        assert!(close(c.at(2.0), 0.02), "{}", c.at(2.0));
        assert!(close(c.at(8.0), 0.01 / 2f64.sqrt()), "{}", c.at(8.0));
        assert!(close(c.at(64.0), 0.0025), "{}", c.at(64.0));
        assert!(close(c.at(0.25), 0.16), "{}", c.at(0.25));
        // A slope steeper than 1/F or flatter than 0.2 is clamped beyond the points.
        let steep = CausticNoise::new(&[(1.0, 0.16), (2.0, 0.01)]);
        assert!(close(steep.at(4.0), 0.005), "{}", steep.at(4.0));
        let flat = CausticNoise::new(&[(1.0, 0.01), (2.0, 0.0099)]);
        assert!(close(flat.at(64.0), 0.0099 * 32f64.powf(-0.2)));
        // Noise that rose with effort is held at the smaller effort's.
        let rising = CausticNoise::new(&[(1.0, 0.01), (4.0, 0.02)]);
        assert_eq!(rising.points[1], (4.0, 0.01));
        let zero = CausticNoise::new(&[(1.0, 0.01), (4.0, 0.0)]);
        assert!(close(zero.at(2.0), 0.01 * 2.0 / 3.0) && zero.at(8.0) == 0.0);
        assert_eq!(CausticNoise::default().at(3.0), 0.0);
        assert!(close(CausticNoise::new(&[(2.0, 0.01)]).at(4.0), 0.005));
        assert_eq!(
            c.to_string(),
            ", and the caustic estimates' 4.00e-2 at x1.000, 1.00e-2 at \
            x4.000, 5.00e-3 at x16.000"
        );
    }

    /// The pilot's pairs become points at the efforts whose radius their `k'` has, counted
    /// `k'/k` times; a thinned pair lost in its noise gives no point, and a pair at `k` lost in
    /// its noise no curve. Closed forms.
    #[test]
    fn thinned_pairs_count_at_the_effort_of_their_radius() {
        assert_eq!(thinned(50, 1.0), 50);
        assert_eq!(thinned(50, 4.0), 13);
        assert_eq!(thinned(50, 16.0), THINNED_LEAST);
        assert_eq!(thinned(4, 16.0), 4);
        let means = [Some(0.04), Some(0.03), None, Some(0.01)];
        let c = caustic_curve(50, 0.25, &means);
        let k = [50.0, 50.0, 13.0, 6.0];
        assert_eq!(c.len, 3);
        assert_eq!(c.points[..2], [(0.25, 0.04), (1.0, 0.03)]);
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 / b.0 - 1.0).abs() + (a.1 / b.1 - 1.0).abs();
        assert!(close(c.points[2], (50.0 / k[3], 0.01 * k[3] / 50.0)) < 1e-12);
        assert_eq!(c.anchors(), (0.04, 0.03));
        // Without either pair at `k`, no curve: the rest holds the caustic's noise.
        let unanchored = [Some(0.04), None, Some(0.02), Some(0.01)];
        let none = caustic_curve(50, 0.25, &unanchored);
        assert_eq!((none.len, none.anchors()), (0, (0.0, 0.0)));
    }

    /// A mean counts only when it lies more than two standard errors above zero.
    #[test]
    fn only_significant_means_count() {
        assert_eq!(significant([1.0, 1.2, 0.8].into_iter()), Some(1.0));
        assert_eq!(significant([1.0, -1.1, 0.2, -0.1].into_iter()), None);
        // Nine pixels in ten see nothing, one sees it all: 2.6 standard errors, then 1.8.
        let rare = |n: usize| (0..n).map(|i| if i % 10 == 0 { 10.0 } else { 0.0 });
        assert!(significant(rare(60)).is_some());
        assert!(significant(rare(30)).is_none());
        assert_eq!(significant(std::iter::empty()), None);
    }
}
