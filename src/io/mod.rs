//! Reading and writing files: meshes in, images out.
//!
//! Text formats (OBJ, MTL, glTF JSON, study CSVs) are read as real tools write them: a leading
//! UTF-8 byte-order mark (Windows editors, Excel's "CSV UTF-8") is dropped by [`strip_bom`]
//! before parsing, and lines may end in `\n` or `\r\n`.

pub mod exr;
pub mod gltf;
pub mod heatmap;
pub mod image;
pub mod mitsuba;
pub mod obj;
pub mod pfm;
pub mod stitch;

/// The UTF-8 encoding of U+FEFF, the byte-order mark some editors put at the start of a file.
pub const UTF8_BOM: &[u8; 3] = b"\xEF\xBB\xBF";

/// Returns `bytes` without a leading UTF-8 byte-order mark, if it has one.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(UTF8_BOM).unwrap_or(bytes)
}
