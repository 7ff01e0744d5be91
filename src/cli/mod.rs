//! The command line: clap's arguments ([`Cli`]), turned into the library's settings
//! ([`settings`]), each command a call into the library ([`crate::frame`]), and what it prints
//! ([`report`]). No pass is wired here.

pub mod report;
pub mod settings;
pub mod study;

use crate::camera::Camera;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::frame;
use crate::integrator::plan::Effect;
use crate::integrator::progressive::Stop;
use crate::integrator::{DEFAULT_GATHER_RAYS, DEFAULT_LIGHT_SAMPLES};
use crate::io::image::{Tonemap, write_image, write_sample_map};
use crate::lua::globals::Global;
use crate::lua::{Dialect, ScriptOptions, run_script_with};
use crate::metrics::Region;
use crate::scene::build::build_scene;
use clap::{Args, Parser, Subcommand};
use report::Bar;
use settings::RenderJob;
use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

/// Most worker threads `--threads` accepts.
pub const MAX_THREADS: usize = 1024;

/// caustic: a photon-mapping ray tracer for CS488 Lua scenes.
#[derive(Debug, Parser)]
#[command(name = "caustic", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene script; every gr.render call renders and writes its image.
    Render(RenderArgs),
    /// Run a scene script without rendering and summarise what it describes.
    Info(InfoArgs),
    /// Assemble tiles rendered with --crop into the full image.
    Stitch(StitchArgs),
    /// Trace a scene's photons and draw them from its camera (global: dots; caustic: crosses).
    Photons(PhotonsArgs),
    /// Write a scene as a Mitsuba 3 XML scene (spheres, cubes, meshes; diffuse, mirror and
    /// dielectric materials; point, area and sphere lights), for validation.
    ExportMitsuba(ExportArgs),
    /// Compare an image with a reference: mean ratio, mean error, RMSE, relative RMSE and 8x8
    /// block bias, over the image or a region.
    Diff(DiffArgs),
    /// Render a scene over a grid of settings and seeds and measure each against a reference:
    /// a CSV, a Markdown table and a plot of error against time with the Pareto front.
    Study(study::StudyArgs),
}

#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The image to judge (EXR, PFM or HDR for linear values; PNG and JPEG compare their 8-bit
    /// codes).
    pub image: PathBuf,
    /// The reference.
    pub reference: PathBuf,
    /// A second, independent reference: the metrics are then against the truth as estimated
    /// from both, and the references' own noise drops out.
    #[arg(long, value_name = "REF2")]
    pub second: Option<PathBuf>,
    /// Only the window x0,y0,x1,y1 (pixels, end exclusive).
    #[arg(long, value_name = "x0,y0,x1,y1", value_delimiter = ',')]
    pub region: Option<Vec<u32>>,
    /// Write a false-colour difference picture (red brighter, blue darker) as PNG.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: Option<PathBuf>,
    /// Contrast of the difference picture, relative to the reference's 99th percentile.
    #[arg(long, value_name = "G", default_value_t = 4.0)]
    pub gain: f32,
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The Lua scene script (its first gr.render is exported).
    pub scene: PathBuf,
    #[command(flatten)]
    pub script: ScriptArgs,
    /// The XML file to write; meshes are written beside it.
    #[arg(short, long, value_name = "OUT.xml")]
    pub output: PathBuf,
    /// Export at this multiple of the script's image size.
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    pub scale: f64,
    /// Samples per pixel of the Mitsuba render.
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub spp: u32,
}

