//! The command line's render options turned into the library's [`Settings`], with every numeric
//! flag checked against its range (a usage error names the flag).

use super::{
    GatherLookup, GiArg, HeatArg, IndirectArg, IntegratorArg, RenderArgs, Switch, TonemapArg,
};
use crate::error::{Error, Result};
use crate::integrator::irradiance_cache::{CacheSettings, DEFAULT_RECORD_RAYS};
use crate::integrator::photon_map::{CAUSTIC_PHOTONS, GLOBAL_PHOTONS, GiSettings, Indirect};
use crate::integrator::plan::Overrides;
use crate::integrator::planner::{Goal, Request};
use crate::integrator::progressive::{
    MAX_PASSES, PASS_CAUSTIC_PHOTONS, PASS_GLOBAL_PHOTONS, ProgressiveSettings,
};
use crate::integrator::{GiMode, Settings};
use crate::io::heatmap::Measure;
use crate::io::image::Tonemap;
use crate::photon::trace::MAX_PHOTONS;
use crate::render::Sampling;
use std::io::IsTerminal;
use std::path::PathBuf;

/// Returns a usage error unless `--scale` is in (0, 16].
pub fn check_scale(scale: f64) -> Result<()> {
    if scale > 0.0 && scale <= 16.0 {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "--scale must be in (0, 16], got {scale}"
        )))
    }
}

/// Returns a usage error unless the photon count of flag `flag` is at most [`MAX_PHOTONS`].
pub fn check_photons(flag: &str, photons: u64) -> Result<()> {
    if photons <= MAX_PHOTONS {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "{flag} must be at most {MAX_PHOTONS}, got {photons}"
        )))
    }
}

/// What `caustic render` does with each image, checked: the frame's settings and what the
/// command line adds around them.
pub struct RenderJob {
    /// The frame's settings, passed to [`crate::frame::render_desc`] unchanged.
    pub settings: Settings,
    /// Multiple of the script's image size.
    pub scale: f64,
    /// The window to render, `[x0, y0, x1, y1]`.
    pub crop: Option<[u32; 4]>,
    pub tonemap: Tonemap,
    /// Where to write the camera-ray count image.
    pub aa_map: Option<PathBuf>,
    /// Where to write each pixel's estimated relative error (`--error-map`).
    pub error_map: Option<PathBuf>,
    /// Where to write a progressive render's pass sums (`--save-passes`).
    pub save_passes: Option<PathBuf>,
    /// What `--heatmap` shows.
    pub heatmap: Option<Measure>,
    /// Print counters and timings.
    pub stats: bool,
    /// Show a progress bar.
    pub progress: bool,
    /// Whether `--spp`, a photon count or scale, and `--cache-rays` were typed: what a time
    /// budget leaves as it is.
    pub typed: (bool, bool, bool),
}

impl RenderJob {
    /// Returns the job the arguments ask for, or a usage error naming the flag out of range.
    pub fn from_args(a: &RenderArgs) -> Result<RenderJob> {
        // First: it checks --time-budget's and --target-error's ranges for both integrators.
        let budget = budget_request(a, a.integrator == IntegratorArg::Progressive)?;
        let progressive = progressive_settings(a)?;
        let sampling = sampling(a, progressive.is_some())?;
        let photons = photon_settings(a, progressive.is_some())?;
        let tonemap = tonemap(a)?;
        if let Some(e) = a.force.iter().find(|e| a.disable.contains(e)) {
            return Err(Error::Usage(format!(
                "--force {0} and --disable {0} contradict each other",
                e.name()
            )));
        }
        if let Some(map) = &a.error_map {
            check_error_map(map, &sampling, progressive.is_some())?;
        }
        if a.heatmap.is_some() && progressive.is_some() {
            return Err(Error::Usage(
                "--heatmap: the progressive integrator has no single camera pass to measure".into(),
            ));
        }
        let settings = Settings {
            seed: a.seed,
            sampling,
            light_samples: a.light_samples,
            timing: a.stats,
            heatmap: a.heatmap.is_some(),
            error_estimate: a.error_map.is_some(),
            gi: match a.gi {
                GiArg::Auto => GiMode::Auto,
                GiArg::On => GiMode::On,
                GiArg::Off => GiMode::Off,
            },
            overrides: Overrides {
                force: a.force.clone(),
                disable: a.disable.clone(),
            },
            photons,
            progressive,
            maps_file: a.photon_maps.clone(),
            budget,
        };
        Ok(RenderJob {
            settings,
            scale: a.scale,
            crop: a.crop,
            tonemap,
            aa_map: a.aa_map.clone(),
            error_map: a.error_map.clone(),
            save_passes: a.save_passes.clone(),
            heatmap: a.heatmap.map(|h| match h {
                HeatArg::Nodes => Measure::Nodes,
                HeatArg::Triangles => Measure::Triangles,
                HeatArg::Time => Measure::Time,
            }),
            stats: a.stats,
            progress: !a.quiet && std::io::stderr().is_terminal(),
            typed: typed(a),
        })
    }
}

