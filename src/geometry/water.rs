//! Procedural water surfaces: a seedable sum of sine waves sampled as an N×N height field, with
//! analytic normals, for caustics through a wavy interface.
//!
//! # Formula
//! The surface is the height field `y = h(x, z)` over the square `[-size/2, size/2]²` with
//!
//! ```text
//! h(x, z) = Σᵢ Aᵢ · sin(kᵢ · (x, z) + φᵢ),     ∇h = Σᵢ Aᵢ · cos(kᵢ · (x, z) + φᵢ) · kᵢ
//! n(x, z) = normalize(−∂h/∂x, 1, −∂h/∂z)
//! ```
//!
//! For each of the `waves` components, drawn from a SplitMix64 stream keyed by `seed`: the
//! wavelength `λᵢ` is uniform in `[wavelength/4, wavelength]`, the direction makes an angle
//! uniform in `[-spread, spread]` with +x (the wind), `kᵢ = 2π/λᵢ · (cos θᵢ, sin θᵢ)`, the phase
//! `φᵢ` is uniform in `[0, 2π)`, and `Aᵢ ∝ λᵢ` (equal steepness) scaled so that `Σ Aᵢ =
//! amplitude`, hence `|h| ≤ amplitude`. Sine waves rather than Gerstner waves keep the surface a
//! true height field over the grid, so vertex `(i, j)` sits exactly at its grid point.
//!
//! A scene reaches the generator through `gr.water_mesh` (which writes its output once as a
//! cached glTF file, `crate::lua` module `generated`), or through the `water` tool, whose file
//! `gr.mesh` then loads:
//!
//! ```lua
//! pool = gr.water_mesh('water', {n = 1001, seed = 7, size = 2.1, depth = 0.85})
//! -- or: cargo run --release -p caustic-tools --bin water -- --n 1001 --seed 7 -o meshes/water_1001.obj
//! water = gr.mesh('water', 'meshes/water_1001.obj')
//! ```
//!
//! [`close_volume`] closes the surface into a watertight body of water (sides and a bottom).

use crate::geometry::mesh::MeshData;
use glam::{DVec2, Vec2, Vec3};
use std::f64::consts::TAU;

/// Largest grid side [`wave_mesh`] accepts: `n²` vertex indices must fit in `u32`.
pub const MAX_N: u32 = 65_535;

/// What [`wave_mesh`] generates.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveParams {
    /// Vertices per side of the grid (N×N vertices, 2(N−1)² triangles), in `2..=MAX_N`.
    pub n: u32,
    /// Side length of the square the grid covers, centred on the origin in the xz plane.
    pub size: f32,
    /// Seed of the wave components: the same seed gives the same surface.
    pub seed: u64,
    /// Number of sine components.
    pub waves: u32,
    /// Sum of the components' amplitudes, a bound on `|y|`.
    pub amplitude: f32,
    /// Longest wavelength; components range down to a quarter of it.
    pub wavelength: f32,
    /// Largest angle, in radians, between a component's direction and +x.
    pub spread: f32,
}

impl Default for WaveParams {
    fn default() -> WaveParams {
        WaveParams {
            n: 129,
            size: 10.0,
            seed: 0,
            waves: 8,
            amplitude: 0.1,
            wavelength: 2.0,
            spread: 0.6,
        }
    }
}

/// One sine component: `amplitude · sin(k · (x, z) + phase)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    pub amplitude: f64,
    /// Wave vector in the xz plane, `2π/λ` long.
    pub k: DVec2,
    pub phase: f64,
}

/// The continuous surface a [`WaveParams`] describes, before sampling.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveField {
    pub waves: Vec<Wave>,
}

