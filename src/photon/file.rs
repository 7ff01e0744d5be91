//! A photon map as bytes: [`write_map`] and [`read_map`] move one map, with each light's photon
//! counts, through a stream exactly as the map holds it (kd-tree order, quantised codes, its
//! power format), so reading is a copy, not a rebuild. The file around the maps (header,
//! fingerprint, irradiance cache, checksum) is the photon-map integrator's:
//! `crate::integrator::maps_file`, which owns saving and loading a frame's prepass.
//!
//! # Layout of one map (little-endian)
//! light count (4), then per light emitted, stored, first-hit-specular (8 each); photon count
//! (8, at most `u32::MAX`); top nodes (8); power base exponent (4); positions (12 per photon);
//! codes (4 per photon); powers (4 per photon).
//!
//! A map read is checked against what a trace can give before any query uses it: the counts
//! ([`check_counts`]), and, once the whole file's checksum holds, the kd-tree's invariants and
//! the power codes ([`PhotonMap::validate`], `store::PowerCodec::validate`).

use super::store::PowerCodec;
use super::stream::PhotonStream;
use super::trace::{LightCounts, TracedMap};
use super::{PhotonMap, kdtree};
use std::io::{Read, Write};

/// Most lights a map's counts are read for.
const MAX_LIGHTS: u32 = 1 << 20;
/// Photons read or written between two buffer refills.
pub const CHUNK: usize = 1 << 16;

/// A map with each light's photon counts.
#[derive(Debug)]
pub struct CountedMap {
    pub map: PhotonMap,
    pub per_light: Vec<LightCounts>,
}

impl CountedMap {
    /// Returns what is wrong with the map for the renderer, if anything: the kd-tree's
    /// invariants ([`PhotonMap::validate`]) and the power codes (`store::PowerCodec::validate`).
    /// A file whose checksum holds may still have been made by hand, and a map that breaks
    /// them would answer queries wrongly.
    pub fn validate(&self) -> Result<(), String> {
        self.map.validate()?;
        self.map.codec.validate(&self.map.power)
    }
}

/// A writer that keeps the CRC-32 of what passes through it.
pub struct CrcWriter<W> {
    pub inner: W,
    crc: crc32fast::Hasher,
}

impl<W: Write> CrcWriter<W> {
    /// Wraps `inner`, with the checksum of nothing yet.
    pub fn new(inner: W) -> CrcWriter<W> {
        CrcWriter {
            inner,
            crc: crc32fast::Hasher::new(),
        }
    }

    /// Returns the CRC-32 of what has been written.
    pub fn crc(&self) -> u32 {
        self.crc.clone().finalize()
    }
}

impl<W: Write> Write for CrcWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A reader that keeps the CRC-32 of what it has read and names what it was reading when the
/// file ends early.
pub struct CrcReader<R> {
    pub inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> CrcReader<R> {
    /// Wraps `inner`, with the checksum of nothing yet.
    pub fn new(inner: R) -> CrcReader<R> {
        CrcReader {
            inner,
            crc: crc32fast::Hasher::new(),
        }
    }

    /// Returns the CRC-32 of what has been read.
    pub fn crc(&self) -> u32 {
        self.crc.clone().finalize()
    }

    /// Fills `out`, or returns an error naming `what` was being read.
    pub fn bytes(&mut self, out: &mut [u8], what: &str) -> Result<(), String> {
        self.inner.read_exact(out).map_err(|e| match e.kind() {
            std::io::ErrorKind::UnexpectedEof => format!("the file ends inside {what}"),
            _ => format!("reading {what}: {e}"),
        })?;
        self.crc.update(out);
        Ok(())
    }

    /// Reads a little-endian `u32`.
    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        let mut b = [0; 4];
        self.bytes(&mut b, what)?;
        Ok(u32::from_le_bytes(b))
    }

    /// Reads a little-endian `u64`.
    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        let mut b = [0; 8];
        self.bytes(&mut b, what)?;
        Ok(u64::from_le_bytes(b))
    }
}

