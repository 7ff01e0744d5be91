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
//! when read.
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
        let win = a.window;
        for v in [
            win.x0,
            win.y0,
            win.x1,
            win.y1,
            win.full_width,
            win.full_height,
        ] {
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

/// Reads the passes saved at `path`; the error says what is wrong with the file.
pub fn read(path: &Path) -> std::result::Result<SavedPasses, String> {
    let (mut r, size) = open(path)?;
    let fingerprint = read_header(&mut r, &PASSES)?;
    let mut v = [0u32; 9];
    for x in &mut v {
        *x = r.u32("the header")?;
    }
    let [
        x0,
        y0,
        x1,
        y1,
        full_width,
        full_height,
        first,
        passes,
        even_passes,
    ] = v;
    let window = Window {
        x0,
        y0,
        x1,
        y1,
        full_width,
        full_height,
    };
    let pixels = u64::from(full_width) * u64::from(full_height);
    if !window.is_valid() || pixels > MAX_PIXELS {
        return Err(format!(
            "the window {x0},{y0},{x1},{y1} of a {full_width}x{full_height} image cannot be"
        ));
    }
    let (w, h) = window.size();
    let n = u64::from(w) * u64::from(h);
    if n.saturating_mul(PIXEL_BYTES) > size {
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
    let mut sums = Accumulator::starting_at(window, first);
    (sums.passes, sums.even_passes) = (passes, even_passes);
    let mut px = [0u8; PIXEL_BYTES as usize];
    for i in 0..n as usize {
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
    Ok(SavedPasses { fingerprint, sums })
}

/// Adds up `parts` (each with the file it came from) into the sums of all their passes, or an
/// error naming the file whose fingerprint or window is not the first part's, or whose passes
/// do not follow the previous part's (the parts, sorted by first pass, must run from pass 0
/// without a gap or an overlap).
pub fn merge(mut parts: Vec<(PathBuf, SavedPasses)>) -> Result<Accumulator> {
    parts.sort_by_key(|p| p.1.sums.first);
    let Some((_, first)) = parts.first() else {
        return Err(Error::Usage("caustic merge: no pass files given".into()));
    };
    let (fingerprint, window) = (first.fingerprint.clone(), first.sums.window);
    let mut total = Accumulator::starting_at(window, 0);
    for (path, p) in &parts {
        let bad = |message: String| Error::File {
            path: path.clone(),
            message,
        };
        if p.fingerprint != fingerprint {
            return Err(bad(
                "these passes are of another render (another scene or other settings than the \
                 first part's)"
                    .into(),
            ));
        }
        if p.sums.window != window {
            return Err(bad(
                "these passes cover another window than the first part's".into(),
            ));
        }
        let next = total.first + total.passes;
        if p.sums.first != next {
            let what = if p.sums.first > next {
                "missing"
            } else {
                "given twice"
            };
            return Err(bad(format!(
                "these are passes {} to {}, but pass {next} comes next: passes are {what}",
                p.sums.first,
                p.sums.first + p.sums.passes - 1
            )));
        }
        total.merge(&p.sums);
    }
    Ok(total)
}
