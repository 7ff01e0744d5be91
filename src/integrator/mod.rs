//! Integrators: how light transport is computed for one frame, a closed family ([`Integrator`]),
//! one file per method, each a short list of named phases.
//!
//! - [`whitted`]: the course's ray tracer. Phases: camera pass.
//! - [`photon_map`]: Jensen's photon mapping. Phases: the prepass (trace photons, build maps,
//!   precompute irradiance: [`precomputed`], cache irradiance: [`irradiance_cache`]), camera
//!   pass. The prepass
//!   can be saved to a file and read back by a tile of a farm ([`maps_file`]).
//! - [`progressive`]: progressive photon mapping, the consistent reference. Phases, per pass:
//!   trace photons, build maps, camera pass with shrinking radii; then the mean of the passes.
//!
//! All share the eye path ([`eye`]): direct light by shadow rays and deterministic specular
//! splitting through the one scattering model ([`crate::material::bsdf`]); they differ in what a
//! diffuse surface receives besides direct light ([`eye::DiffuseTerm`]) and in how the photon
//! estimates choose their photons (the `k` nearest, or a radius that shrinks with passes). Which one a frame uses,
//! and which of its effects, is the effect plan's decision ([`mod@plan`]).
//!
//! To add an integrator: a variant here, a file beside these with its phases, and its case in
//! [`Integrator::render`] and in [`plan::plan`].

pub mod eye;
pub mod irradiance_cache;
pub mod local_radii;
pub mod maps_file;
pub mod mis;
pub mod passes_file;
pub mod photon_map;
pub mod plan;
pub mod planner;
pub mod precomputed;
pub mod progressive;
pub mod whitted;

use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::stats::RenderStats;

pub use plan::{GiMode, Plan, plan};

/// What a frame renders: `window` of the image of `scene` seen through `camera`.
#[derive(Clone, Copy)]
pub struct View<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub window: Window,
}

/// The light-transport methods caustic implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Whitted-style ray tracing with the course's ambient term (the A4 renderer).
    Whitted,
    /// Photon mapping: caustic and global maps, final gathering or the global map seen directly.
    PhotonMap,
    /// Progressive photon mapping: passes of photon mapping with shrinking radii, averaged.
    Progressive,
}

/// What shapes a frame besides the scene, the camera and the window.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Seed of every random stream (the camera pass's; the photon passes take
    /// `photons.seed`).
    pub seed: u64,
    pub sampling: crate::render::Sampling,
    /// Shadow-ray samples per area or sphere light at each shaded point.
    pub light_samples: u32,
    /// Whether to simulate global illumination (`--gi`).
    pub gi: GiMode,
    /// `--force` and `--disable` (see [`mod@plan`]).
    pub overrides: plan::Overrides,
    /// The photon passes and estimates (photon-mapping integrators; per pass for the
    /// progressive one).
    pub photons: photon_map::GiSettings,
    /// Render progressively (`--integrator progressive`) with these settings.
    pub progressive: Option<progressive::ProgressiveSettings>,
    /// `--photon-maps`: read the frame's photon-map prepass from this file instead of making
    /// it ([`maps_file`]; [`crate::frame::render_desc`] loads it).
    pub maps_file: Option<std::path::PathBuf>,
    /// Time material evaluation for `--stats`.
    pub timing: bool,
    /// Record each pixel's traversal counts and time (`--heatmap`; needs
    /// [`crate::accel::counters::enable`]).
    pub heatmap: bool,
    /// Estimate each pixel's error from its half-buffers (`--error-map`; noise sampling always
    /// does): [`RenderStats::error`].
    pub error_estimate: bool,
    /// `--time-budget` or `--target-error` for the photon-map integrator: the planner chooses
    /// samples and prepass effort ([`planner`]).
    pub budget: Option<planner::Request>,
}

/// Camera samples per pixel by default. A pixel is an area: one centre ray (the course's, and
/// `--spp 1`) aliases every edge, which against a box-filtered reference is a bias no photon
/// count removes (a mirror ball's reflected light: 4.7% block bias at one ray, 0.9% at four).
/// The per-sample counts below are a quarter of what one ray per pixel used to take, so a
/// photon-mapped pixel costs about the same: final gathering dominates and its rays per pixel
/// are unchanged.
pub const DEFAULT_SPP: u32 = 4;

/// Shadow rays per area or sphere light per camera sample (16 per pixel at [`DEFAULT_SPP`]).
pub const DEFAULT_LIGHT_SAMPLES: u32 = 4;

/// Final-gather rays per camera sample (64 per pixel at [`DEFAULT_SPP`]).
pub const DEFAULT_GATHER_RAYS: u32 = 16;

