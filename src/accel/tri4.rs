//! Four triangles tested at once: the corners of a BVH leaf stored coordinate by coordinate, so
//! each SSE2 lane runs the watertight test of [`crate::geometry::triangle`] for one triangle.
//!
//! The lanes evaluate exactly the scalar test's IEEE operations in the same order (no fused
//! multiply-add), so they give bit-identical `t` and barycentrics; a lane whose edge function is
//! exactly zero (a ray through an edge or a vertex) is redone by the scalar test, which falls back
//! to double precision there (Woop et al. 2013, §3.3).

use crate::geometry::triangle::{self, RayShear, TriangleHit};
use glam::Vec3A;

/// Triangles per block.
pub const LANES: usize = 4;

/// Up to four triangles: `rows[3 * v + a][lane]` is coordinate `a` of corner `v` of triangle
/// `lane`. Unused lanes hold NaN, which never hits (every comparison with NaN is false).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Tri4 {
    rows: [[f32; LANES]; 9],
}

impl Tri4 {
    /// Packs one to four triangles given by their corners.
    ///
    /// # Panics
    /// When `tris` holds more than four triangles.
    pub fn new(tris: &[[Vec3A; 3]]) -> Tri4 {
        assert!(
            tris.len() <= LANES,
            "a Tri4 holds at most {LANES} triangles"
        );
        let mut rows = [[f32::NAN; LANES]; 9];
        for (lane, corners) in tris.iter().enumerate() {
            for (v, p) in corners.iter().enumerate() {
                for a in 0..3 {
                    rows[3 * v + a][lane] = p[a];
                }
            }
        }
        Tri4 { rows }
    }

    /// Returns the corners of triangle `lane` (NaN for an unused lane).
    pub fn corners(&self, lane: usize) -> [Vec3A; 3] {
        let r = &self.rows;
        [0, 1, 2].map(|v| Vec3A::new(r[3 * v][lane], r[3 * v + 1][lane], r[3 * v + 2][lane]))
    }

    /// Returns the closest hit in `(tmin, tmax)` and its lane, the lowest lane on a tie, one
    /// triangle at a time (the reference for [`Tri4::closest`]).
    pub fn closest_scalar(
        &self,
        shear: &RayShear,
        tmin: f32,
        tmax: f32,
    ) -> Option<(u32, TriangleHit)> {
        let mut best = None;
        let mut tmax = tmax;
        for lane in 0..LANES {
            let [a, b, c] = self.corners(lane);
            if let Some(h) = triangle::intersect(shear, a, b, c, tmin, tmax) {
                best = Some((lane as u32, h));
                tmax = h.t;
            }
        }
        best
    }

    /// Returns the `t` of the lowest lane hit in `(tmin, tmax)`, one triangle at a time.
    pub fn any_scalar(&self, shear: &RayShear, tmin: f32, tmax: f32) -> Option<f32> {
        (0..LANES).find_map(|lane| {
            let [a, b, c] = self.corners(lane);
            triangle::intersect(shear, a, b, c, tmin, tmax).map(|h| h.t)
        })
    }

    /// Returns what [`Tri4::closest_scalar`] returns, testing the four lanes at once.
    #[inline(always)]
    pub fn closest(&self, shear: &RayShear, tmin: f32, tmax: f32) -> Option<(u32, TriangleHit)> {
        #[cfg(target_arch = "x86_64")]
        {
            let mut l = self.lanes(shear, tmin, tmax);
            if l.hit | l.on_edge == 0 {
                return None;
            }
            self.redo_edges(shear, tmin, tmax, &mut l);
            let mut best: Option<(u32, TriangleHit)> = None;
            let mut hits = l.hit;
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                if best.is_none_or(|b| l.t[lane] < b.1.t) {
                    let h = TriangleHit {
                        t: l.t[lane],
                        b1: l.b1[lane],
                        b2: l.b2[lane],
                    };
                    best = Some((lane as u32, h));
                }
            }
            best
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.closest_scalar(shear, tmin, tmax)
    }

