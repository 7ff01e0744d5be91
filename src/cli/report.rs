//! What the command line prints: the progress bar, `--stats` and `caustic info`'s summary.

use crate::desc::{RenderDesc, SceneDesc};
use crate::error::Result;
use crate::frame::Frame;
use crate::integrator::photon_map::GiStats;
use crate::progress::Progress;
use crate::scene::build::count_placements;
use crate::stats::RenderStats;
use std::path::Path;

/// The progress bar of one image on stderr (hidden unless `show`): one phase after another, each
/// with its own count, elapsed time and estimate of time left.
pub struct Bar {
    bar: indicatif::ProgressBar,
    /// The image's path, shown before each phase's name.
    image: String,
}

impl Bar {
    /// Returns the bar of the image written to `out`, shown only when `show`.
    pub fn new(show: bool, out: &std::path::Path) -> Bar {
        let bar = if show {
            let bar = indicatif::ProgressBar::new(0);
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {human_pos}/{human_len}, {elapsed} elapsed, {eta} left",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        } else {
            indicatif::ProgressBar::hidden()
        };
        Bar {
            bar,
            image: out.display().to_string(),
        }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Progress for Bar {
    fn start(&self, what: &str, total: u64) {
        self.bar.reset();
        self.bar.set_length(total);
        self.bar.set_message(format!("{}: {what}", self.image));
    }

    fn advance(&self, n: u64) {
        self.bar.inc(n);
    }

    fn should_stop(&self) -> bool {
        crate::interrupt::requested()
    }
}

/// The progress of one image: its [`Bar`], and a progressive render's running image written
/// to the output at each snapshot (`--write-every`), so the file is always the latest mean.
pub struct Snapshots<'a> {
    pub bar: &'a Bar,
    pub out: &'a Path,
    pub tonemap: crate::io::image::Tonemap,
}

impl Progress for Snapshots<'_> {
    fn start(&self, what: &str, total: u64) {
        self.bar.start(what, total);
    }

    fn advance(&self, n: u64) {
        self.bar.advance(n);
    }

    fn should_stop(&self) -> bool {
        self.bar.should_stop()
    }

    fn snapshot(&self, passes: u32, image: &crate::film::Film) {
        // A failed snapshot loses nothing the final write will not retry; say so and go on.
        if let Err(e) = crate::io::image::write_image(image, self.out, self.tonemap) {
            self.bar
                .bar
                .suspend(|| eprintln!("warning: after {passes} passes: {e}"));
        }
    }
}

/// Prints `--stats` for one frame written to `out` from the `gr.render` call `r`: the scene,
/// the camera pass, the plan with its phases' times, the photon passes and the memory.
pub fn print_stats(
    frame: &Frame,
    r: &RenderDesc,
    out: &Path,
    traversal: Option<&crate::accel::counters::ByKind>,
) {
    print_scene(frame, r, out);
    let secs = print_camera_pass(frame, traversal);
    print_plan(frame, secs);
    let rstats = &frame.stats.render;
    if let Some(photons) = &frame.stats.photons {
        print_photon_stats(photons, rstats);
    }
    if let Some(p) = &frame.stats.progressive {
        let error = p
            .estimated_error
            .map_or("none".to_string(), |e| format!("{e:.4}"));
        println!(
            "  progressive: {} passes in {:.3} s (stopped by {:?}); {}radii global {:.4e} -> {:.4e}, caustic {:.4e} -> {:.4e}; estimated relative RMSE {error}",
            p.passes,
            p.time.as_secs_f64(),
            p.stop,
            if p.local_radii {
                "local radii (medians), "
            } else {
                ""
            },
            p.first_radii.0,
            p.last_radii.0,
            p.first_radii.1,
            p.last_radii.1,
        );
    }
    if let Some(kib) = crate::mem::peak_resident_kib() {
        println!("  peak resident memory: {:.1} MiB", kib as f64 / 1024.0);
    }
}

