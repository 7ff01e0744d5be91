//! Pixel sampling: stratified supersampling and the original project's adaptive scheme.
//!
//! **Stratified**: `spp` samples per pixel, jittered and stratified in x and y
//! ([`crate::sampling::stratified_2d`]), averaged with equal weights (a box filter). One sample is
//! the pixel centre.
//!
//! **Adaptive** (t7cai's objective, after Whitted 1980): rays through the corners of every pixel
//! (shared by neighbouring pixels, traced once for the whole window); a pixel whose four corners
//! differ by more than `threshold` in any channel is split into four sub-squares, each refined the
//! same way, at most `max_depth` times. A square that is not split contributes the mean of its
//! corners. Flat areas thus cost about one ray per pixel, and edges up to `(2^d + 1)²`. It draws
//! no random numbers, so it is deterministic by construction.

use super::noise::{self, Halves};
use super::{PassOptions, Radiance, Sampling, Share, WEAK_SHARERS};
use crate::camera::Camera;
use crate::sampling::{Pass, Rng, point_key, stratified_2d};
use crate::stats::RayCounts;
use glam::Vec3A;
use rayon::prelude::*;

/// Samples pixels of one render; shared by the worker threads.
pub struct PixelSampler<'a> {
    camera: &'a Camera,
    integrator: &'a dyn Radiance,
    opts: &'a PassOptions,
    /// Adaptive mode: radiance at every pixel corner of the window, `(w + 1) × (h + 1)` row-major.
    corners: Vec<Vec3A>,
    corner_counts: RayCounts,
    /// The image's mean brightness from the pilot ([`noise::pilot_mean`]), when pixels'
    /// errors are estimated (noise sampling, or `opts.error_estimate`).
    image_mean: Option<f32>,
}

