//! Readers for the Embree reference harness's binary files (`../shared/bench/README.md`,
//! "File formats"): the wave mesh (`.mesh`) and the ray sets (`.rays`), both little-endian.
//!
//! Every size is checked against the header before anything is read, so a truncated or foreign
//! file is a [`FileError`] naming the file, never a panic.

use caustic::geometry::mesh::MeshData;
use glam::Vec3;
use std::fmt;
use std::path::{Path, PathBuf};

/// Magic number of a `.mesh` file (the bytes `M E S H`).
pub const MESH_MAGIC: u32 = 0x4853_454D;
/// Magic number of a `.rays` file (the bytes `R A Y S`).
pub const RAYS_MAGIC: u32 = 0x5359_4152;

/// A file that could not be read or does not follow its format.
#[derive(Debug)]
pub struct FileError {
    pub path: PathBuf,
    pub message: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.message)
    }
}

impl std::error::Error for FileError {}

fn fail<T>(path: &Path, message: impl Into<String>) -> Result<T, FileError> {
    Err(FileError {
        path: path.to_path_buf(),
        message: message.into(),
    })
}

/// Returns the little-endian `u32` words of `bytes` (whose length is a multiple of 4).
fn words(bytes: &[u8]) -> impl Iterator<Item = u32> + '_ {
    bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|w| u32::from_le_bytes(*w))
}

/// Returns the whole file, or an error naming it.
fn read_all(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).or_else(|e| fail(path, format!("cannot read: {e}")))
}

/// Returns the header words of `bytes` after checking the magic number and version 1.
fn header(path: &Path, bytes: &[u8], magic: u32, len: usize) -> Result<Vec<u32>, FileError> {
    if bytes.len() < len * 4 {
        return fail(
            path,
            format!("truncated header ({} of {} bytes)", bytes.len(), len * 4),
        );
    }
    let h: Vec<u32> = words(&bytes[..len * 4]).collect();
    if h[0] != magic {
        return fail(
            path,
            format!("bad magic {:#010x} (want {magic:#010x})", h[0]),
        );
    }
    if h[1] != 1 {
        return fail(path, format!("unsupported version {} (want 1)", h[1]));
    }
    Ok(h)
}

/// Checks that a file holds exactly `want` bytes.
fn check_size(path: &Path, have: usize, want: u64) -> Result<(), FileError> {
    if have as u64 != want {
        let what = if (have as u64) < want {
            "truncated"
        } else {
            "trailing bytes"
        };
        return fail(
            path,
            format!("{what}: {have} bytes, the header implies {want}"),
        );
    }
    Ok(())
}

/// Reads a `.mesh` file into a [`MeshData`] (positions and triangles in file order).
///
/// Rejects a bad header, a size that disagrees with the counts, an out-of-range index and a
/// non-finite vertex.
pub fn read_mesh(path: &Path) -> Result<MeshData, FileError> {
    let bytes = read_all(path)?;
    let h = header(path, &bytes, MESH_MAGIC, 4)?;
    let (nv, nt) = (h[2] as u64, h[3] as u64);
    check_size(path, bytes.len(), 16 + 12 * nv + 12 * nt)?;
    let pos_end = 16 + 12 * nv as usize;
    let floats: Vec<f32> = words(&bytes[16..pos_end]).map(f32::from_bits).collect();
    let positions: Vec<Vec3> = floats
        .as_chunks::<3>()
        .0
        .iter()
        .map(|&p| Vec3::from(p))
        .collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return fail(path, format!("vertex {bad} is not finite"));
    }
    let idx: Vec<u32> = words(&bytes[pos_end..]).collect();
    let triangles: Vec<[u32; 3]> = idx.as_chunks::<3>().0.to_vec();
    if let Some(bad) = triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as u64 >= nv))
    {
        return fail(
            path,
            format!("triangle {bad} has a vertex index out of range"),
        );
    }
    Ok(MeshData {
        positions,
        triangles,
        source: path.to_path_buf(),
        ..MeshData::default()
    })
}

/// One record of a `.rays` file: `origin + t·dir` for `t` in `[tmin, tmax]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayRecord {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

