//! Progressive passes split over processes: `caustic render --integrator progressive --passes N
//! --first-pass P --save-passes part.pass` runs passes `P` to `P + N - 1` of a progressive
//! render and saves their sums ([`Accumulator`]: the sum of the passes' films, the sums of the
//! even and the odd passes, the samples); `caustic merge a.pass b.pass … -o out.exr` adds the
//! parts up and writes their mean, with the estimated error of all the passes.
//!
//! # What the merge equals
//! Pass `i` runs with the seeds and the radii it has in one process running every pass (its
//! streams are keyed by `i`, its radii shrink by the schedule up to `i`), so the merged passes
//! are those passes, film for film. Their sum is added in another order, though (a part's sum,
//! then the next part's, instead of pass after pass), and `f32` addition is not associative:
//! the merged image equals the one-process image to the rounding of the sums, a relative
//! difference of order `passes × 2^-24` per pixel, far below the passes' noise
//! (`tests/files/progressive_parts.rs` measures it). The even and odd sums follow each pass's
//! index, so the noise estimate ([`Accumulator::estimated_error`]) is that of all the passes.
//!
//! # When parts are refused
//! Each part carries the render's fingerprint (the scene's hash, as a photon-map file has it,
//! and the settings that shape its passes, without the pass range and the stopping rules) and
//! its window. The merge refuses parts of different fingerprints or windows, and pass ranges
//! that do not follow one another from pass 0 (a gap or an overlap), naming the file. A part
//! whose sums are not finite or are negative, or whose sizes its file cannot hold, is refused
//! when read. The merge reads the headers first, then one file's sums at a time in pass
//! order: it holds two windows of sums whatever the number of files.
//!
//! # Layout (little-endian)
//! magic `CAUSTPS\0` (8), format version (4), scene hash (8), settings text (4 + n); the window
//! `x0 y0 x1 y1 full_width full_height` (4 each); first pass, passes, even passes (4 each); per
//! pixel the sum, the even and the odd sums (3 × 3 f32) and the samples (u32); CRC-32 (4).

use super::maps_file::Fingerprint;
use super::maps_file::format::{
    Kind, open, read_checksum, read_header, write_checksum, write_header,
};
use super::progressive::{Accumulator, MAX_PASSES};
use crate::error::{Error, Result};
use crate::film::{MAX_PIXELS, Window};
use crate::photon::file::CrcWriter;
use glam::Vec3A;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The pass file's kind.
const PASSES: Kind = Kind {
    magic: b"CAUSTPS\0",
    version: 1,
    name: "progressive pass file",
    writer: "caustic render --save-passes",
    again: "render the passes again",
};

/// Bytes a pixel takes: three sums of three `f32`, and a `u32` sample count.
const PIXEL_BYTES: u64 = 40;

/// A progressive render's passes, as saved.
#[derive(Debug)]
pub struct SavedPasses {
    pub fingerprint: Fingerprint,
    pub sums: Accumulator,
}

