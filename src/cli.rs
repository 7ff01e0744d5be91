//! The command line: `caustic render` and `caustic info`, and what each runs.

use crate::camera::Camera;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::io::image::{Tonemap, write_image, write_sample_map};
use crate::lua::{ScriptOptions, run_script, run_script_with};
use crate::photon::trace::Progress;
use crate::render::gi::{Gi, GiSettings, Indirect};
use crate::render::plan::{GiMode, plan};
use crate::render::{Film, RenderOptions, RenderStats, Sampling, Window, render_with};
use crate::scene::build::{build_scene, count_placements};
use clap::{Args, Parser, Subcommand};
use std::cell::Cell;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

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
}

#[derive(Debug, Args)]
pub struct PhotonsArgs {
    /// The Lua scene script.
    pub scene: PathBuf,
    /// The picture to write (default: the script's image name with `_photons` added).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Photons per map.
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    pub photons: u64,
    /// Seed of the photon streams.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Draw at this multiple of the script's image size.
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    pub scale: f64,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The Lua scene script.
    pub scene: PathBuf,
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
    /// Stratified samples per pixel (1 = one ray through the pixel centre, as the course).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub spp: u32,
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
    /// Shadow-ray samples per area or sphere light at each shaded point (soft shadows).
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub light_samples: u32,
    /// Photon mapping: auto (when a light has power or num_photons), on, or off (ambient term).
    #[arg(long, value_enum, default_value_t = GiArg::Auto)]
    pub gi: GiArg,
    /// Photons per map, shared by lights without num_photons in proportion to their power.
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    pub photons: u64,
    /// Indirect diffuse light: gather (final gathering, accurate) or direct (the global map seen
    /// directly, fast and blotchy).
    #[arg(long, value_enum, default_value_t = IndirectArg::Gather)]
    pub indirect: IndirectArg,
    /// Final-gather rays per shaded point.
    #[arg(long, value_name = "N", default_value_t = 64)]
    pub gather_rays: u32,
    /// What a final-gather ray reads where it lands: precomputed (irradiance computed beforehand
    /// at one global photon in four, Christensen's method, fast) or estimate (a density estimate
    /// at the hit, slower and sharper).
    #[arg(long, value_enum, default_value_t = GatherLookup::Precomputed)]
    pub gather_lookup: GatherLookup,
    /// Nearest photons per density estimate.
    #[arg(long, value_name = "K", default_value_t = 50)]
    pub photon_k: usize,
    /// Multiply every light's photon count by F, the scene's num_photons included (previews).
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    pub photon_scale: f64,
    /// What a missing or unreadable texture is: an error (default), or a warning (once per file)
    /// with the material rendered in its kd colour.
    #[arg(long, value_enum, default_value_t = MissingTextures::Error)]
    pub missing_textures: MissingTextures,
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

/// The `--indirect` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IndirectArg {
    Gather,
    Direct,
}

/// The `--gather-lookup` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GatherLookup {
    Precomputed,
    Estimate,
}

/// The `--tonemap` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TonemapArg {
    Clamp,
    Srgb,
}

#[derive(Debug, Args)]
pub struct StitchArgs {
    /// Tiles written by `caustic render --crop` (PNG), in any order.
    #[arg(required = true)]
    pub tiles: Vec<PathBuf>,
    /// The full image to write.
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
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => render_command(args),
        Command::Info(args) => info_command(args),
        Command::Stitch(args) => crate::io::image::stitch(&args.tiles, &args.output),
        Command::Photons(args) => photons_command(args),
    }
}

/// Returns the image size after applying `--scale`.
fn scaled_size(r: &RenderDesc, scale: f64) -> (u32, u32) {
    let s = |v: u32| ((v as f64 * scale).round() as u32).max(1);
    (s(r.width), s(r.height))
}

fn render_command(args: RenderArgs) -> Result<()> {
    if !(args.scale > 0.0 && args.scale <= 16.0) {
        return Err(Error::Usage(format!(
            "--scale must be in (0, 16], got {}",
            args.scale
        )));
    }
    if let Some(n) = args.threads {
        if n == 0 {
            return Err(Error::Usage("--threads must be at least 1".into()));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| Error::Usage(format!("cannot start {n} threads: {e}")))?;
    }
    let rendered = Rc::new(Cell::new(0u32));
    let count = Rc::clone(&rendered);
    let output = args.output.clone();
    let settings = RenderSettings::from_args(&args)?;
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        count.set(count.get() + 1);
        let out = match &output {
            None => r.output.clone(),
            Some(o) if count.get() == 1 => o.clone(),
            Some(_) => {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so -o cannot name its output; run without -o",
                ));
            }
        };
        render_one(desc, r, &settings, &out)
    });
    let options = ScriptOptions {
        missing_textures_warn: args.missing_textures == MissingTextures::Warn,
    };
    run_script_with(&args.scene, hook, options)?;
    if rendered.get() == 0 {
        eprintln!(
            "warning: {} never called gr.render; no image written",
            args.scene.display()
        );
    }
    Ok(())
}