#[derive(Debug, Args)]
pub struct PhotonsArgs {
    /// Write the photon maps a render with these flags would trace to FILE (versioned,
    /// checksummed, with the scene's and the settings' fingerprint) for `caustic render
    /// --photon-maps FILE`, instead of drawing them.
    #[arg(long, value_name = "FILE")]
    pub save: Option<PathBuf>,
    /// Every `caustic render` flag, so that the maps traced are the ones a render with the
    /// same flags traces (photon counts, --photon-scale, --seed, --scale, --force, --disable,
    /// the scene's gr.settings); without --save, -o names the picture of the photons (default:
    /// the script's image name with `_photons` added).
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The Lua scene script.
    pub scene: PathBuf,
    /// The words after `render` on the command line as typed, so a scene's `gr.settings` can
    /// be applied under them ([`Cli::from_env`] fills it; empty, the scene's settings apply
    /// alone over these arguments' other values).
    #[arg(skip)]
    pub argv: Vec<std::ffi::OsString>,
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Write the image here instead of the script's file name (scripts that render one image).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Seed of every random stream, so a render is repeatable.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Print counters and timings for each image.
    #[arg(long)]
    pub stats: bool,
    /// Render at this multiple of the script's image size (0.25 for a quick preview).
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    pub scale: f64,
    /// Stratified samples per pixel (1 = one ray through the pixel centre, as the course; the
    /// default anti-aliases) [default: 4; per pass with --integrator progressive: 1, jittered].
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Adaptive anti-aliasing: trace pixel corners and refine where they differ (replaces --spp).
    #[arg(long)]
    pub adaptive: bool,
    /// Adaptive: refine a square whose corners differ by more than this in any channel.
    #[arg(long, value_name = "T", default_value_t = 0.1)]
    pub aa_threshold: f32,
    /// Adaptive: split a pixel at most this many times (up to (2^D+1)² rays per pixel).
    #[arg(long, value_name = "D", default_value_t = 3)]
    pub aa_depth: u32,
    /// Also write a grey image of how many camera rays each pixel took (white = most).
    #[arg(long, value_name = "OUT.png")]
    pub aa_map: Option<PathBuf>,
    /// Render only the window x0,y0,x1,y1 (pixels, end exclusive) of each image, as a tile for
    /// `caustic stitch`.
    #[arg(long, value_name = "x0,y0,x1,y1", value_parser = parse_crop)]
    pub crop: Option<[u32; 4]>,
    /// How radiance becomes 8-bit PNG values: clamp (the course's) or srgb (exposure + sRGB curve).
    #[arg(long, value_enum, default_value_t = TonemapArg::Clamp)]
    pub tonemap: TonemapArg,
    /// Exposure in stops for --tonemap srgb (radiance is multiplied by 2^E).
    #[arg(long, value_name = "E", default_value_t = 0.0)]
    pub exposure: f32,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// On Ctrl-C (SIGINT), end at once and write nothing, instead of stopping and writing what
    /// was rendered as NAME.partial.EXT (exit status 130 either way).
    #[arg(long)]
    pub no_partial: bool,
    /// Shadow-ray samples per area or sphere light at each shaded point (soft shadows).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_LIGHT_SAMPLES)]
    pub light_samples: u32,
    /// Photon mapping: auto (when a light has power or num_photons), on, or off (ambient term).
    #[arg(long, value_enum, default_value_t = GiArg::Auto)]
    pub gi: GiArg,
    /// The integrator: auto (the plan's: photon mapping or the course's ray tracer) or
    /// progressive (alias sppm; progressive photon mapping, the consistent reference: passes with
    /// shrinking radii, averaged; photon counts and --spp are then per pass).
    #[arg(long, value_enum, default_value_t = IntegratorArg::Auto)]
    pub integrator: IntegratorArg,
    /// Progressive: passes to run [default: 64; with --target-error or --time-budget, at most
    /// 1048576].
    #[arg(long, value_name = "N")]
    pub passes: Option<u32>,
    /// Progressive: radius reduction alpha in (0, 1) (r² shrinks by (i + alpha)/(i + 1) after
    /// pass i).
    #[arg(long, value_name = "A", default_value_t = crate::integrator::progressive::DEFAULT_ALPHA)]
    pub alpha: f32,
    /// Progressive: the first pass's global-map radius as a fraction of the scene's diagonal
    /// (the caustic map's is half) [default: from the photon density, about k photons].
    #[arg(long, value_name = "F")]
    pub radius: Option<f32>,
    /// Progressive: stop once the relative RMSE estimated from the even and odd passes is at
    /// most E (noise only; see docs/accuracy.md).
    #[arg(long, value_name = "E")]
    pub target_error: Option<f64>,
    /// Progressive: stop before a pass that would end after S seconds.
    #[arg(long, value_name = "S")]
    pub time_budget: Option<f64>,
    /// Progressive: write the running image to the output every K passes.
    #[arg(long, value_name = "K")]
    pub write_every: Option<u32>,
    /// Simulate EFFECT whatever the plan decides: photon-maps, caustics, final-gathering,
    /// refraction, soft-shadows, textures, normal-maps or noise (repeatable; `caustic info`
    /// and --stats print the plan and its reasons).
    #[arg(long, value_name = "EFFECT", value_parser = parse_effect)]
    pub force: Vec<Effect>,
    /// Do not simulate EFFECT: photon-maps, caustics, final-gathering, refraction (transparent
    /// surfaces turn opaque), soft-shadows (area lights sampled at their centre), textures,
    /// normal-maps or noise (repeatable).
    #[arg(long, value_name = "EFFECT", value_parser = parse_effect)]
    pub disable: Vec<Effect>,
    /// Photons for the global map, shared by lights without num_photons in proportion to their
    /// power [default: 200000]. Setting it (or --caustic-photons, or --photon-scale) stops the
    /// counts from following --scale.
    #[arg(long, value_name = "N")]
    pub photons: Option<u64>,
    /// Photons for the caustic map, shared the same way (more than the global map's: caustics are
    /// seen directly, not through final gathering) [default: 2000000].
    #[arg(long, value_name = "N")]
    pub caustic_photons: Option<u64>,
    /// Indirect diffuse light: gather (final gathering, accurate) or direct (the global map seen
    /// directly, fast and blotchy).
    #[arg(long, value_enum, default_value_t = IndirectArg::Gather)]
    pub indirect: IndirectArg,
    /// Final-gather rays per shaded point (per camera sample).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_GATHER_RAYS)]
    pub gather_rays: u32,
    /// What a final-gather ray reads where it lands: precomputed (irradiance computed beforehand
    /// at about one global photon in four, Christensen's method, fast) or estimate (a density estimate
    /// at the hit, slower and sharper).
    #[arg(long, value_enum, default_value_t = GatherLookup::Precomputed)]
    pub gather_lookup: GatherLookup,
    /// Final gathering interpolates an irradiance cache: on (gather at a few thousand records,
    /// placed where the light can change, with --cache-rays each, and interpolate between them;
    /// points no record serves are gathered as before) or off (gather at every camera sample).
    /// The progressive integrator never caches.
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub irradiance_cache: Switch,
    /// Irradiance cache accuracy a in (0, 1]: a record serves points within a times its mean
    /// distance to other surfaces (smaller: more records, closer to --irradiance-cache off).
    #[arg(long, value_name = "A", default_value_t = crate::integrator::irradiance_cache::DEFAULT_ACCURACY)]
    pub cache_accuracy: f32,
    /// Gather rays per irradiance-cache record.
    #[arg(long, value_name = "N", default_value_t = crate::integrator::irradiance_cache::DEFAULT_RECORD_RAYS)]
    pub cache_rays: u32,
    /// Nearest photons per density estimate.
    #[arg(long, value_name = "K", default_value_t = 50)]
    pub photon_k: usize,
    /// Multiply every light's photon count by F, the scene's num_photons included [default: 1,
    /// times the image's pixels over the script's: a --scale 0.25 preview traces a sixteenth].
    #[arg(long, value_name = "F")]
    pub photon_scale: Option<f64>,
    /// What a missing or unreadable texture is: an error (default), or a warning (once per file)
    /// with the material rendered in its kd colour.
    #[arg(long, value_enum, default_value_t = MissingTextures::Error)]
    pub missing_textures: MissingTextures,
    /// Read the photon maps from FILE (written by `caustic photons SCENE --save FILE` with the
    /// same photon flags) instead of tracing them: every tile of a farm job shares one photon
    /// pass. A file saved for another scene or other photon settings is refused.
    #[arg(long, value_name = "FILE")]
    pub photon_maps: Option<PathBuf>,
    /// Also write NAME.heat-MEASURE.png beside the image: what each pixel cost in BVH nodes
    /// visited, triangles tested or thread time (over all the rays its shading cast), with a
    /// colour-scale legend. Counting costs nothing measurable when off (docs/profiling.md).
    #[arg(long, value_enum, value_name = "MEASURE")]
    pub heatmap: Option<HeatArg>,
}

