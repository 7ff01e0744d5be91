//! The command line as clap parses it: the subcommands ([`Cli`], [`Command`]) and their flags,
//! with the parsers of flag values. What each flag means to the library, and its range check,
//! is [`super::settings`]; the commands themselves are [`super`].

use crate::error::Result;
use crate::integrator::plan::Effect;
use crate::integrator::{DEFAULT_GATHER_RAYS, DEFAULT_LIGHT_SAMPLES};
use crate::lua::globals::Global;
use crate::lua::{Dialect, ScriptOptions};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

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
    /// Add up progressive passes rendered apart (--first-pass, --save-passes) into their mean.
    Merge(MergeArgs),
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
    Study(super::study::StudyArgs),
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
    /// Trace only part I of N of the photon pass (I from 0 to N-1, N at most 4096) and save
    /// its photons, as traced, to --save's FILE; --merge joins the N parts.
    #[arg(long, value_name = "I/N", value_parser = parse_part, requires = "save", conflicts_with = "merge")]
    pub part: Option<crate::photon::trace::Part>,
    /// Join the parts --part saved (every part of one pass, each once) into the photon-map
    /// file --save writes: byte for byte the file one caustic photons --save writes.
    #[arg(long, value_name = "PART", num_args = 1.., requires = "save")]
    pub merge: Vec<PathBuf>,
    /// Every `caustic render` flag, so that the maps traced are the ones a render with the
    /// same flags traces (photon counts, --photon-scale, --seed, --scale, --force, --disable,
    /// the scene's gr.settings); without --save, -o names the picture of the photons (default:
    /// the script's image name with `_photons` added).
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene: a Lua script, or a glTF file (.gltf, .glb) rendered as a whole scene.
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
    /// A glTF scene's camera, by the camera's or its node's name (default: the first).
    #[arg(long, value_name = "NAME")]
    pub camera: Option<String>,
    /// A glTF scene's image size in pixels (default: 800 wide at the camera's aspect ratio).
    #[arg(long, value_names = ["W", "H"], num_args = 2)]
    pub size: Option<Vec<u32>>,
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
    /// Adaptive pixels: after --spp samples (at least 2), double a pixel's samples while its
    /// error, estimated from two half-buffers relative to the pixel's and the image's
    /// brightness, is above E (0.05 = 5%), up to --max-spp. See docs/guide.md.
    #[arg(long, value_name = "E")]
    pub noise_target: Option<f32>,
    /// Adaptive pixels: most samples a pixel takes [default: 64 times --spp, at most 65536].
    #[arg(long, value_name = "N")]
    pub max_spp: Option<u32>,
    /// Also write each pixel's estimated relative error (from its two half-buffers; needs
    /// --spp 2 or more): a colour-scaled picture with a legend (.png) or the values (.exr).
    #[arg(long, value_name = "MAP.png|MAP.exr")]
    pub error_map: Option<PathBuf>,
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
    /// Progressive: radii that vary over space with a pilot map's photon density, about k
    /// photons everywhere (on), or one radius per map for the whole image (off); --radius
    /// sets the median [default: on].
    #[arg(long, value_enum, value_name = "SWITCH")]
    pub local_radii: Option<Switch>,
    /// Photon mapping: plan samples, photons and cache rays for the least time to a relative
    /// RMSE of E (a pilot measures the frame; see docs/accuracy.md). Progressive: stop once
    /// the relative RMSE estimated from the even and odd passes is at most E (noise only).
    #[arg(long, value_name = "E")]
    pub target_error: Option<f64>,
    /// Photon mapping: plan samples, photons and cache rays for the least error in S seconds
    /// of wall time after the scene is built. Progressive: stop before a pass that would end
    /// after S seconds.
    #[arg(long, value_name = "S")]
    pub time_budget: Option<f64>,
    /// Progressive: write the running image to the output every K passes.
    #[arg(long, value_name = "K")]
    pub write_every: Option<u32>,
    /// Progressive: run passes P to P + N - 1 of the render (N from --passes), with the seeds
    /// and radii those passes have in one process running them all, so that passes run on
    /// many machines merge (caustic merge) into the render of all of them [default: 0].
    #[arg(long, value_name = "P")]
    pub first_pass: Option<u32>,
    /// Progressive: also write the passes' sums, with their pass range and the render's
    /// fingerprint, to FILE, for caustic merge.
    #[arg(long, value_name = "FILE")]
    pub save_passes: Option<PathBuf>,
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
    /// Gather rays per irradiance-cache record [default: 256; with --time-budget or
    /// --target-error, the planner's].
    #[arg(long, value_name = "N")]
    pub cache_rays: Option<u32>,
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

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Pass files written by `caustic render --integrator progressive --save-passes`, of one
    /// render, whose pass ranges follow one another from pass 0, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The image of all the passes' mean (.exr, .pfm or .hdr keep the floats; .png clamps).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Also write the merged passes' sums to FILE, to merge with more passes later.
    #[arg(long, value_name = "FILE")]
    pub save_passes: Option<PathBuf>,
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
    /// The scene: a Lua script, or a glTF file (.gltf, .glb).
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

/// Parses `--part I/N`: `I` below `N`, `N` from 1 to [`crate::photon::trace::MAX_PARTS`].
fn parse_part(s: &str) -> std::result::Result<crate::photon::trace::Part, String> {
    use crate::photon::trace::{MAX_PARTS, Part};
    let bad = || format!("expected I/N with 0 <= I < N <= {MAX_PARTS}, got {s}");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (index, count) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if !(1..=MAX_PARTS).contains(&count) || index >= count {
        return Err(bad());
    }
    Ok(Part { index, count })
}

/// Returns `caustic photons`'s words without its own flags, which `caustic render` does not
/// take: `--save FILE` and `--part I/N` (or `--save=FILE`, `--part=I/N`), and `--merge` with
/// the words after it up to the next flag, as clap reads them.
fn without_save(words: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let mut out = Vec::with_capacity(words.len());
    let mut words = words.into_iter().peekable();
    while let Some(w) = words.next() {
        let text = w.to_string_lossy();
        if w == "--" {
            out.push(w);
            out.extend(words.by_ref());
        } else if w == "--save" || w == "--part" {
            words.next();
        } else if w == "--merge" {
            while words
                .next_if(|v| !v.to_string_lossy().starts_with('-'))
                .is_some()
            {}
        } else if !["--save=", "--part=", "--merge="]
            .iter()
            .any(|f| text.starts_with(f))
        {
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
