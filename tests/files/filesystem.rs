//! Writing and reading files the way a careful user's system has them: outputs behind symlinks,
//! with chosen permissions, special files (devices, FIFOs) named as outputs or inputs, and a
//! process killed while writing.
#![cfg(target_os = "linux")]

use crate::common::{caustic, out_dir};
use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// A 4×4 scene writing `out.png` (the command line's `-o` overrides it).
const SCENE: &str = "s = gr.sphere('s'); s:set_material(gr.material({1, 1, 1}, {0, 0, 0}, 0))\n\
    gr.render(s, 'out.png', 4, 4, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},\n\
              {gr.light({0, 0, 5}, {1, 1, 1}, {1, 0, 0})})\n";

/// Writes the scene into a fresh folder for `test`; returns the folder and the script.
fn setup(test: &str) -> (PathBuf, PathBuf) {
    let dir = out_dir(test);
    let script = dir.join("scene.lua");
    std::fs::write(&script, SCENE).unwrap();
    (dir, script)
}

/// Renders `script` to `out` through the command line; returns its exit status and stderr.
fn render(script: &Path, out: &Path) -> (bool, String) {
    let o = caustic()
        .args(["render", "-q", "-o"])
        .arg(out)
        .arg(script)
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// Returns the names of files in `dir` that look like leftover temporary files.
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect()
}

/// Creates a FIFO at `path`.
fn mkfifo(path: &Path) {
    let c = CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: c is a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

/// An output behind a symlink is written through it: the link stays a link and the file it
/// names holds the new 4×4 image (the rename replaced the link with a regular file).
#[test]
fn outputs_behind_symlinks_are_written_through_the_link() {
    let (dir, script) = setup("stability_output_symlink");
    let real = dir.join("real.png");
    std::fs::write(&real, b"old").unwrap();
    let link = dir.join("link.png");
    std::os::unix::fs::symlink("real.png", &link).unwrap();
    let (ok, err) = render(&script, &link);
    assert!(ok, "{err}");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let img = image::open(&real).unwrap();
    assert_eq!((img.width(), img.height()), (4, 4));
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
}

/// Replacing an existing output keeps its permissions (0640 here; the temporary file had the
/// process's default, 0644 under the usual umask).
#[test]
fn replaced_outputs_keep_their_permissions() {
    let (dir, script) = setup("stability_output_permissions");
    let out = dir.join("out.png");
    std::fs::write(&out, b"old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    let (ok, err) = render(&script, &out);
    assert!(ok, "{err}");
    let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o7777;
    assert_eq!(mode, 0o640);
    assert_eq!(image::open(&out).unwrap().width(), 4);
}

/// Special files are refused with an error naming the path and its kind, before rendering:
/// `/dev/null` behind a `.png` symlink and a FIFO named `out.png` as outputs (`/dev/null` is
/// left a device, the FIFO a FIFO); a FIFO and `/dev/null` as the script, and an OBJ whose
/// `mtllib` names `/dev/zero`, as inputs (reading them blocked or never ended). Five cases.
#[test]
fn special_files_are_refused_as_outputs_and_inputs() {
    let (dir, script) = setup("stability_output_special");
    let null = dir.join("null.png");
    std::os::unix::fs::symlink("/dev/null", &null).unwrap();
    let (ok, err) = render(&script, &null);
    assert!(
        !ok && err.contains("null.png") && err.contains("is a device"),
        "{err}"
    );
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );

    let fifo = dir.join("fifo.png");
    mkfifo(&fifo);
    let (ok, err) = render(&script, &fifo);
    assert!(
        !ok && err.contains("fifo.png") && err.contains("is a FIFO"),
        "{err}"
    );
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());

    let fifo_script = dir.join("fifo.lua");
    mkfifo(&fifo_script);
    let (ok, err) = render(&fifo_script, &dir.join("x.png"));
    assert!(
        !ok && err.contains("fifo.lua") && err.contains("is a FIFO"),
        "{err}"
    );
    let (ok, err) = render(Path::new("/dev/null"), &dir.join("x.png"));
    assert!(
        !ok && err.contains("/dev/null") && err.contains("is a device"),
        "{err}"
    );

    std::fs::write(
        dir.join("m.obj"),
        "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let mesh_script = dir.join("mesh.lua");
    std::fs::write(
        &mesh_script,
        SCENE.replace("gr.sphere('s')", "gr.mesh('s', 'm.obj')"),
    )
    .unwrap();
    let (ok, err) = render(&mesh_script, &dir.join("x.png"));
    // Refused either way: outside the scene's folders (the sandbox), or as a device.
    assert!(
        !ok && err.contains("/dev/zero")
            && (err.contains("is a device") || err.contains("outside the folders")),
        "{err}"
    );
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
}

/// A process that receives SIGTERM while writing an output removes its temporary file and
/// still dies by the signal (the `.tmp` file was left behind). Run in a child process
/// (this test binary again), which signals itself from inside the write.
#[test]
fn sigterm_while_writing_removes_the_temporary_file() {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/stability_output_sigterm");
    if std::env::var_os("STABILITY_SIGTERM_CHILD").is_some() {
        let _ = caustic::files::write_replacing(&dir.join("out.png"), |file| {
            use std::io::Write;
            file.write_all(b"partial").map_err(|e| e.to_string())?;
            // SAFETY: raising a signal in this process is always allowed.
            unsafe { libc::raise(libc::SIGTERM) };
            Ok(())
        });
        unreachable!("SIGTERM must end the child");
    }
    let dir = out_dir("stability_output_sigterm");
    std::fs::write(dir.join("out.png"), b"old").unwrap();
    // The test's name in this binary: its module path without the crate's name.
    let (_, module) = module_path!().split_once("::").unwrap();
    let name = format!("{module}::sigterm_while_writing_removes_the_temporary_file");
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", &name, "--test-threads", "1"])
        .env("STABILITY_SIGTERM_CHILD", "1")
        .status()
        .unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGTERM), "{status:?}");
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"old");
}