/// How a scene script is read: the flags of every command that runs one (`--dialect`, `-D`).
#[derive(Clone, Debug, Args)]
pub struct ScriptArgs {
    /// The era of the course's API the script is written for: modern (Fall 2015 onwards: each
    /// transform call acts in the parent's frame, in call order) or legacy (before: transforms
    /// post-multiply, so a node's last call acts on its geometry first) [default: modern, with a
    /// warning when the script looks legacy].
    #[arg(long, value_enum, value_name = "ERA")]
    pub dialect: Option<DialectArg>,
    /// Set the Lua global NAME to VALUE before the script runs (repeatable): an integer or a
    /// float when VALUE reads as one, true or false, else a string.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = Global::parse)]
    pub define: Vec<Global>,
    /// Stop the script after S seconds of its own running time (its renders not counted)
    /// [default: 300].
    #[arg(long, value_name = "S", value_parser = parse_script_time)]
    pub script_time: Option<std::time::Duration>,
    /// Let the scene read files in DIR and below it too (repeatable); a scene reads only its own
    /// folder's tree by default (docs/security.md).
    #[arg(long, value_name = "DIR")]
    pub allow_read: Vec<PathBuf>,
    /// Run the script with the whole Lua standard library (processes, files, native modules):
    /// only for a script you wrote or trust (docs/security.md).
    #[arg(long)]
    pub trusted_script: bool,
    /// Most memory, in GiB, the scene may take (its description, instances, CSG trees,
    /// triangles, textures and photon maps); over it, the script line or file at fault is an
    /// error [default: half of the machine's physical memory].
    #[arg(long, value_name = "GIB", value_parser = parse_gib)]
    pub memory_budget: Option<u64>,
}

/// Parses `--script-time`: seconds, positive, at most a week.
fn parse_script_time(s: &str) -> Result<std::time::Duration, String> {
    let secs: f64 = s
        .parse()
        .map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if !(secs > 0.0 && secs <= 604_800.0) {
        return Err(format!("must be in (0, 604800] seconds, got {s}"));
    }
    Ok(std::time::Duration::from_secs_f64(secs))
}

/// Parses `--memory-budget`: a positive number of GiB, returned in bytes.
fn parse_gib(s: &str) -> std::result::Result<u64, String> {
    match s.parse::<f64>() {
        Ok(g) if g > 0.0 && g.is_finite() => Ok((g * (1u64 << 30) as f64) as u64),
        _ => Err(format!("expected a positive number of GiB, got '{s}'")),
    }
}

impl ScriptArgs {
    /// Returns the script options these flags ask for.
    pub fn options(&self) -> ScriptOptions {
        ScriptOptions {
            dialect: self.dialect.map(|d| match d {
                DialectArg::Modern => Dialect::Modern,
                DialectArg::Legacy => Dialect::Legacy,
            }),
            globals: self.define.clone(),
            script_time: self.script_time,
            allow_read: self.allow_read.clone(),
            trusted: self.trusted_script,
            watchdog: true,
            memory_budget: self.memory_budget,
            ..ScriptOptions::default()
        }
    }
}

/// The `--dialect` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DialectArg {
    Modern,
    Legacy,
}

