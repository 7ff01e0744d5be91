//! Writes the gallery's glTF asset, `scenes/gallery/meshes/trinkets.gltf` (JSON) and
//! `trinkets.bin` (its buffer), deterministically:
//!
//! ```text
//! cargo run --release -p caustic-tools --bin gallery_gltf -- -o scenes/gallery/meshes
//! ```
//!
//! The file shows what caustic's glTF importer reads beyond triangles: a node hierarchy with
//! TRS transforms (a `tray` node whose three children each place a mesh), one buffer shared by
//! two meshes (a gold and a glass ring from the same torus accessors), smooth normals, `u16`
//! indices, and metallic-roughness materials with `KHR_materials_transmission` and
//! `KHR_materials_ior`. About 38 KB in all, small enough to commit; the same build always writes
//! the same bytes.

use clap::Parser;
use glam::Vec3;
use std::f32::consts::TAU;
use std::path::PathBuf;
use std::process::ExitCode;

/// Writes trinkets.gltf and trinkets.bin into the output folder.
#[derive(Parser)]
struct Cli {
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
}

/// An indexed triangle mesh with one normal per vertex.
#[derive(Default)]
struct Shape {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u16; 3]>,
}

impl Shape {
    /// Appends the quad strip joining ring `a` to ring `b` (each `n` vertices, closed around).
    fn join_rings(&mut self, a: usize, b: usize, n: usize) {
        for k in 0..n {
            let (k0, k1) = (k as u16, ((k + 1) % n) as u16);
            let (a, b) = (a as u16, b as u16);
            self.triangles.push([a + k0, b + k0, b + k1]);
            self.triangles.push([a + k0, b + k1, a + k1]);
        }
    }
}

/// Returns a torus around the y axis: tube centre radius `major`, tube radius `minor`.
fn torus(major: f32, minor: f32, around: usize, tube: usize) -> Shape {
    let mut s = Shape::default();
    for i in 0..around {
        let phi = TAU * i as f32 / around as f32;
        let out = Vec3::new(phi.cos(), 0.0, -phi.sin());
        for j in 0..tube {
            let theta = TAU * j as f32 / tube as f32;
            let n = out * theta.cos() + Vec3::Y * theta.sin();
            s.positions.push(out * major + n * minor);
            s.normals.push(n);
        }
    }
    for i in 0..around {
        s.join_rings(i * tube, (i + 1) % around * tube, tube);
    }
    s
}

/// Returns a vase: the profile `r(y) = 0.33 + 0.2·sin(3.5y)` for y in [0, 1.6] (a belly, a neck,
/// a flared lip) turned about the y axis, open at the top, closed by a flat base.
fn vase(around: usize, rings: usize) -> Shape {
    let mut s = Shape::default();
    for i in 0..=rings {
        let y = 1.6 * i as f32 / rings as f32;
        let r = 0.33 + 0.2 * (3.5 * y).sin();
        let slope = 0.2 * 3.5 * (3.5 * y).cos();
        for k in 0..around {
            let phi = TAU * k as f32 / around as f32;
            let out = Vec3::new(phi.cos(), 0.0, -phi.sin());
            s.positions.push(out * r + Vec3::Y * y);
            s.normals.push((out - Vec3::Y * slope).normalize());
        }
    }
    // From the upper ring to the lower, so that triangles wind counter-clockwise seen from outside.
    for i in 0..rings {
        s.join_rings((i + 1) * around, i * around, around);
    }
    // The base: its own vertices (a sharp edge), facing down, fanned from the centre.
    let centre = s.positions.len() as u16;
    s.positions.push(Vec3::ZERO);
    s.normals.push(Vec3::NEG_Y);
    for k in 0..around {
        s.positions.push(s.positions[k]);
        s.normals.push(Vec3::NEG_Y);
    }
    for k in 0..around as u16 {
        let next = (k + 1) % around as u16;
        s.triangles
            .push([centre, centre + 1 + next, centre + 1 + k]);
    }
    s
}

