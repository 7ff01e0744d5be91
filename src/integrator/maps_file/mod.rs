//! The photon-map prepass as a file, saved and loaded: `caustic photons SCENE.lua --save
//! maps.bin` writes the maps a render of the scene would trace, with the frame's irradiance
//! cache ([`save`]), and `caustic render SCENE.lua --photon-maps maps.bin` reads them instead of
//! making them ([`load`]), so the tiles of a render farm
//! share one photon pass and one cache pass (the cache is made over the whole image, so that
//! every tile equals the same window of the full render, and each tile used to make it anew).
//!
//! # Why the map itself, not its photons
//! The file holds a map's three arrays exactly as the map holds them (kd-tree order, quantised
//! codes) and its power format, so reading is a copy, not a rebuild, and a render from the
//! file is bit for bit the render that traced the maps itself.
//!
//! # When a file is refused
//! A file carries a [`Fingerprint`]: a 64-bit FNV-1a hash of the scene as the photons see it
//! (the script's nodes, materials, lights and meshes with their script lines, the render's
//! root, camera and lights, and the bytes of every mesh, texture and normal-map file they
//! name) and, as text, the settings that shape the maps and the cache (seed, each light's
//! photon count for each map, whether there is a caustic map, the image's size, the estimates'
//! `k`, radius and filter, the indirect mode, precomputation, the cache's settings, this
//! program's version). A render whose own
//! fingerprint differs refuses the file and says which part differs; so does a file that is
//! truncated, fails its CRC-32, or has another format version. Editing a script, even a
//! comment that moves a line, refuses the maps: the scene hash cannot tell which edits leave
//! the photons alone.
//!
//! A checksum only says the file is as written, not that an honest program wrote it: every
//! field is also checked against what the renderer can use, and an error names the map or
//! the cache, the field and the photon or record. When the file is read: the kd-tree's
//! invariants, the power codes (a base in `[-179, 33]`, normalised codes, the brightest
//! photon at the top exponent: see `store::PowerCodec::validate`), per-light counts a trace
//! can give, and cache records whose numbers are in range ([`MAX_RECORD_VALUE`], unit
//! normals, non-negative irradiance). When a frame takes the maps ([`SavedMaps::check`]):
//! its light count, caustic map and cache, photons and records inside the scene, the cache's
//! accuracy and radius range.
//!
//! The bytes are [`mod@format`]'s; one map's are [`crate::photon::file`]'s. The frame
//! ([`crate::frame::render_desc`]) calls [`load`] and passes the [`Prepass`] to the photon-map
//! integrator, which runs the phases a file does not hold (the precomputation points);
//! nothing else reads or writes these files.
//!
//! # Layout (little-endian)
//! | bytes | contents |
//! |---|---|
//! | 8 | magic `CAUSTPM\0` |
//! | 4 | format version ([`VERSION`]) |
//! | 8 | scene hash |
//! | 4 + n | settings text, UTF-8, length first (at most [`MAX_TEXT`]) |
//! | 1 | maps: 1 (global) or 2 (global and caustic) |
//! | per map | light count (4), then per light emitted, stored, first-hit-specular (8 each); photon count (8, at most `u32::MAX`); top nodes (8); power base exponent (4); positions (12 per photon); codes (4 per photon); powers (4 per photon) |
//! | 1 | irradiance cache: 0 (none) or 1, then its accuracy (f32), record count (8) and per record position, normal, irradiance, the three rotational and three translational gradients and the radius (28 f32) |
//! | 4 | CRC-32 (IEEE) of everything before it |
pub(crate) mod format;
pub mod parts;

pub use format::{Fnv, MAX_RECORD_VALUE, MAX_TEXT, VERSION, read, write};

use super::irradiance_cache::{IrradianceCache, MIN_IMAGE_SIZE, radius_range};
use super::photon_map::{GiSettings, GiStats, Indirect, Prepass, planned};
use super::{Integrator, Plan};
use crate::camera::Camera;
use crate::desc::{MeshSource, RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::photon::PhotonMap;
use crate::photon::file::CountedMap;
use crate::photon::trace::MapKind;
use crate::progress::Progress;
use crate::scene::Scene;
use glam::Vec3A;
use std::path::Path;

/// What a pair of maps was traced for (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fingerprint {
    /// FNV-1a hash of the scene as the photons see it.
    pub scene: u64,
    /// The settings that shape the maps, as text.
    pub settings: String,
}

/// The maps of one render, as saved.
#[derive(Debug)]
pub struct SavedMaps {
    pub fingerprint: Fingerprint,
    pub global: CountedMap,
    pub caustic: Option<CountedMap>,
    /// The frame's irradiance cache, when it has one: made over the whole image, it is the
    /// same for every tile, so tiles read it rather than each making it again.
    pub cache: Option<IrradianceCache>,
}

/// What the frame reading a file expects of its maps beyond the fingerprint, which an honest
/// file matches whenever its fingerprint does; [`SavedMaps::check`] compares.
#[derive(Clone, Debug)]
pub struct Expected {
    /// The box holding the scene (`min`, `max`), when it is finite: every photon and cache
    /// record lies on a surface, so inside it (with a margin of 1% of its diagonal).
    pub bounds: Option<(Vec3A, Vec3A)>,
    /// The scene's lights: each map counts photons for each.
    pub lights: usize,
    /// Whether the frame has a caustic map.
    pub caustic: bool,
    /// When the frame makes an irradiance cache: its accuracy and the range its records'
    /// radii are clamped to (see [`super::irradiance_cache`]).
    pub cache: Option<(f32, (f32, f32))>,
}

