//! The bytes behind a glTF document: the GLB container, buffers (GLB `BIN` chunk, base64 data
//! URIs, external files) and bounds-checked accessor reads.
//!
//! Nothing here trusts the file: every offset, length, stride and count is checked with
//! overflow-free arithmetic before a byte is read, and faults come back as messages that the
//! caller prefixes with the file name.
//!
//! A load streams: a GLB's `BIN` chunk and an external `.bin` file stay on disk
//! ([`Buffer::File`]) and an accessor is read in runs of [`RUN_BYTES`], each decoded into the
//! mesh before the next is read, so a load never holds a file's bytes and the mesh made of them
//! at once (a 943 MB GLB of 33.5M triangles peaked at 3.5 GiB when it was read whole and its
//! `BIN` chunk copied out). Data URIs, and a file handed over in memory, are [`Buffer::Bytes`].

use base64::Engine;
use glam::{Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use std::borrow::Cow;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The `glTF` magic that opens every GLB file.
pub const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Reads a little-endian `u32` at `at`, or `None` past the end.
pub fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB file into its JSON chunk and optional `BIN` chunk.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let (json, bin) = glb_chunks(bytes.len(), |at| u32_at(bytes, at))?;
    Ok((&bytes[json], bin.map(|b| &bytes[b])))
}

/// Returns where a GLB file's JSON chunk and optional `BIN` chunk lie, from the little-endian
/// words `word(at)` reads (`None` past the end) of a file of `size` bytes: the container is
/// checked without reading the chunks themselves, so a file on disk need not be read whole.
pub fn glb_chunks(
    size: usize,
    word: impl Fn(usize) -> Option<u32>,
) -> Result<(Range<usize>, Option<Range<usize>>), String> {
    let truncated = || "truncated GLB file".to_owned();
    let version = word(4).ok_or_else(truncated)?;
    if version != 2 {
        return Err(format!(
            "GLB version {version} is not supported (glTF 2.0 only)"
        ));
    }
    let length = word(8).ok_or_else(truncated)? as usize;
    if length > size {
        return Err(format!(
            "truncated GLB file: header says {length} bytes, file has {size}"
        ));
    }
    // Only the first two chunks matter (JSON, then BIN); later ones are ignored unread, as
    // glTF asks of chunks a reader does not know. Walking them would let a file of millions of
    // empty chunks cost two reads each from disk.
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length && chunks.len() < 2 {
        let len = word(at).ok_or_else(truncated)? as usize;
        let kind = word(at + 4).ok_or_else(truncated)?;
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&end| end <= length)
            .ok_or_else(|| format!("truncated GLB file: chunk at byte {at} runs past the end"))?;
        chunks.push((kind, start..end));
        at = end;
    }
    match chunks.as_slice() {
        [(CHUNK_JSON, json), rest @ ..] => {
            let bin = rest
                .first()
                .filter(|(k, _)| *k == CHUNK_BIN)
                .map(|c| c.1.clone());
            Ok((json.clone(), bin))
        }
        _ => Err("GLB file does not start with a JSON chunk".to_owned()),
    }
}

/// Bytes of an accessor read and decoded at a time from a file: small enough that a run adds
/// nothing to a load's peak, large enough that the reads cost nothing beside the decoding.
pub const RUN_BYTES: usize = 4 << 20;

/// A glTF buffer's bytes: in memory, or a span of a file read where an accessor or an image asks.
pub enum Buffer<'a> {
    /// A data URI's decoded bytes, or a GLB's `BIN` chunk of a file handed over in memory.
    Bytes(Cow<'a, [u8]>),
    /// `len` bytes of `file` from byte `offset`: a GLB's `BIN` chunk, or an external buffer.
    File {
        file: Mutex<std::fs::File>,
        offset: u64,
        len: usize,
    },
}

