//! The bytes of a photon-map file: a header with the [`Fingerprint`], the maps (each in
//! [`crate::photon::file`]'s layout), the irradiance cache's records and a CRC-32; and the
//! checks a file's fields must pass before a frame takes its maps (see the module doc of
//! [`super`] for the layout and why each check exists).

use super::{Expected, Fingerprint, SavedMaps};
use crate::integrator::irradiance_cache::{IrradianceCache, Record};
use crate::photon::PhotonId;
use crate::photon::file::{CrcReader, CrcWriter, check_counts, read_map, write_map};
use crate::photon::trace::MAX_BOUNCES;
use glam::Vec3A;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

/// The file's first eight bytes.
const MAGIC: &[u8; 8] = b"CAUSTPM\0";
/// The format version this program reads and writes.
pub const VERSION: u32 = 2;
/// Longest settings text read.
pub const MAX_TEXT: u32 = 1 << 16;

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
            let mut ids = (0..m.map.len() as u32).map(PhotonId);
            if let Some(id) = ids.find(|&id| outside(m.map.position(id))) {
                return Err(format!(
                    "{what}: photon {} at {:?} lies outside the scene",
                    id.0,
                    m.map.position(id).to_array()
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

/// Writes `maps` to `path`, replacing it atomically ([`crate::files::write_replacing_io`]).
pub fn write(path: &Path, maps: &SavedMaps) -> std::io::Result<()> {
    crate::files::write_replacing_io(path, |file| {
        let mut w = CrcWriter::new(BufWriter::with_capacity(1 << 20, file));
        write_header(&mut w, &MAPS, &maps.fingerprint)?;
        let count = 1 + u8::from(maps.caustic.is_some());
        w.write_all(&[count])?;
        for m in std::iter::once(&maps.global).chain(&maps.caustic) {
            write_map(&mut w, m)?;
        }
        write_cache(&mut w, maps.cache.as_ref())?;
        write_checksum(&mut w)
    })
}

/// Floats per cache record: position, normal, irradiance, three rotational and three
/// translational gradients, radius.
const RECORD_FLOATS: usize = 3 * 9 + 1;

fn record_floats(r: &Record) -> [f32; RECORD_FLOATS] {
    let (t, g) = (&r.rotation, &r.translation);
    let v = [r.p, r.n, r.e, t[0], t[1], t[2], g[0], g[1], g[2]];
    std::array::from_fn(|i| if i < 27 { v[i / 3][i % 3] } else { r.r })
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

fn read_cache<R: Read>(r: &mut CrcReader<R>, size: u64) -> Result<Option<IrradianceCache>, String> {
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
            rotation: [v(3), v(4), v(5)],
            translation: [v(6), v(7), v(8)],
            r: f(27),
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
    if let Some(t) = r
        .rotation
        .iter()
        .chain(&r.translation)
        .find(|t| !within(**t))
    {
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

/// What kind of file a header opens: its magic and version, its name in messages, the
/// command that writes it and what to do when its version is another.
pub(crate) struct Kind {
    pub magic: &'static [u8; 8],
    pub version: u32,
    pub name: &'static str,
    pub writer: &'static str,
    pub again: &'static str,
}

/// The photon-map file's kind.
const MAPS: Kind = Kind {
    magic: MAGIC,
    version: VERSION,
    name: "photon-map file",
    writer: "caustic photons --save",
    again: "save the maps again",
};

/// Opens `path` as a regular file; returns a checksumming reader over it and its size.
pub(crate) fn open(path: &Path) -> Result<(CrcReader<BufReader<std::fs::File>>, u64), String> {
    crate::files::check_regular(path).map_err(|e| e.to_string())?;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    Ok((
        CrcReader::new(BufReader::with_capacity(1 << 20, file)),
        size,
    ))
}

/// Writes the header of a file of `kind`: magic, version, the fingerprint (scene hash, then
/// the settings text with its length first).
pub(crate) fn write_header<W: Write>(
    w: &mut W,
    kind: &Kind,
    f: &Fingerprint,
) -> std::io::Result<()> {
    w.write_all(kind.magic)?;
    w.write_all(&kind.version.to_le_bytes())?;
    w.write_all(&f.scene.to_le_bytes())?;
    let text = f.settings.as_bytes();
    w.write_all(&(text.len() as u32).to_le_bytes())?;
    w.write_all(text)
}

/// Reads the header [`write_header`] writes for `kind`, or says why the file is not one.
pub(crate) fn read_header<R: Read>(
    r: &mut CrcReader<R>,
    kind: &Kind,
) -> Result<Fingerprint, String> {
    let mut magic = [0; 8];
    r.bytes(&mut magic, "the header")
        .map_err(|_| format!("not a caustic {} (too short)", kind.name))?;
    if &magic != kind.magic {
        return Err(format!(
            "not a caustic {} ({} writes them)",
            kind.name, kind.writer
        ));
    }
    let version = r.u32("the header")?;
    if version != kind.version {
        return Err(format!(
            "format version {version}; this caustic reads version {}: {}",
            kind.version, kind.again
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
    Ok(Fingerprint { scene, settings })
}

/// Writes the CRC-32 of everything `w` has written, and flushes.
pub(crate) fn write_checksum<W: Write>(w: &mut CrcWriter<W>) -> std::io::Result<()> {
    let crc = w.crc();
    w.inner.write_all(&crc.to_le_bytes())?;
    w.inner.flush()
}

/// Reads the CRC-32 that ends a file and compares it with what `r` has read; refuses a file
/// whose checksum differs or that goes on after it.
pub(crate) fn read_checksum<R: Read>(r: &mut CrcReader<R>) -> Result<(), String> {
    let want = r.crc();
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
    Ok(())
}

/// Reads the maps saved at `path`; the error says what is wrong with the file (not what it
/// was traced for: compare [`SavedMaps::fingerprint`] for that).
pub fn read(path: &Path) -> Result<SavedMaps, String> {
    let (mut r, size) = open(path)?;
    let fingerprint = read_header(&mut r, &MAPS)?;
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
    read_checksum(&mut r)?;
    // A file whose checksum holds may still have been made by hand: a map that breaks the
    // tree's invariants would answer queries wrongly, so it is refused.
    for (m, what) in [
        (Some(&global), "the global map"),
        (caustic.as_ref(), "the caustic map"),
    ] {
        if let Some(m) = m {
            m.validate().map_err(|e| format!("{what}: {e}"))?;
        }
    }
    Ok(SavedMaps {
        fingerprint,
        global,
        caustic,
        cache,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::file::CountedMap;
    use crate::photon::trace::LightCounts;
    use crate::photon::{Photon, PhotonMap};
    const CHUNK: usize = crate::photon::file::CHUNK;

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
                        rotation: [Vec3A::X, Vec3A::Y * -2.0, Vec3A::Z * 1e-7],
                        translation: [Vec3A::Z * 3.0, Vec3A::X * -0.5, Vec3A::Y * 1e-6],
                        r: 0.125 + i as f32,
                    })
                    .collect(),
                0.3,
            )),
        }
    }

    /// A test's folder in the system's temporary folder, removed when dropped (a failing test's
    /// too), so test runs leave nothing behind.
    struct Dir(std::path::PathBuf);

    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn dir(name: &str) -> Dir {
        let d = std::env::temp_dir().join(format!("caustic-pm-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }

    #[test]
    fn a_saved_map_reads_back_identical() {
        let d = dir("round");
        let path = d.0.join("m.bin");
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
        let data = 20 * photons + 5 * 112;
        assert!(size >= data && size < data + 200, "{size} bytes");
    }

    #[test]
    fn a_cache_record_that_is_not_finite_is_refused() {
        let d = dir("record");
        let path = d.0.join("m.bin");
        for (i, bad) in [f32::NAN, f32::INFINITY].into_iter().enumerate() {
            let mut m = maps(100);
            let mut records = m.cache.as_ref().unwrap().records().to_vec();
            // The rotational gradient, then the translational one.
            let r = &mut records[3];
            let gradient = if i == 0 {
                &mut r.rotation
            } else {
                &mut r.translation
            };
            gradient[1].y = bad;
            m.cache = Some(IrradianceCache::new(records.clone(), 0.3));
            write(&path, &m).unwrap();
            let e = read(&path).unwrap_err();
            assert!(
                e.starts_with("the irradiance cache: record 3: its gradient"),
                "{e}"
            );
            (records[3].rotation[1].y, records[3].translation[1].y) = (0.0, 0.0);
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
