//! The 8-wide BVH we trace: each node holds up to eight children whose float boxes are stored
//! plane by plane, one lane per child, so one AVX2 slab test (or two SSE2 ones) checks all eight.
//!
//! Traversal continues with the nearest child it enters and keeps the others on a stack, nearest
//! on top (the single-ray scheme of Embree's BVH4/BVH8 kernels, Wald et al., "Embree: A Kernel
//! Framework for Efficient CPU Ray Tracing", 2014). A popped entry is skipped when the closest hit
//! found so far lies in front of it. Nodes are prefetched where the CPU cannot start the load by
//! itself: a node's child references (the line that the slab test's mask indexes), the inner
//! children pushed on the stack, and, through the caller's `prefetch` hook, the primitives of the
//! leaf children pushed there. A plane `p` is met at `p * inv_dir - origin * inv_dir`, one fused
//! multiply-add with the product `origin * inv_dir` made once per ray (as Embree's kernels do):
//! the scalar and AVX2 kernels evaluate the same IEEE operations in the same order, so both
//! visit the same nodes and report the same hits. SSE2 has no fused multiply-add, so its kernel
//! (for x86-64 CPUs without AVX2 and FMA) meets a plane at `(p - origin) * inv_dir`, which may
//! differ from the others in the last bit of a distance: the boxes' padding covers either
//! rounding (`Bounds::padded`), so it finds the same hits, though in a grazing case it may visit
//! a different node or break a tie between equally near triangles the other way.
//!
//! Why the fused form: it takes one operation per plane instead of two, and shortens each
//! node's dependency chain by a multiply; measured on the 2M-triangle wave mesh in ten
//! alternating rounds against Embree 3's AVX2 kernels (`tools/embree_rounds.sh`, Zen 4 VM), the
//! median ratios went, in two such runs, from 0.96 to 0.98–0.99 (camera rays, closest hit), 1.02
//! to 1.02–1.05 (camera rays, shadow), 0.98 to 0.99–1.00 (incoherent, closest) and 1.02 to 1.11
//! (incoherent, shadow), with the same hits, checksums and images.
//!
//! Why float boxes and not quantised ones (the compressed wide nodes of Ylitie et al., HPG 2017,
//! and of Embree's compact mode, which the traversal issue suggested): we built them, a byte per
//! plane on a power-of-two grid per node and axis, 128 bytes a node instead of 256, conservative
//! and giving the same hits. On the 2M-triangle wave mesh (Zen 4 VM, alternating runs) camera
//! rays lost 17-20% (0.156 -> 0.187 s for 1M closest-hit rays): they find their nodes in cache,
//! so each node's test waits on its own arithmetic, and the dequantisation (widen the bytes,
//! convert, multiply, add) lengthens that chain by about a third, even folded into the ray as
//! `q * (step * inv) + (origin - o) * inv`. Incoherent rays, which wait on memory, gained
//! nothing measurable (0.175-0.200 s before, 0.185-0.204 s after): a node is one miss whether
//! it spans two lines or four, and halving the nodes (25 -> 13 MB) did not keep them in the
//! 32 MB L3 beside 81 MB of triangle blocks.

use super::stack::{Entry, Stack};
use super::stream;
use crate::geometry::Ray;
use glam::Vec3A;
use std::ops::Range;

/// Children per node.
pub(super) const WIDTH: usize = 8;

/// Marks a child that is a leaf; the bits below [`PAIR`] are its leaf id.
pub(super) const LEAF: u32 = 1 << 31;
/// Marks a leaf child made of two leaves, `id` and `id + 1` (a run of five to eight primitives
/// tested as two blocks, without a node of its own; see `sah`).
pub(super) const PAIR: u32 = 1 << 30;

/// Returns the leaf ids of a leaf child: one, or two with [`PAIR`].
#[inline(always)]
pub(super) fn leaf_ids(child: u32) -> Range<u32> {
    let id = child & !(LEAF | PAIR);
    id..id + 1 + (child & PAIR != 0) as u32
}

/// A node: up to eight children, each an inner node or a leaf.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    /// Child boxes by plane: min x, max x, min y, max y, min z, max z; one lane per child. An
    /// empty slot holds the inverted box (min +∞, max −∞), which no ray enters.
    pub(super) planes: [[f32; WIDTH]; 6],
    /// Per child: the inner node's index, or [`LEAF`] | the leaf's id (with [`PAIR`]: two).
    pub(super) child: [u32; WIDTH],
}

