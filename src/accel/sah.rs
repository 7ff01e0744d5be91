//! Our own builder: top-down binned SAH straight into 8-wide nodes, in parallel.
//!
//! Why not obvhs's PLOC for meshes: on the 2M-triangle wave mesh PLOC plus its reinsertion and
//! leaf collapse, then our collapse to 8 wide, took 1.9 s on two threads and left 2.9 triangles
//! per leaf (a quarter of every 4-wide triangle test wasted), while Embree's binned SAH builder
//! takes 0.5 s. obvhs has no top-down SAH builder (it builds by PLOC), so this is
//! the one in Wald's "On fast Construction of SAH-based Bounding Volume Hierarchies" (2007), shaped
//! like Embree's BVH8 builder:
//!
//! - primitives are 32-byte references (box and index) that are partitioned in place, so each
//!   level streams through memory instead of gathering boxes by index;
//! - a node starts with its whole range as one child and splits the child with the largest
//!   surface until it has eight ([`WIDTH`]) or none can be split; each split is the cheapest of
//!   [`BINS`] planes per axis over the centroids' extent, costed as area × 4-triangle blocks,
//!   because leaves are tested four at a time;
//! - a node splits every child of more than [`MAX_LEAF`] primitives while it has room; a child
//!   left with five to eight becomes a [`PAIR`] of leaves, tested one after the other, rather
//!   than a node of two leaves, so leaves are full and nodes are not sparse;
//! - ranges of [`PAR_BIN`] or more are binned by all threads, and subtrees of [`PAR_TREE`] or
//!   more are built in parallel into their own arrays, kept apart from their parent's and
//!   written into the final arrays once, in parallel ([`Sub::place`]); binning sums, minima and
//!   maxima do not depend on the order of the reduction, so the tree is the same for any number
//!   of threads;
//! - ranges of at most [`FEW`] references (most splits: a node opens its children down to
//!   leaves) find the same split by sorting the references by bin ([`best_of_few`]) rather than
//!   by filling and sweeping 3 × [`BINS`] bins;
//! - the partition decides a reference's side by comparing its scaled centroid with the plane
//!   ([`Binner::left_of`]) instead of computing its bins on every axis;
//! - a node of [`PAR_NODE`] or more references is opened by halving three times over, the two
//!   sides of each split at once, rather than by splitting the largest child seven times in a
//!   row: at the root the seven serial partitions over 64 MB of references kept the other
//!   threads idle (70 of the 365 ms on two threads). On the wave mesh both ways choose the same
//!   eight children (the checksums are equal).
//!
//! Measured on the wave mesh (2-core VM, `bench_traversal`): first 0.80–0.92 s on one thread and
//! 0.46–0.57 s on two; since the subtrees reserve their arrays, the boxes come from a function
//! instead of an array and the partition stops reading back what it swapped, 0.55–0.67 s and
//! 0.30–0.37 s (Embree 3's binned SAH, the same day: 0.58–0.72 s and 0.29–0.33 s). 3.95
//! triangles per leaf, 5.4 children per node, 55 B per triangle with the mesh's blocks; primary
//! rays 4.5–5.3 Mrays/s against 3.5–3.7 from the PLOC tree. Without pairs nodes averaged 3.2
//! children (ranges of five to eight triangles became nodes of two leaves) and the BVH took
//! 72 B per triangle. At 33.5M and 50M triangles, alternating rounds against Embree 3's medium
//! quality put this builder at 0.91 and 0.92 of its time on two threads (medians; single rounds
//! 0.79–1.07) and 0.95 and 0.81 on one (`docs/profiling.md`, "The builder's second pass").

use super::Bounds;
use super::MAX_LEAF;
use super::wide::{LEAF, Leaf, Node, PAIR, WIDTH, WideBvh};
use glam::{BVec4A, Vec4};
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// Split planes tried per axis.
const BINS: usize = 16;
/// Ranges at least this long are binned in parallel.
const PAR_BIN: usize = 1 << 16;
/// Nodes of ranges at least this long are opened by [`halve`], in parallel.
const PAR_NODE: usize = 1 << 18;
/// Subtrees at least this long are built in parallel.
const PAR_TREE: usize = 1 << 12;
/// Pairs of references ahead of the one binned whose line is prefetched.
const AHEAD: usize = 8;
/// Ranges at most this long find their split without bins ([`best_of_few`]).
const FEW: usize = 16;
/// Ranges at least this long are binned in two sets of bins ([`Bins::add`]).
const TWO_SETS: usize = 64;

