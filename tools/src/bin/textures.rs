//! Generates the final scene's textures, deterministically, as 8-bit RGB PNGs:
//!
//! ```text
//! cargo run --release -p caustic-tools --bin textures -- -o scenes/textures
//! ```
//!
//! - `tiles_white.png`, `tiles_red.png`, `tiles_green.png`, `tiles_norm.png`: 8 × 8 glazed
//!   ceramic tiles, each a slightly different shade of the colour, in grey grout; the normal map
//!   bevels every tile's edge down into the grout. The red and green walls of a Cornell box
//!   bleed their colour onto the floor and the balls.
//! - `rock.png`, `rock_norm.png`: a rocky floor, fractal Perlin noise (six octaves) ridged into
//!   pebbles, coloured from its height; the normal map is the height field's slope.
//!
//! Normal maps follow `caustic::material::texture`'s convention: red along +u, green up the
//! image, blue along the normal, each byte `128 + 127·n`. Sizes default to 512 texels (about
//! 1.4 MB for the four files): enough for a 1024² render of a wall, small enough to commit.
//! The same size always gives the same bytes (no randomness but fixed hashes).

use caustic::io::image::write_rgb8_png;
use caustic::material::perlin::noise;
use caustic::sampling::mix64;
use clap::Parser;
use glam::{Vec3, Vec3A};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Writes tiles_{white,red,green}.png, tiles_norm.png, rock.png and rock_norm.png.
#[derive(Parser)]
struct Cli {
    /// Texels per side.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(16..=4096))]
    size: u32,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
}

/// A square height field and colour, one entry per texel, row 0 at the top.
struct Map {
    size: u32,
    height: Vec<f32>,
    colour: Vec<Vec3>,
}

impl Map {
    /// Returns the tangent-space normal-map bytes of the height field, `strength` the slope
    /// per unit height per texel.
    fn normal_bytes(&self, strength: f32) -> Vec<u8> {
        let n = self.size as i64;
        let h = |x: i64, y: i64| self.height[(y.rem_euclid(n) * n + x.rem_euclid(n)) as usize];
        let mut out = Vec::with_capacity((n * n * 3) as usize);
        for y in 0..n {
            for x in 0..n {
                let dx = (h(x + 1, y) - h(x - 1, y)) * 0.5 * strength;
                // Green points up the image, towards row y - 1.
                let dup = (h(x, y - 1) - h(x, y + 1)) * 0.5 * strength;
                let normal = Vec3::new(-dx, -dup, 1.0).normalize();
                out.extend(normal.to_array().map(|c| (128.0 + 127.0 * c).round() as u8));
            }
        }
        out
    }

    fn colour_bytes(&self) -> Vec<u8> {
        self.colour
            .iter()
            .flat_map(|c| {
                c.to_array()
                    .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            })
            .collect()
    }
}

/// A uniform number in [0, 1) from a hash of `keys`.
fn hash01(keys: &[u64]) -> f32 {
    let h = keys
        .iter()
        .fold(0x9E37_79B9_7F4A_7C15, |h, &k| mix64(h ^ k));
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Fractal Perlin noise: `octaves` of [`noise`], each twice the frequency and half the amplitude.
fn fbm(p: Vec3A, octaves: u32) -> f32 {
    (0..octaves)
        .map(|o| noise(p * (1 << o) as f32) / (1 << o) as f32)
        .sum()
}

/// 8 × 8 tiles of colour `base` with grout a sixteenth of a tile wide and bevelled edges.
fn tiles(size: u32, base: Vec3) -> Map {
    const TILES: f32 = 8.0;
    let (mut height, mut colour) = (Vec::new(), Vec::new());
    for y in 0..size {
        for x in 0..size {
            let u = (x as f32 + 0.5) / size as f32 * TILES;
            let v = (y as f32 + 0.5) / size as f32 * TILES;
            let (i, j) = (u.floor() as u64, v.floor() as u64);
            // Distance from the tile's edge, in tile widths, and the grout line at 1/32 each side.
            let edge = (u.fract().min(1.0 - u.fract())).min(v.fract().min(1.0 - v.fract()));
            let rise = ((edge - 1.0 / 32.0) / 0.06).clamp(0.0, 1.0);
            let glaze = 0.02 * noise(Vec3A::new(u * 6.0, v * 6.0, 0.5));
            height.push(rise * rise * (3.0 - 2.0 * rise) + glaze);
            let tile = base * (0.88 + 0.16 * hash01(&[i, j]));
            let grout = Vec3::splat(0.45 + 0.05 * noise(Vec3A::new(u * 20.0, v * 20.0, 3.5)));
            colour.push(grout.lerp(tile, rise.min(1.0) * 0.9 + 0.1 * (rise > 0.0) as u8 as f32));
        }
    }
    Map {
        size,
        height,
        colour,
    }
}

/// Rocky ground: ridged fractal noise for pebbles over a gentle undulation.
fn rock(size: u32) -> Map {
    let (mut height, mut colour) = (Vec::new(), Vec::new());
    for y in 0..size {
        for x in 0..size {
            let p = Vec3A::new(x as f32, y as f32, 0.0) / size as f32;
            let pebbles = 1.0 - fbm(p * 12.0 + Vec3A::new(0.0, 0.0, 7.3), 4).abs() * 1.6;
            let grain = fbm(p * 80.0 + Vec3A::new(3.1, 0.0, 1.7), 3);
            let h = 0.7 * pebbles.clamp(0.0, 1.0) + 0.1 * grain + 0.2 * fbm(p * 3.0, 2);
            height.push(h);
            let dirt = Vec3::new(0.42, 0.36, 0.30);
            let stone = Vec3::new(0.66, 0.63, 0.58);
            let fleck = 0.06 * noise(p * 200.0 + Vec3A::splat(0.3));
            colour.push(dirt.lerp(stone, pebbles.clamp(0.0, 1.0)) + Vec3::splat(fleck));
        }
    }
    Map {
        size,
        height,
        colour,
    }
}

fn write(path: &Path, size: u32, bytes: &[u8]) -> Result<(), String> {
    write_rgb8_png(path, size, size, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("{}: {size}x{size}", path.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = std::fs::create_dir_all(&cli.output) {
        eprintln!("textures: cannot create {}: {e}", cli.output.display());
        return ExitCode::FAILURE;
    }
    let s = cli.size;
    // Normal strength in slope per texel: the bevel spans about 4 texels at 512.
    let scale = s as f32 / 512.0;
    let colours = [
        ("white", Vec3::new(0.78, 0.77, 0.74)),
        ("red", Vec3::new(0.72, 0.14, 0.10)),
        ("green", Vec3::new(0.16, 0.52, 0.20)),
    ];
    let mut result = Ok(());
    let mut t = None;
    for (name, base) in colours {
        let map = tiles(s, base);
        let path = cli.output.join(format!("tiles_{name}.png"));
        result = result.and_then(|()| write(&path, s, &map.colour_bytes()));
        t = Some(map);
    }
    let t = t.expect("three tile colours");
    let r = rock(s);
    let result = result
        .and_then(|()| {
            write(
                &cli.output.join("tiles_norm.png"),
                s,
                &t.normal_bytes(2.0 * scale),
            )
        })
        .and_then(|()| write(&cli.output.join("rock.png"), s, &r.colour_bytes()))
        .and_then(|()| {
            write(
                &cli.output.join("rock_norm.png"),
                s,
                &r.normal_bytes(6.0 * scale),
            )
        });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("textures: cannot write {e}");
            ExitCode::FAILURE
        }
    }
}
