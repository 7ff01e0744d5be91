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
use crate::desc::MeshSource;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::film::{Film, Window};
use crate::integrator::photon_map::{Gi, GiSettings, GiStats, Preloaded, planned};
use crate::integrator::plan::plan_for;
use crate::integrator::{GiMode, Integrator, Settings, plan};
use crate::lua::MAX_PIXELS;
use crate::photon::file::{CountedMap, Expected, Fingerprint, Fnv, SavedMaps};
use crate::photon::trace::{MAX_PHOTONS, MapKind};
use crate::progress::Progress;
use crate::scene::{Scene, build_scene};

pub use crate::integrator::Stats;

/// A rendered frame with the scene it was rendered from.
pub struct Frame {
    pub scene: Scene,
    pub film: Film,
    pub stats: Stats,
}

/// Renders `window` of the image of `scene` through `camera`: plans the frame, applies the
/// plan's shading features to the scene ([`Scene::apply`]: an effect disabled there stays
/// disabled), then runs the chosen integrator's phases, reporting each to `progress`.
pub fn render(
    scene: &mut Scene,
    camera: &Camera,
    window: Window,
    settings: &Settings,
    progress: &dyn Progress,
) -> (Film, Stats) {
    let plan = plan_for(scene, settings);
    scene.apply(plan.features);
    let scene = &*scene;
    plan.integrator
        .render(scene, camera, window, settings, plan, progress)
}

