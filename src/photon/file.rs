//! Photon maps as files: `caustic photons SCENE.lua --save maps.bin` writes the maps a render
//! of the scene would trace, with the frame's irradiance cache, and `caustic render SCENE.lua
//! --photon-maps maps.bin` reads them instead of making them, so the tiles of a render farm
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
//! # Layout (little-endian)
//! | bytes | contents |
//! |---|---|
//! | 8 | magic `CAUSTPM\0` |
//! | 4 | format version ([`VERSION`]) |
//! | 8 | scene hash |
//! | 4 + n | settings text, UTF-8, length first (at most [`MAX_TEXT`]) |
//! | 1 | maps: 1 (global) or 2 (global and caustic) |
//! | per map | light count (4), then per light emitted, stored, first-hit-specular (8 each); photon count (8, at most `u32::MAX`); top nodes (8); power base exponent (4); positions (12 per photon); codes (4 per photon); powers (4 per photon) |
//! | 1 | irradiance cache: 0 (none) or 1, then its accuracy (f32), record count (8) and per record position, normal, irradiance, the three gradients and the radius (19 f32) |
//! | 4 | CRC-32 (IEEE) of everything before it |

use super::store::PowerCodec;
use super::trace::{LightCounts, MAX_BOUNCES};
use super::{PhotonMap, kdtree};
use crate::integrator::irradiance_cache::{IrradianceCache, Record};
use glam::Vec3A;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

/// The file's first eight bytes.
const MAGIC: &[u8; 8] = b"CAUSTPM\0";
/// The format version this program reads and writes.
pub const VERSION: u32 = 1;
/// Longest settings text read.
pub const MAX_TEXT: u32 = 1 << 16;
/// Most lights a map's counts are read for.
const MAX_LIGHTS: u32 = 1 << 20;
/// Photons read or written between two progress reports and buffer refills.
const CHUNK: usize = 1 << 16;

/// What a pair of maps was traced for (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fingerprint {
    /// FNV-1a hash of the scene as the photons see it.
    pub scene: u64,
    /// The settings that shape the maps, as text.
    pub settings: String,
}

/// A map with each light's photon counts.
#[derive(Debug)]
pub struct CountedMap {
    pub map: PhotonMap,
    pub per_light: Vec<LightCounts>,
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
    /// radii are clamped to (see [`crate::integrator::irradiance_cache`]).
    pub cache: Option<(f32, (f32, f32))>,
}

impl SavedMaps {
    /// Returns an error naming the map and the photon, record or count that the frame
    /// `expected` describes could not have made: a light count, a caustic map or a cache the
    /// frame does not have, a photon or record outside the scene, another cache accuracy or a
    /// record radius outside the frame's range.
    pub fn check(&self, expected: &Expected) -> Result<(), String> {
        let outside = |p: Vec3A| {
            expected.bounds.is_some_and(|(lo, hi)| {
                let margin =
                    0.01 * (hi - lo).length() + 1e-6 * lo.abs().max(hi.abs()).max_element();
                p.cmplt(lo - margin).any() || p.cmpgt(hi + margin).any()
            })
        };
        for (m, what) in std::iter::once((&self.global, "the global map"))
            .chain(self.caustic.as_ref().map(|c| (c, "the caustic map")))
        {
            if m.per_light.len() != expected.lights {
                return Err(format!(
                    "{what}: counts for {} lights, but the scene has {}",
                    m.per_light.len(),
                    expected.lights
                ));
            }
            if let Some(i) = m
                .map
                .pos
                .iter()
                .position(|p| outside(Vec3A::from_array(*p)))
            {
                return Err(format!(
                    "{what}: photon {i} at {:?} lies outside the scene",
                    m.map.pos[i]
                ));
            }
        }
        if self.caustic.is_some() != expected.caustic {
            return Err(match expected.caustic {
                true => "it has no caustic map, and this frame has caustics".into(),
                false => "it has a caustic map, and this frame has no caustics".into(),
            });
        }
        let Some(cache) = &self.cache else {
            return Ok(());
        };
        let what = "the irradiance cache";
        let Some((accuracy, (r_min, r_max))) = expected.cache else {
            return Err(format!("{what}: this frame makes none"));
        };
        if cache.accuracy() != accuracy {
            return Err(format!(
                "{what}: accuracy {}, this frame's is {accuracy}",
                cache.accuracy()
            ));
        }
        let (lo, hi) = (r_min * (1.0 - 1e-5), r_max * (1.0 + 1e-5));
        for (i, r) in cache.records().iter().enumerate() {
            if outside(r.p) {
                return Err(format!(
                    "{what}: record {i} at {} lies outside the scene",
                    r.p
                ));
            }
            if !(lo..=hi).contains(&r.r) {
                return Err(format!(
                    "{what}: record {i}'s radius {} is outside this frame's [{r_min}, {r_max}]",
                    r.r
                ));
            }
        }
        Ok(())
    }
}