/// The render options of the command line, checked.
struct RenderSettings {
    scale: f64,
    seed: u64,
    sampling: Sampling,
    crop: Option<[u32; 4]>,
    tonemap: Tonemap,
    aa_map: Option<PathBuf>,
    stats: bool,
    progress: bool,
    light_samples: u32,
    gi_mode: GiMode,
    gi: GiSettings,
}

impl RenderSettings {
    fn from_args(a: &RenderArgs) -> Result<RenderSettings> {
        if a.spp == 0 || a.spp > 1 << 16 {
            return Err(Error::Usage(format!(
                "--spp must be in [1, 65536], got {}",
                a.spp
            )));
        }
        if !(a.aa_threshold >= 0.0 && a.aa_threshold.is_finite()) || a.aa_depth > 8 {
            return Err(Error::Usage(
                "--aa-threshold must be >= 0 and --aa-depth at most 8".into(),
            ));
        }
        if !(a.photon_scale >= 0.0 && a.photon_scale <= 1e3) {
            return Err(Error::Usage(format!(
                "--photon-scale must be in [0, 1000], got {}",
                a.photon_scale
            )));
        }
        if !a.exposure.is_finite() {
            return Err(Error::Usage("--exposure must be finite".into()));
        }
        for (name, value, max) in [
            ("--light-samples", a.light_samples as u64, 4096),
            ("--photon-k", a.photon_k as u64, 10_000),
            ("--gather-rays", a.gather_rays as u64, 65_536),
        ] {
            if !(1..=max).contains(&value) {
                return Err(Error::Usage(format!(
                    "{name} must be in [1, {max}], got {value}"
                )));
            }
        }
        let sampling = if a.adaptive {
            Sampling::Adaptive {
                threshold: a.aa_threshold,
                max_depth: a.aa_depth,
            }
        } else {
            Sampling::Stratified { spp: a.spp }
        };
        let tonemap = match a.tonemap {
            TonemapArg::Clamp => Tonemap::Clamp,
            TonemapArg::Srgb => Tonemap::Srgb {
                exposure: a.exposure,
            },
        };
        Ok(RenderSettings {
            scale: a.scale,
            seed: a.seed,
            sampling,
            crop: a.crop,
            tonemap,
            aa_map: a.aa_map.clone(),
            stats: a.stats,
            light_samples: a.light_samples,
            gi_mode: match a.gi {
                GiArg::Auto => GiMode::Auto,
                GiArg::On => GiMode::On,
                GiArg::Off => GiMode::Off,
            },
            gi: GiSettings {
                seed: a.seed,
                photons: a.photons,
                photon_scale: a.photon_scale,
                k: a.photon_k,
                indirect: match a.indirect {
                    IndirectArg::Gather => Indirect::Gather {
                        rays: a.gather_rays,
                    },
                    IndirectArg::Direct => Indirect::Direct,
                },
                precompute: a.gather_lookup == GatherLookup::Precomputed,
                ..GiSettings::default()
            },
            progress: !a.quiet && std::io::stderr().is_terminal(),
        })
    }
}

/// The progress bar of one image on stderr (hidden unless `show`): one phase after another, each
/// with its own count, elapsed time and estimate of time left.
struct Bar {
    bar: indicatif::ProgressBar,
    /// The image's path, shown before each phase's name.
    image: String,
}

impl Bar {
    fn new(show: bool, out: &std::path::Path) -> Bar {
        let bar = if show {
            let bar = indicatif::ProgressBar::new(0);
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {human_pos}/{human_len}, {elapsed} elapsed, {eta} left",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        } else {
            indicatif::ProgressBar::hidden()
        };
        Bar {
            bar,
            image: out.display().to_string(),
        }
    }

