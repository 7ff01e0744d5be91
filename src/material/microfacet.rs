//! GGX microfacets (Trowbridge–Reitz; Walter et al. 2007) with visible-normal sampling (Heitz,
//! "Sampling the GGX Distribution of Visible Normals", JCGT 2018): the rough-conductor lobe of
//! issue 37 and the rough dielectric's (Walter et al. 2007 for transmission), in a local frame
//! whose `z` is the shading normal. With roughness (`gr.roughness`) the conductor is a
//! material's mirror lobe ([`super::bsdf::Bsdf::glossy`]), and the dielectric's visible normals
//! split its interface ([`super::bsdf::Bsdf::dielectric`]).
//!
//! # Conventions
//! - Directions are unit vectors pointing away from the surface (`wo` towards where the ray came
//!   from, `wi` towards the light), in the local frame ([`Frame`]).
//! - `alpha` is GGX's width: `alpha = roughness²`, as glTF, Disney and Mitsuba's
//!   `roughconductor` (whose `alpha` is this one) have it. It is clamped to [`MIN_ALPHA`], below
//!   which the lobe is a mirror to `f32` precision and the delta mirror lobe should be used.
//! - The masking-shadowing term is Smith's height-correlated `G2 = 1/(1 + Λ(wo) + Λ(wi))`
//!   (Heitz 2014), as pbrt-v4 and Mitsuba 3 use.
//!
//! # The rough conductor
//! `f(wo, wi) = F · D(h) · G2(wo, wi) / (4 cos θo cos θi)` with `h` the half vector and `F` the
//! colour the caller multiplies in (Mitsuba's conductor of material `none`: a colour, no
//! Fresnel curve). Sampling draws a visible normal `h ~ D_wo(h) = G1(wo)·max(0, wo·h)·D(h)/cos θo`
//! and reflects `wo` about it: `pdf(wi) = D_wo(h) / (4 |wo·h|)`, and the sample's weight
//! `f·cos θi/pdf` is `G2/G1(wo)`, at most 1. A reflected direction below the surface is no sample
//! (the energy single scattering loses at high roughness, as in the references).
//!
//! The tests check the two normalisations the model rests on (`∫ D(h) cos θh dh = 1` and
//! `∫ D_wo(h) dh = 1`, by quadrature), that the sampled directions have the stated density (the
//! mean of `cos θi / pdf` is π), that each sample's weight is its `f·cos/pdf`, and that the
//! albedo the samples estimate is the quadrature of `f·cos` and at most 1 (a white furnace).

use glam::Vec3A;
use std::f32::consts::{FRAC_1_PI, PI, TAU};

/// Smallest GGX width kept: below it the lobe is a mirror to `f32` precision.
pub const MIN_ALPHA: f32 = 1e-3;

/// An orthonormal frame around a unit normal: local `z` is the normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3A,
    pub t: Vec3A,
    pub n: Vec3A,
}

impl Frame {
    /// Returns a frame around unit `n`.
    pub fn around(n: Vec3A) -> Frame {
        let s = n.any_orthonormal_vector();
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    }

    /// Returns world vector `v` in local coordinates.
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Returns local vector `v` in world coordinates.
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// The isotropic GGX distribution of width `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    /// Returns the distribution of perceptual `roughness` in `[0, 1]` (`alpha = roughness²`,
    /// at least [`MIN_ALPHA`]).
    pub fn from_roughness(roughness: f32) -> Ggx {
        Ggx::new(roughness.clamp(0.0, 1.0).powi(2))
    }

    /// Returns the distribution of width `alpha` (clamped to `[MIN_ALPHA, 1]`).
    pub fn new(alpha: f32) -> Ggx {
        Ggx {
            alpha: alpha.clamp(MIN_ALPHA, 1.0),
        }
    }

