//! The geometric half of the legacy check: in which transform order does a scene's layout make
//! sense?
//!
//! A script run without `--dialect` composes each node's calls the modern way into the
//! description and, beside it, the legacy way ([`Calls`]). Only nodes whose two matrices differ
//! can tell the orders apart: one call, or only commuting ones (translations; a rotation and a
//! uniform scale), read the same either way, and a scene made only of such nodes is never warned
//! about. [`compare`] then measures three things in each order ([`Layout`]):
//!
//! - **placed**, the test: both eras' sample scripts place a part by scaling and rotating it about
//!   its own origin and then moving it to the point they type, `M = T·R·S`; modern scripts write
//!   it `scale, rotate, translate`, legacy ones `translate, rotate, scale`. In the intended order
//!   a node's origin therefore lands exactly on the sum of its translate arguments; in the other,
//!   the node's own scale and rotation distort the move (`S·R·t`). `placed` counts the nodes
//!   whose origin lands there in this order only. A node that moves, turns and moves back (a
//!   pivot) lands on neither and counts for neither.
//! - **piled**, a sanity check: the instances of one node stacked on one point. The ring idiom
//!   `n:translate(4, 0, 0); n:rotate('y', 30 * i)` (modern scripts place by distance, then angle:
//!   the corpus's hier.lua places its arch so) reads as legacy by placement, but the legacy order
//!   puts every instance of the ring on the same spot.
//! - **apart**, a sanity check: for every group, its children's boxes ([`super::bounds`]) that
//!   touch (a gap of at most 5% of the smaller box's diagonal) form clusters; `apart` adds up the
//!   clusters beyond one. In the wrong order a cow stands on nothing: the modern order lifts the
//!   legacy macho-cows.lua's cows off the field, and the legacy order lifts the modern copy's.
//!
//! The scene looks legacy ([`Verdict::looks_legacy`]) when at least 2 nodes are placed only in
//! the legacy order, at least twice as many as only in the modern order, and neither sanity check
//! prefers the modern order ([`Verdict::rules_out_legacy`]: more nodes placed, fewer parts apart
//! or fewer instances piled in the modern order). A script that shows a legacy sign (an inline
//! mesh, `readobj`, a Lua 5.1 name) is warned about unless the layouts rule legacy out.
//!
//! Why not touching parts alone, as a first version did: the wrong order also pulls parts
//! together. A modern scene of small balls scaled and then moved apart reads, in the legacy
//! order, as a touching chain (their offsets shrink with their scale), and the modern ring above
//! collapses to one touching pile; both were warned about. Touching is a check here, not the
//! test.
//!
//! Measured (`tests/lua/legacy_detection.rs`): no warning on any modern scene that reaches
//! `gr.render` (14 of the corpus's 20 scripts, the 6 that run of `scenes/`, the guide's modern
//! examples). Their copies with every node's calls reversed (which is how the two eras' copies
//! of hier.lua and macho-cows.lua differ) are warned about where the order matters in 2 nodes
//! or more (the corpus's hier.lua, instance.lua, simple-cows.lua and macho-cows.lua, all 6 of
//! `scenes/`, one of the guide's examples) and not where it matters in one (the corpus's
//! cylinder.lua and room2.lua, 3 of the guide's examples).
//!
//! Limits: a modern scene that places most of its nodes by translating then rotating, each a
//! different object (a solar system), reads as legacy; a legacy scene of parts scaled down and
//! placed apart is not noticed (the modern order shrinks them into touching, and the check
//! vetoes); a scene where the order matters in one node only is never found legacy by its
//! layout (its signs may still tell). Groups of more than [`MAX_PARTS`] children are left out of
//! `apart`, scenes of more than [`MAX_PLACEMENTS`] placements out of `piled`.

use super::bounds::{Aabb, MeshBoxes, subtree_boxes};
use crate::desc::{NodeId, NodeKind, SceneDesc};
use glam::{DAffine3, DVec3};
use std::collections::HashMap;

