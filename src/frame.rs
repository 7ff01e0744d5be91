//! A frame as one library call: the effect plan, then the integrator's passes (photon passes,
//! camera pass), into a [`Film`] and [`Stats`]. The command line, every test helper and every
//! tool render through here; nothing else wires passes together.
//!
//! ```
//! use caustic::{frame, integrator::Settings, progress::NoProgress, render::Sampling};
//! let src = b"s = gr.sphere('s') s:set_material(gr.material({1,1,1}, {0,0,0}, 0))
//!     gr.render(s, 'x.png', 9, 9, {0,0,5}, {0,0,-1}, {0,1,0}, 50, {0,0,0},
//!               {gr.light({0,0,5}, {1,1,1}, {1,0,0})})";
//! let no_render = Box::new(|_: &_, _: &_| Ok(()));
//! let desc = caustic::lua::run_source(src, "doc.lua", ".".as_ref(), no_render).unwrap();
//! // One ray through each pixel's centre (the default, 4 stratified rays, averages the pixel).
//! let settings = Settings { sampling: Sampling::Stratified { spp: 1 }, ..Settings::default() };
//! let f = frame::render_desc(&desc, &desc.renders[0], 1.0, None, &settings, &NoProgress).unwrap();
//! // The sphere faces the light head-on at the centre: kd · I · cos 0 / att(4) = 1.
//! assert!((f.film.get(4, 4).x - 1.0).abs() < 0.01);
//! ```

use crate::camera::Camera;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::film::{Film, Window};
use crate::integrator::maps_file::parts::SavedPart;
use crate::integrator::maps_file::{self, FrameOf, SavedMaps};
use crate::integrator::photon_map::{GiSettings, GiStats, Prepass};
use crate::integrator::plan::plan_for;
use crate::integrator::{GiMode, Integrator, Plan, Settings, View};
use crate::lua::MAX_PIXELS;
use crate::photon::trace::{MAX_PHOTONS, MapKind, Part};
use crate::progress::Progress;
use crate::scene::{Scene, build_scene};

pub use crate::integrator::Stats;

/// A rendered frame with the scene it was rendered from.
pub struct Frame {
    pub scene: Scene,
    pub film: Film,
    pub stats: Stats,
}

/// Returns the effect plan of a frame of `scene` with `settings`
/// ([`mod@crate::integrator::plan`]) and applies its shading features to the scene
/// ([`Scene::apply`]: an effect disabled there stays disabled). A frame is planned once;
/// [`render`] takes the plan.
pub fn plan(scene: &mut Scene, settings: &Settings) -> Plan {
    let plan = plan_for(scene, settings);
    scene.apply(plan.features);
    plan
}

/// Renders `window` of the image of `scene` through `camera` as `plan` says (made by [`plan`]
/// for this scene and these settings): runs the chosen integrator's phases, reporting each to
/// `progress`.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    window: Window,
    settings: &Settings,
    plan: Plan,
    progress: &dyn Progress,
) -> (Film, Stats) {
    let view = View {
        scene,
        camera,
        window,
    };
    plan.integrator.render(view, settings, plan, None, progress)
}

