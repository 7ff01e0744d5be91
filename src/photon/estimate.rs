//! Density estimation: turning the photons near a point into irradiance.
//!
//! A photon `p` at distance `d` from the query point, within the search radius `r`, contributes
//! `Φ_p · w(d, r)`, where the kernel `w` integrates to one over the disc of radius `r` (the photons
//! are assumed to lie on the surface around the point). The estimate is `E = Σ Φ_p w(d_p, r)` and
//! the reflected radiance of a Lambertian surface `L = (kd/π)·E`.
//!
//! Kernels ([`Filter`]):
//! - `Box`: `1/(πr²)`;
//! - `Cone` (Jensen): `(1 − d/(k r)) / ((1 − 2/(3k)) π r²)` with `k = 1.1`;
//! - `Epanechnikov`: `2(1 − d²/r²)/(πr²)` — consistent for smooth irradiance (no first-order
//!   bias), the default;
//! - `Gaussian`: `α(1 − (1 − e^{−β d²/(2r²)})/(1 − e^{−β}))/(πr²)` with Jensen's `β = 1.953` and
//!   the `α` that makes it integrate to one (not Jensen's 0.918, which underestimates).

use std::f32::consts::PI;

/// A density-estimation kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Box,
    Cone,
    Epanechnikov,
    Gaussian,
}

/// The cone filter's slope constant `k`.
const CONE_K: f32 = 1.1;
/// Jensen's Gaussian filter constant `β`.
const GAUSS_BETA: f32 = 1.953;

impl Filter {
    /// Returns the kernel weight of a photon at squared distance `d2` for search radius² `r2`.
    pub fn weight(self, d2: f32, r2: f32) -> f32 {
        if d2 > r2 || r2 <= 0.0 {
            return 0.0;
        }
        let area = PI * r2;
        match self {
            Filter::Box => 1.0 / area,
            Filter::Cone => {
                let d = (d2 / r2).sqrt();
                (1.0 - d / CONE_K) / ((1.0 - 2.0 / (3.0 * CONE_K)) * area)
            }
            Filter::Epanechnikov => 2.0 * (1.0 - d2 / r2) / area,
            Filter::Gaussian => {
                let e = (1.0 - (-GAUSS_BETA * d2 / (2.0 * r2)).exp()) / (1.0 - (-GAUSS_BETA).exp());
                gauss_alpha() * (1.0 - e) / area
            }
        }
    }
}

/// Returns the normalisation of the Gaussian kernel: ∫ over the unit disc of `(1 − e(s))` is
/// `π (1 − (2/β)(1 − e^{−β/2}) ... )`, computed in closed form so the kernel integrates to one.
fn gauss_alpha() -> f32 {
    // ∫_0^1 (1 − (1 − e^{−β s²/2})/(1 − e^{−β})) 2π s ds
    //   = π − π/(1 − e^{−β}) · (1 − (2/β)(1 − e^{−β/2})).
    let b = GAUSS_BETA as f64;
    let denom = 1.0 - (-b).exp();
    let integral =
        std::f64::consts::PI * (1.0 - (1.0 - (2.0 / b) * (1.0 - (-b / 2.0).exp())) / denom);
    (std::f64::consts::PI / integral) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrates the kernel over the disc of radius r numerically (polar midpoint rule).
    fn integral(f: Filter, r: f32) -> f64 {
        let n = 20_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64 * r as f64;
            let w = f.weight((s * s) as f32, r * r) as f64;
            sum += w * 2.0 * std::f64::consts::PI * s * (r as f64 / n as f64);
        }
        sum
    }

    #[test]
    fn every_filter_integrates_to_one() {
        for f in [
            Filter::Box,
            Filter::Cone,
            Filter::Epanechnikov,
            Filter::Gaussian,
        ] {
            for r in [0.01f32, 1.0, 37.0] {
                let i = integral(f, r);
                assert!((i - 1.0).abs() < 1e-3, "{f:?} r {r}: {i}");
            }
            assert_eq!(f.weight(2.0, 1.0), 0.0, "outside the radius");
        }
    }
}
