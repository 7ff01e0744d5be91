//! Packet traversal: up to [`PACKET`] coherent rays (camera rays of neighbouring pixels) walk the
//! tree together, one AVX2 lane per ray, as in Wald et al., "Interactive Rendering with Coherent
//! Ray Tracing" (2001) and Embree's `rtcIntersect8`. A node is fetched once for the packet and
//! each of its children is tested against all the rays at once; a leaf is tested by each ray
//! that reaches it, with the single-ray triangle test. Camera rays of one row of eight pixels
//! visit nearly the same nodes, so the packet pays for a node's cache misses and its test's
//! latency once instead of eight times.
//!
//! Each ray enters exactly the boxes it enters on its own: a child's distances are the
//! single-ray kernel's fused multiply-adds (the smaller of a slab's two plane distances is the
//! one the single ray takes as its near plane, bit for bit), and a ray tests a leaf only if it
//! entered its box before its closest hit so far. So each ray finds its closest `t` bit for bit;
//! only the order of the leaves differs, which can pick the other of two triangles hit at
//! exactly the same `t` (a ray through a shared edge), and which hit an any-hit query reports.
//!
//! AVX2 and FMA only; other CPUs trace coherent rays one by one.

#![cfg(target_arch = "x86_64")]

use super::wide::{LEAF, Node, SlabRay, WIDTH, WideBvh, leaf_ids, prefetch_entry};
use crate::geometry::Ray;
use std::arch::x86_64::*;
use std::ops::Range;

/// Rays per packet: one per AVX2 lane.
pub const PACKET: usize = 8;

/// A packet's rays as vectors, one lane per ray.
struct Rays {
    inv: [__m256; 3],
    org_inv: [__m256; 3],
    tmin: __m256,
    /// The rays that exist (a stream's last packet may be short).
    valid: u32,
    /// The plane rows every ray meets first and last on each axis, when their directions' signs
    /// agree (camera rays of a row of pixels, nearly always): two plane distances per axis and
    /// child instead of four and a min and a max.
    rows: Option<([usize; 3], [usize; 3])>,
}

impl Rays {
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn new(rays: &[Ray]) -> Rays {
        // Lanes past a short packet's end repeat its last ray (and are not valid).
        let pre: [SlabRay; PACKET] =
            std::array::from_fn(|i| SlabRay::new(&rays[i.min(rays.len() - 1)]));
        // Rows: inverse direction x, y, z, origin times it x, y, z, tmin.
        let mut rows = [[0.0f32; PACKET]; 7];
        for (i, s) in pre.iter().enumerate() {
            for a in 0..3 {
                rows[a][i] = s.inv_dir[a];
                rows[3 + a][i] = s.org_inv[a];
            }
            rows[6][i] = s.tmin;
        }
        // SAFETY: the caller guarantees AVX.
        unsafe {
            let inv = [load(&rows[0]), load(&rows[1]), load(&rows[2])];
            // The sign bits of the inverse directions, ray by ray: a ray meets the max plane
            // first where its inverse direction is negative (`SlabRay::new`).
            let signs = [
                _mm256_movemask_ps(inv[0]),
                _mm256_movemask_ps(inv[1]),
                _mm256_movemask_ps(inv[2]),
            ];
            let same = signs.iter().all(|&m| m == 0 || m == 0xff);
            Rays {
                inv,
                org_inv: [load(&rows[3]), load(&rows[4]), load(&rows[5])],
                tmin: load(&rows[6]),
                valid: (1u32 << rays.len()) - 1,
                rows: same.then_some((pre[0].near, pre[0].far)),
            }
        }
    }
}

/// A node waiting on the packet's stack: the rays that entered its box and where.
#[derive(Clone, Copy)]
struct Pending {
    child: u32,
    /// The rays that entered the box (bit per lane).
    rays: u32,
    /// Where the first of them enters, which orders the stack (made only when a node has two
    /// children or more to order).
    key: f32,
    /// Each ray's entry distance (meaningful in `rays`' lanes).
    t: __m256,
}