    /// Removes the bar from the terminal.
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Progress for Bar {
    fn start(&self, what: &str, total: u64) {
        self.bar.reset();
        self.bar.set_length(total);
        self.bar.set_message(format!("{}: {what}", self.image));
    }

    fn advance(&self, n: u64) {
        self.bar.inc(n);
    }
}

/// Builds, renders and writes the image of one `gr.render` call.
fn render_one(
    desc: &SceneDesc,
    r: &RenderDesc,
    settings: &RenderSettings,
    out: &std::path::Path,
) -> Result<()> {
    let (w, h) = scaled_size(r, settings.scale);
    let window = match settings.crop {
        None => Window::full(w, h),
        Some([x0, y0, x1, y1]) => {
            let win = Window {
                x0,
                y0,
                x1,
                y1,
                full_width: w,
                full_height: h,
            };
            if !win.is_valid() {
                return Err(Error::at(
                    &r.loc,
                    format!("--crop {x0},{y0},{x1},{y1} is not inside the {w}x{h} image"),
                ));
            }
            win
        }
    };
    let start = Instant::now();
    let scene = build_scene(desc, r)?;
    let camera = Camera::new(&r.camera, w, h);
    let opts = RenderOptions {
        seed: settings.seed,
        sampling: settings.sampling.clone(),
        window,
        timing: settings.stats,
        light_samples: settings.light_samples,
    };
    let bar = Bar::new(settings.progress, out);
    let plan = plan(&scene, settings.gi_mode);
    let gi = plan.photon_maps.then(|| {
        let gi_settings = GiSettings {
            caustics: plan.caustics,
            ..settings.gi.clone()
        };
        Gi::build_with(&scene, &gi_settings, &bar)
    });
    let rows = window.size().1 as u64;
    bar.start("rendering rows", rows);
    let (film, rstats) = render_with(&scene, &camera, gi.as_ref(), &opts, &|| bar.advance(1));
    bar.finish();
    write_image(&film, out, settings.tonemap)?;
    if let Some(map) = &settings.aa_map {
        write_sample_map(&film, map)?;
    }
    let (fw, fh) = window.size();
    eprintln!(
        "wrote {} ({fw}x{fh}) in {:.2} s",
        out.display(),
        start.elapsed().as_secs_f64()
    );
    if settings.stats {
        print_stats(&scene, &film, &rstats, r, out);
        println!("  effects: {}", plan.reasons.join("; "));
        if let Some(gi) = &gi {
            print_photon_stats(gi, &rstats);
        }
    }
    Ok(())
}

fn print_stats(
    scene: &crate::scene::Scene,
    film: &Film,
    rstats: &RenderStats,
    r: &RenderDesc,
    out: &std::path::Path,
) {
    let b = &scene.stats;
    println!(
        "image {}: {}x{} from {}",
        out.display(),
        film.width,
        film.height,
        r.loc
    );
    let kinds: Vec<String> = b.by_kind.iter().map(|(k, v)| format!("{k} {v}")).collect();
    println!(
        "  scene: {} instances ({}), {} lights",
        scene.instances.len(),
        kinds.join(", "),
        scene.lights.len()
    );
    println!(
        "  triangles: {} placed, {} stored; BVH {} bytes; build {:.3} s",
        b.triangles_placed,
        b.triangles_stored,
        b.bvh_bytes,
        b.build_time.as_secs_f64()
    );
    let n = film.samples.len().max(1) as f64;
    let total: u64 = film.samples.iter().map(|&s| s as u64).sum();
    let (lo, hi) = (
        film.samples.iter().min().copied().unwrap_or(0),
        film.samples.iter().max().copied().unwrap_or(0),
    );
    println!(
        "  camera rays per pixel: mean {:.2}, min {lo}, max {hi}",
        total as f64 / n
    );
    let secs = rstats.time.as_secs_f64();
    let rays = rstats.primary_rays + rstats.shadow_rays + rstats.secondary_rays;
    println!(
        "  rays: {} primary, {} shadow, {} secondary; render {:.3} s ({:.2} Mrays/s, {} threads)",
        rstats.primary_rays,
        rstats.shadow_rays,
        rstats.secondary_rays,
        secs,
        rays as f64 / secs.max(1e-9) / 1e6,
        rayon::current_num_threads()
    );
    // Thread time summed over workers, against wall time times the workers.
    let busy = secs * rayon::current_num_threads() as f64;
    println!(
        "  materials (textures, bump maps, Perlin noise): {:.3} s of thread time, {:.1}% of render time",
        rstats.material_time.as_secs_f64(),
        100.0 * rstats.material_time.as_secs_f64() / busy.max(1e-9)
    );
}

fn photons_command(args: PhotonsArgs) -> Result<()> {
    if !(args.scale > 0.0 && args.scale <= 16.0) {
        return Err(Error::Usage(format!(
            "--scale must be in (0, 16], got {}",
            args.scale
        )));
    }
    let count = Rc::new(Cell::new(0u32));
    let counter = Rc::clone(&count);
    let output = args.output.clone();
    let (photons, seed, scale) = (args.photons, args.seed, args.scale);
    let progress = !args.quiet && std::io::stderr().is_terminal();
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        counter.set(counter.get() + 1);
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
        let (w, h) = scaled_size(r, scale);
        let scene = build_scene(desc, r)?;
        let camera = Camera::new(&r.camera, w, h);
        let plan = plan(&scene, GiMode::On);
        let settings = GiSettings {
            seed,
            photons,
            caustics: plan.caustics,
            precompute: false,
            ..GiSettings::default()
        };
        let bar = Bar::new(progress, &out);
        let gi = Gi::build_with(&scene, &settings, &bar);
        bar.finish();
        let film = crate::render::photon_view::photon_image(&scene, &camera, &gi, w, h);
        write_image(&film, &out, Tonemap::Clamp)?;
        eprintln!(
            "wrote {} ({} global, {} caustic photons)",
            out.display(),
            gi.global.len(),
            gi.caustic.as_ref().map_or(0, |c| c.len())
        );
        Ok(())
    });
    run_script(&args.scene, hook)?;
    Ok(())
}