/// 64-bit FNV-1a, for the scene fingerprint: a fixed, documented hash whose value does not
/// change between builds (std's `DefaultHasher` may).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Hashes `bytes` into the state.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// Hashes the length (8 bytes, little-endian) and then the bytes of the regular file
    /// `path`, read in pieces: a scene's mesh can be larger than is worth holding twice.
    pub fn write_file(&mut self, path: &Path) -> std::io::Result<()> {
        crate::files::check_regular(path)?;
        let mut file = std::fs::File::open(path)?;
        let len = file.metadata()?.len();
        self.write(&len.to_le_bytes());
        let mut buf = vec![0u8; 1 << 16];
        let mut read = 0u64;
        loop {
            let n = file.read(&mut buf)?;
            if n == 0 {
                break;
            }
            self.write(&buf[..n]);
            read += n as u64;
        }
        if read != len {
            return Err(std::io::Error::other("the file changed while it was read"));
        }
        Ok(())
    }

    /// Returns the hash so far.
    pub fn finish(self) -> u64 {
        self.0
    }
}

/// A writer that keeps the CRC-32 of what passes through it.
struct Crc<W> {
    inner: W,
    crc: crc32fast::Hasher,
}

impl<W: Write> Write for Crc<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Writes `maps` to `path`, replacing it atomically ([`crate::files::write_replacing_io`]).
pub fn write(path: &Path, maps: &SavedMaps) -> std::io::Result<()> {
    crate::files::write_replacing_io(path, |file| {
        let mut w = Crc {
            inner: BufWriter::with_capacity(1 << 20, file),
            crc: crc32fast::Hasher::new(),
        };
        w.write_all(MAGIC)?;
        w.write_all(&VERSION.to_le_bytes())?;
        w.write_all(&maps.fingerprint.scene.to_le_bytes())?;
        let text = maps.fingerprint.settings.as_bytes();
        w.write_all(&(text.len() as u32).to_le_bytes())?;
        w.write_all(text)?;
        let count = 1 + u8::from(maps.caustic.is_some());
        w.write_all(&[count])?;
        for m in std::iter::once(&maps.global).chain(&maps.caustic) {
            write_map(&mut w, m)?;
        }
        write_cache(&mut w, maps.cache.as_ref())?;
        let crc = w.crc.clone().finalize();
        w.inner.write_all(&crc.to_le_bytes())?;
        w.inner.flush()
    })
}

/// Floats per cache record: position, normal, irradiance, three gradients, radius.
const RECORD_FLOATS: usize = 3 * 6 + 1;

fn record_floats(r: &Record) -> [f32; RECORD_FLOATS] {
    let v = [r.p, r.n, r.e, r.t[0], r.t[1], r.t[2]];
    std::array::from_fn(|i| if i < 18 { v[i / 3][i % 3] } else { r.r })
}

fn write_cache<W: Write>(w: &mut W, cache: Option<&IrradianceCache>) -> std::io::Result<()> {
    let Some(cache) = cache else {
        return w.write_all(&[0]);
    };
    w.write_all(&[1])?;
    w.write_all(&cache.accuracy().to_le_bytes())?;
    w.write_all(&(cache.records().len() as u64).to_le_bytes())?;
    for r in cache.records() {
        for x in record_floats(r) {
            w.write_all(&x.to_le_bytes())?;
        }
    }
    Ok(())
}

