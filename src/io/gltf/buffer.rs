//! The bytes behind a glTF document: the GLB container, buffers (GLB `BIN` chunk, base64 data
//! URIs, external files) and bounds-checked accessor reads.
//!
//! Nothing here trusts the file: every offset, length, stride and count is checked with
//! overflow-free arithmetic before a byte is read, and faults come back as messages that the
//! caller prefixes with the file name.

use base64::Engine;
use glam::{Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use std::path::{Path, PathBuf};

/// The `glTF` magic that opens every GLB file.
pub const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Reads a little-endian `u32` at `at`, or `None` past the end.
fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB file into its JSON chunk and optional `BIN` chunk.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let truncated = || "truncated GLB file".to_owned();
    let version = u32_at(bytes, 4).ok_or_else(truncated)?;
    if version != 2 {
        return Err(format!(
            "GLB version {version} is not supported (glTF 2.0 only)"
        ));
    }
    let length = u32_at(bytes, 8).ok_or_else(truncated)? as usize;
    if length > bytes.len() {
        return Err(format!(
            "truncated GLB file: header says {length} bytes, file has {}",
            bytes.len()
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < bytes.len() {
        let len = u32_at(bytes, at).ok_or_else(truncated)? as usize;
        let kind = u32_at(bytes, at + 4).ok_or_else(truncated)?;
        let start = at + 8;
        let data = start
            .checked_add(len)
            .and_then(|end| bytes.get(start..end))
            .ok_or_else(|| format!("truncated GLB file: chunk at byte {at} runs past the end"))?;
        chunks.push((kind, data));
        at = start + len;
    }
    match chunks.as_slice() {
        [(CHUNK_JSON, json), rest @ ..] => {
            let bin = rest.first().filter(|(k, _)| *k == CHUNK_BIN).map(|c| c.1);
            Ok((json, bin))
        }
        _ => Err("GLB file does not start with a JSON chunk".to_owned()),
    }
}

/// Returns the percent-decoded form of a URI reference (`%20` → space).
pub fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[i],
            bytes.get(i + 1).copied(),
            bytes.get(i + 2).copied(),
        ) {
            (b'%', Some(h), Some(l)) if hex(h).is_some() && hex(l).is_some() => {
                out.push((hex(h).unwrap_or(0) * 16 + hex(l).unwrap_or(0)) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Returns the file a relative URI names, resolved against `dir`; `None` for `data:` URIs.
pub fn uri_path(uri: &str, dir: &Path) -> Option<PathBuf> {
    (!uri.starts_with("data:")).then(|| dir.join(percent_decode(uri)))
}

/// Loads every buffer of the document; `bin` is the GLB `BIN` chunk, if any; a buffer file
/// must lie in `scope`.
pub fn load_buffers(
    doc: &gltf::Document,
    bin: Option<&[u8]>,
    dir: &Path,
    scope: &crate::files::ReadScope,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => match (i, bin) {
                (0, Some(bin)) => bin.to_vec(),
                _ => {
                    return Err(format!(
                        "buffer {i} has no uri and there is no GLB BIN chunk"
                    ));
                }
            },
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => decode_data_uri(data).map_err(|e| format!("buffer {i}: {e}"))?,
                None => {
                    let file = dir.join(percent_decode(uri));
                    scope
                        .check(&file)
                        .and_then(|()| crate::files::read_regular(&file))
                        .map_err(|e| format!("buffer {i}: cannot read {}: {e}", file.display()))?
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} declares {} bytes but holds only {}",
                buffer.length(),
                data.len()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Decodes the part of a `data:` URI after the scheme; only base64 payloads are accepted.
pub fn decode_data_uri(data: &str) -> Result<Vec<u8>, String> {
    let Some((_, payload)) = data.split_once(";base64,") else {
        return Err("data URI is not base64".to_owned());
    };
    base64::engine::general_purpose::STANDARD
        .decode(payload)
        .map_err(|e| format!("bad base64 in data URI: {e}"))
}

/// Returns the glTF spelling of an accessor's element type, for messages.
fn type_name(dims: Dimensions, data: DataType) -> String {
    let dims = match dims {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    };
    let data = match data {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    };
    format!("{dims} of {data}")
}

/// One accessor's elements, checked to lie inside their buffer view and buffer.
struct Elements<'b> {
    bytes: &'b [u8],
    stride: usize,
    size: usize,
    count: usize,
}

impl<'b> Elements<'b> {
    /// Returns the bytes of element `i` (in range by construction).
    fn get(&self, i: usize) -> &'b [u8] {
        let start = i * self.stride;
        &self.bytes[start..start + self.size]
    }
}

/// Checks an accessor against the loaded buffers and returns its elements.
fn elements<'b>(acc: &gltf::Accessor, buffers: &'b [Vec<u8>]) -> Result<Elements<'b>, String> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(format!("accessor {i} is sparse (not supported)"));
    }
    let Some(view) = acc.view() else {
        return Err(format!("accessor {i} has no buffer view (not supported)"));
    };
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "buffer view {} has stride {stride}, less than accessor {i}'s {size}-byte elements",
            view.index()
        ));
    }
    let data = buffers
        .get(view.buffer().index())
        .map_or(&[][..], Vec::as_slice);
    let view_end = view.offset().checked_add(view.length());
    let Some(view_bytes) = view_end.and_then(|end| data.get(view.offset()..end)) else {
        return Err(format!(
            "buffer view {} (bytes {}..+{}) lies outside buffer {} ({} bytes)",
            view.index(),
            view.offset(),
            view.length(),
            view.buffer().index(),
            data.len()
        ));
    };
    let count = acc.count();
    let needed = match count {
        0 => Some(0),
        n => (n - 1)
            .checked_mul(stride)
            .and_then(|b| b.checked_add(size))
            .and_then(|b| b.checked_add(acc.offset())),
    };
    match needed {
        Some(end) if end <= view_bytes.len() => Ok(Elements {
            bytes: &view_bytes[acc.offset().min(view_bytes.len())..],
            stride,
            size,
            count,
        }),
        _ => Err(format!(
            "accessor {i} ({count} elements from byte {}) runs past the end of buffer view {} ({} bytes)",
            acc.offset(),
            view.index(),
            view_bytes.len()
        )),
    }
}

