//! Triangle meshes in object space: the plain data every loader produces ([`MeshData`]) and the
//! traceable form with its own BVH ([`MeshGeom`]), the bottom level of the scene's two-level BVH.
//!
//! A [`MeshData`] is shared by every node that instances it (`Arc`), so a mesh
//! placed ten times is stored once. Vertex attributes are indexed by one index
//! per corner (loaders unify `v/vt/vn` triples into single vertices).

use crate::accel::{Bounds, Builder, Bvh, Kernel};
use crate::geometry::Ray;
use crate::geometry::tri4::Tri4;
use crate::geometry::triangle::{RayShear, TriangleHit};
use glam::{Vec2, Vec3, Vec3A};
use rayon::prelude::*;
use std::path::PathBuf;

/// A triangle mesh as loaded from a file, in the object space of its node.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions; every entry is finite (loaders reject NaN and infinity).
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, parallel to `positions`, or empty when the file has none.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, parallel to `positions`, or empty when the file has none.
    pub uvs: Vec<Vec2>,
    /// Triangles as indices into `positions` (always in range).
    pub triangles: Vec<[u32; 3]>,
    /// Materials the file defines (OBJ `usemtl`/MTL, glTF materials), used where the script sets none.
    pub materials: Vec<MeshMaterial>,
    /// Per-triangle index into `materials`, parallel to `triangles`, or empty when the file has none.
    pub triangle_materials: Vec<u32>,
    /// The file this mesh was read from, for messages.
    pub source: PathBuf,
}

/// A material carried by a mesh file, in the terms of `gr.material`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshMaterial {
    /// The file's name for it, for messages.
    pub name: String,
    /// Diffuse colour (OBJ `Kd`, glTF base colour).
    pub kd: Vec3,
    /// Specular colour (OBJ `Ks`; glTF: approximated from metallic/roughness).
    pub ks: Vec3,
    /// Phong exponent (OBJ `Ns`; glTF: approximated from roughness).
    pub shininess: f32,
    /// Transparency in [0, 1] (OBJ `1 - d`, glTF `KHR_materials_transmission`).
    pub transparency: f32,
    /// Index of refraction (OBJ `Ni`, glTF `KHR_materials_ior`, default 1.5 for glTF).
    pub ior: f32,
    /// Texture replacing `kd` (OBJ `map_Kd`, glTF base colour texture), resolved to a path.
    pub texture: Option<PathBuf>,
}

impl MeshData {
    /// Returns the number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}

/// A mesh ready for tracing: attributes in object space, triangles reordered into BVH order.
pub struct MeshGeom {
    pub positions: Vec<Vec3A>,
    /// Per-vertex normals, or empty for face normals.
    pub normals: Vec<Vec3A>,
    /// Per-vertex texture coordinates, or empty.
    pub uvs: Vec<Vec2>,
    /// Vertex indices, in BVH order: the BVH's leaf index `i` is triangle `i`.
    pub triangles: Vec<[u32; 3]>,
    /// Scene material (index into `Scene::materials`) of each triangle, in BVH order like
    /// `triangles`, or empty when the file carries no materials.
    pub materials: Vec<u32>,
    pub bvh: Bvh,
    pub bounds: Bounds,
    /// The corners of each BVH leaf's triangles, by leaf id ([`Bvh::leaves`]): what traversal
    /// reads, one contiguous record tested at once instead of indices and scattered positions.
    blocks: Vec<Tri4>,
    /// Area-weighted vertex normals, computed on first use (Perlin noise needs smooth normals).
    smooth: std::sync::OnceLock<Vec<Vec3A>>,
}

impl MeshGeom {
    /// Builds the mesh's BVH; the file's materials become scene materials from `first_material`
    /// on.
    ///
    /// Positions must be finite, and `triangle_materials` empty or parallel to `triangles` with
    /// every entry below `materials.len()` (the scene builder checks both).
    pub fn new(data: &MeshData, first_material: u32) -> MeshGeom {
        MeshGeom::with_builder(data, first_material, Builder::BinnedSah)
    }

