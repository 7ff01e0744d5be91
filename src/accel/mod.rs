//! Bounding volume hierarchies, everything BVH: the builders, the wide nodes and their SIMD slab
//! tests, the mesh BLAS ([`mesh::MeshGeom`]) and its four-triangle SIMD blocks ([`tri4`]). The
//! only module that imports obvhs.
//!
//! Two builders ([`Builder`]) make the same kind of tree: an 8-wide BVH with float boxes stored
//! axis by axis ([`wide`]), so one AVX2 slab test (two SSE2 ones, or a scalar loop, see
//! [`Kernel`]) checks the eight children of a node, traversed by our own code, nearest child
//! first. Leaves hold at most [`MAX_LEAF`] primitives.
//!
//! - Triangle meshes use our binned SAH builder ([`sah`], [`Builder::BinnedSah`]). obvhs has no
//!   top-down SAH builder, and its PLOC path fell short of the geometry issue's bar on the
//!   2M-triangle wave mesh: 1.9 s to build on two threads (target under 1 s), and leaves a quarter
//!   empty (2.9 of 4 triangles) that traced at 0.6× Embree. The SAH builder takes 0.46–0.57 s
//!   there and traces about 1.35× faster (figures in `sah`'s docs and the issue 3 closing
//!   note).
//! - Scene-level BVHs over mixed primitives (analytic shapes, CSG trees, mesh instances) use
//!   obvhs's PLOC ([`Bvh::build`], [`Builder::Ploc`]): they hold a few to a few thousand
//!   boxes, where build time and tree quality hardly matter, and obvhs is the project's BVH
//!   library. `bench_traversal --builder ploc` measures the PLOC path on meshes too.
//!
//! Callers own the primitives: traversal hands a callback either a whole leaf ([`Bvh::closest_leaf`],
//! [`Bvh::any_leaf`]; see [`Bvh::leaves`]) or each *BVH-order* index of a candidate ([`Bvh::closest`],
//! [`Bvh::any`]; see [`Bvh::order`]), and the callback returns the hit's `t`, or infinity on a miss.
//! Callers that store their primitives in BVH order index them directly.
//!
//! Three ways to trace, all giving each ray the same closest `t` (`docs/traversal.md` has the
//! measurements and the choice between them):
//! - one ray at a time ([`Bvh::closest_leaf`]): what the renderer uses today;
//! - a stream of incoherent rays, sixteen in flight, interleaved so that their cache misses
//!   overlap ([`Bvh::closest_leaf_stream`], [`stream`]): about 1.8 times the single-ray rate on
//!   random rays over a 2M-triangle mesh, the same hits bit for bit;
//! - a stream of coherent rays in packets of eight that share each node's test
//!   ([`Bvh::closest_leaf_packets`], AVX2): 1.2 (closest hit) to 1.35 (any hit) times the
//!   single-ray rate on camera rays.
//!
//! [`mesh::MeshGeom::intersect_stream`] picks between the last two by a [`stream::Coherence`]
//! hint, as Embree's `rtcIntersect1M` takes its context's coherence flag.
//!
//! Two things obvhs leaves to its users: boxes are padded so flat
//! primitives do not get zero-thickness boxes that non-conservative slab tests can miss, and the
//! callbacks must reject `t <= tmin` themselves.

pub mod counters;
pub mod mesh;
#[cfg(target_arch = "x86_64")]
mod packet;
mod ploc;
mod sah;
mod stack;
pub mod stream;
pub mod tri4;
mod wide;

pub use wide::{Kernel, Leaf};

use crate::geometry::Ray;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use std::ops::Range;
use wide::WideBvh;

/// How a [`Bvh`] is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// obvhs's PLOC (medium preset) with its reinsertion and leaf collapse, then collapsed to 8
    /// wide: the general builder, for scene-level BVHs over mixed primitives.
    Ploc,
    /// Our top-down binned SAH builder ([`sah`]): full 4-triangle leaves and 8-wide nodes, built
    /// in parallel; several times faster than PLOC on big meshes and traced faster too.
    BinnedSah,
}