/// Returns the pixel sampling the arguments ask for (one jittered sample per pass by default
/// for a `progressive` render), or a usage error for `--spp`, `--aa-threshold`, `--aa-depth`
/// or `--light-samples` out of range.
fn sampling(a: &RenderArgs, progressive: bool) -> Result<Sampling> {
    let spp = a.spp.unwrap_or(if progressive {
        1
    } else {
        crate::integrator::DEFAULT_SPP
    });
    if spp == 0 || spp > 1 << 16 {
        return Err(Error::Usage(format!(
            "--spp must be in [1, 65536], got {spp}"
        )));
    }
    if !(a.aa_threshold >= 0.0 && a.aa_threshold.is_finite()) || a.aa_depth > 8 {
        return Err(Error::Usage(
            "--aa-threshold must be >= 0 and --aa-depth at most 8".into(),
        ));
    }
    check_count("--light-samples", a.light_samples.into(), 4096)?;
    if let Some(target) = a.noise_target {
        return noise_sampling(a, spp, target, progressive);
    }
    if a.max_spp.is_some() {
        return Err(Error::Usage(
            "--max-spp bounds adaptive pixels: give --noise-target too".into(),
        ));
    }
    Ok(if a.adaptive {
        Sampling::Adaptive {
            threshold: a.aa_threshold,
            max_depth: a.aa_depth,
        }
    } else {
        Sampling::Stratified { spp }
    })
}

/// Returns noise-driven adaptive sampling to `target` from `spp` samples, or a usage error for
/// a target or `--max-spp` out of range or a sampling it cannot combine with.
fn noise_sampling(a: &RenderArgs, spp: u32, target: f32, progressive: bool) -> Result<Sampling> {
    use crate::render::noise::MAX_SPP;
    if !(target > 0.0 && target <= 10.0) {
        return Err(Error::Usage(format!(
            "--noise-target must be in (0, 10], got {target}"
        )));
    }
    if progressive || a.adaptive {
        let other = if a.adaptive {
            "--adaptive"
        } else {
            "--integrator progressive"
        };
        return Err(Error::Usage(format!(
            "--noise-target samples pixels its own way: it cannot be combined with {other}"
        )));
    }
    if spp < 2 {
        return Err(Error::Usage(format!(
            "--noise-target needs --spp 2 or more (two half-buffers to estimate a pixel's \
             error), got {spp}"
        )));
    }
    let max_spp = a.max_spp.unwrap_or((64 * spp).min(MAX_SPP));
    if max_spp < spp || max_spp > MAX_SPP {
        return Err(Error::Usage(format!(
            "--max-spp must be in [--spp, {MAX_SPP}] = [{spp}, {MAX_SPP}], got {max_spp}"
        )));
    }
    Ok(Sampling::Noise {
        spp,
        max_spp,
        target,
    })
}

/// Returns a usage error unless `--error-map MAP` can be written for `sampling`: a `.png` or
/// `.exr` name, and samples to split into halves.
fn check_error_map(map: &std::path::Path, sampling: &Sampling, progressive: bool) -> Result<()> {
    let ext = map
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("png" | "exr")) {
        return Err(Error::Usage(format!(
            "--error-map {}: the map is written as .png or .exr",
            map.display()
        )));
    }
    let why = match sampling {
        _ if progressive => {
            Some("the progressive integrator estimates its error per pass (--target-error)")
        }
        Sampling::Adaptive { .. } => Some("--adaptive's corner rays have no half-buffers"),
        Sampling::Stratified { spp: 1 } => {
            Some("one sample a pixel has no half-buffers: give --spp 2 or more")
        }
        _ => None,
    };
    match why {
        Some(why) => Err(Error::Usage(format!("--error-map: {why}"))),
        None => Ok(()),
    }
}