/// Writes `passes` to `path`, replacing it atomically ([`crate::files::write_replacing_io`]).
pub fn write(path: &Path, passes: &SavedPasses) -> std::io::Result<()> {
    crate::files::write_replacing_io(path, |file| {
        let mut w = CrcWriter::new(BufWriter::with_capacity(1 << 20, file));
        write_header(&mut w, &PASSES, &passes.fingerprint)?;
        let a = &passes.sums;
        for v in a.window.to_array() {
            w.write_all(&v.to_le_bytes())?;
        }
        for v in [a.first, a.passes, a.even_passes] {
            w.write_all(&v.to_le_bytes())?;
        }
        let mut buf = Vec::with_capacity(PIXEL_BYTES as usize * 4096);
        for i in 0..a.sum.len() {
            for v in [a.sum[i], a.even[i], a.odd[i]] {
                buf.extend(v.to_array().iter().flat_map(|x| x.to_le_bytes()));
            }
            buf.extend(a.samples[i].to_le_bytes());
            if buf.len() >= PIXEL_BYTES as usize * 4096 {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)?;
        write_checksum(&mut w)
    })
}

/// What a pass file says before its sums.
struct Head {
    fingerprint: Fingerprint,
    window: Window,
    first: u32,
    passes: u32,
    even_passes: u32,
}

/// Reads a pass file's header from `r` (of a file of `size` bytes), refusing a window or a
/// range of passes that cannot be, or a window larger than the file holds.
fn read_head<R: std::io::Read>(
    r: &mut crate::photon::file::CrcReader<R>,
    size: u64,
) -> std::result::Result<Head, String> {
    let fingerprint = read_header(r, &PASSES)?;
    let mut v = [0u32; 9];
    for x in &mut v {
        *x = r.u32("the header")?;
    }
    let window = Window::from_array([v[0], v[1], v[2], v[3], v[4], v[5]]);
    let [first, passes, even_passes] = [v[6], v[7], v[8]];
    let pixels = u64::from(window.full_width) * u64::from(window.full_height);
    if !window.is_valid() || pixels > MAX_PIXELS {
        return Err(format!(
            "the window {:?} (x0, y0, x1, y1 of a width x height image) cannot be",
            window.to_array()
        ));
    }
    let (w, h) = window.size();
    if (u64::from(w) * u64::from(h)).saturating_mul(PIXEL_BYTES) > size {
        return Err(format!(
            "a {w}x{h} window, more than the file's {size} bytes hold"
        ));
    }
    if passes == 0
        || even_passes > passes
        || u64::from(first) + u64::from(passes) > u64::from(MAX_PASSES)
    {
        return Err(format!(
            "passes {first} to {} ({even_passes} of them even) cannot be",
            u64::from(first) + u64::from(passes)
        ));
    }
    Ok(Head {
        fingerprint,
        window,
        first,
        passes,
        even_passes,
    })
}

/// Returns the first pass the file at `path` holds, from its header alone (the merge orders
/// the files by it before reading any sums).
fn first_pass(path: &Path) -> std::result::Result<u32, String> {
    let (mut r, size) = open(path)?;
    Ok(read_head(&mut r, size)?.first)
}

/// Reads the passes saved at `path`; the error says what is wrong with the file.
pub fn read(path: &Path) -> std::result::Result<SavedPasses, String> {
    let (mut r, size) = open(path)?;
    let head = read_head(&mut r, size)?;
    let mut sums = Accumulator::starting_at(head.window, head.first);
    (sums.passes, sums.even_passes) = (head.passes, head.even_passes);
    let mut px = [0u8; PIXEL_BYTES as usize];
    for i in 0..sums.sum.len() {
        r.bytes(&mut px, "the sums")?;
        let f = |j: usize| f32::from_le_bytes([px[j], px[j + 1], px[j + 2], px[j + 3]]);
        let v = |k: usize| Vec3A::new(f(12 * k), f(12 * k + 4), f(12 * k + 8));
        let (s, e, o) = (v(0), v(1), v(2));
        if ![s, e, o]
            .iter()
            .all(|x| x.is_finite() && x.min_element() >= 0.0)
        {
            return Err(format!(
                "pixel {i}'s sums {s}, {e}, {o} are not finite and positive"
            ));
        }
        (sums.sum[i], sums.even[i], sums.odd[i]) = (s, e, o);
        sums.samples[i] = u32::from_le_bytes([px[36], px[37], px[38], px[39]]);
    }
    read_checksum(&mut r)?;
    Ok(SavedPasses {
        fingerprint: head.fingerprint,
        sums,
    })
}

/// Adds up the pass files `paths` into the sums of all their passes, reading one file at a
/// time in the order of their first pass (so at most two windows of sums are held, and the
/// sum does not depend on the order given); returns them with the first file's fingerprint,
/// or an error naming the file that cannot be read, whose fingerprint or window is not the
/// first file's, or whose passes do not follow the previous file's (they must run from pass
/// 0 without a gap or an overlap).
pub fn merge(paths: &[PathBuf]) -> Result<SavedPasses> {
    let bad = |path: &PathBuf, message: String| Error::File {
        path: path.clone(),
        message,
    };
    let mut order = paths
        .iter()
        .map(|p| first_pass(p).map(|f| (f, p)).map_err(|m| bad(p, m)))
        .collect::<Result<Vec<_>>>()?;
    order.sort_by_key(|o| o.0);
    let mut merged: Option<SavedPasses> = None;
    for (_, path) in order {
        let p = read(path).map_err(|m| bad(path, m))?;
        let Some(total) = merged.as_mut() else {
            if p.sums.first != 0 {
                let message = format!(
                    "these are passes {} to {}, but pass 0 comes next: passes are missing",
                    p.sums.first,
                    p.sums.first + p.sums.passes - 1
                );
                return Err(bad(path, message));
            }
            merged = Some(p);
            continue;
        };
        if p.fingerprint != total.fingerprint {
            return Err(bad(
                path,
                "these passes are of another render (another scene or other settings than the \
                 first part's)"
                    .into(),
            ));
        }
        if p.sums.window != total.sums.window {
            let message = "these passes cover another window than the first part's".into();
            return Err(bad(path, message));
        }
        let next = total.sums.first + total.sums.passes;
        if p.sums.first != next {
            let what = if p.sums.first > next {
                "missing"
            } else {
                "given twice"
            };
            return Err(bad(
                path,
                format!(
                    "these are passes {} to {}, but pass {next} comes next: passes are {what}",
                    p.sums.first,
                    p.sums.first + p.sums.passes - 1
                ),
            ));
        }
        total.sums.merge(&p.sums);
    }
    merged.ok_or_else(|| Error::Usage("caustic merge: no pass files given".into()))
}
