//! Measures photon tracing speed on a scene: photons traced per second with 1 and 2 threads,
//! for the global and caustic maps, over every `gr.render` of the script (usually one).
//!
//! ```text
//! cd ../shared/corpus/cs488/tengyucai__Computer-Graphics/Project
//! cargo run --release -p caustic-tools --bin bench_photon_trace -- Assets/room2.lua --photons 1000000
//! ```

use caustic::lua::run_script;
use caustic::photon::trace::{MapKind, photon_budget, trace_map};
use caustic::scene::build::build_scene;
use clap::Parser;
use std::cell::RefCell;
use std::path::PathBuf;
use std::process::ExitCode;
use std::rc::Rc;
use std::time::Instant;

/// Times photon tracing of a scene's maps with 1 and 2 threads.
#[derive(Parser)]
struct Cli {
    /// The Lua scene script.
    scene: PathBuf,
    /// Photons per map (each light's num_photons is ignored here so runs are comparable).
    #[arg(long, default_value_t = 1_000_000)]
    photons: u64,
    /// Timed repetitions per configuration (the best is reported).
    #[arg(long, default_value_t = 3)]
    reps: u32,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let scenes = Rc::new(RefCell::new(Vec::new()));
    let sink = Rc::clone(&scenes);
    let hook = Box::new(
        move |desc: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
            sink.borrow_mut().push(build_scene(desc, r)?);
            Ok(())
        },
    );
    if let Err(e) = run_script(&cli.scene, hook) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    for mut scene in Rc::try_unwrap(scenes).ok().unwrap().into_inner() {
        for l in &mut scene.lights {
            l.photons = None;
        }
        let budget = photon_budget(&scene.lights, cli.photons);
        for kind in [MapKind::Global, MapKind::Caustic] {
            let mut rates = Vec::new();
            for threads in [1usize, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut best = f64::INFINITY;
                let mut stored = 0;
                for _ in 0..cli.reps {
                    let start = Instant::now();
                    let map = pool.install(|| trace_map(&scene, &budget, kind, 0));
                    best = best.min(start.elapsed().as_secs_f64());
                    stored = map.len();
                }
                let emitted: u64 = budget.iter().sum();
                let rate = emitted as f64 / best / 1e6;
                rates.push(rate);
                println!(
                    "{kind:?} map, {threads} thread(s): {emitted} photons emitted, {stored} stored, best {best:.3} s = {rate:.3} M photons/s"
                );
            }
            println!(
                "{kind:?} map: 2-thread speed-up {:.2}x",
                rates[1] / rates[0]
            );
        }
    }
    ExitCode::SUCCESS
}