/// Prints the frame's image, its scene's instances and lights, and its triangles and BVH.
fn print_scene(frame: &Frame, r: &RenderDesc, out: &Path) {
    let (scene, film) = (&frame.scene, &frame.film);
    let b = &scene.stats;
    println!(
        "image {}: {}x{} from {}",
        out.display(),
        film.width,
        film.height,
        r.loc
    );
    let kinds: Vec<String> = b.by_kind.iter().map(|(k, v)| format!("{k} {v}")).collect();
    println!(
        "  scene: {} instances ({}), {} lights",
        scene.instances.len(),
        kinds.join(", "),
        scene.lights.len()
    );
    println!(
        "  triangles: {} placed, {} stored; BVH {} bytes; build {:.3} s",
        b.triangles_placed,
        b.triangles_stored,
        b.bvh_bytes,
        b.build_time.as_secs_f64()
    );
}

/// Prints the camera pass's rays, traversal (by ray kind, when counted), capped paths, weak
/// branches and material time; returns the pass's wall time in seconds.
fn print_camera_pass(frame: &Frame, traversal: Option<&crate::accel::counters::ByKind>) -> f64 {
    let (film, rstats) = (&frame.film, &frame.stats.render);
    let n = film.samples.len().max(1) as f64;
    let total: u64 = film.samples.iter().map(|&s| s as u64).sum();
    let (lo, hi) = (
        film.samples.iter().min().copied().unwrap_or(0),
        film.samples.iter().max().copied().unwrap_or(0),
    );
    println!(
        "  camera rays per pixel: mean {:.2}, min {lo}, max {hi}",
        total as f64 / n
    );
    let secs = rstats.time.as_secs_f64();
    let rays = rstats.primary_rays + rstats.shadow_rays + rstats.secondary_rays;
    println!(
        "  rays: {} primary, {} shadow, {} secondary; render {:.3} s ({:.2} Mrays/s, {} threads)",
        rstats.primary_rays,
        rstats.shadow_rays,
        rstats.secondary_rays,
        secs,
        rays as f64 / secs.max(1e-9) / 1e6,
        rayon::current_num_threads()
    );
    if let Some(by_kind) = traversal {
        let per = |n: u64, rays: u64| n as f64 / rays.max(1) as f64;
        let kinds: Vec<String> = crate::accel::counters::KINDS
            .iter()
            .zip(by_kind)
            .filter(|(_, c)| c.rays > 0)
            .map(|(k, c)| {
                format!(
                    "{} {} rays, {:.1} nodes and {:.1} triangles each",
                    k.name(),
                    c.rays,
                    per(c.nodes, c.rays),
                    per(c.triangles, c.rays)
                )
            })
            .collect();
        println!(
            "  traversal by ray kind (every phase): {}",
            kinds.join("; ")
        );
    }
    println!(
        "  eye paths stopped at the {}-bounce cap: {}; NaN or infinite samples dropped: {}",
        crate::integrator::eye::MAX_PATH_DEPTH,
        rstats.depth_capped,
        rstats.nonfinite_samples
    );
    if rstats.weak_skipped > 0 {
        println!(
            "  weak branches (under {}% of a sample): {} surfaces left unshaded, shaded instead by one sample of their pixel in up to {}",
            crate::render::WEAK_BRANCH * 100.0,
            rstats.weak_skipped,
            crate::render::WEAK_SHARERS
        );
    }
    // Thread time summed over workers, against wall time times the workers.
    let busy = secs * rayon::current_num_threads() as f64;
    println!(
        "  materials (textures, bump maps, Perlin noise): {:.3} s of thread time, {:.1}% of render time",
        rstats.material_time.as_secs_f64(),
        100.0 * rstats.material_time.as_secs_f64() / busy.max(1e-9)
    );
    secs
}