/// Parses an effect name of `--force` and `--disable`.
fn parse_effect(name: &str) -> std::result::Result<Effect, String> {
    Effect::parse(name).ok_or_else(|| {
        let names: Vec<&str> = Effect::OVERRIDABLE.iter().map(|e| e.name()).collect();
        format!(
            "unknown effect '{name}'; the effects are {}",
            names.join(", ")
        )
    })
}

/// The `--missing-textures` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MissingTextures {
    Error,
    Warn,
}

/// The `--gi` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GiArg {
    Auto,
    On,
    Off,
}

/// The `--integrator` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IntegratorArg {
    Auto,
    #[value(alias = "sppm")]
    Progressive,
}

/// The `--indirect` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IndirectArg {
    Gather,
    Direct,
}

/// An on/off choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}

/// The `--gather-lookup` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GatherLookup {
    Precomputed,
    Estimate,
}

/// The `--heatmap` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HeatArg {
    Nodes,
    Triangles,
    Time,
}

/// The `--tonemap` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TonemapArg {
    Clamp,
    Srgb,
}

#[derive(Debug, Args)]
pub struct StitchArgs {
    /// Tiles written by `caustic render --crop`, all PNG or all EXR, in any order.
    #[arg(required = true)]
    pub tiles: Vec<PathBuf>,
    /// The full image to write: .png from PNG tiles; .exr, .pfm or .hdr from EXR tiles.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
}

/// Parses `x0,y0,x1,y1`.
fn parse_crop(s: &str) -> std::result::Result<[u32; 4], String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>().map_err(|e| format!("'{p}': {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match v[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        [_, _, _, _] => Err("need x0 < x1 and y0 < y1".into()),
        _ => Err("expected four numbers x0,y0,x1,y1".into()),
    }
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The Lua scene script.
    pub scene: PathBuf,
    #[command(flatten)]
    pub script: ScriptArgs,
}

impl Cli {
    /// Parses the process's command line (exiting with clap's message on a bad one), keeping the
    /// words of `caustic render` for [`RenderArgs::argv`].
    pub fn from_env() -> Cli {
        let mut cli = Cli::parse();
        let argv = || std::env::args_os().skip(2).collect();
        match &mut cli.command {
            Command::Render(a) => a.argv = argv(),
            // The render's words, without --save (which `caustic render` does not take).
            Command::Photons(a) => a.render.argv = without_save(argv()),
            _ => {}
        }
        cli
    }
}

/// Returns `caustic photons`'s words without `--save FILE` (or `--save=FILE`).
fn without_save(words: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let mut out = Vec::with_capacity(words.len());
    let mut words = words.into_iter();
    while let Some(w) = words.next() {
        if w == "--" {
            out.push(w);
            out.extend(words.by_ref());
        } else if w == "--save" {
            words.next();
        } else if !w.to_string_lossy().starts_with("--save=") {
            out.push(w);
        }
    }
    out
}

/// One `caustic render` command line without the binary's name, as `caustic study`'s settings
/// and a scene's `gr.settings` are parsed; a flag given twice takes its last value.
#[derive(Debug, Parser)]
#[command(
    name = "caustic render",
    no_binary_name = true,
    args_override_self = true
)]
pub(crate) struct RenderLine {
    #[command(flatten)]
    pub render: RenderArgs,
}

/// Returns the job of one `gr.render` call when the scene's `gr.settings` (`r.settings`) change
/// `job`: them under the command line's words `argv` (or, without those, under `scene` alone).
fn job_with_settings(
    job: &RenderJob,
    argv: &[std::ffi::OsString],
    scene: &std::path::Path,
    r: &RenderDesc,
) -> Result<Option<RenderJob>> {
    if r.settings.is_empty() {
        return Ok(None);
    }
    let mut line: Vec<std::ffi::OsString> = r.settings.iter().map(Into::into).collect();
    if argv.is_empty() {
        line.push(scene.into());
    } else {
        line.extend(argv.iter().cloned());
    }
    let parsed = RenderLine::try_parse_from(&line).map_err(|e| {
        let text = e.to_string();
        let first = text
            .lines()
            .next()
            .unwrap_or("bad setting")
            .trim_start_matches("error: ");
        Error::at(&r.loc, format!("gr.settings: {first}"))
    })?;
    let mut with = RenderJob::from_args(&parsed.render)
        .map_err(|e| Error::at(&r.loc, format!("gr.settings: {e}")))?;
    // Counts the scene sets still follow the image; only the command line fixes them.
    with.settings.photons.follow_image = job.settings.photons.follow_image;
    Ok(Some(with))
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => render_command(args),
        Command::Info(args) => info_command(args),
        Command::Stitch(args) => {
            let tiles: Vec<&std::path::Path> = args.tiles.iter().map(PathBuf::as_path).collect();
            check_out(&args.output, &tiles)?;
            let s = crate::io::stitch::stitch(&args.tiles, &args.output)?;
            eprintln!(
                "wrote {} ({}x{} from {} tiles)",
                args.output.display(),
                s.width,
                s.height,
                s.tiles
            );
            Ok(())
        }
        Command::Photons(args) => photons_command(args),
        Command::Diff(args) => diff_command(args),
        Command::ExportMitsuba(args) => export_command(args),
        Command::Study(args) => study::study_command(args),
    }
}