/// Returns the photon passes' settings the arguments ask for (a `progressive` render's
/// per-pass photon counts by default), or a usage error naming the flag out of range.
fn photon_settings(a: &RenderArgs, progressive: bool) -> Result<GiSettings> {
    let photon_scale = a.photon_scale.unwrap_or(1.0);
    if !(0.0..=1e3).contains(&photon_scale) {
        return Err(Error::Usage(format!(
            "--photon-scale must be in [0, 1000], got {photon_scale}"
        )));
    }
    let (photons, caustic_photons) = match progressive {
        true => (PASS_GLOBAL_PHOTONS, PASS_CAUSTIC_PHOTONS),
        false => (GLOBAL_PHOTONS, CAUSTIC_PHOTONS),
    };
    let photons = a.photons.unwrap_or(photons);
    let caustic_photons = a.caustic_photons.unwrap_or(caustic_photons);
    check_photons("--photons", photons)?;
    check_photons("--caustic-photons", caustic_photons)?;
    check_count("--photon-k", a.photon_k as u64, 10_000)?;
    check_count("--gather-rays", a.gather_rays.into(), 65_536)?;
    let cache_rays = a.cache_rays.unwrap_or(DEFAULT_RECORD_RAYS);
    check_count("--cache-rays", cache_rays.into(), 65_536)?;
    if !(a.cache_accuracy > 0.0 && a.cache_accuracy <= 1.0) {
        return Err(Error::Usage(format!(
            "--cache-accuracy must be in (0, 1], got {}",
            a.cache_accuracy
        )));
    }
    Ok(GiSettings {
        seed: a.seed,
        photons,
        caustic_photons,
        photon_scale,
        follow_image: a.photons.is_none()
            && a.caustic_photons.is_none()
            && a.photon_scale.is_none(),
        k: a.photon_k,
        indirect: match a.indirect {
            IndirectArg::Gather => Indirect::Gather {
                rays: a.gather_rays,
            },
            IndirectArg::Direct => Indirect::Direct,
        },
        precompute: a.gather_lookup == GatherLookup::Precomputed,
        cache: CacheSettings {
            enabled: a.irradiance_cache == Switch::On,
            accuracy: a.cache_accuracy,
            rays: cache_rays,
        },
        ..GiSettings::default()
    })
}

/// Returns a usage error naming `flag` when `value` is not in `[1, max]`.
fn check_count(flag: &str, value: u64, max: u64) -> Result<()> {
    if !(1..=max).contains(&value) {
        return Err(Error::Usage(format!(
            "{flag} must be in [1, {max}], got {value}"
        )));
    }
    Ok(())
}

/// Returns the tone map the arguments ask for, or a usage error for an `--exposure` that is
/// not finite.
fn tonemap(a: &RenderArgs) -> Result<Tonemap> {
    if !a.exposure.is_finite() {
        return Err(Error::Usage("--exposure must be finite".into()));
    }
    Ok(match a.tonemap {
        TonemapArg::Clamp => Tonemap::Clamp,
        TonemapArg::Srgb => Tonemap::Srgb {
            exposure: a.exposure,
        },
    })
}

