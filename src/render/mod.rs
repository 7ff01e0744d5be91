//! The camera pass: trace camera rays for every pixel of a window in parallel and average what an
//! integrator sees along them into a [`Film`]. It knows nothing of light transport: the
//! integrator answers [`Radiance::radiance`] for each camera ray ([`crate::integrator`]).
//!
//! # Pixel sampling ([`aa`])
//! - `spp = 1`: one ray through the pixel centre, as the course renders.
//! - `spp = N`: N jittered samples stratified in x and y, box-filtered (the default is 4).
//! - jittered (a progressive render's passes): as `spp = N`, one sample included, so the passes
//!   together cover each pixel's area.
//! - adaptive (the original project's scheme): rays through the pixel corners; where they differ by
//!   more than a threshold, the pixel is split into four and refined recursively.
//!
//! # Determinism and tiles
//! Rows are shaded in parallel with rayon. Every random number a pixel uses comes from the stream
//! keyed by `(seed, Pass::Pixel, pixel index in the full image)` ([`crate::sampling`]), and
//! adaptive corner rays are deterministic, so the image is bit-identical for any thread count and
//! a cropped window equals the same window of the full render.

pub mod aa;
pub mod noise;
pub mod scope;

use crate::accel::counters;
use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::geometry::Ray;
use crate::progress::Progress;
use crate::sampling::Rng;
use crate::stats::{PixelErrors, RayCounts, RenderStats};
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// What an integrator answers for the camera pass: the radiance arriving along a camera ray.
pub trait Radiance: Sync {
    /// Returns the radiance arriving at `ray`'s origin along it for one camera sample that
    /// shares its pixel's weak branches as `share` says ([`Share::All`]: follow everything),
    /// drawing from `rng` and counting the rays it traces in `counts`.
    fn radiance(&self, ray: &Ray, share: Share, rng: &mut Rng, counts: &mut RayCounts) -> Vec3A;
}

/// How the samples of one pixel share the *weak branches* of their eye paths: the reflections
/// and refractions that carry less than [`WEAK_BRANCH`] of the sample (a Fresnel reflection
/// off water or glass, the 4% mirror of a glossy tile).
///
/// Shading the surface a weak branch reaches costs as much as shading a strong one (a caustic
/// lookup, shadow rays, a cache lookup, a texture) for a few percent of the pixel: on the final
/// scene 41% of the diffuse points eye paths reach are on weak branches. Of
/// `S = min(spp, WEAK_SHARERS)` consecutive samples of a pixel, one shades the surfaces its weak
/// branches reach, at `S` times their weight ([`Share::Carry`]), and the others do not
/// ([`Share::Skip`]). Which one is drawn per pixel ([`crate::sampling::Pass::Share`]), so each
/// sample shades a weak branch's surface with probability `1/S` and weight `S`: Russian
/// roulette, unbiased, with the draws stratified over the pixel so that exactly one sample in
/// `S` pays.
///
/// Every sample still traces its weak rays and counts, at their own weight, the emitters and
/// the background they see before meeting a surface ([`Share::Emitters`]): a light's
/// reflection in water or glass is small, bright and cheap, and sharing it would make it
/// `S` times noisier for nothing (on the validation scenes' glass ball, twice the relative
/// RMSE). What sharing adds is the variation, within a pixel, of the weak surfaces' light, seen
/// through `1/S` of the samples and scaled by its weight (below a tenth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Share {
    /// Follow every branch with its own weight: single samples, adaptive refinement, the
    /// irradiance cache's probes, and everything below a weak surface being shaded.
    All,
    /// A camera sample that shades its weak branches' surfaces, at this many times their weight.
    Carry(f32),
    /// A camera sample that does not shade its weak branches' surfaces.
    Skip,
    /// A weak branch of a [`Share::Carry`] sample: its radiance is multiplied by the factor, so
    /// the emitters and background it sees before a surface count divided by it.
    Surfaces(f32),
    /// A weak branch of a [`Share::Skip`] sample: it counts the emitters and background it sees
    /// before a surface, and nothing from the surface.
    Emitters,
}

/// Largest weight of a branch relative to its camera sample that [`Share`] treats as weak.
pub const WEAK_BRANCH: f32 = 0.1;
/// Most samples of a pixel that share one sample's weak branches.
pub const WEAK_SHARERS: u32 = 4;

/// How pixels are sampled.
#[derive(Clone, Debug, PartialEq)]
pub enum Sampling {
    /// `n` stratified jittered samples per pixel (1 = the pixel centre).
    Stratified { spp: u32 },
    /// `n` stratified jittered samples per pixel, one included: a pass of a progressive render,
    /// whose passes together cover the pixel's area.
    Jittered { spp: u32 },
    /// Corner rays, refined where neighbours differ by more than `threshold` (any channel),
    /// splitting at most `max_depth` times.
    Adaptive { threshold: f32, max_depth: u32 },
    /// `spp` stratified samples per pixel (at least 2), then rounds that double them while the
    /// pixel's error estimated from its half-buffers is above `target`, up to `max_spp`
    /// ([`noise`]).
    Noise { spp: u32, max_spp: u32, target: f32 },
}

