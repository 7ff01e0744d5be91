//! OpenEXR out and tiles back in, through the `exr` crate: linear 32-bit float RGB, lossless
//! (`exr`'s fast lossless encoding, RLE).
//!
//! **Windows.** OpenEXR says where a file's pixels sit in the image it belongs to: the *display
//! window* is the whole image, the *data window* the pixels the file holds. A film that is a
//! window of a larger image (`--crop`) is written with the full image as its display window and
//! the tile as its data window, so viewers (tev, Nuke, OpenImageIO) show it in place and
//! [`crate::io::stitch`] needs no record of its own. A full frame has the two equal, as before.
//! Text attributes (the note an interrupted render's image carries) go in the header.

use crate::film::{Film, Window};
use exr::meta::BlockDescription;
use exr::meta::header::Header;
use exr::prelude::*;
use glam::Vec3A;
use std::path::Path;

/// An EXR file read back: its place in its image, its pixels (row-major, row 0 at the top of the
/// data window) and its header's text attributes.
pub struct ExrTile {
    pub window: Window,
    pub pixels: Vec<Vec3A>,
    pub text: Vec<(String, String)>,
}

/// Writes `film` as an EXR file to `file` (open for writing, at its start), its window as the
/// data window in the full image's display window, with the text attributes `text` (ASCII keys
/// and values).
pub fn write(
    film: &Film,
    file: &mut std::fs::File,
    text: &[(&str, &str)],
) -> std::result::Result<(), String> {
    let (w, h) = (film.width as usize, film.height as usize);
    if film.pixels.len() != w * h {
        return Err("internal: film size does not match its pixels".into());
    }
    let win = film.window;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = film.pixels[p.y() * w + p.x()];
        (c.x, c.y, c.z)
    });
    let mut attributes = LayerAttributes {
        layer_position: Vec2(to_i32(win.x0)?, to_i32(win.y0)?),
        ..LayerAttributes::default()
    };
    for (key, value) in text {
        let ascii = |s: &str| Text::new_or_none(s).ok_or_else(|| format!("'{s}' is not ASCII"));
        attributes
            .other
            .insert(ascii(key)?, AttributeValue::Text(ascii(value)?));
    }
    let layer = Layer::new((w, h), attributes, Encoding::default(), channels);
    let display =
        IntegerBounds::from_dimensions((win.full_width as usize, win.full_height as usize));
    Image::new(ImageAttributes::new(display), layer)
        .write()
        .to_unbuffered(file)
        .map_err(|e| e.to_string())
}

/// Returns `v` as an EXR coordinate.
fn to_i32(v: u32) -> std::result::Result<i32, String> {
    i32::try_from(v).map_err(|_| format!("coordinate {v} is too large for OpenEXR"))
}

/// Bytes of decoded pixels a file may stand for beyond what [`max_expansion`] allows: a tiny
/// tile's headers and offset table weigh more than its pixels.
const DECODE_SLACK: u64 = 64 << 10;

/// Returns the most bytes of decoded pixels one byte of a file compressed with `compression`
/// can stand for: 1 uncompressed, 64 for run-length coding (a 2-byte run stands for at most
/// 128 bytes), and deflate's 1032 for the others (a bound for the Huffman and block codes too).
pub fn max_expansion(compression: Compression) -> u64 {
    match compression {
        Compression::Uncompressed => 1,
        Compression::RLE => 64,
        _ => 1032,
    }
}

