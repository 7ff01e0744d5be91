//! Tiles and their stitching: the full image assembled from windows rendered apart (`--crop`),
//! byte-identical to a full render because every random stream is keyed by pixel and seed.
//!
//! A tile remembers its place in its image. A PNG tile carries a `tEXt` chunk
//! [`WINDOW_KEY`] with `x0 y0 x1 y1 full_width full_height`; an EXR
//! tile says it as OpenEXR does, its data window inside its display window ([`super::exr`]).
//! [`stitch`] reads tiles of one kind: PNG tiles make a PNG, EXR tiles a float image (EXR, PFM
//! or HDR) with every value as rendered. Every pixel must be covered by exactly one tile, all
//! tiles must belong to one image size, and a mix of PNG and EXR tiles is refused, as is the
//! marked image of an interrupted render.
//!
//! A tile is a file from anyone (a farm's workers): nothing is allocated from its header
//! before the header is bounded. Multi-part and deep EXRs are refused; windows and tile
//! sizes hold at most [`MAX_PIXELS`]; the pixels a header claims may not decode to more
//! than its file's bytes can expand to under its compression ([`super::exr::max_expansion`];
//! PNG: deflate's 1032 times); and overlaps and uncovered pixels are found before the map of
//! the whole image is made.

use super::image::{
    Format, PARTIAL_KEY, WINDOW_KEY, output_format, parse_window_record, window_record,
    write_image, write_render_png,
};
use crate::error::{Error, Result};
use crate::film::{Film, MAX_PIXELS, Window};
use glam::Vec3A;

use std::path::{Path, PathBuf};

/// What [`stitch`] wrote: the image's size and the tiles it took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stitched {
    pub width: u32,
    pub height: u32,
    pub tiles: usize,
}

/// A tile's pixels: 8-bit RGB codes (PNG) or linear radiance (EXR).
enum Pixels {
    Rgb8(Vec<[u8; 3]>),
    Float(Vec<Vec3A>),
}

/// A tile read back from disk: its window and pixels.
struct Tile {
    path: PathBuf,
    window: Window,
    pixels: Pixels,
}

impl Tile {
    /// Returns the format of the tile's file, for messages.
    fn kind(&self) -> &'static str {
        match self.pixels {
            Pixels::Rgb8(_) => "PNG",
            Pixels::Float(_) => "EXR",
        }
    }
}

/// Returns the error about the tile at `path`.
fn tile_error(path: &Path, message: String) -> Error {
    Error::File {
        path: path.to_path_buf(),
        message,
    }
}

/// Reads the tile at `path`: a PNG or EXR file written by `caustic render --crop`.
fn read_tile(path: &Path) -> Result<Tile> {
    let fail = |message: String| tile_error(path, message);
    crate::files::check_regular(path).map_err(|e| fail(format!("cannot read tile: {e}")))?;
    match output_format(path).ok() {
        Some(Format::Png) => read_png_tile(path),
        Some(Format::Exr) => {
            let t = super::exr::read(path, MAX_PIXELS).map_err(fail)?;
            if let Some((_, note)) = t.text.iter().find(|(k, _)| k == PARTIAL_KEY) {
                return Err(partial_tile(path, note));
            }
            Ok(Tile {
                path: path.to_path_buf(),
                window: t.window,
                pixels: Pixels::Float(t.pixels),
            })
        }
        _ => Err(fail(
            "is not a tile: tiles are the .png or .exr files `caustic render --crop` writes".into(),
        )),
    }
}

/// Returns an error unless `window` (the record `path` carries) is inside an image of at most
/// [`MAX_PIXELS`] and as large as the tile's `size`.
fn check_window(path: &Path, window: Window, (width, height): (u32, u32)) -> Result<()> {
    let w = window;
    let record = window_record(&w);
    if w.full_width as u64 * w.full_height as u64 > MAX_PIXELS {
        return Err(tile_error(
            path,
            format!(
                "its window record '{record}' describes a {}x{} image, larger than {MAX_PIXELS} pixels",
                w.full_width, w.full_height
            ),
        ));
    }
    if !w.is_valid() || w.size() != (width, height) {
        return Err(tile_error(
            path,
            format!("its window '{record}' does not match its {width}x{height} pixels"),
        ));
    }
    Ok(())
}