/// A box; lane `w` carries no meaning (in a [`PrimRef`]'s `lo` it holds the index's bits).
#[derive(Clone, Copy, Debug)]
struct Box4 {
    lo: Vec4,
    hi: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 {
        lo: Vec4::splat(f32::INFINITY),
        hi: Vec4::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, o: &Box4) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    #[inline(always)]
    fn grow_point(&mut self, p: Vec4) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    /// Half the surface area (0 for an empty box).
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive reference: its box, with its index in `lo.w`.
type PrimRef = Box4;

#[inline(always)]
fn prim_index(p: &PrimRef) -> u32 {
    p.lo.w.to_bits()
}

/// Twice the centroid (the factor cancels in every use), lane `w` zero.
///
/// The index in `lo.w` is cleared by a bitwise select before the sum: as a float it is a
/// subnormal or a barely normal number, and without flush-to-zero (which `bench_traversal`
/// sets for its threads and the renderer does not) arithmetic on such values can take a
/// microcode assist per instruction. Summing it into the centroid made the renderer's build of
/// a 33.5M-triangle mesh 2.3 times slower than with the lane cleared (25.1 s against 10.9 s on
/// two threads; the 2M-triangle wave was unchanged within noise).
#[inline(always)]
fn centroid2(p: &PrimRef) -> Vec4 {
    Vec4::select(XYZ, p.lo, Vec4::ZERO) + p.hi
}

/// Lanes x, y and z of a [`Vec4`], for [`Vec4::select`].
const XYZ: BVec4A = BVec4A::new(true, true, true, false);

/// A run of references with its bounds and its centroids' bounds.
#[derive(Clone, Copy, Debug)]
struct Range {
    start: usize,
    end: usize,
    bounds: Box4,
    cent: Box4,
}

impl Range {
    fn len(&self) -> usize {
        self.end - self.start
    }
}

/// Maps centroids to bins along each axis.
#[derive(Clone, Copy)]
struct Binner {
    origin: Vec4,
    scale: Vec4,
}

impl Binner {
    fn new(cent: &Box4) -> Binner {
        let extent = cent.hi - cent.lo;
        let s = |e: f32| {
            if e > 0.0 {
                BINS as f32 * 0.999_99 / e
            } else {
                0.0
            }
        };
        Binner {
            origin: cent.lo,
            scale: Vec4::new(s(extent.x), s(extent.y), s(extent.z), 0.0),
        }
    }

    /// The bin of `p` along each axis (lane 3 unused).
    #[inline(always)]
    fn bins(&self, p: &PrimRef) -> [usize; 4] {
        // `max` first: it maps a NaN lane to 0 (SSE `maxps` returns its second operand then).
        let k = ((centroid2(p) - self.origin) * self.scale)
            .max(Vec4::ZERO)
            .min(Vec4::splat((BINS - 1) as f32));
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
            // One truncating conversion for all lanes; `as usize` on each float adds a
            // saturation check per lane, which made the whole build about 1.3× slower.
            // SAFETY: SSE2 is part of the x86-64 baseline; `Vec4` is an `__m128` there.
            let i: [i32; 4] = unsafe {
                std::mem::transmute::<__m128i, [i32; 4]>(_mm_cvttps_epi32(__m128::from(k)))
            };
            [i[0] as usize, i[1] as usize, i[2] as usize, 0]
        }
        #[cfg(not(target_arch = "x86_64"))]
        [k.x as usize, k.y as usize, k.z as usize, 0]
    }

    /// The test `bins(p)[axis] < plane` for `plane` in `1..BINS`, without the conversion to
    /// integers: a bin is the truncation of a scaled offset that is at least 0, so it is below
    /// the whole number `plane` exactly when the offset is, and clamping to the last bin never
    /// moves a reference across `plane`. The partition's test; 4–7% of the whole build.
    ///
    /// The axis is a constant ([`Binner::partition`] picks it once per split): indexing the
    /// centroid by a variable axis compiled to a jump table on every reference.
    #[inline(always)]
    fn left_of<const AXIS: usize>(&self, plane: usize) -> impl Fn(&PrimRef) -> bool + use<AXIS> {
        let (origin, scale, plane) = (self.origin[AXIS], self.scale[AXIS], plane as f32);
        move |p| (centroid2(p)[AXIS] - origin) * scale < plane
    }

    /// [`partition`]s `part` by [`Binner::left_of`] `plane` on `axis`.
    fn partition(&self, part: &mut [PrimRef], axis: usize, plane: usize) -> (usize, Side, Side) {
        match axis {
            0 => partition(part, self.left_of::<0>(plane)),
            1 => partition(part, self.left_of::<1>(plane)),
            _ => partition(part, self.left_of::<2>(plane)),
        }
    }
}

