//! Files that cannot be turned against the user who renders: temporary outputs a planted
//! symlink cannot redirect, outputs that are never an input of the command, output folders
//! checked before the work, photon-map files validated field by field although their checksum
//! holds, stitch tiles whose headers cannot make us allocate, and `caustic diff` that never
//! reports a NaN or an infinity as no error. The `fuzz_*` properties (proptest, `PROPTEST_CASES`)
//! mutate photon-map files with the checksum recomputed and EXR tiles, and bound the largest
//! allocation by the file's size.
#![cfg(target_os = "linux")]

use crate::common::{Edit, GLASS_BALL, caustic, mutate, out_dir, proptest_config};
use glam::Vec3A;
use proptest::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The system allocator, recording the largest allocation of each thread while asked to.
struct Largest;

thread_local! {
    /// Whether this thread records its allocations, and the largest so far.
    static TRACKING: Cell<(bool, usize)> = const { Cell::new((false, 0)) };
}

/// Records an allocation of `size` bytes on this thread.
fn note(size: usize) {
    let _ = TRACKING.try_with(|t| {
        let (on, most) = t.get();
        if on {
            t.set((on, most.max(size)));
        }
    });
}

// SAFETY: every call is passed to the system allocator unchanged.
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's layout, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Largest = Largest;

/// Runs `f` and returns its result with the largest allocation it made on this thread.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    TRACKING.with(|t| t.set((true, 0)));
    let out = f();
    let most = TRACKING.with(|t| t.replace((false, 0)).1);
    (out, most)
}

/// A 4×4 scene writing `out.png`.
const SCENE: &str = "s = gr.sphere('s'); s:set_material(gr.material({1, 1, 1}, {0, 0, 0}, 0))\n\
    gr.render(s, 'out.png', 4, 4, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},\n\
              {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0})})\n";

/// Writes `text` as `name` in `dir` and returns its path.
fn put(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `caustic ARGS` in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    caustic().current_dir(dir).args(args).output().unwrap()
}

