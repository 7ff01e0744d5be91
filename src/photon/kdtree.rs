//! The implicit balanced kd-tree over a [`PhotonMap`]'s positions: build, k-nearest and radius
//! queries, and the invariant check.
//!
//! The index range `lo..hi` is a subtree. If it holds at most [`LEAF_SIZE`] photons it is a leaf
//! bucket (split axis [`AXIS_NONE`] on each of its photons), otherwise its
//! root is photon `m = lo + (hi - lo) / 2`, whose code word names the split axis `a`, and
//! `pos[lo..m][a] <= pos[m][a] <= pos[m + 1..hi][a]`. The split axis is the one along which the
//! range's bounding box is longest (the lowest axis on ties), so coplanar photons are never split
//! across their plane, and the median split keeps the depth at `log2(n / LEAF_SIZE)` however many
//! photons share a coordinate.
//!
//! # Layout: top levels first
//! The tree's shape is that of the implicit in-order tree above, but the photons are stored in
//! two parts. The medians of the top [`top_depth`] levels (a perfect binary tree of `T = 2^D - 1`
//! nodes, every one of whose subtrees holds more than `2 * BOTTOM_MIN` photons) come first, in
//! breadth-first order (node `i` has children `2i + 1` and `2i + 2`); then the `2^D` bottom
//! subtrees, each a contiguous in-order range as above, in order. In the in-order array bottom
//! subtree `j` starts after `j` top medians, so its range moves left by `j` and right by `T`.
//! A query descends the top through a compact `16 T`-byte region (about 2 MB at 10^7 photons)
//! instead of touching one cache line per level spread over the whole map, which is what random
//! queries on large maps used to wait for. The layout costs no bytes: it is a permutation.
//!
//! A k-nearest query first scans the whole subtree of 2k to 4k photons around the query point (a
//! contiguous index range) and keeps its k nearest, which gives a tight bound for one linear scan
//! and one selection. Queries then descend the near side first, skipping that subtree, and visit
//! the far side only if the box of the far cell (tracked per axis, Arya & Mount 1993) is within
//! the current bound. The photons found are appended to a pool of candidates, and each time it
//! holds `2k` the k nearest are selected (one selection per k photons instead of a heap's sift
//! per photon: a third off a query on 2M photons). The bound test is `d2 <= bound`, where
//! `bound` is the query radius, or once k photons are selected the largest float below the k-th
//! distance, so ties at the query radius are found and ties with the k-th distance are skipped
//! without changing the distances returned. Cell distances are computed from the same
//! coordinate differences as photon distances, so pruning never drops a photon whose computed
//! distance passes the bound.

use super::store::{self, AXIS_NONE, PowerCodec};
use super::stream::{BLOCK, PhotonStream, Staged, Tally};
use super::{Photon, PhotonId, PhotonMap};
use glam::{BVec3A, Vec3A};

/// Largest index range stored as a leaf bucket (searched linearly, no split). Measured with
/// `bench_photons` (k = 50, 10^6 and 10^7 points): 32 beats 8, 16 and 48; a linear scan of a
/// contiguous bucket costs less than the split nodes it replaces.
pub const LEAF_SIZE: usize = 32;
/// Smallest range whose two subtrees are built in parallel.
const PARALLEL_MIN: usize = 1 << 14;
/// Fewest photons in a bottom subtree: the top levels stop where a subtree could hold fewer.
const BOTTOM_MIN: usize = 2 * LEAF_SIZE;

/// Returns the number of top levels `D` of an `n`-photon tree: the largest depth at which every
/// subtree holds at least [`BOTTOM_MIN`] photons (so every top node is a split, not a leaf).
pub(super) fn top_depth(n: usize) -> u32 {
    // The smallest subtree at depth d + 1 is the smaller child, floor((s - 1) / 2), of the
    // smallest at depth d (a subtree of s photons has children of floor(s / 2) and that).
    let (mut d, mut s) = (0, n);
    while s > 0 && (s - 1) / 2 >= BOTTOM_MIN {
        d += 1;
        s = (s - 1) / 2;
    }
    d
}

/// A subtree: a top node (`top` is its breadth-first index plus 1, and `lo..hi` its range in
/// the in-order tree) or a bottom subtree (`top` is 0, and `lo..hi` its range in the arrays).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Node {
    lo: usize,
    hi: usize,
    top: usize,
}

impl Node {
    /// Returns the number of photons in the subtree.
    #[inline(always)]
    fn len(self) -> usize {
        self.hi - self.lo
    }
}

/// A `skip` node no subtree equals.
const NO_SKIP: Node = Node {
    lo: usize::MAX,
    hi: usize::MAX,
    top: usize::MAX,
};

/// A photon during the build, compact and in one piece so `select_nth` moves it whole.
#[derive(Clone, Copy)]
struct Record {
    pos: [f32; 3],
    code: u32,
    power: u32,
}

/// Returns the squared distance between `a` and `b`, as `(a - b).length_squared()` computes it.
#[inline(always)]
fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    #[cfg(test)]
    tests::DIST2_CALLS.with(|c| c.set(c.get() + 1));
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

/// Most photons one [`scan`] takes: a leaf bucket's.
const SCAN: usize = LEAF_SIZE;