/// Writes map `m` with its counts (the layout in the module doc).
pub fn write_map<W: Write>(w: &mut W, m: &CountedMap) -> std::io::Result<()> {
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

/// Returns what is wrong with the per-light counts of `m`, if anything: a light that stored
/// more than `most` photons per photon it emitted (a global photon is stored at each diffuse
/// bounce, at most [`super::trace::MAX_BOUNCES`]; a caustic photon once) or bounced specularly
/// off the first surface more often than it emitted, or counts that stored fewer photons than
/// the map holds.
pub fn check_counts(m: &CountedMap, most: u64) -> Result<(), String> {
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

/// Reads a map with its counts (the layout in the module doc) from `r`, naming `what` in its
/// errors; `size` is the file's size, which bounds every count read before it is allocated
/// (every photon takes 20 bytes, every light's counts 24).
pub fn read_map<R: Read>(
    r: &mut CrcReader<R>,
    what: &str,
    size: u64,
) -> Result<CountedMap, String> {
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
    let mut words = |r: &mut CrcReader<R>| -> Result<Vec<u32>, String> {
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

/// Largest power (W) a photon of a part file may carry: a light's flux is far below it, and a
/// map's power format holds its brightest photon up to it (`store::PowerCodec`).
pub const MAX_PART_POWER: f32 = 18_446_744_073_709_551_616.0; // 2^64

/// Bytes a traced photon takes in a part file: position (12), code word (4), power (12).
const STAGED_BYTES: u64 = 28;

/// Writes the traced photons of one map with each light's counts (a photon pass's part,
/// `caustic photons --part`): light count (4), per light emitted, stored, first-hit-specular,
/// met-surface (8 each) and the projection map's kept share (4); photon count (8); per photon
/// position, code word and power (28 bytes, in the order traced).
pub fn write_traced<W: Write>(w: &mut W, t: &TracedMap) -> std::io::Result<()> {
    w.write_all(&(t.per_light.len() as u32).to_le_bytes())?;
    for c in &t.per_light {
        for v in [c.emitted, c.stored, c.first_hit_specular, c.met_surface] {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&c.kept_ppm.to_le_bytes())?;
    }
    w.write_all(&(t.photons.len() as u64).to_le_bytes())?;
    let mut buf = Vec::with_capacity(STAGED_BYTES as usize * CHUNK);
    for p in t.photons.iter() {
        buf.extend(p.pos.iter().flat_map(|x| x.to_le_bytes()));
        buf.extend(p.code.to_le_bytes());
        buf.extend(p.power.iter().flat_map(|x| x.to_le_bytes()));
        if buf.len() >= STAGED_BYTES as usize * CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)
}

/// Reads what [`write_traced`] wrote from `r`, naming `what` in its errors; `size` is the
/// file's size, which bounds the counts before anything is allocated. Every photon is checked
/// before it is kept: a finite position, a valid code word, a power finite, not negative and
/// at most [`MAX_PART_POWER`]; and the lights' stored counts must add up to the photons.
pub fn read_traced<R: Read>(
    r: &mut CrcReader<R>,
    what: &str,
    size: u64,
) -> Result<TracedMap, String> {
    let lights = r.u32(what)?;
    if lights > MAX_LIGHTS || u64::from(lights) * 36 > size {
        return Err(format!(
            "{what}: {lights} lights, more than the file's {size} bytes hold"
        ));
    }
    let mut per_light = Vec::with_capacity(lights as usize);
    for _ in 0..lights {
        let mut v = [0u64; 4];
        for x in &mut v {
            *x = r.u64(what)?;
        }
        let [emitted, stored, first_hit_specular, met_surface] = v;
        let kept_ppm = r.u32(what)?;
        per_light.push(LightCounts {
            emitted,
            stored,
            first_hit_specular,
            met_surface,
            kept_ppm,
        });
    }
    let n = r.u64(what)?;
    if n.saturating_mul(STAGED_BYTES) > size {
        return Err(format!(
            "{what}: {n} photons, more than the file's {size} bytes hold"
        ));
    }
    let stored = per_light
        .iter()
        .map(|c| c.stored)
        .fold(0u64, u64::saturating_add);
    if stored != n {
        return Err(format!(
            "{what}: its lights stored {stored} photons, but it holds {n}"
        ));
    }
    let mut photons = PhotonStream::new();
    let mut buf = vec![0u8; STAGED_BYTES as usize * CHUNK];
    let mut staged = Vec::with_capacity(CHUNK);
    let mut done = 0u64;
    while done < n {
        let k = (n - done).min(CHUNK as u64) as usize;
        r.bytes(&mut buf[..STAGED_BYTES as usize * k], what)?;
        staged.clear();
        for (i, b) in buf[..STAGED_BYTES as usize * k]
            .chunks_exact(28)
            .enumerate()
        {
            let f = |j: usize| f32::from_le_bytes([b[j], b[j + 1], b[j + 2], b[j + 3]]);
            let p = super::stream::Staged {
                pos: [f(0), f(4), f(8)],
                code: u32::from_le_bytes([b[12], b[13], b[14], b[15]]),
                power: [f(16), f(20), f(24)],
            };
            let id = done + i as u64;
            if !p.pos.iter().all(|x| x.is_finite()) {
                return Err(format!("{what}: photon {id} at {:?} is not finite", p.pos));
            }
            if !super::store::code_is_valid(p.code) {
                return Err(format!("{what}: photon {id} has code word {:#x}", p.code));
            }
            if !p.power.iter().all(|x| (0.0..=MAX_PART_POWER).contains(x)) {
                return Err(format!(
                    "{what}: photon {id}'s power {:?} is not in [0, {MAX_PART_POWER:e}]",
                    p.power
                ));
            }
            staged.push(p);
        }
        photons.extend_from_slice(&staged);
        done += k as u64;
    }
    Ok(TracedMap { photons, per_light })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::Photon;
    use glam::Vec3A;

    /// A map whose bytes read back whole but break the tree's invariants is refused by
    /// [`CountedMap::validate`]: two positions swapped on either side of the root's split.
    #[test]
    fn a_map_with_a_broken_tree_is_refused() {
        let photons = (0..5000)
            .map(|i| Photon {
                position: Vec3A::new((i % 97) as f32, (i % 13) as f32, i as f32 * 1e-3),
                power: Vec3A::splat(1e-4),
                dir: Vec3A::Y,
                normal: Vec3A::Z,
                direct: false,
            })
            .collect();
        let mut m = CountedMap {
            map: PhotonMap::build(photons),
            per_light: vec![LightCounts::default()],
        };
        assert_eq!(m.validate(), Ok(()));
        let last = m.map.pos.len() - 1;
        m.map.pos.swap(0, last);
        let mut bytes = Vec::new();
        write_map(&mut bytes, &m).unwrap();
        let size = bytes.len() as u64;
        let read = read_map(&mut CrcReader::new(&bytes[..]), "the map", size).unwrap();
        assert!(read.validate().is_err());
    }

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
}
