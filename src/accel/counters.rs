//! Traversal counters for profiling: BVH nodes visited and triangles tested, per ray kind
//! (camera, shadow, gather, photon), for `--stats` and `--heatmap`.
//!
//! # Cost when off
//! Counting is off unless [`enable`] is called (the command line does, for `--heatmap` and
//! `--stats`). Every counting point is one relaxed load of a process-wide flag and a branch
//! that is never taken, so traversal runs the same code either way; the overhead off and on is
//! measured in `docs/profiling.md`.
//!
//! # How counts are kept
//! Each thread counts into its own cells (no atomics on the hot path). A ray's kind is set by
//! whoever casts it ([`kind`]) and stays until set again; [`ray`] counts a traversal of the
//! scene (a closest-hit or an any-hit query), [`node`] a BVH node whose children were tested
//! (the scene's top level and every mesh's), and [`triangles`] the triangles of a mesh leaf
//! tested. [`collect`] adds up every rayon thread's counts (and the caller's) and resets them;
//! [`thread_total`] is the calling thread's running total, which the camera pass reads before
//! and after each pixel for the heatmap.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether anything counts.
static ENABLED: AtomicBool = AtomicBool::new(false);

/// What a ray is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Camera rays and the specular bounces of eye paths.
    Camera = 0,
    /// Shadow rays towards lights.
    Shadow = 1,
    /// Final-gather rays (and their specular bounces).
    Gather = 2,
    /// Photon paths.
    Photon = 3,
}

/// Every kind, in order.
pub const KINDS: [RayKind; 4] = [
    RayKind::Camera,
    RayKind::Shadow,
    RayKind::Gather,
    RayKind::Photon,
];

impl RayKind {
    /// Returns the kind's name.
    pub fn name(self) -> &'static str {
        ["camera", "shadow", "gather", "photon"][self as usize]
    }
}

/// Traversal counts of one kind of ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Scene queries (closest or any hit).
    pub rays: u64,
    /// BVH nodes whose children were tested.
    pub nodes: u64,
    /// Triangles tested.
    pub triangles: u64,
}

impl Counts {
    fn add(&mut self, o: &Counts) {
        self.rays += o.rays;
        self.nodes += o.nodes;
        self.triangles += o.triangles;
    }
}

/// Counts by [`RayKind`].
pub type ByKind = [Counts; 4];

struct Tally {
    kind: Cell<usize>,
    rays: [Cell<u64>; 4],
    nodes: [Cell<u64>; 4],
    triangles: [Cell<u64>; 4],
}

thread_local! {
    static TALLY: Tally = const {
        Tally {
            kind: Cell::new(0),
            rays: [const { Cell::new(0) }; 4],
            nodes: [const { Cell::new(0) }; 4],
            triangles: [const { Cell::new(0) }; 4],
        }
    };
}

/// Turns counting on for the rest of the process.
pub fn enable() {
    ENABLED.store(true, Ordering::Relaxed);
}

/// Returns whether counting is on.
#[inline(always)]
pub fn enabled() -> bool {
    ENABLED.load(Ordering::Relaxed)
}

/// Sets the kind of the rays this thread casts next.
#[inline(always)]
pub fn kind(k: RayKind) {
    if enabled() {
        TALLY.with(|t| t.kind.set(k as usize));
    }
}

#[inline(always)]
fn bump(cells: impl Fn(&Tally) -> &[Cell<u64>; 4], n: u64) {
    if enabled() {
        TALLY.with(|t| {
            let c = &cells(t)[t.kind.get()];
            c.set(c.get() + n);
        });
    }
}

/// Counts one scene query.
#[inline(always)]
pub fn ray() {
    bump(|t| &t.rays, 1);
}

/// Counts one BVH node visited.
#[inline(always)]
pub fn node() {
    bump(|t| &t.nodes, 1);
}

/// Counts the triangles tested, `n()` of them. The count is a closure so that nothing is read
/// while counting is off: a leaf's triangle count lives in a table the tracer does not otherwise
/// touch, and reading it anyway cost incoherent rays a cache miss per leaf.
#[inline(always)]
pub fn triangles(n: impl FnOnce() -> u32) {
    if enabled() {
        bump(|t| &t.triangles, u64::from(n()));
    }
}

/// Returns this thread's nodes and triangles so far, over every kind.
pub fn thread_total() -> (u64, u64) {
    TALLY.with(|t| {
        let sum = |c: &[Cell<u64>; 4]| c.iter().map(Cell::get).sum();
        (sum(&t.nodes), sum(&t.triangles))
    })
}

/// Returns [`thread_total`] and resets this thread's counts (for benchmarks that count one
/// phase at a time on the calling thread).
pub fn thread_total_reset() -> (u64, u64) {
    let total = thread_total();
    let _ = take();
    total
}

/// Returns this thread's counts by kind and resets them.
fn take() -> ByKind {
    TALLY.with(|t| {
        std::array::from_fn(|k| Counts {
            rays: t.rays[k].replace(0),
            nodes: t.nodes[k].replace(0),
            triangles: t.triangles[k].replace(0),
        })
    })
}

/// Returns the counts of every thread of the current rayon pool and of the caller, by kind,
/// and resets them.
pub fn collect() -> ByKind {
    let mut all = take();
    for part in rayon::broadcast(|_| take()) {
        for (a, p) in all.iter_mut().zip(&part) {
            a.add(p);
        }
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_go_to_the_kind_set_and_collect_resets_them() {
        enable();
        let _ = collect();
        kind(RayKind::Shadow);
        ray();
        node();
        node();
        triangles(|| 4);
        kind(RayKind::Photon);
        ray();
        triangles(|| 3);
        assert_eq!(thread_total(), (2, 7));
        // This thread's counts only: other tests may count on the pool's threads meanwhile.
        let c = take();
        assert_eq!((c[1].rays, c[1].nodes, c[1].triangles), (1, 2, 4), "shadow");
        assert_eq!((c[3].rays, c[3].nodes, c[3].triangles), (1, 0, 3), "photon");
        assert_eq!(c[0], Counts::default());
        assert_eq!(take(), ByKind::default());
    }
}