/// Returns a 5×5-vertex water surface, a mesh with normals and texture coordinates.
fn small_mesh() -> caustic::geometry::mesh::MeshData {
    use caustic::geometry::water::{WaveParams, wave_mesh};
    wave_mesh(&WaveParams {
        n: 5,
        ..WaveParams::default()
    })
}

/// An exporter writing to the path it is given.
type Writer = fn(&Path) -> Result<(), String>;

/// Runs `write` on another thread and returns its result, or `None` when it has not returned
/// within 20 s (opening a FIFO for writing blocks until someone reads it).
fn within_20_s<T: Send + 'static>(write: impl FnOnce() -> T + Send + 'static) -> Option<T> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(write());
    });
    rx.recv_timeout(std::time::Duration::from_secs(20)).ok()
}

/// The exporters write as images do (`files::write_replacing`): an OBJ, a GLB, a glTF with its
/// `.bin` and a Mitsuba scene with its mesh, each behind a symlink to a file of mode 0640, keep
/// the link and the mode and leave no temporary file, and a FIFO named as any of them is refused
/// with an error (4 writers, 2 cases each). They wrote in place with `File::create`, so an
/// interrupted export left a truncated file, and the OBJ writer blocked for ever on the FIFO.
#[test]
fn exporters_write_through_links_keep_modes_and_refuse_fifos() {
    let dir = out_dir("stability_output_exporters");
    let mitsuba_scene = "m = gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0)\n\
        root = gr.node('root')\n\
        t = gr.mesh('t', {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}); t:set_material(m)\n\
        root:add_child(t)\n\
        gr.render(root, 'x.png', 8, 8, {0, 0, 3}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},\n\
                  {gr.light({0, 0, 3}, {1, 1, 1}, {0, 0, 1})})\n";
    std::fs::write(dir.join("m.lua"), mitsuba_scene).unwrap();
    // Each writer, by the name it is given (the glTF also writes `<stem>.bin` beside it).
    let writers: [(&str, Writer); 4] = [
        ("mesh.obj", |p| {
            caustic::io::obj::write_obj(&small_mesh(), p).map_err(|e| e.to_string())
        }),
        ("mesh.glb", |p| {
            caustic::io::gltf::write_gltf(&small_mesh(), p).map_err(|e| e.to_string())
        }),
        ("mesh.gltf", |p| {
            caustic::io::gltf::write_gltf(&small_mesh(), p).map_err(|e| e.to_string())
        }),
        ("scene.xml", |p| {
            let o = caustic()
                .current_dir(p.parent().unwrap())
                .args(["export-mitsuba", "m.lua", "-o"])
                .arg(p.file_name().unwrap())
                .output()
                .unwrap();
            o.status
                .success()
                .then_some(())
                .ok_or_else(|| String::from_utf8_lossy(&o.stderr).into_owned())
        }),
    ];
    for (name, write) in writers {
        let real = dir.join(format!("real-{name}"));
        std::fs::write(&real, b"old").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.join(name);
        std::os::unix::fs::symlink(real.file_name().unwrap(), &link).unwrap();
        let target = link.clone();
        let result = within_20_s(move || write(&target)).expect("the write did not return");
        assert_eq!(result, Ok(()), "{name}");
        let meta = std::fs::symlink_metadata(&link).unwrap();
        assert!(
            meta.file_type().is_symlink(),
            "{name}: the link was replaced"
        );
        let real_meta = std::fs::metadata(&real).unwrap();
        assert!(
            real_meta.len() > 3,
            "{name}: the linked file was not written"
        );
        assert_eq!(
            real_meta.permissions().mode() & 0o777,
            0o640,
            "{name}: mode"
        );
        assert!(leftovers(&dir).is_empty(), "{name}: {:?}", leftovers(&dir));
        std::fs::remove_file(&link).unwrap();

        mkfifo(&link);
        let target = link.clone();
        let result = within_20_s(move || write(&target)).expect("the write blocked on a FIFO");
        let err = result.expect_err(name);
        assert!(err.contains("regular files only"), "{name}: {err}");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_fifo(),
            "{name}: the FIFO was replaced"
        );
        std::fs::remove_file(&link).unwrap();
    }
}

/// `caustic render --stats | head` closes the pipe before the statistics are all written: the
/// process then ends quietly by SIGPIPE, as any Unix tool does, not with a panic. The read end
/// is closed before the process starts, so its first line meets a closed pipe.
#[test]
fn a_closed_stdout_ends_the_process_quietly() {
    use std::os::fd::{FromRawFd, OwnedFd};
    use std::os::unix::process::ExitStatusExt;
    let (dir, script) = setup("closed-stdout");
    let mut fds = [0; 2];
    // SAFETY: pipe writes two new descriptors into the array it is given.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // SAFETY: both descriptors were just made and are owned here alone.
    let (read, write) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(read);
    let out = caustic()
        .current_dir(&dir)
        .args(["render", "--stats", "-o", "out.png"])
        .arg(&script)
        .stdout(std::process::Stdio::from(write))
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        out.status.signal(),
        Some(libc::SIGPIPE),
        "{:?}: {stderr}",
        out.status
    );
}
