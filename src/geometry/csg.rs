//! Constructive solid geometry over analytic primitives, by interval arithmetic along the ray.
//!
//! A CSG tree lives in the frame of its CSG node. Each leaf is a convex [`Analytic`] primitive
//! (sphere, cube, cylinder, cone) with its own transform and material; along a line, a leaf
//! occupies one interval, and union, intersection and difference combine sorted lists of disjoint
//! intervals. A difference
//! turns the subtracted solid's boundaries into the result's boundaries with their normals flipped,
//! so the inner faces of `a − b` face out of the solid. Every boundary keeps the material of the
//! leaf that made it.
//!
//! Coincident faces (a box minus a cylinder of exactly the box's height, two boxes sharing a face)
//! meet at parameters that differ only by rounding. Boundaries closer than a tolerance of about
//! 1e-6 of the ray's scale count as the same point, so such faces leave no sliver spans (which
//! would render as speckles) and unions leave no internal faces.
//!
//! ```lua
//! ring = gr.difference('ring', gr.cylinder('outer'), inner_cylinder)
//! ```

use super::{Analytic, Crossing};
use crate::desc::CsgOp;
use glam::{Affine3A, Mat3A, Vec3A};

/// A node of a CSG tree; children are indices into [`CsgTree::nodes`].
#[derive(Clone, Debug)]
pub enum CsgNode {
    Leaf {
        shape: Analytic,
        /// Maps the CSG frame into the leaf's object space.
        leaf_from_csg: Affine3A,
        /// Maps leaf-space normals into the CSG frame (inverse transpose).
        normal_to_csg: Mat3A,
        /// Material index in the scene.
        material: u32,
    },
    Op {
        op: CsgOp,
        a: u32,
        b: u32,
    },
}

/// A boundary point along the ray, in the CSG frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Boundary {
    pub t: f64,
    /// Outward normal of the result solid, CSG frame, not normalised.
    pub normal: Vec3A,
    pub material: u32,
    pub face: u8,
    /// Index in [`CsgTree::nodes`] of the leaf this boundary belongs to.
    pub leaf: u32,
}

/// A piece of the solid along the ray: `enter.t <= exit.t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub enter: Boundary,
    pub exit: Boundary,
}

/// A CSG solid: its nodes (children before parents) and the root's index.
#[derive(Clone, Debug)]
pub struct CsgTree {
    pub nodes: Vec<CsgNode>,
    pub root: u32,
}

impl CsgTree {
    /// Returns the solid's spans along the full line `o + t·d` (CSG frame), sorted and disjoint.
    pub fn spans(&self, o: Vec3A, d: Vec3A) -> Vec<Span> {
        let eps = Eps::for_ray(o, d);
        self.spans_of(self.root, o, d, eps)
    }

    /// Returns the first boundary with `t` in `(tmin, tmax)`.
    pub fn first_hit(&self, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<Boundary> {
        let inside = |t: f64| t > tmin as f64 && t < tmax as f64;
        for s in self.spans(o, d) {
            if inside(s.enter.t) {
                return Some(s.enter);
            }
            if inside(s.exit.t) {
                return Some(s.exit);
            }
            if s.enter.t >= tmax as f64 {
                break;
            }
        }
        None
    }

    fn spans_of(&self, id: u32, o: Vec3A, d: Vec3A, eps: Eps) -> Vec<Span> {
        match &self.nodes[id as usize] {
            CsgNode::Leaf {
                shape,
                leaf_from_csg,
                normal_to_csg,
                material,
            } => {
                let lo = leaf_from_csg.transform_point3a(o);
                let ld = leaf_from_csg.transform_vector3a(d);
                let to_boundary = |c: Crossing| Boundary {
                    t: c.t,
                    normal: *normal_to_csg * c.normal,
                    material: *material,
                    leaf: id,
                    face: c.face,
                };
                shape
                    .interval(lo, ld, super::origin_size(leaf_from_csg, o))
                    .map(|iv| Span {
                        enter: to_boundary(iv.enter),
                        exit: to_boundary(iv.exit),
                    })
                    .into_iter()
                    .collect()
            }
            CsgNode::Op { op, a, b } => {
                let sa = self.spans_of(*a, o, d, eps);
                if sa.is_empty() && *op != CsgOp::Union {
                    return sa;
                }
                let sb = self.spans_of(*b, o, d, eps);
                match op {
                    CsgOp::Union => union(sa, sb, eps),
                    CsgOp::Intersection => intersection(&sa, &sb, eps),
                    CsgOp::Difference => difference(&sa, &sb, eps),
                }
            }
        }
    }
}

/// The tolerance below which two boundary parameters count as the same point.
#[derive(Clone, Copy, Debug)]
pub struct Eps {
    /// Absolute part, in ray-parameter units.
    base: f64,
}

impl Eps {
    /// Returns the tolerance for the line `o + t·d` in the CSG frame.
    pub fn for_ray(o: Vec3A, d: Vec3A) -> Eps {
        let len = d.length().max(f32::MIN_POSITIVE) as f64;
        Eps {
            base: 1e-6 * (o.abs().max_element() as f64).max(1.0) / len,
        }
    }

