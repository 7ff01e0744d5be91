//! The progressive integrator against closed forms: its error falls with passes at the rate
//! progressive photon mapping predicts, it converges to the right image, its memory does not
//! grow with passes, it is deterministic, and `--target-error` stops near the error it asks for.

use crate::common::{caustic, out_dir, run_lua, run_ok};
use caustic::camera::Camera;
use caustic::film::{Film, Window};
use caustic::integrator::photon_map::{GiSettings, Indirect};
use caustic::integrator::progressive::{ProgressiveSettings, Stop, pass_seed};
use caustic::integrator::{Integrator, Settings};
use caustic::progress::{NoProgress, Progress};
use caustic::render::Sampling;
use caustic::scene::build::build_scene;
use glam::Vec3A;
use std::sync::Mutex;

/// Side of the analytic scene's image in pixels.
pub(crate) const SIDE: u32 = 24;

/// A diffuse floor (kd 0.5, top face y = 0) under a point light of `rgb` 1 and physical falloff
/// at height 10, with a small perfect mirror (ks 1, 0.2 × 0.2) facing down at height 10.5 that
/// reflects a caustic onto the floor 4.4 wide; the camera at height 1 looks straight down at
/// the middle 1 × 1 of it. Direct light and caustic are both nearly uniform there, so pixel
/// jitter adds almost no noise and the error is the photon estimate's. The mirror, in Lua;
/// [`floor_scene`] adds the rest.
const MIRROR_SCENE: &str = "
mirror_m = gr.material({0, 0, 0}, {1, 1, 1}, 100)
m = gr.cube('mirror'); m:set_material(mirror_m); m:scale(0.2, 0.1, 0.2); m:translate(-0.1, 10.5, -0.1)
root:add_child(m)
";

/// Returns the scene of the floor, the light and the camera of [`MIRROR_SCENE`] with `mirrors`
/// (Lua adding them to `root`).
fn floor_scene(mirrors: &str) -> String {
    format!(
        "
floor_m = gr.material({{0.5, 0.5, 0.5}}, {{0, 0, 0}}, 0)
root = gr.node('root')
f = gr.cube('floor'); f:set_material(floor_m); f:scale(40, 1, 40); f:translate(-20, -1, -20)
root:add_child(f)
{mirrors}
gr.render(root, 'x.png', 24, 24, {{0, 1, 0}}, {{0, -1, 0}}, {{0, 0, -1}}, 53.130102, {{0, 0, 0}},
          {{gr.light({{0, 10, 0}}, {{1, 1, 1}}, {{0, 0, 1}})}})
"
    )
}

/// Returns the radiance of the mirror scene's floor at `p` (y = 0, inside the caustic): the
/// direct term `kd·rgb·cos θ/d²` from the light at height 10, plus the caustic the mirror
/// reflects, which is the direct term of the light's image at height 11 (`kd·ks·rgb·cos θ'/d'²`).
/// Light that left the floor is in neither map here (the global map has no photons), so this
/// is the whole of what the integrator estimates.
fn mirror_closed_form(p: Vec3A) -> f32 {
    let term = |h: f32| {
        let d2 = p.x * p.x + p.z * p.z + h * h;
        0.5 * h / (d2 * d2.sqrt())
    };
    term(10.0) + term(11.0)
}