/// Per axis and bin: the union of the boxes and the count of the references binned there.
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Box4; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    fn empty() -> Bins {
        Bins {
            boxes: [[Box4::EMPTY; BINS]; 3],
            counts: [[0; BINS]; 3],
        }
    }

    fn add(&mut self, prims: &[PrimRef], b: &Binner) {
        if prims.len() < TWO_SETS {
            prims.iter().for_each(|p| self.bin(p, b));
            return;
        }
        // Two sets of bins, one for the even references and one for the odd, merged at the
        // end: neighbouring references of a coherent mesh fall in the same bin, and growing one
        // box twice in a row makes the second wait for the first's store (Embree bins in two
        // sets too). The sums, minima and maxima, and so the tree, are the same.
        let mut odd = Bins::empty();
        let (pairs, rest) = prims.as_chunks::<2>();
        for (k, [p, q]) in pairs.iter().enumerate() {
            super::wide::prefetch_line(pairs.as_ptr().wrapping_add(k + AHEAD).cast());
            self.bin(p, b);
            odd.bin(q, b);
        }
        rest.iter().for_each(|p| self.bin(p, b));
        self.merge(&odd);
    }

    #[inline(always)]
    fn bin(&mut self, p: &PrimRef, b: &Binner) {
        let k = b.bins(p);
        for (axis, &bin) in k[..3].iter().enumerate() {
            // `bins` never exceeds `BINS - 1`; the mask tells the compiler so.
            let bin = bin & (BINS - 1);
            self.boxes[axis][bin].grow(p);
            self.counts[axis][bin] += 1;
        }
    }

    fn merge(&mut self, o: &Bins) {
        for axis in 0..3 {
            for i in 0..BINS {
                self.boxes[axis][i].grow(&o.boxes[axis][i]);
                self.counts[axis][i] += o.counts[axis][i];
            }
        }
    }

    fn of(prims: &[PrimRef], b: &Binner) -> Bins {
        let of_chunk = |c: &[PrimRef]| {
            let mut bins = Bins::empty();
            bins.add(c, b);
            bins
        };
        if prims.len() >= PAR_BIN {
            prims
                .par_chunks(PAR_BIN / 4)
                .map(of_chunk)
                .reduce(Bins::empty, |mut x, y| {
                    x.merge(&y);
                    x
                })
        } else {
            of_chunk(prims)
        }
    }

    /// The cheapest split: (axis, first bin of the right side), or None when every axis has all
    /// references in one bin.
    fn best(&self) -> Option<(usize, usize)> {
        // Leaves are tested four triangles at a time: cost counts blocks of four.
        let blocks = |n: u32| n.div_ceil(MAX_LEAF as u32) as f32;
        let mut best = (f32::INFINITY, None);
        for axis in 0..3 {
            let (boxes, counts) = (&self.boxes[axis], &self.counts[axis]);
            let mut right_cost = [0.0f32; BINS];
            let mut right_n = [0u32; BINS];
            let (mut acc, mut n) = (Box4::EMPTY, 0);
            for i in (1..BINS).rev() {
                acc.grow(&boxes[i]);
                n += counts[i];
                right_cost[i] = acc.half_area() * blocks(n);
                right_n[i] = n;
            }
            let (mut acc, mut n) = (Box4::EMPTY, 0);
            for i in 1..BINS {
                acc.grow(&boxes[i - 1]);
                n += counts[i - 1];
                if n == 0 || right_n[i] == 0 {
                    continue;
                }
                let cost = acc.half_area() * blocks(n) + right_cost[i];
                if cost < best.0 {
                    best = (cost, Some((axis, i)));
                }
            }
        }
        best.1
    }
}