    /// Returns what [`Tri4::any_scalar`] returns, testing the four lanes at once.
    #[inline(always)]
    pub fn any(&self, shear: &RayShear, tmin: f32, tmax: f32) -> Option<f32> {
        #[cfg(target_arch = "x86_64")]
        {
            let mut l = self.lanes(shear, tmin, tmax);
            if l.hit | l.on_edge == 0 {
                return None;
            }
            self.redo_edges(shear, tmin, tmax, &mut l);
            (l.hit != 0).then(|| l.t[l.hit.trailing_zeros() as usize])
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.any_scalar(shear, tmin, tmax)
    }

    /// Replaces the lanes with an exactly zero edge function by the scalar test's result.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn redo_edges(&self, shear: &RayShear, tmin: f32, tmax: f32, l: &mut Lanes) {
        let mut edges = l.on_edge;
        while edges != 0 {
            let lane = edges.trailing_zeros() as usize;
            edges &= edges - 1;
            let [a, b, c] = self.corners(lane);
            if let Some(h) = triangle::intersect(shear, a, b, c, tmin, tmax) {
                l.hit |= 1 << lane;
                (l.t[lane], l.b1[lane], l.b2[lane]) = (h.t, h.b1, h.b2);
            }
        }
    }

    /// Runs the single-precision watertight test on all four lanes.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn lanes(&self, s: &RayShear, tmin: f32, tmax: f32) -> Lanes {
        use std::arch::x86_64::*;
        let [kx, ky, kz] = s.axes();
        let o = s.origin;
        let r = &self.rows;
        let mut l = Lanes::default();
        // SAFETY: SSE2 is part of the x86-64 baseline; `Tri4` is 16-byte aligned and each row is
        // 16 bytes, so every row suits an aligned load; the stores write `[f32; 4]` arrays.
        unsafe {
            let ld = |i: usize| _mm_load_ps(r[i].as_ptr());
            let (ox, oy, oz) = (_mm_set1_ps(o[kx]), _mm_set1_ps(o[ky]), _mm_set1_ps(o[kz]));
            let (sx, sy, sz) = (_mm_set1_ps(s.sx), _mm_set1_ps(s.sy), _mm_set1_ps(s.sz));
            // Corner `v` translated to the ray origin and sheared: (x, y, z) as in the scalar test.
            let corner = |v: usize| {
                let z = _mm_sub_ps(ld(3 * v + kz), oz);
                let x = _mm_sub_ps(_mm_sub_ps(ld(3 * v + kx), ox), _mm_mul_ps(sx, z));
                let y = _mm_sub_ps(_mm_sub_ps(ld(3 * v + ky), oy), _mm_mul_ps(sy, z));
                (x, y, _mm_mul_ps(sz, z))
            };
            let (ax, ay, az) = corner(0);
            let (bx, by, bz) = corner(1);
            let (cx, cy, cz) = corner(2);
            let u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
            let v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
            let w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
            let zero = _mm_setzero_ps();
            let or3 = |a, b, c| _mm_or_ps(_mm_or_ps(a, b), c);
            let on_edge = or3(
                _mm_cmpeq_ps(u, zero),
                _mm_cmpeq_ps(v, zero),
                _mm_cmpeq_ps(w, zero),
            );
            let negative = or3(
                _mm_cmplt_ps(u, zero),
                _mm_cmplt_ps(v, zero),
                _mm_cmplt_ps(w, zero),
            );
            let positive = or3(
                _mm_cmpgt_ps(u, zero),
                _mm_cmpgt_ps(v, zero),
                _mm_cmpgt_ps(w, zero),
            );
            let mixed = _mm_and_ps(negative, positive);
            let det = _mm_add_ps(_mm_add_ps(u, v), w);
            let t_scaled = _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(u, az), _mm_mul_ps(v, bz)),
                _mm_mul_ps(w, cz),
            );
            let inv = _mm_div_ps(_mm_set1_ps(1.0), det);
            let t = _mm_mul_ps(t_scaled, inv);
            let ok = _mm_and_ps(
                _mm_cmpneq_ps(det, zero),
                _mm_and_ps(
                    _mm_cmpgt_ps(t, _mm_set1_ps(tmin)),
                    _mm_cmplt_ps(t, _mm_set1_ps(tmax)),
                ),
            );
            let hit = _mm_andnot_ps(_mm_or_ps(mixed, on_edge), ok);
            l.hit = _mm_movemask_ps(hit) as u32;
            l.on_edge = _mm_movemask_ps(on_edge) as u32;
            if l.hit != 0 {
                _mm_storeu_ps(l.t.as_mut_ptr(), t);
                _mm_storeu_ps(l.b1.as_mut_ptr(), _mm_mul_ps(v, inv));
                _mm_storeu_ps(l.b2.as_mut_ptr(), _mm_mul_ps(w, inv));
            }
        }
        l
    }
}