/// Returns the error about the tile at `path`, the image of an interrupted render (`note`).
fn partial_tile(path: &Path, note: &str) -> Error {
    tile_error(
        path,
        format!("is the image of an interrupted render ({note}); render the tile again"),
    )
}

/// Reads a PNG tile: 8-bit RGB with a [`WINDOW_KEY`] record.
fn read_png_tile(path: &Path) -> Result<Tile> {
    let fail = |message: String| tile_error(path, message);
    let file = std::fs::File::open(path).map_err(|e| fail(format!("cannot read tile: {e}")))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder
        .read_info()
        .map_err(|e| fail(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
        return Err(fail("not an 8-bit RGB tile written by caustic".into()));
    }
    let chunk = |key: &str| {
        info.uncompressed_latin1_text
            .iter()
            .find(|t| t.keyword == key)
    };
    if let Some(t) = chunk(PARTIAL_KEY) {
        return Err(partial_tile(path, &t.text));
    }
    let text = chunk(WINDOW_KEY).map(|t| t.text.clone()).ok_or_else(|| {
        fail(format!(
            "has no '{WINDOW_KEY}' record: was it rendered with --crop?"
        ))
    })?;
    let window = parse_window_record(&text)
        .ok_or_else(|| fail(format!("malformed '{WINDOW_KEY}' record '{text}'")))?;
    check_window(path, window, (width, height))?;
    // A PNG's pixels are deflated: refuse a header claiming more than its bytes can inflate to
    // before allocating for it (a 100-byte file may claim 8192x8192 pixels).
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    let most = 1032 * len + (64 << 10);
    if width as u64 * height as u64 * 3 > most {
        return Err(fail(format!(
            "its header claims {width}x{height} pixels, more than its {len} bytes can hold: a \
             damaged or forged PNG"
        )));
    }
    let mut rgb = vec![
        0;
        reader
            .output_buffer_size()
            .ok_or_else(|| fail("image too large".into()))?
    ];
    reader
        .next_frame(&mut rgb)
        .map_err(|e| fail(format!("truncated or corrupt PNG: {e}")))?;
    rgb.truncate(width as usize * height as usize * 3);
    let pixels = rgb.as_chunks::<3>().0.to_vec();
    Ok(Tile {
        path: path.to_path_buf(),
        window,
        pixels: Pixels::Rgb8(pixels),
    })
}

/// Assembles tiles written with `--crop` into the full image at `out` and returns what it
/// wrote; every pixel must be covered by exactly one tile (see the module doc).
pub fn stitch(tiles: &[PathBuf], out: &Path) -> Result<Stitched> {
    let format = output_format(out)?;
    let tiles: Vec<Tile> = tiles.iter().map(|p| read_tile(p)).collect::<Result<_>>()?;
    let Some(first) = tiles.first() else {
        return Err(Error::Usage("stitch needs at least one tile".into()));
    };
    if let Some(other) = tiles.iter().find(|t| t.kind() != first.kind()) {
        return Err(tile_error(
            &other.path,
            format!(
                "is {} but {} is {}: stitch tiles of one format (all PNG or all EXR)",
                other.kind(),
                first.path.display(),
                first.kind()
            ),
        ));
    }
    let is_png = matches!(first.pixels, Pixels::Rgb8(_));
    if is_png != (format == Format::Png) {
        let wanted = if is_png {
            "PNG tiles stitch into a PNG; name the output .png"
        } else {
            "EXR tiles stitch into a float image; name the output .exr, .pfm or .hdr"
        };
        return Err(tile_error(out, wanted.into()));
    }
    let (fw, fh) = (first.window.full_width, first.window.full_height);
    let owners = owners(&tiles, (fw, fh))?;
    let stitched = Stitched {
        width: fw,
        height: fh,
        tiles: tiles.len(),
    };
    if is_png {
        let rgb: Vec<u8> = gather(&tiles, &owners, fw, |p| match p {
            Pixels::Rgb8(v) => v,
            Pixels::Float(_) => &[],
        })
        .into_iter()
        .flatten()
        .collect();
        write_render_png(out, fw, fh, &rgb)?;
    } else {
        let pixels = gather(&tiles, &owners, fw, |p| match p {
            Pixels::Float(v) => v,
            Pixels::Rgb8(_) => &[],
        });
        let film = Film {
            width: fw,
            height: fh,
            samples: vec![0; pixels.len()],
            pixels,
            window: Window::full(fw, fh),
        };
        write_image(&film, out, super::image::Tonemap::Clamp)?;
    }
    Ok(stitched)
}

/// Returns, for every pixel of the `fw × fh` image, the index of the tile covering it, or an
/// error naming a tile of another image size, two overlapping tiles or an uncovered pixel.
fn owners(tiles: &[Tile], (fw, fh): (u32, u32)) -> Result<Vec<usize>> {
    let first = &tiles[0];
    if let Some(t) = tiles
        .iter()
        .find(|t| (t.window.full_width, t.window.full_height) != (fw, fh))
    {
        return Err(tile_error(
            &t.path,
            format!(
                "belongs to a {}x{} image, but {} to a {fw}x{fh} one",
                t.window.full_width,
                t.window.full_height,
                first.path.display()
            ),
        ));
    }
    // Overlaps, then pixels left uncovered, are found without the map of the whole image,
    // which a small tile claiming a large image would make us allocate: tiles that do not
    // overlap and hold fewer pixels than the image leave one uncovered.
    for (k, t) in tiles.iter().enumerate() {
        if let Some((y, x, j)) = tiles[..k]
            .iter()
            .enumerate()
            .filter_map(|(j, o)| overlap(t.window, o.window).map(|(x, y)| (y, x, j)))
            .min()
        {
            return Err(tile_error(
                &t.path,
                format!("overlaps {} at pixel ({x}, {y})", tiles[j].path.display()),
            ));
        }
    }
    let covered: u64 = tiles
        .iter()
        .map(|t| t.window.size().0 as u64 * t.window.size().1 as u64)
        .sum();
    if covered < fw as u64 * fh as u64 {
        return Err(uncovered(tiles, (fw, fh)));
    }
    let mut owner: Vec<Option<usize>> = vec![None; fw as usize * fh as usize];
    for (k, t) in tiles.iter().enumerate() {
        for y in t.window.y0..t.window.y1 {
            for x in t.window.x0..t.window.x1 {
                let i = (y * fw + x) as usize;
                if let Some(other) = owner[i] {
                    return Err(tile_error(
                        &t.path,
                        format!(
                            "overlaps {} at pixel ({x}, {y})",
                            tiles[other].path.display()
                        ),
                    ));
                }
                owner[i] = Some(k);
            }
        }
    }
    owner
        .iter()
        .enumerate()
        .map(|(i, o)| {
            o.ok_or_else(|| {
                Error::Usage(format!(
                    "the tiles leave pixel ({}, {}) of the {fw}x{fh} image uncovered",
                    i as u32 % fw,
                    i as u32 / fw
                ))
            })
        })
        .collect()
}

/// Returns the first pixel (in row order) that windows `a` and `b` share, if any.
fn overlap(a: Window, b: Window) -> Option<(u32, u32)> {
    let (x0, y0) = (a.x0.max(b.x0), a.y0.max(b.y0));
    (x0 < a.x1.min(b.x1) && y0 < a.y1.min(b.y1)).then_some((x0, y0))
}

/// Returns the error naming the first pixel (in row order) of the `fw × fh` image that no tile
/// covers, for tiles that cover fewer pixels than it has (so such a pixel exists).
fn uncovered(tiles: &[Tile], (fw, fh): (u32, u32)) -> Error {
    let inside = |t: &Tile, x: u32, y: u32| {
        (t.window.x0..t.window.x1).contains(&x) && (t.window.y0..t.window.y1).contains(&y)
    };
    let (x, y) = (0..fh)
        .flat_map(|y| (0..fw).map(move |x| (x, y)))
        .find(|&(x, y)| !tiles.iter().any(|t| inside(t, x, y)))
        .unwrap_or((0, 0));
    Error::Usage(format!(
        "the tiles leave pixel ({x}, {y}) of the {fw}x{fh} image uncovered"
    ))
}

/// Returns the full image's pixels, each taken from the tile `owners` names, through `pixels`
/// (the tile's pixels of the kind being stitched).
fn gather<T: Copy>(
    tiles: &[Tile],
    owners: &[usize],
    fw: u32,
    pixels: impl Fn(&Pixels) -> &[T],
) -> Vec<T> {
    owners
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let (x, y) = (i as u32 % fw, i as u32 / fw);
            let w = tiles[k].window;
            let j = (y - w.y0) * (w.x1 - w.x0) + (x - w.x0);
            pixels(&tiles[k].pixels)[j as usize]
        })
        .collect()
}