/// Writes the squared distance from `q` to each photon of `pos` (at most [`SCAN`]) to the same
/// index of `d2`, computed as [`dist2`] computes it (no fused multiply-adds, so bit for bit the
/// same), and returns the bit mask of those `<= bound` (NaN: not). Eight at a time where the CPU
/// has AVX: a leaf's distances were half of a `k`-nearest search's time, one at a time.
#[inline(always)]
fn scan(pos: &[[f32; 3]], q: [f32; 3], bound: f32, d2: &mut [f32; SCAN]) -> u32 {
    debug_assert!(pos.len() <= SCAN);
    #[cfg(test)]
    tests::DIST2_CALLS.with(|c| c.set(c.get() + pos.len()));
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked just above).
        return unsafe { scan_avx(pos, q, bound, d2) };
    }
    scan_scalar(pos, q, bound, d2)
}

/// [`scan`], one photon at a time.
#[inline(always)]
fn scan_scalar(pos: &[[f32; 3]], q: [f32; 3], bound: f32, d2: &mut [f32; SCAN]) -> u32 {
    let mut mask = 0;
    for (j, &x) in pos.iter().enumerate() {
        let (dx, dy, dz) = (x[0] - q[0], x[1] - q[1], x[2] - q[2]);
        d2[j] = dx * dx + dy * dy + dz * dz;
        mask |= u32::from(d2[j] <= bound) << j;
    }
    mask
}

/// [`scan`] with AVX: eight photons' 24 coordinates are loaded as six 4-float quarters and
/// shuffled into eight x, eight y and eight z (Intel's AoS-to-SoA transpose), so the array keeps
/// its layout; the photons past the last multiple of eight go one at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn scan_avx(pos: &[[f32; 3]], q: [f32; 3], bound: f32, d2: &mut [f32; SCAN]) -> u32 {
    use std::arch::x86_64::*;
    /// `_MM_SHUFFLE(a, b, c, d)`.
    const fn order(a: i32, b: i32, c: i32, d: i32) -> i32 {
        (a << 6) | (b << 4) | (c << 2) | d
    }
    let n = pos.len().min(SCAN);
    let full = n / 8 * 8;
    let (qx, qy, qz) = (
        _mm256_set1_ps(q[0]),
        _mm256_set1_ps(q[1]),
        _mm256_set1_ps(q[2]),
    );
    let b = _mm256_set1_ps(bound);
    let mut mask = 0u32;
    let mut i = 0;
    while i < full {
        // SAFETY: photons i..i + 8 are in `pos` (i + 8 <= full <= len), so the 24 floats read
        // are, and `d2` has room for them (full <= SCAN).
        unsafe {
            let p = pos.as_ptr().add(i).cast::<f32>();
            let quarter = |k: usize| _mm_loadu_ps(p.add(4 * k));
            // Lanes 0-3 hold photons i..i + 4, lanes 4-7 photons i + 4..i + 8.
            let m03 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(quarter(0)), quarter(3));
            let m14 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(quarter(1)), quarter(4));
            let m25 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(quarter(2)), quarter(5));
            let xy = _mm256_shuffle_ps::<{ order(2, 1, 3, 2) }>(m14, m25);
            let yz = _mm256_shuffle_ps::<{ order(1, 0, 2, 1) }>(m03, m14);
            let x = _mm256_shuffle_ps::<{ order(2, 0, 3, 0) }>(m03, xy);
            let y = _mm256_shuffle_ps::<{ order(3, 1, 2, 0) }>(yz, xy);
            let z = _mm256_shuffle_ps::<{ order(3, 0, 3, 1) }>(yz, m25);
            let (dx, dy, dz) = (
                _mm256_sub_ps(x, qx),
                _mm256_sub_ps(y, qy),
                _mm256_sub_ps(z, qz),
            );
            let s = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                _mm256_mul_ps(dz, dz),
            );
            _mm256_storeu_ps(d2.as_mut_ptr().add(i), s);
            let within = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(s, b)) as u32;
            mask |= within << i;
        }
        i += 8;
    }
    for j in full..n {
        let x = pos[j];
        let (dx, dy, dz) = (x[0] - q[0], x[1] - q[1], x[2] - q[2]);
        d2[j] = dx * dx + dy * dy + dz * dz;
        mask |= u32::from(d2[j] <= bound) << j;
    }
    mask
}

/// Offers `sink` the photons of the array range starting at `lo` whose positions are `pos`,
/// in order, each within the sink's bound at the time it is offered: as a loop of [`dist2`] and
/// `offer` would, [`SCAN`] distances at a time (a sink's bound never grows, so the photons a
/// scan passes against its bound at the start are the only ones that can pass later).
#[inline(always)]
fn offer_all<S: Sink>(pos: &[[f32; 3]], lo: usize, q: [f32; 3], sink: &mut S) {
    let mut d2 = [0.0; SCAN];
    for (c, chunk) in pos.chunks(SCAN).enumerate() {
        let mut mask = scan(chunk, q, sink.bound(), &mut d2);
        while mask != 0 {
            let j = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if d2[j] <= sink.bound() {
                sink.offer(d2[j], lo + c * SCAN + j);
            }
        }
    }
}

