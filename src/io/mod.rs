//! File formats: meshes and textures in, images out, each format one module.
//!
//! - [`obj`] (with MTL) and [`gltf`] (glTF 2.0 and GLB): meshes and their materials in, and
//!   written out for the generated meshes' cache and `caustic export`;
//! - [`image`]: textures in (PNG, JPEG, EXR, PFM, HDR) and films out, by extension, written
//!   atomically ([`crate::files`]); [`exr`] and [`pfm`] are the formats written by hand;
//! - [`stitch`]: tiles of a farm render back into one image (`caustic stitch`);
//! - [`heatmap`]: per-pixel traversal counts as a picture (`--heatmap`), with [`font`] for the
//!   text of every picture caustic draws.
//!
//! A scene written for another renderer (`caustic export-mitsuba`) is the scene's own
//! (`crate::scene::mitsuba`): this floor sits below the scene and knows nothing of it.
//!
//! Text formats (OBJ, MTL, glTF JSON, study CSVs) are read as real tools write them: a leading
//! UTF-8 byte-order mark (Windows editors, Excel's "CSV UTF-8") is dropped by [`strip_bom`]
//! before parsing, and lines may end in `\n` or `\r\n`.

pub mod exr;
pub mod font;
pub mod gltf;
pub mod heatmap;
pub mod image;
pub mod obj;
pub mod pfm;
pub mod stitch;

/// The UTF-8 encoding of U+FEFF, the byte-order mark some editors put at the start of a file.
pub const UTF8_BOM: &[u8; 3] = b"\xEF\xBB\xBF";

/// Returns `bytes` without a leading UTF-8 byte-order mark, if it has one.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(UTF8_BOM).unwrap_or(bytes)
}
