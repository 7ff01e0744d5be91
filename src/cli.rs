//! The command line: `caustic render` and `caustic info`, and what each runs.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::io::image::write_png;
use crate::render::render;
use crate::scene::build::{build_scene, count_placements};
use crate::scene::desc::{RenderDesc, SceneDesc};
use crate::scene::lua::run_script;
use clap::{Args, Parser, Subcommand};
use std::cell::Cell;
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
    let (scale, stats) = (args.scale, args.stats);
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
        let (w, h) = scaled_size(r, scale);
        let start = Instant::now();
        let scene = build_scene(desc, r)?;
        let camera = Camera::new(&r.camera, w, h);
        let (film, rstats) = render(&scene, &camera, w, h);
        write_png(&film, &out)?;
        eprintln!(
            "wrote {} ({w}x{h}) in {:.2} s",
            out.display(),
            start.elapsed().as_secs_f64()
        );
        if stats {
            let b = &scene.stats;
            println!("image {}: {w}x{h} from {}", out.display(), r.loc);
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
        }
        Ok(())
    });
    let _seed = args.seed; // No random stream exists yet: the first renderer is deterministic.
    run_script(&args.scene, hook)?;
    if rendered.get() == 0 {
        eprintln!(
            "warning: {} never called gr.render; no image written",
            args.scene.display()
        );
    }
    Ok(())
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
    let triangles: usize = desc.meshes.iter().map(|m| m.data.triangles.len()).sum();
    let _ = writeln!(s, "scene {name}");
    let _ = writeln!(s, "  nodes: {} ({})", desc.nodes.len(), list(&kinds));
    let _ = writeln!(
        s,
        "  meshes: {} files, {triangles} triangles",
        desc.meshes.len()
    );
    for m in &desc.meshes {
        let _ = writeln!(
            s,
            "    {}: {} triangles",
            m.data.source.display(),
            m.data.triangles.len()
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