/// Starts `n` worker threads for the whole process (`--threads`), or returns a usage error
/// when `n` is out of range.
fn set_threads(n: usize) -> Result<()> {
    if !(1..=MAX_THREADS).contains(&n) {
        return Err(Error::Usage(format!(
            "--threads must be in [1, {MAX_THREADS}], got {n}"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| Error::Usage(format!("cannot start {n} threads: {e}")))
}

/// Returns the window `--region x0,y0,x1,y1` names in a `width × height` image (the whole
/// image without one), or a usage error when it is not a non-empty window inside it.
fn parse_region(region: Option<&[u32]>, width: u32, height: u32) -> Result<Region> {
    match region {
        None => Ok(Region::full(width, height)),
        Some(&[x0, y0, x1, y1]) if x0 < x1 && y0 < y1 && x1 <= width && y1 <= height => {
            Ok(Region { x0, y0, x1, y1 })
        }
        Some(v) => Err(Error::Usage(format!(
            "--region {v:?} is not a non-empty window inside the {width}x{height} image"
        ))),
    }
}

/// Returns an error naming `path` when its image `img` has a NaN or infinite value in
/// `region`: how many such pixels, and the first.
pub(crate) fn check_finite(
    img: &crate::metrics::Image,
    path: &std::path::Path,
    region: Region,
) -> Result<()> {
    match img.non_finite(region) {
        None => Ok(()),
        Some((count, (x, y))) => Err(Error::File {
            path: path.to_path_buf(),
            message: format!(
                "{count} pixels are not finite (NaN or infinite), the first at ({x}, {y}): \
                 no error metric can be computed"
            ),
        }),
    }
}

/// Returns an error naming `out` when it cannot be written ([`crate::files::check_output`]: a
/// special file, a folder that does not exist or cannot be written to) or is the same file as
/// one of `inputs` ([`crate::files::check_not_input`]).
fn check_out(out: &std::path::Path, inputs: &[&std::path::Path]) -> Result<()> {
    crate::files::check_output(out)
        .and_then(|_| crate::files::check_not_input(out, inputs))
        .map_err(|message| Error::File {
            path: out.to_path_buf(),
            message,
        })
}

/// Returns the files `desc` names that a render reads: mesh files, textures and normal maps.
fn scene_inputs(desc: &SceneDesc) -> Vec<&std::path::Path> {
    let meshes = desc.meshes.iter().filter_map(|m| match &m.source {
        crate::desc::MeshSource::File { path, .. } => Some(path.as_path()),
        crate::desc::MeshSource::Inline { .. } => None,
    });
    let images = desc
        .materials
        .iter()
        .flat_map(|m| m.texture.iter().chain(&m.bump))
        .map(PathBuf::as_path);
    meshes.chain(images).collect()
}

/// Returns the command line's inputs of a command that runs `scene`: the script, and the
/// photon-map file `maps` when one is read.
fn script_inputs<'a>(
    scene: &'a std::path::Path,
    maps: Option<&'a PathBuf>,
) -> Vec<&'a std::path::Path> {
    std::iter::once(scene)
        .chain(maps.map(PathBuf::as_path))
        .collect()
}

fn render_command(args: RenderArgs) -> Result<()> {
    settings::check_scale(args.scale)?;
    if args.stats || args.heatmap.is_some() {
        crate::accel::counters::enable();
    }
    if let Some(n) = args.threads {
        set_threads(n)?;
    }
    // The flags' own errors first, then the outputs, then the work.
    let job = RenderJob::from_args(&args)?;
    let inputs = script_inputs(&args.scene, args.photon_maps.as_ref());
    for out in args.output.iter().chain(&args.aa_map) {
        check_out(out, &inputs)?;
    }
    let rendered = Rc::new(Cell::new(0u32));
    let count = Rc::clone(&rendered);
    let output = args.output.clone();
    let (argv, scene) = (args.argv.clone(), args.scene.clone());
    let maps = args.photon_maps.clone();
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        count.set(count.get() + 1);
        let out = match &output {
            None => {
                crate::lua::check_scene_output(&scene, &r.output)
                    .map_err(|m| Error::fault_at(crate::error::Fault::Sandbox, &r.loc, m))?;
                r.output.clone()
            }
            Some(o) if count.get() == 1 => o.clone(),
            Some(_) => {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so -o cannot name its output; run without -o",
                ));
            }
        };
        let mut inputs = script_inputs(&scene, maps.as_ref());
        inputs.extend(scene_inputs(desc));
        match job_with_settings(&job, &argv, &scene, r)? {
            Some(own) => render_one(desc, r, &own, &out, &inputs),
            None => render_one(desc, r, &job, &out, &inputs),
        }
    });
    // Ctrl-C stops the render and writes what it has (crate::interrupt), unless --no-partial.
    if !args.no_partial {
        crate::interrupt::catch_sigint();
    }
    let options = ScriptOptions {
        missing_textures_warn: args.missing_textures == MissingTextures::Warn,
        interruptible: !args.no_partial,
        ..args.script.options()
    };
    run_script_with(&args.scene, hook, options)?;
    if crate::interrupt::requested() {
        // Ctrl-C came as the last image was being written, or after: nothing was lost, but
        // the exit status says the run was interrupted, as it always does.
        return Err(Error::Interrupted(
            "after the script's last image was written; nothing was lost".into(),
        ));
    }
    if rendered.get() == 0 {
        eprintln!(
            "warning: {} never called gr.render; no image written",
            args.scene.display()
        );
    }
    Ok(())
}

