//! The 4-wide BVH we trace: obvhs's binary BVH collapsed so that each node holds up to four
//! children whose float boxes are stored plane by plane, one SSE2 lane per child.
//!
//! Traversal tests the four children of a node with one 4-wide slab test, continues with the
//! nearest child it enters and keeps the others on a stack, nearest on top (the single-ray scheme
//! of Embree's BVH4 kernels, Wald et al., "Embree: A Kernel Framework for Efficient CPU Ray
//! Tracing", 2014). A popped entry is skipped when the closest hit found so far lies in front of it.

use crate::geometry::Ray;
use glam::Vec3A;
use obvhs::bvh2::Bvh2;
use std::mem::MaybeUninit;

/// Stack entries that live on the thread stack; deeper trees (pathological scenes) use the heap.
const STACK: usize = 96;

/// A node: up to four children, each an inner node or a leaf (a run of BVH-order primitives).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    /// Child boxes by plane: min x, max x, min y, max y, min z, max z; one lane per child. An
    /// empty slot holds the inverted box (min +∞, max −∞), which no ray enters.
    planes: [[f32; 4]; 6],
    /// Per child: the inner node's index, or the leaf's first BVH-order primitive.
    index: [u32; 4],
    /// Per child: 0 for an inner node, else the leaf's primitive count.
    count: [u32; 4],
}

impl Node {
    const EMPTY: Node = Node {
        planes: [
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
        ],
        index: [0; 4],
        count: [0; 4],
    };

    fn set_box(&mut self, slot: usize, min: Vec3A, max: Vec3A) {
        for axis in 0..3 {
            self.planes[2 * axis][slot] = min[axis];
            self.planes[2 * axis + 1][slot] = max[axis];
        }
    }
}

/// A 4-wide BVH over the primitives of an obvhs [`Bvh2`], root at node 0.
pub(super) struct WideBvh {
    nodes: Vec<Node>,
    /// For each BVH-order index, the caller's primitive index (obvhs's `primitive_indices`).
    pub order: Vec<u32>,
    /// Stack entries a traversal can need: three per level below the root, plus one.
    stack_len: usize,
}

/// A child waiting on the traversal stack, with the ray's entry distance into its box.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    index: u32,
    count: u32,
    t: f32,
}

/// A traversal stack over borrowed slots that are never initialised up front, so a ray pays
/// nothing for the capacity it does not use (zeroing the fixed array cost every ray 1 KiB of stores).
struct Stack<'a> {
    slots: &'a mut [MaybeUninit<Entry>],
    /// Slots `..len` hold entries written by `push` or `insert_sorted`; the rest may be
    /// uninitialised.
    len: usize,
}

impl Stack<'_> {
    /// Returns entry `i`.
    ///
    /// # Panics
    /// When `i >= len`.
    #[inline(always)]
    fn get(&self, i: usize) -> Entry {
        assert!(i < self.len);
        // SAFETY: slots below `len` have been written (the invariant of `len`).
        unsafe { self.slots[i].assume_init() }
    }

    /// Pushes `e`.
    ///
    /// # Panics
    /// When the stack is full (the tree is deeper than its stack length allows: a bug).
    #[inline(always)]
    fn push(&mut self, e: Entry) {
        self.slots[self.len].write(e);
        self.len += 1;
    }

    /// Pushes `e` among the entries from `base` up, which stay sorted by `t`, nearest on top.
    #[inline(always)]
    fn insert_sorted(&mut self, base: usize, e: Entry) {
        let mut j = self.len;
        self.push(e);
        while j > base && self.get(j - 1).t < e.t {
            let moved = self.get(j - 1);
            self.slots[j].write(moved);
            j -= 1;
        }
        self.slots[j].write(e);
    }

    /// Pops the top entry, if any.
    #[inline(always)]
    fn pop(&mut self) -> Option<Entry> {
        let top = self.len.checked_sub(1)?;
        let e = self.get(top);
        self.len = top;
        Some(e)
    }
}