    /// Returns the density of micro-normal `h` (local, unit) per steradian of normals, zero
    /// below the surface: `α² / (π (cos²θ (α² − 1) + 1)²)`.
    pub fn d(&self, h: Vec3A) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = h.z * h.z;
        let denom = c2 * (a2 - 1.0) + 1.0;
        a2 * FRAC_1_PI / (denom * denom)
    }

    /// Returns Smith's `Λ(w)`: `(√(1 + α² tan²θ) − 1) / 2`.
    pub fn lambda(&self, w: Vec3A) -> f32 {
        let c2 = w.z * w.z;
        if c2 <= 0.0 {
            return f32::INFINITY;
        }
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    /// Returns the masking term `G1(w) = 1 / (1 + Λ(w))`.
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Returns the height-correlated masking-shadowing term `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
    pub fn g2(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Returns the density of visible normal `h` seen from `wo` (above the surface):
    /// `G1(wo) · max(0, wo·h) · D(h) / cos θo`.
    pub fn d_visible(&self, wo: Vec3A, h: Vec3A) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(h).max(0.0) * self.d(h) / wo.z
    }

    /// Returns a visible normal seen from `wo` (above the surface), distributed by
    /// [`Ggx::d_visible`], from two uniform numbers (Heitz 2018).
    pub fn sample_visible(&self, wo: Vec3A, u: (f32, f32)) -> Vec3A {
        let a = self.alpha;
        // The view in the hemisphere configuration (the distribution stretched to α = 1).
        let v = Vec3A::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = v.x * v.x + v.y * v.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-v.y, v.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = v.cross(t1);
        // A point on the projected disc, its far half squeezed to the visible part.
        let r = u.0.sqrt();
        let phi = TAU * u.1;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + v.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        let nh = t1 * p1 + t2 * p2 + v * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        // Back to the ellipsoid configuration.
        Vec3A::new(a * nh.x, a * nh.y, nh.z.max(0.0)).normalize()
    }
}

/// Returns `wo` mirrored about unit `h`.
fn reflect(wo: Vec3A, h: Vec3A) -> Vec3A {
    2.0 * wo.dot(h) * h - wo
}

/// A rough conductor's lobe: GGX of width `alpha`, its colour (`F`) left to the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    pub ggx: Ggx,
}

/// A direction sampled from a lobe, with its weight `f · cos θi / pdf` (before the colour) and
/// its density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeSample {
    pub wi: Vec3A,
    pub weight: f32,
    pub pdf: f32,
}

impl RoughConductor {
    /// Returns `f(wo, wi)` per unit colour (local directions), zero unless both lie above.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z)
    }

    /// Returns the density per steradian with which [`RoughConductor::sample`] draws `wi`.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let cos = wo.dot(h);
        if cos <= 0.0 {
            return 0.0;
        }
        self.ggx.d_visible(wo, h) / (4.0 * cos)
    }

    /// Returns a direction by visible-normal sampling, or `None` when `wo` is below the
    /// surface or the reflection about the sampled normal is.
    pub fn sample(&self, wo: Vec3A, u: (f32, f32)) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let h = self.ggx.sample_visible(wo, u);
        let wi = reflect(wo, h);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| LobeSample {
            wi,
            weight: self.ggx.g2(wo, wi) / self.ggx.g1(wo),
            pdf,
        })
    }
}

/// A rough dielectric interface (Walter et al. 2007): GGX of width `alpha` between the medium on
/// `wo`'s side (local `z > 0`) and the other, `eta` = index on `wo`'s side over the other's.
///
/// The lobe is in flux form, as photons carry it: a transmitted sample's radiance is also
/// scaled by `eta²` ([`DielectricSample::radiance_scale`]), as the smooth interface's is
/// ([`super::bsdf`]). Reflection about a visible normal `h` has Fresnel weight `F(wo·h)`;
/// transmission through it `1 − F`, with `f = (1 − F) D G2 |wi·h| |wo·h| / (|cos θi| |cos θo|
/// (η (wo·h) + wi·h)²)` (pbrt-v4's `DielectricBxDF` in importance mode). A sample chooses
/// between them by `F`, so its weight is `G2/G1(wo)` either way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    pub ggx: Ggx,
    pub eta: f32,
}

/// A direction sampled from a [`RoughDielectric`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricSample {
    pub wi: Vec3A,
    /// `f · |cos θi| / pdf` in flux form.
    pub weight: f32,
    pub pdf: f32,
    /// What radiance is multiplied by along this sample: `eta²` through the interface, else 1.
    pub radiance_scale: f32,
}

