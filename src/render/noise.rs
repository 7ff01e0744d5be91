//! Noise-driven adaptive sampling: each pixel's error estimated from two independent
//! half-buffers, and samples added where it is above the target (`--noise-target`), and the
//! error map that shows it (`--error-map`).
//!
//! # The estimates
//! A pixel's samples go alternately to two halves `A` and `B` (sample `i` of the pixel to `A`
//! when `i` is even). The halves are independent estimates of the pixel, so with `a` and `b`
//! samples in each, `E[(A − B)²] = σ²(1/a + 1/b)` per channel, and the variance of the pixel's
//! mean of `n = a + b` samples, `σ²/n`, is estimated by `(A − B)²·ab/n²` (the same estimator
//! the progressive integrator stops on; Cycles and LuxCore estimate their adaptive sampling's
//! error from two half-buffers too). Summed over the image's pixels it is the image's
//! estimated relative RMSE that every render estimating errors prints.
//!
//! One pixel's halves are a poor test of that pixel, though: their difference has one degree
//! of freedom a channel, three in all, so a pixel whose true error is 20% above the target
//! passes the test by luck a third of the time, and the pixels that stop early are exactly the
//! ones that are still noisy. Measured on uniform noise (`tests/light_transport/
//! adaptive_pixels.rs`): with the halves as the test, the noisy pixels ended at an RMS error
//! of 1.54 times the target. Cycles answers with a spatial filter over neighbouring pixels,
//! which would tie a tile's pixels to pixels outside it. caustic tests each pixel by the
//! standard error from its samples' variance instead (Welford's running sums, in double
//! precision), `3(n − 1)` degrees of freedom: a pixel of 64 samples knows its error to 5%.
//! Stratification makes the mean of a pixel's samples a little better than their variance
//! says, so the test errs on the side of more samples. The error map shows the test's
//! figure.
//!
//! # The test: relative to the image
//! A pixel's standard error `e` (the root mean square over its channels) is compared with the
//! target after dividing by `m`, the image's mean brightness. Then `--noise-target E` holds the
//! noise part of the image's relative RMSE (the figure `caustic study`, `caustic diff` and the
//! validation measure, and the one `--target-error` stops the progressive integrator on) at
//! most `E`: if no pixel's standard error is above `E·m`, their root mean square is not
//! either. The samples go where the absolute noise is, which is what that figure counts: a
//! caustic ten times the image's brightness must be ten times cleaner in relative terms than
//! the wall beside it, and a dark corner's noise, small in absolute terms, is left as it is.
//!
//! The alternatives measured no better. Relative to the geometric mean of the pixel's and the
//! image's brightness (as Cycles divides its error by the square root of the pixel's value),
//! the three scenes of `docs/accuracy.md` gave the same errors at the same targets, within
//! the timing noise of renders of a few seconds (`tools/accuracy/adaptive.sh`); relative to
//! the pixel alone, dark pixels take most of the samples for error that figure hardly counts.
//!
//! `m` comes from a pilot: the pixel centres of a [`PILOT`] × [`PILOT`] grid over the *full*
//! image, keyed by their image-plane points ([`crate::sampling::Pass::Point`]), so every tile
//! of a farm render computes the same `m` and the same decisions.
//!
//! # Rounds
//! A pixel first takes `--spp` samples (at least 2, so that both halves have one). While its
//! test fails and it has fewer than `--max-spp`, it takes another round as large as all its
//! samples so far (doubling, capped at `--max-spp`), from its own stream keyed by the pixel and
//! the round ([`crate::sampling::Pass::Refine`]). Doubling keeps the number of tests per pixel
//! logarithmic: every test of a noisy estimate is a chance to stop early by luck, and a pixel's
//! estimate after each doubling is twice as well founded as the last. Each decision depends on
//! the pixel's own samples and `m` only, so the image is the same for any thread count and a
//! tile equals the same window of the full render, as every other sampling is.

use crate::camera::Camera;
use crate::render::Radiance;
use crate::sampling::{Pass, Rng, point_key};
use crate::stats::RayCounts;
use glam::Vec3A;

/// Side of the pilot grid of pixel centres whose mean sets the image's brightness `m`.
pub const PILOT: u32 = 32;
/// Most samples a pixel may take (`--max-spp`'s bound, as `--spp`'s).
pub const MAX_SPP: u32 = 1 << 16;

/// The running sums of one pixel's samples: all of them, its two halves, and their variance.
#[derive(Clone, Copy, Debug, Default)]
pub struct Halves {
    /// The sum of every sample, in sample order (the pixel's value is `sum / n`).
    pub sum: Vec3A,
    /// The sums of the even- and odd-numbered samples.
    pub even: Vec3A,
    pub odd: Vec3A,
    /// Samples taken.
    pub n: u32,
    /// Welford's running mean and sum of squared deviations, per channel.
    mean: glam::DVec3,
    m2: glam::DVec3,
}

impl Halves {
    /// Adds the pixel's next sample.
    pub fn add(&mut self, s: Vec3A) {
        self.sum += s;
        if self.n.is_multiple_of(2) {
            self.even += s;
        } else {
            self.odd += s;
        }
        self.n += 1;
        let x = glam::DVec3::new(s.x as f64, s.y as f64, s.z as f64);
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Returns the standard error of the pixel's mean (root mean square over the channels)
    /// from its samples' variance, the per-pixel test's (see the module doc); `None` with
    /// fewer than two samples.
    pub fn sample_error(&self) -> Option<f32> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f64;
        let variance = self.m2.element_sum() / 3.0 / (n - 1.0);
        Some((variance / n).max(0.0).sqrt() as f32)
    }

