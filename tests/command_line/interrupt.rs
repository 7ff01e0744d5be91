//! Stopping a render early (Ctrl-C, `src/interrupt.rs`): the passes keep what they finished and
//! say so; the command line writes it as `NAME.partial.EXT`, marked, and exits with status 130;
//! a second SIGINT and `--no-partial` end the process at once, writing nothing.

use crate::common;

use crate::common::run_lua;
use caustic::camera::Camera;
use caustic::film::{Film, Window};
use caustic::integrator::progressive::ProgressiveSettings;
use caustic::integrator::{Partial, Settings};
use caustic::progress::Progress;
use caustic::scene::build::build_scene;
use std::sync::atomic::{AtomicU64, Ordering};

/// A lit back wall behind a ball, so that every rendered pixel has light and an unrendered
/// (black) row is told apart; `{W}`, `{H}` and `{LIGHT}` are filled in.
const SCENE: &str = "
    wall = gr.cube('wall'); wall:set_material(gr.material({0.6, 0.6, 0.6}, {0, 0, 0}, 0))
    wall:scale(20, 20, 1); wall:translate(-10, -10, -3)
    ball = gr.nh_sphere('ball', {0, 0, 0}, 1)
    ball:set_material(gr.material({0.7, 0.3, 0.2}, {0.3, 0.3, 0.3}, 20))
    root = gr.node('root'); root:add_child(wall); root:add_child(ball)
    gr.render(root, 'out.png', {W}, {H}, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0.2, 0.2, 0.2},
              {{LIGHT}})
";

/// Returns the scene script at `w × h` with the point light, or with photons when `photons`.
fn scene(w: u32, h: u32, photons: bool) -> String {
    let light = if photons {
        "gr.light({0, 3, 4}, {1, 1, 1}, {1, 0, 0}, 1, 2000)"
    } else {
        "gr.area_light({0, 3, 4}, {1, 1, 1}, {1, 0, 0}, nil, nil, {0.5, 0, 0}, {0, 0, 0.5})"
    };
    SCENE
        .replace("{W}", &w.to_string())
        .replace("{H}", &h.to_string())
        .replace("{LIGHT}", light)
}

/// A progress display that asks to stop once `after` units (rows, or passes) are done.
struct StopAfter {
    after: u64,
    done: AtomicU64,
}

impl Progress for StopAfter {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::SeqCst);
    }
    fn should_stop(&self) -> bool {
        self.done.load(Ordering::SeqCst) >= self.after
    }
}

/// Renders the script `src` with `settings`, stopped by `progress`.
fn render(src: &str, settings: &Settings, progress: &dyn Progress) -> (Film, Option<Partial>) {
    let d = run_lua(src).unwrap();
    let r = &d.renders[0];
    let mut scene = build_scene(&d, r).unwrap();
    let camera = Camera::new(&r.camera, r.width, r.height);
    let window = Window::full(r.width, r.height);
    let (film, stats) =
        crate::common::render_frame(&mut scene, &camera, window, settings, progress);
    (film, stats.interrupted)
}

/// A camera pass asked to stop after 5 of 64 rows finishes the rows it had started and starts
/// no more: every row is the full render's exactly or black with no samples, and the frame
/// says how many it rendered.
#[test]
fn a_stopped_camera_pass_keeps_the_rows_it_finished() {
    let src = scene(16, 64, false);
    let settings = common::whitted();
    let never = StopAfter {
        after: u64::MAX,
        done: AtomicU64::new(0),
    };
    let (full, none) = render(&src, &settings, &never);
    assert_eq!(none, None);
    let stop = StopAfter {
        after: 5,
        done: AtomicU64::new(0),
    };
    let (film, partial) = render(&src, &settings, &stop);
    let Some(Partial::Rows { done, rows: 64 }) = partial else {
        panic!("not stopped by rows: {partial:?}");
    };
    assert!((5..64).contains(&done), "{done} rows done");
    let mut rendered = 0;
    for y in 0..64usize {
        let row = y * 16..(y + 1) * 16;
        if film.samples[row.clone()].iter().all(|&n| n > 0) {
            assert_eq!(film.pixels[row.clone()], full.pixels[row], "row {y}");
            rendered += 1;
        } else {
            assert!(film.samples[row.clone()].iter().all(|&n| n == 0));
            assert!(film.pixels[row].iter().all(|p| *p == glam::Vec3A::ZERO));
        }
    }
    assert_eq!(rendered, done);
}

