//! Building with obvhs: its PLOC binary BVH, collapsed into our 8-wide nodes.

use super::MAX_LEAF;
use super::wide::{LEAF, Leaf, Node, WIDTH, WideBvh};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2;
use std::time::Duration;

/// Builds obvhs's medium-preset PLOC BVH over `boxes` (at least two) and collapses it.
pub(super) fn build(boxes: &[Aabb]) -> WideBvh {
    let params = BvhBuildParams {
        max_prims_per_leaf: MAX_LEAF as u32,
        ..BvhBuildParams::medium_build()
    };
    collapse(&build_bvh2(boxes, params, &mut Duration::default()))
}

/// Collapses `bvh2` (at least one node) into 8-wide nodes: each node takes its two children
/// and then repeatedly opens the inner child with the largest surface until it has eight.
pub(super) fn collapse(bvh2: &Bvh2) -> WideBvh {
    let src = &bvh2.nodes;
    let mut nodes = vec![Node::EMPTY];
    let mut leaves = Vec::new();
    let mut max_level = 1;
    let leaf = |leaves: &mut Vec<Leaf>, k: usize| {
        leaves.push(Leaf {
            first: src[k].first_index,
            count: src[k].prim_count,
        });
        LEAF | (leaves.len() as u32 - 1)
    };
    if src[0].prim_count > 0 {
        // A leaf at the root: one node with one leaf child.
        nodes[0].set_box(0, src[0].aabb.min, src[0].aabb.max);
        nodes[0].child[0] = leaf(&mut leaves, 0);
    } else {
        // (source inner node, our node, level); a work list rather than recursion, so a
        // degenerate, very deep tree cannot overflow the thread's stack.
        let mut work = vec![(0usize, 0usize, 1usize)];
        while let Some((at, me, level)) = work.pop() {
            max_level = max_level.max(level);
            let first = src[at].first_index as usize;
            let mut kids = [0usize; WIDTH];
            kids[..2].copy_from_slice(&[first, first + 1]);
            let mut n = 2;
            while n < WIDTH {
                let widest = kids[..n]
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
                kids[n] = f + 1;
                n += 1;
            }
            for (slot, &k) in kids[..n].iter().enumerate() {
                let s = &src[k];
                nodes[me].set_box(slot, s.aabb.min, s.aabb.max);
                nodes[me].child[slot] = if s.prim_count > 0 {
                    leaf(&mut leaves, k)
                } else {
                    nodes.push(Node::EMPTY);
                    work.push((k, nodes.len() - 1, level + 1));
                    nodes.len() as u32 - 1
                };
            }
        }
    }
    nodes.shrink_to_fit();
    crate::mem::prefer_huge_pages(&nodes);
    crate::mem::prefer_huge_pages(&leaves);
    WideBvh::new(nodes, leaves, bvh2.primitive_indices.clone(), max_level)
}