/// Returns an error unless the one header of an EXR file of `file_len` bytes is one that
/// [`read()`] may allocate for: a single flat part (not multi-part, not deep) whose windows
/// and tiles hold at most `max_pixels`, and whose decoded pixels (as stored, and as the RGB
/// floats read) are no more than the file's compression can expand its bytes to.
fn check_header(
    meta: &MetaData,
    file_len: u64,
    max_pixels: u64,
) -> std::result::Result<&Header, String> {
    let header = match &meta.headers[..] {
        [] => return Err("an EXR with no layer".into()),
        [one] => one,
        parts => {
            return Err(format!(
                "a multi-part EXR ({} parts): a tile is a single-part image",
                parts.len()
            ));
        }
    };
    if header.deep {
        return Err("a deep EXR (samples per pixel): a tile is a flat image".into());
    }
    let display = header.shared_attributes.display_window;
    let mut sizes = vec![
        ("display window", display.size),
        ("data window", header.layer_size),
    ];
    if let BlockDescription::Tiles(t) = &header.blocks {
        sizes.push(("tile size", t.tile_size));
    }
    for (what, size) in sizes {
        let area = size.width() as u64 * size.height() as u64;
        if area > max_pixels {
            return Err(format!(
                "its {what} is {}x{}, larger than {max_pixels} pixels",
                size.width(),
                size.height()
            ));
        }
    }
    let area = header.layer_size.width() as u64 * header.layer_size.height() as u64;
    let per_pixel = (header.channels.bytes_per_pixel as u64).max(16);
    let most = max_expansion(header.compression).saturating_mul(file_len) + DECODE_SLACK;
    // The reader decodes a whole tile at once, however little of it the data window holds.
    if let BlockDescription::Tiles(t) = &header.blocks {
        let tile = t.tile_size.width() as u64 * t.tile_size.height() as u64;
        if tile.saturating_mul(per_pixel) > most {
            return Err(format!(
                "its {}x{} tiles are more than its {file_len} bytes can hold with {} \
                 compression: a damaged or forged header",
                t.tile_size.width(),
                t.tile_size.height(),
                header.compression
            ));
        }
    }
    if area.saturating_mul(per_pixel) > most {
        return Err(format!(
            "its {}x{} pixels ({} bytes a pixel decoded) are more than its {file_len} bytes \
             can hold with {} compression: a damaged or forged header",
            header.layer_size.width(),
            header.layer_size.height(),
            header.channels.bytes_per_pixel,
            header.compression
        ));
    }
    // The reader allocates an offset table of one u64 per chunk before it reads a pixel: a
    // file must hold at least those offsets.
    if (header.chunk_count as u64).saturating_mul(8) > file_len {
        return Err(format!(
            "its header claims {} chunks, more than its {file_len} bytes can index: a damaged \
             or forged header",
            header.chunk_count
        ));
    }
    Ok(header)
}

/// Reads the EXR file at `path` as a tile: its window (the data window's place in the display
/// window), RGB pixels and text attributes; a message says what is wrong otherwise. Files whose
/// windows hold more than `max_pixels`, multi-part and deep files, and files whose header
/// claims more pixels than their bytes can hold ([`max_expansion`]) are refused before their
/// pixels are read.
pub fn read(path: &Path, max_pixels: u64) -> std::result::Result<ExrTile, String> {
    let file_len = std::fs::metadata(path)
        .map_err(|e| format!("cannot read it: {e}"))?
        .len();
    let meta =
        MetaData::read_from_file(path, false).map_err(|e| format!("not a readable EXR: {e}"))?;
    let header = check_header(&meta, file_len, max_pixels)?;
    let display = header.shared_attributes.display_window;
    let data = (header.own_attributes.layer_position, header.layer_size);
    let window = place(display, data).ok_or_else(|| {
        format!(
            "its data window ({}, {}) {}x{} is not inside its display window ({}, {}) {}x{}",
            data.0.x(),
            data.0.y(),
            data.1.width(),
            data.1.height(),
            display.position.x(),
            display.position.y(),
            display.size.width(),
            display.size.height()
        )
    })?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![Vec3A::ZERO; size.area()]),
            |(w, px): &mut (usize, Vec<Vec3A>), p, (r, g, b): (f32, f32, f32)| {
                px[p.y() * *w + p.x()] = Vec3A::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("cannot read its RGB pixels: {e}"))?;
    let layer = image.layer_data;
    if layer.size != data.1 || layer.attributes.layer_position != data.0 {
        return Err("its RGB layer is not its first layer".into());
    }
    let text = layer
        .attributes
        .other
        .iter()
        .chain(&image.attributes.other)
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok(ExrTile {
        window,
        pixels: layer.channel_data.pixels.1,
        text,
    })
}

/// Returns the window the data window `(position, size)` is in `display`, or `None` when it is
/// empty or not inside it.
fn place(display: IntegerBounds, (position, size): (Vec2<i32>, Vec2<usize>)) -> Option<Window> {
    let offset = |p: i32, d: i32| u32::try_from(p as i64 - d as i64).ok();
    let x0 = offset(position.x(), display.position.x())?;
    let y0 = offset(position.y(), display.position.y())?;
    let window = Window {
        x0,
        y0,
        x1: x0.checked_add(u32::try_from(size.width()).ok()?)?,
        y1: y0.checked_add(u32::try_from(size.height()).ok()?)?,
        full_width: u32::try_from(display.size.width()).ok()?,
        full_height: u32::try_from(display.size.height()).ok()?,
    };
    window.is_valid().then_some(window)
}