impl WideBvh {
    /// Collapses `bvh2` (at least one node) into 4-wide nodes: each node takes its two children
    /// and then repeatedly opens the inner child with the largest surface until it has four.
    pub(super) fn from_bvh2(bvh2: &Bvh2) -> WideBvh {
        let src = &bvh2.nodes;
        let mut nodes = vec![Node::EMPTY];
        let mut max_level = 1;
        if src[0].prim_count > 0 {
            // A leaf at the root: one node with one leaf child.
            let r = &src[0];
            nodes[0].set_box(0, r.aabb.min, r.aabb.max);
            nodes[0].index[0] = r.first_index;
            nodes[0].count[0] = r.prim_count;
        } else {
            // (source inner node, our node, level); a work list rather than recursion, so a
            // degenerate, very deep tree cannot overflow the thread's stack.
            let mut work = vec![(0usize, 0usize, 1usize)];
            while let Some((at, me, level)) = work.pop() {
                max_level = max_level.max(level);
                let first = src[at].first_index as usize;
                let mut kids = vec![first, first + 1];
                while kids.len() < 4 {
                    let widest = kids
                        .iter()
                        .enumerate()
                        .filter(|&(_, &k)| src[k].prim_count == 0)
                        .max_by(|a, b| {
                            src[*a.1]
                                .aabb
                                .half_area()
                                .total_cmp(&src[*b.1].aabb.half_area())
                        });
                    let Some((pos, &k)) = widest else { break };
                    let f = src[k].first_index as usize;
                    kids[pos] = f;
                    kids.push(f + 1);
                }
                for (slot, &k) in kids.iter().enumerate() {
                    let n = &src[k];
                    nodes[me].set_box(slot, n.aabb.min, n.aabb.max);
                    if n.prim_count > 0 {
                        nodes[me].index[slot] = n.first_index;
                        nodes[me].count[slot] = n.prim_count;
                    } else {
                        nodes[me].index[slot] = nodes.len() as u32;
                        nodes.push(Node::EMPTY);
                        work.push((k, nodes.len() - 1, level + 1));
                    }
                }
            }
        }
        nodes.shrink_to_fit();
        WideBvh {
            nodes,
            order: bvh2.primitive_indices.clone(),
            stack_len: 3 * max_level + 1,
        }
    }

    /// Returns the bytes the nodes and the order take.
    pub(super) fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.order.as_slice())
    }

    /// Runs `f` with an empty traversal stack long enough for this tree.
    #[inline(always)]
    fn with_stack<R>(&self, f: impl FnOnce(Stack) -> R) -> R {
        if self.stack_len <= STACK {
            f(Stack {
                slots: &mut [const { MaybeUninit::uninit() }; STACK],
                len: 0,
            })
        } else {
            let mut heap = Vec::new();
            heap.resize_with(self.stack_len, MaybeUninit::uninit);
            f(Stack {
                slots: &mut heap,
                len: 0,
            })
        }
    }

    /// Finds the closest hit; see [`super::Bvh::closest`].
    #[inline(always)]
    pub(super) fn closest(
        &self,
        ray: &Ray,
        mut hit_fn: impl FnMut(&Ray, usize) -> f32,
    ) -> Option<(usize, f32)> {
        let pre = SlabRay::new(ray);
        let mut r = *ray;
        let mut best = None;
        self.with_stack(
            #[inline(always)]
            |mut stack| {
                let mut cur = Entry {
                    t: ray.tmin,
                    ..Entry::default()
                };
                loop {
                    if cur.count == 0 {
                        let node = &self.nodes[cur.index as usize];
                        let (mut mask, tnear) = pre.enter(node, r.tmax);
                        if mask != 0 {
                            let child = |c: usize| Entry {
                                index: node.index[c],
                                count: node.count[c],
                                t: tnear[c],
                            };
                            // Continue with the nearest child; push the others, nearest on top.
                            let mut near = child(mask.trailing_zeros() as usize);
                            mask &= mask - 1;
                            let base = stack.len;
                            while mask != 0 {
                                let mut e = child(mask.trailing_zeros() as usize);
                                mask &= mask - 1;
                                if e.t < near.t {
                                    std::mem::swap(&mut e, &mut near);
                                }
                                stack.insert_sorted(base, e);
                            }
                            cur = near;
                            continue;
                        }
                    } else {
                        for i in cur.index..cur.index + cur.count {
                            let t = hit_fn(&r, i as usize);
                            if t < r.tmax {
                                best = Some((i as usize, t));
                                r.tmax = t;
                            }
                        }
                    }
                    loop {
                        match stack.pop() {
                            None => return best,
                            Some(e) if e.t <= r.tmax => {
                                cur = e;
                                break;
                            }
                            Some(_) => {}
                        }
                    }
                }
            },
        )
    }

    /// Returns true when some primitive reports a hit; see [`super::Bvh::any`].
    #[inline(always)]
    pub(super) fn any(&self, ray: &Ray, mut hit_fn: impl FnMut(&Ray, usize) -> f32) -> bool {
        let pre = SlabRay::new(ray);
        self.with_stack(
            #[inline(always)]
            |mut stack| {
                let mut cur = Entry::default();
                loop {
                    if cur.count == 0 {
                        let node = &self.nodes[cur.index as usize];
                        let (mut mask, _) = pre.enter(node, ray.tmax);
                        if mask != 0 {
                            let child = |c: u32| Entry {
                                index: node.index[c as usize],
                                count: node.count[c as usize],
                                t: 0.0,
                            };
                            cur = child(mask.trailing_zeros());
                            mask &= mask - 1;
                            while mask != 0 {
                                stack.push(child(mask.trailing_zeros()));
                                mask &= mask - 1;
                            }
                            continue;
                        }
                    } else {
                        for i in cur.index..cur.index + cur.count {
                            if hit_fn(ray, i as usize) < ray.tmax {
                                return true;
                            }
                        }
                    }
                    match stack.pop() {
                        None => return false,
                        Some(e) => cur = e,
                    }
                }
            },
        )
    }
}