fn read_cache<R: Read>(r: &mut Input<R>, size: u64) -> Result<Option<IrradianceCache>, String> {
    let what = "the irradiance cache";
    let mut flag = [0];
    r.bytes(&mut flag, what)?;
    match flag[0] {
        0 => return Ok(None),
        1 => {}
        f => return Err(format!("{what}: flag {f} (0 or 1)")),
    }
    let accuracy = f32::from_bits(r.u32(what)?);
    if !(accuracy > 0.0 && accuracy <= 1.0) {
        return Err(format!("{what}: accuracy {accuracy}"));
    }
    let n = r.u64(what)?;
    if n.saturating_mul(4 * RECORD_FLOATS as u64) > size {
        return Err(format!(
            "{what}: {n} records, more than the file's {size} bytes hold"
        ));
    }
    let mut records = Vec::with_capacity(n as usize);
    let mut buf = [0u8; 4 * RECORD_FLOATS];
    for _ in 0..n {
        r.bytes(&mut buf, what)?;
        let f = |i: usize| {
            f32::from_le_bytes([buf[4 * i], buf[4 * i + 1], buf[4 * i + 2], buf[4 * i + 3]])
        };
        let v = |k: usize| Vec3A::new(f(3 * k), f(3 * k + 1), f(3 * k + 2));
        let rec = Record {
            p: v(0),
            n: v(1),
            e: v(2),
            t: [v(3), v(4), v(5)],
            r: f(18),
        };
        check_record(&rec).map_err(|e| format!("{what}: record {}: {e}", records.len()))?;
        records.push(rec);
    }
    Ok(Some(IrradianceCache::new(records, accuracy)))
}

/// Largest irradiance (W/m²) and rotational-gradient component a cache record read from a file
/// may hold: an interpolation sums up to 2^32 records of at most 2^64 each, and the shading
/// after it multiplies by albedos and cosines, all far inside `f32` (2^128).
pub const MAX_RECORD_VALUE: f32 = 18_446_744_073_709_551_616.0; // 2^64

/// Returns what is wrong with cache record `r` for the renderer, if anything (checked before
/// the cache's grid is built over the records): a position or a radius beyond
/// [`MAX_RECORD_VALUE`], a normal that is not a unit vector, an irradiance that is negative, not
/// finite or above [`MAX_RECORD_VALUE`], a gradient component beyond it, or a radius that is
/// not positive.
fn check_record(r: &Record) -> Result<(), String> {
    let within = |v: Vec3A| v.is_finite() && v.abs().max_element() <= MAX_RECORD_VALUE;
    if !within(r.p) {
        return Err(format!(
            "its position {} is not finite or beyond {MAX_RECORD_VALUE:e}",
            r.p
        ));
    }
    if !(r.n.is_finite() && (r.n.length() - 1.0).abs() <= 1e-3) {
        return Err(format!("its normal {} is not a unit vector", r.n));
    }
    if !(within(r.e) && r.e.min_element() >= 0.0) {
        return Err(format!(
            "its irradiance {} is not in [0, {MAX_RECORD_VALUE:e}]",
            r.e
        ));
    }
    if let Some(t) = r.t.iter().find(|t| !within(**t)) {
        return Err(format!(
            "its gradient {t} is not finite or beyond {MAX_RECORD_VALUE:e}"
        ));
    }
    if !(r.r > 0.0 && r.r <= MAX_RECORD_VALUE) {
        return Err(format!(
            "its radius {} is not in (0, {MAX_RECORD_VALUE:e}]",
            r.r
        ));
    }
    Ok(())
}

fn write_map<W: Write>(w: &mut W, m: &CountedMap) -> std::io::Result<()> {
    w.write_all(&(m.per_light.len() as u32).to_le_bytes())?;
    for c in &m.per_light {
        for v in [c.emitted, c.stored, c.first_hit_specular] {
            w.write_all(&v.to_le_bytes())?;
        }
    }
    let map = &m.map;
    w.write_all(&(map.len() as u64).to_le_bytes())?;
    w.write_all(&(map.top_nodes as u64).to_le_bytes())?;
    w.write_all(&map.codec.base().to_le_bytes())?;
    let mut buf = Vec::with_capacity(12 * CHUNK);
    for part in map.pos.chunks(CHUNK) {
        buf.clear();
        buf.extend(part.iter().flatten().flat_map(|x| x.to_le_bytes()));
        w.write_all(&buf)?;
    }
    for words in [&map.code, &map.power] {
        for part in words.chunks(CHUNK) {
            buf.clear();
            buf.extend(part.iter().flat_map(|x| x.to_le_bytes()));
            w.write_all(&buf)?;
        }
    }
    Ok(())
}

