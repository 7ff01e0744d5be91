//! Every scene in `scenes/` runs and renders; big generated meshes are replaced by small ones
//! made here, at the path the scene expects.

mod common;

use caustic::geometry::water::{WaveParams, wave_mesh};
use common::{caustic, out_dir};
use std::path::Path;

#[test]
fn every_scene_in_scenes_renders() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = out_dir("scenes");
    std::fs::create_dir_all(tree.join("scenes")).unwrap();
    std::fs::create_dir_all(tree.join("meshes")).unwrap();
    // The showcase's 2M-triangle water surface, at 65×65 vertices for the test.
    let mesh = wave_mesh(&WaveParams {
        n: 65,
        size: 2.0,
        seed: 7,
        ..WaveParams::default()
    });
    caustic::io::gltf::write_gltf(&mesh, &tree.join("meshes/water_1001.glb")).unwrap();
    let mut count = 0;
    for entry in std::fs::read_dir(root.join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "lua") {
            continue;
        }
        let name = path.file_name().unwrap();
        std::fs::copy(&path, tree.join("scenes").join(name)).unwrap();
        let png = tree.join(format!("{}.png", name.to_string_lossy()));
        let out = caustic()
            .current_dir(&tree)
            .arg("render")
            .arg(Path::new("scenes").join(name))
            .args(["--scale", "0.1", "-q", "-o"])
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}: {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        let img = image::open(&png).unwrap();
        assert!(img.width() > 0 && img.height() > 0);
        count += 1;
    }
    assert!(count >= 1, "scenes/ has no scene");
}