/// A node's matrix in one order.
pub type Transforms<'a> = &'a dyn Fn(NodeId) -> DAffine3;

/// What the check knows of one node's transform calls beyond its (modern-order) matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calls {
    /// The calls composed in the legacy order.
    pub legacy: DAffine3,
    /// The sum of the node's `translate` arguments: where its origin lands when its own
    /// rotations and scales do not move it.
    pub moved_by: DVec3,
}

impl Default for Calls {
    fn default() -> Calls {
        Calls {
            legacy: DAffine3::IDENTITY,
            moved_by: DVec3::ZERO,
        }
    }
}

impl Calls {
    /// Adds the transform `t` of one more call (a translate when `t` has no linear part).
    pub fn push(&mut self, t: DAffine3) {
        self.legacy = super::Dialect::Legacy.compose(self.legacy, t);
        if t.matrix3 == glam::DMat3::IDENTITY {
            self.moved_by += t.translation;
        }
    }
}

/// The two orders of one script's nodes: the description's (modern) and the legacy one.
pub struct Orders<'a> {
    pub desc: &'a SceneDesc,
    /// Each node's calls, by node id; a node past the end had none.
    pub calls: &'a [Calls],
}

impl Orders<'_> {
    fn calls(&self, n: NodeId) -> Calls {
        self.calls.get(n.0 as usize).copied().unwrap_or_default()
    }

    fn modern(&self, n: NodeId) -> DAffine3 {
        self.desc.node(n).transform
    }

    fn legacy(&self, n: NodeId) -> DAffine3 {
        self.calls(n).legacy
    }

    /// Returns true when node `n`'s matrix differs between the orders (beyond rounding).
    fn differ(&self, n: NodeId) -> bool {
        let (x, y) = (
            self.modern(n).to_cols_array(),
            self.legacy(n).to_cols_array(),
        );
        let scale = x.iter().chain(&y).fold(1.0f64, |m, v| m.max(v.abs()));
        x.iter().zip(&y).any(|(p, q)| (p - q).abs() > 1e-9 * scale)
    }
}

/// Returns true when some node reachable from `root` has a different matrix in the two orders.
pub fn orders_differ(o: &Orders, root: NodeId) -> bool {
    reachable(o.desc, root).into_iter().any(|n| o.differ(n))
}

/// Returns every node reachable from `root`, each once.
fn reachable(desc: &SceneDesc, root: NodeId) -> Vec<NodeId> {
    let mut seen = vec![false; desc.nodes.len()];
    let mut out = Vec::new();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        if std::mem::replace(&mut seen[n.0 as usize], true) {
            continue;
        }
        out.push(n);
        let node = desc.node(n);
        stack.extend(node.children.iter().map(|(c, _)| *c));
        if let NodeKind::Csg { a, b, .. } = node.kind {
            stack.extend([a, b]);
        }
    }
    out
}

/// How one order places a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// Nodes whose origin lands exactly where their translate calls put it in this order only.
    pub placed: usize,
    /// Over every group with two or more parts: the parts minus the clusters of touching parts.
    pub apart: usize,
    /// Over every geometry node placed more than once: its placements minus the distinct
    /// points its origin lands on (instances stacked on one another).
    pub piled: usize,
}

/// The two layouts of one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub modern: Layout,
    pub legacy: Layout,
}

impl Verdict {
    /// Returns true when the layouts alone make the case for the legacy order.
    pub fn looks_legacy(&self) -> bool {
        let (m, l) = (&self.modern, &self.legacy);
        l.placed >= 2 && l.placed >= 2 * m.placed && !self.rules_out_legacy()
    }

    /// Returns true when the layouts speak for the modern order.
    pub fn rules_out_legacy(&self) -> bool {
        let (m, l) = (&self.modern, &self.legacy);
        m.placed > l.placed || l.apart > m.apart || l.piled > m.piled
    }