impl Node {
    pub(super) const EMPTY: Node = Node {
        planes: [
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [0; WIDTH],
    };

    /// Stores child `slot`'s box.
    pub(super) fn set_box(&mut self, slot: usize, min: Vec3A, max: Vec3A) {
        for axis in 0..3 {
            self.planes[2 * axis][slot] = min[axis];
            self.planes[2 * axis + 1][slot] = max[axis];
        }
    }
}

/// A run of BVH-order primitives that the traversal hands to the caller at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leaf {
    /// The first BVH-order primitive.
    pub first: u32,
    /// The number of primitives, 1 to [`super::MAX_LEAF`].
    pub count: u32,
}

impl Leaf {
    /// The leaf's BVH-order primitives.
    pub fn range(&self) -> Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }
}

/// The SIMD code that tests a node's eight boxes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kernel {
    /// One box at a time (any CPU).
    Scalar,
    /// Two 4-wide SSE2 tests (every x86-64 CPU), without fused multiply-adds (see the module
    /// docs).
    Sse2,
    /// One 8-wide AVX2 test with fused multiply-adds (chosen at run time where the CPU has AVX2
    /// and FMA).
    Avx2,
}

impl Kernel {
    /// Returns the fastest kernel this CPU runs.
    pub fn best() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                Kernel::Avx2
            } else {
                Kernel::Sse2
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Kernel::Scalar
    }
}

/// An 8-wide BVH, root at node 0.
pub(super) struct WideBvh {
    pub(super) nodes: Vec<Node>,
    /// The leaves, by leaf id.
    pub(super) leaves: Vec<Leaf>,
    /// For each BVH-order index, the caller's primitive index.
    pub(super) order: Vec<u32>,
    /// Stack entries a traversal can need: `WIDTH - 1` per level below the root, plus one.
    pub(super) stack_len: usize,
    /// The node test in use; never one the CPU lacks (checked by [`WideBvh::set_kernel`]).
    kernel: Kernel,
}

impl WideBvh {
    /// Wraps built nodes (root at 0), choosing the fastest kernel; `depth` counts node levels.
    pub(super) fn new(nodes: Vec<Node>, leaves: Vec<Leaf>, order: Vec<u32>, depth: usize) -> Self {
        WideBvh {
            nodes,
            leaves,
            order,
            stack_len: (WIDTH - 1) * depth + 1,
            kernel: Kernel::best(),
        }
    }

