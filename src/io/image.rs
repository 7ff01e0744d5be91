//! Image output: PNG as the course writes it, written atomically.
//!
//! Each channel becomes `(u8)(255·clamp(c, 0, 1))`, truncating as the course's `Image::savePng`
//! does (0.999 → 254); 8-bit RGB, no alpha, no gamma, row 0 at the top. The file is written to a
//! temporary name beside the target and renamed over it, so a failed render never leaves a
//! truncated image where a good one was.

use crate::error::{Error, Result};
use crate::render::Film;
use std::path::Path;

/// Returns the film as 8-bit RGB bytes, row 0 first.
pub fn to_rgb8(film: &Film) -> Vec<u8> {
    film.pixels
        .iter()
        .flat_map(|c| c.to_array().map(|v| (255.0 * v.clamp(0.0, 1.0)) as u8))
        .collect()
}

/// Writes `film` as a PNG at `path`, atomically.
pub fn write_png(film: &Film, path: &Path) -> Result<()> {
    let fail = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let name = path
        .file_name()
        .ok_or_else(|| fail("output path names no file".into()))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let img = image::RgbImage::from_raw(film.width, film.height, to_rgb8(film))
        .ok_or_else(|| fail("internal: film size does not match its pixels".into()))?;
    img.save_with_format(&tmp, image::ImageFormat::Png)
        .map_err(|e| fail(format!("cannot write image: {e}")))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(format!("cannot write image: {e}"))
    })
}
