//! Four triangles tested at once: the corners of a BVH leaf stored coordinate by coordinate, so
//! each SSE2 lane runs the watertight test of [`crate::geometry::triangle`] for one triangle.
//!
//! The lanes evaluate exactly the scalar test's IEEE operations in the same order (no fused
//! multiply-add), so they give bit-identical `t` and barycentrics; a lane whose edge function is
//! exactly zero (a ray through an edge or a vertex) is redone by the scalar test, which falls back
//! to double precision there (Woop et al. 2013, §3.3).
//!
//! One generic test (`lanes`) runs on four lanes (SSE2) or eight (AVX): a BVH leaf of five to
//! eight triangles is a pair of blocks, which the AVX2 traversal kernel tests as one 8-wide
//! block ([`closest_pair`], [`any_pair`]) instead of two 4-wide ones. A block with no lane whose
//! edge functions share a sign returns before the division: most blocks a ray reaches are such.

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
            // SAFETY: SSE2 is part of the x86-64 baseline.
            let mut l = unsafe { lanes::<simd::Sse, 4>(self, shear, tmin, tmax) };
            redo_edges(&mut l, |lane| self.corners(lane), shear, tmin, tmax);
            l.closest()
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.closest_scalar(shear, tmin, tmax)
    }

    /// Returns what [`Tri4::any_scalar`] returns, testing the four lanes at once.
    #[inline(always)]
    pub fn any(&self, shear: &RayShear, tmin: f32, tmax: f32) -> Option<f32> {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: SSE2 is part of the x86-64 baseline.
            let mut l = unsafe { lanes::<simd::Sse, 4>(self, shear, tmin, tmax) };
            redo_edges(&mut l, |lane| self.corners(lane), shear, tmin, tmax);
            l.first()
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.any_scalar(shear, tmin, tmax)
    }
}

/// Returns what testing block `a` and then block `b` with [`Tri4::closest`] finds (lanes 4 to 7
/// are `b`'s), in one 8-wide AVX test: a BVH leaf of five to eight triangles is such a pair.
///
/// # Safety
/// The CPU must have AVX. Call it from a function compiled with AVX (the AVX2 traversal kernel
/// inlines it), or its intrinsics are not inlined and it is slow.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub unsafe fn closest_pair(
    a: &Tri4,
    b: &Tri4,
    shear: &RayShear,
    tmin: f32,
    tmax: f32,
) -> Option<(u32, TriangleHit)> {
    // SAFETY: the caller guarantees AVX; rows are 16-byte aligned 16-byte arrays.
    let mut l = unsafe { lanes::<simd::Avx, 8>((a, b), shear, tmin, tmax) };
    redo_edges(&mut l, |lane| pair_corners(a, b, lane), shear, tmin, tmax);
    l.closest()
}

/// Returns what testing block `a` and then block `b` with [`Tri4::any`] finds, in one 8-wide
/// AVX test.
///
/// # Safety
/// As for [`closest_pair`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub unsafe fn any_pair(a: &Tri4, b: &Tri4, shear: &RayShear, tmin: f32, tmax: f32) -> Option<f32> {
    // SAFETY: as in `closest_pair`.
    let mut l = unsafe { lanes::<simd::Avx, 8>((a, b), shear, tmin, tmax) };
    redo_edges(&mut l, |lane| pair_corners(a, b, lane), shear, tmin, tmax);
    l.first()
}

#[cfg(target_arch = "x86_64")]
/// The corners of lane `lane` of the pair (`a`, `b`).
fn pair_corners(a: &Tri4, b: &Tri4, lane: usize) -> [Vec3A; 3] {
    if lane < LANES {
        a.corners(lane)
    } else {
        b.corners(lane - LANES)
    }
}

#[cfg(target_arch = "x86_64")]
/// Replaces the lanes with an exactly zero edge function by the scalar test's result.
#[inline(always)]
fn redo_edges<const N: usize>(
    l: &mut Lanes<N>,
    corners: impl Fn(usize) -> [Vec3A; 3],
    shear: &RayShear,
    tmin: f32,
    tmax: f32,
) {
    let mut edges = l.on_edge;
    while edges != 0 {
        let lane = edges.trailing_zeros() as usize;
        edges &= edges - 1;
        let [a, b, c] = corners(lane);
        if let Some(h) = triangle::intersect(shear, a, b, c, tmin, tmax) {
            l.hit |= 1 << lane;
            (l.t[lane], l.b1[lane], l.b2[lane]) = (h.t, h.b1, h.b2);
        }
    }
}