    /// Returns the bytes the nodes, leaves and order take.
    pub(super) fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.leaves.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
    }

    pub(super) fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Uses `k`, or the fastest kernel this CPU runs if it lacks `k`; returns the one in use.
    pub(super) fn set_kernel(&mut self, k: Kernel) -> Kernel {
        self.kernel = k.min(Kernel::best());
        self.kernel
    }

    /// Finds the closest hit: `leaf_fn(ray, ids)` returns the smallest `t` below the ray's
    /// current `tmax` among the primitives of leaves `ids` (one leaf, or a [`PAIR`]'s two), or
    /// infinity; the ray it sees carries the closest `t` so far as `tmax`. `prefetch(ids)` is
    /// told of each leaf child put on the stack, to start loading what `leaf_fn` will read.
    #[inline(always)]
    pub(super) fn closest(
        &self,
        ray: &Ray,
        leaf_fn: impl FnMut(&Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `kernel` is `Avx2` only where `Kernel::best` detected AVX2 and FMA.
            Kernel::Avx2 => unsafe { closest_avx2(self, ray, leaf_fn, prefetch) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Sse2 => closest_with::<Sse2>(self, ray, leaf_fn, prefetch),
            _ => closest_with::<Scalar>(self, ray, leaf_fn, prefetch),
        }
    }

    /// Returns true when `leaf_fn(ray, ids)` reports a hit for some run of leaves (one, or a
    /// [`PAIR`]'s two) the ray reaches; `prefetch` as for [`WideBvh::closest`].
    #[inline(always)]
    pub(super) fn any(
        &self,
        ray: &Ray,
        leaf_fn: impl FnMut(&Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) -> bool {
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `kernel` is `Avx2` only where `Kernel::best` detected AVX2 and FMA.
            Kernel::Avx2 => unsafe { any_avx2(self, ray, leaf_fn, prefetch) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Sse2 => any_with::<Sse2>(self, ray, leaf_fn, prefetch),
            _ => any_with::<Scalar>(self, ray, leaf_fn, prefetch),
        }
    }
}

impl WideBvh {
    /// Returns what is wrong with this BVH, if anything, given the box of the primitive at each
    /// BVH-order index (`box_at(j)`, for `j` below `order.len()`):
    /// - `order` is a permutation of the primitives;
    /// - the nodes form a tree from the root: every child index in range, every node reached
    ///   once, and no deeper than the traversal stack ([`WideBvh::stack_len`]) holds;
    /// - every leaf is reached once and holds 1 to [`super::MAX_LEAF`] primitives, the leaves
    ///   cover the BVH order once, and a [`PAIR`] names two leaves side by side;
    /// - an empty slot holds the inverted box; every other child box is finite and holds its
    ///   subtree: the boxes of a child node's children, the primitives of a leaf.
    pub(super) fn validate(&self, box_at: impl Fn(usize) -> super::Bounds) -> Result<(), String> {
        let n = self.order.len();
        let mut seen = vec![false; n];
        for &i in &self.order {
            match seen.get_mut(i as usize) {
                Some(s) if !*s => *s = true,
                _ => return Err(format!("order holds {i} twice or out of range (of {n})")),
            }
        }
        let mut node_seen = vec![false; self.nodes.len()];
        let mut leaf_seen = vec![false; self.leaves.len()];
        let mut covered = vec![false; n];
        // (node, depth in node levels), from the root.
        let mut todo = vec![(0usize, 1usize)];
        while let Some((i, depth)) = todo.pop() {
            let node = self.nodes.get(i).ok_or(format!("node {i} out of range"))?;
            if std::mem::replace(&mut node_seen[i], true) {
                return Err(format!("node {i} is reached twice"));
            }
            if (WIDTH - 1) * depth + 1 > self.stack_len {
                return Err(format!(
                    "node {i} is {depth} levels deep, beyond the stack's"
                ));
            }
            for slot in 0..WIDTH {
                let (min, max) = slot_box(node, slot);
                let empty =
                    min.cmpeq(Vec3A::INFINITY).all() && max.cmpeq(Vec3A::NEG_INFINITY).all();
                if empty {
                    continue;
                }
                if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
                    return Err(format!("node {i} slot {slot}: box {min}..{max}"));
                }
                let holds = |b: super::Bounds| min.cmple(b.min).all() && b.max.cmple(max).all();
                let c = node.child[slot];
                if c & LEAF == 0 {
                    let child = self
                        .nodes
                        .get(c as usize)
                        .ok_or(format!("node {i} slot {slot}: child {c} out of range"))?;
                    for s in 0..WIDTH {
                        let (cmin, cmax) = slot_box(child, s);
                        let inverted = cmin.cmpgt(cmax).any();
                        if !inverted
                            && !holds(super::Bounds {
                                min: cmin,
                                max: cmax,
                            })
                        {
                            return Err(format!(
                                "node {i} slot {slot} does not hold node {c}'s child {s}"
                            ));
                        }
                    }
                    todo.push((c as usize, depth + 1));
                    continue;
                }
                for id in leaf_ids(c) {
                    let leaf = self
                        .leaves
                        .get(id as usize)
                        .ok_or(format!("node {i} slot {slot}: leaf {id} out of range"))?;
                    if std::mem::replace(&mut leaf_seen[id as usize], true) {
                        return Err(format!("leaf {id} is reached twice"));
                    }
                    if !(1..=super::MAX_LEAF as u32).contains(&leaf.count) || leaf.range().end > n {
                        return Err(format!(
                            "leaf {id}: {} primitives from {}",
                            leaf.count, leaf.first
                        ));
                    }
                    for j in leaf.range() {
                        if std::mem::replace(&mut covered[j], true) {
                            return Err(format!("BVH-order primitive {j} is in two leaves"));
                        }
                        if !holds(box_at(j)) {
                            return Err(format!(
                                "node {i} slot {slot} does not hold primitive {j} of leaf {id}"
                            ));
                        }
                    }
                }
            }
        }
        if let Some(l) = leaf_seen.iter().position(|s| !s) {
            return Err(format!("leaf {l} is not reached"));
        }
        if let Some(j) = covered.iter().position(|c| !c) {
            return Err(format!("BVH-order primitive {j} is in no leaf"));
        }
        Ok(())
    }
}