/// The split [`Bins::best`] finds for these references (at most [`FEW`]), found by sorting them
/// by bin on each axis and trying only the planes between occupied bins.
///
/// Why: most splits are of ranges of five to sixteen references (a node opens its children
/// down to leaves of four), and filling, sweeping and copying 3 × [`BINS`] bins for ten
/// references cost about a microsecond each time (timed per split on the 8.4M-triangle wave,
/// timers included, splits of 8 to 31 references took 1.4 of the 3.1 s spent binning; without
/// timers the whole build is 5–10% faster with this path). The answer is the same:
/// every plane between two occupied bins `a < b` parts the references alike and costs the same,
/// and [`Bins::best`] keeps the first, `a + 1`, which is the one returned here; the costs are
/// computed from the same unions in the same order, so they are equal to the bit.
fn best_of_few(prims: &[PrimRef], b: &Binner) -> Option<(usize, usize)> {
    let n = prims.len();
    debug_assert!(n <= FEW);
    let blocks = |n: usize| n.div_ceil(MAX_LEAF) as f32;
    // Per axis, (bin << 8) | index of each reference; sorted, the references in bin order.
    let mut keys = [[0u16; FEW]; 3];
    for (i, p) in prims.iter().enumerate() {
        for (axis_keys, &bin) in keys.iter_mut().zip(&b.bins(p)[..3]) {
            axis_keys[i] = (bin << 8 | i) as u16;
        }
    }
    let mut best = (f32::INFINITY, None);
    let mut right_cost = [0.0f32; FEW];
    for (axis, keys) in keys.iter_mut().enumerate() {
        let keys = &mut keys[..n];
        keys.sort_unstable();
        let bin = |j: usize| (keys[j] >> 8) as usize;
        let prim = |j: usize| &prims[(keys[j] & 0xff) as usize];
        let mut acc = Box4::EMPTY;
        for j in (1..n).rev() {
            acc.grow(prim(j));
            if bin(j - 1) != bin(j) {
                right_cost[j] = acc.half_area() * blocks(n - j);
            }
        }
        let mut acc = Box4::EMPTY;
        for (j, &right) in right_cost.iter().enumerate().take(n).skip(1) {
            acc.grow(prim(j - 1));
            if bin(j - 1) != bin(j) {
                let cost = acc.half_area() * blocks(j) + right;
                if cost < best.0 {
                    best = (cost, Some((axis, bin(j - 1) + 1)));
                }
            }
        }
    }
    best.1
}

/// Splits `r` in two non-empty ranges, reordering `part`, its references (at least two).
fn split(part: &mut [PrimRef], r: &Range) -> (Range, Range) {
    debug_assert_eq!(part.len(), r.len());
    let binner = Binner::new(&r.cent);
    let best = if part.len() <= FEW {
        best_of_few(part, &binner)
    } else {
        Bins::of(part, &binner).best()
    };
    let (mid, left, right) = match best {
        Some((axis, plane)) => binner.partition(part, axis, plane),
        None => {
            // All centroids in one bin on every axis (equal, or too close for f32 to separate):
            // any split costs the same, so halve the range by position along the widest axis.
            let axis = (r.cent.hi - r.cent.lo).truncate().max_position();
            let half = part.len() / 2;
            part.select_nth_unstable_by(half, |a, b| {
                centroid2(a)[axis].total_cmp(&centroid2(b)[axis])
            });
            let (l, rr) = part.split_at(half);
            (half, Side::of(l), Side::of(rr))
        }
    };
    let range = |s: Side, start: usize, end: usize| Range {
        start,
        end,
        bounds: s.bounds,
        cent: s.cent,
    };
    (
        range(left, r.start, r.start + mid),
        range(right, r.start + mid, r.end),
    )
}

/// Splits `r`, whose references are `part`, into two, then each side `depth - 1` times over, the
/// two sides of each split at once; ranges of [`MAX_LEAF`] or fewer are not split.
fn halve(part: &mut [PrimRef], r: Range, depth: u32) -> Vec<Range> {
    if depth == 0 || r.len() <= MAX_LEAF {
        return vec![r];
    }
    let (a, b) = split(part, &r);
    let (pa, pb) = part.split_at_mut(a.len());
    let (mut x, y) = rayon::join(|| halve(pa, a, depth - 1), || halve(pb, b, depth - 1));
    x.extend(y);
    x
}

/// The bounds and centroid bounds of some references.
#[derive(Clone, Copy)]
struct Side {
    bounds: Box4,
    cent: Box4,
}

impl Side {
    const EMPTY: Side = Side {
        bounds: Box4::EMPTY,
        cent: Box4::EMPTY,
    };

    #[inline(always)]
    fn add(&mut self, p: &PrimRef) {
        self.bounds.grow(p);
        self.cent.grow_point(centroid2(p));
    }

    fn of(s: &[PrimRef]) -> Side {
        let mut side = Side::EMPTY;
        s.iter().for_each(|p| side.add(p));
        side
    }

    fn merge(mut self, o: Side) -> Side {
        self.bounds.grow(&o.bounds);
        self.cent.grow(&o.cent);
        self
    }
}

/// Moves the references satisfying `left` to the front, measuring both sides on the way;
/// returns how many satisfy it and the two sides' bounds.
fn partition(s: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool) -> (usize, Side, Side) {
    let (mut l, mut r) = (Side::EMPTY, Side::EMPTY);
    let (mut i, mut j) = (0, s.len());
    loop {
        while i < j && left(&s[i]) {
            l.add(&s[i]);
            i += 1;
        }
        while i < j && !left(&s[j - 1]) {
            r.add(&s[j - 1]);
            j -= 1;
        }
        if i >= j {
            return (i, l, r);
        }
        // s[i] goes right and s[j - 1] left: swap them, and count each on its side (from the
        // values in hand: read back after the swap, each waited for its own store).
        let (a, b) = (s[i], s[j - 1]);
        l.add(&b);
        r.add(&a);
        s[i] = b;
        s[j - 1] = a;
        i += 1;
        j -= 1;
    }
}