/// Runs `caustic ARGS` in `dir`, asserting failure; returns stderr.
fn fails_in(dir: &Path, args: &[&str]) -> String {
    let o = run_in(dir, args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{args:?} succeeded: {err}");
    err
}

// ---------------------------------------------------------------------------------------------
// Temporary outputs.

/// A symlink planted at the name the temporary file used to have (`.NAME.tmp<PID>`, the
/// process id being easy to guess) made every writer write through it: onto `~/.bashrc`, for
/// an attacker who planted the link in a shared output folder. Now the temporary name is
/// random and created exclusively: the file the link names is untouched, and each output
/// holds what was written (bytes, an OBJ, a PNG, a photon-map file).
#[test]
fn a_symlink_planted_at_the_temporary_name_is_never_written_through() {
    let dir = out_dir("hostile_files_planted");
    let victim = put(&dir, "bashrc", "precious");
    let film = caustic::film::Film {
        width: 2,
        height: 2,
        pixels: vec![Vec3A::ONE; 4],
        samples: vec![1; 4],
        window: caustic::film::Window::full(2, 2),
    };
    let mesh = caustic::geometry::mesh::MeshData {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    };
    type Writer<'a> = Box<dyn Fn(&Path) -> Result<(), String> + 'a>;
    let writers: [(&str, Writer); 4] = [
        (
            "out.txt",
            Box::new(|p| caustic::files::write_bytes(p, b"new")),
        ),
        (
            "out.obj",
            Box::new(|p| caustic::io::obj::write_obj(&mesh, p).map_err(|e| e.to_string())),
        ),
        (
            "out.png",
            Box::new(|p| caustic::io::image::write_png(&film, p).map_err(|e| e.to_string())),
        ),
        (
            "maps.bin",
            Box::new(|p| {
                caustic::integrator::maps_file::write(p, &small_maps(50)).map_err(|e| e.to_string())
            }),
        ),
    ];
    for (name, write) in writers {
        let planted = dir.join(format!(".{name}.tmp{}", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        write(&dir.join(name)).unwrap();
        assert_eq!(
            std::fs::read_to_string(&victim).unwrap(),
            "precious",
            "{name}"
        );
        let meta = std::fs::symlink_metadata(dir.join(name)).unwrap();
        assert!(meta.is_file() && meta.len() > 0, "{name}: {meta:?}");
    }
}

/// Returns the path of the file open as `file`, as the kernel names it.
fn path_of(file: &std::fs::File) -> PathBuf {
    use std::os::fd::AsRawFd;
    std::fs::read_link(format!("/proc/self/fd/{}", file.as_raw_fd())).unwrap()
}

/// The temporary file a writer is given is beside the target, named `.NAME.<16 hex
/// digits>.tmp` with 64 random bits (no process id in it), different at every write, and
/// created with no more permission than the file it replaces (0600 here: it was 0644 with
/// the umask, readable by all while the private file was being written).
#[test]
fn temporary_names_are_random_and_no_more_open_than_the_target() {
    use std::os::unix::fs::PermissionsExt;
    let dir = out_dir("hostile_files_names");
    let out = put(&dir, "secret.txt", "old");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
    let mut names = Vec::new();
    for _ in 0..2 {
        caustic::files::write_replacing(&out, |file| {
            let tmp = path_of(file);
            assert_eq!(tmp.parent().unwrap(), dir.canonicalize().unwrap());
            let mode = file.metadata().unwrap().permissions().mode() & 0o777;
            assert_eq!(mode & 0o077, 0, "temporary file mode {mode:o}");
            names.push(tmp.file_name().unwrap().to_string_lossy().into_owned());
            use std::io::Write;
            file.write_all(b"new").map_err(|e| e.to_string())
        })
        .unwrap();
    }
    for name in &names {
        let hex = name
            .strip_prefix(".secret.txt.")
            .and_then(|r| r.strip_suffix(".tmp"))
            .unwrap_or_else(|| panic!("{name}"));
        assert!(
            hex.len() == 16 && hex.chars().all(|c| c.is_ascii_hexdigit()),
            "{name}"
        );
        assert!(!name.contains(&std::process::id().to_string()), "{name}");
    }
    assert_ne!(names[0], names[1]);
    let meta = std::fs::metadata(&out).unwrap();
    assert_eq!(meta.permissions().mode() & 0o777, 0o600);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
}

// ---------------------------------------------------------------------------------------------
// Outputs that are inputs.

/// A scene reading a mesh and a texture, for the checks of outputs against inputs.
const TEXTURED: &str = "m = gr.material({1, 1, 1}, {0, 0, 0}, 0, 0, 1, 0, 'tex.png')\n\
    t = gr.mesh('t', 'tri.obj'); t:set_material(m)\n\
    gr.render(t, 'out.png', 4, 4, {0.3, 0.3, 3}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},\n\
              {gr.light({0, 0, 3}, {1, 1, 1}, {1, 0, 0})})\n";

/// Writes the textured scene (`scene.lua`, `tri.obj`, `tex.png`) into `dir`.
fn textured_scene(dir: &Path) {
    put(dir, "scene.lua", TEXTURED);
    put(
        dir,
        "tri.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
    );
    let film = caustic::film::Film {
        width: 2,
        height: 2,
        pixels: vec![Vec3A::new(0.5, 0.25, 1.0); 4],
        samples: vec![1; 4],
        window: caustic::film::Window::full(2, 2),
    };
    caustic::io::image::write_png(&film, &dir.join("tex.png")).unwrap();
}

/// `export-mitsuba scene.lua -o scene.lua` replaced the script with XML, and `-o ./scene.lua`,
/// a symlink or a hard link to it did the same; now each is refused before anything is
/// written, the error naming the output and the input, and the script is unchanged.
#[test]
fn an_output_that_is_the_script_is_refused_under_any_name() {
    let dir = out_dir("hostile_files_script_out");
    textured_scene(&dir);
    std::os::unix::fs::symlink("scene.lua", dir.join("link.xml")).unwrap();
    std::fs::hard_link(dir.join("scene.lua"), dir.join("hard.xml")).unwrap();
    for out in ["scene.lua", "./scene.lua", "link.xml", "hard.xml"] {
        let err = fails_in(&dir, &["export-mitsuba", "scene.lua", "-o", out]);
        assert!(
            err.contains(&format!("{out}: is the same file as the input scene.lua")),
            "{out}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("scene.lua")).unwrap(),
            TEXTURED
        );
    }
}

/// The image a render writes may not be a file the scene reads: `-o tex.png` replaced the
/// scene's texture, and `-o tri_mesh0.obj`'s Mitsuba export wrote its mesh over an input mesh
/// named like the exported ones. `stitch a.png b.png -o a.png` and `diff a b -o a` wrote over
/// their inputs too.
#[test]
fn outputs_never_replace_the_scenes_meshes_textures_tiles_or_images() {
    let dir = out_dir("hostile_files_inputs");
    textured_scene(&dir);
    let tex = std::fs::read(dir.join("tex.png")).unwrap();
    let err = fails_in(&dir, &["render", "-q", "scene.lua", "-o", "./tex.png"]);
    assert!(
        err.contains("./tex.png: is the same file as the input"),
        "{err}"
    );
    assert!(err.contains("tex.png"), "{err}");
    assert_eq!(std::fs::read(dir.join("tex.png")).unwrap(), tex);

    // The export writes instance 0's mesh as `x_mesh0.obj`: the scene's own mesh here.
    let obj = std::fs::read_to_string(dir.join("tri.obj")).unwrap();
    put(&dir, "x_mesh0.obj", &obj);
    put(
        &dir,
        "x.lua",
        &TEXTURED
            .replace("tri.obj", "x_mesh0.obj")
            .replace(", 'tex.png'", ""),
    );
    let err = fails_in(&dir, &["export-mitsuba", "x.lua", "-o", "x.xml"]);
    assert!(
        err.contains("x_mesh0.obj: is the same file as the input"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("x_mesh0.obj")).unwrap(),
        obj
    );
    assert!(!dir.join("x.xml").exists());

    for args in [
        &["stitch", "tex.png", "-o", "tex.png"][..],
        &["diff", "tex.png", "tex.png", "-o", "tex.png"][..],
    ] {
        let err = fails_in(&dir, args);
        assert!(
            err.contains("tex.png: is the same file as the input tex.png"),
            "{args:?}: {err}"
        );
        assert_eq!(std::fs::read(dir.join("tex.png")).unwrap(), tex);
    }
}

// ---------------------------------------------------------------------------------------------
// Output folders checked before the work.

/// An output in a folder that does not exist was found only when the finished image was
/// written: `--aa-map` in such a folder left the image written and the map lost, `diff -o`
/// printed its metrics first, `export-mitsuba -o` ran the script and built the scene, and a
/// `gr.render` naming such a folder rendered the frame in vain. Each is now refused first,
/// the error naming the path and the folder.
#[test]
fn outputs_in_missing_folders_are_refused_before_the_work() {
    let dir = out_dir("hostile_files_folders");
    put(&dir, "scene.lua", SCENE);
    let err = fails_in(
        &dir,
        &[
            "render",
            "-q",
            "scene.lua",
            "--adaptive",
            "--aa-map",
            "nowhere/map.png",
        ],
    );
    assert!(
        err.contains("nowhere/map.png: the folder nowhere does not exist"),
        "{err}"
    );
    assert!(
        !dir.join("out.png").exists(),
        "the image was rendered first"
    );

    let o = run_in(
        &dir,
        &["diff", "scene.lua", "scene.lua", "-o", "nowhere/d.png"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("nowhere/d.png: the folder nowhere"),
        "{err}"
    );

    for args in [
        &["export-mitsuba", "scene.lua", "-o", "nowhere/s.xml"][..],
        &["photons", "-q", "scene.lua", "--save", "nowhere/maps.bin"][..],
        &["stitch", "a.png", "-o", "nowhere/full.png"][..],
    ] {
        let err = fails_in(&dir, args);
        assert!(
            err.contains("the folder nowhere does not exist"),
            "{args:?}: {err}"
        );
    }

    put(
        &dir,
        "far.lua",
        &SCENE.replace("'out.png'", "'nowhere/out.png'"),
    );
    let err = fails_in(&dir, &["render", "-q", "far.lua"]);
    assert!(
        err.contains("nowhere/out.png: the folder ") && err.contains("nowhere does not exist"),
        "{err}"
    );
    assert!(!err.contains("wrote"), "{err}");

    // A file where the folder should be, and a folder that cannot be written (not as root,
    // who may write anywhere).
    put(&dir, "file", "x");
    let err = fails_in(&dir, &["render", "-q", "scene.lua", "-o", "file/out.png"]);
    assert!(err.contains("file is not a folder"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Photon-map files.

/// The photon flags the save and every render share (the fingerprint holds them).
const PHOTON_FLAGS: [&str; 10] = [
    "--photons",
    "3000",
    "--caustic-photons",
    "3000",
    "--gather-rays",
    "4",
    "--cache-rays",
    "16",
    "--spp",
    "1",
];

/// Where the fields of a photon-map file are (see `caustic::integrator::maps_file`'s layout).
#[derive(Debug)]
struct MapFile {
    /// Per map: its per-light counts, photon count, power base, positions and powers.
    maps: Vec<MapAt>,
    /// The cache's accuracy and first record, when there is a cache.
    cache: Option<(usize, usize, usize)>,
}

#[derive(Debug)]
struct MapAt {
    counts: usize,
    n: usize,
    base: usize,
    pos: usize,
    power: usize,
}

/// Returns where the fields of the photon-map file `b` are.
fn map_file(b: &[u8]) -> MapFile {
    let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap()) as usize;
    let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap()) as usize;
    let mut at = 8 + 4 + 8;
    at += 4 + u32_at(at);
    let count = b[at];
    at += 1;
    let mut maps = Vec::new();
    for _ in 0..count {
        let counts = at + 4;
        at += 4 + 24 * u32_at(at);
        let n = u64_at(at);
        let base = at + 16;
        let pos = base + 4;
        let power = pos + 16 * n;
        maps.push(MapAt {
            counts,
            n,
            base,
            pos,
            power,
        });
        at = pos + 20 * n;
    }
    let cache = (b[at] == 1).then(|| (at + 1, at + 13, u64_at(at + 5)));
    MapFile { maps, cache }
}

/// Recomputes the CRC-32 at the end of the photon-map file `b`.
fn reseal(b: &mut [u8]) {
    let end = b.len() - 4;
    let crc = crc32fast::hash(&b[..end]);
    b[end..].copy_from_slice(&crc.to_le_bytes());
}

/// Overwrites `b` at `at` with `values` (little-endian f32s).
fn put_f32s(b: &mut [u8], at: usize, values: &[f32]) {
    for (k, v) in values.iter().enumerate() {
        b[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// One forged edit of a photon-map file, and what the error must say.
type Forgery = (&'static str, fn(&mut [u8], &MapFile), &'static str);

/// Forged photon-map files whose checksum holds, each with a field out of the renderer's
/// range, and the error expected: every one was read and rendered (infinite pixels from a
/// power base of 900, black ones from -900, caustics from photons moved out of the scene, a
/// cache interpolating irradiance of 1e30 or -1, a normal of length 5, a radius a thousand
/// times the scene), and a translational gradient of 1e30, which would extrapolate a record's
/// light to a glare. The file is damaged only in the field named.
const FORGERIES: [Forgery; 12] = [
    (
        "base 900",
        |b, f| b[f.maps[0].base..][..4].copy_from_slice(&900i32.to_le_bytes()),
        "the global map: power base exponent 900",
    ),
    (
        "base -900",
        |b, f| b[f.maps[0].base..][..4].copy_from_slice(&(-900i32).to_le_bytes()),
        "the global map: power base exponent -900",
    ),
    (
        "code",
        |b, f| b[f.maps[1].power..][..4].copy_from_slice(&((5u32 << 27) | 1).to_le_bytes()),
        "the caustic map: photon 0's power code 0x28000001 is not normalised",
    ),
    (
        "positions",
        |b, f| {
            let m = &f.maps[0];
            for k in 0..3 * m.n {
                let at = m.pos + 4 * k;
                let v = f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
                put_f32s(b, at, &[v * 1048576.0]);
            }
        },
        "lies outside the scene",
    ),
    (
        "counts",
        |b, f| b[f.maps[0].counts..][..8].copy_from_slice(&0u64.to_le_bytes()),
        "the global map: light 0's counts (emitted 0",
    ),
    (
        "accuracy",
        |b, f| put_f32s(b, f.cache.unwrap().0, &[0.9]),
        "the irradiance cache: accuracy 0.9, this frame's is 0.3",
    ),
    (
        "irradiance",
        |b, f| put_f32s(b, f.cache.unwrap().1 + 24, &[1e30]),
        "the irradiance cache: record 0: its irradiance",
    ),
    (
        "negative",
        |b, f| put_f32s(b, f.cache.unwrap().1 + 28, &[-1.0]),
        "the irradiance cache: record 0: its irradiance",
    ),
    (
        "normal",
        |b, f| put_f32s(b, f.cache.unwrap().1 + 12, &[0.0, 5.0, 0.0]),
        "the irradiance cache: record 0: its normal",
    ),
    (
        "translation",
        |b, f| put_f32s(b, f.cache.unwrap().1 + 84, &[1e30]),
        "the irradiance cache: record 0: its gradient",
    ),
    (
        "radius",
        |b, f| put_f32s(b, f.cache.unwrap().1 + 108, &[1e4]),
        "the irradiance cache: record 0's radius 10000 is outside this frame's",
    ),
    (
        "place",
        |b, f| put_f32s(b, f.cache.unwrap().1, &[1e6]),
        "the irradiance cache: record 0 at [1000000",
    ),
];

/// A photon-map file whose checksum holds but whose fields are out of range is refused by
/// `render --photon-maps` with an error naming the file, the map or cache, the field and the
/// photon or record; the file as saved still renders.
#[test]
fn forged_photon_map_fields_are_refused_though_the_checksum_holds() {
    let dir = out_dir("hostile_files_maps");
    put(&dir, "ball.lua", GLASS_BALL);
    let saved = run_in(
        &dir,
        &[
            &["photons", "-q", "ball.lua", "--save", "maps.bin"][..],
            &PHOTON_FLAGS,
        ]
        .concat(),
    );
    assert!(
        saved.status.success(),
        "{}",
        String::from_utf8_lossy(&saved.stderr)
    );
    let good = std::fs::read(dir.join("maps.bin")).unwrap();
    let layout = map_file(&good);
    assert!(layout.maps.len() == 2 && layout.maps[1].n > 0, "{layout:?}");
    assert!(layout.cache.is_some_and(|c| c.2 > 0), "{layout:?}");
    let render = |file: &str| {
        let args = [
            &["render", "-q", "ball.lua", "--photon-maps", file][..],
            &PHOTON_FLAGS,
        ]
        .concat();
        run_in(&dir, &args)
    };
    let o = render("maps.bin");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (name, forge, expected) in FORGERIES {
        let mut b = good.clone();
        forge(&mut b, &layout);
        reseal(&mut b);
        std::fs::write(dir.join("forged.bin"), &b).unwrap();
        let o = render("forged.bin");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: accepted");
        assert!(
            err.contains("forged.bin: ") && err.contains(expected),
            "{name}: {err}"
        );
    }
}

/// Returns maps of `n` photons (and a third as many caustic ones) and a small cache, with
/// consistent counts, as a render would save them.
fn small_maps(n: usize) -> caustic::integrator::maps_file::SavedMaps {
    use caustic::integrator::irradiance_cache::{IrradianceCache, Record};
    use caustic::integrator::maps_file::{Fingerprint, SavedMaps};
    use caustic::photon::file::CountedMap;
    use caustic::photon::trace::LightCounts;
    use caustic::photon::{Photon, PhotonMap};
    let photon = |i: usize| Photon {
        position: Vec3A::new((i % 7) as f32, (i % 5) as f32 * 0.5, i as f32 * 1e-2),
        power: Vec3A::new(1.0, 0.5, 0.25) * (1.0 + (i % 3) as f32) * 1e-3,
        dir: Vec3A::Y,
        normal: Vec3A::Z,
        direct: i.is_multiple_of(2),
    };
    let counted = |n: usize| CountedMap {
        map: PhotonMap::build((0..n).map(photon).collect()),
        per_light: vec![LightCounts {
            emitted: n as u64,
            stored: n as u64,
            first_hit_specular: 1,
            ..LightCounts::default()
        }],
    };
    let record = |i: usize| Record {
        p: Vec3A::splat(i as f32),
        n: Vec3A::Y,
        e: Vec3A::new(0.5, 0.25, 1.0),
        rotation: [Vec3A::X, Vec3A::Y, Vec3A::Z],
        translation: [Vec3A::Z, Vec3A::X, Vec3A::Y],
        r: 0.5,
    };
    SavedMaps {
        fingerprint: Fingerprint {
            scene: 7,
            settings: "seed 0".into(),
        },
        global: counted(n),
        caustic: Some(counted(n / 3)),
        cache: Some(IrradianceCache::new((0..3).map(record).collect(), 0.3)),
    }
}

/// One edit of a photon-map file: a byte, or a whole word set to a value a forger would try.
#[derive(Clone, Debug)]
enum MapEdit {
    Byte(usize, u8),
    Word(usize, u32),
    Insert(usize, u8),
    Delete(usize),
}

/// Words a forger tries: NaN, infinities, huge and tiny floats, negative numbers, large
/// counts and exponents.
const WORDS: [u32; 10] = [
    0x7fc0_0000,
    0x7f80_0000,
    0xff80_0000,
    0x7149_f2ca, // 1e30
    0x0000_0001,
    0xbf80_0000, // -1
    0xffff_ffff,
    0x8000_0000,
    0x0000_0384, // 900
    0x4000_0000,
];

fn map_edit() -> impl Strategy<Value = MapEdit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, v)| MapEdit::Byte(i, v)),
        (any::<usize>(), 0..WORDS.len()).prop_map(|(i, w)| MapEdit::Word(i, WORDS[w])),
        (any::<usize>(), any::<u32>()).prop_map(|(i, w)| MapEdit::Word(i, w)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, v)| MapEdit::Insert(i, v)),
        any::<usize>().prop_map(MapEdit::Delete),
    ]
}

/// Returns `valid` with `edits` applied before its checksum, and the checksum recomputed.
fn forge(valid: &[u8], edits: &[MapEdit]) -> Vec<u8> {
    let mut body = valid[..valid.len() - 4].to_vec();
    for e in edits {
        let n = body.len();
        match *e {
            MapEdit::Byte(i, v) => body[i % n] = v,
            MapEdit::Word(i, w) => {
                let at = (i % (n / 4)) * 4;
                body[at..at + 4].copy_from_slice(&w.to_le_bytes());
            }
            MapEdit::Insert(i, v) => body.insert(i % (n + 1), v),
            MapEdit::Delete(i) => {
                body.remove(i % n);
            }
        }
    }
    let crc = crc32fast::hash(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    body
}

/// What a frame expects of `small_maps`: its photons and records inside a box of the scene.
fn small_expected() -> caustic::integrator::maps_file::Expected {
    caustic::integrator::maps_file::Expected {
        bounds: Some((Vec3A::splat(-1.0), Vec3A::splat(10.0))),
        lights: 1,
        caustic: true,
        cache: Some((0.3, (0.1, 1.0))),
    }
}

proptest! {
    #![proptest_config(proptest_config(48))]

    /// A photon-map file with edits and its checksum recomputed is read as maps (that the
    /// frame's check then accepts or refuses) or refused, never a panic; the largest
    /// allocation reading it is a few times its size (a count read from the file cannot
    /// allocate more than the file holds).
    #[test]
    fn fuzz_photon_map_files_with_a_valid_checksum(edits in prop::collection::vec(map_edit(), 1..6)) {
        static VALID: std::sync::OnceLock<(PathBuf, Vec<u8>)> = std::sync::OnceLock::new();
        let (dir, valid) = VALID.get_or_init(|| {
            let dir = out_dir("hostile_files_fuzz_maps");
            caustic::integrator::maps_file::write(&dir.join("maps.bin"), &small_maps(300)).unwrap();
            let valid = std::fs::read(dir.join("maps.bin")).unwrap();
            (dir, valid)
        });
        let path = dir.join("forged.bin");
        let bytes = forge(valid, &edits);
        std::fs::write(&path, &bytes).unwrap();
        let (read, most) = largest_allocation(|| caustic::integrator::maps_file::read(&path));
        if let Ok(maps) = read {
            let _ = maps.check(&small_expected());
        }
        // Arrays of at most the photons the file holds, the reader's buffers (1 MiB) and the
        // cache's grid: at most 2^20 cells, whatever its records, whose start offsets and their
        // working copy take 2 x 8 MiB (the campaign found 17.5 MiB for an 8 KB file, over the
        // 16 MiB this bound first allowed: a constant, not a size read from the file).
        prop_assert!(most <= 4 * bytes.len() + (20 << 20), "{most} bytes allocated for {}", bytes.len());
    }

    /// A photon-pass part (`caustic photons --part`) with edits and its checksum recomputed is
    /// read or refused, never a panic, and reading it allocates a few times its size at most
    /// plus the reader's buffers: counts read from the file are bounded by its size first.
    #[test]
    fn fuzz_photon_pass_parts_with_a_valid_checksum(edits in prop::collection::vec(map_edit(), 1..6)) {
        static VALID: std::sync::OnceLock<(PathBuf, Vec<u8>)> = std::sync::OnceLock::new();
        let (dir, valid) = VALID.get_or_init(|| {
            let dir = out_dir("hostile_files_fuzz_parts");
            caustic::integrator::maps_file::parts::write(&dir.join("part.bin"), &small_part(300)).unwrap();
            let valid = std::fs::read(dir.join("part.bin")).unwrap();
            (dir, valid)
        });
        let path = dir.join("forged.bin");
        let bytes = forge(valid, &edits);
        std::fs::write(&path, &bytes).unwrap();
        let (read, most) = largest_allocation(|| caustic::integrator::maps_file::parts::read(&path));
        if let Ok(part) = read {
            prop_assert!(part.global.len() as u64 <= bytes.len() as u64 / 28);
        }
        // The photons as blocks of 1.75 MiB, the reader's buffers (1 MiB and 1.75 MiB).
        prop_assert!(most <= 4 * bytes.len() + (8 << 20), "{most} bytes allocated for {}", bytes.len());
    }

    /// A progressive pass file (`caustic render --save-passes`) with edits and its checksum
    /// recomputed is read or refused, never a panic, and reading it allocates a few times its
    /// size at most: the window's size is bounded by the file's first.
    #[test]
    fn fuzz_progressive_pass_files_with_a_valid_checksum(edits in prop::collection::vec(map_edit(), 1..6)) {
        static VALID: std::sync::OnceLock<(PathBuf, Vec<u8>)> = std::sync::OnceLock::new();
        let (dir, valid) = VALID.get_or_init(|| {
            let dir = out_dir("hostile_files_fuzz_passes");
            caustic::integrator::passes_file::write(&dir.join("a.pass"), &small_passes()).unwrap();
            let valid = std::fs::read(dir.join("a.pass")).unwrap();
            (dir, valid)
        });
        let path = dir.join("forged.pass");
        let bytes = forge(valid, &edits);
        std::fs::write(&path, &bytes).unwrap();
        let (read, most) = largest_allocation(|| caustic::integrator::passes_file::read(&path));
        if let Ok(p) = read {
            prop_assert!(p.sums.sum.len() as u64 * 40 <= bytes.len() as u64);
        }
        prop_assert!(most <= 4 * bytes.len() + (2 << 20), "{most} bytes allocated for {}", bytes.len());
    }
}

/// The sums of passes 3 to 6 of a 12x9 window of a 20x10 image, as `caustic render
/// --save-passes` saves them.
fn small_passes() -> caustic::integrator::passes_file::SavedPasses {
    use caustic::film::{Film, Window};
    use caustic::integrator::progressive::Accumulator;
    let window = Window {
        x0: 4,
        y0: 1,
        x1: 16,
        y1: 10,
        full_width: 20,
        full_height: 10,
    };
    let mut sums = Accumulator::starting_at(window, 3);
    for pass in 0..4 {
        let pixels = (0..12 * 9)
            .map(|i| Vec3A::splat((i + pass) as f32 * 0.01))
            .collect();
        sums.add(&Film {
            width: 12,
            height: 9,
            pixels,
            samples: vec![1; 12 * 9],
            window,
        });
    }
    caustic::integrator::passes_file::SavedPasses {
        fingerprint: caustic::integrator::maps_file::Fingerprint {
            scene: 3,
            settings: "seed 0".into(),
        },
        sums,
    }
}

/// A part of a photon pass of `n` photons of one light, both maps, as `caustic photons --part`
/// saves it.
fn small_part(n: usize) -> caustic::integrator::maps_file::parts::SavedPart {
    use caustic::integrator::maps_file::Fingerprint;
    use caustic::photon::Photon;
    use caustic::photon::stream::PhotonStream;
    use caustic::photon::trace::{LightCounts, Part, TracedMap};
    let photon = |i: usize| Photon {
        position: Vec3A::new((i % 7) as f32, (i % 5) as f32 * 0.5, i as f32 * 1e-2),
        power: Vec3A::new(1.0, 0.5, 0.25) * 1e-3,
        dir: Vec3A::Y,
        normal: Vec3A::Z,
        direct: i.is_multiple_of(2),
    };
    let traced = |n: usize| TracedMap {
        photons: PhotonStream::of(&(0..n).map(photon).collect::<Vec<_>>()),
        per_light: vec![LightCounts {
            emitted: n as u64,
            stored: n as u64,
            ..LightCounts::default()
        }],
    };
    caustic::integrator::maps_file::parts::SavedPart {
        fingerprint: Fingerprint {
            scene: 7,
            settings: "seed 0".into(),
        },
        part: Part { index: 1, count: 3 },
        global: traced(n),
        caustic: Some(traced(n / 2)),
    }
}

// ---------------------------------------------------------------------------------------------
// Stitch inputs.

/// Files by name, with their bytes.
type Files = Vec<(&'static str, Vec<u8>)>;

/// Writes the three kinds of EXR file a tile may come as into `dir` and returns their bytes:
/// caustic's own (single-part scan lines, run-length coded), a multi-part file and a tiled
/// one (ZIP); `own.png` is caustic's PNG of the same tile.
fn exr_files(dir: &Path) -> Files {
    use exr::prelude::*;
    let layer = |attributes: LayerAttributes, encoding: Encoding| {
        Layer::new(
            (4, 4),
            attributes,
            encoding,
            SpecificChannels::rgb(|p: Vec2<usize>| (p.x() as f32, p.y() as f32, 0.5f32)),
        )
    };
    let film = caustic::film::Film {
        width: 4,
        height: 4,
        pixels: (0..16).map(|i| Vec3A::splat(i as f32 * 0.1)).collect(),
        samples: vec![1; 16],
        window: caustic::film::Window {
            x0: 4,
            y0: 0,
            x1: 8,
            y1: 4,
            full_width: 8,
            full_height: 4,
        },
    };
    let own = dir.join("own.exr");
    caustic::io::image::write_png(&film, &dir.join("own.png")).unwrap();
    caustic::io::image::write_image(&film, &own, caustic::io::image::Tonemap::Clamp).unwrap();
    let display = ImageAttributes::new(IntegerBounds::from_dimensions((4, 4)));
    let parts = Image::from_layers(
        display.clone(),
        SmallVec::from_vec(vec![
            layer(LayerAttributes::named("a"), Encoding::FAST_LOSSLESS),
            layer(LayerAttributes::named("b"), Encoding::FAST_LOSSLESS),
        ]),
    );
    parts.write().to_file(dir.join("parts.exr")).unwrap();
    let tiled = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::Tiles(Vec2(2, 2)),
        line_order: LineOrder::Increasing,
    };
    Image::from_layers(
        display,
        SmallVec::from_vec(vec![layer(LayerAttributes::default(), tiled)]),
    )
    .write()
    .to_file(dir.join("tiled.exr"))
    .unwrap();
    ["own.exr", "parts.exr", "tiled.exr"]
        .map(|n| (n, std::fs::read(dir.join(n)).unwrap()))
        .into()
}

/// Returns `bytes` with the four `i32`s after the attribute `name` (a `box2i`) replaced.
fn with_box(bytes: &[u8], name: &str, b: [i32; 4]) -> Vec<u8> {
    let key = [name.as_bytes(), b"\0box2i\0"].concat();
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .unwrap_or_else(|| panic!("no {name}"))
        + key.len()
        + 4;
    let mut out = bytes.to_vec();
    for (k, v) in b.iter().enumerate() {
        out[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    out
}

/// A multi-part EXR was read by its first part whatever the others held, and a tiny tile whose
/// header claims an 8192x8192 data window made stitch allocate a gigabyte before finding the
/// file holds no such pixels; a tile claiming a huge image around its few pixels made the
/// coverage map of the whole image (a gigabyte) before finding the pixels uncovered; a PNG
/// tile's header claiming 8192x8192 pixels allocated its buffer before inflating anything.
/// Now each is refused by its header, allocating a few times the file's size.
#[test]
fn stitch_refuses_multi_part_and_forged_headers_before_allocating() {
    let (v, seen) = largest_allocation(|| vec![1u8; 3 << 20]);
    assert!(seen >= v.len(), "the allocation tracker saw {seen} bytes");
    let dir = out_dir("hostile_files_stitch");
    let files = exr_files(&dir);
    let own = &files[0].1;
    let stitch = |tiles: &[&str]| {
        let paths: Vec<PathBuf> = tiles.iter().map(|t| dir.join(t)).collect();
        largest_allocation(|| caustic::io::stitch::stitch(&paths, &dir.join("full.exr")))
    };
    let (r, _) = stitch(&["parts.exr"]);
    let err = r.unwrap_err().to_string();
    assert!(
        err.contains("parts.exr: a multi-part EXR (2 parts)"),
        "{err}"
    );

    let big = with_box(own, "dataWindow", [0, 0, 8191, 8191]);
    let big = with_box(&big, "displayWindow", [0, 0, 8191, 8191]);
    std::fs::write(dir.join("big.exr"), &big).unwrap();
    let (r, most) = stitch(&["big.exr"]);
    let err = r.unwrap_err().to_string();
    assert!(
        err.contains("big.exr: its 8192x8192 pixels") && err.contains("can hold"),
        "{err}"
    );
    assert!(most < 64 * big.len() + (1 << 20), "{most} bytes allocated");

    let wide = with_box(own, "displayWindow", [0, 0, 8191, 8191]);
    std::fs::write(dir.join("wide.exr"), &wide).unwrap();
    let (r, most) = stitch(&["wide.exr"]);
    let err = r.unwrap_err().to_string();
    assert!(
        err.contains("the tiles leave pixel (0, 0) of the 8192x8192 image uncovered"),
        "{err}"
    );
    assert!(most < 1 << 20, "{most} bytes allocated");

    let png = png_claiming(8192, 8192);
    std::fs::write(dir.join("big.png"), &png).unwrap();
    let paths = [dir.join("big.png")];
    let (r, most) =
        largest_allocation(|| caustic::io::stitch::stitch(&paths, &dir.join("full.png")));
    let err = r.unwrap_err().to_string();
    assert!(
        err.contains("big.png: its header claims 8192x8192 pixels, more than"),
        "{err}"
    );
    assert!(most < 1 << 20, "{most} bytes allocated");
}

/// Returns a PNG of a few dozen bytes whose header claims `w × h` 8-bit RGB pixels, a whole
/// image by its window record, and whose data is a few zero bytes.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let chunk = |kind: &[u8], data: &[u8]| {
        let body = [kind, data].concat();
        let crc = crc32fast::hash(&body);
        [
            &(data.len() as u32).to_be_bytes()[..],
            &body,
            &crc.to_be_bytes(),
        ]
        .concat()
    };
    let ihdr = [&w.to_be_bytes()[..], &h.to_be_bytes(), &[8, 2, 0, 0, 0]].concat();
    let text = format!("caustic-window\00 0 {w} {h} {w} {h}");
    let idat = [0x78, 0x9c, 0x63, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01];
    [
        &b"\x89PNG\r\n\x1a\n"[..],
        &chunk(b"IHDR", &ihdr),
        &chunk(b"tEXt", text.as_bytes()),
        &chunk(b"IDAT", &idat),
        &chunk(b"IEND", &[]),
    ]
    .concat()
}

/// One edit of a byte string: overwrite a byte, set a 32-bit word, insert, delete or truncate.
fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), any::<u32>()).prop_map(|(i, w)| Edit::Word(i, w)),
        (any::<usize>(), 0..WORDS.len()).prop_map(|(i, w)| Edit::Word(i, WORDS[w])),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Insert(i, b)),
        any::<usize>().prop_map(Edit::Delete),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

proptest! {
    #![proptest_config(proptest_config(48))]

    /// An EXR file (caustic's own tile, a multi-part file, a tiled one), mutated and given to
    /// stitch's reader, is read or refused, never a panic; its largest allocation is bounded
    /// by the file's size times what its compression can expand (deflate's 1032, the most),
    /// with 1 MiB for the reader's own tables.
    #[test]
    fn fuzz_exr_tiles_mutated(which in 0usize..3, edits in prop::collection::vec(edit(), 1..6)) {
        static FILES: std::sync::OnceLock<(PathBuf, Files)> = std::sync::OnceLock::new();
        let (dir, files) = FILES.get_or_init(|| {
            let dir = out_dir("hostile_files_fuzz_exr");
            let files = exr_files(&dir);
            (dir, files)
        });
        let bytes = mutate(&files[which].1, &edits);
        let path = dir.join("mutated.exr");
        std::fs::write(&path, &bytes).unwrap();
        let (_, most) = largest_allocation(|| caustic::io::exr::read(&path, caustic::film::MAX_PIXELS));
        prop_assert!(most <= 1100 * bytes.len() + (1 << 20), "{most} bytes allocated for {}", bytes.len());
    }
}

/// The second fuzz campaign's finding: one byte inserted into a photon-map file (its checksum
/// recomputed) made a light count of the file's next bytes, and the reader allocated the
/// counts of up to 2^20 lights (22.5 MiB for 8 KB) before reading any.
#[test]
fn a_light_count_the_file_cannot_hold_is_refused_before_it_is_allocated() {
    let dir = out_dir("hostile_files_light_count");
    caustic::integrator::maps_file::write(&dir.join("maps.bin"), &small_maps(300)).unwrap();
    let valid = std::fs::read(dir.join("maps.bin")).unwrap();
    let bytes = forge(&valid, &[MapEdit::Insert(13423561826027610574, 9)]);
    let path = dir.join("forged.bin");
    std::fs::write(&path, &bytes).unwrap();
    let (_, most) = largest_allocation(|| caustic::integrator::maps_file::read(&path));
    assert!(
        most <= 4 * bytes.len() + (20 << 20),
        "{most} bytes allocated for {}",
        bytes.len()
    );
}

/// The fuzz campaign's finding: caustic's own tile with one byte changed and two inserted
/// became a tiled file of 16448 x 64 tiles, whose one tile buffer the reader allocated (12 MiB
/// for a 612-byte file): the tile's size was bounded by the image limit alone.
#[test]
fn a_mutated_tile_from_the_campaign_stays_within_its_allocation_bound() {
    let dir = out_dir("hostile_files_exr_campaign");
    let files = exr_files(&dir);
    let edits = [
        Edit::Insert(3495146590363952256, 1),
        Edit::Set(16000715553870099837, 64),
        Edit::Insert(14160783028930016096, 1),
    ];
    let bytes = mutate(&files[0].1, &edits);
    let path = dir.join("mutated.exr");
    std::fs::write(&path, &bytes).unwrap();
    let (read, most) =
        largest_allocation(|| caustic::io::exr::read(&path, caustic::film::MAX_PIXELS));
    assert!(
        most <= 1100 * bytes.len() + (1 << 20),
        "{most} bytes allocated for {}: {:?}",
        bytes.len(),
        read.map(|_| ())
    );
}

// ---------------------------------------------------------------------------------------------
// caustic diff.

/// Writes a `w × h` PFM image of `pixels` (row 0 at the top) at `path`.
fn pfm(path: &Path, w: u32, h: u32, pixels: &[Vec3A]) {
    std::fs::write(path, caustic::io::pfm::encode(w, h, pixels)).unwrap();
}

/// `caustic diff` of an image with a NaN pixel against a reference printed an RMSE of 0 and
/// succeeded (the NaN squared error was clamped to 0), and an infinite pixel gave an infinite
/// RMSE with no word of where. Now a NaN or an infinity in the image or in either reference
/// fails the command, naming the file, the count of such pixels and the first.
#[test]
fn diff_names_nan_and_infinite_pixels_instead_of_a_silent_zero() {
    let dir = out_dir("hostile_files_diff");
    let ones = vec![Vec3A::ONE; 12];
    let mut bad = ones.clone();
    bad[5] = Vec3A::new(1.0, f32::NAN, 1.0); // (1, 1) in a 4-wide image
    bad[10] = Vec3A::new(f32::INFINITY, 1.0, 1.0); // (2, 2)
    pfm(&dir.join("ref.pfm"), 4, 3, &ones);
    pfm(&dir.join("bad.pfm"), 4, 3, &bad);
    for args in [
        &["diff", "bad.pfm", "ref.pfm"][..],
        &["diff", "ref.pfm", "bad.pfm"][..],
        &["diff", "ref.pfm", "ref.pfm", "--second", "bad.pfm"][..],
    ] {
        let o = run_in(&dir, args);
        let (out, err) = (
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr),
        );
        assert!(!o.status.success(), "{args:?}: {out}");
        assert!(
            err.contains("bad.pfm: 2 pixels are not finite (NaN or infinite), the first at (1, 1)"),
            "{args:?}: {err}"
        );
        assert!(!out.contains("RMSE"), "{args:?}: {out}");
    }
    // Outside the region compared, a NaN does not matter.
    let o = run_in(&dir, &["diff", "bad.pfm", "ref.pfm", "--region", "0,0,1,3"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && out.contains("RMSE 0.000000"), "{out}");
}
