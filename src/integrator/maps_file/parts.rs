//! A photon pass split over processes: `caustic photons SCENE --part i/N --save part_i.bin`
//! (`i` from 0 to `N - 1`, as a Slurm array numbers its tasks) traces a deterministic share of every light's photons ([`Part`]) and saves them as traced,
//! not yet built into maps; `caustic photons SCENE --merge part_*.bin --save maps.bin` puts
//! the parts' photons back in the order one process traces them, builds the maps, runs the rest
//! of the prepass (precomputation points, irradiance cache) and writes the file `caustic
//! photons --save` would have written, byte for byte.
//!
//! # Why photons, not maps, in a part
//! A map is a kd-tree over all its photons: maps built apart cannot be joined into the one a
//! single process builds. The photons can: each photon's random stream is keyed by its light,
//! its map and its index, so a part traces exactly the photons a whole pass traces at those
//! indices, and the merge restores the whole pass's order (light by light, each light's shares
//! in part order). The kd-tree, the precomputation points and the irradiance cache are then
//! made once, by the merge, as one process makes them.
//!
//! # When parts are refused
//! Each part carries the fingerprint a maps file has (the scene and the settings that shape
//! the maps, see [`super`]) and its `i/N`. The merge refuses a part whose fingerprint is not
//! this frame's, parts of different `N`, a part given twice or missing, counts a trace of that
//! share could not give (emitted photons other than the share, more stored than bounces
//! allow), and any photon that is not finite, has an invalid code word or a power out of range
//! ([`crate::photon::file::read_traced`]). A part file is checksummed like a maps file.
//!
//! # Layout (little-endian)
//! magic `CAUSTPP\0` (8), format version (4), scene hash (8), settings text (4 + n), part index
//! and count (4 each), maps 1 or 2 (1), each map's traced photons
//! ([`crate::photon::file::write_traced`]), CRC-32 (4).

use super::format::{Kind, open, read_checksum, read_header, write_checksum, write_header};
use super::{Fingerprint, FrameOf, SavedMaps, fingerprint, saved, settings_of};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::integrator::photon_map::{GiSettings, GiStats, Prepass};
use crate::photon::PhotonMap;
use crate::photon::file::{CountedMap, CrcWriter, read_traced, write_traced};
use crate::photon::stream::{PhotonStream, Staged};
use crate::photon::trace::{
    LightCounts, MAX_BOUNCES, MAX_PARTS, MapKind, Part, TracedMap, trace_map_part,
};
use crate::progress::Progress;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A part file's first eight bytes.
const MAGIC: &[u8; 8] = b"CAUSTPP\0";
/// The part format this program reads and writes.
pub const VERSION: u32 = 1;

/// One process's share of a photon pass, as saved.
#[derive(Debug)]
pub struct SavedPart {
    pub fingerprint: Fingerprint,
    pub part: Part,
    pub global: TracedMap,
    pub caustic: Option<TracedMap>,
}

/// Traces part `part` of the photon pass of `frame` with `photons` (`caustic photons --part`).
/// Errors name `--part` when the frame is not photon-mapped.
pub fn trace(
    frame: FrameOf,
    photons: &GiSettings,
    part: Part,
    progress: &dyn Progress,
) -> Result<SavedPart> {
    let gi = settings_of(frame.plan, photons, "--part")?;
    let fingerprint = fingerprint(frame, &gi)?;
    let lights = &frame.scene.lights;
    let map = |kind| {
        let budget = gi.budget(lights, kind);
        trace_map_part(frame.scene, &budget, (kind, gi.seed), part, progress)
    };
    let global = map(MapKind::Global);
    let caustic = gi.caustics.then(|| map(MapKind::Caustic));
    Ok(SavedPart {
        fingerprint,
        part,
        global,
        caustic,
    })
}

