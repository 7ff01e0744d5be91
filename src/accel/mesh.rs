//! The bottom level of the scene's two-level BVH: a triangle mesh ready for tracing, with its own
//! BVH and its triangles packed four to a block ([`super::tri4::Tri4`]).
//!
//! [`MeshGeom::new`] reorders a [`MeshData`]'s triangles into BVH order and copies each leaf's
//! corners into one contiguous block, which the SIMD kernels test at once. Object-space rays
//! only: the scene transforms a ray into the instance's space before calling
//! [`MeshGeom::intersect`] or [`MeshGeom::any_hit`].
//!
//! ```lua
//! cow = gr.mesh('cow', 'cow.obj')   -- one MeshGeom, however many nodes place it
//! ```

use crate::accel::stream::{Coherence, LANES as LANES_IN_FLIGHT};
use crate::accel::tri4::Tri4;
#[cfg(target_arch = "x86_64")]
use crate::accel::tri4::{self, LANES};
use crate::accel::{Bounds, Builder, Bvh, Kernel};
use crate::geometry::Ray;
use crate::geometry::mesh::MeshData;
use crate::geometry::triangle::{RayShear, TriangleHit};
use glam::Vec3A;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// A BVH leaf's triangles as traversal reads them: their corners, and the BVH-order index of
/// the first, so that a hit names its triangle from the cache lines just tested. Looking it up in
/// [`Bvh::leaves`] instead cost a random ray one more cache miss per hit, which the traversal
/// could not hide (perf: 10% of the closest-hit samples on incoherent rays). The 16 bytes it adds
/// to a block (144 -> 160) do not add a cache line: a block at a 16-byte boundary already spans
/// three.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Block {
    tris: Tri4,
    first: u32,
    _pad: [u32; 3],
}

/// A mesh ready for tracing: its [`MeshData`] shared with the scene's mesh cache (attributes in
/// object space, triangles in the file's order), and what tracing adds: the BVH, whose order
/// maps a BVH-order triangle index to the file's, and each leaf's corners in one block.
///
/// Nothing of the data is copied: at 33.5M triangles the copies (positions, normals and uvs as
/// `Vec3A`, the triangles in BVH order) were 1.07 GB, a third of the traceable mesh; a hit
/// reads its triangle through [`Bvh::order`], one more load per shaded hit, none in traversal.
pub struct MeshGeom {
    data: Arc<MeshData>,
    /// Scene material (index into `Scene::materials`) of each triangle, in BVH order, or empty
    /// when the file carries no materials.
    pub materials: Vec<u32>,
    pub bvh: Bvh,
    pub bounds: Bounds,
    /// The corners of each BVH leaf's triangles, by leaf id ([`Bvh::leaves`]): what traversal
    /// reads, one contiguous record tested at once instead of indices and scattered positions.
    blocks: Vec<Block>,
    /// Area-weighted vertex normals, computed on first use (Perlin noise needs smooth normals).
    smooth: std::sync::OnceLock<Vec<Vec3A>>,
}

impl MeshGeom {
    /// Builds the mesh's BVH; the file's materials become scene materials from `first_material`
    /// on.
    ///
    /// Positions must be finite, and `triangle_materials` empty or parallel to `triangles` with
    /// every entry below `materials.len()` (the scene builder checks both).
    pub fn new(data: impl Into<Arc<MeshData>>, first_material: u32) -> MeshGeom {
        MeshGeom::with_builder(data, first_material, Builder::BinnedSah)
    }

    /// [`MeshGeom::new`] with the BVH built by `builder` (for benchmarks and tests).
    pub fn with_builder(
        data: impl Into<Arc<MeshData>>,
        first_material: u32,
        builder: Builder,
    ) -> MeshGeom {
        let data: Arc<MeshData> = data.into();
        let corner = |i: u32| Vec3A::from(data.positions[i as usize]);
        let box_of = |t: usize| {
            data.triangles[t]
                .iter()
                .fold(Bounds::EMPTY, |b, &i| b.grow(corner(i)))
        };
        let bvh = Bvh::build_by(data.triangles.len(), box_of, builder);
        let materials = if data.triangle_materials.is_empty() {
            Vec::new()
        } else {
            bvh.order()
                .iter()
                .map(|&i| first_material + data.triangle_materials[i as usize])
                .collect()
        };
        // The blocks, and the mesh's bounds from the corners on the way (a pass of its own over
        // every triangle's corners took 6-10 ms of a 2M-triangle build).
        let leaves = bvh.leaves();
        let order = bvh.order();
        let mut blocks: Vec<Block> = crate::mem::huge_vec(leaves.len());
        let bounds = blocks.spare_capacity_mut()[..leaves.len()]
            .par_iter_mut()
            .zip(leaves)
            .map(|(slot, l)| {
                let mut corners = [[Vec3A::ZERO; 3]; 4];
                let range = l.first as usize..(l.first + l.count) as usize;
                let mut b = Bounds::EMPTY;
                for (c, &t) in corners.iter_mut().zip(&order[range]) {
                    *c = data.triangles[t as usize].map(corner);
                    b = c.iter().fold(b, |b, &p| b.grow(p));
                }
                slot.write(Block {
                    tris: Tri4::new(&corners[..l.count as usize]),
                    first: l.first,
                    _pad: [0; 3],
                });
                b
            })
            .reduce(|| Bounds::EMPTY, Bounds::union);
        // SAFETY: the loop above wrote each of the first `leaves.len()` slots.
        unsafe { blocks.set_len(leaves.len()) };
        MeshGeom {
            data,
            materials,
            bvh,
            bounds,
            blocks,
            smooth: std::sync::OnceLock::new(),
        }
    }