/// Prints the plan, each decision with the time of the phases it ran (the camera pass, `secs`,
/// runs every one that shades).
fn print_plan(frame: &crate::frame::Frame, secs: f64) {
    use crate::integrator::plan::Effect;
    let plan = &frame.stats.plan;
    let (r, photons) = (&frame.stats.render, frame.stats.photons.as_ref());
    let s = |d: std::time::Duration| d.as_secs_f64();
    println!("  plan, with the phases each decision runs:");
    for d in &plan.decisions {
        let phase = match (d.effect, d.on, photons) {
            (Effect::PhotonMaps, true, Some(p)) => format!(
                "; global map traced and built in {:.3} s",
                s((p.trace_time + p.build_time).saturating_sub(p.caustic_time))
            ),
            (Effect::Caustics, true, Some(p)) => {
                format!(
                    "; caustic map traced and built in {:.3} s",
                    s(p.caustic_time)
                )
            }
            (Effect::FinalGathering, true, Some(p)) => format!(
                "; precomputation points {:.3} s, irradiance cache {:.3} s, {} gathers in the camera pass",
                s(p.precompute_time),
                p.cache.as_ref().map_or(0.0, |c| s(c.time)),
                r.gathered
            ),
            (Effect::SoftShadows, true, _) => {
                format!("; {} shadow rays in the camera pass", r.shadow_rays)
            }
            (Effect::Textures | Effect::NormalMaps | Effect::Noise, true, _) => format!(
                "; materials (textures, maps and noise together) {:.3} s of thread time in the camera pass",
                s(r.material_time)
            ),
            _ => String::new(),
        };
        println!("    {d}{phase}");
    }
    println!(
        "    specular depth: {} ({})",
        plan.features.specular_depth, plan.depth_why
    );
    println!("    camera pass: {secs:.3} s");
    if let Some(planned) = photons.and_then(|p| p.planned.as_ref()) {
        println!("    budget: {planned}");
    }
    for note in &plan.notes {
        println!("    {note}");
    }
}

/// Prints the photon passes' counters and the camera pass's photon lookups.
fn print_photon_stats(s: &GiStats, rstats: &RenderStats) {
    for (name, counts, bytes) in [
        ("global", &s.global, s.global_bytes),
        ("caustic", &s.caustic, s.caustic_bytes),
    ] {
        let emitted: u64 = counts.iter().map(|c| c.emitted).sum();
        let stored: u64 = counts.iter().map(|c| c.stored).sum();
        let per_light: Vec<String> = counts
            .iter()
            .map(|c| format!("{}/{}", c.stored, c.emitted))
            .collect();
        println!(
            "  {name} map: {emitted} photons emitted, {stored} stored (per light stored/emitted: {}), {:.1} bytes per photon",
            per_light.join(", "),
            bytes as f64 / stored.max(1) as f64
        );
    }
    let emitted: u64 = s.global.iter().map(|c| c.emitted).sum();
    let met: u64 = s.global.iter().map(|c| c.met_surface).sum();
    if emitted > 0 && s.read_time.is_none() {
        let kept: Vec<String> = s
            .global
            .iter()
            .enumerate()
            .filter(|(_, c)| c.kept_ppm > 0)
            .map(|(l, c)| format!("light {} {:.1}%", l + 1, c.kept_ppm as f64 / 1e4))
            .collect();
        let maps = if kept.is_empty() {
            "no projection map: every light can reach the scene in any direction, or is not a point light"
                .to_string()
        } else {
            format!("projection maps kept {} of the directions", kept.join(", "))
        };
        println!(
            "  global photons: {:.1}% of {emitted} met a surface ({maps})",
            100.0 * met as f64 / emitted as f64
        );
    }
    let emitted: u64 = s.caustic.iter().map(|c| c.emitted).sum();
    if emitted > 0 {
        let on: u64 = s.caustic.iter().map(|c| c.first_hit_specular).sum();
        println!(
            "  caustic photons aimed at the specular objects: {:.1}% of {emitted} bounced specularly off the first surface they met",
            100.0 * on as f64 / emitted as f64
        );
    }
    let (lookups, used) = (rstats.lookups, rstats.photons_used);
    if let Some(read) = s.read_time {
        println!(
            "  photon maps: read from --photon-maps in {:.3} s (not traced), with {} irradiance-cache records",
            read.as_secs_f64(),
            s.read_records
        );
    }
    println!(
        "  photon phases: trace {:.3} s, kd-tree build {:.3} s, precomputation points {:.3} s ({} points, {} of them estimated: all up front when there are no more than the image's pixels, else where gather rays read them)",
        s.trace_time.as_secs_f64(),
        s.build_time.as_secs_f64(),
        s.precompute_time.as_secs_f64(),
        s.precomputed_points,
        s.precomputed_evaluated,
    );
    println!(
        "  photon lookups while rendering: {lookups}, {:.1} photons per lookup; {} caustic estimates taken from another sample of the pixel",
        used as f64 / lookups.max(1) as f64,
        rstats.reused,
    );
    if let Some(c) = &s.cache {
        let levels: Vec<String> = c.per_level.iter().map(|n| n.to_string()).collect();
        println!(
            "  irradiance cache: {} records ({} by level, coarse to fine) from {} probe rays and {} gather rays in {:.3} s; {} diffuse points interpolated it, {} were gathered afresh",
            c.records,
            levels.join(" + "),
            c.probes,
            c.rays.secondary,
            c.time.as_secs_f64(),
            rstats.cached,
            rstats.gathered
        );
    }
}