/// A built subtree: its nodes (root first, child references relative to this array), its
/// leaves (ids relative to this array), and the subtrees built apart from it in parallel, which
/// [`Sub::place`] writes after it.
///
/// Why apart, not appended: appending each parallel subtree to its parent as it finished copied
/// every node and leaf once per parallel level (about four copies of 509 MB of nodes at 33.5M
/// triangles) and faulted in a new array each time; placed at the end, each is copied once.
#[derive(Default)]
struct Sub {
    nodes: Vec<Node>,
    leaves: Vec<Leaf>,
    depth: usize,
    apart: Vec<Apart>,
}

/// A subtree built apart: the root of `sub` is child `slot` of node `node` of the parent.
struct Apart {
    node: u32,
    slot: usize,
    root: u32,
    sub: Sub,
}

impl Sub {
    /// The nodes, leaves and depth of this subtree and all those apart from it.
    fn totals(&self) -> (usize, usize, usize) {
        self.apart.iter().fold(
            (self.nodes.len(), self.leaves.len(), self.depth),
            |(n, l, d), a| {
                let (an, al, ad) = a.sub.totals();
                (n + an, l + al, d.max(ad))
            },
        )
    }

    /// Writes this subtree into `nodes` and `leaves`, then each subtree apart from it after it
    /// (in the order they were added, depth first), linking their roots; the slices are exactly
    /// [`Sub::totals`] long and start at `base` (nodes, leaves) of the whole arrays. Subtrees
    /// apart are written in parallel: placing them one after the other took 0.26 s of a 7.3 s
    /// build of 33.5M triangles on two threads.
    fn place(
        self,
        nodes: &mut [MaybeUninit<Node>],
        leaves: &mut [MaybeUninit<Leaf>],
        base: (u32, u32),
    ) {
        let (own_nodes, mut rest_nodes) = nodes.split_at_mut(self.nodes.len());
        let (own_leaves, mut rest_leaves) = leaves.split_at_mut(self.leaves.len());
        for (slot, l) in own_leaves.iter_mut().zip(&self.leaves) {
            slot.write(*l);
        }
        let mut own = self.nodes;
        for n in &mut own {
            n.child = n.child.map(|c| rebase(c, base));
        }
        let mut at = (base.0 + own.len() as u32, base.1 + self.leaves.len() as u32);
        let mut jobs = Vec::with_capacity(self.apart.len());
        for a in self.apart {
            own[a.node as usize].child[a.slot] = rebase(a.root, at);
            let (n, l, _) = a.sub.totals();
            let (sub_nodes, tail) = rest_nodes.split_at_mut(n);
            rest_nodes = tail;
            let (sub_leaves, tail) = rest_leaves.split_at_mut(l);
            rest_leaves = tail;
            jobs.push((a.sub, sub_nodes, sub_leaves, at));
            at = (at.0 + n as u32, at.1 + l as u32);
        }
        // Every slot is written: the slices were cut to the totals, to the last element.
        assert!(rest_nodes.is_empty() && rest_leaves.is_empty());
        for (slot, n) in own_nodes.iter_mut().zip(own) {
            slot.write(n);
        }
        jobs.into_par_iter()
            .for_each(|(sub, n, l, at)| sub.place(n, l, at));
    }
}

/// A child reference of a subtree whose nodes and leaves start at `base` (nodes, leaves) of the
/// whole arrays, made relative to those arrays.
fn rebase(child: u32, base: (u32, u32)) -> u32 {
    if child & LEAF != 0 {
        child + base.1
    } else {
        child + base.0
    }
}