/// Puts the photons of `parts` (each with the file it came from) back in one pass's order for
/// `frame` with `photons`, builds the maps and runs the rest of the prepass; returns them as
/// `caustic photons --save` returns a whole pass's. Errors name the part file at fault, or
/// `--merge` when the frame is not photon-mapped.
pub fn merge(
    frame: FrameOf,
    photons: &GiSettings,
    parts: Vec<(PathBuf, SavedPart)>,
    progress: &dyn Progress,
) -> Result<(SavedMaps, GiStats)> {
    let start = std::time::Instant::now();
    let gi = settings_of(frame.plan, photons, "--merge")?;
    let want = fingerprint(frame, &gi)?;
    let parts = in_order(parts, &want, gi.caustics)?;
    let lights = frame.scene.lights.len();
    let joined = |kind: MapKind| -> Result<CountedMap> {
        let budget = gi.budget(&frame.scene.lights, kind);
        let maps: Vec<(&Path, &TracedMap)> = parts
            .iter()
            .map(|(path, p)| {
                let map = match kind {
                    MapKind::Global => Some(&p.global),
                    MapKind::Caustic => p.caustic.as_ref(),
                };
                (
                    path.as_path(),
                    map.expect("in_order checked the caustic maps"),
                )
            })
            .collect();
        join(&maps, &budget, lights, kind)
    };
    let global = joined(MapKind::Global)?;
    let caustic = match gi.caustics {
        true => Some(joined(MapKind::Caustic)?),
        false => None,
    };
    let read = Prepass::of_read_maps(frame.scene, &gi, (global, caustic, None), start.elapsed());
    let camera = Camera::new(&frame.render.camera, frame.size.0, frame.size.1);
    let prepass =
        super::super::photon_map::prepass(frame.scene, &camera, &gi, Some(read), progress);
    Ok(saved(want, &gi, prepass))
}

/// Returns `parts` in part order, or an error naming the file whose fingerprint is not `want`,
/// whose count differs from the number of parts, whose index is taken, or whose caustic map is
/// there when `caustics` is false or missing when it is true.
fn in_order(
    parts: Vec<(PathBuf, SavedPart)>,
    want: &Fingerprint,
    caustics: bool,
) -> Result<Vec<(PathBuf, SavedPart)>> {
    let n = parts.len();
    let mut slots: Vec<Option<(PathBuf, SavedPart)>> = (0..n).map(|_| None).collect();
    for (path, p) in parts {
        let bad = |message: String| Error::File {
            path: path.clone(),
            message,
        };
        if p.fingerprint.scene != want.scene {
            return Err(bad(format!(
                "this part was traced for another scene (scene hash {:016x}, this one's is \
                 {:016x}): trace it again with caustic photons --part",
                p.fingerprint.scene, want.scene
            )));
        }
        if p.fingerprint.settings != want.settings {
            return Err(bad(format!(
                "this part was traced with other settings\n  part: {}\n  this merge: {}",
                p.fingerprint.settings, want.settings
            )));
        }
        if p.part.count as usize != n {
            return Err(bad(format!(
                "this is part {}/{} but {n} parts were given: give every part, each once",
                p.part.index, p.part.count
            )));
        }
        if p.caustic.is_some() != caustics {
            return Err(bad(
                "its caustic map does not match this frame's plan".into()
            ));
        }
        let slot = &mut slots[p.part.index as usize];
        if let Some((other, _)) = slot {
            return Err(bad(format!(
                "part {}/{n} is given twice (also as {})",
                p.part.index,
                other.display()
            )));
        }
        *slot = Some((path, p));
    }
    // n files, n slots, no slot taken twice: every slot is full.
    Ok(slots.into_iter().flatten().collect())
}

/// Joins the `kind` map of each part (in part order, each with its file) into the map one pass
/// of `budget[l]` photons per light builds, with the lights' counts summed; or an error naming
/// the file whose counts that share's trace could not give.
fn join(
    maps: &[(&Path, &TracedMap)],
    budget: &[u64],
    lights: usize,
    kind: MapKind,
) -> Result<CountedMap> {
    let n = maps.len() as u32;
    let most = match kind {
        MapKind::Global => u64::from(MAX_BOUNCES),
        MapKind::Caustic => 1,
    };
    for (i, (path, t)) in maps.iter().enumerate() {
        let part = Part {
            index: i as u32,
            count: n,
        };
        check_share(t, part, budget, lights, most).map_err(|message| Error::File {
            path: path.to_path_buf(),
            message: format!("the {kind:?} map: {message}").to_lowercase(),
        })?;
    }
    // Each part's photons in order, light after light: a light's are the next `stored` of them.
    let mut rest: Vec<_> = maps.iter().map(|(_, t)| t.photons.iter()).collect();
    let mut photons = PhotonStream::new();
    let mut per_light = Vec::with_capacity(lights);
    let mut buf: Vec<Staged> = Vec::new();
    for l in 0..lights {
        let mut sum = LightCounts {
            kept_ppm: maps.first().map_or(0, |m| m.1.per_light[l].kept_ppm),
            ..LightCounts::default()
        };
        for ((_, t), part) in maps.iter().zip(&mut rest) {
            let c = &t.per_light[l];
            buf.clear();
            buf.extend(part.by_ref().take(c.stored as usize));
            photons.extend_from_slice(&buf);
            sum.emitted += c.emitted;
            sum.stored += c.stored;
            sum.first_hit_specular += c.first_hit_specular;
            sum.met_surface += c.met_surface;
        }
        per_light.push(sum);
    }
    Ok(CountedMap {
        map: PhotonMap::from_stream(photons),
        per_light,
    })
}