    /// Returns the mesh's data: attributes, and triangles in the file's order.
    pub fn data(&self) -> &MeshData {
        &self.data
    }

    /// Returns the number of triangles.
    pub fn len(&self) -> usize {
        self.data.triangles.len()
    }

    /// Returns true when the mesh has no triangle.
    pub fn is_empty(&self) -> bool {
        self.data.triangles.is_empty()
    }

    /// Returns the vertex indices of the triangle with BVH-order index `prim` (what a hit names).
    #[inline]
    pub fn triangle(&self, prim: u32) -> [u32; 3] {
        self.data.triangles[self.bvh.order()[prim as usize] as usize]
    }

    /// Returns the corners of the triangle with BVH-order index `prim`, in object space.
    #[inline]
    pub fn corners(&self, prim: u32) -> [Vec3A; 3] {
        self.triangle(prim)
            .map(|i| Vec3A::from(self.data.positions[i as usize]))
    }

    /// Returns area-weighted vertex normals (computed once, on first call), for meshes whose file
    /// has none; oriented like the faces' `(v1 − v0) × (v2 − v0)`.
    pub fn smooth_normals(&self) -> &[Vec3A] {
        self.smooth.get_or_init(|| {
            let positions = &self.data.positions;
            let mut acc = vec![Vec3A::ZERO; positions.len()];
            for t in &self.data.triangles {
                let [a, b, c] = t.map(|i| Vec3A::from(positions[i as usize]));
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

    /// Returns what is wrong with the mesh's BVH, if anything: the wide BVH's checks
    /// ([`Bvh::validate`]) over its triangles' boxes, in BVH order.
    pub fn validate(&self) -> Result<(), String> {
        let box_at = |j: usize| {
            let [a, b, c] = self.corners(j as u32);
            Bounds {
                min: a.min(b).min(c),
                max: a.max(b).max(c),
            }
        };
        match &self.bvh.inner {
            Some(bvh) => bvh.validate(box_at),
            None => Ok(()),
        }
    }

    /// Returns the closest triangle hit by an object-space ray and its barycentrics.
    pub fn intersect(&self, ray: &Ray) -> Option<(u32, TriangleHit)> {
        // Made at the first leaf: most random rays miss the mesh's box and never need it.
        let mut shear = None;
        let kernel = self.bvh.kernel();
        let mut best = None;
        self.bvh.closest_leaf(
            ray,
            #[inline(always)]
            |r, ids| {
                let shear = shear.get_or_insert_with(|| RayShear::new(ray));
                let blocks = self.leaf_blocks(ids);
                let (found, tmax) = closest_in(blocks, kernel, shear, r.tmin, r.tmax);
                if found.is_some() {
                    best = found;
                }
                tmax
            },
            #[inline(always)]
            |id| self.prefetch_leaf(id),
        );
        best
    }

    /// Returns the `t` of some triangle on the ray within `(tmin, tmax)` (any hit, not the closest).
    pub fn any_hit(&self, ray: &Ray) -> Option<f32> {
        let mut shear = None;
        let kernel = self.bvh.kernel();
        let mut found = None;
        self.bvh.any_leaf(
            ray,
            #[inline(always)]
            |r, ids| {
                let shear = shear.get_or_insert_with(|| RayShear::new(ray));
                let blocks = self.leaf_blocks(ids);
                found = any_in(blocks, kernel, shear, r.tmin, r.tmax);
                found.is_some()
            },
            #[inline(always)]
            |id| self.prefetch_leaf(id),
        );
        found
    }

    /// [`MeshGeom::intersect`] for every ray of `rays`, into `out` (the same length).
    /// [`Coherence::Incoherent`] rays are traced sixteen at a time, interleaved so that their
    /// cache misses overlap ([`crate::accel::stream`]), and give the same hits bit for bit;
    /// coherent ones in packets of eight that share each node's test (AVX2; one by one
    /// elsewhere), and give the same `t` bit for bit, though where two triangles are hit at
    /// exactly that `t` (a ray through a shared edge) the packet may name the other one.
    ///
    /// # Panics
    /// When `out` and `rays` differ in length.
    pub fn intersect_stream(
        &self,
        rays: &[Ray],
        out: &mut [Option<(u32, TriangleHit)>],
        coherence: Coherence,
    ) {
        let Some(mut q) = StreamQuery::new(rays, out, self.bvh.kernel()) else {
            return;
        };
        match coherence {
            Coherence::Incoherent => self.bvh.closest_leaf_stream(
                rays,
                #[inline(always)]
                |lane, i, r, ids| self.closest_into(&mut q, lane, i, r, ids),
                #[inline(always)]
                |id| self.prefetch_leaf(id),
            ),
            Coherence::Coherent => self.bvh.closest_leaf_packets(
                rays,
                #[inline(always)]
                |i, r, ids| self.closest_into(&mut q, i % LANES_IN_FLIGHT, i, r, ids),
                #[inline(always)]
                |id| self.prefetch_leaf(id),
            ),
        }
    }

    /// [`MeshGeom::any_hit`] for every ray of `rays`, into `out` (the same length), traced as
    /// [`MeshGeom::intersect_stream`] traces them: incoherent rays give the same answers bit for
    /// bit, coherent ones the same occlusion, though possibly another hit's `t`.
    ///
    /// # Panics
    /// When `out` and `rays` differ in length.
    pub fn any_hit_stream(&self, rays: &[Ray], out: &mut [Option<f32>], coherence: Coherence) {
        let Some(mut q) = StreamQuery::new(rays, out, self.bvh.kernel()) else {
            return;
        };
        match coherence {
            Coherence::Incoherent => self.bvh.any_leaf_stream(
                rays,
                #[inline(always)]
                |lane, i, r, ids| self.any_into(&mut q, lane, i, r, ids),
                #[inline(always)]
                |id| self.prefetch_leaf(id),
            ),
            Coherence::Coherent => self.bvh.any_leaf_packets(
                rays,
                #[inline(always)]
                |i, r, ids| self.any_into(&mut q, i % LANES_IN_FLIGHT, i, r, ids),
                #[inline(always)]
                |id| self.prefetch_leaf(id),
            ),
        }
    }

    /// A stream's closest-hit leaf callback: tests leaves `ids` for ray `i` (`r`, with its
    /// closest hit so far as `tmax`) in lane `lane`, keeps a hit in `q`'s results and returns
    /// where the ray now ends.
    #[inline(always)]
    fn closest_into(
        &self,
        q: &mut StreamQuery<(u32, TriangleHit)>,
        lane: usize,
        i: usize,
        r: &Ray,
        ids: Range<u32>,
    ) -> f32 {
        let blocks = self.leaf_blocks(ids);
        let shear = q.shears.get(lane, i);
        let (found, tmax) = closest_in(blocks, q.kernel, shear, r.tmin, r.tmax);
        if found.is_some() {
            q.out[i] = found;
        }
        tmax
    }

    /// A stream's any-hit leaf callback, as [`MeshGeom::closest_into`]: returns whether ray `i`
    /// hits a triangle of leaves `ids`.
    #[inline(always)]
    fn any_into(
        &self,
        q: &mut StreamQuery<f32>,
        lane: usize,
        i: usize,
        r: &Ray,
        ids: Range<u32>,
    ) -> bool {
        let blocks = self.leaf_blocks(ids);
        let shear = q.shears.get(lane, i);
        q.out[i] = any_in(blocks, q.kernel, shear, r.tmin, r.tmax);
        q.out[i].is_some()
    }

    /// The blocks of leaves `ids`, counted as triangle tests (when counting is on).
    #[inline(always)]
    fn leaf_blocks(&self, ids: Range<u32>) -> &[Block] {
        self.count(&ids);
        &self.blocks[ids.start as usize..ids.end as usize]
    }

    /// Starts loading every cache line of the blocks of leaves `ids`, a leaf child that the
    /// traversal has just put on its stack, so that their misses overlap the work on nearer
    /// children instead of waiting until the entry is popped.
    #[inline(always)]
    fn prefetch_leaf(&self, ids: Range<u32>) {
        let base = self.blocks.as_ptr();
        let start = base.wrapping_add(ids.start as usize) as usize & !63;
        let end = base.wrapping_add(ids.end as usize) as usize;
        for line in (start..end).step_by(64) {
            super::wide::prefetch_line(line as *const u8);
        }
    }

    /// Counts the triangle tests of leaves `ids` (when counting is on).
    #[inline(always)]
    fn count(&self, ids: &Range<u32>) {
        super::counters::triangles(|| {
            let leaves = &self.bvh.leaves()[ids.start as usize..ids.end as usize];
            leaves.iter().map(|l| l.count).sum()
        });
    }
}

/// What a stream query's leaf callbacks share: the results, each lane's ray shear and the
/// kernel.
struct StreamQuery<'a, T> {
    out: &'a mut [Option<T>],
    shears: LaneShears<'a>,
    kernel: Kernel,
}

impl<'a, T> StreamQuery<'a, T> {
    /// Clears `out` (one result per ray); None for an empty stream.
    ///
    /// # Panics
    /// When `out` and `rays` differ in length.
    fn new(rays: &'a [Ray], out: &'a mut [Option<T>], kernel: Kernel) -> Option<Self> {
        assert_eq!(rays.len(), out.len(), "one result per ray");
        out.fill_with(|| None);
        Some(StreamQuery {
            shears: LaneShears::new(rays)?,
            out,
            kernel,
        })
    }
}

/// Each stream lane's ray shear (a packet's rays take lanes by their index): made at the ray's
/// first leaf, as [`MeshGeom::intersect`] makes it (most random rays miss the mesh's box and
/// never need one).
struct LaneShears<'a> {
    rays: &'a [Ray],
    /// Per lane: the ray whose shear it holds, and the shear.
    made: [(usize, RayShear); LANES_IN_FLIGHT],
}

impl<'a> LaneShears<'a> {
    /// Returns None for an empty stream.
    fn new(rays: &'a [Ray]) -> Option<LaneShears<'a>> {
        let first = RayShear::new(rays.first()?);
        Some(LaneShears {
            rays,
            made: [(usize::MAX, first); LANES_IN_FLIGHT],
        })
    }

    /// Returns ray `i`'s shear, traced in lane `lane`.
    #[inline(always)]
    fn get(&mut self, lane: usize, i: usize) -> &RayShear {
        let s = &mut self.made[lane];
        if s.0 != i {
            *s = (i, RayShear::new(&self.rays[i]));
        }
        &s.1
    }
}

/// Returns the closest hit among one block or a pair (its triangle and hit) and the `t` the ray
/// ends at: the hit's, or infinity. The AVX2 kernel tests a pair's eight lanes at once; the
/// others test the blocks one after the other, which finds the same hit (lowest lane on a tie).
#[inline(always)]
fn closest_in(
    blocks: &[Block],
    kernel: Kernel,
    shear: &RayShear,
    tmin: f32,
    tmax: f32,
) -> (Option<(u32, TriangleHit)>, f32) {
    #[cfg(target_arch = "x86_64")]
    if let [a, b] = blocks
        && kernel == Kernel::Avx2
    {
        // SAFETY: the kernel is `Avx2` only where the CPU has AVX2 (`Bvh::set_kernel`).
        let hit = unsafe { tri4::closest_pair(&a.tris, &b.tris, shear, tmin, tmax) };
        return match hit {
            Some((lane, h)) => {
                let block = if lane < LANES as u32 { a } else { b };
                (Some((block.first + lane % LANES as u32, h)), h.t)
            }
            None => (None, f32::INFINITY),
        };
    }
    let mut best = None;
    let mut tmax = tmax;
    for block in blocks {
        let hit = if kernel == Kernel::Scalar {
            block.tris.closest_scalar(shear, tmin, tmax)
        } else {
            block.tris.closest(shear, tmin, tmax)
        };
        if let Some((lane, h)) = hit {
            best = Some((block.first + lane, h));
            tmax = h.t;
        }
    }
    let t = best.map_or(f32::INFINITY, |(_, h)| h.t);
    (best, t)
}

/// Returns the `t` of some hit among one block or a pair, the first in lane order.
#[inline(always)]
fn any_in(blocks: &[Block], kernel: Kernel, shear: &RayShear, tmin: f32, tmax: f32) -> Option<f32> {
    #[cfg(target_arch = "x86_64")]
    if let [a, b] = blocks
        && kernel == Kernel::Avx2
    {
        // SAFETY: as in `closest_in`.
        return unsafe { tri4::any_pair(&a.tris, &b.tris, shear, tmin, tmax) };
    }
    for block in blocks {
        let t = if kernel == Kernel::Scalar {
            block.tris.any_scalar(shear, tmin, tmax)
        } else {
            block.tris.any(shear, tmin, tmax)
        };
        if t.is_some() {
            return t;
        }
    }
    None
}