/// Builds the subtree of `r` (a range of `prims`, whose index 0 is BVH-order index `base`) into
/// `out`, returning the reference to its root: a leaf or a node.
fn subtree(prims: &mut [PrimRef], base: usize, r: Range, out: &mut Sub, level: usize) -> u32 {
    out.depth = out.depth.max(level);
    if r.len() <= 2 * MAX_LEAF {
        // One leaf, or a pair: the first `MAX_LEAF` references and the rest.
        let first = (base + r.start) as u32;
        let n = r.len() as u32;
        let head = n.min(MAX_LEAF as u32);
        out.leaves.push(Leaf { first, count: head });
        let id = out.leaves.len() as u32 - 1;
        if n == head {
            return LEAF | id;
        }
        out.leaves.push(Leaf {
            first: first + head,
            count: n - head,
        });
        return LEAF | PAIR | id;
    }
    // Open the child with the largest surface until there are eight; a long range is halved three
    // times instead, both sides of each split at once.
    let mut kids = if r.len() >= PAR_NODE {
        halve(&mut prims[r.start..r.end], r, WIDTH.ilog2())
    } else {
        vec![r]
    };
    while kids.len() < WIDTH {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| k.len() > MAX_LEAF)
            .max_by(|a, b| a.1.bounds.half_area().total_cmp(&b.1.bounds.half_area()));
        let Some((at, _)) = widest else { break };
        let (a, b) = split(&mut prims[kids[at].start..kids[at].end], &kids[at]);
        kids[at] = a;
        kids.push(b);
    }
    kids.sort_unstable_by_key(|k| k.start);
    let me = out.nodes.len();
    out.nodes.push(Node::EMPTY);
    for (slot, k) in kids.iter().enumerate() {
        out.nodes[me].set_box(
            slot,
            k.bounds.lo.truncate().into(),
            k.bounds.hi.truncate().into(),
        );
    }
    if r.len() >= PAR_TREE {
        // Hand each child its own slice of `prims` and build them at once.
        let mut rest = &mut prims[r.start..r.end];
        let mut jobs = Vec::with_capacity(kids.len());
        for k in &kids {
            let (mine, tail) = rest.split_at_mut(k.len());
            rest = tail;
            let local = Range {
                start: 0,
                end: k.len(),
                ..*k
            };
            jobs.push((mine, base + k.start, local));
        }
        let subs: Vec<(u32, Sub)> = jobs
            .into_par_iter()
            .map(|(mine, at, local)| {
                // Room for the leaves and nodes such a range makes (n/3.95 leaves, a few
                // under four triangles each, and about n/20 nodes), so that building does not
                // grow the arrays by copying; a range built in parallel keeps only its root.
                let n = local.len();
                let (nodes, leaves) = if n >= PAR_TREE {
                    (1, 0)
                } else {
                    (n / 16 + 4, n / 4 + n / 32 + 4)
                };
                let mut s = Sub {
                    nodes: Vec::with_capacity(nodes),
                    leaves: Vec::with_capacity(leaves),
                    depth: 0,
                    apart: Vec::new(),
                };
                let root = subtree(mine, at, local, &mut s, level + 1);
                (root, s)
            })
            .collect();
        for (slot, (root, sub)) in subs.into_iter().enumerate() {
            out.apart.push(Apart {
                node: me as u32,
                slot,
                root,
                sub,
            });
        }
    } else {
        for (slot, k) in kids.into_iter().enumerate() {
            let c = subtree(prims, base, k, out, level + 1);
            out.nodes[me].child[slot] = c;
        }
    }
    me as u32
}