/// Returns `1/x`, or `±1/ε` for `|x| <= ε`, so slab distances stay finite (obvhs's rule).
fn safe_inverse(x: f32) -> f32 {
    if x.abs() <= f32::EPSILON {
        x.signum() / f32::EPSILON
    } else {
        1.0 / x
    }
}

/// A ray prepared for slab tests: reciprocal direction and which plane of each axis comes first.
struct SlabRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    /// Per axis, the plane row (`Node::planes`) the ray meets first and last.
    near: [usize; 3],
    far: [usize; 3],
    tmin: f32,
}

impl SlabRay {
    #[inline(always)]
    fn new(r: &Ray) -> SlabRay {
        let inv_dir = Vec3A::new(
            safe_inverse(r.dir.x),
            safe_inverse(r.dir.y),
            safe_inverse(r.dir.z),
        );
        let neg = |a: usize| (inv_dir[a] < 0.0) as usize;
        SlabRay {
            origin: r.origin,
            inv_dir,
            near: [neg(0), 2 + neg(1), 4 + neg(2)],
            far: [1 - neg(0), 3 - neg(1), 5 - neg(2)],
            tmin: r.tmin,
        }
    }

    /// Returns the mask of `node`'s children whose boxes the ray overlaps within
    /// `[tmin, tmax]`, and the entry distance into each.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn enter(&self, node: &Node, tmax: f32) -> (u32, [f32; 4]) {
        use std::arch::x86_64::*;
        let p = &node.planes;
        let mut tnear = [0.0f32; 4];
        // SAFETY: SSE2 is part of the x86-64 baseline; `Node` is 64-byte aligned, so every plane
        // row (16 bytes at a multiple of 16) suits an aligned load, and `tnear` takes an unaligned store.
        let mask = unsafe {
            let dist = |row: usize, axis: usize| {
                _mm_mul_ps(
                    _mm_sub_ps(_mm_load_ps(p[row].as_ptr()), _mm_set1_ps(self.origin[axis])),
                    _mm_set1_ps(self.inv_dir[axis]),
                )
            };
            let near = _mm_max_ps(
                _mm_max_ps(dist(self.near[0], 0), dist(self.near[1], 1)),
                _mm_max_ps(dist(self.near[2], 2), _mm_set1_ps(self.tmin)),
            );
            let far = _mm_min_ps(
                _mm_min_ps(dist(self.far[0], 0), dist(self.far[1], 1)),
                _mm_min_ps(dist(self.far[2], 2), _mm_set1_ps(tmax)),
            );
            _mm_storeu_ps(tnear.as_mut_ptr(), near);
            _mm_movemask_ps(_mm_cmple_ps(near, far)) as u32
        };
        (mask, tnear)
    }

    /// Returns the mask of `node`'s children whose boxes the ray overlaps within
    /// `[tmin, tmax]`, and the entry distance into each.
    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    fn enter(&self, node: &Node, tmax: f32) -> (u32, [f32; 4]) {
        let p = &node.planes;
        let mut tnear = [0.0f32; 4];
        let mut mask = 0;
        for c in 0..4 {
            let d = |row: usize, axis: usize| (p[row][c] - self.origin[axis]) * self.inv_dir[axis];
            let near = d(self.near[0], 0)
                .max(d(self.near[1], 1))
                .max(d(self.near[2], 2).max(self.tmin));
            let far = d(self.far[0], 0)
                .min(d(self.far[1], 1))
                .min(d(self.far[2], 2).min(tmax));
            tnear[c] = near;
            mask |= ((near <= far) as u32) << c;
        }
        (mask, tnear)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::BvhBuildParams;
    use obvhs::aabb::Aabb;
    use obvhs::bvh2::builder::build_bvh2;

    /// Every primitive sits in exactly one leaf, inside its leaf's box.
    #[test]
    fn collapse_keeps_every_primitive_once() {
        let boxes: Vec<Aabb> = (0..1000)
            .map(|i| {
                let c = Vec3A::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32);
                Aabb::new(c, c + Vec3A::splat(0.5))
            })
            .collect();
        let b2 = build_bvh2(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut Default::default(),
        );
        let w = WideBvh::from_bvh2(&b2);
        let mut seen = vec![0; boxes.len()];
        for n in &w.nodes {
            for c in 0..4 {
                for i in n.index[c]..n.index[c] + n.count[c] {
                    let b = &boxes[w.order[i as usize] as usize];
                    seen[w.order[i as usize] as usize] += 1;
                    for a in 0..3 {
                        assert!(
                            n.planes[2 * a][c] <= b.min[a] && b.max[a] <= n.planes[2 * a + 1][c]
                        );
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert!(w.stack_len <= STACK);
    }
}