/// Returns child `slot`'s box in `node` (inverted for an empty slot).
fn slot_box(node: &Node, slot: usize) -> (Vec3A, Vec3A) {
    let p = &node.planes;
    (
        Vec3A::new(p[0][slot], p[2][slot], p[4][slot]),
        Vec3A::new(p[1][slot], p[3][slot], p[5][slot]),
    )
}

impl WideBvh {
    /// [`WideBvh::closest`] for each ray of a stream, [`super::stream::LANES`] rays in flight:
    /// `leaf_fn(lane, i, ray, ids)` is the leaf callback for ray `i` of `rays`, traced in lane
    /// `lane` (below `LANES`; a lane's previous ray is done when it starts another).
    #[inline(always)]
    pub(super) fn closest_stream(
        &self,
        rays: &[Ray],
        leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `kernel` is `Avx2` only where `Kernel::best` detected AVX2 and FMA.
            Kernel::Avx2 => unsafe { closest_stream_avx2(self, rays, leaf_fn, prefetch) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Sse2 => stream::closest_with::<Sse2>(self, rays, leaf_fn, prefetch),
            _ => stream::closest_with::<Scalar>(self, rays, leaf_fn, prefetch),
        }
    }

    /// [`WideBvh::any`] for each ray of a stream: `leaf_fn(lane, i, ray, ids)` as for
    /// [`WideBvh::closest_stream`]; a ray is done once its callback returns true.
    #[inline(always)]
    pub(super) fn any_stream(
        &self,
        rays: &[Ray],
        leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) {
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `closest_stream`.
            Kernel::Avx2 => unsafe { any_stream_avx2(self, rays, leaf_fn, prefetch) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Sse2 => stream::any_with::<Sse2>(self, rays, leaf_fn, prefetch),
            _ => stream::any_with::<Scalar>(self, rays, leaf_fn, prefetch),
        }
    }
}

impl WideBvh {
    /// [`WideBvh::closest`] for each ray of `rays`, in packets of [`super::packet::PACKET`]
    /// where the kernel is AVX2, else one by one: `leaf_fn(i, ray, ids)` for ray `i`.
    #[inline(always)]
    pub(super) fn closest_packets(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> f32,
        prefetch: impl Fn(Range<u32>),
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.kernel == Kernel::Avx2 {
            // SAFETY: `kernel` is `Avx2` only where `Kernel::best` detected AVX2 and FMA.
            return unsafe { super::packet::closest(self, rays, leaf_fn, prefetch) };
        }
        for (i, r) in rays.iter().enumerate() {
            self.closest(r, |r, ids| leaf_fn(i, r, ids), &prefetch);
        }
    }

    /// [`WideBvh::any`] for each ray of `rays`, in packets where the kernel is AVX2:
    /// `leaf_fn(i, ray, ids)` for ray `i`, which is done once its callback returns true.
    #[inline(always)]
    pub(super) fn any_packets(
        &self,
        rays: &[Ray],
        mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> bool,
        prefetch: impl Fn(Range<u32>),
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.kernel == Kernel::Avx2 {
            // SAFETY: as in `closest_packets`.
            return unsafe { super::packet::any(self, rays, leaf_fn, prefetch) };
        }
        for (i, r) in rays.iter().enumerate() {
            self.any(r, |r, ids| leaf_fn(i, r, ids), &prefetch);
        }
    }
}

/// [`stream::closest_with`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn closest_stream_avx2(
    bvh: &WideBvh,
    rays: &[Ray],
    leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> f32,
    prefetch: impl Fn(Range<u32>),
) {
    stream::closest_with::<Avx2>(bvh, rays, leaf_fn, prefetch)
}

/// [`stream::any_with`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn any_stream_avx2(
    bvh: &WideBvh,
    rays: &[Ray],
    leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> bool,
    prefetch: impl Fn(Range<u32>),
) {
    stream::any_with::<Avx2>(bvh, rays, leaf_fn, prefetch)
}