/// Returns an error unless every file a render of `out` with `job` may write (the image, the
/// ray-count map, the heatmap, the image of an interrupted render) has a format it can be
/// written in, can be written, and is none of `inputs`: checked before the render is spent.
fn check_render_outputs(
    job: &RenderJob,
    out: &std::path::Path,
    inputs: &[&std::path::Path],
) -> Result<()> {
    let format = crate::io::image::output_format(out)?;
    if job.crop.is_some()
        && !matches!(
            format,
            crate::io::image::Format::Png | crate::io::image::Format::Exr
        )
    {
        return Err(Error::Usage(format!(
            "--crop: {} cannot record the tile's place in the image; name it .png or .exr",
            out.display()
        )));
    }
    if let Some(map) = &job.aa_map
        && crate::io::image::output_format(map)? != crate::io::image::Format::Png
    {
        return Err(Error::Usage(format!(
            "--aa-map {} : the ray-count map is written as PNG; name it .png",
            map.display()
        )));
    }
    let heat = job.heatmap.map(|m| heatmap_path(out, m));
    let partial = crate::io::image::partial_path(out);
    for path in [
        Some(out),
        job.aa_map.as_deref(),
        heat.as_deref(),
        Some(&partial),
    ] {
        path.map_or(Ok(()), |p| check_out(p, inputs))?;
    }
    Ok(())
}

/// Renders and writes the image of one `gr.render` call; every file it may write is checked
/// first, against the command's `inputs` too.
fn render_one(
    desc: &SceneDesc,
    r: &RenderDesc,
    job: &RenderJob,
    out: &std::path::Path,
    inputs: &[&std::path::Path],
) -> Result<()> {
    check_render_outputs(job, out, inputs)?;
    let start = Instant::now();
    let bar = Bar::new(job.progress, out);
    let progress = report::Snapshots {
        bar: &bar,
        out,
        tonemap: job.tonemap,
    };
    let frame = frame::render_desc(desc, r, job.scale, job.crop, &job.settings, &progress);
    bar.finish();
    let frame = frame?;
    if let Some(partial) = frame.stats.interrupted {
        return Err(write_partial(&frame.film, partial, out, job.tonemap));
    }
    for note in &frame.stats.plan.notes {
        eprintln!("{note}");
    }
    for d in &frame.stats.plan.decisions {
        if matches!(d.why, crate::integrator::plan::Why::ForcedInVain(_)) {
            eprintln!("warning: {d}");
        }
    }
    // Never a silent loss: paths ended by the safety cap miss the light of longer paths.
    let capped = frame.stats.render.depth_capped;
    if capped > 0 {
        eprintln!(
            "warning: {capped} eye paths stopped at the {}-bounce cap; light that only longer \
             paths carry (many nested glass shells, facing mirrors) is missing from {}",
            crate::integrator::eye::MAX_PATH_DEPTH,
            out.display()
        );
    }
    write_image(&frame.film, out, job.tonemap)?;
    if let Some(map) = &job.aa_map {
        write_sample_map(&frame.film, map)?;
    }
    let traversal = crate::accel::counters::enabled().then(crate::accel::counters::collect);
    if let (Some(measure), Some(heat)) = (job.heatmap, &frame.stats.render.heat) {
        write_heatmap(out, measure, heat, frame.film.window.size())?;
    }
    let (fw, fh) = frame.film.window.size();
    eprintln!(
        "wrote {} ({fw}x{fh}) in {:.2} s",
        out.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(p) = &frame.stats.progressive {
        let error = p
            .estimated_error
            .map_or("not yet (one pass)".to_string(), |e| format!("{e:.4}"));
        let why = match p.stop {
            Stop::Passes => "the passes asked for",
            Stop::TargetError => "--target-error",
            Stop::TimeBudget => "--time-budget",
            Stop::Interrupted => "an interrupt",
        };
        eprintln!(
            "progressive: {} passes in {:.2} s, stopped by {why}; estimated relative RMSE {error}",
            p.passes,
            p.time.as_secs_f64()
        );
    }
    if job.stats {
        report::print_stats(&frame, r, out, traversal.as_ref());
    }
    Ok(())
}

/// Returns where the heatmap of `measure` for the image `out` goes: `NAME.heat-MEASURE.png`
/// beside it.
fn heatmap_path(out: &std::path::Path, measure: crate::io::heatmap::Measure) -> std::path::PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned());
    let name = format!("{}.heat-{}.png", stem.unwrap_or_default(), measure.name());
    out.with_file_name(name)
}