impl<'a> Buffer<'a> {
    /// Returns the regular file `path` as a buffer, without reading it.
    pub fn file(path: &Path) -> std::io::Result<Buffer<'static>> {
        let file = crate::files::open_regular(path)?;
        let len = usize::try_from(file.metadata()?.len()).unwrap_or(usize::MAX);
        Ok(Buffer::File {
            file: Mutex::new(file),
            offset: 0,
            len,
        })
    }

    /// Returns bytes `range` of the buffer as a buffer of their own (a file's stay unread).
    ///
    /// # Panics
    /// When `range` does not lie inside the buffer.
    pub fn span(self, range: Range<usize>) -> Buffer<'a> {
        assert!(range.start <= range.end && range.end <= self.len());
        match self {
            Buffer::Bytes(Cow::Borrowed(b)) => Buffer::Bytes(Cow::Borrowed(&b[range])),
            Buffer::Bytes(Cow::Owned(b)) => Buffer::Bytes(Cow::Owned(b[range].to_vec())),
            Buffer::File { file, offset, .. } => Buffer::File {
                file,
                offset: offset + range.start as u64,
                len: range.len(),
            },
        }
    }

    /// Returns the buffer's length in bytes.
    pub fn len(&self) -> usize {
        match self {
            Buffer::Bytes(b) => b.len(),
            Buffer::File { len, .. } => *len,
        }
    }

    /// Returns bytes `start..start + len` of the buffer, or an error when they do not lie
    /// inside it; a file that shrank since it was opened is an error too, not a panic.
    pub fn read(&self, start: usize, len: usize) -> Result<Cow<'_, [u8]>, String> {
        if start.checked_add(len).is_none_or(|end| end > self.len()) {
            return Err(format!("bytes {start}..+{len} lie outside the buffer"));
        }
        match self {
            Buffer::Bytes(b) => Ok(Cow::Borrowed(&b[start..start + len])),
            Buffer::File { file, offset, .. } => {
                use std::io::{Read, Seek, SeekFrom};
                let mut out = vec![0; len];
                let mut file = file
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                file.seek(SeekFrom::Start(offset + start as u64))
                    .and_then(|_| file.read_exact(&mut out))
                    .map_err(|e| format!("cannot read bytes {start}..+{len} of the file: {e}"))?;
                Ok(Cow::Owned(out))
            }
        }
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