#[cfg(target_arch = "x86_64")]
/// Runs the single-precision watertight test on the `N` lanes of `tris`, with the scalar
/// test's operations in its order.
///
/// # Safety
/// The CPU must have `V`'s instructions.
#[inline(always)]
unsafe fn lanes<V: simd::Simd<N>, const N: usize>(
    tris: impl simd::Rows<V>,
    s: &RayShear,
    tmin: f32,
    tmax: f32,
) -> Lanes<N> {
    let [kx, ky, kz] = s.axes();
    let o = s.origin;
    let mut l = Lanes::<N>::NONE;
    // SAFETY: the caller guarantees `V`'s instructions.
    unsafe {
        let o = [V::splat(o[kx]), V::splat(o[ky]), V::splat(o[kz])];
        let shear = [V::splat(s.sx), V::splat(s.sy), V::splat(s.sz)];
        let k = [kx, ky, kz];
        let (ax, ay, az) = corner(tris, 0, k, o, shear);
        let (bx, by, bz) = corner(tris, 1, k, o, shear);
        let (cx, cy, cz) = corner(tris, 2, k, o, shear);
        let u = cx.mul(by).sub(cy.mul(bx));
        let v = ax.mul(cy).sub(ay.mul(cx));
        let w = bx.mul(ay).sub(by.mul(ax));
        let zero = V::splat(0.0);
        let on_edge = u.eq(zero).or(v.eq(zero)).or(w.eq(zero));
        let negative = u.lt(zero).or(v.lt(zero)).or(w.lt(zero));
        let positive = u.gt(zero).or(v.gt(zero)).or(w.gt(zero));
        let mixed = negative.and(positive);
        // A lane can hit only with its edge functions of one sign (or one exactly zero, for the
        // scalar redo); unused NaN lanes have no sign. Most blocks a ray reaches have no such
        // lane and return before the division.
        if on_edge.or(negative.or(positive).andnot(mixed)).mask() == 0 {
            return l;
        }
        let det = u.add(v).add(w);
        let t_scaled = u.mul(az).add(v.mul(bz)).add(w.mul(cz));
        let inv = V::splat(1.0).div(det);
        let t = t_scaled.mul(inv);
        let ok = det
            .neq(zero)
            .and(t.gt(V::splat(tmin)).and(t.lt(V::splat(tmax))));
        let hit = ok.andnot(mixed.or(on_edge));
        l.hit = hit.mask();
        l.on_edge = on_edge.mask();
        if l.hit != 0 {
            t.store(&mut l.t);
            v.mul(inv).store(&mut l.b1);
            w.mul(inv).store(&mut l.b2);
        }
    }
    l
}

/// Corner `v` of the lanes translated to the ray origin `o` and sheared: (x, y, z) as in the
/// scalar test, with `k` the shear's axes. A function, not a closure: closures are not inlined
/// reliably, and every intrinsic in one that is not ran as a call.
///
/// # Safety
/// The CPU must have `V`'s instructions.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn corner<V: simd::Simd<N>, const N: usize>(
    tris: impl simd::Rows<V>,
    v: usize,
    k: [usize; 3],
    o: [V; 3],
    shear: [V; 3],
) -> (V, V, V) {
    // SAFETY: the caller guarantees `V`'s instructions.
    unsafe {
        let z = tris.row(3 * v + k[2]).sub(o[2]);
        let x = tris.row(3 * v + k[0]).sub(o[0]).sub(shear[0].mul(z));
        let y = tris.row(3 * v + k[1]).sub(o[1]).sub(shear[1].mul(z));
        (x, y, shear[2].mul(z))
    }
}

#[cfg(target_arch = "x86_64")]
/// The per-lane results of the `N`-wide test: lane masks and the hits' values (valid where
/// `hit`).
#[derive(Clone, Copy, Debug)]
struct Lanes<const N: usize> {
    hit: u32,
    /// Lanes with an edge function exactly zero, to be redone by the scalar test.
    on_edge: u32,
    t: [f32; N],
    b1: [f32; N],
    b2: [f32; N],
}

#[cfg(target_arch = "x86_64")]
impl<const N: usize> Lanes<N> {
    const NONE: Lanes<N> = Lanes {
        hit: 0,
        on_edge: 0,
        t: [0.0; N],
        b1: [0.0; N],
        b2: [0.0; N],
    };