/// Writes the heatmap of `measure` beside `out` as `NAME.heat-MEASURE.png` and says so.
fn write_heatmap(
    out: &std::path::Path,
    measure: crate::io::heatmap::Measure,
    heat: &[[f32; 3]],
    size: (u32, u32),
) -> Result<()> {
    let path = heatmap_path(out, measure);
    let (top, text) = crate::io::heatmap::write(&path, heat, size, measure)?;
    let unit = if measure == crate::io::heatmap::Measure::Time {
        format!("{:.1} µs", top / 1000.0)
    } else {
        format!("{top:.0}")
    };
    let legend = if text {
        ""
    } else {
        " (no font found: the legend has no labels)"
    };
    eprintln!(
        "wrote {} (top colour: {unit} {} per pixel and above){legend}",
        path.display(),
        measure.name()
    );
    Ok(())
}

/// Writes the film of an interrupted render of `out` beside it as `NAME.partial.EXT`, marked
/// with what it holds ([`crate::interrupt`]), and returns the error that ends the run saying
/// what was written; nothing is written when no pixel was rendered.
fn write_partial(
    film: &crate::film::Film,
    partial: crate::integrator::Partial,
    out: &std::path::Path,
    tonemap: Tonemap,
) -> Error {
    if partial.is_empty() {
        return Error::Interrupted(format!(
            "before any pixel of {} was rendered; nothing written",
            out.display()
        ));
    }
    let path = crate::io::image::partial_path(out);
    let note = format!("interrupted: {partial}");
    match crate::io::image::write_image_noted(film, &path, tonemap, Some(&note)) {
        Ok(()) => Error::Interrupted(format!("wrote {partial} to {}", path.display())),
        Err(e) => Error::Interrupted(format!("the image rendered so far was not written: {e}")),
    }
}

fn photons_command(args: PhotonsArgs) -> Result<()> {
    let a = &args.render;
    settings::check_scale(a.scale)?;
    if let Some(n) = a.threads {
        set_threads(n)?;
    }
    if a.photon_maps.is_some() {
        return Err(Error::Usage(
            "--photon-maps: caustic photons traces maps; it does not read them".into(),
        ));
    }
    // With --save the maps are the output; without it, the picture -o names.
    if let Some(out) = args.save.as_ref().or(a.output.as_ref()) {
        check_out(out, &[&a.scene])?;
    }
    let count = Rc::new(Cell::new(0u32));
    let counter = Rc::clone(&count);
    let job = RenderJob::from_args(a)?;
    let (argv, scene, output, save) = (
        a.argv.clone(),
        a.scene.clone(),
        a.output.clone(),
        args.save.clone(),
    );
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        counter.set(counter.get() + 1);
        let own = job_with_settings(&job, &argv, &scene, r)?;
        let job = own.as_ref().unwrap_or(&job);
        let mut inputs = scene_inputs(desc);
        inputs.push(&scene);
        if let Some(path) = &save {
            if counter.get() > 1 {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so --save cannot hold its maps",
                ));
            }
            check_out(path, &inputs)?;
            return save_maps(desc, r, job, path);
        }
        let out = match &output {
            Some(o) if counter.get() == 1 => o.clone(),
            Some(_) => {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so -o cannot name its output",
                ));
            }
            None => {
                let stem = r
                    .output
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                r.output.with_file_name(format!("{stem}_photons.png"))
            }
        };
        crate::io::image::output_format(&out)?;
        check_out(&out, &inputs)?;
        let win = frame::window(r, job.scale, None)?;
        let size = (win.full_width, win.full_height);
        let scene = build_scene(desc, r)?;
        let caustics = crate::integrator::plan(&scene, crate::integrator::GiMode::On).caustics;
        frame::charge_photons(desc, r, &scene, &job.settings.photons, caustics)?;
        let camera = Camera::new(&r.camera, size.0, size.1);
        let bar = Bar::new(job.progress, &out);
        let (film, stats) = frame::photon_view(&scene, &camera, size, &job.settings.photons, &bar);
        bar.finish();
        write_image(&film, &out, Tonemap::Clamp)?;
        eprintln!(
            "wrote {} ({} global, {} caustic photons)",
            out.display(),
            stored(&stats.global),
            stored(&stats.caustic)
        );
        Ok(())
    });
    run_script_with(&a.scene, hook, a.script.options())?;
    Ok(())
}

/// Returns the photons stored over these lights' counts.
fn stored(counts: &[crate::photon::trace::LightCounts]) -> u64 {
    counts.iter().map(|c| c.stored).sum()
}