/// Builds an 8-wide BVH over the `len` boxes `box_of` gives (at least two, all finite), each
/// padded as [`Bounds::padded`] says.
pub(super) fn build(len: usize, box_of: impl Fn(usize) -> Bounds + Sync) -> WideBvh {
    let reference = |i: usize| {
        let b = box_of(i);
        debug_assert!(b.is_finite());
        let b = b.padded();
        let mut lo = Vec4::from((b.min, 0.0));
        lo.w = f32::from_bits(i as u32);
        PrimRef {
            lo,
            hi: Vec4::from((b.max, 0.0)),
        }
    };
    // The references and their bounds in one pass: a second pass to measure them read the whole
    // array again (1.6 GB at 50M triangles).
    let mut prims = crate::mem::huge_vec(len);
    const CHUNK: usize = PAR_BIN / 4;
    let Side { bounds, cent } = prims.spare_capacity_mut()[..len]
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut side = Side::EMPTY;
            for (k, slot) in chunk.iter_mut().enumerate() {
                side.add(slot.write(reference(c * CHUNK + k)));
            }
            side
        })
        .reduce(|| Side::EMPTY, Side::merge);
    // SAFETY: the chunks cover the first `len` slots, and each slot was written.
    unsafe { prims.set_len(len) };
    let whole = Range {
        start: 0,
        end: prims.len(),
        bounds,
        cent,
    };
    let mut sub = Sub::default();
    let root = subtree(&mut prims, 0, whole, &mut sub, 1);
    let mut order = crate::mem::huge_vec(prims.len());
    prims
        .par_iter()
        .map(prim_index)
        .collect_into_vec(&mut order);
    // The references go before the arrays are written: the subtrees' own arrays and the final
    // ones are both resident until the end of `place`.
    drop(prims);
    // The arrays are written once, here: fault them in as huge pages (`crate::mem`).
    let (n_nodes, n_leaves, depth) = sub.totals();
    let mut nodes = crate::mem::huge_vec(n_nodes + 1);
    let mut leaves = crate::mem::huge_vec(n_leaves);
    sub.place(
        &mut nodes.spare_capacity_mut()[..n_nodes],
        &mut leaves.spare_capacity_mut()[..n_leaves],
        (0, 0),
    );
    // SAFETY: `place` wrote every one of the first `n_nodes` nodes and `n_leaves` leaves (it
    // asserts that the slices it was given were used up).
    unsafe {
        nodes.set_len(n_nodes);
        leaves.set_len(n_leaves);
    }
    // The small subtrees' arrays (under 4096 references each, so from the allocator's heaps, not
    // mapped on their own) were all alive at once and are free now: without giving their pages
    // back, the final scene's peak resident size rose from 284 to 341 MB at 1024²; given back,
    // 323 MB (the rest sits in pages the allocator still uses: see docs/profiling.md). At 33.6M
    // triangles the peak is the same as before the subtrees were kept apart (2.78 GB). Only
    // after large builds: the trim walks every heap, and a scene may build thousands of meshes.
    if len >= PAR_NODE {
        crate::mem::release_free_memory();
    }
    if root & LEAF != 0 {
        // Too few primitives for a node: one node with the leaf as its only child.
        let mut n = Node::EMPTY;
        n.set_box(0, bounds.lo.truncate().into(), bounds.hi.truncate().into());
        n.child[0] = root;
        nodes.push(n);
    }
    WideBvh::new(nodes, leaves, order, depth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::mix64;

    /// Binning in two sets (even and odd references) gives exactly the bins of one set, for
    /// ranges of every parity around the threshold and a long one.
    #[test]
    fn two_sets_of_bins_bin_as_one() {
        let mut rng = crate::sampling::Rng::new(99, crate::sampling::Pass::Pixel, 0);
        let mut point = || Vec4::new(rng.next_f32(), rng.next_f32(), rng.next_f32(), 0.0);
        for len in [TWO_SETS - 1, TWO_SETS, TWO_SETS + 1, 1001] {
            let prims: Vec<PrimRef> = (0..len)
                .map(|i| {
                    let lo = point() * 10.0;
                    PrimRef {
                        lo: lo.with_w(f32::from_bits(i as u32)),
                        hi: lo + point(),
                    }
                })
                .collect();
            let side = Side::of(&prims);
            let binner = Binner::new(&side.cent);
            let mut two = Bins::empty();
            two.add(&prims, &binner);
            let mut one = Bins::empty();
            prims.iter().for_each(|p| one.bin(p, &binner));
            assert_eq!(two.counts, one.counts, "{len} references");
            for axis in 0..3 {
                for i in 0..BINS {
                    let (a, b) = (two.boxes[axis][i], one.boxes[axis][i]);
                    assert_eq!((a.lo, a.hi), (b.lo, b.hi), "{len} references, bin {i}");
                }
            }
        }
    }

    /// Sorting a few references by bin finds exactly the split the bins find, axis and plane,
    /// for every count up to [`FEW`]: on spread references, on references crowded into two or
    /// three bins (where many planes tie), on equal ones (no split) and on flat boxes.
    #[test]
    fn few_references_split_as_the_bins_do() {
        let mut rng = crate::sampling::Rng::new(5, crate::sampling::Pass::Pixel, 0);
        let (mut splits, mut none) = (0, 0);
        for case in 0..4000 {
            let n = 2 + case % (FEW - 1);
            let crowd = case / FEW % 4;
            let prims: Vec<PrimRef> = (0..n)
                .map(|i| {
                    let mut c = Vec4::new(rng.next_f32(), rng.next_f32(), rng.next_f32(), 0.0);
                    match crowd {
                        1 => c = (c * 3.0).floor(),
                        2 => c = Vec4::new(1.0, 2.0, 3.0, 0.0),
                        _ => {}
                    }
                    let mut size = Vec4::new(rng.next_f32(), rng.next_f32(), 0.0, 0.0);
                    if crowd == 2 {
                        size = Vec4::new(0.5, 0.25, 0.0, 0.0);
                    }
                    PrimRef {
                        lo: c.with_w(f32::from_bits(i as u32)),
                        hi: c + size * if crowd == 3 { 0.0 } else { 0.3 },
                    }
                })
                .collect();
            let binner = Binner::new(&Side::of(&prims).cent);
            let want = Bins::of(&prims, &binner).best();
            assert_eq!(
                best_of_few(&prims, &binner),
                want,
                "case {case}, {n} references"
            );
            if want.is_some() {
                splits += 1
            } else {
                none += 1
            }
        }
        // Both answers occur: the test is not vacuous.
        assert!(
            splits > 2000 && none > 500,
            "{splits} splits, {none} without"
        );
    }

    /// The index a reference carries in `lo.w` never enters the centroid's arithmetic: as a
    /// float it is subnormal or barely normal, and arithmetic on it made the renderer's build
    /// of a 33.5M-triangle mesh (no flush-to-zero) 2.3 times slower. Lane `w` of every centroid,
    /// and so of the binner's origin and of every `Side`'s centroid bounds, is exactly zero.
    #[test]
    fn the_index_lane_stays_out_of_the_arithmetic() {
        for i in [1u32, 5, 1 << 22, (1 << 23) - 1, 1 << 23, 123_456_789] {
            let mut lo = Vec4::new(-1.0, 2.0, 0.5, 0.0);
            lo.w = f32::from_bits(i);
            let p = PrimRef {
                lo,
                hi: Vec4::new(1.0, 3.0, 0.75, 0.0),
            };
            let c = centroid2(&p);
            assert_eq!(c.w.to_bits(), 0, "index {i}");
            assert_eq!(c.truncate(), glam::Vec3::new(0.0, 5.0, 1.25));
            assert_eq!(prim_index(&p), i);
            let side = Side::of(&[p, p]);
            assert_eq!((side.cent.lo.w, side.cent.hi.w), (0.0, 0.0));
            assert_eq!(Binner::new(&side.cent).origin.w, 0.0);
        }
    }

    /// The partition's test agrees with the bins for every axis and plane: on random
    /// references, on references at each bin's edge and one float step either side of it, and at
    /// the ends of the centroids' extent, in boxes from tiny to huge and flat.
    #[test]
    fn left_of_agrees_with_bins() {
        let mut state = 7u64;
        let mut unit = || {
            state = mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let extents = [
            (
                Vec4::new(-1.0, 0.0, 3.0, 0.0),
                Vec4::new(1.0, 1e-6, 3.5, 0.0),
            ),
            (
                Vec4::new(1e6, -1e7, 0.0, 0.0),
                Vec4::new(1e6 + 3.0, 1e7, 0.0, 0.0),
            ),
            (
                Vec4::new(1e-30, 0.1, -0.3, 0.0),
                Vec4::new(3e-30, 0.1 + 1e-7, 0.3, 0.0),
            ),
        ];
        let (mut checked, mut lefts) = (0u64, 0u64);
        for (lo, hi) in extents {
            let cent = Box4 { lo, hi };
            let binner = Binner::new(&cent);
            // Twice the centroids, as `centroid2` makes them, inside [lo, hi].
            let mut points: Vec<Vec4> = (0..2000)
                .map(|_| lo + (hi - lo) * Vec4::new(unit(), unit(), unit(), 0.0))
                .collect();
            for j in 0..=BINS {
                let edge = lo + (hi - lo) * (j as f32 / BINS as f32);
                let step = |v: Vec4, f: fn(f32) -> f32| Vec4::new(f(v.x), f(v.y), f(v.z), 0.0);
                points.extend([edge, step(edge, f32::next_up), step(edge, f32::next_down)]);
            }
            points.extend([lo, hi]);
            // Points whose scaled offset is exactly a plane, where `<` and `<=` part.
            let mut exact = 0;
            for plane in 1..BINS {
                let mut at = lo + Vec4::splat(plane as f32) / binner.scale.max(Vec4::splat(1e-30));
                for _ in 0..8 {
                    let k = (at - binner.origin) * binner.scale;
                    for axis in 0..3 {
                        if k[axis] == plane as f32 {
                            let mut q = (lo + hi) * 0.5;
                            q[axis] = at[axis];
                            points.push(q);
                            exact += 1;
                        }
                        at[axis] = if k[axis] < plane as f32 {
                            at[axis].next_up()
                        } else {
                            at[axis].next_down()
                        };
                    }
                }
            }
            assert!(exact >= BINS, "only {exact} points on a plane");
            for c in points {
                let c = c.clamp(lo, hi);
                // Only `lo + hi` matters to the bins: make it exactly `c`.
                let p = PrimRef {
                    lo: c,
                    hi: Vec4::ZERO,
                };
                assert_eq!(centroid2(&p), c);
                let bins = binner.bins(&p);
                for (axis, &bin) in bins[..3].iter().enumerate() {
                    for plane in 1..BINS {
                        let left = match axis {
                            0 => binner.left_of::<0>(plane)(&p),
                            1 => binner.left_of::<1>(plane)(&p),
                            _ => binner.left_of::<2>(plane)(&p),
                        };
                        assert_eq!(left, bin < plane, "{c:?} axis {axis} plane {plane}");
                        checked += 1;
                        lefts += left as u64;
                    }
                }
            }
        }
        // Both answers occur often: the test is not vacuous.
        assert!(
            lefts > checked / 4 && lefts < 3 * checked / 4,
            "{lefts} of {checked}"
        );
    }
}
