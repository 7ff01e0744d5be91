//! Writing and reading files the way a careful user's system has them: outputs behind symlinks,
//! with chosen permissions, special files (devices, FIFOs) named as outputs or inputs, and a
//! process killed while writing.
#![cfg(target_os = "linux")]

mod common;

use common::{caustic, out_dir};
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
    assert!(
        !ok && err.contains("/dev/zero") && err.contains("is a device"),
        "{err}"
    );
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
}

/// A process that receives SIGTERM while writing an output removes its temporary file and
/// still dies by the signal (the `.tmp<PID>` file was left behind). Run in a child process
/// (this test binary again), which signals itself from inside the write.
#[test]
fn sigterm_while_writing_removes_the_temporary_file() {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/stability_output_sigterm");
    if std::env::var_os("STABILITY_SIGTERM_CHILD").is_some() {
        let _ = caustic::files::write_replacing(&dir.join("out.png"), |tmp| {
            std::fs::write(tmp, b"partial").map_err(|e| e.to_string())?;
            // SAFETY: raising a signal in this process is always allowed.
            unsafe { libc::raise(libc::SIGTERM) };
            Ok(())
        });
        unreachable!("SIGTERM must end the child");
    }
    let dir = out_dir("stability_output_sigterm");
    std::fs::write(dir.join("out.png"), b"old").unwrap();
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "sigterm_while_writing_removes_the_temporary_file",
            "--test-threads",
            "1",
        ])
        .env("STABILITY_SIGTERM_CHILD", "1")
        .status()
        .unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGTERM), "{status:?}");
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"old");
}
