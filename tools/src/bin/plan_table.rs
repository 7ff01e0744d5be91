//! What the effect plan saves: every scene of `scenes/` and the corpus rendered as the plan
//! decides and with every overridable effect but photon maps forced on (caustics, final
//! gathering, refraction, soft shadows, textures, normal maps, noise), as a Markdown table of
//! the effects the plan skipped, the two times, their ratio and whether the images are
//! bit-identical.
//!
//! ```text
//! cargo run --release -p caustic-tools --bin plan_table -- [--size 96] [DIR_OR_SCRIPT...]
//! ```
//!
//! Without arguments it takes `scenes/` and `../shared/corpus/cs488/`. Each script's first
//! `gr.render` is rendered at `--size` pixels along its longer side (photon counts follow the
//! image), from its own folder or else the folder above it (projects that open `Assets/...`).
//! Times are wall clock on every core: run it on an idle machine. Photon maps are not forced:
//! on a course scene they change its lighting model (global illumination instead of the
//! ambient term), so its images would differ by design, and the effects that need them are then
//! forced in vain. For every other effect a skipped effect is one whose absence leaves the image
//! unchanged, bit for bit.

use caustic::desc::{RenderDesc, SceneDesc};
use caustic::frame::render_desc;
use caustic::integrator::Settings;
use caustic::integrator::plan::{Effect, Overrides};
use caustic::lua::run_source;
use caustic::progress::NoProgress;
use clap::Parser;
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

/// Renders scenes with the plan and with everything forced on.
#[derive(Parser)]
struct Cli {
    /// Scripts or folders of scripts (default: scenes/ and ../shared/corpus/cs488/).
    paths: Vec<PathBuf>,
    /// Pixels along each image's longer side.
    #[arg(long, default_value_t = 96)]
    size: u32,
}

/// One row of the table.
struct Row {
    script: String,
    skipped: Vec<&'static str>,
    plan_s: f64,
    forced_s: f64,
    identical: bool,
}

/// Returns every `.lua` file under `path` (or `path` itself), sorted.
fn scripts(path: &Path) -> Vec<PathBuf> {
    if path.is_file() {
        return vec![path.to_path_buf()];
    }
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(path) {
        for entry in entries.flatten() {
            let p = entry.path();
            if p.is_dir() {
                out.extend(scripts(&p));
            } else if p.extension().is_some_and(|e| e == "lua") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Renders `script`'s first image from `dir` both ways; returns its row.
fn measure(script: &Path, dir: &Path, size: u32) -> Result<Option<Row>, caustic::Error> {
    let src = std::fs::read(script).map_err(|e| caustic::Error::Usage(e.to_string()))?;
    let row = Rc::new(RefCell::new(None));
    let sink = Rc::clone(&row);
    let name = script.display().to_string();
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| {
        if sink.borrow().is_some() {
            return Ok(());
        }
        let scale = size as f64 / r.width.max(r.height) as f64;
        let plan_settings = Settings::default();
        let forced = Settings {
            overrides: Overrides {
                force: Effect::OVERRIDABLE
                    .into_iter()
                    .filter(|&e| e != Effect::PhotonMaps)
                    .collect(),
                disable: Vec::new(),
            },
            ..Settings::default()
        };
        let start = Instant::now();
        let a = render_desc(desc, r, scale, None, &plan_settings, &NoProgress)?;
        let plan_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let b = render_desc(desc, r, scale, None, &forced, &NoProgress)?;
        let forced_s = start.elapsed().as_secs_f64();
        let skipped = a
            .stats
            .plan
            .decisions
            .iter()
            .filter(|d| {
                !d.on && Effect::OVERRIDABLE.contains(&d.effect) && d.effect != Effect::PhotonMaps
            })
            .map(|d| d.effect.name())
            .collect();
        *sink.borrow_mut() = Some(Row {
            script: String::new(),
            skipped,
            plan_s,
            forced_s,
            identical: a.film.pixels == b.film.pixels,
        });
        Ok(())
    });
    run_source(&src, &name, dir, hook)?;
    Ok(Rc::try_unwrap(row).ok().and_then(|r| r.into_inner()))
}

fn main() {
    let cli = Cli::parse();
    let paths = if cli.paths.is_empty() {
        vec![
            PathBuf::from("scenes"),
            PathBuf::from("../shared/corpus/cs488"),
        ]
    } else {
        cli.paths.clone()
    };
    println!("| scene | effects the plan skipped | plan s | all forced s | ratio | identical |");
    println!("|---|---|---|---|---|---|");
    let mut failed = Vec::new();
    for script in paths.iter().flat_map(|p| scripts(p)) {
        let own = script.parent().unwrap_or(Path::new(".")).to_path_buf();
        let above = own.parent().unwrap_or(Path::new(".")).to_path_buf();
        let result =
            measure(&script, &own, cli.size).or_else(|_| measure(&script, &above, cli.size));
        match result {
            Ok(Some(mut row)) => {
                row.script = script.display().to_string();
                let skipped = if row.skipped.is_empty() {
                    "none".to_string()
                } else {
                    row.skipped.join(", ")
                };
                println!(
                    "| {} | {skipped} | {:.2} | {:.2} | {:.1}x | {} |",
                    row.script,
                    row.plan_s,
                    row.forced_s,
                    row.forced_s / row.plan_s.max(1e-9),
                    if row.identical { "yes" } else { "no" }
                );
            }
            Ok(None) => failed.push(format!("{}: no gr.render", script.display())),
            Err(e) => failed.push(format!("{}: {e}", script.display())),
        }
    }
    for f in failed {
        eprintln!("not rendered: {f}");
    }
}
