//! Improved Perlin noise (Perlin, "Improving Noise", SIGGRAPH 2002) and the normal perturbation
//! the `s` argument of `gr.material` asks for.
//!
//! `noise(p)` is the 2002 reference: a quintic fade, gradients from the 12 cube-edge directions,
//! the standard permutation. Its value lies in about [-1, 1] with mean 0 and it is C² smooth.
//!
//! A material with Perlin scale `s > 0` bends the shading normal `n` at world point `p` by the
//! tangential part of the noise gradient: `n' = normalize(n − s·K·∇⊥N(F·p))` with frequency
//! `F = 10` features per scene unit and `K = 0.02·F`, so `s = 1` tilts normals by roughly 10–20°.
//! The perturbation depends only on `p` and `n`, so it is continuous wherever they are: on meshes
//! it is applied to smooth (interpolated) normals, and a coarse water mesh looks smooth.

use glam::Vec3A;

/// Noise features per scene unit.
pub const FREQUENCY: f32 = 10.0;
/// Strength of the normal perturbation per unit of Perlin scale.
const STRENGTH: f32 = 0.02 * FREQUENCY;

const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

fn perm(i: i32) -> i32 {
    PERM[(i & 255) as usize] as i32
}

fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

fn grad(hash: i32, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// Returns improved Perlin noise at `p`.
pub fn noise(p: Vec3A) -> f32 {
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    let (xi, yi, zi) = (fx as i32, fy as i32, fz as i32);
    let (x, y, z) = (p.x - fx, p.y - fy, p.z - fz);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let a = perm(xi) + yi;
    let (aa, ab) = (perm(a) + zi, perm(a + 1) + zi);
    let b = perm(xi + 1) + yi;
    let (ba, bb) = (perm(b) + zi, perm(b + 1) + zi);
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(perm(aa), x, y, z), grad(perm(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(perm(ab), x, y - 1.0, z),
                grad(perm(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(perm(aa + 1), x, y, z - 1.0),
                grad(perm(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(perm(ab + 1), x, y - 1.0, z - 1.0),
                grad(perm(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// Returns the gradient vector [`grad`] dots with the offset for `hash`: `±1` on the two axes
/// it picks.
fn grad_vector(hash: i32) -> Vec3A {
    let h = hash & 15;
    let u = if h < 8 { 0 } else { 1 };
    let v = if h < 4 {
        1
    } else if h == 12 || h == 14 {
        0
    } else {
        2
    };
    let mut g = Vec3A::ZERO;
    g[u] = if h & 1 == 0 { 1.0 } else { -1.0 };
    g[v] = if h & 2 == 0 { 1.0 } else { -1.0 };
    g
}

/// Returns the derivative of [`fade`].
fn fade_derivative(t: f32) -> f32 {
    30.0 * t * t * (t - 1.0) * (t - 1.0)
}

/// Returns the gradient of [`noise`] at `p`, exactly (up to rounding).
///
/// Why not central differences, as before: they cost six evaluations of the noise, and the
/// water of the final scene bends its normal at every hit of every camera ray and photon (4.5%
/// of the frame's samples in `perf`). The noise is a trilinear blend, by fade weights, of the
/// eight corners' values `g·(p − corner)`, so its derivative is the blend of the corners'
/// gradients `g` plus the corners' values blended by the fade's derivative along each axis:
/// the eight corners once.
pub fn gradient(p: Vec3A) -> Vec3A {
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    let (xi, yi, zi) = (fx as i32, fy as i32, fz as i32);
    let f = Vec3A::new(p.x - fx, p.y - fy, p.z - fz);
    let w1 = Vec3A::new(fade(f.x), fade(f.y), fade(f.z));
    let dw = Vec3A::new(
        fade_derivative(f.x),
        fade_derivative(f.y),
        fade_derivative(f.z),
    );
    let mut out = Vec3A::ZERO;
    for corner in 0..8 {
        let (i, j, k) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        let hash = perm(perm(perm(xi + i) + yi + j) + zi + k);
        let g = grad_vector(hash);
        let offset = f - Vec3A::new(i as f32, j as f32, k as f32);
        let value = g.dot(offset);
        // The corner's weight along each axis, and its derivative there.
        let pick = |axis: usize, on: i32| match on {
            1 => (w1[axis], dw[axis]),
            _ => (1.0 - w1[axis], -dw[axis]),
        };
        let ((wx, dx), (wy, dy), (wz, dz)) = (pick(0, i), pick(1, j), pick(2, k));
        out += g * (wx * wy * wz) + value * Vec3A::new(dx * wy * wz, wx * dy * wz, wx * wy * dz);
    }
    out
}

/// Returns the unit normal `n` at world point `p` bent by Perlin noise of scale `s`.
pub fn perturb_normal(n: Vec3A, p: Vec3A, s: f32) -> Vec3A {
    let g = gradient(p * FREQUENCY);
    let tangential = g - n * g.dot(n);
    (n - tangential * (s * STRENGTH)).normalize_or(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> impl Iterator<Item = Vec3A> {
        (0..n).map(|i| {
            let f = i as f32;
            Vec3A::new(
                (f * 0.731).sin() * 37.1,
                (f * 0.377).cos() * 23.7,
                f * 0.0917 - 40.0,
            )
        })
    }

    /// The exact gradient is the noise's: at 20,000 points it is within 5e-4 of central
    /// differences taken in f64 arithmetic of the f32 noise, steps 1e-2 and 5e-3 combined by
    /// Richardson's extrapolation (their own error, 2e-4 at worst: the noise is only C² across
    /// its cell faces, where the extrapolation's h² terms do not cancel; a gradient is of size
    /// 1–3, and a wrong sign or axis is off by about 1), and `grad_vector` dotted with an
    /// offset is `grad` at every hash.
    #[test]
    fn the_gradient_is_the_noise_derivative() {
        for hash in 0..256 {
            let o = Vec3A::new(0.3, -0.7, 0.45);
            assert_eq!(
                grad_vector(hash).dot(o),
                grad(hash, o.x, o.y, o.z),
                "hash {hash}"
            );
        }
        let mut worst = 0.0f64;
        for p in points(20_000) {
            // Divided by the step the f32 points really are apart (a coordinate of 40 has an
            // ulp of 4e-6, a thousandth of the step).
            let central = |e: Vec3A, h: f32| {
                let (hi, lo) = (p + e * h, p - e * h);
                (noise(hi) as f64 - noise(lo) as f64) / (hi - lo).dot(e) as f64
            };
            // Richardson's extrapolation of two steps: the h² error terms cancel.
            let d = |e: Vec3A| (4.0 * central(e, 5e-3) - central(e, 1e-2)) / 3.0;
            let numeric = [d(Vec3A::X), d(Vec3A::Y), d(Vec3A::Z)];
            let exact = gradient(p);
            for a in 0..3 {
                worst = worst.max((exact[a] as f64 - numeric[a]).abs());
            }
        }
        assert!(worst < 5e-4, "largest difference {worst}");
    }

    #[test]
    fn value_range_mean_and_lattice_zeros() {
        let values: Vec<f32> = points(100_000).map(noise).collect();
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        let (lo, hi) = values
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!(
            lo >= -1.05 && hi <= 1.05 && lo < -0.5 && hi > 0.5,
            "range [{lo}, {hi}]"
        );
        // Zero at every integer lattice point.
        for k in -5..5 {
            assert_eq!(noise(Vec3A::new(k as f32, (2 * k) as f32, 3.0)), 0.0);
        }
    }

    #[test]
    fn noise_is_continuous() {
        for p in points(2000) {
            let e = Vec3A::splat(1e-4);
            assert!((noise(p) - noise(p + e)).abs() < 2e-3, "jump at {p}");
        }
    }

    #[test]
    fn perturbed_normal_is_continuous_across_a_shared_triangle_edge() {
        // Two triangles share the edge from a to b; their interpolated normals agree on it, so the
        // perturbed normals at points of the edge reached from either side agree too.
        let (a, b) = (Vec3A::new(0.0, 0.0, 0.0), Vec3A::new(1.0, 0.1, 0.0));
        let (na, nb) = (
            Vec3A::new(0.1, 0.2, 1.0).normalize(),
            Vec3A::new(-0.2, 0.1, 1.0).normalize(),
        );
        let (c1, n1) = (
            Vec3A::new(0.5, 1.0, 0.2),
            Vec3A::new(0.0, -0.3, 1.0).normalize(),
        );
        let (c2, n2) = (
            Vec3A::new(0.5, -1.0, -0.1),
            Vec3A::new(0.3, 0.3, 1.0).normalize(),
        );
        let shade = |w: [f32; 3], c: Vec3A, nc: Vec3A| {
            let p = a * w[0] + b * w[1] + c * w[2];
            let n = (na * w[0] + nb * w[1] + nc * w[2]).normalize();
            perturb_normal(n, p, 1.5)
        };
        for k in 0..=50 {
            let t = k as f32 / 50.0;
            let eps = 1e-5;
            let left = shade([1.0 - t - eps, t, eps], c1, n1);
            let right = shade([1.0 - t - eps, t, eps], c2, n2);
            assert!(
                (left - right).length() < 2e-3,
                "edge point {t}: {left} vs {right}"
            );
        }
        // And the perturbation is real: the bent normal differs from the base one.
        let bent = perturb_normal(Vec3A::Z, Vec3A::new(0.123, 0.456, 0.0), 1.5);
        assert!(
            bent.dot(Vec3A::Z) < 0.999 && bent.dot(Vec3A::Z) > 0.5,
            "{bent}"
        );
    }
}
