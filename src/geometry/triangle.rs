//! Watertight ray/triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013).
//!
//! Rays aimed exactly at a shared edge or vertex hit at least one of the triangles sharing it:
//! the edge functions are evaluated in a ray-aligned frame and fall back to double precision when
//! one of them is exactly zero, so neighbouring triangles agree on which side an edge point lies.

use super::ray::Ray;
use glam::Vec3A;

/// The per-ray part of the watertight test: the dominant axis `kz` of the direction and a shear
/// that maps the ray onto +z.
///
/// The paper also swaps `kx` and `ky` when `d[kz] < 0` to keep the winding; without back-face
/// culling that swap only negates all three edge functions and the determinant exactly (`a − b =
/// −(b − a)` in floating point), so `t`, the barycentrics and every inside/outside decision are
/// the same without it, and the axes can be fixed per `kz` at compile time.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    kz: u8,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
    pub(crate) origin: Vec3A,
}

impl RayShear {
    /// Returns the shear for `ray` (its direction must not be zero).
    pub fn new(ray: &Ray) -> RayShear {
        let d = ray.dir;
        let kz = d.abs().max_position();
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        RayShear {
            kz: kz as u8,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            origin: ray.origin,
        }
    }
}

impl RayShear {
    /// Returns the ray-aligned axes `[kx, ky, kz]`: `kz` is the direction's dominant axis.
    #[inline(always)]
    pub(crate) fn axes(&self) -> [usize; 3] {
        match self.kz {
            0 => [1, 2, 0],
            1 => [2, 0, 1],
            _ => [0, 1, 2],
        }
    }
}

/// A hit on a triangle: the ray parameter and the barycentric weights of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

/// Intersects the ray described by `shear` with triangle `(v0, v1, v2)` for `t` in `(tmin, tmax)`.
///
/// Both sides of the triangle are hit (no back-face culling).
#[inline(always)]
pub fn intersect(
    shear: &RayShear,
    v0: Vec3A,
    v1: Vec3A,
    v2: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    // One branch per call, predicted perfectly along a ray; each arm indexes lanes statically.
    match shear.kz {
        0 => intersect_axes::<1, 2, 0>(shear, v0, v1, v2, tmin, tmax),
        1 => intersect_axes::<2, 0, 1>(shear, v0, v1, v2, tmin, tmax),
        _ => intersect_axes::<0, 1, 2>(shear, v0, v1, v2, tmin, tmax),
    }
}

/// Runs the watertight test with the ray-aligned axes `(KX, KY, KZ)` known at compile time.
#[inline(always)]
fn intersect_axes<const KX: usize, const KY: usize, const KZ: usize>(
    s: &RayShear,
    v0: Vec3A,
    v1: Vec3A,
    v2: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    let a = v0 - s.origin;
    let b = v1 - s.origin;
    let c = v2 - s.origin;
    let ax = a[KX] - s.sx * a[KZ];
    let ay = a[KY] - s.sy * a[KZ];
    let bx = b[KX] - s.sx * b[KZ];
    let by = b[KY] - s.sy * b[KZ];
    let cx = c[KX] - s.sx * c[KZ];
    let cy = c[KY] - s.sy * c[KZ];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        // Exactly on an edge in single precision: decide in double precision (paper, §3.3).
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let (az, bz, cz) = (s.sz * a[KZ], s.sz * b[KZ], s.sz * c[KZ]);
    let t_scaled = u * az + v * bz + w * cz;
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    if !(t > tmin && t < tmax) {
        return None;
    }
    Some(TriangleHit {
        t,
        b1: v * inv,
        b2: w * inv,
    })
}

/// Returns the unnormalised geometric normal `(v1 − v0) × (v2 − v0)`, computed in double precision.
pub fn geometric_normal(v0: Vec3A, v1: Vec3A, v2: Vec3A) -> Vec3A {
    let (v0, v1, v2) = (v0.as_dvec3(), v1.as_dvec3(), v2.as_dvec3());
    let n = (v1 - v0).cross(v2 - v0);
    Vec3A::from(n.as_vec3())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(o: Vec3A, d: Vec3A, v: [Vec3A; 3]) -> Option<TriangleHit> {
        let ray = Ray::new(o, d);
        intersect(&RayShear::new(&ray), v[0], v[1], v[2], 0.0, f32::INFINITY)
    }

    #[test]
    fn barycentrics_and_t_match_the_hit_point() {
        let v = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let h = hit(Vec3A::new(0.25, 0.5, 2.0), -Vec3A::Z, v).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        // Back side, scaled direction: t is in units of the direction's length.
        let h = hit(Vec3A::new(0.25, 0.25, -1.0), Vec3A::new(0.0, 0.0, 4.0), v).unwrap();
        assert!((h.t - 0.25).abs() < 1e-6);
        assert!(hit(Vec3A::new(0.75, 0.75, 1.0), -Vec3A::Z, v).is_none());
    }

    #[test]
    fn shared_edge_is_never_missed_by_both_triangles() {
        // Two triangles sharing the diagonal of the unit square; rays at points on the diagonal.
        let (a, b, c, d) = (Vec3A::ZERO, Vec3A::X, Vec3A::new(1.0, 1.0, 0.0), Vec3A::Y);
        for i in 0..=1000 {
            let s = i as f32 / 1000.0;
            let dir = Vec3A::new(0.1 * (i as f32).sin(), 0.07, -1.0);
            let origin = Vec3A::new(s, s, 0.0) - dir * 1.3;
            let h1 = hit(origin, dir, [a, b, c]);
            let h2 = hit(origin, dir, [a, c, d]);
            assert!(
                h1.is_some() || h2.is_some(),
                "ray {i} leaked through the shared edge"
            );
        }
    }
}
