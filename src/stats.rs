//! Counters of the camera pass: rays by kind, photon lookups, material time. A leaf: the passes
//! fill them per thread ([`RayCounts`]) and `--stats` prints the sums ([`RenderStats`]). And
//! the process's CPU time ([`process_cpu_time`]), by which studies time renders.

use std::time::Duration;

/// Counters from one render, printed by `--stats`.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub primary_rays: u64,
    pub shadow_rays: u64,
    pub secondary_rays: u64,
    pub time: Duration,
    /// Thread time spent in texture, bump-map and Perlin-noise evaluation (with `timing`).
    pub material_time: Duration,
    /// Photon-map estimates made while rendering, and the photons they found.
    pub lookups: u64,
    pub photons_used: u64,
    /// Caustic estimates taken from an earlier sample of the same pixel instead of a lookup.
    pub reused: u64,
    /// Eye paths stopped at the hard depth cap ([`crate::integrator::eye::MAX_PATH_DEPTH`]).
    pub depth_capped: u64,
    /// Camera samples and pixels whose radiance was NaN or infinite, dropped (counted as black).
    pub nonfinite_samples: u64,
    /// Diffuse points of eye paths served by the irradiance cache, and final-gather points
    /// gathered afresh (no record served them).
    pub cached: u64,
    pub gathered: u64,
    /// Surfaces reached by weak branches that this sample did not shade: another sample of the
    /// pixel shaded its own ([`crate::render::Share`]).
    pub weak_skipped: u64,
    /// Rows of the window left black because the render was asked to stop
    /// ([`crate::progress::Progress::should_stop`]).
    pub rows_skipped: u64,
    /// With `heatmap`: each pixel's BVH nodes visited, triangles tested and nanoseconds of
    /// thread time while it was shaded (row-major, the window's size), for `--heatmap`.
    pub heat: Option<Vec<[f32; 3]>>,
    /// With error estimates (noise sampling, `--error-map`): each pixel's standard error.
    pub error: Option<PixelErrors>,
}

/// Each pixel's standard error estimated from its half-buffers and from its samples' variance
/// ([`crate::render::noise`]), for the image's estimated error and `--error-map`.
#[derive(Clone, Debug, Default)]
pub struct PixelErrors {
    /// From the half-buffers (unbiased: the image's estimate). Row-major, the window's size;
    /// NaN where the pixel has no estimate (a dropped render row).
    pub std_error: Vec<f32>,
    /// From the samples' variance (steady: adaptive pixels' test and the error map), likewise.
    pub sample_error: Vec<f32>,
    /// Whether a camera ray of the pixel met a light before any surface (such pixels are left
    /// out of [`PixelErrors::relative_rmse`]), likewise.
    pub lit: Vec<bool>,
    /// The image's mean brightness `m` from the pilot, which the test normalises by.
    pub image_mean: f32,
}

impl PixelErrors {
    /// Returns the image's relative RMSE estimated from the pixels' errors: the root mean
    /// square of their standard errors over the mean of `pixels` (the image they estimate, as
    /// `caustic compare` divides by the reference's mean), both over the pixels that see no
    /// light directly (as the planner's pilot measures, and `docs/`'s regions below the light);
    /// `None` without estimates.
    pub fn relative_rmse(&self, pixels: &[glam::Vec3A]) -> Option<f64> {
        let (mut sq, mut n, mut sum, mut m) = (0.0f64, 0usize, 0.0f64, 0usize);
        for (i, p) in pixels.iter().enumerate() {
            if self.lit.get(i).copied().unwrap_or(false) {
                continue;
            }
            sum += p.element_sum() as f64 / 3.0;
            m += 1;
            match self.std_error.get(i) {
                Some(e) if e.is_finite() => {
                    sq += (*e as f64).powi(2);
                    n += 1;
                }
                _ => {}
            }
        }
        let mean = sum / m.max(1) as f64;
        (n > 0 && mean > 0.0).then(|| (sq / n as f64).sqrt() / mean)
    }