    /// [`MeshGeom::new`] with the BVH built by `builder` (for benchmarks and tests).
    pub fn with_builder(data: &MeshData, first_material: u32, builder: Builder) -> MeshGeom {
        let mut positions = crate::mem::huge_vec(data.positions.len());
        data.positions
            .par_iter()
            .map(|&p| p.into())
            .collect_into_vec(&mut positions);
        let boxes: Vec<Bounds> = data
            .triangles
            .par_iter()
            .map(|t| {
                t.iter()
                    .fold(Bounds::EMPTY, |b, &i| b.grow(positions[i as usize]))
            })
            .collect();
        let bvh = Bvh::build_with(&boxes, builder);
        let mut triangles = crate::mem::huge_vec(bvh.len());
        bvh.order()
            .par_iter()
            .map(|&i| data.triangles[i as usize])
            .collect_into_vec(&mut triangles);
        let materials = if data.triangle_materials.is_empty() {
            Vec::new()
        } else {
            bvh.order()
                .iter()
                .map(|&i| first_material + data.triangle_materials[i as usize])
                .collect()
        };
        let mut blocks = crate::mem::huge_vec(bvh.leaves().len());
        bvh.leaves()
            .par_iter()
            .map(|l| {
                let mut corners = [[Vec3A::ZERO; 3]; 4];
                let range = l.first as usize..(l.first + l.count) as usize;
                for (c, t) in corners.iter_mut().zip(&triangles[range]) {
                    *c = t.map(|i| positions[i as usize]);
                }
                Tri4::new(&corners[..l.count as usize])
            })
            .collect_into_vec(&mut blocks);
        let bounds = boxes
            .par_iter()
            .copied()
            .reduce(|| Bounds::EMPTY, Bounds::union);
        MeshGeom {
            positions,
            normals: data.normals.iter().map(|&n| n.into()).collect(),
            uvs: data.uvs.clone(),
            triangles,
            materials,
            bvh,
            bounds,
            blocks,
            smooth: std::sync::OnceLock::new(),
        }
    }

    /// Returns area-weighted vertex normals (computed once, on first call), for meshes whose file
    /// has none; oriented like the faces' `(v1 − v0) × (v2 − v0)`.
    pub fn smooth_normals(&self) -> &[Vec3A] {
        self.smooth.get_or_init(|| {
            let mut acc = vec![Vec3A::ZERO; self.positions.len()];
            for t in &self.triangles {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                let n = (b - a).cross(c - a); // length = twice the area: area weighting
                for &i in t {
                    acc[i as usize] += n;
                }
            }
            acc.into_iter().map(|n| n.normalize_or_zero()).collect()
        })
    }

    /// Returns the bytes of triangle data kept for tracing only, beyond the shared attributes.
    pub fn tracer_bytes(&self) -> usize {
        std::mem::size_of_val(self.blocks.as_slice())
    }

    /// Returns the closest triangle hit by an object-space ray and its barycentrics.
    pub fn intersect(&self, ray: &Ray) -> Option<(u32, TriangleHit)> {
        let shear = RayShear::new(ray);
        let scalar = self.bvh.kernel() == Kernel::Scalar;
        let mut best = None;
        self.bvh.closest_leaf(
            ray,
            #[inline(always)]
            |r, leaf| {
                let block = &self.blocks[leaf as usize];
                let hit = if scalar {
                    block.closest_scalar(&shear, r.tmin, r.tmax)
                } else {
                    block.closest(&shear, r.tmin, r.tmax)
                };
                match hit {
                    Some((lane, h)) => {
                        best = Some((leaf, lane, h));
                        h.t
                    }
                    None => f32::INFINITY,
                }
            },
        );
        best.map(|(leaf, lane, h)| (self.bvh.leaves()[leaf as usize].first + lane, h))
    }

    /// Returns the `t` of some triangle on the ray within `(tmin, tmax)` (any hit, not the closest).
    pub fn any_hit(&self, ray: &Ray) -> Option<f32> {
        let shear = RayShear::new(ray);
        let scalar = self.bvh.kernel() == Kernel::Scalar;
        let mut found = None;
        self.bvh.any_leaf(
            ray,
            #[inline(always)]
            |r, leaf| {
                let block = &self.blocks[leaf as usize];
                found = if scalar {
                    block.any_scalar(&shear, r.tmin, r.tmax)
                } else {
                    block.any(&shear, r.tmin, r.tmax)
                };
                found.is_some()
            },
        );
        found
    }
}