/// Returns each pixel's closed-form value averaged over its area (16 × 16 sub-positions), as
/// jittered passes average it.
fn mirror_reference(camera: &Camera) -> Vec<f32> {
    let mut out = Vec::new();
    for y in 0..SIDE {
        for x in 0..SIDE {
            let mut sum = 0.0;
            for j in 0..16 {
                for i in 0..16 {
                    let (u, v) = ((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                    let ray = camera.ray(x as f32 + u, y as f32 + v);
                    let t = -ray.origin.y / ray.dir.y;
                    sum += mirror_closed_form(ray.origin + t * ray.dir);
                }
            }
            out.push(sum / 256.0);
        }
    }
    out
}

/// The progressive settings of the mirror scene: caustic photons only, the global map empty and
/// seen directly (no gather rays), one jittered sample per pass.
pub(crate) fn mirror_settings(seed: u64, progressive: ProgressiveSettings) -> Settings {
    Settings {
        seed,
        sampling: Sampling::Stratified { spp: 1 },
        photons: GiSettings {
            seed,
            photons: 0,
            caustic_photons: 20_000,
            follow_image: false,
            indirect: Indirect::Direct,
            ..GiSettings::default()
        },
        progressive: Some(progressive),
        ..Settings::default()
    }
}

/// Keeps every snapshot a progressive render reports.
#[derive(Default)]
struct Snapshots(Mutex<Vec<(u32, Film)>>);

impl Progress for Snapshots {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn snapshot(&self, passes: u32, image: &Film) {
        self.0.lock().unwrap().push((passes, image.clone()));
    }
}

/// Returns the mirror scene and its camera.
pub(crate) fn mirror_scene() -> (caustic::scene::Scene, Camera) {
    floor_scene_with(MIRROR_SCENE)
}

/// Returns the mirror scene, its camera, each pixel's closed form ([`mirror_reference`]) and
/// their mean.
pub(crate) fn mirror_with_reference() -> (caustic::scene::Scene, Camera, Vec<f32>, f64) {
    let (scene, camera) = mirror_scene();
    let reference = mirror_reference(&camera);
    let mean = reference.iter().map(|&r| r as f64).sum::<f64>() / reference.len() as f64;
    (scene, camera, reference, mean)
}

/// Returns [`floor_scene`] with `mirrors`, built, and its camera.
fn floor_scene_with(mirrors: &str) -> (caustic::scene::Scene, Camera) {
    let d = run_lua(&floor_scene(mirrors)).unwrap();
    let r = &d.renders[0];
    (
        build_scene(&d, r).unwrap(),
        Camera::new(&r.camera, r.width, r.height),
    )
}

/// Renders `scene` progressively with [`mirror_settings`] of `seed` and `progressive`, and
/// returns the running images after each of `checkpoints` passes (each a snapshot it asks for).
fn mirror_snapshots(
    scene: &mut caustic::scene::Scene,
    camera: &Camera,
    seed: u64,
    progressive: ProgressiveSettings,
    checkpoints: &[u32],
) -> Vec<Film> {
    let settings = mirror_settings(seed, progressive);
    let snapshots = Snapshots::default();
    let window = Window::full(SIDE, SIDE);
    let (_, stats) = crate::common::render_frame(scene, camera, window, &settings, &snapshots);
    assert_eq!(stats.plan.integrator, Integrator::Progressive);
    let mut snaps = snapshots.0.into_inner().unwrap();
    checkpoints
        .iter()
        .map(|&n| {
            let i = snaps.iter().position(|s| s.0 == n).expect("a snapshot");
            snaps.swap_remove(i).1
        })
        .collect()
}

/// Returns the mean squared error and the mean of `film` against the per-pixel `reference`.
pub(crate) fn mse_and_mean(film: &Film, reference: &[f32]) -> (f64, f64) {
    let (mut se, mut sum) = (0.0f64, 0.0f64);
    for (p, &r) in film.pixels.iter().zip(reference) {
        for c in 0..3 {
            se += ((p[c] - r) as f64).powi(2);
            sum += p[c] as f64;
        }
    }
    let n = 3.0 * reference.len() as f64;
    (se / n, sum / n)
}

/// The caustic's error falls as passes^(−1/3) (α = 2/3): the RMSE against the closed form, over
/// 6 seeds at 4, 8, 16, 32 and 64 passes (6 × 64 passes of 20,000 photons and 576 pixels), has
/// a least-squares log-log slope within 0.1 of −1/3, and after 64 passes the image's mean is
/// within 1% of the closed form's. A fixed radius would fall as −1/2, a radius shrinking as in
/// SPPM's α = 1/3 as −1/6; a wrong power or kernel normalisation moves the mean.
#[test]
fn progressive_error_falls_at_the_predicted_rate_and_converges_to_the_closed_form() {
    let (mut scene, camera, reference, ref_mean) = mirror_with_reference();
    let seeds = 6;
    let checkpoints = [4u32, 8, 16, 32, 64];
    let mut mse = [0.0f64; 5];
    let mut final_mean = 0.0;
    for seed in 0..seeds {
        let progressive = ProgressiveSettings {
            passes: 64,
            snapshot_every: Some(4),
            ..ProgressiveSettings::default()
        };
        let films = mirror_snapshots(&mut scene, &camera, seed, progressive, &checkpoints);
        for (k, (film, &n)) in films.iter().zip(&checkpoints).enumerate() {
            let (e, m) = mse_and_mean(film, &reference);
            mse[k] += e / seeds as f64;
            if n == 64 {
                final_mean += m / seeds as f64;
            }
        }
    }
    let xs: Vec<f64> = checkpoints.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = mse.iter().map(|&e| 0.5 * e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 5.0, ys.iter().sum::<f64>() / 5.0);
    let slope = xs
        .iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    let rel: Vec<String> = mse
        .iter()
        .map(|e| format!("{:.4}", e.sqrt() / ref_mean))
        .collect();
    println!("relative RMSE at {checkpoints:?} passes: {rel:?}; slope {slope:.3}");
    assert!(
        (slope + 1.0 / 3.0).abs() < 0.1,
        "log-log slope {slope:.3}, expected -1/3 ± 0.1 (relative RMSE {rel:?})"
    );
    let ratio = final_mean / ref_mean;
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "mean after 64 passes is {ratio:.4} of the closed form's"
    );
}

/// The mirror scene with a mirror half as wide (its caustic 2.2 wide, the photons 4 times
/// denser), split in two halves along x = 0: the left reflects all the light (ks 1), the right
/// a tenth (ks 0.1), so the floor's caustic is ten times dimmer, and its photons ten times
/// sparser, for x > 0 (the image's right half: the camera's right is +x). The mirrors, in Lua.
const TWO_MIRRORS: &str = "
bright_m = gr.material({0, 0, 0}, {1, 1, 1}, 100)
dim_m = gr.material({0, 0, 0}, {0.1, 0.1, 0.1}, 100)
a = gr.cube('bright'); a:set_material(bright_m); a:scale(0.05, 0.1, 0.1); a:translate(-0.05, 10.5, -0.05)
root:add_child(a)
b = gr.cube('dim'); b:set_material(dim_m); b:scale(0.05, 0.1, 0.1); b:translate(0, 10.5, -0.05)
root:add_child(b)
";

/// Returns the two-mirror scene's caustic alone at floor point `p` (the part the photon maps
/// estimate; the direct term is the same shadow ray in both halves): the light's image at
/// height 11 seen through the half of the mirror over `p`.
fn two_mirrors_caustic(p: Vec3A) -> f32 {
    let d2 = p.x * p.x + p.z * p.z + 121.0;
    let ks = if p.x < 0.0 { 1.0 } else { 0.1 };
    ks * 0.5 * 11.0 / (d2 * d2.sqrt())
}

/// Local radii make a dim caustic converge as a bright one does. On the two-mirror scene (the
/// right half's caustic a tenth of the left's, its photons ten times sparser), over 4 seeds at
/// 8, 16 and 32 passes of 20,000 caustic photons: with one radius per map the right half's
/// error relative to its caustic is about √10 times the left's (the same radius holds a tenth
/// of the photons); with local radii the two are within a factor 1.6 of each other, the dim
/// half's error is at most 0.6 times the one radius's, each half's error still falls at
/// −1/3 ± 0.15 against passes, and each half's mean after 32 passes is within 2% of the closed
/// form (the three columns either side of the halves' edge left out: there any radius blurs
/// the bright caustic into the dim one).
#[test]
fn local_radii_make_dim_caustics_converge_as_bright_ones_do() {
    let (mut scene, camera) = floor_scene_with(TWO_MIRRORS);
    let direct = |p: Vec3A| {
        let d2 = p.x * p.x + p.z * p.z + 100.0;
        0.5 * 10.0 / (d2 * d2.sqrt())
    };
    // Each pixel's direct term and caustic averaged over its area.
    let mut reference = Vec::new();
    for y in 0..SIDE {
        for x in 0..SIDE {
            let (mut dir, mut cau) = (0.0, 0.0);
            for j in 0..16 {
                for i in 0..16 {
                    let (u, v) = ((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                    let ray = camera.ray(x as f32 + u, y as f32 + v);
                    let p = ray.origin + (-ray.origin.y / ray.dir.y) * ray.dir;
                    (dir, cau) = (
                        dir + direct(p) / 256.0,
                        cau + two_mirrors_caustic(p) / 256.0,
                    );
                }
            }
            reference.push((dir, cau));
        }
    }
    let halves = [0..SIDE / 2 - 3, SIDE / 2 + 3..SIDE];
    let checkpoints = [8u32, 16, 32];
    let seeds = 4;
    // [mode][half][checkpoint]: squared error summed over seeds, pixels and channels; and the
    // mean ratio to the closed form after the last pass.
    let mut se = [[[0.0f64; 3]; 2]; 2];
    let mut ratio = [[0.0f64; 2]; 2];
    for (mode, local_radii) in [false, true].into_iter().enumerate() {
        for seed in 0..seeds {
            let progressive = ProgressiveSettings {
                passes: 32,
                snapshot_every: Some(8),
                local_radii,
                ..ProgressiveSettings::default()
            };
            let films = mirror_snapshots(&mut scene, &camera, seed, progressive, &checkpoints);
            for (c, (film, &n)) in films.iter().zip(&checkpoints).enumerate() {
                for (h, cols) in halves.iter().enumerate() {
                    let (mut sum, mut want) = (0.0f64, 0.0f64);
                    for y in 0..SIDE {
                        for x in cols.clone() {
                            let (dir, cau) = reference[(y * SIDE + x) as usize];
                            let caustic = film.get(x, y) - Vec3A::splat(dir);
                            for ch in 0..3 {
                                se[mode][h][c] += ((caustic[ch] - cau) as f64).powi(2);
                                sum += caustic[ch] as f64;
                                want += cau as f64;
                            }
                        }
                    }
                    if n == 32 {
                        ratio[mode][h] += sum / want / seeds as f64;
                    }
                }
            }
        }
    }
    // Relative RMSE of each half's caustic: over its closed form's mean.
    let pixels = 3.0 * (SIDE * halves[0].len() as u32) as f64 * seeds as f64;
    let mean_caustic = |h: usize| {
        let mut m = 0.0f64;
        for y in 0..SIDE {
            for x in halves[h].clone() {
                m += reference[(y * SIDE + x) as usize].1 as f64;
            }
        }
        m / (SIDE * halves[h].len() as u32) as f64
    };
    let rel = |mode: usize, h: usize, c: usize| (se[mode][h][c] / pixels).sqrt() / mean_caustic(h);
    let slope = |mode: usize, h: usize| {
        let xs = checkpoints.map(|n| (n as f64).ln());
        let ys = [0, 1, 2].map(|c| rel(mode, h, c).ln());
        let (mx, my) = (xs.iter().sum::<f64>() / 3.0, ys.iter().sum::<f64>() / 3.0);
        let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
        num / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>()
    };
    for (mode, name) in ["one radius", "local radii"].iter().enumerate() {
        println!(
            "{name}: bright {:.4} {:.4} {:.4} (slope {:.3}, mean {:.4}), dim {:.4} {:.4} {:.4} (slope {:.3}, mean {:.4})",
            rel(mode, 0, 0),
            rel(mode, 0, 1),
            rel(mode, 0, 2),
            slope(mode, 0),
            ratio[mode][0],
            rel(mode, 1, 0),
            rel(mode, 1, 1),
            rel(mode, 1, 2),
            slope(mode, 1),
            ratio[mode][1],
        );
    }
    let global_ratio = rel(0, 1, 2) / rel(0, 0, 2);
    let local_ratio = rel(1, 1, 2) / rel(1, 0, 2);
    assert!(
        global_ratio > 2.0,
        "one radius: dim/bright error ratio {global_ratio:.2}, expected about √10"
    );
    assert!(
        (1.0 / 1.6..1.6).contains(&local_ratio),
        "local radii: dim/bright error ratio {local_ratio:.2}"
    );
    assert!(
        rel(1, 1, 2) < 0.6 * rel(0, 1, 2),
        "local radii: dim half {:.4} against one radius's {:.4}",
        rel(1, 1, 2),
        rel(0, 1, 2)
    );
    for (h, &m) in ratio[1].iter().enumerate() {
        let s = slope(1, h);
        assert!(
            (s + 1.0 / 3.0).abs() < 0.15,
            "local radii, half {h}: slope {s:.3}"
        );
        assert!(
            (m - 1.0).abs() < 0.02,
            "local radii, half {h}: mean ratio {m:.4}"
        );
    }
}

/// `target_error` stops where the actual error is close to the target: on the mirror scene, for
/// targets 0.02 and 0.01 (2 seeds each), the relative RMSE against the closed form when it
/// stops is within a factor 1.5 of the target either way, and it stopped for that reason.
#[test]
fn target_error_stops_near_the_error_it_asks_for() {
    let (mut scene, camera, reference, ref_mean) = mirror_with_reference();
    for target in [0.02, 0.01] {
        for seed in [1, 2] {
            let settings = mirror_settings(
                seed,
                ProgressiveSettings {
                    passes: 4096,
                    target_error: Some(target),
                    ..ProgressiveSettings::default()
                },
            );
            let window = Window::full(SIDE, SIDE);
            let (film, stats) =
                crate::common::render_frame(&mut scene, &camera, window, &settings, &NoProgress);
            let p = stats.progressive.unwrap();
            assert_eq!(p.stop, Stop::TargetError, "target {target}");
            let actual = mse_and_mean(&film, &reference).0.sqrt() / ref_mean;
            println!(
                "target {target}, seed {seed}: {} passes, estimated {:.4}, actual {actual:.4}",
                p.passes,
                p.estimated_error.unwrap()
            );
            assert!(
                actual < 1.5 * target && actual > target / 1.5,
                "target {target}: actual relative RMSE {actual:.4} after {} passes",
                p.passes
            );
        }
    }
}

/// A time budget stops the render by itself: with a budget of 0.3 s and at most 10^6 passes,
/// it stops for the budget after at least one pass and reports an error estimate once it has
/// two.
#[test]
fn time_budget_stops_the_render() {
    let (mut scene, camera) = mirror_scene();
    let settings = mirror_settings(
        3,
        ProgressiveSettings {
            passes: 1 << 20,
            time_budget: Some(std::time::Duration::from_millis(300)),
            ..ProgressiveSettings::default()
        },
    );
    let window = Window::full(SIDE, SIDE);
    let (_, stats) =
        crate::common::render_frame(&mut scene, &camera, window, &settings, &NoProgress);
    let p = stats.progressive.unwrap();
    assert_eq!(p.stop, Stop::TimeBudget);
    assert!(p.passes >= 1 && p.passes < 1 << 20, "{} passes", p.passes);
    assert_eq!(p.estimated_error.is_some(), p.passes >= 2);
}

/// A Cornell box with a glass ball and an area light, small enough for tests.
const GLASS_BOX: &str = "
white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
red = gr.material({0.7, 0.1, 0.1}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
root = gr.node('root')
function wall(name, mat, sx, sy, sz, tx, ty, tz)
  local b = gr.cube(name); b:set_material(mat); b:scale(sx, sy, sz); b:translate(tx, ty, tz)
  root:add_child(b)
end
wall('floor', white, 2.2, 0.1, 2.2, -1.1, -1.1, -1.1)
wall('ceiling', white, 2.2, 0.1, 2.2, -1.1, 1.0, -1.1)
wall('back', white, 2.2, 2.2, 0.1, -1.1, -1.1, -1.1)
wall('left', red, 0.1, 2.2, 2.2, -1.1, -1.1, -1.1)
wall('right', white, 0.1, 2.2, 2.2, 1.0, -1.1, -1.1)
ball = gr.sphere('ball'); ball:set_material(glass); ball:scale(0.35, 0.35, 0.35)
ball:translate(0.2, -0.65, 0); root:add_child(ball)
light = gr.area_light({0, 0.98, 0}, {4, 4, 4}, {0, 0, 1}, nil, nil, {0.3, 0, 0}, {0, 0, 0.3})
gr.render(root, 'box.png', 32, 32, {0, 0, 3.2}, {0, 0, -1}, {0, 1, 0}, 45, {0, 0, 0}, {light})
";

/// The peak resident memory `--stats` reports after `passes` progressive passes of the glass box
/// (a process of its own, so nothing else in it allocates), in MiB.
fn peak_after(passes: u32) -> f64 {
    let dir = out_dir("progressive_memory");
    let script = dir.join("box.lua");
    std::fs::write(&script, GLASS_BOX).unwrap();
    let out = run_ok(caustic().args([
        "render",
        script.to_str().unwrap(),
        "-o",
        dir.join(format!("box{passes}.png")).to_str().unwrap(),
        "--integrator",
        "progressive",
        "--passes",
        &passes.to_string(),
        "--photons",
        "100000",
        "--caustic-photons",
        "200000",
        "--gather-rays",
        "4",
        "--threads",
        "2",
        "--stats",
        "-q",
    ]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let said = format!("progressive: {passes} passes in");
    assert!(stderr.contains(&said), "no '{said}' on stderr:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.contains("peak resident memory"))
        .unwrap_or_else(|| panic!("no peak memory in --stats:\n{stdout}"));
    let mib = line
        .split(':')
        .nth(1)
        .unwrap()
        .trim()
        .trim_end_matches(" MiB");
    mib.parse().unwrap()
}

/// Memory stays flat across passes: the peak resident size after 64 passes is within 5% of the
/// peak after 4 (each pass's maps, 300,000 photons emitted, are freed before the next), where
/// keeping per-pass state would grow the passes' part 16-fold, and where the allocator's free
/// pieces left resident by each pass made it creep by 20-30 KB a pass.
#[test]
fn peak_memory_does_not_grow_with_passes() {
    if !std::path::Path::new("/proc/self/status").exists() {
        println!("skipped peak_memory_does_not_grow_with_passes: no /proc/self/status here");
        return;
    }
    let (four, sixty_four) = (peak_after(4), peak_after(64));
    println!("peak resident memory: {four:.1} MiB after 4 passes, {sixty_four:.1} MiB after 64");
    assert!(
        sixty_four < 1.05 * four,
        "peak {sixty_four:.1} MiB after 64 passes against {four:.1} MiB after 4"
    );
}

/// A progressive render is deterministic: 6 passes of the glass box are bit-identical on one
/// and two threads, and a window rendered alone equals the same window of the full image.
#[test]
fn progressive_renders_are_deterministic_across_threads_and_tiles() {
    let d = run_lua(GLASS_BOX).unwrap();
    let r = &d.renders[0];
    let mut scene = build_scene(&d, r).unwrap();
    let camera = Camera::new(&r.camera, r.width, r.height);
    let settings = Settings {
        photons: GiSettings {
            photons: 10_000,
            caustic_photons: 20_000,
            follow_image: false,
            indirect: Indirect::Gather { rays: 4 },
            ..GiSettings::default()
        },
        progressive: Some(ProgressiveSettings {
            passes: 6,
            ..ProgressiveSettings::default()
        }),
        sampling: Sampling::Stratified { spp: 1 },
        ..Settings::default()
    };
    let mut render = |threads: usize, window: Window| {
        crate::common::render_on_threads(threads, &mut scene, &camera, window, &settings).0
    };
    let full = Window::full(32, 32);
    let one = render(1, full);
    let two = render(2, full);
    assert!(one.pixels == two.pixels, "1 and 2 threads differ");
    let tile = Window {
        x0: 8,
        y0: 12,
        x1: 24,
        y1: 20,
        ..full
    };
    crate::common::assert_window_of(&render(2, tile), &one, tile);
    assert!(one.pixels.iter().any(|p| p.max_element() > 0.0));
    assert_ne!(pass_seed(0, 0), pass_seed(0, 1));
}

/// The command line's progressive flags are bounded and need the integrator: each bad value is a
/// usage error naming its flag, before any work.
#[test]
fn progressive_flags_are_checked() {
    let dir = out_dir("progressive_flags");
    let script = dir.join("box.lua");
    std::fs::write(&script, GLASS_BOX).unwrap();
    let s = script.to_str().unwrap();
    for (args, flag) in [
        (vec!["--passes", "4"], "--passes"),
        (vec!["--write-every", "2"], "--write-every"),
        (vec!["--local-radii", "off"], "--local-radii"),
        (vec!["--integrator", "sppm", "--passes", "0"], "--passes"),
        (
            vec!["--integrator", "sppm", "--passes", "2000000"],
            "--passes",
        ),
        (
            vec!["--integrator", "progressive", "--alpha", "1"],
            "--alpha",
        ),
        (
            vec!["--integrator", "progressive", "--radius", "0"],
            "--radius",
        ),
        (
            vec!["--integrator", "progressive", "--target-error=-1"],
            "--target-error",
        ),
        (
            vec!["--integrator", "progressive", "--time-budget", "nan"],
            "--time-budget",
        ),
        (
            vec!["--integrator", "progressive", "--adaptive"],
            "--adaptive",
        ),
        (
            vec!["--integrator", "progressive", "--gi", "off"],
            "--gi off",
        ),
    ] {
        let out = caustic()
            .args(["render", s, "-o", dir.join("x.png").to_str().unwrap()])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}