/// [`closest_with`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn closest_avx2(
    bvh: &WideBvh,
    ray: &Ray,
    leaf_fn: impl FnMut(&Ray, Range<u32>) -> f32,
    prefetch: impl Fn(Range<u32>),
) {
    closest_with::<Avx2>(bvh, ray, leaf_fn, prefetch)
}

/// [`any_with`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn any_avx2(
    bvh: &WideBvh,
    ray: &Ray,
    leaf_fn: impl FnMut(&Ray, Range<u32>) -> bool,
    prefetch: impl Fn(Range<u32>),
) -> bool {
    any_with::<Avx2>(bvh, ray, leaf_fn, prefetch)
}

/// Closest-hit traversal with node test `T`.
#[inline(always)]
fn closest_with<T: NodeTest>(
    bvh: &WideBvh,
    ray: &Ray,
    mut leaf_fn: impl FnMut(&Ray, Range<u32>) -> f32,
    prefetch: impl Fn(Range<u32>),
) {
    let pre = SlabRay::new(ray);
    let mut r = *ray;
    Stack::with_capacity(
        bvh.stack_len,
        #[inline(always)]
        |mut stack| {
            let mut cur = Entry {
                child: 0,
                t: ray.tmin,
            };
            loop {
                if cur.child & LEAF == 0 {
                    super::counters::node();
                    let node = &bvh.nodes[cur.child as usize];
                    prefetch_children(node);
                    let (mask, tnear) = T::enter(&pre, node, r.tmax);
                    if mask != 0 {
                        cur = nearest_first(node, mask, &tnear, &mut stack, |e| {
                            prefetch_entry(bvh, e.child, &prefetch)
                        });
                        continue;
                    }
                } else {
                    let t = leaf_fn(&r, leaf_ids(cur.child));
                    if t < r.tmax {
                        r.tmax = t;
                    }
                }
                match stack.pop_within(r.tmax) {
                    None => return,
                    Some(e) => cur = e,
                }
            }
        },
    )
}

/// Returns the nearest of `node`'s children in `mask` (not empty), entered at `tnear`, and
/// pushes the others on `stack`, nearest on top, telling `pushed` of each: the closest-hit
/// traversal's order, for single rays and streams alike.
#[inline(always)]
pub(super) fn nearest_first(
    node: &Node,
    mut mask: u32,
    tnear: &[f32; WIDTH],
    stack: &mut Stack,
    pushed: impl Fn(&Entry),
) -> Entry {
    let child = |c: u32| Entry {
        child: node.child[c as usize],
        t: tnear[c as usize],
    };
    let mut near = child(mask.trailing_zeros());
    mask &= mask - 1;
    let base = stack.len();
    while mask != 0 {
        let mut e = child(mask.trailing_zeros());
        mask &= mask - 1;
        pushed(&e);
        if e.t < near.t {
            std::mem::swap(&mut e, &mut near);
        }
        stack.insert_sorted(base, e);
    }
    near
}

/// Returns the first of `node`'s children in `mask` (not empty) and pushes the others in lane
/// order, telling `pushed` of each: the any-hit traversal's order, for single rays and streams
/// alike.
#[inline(always)]
pub(super) fn first_in_lane_order(
    node: &Node,
    mut mask: u32,
    stack: &mut Stack,
    pushed: impl Fn(u32),
) -> u32 {
    let first = node.child[mask.trailing_zeros() as usize];
    mask &= mask - 1;
    while mask != 0 {
        let child = node.child[mask.trailing_zeros() as usize];
        mask &= mask - 1;
        pushed(child);
        stack.push(Entry { child, t: 0.0 });
    }
    first
}

/// Any-hit traversal with node test `T`: children in lane order, no sorting.
#[inline(always)]
fn any_with<T: NodeTest>(
    bvh: &WideBvh,
    ray: &Ray,
    mut leaf_fn: impl FnMut(&Ray, Range<u32>) -> bool,
    prefetch: impl Fn(Range<u32>),
) -> bool {
    let pre = SlabRay::new(ray);
    Stack::with_capacity(
        bvh.stack_len,
        #[inline(always)]
        |mut stack| {
            let mut cur = 0;
            loop {
                if cur & LEAF == 0 {
                    super::counters::node();
                    let node = &bvh.nodes[cur as usize];
                    prefetch_children(node);
                    let (mask, _) = T::enter(&pre, node, ray.tmax);
                    if mask != 0 {
                        cur = first_in_lane_order(node, mask, &mut stack, |c| {
                            prefetch_entry(bvh, c, &prefetch)
                        });
                        continue;
                    }
                } else if leaf_fn(ray, leaf_ids(cur)) {
                    return true;
                }
                match stack.pop() {
                    None => return false,
                    Some(e) => cur = e.child,
                }
            }
        },
    )
}

