//! Image output: PNG as the course writes it, OpenEXR for linear floats, tiles and their stitching.
//!
//! **Tone mapping** ([`Tonemap`]) turns linear radiance into 8 bits:
//! - `clamp` (the default, the course's `Image::savePng`): `(u8)(255·clamp(c, 0, 1))`, truncating
//!   (0.999 → 254), no gamma;
//! - `srgb`: multiply by `2^exposure`, clamp to [0, 1], apply the sRGB transfer curve, round.
//!
//! **Formats** ([`Format`], chosen by the output's extension, any case): `.png` is 8-bit RGB
//! through the tone map, row 0 at the top; the others are linear radiance, no tone mapping:
//! `.exr` 32-bit float RGB OpenEXR, `.pfm` the Portable Float Map ([`super::pfm`], exact f32), and
//! `.hdr` Radiance RGBE (a shared 8-bit exponent: about 1% relative precision, non-negative
//! values only), for tools that read one of these and not EXR. Any other extension is an error
//! listing these four. Every file is written to a temporary name beside the target and renamed
//! over it, so a failed or interrupted render never leaves a truncated image where a good one was
//! ([`crate::files::write_replacing`]).
//!
//! **Tiles.** A PNG of a window of an image (`--crop`) carries a `tEXt` chunk `caustic-window`
//! with `x0 y0 x1 y1 full_width full_height`; an EXR records its data window in the full image's
//! display window ([`super::exr`]). [`super::stitch`] reads tiles back and assembles the full
//! image, byte-identical to a full render's.

use crate::error::{Error, Result};
use crate::film::{Film, MAX_PIXELS, Window};
use glam::Vec3A;
use std::io::{BufWriter, Write};
use std::path::Path;

/// The `tEXt` keyword that records a tile's place in its image.
pub const WINDOW_KEY: &str = "caustic-window";

/// The `tEXt` keyword (PNG) and header attribute (EXR) that mark the image of an interrupted
/// render and say what it holds ([`crate::interrupt`]).
pub const PARTIAL_KEY: &str = "caustic-partial";

/// Returns where an interrupted render's image of `out` goes: `NAME.partial.EXT` beside it.
pub fn partial_path(out: &Path) -> std::path::PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let name = match out.extension() {
        Some(ext) => format!("{stem}.partial.{}", ext.to_string_lossy()),
        None => format!("{stem}.partial"),
    };
    out.with_file_name(name)
}

/// How linear radiance becomes 8-bit pixel values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tonemap {
    /// Clamp to [0, 1] and truncate, as the course does.
    Clamp,
    /// Scale by `2^exposure`, clamp, encode with the sRGB curve, round.
    Srgb { exposure: f32 },
}

/// Returns the sRGB encoding of a linear value in [0, 1].
fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Returns the film as 8-bit RGB bytes, row 0 first.
pub fn to_rgb8(film: &Film, tonemap: Tonemap) -> Vec<u8> {
    let map = |v: f32| -> u8 {
        match tonemap {
            Tonemap::Clamp => (255.0 * v.clamp(0.0, 1.0)) as u8,
            Tonemap::Srgb { exposure } => {
                let v = (v * exposure.exp2()).clamp(0.0, 1.0);
                (255.0 * srgb_encode(v) + 0.5) as u8
            }
        }
    };
    film.pixels
        .iter()
        .flat_map(|c| c.to_array().map(map))
        .collect()
}

/// Returns the text of a PNG tile's [`WINDOW_KEY`] record: `x0 y0 x1 y1 full_width full_height`.
pub(super) fn window_record(w: &Window) -> String {
    w.to_array().map(|v| v.to_string()).join(" ")
}

/// Returns the window a [`WINDOW_KEY`] record's text names ([`window_record`]), or `None`
/// unless its words that read as unsigned integers are six.
pub(super) fn parse_window_record(text: &str) -> Option<Window> {
    let v: Vec<u32> = text
        .split_whitespace()
        .filter_map(|s| s.parse().ok())
        .collect();
    <[u32; 6]>::try_from(v).ok().map(Window::from_array)
}

