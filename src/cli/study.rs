//! `caustic study`: renders a scene over a grid of settings and seeds, measures each image
//! against a reference, and writes the CSV, the Markdown table and the plot
//! ([`crate::study`]). Each setting is a list of `caustic render` flags, parsed and checked as
//! `caustic render` parses them, so a study renders exactly what the same command line would.

use super::RenderLine;
use super::settings::RenderJob;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::metrics::{Image, Metrics, Region, pair_block_bias};
use crate::progress::NoProgress;
use crate::study::{Curve, MAX_SEEDS, Point, Row, Sweep, grid, summarise};
use clap::{Args, Parser as _};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args)]
pub struct StudyArgs {
    /// The Lua scene script (its first gr.render is studied).
    pub scene: PathBuf,
    #[command(flatten)]
    pub script: super::ScriptArgs,
    /// The reference image (EXR, linear), of the size the renders have.
    #[arg(long, value_name = "REF.exr")]
    pub reference: PathBuf,
    /// A second, independent reference: errors are then against the truth as estimated from
    /// both (their own noise drops out).
    #[arg(long, value_name = "REF2.exr")]
    pub second: Option<PathBuf>,
    /// A render flag and its values, KEY=V1,V2,... (repeatable; the grid is every
    /// combination): photons=1e4,1e5 or gather-rays=16,64 or passes=4,16,64.
    #[arg(long, value_name = "KEY=VALUES")]
    pub sweep: Vec<String>,
    /// Render flags every setting shares, as one string: --base="--integrator progressive".
    #[arg(long, value_name = "FLAGS", allow_hyphen_values = true)]
    pub base: Option<String>,
    /// Seeds per setting (0, 1, ...): more separate noise from bias.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seeds: u32,
    /// Measure only the window x0,y0,x1,y1 (pixels, end exclusive).
    #[arg(long, value_name = "x0,y0,x1,y1", value_delimiter = ',')]
    pub region: Option<Vec<u32>>,
    /// Another curve to draw and list, LABEL=FILE.csv (a CSV with cpu_s and rel_rmse columns:
    /// another study's, or a path tracer's from tools/accuracy/).
    #[arg(long, value_name = "LABEL=FILE")]
    pub compare: Vec<String>,
    /// The title of the table and the plot.
    #[arg(long, value_name = "TEXT")]
    pub title: Option<String>,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// The folder to write study.csv, study.md, study.png and the images to.
    #[arg(short, long, value_name = "DIR", default_value = "study")]
    pub output: PathBuf,
}

/// Runs `caustic study`: checks every setting, the references and the outputs before it
/// renders anything ([`Study::prepare`]), then renders the script's first `gr.render` at every
/// setting and seed and writes the tables and the plot.
pub fn study_command(args: StudyArgs) -> Result<()> {
    if args.seeds == 0 || args.seeds > MAX_SEEDS {
        return Err(Error::Usage(format!(
            "--seeds must be in [1, {MAX_SEEDS}], got {}",
            args.seeds
        )));
    }
    super::set_threads(args.threads)?;
    let study = Study::prepare(&args)?;
    let mut done = false;
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        if std::mem::replace(&mut done, true) {
            eprintln!(
                "note: {}: only the script's first gr.render is studied",
                r.loc
            );
            return Ok(());
        }
        study.check_sizes(r)?;
        let (rows, pair) = study.render_rows(desc, r)?;
        study.write(&rows, &pair)
    });
    crate::lua::run_script_with(&args.scene, hook, args.script.options())?;
    Ok(())
}

/// A study ready to render: its settings with their flags checked, the references read and
/// the outputs checked.
struct Study {
    points: Vec<Point>,
    /// Each point's `caustic render` flags (the shared `--base` ones first).
    jobs: Vec<Vec<String>>,
    curves: Vec<Curve>,
    r1: Image,
    /// The second reference, or the first again.
    r2: Image,
    region: Region,
    scene: PathBuf,
    reference: PathBuf,
    seeds: u32,
    out: PathBuf,
    title: String,
}