/// Builds the scene of the `gr.render` call `r` and renders it at `scale` times its size, or the
/// window `crop` (`[x0, y0, x1, y1]`, end exclusive) of it. With `settings.maps_file`, the
/// photon-map prepass is read from that file ([`maps_file::load`]) instead of made, once the
/// file is found to hold the maps this frame would trace.
pub fn render_desc(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    crop: Option<[u32; 4]>,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Frame> {
    let f = prepare(desc, r, scale, crop, settings)?;
    let read = match &f.settings.maps_file {
        Some(path) => Some(maps_file::load(f.of(desc, r), &f.settings.photons, path)?),
        None => None,
    };
    let size = f.of(desc, r).size;
    let camera = Camera::new(&r.camera, size.0, size.1);
    let Prepared {
        window,
        scene,
        settings,
        plan,
        factor,
    } = f;
    let view = View {
        scene: &scene,
        camera: &camera,
        window,
    };
    let (film, mut stats) = plan
        .integrator
        .render(view, &settings, plan, read, progress);
    // The time planner decides on adaptive rounds once the prepass is made, after the plan.
    let planned = stats.photons.as_ref().and_then(|p| p.planned.as_ref());
    if planned.is_some_and(|p| p.adaptive.is_some()) {
        stats
            .plan
            .adaptive(crate::integrator::plan::Why::PlannedRounds);
    }
    // Why the photon counts differ from the script's and the settings' (see
    // `GiSettings::follow_image`), among the plan's notes.
    if let Some(factor) = factor
        && stats.photons.is_some()
    {
        stats.plan.notes.push(format!(
            "photons: x{factor:.4} with the image ({}x{} of the script's {}x{}); --photons, \
             --caustic-photons or --photon-scale fixes the count",
            window.full_width, window.full_height, r.width, r.height
        ));
    }
    Ok(Frame { scene, film, stats })
}

/// Runs the photon-map prepass a render of `r` at `scale` with `settings` would run and returns
/// it as a file holds it, to be saved (`caustic photons --save`, [`maps_file::save`]). Errors
/// name the flag `--save` when the frame is not photon-mapped.
pub fn trace_maps(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(SavedMaps, GiStats)> {
    let f = prepare(desc, r, scale, None, settings)?;
    maps_file::save(f.of(desc, r), &f.settings.photons, progress)
}

/// Traces part `part` of the photon pass a render of `r` at `scale` with `settings` would run
/// (`caustic photons --part`, [`maps_file::parts::trace`]).
pub fn trace_part(
    (desc, r): (&SceneDesc, &RenderDesc),
    scale: f64,
    settings: &Settings,
    part: Part,
    progress: &dyn Progress,
) -> Result<SavedPart> {
    let f = prepare(desc, r, scale, None, settings)?;
    maps_file::parts::trace(f.of(desc, r), &f.settings.photons, part, progress)
}

/// Merges the parts of the photon pass a render of `r` at `scale` with `settings` would run
/// into the maps that pass makes, with the rest of its prepass, to be saved (`caustic photons
/// --merge`, [`maps_file::parts::merge`]).
pub fn merge_parts(
    (desc, r): (&SceneDesc, &RenderDesc),
    scale: f64,
    settings: &Settings,
    parts: Vec<(std::path::PathBuf, SavedPart)>,
    progress: &dyn Progress,
) -> Result<(SavedMaps, GiStats)> {
    let f = prepare(desc, r, scale, None, settings)?;
    maps_file::parts::merge(f.of(desc, r), &f.settings.photons, parts, progress)
}

/// A frame ready for its passes: its window, its scene as the plan shades it, its settings
/// (photon counts scaled with the image when they follow it), its one plan, and the factor
/// the counts were scaled by.
struct Prepared {
    window: Window,
    scene: Scene,
    settings: Settings,
    plan: Plan,
    factor: Option<f64>,
}

impl Prepared {
    /// Returns this frame of `r` of `desc` as the photon-map file sees it.
    fn of<'a>(&'a self, desc: &'a SceneDesc, r: &'a RenderDesc) -> FrameOf<'a> {
        FrameOf {
            desc,
            render: r,
            scene: &self.scene,
            plan: &self.plan,
            size: (self.window.full_width, self.window.full_height),
        }
    }
}

/// Returns the frame of `r` at `scale` (or its window `crop`) with `settings`: its scene built,
/// its photon counts scaled with the image when they follow it and checked and charged to the
/// scene's budget, and its plan made and applied ([`plan`]).
fn prepare(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    crop: Option<[u32; 4]>,
    settings: &Settings,
) -> Result<Prepared> {
    let window = window(r, scale, crop)?;
    let mut scene = build_scene(desc, r)?;
    let pixels = |w: u32, h: u32| w as f64 * h as f64;
    let factor = pixels(window.full_width, window.full_height) / pixels(r.width, r.height);
    let mut settings = settings.clone();
    let follow = settings.photons.follow_image && factor != 1.0;
    if follow {
        settings.photons.photon_scale *= factor;
    }
    check_photon_budget(desc, r, &scene, &settings)?;
    // Every pass of the frame, and the photon-map file's, sees the scene as the plan shades it.
    let plan = plan(&mut scene, &settings);
    if plan.integrator != Integrator::Whitted {
        charge_photons(desc, r, &scene, &settings.photons, plan.caustics)?;
    }
    Ok(Prepared {
        window,
        scene,
        settings,
        plan,
        factor: follow.then_some(factor),
    })
}