/// The buffer and the JSON of its views and accessors, built up shape by shape.
#[derive(Default)]
struct Buffer {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Buffer {
    /// Appends `bytes` as a view (4-byte aligned) read by one accessor with JSON `members`;
    /// returns the accessor's index.
    fn accessor(&mut self, bytes: &[u8], members: String) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        let view = self.views.len() - 1;
        self.accessors
            .push(format!(r#"{{"bufferView":{view},{members}}}"#));
        self.accessors.len() - 1
    }

    /// Appends `VEC3` floats (with the min and max the spec asks of positions).
    fn vec3s(&mut self, values: &[Vec3]) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flat_map(|v| v.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let lo = values.iter().copied().reduce(Vec3::min).unwrap_or_default();
        let hi = values.iter().copied().reduce(Vec3::max).unwrap_or_default();
        let list = |v: Vec3| format!("[{},{},{}]", v.x, v.y, v.z);
        let members = format!(
            r#""componentType":5126,"count":{},"type":"VEC3","min":{},"max":{}"#,
            values.len(),
            list(lo),
            list(hi)
        );
        self.accessor(&bytes, members)
    }

    /// Appends `u16` triangle indices.
    fn indices(&mut self, triangles: &[[u16; 3]]) -> usize {
        let bytes: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let members = format!(
            r#""componentType":5123,"count":{},"type":"SCALAR""#,
            3 * triangles.len()
        );
        self.accessor(&bytes, members)
    }

    /// Appends a shape; returns its primitive's attributes and indices as JSON members.
    fn shape(&mut self, s: &Shape) -> String {
        let position = self.vec3s(&s.positions);
        let normal = self.vec3s(&s.normals);
        let indices = self.indices(&s.triangles);
        format!(r#""attributes":{{"POSITION":{position},"NORMAL":{normal}}},"indices":{indices}"#)
    }
}

/// Returns the JSON document around `buffer` (named `bin_name`) with the meshes' primitives.
fn document(buffer: &Buffer, bin_name: &str, ring: &str, pot: &str) -> String {
    // Materials: polished gold, clear glass (transmission 1, index 1.5), blue glazed ceramic.
    let materials = [
        r#"{"name":"gold","pbrMetallicRoughness":{"baseColorFactor":[1.0,0.77,0.34,1],"metallicFactor":1,"roughnessFactor":0.25}}"#,
        r#"{"name":"glass","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,1],"metallicFactor":0,"roughnessFactor":0},"extensions":{"KHR_materials_transmission":{"transmissionFactor":1},"KHR_materials_ior":{"ior":1.5}}}"#,
        r#"{"name":"ceramic","pbrMetallicRoughness":{"baseColorFactor":[0.12,0.28,0.65,1],"metallicFactor":0,"roughnessFactor":0.45}}"#,
    ]
    .join(",");
    // Two meshes share the torus's accessors; each primitive names its material.
    let meshes = format!(
        r#"{{"name":"gold ring","primitives":[{{{ring},"material":0}}]}},{{"name":"glass ring","primitives":[{{{ring},"material":1}}]}},{{"name":"vase","primitives":[{{{pot},"material":2}}]}}"#
    );
    // The tray places its children; each child's TRS composes with the tray's.
    let nodes = [
        r#"{"name":"tray","children":[1,2,3],"translation":[0,0,0],"scale":[1,1,1]}"#,
        r#"{"name":"vase","mesh":2}"#,
        r#"{"name":"gold ring","mesh":0,"translation":[0.95,0.105,0.55],"scale":[0.3,0.3,0.3]}"#,
        r#"{"name":"glass ring","mesh":1,"translation":[-0.95,0.5,0.35],"rotation":[0.7071068,0,0,0.7071068],"scale":[0.37,0.37,0.37]}"#,
    ]
    .join(",");
    format!(
        r#"{{"asset":{{"version":"2.0","generator":"caustic-tools gallery_gltf"}},"extensionsUsed":["KHR_materials_transmission","KHR_materials_ior"],"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{nodes}],"meshes":[{meshes}],"materials":[{materials}],"buffers":[{{"uri":"{bin_name}","byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
        buffer.bin.len(),
        buffer.views.join(","),
        buffer.accessors.join(",")
    ) + "\n"
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let mut buffer = Buffer::default();
    // A tube a third of the ring's radius: scaled by 0.3 the gold ring is 0.1 thick, lying flat.
    let ring = buffer.shape(&torus(1.0, 0.35, 32, 12));
    let pot = buffer.shape(&vase(24, 24));
    let json = document(&buffer, "trinkets.bin", &ring, &pot);
    let write = |name: &str, bytes: &[u8]| {
        let path = cli.output.join(name);
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    match write("trinkets.bin", &buffer.bin).and_then(|()| write("trinkets.gltf", json.as_bytes()))
    {
        Ok(()) => {
            println!(
                "wrote trinkets.gltf and trinkets.bin ({} bytes) in {}",
                buffer.bin.len(),
                cli.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