    /// The closest hit lane, the lowest on a tie.
    #[inline(always)]
    fn closest(&self) -> Option<(u32, TriangleHit)> {
        let mut best: Option<(u32, TriangleHit)> = None;
        let mut hits = self.hit;
        while hits != 0 {
            let lane = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            if best.is_none_or(|b| self.t[lane] < b.1.t) {
                let h = TriangleHit {
                    t: self.t[lane],
                    b1: self.b1[lane],
                    b2: self.b2[lane],
                };
                best = Some((lane as u32, h));
            }
        }
        best
    }

    /// The `t` of the lowest hit lane.
    #[inline(always)]
    fn first(&self) -> Option<f32> {
        (self.hit != 0).then(|| self.t[self.hit.trailing_zeros() as usize])
    }
}

/// The vector operations of [`lanes`], over four lanes (SSE2) or eight (AVX). Each is the IEEE
/// operation of the scalar test, lane by lane; comparisons give all-ones lanes.
#[cfg(target_arch = "x86_64")]
mod simd {
    use super::Tri4;
    use std::arch::x86_64::*;

    /// `N` lanes of `f32`.
    ///
    /// # Safety
    /// Every method needs the CPU to have the type's instructions.
    pub(super) trait Simd<const N: usize>: Copy {
        unsafe fn splat(x: f32) -> Self;
        unsafe fn add(self, b: Self) -> Self;
        unsafe fn sub(self, b: Self) -> Self;
        unsafe fn mul(self, b: Self) -> Self;
        unsafe fn div(self, b: Self) -> Self;
        unsafe fn or(self, b: Self) -> Self;
        unsafe fn and(self, b: Self) -> Self;
        /// `self` and not `b`.
        unsafe fn andnot(self, b: Self) -> Self;
        unsafe fn eq(self, b: Self) -> Self;
        unsafe fn neq(self, b: Self) -> Self;
        unsafe fn lt(self, b: Self) -> Self;
        unsafe fn gt(self, b: Self) -> Self;
        /// The lanes' sign bits.
        unsafe fn mask(self) -> u32;
        unsafe fn store(self, out: &mut [f32; N]);
    }

    /// Four lanes in an SSE register.
    #[derive(Clone, Copy)]
    pub(super) struct Sse(__m128);

    /// Triangle corners as vector rows: row `i` holds coordinate `i % 3` of corner `i / 3` of
    /// every lane.
    pub(super) trait Rows<V>: Copy {
        /// # Safety
        /// The CPU must have `V`'s instructions.
        unsafe fn row(self, i: usize) -> V;
    }

    impl Rows<Sse> for &Tri4 {
        #[inline(always)]
        unsafe fn row(self, i: usize) -> Sse {
            // SAFETY: `Tri4` is 16-byte aligned and each row is 16 bytes, so every row suits an
            // aligned load; SSE2 is part of the x86-64 baseline.
            Sse(unsafe { _mm_load_ps(self.rows[i].as_ptr()) })
        }
    }

    /// Eight lanes in an AVX register.
    #[derive(Clone, Copy)]
    pub(super) struct Avx(__m256);

    /// A pair of blocks: the first's lanes low, the second's high.
    impl Rows<Avx> for (&Tri4, &Tri4) {
        #[inline(always)]
        unsafe fn row(self, i: usize) -> Avx {
            // SAFETY: the caller has AVX; each row is four floats.
            Avx(unsafe { _mm256_loadu2_m128(self.1.rows[i].as_ptr(), self.0.rows[i].as_ptr()) })
        }
    }