/// Returns an error at the light's script line when its photon count (its `num_photons` or its
/// share of `--photons` or `--caustic-photons`, times `--photon-scale`) exceeds [`MAX_PHOTONS`].
fn check_photon_budget(
    desc: &SceneDesc,
    r: &RenderDesc,
    scene: &Scene,
    settings: &Settings,
) -> Result<()> {
    let kinds = [MapKind::Global, MapKind::Caustic];
    for budget in kinds.map(|kind| settings.photons.budget(&scene.lights, kind)) {
        for (l, &n) in budget.iter().enumerate() {
            if n <= MAX_PHOTONS {
                continue;
            }
            let loc = r.light_loc(desc, l);
            return Err(Error::at(
                loc,
                format!(
                    "this light would emit {n:.3e} photons for a map (with --photon-scale {}), more than {MAX_PHOTONS}",
                    settings.photons.photon_scale
                ),
            ));
        }
    }
    Ok(())
}

/// Bytes a stored photon takes: its 28-byte record in the traced stream, then 20 bytes in the
/// map built from it.
const PHOTON_BYTES: u64 = 48;

/// Charges the global map, and the caustic map when `caustics`, that `photons` traces for the
/// frame of `r` to the scene's account, at one stored photon per photon emitted (a diffuse
/// bounce stores one more; a photon that leaves the scene none), each light's share at its
/// script line. One pass's maps: a progressive render frees its maps before the next pass's.
pub fn charge_photons(
    desc: &SceneDesc,
    r: &RenderDesc,
    scene: &Scene,
    photons: &GiSettings,
    caustics: bool,
) -> Result<()> {
    let mut kinds = vec![MapKind::Global];
    if caustics {
        kinds.push(MapKind::Caustic);
    }
    for kind in kinds {
        for (l, &n) in photons.budget(&scene.lights, kind).iter().enumerate() {
            let what = format!("this light's {n} photons for the {kind:?} map").to_lowercase();
            let at = crate::budget::At::Script(r.light_loc(desc, l));
            scene
                .account
                .charge(n.saturating_mul(PHOTON_BYTES), what, at)?;
        }
    }
    Ok(())
}

/// Returns the size of `r`'s image at `scale` times the script's.
pub fn scaled_size(r: &RenderDesc, scale: f64) -> (u32, u32) {
    let s = |v: u32| ((v as f64 * scale).round() as u32).max(1);
    (s(r.width), s(r.height))
}

/// Returns the window of `r`'s image at `scale` that `crop` names (the whole image without one),
/// or an error at `r`'s line when it is not inside the image.
pub fn window(r: &RenderDesc, scale: f64, crop: Option<[u32; 4]>) -> Result<Window> {
    let (w, h) = scaled_size(r, scale);
    if w as u64 * h as u64 > MAX_PIXELS {
        return Err(Error::at(
            &r.loc,
            format!(
                "--scale {scale} makes the {}x{} image {w}x{h}, more than {MAX_PIXELS} pixels",
                r.width, r.height
            ),
        ));
    }
    let Some([x0, y0, x1, y1]) = crop else {
        return Ok(Window::full(w, h));
    };
    let win = Window {
        x0,
        y0,
        x1,
        y1,
        full_width: w,
        full_height: h,
    };
    if !win.is_valid() {
        return Err(Error::at(
            &r.loc,
            format!("--crop {x0},{y0},{x1},{y1} is not inside the {w}x{h} image"),
        ));
    }
    Ok(win)
}

/// Traces the photon maps of `scene` (global illumination on, no irradiance precomputation) and
/// draws the stored photons from `camera` into a `width × height` film (`caustic photons`).
pub fn photon_view(
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    photons: &GiSettings,
    progress: &dyn Progress,
) -> (Film, GiStats) {
    let plan = crate::integrator::plan(scene, GiMode::On);
    let settings = GiSettings {
        caustics: plan.caustics,
        precompute: false,
        ..photons.clone()
    };
    let gi = Prepass::build_with(scene, &settings, progress);
    let film = crate::photon::view::photon_image(
        scene,
        camera,
        &gi.global,
        gi.caustic.as_ref(),
        width,
        height,
    );
    (film, gi.stats)
}