/// Returns the time planner's request for a photon-mapped render with `--time-budget` or
/// `--target-error` (`None` without either, or for a progressive render, which stops on them
/// instead), or a usage error for a value out of range or a flag the planner cannot honour.
fn budget_request(a: &RenderArgs, progressive: bool) -> Result<Option<Request>> {
    let usage = |m: String| Err(Error::Usage(m));
    if let Some(e) = a.target_error
        && !(e > 0.0 && e <= 10.0)
    {
        return usage(format!("--target-error must be in (0, 10], got {e}"));
    }
    if let Some(s) = a.time_budget
        && !(s > 0.0 && s <= 1e7)
    {
        return usage(format!(
            "--time-budget must be in (0, 1e7] seconds, got {s}"
        ));
    }
    let goal = match (a.time_budget, a.target_error) {
        _ if progressive => return Ok(None),
        (None, None) => return Ok(None),
        (Some(_), Some(_)) => {
            return usage(
                "--time-budget and --target-error: a photon-mapped render plans for one of them"
                    .into(),
            );
        }
        (Some(s), None) => Goal::Time(std::time::Duration::from_secs_f64(s)),
        (None, Some(e)) => Goal::Error(e),
    };
    let flag = if a.time_budget.is_some() {
        "--time-budget"
    } else {
        "--target-error"
    };
    let conflicts = [
        ("--noise-target", a.noise_target.is_some()),
        ("--adaptive", a.adaptive),
        ("--photon-maps", a.photon_maps.is_some()),
    ];
    if let Some((other, _)) = conflicts.iter().find(|c| c.1) {
        return usage(format!(
            "{flag} plans the samples and the photon maps itself: it cannot be combined with \
             {other}"
        ));
    }
    let (fixed_spp, fixed_photons, fixed_cache_rays) = typed(a);
    Ok(Some(Request {
        goal,
        fixed_spp,
        fixed_photons,
        fixed_cache_rays,
    }))
}

/// Returns whether `--spp`, a photon count or `--photon-scale`, and `--cache-rays` are given.
fn typed(a: &RenderArgs) -> (bool, bool, bool) {
    let photons = a.photons.is_some() || a.caustic_photons.is_some() || a.photon_scale.is_some();
    (a.spp.is_some(), photons, a.cache_rays.is_some())
}

/// Returns the progressive settings the arguments ask for (`None` without `--integrator
/// progressive`), or a usage error naming the flag out of range or given without it.
fn progressive_settings(a: &RenderArgs) -> Result<Option<ProgressiveSettings>> {
    let usage = |m: String| Err(Error::Usage(m));
    if a.integrator != IntegratorArg::Progressive {
        let given = [
            ("--passes", a.passes.is_some()),
            ("--radius", a.radius.is_some()),
            ("--local-radii", a.local_radii.is_some()),
            ("--write-every", a.write_every.is_some()),
            ("--first-pass", a.first_pass.is_some()),
            ("--save-passes", a.save_passes.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|g| g.1) {
            return usage(format!("{flag} needs --integrator progressive"));
        }
        return Ok(None);
    }
    if a.adaptive {
        return usage(
            "--adaptive has no progressive form; progressive passes jitter --spp samples".into(),
        );
    }
    if a.gi == GiArg::Off {
        return usage("--integrator progressive is photon mapping; it contradicts --gi off".into());
    }
    let bounded = a.target_error.is_some() || a.time_budget.is_some();
    let passes = a.passes.unwrap_or(if bounded {
        MAX_PASSES
    } else {
        crate::integrator::progressive::DEFAULT_PASSES
    });
    if !(1..=MAX_PASSES).contains(&passes) {
        return usage(format!(
            "--passes must be in [1, {MAX_PASSES}], got {passes}"
        ));
    }
    if !(a.alpha > 0.0 && a.alpha < 1.0) {
        return usage(format!("--alpha must be in (0, 1), got {}", a.alpha));
    }
    if let Some(r) = a.radius
        && !(r > 0.0 && r <= 1.0)
    {
        return usage(format!(
            "--radius must be in (0, 1] (of the scene's diagonal), got {r}"
        ));
    }
    if a.write_every == Some(0) {
        return usage("--write-every must be at least 1".into());
    }
    let first_pass = a.first_pass.unwrap_or(0);
    if first_pass.saturating_add(passes) > MAX_PASSES {
        return usage(format!(
            "--first-pass {first_pass} with --passes {passes} runs passes beyond {MAX_PASSES}"
        ));
    }
    Ok(Some(ProgressiveSettings {
        passes,
        alpha: a.alpha,
        initial_radius: a.radius,
        target_error: a.target_error,
        time_budget: a.time_budget.map(std::time::Duration::from_secs_f64),
        snapshot_every: a.write_every,
        first_pass,
        local_radii: a.local_radii != Some(Switch::Off),
    }))
}
