//! Meshes a script generates: `gr.water_mesh(name, {params})`, a wave surface written once as a
//! glTF binary (`.glb`) in a cache folder and then loaded like any `gr.mesh` file.
//!
//! ```lua
//! surface = gr.water_mesh('water', {n = 1001, seed = 7, size = 2.2, amplitude = 0.012,
//!                                   wavelength = 0.5})
//! surface:set_material(water)
//! ```
//!
//! With `depth = d` the surface is closed into a body of water `d` deep below `y = 0` (sides
//! and a flat bottom, [`close_volume`]): a solid whose refraction and nested media are exact
//! wherever the camera or a photon enters it, including through its sides.
//!
//! # Why a cached file, not geometry made in memory
//! - A fresh clone renders a scene with a 2M-triangle water surface with no separate step, and
//!   every later run (a preview, then the final image; the tiles of a render farm) reads the
//!   same file instead of sampling the waves again.
//! - The mesh then takes the glTF importer's path, the one a user's own water (from Blender or
//!   our `water` tool) takes, so what renders is what the tool and other programs read too:
//!   `caustic export-mitsuba` hands the same file to Mitsuba.
//!
//! The file is `<cache>/water-n<N>-<fingerprint>.glb`, where the fingerprint is a 64-bit hash of
//! every parameter and [`GENERATOR_VERSION`]: the same table always names the same file, a
//! changed one a new file, and a file is never reused for other parameters. `<cache>` is
//! `$CAUSTIC_CACHE` when set, else `.cache` in the script's folder (ignored by git). The file is
//! written to a temporary name and renamed ([`crate::files::write_replacing`]), so tiles of a farm
//! generating it at once never read half a file. The parameters are those of
//! [`WaveParams`]; `n` is bounded here by [`MAX_SCRIPT_N`] (33.6M triangles), the tool allows more.

use super::State;
use crate::desc::MeshId;
use crate::error::Fault;
use crate::geometry::water::{WaveParams, close_volume, wave_mesh};
use crate::lua::args::Args;
use mlua::Value;
use std::path::PathBuf;

/// Bumped whenever [`wave_mesh`] or the glTF writer changes what a parameter table produces.
pub const GENERATOR_VERSION: u64 = 1;

/// Largest grid side a script may ask for: 2·4096² ≈ 33.6M triangles, about 940 MB of file
/// (the pool surface of issue 39; each new file is also charged to the memory budget).
pub const MAX_SCRIPT_N: u32 = 4097;

/// The keys `gr.water_mesh`'s table accepts, as the message for an unknown one lists them.
const KEYS: &[&str] = &[
    "n",
    "seed",
    "size",
    "waves",
    "amplitude",
    "wavelength",
    "spread",
    "depth",
];

/// `gr.water_mesh(name, params)`: the mesh of a cached wave surface (see the module doc).
pub(super) fn water_mesh(s: &mut State, a: &Args) -> mlua::Result<MeshId> {
    let (params, depth) = wave_params(a)?;
    let path = cache_dir(s).join(format!(
        "water-n{}-{:016x}.glb",
        params.n,
        fingerprint(&params, depth)
    ));
    if !path.is_file() {
        // What a script writes is part of what it creates: a loop over parameters would fill
        // the disk with meshes it never renders. Each new file is charged to the budget, at
        // about 60 bytes per grid vertex (positions, normals, coordinates and two triangles).
        let n = u64::from(params.n);
        super::gr::charge(
            s,
            a,
            (n * n * 60) as usize,
            &format!("a new {n}x{n} generated water mesh file"),
        )?;
        let folder = path.parent().expect("the cache path has a folder");
        let written = std::fs::create_dir_all(folder)
            .map_err(|e| e.to_string())
            .and_then(|()| {
                let mut mesh = wave_mesh(&params);
                if let Some(depth) = depth {
                    close_volume(&mut mesh, &params, -depth);
                }
                crate::io::gltf::write_gltf(&mesh, &path).map_err(|e| e.to_string())
            });
        if let Err(e) = written {
            return Err(a.fault(
                Fault::MeshLoad,
                format!(
                    "cannot write the generated water mesh {}: {e} (set CAUSTIC_CACHE to a writable folder)",
                    path.display()
                ),
            ));
        }
    }
    // A mesh caustic generated itself, in its cache: not a file the scene names, so outside
    // the sandbox's read folders (CAUSTIC_CACHE may be anywhere).
    super::gr::mesh_at(s, a, &path.to_string_lossy(), path.clone())
}

