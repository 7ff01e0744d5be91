//! Generates a water-surface mesh (a seedable sum of sine waves, see `caustic::geometry::water`)
//! and writes it as OBJ, glTF (`.gltf` + `.bin`) or GLB, chosen by the output's extension:
//!
//! ```text
//! cargo run --release -p caustic-tools --bin water -- --n 1001 --seed 7 -o meshes/water_1001.obj
//! ```

use caustic::geometry::water::{MAX_N, WaveParams, close_volume, wave_mesh};
use caustic::io::{gltf, obj};
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Writes an N×N water height field with analytic normals and uvs.
#[derive(Parser)]
struct Cli {
    /// Vertices per side (N×N vertices, 2(N-1)² triangles).
    #[arg(long, default_value_t = 129, value_parser = clap::value_parser!(u32).range(2..=MAX_N as i64))]
    n: u32,
    /// Side length of the square surface, centred on the origin in the xz plane.
    #[arg(long, default_value_t = 10.0)]
    size: f32,
    /// Seed of the wave components.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Number of sine components.
    #[arg(long, default_value_t = 8)]
    waves: u32,
    /// Sum of the component amplitudes (a bound on |y|).
    #[arg(long, default_value_t = 0.1)]
    amplitude: f32,
    /// Longest wavelength; components range down to a quarter of it.
    #[arg(long, default_value_t = 2.0)]
    wavelength: f32,
    /// Largest angle in radians between a component's direction and +x.
    #[arg(long, default_value_t = 0.6)]
    spread: f32,
    /// Close the surface into a body of water this deep below y = 0 (sides and a flat bottom,
    /// as `gr.water_mesh`'s `depth`); by default the surface stays open.
    #[arg(long)]
    depth: Option<f32>,
    /// Output file: .obj, .gltf (with a .bin beside it) or .glb.
    #[arg(short, long)]
    output: PathBuf,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let numbers = [
        cli.size,
        cli.amplitude,
        cli.wavelength,
        cli.spread,
        cli.depth.unwrap_or(1.0),
    ];
    if numbers.iter().any(|x| !x.is_finite()) || cli.size <= 0.0 || cli.wavelength <= 0.0 {
        eprintln!("water: size and wavelength must be positive, all numbers finite");
        return ExitCode::FAILURE;
    }
    let params = WaveParams {
        n: cli.n,
        size: cli.size,
        seed: cli.seed,
        waves: cli.waves,
        amplitude: cli.amplitude,
        wavelength: cli.wavelength,
        spread: cli.spread,
    };
    let ext = cli
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let write = match ext.as_str() {
        "obj" => obj::write_obj,
        "gltf" | "glb" => gltf::write_gltf,
        _ => {
            eprintln!("water: output must end in .obj, .gltf or .glb");
            return ExitCode::FAILURE;
        }
    };
    let start = Instant::now();
    let mut mesh = wave_mesh(&params);
    if let Some(depth) = cli.depth {
        if depth <= cli.amplitude {
            eprintln!("water: --depth must exceed --amplitude (the bottom lies below the waves)");
            return ExitCode::FAILURE;
        }
        close_volume(&mut mesh, &params, -depth);
    }
    let generated = start.elapsed();
    let folder = cli.output.parent().filter(|p| !p.as_os_str().is_empty());
    let written = folder
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| write(&mesh, &cli.output));
    if let Err(e) = written {
        eprintln!("water: cannot write {}: {e}", cli.output.display());
        return ExitCode::FAILURE;
    }
    println!(
        "{}: {} vertices, {} triangles (generated in {:.2?}, written in {:.2?})",
        cli.output.display(),
        mesh.positions.len(),
        mesh.triangle_count(),
        generated,
        start.elapsed() - generated
    );
    ExitCode::SUCCESS
}