/// A progressive render asked to stop after its third pass returns the mean of those three
/// passes, equal to a three-pass render's image, and says so.
#[test]
fn a_stopped_progressive_render_keeps_the_mean_of_its_finished_passes() {
    let src = scene(12, 8, true);
    let progressive = |passes| Settings {
        progressive: Some(ProgressiveSettings {
            passes,
            ..ProgressiveSettings::default()
        }),
        ..Settings::default()
    };
    let stop = StopAfter {
        after: 3,
        done: AtomicU64::new(0),
    };
    let (film, partial) = render(&src, &progressive(1000), &stop);
    assert_eq!(
        partial,
        Some(Partial::Passes {
            done: 3,
            planned: 1000
        })
    );
    let never = StopAfter {
        after: u64::MAX,
        done: AtomicU64::new(0),
    };
    let (three, _) = render(&src, &progressive(3), &never);
    assert_eq!(film.pixels, three.pixels);
}

/// The command line, sent real signals.
#[cfg(target_os = "linux")]
mod signals {
    use super::scene;
    use crate::common::{caustic, out_dir};
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    use std::path::{Path, PathBuf};
    use std::process::{Child, Stdio};
    use std::time::Duration;

    /// Writes `src` as `scene.lua` in a fresh folder for `test`, preceded by a line that creates
    /// `started` (so a test knows the signal handler is in place: it is installed before the
    /// script runs); returns the folder.
    fn setup(test: &str, src: &str) -> PathBuf {
        let dir = out_dir(test);
        let script = format!("io.open('started', 'w'):close()\n{src}");
        std::fs::write(dir.join("scene.lua"), script).unwrap();
        dir
    }

    /// Starts `caustic render scene.lua ARGS` in `dir`, waits until the script has started and
    /// `settle` more (time for the scene to be built and rows to be rendered; the tests hold
    /// whatever was reached by then), and returns the process.
    ///
    /// The child starts with SIGINT at its default action whatever this process inherited: a
    /// test run launched in the background of a non-interactive shell has SIGINT ignored, and
    /// `--no-partial` (which installs no handler) would then keep ignoring it.
    fn start(dir: &Path, args: &[&str], settle: Duration) -> Child {
        let mut command = caustic();
        command
            .current_dir(dir)
            // The script marks its start by writing a file, which only a trusted script may.
            .args(["render", "scene.lua", "-q", "--trusted-script"])
            .args(args)
            .stderr(Stdio::piped());
        // SAFETY: between fork and exec only the async-signal-safe `signal` runs.
        unsafe {
            command.pre_exec(|| {
                libc::signal(libc::SIGINT, libc::SIG_DFL);
                Ok(())
            });
        }
        let child = command.spawn().unwrap();
        while !dir.join("started").exists() {
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(settle);
        child
    }

    /// Sends SIGINT to `child`.
    fn interrupt(child: &Child) {
        // SAFETY: kill with a valid pid and signal has no memory effects.
        let r = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
        assert_eq!(r, 0);
    }

    /// Sends SIGINT to `child` and waits for it; returns its stderr after checking that it
    /// exited with status 130.
    fn interrupted(child: Child) -> String {
        interrupt(&child);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(130), "{err}");
        err
    }