/// Returns the `k`-th little-endian component of `bytes` as `f32`, normalising integers to [0, 1].
fn component(bytes: &[u8], k: usize, data: DataType) -> f32 {
    match data {
        DataType::F32 => {
            let b = &bytes[4 * k..4 * k + 4];
            f32::from_le_bytes([b[0], b[1], b[2], b[3]])
        }
        DataType::U8 => bytes[k] as f32 / 255.0,
        DataType::U16 => u16::from_le_bytes([bytes[2 * k], bytes[2 * k + 1]]) as f32 / 65535.0,
        _ => 0.0,
    }
}

/// Reads a `VEC3` of `FLOAT` accessor (positions, normals); `what` names it in messages.
pub fn read_vec3(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<Vec3>, String> {
    let (dims, data) = (acc.dimensions(), acc.data_type());
    if dims != Dimensions::Vec3 || data != DataType::F32 {
        return Err(format!(
            "{what} accessor {} must be VEC3 of FLOAT, found {}",
            acc.index(),
            type_name(dims, data)
        ));
    }
    let e = elements(acc, buffers)?;
    let v: Vec<Vec3> = (0..e.count)
        .map(|i| {
            let b = e.get(i);
            Vec3::new(
                component(b, 0, data),
                component(b, 1, data),
                component(b, 2, data),
            )
        })
        .collect();
    if let Some(bad) = v.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "{what} {bad} of accessor {} is not finite",
            acc.index()
        ));
    }
    if what == "position"
        && let Some((bad, e)) = v
            .iter()
            .enumerate()
            .find_map(|(i, p)| crate::range::coordinate(p.to_array()).err().map(|e| (i, e)))
    {
        return Err(format!("position {bad} of accessor {}: {e}", acc.index()));
    }
    Ok(v)
}

/// Reads a `VEC2` texture-coordinate accessor: `FLOAT`, or normalised `UNSIGNED_BYTE`/`SHORT`.
pub fn read_uvs(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<Vec2>, String> {
    let (dims, data) = (acc.dimensions(), acc.data_type());
    let float = data == DataType::F32;
    let unorm = acc.normalized() && matches!(data, DataType::U8 | DataType::U16);
    if dims != Dimensions::Vec2 || !(float || unorm) {
        return Err(format!(
            "TEXCOORD_0 accessor {} must be VEC2 of FLOAT or normalized unsigned integers, found {}",
            acc.index(),
            type_name(dims, data)
        ));
    }
    let e = elements(acc, buffers)?;
    let v: Vec<Vec2> = (0..e.count)
        .map(|i| Vec2::new(component(e.get(i), 0, data), component(e.get(i), 1, data)))
        .collect();
    match v.iter().position(|t| !t.is_finite()) {
        Some(bad) => Err(format!(
            "texture coordinate {bad} of accessor {} is not finite",
            acc.index()
        )),
        None => Ok(v),
    }
}

/// Reads a `SCALAR` index accessor of `UNSIGNED_BYTE`, `UNSIGNED_SHORT` or `UNSIGNED_INT`.
pub fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let (dims, data) = (acc.dimensions(), acc.data_type());
    if dims != Dimensions::Scalar || !matches!(data, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(format!(
            "index accessor {} must be SCALAR of unsigned integers, found {}",
            acc.index(),
            type_name(dims, data)
        ));
    }
    let e = elements(acc, buffers)?;
    Ok((0..e.count)
        .map(|i| {
            let b = e.get(i);
            match data {
                DataType::U8 => b[0] as u32,
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_percent_escapes_and_resolves_uris() {
        assert_eq!(percent_decode("my%20mesh.bin"), "my mesh.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%zz%4"), "%zz%4");
        let dir = Path::new("models");
        assert_eq!(uri_path("a%20b.png", dir), Some(dir.join("a b.png")));
        assert_eq!(uri_path("data:image/png;base64,AAAA", dir), None);
    }

    #[test]
    fn rejects_malformed_glb_containers() {
        let header = |len: u32| [&b"glTF"[..], &2u32.to_le_bytes(), &len.to_le_bytes()].concat();
        assert_eq!(split_glb(b"glTF").unwrap_err(), "truncated GLB file");
        let mut v1 = header(12);
        v1[4] = 1;
        assert!(split_glb(&v1).unwrap_err().contains("version 1"));
        assert!(
            split_glb(&header(99))
                .unwrap_err()
                .contains("header says 99")
        );
        assert!(split_glb(&header(12)).unwrap_err().contains("JSON chunk"));
        let glb = |total: u32, data: &[u8]| {
            let mut v = header(total);
            v.extend(8u32.to_le_bytes());
            v.extend(CHUNK_JSON.to_le_bytes());
            v.extend(data);
            v
        };
        let short = glb(24, b"{}  ");
        assert!(split_glb(&short).unwrap_err().contains("runs past the end"));
        let whole = glb(28, b"{}      ");
        assert_eq!(split_glb(&whole).unwrap(), (&b"{}      "[..], None));
    }
}