/// Builds the scene of the `gr.render` call `r` and renders it at `scale` times its size, or the
/// window `crop` (`[x0, y0, x1, y1]`, end exclusive) of it. With `settings.photons.maps_file`,
/// the photon maps are read from that file ([`crate::photon::file`]) instead of traced, once
/// the file is found to hold the maps this frame would trace.
pub fn render_desc(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    crop: Option<[u32; 4]>,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Frame> {
    let (window, mut scene, mut settings, factor) = prepare(desc, r, scale, crop, settings)?;
    if let Some(path) = settings.photons.maps_file.clone() {
        let size = (window.full_width, window.full_height);
        let maps = read_maps(desc, r, &scene, &settings, &path, size)?;
        settings.photons.preloaded = Some(maps);
    }
    let camera = Camera::new(&r.camera, window.full_width, window.full_height);
    let (film, mut stats) = render(&mut scene, &camera, window, &settings, progress);
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

/// Returns the window, the scene and the settings of a frame of `r` (photon counts scaled with
/// the image when they follow it, and checked), and the factor they were scaled by.
fn prepare(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    crop: Option<[u32; 4]>,
    settings: &Settings,
) -> Result<(Window, Scene, Settings, Option<f64>)> {
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
    let plan = plan_for(&scene, &settings);
    if plan.integrator != Integrator::Whitted {
        charge_photons(desc, r, &scene, &settings.photons, plan.caustics)?;
    }
    scene.apply(plan.features);
    Ok((window, scene, settings, follow.then_some(factor)))
}

/// Returns the photon-mapping settings a frame of `scene` with `settings` traces its maps with,
/// or a usage error naming `flag` when the frame is not photon-mapped.
fn map_settings(scene: &Scene, settings: &Settings, flag: &str) -> Result<GiSettings> {
    let plan = plan_for(scene, settings);
    if plan.integrator != Integrator::PhotonMap {
        let what = match plan.integrator {
            Integrator::Progressive => "progressively, with fresh photon maps every pass",
            _ => "without photon maps (photon mapping is off for it: see caustic info)",
        };
        return Err(Error::Usage(format!(
            "{flag}: this frame is rendered {what}, so it has no photon maps to share"
        )));
    }
    Ok(GiSettings {
        maps_file: None,
        preloaded: None,
        ..planned(&settings.photons, &plan)
    })
}

/// Returns the fingerprint of the maps that `gi` traces, and of the irradiance cache it makes,
/// for the `w × h` frame of `r` ([`file`]).
fn fingerprint(
    desc: &SceneDesc,
    r: &RenderDesc,
    scene: &Scene,
    gi: &GiSettings,
    (width, height): (u32, u32),
) -> Result<Fingerprint> {
    let mut h = Fnv::default();
    let text = format!(
        "{:?}",
        (
            &desc.nodes,
            &desc.materials,
            &desc.lights,
            &desc.meshes,
            r.root,
            r.camera,
            &r.lights
        )
    );
    h.write(text.as_bytes());
    let meshes = desc.meshes.iter().filter_map(|m| match &m.source {
        MeshSource::File { path, .. } => Some(path),
        MeshSource::Inline { .. } => None,
    });
    let images = desc
        .materials
        .iter()
        .flat_map(|m| m.texture.iter().chain(&m.bump));
    for path in meshes.chain(images) {
        h.write_file(path).map_err(|e| Error::File {
            path: path.clone(),
            message: e.to_string(),
        })?;
    }
    let budget = |kind| format!("{:?}", gi.budget(&scene.lights, kind));
    let caustic = if gi.caustics {
        budget(MapKind::Caustic)
    } else {
        "none".to_string()
    };
    Ok(Fingerprint {
        scene: h.finish(),
        settings: format!(
            "caustic {}; seed {}; global photons per light {}; caustic photons per light \
             {caustic}; image {width}x{height}; k {}; max radius {}; {:?}; {:?}; precomputed points {}; \
             {:?}",
            env!("CARGO_PKG_VERSION"),
            gi.seed,
            budget(MapKind::Global),
            gi.k,
            gi.max_radius,
            gi.filter,
            gi.indirect,
            gi.precompute,
            gi.cache,
        ),
    })
}

/// Traces the photon maps a render of `r` at `scale` with `settings` would trace and returns
/// them with their fingerprint, to be saved (`caustic photons --save`). Errors name the flag
/// `--save` when the frame is not photon-mapped.
pub fn trace_maps(
    desc: &SceneDesc,
    r: &RenderDesc,
    scale: f64,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<(SavedMaps, GiStats)> {
    let (window, scene, settings, _) = prepare(desc, r, scale, None, settings)?;
    let gi_settings = map_settings(&scene, &settings, "--save")?;
    let size = (window.full_width, window.full_height);
    let fingerprint = fingerprint(desc, r, &scene, &gi_settings, size)?;
    let camera = Camera::new(&r.camera, size.0, size.1);
    let gi = Gi::build_with(&scene, &gi_settings, progress)
        .precompute_for(&camera)
        .with_cache(&scene, &camera, progress);
    let stats = gi.stats.clone();
    let maps = SavedMaps {
        fingerprint,
        global: CountedMap {
            map: gi.global,
            per_light: stats.global.clone(),
        },
        caustic: gi_settings.caustics.then(|| CountedMap {
            map: gi
                .caustic
                .unwrap_or_else(|| crate::photon::PhotonMap::build(Vec::new())),
            per_light: stats.caustic.clone(),
        }),
        cache: gi.cache,
    };
    Ok((maps, stats))
}

/// Reads the photon maps at `path` for the frame of `r`, or returns an error naming the file
/// and, when it holds other maps than this frame traces, what differs.
fn read_maps(
    desc: &SceneDesc,
    r: &RenderDesc,
    scene: &Scene,
    settings: &Settings,
    path: &std::path::Path,
    size: (u32, u32),
) -> Result<Preloaded> {
    let gi_settings = map_settings(scene, settings, "--photon-maps")?;
    let want = fingerprint(desc, r, scene, &gi_settings, size)?;
    let bad = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let start = std::time::Instant::now();
    let saved = crate::photon::file::read(path).map_err(bad)?;
    if saved.fingerprint.scene != want.scene {
        return Err(bad(format!(
            "these photon maps were traced for another scene (scene hash {:016x}, this one's is \
             {:016x}: the script, a mesh or a texture differs); save them again with caustic \
             photons --save",
            saved.fingerprint.scene, want.scene
        )));
    }
    if saved.fingerprint.settings != want.settings {
        return Err(bad(format!(
            "these photon maps were traced with other settings\n  saved: {}\n  this render: {}\n\
             give caustic photons --save the flags this render has",
            saved.fingerprint.settings, want.settings
        )));
    }
    saved
        .check(&expected(scene, &gi_settings, size))
        .map_err(bad)?;
    Ok(Preloaded::new(saved, start.elapsed()))
}

/// Returns what a frame of `scene` at `size` with `gi` expects of photon maps read from a file
/// beyond their fingerprint ([`crate::photon::file::Expected`]).
fn expected(scene: &Scene, gi: &GiSettings, size: (u32, u32)) -> Expected {
    use crate::integrator::irradiance_cache::{MIN_IMAGE_SIZE, radius_range};
    let b = scene
        .instances
        .iter()
        .fold(crate::accel::Bounds::EMPTY, |a, i| a.union(i.bounds));
    let gathers = matches!(
        gi.indirect,
        crate::integrator::photon_map::Indirect::Gather { .. }
    );
    let caches = gi.cache.enabled && gathers && size.0.max(size.1) >= MIN_IMAGE_SIZE;
    Expected {
        bounds: b.is_finite().then_some((b.min, b.max)),
        lights: scene.lights.len(),
        caustic: gi.caustics,
        cache: caches.then(|| (gi.cache.accuracy, radius_range(scene, size))),
    }
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
            let loc = &desc.lights[r.lights[l].0 as usize].loc;
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
            let at = crate::budget::At::Script(&desc.lights[r.lights[l].0 as usize].loc);
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
    let plan = plan(scene, GiMode::On);
    let settings = GiSettings {
        caustics: plan.caustics,
        precompute: false,
        ..photons.clone()
    };
    let gi = Gi::build_with(scene, &settings, progress);
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