/// The per-lane results of the 4-wide test: lane masks and the hits' values (valid where `hit`).
#[derive(Clone, Copy, Debug, Default)]
struct Lanes {
    hit: u32,
    /// Lanes with an edge function exactly zero, to be redone by the scalar test.
    on_edge: u32,
    t: [f32; LANES],
    b1: [f32; LANES],
    b2: [f32; LANES],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;

    /// A small deterministic generator (xorshift), so failures reproduce.
    struct Rng(u32);

    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            (self.0 >> 8) as f32 / (1 << 24) as f32
        }

        fn point(&mut self, scale: f32) -> Vec3A {
            Vec3A::new(self.next(), self.next(), self.next()) * (2.0 * scale) - scale
        }
    }

    fn same(a: Option<(u32, TriangleHit)>, b: Option<(u32, TriangleHit)>) -> bool {
        let bits = |h: Option<(u32, TriangleHit)>| {
            h.map(|(l, h)| (l, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
        };
        bits(a) == bits(b)
    }

    /// The 4-wide test equals the scalar one bit for bit on random triangles, with rays aimed at
    /// random points, shared edges and shared vertices, for 1 to 4 lanes used.
    #[test]
    fn simd_equals_scalar() {
        let mut rng = Rng(0x1234_5678);
        let mut edge_hits = 0;
        for k in 0..200_000 {
            let n = 1 + k % LANES;
            // A fan around a shared vertex, so lanes share edges and a vertex.
            let hub = rng.point(1.0);
            let rim: Vec<Vec3A> = (0..=n).map(|_| rng.point(1.0)).collect();
            let tris: Vec<[Vec3A; 3]> = (0..n).map(|i| [hub, rim[i], rim[i + 1]]).collect();
            let block = Tri4::new(&tris);
            let target = match k % 4 {
                0 => hub,
                1 => (hub + rim[1]) * 0.5,
                2 => rim[1],
                _ => rng.point(1.0),
            };
            let o = rng.point(3.0);
            let ray = Ray::new(o, target - o);
            let shear = RayShear::new(&ray);
            let tmax = if k % 7 == 0 { 0.5 } else { f32::INFINITY };
            let scalar = block.closest_scalar(&shear, 0.0, tmax);
            let simd = block.closest(&shear, 0.0, tmax);
            assert!(same(scalar, simd), "ray {k}: {scalar:?} vs {simd:?}");
            let any = block.any(&shear, 0.0, tmax).map(f32::to_bits);
            assert_eq!(
                any,
                block.any_scalar(&shear, 0.0, tmax).map(f32::to_bits),
                "ray {k}"
            );
            edge_hits += (k % 4 != 3 && scalar.is_some()) as u32;
        }
        assert!(edge_hits > 50_000, "only {edge_hits} edge and vertex hits");
    }

    #[test]
    fn unused_lanes_never_hit() {
        let t = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let block = Tri4::new(&[t]);
        let ray = Ray::new(Vec3A::new(0.2, 0.2, 1.0), -Vec3A::Z);
        let shear = RayShear::new(&ray);
        let (lane, h) = block.closest(&shear, 0.0, f32::INFINITY).unwrap();
        assert_eq!((lane, h.t), (0, 1.0));
        let far = Ray::new(Vec3A::new(5.0, 5.0, 1.0), -Vec3A::Z);
        assert!(
            block
                .closest(&RayShear::new(&far), 0.0, f32::INFINITY)
                .is_none()
        );
    }
}