/// Tests `node`'s children against the rays in `active` whose closest hits so far are `tmax`:
/// returns the mask of the child slots some ray enters, with each such slot's child, rays and
/// entry distances in `out` at the slot's index (`key` unset).
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[inline(always)]
unsafe fn enter(
    r: &Rays,
    node: &Node,
    active: u32,
    tmax: __m256,
    out: &mut [Pending; WIDTH],
) -> u32 {
    let p = &node.planes;
    let mut hit = 0;
    // SAFETY: the caller guarantees AVX2 and FMA; `Node` is 64-byte aligned, so its 32-byte
    // rows suit aligned loads.
    unsafe {
        // Empty slots hold min x = +inf.
        let slots = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(
            _mm256_load_ps(p[0].as_ptr()),
            _mm256_set1_ps(f32::INFINITY),
        )) as u32;
        // The active rays as a lane mask: the others enter no child.
        let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let live = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_and_si256(_mm256_set1_epi32(active as i32), bits),
            bits,
        ));
        let mut todo = slots;
        while todo != 0 {
            let c = todo.trailing_zeros() as usize;
            todo &= todo - 1;
            // A function, not a closure (see `plane`).
            let d = dist;
            let (near, far) = if let Some((nr, fr)) = r.rows {
                (
                    _mm256_max_ps(
                        _mm256_max_ps(d(r, node, nr[0], c, 0), d(r, node, nr[1], c, 1)),
                        _mm256_max_ps(d(r, node, nr[2], c, 2), r.tmin),
                    ),
                    _mm256_min_ps(
                        _mm256_min_ps(d(r, node, fr[0], c, 0), d(r, node, fr[1], c, 1)),
                        _mm256_min_ps(d(r, node, fr[2], c, 2), tmax),
                    ),
                )
            } else {
                // The smaller of a slab's two distances is the near plane's, bit for bit.
                let (x0, x1) = (d(r, node, 0, c, 0), d(r, node, 1, c, 0));
                let (y0, y1) = (d(r, node, 2, c, 1), d(r, node, 3, c, 1));
                let (z0, z1) = (d(r, node, 4, c, 2), d(r, node, 5, c, 2));
                (
                    _mm256_max_ps(
                        _mm256_max_ps(_mm256_min_ps(x0, x1), _mm256_min_ps(y0, y1)),
                        _mm256_max_ps(_mm256_min_ps(z0, z1), r.tmin),
                    ),
                    _mm256_min_ps(
                        _mm256_min_ps(_mm256_max_ps(x0, x1), _mm256_max_ps(y0, y1)),
                        _mm256_min_ps(_mm256_max_ps(z0, z1), tmax),
                    ),
                )
            };
            let enters = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far), live);
            let rays = _mm256_movemask_ps(enters) as u32;
            // Written at the slot's own index whether or not a ray enters: a branch here
            // mispredicted often enough to cost 7% of the packets' time, and packing the hits
            // made each child's store wait for the test of the one before.
            out[c] = Pending {
                child: node.child[c],
                rays,
                key: 0.0,
                t: near,
            };
            hit |= ((rays != 0) as u32) << c;
        }
    }
    hit
}

/// Sets the ordering key of the children in `hit`: the distance at which the first of each
/// child's rays enters it. The minimum over the rays cost a horizontal reduction per child (9%
/// of the packets' time), and the camera rays of one packet order a node's children alike.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn set_keys(kids: &mut [Pending; WIDTH], hit: u32) {
    let mut left = hit;
    while left != 0 {
        let k = &mut kids[left.trailing_zeros() as usize];
        left &= left - 1;
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let lane = _mm256_set1_epi32(k.rays.trailing_zeros() as i32);
            k.key = _mm256_cvtss_f32(_mm256_permutevar8x32_ps(k.t, lane));
        }
    }
}

/// Each ray's distance to plane `row` of child `c` of `node`, on axis `a`: the single-ray
/// kernel's fused multiply-add. A function, not a closure: a closure holding an intrinsic is not
/// always inlined, and then the intrinsic is a call (the any-hit packets took 15% longer).
///
/// # Safety
/// The CPU must have AVX and FMA.
#[inline(always)]
unsafe fn dist(r: &Rays, node: &Node, row: usize, c: usize, a: usize) -> __m256 {
    // SAFETY: the caller guarantees AVX and FMA.
    unsafe { _mm256_fmsub_ps(_mm256_set1_ps(node.planes[row][c]), r.inv[a], r.org_inv[a]) }
}

/// Eight floats as a vector.
///
/// # Safety
/// The CPU must have AVX.
#[inline(always)]
unsafe fn load(v: &[f32; PACKET]) -> __m256 {
    // SAFETY: the caller guarantees AVX; `v` is eight floats.
    unsafe { _mm256_loadu_ps(v.as_ptr()) }
}