impl RoughDielectric {
    /// Returns the micro-normal that takes `wo` to `wi` (on `wo`'s side, `z > 0`) and whether
    /// the pair is a reflection, or `None` when no normal facing `wo` does.
    fn half(&self, wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, bool)> {
        let reflect = wi.z > 0.0;
        let h = if reflect { wo + wi } else { wi + self.eta * wo };
        let h = h.normalize_or_zero();
        let h = if h.z < 0.0 { -h } else { h };
        let ok = h.z > 0.0 && wo.dot(h) > 0.0 && (reflect || wi.dot(h) < 0.0);
        ok.then_some((h, reflect))
    }

    /// Returns `f(wo, wi)` in flux form (local directions, `wo` above).
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((h, reflect)) = self.half(wo, wi) else {
            return 0.0;
        };
        let f = super::fresnel::dielectric(wo.dot(h), self.eta);
        let dg = self.ggx.d(h) * self.ggx.g2(wo, wi);
        if reflect {
            f * dg / (4.0 * wo.z * wi.z)
        } else {
            let denom = self.eta * wo.dot(h) + wi.dot(h);
            (1.0 - f) * dg * (wi.dot(h) * wo.dot(h)).abs() / ((wi.z * wo.z).abs() * denom * denom)
        }
    }

    /// Returns the density per steradian with which [`RoughDielectric::sample`] draws `wi`.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((h, reflect)) = self.half(wo, wi) else {
            return 0.0;
        };
        let f = super::fresnel::dielectric(wo.dot(h), self.eta);
        let visible = self.ggx.d_visible(wo, h);
        if reflect {
            f * visible / (4.0 * wo.dot(h))
        } else {
            let denom = self.eta * wo.dot(h) + wi.dot(h);
            (1.0 - f) * visible * wi.dot(h).abs() / (denom * denom)
        }
    }

    /// Returns the density per steradian of `wi` on its side alone: the draw of a path that
    /// takes both sides at every visible normal (the eye's deterministic split), which is
    /// [`RoughDielectric::pdf`] without the Fresnel choice, `pdf/F` or `pdf/(1 − F)`.
    pub fn side_pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((h, reflect)) = self.half(wo, wi) else {
            return 0.0;
        };
        let visible = self.ggx.d_visible(wo, h);
        if reflect {
            visible / (4.0 * wo.dot(h))
        } else {
            let denom = self.eta * wo.dot(h) + wi.dot(h);
            visible * wi.dot(h).abs() / (denom * denom)
        }
    }

    /// Returns a direction: a visible normal from `u`, then reflection with probability
    /// `F(wo·h)` (`u.2`) or refraction; `None` when `wo` is below or the direction leaves on the
    /// wrong side.
    pub fn sample(&self, wo: Vec3A, u: (f32, f32, f32)) -> Option<DielectricSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let h = self.ggx.sample_visible(wo, (u.0, u.1));
        let f = super::fresnel::dielectric(wo.dot(h), self.eta);
        let (wi, radiance_scale) = if u.2 < f {
            let wi = reflect(wo, h);
            if wi.z <= 0.0 {
                return None;
            }
            (wi, 1.0)
        } else {
            let wi = super::fresnel::refract(wo, h, self.eta)?;
            if wi.z >= 0.0 {
                return None;
            }
            (wi, self.eta * self.eta)
        };
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| DielectricSample {
            wi,
            weight: self.ggx.g2(wo, wi) / self.ggx.g1(wo),
            pdf,
            radiance_scale,
        })
    }
}

/// Returns the unit direction at polar angle `theta` and azimuth `phi` in the local frame.
pub fn spherical(theta: f32, phi: f32) -> Vec3A {
    let (s, c) = theta.sin_cos();
    Vec3A::new(s * phi.cos(), s * phi.sin(), c)
}