    /// Returns the warning's reason.
    pub fn describe(&self) -> String {
        format!(
            "this script's transforms look written for the course's legacy API (before Fall \
             2015): {} of its nodes land where their translate calls put them only when each \
             node's transforms compose the legacy way ({} only the modern way)",
            self.legacy.placed, self.modern.placed
        )
    }
}

/// Returns both layouts of the scene under `root`.
pub fn compare(o: &Orders, root: NodeId, meshes: &mut MeshBoxes) -> Verdict {
    let modern = |n: NodeId| o.modern(n);
    let legacy = |n: NodeId| o.legacy(n);
    let mut v = Verdict {
        modern: layout(o.desc, root, &modern, meshes),
        legacy: layout(o.desc, root, &legacy, meshes),
    };
    for n in reachable(o.desc, root) {
        if !o.differ(n) {
            continue;
        }
        let target = o.calls(n).moved_by;
        let lands =
            |m: DAffine3| (m.translation - target).length() <= 1e-9 * (1.0 + target.length());
        match (lands(o.modern(n)), lands(o.legacy(n))) {
            (true, false) => v.modern.placed += 1,
            (false, true) => v.legacy.placed += 1,
            _ => {}
        }
    }
    v
}

/// Returns the layout of the scene under `root` with the matrices `xf` (without `placed`).
fn layout(desc: &SceneDesc, root: NodeId, xf: Transforms, meshes: &mut MeshBoxes) -> Layout {
    let boxes = subtree_boxes(desc, root, xf, meshes);
    let mut out = Layout {
        piled: piled(desc, root, xf),
        ..Layout::default()
    };
    for n in reachable(desc, root) {
        let node = desc.node(n);
        let parts: Vec<Aabb> = node
            .children
            .iter()
            .filter_map(|(c, _)| boxes[c.0 as usize].map(|b| b.transformed(&xf(*c))))
            .filter(|b| !b.is_empty())
            .collect();
        if parts.len() < 2 || parts.len() > MAX_PARTS {
            continue;
        }
        out.apart += clusters(&parts) - 1;
    }
    out
}

/// Most children of one group [`Layout::apart`] compares pairwise; a larger group is left out.
pub const MAX_PARTS: usize = 2048;

/// Most placements the check flattens; a larger scene gets no [`Layout::piled`] count.
pub const MAX_PLACEMENTS: usize = 1 << 20;

/// Returns, over the geometry nodes placed under `root` more than once, the placements minus
/// the distinct points (to a millionth of their distance from the origin) their origins land on.
fn piled(desc: &SceneDesc, root: NodeId, xf: Transforms) -> usize {
    let mut origins: HashMap<NodeId, Vec<DVec3>> = HashMap::new();
    let mut stack = vec![(root, DAffine3::IDENTITY)];
    let mut visits = 0;
    while let Some((n, parent)) = stack.pop() {
        visits += 1;
        if visits > MAX_PLACEMENTS {
            return 0;
        }
        let world = parent * xf(n);
        let node = desc.node(n);
        if node.kind.is_geometry() {
            origins.entry(n).or_default().push(world.translation);
        }
        stack.extend(node.children.iter().map(|(c, _)| (*c, world)));
    }
    let mut out = 0;
    for points in origins.values().filter(|p| p.len() > 1) {
        let size = points
            .iter()
            .fold(1.0f64, |m, p| m.max(p.abs().max_element()));
        let cell = 1e-6 * size;
        let mut distinct: Vec<[i64; 3]> = points
            .iter()
            .map(|p| (*p / cell).round().as_i64vec3().to_array())
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        out += points.len() - distinct.len();
    }
    out
}

/// Returns how many clusters of touching boxes `parts` form.
fn clusters(parts: &[Aabb]) -> usize {
    let mut parent: Vec<usize> = (0..parts.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut count = parts.len();
    for i in 0..parts.len() {
        for j in i + 1..parts.len() {
            let tol = 0.05 * parts[i].diagonal().min(parts[j].diagonal());
            if parts[i].gap(&parts[j]) <= tol {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                if a != b {
                    parent[a] = b;
                    count -= 1;
                }
            }
        }
    }
    count
}