/// A reader that keeps the CRC-32 of what it has read and names what it was reading when the
/// file ends early.
struct Input<R> {
    inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> Input<R> {
    fn bytes(&mut self, out: &mut [u8], what: &str) -> Result<(), String> {
        self.inner.read_exact(out).map_err(|e| match e.kind() {
            std::io::ErrorKind::UnexpectedEof => format!("the file ends inside {what}"),
            _ => format!("reading {what}: {e}"),
        })?;
        self.crc.update(out);
        Ok(())
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let mut b = [0; 4];
        self.bytes(&mut b, what)?;
        Ok(u32::from_le_bytes(b))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let mut b = [0; 8];
        self.bytes(&mut b, what)?;
        Ok(u64::from_le_bytes(b))
    }
}

/// Reads the maps saved at `path`; the error says what is wrong with the file (not what it
/// was traced for: compare [`SavedMaps::fingerprint`] for that).
pub fn read(path: &Path) -> Result<SavedMaps, String> {
    crate::files::check_regular(path).map_err(|e| e.to_string())?;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    let mut r = Input {
        inner: BufReader::with_capacity(1 << 20, file),
        crc: crc32fast::Hasher::new(),
    };
    let mut magic = [0; 8];
    r.bytes(&mut magic, "the header")
        .map_err(|_| "not a caustic photon-map file (too short)".to_string())?;
    if &magic != MAGIC {
        return Err("not a caustic photon-map file (caustic photons --save writes them)".into());
    }
    let version = r.u32("the header")?;
    if version != VERSION {
        return Err(format!(
            "format version {version}; this caustic reads version {VERSION}: save the maps again"
        ));
    }
    let scene = r.u64("the header")?;
    let len = r.u32("the header")?;
    if len > MAX_TEXT {
        return Err(format!(
            "a settings text of {len} bytes (at most {MAX_TEXT})"
        ));
    }
    let mut text = vec![0; len as usize];
    r.bytes(&mut text, "the settings text")?;
    let settings =
        String::from_utf8(text).map_err(|_| "the settings text is not UTF-8".to_string())?;
    let mut count = [0];
    r.bytes(&mut count, "the header")?;
    if !(1..=2).contains(&count[0]) {
        return Err(format!("{} maps (a file holds 1 or 2)", count[0]));
    }
    // Every photon takes 20 bytes, so the file's size bounds the counts it can honestly hold.
    let global = read_map(&mut r, "the global map", size)?;
    let caustic = match count[0] {
        2 => Some(read_map(&mut r, "the caustic map", size)?),
        _ => None,
    };
    for (m, what, most) in [
        (Some(&global), "the global map", u64::from(MAX_BOUNCES)),
        (caustic.as_ref(), "the caustic map", 1),
    ] {
        if let Some(m) = m {
            check_counts(m, most).map_err(|e| format!("{what}: {e}"))?;
        }
    }
    let cache = read_cache(&mut r, size)?;
    let want = r.crc.clone().finalize();
    let mut b = [0; 4];
    r.inner
        .read_exact(&mut b)
        .map_err(|_| "the file ends before its checksum".to_string())?;
    if u32::from_le_bytes(b) != want {
        return Err("the checksum does not match: the file is damaged".into());
    }
    if r.inner.read(&mut b).map_err(|e| e.to_string())? != 0 {
        return Err("bytes follow the checksum".into());
    }
    // A file whose checksum holds may still have been made by hand: a map that breaks the
    // tree's invariants would answer queries wrongly, so it is refused.
    for (m, what) in [
        (Some(&global), "the global map"),
        (caustic.as_ref(), "the caustic map"),
    ] {
        if let Some(m) = m {
            m.map.validate().map_err(|e| format!("{what}: {e}"))?;
            m.map
                .codec
                .validate(&m.map.power)
                .map_err(|e| format!("{what}: {e}"))?;
        }
    }
    Ok(SavedMaps {
        fingerprint: Fingerprint { scene, settings },
        global,
        caustic,
        cache,
    })
}

/// Returns what is wrong with the per-light counts of `m`, if anything: a light that stored
/// more than `most` photons per photon it emitted (a global photon is stored at each diffuse
/// bounce, at most [`MAX_BOUNCES`]; a caustic photon once) or met a specular surface first
/// more often than it emitted, or counts that stored fewer photons than the map holds.
fn check_counts(m: &CountedMap, most: u64) -> Result<(), String> {
    let mut stored = 0u64;
    for (l, c) in m.per_light.iter().enumerate() {
        if c.stored > c.emitted.saturating_mul(most) || c.first_hit_specular > c.emitted {
            return Err(format!(
                "light {l}'s counts (emitted {}, stored {}, first hit specular {}) cannot be",
                c.emitted, c.stored, c.first_hit_specular
            ));
        }
        stored = stored.saturating_add(c.stored);
    }
    if stored < m.map.len() as u64 {
        return Err(format!(
            "its lights stored {stored} photons, but it holds {}",
            m.map.len()
        ));
    }
    Ok(())
}

fn read_map<R: Read>(r: &mut Input<R>, what: &str, size: u64) -> Result<CountedMap, String> {
    let lights = r.u32(what)?;
    if lights > MAX_LIGHTS {
        return Err(format!("{what}: {lights} lights (at most {MAX_LIGHTS})"));
    }
    // Each light's counts take 24 bytes of the file: a count the file cannot hold is refused
    // before the counts are allocated (a forged count made an 8 KB file take 22 MiB).
    if u64::from(lights) * 24 > size {
        return Err(format!(
            "{what}: {lights} lights, more than the file's {size} bytes hold"
        ));
    }
    let mut per_light = Vec::with_capacity(lights as usize);
    for _ in 0..lights {
        per_light.push(LightCounts {
            emitted: r.u64(what)?,
            stored: r.u64(what)?,
            first_hit_specular: r.u64(what)?,
            ..LightCounts::default()
        });
    }
    let n = r.u64(what)?;
    if n > u64::from(u32::MAX) || n.saturating_mul(20) > size {
        return Err(format!(
            "{what}: {n} photons, more than the file's {size} bytes hold"
        ));
    }
    let n = n as usize;
    let top = r.u64(what)?;
    if top != ((1u64 << kdtree::top_depth(n)) - 1) {
        return Err(format!(
            "{what}: {top} top nodes, not the layout of {n} photons"
        ));
    }
    let base = r.u32(what)? as i32;
    let codec = PowerCodec::from_base(base).ok_or_else(|| format!("{what}: power base {base}"))?;
    let mut buf = vec![0u8; 12 * CHUNK];
    let mut pos = crate::mem::huge_vec::<[f32; 3]>(n);
    while pos.len() < n {
        let k = CHUNK.min(n - pos.len());
        r.bytes(&mut buf[..12 * k], what)?;
        pos.extend(buf[..12 * k].as_chunks::<12>().0.iter().map(|p| {
            let f = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
            [f(0), f(4), f(8)]
        }));
    }
    let mut words = |r: &mut Input<R>| -> Result<Vec<u32>, String> {
        let mut v = crate::mem::huge_vec::<u32>(n);
        while v.len() < n {
            let k = CHUNK.min(n - v.len());
            r.bytes(&mut buf[..4 * k], what)?;
            v.extend(
                buf[..4 * k]
                    .as_chunks::<4>()
                    .0
                    .iter()
                    .map(|b| u32::from_le_bytes(*b)),
            );
        }
        Ok(v)
    };
    let code = words(r)?;
    let power = words(r)?;
    let map = PhotonMap {
        pos,
        code,
        power,
        codec,
        top_nodes: top as usize,
    };
    Ok(CountedMap { map, per_light })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::Photon;

    fn maps(n: usize) -> SavedMaps {
        let photon = |i: usize| Photon {
            position: Vec3A::new((i % 97) as f32, (i % 13) as f32 * 0.5, i as f32 * 1e-3),
            power: Vec3A::new(1.0, 0.5, 0.25) * (1.0 + (i % 7) as f32) * 1e-4,
            dir: Vec3A::Y,
            normal: Vec3A::Z,
            direct: i.is_multiple_of(3),
        };
        let counts = |stored: usize| {
            vec![LightCounts {
                emitted: stored as u64 + 1000,
                stored: stored as u64,
                first_hit_specular: 7,
                ..LightCounts::default()
            }]
        };
        SavedMaps {
            fingerprint: Fingerprint {
                scene: 0x1234_5678_9abc_def0,
                settings: "seed 0; ünïcode".into(),
            },
            global: CountedMap {
                map: PhotonMap::build((0..n).map(photon).collect()),
                per_light: counts(n),
            },
            caustic: Some(CountedMap {
                map: PhotonMap::build((0..n / 3).map(photon).collect()),
                per_light: counts(n / 3),
            }),
            cache: Some(IrradianceCache::new(
                (0..5)
                    .map(|i| Record {
                        p: Vec3A::splat(i as f32),
                        n: Vec3A::Y,
                        e: Vec3A::new(0.5, 0.25, i as f32),
                        t: [Vec3A::X, Vec3A::Y * -2.0, Vec3A::Z * 1e-7],
                        r: 0.125 + i as f32,
                    })
                    .collect(),
                0.3,
            )),
        }
    }

    fn dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("caustic-pm-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_saved_map_reads_back_identical() {
        let path = dir("round").join("m.bin");
        let m = maps(3 * CHUNK + 5);
        write(&path, &m).unwrap();
        let r = read(&path).unwrap();
        assert_eq!(r.fingerprint, m.fingerprint);
        assert_eq!(r.global.map, m.global.map);
        assert_eq!(r.global.per_light, m.global.per_light);
        let (a, b) = (r.caustic.unwrap(), m.caustic.unwrap());
        assert_eq!((a.map, a.per_light), (b.map, b.per_light));
        let (a, b) = (r.cache.unwrap(), m.cache.unwrap());
        assert_eq!(a.accuracy(), b.accuracy());
        assert_eq!(a.records(), b.records());
        // 20 bytes a photon, 76 a cache record, and a small header.
        let photons = (3 * CHUNK + 5) + (3 * CHUNK + 5) / 3;
        let size = std::fs::metadata(&path).unwrap().len() as usize;
        let data = 20 * photons + 5 * 76;
        assert!(size >= data && size < data + 200, "{size} bytes");
    }

    #[test]
    fn a_file_with_a_good_checksum_but_a_broken_tree_is_refused() {
        let path = dir("broken").join("m.bin");
        let mut m = maps(5000);
        // Swap two positions on either side of the root's split: the checksum is computed
        // over the broken map, so only the tree's own check can find it.
        let last = m.global.map.pos.len() - 1;
        m.global.map.pos.swap(0, last);
        write(&path, &m).unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.starts_with("the global map: "), "{e}");
    }