    /// Returns how many pixels see a light directly.
    pub fn lit_pixels(&self) -> usize {
        self.lit.iter().filter(|&&l| l).count()
    }
}

impl RenderStats {
    /// Returns the counters of `t` (the rows' sums), with no time, skipped rows or pictures.
    pub fn of_counts(t: &RayCounts) -> RenderStats {
        RenderStats {
            primary_rays: t.primary,
            shadow_rays: t.shadow,
            secondary_rays: t.secondary,
            material_time: Duration::from_nanos(t.material_nanos),
            lookups: t.lookups,
            photons_used: t.photons_used,
            reused: t.reused,
            depth_capped: t.depth_capped,
            nonfinite_samples: t.nonfinite,
            cached: t.cached,
            gathered: t.gathered,
            weak_skipped: t.weak_skipped,
            ..RenderStats::default()
        }
    }

    /// Adds `o`'s counts and time to these (the passes of a progressive render).
    pub fn add(&mut self, o: &RenderStats) {
        self.primary_rays += o.primary_rays;
        self.shadow_rays += o.shadow_rays;
        self.secondary_rays += o.secondary_rays;
        self.time += o.time;
        self.material_time += o.material_time;
        self.lookups += o.lookups;
        self.photons_used += o.photons_used;
        self.reused += o.reused;
        self.depth_capped += o.depth_capped;
        self.nonfinite_samples += o.nonfinite_samples;
        self.cached += o.cached;
        self.gathered += o.gathered;
        self.weak_skipped += o.weak_skipped;
        self.rows_skipped += o.rows_skipped;
    }
}

/// Per-thread ray counts, summed into [`RenderStats`] once per row.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub secondary: u64,
    /// Whether to time material evaluation (textures, bump maps, noise): `--stats` only, since
    /// reading the clock twice per hit costs time of its own.
    pub timing: bool,
    /// Nanoseconds spent evaluating materials, when `timing`.
    pub material_nanos: u64,
    /// Photon-map lookups and the photons they found.
    pub lookups: u64,
    pub photons_used: u64,
    /// Caustic estimates taken from an earlier sample of the same pixel instead of a lookup.
    pub reused: u64,
    /// Eye paths stopped at the hard depth cap ([`crate::integrator::eye::MAX_PATH_DEPTH`]).
    pub depth_capped: u64,
    /// Camera samples whose radiance was NaN or infinite, dropped (counted as black).
    pub nonfinite: u64,
    /// Diffuse points of eye paths served by the irradiance cache, and final-gather points
    /// gathered afresh (no record served them).
    pub cached: u64,
    pub gathered: u64,
    /// Surfaces reached by weak branches left unshaded ([`crate::render::Share`]).
    pub weak_skipped: u64,
}

impl RayCounts {
    /// Adds `o`'s counts to these.
    pub fn add(&mut self, o: &RayCounts) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.secondary += o.secondary;
        self.material_nanos += o.material_nanos;
        self.lookups += o.lookups;
        self.photons_used += o.photons_used;
        self.reused += o.reused;
        self.depth_capped += o.depth_capped;
        self.nonfinite += o.nonfinite;
        self.cached += o.cached;
        self.gathered += o.gathered;
        self.weak_skipped += o.weak_skipped;
    }
}

/// Returns the CPU time the process has used so far, over all its threads (user and system), or
/// `None` where the system does not say (`caustic study` times renders by it).
pub fn process_cpu_time() -> Option<Duration> {
    #[cfg(target_os = "linux")]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::uninit();
        // SAFETY: getrusage writes a whole rusage into the pointer it is given, or fails.
        let ok = unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } == 0;
        if !ok {
            return None;
        }
        // SAFETY: getrusage succeeded, so it initialised the struct.
        let u = unsafe { usage.assume_init() };
        let time = |t: libc::timeval| {
            Duration::from_secs(t.tv_sec.max(0) as u64)
                + Duration::from_micros(t.tv_usec.max(0) as u64)
        };
        Some(time(u.ru_utime) + time(u.ru_stime))
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}