    /// Implements [`Simd`] for `$t` by its intrinsics.
    macro_rules! simd {
        ($t:ident, $n:literal, $set1:ident, $add:ident, $sub:ident, $mul:ident, $div:ident,
         $or:ident, $and:ident, $andnot:ident, $cmp:ident, $movemask:ident, $storeu:ident) => {
            impl Simd<$n> for $t {
                #[inline(always)]
                unsafe fn splat(x: f32) -> Self {
                    $t(unsafe { $set1(x) })
                }
                #[inline(always)]
                unsafe fn add(self, b: Self) -> Self {
                    $t(unsafe { $add(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn sub(self, b: Self) -> Self {
                    $t(unsafe { $sub(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn mul(self, b: Self) -> Self {
                    $t(unsafe { $mul(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn div(self, b: Self) -> Self {
                    $t(unsafe { $div(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn or(self, b: Self) -> Self {
                    $t(unsafe { $or(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn and(self, b: Self) -> Self {
                    $t(unsafe { $and(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn andnot(self, b: Self) -> Self {
                    // The intrinsic negates its first operand.
                    $t(unsafe { $andnot(b.0, self.0) })
                }
                #[inline(always)]
                unsafe fn eq(self, b: Self) -> Self {
                    $t(unsafe { $cmp::<_CMP_EQ_OQ>(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn neq(self, b: Self) -> Self {
                    $t(unsafe { $cmp::<_CMP_NEQ_UQ>(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn lt(self, b: Self) -> Self {
                    $t(unsafe { $cmp::<_CMP_LT_OQ>(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn gt(self, b: Self) -> Self {
                    $t(unsafe { $cmp::<_CMP_GT_OQ>(self.0, b.0) })
                }
                #[inline(always)]
                unsafe fn mask(self) -> u32 {
                    unsafe { $movemask(self.0) as u32 }
                }
                #[inline(always)]
                unsafe fn store(self, out: &mut [f32; $n]) {
                    unsafe { $storeu(out.as_mut_ptr(), self.0) }
                }
            }
        };
    }

    simd!(
        Sse,
        4,
        _mm_set1_ps,
        _mm_add_ps,
        _mm_sub_ps,
        _mm_mul_ps,
        _mm_div_ps,
        _mm_or_ps,
        _mm_and_ps,
        _mm_andnot_ps,
        sse_cmp,
        _mm_movemask_ps,
        _mm_storeu_ps
    );
    simd!(
        Avx,
        8,
        _mm256_set1_ps,
        _mm256_add_ps,
        _mm256_sub_ps,
        _mm256_mul_ps,
        _mm256_div_ps,
        _mm256_or_ps,
        _mm256_and_ps,
        _mm256_andnot_ps,
        _mm256_cmp_ps,
        _mm256_movemask_ps,
        _mm256_storeu_ps
    );

    /// SSE2's comparisons under AVX's predicate names (`_mm_cmp_ps` needs AVX).
    #[inline(always)]
    unsafe fn sse_cmp<const P: i32>(a: __m128, b: __m128) -> __m128 {
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe {
            match P {
                _CMP_EQ_OQ => _mm_cmpeq_ps(a, b),
                _CMP_NEQ_UQ => _mm_cmpneq_ps(a, b),
                _CMP_LT_OQ => _mm_cmplt_ps(a, b),
                _ => _mm_cmpgt_ps(a, b),
            }
        }
    }
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

    /// The 8-wide test of a pair equals the scalar test of its first block and then its second
    /// (with the first's hit as `tmax`), bit for bit, for 5 to 8 triangles around shared edges
    /// and vertices, and for any-hit the first lane in order.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn pair_equals_scalar_in_sequence() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped pair_equals_scalar_in_sequence: this CPU has no AVX2");
            return;
        }
        let mut rng = Rng(0x9e37_79b9);
        let (mut hits, mut second) = (0, 0);
        for k in 0..100_000 {
            let n = 5 + k % 4;
            let hub = rng.point(1.0);
            let rim: Vec<Vec3A> = (0..=n).map(|_| rng.point(1.0)).collect();
            let tris: Vec<[Vec3A; 3]> = (0..n).map(|i| [hub, rim[i], rim[i + 1]]).collect();
            let (a, b) = (Tri4::new(&tris[..LANES]), Tri4::new(&tris[LANES..]));
            let target = match k % 4 {
                0 => hub,
                1 => (hub + rim[5]) * 0.5,
                2 => rim[2],
                _ => rng.point(1.0),
            };
            let o = rng.point(3.0);
            let ray = Ray::new(o, target - o);
            let shear = RayShear::new(&ray);
            let tmax = if k % 7 == 0 { 0.5 } else { f32::INFINITY };
            let first = a.closest_scalar(&shear, 0.0, tmax);
            let bound = first.map_or(tmax, |h| h.1.t);
            let then = b.closest_scalar(&shear, 0.0, bound);
            let want = then.map(|(l, h)| (l + LANES as u32, h)).or(first);
            // SAFETY: AVX2 was detected above.
            let got = unsafe { closest_pair(&a, &b, &shear, 0.0, tmax) };
            assert!(same(want, got), "ray {k}: {want:?} vs {got:?}");
            let any_want = a
                .any_scalar(&shear, 0.0, tmax)
                .or_else(|| b.any_scalar(&shear, 0.0, tmax));
            // SAFETY: as above.
            let any_got = unsafe { any_pair(&a, &b, &shear, 0.0, tmax) };
            assert_eq!(
                any_want.map(f32::to_bits),
                any_got.map(f32::to_bits),
                "ray {k}"
            );
            hits += want.is_some() as u32;
            second += then.is_some() as u32;
        }
        assert!(
            hits > 30_000 && second > 5_000,
            "{hits} hits, {second} in the second block"
        );
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