/// Returns the summary `caustic info` prints for a script's description.
pub fn describe(name: &str, desc: &SceneDesc) -> Result<String> {
    use std::collections::BTreeMap;
    use std::fmt::Write;
    let mut s = String::new();
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    for n in &desc.nodes {
        *kinds.entry(n.kind.label()).or_default() += 1;
    }
    let list = |m: &BTreeMap<&str, usize>| {
        m.iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let meshes = crate::scene::meshes::load_meshes(desc)?;
    let triangles: usize = meshes.iter().map(|m| m.triangles.len()).sum();
    let _ = writeln!(s, "scene {name}");
    let _ = writeln!(s, "  nodes: {} ({})", desc.nodes.len(), list(&kinds));
    let _ = writeln!(
        s,
        "  meshes: {} files, {triangles} triangles",
        desc.meshes.len()
    );
    for m in &meshes {
        let _ = writeln!(
            s,
            "    {}: {} triangles",
            m.source.display(),
            m.triangles.len()
        );
    }
    let _ = writeln!(s, "  materials: {}", desc.materials.len());
    let _ = writeln!(s, "  lights: {}", desc.lights.len());
    let _ = writeln!(s, "  renders: {}", desc.renders.len());
    for (i, r) in desc.renders.iter().enumerate() {
        let c = &r.camera;
        let placed = count_placements(desc, r.root)?;
        let _ = writeln!(
            s,
            "  render {} at {}: {} {}x{}",
            i + 1,
            r.loc,
            r.output.display(),
            r.width,
            r.height
        );
        let _ = writeln!(
            s,
            "    camera: eye ({}, {}, {}) view ({}, {}, {}) up ({}, {}, {}) fov {}°",
            c.eye.x,
            c.eye.y,
            c.eye.z,
            c.view.x,
            c.view.y,
            c.view.z,
            c.up.x,
            c.up.y,
            c.up.z,
            c.fov_deg
        );
        let _ = writeln!(
            s,
            "    root '{}', ambient ({}, {}, {}), {} lights",
            desc.node(r.root).name,
            r.ambient.x,
            r.ambient.y,
            r.ambient.z,
            r.lights.len()
        );
        let _ = writeln!(
            s,
            "    placed: {} ({} triangles)",
            list(&placed.by_kind),
            placed.triangles
        );
    }
    Ok(s)
}

/// Returns what `caustic info` says of the medium the camera is in: air, or the solids that hold
/// it (outermost first), the index and absorption of the one whose medium it is, and the solids
/// whose probes could not agree.
pub fn camera_medium(desc: &SceneDesc, scene: &crate::scene::Scene) -> String {
    let media = &scene.eye_media;
    let name = |i: &u32| format!("'{}'", desc.node(scene.instances[*i as usize].node).name);
    let mut out = if media.inside.is_empty() {
        "air".to_owned()
    } else {
        let held: Vec<String> = media.inside.iter().map(name).collect();
        let mut line = format!("inside {}; index {}", held.join(" in "), media.stack.ior());
        if let Some(m) = media.stack.winner() {
            let a = scene.materials[m as usize].absorption;
            if a != glam::Vec3A::ZERO {
                line += &format!(", absorbing ({}, {}, {}) per unit", a.x, a.y, a.z);
            }
        }
        line
    };
    if !media.doubtful.is_empty() {
        let unsure: Vec<String> = media.doubtful.iter().map(name).collect();
        out += &format!(
            " (the eye is on the surface of {}, or it is not closed: whether it is inside is a guess)",
            unsure.join(", ")
        );
    }
    out
}