/// Starts loading the cache line of `node`'s child references while the slab test waits for
/// its planes. The test picks a child by the mask it computes, so the CPU cannot issue that load
/// before the planes have arrived: without the hint an incoherent ray paid two cache misses in a
/// row per node.
#[inline(always)]
fn prefetch_children(node: &Node) {
    prefetch_line(node.child.as_ptr().cast());
}

/// Starts loading all four cache lines of inner node `child`, which the traversal has just put on
/// its stack: its misses then overlap the work on the nearer child instead of waiting until the
/// entry is popped.
#[inline(always)]
pub(super) fn prefetch_node(bvh: &WideBvh, child: u32) {
    let p: *const u8 = bvh.nodes.as_ptr().wrapping_add(child as usize).cast();
    for line in 0..4 {
        prefetch_line(p.wrapping_add(64 * line));
    }
}

/// Starts loading what child reference `child` (as in [`Node::child`]) refers to: an inner
/// node's four cache lines, or through the caller's `prefetch` hook a leaf run's primitives.
#[inline(always)]
pub(super) fn prefetch_entry(bvh: &WideBvh, child: u32, prefetch: &impl Fn(Range<u32>)) {
    if child & LEAF == 0 {
        prefetch_node(bvh, child);
    } else {
        prefetch(leaf_ids(child));
    }
}