/// Returns the next SplitMix64 output (Steele, Lea and Flood 2014) and advances `state`.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl WaveField {
    /// Draws the components of `p` from its seed.
    pub fn new(p: &WaveParams) -> WaveField {
        let mut state = p.seed;
        let mut uniform = || (splitmix64(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
        let mut waves: Vec<Wave> = (0..p.waves)
            .map(|_| {
                let wavelength = p.wavelength as f64 * (0.25 + 0.75 * uniform());
                let angle = p.spread as f64 * (2.0 * uniform() - 1.0);
                Wave {
                    amplitude: wavelength,
                    k: DVec2::from_angle(angle) * (TAU / wavelength),
                    phase: TAU * uniform(),
                }
            })
            .collect();
        let total: f64 = waves.iter().map(|w| w.amplitude).sum();
        for w in &mut waves {
            w.amplitude *= p.amplitude as f64 / total;
        }
        WaveField { waves }
    }

    /// Returns the height `h(x, z)`.
    pub fn height(&self, x: f64, z: f64) -> f64 {
        let at = DVec2::new(x, z);
        self.waves
            .iter()
            .map(|w| w.amplitude * (w.k.dot(at) + w.phase).sin())
            .sum()
    }

    /// Returns the unit normal `normalize(−∂h/∂x, 1, −∂h/∂z)`, which points up (+y).
    pub fn normal(&self, x: f64, z: f64) -> Vec3 {
        let at = DVec2::new(x, z);
        let gradient: DVec2 = self
            .waves
            .iter()
            .map(|w| w.k * (w.amplitude * (w.k.dot(at) + w.phase).cos()))
            .sum();
        glam::DVec3::new(-gradient.x, 1.0, -gradient.y)
            .normalize()
            .as_vec3()
    }
}

/// Samples the wave surface of `p` as an N×N grid mesh with analytic normals and uvs.
///
/// Grid vertex `(i, j)` lies at `x = −size/2 + size·i/(N−1)`, `z = −size/2 + size·j/(N−1)`,
/// `y = h(x, z)`, with uv `(i/(N−1), j/(N−1))`. Each grid cell gives two triangles wound
/// counter-clockwise seen from +y, so geometric normals point up like the vertex normals.
/// Vertices are numbered in the order the triangles first use them (the order an OBJ loader
/// rebuilds), so a mesh written to any format loads back with the same numbering.
///
/// # Panics
/// If `p.n` is outside `2..=MAX_N`.
pub fn wave_mesh(p: &WaveParams) -> MeshData {
    assert!(
        (2..=MAX_N).contains(&p.n),
        "wave grid side {} outside 2..={MAX_N}",
        p.n
    );
    let n = p.n as usize;
    let grid = |i: usize, j: usize| (j * n + i) as u32;
    let mut grid_triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b) = (grid(i, j), grid(i + 1, j));
            let (c, d) = (grid(i, j + 1), grid(i + 1, j + 1));
            grid_triangles.push([a, c, b]);
            grid_triangles.push([b, c, d]);
        }
    }
    // Renumber by first use; every grid point is used, so `order` ends up a permutation.
    let mut number = vec![u32::MAX; n * n];
    let mut order = Vec::with_capacity(n * n);
    let triangles = grid_triangles
        .iter()
        .map(|t| {
            t.map(|g| {
                let slot = &mut number[g as usize];
                if *slot == u32::MAX {
                    *slot = order.len() as u32;
                    order.push(g as usize);
                }
                *slot
            })
        })
        .collect();
    let field = WaveField::new(p);
    let last = (n - 1) as f64;
    let mut mesh = MeshData {
        triangles,
        source: format!("wave mesh (n {}, seed {})", p.n, p.seed).into(),
        ..Default::default()
    };
    for &g in &order {
        let (i, j) = (g % n, g / n);
        mesh.positions.push(grid_position(&field, p, i, j));
        mesh.normals
            .push(field.normal(grid_coordinate(p, i), grid_coordinate(p, j)));
        mesh.uvs.push(Vec2::new(
            (i as f64 / last) as f32,
            (j as f64 / last) as f32,
        ));
    }
    mesh
}