/// What shapes the camera pass besides the integrator and the camera.
#[derive(Clone, Debug, PartialEq)]
pub struct PassOptions {
    pub seed: u64,
    pub sampling: Sampling,
    /// The part of the image to render.
    pub window: Window,
    /// Time material evaluation for `--stats`.
    pub timing: bool,
    /// Record each pixel's traversal counts and time ([`RenderStats::heat`]).
    pub heatmap: bool,
    /// Estimate each pixel's error from its half-buffers ([`RenderStats::error`]) under
    /// stratified sampling of at least two samples (noise sampling always does).
    pub error_estimate: bool,
}

/// Renders the window `opts.window` of the image through `camera`, asking `integrator` for each
/// camera ray; `progress` advances once per finished row. Once `progress` asks to stop, rows
/// not yet started are left black, with no samples, and counted in
/// [`RenderStats::rows_skipped`].
pub fn camera_pass(
    camera: &Camera,
    integrator: &dyn Radiance,
    opts: &PassOptions,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    // A caller that renders before building any scene (a synthetic integrator, a test) must
    // not leave the process's workers at the default stack, which a deep eye path overflows.
    let _ = crate::accel::start_workers(None);
    let start = Instant::now();
    let win = opts.window;
    let (w, h) = win.size();
    // Rows add their counts once each (a lock per row costs nothing next to a row of pixels).
    let totals = Mutex::new(RayCounts::default());
    let skipped = AtomicU64::new(0);
    let mut pixels = vec![Vec3A::ZERO; w as usize * h as usize];
    let mut samples = vec![0u32; w as usize * h as usize];
    let sampler = aa::PixelSampler::new(camera, integrator, opts);
    let mut errors = vec![
        aa::PixelError::NONE;
        if sampler.estimates_error() {
            pixels.len()
        } else {
            0
        }
    ];
    let error_rows: Vec<Option<&mut [aa::PixelError]>> = match errors.is_empty() {
        true => (0..h).map(|_| None).collect(),
        false => errors.chunks_mut(w as usize).map(Some).collect(),
    };
    // Each row's heat (with `heatmap`), in row order.
    let heat_rows: Vec<Vec<[f32; 3]>> = pixels
        .par_chunks_mut(w as usize)
        .zip(samples.par_chunks_mut(w as usize))
        .zip(error_rows)
        .enumerate()
        .map(|(row, ((px_row, count_row), mut error_row))| {
            let mut heat_row = opts.heatmap.then(|| vec![[0f32; 3]; px_row.len()]);
            if progress.should_stop() {
                skipped.fetch_add(1, Ordering::Relaxed);
                return heat_row.unwrap_or_default();
            }
            let y = win.y0 + row as u32;
            let mut counts = RayCounts {
                timing: opts.timing,
                ..RayCounts::default()
            };
            for (i, (px, n)) in px_row.iter_mut().zip(count_row.iter_mut()).enumerate() {
                let before = counts.primary;
                let start = heat_row
                    .as_ref()
                    .map(|_| (counters::thread_total(), Instant::now()));
                let (value, error) = sampler.pixel(win.x0 + i as u32, y, &mut counts);
                *px = value;
                if let Some(e) = error_row.as_deref_mut() {
                    e[i] = error;
                }
                *n = (counts.primary - before) as u32
                    + sampler.corner_rays_charged(i as u32, row as u32);
                if let (Some(heat), Some(((nodes, tris), t))) = (heat_row.as_mut(), start) {
                    let (nodes2, tris2) = counters::thread_total();
                    let ns = t.elapsed().as_nanos() as f32;
                    heat[i] = [(nodes2 - nodes) as f32, (tris2 - tris) as f32, ns];
                }
            }
            totals
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .add(&counts);
            progress.advance(1);
            heat_row.unwrap_or_default()
        })
        .collect();
    let mut t = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    t.add(&sampler.corner_counts());
    let stats = RenderStats {
        rows_skipped: skipped.into_inner(),
        time: start.elapsed(),
        heat: opts.heatmap.then(|| heat_rows.concat()),
        error: sampler.image_mean().map(|image_mean| PixelErrors {
            std_error: errors.iter().map(|e| e.std).collect(),
            sample_error: errors.iter().map(|e| e.sample).collect(),
            lit: errors.iter().map(|e| e.lit).collect(),
            image_mean,
        }),
        ..RenderStats::of_counts(&t)
    };
    let film = Film {
        width: w,
        height: h,
        pixels,
        samples,
        window: win,
    };
    crate::film::log::record(&film);
    (film, stats)
}