/// Traces the photon maps that `caustic render` with `job` would trace for `r` and writes them
/// to `path` (`caustic photons --save`; the caller has checked `path`).
fn save_maps(
    desc: &SceneDesc,
    r: &RenderDesc,
    job: &RenderJob,
    path: &std::path::Path,
) -> Result<()> {
    let start = Instant::now();
    let bar = Bar::new(job.progress, path);
    let traced = frame::trace_maps(desc, r, job.scale, &job.settings, &bar);
    bar.finish();
    let (maps, stats) = traced?;
    if crate::interrupt::requested() {
        return Err(Error::Interrupted(
            "the photon maps were not written".into(),
        ));
    }
    crate::photon::file::write(path, &maps).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
    let records = maps.cache.as_ref().map_or(0, |c| c.len());
    eprintln!(
        "wrote {} ({} global, {} caustic photons, {records} irradiance-cache records, {:.1} MB) in {:.2} s",
        path.display(),
        stored(&stats.global),
        stored(&stats.caustic),
        bytes as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn export_command(args: ExportArgs) -> Result<()> {
    settings::check_scale(args.scale)?;
    if !(1..=1 << 20).contains(&args.spp) {
        return Err(Error::Usage(format!(
            "--spp must be in [1, 1048576], got {}",
            args.spp
        )));
    }
    check_out(&args.output, &[&args.scene])?;
    let desc = run_script_with(&args.scene, Box::new(|_, _| Ok(())), args.script.options())?;
    let Some(r) = desc.renders.first() else {
        return Err(Error::Usage(format!(
            "{} never calls gr.render: nothing to export",
            args.scene.display()
        )));
    };
    let scene = build_scene(&desc, r)?;
    let mut inputs = scene_inputs(&desc);
    inputs.push(&args.scene);
    for out in crate::io::mitsuba::outputs(&scene, &args.output) {
        check_out(&out, &inputs)?;
    }
    let win = frame::window(r, args.scale, None)?;
    let size = (win.full_width, win.full_height);
    crate::io::mitsuba::export(&desc, r, &scene, size, args.spp, &args.output)?;
    eprintln!(
        "wrote {} ({}x{}, {} spp)",
        args.output.display(),
        size.0,
        size.1,
        args.spp
    );
    Ok(())
}

fn diff_command(args: DiffArgs) -> Result<()> {
    use crate::metrics::{Metrics, difference_image};
    if let Some(out) = &args.output {
        let inputs = [
            Some(&args.image),
            Some(&args.reference),
            args.second.as_ref(),
        ];
        let inputs: Vec<&std::path::Path> =
            inputs.into_iter().flatten().map(PathBuf::as_path).collect();
        check_out(out, &inputs)?;
    }
    let a = crate::io::image::read_rgb(&args.image)?;
    let r1 = crate::io::image::read_rgb(&args.reference)?;
    let r2 = match &args.second {
        Some(p) => crate::io::image::read_rgb(p)?,
        None => r1.clone(),
    };
    let second = args.second.as_ref().unwrap_or(&args.reference);
    for (img, path) in [(&r1, &args.reference), (&r2, second)] {
        if (img.width, img.height) != (a.width, a.height) {
            return Err(Error::Usage(format!(
                "{} is {}x{} but {} is {}x{}",
                args.image.display(),
                a.width,
                a.height,
                path.display(),
                img.width,
                img.height
            )));
        }
    }
    let region = parse_region(args.region.as_deref(), a.width, a.height)?;
    for (img, path) in [(&a, &args.image), (&r1, &args.reference), (&r2, second)] {
        check_finite(img, path, region)?;
    }
    let m = Metrics::against_two(&a, &r1, &r2, region);
    println!("mean ratio {:.5}", m.mean_ratio);
    println!("mean error {:+.5}", m.mean_error);
    println!("RMSE {:.6}", m.rmse);
    println!("relative RMSE {:.5}", m.rel_rmse);
    println!("block bias {:.5}", m.block_bias);
    if let Some(out) = &args.output {
        if !(args.gain.is_finite() && args.gain > 0.0) {
            return Err(Error::Usage("--gain must be positive".into()));
        }
        if crate::io::image::output_format(out)? != crate::io::image::Format::Png {
            return Err(Error::Usage(format!(
                "-o {}: the difference picture is written as PNG; name it .png",
                out.display()
            )));
        }
        let rgb = difference_image(&a, &r1, args.gain);
        crate::io::image::write_rgb8_png(out, a.width, a.height, &rgb)?;
    }
    Ok(())
}

fn info_command(args: InfoArgs) -> Result<()> {
    let desc = run_script_with(&args.scene, Box::new(|_, _| Ok(())), args.script.options())?;
    print!(
        "{}",
        report::describe(&args.scene.display().to_string(), &desc)?
    );
    // The plan each render would follow at the default settings, or under the scene's own
    // gr.settings, with the photon budgets.
    for (i, r) in desc.renders.iter().enumerate() {
        let (settings, which) = if r.settings.is_empty() {
            (crate::integrator::Settings::default(), "default settings")
        } else {
            let base = RenderLine::try_parse_from([args.scene.as_os_str()])
                .map_err(|e| Error::Usage(e.to_string()))?;
            let job = RenderJob::from_args(&base.render)?;
            let scene_job = job_with_settings(&job, &[], &args.scene, r)?;
            let settings = scene_job.map_or(job.settings, |j| j.settings);
            (settings, "the scene's gr.settings")
        };
        let scene = build_scene(&desc, r)?;
        let plan = crate::integrator::plan::plan_for(&scene, &settings);
        println!("  plan of render {} ({which}):", i + 1);
        for line in plan.lines() {
            println!("    {line}");
        }
        if plan.integrator == crate::integrator::Integrator::PhotonMap {
            use crate::photon::trace::MapKind;
            for (name, kind, on) in [
                ("global", MapKind::Global, true),
                ("caustic", MapKind::Caustic, plan.caustics),
            ] {
                if on {
                    let budget = settings.photons.budget(&scene.lights, kind);
                    let total: u64 = budget.iter().sum();
                    println!("    {name} photons: {total} (per light: {budget:?})");
                }
            }
        }
    }
    Ok(())
}