/// Returns the world coordinate (x or z) of grid column or row `k` of `p`'s grid.
fn grid_coordinate(p: &WaveParams, k: usize) -> f64 {
    p.size as f64 * (k as f64 / (p.n as usize - 1) as f64 - 0.5)
}

/// Returns the position of grid vertex `(i, j)` of the surface of `p` on `field`, as
/// [`wave_mesh`] stores it (and [`close_volume`] finds it again, bit for bit).
fn grid_position(field: &WaveField, p: &WaveParams, i: usize, j: usize) -> Vec3 {
    let (x, z) = (grid_coordinate(p, i), grid_coordinate(p, j));
    Vec3::new(x as f32, field.height(x, z) as f32, z as f32)
}

/// Closes the surface [`wave_mesh`] made from `p` into a watertight body of water reaching
/// down to `y = bottom`: four side walls under the grid's edges and a flat bottom.
///
/// The side walls and the bottom have their own vertices (with flat outward normals) at exactly
/// the positions of the grid's edge vertices and of each other, so every edge is shared by two
/// faces at bit-identical end points: the watertight ray/triangle test then never lets a ray slip
/// between the surface and a wall. Triangles wind
/// counter-clockwise seen from outside, so every geometric normal points out of the water.
///
/// # Panics
/// If `bottom` is not below every vertex of the surface (`p.amplitude`).
pub fn close_volume(mesh: &mut MeshData, p: &WaveParams, bottom: f32) {
    assert!(
        bottom < -p.amplitude,
        "the bottom {bottom} must lie below the waves (amplitude {})",
        p.amplitude
    );
    let n = p.n as usize;
    // The grid's boundary, counter-clockwise seen from +y, as positions of surface vertices:
    // computed as wave_mesh computed them, so the sides reuse the surface's exact floats.
    let field = WaveField::new(p);
    let at = |i: usize, j: usize| grid_position(&field, p, i, j);
    // Counter-clockwise seen from +y (x right, z towards the viewer): along z = +half (j = n-1)
    // with x rising, up x = +half with z falling, back along z = -half, down x = -half.
    let mut ring: Vec<(Vec3, Vec3)> = Vec::with_capacity(4 * (n - 1));
    for i in 0..n - 1 {
        ring.push((at(i, n - 1), Vec3::Z));
    }
    for j in (1..n).rev() {
        ring.push((at(n - 1, j), Vec3::X));
    }
    for i in (1..n).rev() {
        ring.push((at(i, 0), Vec3::NEG_Z));
    }
    for j in 0..n - 1 {
        ring.push((at(0, j), Vec3::NEG_X));
    }
    let push = |mesh: &mut MeshData, v: Vec3, normal: Vec3| {
        mesh.positions.push(v);
        mesh.normals.push(normal);
        mesh.uvs.push(Vec2::ZERO);
        (mesh.positions.len() - 1) as u32
    };
    let floor = |v: Vec3| Vec3::new(v.x, bottom, v.z);
    for k in 0..ring.len() {
        let (a, normal) = ring[k];
        let b = ring[(k + 1) % ring.len()].0;
        // One quad per boundary edge, facing `normal` (a corner edge belongs to the side it
        // starts on).
        let ta = push(mesh, a, normal);
        let tb = push(mesh, b, normal);
        let ba = push(mesh, floor(a), normal);
        let bb = push(mesh, floor(b), normal);
        mesh.triangles.push([ta, ba, bb]);
        mesh.triangles.push([ta, bb, tb]);
    }
    // The bottom, in columns between x_i and x_(i+1) reaching from z = -size/2 to +size/2 (long,
    // thin, disjoint triangles a BVH separates well, unlike a fan around the centre). The two
    // outer columns also take the side walls' vertices along x = -size/2 and +size/2, as fans.
    let mut below = std::collections::HashMap::new();
    let mut b = |mesh: &mut MeshData, i: usize, j: usize| {
        *below
            .entry((i, j))
            .or_insert_with(|| push(mesh, floor(at(i, j)), Vec3::NEG_Y))
    };
    let (lo, hi) = (0, n - 1);
    for i in 0..n - 1 {
        let (p, q) = (b(mesh, i + 1, lo), b(mesh, i + 1, hi));
        if i == 0 && n > 2 {
            for j in 0..n - 1 {
                let (l0, l1) = (b(mesh, 0, j), b(mesh, 0, j + 1));
                mesh.triangles.push([p, l1, l0]);
            }
            let top = b(mesh, 0, hi);
            mesh.triangles.push([p, q, top]);
        } else if i == n - 2 && n > 2 {
            let (p, q) = (b(mesh, i, lo), b(mesh, i, hi));
            for j in 0..n - 1 {
                let (r0, r1) = (b(mesh, n - 1, j), b(mesh, n - 1, j + 1));
                mesh.triangles.push([p, r0, r1]);
            }
            let top = b(mesh, n - 1, hi);
            mesh.triangles.push([p, top, q]);
        } else {
            let (a, d) = (b(mesh, i, lo), b(mesh, i, hi));
            mesh.triangles.push([a, p, d]);
            mesh.triangles.push([p, q, d]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes_sum_to_the_bound_and_directions_stay_in_the_spread() {
        let p = WaveParams::default();
        let field = WaveField::new(&p);
        let sum: f64 = field.waves.iter().map(|w| w.amplitude).sum();
        assert!((sum - p.amplitude as f64).abs() < 1e-9);
        for w in &field.waves {
            assert!(w.k.y.atan2(w.k.x).abs() <= p.spread as f64 + 1e-12);
            let wavelength = TAU / w.k.length();
            assert!(
                (0.5 - 1e-9..=2.0 + 1e-9).contains(&wavelength),
                "{wavelength}"
            );
        }
    }

    #[test]
    fn smallest_grid_is_one_cell_numbered_by_first_use() {
        let mesh = wave_mesh(&WaveParams {
            n: 2,
            ..Default::default()
        });
        assert_eq!(mesh.triangles, [[0, 1, 2], [2, 1, 3]]);
        let xz: Vec<[f32; 2]> = mesh.positions.iter().map(|p| [p.x, p.z]).collect();
        assert_eq!(xz, [[-5.0, -5.0], [-5.0, 5.0], [5.0, -5.0], [5.0, 5.0]]);
        assert_eq!(mesh.uvs, [Vec2::ZERO, Vec2::Y, Vec2::X, Vec2::ONE]);
    }

    #[test]
    fn a_closed_volume_is_watertight_with_outward_faces_and_the_expected_volume() {
        for n in [2, 3, 17] {
            let p = WaveParams {
                n,
                size: 2.0,
                amplitude: 0.05,
                ..Default::default()
            };
            let mut mesh = wave_mesh(&p);
            close_volume(&mut mesh, &p, -0.8);
            // Every directed edge, by exact positions, has its reverse exactly once: a closed,
            // consistently oriented 2-manifold.
            let key = |v: Vec3| v.to_array().map(f32::to_bits);
            let mut edges = std::collections::HashMap::new();
            for t in &mesh.triangles {
                for k in 0..3 {
                    let (a, b) = (
                        mesh.positions[t[k] as usize],
                        mesh.positions[t[(k + 1) % 3] as usize],
                    );
                    *edges.entry((key(a), key(b))).or_insert(0) += 1;
                }
            }
            for (&(a, b), &count) in &edges {
                assert_eq!(count, 1, "edge used {count} times in one direction");
                assert_eq!(edges.get(&(b, a)), Some(&1), "edge without its twin");
            }
            // Divergence theorem: V = Σ (a · (b × c)) / 6, positive for outward faces; the waves add
            // at most amplitude · size² to the slab's 0.8 · 4.
            let volume: f64 = mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!((volume - 3.2).abs() <= 0.05 * 4.0, "volume {volume}");
            assert_eq!(mesh.normals.len(), mesh.positions.len());
        }
    }
}