/// Returns `∫ g(w) dω` over the upper hemisphere by the midpoint rule on `n_theta × n_phi`
/// cells (f64 sums); for the tests and for tabulating albedos.
pub fn hemisphere_integral(n_theta: usize, n_phi: usize, mut g: impl FnMut(Vec3A) -> f32) -> f64 {
    let (dt, dp) = (0.5 * PI as f64 / n_theta as f64, TAU as f64 / n_phi as f64);
    let mut sum = 0.0f64;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * dt;
        let mut ring = 0.0f64;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * dp;
            ring += g(spherical(theta as f32, phi as f32)) as f64;
        }
        sum += ring * theta.sin() * dt * dp;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    const ALPHAS: [f32; 4] = [0.05, 0.2, 0.5, 1.0];

    /// Outgoing directions at 0°, 30°, 60° and 85° from the normal.
    fn views() -> Vec<Vec3A> {
        [0.0f32, 30.0, 60.0, 85.0]
            .iter()
            .map(|d| spherical(d.to_radians(), 0.7))
            .collect()
    }

    /// `∫ D(h) cos θh dh = 1`: the micro-normals' projected area is the surface's (quadrature
    /// along θ, which D depends on alone; within 1e-3).
    #[test]
    fn ggx_normals_project_to_unit_area() {
        for alpha in ALPHAS {
            let ggx = Ggx::new(alpha);
            let n = 200_000;
            let dt = 0.5 * PI as f64 / n as f64;
            let total: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) * dt;
                    let h = spherical(t as f32, 0.0);
                    ggx.d(h) as f64 * t.cos() * t.sin() * TAU as f64 * dt
                })
                .sum();
            assert!((total - 1.0).abs() < 1e-3, "alpha {alpha}: {total}");
        }
    }

    /// `∫ G1(wo)·max(0, wo·h)·D(h) dh = cos θo` (Heitz 2014): the visible normals' density
    /// integrates to one, for four views and four widths (quadrature, within 0.5%).
    #[test]
    fn visible_normals_integrate_to_one() {
        for alpha in ALPHAS {
            let ggx = Ggx::new(alpha);
            for wo in views() {
                // Narrow lobes need fine cells near the pole.
                let n_theta = if alpha < 0.1 { 4000 } else { 800 };
                let total = hemisphere_integral(n_theta, 720, |h| ggx.d_visible(wo, h));
                assert!(
                    (total - 1.0).abs() < 5e-3,
                    "alpha {alpha}, view {wo}: {total}"
                );
            }
        }
    }

    /// The sampled directions have the density [`RoughConductor::pdf`] says: the mean of
    /// `cos θi / pdf(wi)` over 400k samples (0 where a sample falls below the surface) is
    /// `∫ cos θ dω = π` (the pdf covers the whole hemisphere) within 2%, for the widths and
    /// views whose estimate converges at that count; and each sample's weight is
    /// `f·cos θi / pdf` within 1e-4, at most 1.
    #[test]
    fn conductor_samples_have_their_stated_density_and_weight() {
        let mut rng = Rng::new(37, Pass::Photon, 0);
        for alpha in [0.2f32, 0.5, 1.0] {
            let lobe = RoughConductor {
                ggx: Ggx::new(alpha),
            };
            for wo in views() {
                let n = 400_000;
                let mut mean = 0.0f64;
                for _ in 0..n {
                    let u = (rng.next_f32(), rng.next_f32());
                    if let Some(s) = lobe.sample(wo, u) {
                        mean += (s.wi.z / s.pdf) as f64 / n as f64;
                        let want = lobe.eval(wo, s.wi) * s.wi.z / s.pdf;
                        assert!(
                            (s.weight - want).abs() <= 1e-4 * want.max(1.0),
                            "alpha {alpha}, view {wo}: weight {} against f·cos/pdf {want}",
                            s.weight
                        );
                        assert!(s.weight <= 1.0 + 1e-6);
                    }
                }
                // With narrow lobes cos/pdf has a heavy tail; the test keeps to widths whose
                // estimate of π converges at this count.
                if alpha >= 0.5 || wo.z > 0.9 {
                    assert!(
                        (mean / PI as f64 - 1.0).abs() < 0.02,
                        "alpha {alpha}, view {wo}: mean cos/pdf {mean}"
                    );
                }
            }
        }
    }

    /// A white furnace: the albedo the samples estimate (the mean weight) equals the quadrature
    /// of `f·cos θi` over the hemisphere within 1%, is at most 1, and is nearly 1 for a nearly
    /// smooth surface (single scattering loses energy only where microfacets shadow each
    /// other: at most 40% at α = 1 and grazing views).
    #[test]
    fn conductor_albedo_matches_quadrature_and_never_exceeds_one() {
        let mut rng = Rng::new(38, Pass::Photon, 0);
        for alpha in ALPHAS {
            let lobe = RoughConductor {
                ggx: Ggx::new(alpha),
            };
            for wo in views() {
                let n = 200_000;
                let mut albedo = 0.0f64;
                for _ in 0..n {
                    if let Some(s) = lobe.sample(wo, (rng.next_f32(), rng.next_f32())) {
                        albedo += s.weight as f64 / n as f64;
                    }
                }
                let n_theta = if alpha < 0.1 { 4000 } else { 800 };
                let quadrature = hemisphere_integral(n_theta, 720, |wi| lobe.eval(wo, wi) * wi.z);
                assert!(albedo <= 1.0 + 1e-6, "alpha {alpha}, view {wo}: {albedo}");
                assert!(
                    (albedo - quadrature).abs() < 0.01,
                    "alpha {alpha}, view {wo}: sampled {albedo}, quadrature {quadrature}"
                );
                // Nearly smooth: lossless but at grazing views (85°: 0.90 at α = 0.05, where
                // G1 = 0.93 already masks part of the surface).
                if alpha <= 0.05 && wo.z > 0.4 {
                    assert!(albedo > 0.99, "alpha {alpha}, view {wo}: {albedo}");
                }
            }
        }
    }

    /// `∫ g(w) dω` over the whole sphere: the upper hemisphere and its mirror image below.
    fn sphere_integral(n_theta: usize, mut g: impl FnMut(Vec3A) -> f32) -> f64 {
        let flip = Vec3A::new(1.0, 1.0, -1.0);
        hemisphere_integral(n_theta, 720, &mut g)
            + hemisphere_integral(n_theta, 720, |w| g(w * flip))
    }

    /// A rough dielectric, into glass (η = 1/1.5) and out of it (η = 1.5, where total internal
    /// reflection takes part of the sphere): each sample's weight is its `f·|cos|/pdf` within
    /// 1e-4 and at most 1; the pdf integrates over the sphere (quadrature) to the share of
    /// samples returned (Monte Carlo, 200k) within 1.5%; and the albedo the samples estimate
    /// equals the quadrature of `f·|cos θi|` within 1.5%, at most 1 (light is neither created nor,
    /// for a nearly smooth interface seen head-on, lost: above 0.99 at α = 0.05).
    #[test]
    fn dielectric_samples_match_their_density_and_conserve_energy() {
        let mut rng = Rng::new(39, Pass::Photon, 0);
        for eta in [1.0 / 1.5, 1.5] {
            for alpha in [0.05f32, 0.3, 0.8] {
                let lobe = RoughDielectric {
                    ggx: Ggx::new(alpha),
                    eta,
                };
                for wo in views() {
                    let n = 200_000;
                    let (mut returned, mut albedo) = (0usize, 0.0f64);
                    for _ in 0..n {
                        let u = (rng.next_f32(), rng.next_f32(), rng.next_f32());
                        let Some(s) = lobe.sample(wo, u) else {
                            continue;
                        };
                        returned += 1;
                        albedo += s.weight as f64 / n as f64;
                        let want = lobe.eval(wo, s.wi) * s.wi.z.abs() / s.pdf;
                        assert!(
                            (s.weight - want).abs() <= 1e-4 * want.max(1.0)
                                && s.weight <= 1.0 + 1e-6,
                            "eta {eta}, alpha {alpha}, view {wo}: weight {} against {want}",
                            s.weight
                        );
                        let scale = if s.wi.z < 0.0 { eta * eta } else { 1.0 };
                        assert_eq!(s.radiance_scale, scale);
                    }
                    let n_theta = if alpha < 0.1 { 4000 } else { 800 };
                    let covered = sphere_integral(n_theta, |wi| lobe.pdf(wo, wi));
                    let share = returned as f64 / n as f64;
                    assert!(
                        (covered - share).abs() < 0.015,
                        "eta {eta}, alpha {alpha}, view {wo}: pdf integrates to {covered}, {share} of samples returned"
                    );
                    let quadrature = sphere_integral(n_theta, |wi| lobe.eval(wo, wi) * wi.z.abs());
                    assert!(
                        albedo <= 1.0 + 1e-6 && (albedo - quadrature).abs() < 0.015,
                        "eta {eta}, alpha {alpha}, view {wo}: sampled {albedo}, quadrature {quadrature}"
                    );
                    if alpha <= 0.05 && wo.z > 0.9 {
                        assert!(
                            albedo > 0.99,
                            "eta {eta}, alpha {alpha}, view {wo}: {albedo}"
                        );
                    }
                }
            }
        }
    }

    /// The eye's split draws (a visible normal, then both reflection and refraction about it):
    /// `side_pdf` is the density of each side's draw, so it integrates over the upper
    /// hemisphere to the share of visible normals whose reflection stays above (Monte Carlo,
    /// 100k draws, within 1.5%), and the one-lobe `pdf` is it times the Fresnel choice.
    #[test]
    fn side_densities_are_the_split_draws() {
        let mut rng = Rng::new(41, Pass::Photon, 0);
        for eta in [1.0 / 1.5, 1.5] {
            for alpha in [0.09f32, 0.5] {
                let lobe = RoughDielectric {
                    ggx: Ggx::new(alpha),
                    eta,
                };
                for wo in views() {
                    let n = 100_000;
                    let mut above = 0usize;
                    for _ in 0..n {
                        let h = lobe
                            .ggx
                            .sample_visible(wo, (rng.next_f32(), rng.next_f32()));
                        let f = super::super::fresnel::dielectric(wo.dot(h), eta);
                        let wr = reflect(wo, h);
                        if wr.z > 0.0 {
                            above += 1;
                            let (side, one) = (lobe.side_pdf(wo, wr), lobe.pdf(wo, wr));
                            assert!(
                                (side * f - one).abs() <= 1e-3 * one.max(1e-3),
                                "{side} {f} {one}"
                            );
                        }
                        if let Some(wt) = super::super::fresnel::refract(wo, h, eta)
                            && wt.z < 0.0
                        {
                            let (side, one) = (lobe.side_pdf(wo, wt), lobe.pdf(wo, wt));
                            assert!(
                                (side * (1.0 - f) - one).abs() <= 1e-3 * one.max(1e-3),
                                "{side} {f} {one}"
                            );
                        }
                    }
                    let upper = sphere_integral(1200, |wi| {
                        if wi.z > 0.0 {
                            lobe.side_pdf(wo, wi)
                        } else {
                            0.0
                        }
                    });
                    let share = above as f64 / n as f64;
                    assert!(
                        (upper - share).abs() < 0.015,
                        "eta {eta}, alpha {alpha}, view {wo}: {upper} against {share}"
                    );
                }
            }
        }
    }

    /// The frame maps the normal to `z` and back, and keeps lengths.
    #[test]
    fn frames_round_trip() {
        let n = Vec3A::new(0.3, -0.5, 0.8).normalize();
        let f = Frame::around(n);
        assert!((f.to_local(n) - Vec3A::Z).length() < 1e-6);
        let v = Vec3A::new(-0.2, 0.9, 0.1).normalize();
        assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
    }
}