impl Study {
    /// Returns the study `args` ask for, or the first error in its settings, its compared
    /// curves, its references or its outputs, before anything is rendered.
    fn prepare(args: &StudyArgs) -> Result<Study> {
        let sweeps = args
            .sweep
            .iter()
            .map(|s| Sweep::parse(s))
            .collect::<Result<Vec<_>>>()?;
        let points = grid(&sweeps)?;
        let base: Vec<String> = args
            .base
            .as_deref()
            .unwrap_or("")
            .split_whitespace()
            .map(String::from)
            .collect();
        // Check every setting's flags before rendering any.
        let jobs = points
            .iter()
            .map(|p| {
                let flags: Vec<String> = base.iter().cloned().chain(p.flags()).collect();
                parse_job(&args.scene, &flags, 0)
                    .map_err(|e| Error::Usage(format!("setting '{}': {e}", p.label())))?;
                Ok(flags)
            })
            .collect::<Result<Vec<_>>>()?;
        let curves = args
            .compare
            .iter()
            .map(|c| {
                let (label, file) = c.split_once('=').ok_or_else(|| {
                    Error::Usage(format!("--compare {c}: expected LABEL=FILE.csv"))
                })?;
                Curve::read(label, Path::new(file))
            })
            .collect::<Result<Vec<_>>>()?;
        let (r1, r2, region) = references(args)?;
        check_outputs(args)?;
        Ok(Study {
            points,
            jobs,
            curves,
            r1,
            r2,
            region,
            scene: args.scene.clone(),
            reference: args.reference.clone(),
            seeds: args.seeds,
            out: args.output.clone(),
            title: args
                .title
                .clone()
                .unwrap_or_else(|| format!("Study of {}", args.scene.display())),
        })
    }