/// Returns every buffer of the document; `bin` is the GLB `BIN` chunk, if any; a buffer file
/// must lie in `scope` (it is opened, not read).
pub fn load_buffers<'a>(
    doc: &gltf::Document,
    mut bin: Option<Buffer<'a>>,
    dir: &Path,
    scope: &crate::files::ReadScope,
) -> Result<Vec<Buffer<'a>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => match (i, bin.take()) {
                (0, Some(bin)) => bin,
                _ => {
                    return Err(format!(
                        "buffer {i} has no uri and there is no GLB BIN chunk"
                    ));
                }
            },
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => Buffer::Bytes(Cow::Owned(
                    decode_data_uri(data).map_err(|e| format!("buffer {i}: {e}"))?,
                )),
                None => {
                    let file = dir.join(percent_decode(uri));
                    scope
                        .check(&file)
                        .and_then(|()| Buffer::file(&file))
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

/// A run of an accessor's elements, in memory.
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

/// An accessor's elements, checked to lie inside their buffer view and buffer: `count`
/// elements of `size` bytes, `stride` apart, from byte `start` of `buffer`.
struct Span<'b, 'a> {
    buffer: &'b Buffer<'a>,
    start: usize,
    stride: usize,
    size: usize,
    count: usize,
}

impl Span<'_, '_> {
    /// Calls `each` on the elements in order, a run of at most [`RUN_BYTES`] at a time, with
    /// the index of the run's first element; stops at the first error.
    fn runs(
        &self,
        mut each: impl FnMut(usize, &Elements) -> Result<(), String>,
    ) -> Result<(), String> {
        let per_run = (RUN_BYTES / self.stride.max(1)).max(1);
        let mut first = 0;
        while first < self.count {
            let count = per_run.min(self.count - first);
            let len = (count - 1) * self.stride + self.size;
            let bytes = self.buffer.read(self.start + first * self.stride, len)?;
            each(
                first,
                &Elements {
                    bytes: &bytes,
                    stride: self.stride,
                    size: self.size,
                    count,
                },
            )?;
            first += count;
        }
        Ok(())
    }
}

/// Checks an accessor against the buffers and returns where its elements lie.
fn elements<'b, 'a>(
    acc: &gltf::Accessor,
    buffers: &'b [Buffer<'a>],
) -> Result<Span<'b, 'a>, String> {
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
    let buffer = buffers.get(view.buffer().index());
    let data_len = buffer.map_or(0, Buffer::len);
    let view_end = view.offset().checked_add(view.length());
    let (Some(buffer), Some(_)) = (buffer, view_end.filter(|&end| end <= data_len)) else {
        return Err(format!(
            "buffer view {} (bytes {}..+{}) lies outside buffer {} ({} bytes)",
            view.index(),
            view.offset(),
            view.length(),
            view.buffer().index(),
            data_len
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
        Some(end) if end <= view.length() => Ok(Span {
            buffer,
            start: view.offset() + acc.offset().min(view.length()),
            stride,
            size,
            count,
        }),
        _ => Err(format!(
            "accessor {i} ({count} elements from byte {}) runs past the end of buffer view {} ({} bytes)",
            acc.offset(),
            view.index(),
            view.length()
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
    buffers: &[Buffer],
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
    let span = elements(acc, buffers)?;
    let mut v = Vec::with_capacity(span.count);
    span.runs(|first, e| {
        for i in 0..e.count {
            let b = e.get(i);
            let p = Vec3::new(
                component(b, 0, data),
                component(b, 1, data),
                component(b, 2, data),
            );
            if !p.is_finite() {
                return Err(format!(
                    "{what} {} of accessor {} is not finite",
                    first + i,
                    acc.index()
                ));
            }
            if what == "position"
                && let Err(e) = crate::range::coordinate(p.to_array())
            {
                return Err(format!(
                    "position {} of accessor {}: {e}",
                    first + i,
                    acc.index()
                ));
            }
            v.push(p);
        }
        Ok(())
    })?;
    Ok(v)
}

/// Reads a `VEC2` texture-coordinate accessor: `FLOAT`, or normalised `UNSIGNED_BYTE`/`SHORT`.
pub fn read_uvs(acc: &gltf::Accessor, buffers: &[Buffer]) -> Result<Vec<Vec2>, String> {
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
    let span = elements(acc, buffers)?;
    let mut v = Vec::with_capacity(span.count);
    span.runs(|first, e| {
        for i in 0..e.count {
            let t = Vec2::new(component(e.get(i), 0, data), component(e.get(i), 1, data));
            if !t.is_finite() {
                return Err(format!(
                    "texture coordinate {} of accessor {} is not finite",
                    first + i,
                    acc.index()
                ));
            }
            v.push(t);
        }
        Ok(())
    })?;
    Ok(v)
}

/// Reads a `SCALAR` index accessor of `UNSIGNED_BYTE`, `UNSIGNED_SHORT` or `UNSIGNED_INT`,
/// each index checked to be below `vertices`.
pub fn read_indices(
    acc: &gltf::Accessor,
    buffers: &[Buffer],
    vertices: usize,
) -> Result<Vec<u32>, String> {
    let span = index_span(acc, buffers)?;
    let mut out = Vec::with_capacity(span.count);
    each_index(&span, acc.data_type(), vertices, |i| out.push(i))?;
    Ok(out)
}

/// Reads a `TRIANGLES` primitive's index accessor straight into triangles (surplus indices
/// ignored), each index checked to be below `vertices`: no list of single indices is made.
pub fn read_triangle_list(
    acc: &gltf::Accessor,
    buffers: &[Buffer],
    vertices: usize,
) -> Result<Vec<[u32; 3]>, String> {
    let span = index_span(acc, buffers)?;
    let mut out = Vec::with_capacity(span.count / 3);
    let (mut corner, mut k) = ([0; 3], 0);
    each_index(&span, acc.data_type(), vertices, |i| {
        corner[k] = i;
        k += 1;
        if k == 3 {
            out.push(corner);
            k = 0;
        }
    })?;
    Ok(out)
}

/// Checks that an index accessor is `SCALAR` of unsigned integers and returns its elements.
fn index_span<'b, 'a>(
    acc: &gltf::Accessor,
    buffers: &'b [Buffer<'a>],
) -> Result<Span<'b, 'a>, String> {
    let (dims, data) = (acc.dimensions(), acc.data_type());
    if dims != Dimensions::Scalar || !matches!(data, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(format!(
            "index accessor {} must be SCALAR of unsigned integers, found {}",
            acc.index(),
            type_name(dims, data)
        ));
    }
    elements(acc, buffers)
}

/// Calls `each` on every index of `span` (of type `data`) in order, after checking it.
fn each_index(
    span: &Span,
    data: DataType,
    vertices: usize,
    mut each: impl FnMut(u32),
) -> Result<(), String> {
    span.runs(|_, e| {
        for i in 0..e.count {
            let b = e.get(i);
            let index = match data {
                DataType::U8 => b[0] as u32,
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            };
            if index as usize >= vertices {
                return Err(format!("index {index} out of range ({vertices} vertices)"));
            }
            each(index);
        }
        Ok(())
    })
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
        // Chunks after the JSON and BIN chunks are never read: a third chunk claiming more
        // bytes than the file has, then a million empty ones, change nothing.
        let mut more = glb(0, b"{}      ");
        more.extend(4u32.to_le_bytes());
        more.extend(CHUNK_BIN.to_le_bytes());
        more.extend([1, 2, 3, 4]);
        more.extend(u32::MAX.to_le_bytes());
        more.extend(b"XTRA");
        for _ in 0..1_000_000 {
            more.extend([0u8; 4]);
            more.extend(b"NONE");
        }
        let total = (more.len() as u32).to_le_bytes();
        more[8..12].copy_from_slice(&total);
        assert_eq!(
            split_glb(&more).unwrap(),
            (&b"{}      "[..], Some(&[1u8, 2, 3, 4][..]))
        );
    }
}