/// Reads argument 2, a table of [`KEYS`], over [`WaveParams::default`], and the depth of a
/// closed volume (`None`: an open surface).
fn wave_params(a: &Args) -> mlua::Result<(WaveParams, Option<f32>)> {
    let table = match a.get(2) {
        Some(Value::Table(t)) => t.clone(),
        None | Some(Value::Nil) => return Ok((WaveParams::default(), None)),
        Some(v) => {
            return Err(a.bad(
                2,
                format!("table expected, got {}", super::args::type_name(v)),
            ));
        }
    };
    let mut p = WaveParams::default();
    let mut depth = None;
    for pair in table.pairs::<Value, Value>() {
        let (key, value) = pair?;
        let Value::String(key) = key else {
            return Err(a.bad(2, "keys must be names such as n, seed, size"));
        };
        let key = key.to_str()?.to_string();
        let number = match value {
            Value::Integer(i) => i as f64,
            Value::Number(x) => x,
            ref v => {
                return Err(a.bad(
                    2,
                    format!(
                        "'{key}' must be a number, got {}",
                        super::args::type_name(v)
                    ),
                ));
            }
        };
        if !number.is_finite() {
            return Err(a.bad(2, format!("'{key}' must be finite")));
        }
        let count = |lo: f64, hi: f64| -> mlua::Result<f64> {
            if number.fract() != 0.0 || !(lo..=hi).contains(&number) {
                return Err(a.bad(2, format!("'{key}' must be a whole number in {lo}..={hi}")));
            }
            Ok(number)
        };
        let positive = || -> mlua::Result<f32> {
            if number <= 0.0 || number > 1e6 {
                return Err(a.bad(2, format!("'{key}' must be in (0, 1e6]")));
            }
            Ok(number as f32)
        };
        match key.as_str() {
            "n" => p.n = count(2.0, MAX_SCRIPT_N as f64)? as u32,
            "seed" => p.seed = count(0.0, 2f64.powi(53))? as u64,
            "waves" => p.waves = count(1.0, 256.0)? as u32,
            "size" => p.size = positive()?,
            "depth" => depth = Some(positive()?),
            "wavelength" => p.wavelength = positive()?,
            "amplitude" => {
                if !(0.0..=1e6).contains(&number) {
                    return Err(a.bad(2, "'amplitude' must be in [0, 1e6]"));
                }
                p.amplitude = number as f32
            }
            "spread" => {
                if !(0.0..=std::f64::consts::PI).contains(&number) {
                    return Err(a.bad(2, "'spread' must be an angle in [0, pi] radians"));
                }
                p.spread = number as f32
            }
            _ => {
                return Err(a.bad(
                    2,
                    format!("unknown key '{key}' (the keys are {})", KEYS.join(", ")),
                ));
            }
        }
    }
    if let Some(d) = depth
        && d <= p.amplitude
    {
        return Err(a.bad(
            2,
            format!(
                "'depth' ({d}) must exceed 'amplitude' ({}): the bottom lies below the waves",
                p.amplitude
            ),
        ));
    }
    Ok((p, depth))
}

/// The folder generated meshes go to: `$CAUSTIC_CACHE`, else `.cache` beside the script.
fn cache_dir(s: &State) -> PathBuf {
    match std::env::var_os("CAUSTIC_CACHE") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => s.script_dir.join(".cache"),
    }
}

/// A 64-bit hash of every parameter, the depth and the generator's version.
pub fn fingerprint(p: &WaveParams, depth: Option<f32>) -> u64 {
    let words = [
        GENERATOR_VERSION,
        p.n as u64,
        p.seed,
        p.waves as u64,
        p.size.to_bits() as u64,
        p.amplitude.to_bits() as u64,
        p.wavelength.to_bits() as u64,
        p.spread.to_bits() as u64,
        depth.map_or(u64::MAX, |d| d.to_bits() as u64),
    ];
    words.iter().fold(0x243F_6A88_85A3_08D3, |h, &w| {
        crate::sampling::mix64(h ^ crate::sampling::mix64(w))
    })
}