/// Returns `v` with lane `a` (0, 1 or 2) replaced by `x`, without a round trip through memory.
#[inline(always)]
fn with_lane(v: Vec3A, a: usize, x: f32) -> Vec3A {
    const LANES: [BVec3A; 3] = [
        BVec3A::new(true, false, false),
        BVec3A::new(false, true, false),
        BVec3A::new(false, false, true),
    ];
    Vec3A::select(LANES[a], Vec3A::splat(x), v)
}

/// Returns the axis along which the positions spread furthest (the lowest axis on ties).
fn widest_axis(points: impl Iterator<Item = [f32; 3]>) -> u32 {
    let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    for p in points {
        let p = Vec3A::from_array(p);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let ext = (hi - lo).to_array();
    let mut best = 0;
    for a in 1..3 {
        if ext[a] > ext[best] {
            best = a;
        }
    }
    best as u32
}

/// Returns the top-first layout of an `n`-photon tree (see the module doc): the in-order index
/// of each top node's median, breadth-first, and the in-order ranges of the bottom subtrees, in
/// order (bottom subtree `j`, in-order `lo..hi`, is stored at `lo - j + T..hi - j + T`).
fn top_first_layout(n: usize) -> (Vec<usize>, Vec<(usize, usize)>) {
    let mut tops = Vec::new();
    let mut level = vec![(0, n)];
    for _ in 0..top_depth(n) {
        let mut next = Vec::with_capacity(2 * level.len());
        for (lo, hi) in level {
            let m = lo + (hi - lo) / 2;
            tops.push(m);
            next.extend([(lo, m), (m + 1, hi)]);
        }
        level = next;
    }
    (tops, level)
}

/// Records copied into a map's arrays between two hand-backs of the records' pages (8 MiB).
const RELEASE_RECORDS: usize = 1 << 19;

/// Orders `recs` as a kd-subtree (see the module doc), in parallel for large ranges.
fn build_subtree(recs: &mut [Record]) {
    let n = recs.len();
    if n <= LEAF_SIZE {
        return; // Records start with axis AXIS_NONE.
    }
    let axis = widest_axis(recs.iter().map(|r| r.pos));
    let a = axis as usize;
    let m = n / 2;
    recs.select_nth_unstable_by(m, |x, y| x.pos[a].total_cmp(&y.pos[a]));
    recs[m].code = store::with_axis(recs[m].code, axis);
    let (left, rest) = recs.split_at_mut(m);
    let right = &mut rest[1..];
    if n >= PARALLEL_MIN {
        rayon::join(|| build_subtree(left), || build_subtree(right));
    } else {
        build_subtree(left);
        build_subtree(right);
    }
}

impl PhotonMap {
    /// Returns the map of `photons`, built in parallel on the current rayon pool; the result is
    /// the same for any number of threads.
    ///
    /// Photons with a NaN or infinite position are skipped (a tracer bug: debug builds assert).
    pub fn build(photons: Vec<Photon>) -> PhotonMap {
        let stream = PhotonStream::of(&photons);
        drop(photons);
        PhotonMap::from_stream(stream)
    }

    /// Returns the map of the photons of `stream`, as [`PhotonMap::build`] of the same photons
    /// in the same order would, holding at most about 28 bytes per photon while it builds (see
    /// [`super::stream`]): the stream's blocks are converted to 20-byte records and freed in
    /// parallel, the records are ordered as the tree in place, and they are copied into the
    /// map's arrays from the end, their pages given back as they go.
    pub fn from_stream(stream: PhotonStream) -> PhotonMap {
        use rayon::prelude::*;
        let (blocks, tallies) = (stream.blocks, stream.tallies);
        let finite = |s: &&Staged| {
            let ok = s.is_finite();
            debug_assert!(ok, "photon at {:?}", s.pos);
            ok
        };
        let max_exponent = tallies.iter().map(|t| t.max_exponent).max();
        let codec = PowerCodec::new(max_exponent.unwrap_or(i32::MIN));
        // Each block's finite photons, capped so that at most u32::MAX are kept in all.
        let mut room = u32::MAX as usize;
        let takes: Vec<usize> = tallies
            .iter()
            .map(|&Tally { finite: k, .. }| {
                let take = k.min(room);
                room -= take;
                take
            })
            .collect();
        let n: usize = takes.iter().sum();
        let mut recs: Vec<Record> = crate::mem::huge_vec(n);
        let mut parts = Vec::with_capacity(blocks.len());
        let mut rest = &mut recs.spare_capacity_mut()[..n];
        for &take in &takes {
            let (part, after) = rest.split_at_mut(take);
            parts.push(part);
            rest = after;
        }
        blocks.into_par_iter().zip(parts).for_each(|(block, part)| {
            for (slot, s) in part.iter_mut().zip(block.iter().filter(finite)) {
                slot.write(Record {
                    pos: s.pos,
                    code: s.code,
                    power: codec.encode(Vec3A::from_array(s.power)),
                });
            }
            // The block is freed here, as its records are written.
        });
        // SAFETY: the parts cover the first n slots, and each part was written whole: a part
        // is as long as its block's first finite photons, which the loop above wrote in order.
        unsafe { recs.set_len(n) };
        build_subtree(&mut recs);
        PhotonMap::from_tree(recs, codec)
    }

    /// Returns the map of the photons for which `keep` holds, taken in id order (positions,
    /// directions and `direct` as stored; power decoded and encoded afresh for the new map).
    pub fn thinned(&self, keep: impl Fn(PhotonId) -> bool + Sync) -> PhotonMap {
        use rayon::prelude::*;
        let staged = |i: usize| Staged {
            pos: self.pos[i],
            code: store::with_axis(self.code[i], AXIS_NONE),
            power: self.codec.decode(self.power[i]).to_array(),
        };
        let mut stream = PhotonStream::new();
        for start in (0..self.len()).step_by(BLOCK) {
            let part: Vec<Staged> = (start..(start + BLOCK).min(self.len()))
                .into_par_iter()
                .filter(|&i| keep(PhotonId(i as u32)))
                .map(staged)
                .collect();
            stream.extend_from_slice(&part);
        }
        PhotonMap::from_stream(stream)
    }

    /// Returns the map of `recs`, an in-order tree ([`build_subtree`]), in the top-first layout,
    /// giving the records' pages back to the system as they are copied.
    fn from_tree(mut recs: Vec<Record>, codec: PowerCodec) -> PhotonMap {
        let n = recs.len();
        let (tops, bottoms) = top_first_layout(n);
        let t = tops.len();
        let mut pos: Vec<[f32; 3]> = crate::mem::huge_vec(n);
        let mut code: Vec<u32> = crate::mem::huge_vec(n);
        let mut power: Vec<u32> = crate::mem::huge_vec(n);
        {
            let (ps, cs, ws) = (
                &mut pos.spare_capacity_mut()[..n],
                &mut code.spare_capacity_mut()[..n],
                &mut power.spare_capacity_mut()[..n],
            );
            let mut put = |at: usize, r: &Record| {
                ps[at].write(r.pos);
                cs[at].write(r.code);
                ws[at].write(r.power);
            };
            for (j, &m) in tops.iter().enumerate() {
                put(j, &recs[m]);
            }
            // From the last bottom subtree to the first, so the records left are a prefix.
            let mut kept = n;
            for (j, &(lo, hi)) in bottoms.iter().enumerate().rev() {
                for (i, r) in recs[lo..hi].iter().enumerate() {
                    put(lo + t - j + i, r);
                }
                if kept - lo >= RELEASE_RECORDS {
                    // SAFETY: a Record is plain f32 and u32 fields, valid as all zeros.
                    unsafe { crate::mem::discard(&mut recs[lo..kept]) };
                    kept = lo;
                }
            }
        }
        // SAFETY: the top medians filled slots 0..t and bottom subtree j (lo..hi, in order)
        // slots lo + t - j..hi + t - j; the layout's ranges tile 0..n exactly (the tops are
        // the medians between consecutive bottom ranges), so every slot of 0..n was written.
        unsafe {
            pos.set_len(n);
            code.set_len(n);
            power.set_len(n);
        }
        drop(recs);
        PhotonMap {
            pos,
            code,
            power,
            codec,
            top_nodes: t,
        }
    }

    /// Writes the k nearest photons to p with squared distance <= max_d2 to `out` (cleared first),
    /// in any order; returns the largest squared distance found (0 if none).
    ///
    /// Among photons tied at the k-th distance, which ones are returned is unspecified. A NaN
    /// query point or `max_d2` finds nothing.
    pub fn knn(&self, p: Vec3A, k: usize, max_d2: f32, out: &mut Vec<(f32, PhotonId)>) -> f32 {
        out.clear();
        if k == 0 || self.is_empty() || max_d2.is_nan() || max_d2 < 0.0 {
            return 0.0;
        }
        let q = p.to_array();
        // Seed: every photon of a small subtree around q gives a tight first bound cheaply (one
        // linear scan and one selection instead of a heap insertion per photon).
        let seed = self.seed_node(q, k);
        out.reserve(k.max(seed.len()));
        let mut all = Within { r2: max_d2, out };
        if seed.top == 0 {
            offer_all(&self.pos[seed.lo..seed.hi], seed.lo, q, &mut all);
        } else {
            self.search(seed, q, Vec3A::ZERO, NO_SKIP, &mut all);
        }
        let mut pool = Pool {
            bound: max_d2,
            items: out,
            k,
        };
        pool.select();
        self.search(self.root(), q, Vec3A::ZERO, seed, &mut pool);
        pool.select();
        out.iter().fold(0.0, |m, e| e.0.max(m))
    }

    /// [`PhotonMap::knn`] among the photons for which `accept` holds (asked of every photon
    /// within the current bound, so it should be cheap). Slower than `knn`: no seeding.
    pub fn knn_where(
        &self,
        p: Vec3A,
        k: usize,
        max_d2: f32,
        accept: impl Fn(PhotonId) -> bool,
        out: &mut Vec<(f32, PhotonId)>,
    ) -> f32 {
        out.clear();
        if k == 0 || self.is_empty() || max_d2.is_nan() || max_d2 < 0.0 {
            return 0.0;
        }
        let mut sink = Where {
            heap: Heap::new(out, k, max_d2),
            accept,
        };
        self.search(self.root(), p.to_array(), Vec3A::ZERO, NO_SKIP, &mut sink);
        out.first().map_or(0.0, |e| e.0)
    }

    /// Returns the subtree holding `q`'s leaf that has between `2k` and `4k` photons (or the
    /// leaf, or the whole map if smaller).
    fn seed_node(&self, q: [f32; 3], k: usize) -> Node {
        let mut node = self.root();
        while node.len() > LEAF_SIZE && node.len() / 2 >= 2 * k {
            let (m, left, right) = self.split(node);
            let a = store::code_axis(self.code[m]) as usize;
            node = if q[a] <= self.pos[m][a] { left } else { right };
        }
        node
    }

    /// Returns the whole tree as a subtree.
    #[inline(always)]
    fn root(&self) -> Node {
        let top = usize::from(self.top_nodes > 0);
        Node {
            lo: 0,
            hi: self.len(),
            top,
        }
    }

    /// Returns the array index of a split node's median photon and its two subtrees.
    #[inline(always)]
    fn split(&self, node: Node) -> (usize, Node, Node) {
        let m = node.lo + node.len() / 2;
        if node.top == 0 {
            let left = Node { hi: m, ..node };
            let right = Node { lo: m + 1, ..node };
            return (m, left, right);
        }
        let i = node.top - 1;
        let child = |c: usize, lo: usize, hi: usize| {
            let t = self.top_nodes;
            if c < t {
                Node { lo, hi, top: c + 1 }
            } else {
                // Bottom subtree j = c - t: j top medians precede it in order, t in the arrays.
                let shift = t - (c - t);
                Node {
                    lo: lo + shift,
                    hi: hi + shift,
                    top: 0,
                }
            }
        };
        (
            i,
            child(2 * i + 1, node.lo, m),
            child(2 * i + 2, m + 1, node.hi),
        )
    }

    /// Offers `sink` every photon of subtree `node` within its bound, except those of the
    /// already searched subtree `skip`, nearer subtrees first; `off` is the per-axis offset from
    /// `q` to the subtree's cell. Every query is this walk with its own [`Sink`].
    fn search<S: Sink>(
        &self,
        mut node: Node,
        q: [f32; 3],
        mut off: Vec3A,
        skip: Node,
        sink: &mut S,
    ) {
        let pos = &self.pos[..];
        loop {
            if node == skip {
                return;
            }
            if node.len() <= LEAF_SIZE {
                // Only bottom subtrees are this small: lo..hi is an array range.
                offer_all(&pos[node.lo..node.hi], node.lo, q, sink);
                return;
            }
            let (m, left, right) = self.split(node);
            let a = store::code_axis(self.code[m]) as usize;
            let split = pos[m];
            let d = q[a] - split[a];
            let (near, far) = if d <= 0.0 {
                (left, right)
            } else {
                (right, left)
            };
            self.search(near, q, off, skip, sink);
            let d2 = dist2(split, q);
            if d2 <= sink.bound() {
                sink.offer(d2, m);
            }
            off = with_lane(off, a, d);
            if off.length_squared() > sink.bound() {
                return;
            }
            node = far;
        }
    }

    /// Returns the nearest photon to `p` with squared distance <= `max_d2` for which `accept`
    /// holds, and its squared distance; `accept` is asked only of photons nearer than the best
    /// accepted so far. Among photons at the same distance, the lowest id wins. A NaN query
    /// point or `max_d2` finds nothing.
    pub fn nearest_where(
        &self,
        p: Vec3A,
        max_d2: f32,
        accept: &mut impl FnMut(PhotonId) -> bool,
    ) -> Option<(f32, PhotonId)> {
        if self.is_empty() || max_d2.is_nan() || max_d2 < 0.0 {
            return None;
        }
        let mut sink = Nearest {
            best: (max_d2, None),
            accept,
        };
        self.search(self.root(), p.to_array(), Vec3A::ZERO, NO_SKIP, &mut sink);
        sink.best.1.map(|id| (sink.best.0, id))
    }

    /// Writes every photon with squared distance <= r2 from p to `out` (cleared first).
    ///
    /// The order is unspecified. A NaN query point or `r2` finds nothing.
    pub fn within(&self, p: Vec3A, r2: f32, out: &mut Vec<(f32, PhotonId)>) {
        out.clear();
        if self.is_empty() || r2.is_nan() || r2 < 0.0 {
            return;
        }
        let mut sink = Within { r2, out };
        self.search(self.root(), p.to_array(), Vec3A::ZERO, NO_SKIP, &mut sink);
    }

    /// Checks the kd-tree invariants (see the module doc); returns the first violation found.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.len();
        if self.code.len() != n || self.power.len() != n {
            return Err(format!(
                "array lengths differ: {n} positions, {} codes, {} powers",
                self.code.len(),
                self.power.len()
            ));
        }
        if n > u32::MAX as usize {
            return Err(format!("{n} photons do not fit PhotonId"));
        }
        for (i, (p, &c)) in self.pos.iter().zip(&self.code).enumerate() {
            if !p.iter().all(|x| x.is_finite()) {
                return Err(format!("photon {i} at {p:?} is not finite"));
            }
            if !store::code_is_valid(c) {
                return Err(format!("photon {i} has direction code {c:#x} out of range"));
            }
        }
        let top = (1usize << top_depth(n)) - 1;
        if self.top_nodes != top {
            return Err(format!(
                "{} top nodes, the layout of {n} photons has {top}",
                self.top_nodes
            ));
        }
        let mut stack = vec![self.root()];
        while let Some(node) = stack.pop() {
            self.validate_node(node)?;
            if node.len() > LEAF_SIZE {
                let (_, left, right) = self.split(node);
                stack.extend([left, right]);
            }
        }
        Ok(())
    }

    /// Appends the array index of every photon of subtree `node` to `out`.
    fn subtree_ids(&self, node: Node, out: &mut Vec<usize>) {
        if node.top == 0 {
            out.extend(node.lo..node.hi);
        } else {
            let (m, left, right) = self.split(node);
            self.subtree_ids(left, out);
            out.push(m);
            self.subtree_ids(right, out);
        }
    }

    /// Checks one subtree's root: its axis, and the coordinates on both sides of its split.
    fn validate_node(&self, node: Node) -> Result<(), String> {
        let ids = |node| {
            let mut v = Vec::new();
            self.subtree_ids(node, &mut v);
            v
        };
        let (lo, hi) = (node.lo, node.hi);
        if node.len() <= LEAF_SIZE {
            return match (lo..hi).find(|&i| store::code_axis(self.code[i]) != AXIS_NONE) {
                Some(i) => Err(format!("leaf photon {i} of {lo}..{hi} has a split axis")),
                None => Ok(()),
            };
        }
        let (m, left, right) = self.split(node);
        let axis = store::code_axis(self.code[m]);
        let widest = widest_axis(ids(node).into_iter().map(|i| self.pos[i]));
        if axis != widest {
            return Err(format!(
                "node {m} of {node:?} splits on axis {axis}, widest is {widest}"
            ));
        }
        let (a, s) = (axis as usize, self.pos[m][axis as usize]);
        if let Some(i) = ids(left).into_iter().find(|&i| self.pos[i][a] > s) {
            return Err(format!(
                "photon {i} left of node {m} is above its split {s}"
            ));
        }
        if let Some(i) = ids(right).into_iter().find(|&i| self.pos[i][a] < s) {
            return Err(format!(
                "photon {i} right of node {m} is below its split {s}"
            ));
        }
        Ok(())
    }
}