/// Starts loading the cache line holding `p`: a hint, which never faults, whatever `p` is (the
/// one place the traversal and the mesh leaves issue prefetches).
#[inline(always)]
pub(super) fn prefetch_line(p: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint; it never faults, even on an invalid address.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Returns `1/x`, or `±1/ε` for `|x| <= ε`, so slab distances stay finite (obvhs's rule), with
/// `ε` relative to `size`, the direction's largest component: a ray moved into the object space
/// of an instance scaled by 1e5 is not renormalised, and an absolute `ε` there shortened a slab
/// to less than the distance to a triangle inside it (`tests/geometry/spawned_rays.rs`).
fn safe_inverse(x: f32, size: f32) -> f32 {
    let eps = (f32::EPSILON * size).max(f32::MIN_POSITIVE);
    if x.abs() <= eps {
        x.signum() / eps
    } else {
        1.0 / x
    }
}

/// A ray prepared for slab tests: reciprocal direction and which plane of each axis comes first.
pub(super) struct SlabRay {
    origin: [f32; 3],
    pub(super) inv_dir: [f32; 3],
    /// `origin * inv_dir` per axis, which the fused slab test subtracts.
    pub(super) org_inv: [f32; 3],
    /// Per axis, the plane row (`Node::planes`) the ray meets first and last.
    pub(super) near: [usize; 3],
    pub(super) far: [usize; 3],
    pub(super) tmin: f32,
}

impl SlabRay {
    #[inline(always)]
    pub(super) fn new(r: &Ray) -> SlabRay {
        let size = r.dir.abs().max_element();
        let inv_dir = [
            safe_inverse(r.dir.x, size),
            safe_inverse(r.dir.y, size),
            safe_inverse(r.dir.z, size),
        ];
        let neg = |a: usize| (inv_dir[a] < 0.0) as usize;
        SlabRay {
            origin: r.origin.to_array(),
            inv_dir,
            org_inv: [0, 1, 2].map(|a| r.origin[a] * inv_dir[a]),
            near: [neg(0), 2 + neg(1), 4 + neg(2)],
            far: [1 - neg(0), 3 - neg(1), 5 - neg(2)],
            tmin: r.tmin,
        }
    }
}

/// A node test: the mask of the children whose boxes the ray overlaps within `[tmin, tmax]`,
/// and the entry distance into each (lanes outside the mask are unspecified).
pub(super) trait NodeTest {
    fn enter(ray: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]);
}

/// The portable node test.
pub(super) struct Scalar;

impl NodeTest for Scalar {
    #[inline(always)]
    fn enter(s: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        enter_one_by_one(s, node, tmax, |p, axis| {
            p.mul_add(s.inv_dir[axis], -s.org_inv[axis])
        })
    }
}

/// The node test one child at a time, with `dist(plane, axis)` the ray's distance to a plane:
/// the scalar kernel's, and in tests the SSE2 kernel's formula.
#[inline(always)]
fn enter_one_by_one(
    s: &SlabRay,
    node: &Node,
    tmax: f32,
    dist: impl Fn(f32, usize) -> f32,
) -> (u32, [f32; WIDTH]) {
    let p = &node.planes;
    let mut tnear = [0.0f32; WIDTH];
    let mut mask = 0;
    // `max`/`min` spelled as comparisons to match the SIMD instructions lane for lane
    // (`maxps a, b` returns `b` unless `a > b`); no operand is NaN here anyway.
    let max = |a: f32, b: f32| if a > b { a } else { b };
    let min = |a: f32, b: f32| if a < b { a } else { b };
    for (c, tn) in tnear.iter_mut().enumerate() {
        let d = |row: usize, axis: usize| dist(p[row][c], axis);
        let near = max(
            max(d(s.near[0], 0), d(s.near[1], 1)),
            max(d(s.near[2], 2), s.tmin),
        );
        let far = min(
            min(d(s.far[0], 0), d(s.far[1], 1)),
            min(d(s.far[2], 2), tmax),
        );
        *tn = near;
        mask |= ((near <= far) as u32) << c;
    }
    (mask, tnear)
}

/// The SSE2 node test: the two halves of the node, four children each.
#[cfg(target_arch = "x86_64")]
pub(super) struct Sse2;

#[cfg(target_arch = "x86_64")]
impl NodeTest for Sse2 {
    #[inline(always)]
    fn enter(s: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        use std::arch::x86_64::*;
        let p = &node.planes;
        let mut tnear = [0.0f32; WIDTH];
        let mut mask = 0;
        for half in 0..2 {
            let lane = 4 * half;
            // SAFETY: SSE2 is part of the x86-64 baseline; `Node` is 64-byte aligned and each
            // plane row is 32 bytes, so every half row (16 bytes at a multiple of 16) suits an
            // aligned load; the store writes lanes `lane..lane + 4` of `tnear`, within its 8.
            unsafe {
                let dist = |row: usize, axis: usize| {
                    _mm_mul_ps(
                        _mm_sub_ps(
                            _mm_load_ps(p[row][lane..].as_ptr()),
                            _mm_set1_ps(s.origin[axis]),
                        ),
                        _mm_set1_ps(s.inv_dir[axis]),
                    )
                };
                let near = _mm_max_ps(
                    _mm_max_ps(dist(s.near[0], 0), dist(s.near[1], 1)),
                    _mm_max_ps(dist(s.near[2], 2), _mm_set1_ps(s.tmin)),
                );
                let far = _mm_min_ps(
                    _mm_min_ps(dist(s.far[0], 0), dist(s.far[1], 1)),
                    _mm_min_ps(dist(s.far[2], 2), _mm_set1_ps(tmax)),
                );
                _mm_storeu_ps(tnear[lane..].as_mut_ptr(), near);
                mask |= (_mm_movemask_ps(_mm_cmple_ps(near, far)) as u32) << lane;
            }
        }
        (mask, tnear)
    }
}

/// The AVX2 node test: all eight children at once. Only used inside `#[target_feature(enable =
/// "avx2")]` functions, which [`WideBvh`] calls only where the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
pub(super) struct Avx2;

#[cfg(target_arch = "x86_64")]
impl NodeTest for Avx2 {
    #[inline(always)]
    fn enter(s: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        use std::arch::x86_64::*;
        let p = &node.planes;
        let mut tnear = [0.0f32; WIDTH];
        // SAFETY: `Avx2` is only used by `closest_avx2` / `any_avx2`, which run only where
        // `Kernel::best` detected AVX2 and FMA, and into which this function is inlined (so are the
        // intrinsics: a separate `#[target_feature]` function was not inlined and cost 15 %).
        // `Node` is 64-byte aligned and each plane row is 32 bytes, so every row suits an
        // aligned 32-byte load; `tnear` takes an unaligned store.
        let mask = unsafe {
            let dist = |row: usize, axis: usize| {
                _mm256_fmsub_ps(
                    _mm256_load_ps(p[row].as_ptr()),
                    _mm256_set1_ps(s.inv_dir[axis]),
                    _mm256_set1_ps(s.org_inv[axis]),
                )
            };
            let near = _mm256_max_ps(
                _mm256_max_ps(dist(s.near[0], 0), dist(s.near[1], 1)),
                _mm256_max_ps(dist(s.near[2], 2), _mm256_set1_ps(s.tmin)),
            );
            let far = _mm256_min_ps(
                _mm256_min_ps(dist(s.far[0], 0), dist(s.far[1], 1)),
                _mm256_min_ps(dist(s.far[2], 2), _mm256_set1_ps(tmax)),
            );
            _mm256_storeu_ps(tnear.as_mut_ptr(), near);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32
        };
        (mask, tnear)
    }
}

/// Runs the AVX2 node test where the CPU has AVX2 (for tests).
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
fn enter_avx2(s: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
    Avx2::enter(s, node, tmax)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node with eight random boxes, some slots empty.
    fn node(seed: u32) -> Node {
        let mut n = Node::EMPTY;
        let mut x = seed.wrapping_mul(2_654_435_761);
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1 << 24) as f32 * 4.0 - 2.0
        };
        for slot in 0..WIDTH {
            if (seed as usize + slot).is_multiple_of(5) {
                continue;
            }
            let (a, b) = (
                Vec3A::new(next(), next(), next()),
                Vec3A::new(next(), next(), next()),
            );
            n.set_box(slot, a.min(b), a.max(b));
        }
        n
    }

    /// The SSE2 test's two roundings, `(p - origin) * inv_dir`, one child at a time.
    #[cfg(target_arch = "x86_64")]
    fn two_roundings(s: &SlabRay, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        enter_one_by_one(s, node, tmax, |p, a| (p - s.origin[a]) * s.inv_dir[a])
    }

    /// The scalar and AVX2 tests return the same mask and entry distances bit for bit; the SSE2
    /// test returns its two-rounding formula's bit for bit, within a few float steps of the
    /// fused ones.
    #[test]
    fn kernels_agree_bit_for_bit() {
        for k in 0..2000u32 {
            let n = node(k);
            let f = k as f32;
            let ray = Ray::new(
                Vec3A::new(
                    (f * 0.3).sin() * 3.0,
                    (f * 0.7).cos() * 3.0,
                    (f * 1.1).sin(),
                ),
                Vec3A::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.13).sin() + 0.01),
            );
            let s = SlabRay::new(&ray);
            let tmax = if k.is_multiple_of(3) {
                2.0
            } else {
                f32::INFINITY
            };
            let (m, t) = Scalar::enter(&s, &n, tmax);
            let keep = |t: [f32; WIDTH]| (0..WIDTH).map(|c| (m >> c) & 1 == 1).zip(t);
            let hits = |t: [f32; WIDTH]| {
                keep(t)
                    .filter(|x| x.0)
                    .map(|x| x.1.to_bits())
                    .collect::<Vec<_>>()
            };
            #[cfg(target_arch = "x86_64")]
            {
                let (m2, t2) = Sse2::enter(&s, &n, tmax);
                let (mr, tr) = two_roundings(&s, &n, tmax);
                let sse_hits = |t: [f32; WIDTH]| {
                    (0..WIDTH)
                        .filter(|c| (mr >> c) & 1 == 1)
                        .map(|c| t[c].to_bits())
                        .collect::<Vec<_>>()
                };
                assert_eq!((mr, sse_hits(tr)), (m2, sse_hits(t2)), "sse2, node {k}");
                for c in (0..WIDTH).filter(|c| (m & mr) >> c & 1 == 1) {
                    let scale = t[c].abs().max(1.0) * 1e-5;
                    assert!(
                        (t[c] - tr[c]).abs() <= scale,
                        "node {k}: {} {}",
                        t[c],
                        tr[c]
                    );
                }
                if Kernel::best() == Kernel::Avx2 {
                    // SAFETY: AVX2 and FMA were detected just above.
                    let (m3, t3) = unsafe { enter_avx2(&s, &n, tmax) };
                    assert_eq!((m, hits(t)), (m3, hits(t3)), "avx2, node {k}");
                }
            }
        }
    }
}