    /// Returns the standard error of the pixel's mean (root mean square over the channels)
    /// estimated from its halves (see the module doc): unbiased, for the image's estimate;
    /// `None` with fewer than two samples.
    pub fn std_error(&self) -> Option<f32> {
        if self.n < 2 {
            return None;
        }
        let a = self.n.div_ceil(2) as f32;
        let b = (self.n / 2) as f32;
        let n = self.n as f32;
        let d = self.even / a - self.odd / b;
        Some((d.length_squared() / 3.0 * a * b / (n * n)).sqrt())
    }
}

/// Returns the error adaptive sampling tests a pixel by: its standard error `e` over the
/// image's mean brightness `m` ([`pilot_mean`]; see the module doc). Zero when `m` is not
/// positive (a black image has nothing to refine).
pub fn relative_error(e: f32, m: f32) -> f32 {
    if m.is_nan() || m <= 0.0 {
        return 0.0;
    }
    e / m
}

/// Returns the image's mean brightness `m` (the mean of the channels over a
/// [`PILOT`] × [`PILOT`] grid of pixel centres of the full `width × height` image), tracing the
/// rays with streams keyed by their image-plane points so that every tile finds the same.
pub fn pilot_mean(
    camera: &Camera,
    integrator: &dyn Radiance,
    seed: u64,
    (width, height): (u32, u32),
    counts: &mut RayCounts,
) -> f32 {
    use rayon::prelude::*;
    let cells = PILOT.min(width) * PILOT.min(height);
    let (cols, rows) = (PILOT.min(width), PILOT.min(height));
    let sums: Vec<(f64, RayCounts)> = (0..rows)
        .into_par_iter()
        .map(|j| {
            let mut c = RayCounts {
                timing: counts.timing,
                ..RayCounts::default()
            };
            let mut sum = 0.0f64;
            for i in 0..cols {
                // The centre of the pixel under the grid cell's centre.
                let x = ((2 * i + 1) * width / (2 * cols)) as f32 + 0.5;
                let y = ((2 * j + 1) * height / (2 * rows)) as f32 + 0.5;
                let mut rng = Rng::new(seed, Pass::Point, point_key(x, y));
                c.primary += 1;
                let r = integrator.radiance(
                    &camera.ray(x, y),
                    crate::render::Share::All,
                    &mut rng,
                    &mut c,
                );
                if r.is_finite() {
                    sum += (r.element_sum() / 3.0) as f64;
                }
            }
            (sum, c)
        })
        .collect();
    let mut total = 0.0;
    for (s, c) in sums {
        total += s;
        counts.add(&c);
    }
    (total / cells as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The halves' estimate of the mean's variance is unbiased: over many pixels of uniform
    /// noise (σ² = 1/12 per channel) its mean square is σ²/n within 3% (4·10⁴ pixels give
    /// the mean of the squares a relative standard error of about 1.2% for n = 8, a χ² of 3
    /// degrees of freedom per pixel), for even and odd n.
    #[test]
    fn halves_estimate_the_variance_of_the_mean() {
        for n in [2u32, 3, 8, 13] {
            let mut rng = Rng::new(7, Pass::Pixel, n as u64);
            let pixels = 40_000;
            let mut sq = 0.0f64;
            for _ in 0..pixels {
                let mut h = Halves::default();
                for _ in 0..n {
                    h.add(Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()));
                }
                sq += (h.std_error().unwrap() as f64).powi(2);
            }
            let truth = 1.0 / 12.0 / n as f64;
            let ratio = sq / pixels as f64 / truth;
            assert!((ratio - 1.0).abs() < 0.03, "n = {n}: ratio {ratio}");
        }
    }

    /// The samples' variance gives the same standard error, far more steadily: on uniform noise
    /// its square is within 1% of σ²/n for n = 64 over 4,000 pixels, each pixel within 35%
    /// (five standard deviations of a variance of 189 degrees of freedom).
    #[test]
    fn sample_variance_estimates_the_error_steadily() {
        let mut rng = Rng::new(9, Pass::Pixel, 0);
        let (n, pixels) = (64, 4000);
        let truth = 1.0 / 12.0 / n as f64;
        let mut sq = 0.0f64;
        for _ in 0..pixels {
            let mut h = Halves::default();
            for _ in 0..n {
                h.add(Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()));
            }
            let e2 = (h.sample_error().unwrap() as f64).powi(2);
            assert!((e2 / truth - 1.0).abs() < 0.35, "{e2} against {truth}");
            sq += e2;
        }
        let ratio = sq / pixels as f64 / truth;
        assert!((ratio - 1.0).abs() < 0.01, "ratio {ratio}");
    }

    /// One sample has no halves; a constant pixel has no error.
    #[test]
    fn degenerate_pixels() {
        let mut h = Halves::default();
        assert_eq!(h.std_error(), None);
        h.add(Vec3A::splat(0.5));
        assert_eq!(h.std_error(), None);
        h.add(Vec3A::splat(0.5));
        assert_eq!(h.std_error(), Some(0.0));
        assert_eq!(h.sample_error(), Some(0.0));
    }

    /// The test's normalisation: the image's mean, whatever the pixel's value; nothing to
    /// refine in a black image.
    #[test]
    fn relative_error_normalisation() {
        assert!((relative_error(0.05, 0.5) - 0.1).abs() < 1e-6);
        assert_eq!(relative_error(1.0, 0.0), 0.0);
        assert_eq!(relative_error(1.0, f32::NAN), 0.0);
    }
}