/// What a query does with the photons [`PhotonMap::search`] finds.
trait Sink {
    /// Largest squared distance still of interest (it may shrink as photons are offered).
    fn bound(&self) -> f32;
    /// Takes photon `i` at squared distance `d2 <= self.bound()`.
    fn offer(&mut self, d2: f32, i: usize);
}

/// Every photon within `r2` ([`PhotonMap::within`]).
struct Within<'a> {
    r2: f32,
    out: &'a mut Vec<(f32, PhotonId)>,
}

impl Sink for Within<'_> {
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.r2
    }
    #[inline(always)]
    fn offer(&mut self, d2: f32, i: usize) {
        self.out.push((d2, PhotonId(i as u32)));
    }
}

/// The nearest photon `accept` takes, lowest id among equals ([`PhotonMap::nearest_where`]).
struct Nearest<'a, F> {
    best: (f32, Option<PhotonId>),
    accept: &'a mut F,
}

impl<F: FnMut(PhotonId) -> bool> Sink for Nearest<'_, F> {
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.best.0
    }
    #[inline(always)]
    fn offer(&mut self, d2: f32, i: usize) {
        let id = PhotonId(i as u32);
        let better = d2 < self.best.0 || self.best.1.is_none_or(|b| id < b);
        if better && (self.accept)(id) {
            self.best = (d2, Some(id));
        }
    }
}