/// The rays of `rays` (a bit per lane) whose entry distance `t` is not beyond `tmax`.
///
/// # Safety
/// The CPU must have AVX.
#[inline(always)]
unsafe fn still_in(rays: u32, t: __m256, tmax: __m256) -> u32 {
    // SAFETY: the caller guarantees AVX.
    rays & unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t, tmax)) as u32 }
}

/// Runs `one(packet, first, stack)` on each packet of `rays` in order (the last may be short),
/// `first` the index of its first ray, with an empty `stack` to use.
#[inline(always)]
fn each_packet(bvh: &WideBvh, rays: &[Ray], mut one: impl FnMut(&[Ray], usize, &mut Vec<Pending>)) {
    let mut stack = Vec::with_capacity(bvh.stack_len);
    for (k, packet) in rays.chunks(PACKET).enumerate() {
        one(packet, k * PACKET, &mut stack);
        stack.clear();
    }
}

/// A packet's rays as vectors, room for a node's children, and the root as the first node to
/// visit, entered by every ray.
///
/// # Safety
/// The CPU must have AVX.
#[inline(always)]
unsafe fn start(rays: &[Ray]) -> (Rays, [Pending; WIDTH], Pending) {
    // SAFETY: the caller guarantees AVX.
    let r = unsafe { Rays::new(rays) };
    let root = Pending {
        child: 0,
        rays: r.valid,
        key: 0.0,
        t: r.tmin,
    };
    (r, [root; WIDTH], root)
}

/// Closest-hit traversal of `rays` in packets of [`PACKET`] (the last may be short), in order:
/// `leaf_fn(i, ray, ids)` is [`WideBvh::closest`]'s leaf callback for ray `i` of `rays`.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn closest(
    bvh: &WideBvh,
    rays: &[Ray],
    mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> f32,
    prefetch: impl Fn(Range<u32>),
) {
    each_packet(
        bvh,
        rays,
        #[inline(always)]
        |packet, first, stack| {
            // SAFETY: this function is compiled for AVX2 and FMA, which the caller guarantees.
            unsafe {
                closest_packet(
                    bvh,
                    packet,
                    stack,
                    #[inline(always)]
                    |i, r, ids| leaf_fn(first + i, r, ids),
                    &prefetch,
                )
            }
        },
    )
}

/// Closest-hit traversal of one packet of 1 to [`PACKET`] rays, with an empty `stack` to use
/// (left empty): `leaf_fn(i, ray, ids)` for ray `i` of the packet.
///
/// # Safety
/// The CPU must have AVX2 and FMA (the caller is compiled for them, and this is inlined there).
#[inline(always)]
unsafe fn closest_packet(
    bvh: &WideBvh,
    rays: &[Ray],
    stack: &mut Vec<Pending>,
    mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> f32,
    prefetch: &impl Fn(Range<u32>),
) {
    debug_assert!((1..=PACKET).contains(&rays.len()) && stack.is_empty());
    // SAFETY: the caller guarantees AVX2 and FMA.
    let (r, mut kids, mut cur) = unsafe { start(rays) };
    let mut tmax: [f32; PACKET] = std::array::from_fn(|i| rays.get(i).map_or(0.0, |r| r.tmax));
    // SAFETY: as above.
    let mut tmax_v = unsafe { load(&tmax) };
    loop {
        // SAFETY: the caller guarantees AVX2.
        let active = unsafe { still_in(cur.rays, cur.t, tmax_v) };
        if active != 0 {
            if cur.child & LEAF == 0 {
                super::counters::node();
                let node = &bvh.nodes[cur.child as usize];
                // SAFETY: the caller guarantees AVX2 and FMA.
                let hit = unsafe { enter(&r, node, active, tmax_v, &mut kids) };
                if hit != 0 {
                    let mut near = hit.trailing_zeros() as usize;
                    let mut rest = hit & (hit - 1);
                    if rest != 0 {
                        // Continue with the nearest child; push the others, nearest on top.
                        // SAFETY: the caller guarantees AVX2.
                        unsafe { set_keys(&mut kids, hit) };
                        let mut left = rest;
                        while left != 0 {
                            let k = left.trailing_zeros() as usize;
                            left &= left - 1;
                            if kids[k].key < kids[near].key {
                                near = k;
                            }
                        }
                        rest = hit & !(1 << near);
                    }
                    let base = stack.len();
                    while rest != 0 {
                        let e = &kids[rest.trailing_zeros() as usize];
                        rest &= rest - 1;
                        prefetch_entry(bvh, e.child, prefetch);
                        let mut j = stack.len();
                        stack.push(*e);
                        while j > base && stack[j - 1].key < e.key {
                            stack[j] = stack[j - 1];
                            j -= 1;
                        }
                        stack[j] = *e;
                    }
                    cur = kids[near];
                    continue;
                }
            } else {
                let ids = leaf_ids(cur.child);
                let mut left = active;
                while left != 0 {
                    let i = left.trailing_zeros() as usize;
                    left &= left - 1;
                    let ray = Ray {
                        tmax: tmax[i],
                        ..rays[i]
                    };
                    let t = leaf_fn(i, &ray, ids.clone());
                    if t < tmax[i] {
                        tmax[i] = t;
                    }
                }
                // SAFETY: as above.
                tmax_v = unsafe { load(&tmax) };
            }
        }
        match stack.pop() {
            Some(e) => cur = e,
            None => return,
        }
    }
}

