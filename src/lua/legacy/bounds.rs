//! Boxes for the legacy check's layouts: each node's geometry and subtree in its own frame, under
//! either transform order.
//!
//! Analytic primitives have their unit boxes, meshes the box of their vertices (inline ones from
//! the description, files read once per script run; a file that cannot be read is left out, and
//! the scene build reports it), CSG nodes their operands' (`a ∪ b` for a union, `a` otherwise).
//! Boxes are transformed by their 8 corners, so rotations loosen them as the scene's own TLAS
//! boxes are loosened.

use super::order::Transforms;
use crate::desc::{CsgOp, MeshFormat, MeshId, MeshSource, NodeId, NodeKind, SceneDesc};
use glam::{DAffine3, DVec3};
use std::collections::HashMap;

/// An axis-aligned box in double precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    /// The empty box, the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// Returns true when the box holds no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    /// Returns the smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Returns the box holding `self` after the transform `m`.
    pub fn transformed(self, m: &DAffine3) -> Aabb {
        if self.is_empty() {
            return self;
        }
        let mut out = Aabb::EMPTY;
        for k in 0..8 {
            let c = DVec3::new(
                if k & 1 == 0 { self.min.x } else { self.max.x },
                if k & 2 == 0 { self.min.y } else { self.max.y },
                if k & 4 == 0 { self.min.z } else { self.max.z },
            );
            let p = m.transform_point3(c);
            out.min = out.min.min(p);
            out.max = out.max.max(p);
        }
        out
    }

    /// Returns the length of the box's diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }

    /// Returns the distance between the two boxes (0 when they overlap or touch).
    pub fn gap(&self, o: &Aabb) -> f64 {
        let d = (o.min - self.max).max(self.min - o.max).max(DVec3::ZERO);
        d.length()
    }
}

/// Mesh boxes read so far, by mesh (`None`: unreadable, left out of the check).
pub type MeshBoxes = HashMap<MeshId, Option<Aabb>>;

/// Returns each reachable node's box in its own frame (its geometry and its children's), by node
/// id; `None` for nodes not reached.
pub fn subtree_boxes(
    desc: &SceneDesc,
    root: NodeId,
    xf: Transforms,
    meshes: &mut MeshBoxes,
) -> Vec<Option<Aabb>> {
    let mut boxes: Vec<Option<Aabb>> = vec![None; desc.nodes.len()];
    let mut open = vec![false; desc.nodes.len()];
    let mut stack = vec![(root, false)];
    while let Some((n, children_done)) = stack.pop() {
        let i = n.0 as usize;
        let node = desc.node(n);
        if !children_done {
            if boxes[i].is_some() || open[i] {
                continue;
            }
            open[i] = true;
            stack.push((n, true));
            for (c, _) in &node.children {
                stack.push((*c, false));
            }
            continue;
        }
        let mut b = own_box(desc, &node.kind, xf, meshes, 0);
        for (c, _) in &node.children {
            // A child still open is an ancestor (a cycle, which the scene build reports).
            if let Some(cb) = boxes[c.0 as usize] {
                b = b.union(cb.transformed(&xf(*c)));
            }
        }
        open[i] = false;
        boxes[i] = Some(b);
    }
    boxes
}

/// Returns the box of a node's own geometry in its frame (empty for groups).
fn own_box(
    desc: &SceneDesc,
    kind: &NodeKind,
    xf: Transforms,
    meshes: &mut MeshBoxes,
    depth: usize,
) -> Aabb {
    let unit = |min: DVec3| Aabb {
        min,
        max: DVec3::ONE,
    };
    match kind {
        NodeKind::Group => Aabb::EMPTY,
        NodeKind::Sphere | NodeKind::Cylinder => unit(DVec3::NEG_ONE),
        NodeKind::Cube => unit(DVec3::ZERO),
        NodeKind::Cone => unit(DVec3::new(-1.0, -1.0, 0.0)),
        NodeKind::NhSphere { center, radius } => Aabb {
            min: center - DVec3::splat(*radius),
            max: center + DVec3::splat(*radius),
        },
        NodeKind::NhBox { corner, size } => Aabb {
            min: *corner,
            max: corner + DVec3::splat(*size),
        },
        NodeKind::Mesh(id) => mesh_box(desc, *id, meshes).unwrap_or(Aabb::EMPTY),
        NodeKind::Csg { op, a, b } => {
            if depth > 64 {
                return Aabb::EMPTY;
            }
            let operand = |n: NodeId, meshes: &mut MeshBoxes| {
                own_box(desc, &desc.node(n).kind, xf, meshes, depth + 1).transformed(&xf(n))
            };
            let ba = operand(*a, meshes);
            match op {
                CsgOp::Union => ba.union(operand(*b, meshes)),
                CsgOp::Intersection | CsgOp::Difference => ba,
            }
        }
    }
}

/// Returns the box of mesh `id`'s vertices, reading its file once; `None` when it cannot be read.
fn mesh_box(desc: &SceneDesc, id: MeshId, meshes: &mut MeshBoxes) -> Option<Aabb> {
    if let Some(b) = meshes.get(&id) {
        return *b;
    }
    let of = |ps: &mut dyn Iterator<Item = DVec3>| {
        ps.fold(Aabb::EMPTY, |b, p| Aabb {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    };
    let b = match &desc.meshes[id.0 as usize].source {
        MeshSource::Inline { positions, .. } => Some(of(&mut positions.iter().copied())),
        MeshSource::File {
            path, format, part, ..
        } => {
            // Charged to the script's budget while the mesh is read, given back after.
            let account = desc.budget.account();
            let data = match format {
                MeshFormat::Obj => crate::io::obj::load_obj_with(path, &account).ok(),
                MeshFormat::Gltf => {
                    crate::io::gltf::load_gltf_mesh_with(path, *part, &account).ok()
                }
            };
            data.map(|d| of(&mut d.positions.iter().map(|p| p.as_dvec3())))
        }
    };
    meshes.insert(id, b);
    b
}