/// The k nearest photons `accept` takes ([`PhotonMap::knn_where`]).
struct Where<'a, F> {
    heap: Heap<'a>,
    accept: F,
}

impl<F: Fn(PhotonId) -> bool> Sink for Where<'_, F> {
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.heap.bound
    }
    #[inline(always)]
    fn offer(&mut self, d2: f32, i: usize) {
        if (self.accept)(PhotonId(i as u32)) {
            self.heap.push(d2, i as u32);
        }
    }
}

impl Sink for Heap<'_> {
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }
    #[inline(always)]
    fn offer(&mut self, d2: f32, i: usize) {
        self.push(d2, i as u32);
    }
}

/// The k nearest photons found so far, kept loosely ([`PhotonMap::knn`]): photons within the
/// bound are appended, and once there are `2k` the k nearest are selected and the bound drops
/// below the k-th distance. One selection per `k` photons costs less than a heap's sift per
/// photon, and the seed's bound is tight enough that most queries add only a few photons.
struct Pool<'a> {
    items: &'a mut Vec<(f32, PhotonId)>,
    k: usize,
    /// Largest squared distance still accepted: the query's `max_d2` until k photons were
    /// selected, then the largest float below the k-th distance (ties with it are not taken).
    bound: f32,
}

impl Pool<'_> {
    /// Keeps the k nearest items (all, if there are no more) and lowers the bound to match.
    fn select(&mut self) {
        let k = self.k;
        let kth = match self.items.len().cmp(&k) {
            std::cmp::Ordering::Less => return,
            std::cmp::Ordering::Equal => self.items.iter().fold(0.0, |m, e| e.0.max(m)),
            std::cmp::Ordering::Greater => {
                // Squared distances are >= 0 and not NaN, so their bits order as they do, and
                // integers compare faster than `total_cmp` (a lookup took 10% less time).
                debug_assert!(self.items.iter().all(|e| e.0 >= 0.0));
                self.items
                    .select_nth_unstable_by_key(k - 1, |e| e.0.to_bits());
                self.items.truncate(k);
                self.items[k - 1].0
            }
        };
        self.bound = self.bound.min(kth.next_down());
    }
}