    /// Returns the names of the files in `dir` other than the script and the start mark.
    fn written(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n != "scene.lua" && n != "started")
            .collect();
        names.sort();
        names
    }

    /// A PNG's `tEXt` chunks: (keyword, text).
    type TextChunks = Vec<(String, String)>;

    /// Returns the PNG at `path`'s size, RGB bytes and `tEXt` chunks.
    fn read_png(path: &Path) -> ((u32, u32), Vec<u8>, TextChunks) {
        let file = std::fs::File::open(path).unwrap();
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let info = reader.info();
        let size = (info.width, info.height);
        let text = info
            .uncompressed_latin1_text
            .iter()
            .map(|t| (t.keyword.clone(), t.text.clone()))
            .collect();
        let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut rgb).unwrap();
        (size, rgb, text)
    }

    /// SIGINT during the rows: the process exits with status 130 saying what it wrote, the
    /// rows rendered so far are in `out.partial.png` with a `caustic-partial` chunk that counts
    /// them (every other row black), and nothing is at `out.png`. (The render would take many
    /// seconds; rows take milliseconds.)
    #[test]
    fn sigint_writes_the_rows_rendered_so_far_marked_and_exits_130() {
        let dir = setup("interrupt_rows", &scene(160, 120, false));
        let child = start(
            &dir,
            &["--spp", "256", "--light-samples", "16"],
            Duration::from_millis(500),
        );
        let err = interrupted(child);
        assert!(
            err.contains("interrupted: wrote ") && err.contains("to out.partial.png"),
            "{err}"
        );
        assert_eq!(written(&dir), ["out.partial.png"]);
        let ((w, h), rgb, text) = read_png(&dir.join("out.partial.png"));
        assert_eq!((w, h), (160, 120));
        let note = text
            .iter()
            .find(|(k, _)| k == "caustic-partial")
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("no caustic-partial chunk in {text:?}"));
        let rows = rgb.as_chunks::<{ 160 * 3 }>().0.iter();
        let lit = rows.clone().filter(|r| r.iter().all(|&c| c > 0)).count();
        let black = rows.filter(|r| r.iter().all(|&c| c == 0)).count();
        assert_eq!(lit + black, 120, "a row half rendered");
        assert!(lit > 0 && lit < 120, "{lit} rows rendered");
        assert!(note.contains(&format!("({lit} of 120;")), "{note}");
        assert!(err.contains(&format!("({lit} of 120;")), "{err}");
    }

    /// An interrupted progressive render writes the mean of the passes it finished (every
    /// pixel rendered), marked as such, in the output's format: here an EXR with a
    /// `caustic-partial` attribute.
    #[test]
    fn sigint_during_passes_writes_the_mean_of_the_finished_passes() {
        let dir = setup("interrupt_passes", &scene(24, 16, true));
        let child = start(
            &dir,
            &[
                "--integrator",
                "progressive",
                "--passes",
                "1000000",
                "--photons",
                "2000",
                "--caustic-photons",
                "2000",
                "-o",
                "out.exr",
            ],
            Duration::from_millis(1000),
        );
        let err = interrupted(child);
        assert!(
            err.contains("the mean of") && err.contains("out.partial.exr"),
            "{err}"
        );
        assert_eq!(written(&dir), ["out.partial.exr"]);
        let meta = exr::meta::MetaData::read_from_file(dir.join("out.partial.exr"), false).unwrap();
        let note = meta.headers[0]
            .own_attributes
            .other
            .iter()
            .find(|(k, _)| *k == "caustic-partial")
            .map(|(_, v)| format!("{v:?}"))
            .expect("no caustic-partial attribute");
        assert!(note.contains("the mean of"), "{note}");
        let img = caustic::io::image::read_rgb(&dir.join("out.partial.exr")).unwrap();
        assert!(img.pixels.iter().all(|p| p.min_element() > 0.0));
        // A partial image is no tile to stitch.
        let stitched = caustic()
            .current_dir(&dir)
            .args(["stitch", "out.partial.exr", "-o", "x.exr"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&stitched.stderr);
        assert!(
            !stitched.status.success() && err.contains("interrupted"),
            "{err}"
        );
    }

    /// SIGINT while the script itself runs (a loop that never ends) stops it at its next
    /// sampled line: status 130, the line named, no image.
    #[test]
    fn sigint_stops_a_running_script() {
        let dir = setup("interrupt_script", "x = 0\nwhile true do x = x + 1 end\n");
        let child = start(&dir, &[], Duration::from_millis(100));
        let err = interrupted(child);
        assert!(
            err.contains("interrupted: the script stopped near scene.lua:3"),
            "{err}"
        );
        assert!(written(&dir).is_empty());
    }

    /// With `--no-partial`, SIGINT ends the process as the signal does and nothing is written
    /// (no image, no partial image, no temporary file).
    #[test]
    fn sigint_with_no_partial_ends_the_process_writing_nothing() {
        let dir = setup("interrupt_no_partial", &scene(160, 120, false));
        let child = start(
            &dir,
            &["--spp", "256", "--light-samples", "16", "--no-partial"],
            Duration::from_millis(300),
        );
        interrupt(&child);
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.signal(), Some(libc::SIGINT), "{:?}", out.status);
        assert!(written(&dir).is_empty(), "{:?}", written(&dir));
    }

    /// A second SIGINT ends the process at once, while the first is still winding the render
    /// down (each row here takes about a second), and nothing is written.
    #[test]
    fn a_second_sigint_ends_the_process_at_once() {
        let dir = setup("interrupt_twice", &scene(4, 4, false));
        let child = start(
            &dir,
            &["--spp", "65536", "--light-samples", "64"],
            Duration::from_millis(300),
        );
        interrupt(&child);
        // Apart enough that the two are not merged into one pending signal.
        std::thread::sleep(Duration::from_millis(200));
        interrupt(&child);
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.signal(), Some(libc::SIGINT), "{:?}", out.status);
        assert!(written(&dir).is_empty(), "{:?}", written(&dir));
    }
}
