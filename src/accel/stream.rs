//! Stream traversal: many independent rays traced at once, [`LANES`] in flight, each taking one
//! step (one node or one leaf) in turn. After its step a ray prefetches the node or leaf it
//! will visit next and yields to the others, so by the time its turn comes back the data has
//! (mostly) arrived: the cache misses of up to [`LANES`] rays overlap instead of following one
//! another. This is the "asynchronous memory access chaining" of Kocberber et al. (VLDB 2015),
//! applied to BVH traversal; Embree's stream API (`rtcIntersect1M`) takes the same input and
//! traces it ray by ray for incoherent streams.
//!
//! Why: an incoherent ray on the 2M-triangle wave mesh spends most of its time waiting for
//! memory (its nodes and triangle blocks are nowhere in cache): rays going down took about
//! 340 ns for 4.3 nodes and 4 triangles, against 18 ns for rays going up, which leave after the
//! root. One ray's misses depend on each other (a node's children are known only once it has
//! arrived); the misses of different rays do not.
//!
//! Each ray runs exactly the single-ray traversal of `accel::wide` (the same node test, the
//! same order of children, the same leaf calls in the same order), so a stream finds, ray by
//! ray, the hits that [`super::Bvh::closest_leaf`] and [`super::Bvh::any_leaf`] find, bit for
//! bit. Only the interleaving differs: the callbacks receive the lane and the ray's index, and
//! calls for different rays come interleaved.

use super::stack::{Entry, Stack};
use super::wide::{
    LEAF, Node, NodeTest, SlabRay, WIDTH, WideBvh, first_in_lane_order, leaf_ids, nearest_first,
    prefetch_entry, prefetch_node,
};
use crate::geometry::Ray;
use glam::Vec3A;
use std::mem::MaybeUninit;
use std::ops::Range;

/// What the caller knows of a stream's rays (as Embree's `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`
/// and `..._INCOHERENT`): it decides how [`crate::accel::mesh::MeshGeom::intersect_stream`]
/// traces them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coherence {
    /// Rays that start together and point alike (camera rays of neighbouring pixels, in
    /// order): traced in packets of eight that share each node's test (`accel::packet`) where
    /// the CPU has AVX2, else one by one. Interleaving them only added work: on the wave mesh
    /// camera rays took 0.18-0.22 s per million interleaved against 0.15 s one by one.
    Coherent,
    /// Rays going anywhere (gather rays, photons, the harness's random rays): interleaved,
    /// [`LANES`] in flight.
    Incoherent,
}

/// Rays in flight. On the wave mesh's random rays (Zen 4 VM) four lanes took 0.11-0.13 s per
/// million rays, eight 0.095-0.11 s and sixteen 0.090-0.12 s for the closest hit and 0.089-0.091
/// s against 0.096-0.105 s with eight for any hit; sixteen lanes' state and stacks take about
/// 10 KB, well inside L1.
pub const LANES: usize = 16;

/// One ray in flight.
struct Lane {
    /// The ray's index in the stream, or [`IDLE`].
    ray: usize,
    /// The ray, with `tmax` the closest hit so far.
    r: Ray,
    pre: SlabRay,
    /// What the ray visits at its next step.
    cur: Entry,
    /// Entries on the lane's stack (kept by [`run`]).
    depth: usize,
}

/// Marks a lane with no ray.
const IDLE: usize = usize::MAX;

impl Lane {
    fn idle() -> Lane {
        let r = Ray::new(Vec3A::ZERO, Vec3A::X);
        Lane {
            ray: IDLE,
            pre: SlabRay::new(&r),
            r,
            cur: Entry::default(),
            depth: 0,
        }
    }

    /// Starts ray `i` at the root, which it visits at its next step.
    #[inline(always)]
    fn start(&mut self, bvh: &WideBvh, i: usize, ray: &Ray) {
        self.ray = i;
        self.r = *ray;
        self.pre = SlabRay::new(ray);
        self.cur = Entry {
            child: 0,
            t: ray.tmin,
        };
        self.depth = 0;
        prefetch_node(bvh, 0);
    }
}

/// The lanes and their stacks, and the next ray of the stream to start.
struct Flight<'a> {
    bvh: &'a WideBvh,
    rays: &'a [Ray],
    lanes: [Lane; LANES],
    /// Lane `k`'s stack is `slots[k * cap..(k + 1) * cap]`.
    slots: Vec<MaybeUninit<Entry>>,
    cap: usize,
    next: usize,
    active: usize,
}