/// The kind of a ray set, as its header states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Pinhole camera rays in image order.
    Primary,
    /// Random origins above the mesh with uniform directions.
    Incoherent,
}

impl RayKind {
    /// Returns the name the BUILD/TRACE lines use (`kind=`).
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Incoherent => "incoherent",
        }
    }
}

/// A ray set as read from a `.rays` file, records in file order.
#[derive(Clone, Debug)]
pub struct RaySet {
    pub path: PathBuf,
    pub kind: RayKind,
    pub width: u32,
    pub height: u32,
    pub rays: Vec<RayRecord>,
}

/// Reads a `.rays` file; rejects a bad header, an unknown kind, a size that disagrees with the
/// count and image dimensions whose product is not the count.
pub fn read_rays(path: &Path) -> Result<RaySet, FileError> {
    let bytes = read_all(path)?;
    let h = header(path, &bytes, RAYS_MAGIC, 8)?;
    let (count, width, height) = (h[2], h[3], h[4]);
    let kind = match h[5] {
        0 => RayKind::Primary,
        1 => RayKind::Incoherent,
        k => return fail(path, format!("unknown ray kind {k}")),
    };
    if width != 0 && width as u64 * height as u64 != count as u64 {
        return fail(
            path,
            format!("width {width} × height {height} ≠ count {count}"),
        );
    }
    check_size(path, bytes.len(), 32 + 32 * count as u64)?;
    let floats: Vec<f32> = words(&bytes[32..]).map(f32::from_bits).collect();
    let rays = floats
        .as_chunks::<8>()
        .0
        .iter()
        .map(|r| RayRecord {
            origin: [r[0], r[1], r[2]],
            tmin: r[3],
            dir: [r[4], r[5], r[6]],
            tmax: r[7],
        })
        .collect();
    Ok(RaySet {
        path: path.to_path_buf(),
        kind,
        width,
        height,
        rays,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("caustic-benchfile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn le(words: &[u32]) -> Vec<u8> {
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    fn one_triangle_mesh() -> Vec<u8> {
        let mut w = vec![MESH_MAGIC, 1, 3, 1];
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
            w.push(v.to_bits());
        }
        w.extend([0, 1, 2]);
        le(&w)
    }

    #[test]
    fn reads_a_mesh_and_rejects_truncation_and_bad_indices() {
        let good = one_triangle_mesh();
        let m = read_mesh(&write("good.mesh", &good)).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.positions[1], Vec3::X);
        let e = read_mesh(&write("short.mesh", &good[..good.len() - 1])).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        let e = read_mesh(&write("tiny.mesh", &good[..6])).unwrap_err();
        assert!(e.message.contains("truncated header"), "{e}");
        let mut bad = good.clone();
        let n = bad.len();
        bad[n - 4..].copy_from_slice(&7u32.to_le_bytes());
        let e = read_mesh(&write("bad.mesh", &bad)).unwrap_err();
        assert!(e.message.contains("out of range"), "{e}");
        let e = read_mesh(&write("rays.mesh", &le(&[RAYS_MAGIC, 1, 0, 0]))).unwrap_err();
        assert!(e.message.contains("bad magic"), "{e}");
    }

    #[test]
    fn reads_rays_and_rejects_bad_sizes() {
        let mut w = vec![RAYS_MAGIC, 1, 1, 1, 1, 0, 0, 0];
        for v in [0.0f32, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, f32::INFINITY] {
            w.push(v.to_bits());
        }
        let good = le(&w);
        let r = read_rays(&write("good.rays", &good)).unwrap();
        assert_eq!(r.kind, RayKind::Primary);
        assert_eq!(r.rays[0].dir, [0.0, -1.0, 0.0]);
        let e = read_rays(&write("short.rays", &good[..40])).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        let mut bad = w.clone();
        bad[3] = 2;
        let e = read_rays(&write("dims.rays", &le(&bad))).unwrap_err();
        assert!(e.message.contains("count"), "{e}");
        bad = w.clone();
        bad[1] = 2;
        let e = read_rays(&write("ver.rays", &le(&bad))).unwrap_err();
        assert!(e.message.contains("version"), "{e}");
    }
}
