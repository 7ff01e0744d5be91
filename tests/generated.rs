//! Meshes a scene makes for itself: `gr.water_mesh` (a wave surface or a closed body of water,
//! generated once into a cache as glTF).

mod common;

use caustic::desc::MeshSource;
use caustic::geometry::water::{WaveParams, close_volume, wave_mesh};
use common::{out_dir, run_lua_in};
use std::path::{Path, PathBuf};

/// Returns the file the script's only mesh resolved to.
fn mesh_file(src: &str, dir: &Path) -> PathBuf {
    let desc = run_lua_in(src, dir).unwrap();
    match &desc.meshes[0].source {
        MeshSource::File { path, .. } => path.clone(),
        other => panic!("expected a file mesh, got {other:?}"),
    }
}

#[test]
fn water_mesh_writes_the_generator_output_once_per_parameter_set() {
    let dir = out_dir("water-mesh-cache");
    let src = "w = gr.water_mesh('w', {n = 33, seed = 3, size = 2, amplitude = 0.02, depth = 0.5})";
    let path = mesh_file(src, &dir);
    assert!(path.starts_with(dir.join(".cache")), "{}", path.display());
    // The file holds exactly the generator's closed volume, number for number.
    let p = WaveParams {
        n: 33,
        seed: 3,
        size: 2.0,
        amplitude: 0.02,
        ..WaveParams::default()
    };
    let mut expected = wave_mesh(&p);
    close_volume(&mut expected, &p, -0.5);
    let read = caustic::io::gltf::load_gltf(&path).unwrap();
    assert_eq!(read.positions, expected.positions);
    assert_eq!(read.triangles, expected.triangles);
    assert_eq!(read.normals, expected.normals);
    // A second run reuses the file (not rewritten), the same table names the same file, and
    // another table (here one more wave, or no depth) another file.
    let written = std::fs::metadata(&path).unwrap().modified().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    assert_eq!(mesh_file(src, &dir), path);
    assert_eq!(
        std::fs::metadata(&path).unwrap().modified().unwrap(),
        written
    );
    let other = mesh_file(&src.replace("seed = 3", "seed = 3, waves = 9"), &dir);
    let open = mesh_file(&src.replace(", depth = 0.5", ""), &dir);
    assert_ne!(other, path);
    assert_ne!(open, path);
    assert_eq!(
        caustic::io::gltf::load_gltf(&open).unwrap().triangles.len(),
        2 * 32 * 32,
        "without depth the surface stays open"
    );
    let files = std::fs::read_dir(dir.join(".cache")).unwrap().count();
    assert_eq!(files, 3, "one file per distinct table, no temporary left");
}

#[test]
fn water_mesh_rejects_bad_tables_naming_the_key() {
    let dir = out_dir("water-mesh-errors");
    let cases = [
        ("{n = 1}", "'n' must be a whole number in 2..=2049"),
        ("{n = 5000}", "'n' must be a whole number in 2..=2049"),
        ("{n = 2.5}", "'n' must be a whole number"),
        ("{size = -1}", "'size' must be in (0, 1e6]"),
        (
            "{sise = 2}",
            "unknown key 'sise' (the keys are n, seed, size",
        ),
        ("{seed = 'x'}", "'seed' must be a number, got string"),
        (
            "{amplitude = 0.2, depth = 0.1}",
            "'depth' (0.1) must exceed 'amplitude' (0.2)",
        ),
        ("{spread = 4}", "'spread' must be an angle in [0, pi]"),
        ("{n = 0/0}", "'n' must be finite"),
        ("7", "table expected, got number"),
    ];
    for (table, want) in cases {
        let src = format!("w = gr.water_mesh('w', {table})");
        let e = run_lua_in(&src, &dir).unwrap_err().to_string();
        assert!(
            e.starts_with("test.lua:1: bad argument #2 to 'water_mesh'") && e.contains(want),
            "{table}: {e}"
        );
    }
    assert!(!dir.join(".cache").exists(), "no file for a rejected table");
}