impl Default for Settings {
    /// Returns the defaults: [`DEFAULT_SPP`] stratified samples per pixel, photon maps when a
    /// light asks.
    fn default() -> Settings {
        Settings {
            seed: 0,
            sampling: crate::render::Sampling::Stratified { spp: DEFAULT_SPP },
            light_samples: DEFAULT_LIGHT_SAMPLES,
            gi: GiMode::Auto,
            overrides: plan::Overrides::default(),
            photons: photon_map::GiSettings::default(),
            progressive: None,
            maps_file: None,
            timing: false,
            heatmap: false,
            error_estimate: false,
            budget: None,
        }
    }
}

/// What a frame reports besides its film, for `--stats`.
#[derive(Debug)]
pub struct Stats {
    pub plan: Plan,
    /// The camera pass's counters.
    pub render: RenderStats,
    /// The photon passes' counters, when the frame traced photons (summed over passes).
    pub photons: Option<photon_map::GiStats>,
    /// The passes, radii and estimated error of a progressive render.
    pub progressive: Option<progressive::ProgressiveStats>,
    /// How much of the frame was done when it was asked to stop
    /// ([`Progress::should_stop`]); `None` for a finished frame.
    pub interrupted: Option<Partial>,
}

/// What an interrupted frame's film holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Partial {
    /// The camera pass rendered `done` of the window's `rows` rows; the others are black, with
    /// no samples.
    Rows { done: u32, rows: u32 },
    /// A progressive render finished `done` passes (of at most `planned`); the film is their
    /// mean, every pixel rendered.
    Passes { done: u32, planned: u32 },
}

impl Partial {
    /// Returns what the film of a camera pass that skipped `stats.rows_skipped` of its `rows`
    /// rows holds, or `None` when it skipped none.
    pub fn of_rows(stats: &RenderStats, rows: u32) -> Option<Partial> {
        (stats.rows_skipped > 0).then(|| Partial::Rows {
            done: rows.saturating_sub(stats.rows_skipped as u32),
            rows,
        })
    }

    /// Returns true when the film holds no rendered pixel at all.
    pub fn is_empty(&self) -> bool {
        match *self {
            Partial::Rows { done, .. } | Partial::Passes { done, .. } => done == 0,
        }
    }
}

impl std::fmt::Display for Partial {
    /// Writes what the film holds: `37% of rows (37 of 100; the others black)` or `the mean of
    /// 12 passes (of at most 64)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Partial::Rows { done, rows } => write!(
                f,
                "{}% of rows ({done} of {rows}; the others black)",
                (100 * done as u64) / rows.max(1) as u64
            ),
            Partial::Passes { done, planned } => {
                write!(f, "the mean of {done} passes (of at most {planned})")
            }
        }
    }
}

impl Integrator {
    /// Renders `view` with this integrator as `plan` says, running its phases in turn and
    /// reporting each to `progress`. `read` is a photon-map prepass read from a file
    /// ([`maps_file::load`], which refuses a frame of another integrator); the others never get
    /// one.
    pub fn render(
        self,
        view: View,
        settings: &Settings,
        plan: Plan,
        read: Option<photon_map::Prepass>,
        progress: &dyn Progress,
    ) -> (Film, Stats) {
        debug_assert!(read.is_none() || self == Integrator::PhotonMap);
        let rows = view.window.size().1;
        let stats = |plan, render: RenderStats, photons| Stats {
            plan,
            interrupted: Partial::of_rows(&render, rows),
            render,
            photons,
            progressive: None,
        };
        match self {
            Integrator::Whitted => {
                let (film, render) = whitted::render(view, settings, progress);
                (film, stats(plan, render, None))
            }
            Integrator::PhotonMap => {
                let (film, render, photons) =
                    photon_map::render(view, settings, &plan, read, progress);
                (film, stats(plan, render, Some(photons)))
            }
            Integrator::Progressive => progressive::render(view, settings, plan, progress),
        }
    }
}

/// Runs the camera pass of `view`: the eye path with the integrator's `diffuse` term, reporting
/// rows to `progress`.
fn camera_pass(
    view: View,
    diffuse: eye::DiffuseTerm,
    settings: &Settings,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    let View {
        scene,
        camera,
        window,
    } = view;
    let tracer = eye::Tracer {
        scene,
        camera,
        light_samples: settings.light_samples,
        diffuse,
    };
    let opts = crate::render::PassOptions {
        seed: settings.seed,
        sampling: settings.sampling.clone(),
        window,
        timing: settings.timing,
        heatmap: settings.heatmap,
        error_estimate: settings.error_estimate,
    };
    progress.start("rendering rows", window.size().1 as u64);
    crate::render::camera_pass(camera, &tracer, &opts, progress)
}