/// The frame a file is saved for or loaded into: the scene as the plan shades it, its
/// description and `gr.render` call (which the fingerprint hashes), the plan and the image size.
#[derive(Clone, Copy)]
pub struct FrameOf<'a> {
    pub desc: &'a SceneDesc,
    pub render: &'a RenderDesc,
    pub scene: &'a Scene,
    pub plan: &'a Plan,
    /// The full image's width and height (a tile's frame is the whole image's).
    pub size: (u32, u32),
}

/// Runs the photon-map prepass of `frame` with `photons` ([`super::photon_map::prepass`]) and
/// returns it as a file holds it, with its fingerprint and the phases' counters
/// (`caustic photons --save`; [`write()`] writes it). Errors name `--save` when the frame is not
/// photon-mapped.
pub fn save(
    frame: FrameOf,
    photons: &GiSettings,
    progress: &dyn Progress,
) -> Result<(SavedMaps, GiStats)> {
    let gi = settings_of(frame.plan, photons, "--save")?;
    let fingerprint = fingerprint(frame, &gi)?;
    let camera = Camera::new(&frame.render.camera, frame.size.0, frame.size.1);
    let prepass = super::photon_map::prepass(frame.scene, &camera, &gi, None, progress);
    Ok(saved(fingerprint, &gi, prepass))
}

/// Returns `prepass`, made with `gi`, as a file holds it (with `fingerprint`), and its counters.
fn saved(fingerprint: Fingerprint, gi: &GiSettings, prepass: Prepass) -> (SavedMaps, GiStats) {
    let stats = prepass.stats.clone();
    let maps = SavedMaps {
        fingerprint,
        global: CountedMap {
            map: prepass.global,
            per_light: stats.global.clone(),
        },
        caustic: gi.caustics.then(|| CountedMap {
            map: prepass
                .caustic
                .unwrap_or_else(|| PhotonMap::build(Vec::new())),
            per_light: stats.caustic.clone(),
        }),
        cache: prepass.cache,
    };
    (maps, stats)
}

/// Reads the photon maps at `path` for `frame` with `photons` and returns them as the frame's
/// prepass (the precomputation points still to estimate), or an error naming the file and,
/// when it holds other maps than this frame traces, what differs. Errors name `--photon-maps`
/// when the frame is not photon-mapped.
pub fn load(frame: FrameOf, photons: &GiSettings, path: &Path) -> Result<Prepass> {
    let gi = settings_of(frame.plan, photons, "--photon-maps")?;
    let want = fingerprint(frame, &gi)?;
    let bad = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let start = std::time::Instant::now();
    let saved = read(path).map_err(bad)?;
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
    saved.check(&expected(frame, &gi)).map_err(bad)?;
    let maps = (saved.global, saved.caustic, saved.cache);
    Ok(Prepass::of_read_maps(
        frame.scene,
        &gi,
        maps,
        start.elapsed(),
    ))
}

/// Returns the photon settings of a frame planned as `plan` with `photons` (the plan's
/// choices, [`planned`]), or a usage error naming `flag` when the frame is not photon-mapped.
fn settings_of(plan: &Plan, photons: &GiSettings, flag: &str) -> Result<GiSettings> {
    if plan.integrator != Integrator::PhotonMap {
        let what = match plan.integrator {
            Integrator::Progressive => "progressively, with fresh photon maps every pass",
            _ => "without photon maps (photon mapping is off for it: see caustic info)",
        };
        return Err(Error::Usage(format!(
            "{flag}: this frame is rendered {what}, so it has no photon maps to share"
        )));
    }
    Ok(planned(photons, plan))
}

/// Returns the hash of the scene of the `gr.render` call `r` as the photons see it: the
/// script's nodes, materials, lights and meshes with their script lines, the render's root,
/// camera and lights, and the bytes of every mesh, texture and normal-map file they name (see
/// the module doc). Progressive pass files carry it too ([`super::passes_file`]).
pub fn scene_hash(desc: &SceneDesc, r: &RenderDesc) -> Result<u64> {
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
    Ok(h.finish())
}

/// Returns the fingerprint of the maps that `gi` traces for `frame`, and of the irradiance
/// cache it makes (see the module doc).
fn fingerprint(frame: FrameOf, gi: &GiSettings) -> Result<Fingerprint> {
    let scene = scene_hash(frame.desc, frame.render)?;
    let budget = |kind| format!("{:?}", gi.budget(&frame.scene.lights, kind));
    let caustic = if gi.caustics {
        budget(MapKind::Caustic)
    } else {
        "none".to_string()
    };
    let (width, height) = frame.size;
    Ok(Fingerprint {
        scene,
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

/// Returns what `frame` with `gi` expects of photon maps read from a file beyond their
/// fingerprint ([`Expected`]).
fn expected(frame: FrameOf, gi: &GiSettings) -> Expected {
    let scene = frame.scene;
    let b = scene
        .instances
        .iter()
        .fold(crate::accel::Bounds::EMPTY, |a, i| a.union(i.bounds));
    let gathers = matches!(gi.indirect, Indirect::Gather { .. });
    let caches = gi.cache.enabled && gathers && frame.size.0.max(frame.size.1) >= MIN_IMAGE_SIZE;
    Expected {
        bounds: b.is_finite().then_some((b.min, b.max)),
        lights: scene.lights.len(),
        caustic: gi.caustics,
        cache: caches.then(|| (gi.cache.accuracy, radius_range(scene, frame.size))),
    }
}