    /// Returns an error at `r`'s line when a setting's image would not have the reference's
    /// size (checked before rendering any).
    fn check_sizes(&self, r: &RenderDesc) -> Result<()> {
        for (p, flags) in self.points.iter().zip(&self.jobs) {
            let (w, h) = crate::frame::scaled_size(r, parse_job(&self.scene, flags, 0)?.scale);
            if (w, h) != (self.r1.width, self.r1.height) {
                return Err(Error::at(
                    &r.loc,
                    format!(
                        "setting '{}' renders {w}x{h} but {} is {}x{}",
                        p.label(),
                        self.reference.display(),
                        self.r1.width,
                        self.r1.height
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Renders every setting at every seed; returns the rows and, per setting, the block bias
    /// of its first two seeds' images when it has two.
    fn render_rows(
        &self,
        desc: &SceneDesc,
        r: &RenderDesc,
    ) -> Result<(Vec<Row>, Vec<Option<f64>>)> {
        let mut rows = Vec::new();
        let mut pair = Vec::new();
        for (p, flags) in self.points.iter().zip(&self.jobs) {
            let mut first_two = Vec::new();
            for seed in 0..self.seeds as u64 {
                let (row, image) = self.render_point(desc, r, p, flags, seed)?;
                eprintln!(
                    "study: {} seed {seed}: {:.2} s CPU, relative RMSE {:.4}",
                    p.label(),
                    row.cpu_s,
                    row.metrics.rel_rmse
                );
                rows.push(Row {
                    point: p.index,
                    setting: p.label(),
                    ..row
                });
                if first_two.len() < 2 {
                    first_two.push(image);
                }
            }
            pair.push(match &first_two[..] {
                [a, b] => Some(pair_block_bias(a, b, &self.r1, &self.r2, self.region)),
                _ => None,
            });
        }
        Ok((rows, pair))
    }

    /// Writes `study.csv`, `study.png` and `study.md` of `rows` and `pair` (as
    /// [`Study::render_rows`] returns them), and prints the table.
    fn write(&self, rows: &[Row], pair: &[Option<f64>]) -> Result<()> {
        let summaries = summarise(&self.points, rows, pair);
        write(&self.out.join("study.csv"), &crate::study::csv(rows))?;
        let png = self.out.join("study.png");
        let text = crate::study::plot::draw(&self.title, &summaries, &self.curves, &png)?;
        if !text {
            eprintln!(
                "warning: no font found for the plot's text (set CAUSTIC_PLOT_FONT to a .ttf); \
                 study.png has curves only"
            );
        }
        let md = crate::study::markdown(&self.title, &summaries, &self.curves, Some("study.png"));
        write(&self.out.join("study.md"), &md)?;
        print!("{md}");
        Ok(())
    }

    /// Renders setting `p` (its `flags`) at `seed`, writes its image and returns its row (the
    /// point's index and label are the caller's to fill) and its image.
    fn render_point(
        &self,
        desc: &SceneDesc,
        r: &RenderDesc,
        p: &Point,
        flags: &[String],
        seed: u64,
    ) -> Result<(Row, Image)> {
        let job = parse_job(&self.scene, flags, seed)?;
        let (cpu0, wall0) = (crate::stats::process_cpu_time(), Instant::now());
        let settings = &job.settings;
        let frame = crate::frame::render_desc(desc, r, job.scale, None, settings, &NoProgress)?;
        let wall_s = wall0.elapsed().as_secs_f64();
        let cpu_s = match (cpu0, crate::stats::process_cpu_time()) {
            (Some(a), Some(b)) => (b - a).as_secs_f64(),
            // No CPU clock here: wall time on every worker is the closest stand-in.
            _ => wall_s * rayon::current_num_threads() as f64,
        };
        let film = &frame.film;
        let image = Image {
            width: film.width,
            height: film.height,
            pixels: film.pixels.clone(),
        };
        same_size(&image, Path::new("the render"), &self.r1, &self.reference)?;
        let name = format!("p{}_{}_s{seed}.exr", p.index, image_stem(flags));
        let path = self.out.join("images").join(&name);
        crate::io::image::write_image(film, &path, job.tonemap)?;
        let metrics = Metrics::against_two(&image, &self.r1, &self.r2, self.region);
        let row = Row {
            point: 0,
            seed,
            setting: String::new(),
            cpu_s,
            wall_s,
            metrics,
            image: format!("images/{name}"),
        };
        Ok((row, image))
    }
}

/// Returns the study's references (the second one, or the first again) and the region
/// measured, or an error naming a reference that differs in size or is not finite there.
fn references(args: &StudyArgs) -> Result<(Image, Image, Region)> {
    let r1 = crate::io::image::read_rgb(&args.reference)?;
    let r2 = match &args.second {
        Some(p) => {
            let r2 = crate::io::image::read_rgb(p)?;
            same_size(&r2, p, &r1, &args.reference)?;
            r2
        }
        None => r1.clone(),
    };
    let region = super::parse_region(args.region.as_deref(), r1.width, r1.height)?;
    let second = args.second.as_ref().unwrap_or(&args.reference);
    for (img, path) in [(&r1, &args.reference), (&r2, second)] {
        super::check_finite(img, path, region)?;
    }
    Ok((r1, r2, region))
}

/// Makes the study's image folder and checks that its tables and plot can be written and are
/// none of the study's inputs.
fn check_outputs(args: &StudyArgs) -> Result<()> {
    let images = args.output.join("images");
    std::fs::create_dir_all(&images).map_err(|e| Error::File {
        path: images.clone(),
        message: format!("cannot create the study's folder: {e}"),
    })?;
    let compared: Vec<&Path> = args
        .compare
        .iter()
        .filter_map(|c| c.split_once('=').map(|(_, f)| Path::new(f)))
        .collect();
    let mut inputs = vec![args.scene.as_path(), args.reference.as_path()];
    inputs.extend(args.second.as_deref().into_iter().chain(compared));
    for name in ["study.csv", "study.md", "study.png"] {
        super::check_out(&args.output.join(name), &inputs)?;
    }
    Ok(())
}

/// Returns the settings of `caustic render SCENE FLAGS --seed SEED`, checked.
fn parse_job(scene: &Path, flags: &[String], seed: u64) -> Result<RenderJob> {
    let mut line: Vec<String> = vec![scene.display().to_string()];
    line.extend(flags.iter().cloned());
    line.extend(["--seed".into(), seed.to_string(), "-q".into()]);
    let parsed = RenderLine::try_parse_from(&line).map_err(|e| {
        let text = e.to_string();
        Error::Usage(text.lines().next().unwrap_or("bad flags").to_string())
    })?;
    let a = parsed.render;
    if a.output.is_some()
        || a.crop.is_some()
        || a.aa_map.is_some()
        || a.threads.is_some()
        || a.script.dialect.is_some()
        || !a.script.define.is_empty()
        || a.no_partial
    {
        return Err(Error::Usage(
            "-o, --crop, --aa-map, --threads, --dialect, -D and --no-partial are the study's to \
             set, not a setting's"
                .into(),
        ));
    }
    super::settings::check_scale(a.scale)?;
    RenderJob::from_args(&a)
}

/// Returns a file-name stem naming a setting's flags (`photons-10000_gather-rays-16`).
fn image_stem(flags: &[String]) -> String {
    let joined = flags.join("_").replace("--", "");
    let stem: String = joined
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if stem.is_empty() {
        "default".into()
    } else {
        stem.chars().take(150).collect()
    }
}

/// Returns a usage error unless `a` (read from `a_path`) has the size of `b` (from `b_path`).
fn same_size(a: &Image, a_path: &Path, b: &Image, b_path: &Path) -> Result<()> {
    if (a.width, a.height) == (b.width, b.height) {
        return Ok(());
    }
    Err(Error::Usage(format!(
        "{} is {}x{} but {} is {}x{}",
        a_path.display(),
        a.width,
        a.height,
        b_path.display(),
        b.width,
        b.height
    )))
}

/// Writes `text` to `path`, replacing it safely.
fn write(path: &Path, text: &str) -> Result<()> {
    crate::files::write_bytes(path, text.as_bytes()).map_err(|message| Error::File {
        path: path.to_path_buf(),
        message,
    })
}