    #[test]
    fn a_cache_record_that_is_not_finite_is_refused() {
        let path = dir("record").join("m.bin");
        for bad in [f32::NAN, f32::INFINITY] {
            let mut m = maps(100);
            let mut records = m.cache.as_ref().unwrap().records().to_vec();
            records[3].t[1].y = bad;
            m.cache = Some(IrradianceCache::new(records.clone(), 0.3));
            write(&path, &m).unwrap();
            let e = read(&path).unwrap_err();
            assert!(
                e.starts_with("the irradiance cache: record 3: its gradient"),
                "{e}"
            );
            records[3].t[1].y = 0.0;
            records[4].r = bad;
            m.cache = Some(IrradianceCache::new(records, 0.3));
            write(&path, &m).unwrap();
            let e = read(&path).unwrap_err();
            assert!(
                e.starts_with("the irradiance cache: record 4: its radius"),
                "{e}"
            );
        }
    }

    /// Every map a render builds passes the power check: powers over the whole `f32` range a
    /// map can hold (its brightest photon up to 2^64 W), subnormal and zero powers among them,
    /// and a map whose powers are all zero.
    #[test]
    fn every_map_built_passes_the_power_check() {
        let mut r = crate::sampling::Rng::new(9, crate::sampling::Pass::Photon, 0);
        for top in [-140i32, -60, -3, 0, 20, 63] {
            let photons: Vec<Photon> = (0..2000)
                .map(|i| {
                    let scale = |u: f32| (2.0f32).powi(top - (u * 40.0) as i32);
                    let p = Vec3A::new(scale(r.next_f32()), scale(r.next_f32()), 0.0);
                    Photon {
                        position: Vec3A::new(r.next_f32(), r.next_f32(), r.next_f32()),
                        power: if i % 17 == 0 { Vec3A::ZERO } else { p },
                        dir: Vec3A::Y,
                        normal: Vec3A::Z,
                        direct: false,
                    }
                })
                .collect();
            let map = PhotonMap::build(photons);
            assert_eq!(map.codec.validate(&map.power), Ok(()), "top exponent {top}");
        }
        let dark = PhotonMap::build(vec![
            Photon {
                position: Vec3A::ZERO,
                power: Vec3A::ZERO,
                dir: Vec3A::Y,
                normal: Vec3A::Z,
                direct: true,
            };
            10
        ]);
        assert_eq!(dark.codec.validate(&dark.power), Ok(()));
    }

    #[test]
    fn fnv_matches_its_published_test_vectors() {
        let hash = |s: &str| {
            let mut h = Fnv::default();
            h.write(s.as_bytes());
            h.finish()
        };
        assert_eq!(hash(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(hash("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(hash("foobar"), 0x8594_4171_f739_67e8);
    }
}
