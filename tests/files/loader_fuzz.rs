//! Property-based tests (proptest) of everything that reads user files: Lua scripts, OBJ, MTL,
//! PNG textures and stitch tiles, fed random and mutated inputs. Each property is "an error or a
//! result, never a panic" (a panic fails the case). Lua runs under its memory limit; the files
//! are small, so a loader that trusted a count it read would fail by panicking or aborting, not
//! quietly. CI runs 48 cases per property; `tools/fuzz.sh SECONDS` runs a long campaign
//! (`PROPTEST_CASES`) under a `ulimit -v` memory limit.

use crate::common::{Edit, mutate, out_dir, proptest_config};
use caustic::error::Loc;
use caustic::scene::images::ImageCache;
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One edit of a byte string: overwrite, flip a bit, insert, delete or truncate.
fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), 0u8..8).prop_map(|(i, b)| Edit::Flip(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Insert(i, b)),
        any::<usize>().prop_map(Edit::Delete),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

/// Numbers that stress parsers: huge, tiny, negative, non-finite spellings and index-like ones.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v}")),
        any::<i64>().prop_map(|v| v.to_string()),
        Just("1e308".to_string()),
        Just("-1e39".to_string()),
        Just("0".to_string()),
        Just("nan".to_string()),
        Just("4294967295".to_string()),
        (0u32..4).prop_map(|v| v.to_string()),
    ]
}

/// `n` hostile numbers to write into a file, and up to 5 edits of the file.
fn numbers_and_edits(n: usize) -> impl Strategy<Value = (Vec<String>, Vec<Edit>)> {
    (
        prop::collection::vec(number(), n),
        prop::collection::vec(edit(), 0..6),
    )
}

const SCENE: &str = include_str!("../../scenes/cornell_glass.lua");

fn loc() -> Loc {
    Loc {
        file: Arc::from("fuzz.lua"),
        line: 1,
    }
}

/// A Lua call of `gr` with random arguments: tables of numbers, strings, nil.
fn gr_call() -> impl Strategy<Value = String> {
    let name = prop::sample::select(vec![
        "node",
        "sphere",
        "cube",
        "mesh",
        "material",
        "light",
        "area_light",
        "sphere_light",
        "spot_light",
        "directional_light",
        "nh_sphere",
        "nh_box",
        "cylinder",
        "cone",
        "texture",
        "render",
        "union",
        "difference",
    ]);
    let arg = prop_oneof![
        number(),
        prop::collection::vec(number(), 0..5).prop_map(|v| format!("{{{}}}", v.join(", "))),
        "[a-z./]{0,12}".prop_map(|s| format!("'{s}'")),
        Just("nil".to_string()),
        Just("n".to_string()),
    ];
    // Each call in a pcall, so one bad call does not end the script before the others run.
    (name, prop::collection::vec(arg, 0..11))
        .prop_map(|(f, args)| format!("pcall(function() n = gr.{f}({}) end)", args.join(", ")))
}

/// Runs a script without rendering; `gr.render` calls build the scene (meshes, textures), which
/// is where bad values surface.
fn run_script(src: &str, dir: &Path) {
    let hook = Box::new(
        |d: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
            caustic::scene::build::build_scene(d, r).map(|_| ())
        },
    );
    let _ = caustic::lua::run_source(src.as_bytes(), "fuzz.lua", dir, hook);
}

