//! Writes a [`MeshData`] as glTF 2.0: `.gltf` JSON beside a `.bin` buffer, or one `.glb`.

use crate::geometry::mesh::MeshData;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Writes `mesh` as one glTF mesh with one primitive: a `.glb` when `path` ends in `.glb`
/// (any case), otherwise `.gltf` JSON plus a `.bin` buffer named after it in the same folder.
///
/// Positions, normals and uvs (when present) and `u32` indices are written exactly (little-endian
/// `f32`), so [`super::load_gltf`] reads back the same numbers. Materials are not written.
/// Each file is replaced as images are ([`crate::files::write_replacing`]: symlinks followed,
/// permissions kept, special files refused, no temporary file left behind).
pub fn write_gltf(mesh: &MeshData, path: &Path) -> io::Result<()> {
    let is_glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let layout = Layout::new(mesh);
    if is_glb {
        crate::files::write_replacing_io(path, |file| write_glb(mesh, &layout, file))
    } else {
        let bin_path = path.with_extension("bin");
        let bin_name = bin_path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        crate::files::write_replacing_io(&bin_path, |file| {
            let mut bin = BufWriter::new(file);
            write_buffer(mesh, &mut bin)?;
            bin.flush()
        })?;
        let json = layout.json(Some(&percent_encode(&bin_name)));
        crate::files::write_bytes(path, json.as_bytes()).map_err(io::Error::other)
    }
}

/// Writes `mesh` laid out by `layout` as one GLB file to `file`.
fn write_glb(mesh: &MeshData, layout: &Layout, file: &mut std::fs::File) -> io::Result<()> {
    let json = pad(layout.json(None).into_bytes(), b' ');
    let bin_len = layout.total.next_multiple_of(4);
    let total = 12 + 8 + json.len() + 8 + bin_len;
    let mut out = BufWriter::new(file);
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&to_u32(total)?.to_le_bytes())?;
    out.write_all(&to_u32(json.len())?.to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json)?;
    out.write_all(&to_u32(bin_len)?.to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    write_buffer(mesh, &mut out)?;
    out.write_all(&vec![0; bin_len - layout.total])?;
    out.flush()
}

/// Converts a byte count to the `u32` GLB stores, failing past 4 GiB.
fn to_u32(n: usize) -> io::Result<u32> {
    u32::try_from(n).map_err(|_| io::Error::other("mesh too large for a GLB file (over 4 GiB)"))
}

/// Pads `bytes` with `fill` to a multiple of 4.
fn pad(mut bytes: Vec<u8>, fill: u8) -> Vec<u8> {
    bytes.resize(bytes.len().next_multiple_of(4), fill);
    bytes
}

/// Escapes every byte of a file name that is not an unreserved URI character.
fn percent_encode(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// Where each attribute sits in the one buffer: positions, normals, uvs, then indices.
struct Layout {
    vertices: usize,
    triangles: usize,
    normals: bool,
    uvs: bool,
    total: usize,
    min: [f32; 3],
    max: [f32; 3],
}

impl Layout {
    fn new(mesh: &MeshData) -> Layout {
        let vertices = mesh.positions.len();
        let normals = !mesh.normals.is_empty();
        let uvs = !mesh.uvs.is_empty();
        let total =
            vertices * (12 + 12 * normals as usize + 8 * uvs as usize) + mesh.triangles.len() * 12;
        let (mut min, mut max) = ([0.0; 3], [0.0; 3]);
        if let Some(first) = mesh.positions.first() {
            let lo = mesh.positions.iter().fold(*first, |a, p| a.min(*p));
            let hi = mesh.positions.iter().fold(*first, |a, p| a.max(*p));
            (min, max) = (lo.to_array(), hi.to_array());
        }
        Layout {
            vertices,
            triangles: mesh.triangles.len(),
            normals,
            uvs,
            total,
            min,
            max,
        }
    }

    /// Returns the glTF JSON; `uri` names the external buffer (`None` for the GLB chunk).
    fn json(&self, uri: Option<&str>) -> String {
        let n = self.vertices;
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut attributes = Vec::new();
        let mut offset = 0;
        let mut add = |name: &str,
                       bytes: usize,
                       count: usize,
                       kind: &str,
                       comp: u32,
                       extra: &str| {
            let i = views.len();
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{bytes}}}"#
            ));
            accessors.push(format!(
                r#"{{"bufferView":{i},"componentType":{comp},"count":{count},"type":"{kind}"{extra}}}"#
            ));
            if !name.is_empty() {
                attributes.push(format!(r#""{name}":{i}"#));
            }
            offset += bytes;
        };
        let bound = |v: [f32; 3]| format!("[{},{},{}]", v[0], v[1], v[2]);
        let minmax = format!(r#","min":{},"max":{}"#, bound(self.min), bound(self.max));
        add("POSITION", 12 * n, n, "VEC3", 5126, &minmax);
        if self.normals {
            add("NORMAL", 12 * n, n, "VEC3", 5126, "");
        }
        if self.uvs {
            add("TEXCOORD_0", 8 * n, n, "VEC2", 5126, "");
        }
        let indices = 1 + self.normals as usize + self.uvs as usize;
        add(
            "",
            12 * self.triangles,
            3 * self.triangles,
            "SCALAR",
            5125,
            "",
        );
        let uri = uri.map_or(String::new(), |u| format!(r#""uri":"{u}","#));
        format!(
            concat!(
                r#"{{"asset":{{"version":"2.0","generator":"caustic"}},"scene":0,"#,
                r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"#,
                r#""meshes":[{{"primitives":[{{"attributes":{{{}}},"indices":{},"mode":4}}]}}],"#,
                r#""buffers":[{{{}"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#
            ),
            attributes.join(","),
            indices,
            uri,
            self.total,
            views.join(","),
            accessors.join(",")
        )
    }
}

/// Writes the buffer's bytes in [`Layout`] order.
fn write_buffer(mesh: &MeshData, out: &mut impl Write) -> io::Result<()> {
    let floats = mesh
        .positions
        .iter()
        .chain(&mesh.normals)
        .flat_map(|v| v.to_array())
        .chain(mesh.uvs.iter().flat_map(|t| t.to_array()));
    for f in floats {
        out.write_all(&f.to_le_bytes())?;
    }
    for i in mesh.triangles.iter().flatten() {
        out.write_all(&i.to_le_bytes())?;
    }
    Ok(())
}