impl<'a> PixelSampler<'a> {
    /// Prepares sampling; in adaptive mode traces every corner ray of the window (in parallel).
    pub fn new(
        camera: &'a Camera,
        integrator: &'a dyn Radiance,
        opts: &'a PassOptions,
    ) -> PixelSampler<'a> {
        let mut sampler = PixelSampler {
            camera,
            integrator,
            opts,
            corners: Vec::new(),
            corner_counts: RayCounts::default(),
            image_mean: None,
        };
        if sampler.estimates_error() {
            let win = opts.window;
            let mut counts = RayCounts {
                timing: opts.timing,
                ..RayCounts::default()
            };
            let full = (win.full_width, win.full_height);
            let m = noise::pilot_mean(camera, integrator, opts.seed, full, &mut counts);
            sampler.image_mean = Some(m);
            sampler.corner_counts.add(&counts);
        }
        if let Sampling::Adaptive { .. } = opts.sampling {
            let win = opts.window;
            let (w, h) = win.size();
            let rows: Vec<(Vec<Vec3A>, RayCounts)> = (0..=h)
                .into_par_iter()
                .map(|j| {
                    let mut counts = RayCounts {
                        timing: opts.timing,
                        ..RayCounts::default()
                    };
                    let row = (0..=w)
                        .map(|i| {
                            sampler.trace_point(
                                (win.x0 + i) as f32,
                                (win.y0 + j) as f32,
                                &mut counts,
                            )
                        })
                        .collect();
                    (row, counts)
                })
                .collect();
            for (row, c) in rows {
                sampler.corners.extend(row);
                sampler.corner_counts.add(&c);
            }
        }
        sampler
    }

    /// Returns the rays traced for the corner grid and the noise pilot (zero unless adaptive
    /// or estimating errors).
    pub fn corner_counts(&self) -> RayCounts {
        self.corner_counts
    }

    /// Returns whether pixels' errors are estimated: noise sampling always, stratified sampling
    /// of at least two samples when asked.
    pub fn estimates_error(&self) -> bool {
        match self.opts.sampling {
            Sampling::Noise { .. } => true,
            Sampling::Stratified { spp } => self.opts.error_estimate && spp >= 2,
            Sampling::Jittered { .. } | Sampling::Adaptive { .. } => false,
        }
    }

    /// Returns the image's mean brightness from the pilot, when errors are estimated.
    pub fn image_mean(&self) -> Option<f32> {
        self.image_mean
    }

    /// Returns how many corner rays are charged to window pixel `(i, j)`: its top-left corner,
    /// plus the right and bottom edges' extra corners for the last column and row.
    pub fn corner_rays_charged(&self, i: u32, j: u32) -> u32 {
        if self.corners.is_empty() {
            return 0;
        }
        let (w, h) = self.opts.window.size();
        let right = u32::from(i + 1 == w);
        let bottom = u32::from(j + 1 == h);
        1 + right + bottom + right * bottom
    }

    /// Returns the radiance along the camera ray through image-plane position `(x, y)`.
    fn trace(&self, x: f32, y: f32, rng: &mut Rng, counts: &mut RayCounts) -> Vec3A {
        self.trace_shared(x, y, Share::All, rng, counts)
    }

    /// [`PixelSampler::trace`] for a sample that shares its pixel's weak branches by `share`.
    fn trace_shared(
        &self,
        x: f32,
        y: f32,
        share: Share,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        counts.primary += 1;
        let ray = self.camera.ray(x, y);
        let radiance = self.integrator.radiance(&ray, share, rng, counts);
        finite_or_dropped(radiance, counts)
    }

    /// Returns the radiance through `(x, y)` with the random stream of that image-plane point, so
    /// every tile computes the same value for a corner it shares.
    fn trace_point(&self, x: f32, y: f32, counts: &mut RayCounts) -> Vec3A {
        let mut rng = Rng::new(self.opts.seed, Pass::Point, point_key(x, y));
        self.trace(x, y, &mut rng, counts)
    }

    /// Returns the value of pixel `(x, y)` (full-image coordinates), never NaN or infinite,
    /// and when errors are estimated its standard errors from its half-buffers and from its
    /// samples' variance ([`noise`]; NaN otherwise) and whether it sees a light directly.
    pub fn pixel(&self, x: u32, y: u32, counts: &mut RayCounts) -> (Vec3A, PixelError) {
        super::scope::take_light_seen();
        let (value, [std, sample]) = self.pixel_mean(x, y, counts);
        let lit = super::scope::take_light_seen();
        // Finite samples can still sum past the largest float.
        let error = PixelError { std, sample, lit };
        (finite_or_dropped(value, counts), error)
    }

    fn pixel_mean(&self, x: u32, y: u32, counts: &mut RayCounts) -> (Vec3A, [f32; 2]) {
        match self.opts.sampling {
            Sampling::Stratified { spp } | Sampling::Jittered { spp } => {
                let index = self.pixel_index(x, y);
                let mut rng = Rng::new(self.opts.seed, Pass::Pixel, index);
                let first =
                    Rng::new(self.opts.seed, Pass::Share, index).below(spp.min(WEAK_SHARERS));
                // One stratified sample is the pixel centre, as the course renders; more, or
                // jittered ones, are stratified.
                let centre = matches!(self.opts.sampling, Sampling::Stratified { .. });
                let mut h = Halves::default();
                let round = Round {
                    n: spp,
                    centre,
                    first,
                };
                self.round((x, y), round, &mut rng, &mut h, counts);
                let error = match self.estimates_error() {
                    true => errors(&h),
                    false => [f32::NAN; 2],
                };
                (h.sum / spp as f32, error)
            }
            Sampling::Noise {
                spp,
                max_spp,
                target,
            } => self.refined_pixel(x, y, (spp, max_spp), target, counts),
            Sampling::Adaptive {
                threshold,
                max_depth,
            } => {
                let win = self.opts.window;
                let stride = (win.size().0 + 1) as usize;
                let (i, j) = ((x - win.x0) as usize, (y - win.y0) as usize);
                let c = [
                    self.corners[j * stride + i],
                    self.corners[j * stride + i + 1],
                    self.corners[(j + 1) * stride + i],
                    self.corners[(j + 1) * stride + i + 1],
                ];
                let square = Square {
                    x: x as f32,
                    y: y as f32,
                    size: 1.0,
                };
                (
                    self.refine(square, c, threshold, max_depth, counts),
                    [f32::NAN; 2],
                )
            }
        }
    }

    /// Returns the key of pixel `(x, y)`'s streams: its index in the full image.
    fn pixel_index(&self, x: u32, y: u32) -> u64 {
        y as u64 * self.opts.window.full_width as u64 + x as u64
    }

    /// Traces one round of pixel `(x, y)`'s samples drawn from `rng`, adding them to `h` in
    /// order.
    fn round(
        &self,
        (x, y): (u32, u32),
        Round { n, centre, first }: Round,
        rng: &mut Rng,
        h: &mut Halves,
        counts: &mut RayCounts,
    ) {
        let positions = if n == 1 && centre {
            vec![(0.5, 0.5)]
        } else {
            stratified_2d(rng, n)
        };
        let sharers = n.min(WEAK_SHARERS);
        let _scope = super::scope::PixelScope::open();
        for (i, &(u, v)) in positions.iter().enumerate() {
            let share = match sharers {
                1 => Share::All,
                s if (i as u32 + first).is_multiple_of(s) => Share::Carry(s as f32),
                _ => Share::Skip,
            };
            let (x, y) = (x as f32 + u, y as f32 + v);
            h.add(self.trace_shared(x, y, share, rng, counts));
        }
    }

    /// Returns pixel `(x, y)` sampled in rounds until its estimated error is at most `target`
    /// or it has `max_spp` samples (see [`noise`]), and its standard error.
    fn refined_pixel(
        &self,
        x: u32,
        y: u32,
        (spp, max_spp): (u32, u32),
        target: f32,
        counts: &mut RayCounts,
    ) -> (Vec3A, [f32; 2]) {
        let index = self.pixel_index(x, y);
        let m = self.image_mean.unwrap_or(0.0);
        let mut h = Halves::default();
        let mut size = spp;
        for r in 0u64.. {
            // Round 0 is the stratified render's own samples; later rounds have their streams.
            let mut rng = match r {
                0 => Rng::new(self.opts.seed, Pass::Pixel, index),
                _ => Rng::new(self.opts.seed, Pass::Refine, index | r << 32),
            };
            let first = match r {
                0 => Rng::new(self.opts.seed, Pass::Share, index).below(size.min(WEAK_SHARERS)),
                _ => rng.below(size.min(WEAK_SHARERS)),
            };
            let round = Round {
                n: size,
                centre: false,
                first,
            };
            self.round((x, y), round, &mut rng, &mut h, counts);
            let e = h.sample_error().unwrap_or(0.0);
            if h.n >= max_spp || noise::relative_error(e, m) <= target {
                break;
            }
            size = h.n.min(max_spp - h.n);
        }
        (h.sum / h.n as f32, errors(&h))
    }

    /// Returns the mean radiance over `sq` given its corners `[top-left, top-right, bottom-left,
    /// bottom-right]`, splitting while they differ by more than `threshold`.
    fn refine(
        &self,
        sq: Square,
        c: [Vec3A; 4],
        threshold: f32,
        depth: u32,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let lo = c[0].min(c[1]).min(c[2].min(c[3]));
        let hi = c[0].max(c[1]).max(c[2].max(c[3]));
        if depth == 0 || (hi - lo).max_element() <= threshold {
            return (c[0] + c[1] + c[2] + c[3]) * 0.25;
        }
        let half = sq.size * 0.5;
        let (x, y) = (sq.x, sq.y);
        let top = self.trace_point(x + half, y, counts);
        let left = self.trace_point(x, y + half, counts);
        let mid = self.trace_point(x + half, y + half, counts);
        let right = self.trace_point(x + sq.size, y + half, counts);
        let bottom = self.trace_point(x + half, y + sq.size, counts);
        let sub = |x, y| Square { x, y, size: half };
        let d = depth - 1;
        (self.refine(sub(x, y), [c[0], top, left, mid], threshold, d, counts)
            + self.refine(
                sub(x + half, y),
                [top, c[1], mid, right],
                threshold,
                d,
                counts,
            )
            + self.refine(
                sub(x, y + half),
                [left, mid, c[2], bottom],
                threshold,
                d,
                counts,
            )
            + self.refine(
                sub(x + half, y + half),
                [mid, right, bottom, c[3]],
                threshold,
                d,
                counts,
            ))
            * 0.25
    }
}