    /// Returns true when `a` lies clearly before `b`.
    fn before(self, a: f64, b: f64) -> bool {
        a < b - (self.base + 1e-7 * b.abs().max(a.abs()))
    }
}

fn flipped(b: Boundary) -> Boundary {
    Boundary {
        normal: -b.normal,
        ..b
    }
}

/// Returns `a ∪ b` for sorted, disjoint span lists.
pub fn union(mut a: Vec<Span>, b: Vec<Span>, eps: Eps) -> Vec<Span> {
    a.extend(b);
    a.sort_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
    let mut out: Vec<Span> = Vec::with_capacity(a.len());
    for s in a {
        match out.last_mut() {
            Some(last) if !eps.before(last.exit.t, s.enter.t) => {
                if s.exit.t > last.exit.t {
                    last.exit = s.exit;
                }
            }
            _ => out.push(s),
        }
    }
    out
}

/// Returns `a ∩ b` for sorted, disjoint span lists.
pub fn intersection(a: &[Span], b: &[Span], eps: Eps) -> Vec<Span> {
    let (mut i, mut j) = (0, 0);
    let mut out = Vec::new();
    while i < a.len() && j < b.len() {
        let enter = if a[i].enter.t >= b[j].enter.t {
            a[i].enter
        } else {
            b[j].enter
        };
        let exit = if a[i].exit.t <= b[j].exit.t {
            a[i].exit
        } else {
            b[j].exit
        };
        if eps.before(enter.t, exit.t) {
            out.push(Span { enter, exit });
        }
        if a[i].exit.t <= b[j].exit.t {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// Returns `a − b` for sorted, disjoint span lists; `b`'s boundaries get flipped normals.
pub fn difference(a: &[Span], b: &[Span], eps: Eps) -> Vec<Span> {
    let mut out = Vec::new();
    for s in a {
        let mut cur = s.enter;
        for r in b {
            if !eps.before(cur.t, r.exit.t) {
                continue;
            }
            if !eps.before(r.enter.t, s.exit.t) {
                break;
            }
            if eps.before(cur.t, r.enter.t) {
                out.push(Span {
                    enter: cur,
                    exit: flipped(r.enter),
                });
            }
            cur = flipped(r.exit);
        }
        if eps.before(cur.t, s.exit.t) {
            out.push(Span {
                enter: cur,
                exit: s.exit,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(t0: f64, t1: f64, m: u32) -> Span {
        let b = |t| Boundary {
            t,
            normal: Vec3A::X,
            material: m,
            face: 0,
            leaf: 0,
        };
        Span {
            enter: b(t0),
            exit: b(t1),
        }
    }

    fn ts(v: &[Span]) -> Vec<(f64, f64)> {
        v.iter().map(|s| (s.enter.t, s.exit.t)).collect()
    }

    #[test]
    fn interval_operations_match_hand_computed_sets() {
        let a = vec![span(0.0, 4.0, 0), span(6.0, 8.0, 0)];
        let b = vec![span(1.0, 2.0, 1), span(3.0, 7.0, 1)];
        let eps = Eps::for_ray(Vec3A::ZERO, Vec3A::X);
        assert_eq!(ts(&union(a.clone(), b.clone(), eps)), vec![(0.0, 8.0)]);
        assert_eq!(
            ts(&intersection(&a, &b, eps)),
            vec![(1.0, 2.0), (3.0, 4.0), (6.0, 7.0)]
        );
        let d = difference(&a, &b, eps);
        assert_eq!(ts(&d), vec![(0.0, 1.0), (2.0, 3.0), (7.0, 8.0)]);
        // The carved faces come from b: its material, normals flipped to face out of the solid.
        assert_eq!((d[0].exit.material, d[0].exit.normal), (1, -Vec3A::X));
        assert_eq!(ts(&difference(&b, &a, eps)), vec![(4.0, 6.0)]);
    }

    #[test]
    fn coincident_boundaries_leave_no_slivers() {
        let eps = Eps::for_ray(Vec3A::ZERO, Vec3A::X);
        let wobble = 3e-13;
        // A hole exactly as tall as the slab it cuts: nothing is left along the hole's axis.
        let slab = vec![span(1.0, 2.0, 0)];
        let hole = vec![span(1.0 + wobble, 2.0 - wobble, 1)];
        assert!(difference(&slab, &hole, eps).is_empty());
        let hole = vec![span(1.0 - wobble, 2.0 + wobble, 1)];
        assert!(difference(&slab, &hole, eps).is_empty());
        // Two boxes sharing a face: one span, no internal face.
        assert_eq!(
            ts(&union(
                vec![span(0.0, 1.0, 0)],
                vec![span(1.0 + wobble, 2.0, 0)],
                eps
            )),
            vec![(0.0, 2.0)]
        );
        // Touching solids do not intersect in a sliver.
        assert!(intersection(&[span(0.0, 1.0, 0)], &[span(1.0 - wobble, 2.0, 0)], eps).is_empty());
        // Genuinely thin pieces above the tolerance survive.
        assert_eq!(difference(&slab, &[span(1.0 + 1e-3, 2.0, 1)], eps).len(), 1);
    }

    #[test]
    fn nested_tree_of_transformed_leaves() {
        // (sphere ∪ sphere shifted by 3) − cube scaled to [0.5, 3.5] on x.
        let leaf = |shape, m: Affine3A, material| CsgNode::Leaf {
            shape,
            leaf_from_csg: m.inverse(),
            normal_to_csg: m.matrix3.inverse().transpose(),
            material,
        };
        let tree = CsgTree {
            nodes: vec![
                leaf(Analytic::Sphere, Affine3A::IDENTITY, 0),
                leaf(
                    Analytic::Sphere,
                    Affine3A::from_translation(Vec3A::new(3.0, 0.0, 0.0).into()),
                    0,
                ),
                CsgNode::Op {
                    op: CsgOp::Union,
                    a: 0,
                    b: 1,
                },
                leaf(
                    Analytic::Cube,
                    Affine3A::from_translation(glam::Vec3::new(0.5, -2.0, -2.0))
                        * Affine3A::from_scale(glam::Vec3::new(3.0, 4.0, 4.0)),
                    1,
                ),
                CsgNode::Op {
                    op: CsgOp::Difference,
                    a: 2,
                    b: 3,
                },
            ],
            root: 4,
        };
        let spans = tree.spans(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X);
        let got = ts(&spans);
        let want = [(4.0, 5.5), (8.5, 9.0)];
        assert_eq!(got.len(), 2);
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g.0 - w.0).abs() < 1e-6 && (g.1 - w.1).abs() < 1e-6,
                "{got:?}"
            );
        }
        let first = tree
            .first_hit(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X, 0.0, f32::INFINITY)
            .unwrap();
        assert!((first.t - 4.0).abs() < 1e-6 && first.normal.x < 0.0);
        // The carved face at x = 0.5 faces +x, out of the remaining solid (x < 0.5).
        assert!(spans[0].exit.normal.x > 0.0 && spans[0].exit.material == 1);
    }
}