/// Any-hit traversal of `rays` in packets of [`PACKET`], in order: `leaf_fn(i, ray, ids)` is
/// [`WideBvh::any`]'s leaf callback for ray `i` of `rays`; a ray is done once its callback
/// returns true.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn any(
    bvh: &WideBvh,
    rays: &[Ray],
    mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> bool,
    prefetch: impl Fn(Range<u32>),
) {
    each_packet(
        bvh,
        rays,
        #[inline(always)]
        |packet, first, stack| {
            // SAFETY: as in `closest`.
            unsafe {
                any_packet(
                    bvh,
                    packet,
                    stack,
                    #[inline(always)]
                    |i, r, ids| leaf_fn(first + i, r, ids),
                    &prefetch,
                )
            }
        },
    )
}

/// Any-hit traversal of one packet of 1 to [`PACKET`] rays, with an empty `stack` to use;
/// `leaf_fn(i, ray, ids)` for ray `i` of the packet.
///
/// # Safety
/// As for [`closest_packet`].
#[inline(always)]
unsafe fn any_packet(
    bvh: &WideBvh,
    rays: &[Ray],
    stack: &mut Vec<Pending>,
    mut leaf_fn: impl FnMut(usize, &Ray, Range<u32>) -> bool,
    prefetch: &impl Fn(Range<u32>),
) {
    debug_assert!((1..=PACKET).contains(&rays.len()) && stack.is_empty());
    // SAFETY: the caller guarantees AVX2 and FMA.
    let (r, mut kids, mut cur) = unsafe { start(rays) };
    let tmax: [f32; PACKET] = std::array::from_fn(|i| rays.get(i).map_or(0.0, |r| r.tmax));
    // SAFETY: as above.
    let tmax_v = unsafe { load(&tmax) };
    let mut done = 0u32;
    loop {
        let active = cur.rays & !done;
        if active != 0 {
            if cur.child & LEAF == 0 {
                super::counters::node();
                let node = &bvh.nodes[cur.child as usize];
                // SAFETY: the caller guarantees AVX2 and FMA.
                let hit = unsafe { enter(&r, node, active, tmax_v, &mut kids) };
                if hit != 0 {
                    // Children in lane order, no sorting: push all but the first, the last
                    // deepest.
                    let first = hit.trailing_zeros() as usize;
                    let mut rest = hit & (hit - 1);
                    while rest != 0 {
                        let top = 31 - rest.leading_zeros() as usize;
                        rest &= !(1 << top);
                        let e = &kids[top];
                        prefetch_entry(bvh, e.child, prefetch);
                        stack.push(*e);
                    }
                    cur = kids[first];
                    continue;
                }
            } else {
                let ids = leaf_ids(cur.child);
                let mut left = active;
                while left != 0 {
                    let i = left.trailing_zeros() as usize;
                    left &= left - 1;
                    if leaf_fn(i, &rays[i], ids.clone()) {
                        done |= 1 << i;
                    }
                }
                if done == r.valid {
                    return;
                }
            }
        }
        match stack.pop() {
            Some(e) => cur = e,
            None => return,
        }
    }
}