/// A pixel's standard errors from its half-buffers and from its samples' variance (NaN without
/// two samples, or when errors are not estimated), and whether a camera ray of it met a light
/// before any surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelError {
    pub std: f32,
    pub sample: f32,
    pub lit: bool,
}

impl PixelError {
    /// No estimate.
    pub const NONE: PixelError = PixelError {
        std: f32::NAN,
        sample: f32::NAN,
        lit: false,
    };
}

/// Returns a pixel's standard errors from its half-buffers and from its samples' variance (NaN
/// without two samples).
fn errors(h: &Halves) -> [f32; 2] {
    [
        h.std_error().unwrap_or(f32::NAN),
        h.sample_error().unwrap_or(f32::NAN),
    ]
}

/// Returns `radiance`, or black when it is NaN or infinite in any channel, counting it in
/// [`RayCounts::nonfinite`]: no such value may reach the image.
fn finite_or_dropped(radiance: Vec3A, counts: &mut RayCounts) -> Vec3A {
    if radiance.is_finite() {
        radiance
    } else {
        counts.nonfinite += 1;
        Vec3A::ZERO
    }
}

/// One round of a pixel's samples: `n` stratified samples (or the pixel's centre when `n` is 1
/// and `centre`), of which the sample `first` (mod the sharers) of each group of
/// `min(n, WEAK_SHARERS)` shades the weak branches' surfaces (see [`Share`]).
#[derive(Clone, Copy, Debug)]
struct Round {
    n: u32,
    centre: bool,
    first: u32,
}

/// A square of the image plane in pixel units: top-left corner and side.
#[derive(Clone, Copy, Debug)]
struct Square {
    x: f32,
    y: f32,
    size: f32,
}
