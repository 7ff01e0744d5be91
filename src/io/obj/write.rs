//! Writes a [`MeshData`] as Wavefront OBJ text.

use crate::geometry::mesh::MeshData;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Writes `mesh` as OBJ: `v`, then `vt` and `vn` when present, then one `f` per triangle whose
/// corners share one index for all attributes (`f a/a/a`, `a//a`, `a/a` or `a`).
///
/// Numbers are written in Rust's shortest round-trip form, so [`super::load_obj`] reads back
/// the same `f32`s. Materials are not written. The file is replaced as images are
/// ([`crate::files::write_replacing`]: symlinks followed, permissions kept, special files
/// refused, no temporary file left behind).
pub fn write_obj(mesh: &MeshData, path: &Path) -> io::Result<()> {
    crate::files::write_replacing_io(path, |file| write_to(mesh, file))
}

fn write_to(mesh: &MeshData, file: &mut std::fs::File) -> io::Result<()> {
    let mut out = BufWriter::with_capacity(1 << 20, file);
    writeln!(out, "# written by caustic")?;
    for p in &mesh.positions {
        writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in &mesh.uvs {
        writeln!(out, "vt {} {}", t.x, t.y)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let (uvs, normals) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    for t in &mesh.triangles {
        out.write_all(b"f")?;
        for i in t.map(|i| u64::from(i) + 1) {
            match (uvs, normals) {
                (true, true) => write!(out, " {i}/{i}/{i}")?,
                (false, true) => write!(out, " {i}//{i}")?,
                (true, false) => write!(out, " {i}/{i}")?,
                (false, false) => write!(out, " {i}")?,
            }
        }
        out.write_all(b"\n")?;
    }
    out.flush()
}