proptest! {
    #![proptest_config(proptest_config(48))]

    /// Random sequences of gr calls with hostile arguments: a located error or a scene.
    #[test]
    fn random_gr_calls_never_panic(calls in prop::collection::vec(gr_call(), 1..12)) {
        let dir = out_dir_once("fuzz_lua");
        // Then render whatever n is, so the scene is built from what the calls made.
        let render = "pcall(function() gr.render(n, 'x.png', 4, 4, {0,0,5}, {0,0,-1}, {0,1,0}, 50, \
                      {0,0,0}, {gr.light({0,0,5}, {1,1,1}, {1,0,0})}) end)";
        run_script(&format!("{}\n{render}", calls.join("\n")), &dir);
    }

    /// The showcase script with bytes edited (edits that could make a loop keyword are skipped:
    /// an endless script is the user's to stop, not a crash).
    #[test]
    fn mutated_scripts_never_panic(edits in prop::collection::vec(edit(), 1..6)) {
        let src = String::from_utf8_lossy(&mutate(SCENE.as_bytes(), &edits)).into_owned();
        prop_assume!(!["while", "repeat", "for", "goto"].iter().any(|k| src.contains(k)));
        let dir = out_dir_once("fuzz_lua");
        run_script(&src, &dir);
    }

    /// OBJ text with hostile numbers and indices, then mutated: an error naming the file or a
    /// mesh whose indices are in range.
    #[test]
    fn mutated_obj_files_never_panic(
        (nums, edits) in numbers_and_edits(12),
    ) {
        let text = format!(
            "mtllib m.mtl\nv {} {} {}\nv {} {} {}\nv {} {} {}\nvt {} {}\nvn 0 1 0\nusemtl a\nf 1/1/1 2/1/1 {}\nf -1 -2 {}\n",
            nums[0], nums[1], nums[2], nums[3], nums[4], nums[5], nums[6], nums[7], nums[8],
            nums[9], nums[10], nums[11], nums[0]
        );
        let dir = out_dir_once("fuzz_obj");
        let path = dir.join(format!("f{}.obj", unique()));
        std::fs::write(&path, mutate(text.as_bytes(), &edits)).unwrap();
        std::fs::write(dir.join("m.mtl"), "newmtl a\nKd 0.5 0.5 0.5\n").unwrap();
        if let Ok(mesh) = caustic::io::obj::load_obj(&path) {
            let n = mesh.positions.len();
            prop_assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
        }
        let _ = std::fs::remove_file(&path);
    }

    /// MTL text mutated (colours, exponents, texture names), read through an OBJ that uses it.
    #[test]
    fn mutated_mtl_files_never_panic(
        (nums, edits) in numbers_and_edits(6),
    ) {
        let mtl = format!(
            "newmtl a\nKd {} {} {}\nKs 1 1 1\nNs {}\nNi {}\nd {}\nmap_Kd none.png\n",
            nums[0], nums[1], nums[2], nums[3], nums[4], nums[5]
        );
        let dir = out_dir_once("fuzz_mtl");
        let id = unique();
        std::fs::write(dir.join(format!("m{id}.mtl")), mutate(mtl.as_bytes(), &edits)).unwrap();
        let obj = dir.join(format!("f{id}.obj"));
        std::fs::write(&obj, format!("mtllib m{id}.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")).unwrap();
        let _ = caustic::io::obj::load_obj(&obj);
    }

    /// A valid PNG texture with bytes edited: the texture loader reports the file or returns a
    /// texture, never panics.
    #[test]
    fn mutated_png_textures_never_panic(edits in prop::collection::vec(edit(), 1..8)) {
        let dir = out_dir_once("fuzz_png");
        let path = dir.join(format!("t{}.png", unique()));
        std::fs::write(&path, mutate(&valid_png(), &edits)).unwrap();
        let _ = ImageCache::new(false).texture(&path, &loc());
        let _ = ImageCache::new(false).bump(&path, &loc());
        let _ = std::fs::remove_file(&path);
    }

    /// A valid pair of tiles, one mutated: stitch gives an image or an error naming a tile.
    #[test]
    fn mutated_tiles_never_panic(edits in prop::collection::vec(edit(), 1..8)) {
        let dir = out_dir_once("fuzz_tiles");
        let (a, b) = valid_tiles();
        let id = unique();
        let (pa, pb) = (dir.join(format!("a{id}.png")), dir.join(format!("b{id}.png")));
        std::fs::write(&pa, mutate(&a, &edits)).unwrap();
        std::fs::write(&pb, &b).unwrap();
        let out = dir.join(format!("o{id}.png"));
        if let Err(e) = caustic::io::stitch::stitch(&[pa.clone(), pb.clone()], &out) {
            let msg = e.to_string();
            prop_assert!(msg.contains(&format!("a{id}.png")) || msg.contains(&format!("b{id}.png")), "{msg}");
        }
        for p in [pa, pb, out] {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// A process-wide counter for unique file names (cases may run in parallel across tests).
fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

/// `out_dir(name)` made once per process (it clears the folder), so cases can share it.
fn out_dir_once(name: &'static str) -> PathBuf {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static DIRS: OnceLock<Mutex<HashMap<&'static str, PathBuf>>> = OnceLock::new();
    let mut dirs = DIRS.get_or_init(Default::default).lock().unwrap();
    dirs.entry(name).or_insert_with(|| out_dir(name)).clone()
}

/// An 8×8 RGB PNG.
fn valid_png() -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 8, 8);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().unwrap();
    let data: Vec<u8> = (0..8 * 8 * 3).map(|i| (i * 7) as u8).collect();
    w.write_image_data(&data).unwrap();
    w.finish().unwrap();
    out
}

/// Two 4×2 tiles covering a 4×4 image, with their window records.
fn valid_tiles() -> (Vec<u8>, Vec<u8>) {
    let tile = |y0: u32| {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, 4, 2);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.add_text_chunk(
            caustic::io::image::WINDOW_KEY.to_string(),
            format!("0 {y0} 4 {} 4 4", y0 + 2),
        )
        .unwrap();
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[100; 4 * 2 * 3]).unwrap();
        w.finish().unwrap();
        out
    };
    (tile(0), tile(2))
}