impl<'a> Flight<'a> {
    fn new(bvh: &'a WideBvh, rays: &'a [Ray]) -> Flight<'a> {
        let cap = bvh.stack_len;
        let mut slots = Vec::new();
        slots.resize_with(LANES * cap, MaybeUninit::uninit);
        let mut f = Flight {
            bvh,
            rays,
            lanes: std::array::from_fn(|_| Lane::idle()),
            slots,
            cap,
            next: 0,
            active: 0,
        };
        for k in 0..LANES {
            f.refill(k);
        }
        f
    }

    /// Starts the stream's next ray in lane `k`, whose ray is done, or leaves it idle.
    #[inline(always)]
    fn refill(&mut self, k: usize) {
        let was = self.lanes[k].ray != IDLE;
        if let Some(ray) = self.rays.get(self.next) {
            self.lanes[k].start(self.bvh, self.next, ray);
            self.next += 1;
            self.active += 1;
        } else {
            self.lanes[k].ray = IDLE;
        }
        if was {
            self.active -= 1;
        }
    }

    /// Lane `k` and its stack.
    #[inline(always)]
    fn lane(&mut self, k: usize) -> (&mut Lane, Stack<'_>) {
        let lane = &mut self.lanes[k];
        let depth = lane.depth;
        let slots = &mut self.slots[k * self.cap..(k + 1) * self.cap];
        // SAFETY: `depth` is 0 when a ray starts and is otherwise set from the length of the
        // stack over these same slots, so the slots below it hold entries that stack wrote.
        (lane, unsafe { Stack::over(slots, depth) })
    }
}

/// Runs `step(lane, state, stack)` on each lane that has a ray, lane after lane, until every
/// ray of the stream is done; `step` takes one step of its lane's ray (one node or one leaf,
/// then a prefetch of what comes next) and returns false when that ray is done, and the lane
/// starts the stream's next ray.
#[inline(always)]
fn run(bvh: &WideBvh, rays: &[Ray], mut step: impl FnMut(usize, &mut Lane, &mut Stack) -> bool) {
    let mut f = Flight::new(bvh, rays);
    while f.active > 0 {
        for k in 0..LANES {
            let (l, mut stack) = f.lane(k);
            if l.ray == IDLE {
                continue;
            }
            let going = step(k, l, &mut stack);
            l.depth = stack.len();
            if !going {
                f.refill(k);
            }
        }
    }
}

/// Lane `l`'s visit to its current node (inner): the node, and the children's mask and entry
/// distances from test `T`.
#[inline(always)]
fn visit<'b, T: NodeTest>(bvh: &'b WideBvh, l: &Lane) -> (&'b Node, u32, [f32; WIDTH]) {
    super::counters::node();
    let node = &bvh.nodes[l.cur.child as usize];
    let (mask, tnear) = T::enter(&l.pre, node, l.r.tmax);
    (node, mask, tnear)
}

/// Closest-hit traversal of a stream with node test `T`: `leaf_fn(lane, i, ray, ids)` is
/// [`WideBvh::closest`]'s leaf callback for ray `i` of `rays`, traced in lane `lane`.
#[inline(always)]
pub(super) fn closest_with<T: NodeTest>(
    bvh: &WideBvh,
    rays: &[Ray],
    mut leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> f32,
    prefetch: impl Fn(Range<u32>),
) {
    run(
        bvh,
        rays,
        // Inlined, or the node test's intrinsics are calls: any hits took 5 times as long.
        #[inline(always)]
        |k, l, stack| {
            if l.cur.child & LEAF == 0 {
                let (node, mask, tnear) = visit::<T>(bvh, l);
                if mask != 0 {
                    l.cur = nearest_first(node, mask, &tnear, stack, |_| {});
                    prefetch_entry(bvh, l.cur.child, &prefetch);
                    return true;
                }
            } else {
                let t = leaf_fn(k, l.ray, &l.r, leaf_ids(l.cur.child));
                if t < l.r.tmax {
                    l.r.tmax = t;
                }
            }
            let Some(e) = stack.pop_within(l.r.tmax) else {
                return false;
            };
            l.cur = e;
            prefetch_entry(bvh, e.child, &prefetch);
            true
        },
    )
}

/// Any-hit traversal of a stream with node test `T`: `leaf_fn(lane, i, ray, ids)` is
/// [`WideBvh::any`]'s leaf callback for ray `i`; a ray stops at its first hit.
#[inline(always)]
pub(super) fn any_with<T: NodeTest>(
    bvh: &WideBvh,
    rays: &[Ray],
    mut leaf_fn: impl FnMut(usize, usize, &Ray, Range<u32>) -> bool,
    prefetch: impl Fn(Range<u32>),
) {
    run(
        bvh,
        rays,
        // Inlined, or the node test's intrinsics are calls: any hits took 5 times as long.
        #[inline(always)]
        |k, l, stack| {
            if l.cur.child & LEAF == 0 {
                let (node, mask, _) = visit::<T>(bvh, l);
                if mask != 0 {
                    // As the single-ray traversal, whose pushes alone are prefetched.
                    let child = first_in_lane_order(node, mask, stack, |_| {});
                    l.cur = Entry { child, t: 0.0 };
                    prefetch_entry(bvh, child, &prefetch);
                    return true;
                }
            } else if leaf_fn(k, l.ray, &l.r, leaf_ids(l.cur.child)) {
                return false;
            }
            let Some(e) = stack.pop() else {
                return false;
            };
            l.cur = e;
            prefetch_entry(bvh, e.child, &prefetch);
            true
        },
    )
}