impl Builder {
    /// Names the configuration, for benchmark reports.
    pub fn name(self) -> &'static str {
        match self {
            Builder::Ploc => "bvh8-ploc-medium",
            Builder::BinnedSah => "bvh8-sah16",
        }
    }
}

/// The most primitives a leaf holds (one 4-wide SIMD test of triangles). A node's child can be
/// a pair of leaves (see [`sah`]).
pub const MAX_LEAF: usize = 4;

/// An axis-aligned box; `min <= max` on every axis for a non-empty box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Bounds {
    /// Returns the empty box (the identity of [`Bounds::union`]).
    pub const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    /// Returns the smallest box holding `self` and point `p`.
    pub fn grow(self, p: Vec3A) -> Bounds {
        Bounds {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Returns the smallest box holding both boxes.
    pub fn union(self, o: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Returns true when every coordinate is finite (an empty box is not).
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Returns the box grown by a margin relative to its coordinates' magnitude.
    fn padded(self) -> Bounds {
        let scale = self.min.abs().max(self.max.abs()).max_element();
        let pad = Vec3A::splat(scale * 1e-6 + 1e-12);
        Bounds {
            min: self.min - pad,
            max: self.max + pad,
        }
    }
}

/// A BVH over boxes. With fewer than two primitives there is no tree: an empty one misses, a
/// single primitive is always tested.
pub struct Bvh {
    inner: Option<WideBvh>,
    len: usize,
}

/// The BVH order and the leaf of a one-primitive BVH.
const SINGLE: [u32; 1] = [0];
const SINGLE_LEAF: [Leaf; 1] = [Leaf { first: 0, count: 1 }];

impl Bvh {
    /// Builds a BVH over `boxes` with obvhs's PLOC ([`Builder::Ploc`]); the boxes must all be
    /// finite (callers check and name the culprit).
    pub fn build(boxes: &[Bounds]) -> Bvh {
        Bvh::build_with(boxes, Builder::Ploc)
    }

    /// Builds a BVH over `boxes`, which must all be finite, with `builder`.
    pub fn build_with(boxes: &[Bounds], builder: Builder) -> Bvh {
        Bvh::build_by(boxes.len(), |i| boxes[i], builder)
    }

    /// Builds a BVH over `len` primitives whose boxes `box_of(i)` gives (all finite), with
    /// `builder`, without an array of boxes: the binned SAH builder asks for each box once, as
    /// it makes its references. For a big mesh that array was 32 bytes a triangle written, faulted
    /// in and read back for nothing.
    pub fn build_by(len: usize, box_of: impl Fn(usize) -> Bounds + Sync, builder: Builder) -> Bvh {
        if len < 2 {
            return Bvh { inner: None, len };
        }
        let inner = match builder {
            Builder::Ploc => {
                let aabbs: Vec<Aabb> = (0..len)
                    .map(|i| {
                        let b = box_of(i);
                        debug_assert!(b.is_finite());
                        let p = b.padded();
                        Aabb::new(p.min, p.max)
                    })
                    .collect();
                ploc::build(&aabbs)
            }
            Builder::BinnedSah => sah::build(len, box_of),
        };
        Bvh {
            inner: Some(inner),
            len,
        }
    }

    /// Returns the number of primitives.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Returns true when the BVH holds no primitive.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Returns, for each BVH-order index, the caller's primitive index.
    pub fn order(&self) -> &[u32] {
        match &self.inner {
            Some(b) => &b.order,
            None => &SINGLE[..self.len],
        }
    }

    /// Returns the leaves by leaf id: disjoint runs of BVH-order indices covering them all.
    pub fn leaves(&self) -> &[Leaf] {
        match &self.inner {
            Some(b) => &b.leaves,
            None => &SINGLE_LEAF[..self.len],
        }
    }

    /// Returns what is wrong with this BVH over primitives whose boxes `box_of(i)` gives (the
    /// caller's indices, as at the build), if anything: the checks of the wide BVH's own
    /// `validate` (a tree, the leaves a partition of the primitives, every box holding its
    /// subtree). Tests call it after every build.
    pub fn validate(&self, box_of: impl Fn(usize) -> Bounds) -> Result<(), String> {
        match &self.inner {
            Some(b) => b.validate(|j| box_of(b.order[j] as usize)),
            None if self.len <= 1 => Ok(()),
            None => Err(format!("{} primitives without a tree", self.len)),
        }
    }

    /// Returns the bytes the nodes, leaves and index take.
    pub fn bytes(&self) -> usize {
        self.inner.as_ref().map_or(0, WideBvh::bytes)
    }

    /// Returns the node test in use.
    pub fn kernel(&self) -> Kernel {
        self.inner.as_ref().map_or(Kernel::best(), WideBvh::kernel)
    }

    /// Uses node test `k`, or the fastest this CPU runs if it lacks `k` (for tests and
    /// benchmarks; [`Bvh::build`] picks the fastest); returns the one in use.
    pub fn set_kernel(&mut self, k: Kernel) -> Kernel {
        self.inner
            .as_mut()
            .map_or(k.min(Kernel::best()), |b| b.set_kernel(k))
    }

    /// Finds the closest hit leaf by leaf: `leaf_fn(ray, ids)` returns the smallest `t` in the
    /// ray's `(tmin, tmax)` among the primitives of leaves `ids` (indices into [`Bvh::leaves`]:
    /// one leaf, or two that the builder put side by side, five to eight primitives tested
    /// together), or infinity; the ray it sees has the closest `t` found so far as its `tmax`.
    ///
    /// `prefetch(ids)` is called for each leaf run the traversal puts on its stack, before
    /// `leaf_fn` sees it (if it does): a hint to start loading the run's primitives, whose cache
    /// misses then overlap the work on nearer children. Pass `|_| {}` when there is nothing to load.
    #[inline]
    pub fn closest_leaf(
        &self,
        ray: &Ray,
        mut leaf_fn: impl FnMut(&Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        match &self.inner {
            Some(bvh) => bvh.closest(ray, leaf_fn, prefetch),
            None => {
                if self.len == 1 {
                    leaf_fn(ray, 0..1);
                }
            }
        }
    }

    /// Returns true when `leaf_fn(ray, ids)` reports a hit in the ray's `(tmin, tmax)` among
    /// leaves `ids` (as for [`Bvh::closest_leaf`], with the same `prefetch` hook) for some run the
    /// ray reaches.
    #[inline]
    pub fn any_leaf(
        &self,
        ray: &Ray,
        mut leaf_fn: impl FnMut(&Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) -> bool {
        match &self.inner {
            Some(bvh) => bvh.any(ray, leaf_fn, prefetch),
            None => self.len == 1 && leaf_fn(ray, 0..1),
        }
    }

    /// [`Bvh::closest_leaf`] for every ray of `rays`, several in flight at once
    /// ([`stream`]): `leaf_fn(lane, i, ray, ids)` is the leaf callback for ray `i`, traced in
    /// lane `lane` (below [`stream::LANES`]). Each ray sees the calls that
    /// [`Bvh::closest_leaf`] makes, in the same order; calls for different rays interleave, and
    /// a lane's previous ray is done when the lane starts another.
    #[inline]
    pub fn closest_leaf_stream(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        match &self.inner {
            Some(bvh) => bvh.closest_stream(rays, leaf_fn, prefetch),
            None => {
                if self.len == 1 {
                    for (i, r) in rays.iter().enumerate() {
                        leaf_fn(0, i, r, 0..1);
                    }
                }
            }
        }
    }

    /// [`Bvh::any_leaf`] for every ray of `rays`, several in flight at once: `leaf_fn(lane, i,
    /// ray, ids)` as for [`Bvh::closest_leaf_stream`]; a ray is done once its callback returns
    /// true.
    #[inline]
    pub fn any_leaf_stream(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) {
        match &self.inner {
            Some(bvh) => bvh.any_stream(rays, leaf_fn, prefetch),
            None => {
                if self.len == 1 {
                    for (i, r) in rays.iter().enumerate() {
                        leaf_fn(0, i, r, 0..1);
                    }
                }
            }
        }
    }

    /// [`Bvh::closest_leaf`] for every ray of `rays`, coherent rays (neighbouring camera rays)
    /// taken in packets of eight that share each node's test where the CPU has AVX2, else one
    /// by one: `leaf_fn(i, ray, ids)` is the leaf callback for ray `i`. Each ray sees the calls
    /// it would see alone, though possibly in another order of leaves.
    #[inline]
    pub fn closest_leaf_packets(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        match &self.inner {
            Some(bvh) => bvh.closest_packets(rays, leaf_fn, prefetch),
            None => {
                if self.len == 1 {
                    for (i, r) in rays.iter().enumerate() {
                        leaf_fn(i, r, 0..1);
                    }
                }
            }
        }
    }

    /// [`Bvh::any_leaf`] for every ray of `rays`, in packets as [`Bvh::closest_leaf_packets`]:
    /// `leaf_fn(i, ray, ids)` for ray `i`, which is done once its callback returns true.
    #[inline]
    pub fn any_leaf_packets(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) {
        match &self.inner {
            Some(bvh) => bvh.any_packets(rays, leaf_fn, prefetch),
            None => {
                if self.len == 1 {
                    for (i, r) in rays.iter().enumerate() {
                        leaf_fn(i, r, 0..1);
                    }
                }
            }
        }
    }

    /// Finds the closest hit: `hit_fn(ray, i)` returns the `t` of BVH-order primitive `i` within
    /// the ray's current `(tmin, tmax)`, or infinity. Returns the index and `t` of the closest.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        mut hit_fn: impl FnMut(&Ray, usize) -> f32,
    ) -> Option<(usize, f32)> {
        let leaves = self.leaves();
        let mut best = None;
        self.closest_leaf(
            ray,
            |r, ids| {
                let mut r = *r;
                for i in ids.flat_map(|id| leaves[id as usize].range()) {
                    let t = hit_fn(&r, i);
                    if t > r.tmin && t < r.tmax {
                        best = Some((i, t));
                        r.tmax = t;
                    }
                }
                r.tmax
            },
            |_| {},
        );
        best
    }

    /// Returns true when any primitive reports a hit with `t` in the ray's `(tmin, tmax)`.
    #[inline]
    pub fn any(&self, ray: &Ray, mut hit_fn: impl FnMut(&Ray, usize) -> f32) -> bool {
        let leaves = self.leaves();
        self.any_leaf(
            ray,
            |r, ids| {
                ids.flat_map(|id| leaves[id as usize].range())
                    .any(|i| hit_fn(r, i) < r.tmax)
            },
            |_| {},
        )
    }
}

/// Stack of each worker thread: an eye path recurses once per bounce, up to
/// [`crate::integrator::eye::MAX_PATH_DEPTH`] bounces between facing mirrors, which overflows
/// the 2 MiB a thread gets by default (an abort, not an error). Reserved, not committed: only
/// the pages a deep path touches are used.
pub const WORKER_STACK_BYTES: usize = 16 << 20;

/// Starts the process's worker threads with [`WORKER_STACK_BYTES`] of stack each (`threads` of
/// them, one per core by default), unless something started them already: the command line
/// starts them first ([`crate::cli`]), and a library caller gets them from the scene build.
/// Returns whether this call started them.
pub fn start_workers(threads: Option<usize>) -> Result<bool, rayon::ThreadPoolBuildError> {
    static STARTED: std::sync::Mutex<bool> = std::sync::Mutex::new(false);
    let mut started = STARTED.lock().unwrap_or_else(|e| e.into_inner());
    if *started {
        return Ok(false);
    }
    let mut builder = rayon::ThreadPoolBuilder::new().stack_size(WORKER_STACK_BYTES);
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    *started = true;
    builder.build_global().map(|()| true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    fn unit_box(c: Vec3A) -> Bounds {
        Bounds {
            min: c - Vec3A::splat(0.5),
            max: c + Vec3A::splat(0.5),
        }
    }

    /// Brute force and BVH agree on the closest of many boxes (each box reports its entry t),
    /// with every node test.
    #[test]
    fn closest_matches_brute_force() {
        let boxes: Vec<Bounds> = (0..200)
            .map(|i| {
                let f = i as f32;
                unit_box(Vec3A::new(
                    (f * 1.7).sin() * 20.0,
                    (f * 0.9).cos() * 20.0,
                    (f * 2.3).sin() * 20.0,
                ))
            })
            .collect();
        let slab = |b: &Bounds, r: &Ray| -> f32 {
            let t0 = (b.min - r.origin) / r.dir;
            let t1 = (b.max - r.origin) / r.dir;
            let near = t0.min(t1).max_element();
            let far = t0.max(t1).min_element();
            if near <= far && near > r.tmin && near < r.tmax {
                near
            } else {
                f32::INFINITY
            }
        };
        for (builder, kernel) in BUILDERS
            .iter()
            .flat_map(|&b| [Kernel::Scalar, Kernel::Sse2, Kernel::Avx2].map(|k| (b, k)))
        {
            let mut bvh = Bvh::build_with(&boxes, builder);
            bvh.set_kernel(kernel);
            for k in 0..500 {
                let f = k as f32;
                let ray = Ray::new(
                    Vec3A::new(0.0, 0.0, 0.0),
                    Vec3A::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.13).sin() + 0.01)
                        .normalize(),
                );
                let brute = boxes
                    .iter()
                    .map(|b| slab(b, &ray))
                    .fold(f32::INFINITY, f32::min);
                let order = bvh.order().to_vec();
                let got = bvh
                    .closest(&ray, |r, i| slab(&boxes[order[i] as usize], r))
                    .map(|h| h.1);
                let what = format!("{builder:?} {kernel:?}, ray {k}");
                assert_eq!(got.unwrap_or(f32::INFINITY), brute, "{what}");
                let any = bvh.any(&ray, |r, i| slab(&boxes[order[i] as usize], r));
                assert_eq!(any, brute.is_finite(), "{what}");
            }
        }
    }

    /// The prefetch hook names leaf runs the traversal goes on to test: with an any-hit callback
    /// that never reports a hit (nothing is culled), every run prefetched is then tested, and
    /// every closest-hit prefetch is a run that exhaustive search tests too. Rays cross a grid of
    /// boxes, so many nodes have several leaf children and the hook must be called.
    #[test]
    fn prefetched_leaf_runs_are_runs_the_traversal_tests() {
        // Small boxes scattered through a cube: a node with eight children left over leaves of
        // five to eight as pairs, and the hook must name both of a pair's leaves.
        let mut x = 12345u32;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1 << 24) as f32 * 16.0
        };
        let grid: Vec<Bounds> = (0..20_000)
            .map(|_| {
                let c = Vec3A::new(next(), next(), next());
                Bounds {
                    min: c - 0.2,
                    max: c + 0.2,
                }
            })
            .collect();
        let (mut prefetched_total, mut pairs) = (0, 0);
        for kernel in [Kernel::Scalar, Kernel::Sse2, Kernel::Avx2] {
            let mut bvh = Bvh::build_with(&grid, Builder::BinnedSah);
            bvh.set_kernel(kernel);
            for k in 0..300 {
                let f = k as f32;
                let ray = Ray::new(
                    Vec3A::new(-5.0, 7.5, 7.5),
                    Vec3A::new(1.0, (f * 0.37).sin() * 0.5, (f * 0.91).cos() * 0.5).normalize(),
                );
                let (tested, prefetched) = (RefCell::new(Vec::new()), RefCell::new(Vec::new()));
                let hit = bvh.any_leaf(
                    &ray,
                    |_, ids| {
                        tested.borrow_mut().push(ids);
                        false
                    },
                    |ids| prefetched.borrow_mut().push(ids),
                );
                assert!(!hit);
                let (tested, prefetched) = (tested.into_inner(), prefetched.into_inner());
                for ids in &prefetched {
                    pairs += (ids.len() == 2) as usize;
                    assert!(
                        tested.contains(ids),
                        "{kernel:?}, ray {k}: {ids:?} never tested"
                    );
                }
                prefetched_total += prefetched.len();
                let closest_prefetched = RefCell::new(Vec::new());
                bvh.closest_leaf(
                    &ray,
                    |r, ids| {
                        // Each leaf reports a hit just beyond the ray's start, so later runs are
                        // culled: prefetches must still name runs that exist.
                        assert!(tested.contains(&ids));
                        r.tmin + 1.0 + ids.start as f32 * 1e-3
                    },
                    |ids| closest_prefetched.borrow_mut().push(ids),
                );
                for ids in closest_prefetched.into_inner() {
                    assert!(tested.contains(&ids), "{kernel:?}, ray {k}: {ids:?}");
                }
            }
        }
        assert!(
            prefetched_total > 1000,
            "the hook was called {prefetched_total} times"
        );
        assert!(pairs > 100, "{pairs} pairs prefetched");
    }

    #[test]
    fn empty_and_single() {
        let ray = Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z);
        assert!(Bvh::build(&[]).closest(&ray, |_, _| 1.0).is_none());
        let one = Bvh::build(&[unit_box(Vec3A::ZERO)]);
        assert_eq!(one.closest(&ray, |_, _| 4.5), Some((0, 4.5)));
        assert!(one.any(&ray, |_, _| 4.5));
        assert_eq!(one.leaves(), &[Leaf { first: 0, count: 1 }]);
    }

    /// Leaves cover every BVH-order index once, each leaf inside the box of its node slot, and
    /// every node inside its parent's slot; for both builders, on a grid of boxes, on boxes that
    /// all coincide (no split plane separates them) and on a mix.
    #[test]
    fn leaves_partition_the_order() {
        let grid: Vec<Bounds> = (0..1000)
            .map(|i| {
                let c = Vec3A::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32);
                unit_box(c)
            })
            .collect();
        let same = vec![unit_box(Vec3A::new(3.0, -2.0, 1.0)); 5000];
        let mixed: Vec<Bounds> = grid.iter().chain(&same).copied().collect();
        for boxes in [&grid, &same, &mixed] {
            for builder in BUILDERS {
                check_partition(boxes, &Bvh::build_with(boxes, builder), builder);
            }
        }
    }

    /// `validate` finds each kind of damage: a child box that does not hold a primitive, a
    /// node reached twice, a leaf reached twice, and an order that is not a permutation.
    #[test]
    fn validate_finds_a_broken_bvh() {
        let boxes: Vec<Bounds> = (0..500)
            .map(|i| {
                unit_box(Vec3A::new(
                    (i % 10) as f32,
                    (i / 10 % 10) as f32,
                    (i / 100) as f32,
                ))
            })
            .collect();
        for builder in BUILDERS {
            let fresh = || Bvh::build_with(&boxes, builder);
            assert_eq!(fresh().validate(|i| boxes[i]), Ok(()));
            let broken = |damage: &dyn Fn(&mut WideBvh)| {
                let mut bvh = fresh();
                damage(bvh.inner.as_mut().unwrap());
                bvh.validate(|i| boxes[i]).unwrap_err()
            };
            let e = broken(&|b| b.nodes[0].planes[1][0] = b.nodes[0].planes[0][0]);
            assert!(e.contains("does not hold"), "{e}");
            let e = broken(&|b| {
                let inner = (0..wide::WIDTH).find(|&s| b.nodes[0].child[s] & wide::LEAF == 0);
                let s = inner.unwrap();
                let (c, boxes) = (b.nodes[0].child[s], b.nodes[0].planes);
                let t = (s + 1) % wide::WIDTH;
                b.nodes[0].child[t] = c;
                for (p, plane) in boxes.iter().enumerate() {
                    b.nodes[0].planes[p][t] = plane[s];
                }
            });
            assert!(e.contains("twice"), "{e}");
            let e = broken(&|b| b.order[3] = b.order[4]);
            assert!(e.contains("order holds"), "{e}");
            let e = broken(&|b| b.leaves[1] = b.leaves[0]);
            assert!(
                e.contains("two leaves") || e.contains("does not hold"),
                "{e}"
            );
        }
    }

    const BUILDERS: [Builder; 2] = [Builder::Ploc, Builder::BinnedSah];

    fn check_partition(boxes: &[Bounds], bvh: &Bvh, builder: Builder) {
        assert_eq!(bvh.validate(|i| boxes[i]), Ok(()), "{builder:?}");
        let mut seen = vec![0; boxes.len()];
        for l in bvh.leaves() {
            assert!((1..=MAX_LEAF as u32).contains(&l.count));
            for i in l.first..l.first + l.count {
                seen[bvh.order()[i as usize] as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        let inner = bvh.inner.as_ref().unwrap();
        for n in &inner.nodes {
            for (slot, &c) in n.child.iter().enumerate() {
                if c & wide::LEAF == 0 || n.planes[0][slot] > n.planes[1][slot] {
                    continue;
                }
                for id in wide::leaf_ids(c) {
                    let l = inner.leaves[id as usize];
                    for i in l.first..l.first + l.count {
                        let b = boxes[inner.order[i as usize] as usize];
                        for a in 0..3 {
                            assert!(n.planes[2 * a][slot] <= b.min[a]);
                            assert!(b.max[a] <= n.planes[2 * a + 1][slot]);
                        }
                    }
                }
            }
        }
        // PLOC pairs coincident boxes into a deep chain (the traversal stack then moves to the
        // heap); the SAH builder halves them.
        if builder == Builder::BinnedSah || boxes.len() == 1000 {
            assert!(inner.stack_len <= 256, "{builder:?}: {}", inner.stack_len);
        }
        // Each inner node's child boxes lie inside the parent slot's box.
        for n in &inner.nodes {
            for (slot, &c) in n.child.iter().enumerate() {
                if c & wide::LEAF != 0 || n.planes[0][slot] > n.planes[1][slot] {
                    continue;
                }
                let kid = &inner.nodes[c as usize];
                for k in 0..wide::WIDTH {
                    if kid.planes[0][k] > kid.planes[1][k] {
                        continue;
                    }
                    for a in 0..3 {
                        assert!(n.planes[2 * a][slot] <= kid.planes[2 * a][k], "{builder:?}");
                        assert!(kid.planes[2 * a + 1][k] <= n.planes[2 * a + 1][slot]);
                    }
                }
            }
        }
    }

    /// The binned SAH builder makes the same tree, byte for byte, on one thread and on two (it
    /// bins and builds subtrees in parallel above a size), and fills its leaves and nodes.
    #[test]
    fn binned_sah_is_deterministic_and_full() {
        // A bumpy height field of 200k thin boxes, like a triangle mesh's.
        let n = 320;
        let boxes: Vec<Bounds> = (0..n * n * 2)
            .map(|i| {
                let (x, z) = ((i / 2 % n) as f32, (i / 2 / n) as f32);
                let y = (x * 0.1).sin() + (z * 0.07).cos();
                Bounds {
                    min: Vec3A::new(x, y, z),
                    max: Vec3A::new(x + 1.0, y + 0.05 * (i % 2) as f32, z + 1.0),
                }
            })
            .collect();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Bvh::build_with(&boxes, Builder::BinnedSah))
        };
        let (a, b) = (build(1), build(2));
        let (a, b) = (a.inner.unwrap(), b.inner.unwrap());
        assert_eq!(a.order, b.order);
        assert_eq!(a.leaves, b.leaves);
        assert_eq!(a.nodes.len(), b.nodes.len());
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            assert_eq!(x.child, y.child);
            assert_eq!(
                x.planes.map(|r| r.map(f32::to_bits)),
                y.planes.map(|r| r.map(f32::to_bits))
            );
        }
        // Leaves are (nearly) full, and nodes are not sparse.
        let per_leaf = boxes.len() as f64 / a.leaves.len() as f64;
        assert!(per_leaf > 3.8, "{per_leaf:.2} boxes per leaf");
        let used = |n: &wide::Node| {
            (0..wide::WIDTH)
                .filter(|&k| n.planes[0][k] <= n.planes[1][k])
                .count()
        };
        let per_node = a.nodes.iter().map(used).sum::<usize>() as f64 / a.nodes.len() as f64;
        assert!(per_node > 5.0, "{per_node:.2} children per node");
    }
}
