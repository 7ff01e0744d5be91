//! Anti-aliasing study: what the adaptive scheme and uniform stratified supersampling cost in time
//! and camera rays for the error they leave, against a high-spp reference of the same scene.
//!
//! ```text
//! cargo run --release -p caustic-tools --bin aa_study -- SCENE.lua [--scale F] [--ref-spp N]
//!     [--spp 1,4,9,16] [--thresholds 0.2,0.1,0.05] [--depth D] [--reps R]
//! ```
//!
//! Renders use every core; times are wall clock, the best of `--reps`. Error is the RMSE of the
//! linear pixel values against the reference, over all pixels and over the pixels on edges (where
//! the reference differs from its 1-spp render by more than 0.05 in some channel). Scenes with
//! photon maps are rendered without them (`--gi off` in the CLI's terms): this is about pixels.

use caustic::camera::Camera;
use caustic::film::{Film, Window};
use caustic::integrator::{GiMode, Settings};
use caustic::lua::run_script;
use caustic::progress::NoProgress;
use caustic::render::Sampling;
use caustic::scene::Scene;
use caustic::scene::build::build_scene;
use clap::Parser;
use std::cell::RefCell;
use std::path::PathBuf;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::Instant;

/// Compares adaptive and uniform anti-aliasing against a reference render.
#[derive(Parser)]
struct Cli {
    /// The Lua scene script (its first gr.render is used).
    scene: PathBuf,
    /// Render at this multiple of the script's image size.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Samples per pixel of the reference.
    #[arg(long, default_value_t = 400)]
    ref_spp: u32,
    /// Uniform rates to compare.
    #[arg(long, value_delimiter = ',', default_value = "1,4,9,16,25")]
    spp: Vec<u32>,
    /// Adaptive thresholds to compare.
    #[arg(long, value_delimiter = ',', default_value = "0.2,0.1,0.05,0.025")]
    thresholds: Vec<f32>,
    /// Adaptive subdivision depth.
    #[arg(long, default_value_t = 3)]
    depth: u32,
    /// Timed repetitions per configuration (the best is reported).
    #[arg(long, default_value_t = 3)]
    reps: u32,
}

/// Renders `sampling` `reps` times; returns the film and the best wall time.
fn timed(
    scene: &mut Scene,
    camera: &Camera,
    w: u32,
    h: u32,
    sampling: Sampling,
    reps: u32,
) -> (Film, f64) {
    let settings = Settings {
        sampling,
        gi: GiMode::Off,
        ..Settings::default()
    };
    let plan = caustic::frame::plan(scene, &settings);
    let mut best = f64::INFINITY;
    let mut film = None;
    for _ in 0..reps.max(1) {
        let start = Instant::now();
        let window = Window::full(w, h);
        let (f, _) =
            caustic::frame::render(scene, camera, window, &settings, plan.clone(), &NoProgress);
        best = best.min(start.elapsed().as_secs_f64());
        film = Some(f);
    }
    (film.expect("at least one repetition"), best)
}

/// Returns the RMSE of `a` against `b` over the pixels `which` selects.
fn rmse(a: &Film, b: &Film, which: &dyn Fn(usize) -> bool) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if which(i) {
            let d = *p - *q;
            sum += d.dot(d) as f64 / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let found = Rc::new(RefCell::new(None));
    let sink = Rc::clone(&found);
    let hook = Box::new(
        move |desc: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
            if sink.borrow().is_none() {
                let w = ((r.width as f64 * cli.scale).round() as u32).max(1);
                let h = ((r.height as f64 * cli.scale).round() as u32).max(1);
                let camera = Camera::new(&r.camera, w, h);
                *sink.borrow_mut() = Some((build_scene(desc, r)?, camera, w, h));
            }
            Ok(())
        },
    );
    if let Err(e) = run_script(&cli.scene, hook) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let Some((mut scene, camera, w, h)) = found.borrow_mut().take() else {
        eprintln!("error: {} calls no gr.render", cli.scene.display());
        return ExitCode::FAILURE;
    };
    let (reference, ref_s) = timed(
        &mut scene,
        &camera,
        w,
        h,
        Sampling::Stratified { spp: cli.ref_spp },
        1,
    );
    let (centre, _) = timed(
        &mut scene,
        &camera,
        w,
        h,
        Sampling::Stratified { spp: 1 },
        1,
    );
    let edge: Vec<bool> = reference
        .pixels
        .iter()
        .zip(&centre.pixels)
        .map(|(a, b)| (*a - *b).abs().max_element() > 0.05)
        .collect();
    let edges = edge.iter().filter(|&&e| e).count();
    println!(
        "{} at {w}x{h}, {} threads; reference {} spp in {ref_s:.2} s; {edges} edge pixels of {}",
        cli.scene.display(),
        rayon::current_num_threads(),
        cli.ref_spp,
        w * h
    );
    println!();
    println!("| sampling | camera rays per pixel | time (s) | RMSE all | RMSE edges |");
    println!("|---|---|---|---|---|");
    let row = |name: String, film: &Film, secs: f64| {
        let rays: u64 = film.samples.iter().map(|&s| s as u64).sum();
        println!(
            "| {name} | {:.2} | {secs:.3} | {:.5} | {:.5} |",
            rays as f64 / film.samples.len() as f64,
            rmse(film, &reference, &|_| true),
            rmse(film, &reference, &|i| edge[i]),
        );
    };
    for &spp in &cli.spp {
        let (film, secs) = timed(
            &mut scene,
            &camera,
            w,
            h,
            Sampling::Stratified { spp },
            cli.reps,
        );
        row(format!("uniform {spp} spp"), &film, secs);
    }
    for &threshold in &cli.thresholds {
        let sampling = Sampling::Adaptive {
            threshold,
            max_depth: cli.depth,
        };
        let (film, secs) = timed(&mut scene, &camera, w, h, sampling, cli.reps);
        row(
            format!("adaptive t={threshold} depth {}", cli.depth),
            &film,
            secs,
        );
    }
    ExitCode::SUCCESS
}