/// Returns what is wrong with `t` as part `part` of a pass of `budget[l]` photons per light for
/// `lights` lights, if anything: another light count, emitted photons other than the part's
/// share, more stored than `most` per photon emitted, more photons meeting a surface (or a
/// specular one first) than emitted, or a projection map keeping more than all directions.
fn check_share(
    t: &TracedMap,
    part: Part,
    budget: &[u64],
    lights: usize,
    most: u64,
) -> std::result::Result<(), String> {
    if t.per_light.len() != lights {
        return Err(format!(
            "counts for {} lights, but the scene has {lights}",
            t.per_light.len()
        ));
    }
    for (l, c) in t.per_light.iter().enumerate() {
        let share = part.range(budget.get(l).copied().unwrap_or(0));
        let cannot = c.emitted != share.end - share.start
            || c.stored > c.emitted.saturating_mul(most)
            || c.first_hit_specular > c.emitted
            || c.met_surface > c.emitted
            || c.kept_ppm > 1_000_000;
        if cannot {
            return Err(format!(
                "light {l}'s counts (emitted {}, stored {}, first hit specular {}) cannot be \
                 part {}/{}'s share of its {} photons",
                c.emitted,
                c.stored,
                c.first_hit_specular,
                part.index,
                part.count,
                share.end - share.start
            ));
        }
    }
    Ok(())
}

/// The part file's kind.
const PARTS: Kind = Kind {
    magic: MAGIC,
    version: VERSION,
    name: "photon-pass part",
    writer: "caustic photons --part",
    again: "trace it again",
};

/// Writes `part` to `path`, replacing it atomically ([`crate::files::write_replacing_io`]).
pub fn write(path: &Path, part: &SavedPart) -> std::io::Result<()> {
    crate::files::write_replacing_io(path, |file| {
        let mut w = CrcWriter::new(BufWriter::with_capacity(1 << 20, file));
        write_header(&mut w, &PARTS, &part.fingerprint)?;
        w.write_all(&part.part.index.to_le_bytes())?;
        w.write_all(&part.part.count.to_le_bytes())?;
        w.write_all(&[1 + u8::from(part.caustic.is_some())])?;
        for t in std::iter::once(&part.global).chain(&part.caustic) {
            write_traced(&mut w, t)?;
        }
        write_checksum(&mut w)
    })
}

/// Reads the part saved at `path`; the error says what is wrong with the file (not what it was
/// traced for: [`merge`] compares that).
pub fn read(path: &Path) -> std::result::Result<SavedPart, String> {
    let (mut r, size) = open(path)?;
    let fingerprint = read_header(&mut r, &PARTS)?;
    let (index, count) = (r.u32("the header")?, r.u32("the header")?);
    if !(1..=MAX_PARTS).contains(&count) || index >= count {
        return Err(format!(
            "part {index} of {count} (at most {MAX_PARTS} parts)"
        ));
    }
    let mut maps = [0];
    r.bytes(&mut maps, "the header")?;
    if !(1..=2).contains(&maps[0]) {
        return Err(format!("{} maps (a part holds 1 or 2)", maps[0]));
    }
    let global = read_traced(&mut r, "the global map", size)?;
    let caustic = match maps[0] {
        2 => Some(read_traced(&mut r, "the caustic map", size)?),
        _ => None,
    };
    read_checksum(&mut r)?;
    Ok(SavedPart {
        fingerprint,
        part: Part { index, count },
        global,
        caustic,
    })
}