fn print_photon_stats(gi: &Gi, rstats: &RenderStats) {
    let s = &gi.stats;
    for (name, counts, map) in [
        ("global", &s.global, Some(&gi.global)),
        ("caustic", &s.caustic, gi.caustic.as_ref()),
    ] {
        let emitted: u64 = counts.iter().map(|c| c.emitted).sum();
        let stored: u64 = counts.iter().map(|c| c.stored).sum();
        let per_light: Vec<String> = counts
            .iter()
            .map(|c| format!("{}/{}", c.stored, c.emitted))
            .collect();
        let bytes = map.map_or(0, |m| m.bytes());
        println!(
            "  {name} map: {emitted} photons emitted, {stored} stored (per light stored/emitted: {}), {:.1} bytes per photon",
            per_light.join(", "),
            bytes as f64 / stored.max(1) as f64
        );
    }
    let (lookups, used) = (rstats.lookups, rstats.photons_used);
    println!(
        "  photon phases: trace {:.3} s, kd-tree build {:.3} s, irradiance precomputed at {} points in {:.3} s",
        s.trace_time.as_secs_f64(),
        s.build_time.as_secs_f64(),
        s.precomputed_points,
        s.precompute_time.as_secs_f64(),
    );
    println!(
        "  photon lookups while rendering: {lookups}, {:.1} photons per lookup",
        used as f64 / lookups.max(1) as f64
    );
}

fn info_command(args: InfoArgs) -> Result<()> {
    let desc = run_script(&args.scene, Box::new(|_, _| Ok(())))?;
    print!("{}", describe(&args.scene.display().to_string(), &desc)?);
    Ok(())
}

/// Returns the summary `caustic info` prints for a script's description.
pub fn describe(name: &str, desc: &SceneDesc) -> Result<String> {
    use std::collections::BTreeMap;
    use std::fmt::Write;
    let mut s = String::new();
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    for n in &desc.nodes {
        *kinds.entry(n.kind.label()).or_default() += 1;
    }
    let list = |m: &BTreeMap<&str, usize>| {
        m.iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let meshes = crate::scene::meshes::load_meshes(desc)?;
    let triangles: usize = meshes.iter().map(|m| m.triangles.len()).sum();
    let _ = writeln!(s, "scene {name}");
    let _ = writeln!(s, "  nodes: {} ({})", desc.nodes.len(), list(&kinds));
    let _ = writeln!(
        s,
        "  meshes: {} files, {triangles} triangles",
        desc.meshes.len()
    );
    for m in &meshes {
        let _ = writeln!(
            s,
            "    {}: {} triangles",
            m.source.display(),
            m.triangles.len()
        );
    }
    let _ = writeln!(s, "  materials: {}", desc.materials.len());
    let _ = writeln!(s, "  lights: {}", desc.lights.len());
    let _ = writeln!(s, "  renders: {}", desc.renders.len());
    for (i, r) in desc.renders.iter().enumerate() {
        let c = &r.camera;
        let placed = count_placements(desc, r.root)?;
        let _ = writeln!(
            s,
            "  render {} at {}: {} {}x{}",
            i + 1,
            r.loc,
            r.output.display(),
            r.width,
            r.height
        );
        let _ = writeln!(
            s,
            "    camera: eye ({}, {}, {}) view ({}, {}, {}) up ({}, {}, {}) fov {}°",
            c.eye.x,
            c.eye.y,
            c.eye.z,
            c.view.x,
            c.view.y,
            c.view.z,
            c.up.x,
            c.up.y,
            c.up.z,
            c.fov_deg
        );
        let _ = writeln!(
            s,
            "    root '{}', ambient ({}, {}, {}), {} lights",
            desc.node(r.root).name,
            r.ambient.x,
            r.ambient.y,
            r.ambient.z,
            r.lights.len()
        );
        let _ = writeln!(
            s,
            "    placed: {} ({} triangles)",
            list(&placed.by_kind),
            placed.triangles
        );
    }
    Ok(s)
}
