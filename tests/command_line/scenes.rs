//! Every scene in `scenes/` runs and renders (generated meshes from the shared test cache).

use crate::common;

use crate::common::{caustic, out_dir};
use std::path::Path;

#[test]
fn every_scene_in_scenes_renders() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = out_dir("scenes");
    common::copy_assets(&root.join("scenes"), &tree.join("scenes"));
    // The scripts the scenes load (copy_assets leaves scripts out).
    for entry in std::fs::read_dir(root.join("scenes/lib")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "lua") {
            continue;
        }
        std::fs::copy(
            &path,
            tree.join("scenes/lib").join(path.file_name().unwrap()),
        )
        .unwrap();
    }
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

/// The test helpers and the command line render through the one frame call, so a scene whose
/// light asks for photon maps comes out the same, float for float, from both. (When the CLI
/// alone wired the photon passes, the helpers silently rendered without them.)
#[test]
fn test_helpers_render_exactly_what_the_command_line_writes() {
    let dir = out_dir("helpers-equal-cli");
    let src = "white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
        glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
        root = gr.node('root')
        box = gr.cube('box'); box:scale(4, 4, 4); box:translate(-2, -2, -2); box:set_material(white)
        ball = gr.sphere('ball'); ball:scale(0.6, 0.6, 0.6); ball:translate(0, -1, 0); ball:set_material(glass)
        root:add_child(box); root:add_child(ball)
        gr.render(root, 'x.exr', 24, 24, {0, 0, 1.9}, {0, 0, -1}, {0, 1, 0}, 70, {0.1, 0.1, 0.1},
                  {gr.light({0, 1.8, 0}, {1, 1, 1}, {1, 0, 0}, 100, 20000)})";
    std::fs::write(dir.join("s.lua"), src).unwrap();
    common::run_ok(caustic().current_dir(&dir).args([
        "render",
        "s.lua",
        "-q",
        "--gather-rays",
        "4",
    ]));
    let written = image::open(dir.join("x.exr")).unwrap().to_rgb32f();
    let settings = caustic::integrator::Settings {
        photons: caustic::integrator::photon_map::GiSettings {
            indirect: caustic::integrator::photon_map::Indirect::Gather { rays: 4 },
            ..Default::default()
        },
        ..Default::default()
    };
    let films = common::render_films_with(src.as_bytes(), "s.lua", &dir, &settings).unwrap();
    let film = &films[0].2;
    let mut differ = 0;
    for (p, q) in film.pixels.iter().zip(written.pixels()) {
        differ += usize::from(p.to_array() != q.0);
    }
    assert_eq!(differ, 0, "{differ} of {} pixels differ", film.pixels.len());
    // And the photon maps are really in it: the same scene without them is darker overall.
    let plain =
        common::render_films_with(src.as_bytes(), "s.lua", &dir, &common::whitted()).unwrap();
    let mean = |f: &caustic::film::Film| f.pixels.iter().map(|p| p.x).sum::<f32>();
    assert!(
        mean(film) > 1.05 * mean(&plain[0].2),
        "{} vs {}",
        mean(film),
        mean(&plain[0].2)
    );
}
