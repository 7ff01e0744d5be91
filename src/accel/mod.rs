//! Bounding volume hierarchies: the only module that imports obvhs.
//!
//! obvhs builds a binary BVH by PLOC over padded boxes ([`Bvh::build`]); we collapse it into a
//! 4-wide BVH with float boxes stored axis by axis ([`wide`]), so one SSE2 slab test checks the
//! four children of a node, and traverse that ourselves, nearest child first. Callers own the
//! primitives: traversal hands a callback the *BVH-order* index of each candidate (see
//! [`Bvh::order`]) and the callback returns the hit's `t`, or infinity on a miss. Callers that store
//! their primitives in BVH order index them directly.
//!
//! Two things obvhs leaves to us (`../shared/docs/obvhs.md` §5): boxes are padded so flat
//! primitives do not get zero-thickness boxes that non-conservative slab tests can miss, and the
//! callbacks must reject `t <= tmin` themselves.

mod wide;

use crate::geometry::Ray;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use std::time::Duration;
use wide::WideBvh;

/// Names the build configuration [`Bvh::build`] uses, for benchmark reports.
pub const BUILD_CONFIG: &str = "bvh4-ploc-medium";

/// An axis-aligned box; `min <= max` on every axis for a non-empty box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Bounds {
    /// Returns the empty box (the identity of [`Bounds::union`]).
    pub const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    /// Returns the smallest box holding `self` and point `p`.
    pub fn grow(self, p: Vec3A) -> Bounds {
        Bounds {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Returns the smallest box holding both boxes.
    pub fn union(self, o: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Returns true when every coordinate is finite (an empty box is not).
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Returns the box grown by a margin relative to its coordinates' magnitude.
    fn padded(self) -> Aabb {
        let scale = self.min.abs().max(self.max.abs()).max_element();
        let pad = Vec3A::splat(scale * 1e-6 + 1e-12);
        Aabb::new(self.min - pad, self.max + pad)
    }
}

/// A BVH over boxes. With fewer than two primitives there is no tree: an empty one misses, a
/// single primitive is always tested.
pub struct Bvh {
    inner: Option<WideBvh>,
    len: usize,
}

/// The BVH order of a one-primitive BVH.
const SINGLE: [u32; 1] = [0];

/// The obvhs build settings: its medium preset with leaves of at most four primitives.
fn build_params() -> BvhBuildParams {
    BvhBuildParams {
        max_prims_per_leaf: 4,
        ..BvhBuildParams::medium_build()
    }
}

impl Bvh {
    /// Builds a BVH over `boxes`, which must all be finite (callers check and name the culprit).
    pub fn build(boxes: &[Bounds]) -> Bvh {
        debug_assert!(boxes.iter().all(Bounds::is_finite));
        if boxes.len() < 2 {
            return Bvh {
                inner: None,
                len: boxes.len(),
            };
        }
        let aabbs: Vec<Aabb> = boxes.iter().map(|b| b.padded()).collect();
        let bvh2 = build_bvh2(&aabbs, build_params(), &mut Duration::default());
        Bvh {
            inner: Some(WideBvh::from_bvh2(&bvh2)),
            len: boxes.len(),
        }
    }

    /// Returns the number of primitives.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Returns true when the BVH holds no primitive.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Returns, for each BVH-order index, the caller's primitive index.
    pub fn order(&self) -> &[u32] {
        match &self.inner {
            Some(b) => &b.order,
            None => &SINGLE[..self.len],
        }
    }

    /// Returns the bytes the nodes and index take.
    pub fn bytes(&self) -> usize {
        self.inner.as_ref().map_or(0, WideBvh::bytes)
    }

    /// Finds the closest hit: `hit_fn(ray, i)` returns the `t` of BVH-order primitive `i` within
    /// the ray's current `(tmin, tmax)`, or infinity. Returns the index and `t` of the closest.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        hit_fn: impl FnMut(&Ray, usize) -> f32,
    ) -> Option<(usize, f32)> {
        match &self.inner {
            Some(bvh) => bvh.closest(ray, hit_fn),
            None => {
                let mut hit_fn = hit_fn;
                let t = if self.len == 1 {
                    hit_fn(ray, 0)
                } else {
                    f32::INFINITY
                };
                (t > ray.tmin && t < ray.tmax).then_some((0, t))
            }
        }
    }

    /// Returns true when any primitive reports a hit with `t` in the ray's `(tmin, tmax)`.
    #[inline]
    pub fn any(&self, ray: &Ray, mut hit_fn: impl FnMut(&Ray, usize) -> f32) -> bool {
        match &self.inner {
            Some(bvh) => bvh.any(ray, hit_fn),
            None => self.len == 1 && hit_fn(ray, 0) < ray.tmax,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box(c: Vec3A) -> Bounds {
        Bounds {
            min: c - Vec3A::splat(0.5),
            max: c + Vec3A::splat(0.5),
        }
    }

    /// Brute force and BVH agree on the closest of many boxes (each box reports its entry t).
    #[test]
    fn closest_matches_brute_force() {
        let boxes: Vec<Bounds> = (0..200)
            .map(|i| {
                let f = i as f32;
                unit_box(Vec3A::new(
                    (f * 1.7).sin() * 20.0,
                    (f * 0.9).cos() * 20.0,
                    (f * 2.3).sin() * 20.0,
                ))
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let slab = |b: &Bounds, r: &Ray| -> f32 {
            let t0 = (b.min - r.origin) / r.dir;
            let t1 = (b.max - r.origin) / r.dir;
            let near = t0.min(t1).max_element();
            let far = t0.max(t1).min_element();
            if near <= far && near > r.tmin && near < r.tmax {
                near
            } else {
                f32::INFINITY
            }
        };
        for k in 0..500 {
            let f = k as f32;
            let ray = Ray::new(
                Vec3A::new(0.0, 0.0, 0.0),
                Vec3A::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.13).sin() + 0.01).normalize(),
            );
            let brute = boxes
                .iter()
                .map(|b| slab(b, &ray))
                .fold(f32::INFINITY, f32::min);
            let order = bvh.order().to_vec();
            let got = bvh
                .closest(&ray, |r, i| slab(&boxes[order[i] as usize], r))
                .map(|h| h.1);
            assert_eq!(got.unwrap_or(f32::INFINITY), brute, "ray {k}");
        }
    }

    #[test]
    fn empty_and_single() {
        let ray = Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z);
        assert!(Bvh::build(&[]).closest(&ray, |_, _| 1.0).is_none());
        let one = Bvh::build(&[unit_box(Vec3A::ZERO)]);
        assert_eq!(one.closest(&ray, |_, _| 4.5), Some((0, 4.5)));
        assert!(one.any(&ray, |_, _| 4.5));
    }
}