impl Sink for Pool<'_> {
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }
    #[inline(always)]
    fn offer(&mut self, d2: f32, i: usize) {
        self.items.push((d2, PhotonId(i as u32)));
        if self.items.len() >= 2 * self.k {
            self.select();
        }
    }
}

/// A bounded max-heap of the k nearest photons found so far, kept in the caller's `Vec`.
struct Heap<'a> {
    items: &'a mut Vec<(f32, PhotonId)>,
    k: usize,
    /// Largest squared distance still accepted: the query's `max_d2` until k photons are found,
    /// then the largest float below the k-th distance.
    bound: f32,
}

impl<'a> Heap<'a> {
    /// Returns a heap of the at most `k` photons already in `items`, accepting up to `max_d2`.
    fn new(items: &'a mut Vec<(f32, PhotonId)>, k: usize, max_d2: f32) -> Heap<'a> {
        debug_assert!(items.len() <= k && items.iter().all(|e| e.0 <= max_d2));
        for i in (0..items.len() / 2).rev() {
            let x = items[i];
            sift_down(items, i, x);
        }
        let bound = match items.first() {
            Some(top) if items.len() == k => top.0.next_down(),
            _ => max_d2,
        };
        Heap { items, k, bound }
    }

    /// Adds photon `id` at squared distance `d2 <= self.bound`, evicting the farthest if full.
    #[inline(always)]
    fn push(&mut self, d2: f32, id: u32) {
        let h = &mut *self.items;
        let x = (d2, PhotonId(id));
        if h.len() < self.k {
            h.push(x);
            let mut i = h.len() - 1;
            while i > 0 {
                let parent = (i - 1) / 2;
                if h[parent].0 >= d2 {
                    break;
                }
                h[i] = h[parent];
                i = parent;
            }
            h[i] = x;
            if h.len() < self.k {
                return;
            }
        } else {
            sift_down(h, 0, x);
        }
        self.bound = h[0].0.next_down();
    }
}

/// Puts `x` at `i` of max-heap `h` and moves it down until both its children are not larger.
#[inline(always)]
fn sift_down(h: &mut [(f32, PhotonId)], mut i: usize, x: (f32, PhotonId)) {
    let n = h.len();
    loop {
        let mut c = 2 * i + 1;
        if c >= n {
            break;
        }
        if c + 1 < n && h[c + 1].0 > h[c].0 {
            c += 1;
        }
        if h[c].0 <= x.0 {
            break;
        }
        h[i] = h[c];
        i = c;
    }
    h[i] = x;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    fn photon(position: Vec3A) -> Photon {
        Photon {
            position,
            power: Vec3A::splat(1e-3),
            dir: Vec3A::Y,
            normal: Vec3A::Y,
            direct: false,
        }
    }

    /// The eight-wide scan returns what the one-at-a-time scan does, bit for bit, for every
    /// length up to a bucket's (the tail past a multiple of eight included), NaN coordinates,
    /// ties at the bound and a NaN bound; and both agree with `dist2`.
    #[test]
    fn the_wide_scan_matches_the_scalar_one_bit_for_bit() {
        let mut rng = crate::sampling::Rng::new(7, crate::sampling::Pass::Photon, 0);
        let mut pos: Vec<[f32; 3]> = (0..SCAN)
            .map(|_| std::array::from_fn(|_| rng.next_f32() * 2.0 - 1.0))
            .collect();
        pos[5] = [f32::NAN, 0.0, 0.0];
        pos[13] = [1e30, -1e30, 3.0];
        let q = [0.1, -0.2, 0.3];
        // A bound equal to one photon's distance: that photon passes (`<=`).
        let tie = dist2(pos[9], q);
        for bound in [0.0, 0.5, tie, 1.5, f32::INFINITY, f32::NAN] {
            for n in 0..=SCAN {
                let (mut a, mut b) = ([0.0; SCAN], [0.0; SCAN]);
                let want = scan_scalar(&pos[..n], q, bound, &mut a);
                let got = scan(&pos[..n], q, bound, &mut b);
                assert_eq!(got, want, "n {n}, bound {bound}");
                for j in 0..n {
                    assert_eq!(a[j].to_bits(), b[j].to_bits(), "n {n}, photon {j}");
                    assert_eq!(a[j].to_bits(), dist2(pos[j], q).to_bits());
                }
                let expect = (0..n).filter(|&j| a[j] <= bound).fold(0, |m, j| m | 1 << j);
                assert_eq!(want, expect);
            }
        }
    }

    #[test]
    fn widest_axis_prefers_the_lowest_on_ties() {
        let pts = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.5]];
        assert_eq!(widest_axis(pts.into_iter()), 0);
        let pts = [[0.0, 0.0, 0.0], [0.5, 1.0, 1.0]];
        assert_eq!(widest_axis(pts.into_iter()), 1);
        assert_eq!(widest_axis([[2.0; 3]; 5].into_iter()), 0);
    }

    #[test]
    fn heap_keeps_the_k_smallest_and_its_bound() {
        let mut v = Vec::new();
        let mut h = Heap::new(&mut v, 3, 10.0);
        for (i, d) in [5.0, 1.0, 7.0, 3.0, 3.0, 0.5].into_iter().enumerate() {
            if d <= h.bound {
                h.push(d, i as u32);
            }
        }
        assert_eq!(h.bound, 3f32.next_down());
        let mut d: Vec<f32> = v.iter().map(|e| e.0).collect();
        d.sort_by(f32::total_cmp);
        assert_eq!(d, [0.5, 1.0, 3.0]);
    }

    #[test]
    fn validate_catches_a_broken_split() {
        let mut r = Rng::new(5, Pass::Photon, 0);
        let photons = (0..1000)
            .map(|_| photon(Vec3A::new(r.next_f32(), r.next_f32(), r.next_f32())))
            .collect();
        let mut map = PhotonMap::build(photons);
        assert_eq!(map.validate(), Ok(()));
        assert_eq!(map.top_nodes, 7, "1000 photons have 3 top levels");
        let (m, left, _) = map.split(map.root());
        let a = store::code_axis(map.code[m]) as usize;
        let mut ids = Vec::new();
        map.subtree_ids(left, &mut ids);
        let i = ids[ids.len() / 2];
        map.pos[i][a] = map.pos[m][a] + 0.5;
        assert_eq!(
            map.validate(),
            Err(format!(
                "photon {i} left of node 0 is above its split {}",
                map.pos[0][a]
            ))
        );
    }

    /// Returns the photon distances `f` computes (queries compute one per photon they look at).
    fn distances_computed(f: impl FnOnce()) -> usize {
        let before = DIST2_CALLS.get();
        f();
        DIST2_CALLS.get() - before
    }

    #[test]
    fn top_levels_end_where_a_subtree_could_hold_fewer_than_bottom_min() {
        assert_eq!(top_depth(0), 0);
        assert_eq!(top_depth(2 * BOTTOM_MIN), 0);
        assert_eq!(top_depth(2 * BOTTOM_MIN + 1), 1);
        for n in [1000, 4 * BOTTOM_MIN + 2, 4 * BOTTOM_MIN + 3, 123_457] {
            let d = top_depth(n);
            // Walk every subtree at depth d, and one level below, of the in-order tree.
            let mut level = vec![(0usize, n)];
            for _ in 0..d {
                level = level
                    .iter()
                    .flat_map(|&(lo, hi)| {
                        let m = lo + (hi - lo) / 2;
                        [(lo, m), (m + 1, hi)]
                    })
                    .collect();
            }
            let smallest = level.iter().map(|r| r.1 - r.0).min().unwrap();
            assert!(smallest >= BOTTOM_MIN, "n {n}: depth {d} has {smallest}");
            assert!(
                (smallest - 1) / 2 < BOTTOM_MIN,
                "n {n}: depth {d} is not the last"
            );
        }
    }

    #[test]
    fn all_duplicates_build_a_balanced_tree_and_query_near_one_path() {
        let n = 100_000;
        let map = PhotonMap::build(vec![photon(Vec3A::ONE); n]);
        assert_eq!(map.validate(), Ok(()));
        let mut out = Vec::new();
        // Ties with the k-th distance are pruned, so the query reads the seed subtree (at most
        // 4k photons) and the medians on one root-to-leaf path, not the whole map.
        let looked = distances_computed(|| {
            assert_eq!(map.knn(Vec3A::ONE, 50, f32::INFINITY, &mut out), 0.0);
        });
        assert_eq!(out.len(), 50);
        assert!(looked <= 4 * 50 + 64, "{looked} of {n} photons");
    }

    #[test]
    fn a_large_coplanar_map_builds_balanced_and_queries_locally() {
        // 400 000 photons on y = 0 on a 200 × 200 grid (10 duplicates each): kiddo's failure case.
        let points = (0..400_000).map(|i| {
            let (x, z) = ((i % 200) as f32, ((i / 200) % 200) as f32);
            photon(Vec3A::new(x * 0.005, 0.0, z * 0.005))
        });
        let map = PhotonMap::build(points.collect());
        assert_eq!(map.validate(), Ok(()));
        let mut out = Vec::new();
        let queries = 20_000;
        let looked = distances_computed(|| {
            for i in 0..queries {
                let q = Vec3A::new((i % 141) as f32 * 0.007, 0.0, (i / 141) as f32 * 0.007);
                map.knn(q, 50, f32::INFINITY, &mut out);
                assert_eq!(out.len(), 50);
            }
        });
        // 50 photons are 5 grid points; a query that stays local reads a few leaves around them
        // (282 per query when written), where a degenerate tree would read a large
        // part of the 400 000.
        let per_query = looked as f64 / queries as f64;
        assert!(per_query < 600.0, "{per_query} photons per query");
    }

    thread_local! {
        /// Calls of [`dist2`] on this thread.
        pub(super) static DIST2_CALLS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
    }
}