/// Writes through `write` to a temporary file beside `path`'s target, created exclusively and
/// given to `write` open, then renames it over the target ([`crate::files::write_replacing`]:
/// symlinks followed, permissions kept, special files refused).
pub(super) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::result::Result<(), String>,
) -> Result<()> {
    crate::files::write_replacing(path, write).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!("cannot write image: {e}"),
    })
}

/// Encodes 8-bit RGB (`channels = 3`) or grey (`channels = 1`) rows as PNG, with `tEXt` chunks
/// of `text` (keyword, text).
pub(super) fn encode_png(
    out: impl Write,
    width: u32,
    height: u32,
    channels: u8,
    data: &[u8],
    text: &[(&str, String)],
) -> std::result::Result<(), String> {
    let mut enc = png::Encoder::new(out, width, height);
    enc.set_color(if channels == 1 {
        png::ColorType::Grayscale
    } else {
        png::ColorType::Rgb
    });
    enc.set_depth(png::BitDepth::Eight);
    for (keyword, text) in text {
        enc.add_text_chunk(keyword.to_string(), text.clone())
            .map_err(|e| e.to_string())?;
    }
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(data).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// The image formats caustic writes, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.png`: 8-bit RGB through the tone map.
    Png,
    /// `.exr`: linear 32-bit float RGB.
    Exr,
    /// `.pfm`: linear 32-bit float RGB, bottom row first ([`super::pfm`]).
    Pfm,
    /// `.hdr`: linear RGB as Radiance RGBE.
    Hdr,
}

/// The extensions [`output_format`] accepts, for messages.
const WRITTEN: &str = "caustic writes .png, .exr, .pfm and .hdr";

/// Returns the format `path`'s extension names (case-insensitive), or an error naming the
/// path: an unknown or missing extension is refused rather than written as PNG under that name.
pub fn output_format(path: &Path) -> Result<Format> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("png") => Ok(Format::Png),
        Some("exr") => Ok(Format::Exr),
        Some("pfm") => Ok(Format::Pfm),
        Some("hdr") => Ok(Format::Hdr),
        other => Err(Error::File {
            path: path.to_path_buf(),
            message: match other {
                Some(e) => format!("unknown output format '.{e}' ({WRITTEN})"),
                None => format!("the output has no extension ({WRITTEN})"),
            },
        }),
    }
}

/// Writes `film` at `path` in the format its extension names ([`output_format`]): PNG with
/// `tonemap`, or linear EXR, PFM or Radiance HDR. A film that is a window of a larger image
/// records its place (PNG and EXR).
pub fn write_image(film: &Film, path: &Path, tonemap: Tonemap) -> Result<()> {
    write_image_noted(film, path, tonemap, None)
}

/// Writes `film` as [`write_image`] does, marked when `partial` is given as the image of an
/// interrupted render, with that note saying what it holds: a [`PARTIAL_KEY`] `tEXt` chunk in a
/// PNG, an attribute of that name in an EXR (PFM and HDR have no place for it).
pub fn write_image_noted(
    film: &Film,
    path: &Path,
    tonemap: Tonemap,
    partial: Option<&str>,
) -> Result<()> {
    let mut text = Vec::new();
    if let Some(note) = partial {
        text.push((PARTIAL_KEY, note.to_string()));
    }
    match output_format(path)? {
        Format::Png => {}
        Format::Exr => {
            let text: Vec<(&str, &str)> = text.iter().map(|(k, v)| (*k, v.as_str())).collect();
            return write_atomically(path, |file| super::exr::write(film, file, &text));
        }
        Format::Pfm => {
            let bytes = super::pfm::encode(film.width, film.height, &film.pixels);
            return write_atomically(path, |file| {
                file.write_all(&bytes).map_err(|e| e.to_string())
            });
        }
        Format::Hdr => {
            // RGBE has no sign: radiance is never negative, but clamp what rounding may leave.
            let rgb: Vec<image::Rgb<f32>> = film
                .pixels
                .iter()
                .map(|c| image::Rgb(c.max(Vec3A::ZERO).to_array()))
                .collect();
            let (w, h) = (film.width as usize, film.height as usize);
            return write_atomically(path, |file| {
                let mut out = BufWriter::new(file);
                image::codecs::hdr::HdrEncoder::new(&mut out)
                    .encode(&rgb, w, h)
                    .map_err(|e| e.to_string())?;
                out.flush().map_err(|e| e.to_string())
            });
        }
    }
    // Every PNG says where it lies in its image, a whole image too: one band covering the image
    // is a tile `caustic stitch` takes (a render farm of one node).
    text.push((WINDOW_KEY, window_record(&film.window)));
    let data = to_rgb8(film, tonemap);
    write_atomically(path, |file| {
        let mut out = BufWriter::new(file);
        encode_png(&mut out, film.width, film.height, 3, &data, &text)?;
        out.flush().map_err(|e| e.to_string())
    })
}

/// Writes `film` as a course-style PNG (clamped, truncated) at `path`.
pub fn write_png(film: &Film, path: &Path) -> Result<()> {
    write_image(film, path, Tonemap::Clamp)
}

/// Writes the per-pixel sample counts of `film` as a grey PNG, white = the most samples.
pub fn write_sample_map(film: &Film, path: &Path) -> Result<()> {
    let max = film.samples.iter().copied().max().unwrap_or(1).max(1) as f32;
    let data: Vec<u8> = film
        .samples
        .iter()
        .map(|&n| (255.0 * n as f32 / max + 0.5) as u8)
        .collect();
    write_atomically(path, |file| {
        let mut out = BufWriter::new(file);
        encode_png(&mut out, film.width, film.height, 1, &data, &[])?;
        out.flush().map_err(|e| e.to_string())
    })
}

/// Writes 8-bit RGB `data` (`width × height`, row-major) as a PNG at `path`, atomically
/// (difference pictures, plots).
pub fn write_rgb8_png(path: &Path, width: u32, height: u32, data: &[u8]) -> Result<()> {
    write_atomically(path, |file| {
        let mut out = BufWriter::new(file);
        encode_png(&mut out, width, height, 3, data, &[])?;
        out.flush().map_err(|e| e.to_string())
    })
}

/// Writes 8-bit RGB `data` of a whole `width × height` render (a stitched image) as PNG, with
/// the window record every rendered PNG carries ([`WINDOW_KEY`]), replacing `path` atomically.
pub(super) fn write_render_png(path: &Path, width: u32, height: u32, data: &[u8]) -> Result<()> {
    let record = window_record(&Window::full(width, height));
    write_atomically(path, |file| {
        let mut out = BufWriter::new(file);
        encode_png(&mut out, width, height, 3, data, &[(WINDOW_KEY, record)])?;
        out.flush().map_err(|e| e.to_string())
    })
}

/// Reads the PNG, JPEG, EXR, PFM or Radiance HDR image at `path` as linear RGB for
/// [`crate::metrics`]: the float formats as stored, 8-bit formats as their codes over 255 (not
/// sRGB-decoded, so two PNGs compare as they are written). The image crate's default limits, and
/// [`MAX_PIXELS`] for PFM, bound the decoded size.
pub fn read_rgb(path: &Path) -> Result<crate::metrics::Image> {
    let fail = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    if output_format(path).ok() == Some(Format::Pfm) {
        // The largest PFM read: MAX_PIXELS colour pixels and a generous header.
        let most = MAX_PIXELS * 12 + 4096;
        let bytes = std::fs::metadata(path)
            .and_then(|m| match m.len() {
                n if n > most => Err(std::io::Error::other(format!(
                    "{n} bytes is more than a PFM of {MAX_PIXELS} pixels holds"
                ))),
                _ => crate::files::read_regular(path),
            })
            .map_err(|e| fail(format!("cannot read image: {e}")))?;
        let (width, height, pixels) =
            super::pfm::decode(&bytes, MAX_PIXELS).map_err(|e| fail(format!("bad PFM: {e}")))?;
        return Ok(crate::metrics::Image {
            width,
            height,
            pixels,
        });
    }
    let img = image::ImageReader::open(path)
        .map_err(|e| fail(format!("cannot read image: {e}")))?
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read image: {e}")))?
        .decode()
        .map_err(|e| fail(format!("not a readable PNG, JPEG, EXR or HDR image: {e}")))?
        .to_rgb32f();
    let (width, height) = img.dimensions();
    let pixels = img.pixels().map(|p| Vec3A::new(p[0], p[1], p[2])).collect();
    Ok(crate::metrics::Image {
        width,
        height,
        pixels,
    })
}
