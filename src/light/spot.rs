//! A spot light's cone: glTF's angular falloff (`KHR_lights_punctual`), the solid angle it
//! weights, and photon directions drawn in proportion to it.
//!
//! ```lua
//! gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 15, 20)   -- full to 15°, dark past 20°
//! ```
//!
//! # The falloff
//! The specification's implementation note, in terms of `c = cos θ` from the spot's axis:
//! `scale = 1 / max(0.001, cos inner − cos outer)`, `t = clamp((c − cos outer)·scale, 0, 1)`, and
//! the intensity is `I·t²` ([`SpotCone::falloff`]): `I` within the inner cone, a squared ramp in
//! the cosine down to exactly 0 at the outer cone and beyond. (The note writes it
//! `c·scale + offset` with `offset = −cos outer·scale`: the same number, rounded once less.)
//! With `inner = outer` the ramp is 0.001 wide in cosine: a hard edge.
//!
//! # What it weights, in closed form
//! Writing `x = 1 − c` (0 on the axis), `X = 1 − cos outer`, `W = 1/scale` and `A = max(0, X − W)`:
//! `t = 1` on the plateau `[0, A]` and `t = (X − x)/W` on the ramp `[A, X]` (when `W > X` there
//! is no plateau, and the axis cuts the ramp short at `t = X/W < 1`), so
//! `∫ t² dω = 2π·(A + (X − A)³/(3W²))` ([`SpotCone::solid_angle`]), and the spot's flux is its
//! physical head-on intensity times that. The sums are taken in `f64` from the angles
//! (`1 − cos o = 2 sin²(o/2)`, `cos i − cos o = 2 sin((o + i)/2)·sin((o − i)/2)`), so a cone of a
//! hundredth of a degree keeps its digits.
//!
//! # Photon directions
//! Photons leave in proportion to the falloff ([`SpotCone::sample`], density
//! [`SpotCone::pdf`]): `x` is drawn by inverting the cumulative `F(x) = x` on the plateau and
//! `A + ((X − A)³ − (X − x)³)/(3W²)` on the ramp, `φ` uniformly. Every photon then carries the
//! same power, `Φ/n`, and none is sent where the spot is dark.

use glam::Vec3A;
use std::f32::consts::TAU;

/// The narrowest ramp the specification allows, in cosine.
const MIN_RAMP: f64 = 0.001;

/// glTF's spot cone about an axis, in the cosine from that axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// The inner angle, radians: full intensity within it.
    pub inner: f32,
    /// The outer angle, radians: dark beyond it.
    pub outer: f32,
    /// Cosine of the outer angle: the falloff is 0 at and beyond it.
    pub cos_outer: f32,
    /// The specification's `lightAngleScale`, `1 / max(0.001, cos inner − cos outer)`.
    pub scale: f32,
    /// `X = 1 − cos outer`, to `f64` precision from the angle.
    x_outer: f64,
    /// `W = 1/scale`, the ramp's width in cosine.
    ramp: f64,
    /// `A = max(0, X − W)`, where the plateau ends.
    plateau: f64,
    /// `∫ t² dω` over the sphere, steradians.
    solid_angle: f32,
}

impl SpotCone {
    /// Returns the cone full within `inner` and dark beyond `outer` (radians, `0 ≤ inner ≤
    /// outer ≤ π/2`; the caller checks, [`check_angles`]).
    pub fn new(inner: f32, outer: f32) -> SpotCone {
        let (i, o) = (f64::from(inner), f64::from(outer));
        let x_outer = 2.0 * (o / 2.0).sin().powi(2);
        let width = 2.0 * ((o + i) / 2.0).sin() * ((o - i) / 2.0).sin();
        let ramp = width.max(MIN_RAMP);
        let plateau = (x_outer - ramp).max(0.0);
        let solid_angle =
            std::f64::consts::TAU * (plateau + (x_outer - plateau).powi(3) / (3.0 * ramp * ramp));
        SpotCone {
            inner,
            outer,
            cos_outer: o.cos() as f32,
            scale: (1.0 / ramp) as f32,
            x_outer,
            ramp,
            plateau,
            solid_angle: solid_angle as f32,
        }
    }

    /// Returns the falloff `t²` at cosine `cos` from the axis: 1 within the inner cone, 0 at and
    /// beyond the outer one.
    pub fn falloff(&self, cos: f32) -> f32 {
        let t = ((cos - self.cos_outer) * self.scale).clamp(0.0, 1.0);
        t * t
    }

    /// Returns `∫ t² dω` over the sphere of directions (steradians): the flux of a spot of
    /// head-on intensity 1.
    pub fn solid_angle(&self) -> f32 {
        self.solid_angle
    }

    /// Returns a direction about unit `axis` drawn from `u` in [0, 1)² with density
    /// [`SpotCone::pdf`]: in proportion to the falloff, never beyond the outer cone.
    pub fn sample(&self, axis: Vec3A, u: (f32, f32)) -> Vec3A {
        let x = self.sample_x(f64::from(u.0));
        let sin = (x * (2.0 - x)).max(0.0).sqrt() as f32;
        let phi = TAU * u.1;
        let t = axis.any_orthonormal_vector();
        let b = axis.cross(t);
        (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * (1.0 - x) as f32).normalize()
    }

    /// Returns `x = 1 − cos θ` of the cumulative share `v` in [0, 1] of the falloff's weight.
    fn sample_x(&self, v: f64) -> f64 {
        let (a, x, w) = (self.plateau, self.x_outer, self.ramp);
        let ramp = (x - a).powi(3) / (3.0 * w * w);
        let s = v * (a + ramp);
        if s < a {
            s
        } else {
            let left = ((x - a).powi(3) - 3.0 * w * w * (s - a)).max(0.0);
            (x - left.cbrt()).clamp(0.0, x)
        }
    }

    /// Returns the density per steradian of [`SpotCone::sample`]'s direction at cosine `cos`
    /// from the axis: `t²` over `∫ t² dω`.
    pub fn pdf(&self, cos: f32) -> f32 {
        self.falloff(cos) / self.solid_angle
    }
}

/// Returns an error unless `0 ≤ inner ≤ outer ≤ π/2` (radians; NaN fails), as glTF's
/// `innerConeAngle` and `outerConeAngle` must be (the specification asks `inner < outer`; equal
/// angles make the hard edge of the 0.001 ramp).
pub fn check_angles(inner: f32, outer: f32) -> Result<(), String> {
    let right = std::f32::consts::FRAC_PI_2;
    if (0.0..=right).contains(&inner) && (0.0..=right).contains(&outer) && inner <= outer {
        Ok(())
    } else {
        Err(format!(
            "spot cone angles inner {inner} and outer {outer} radians ({:.4}° and {:.4}°) must \
             satisfy 0 ≤ inner ≤ outer ≤ π/2",
            inner.to_degrees(),
            outer.to_degrees()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    /// Returns `∫ t² dω` by the midpoint rule over `x = 1 − cos θ` in `f64`.
    fn numeric(cone: &SpotCone) -> f64 {
        let n = 200_000;
        let dx = cone.x_outer / n as f64;
        let scale = 1.0 / cone.ramp;
        (0..n)
            .map(|k| {
                let x = (k as f64 + 0.5) * dx;
                let t = ((cone.x_outer - x) * scale).clamp(0.0, 1.0);
                t * t * dx
            })
            .sum::<f64>()
            * std::f64::consts::TAU
    }

    /// The closed form of `∫ t² dω` matches a fine numeric integral for wide, narrow, hard and
    /// axis-cut cones, and the falloff is 1 inside, 0 outside and the square of the ramp between.
    #[test]
    fn the_weighted_solid_angle_is_the_integral_of_the_falloff() {
        for (inner, outer) in [
            (18.0f32, 22.5f32),
            (0.0, 45.0),
            (30.0, 30.0),
            (89.0, 90.0),
            (0.0, 0.5),
            (0.01, 0.02),
        ] {
            let cone = SpotCone::new(inner.to_radians(), outer.to_radians());
            let want = numeric(&cone);
            let got = f64::from(cone.solid_angle());
            assert!(
                (got - want).abs() < 1e-5 * want,
                "{inner}°..{outer}°: {got} against {want}"
            );
        }
        let cone = SpotCone::new(20f32.to_radians(), 30f32.to_radians());
        assert_eq!(cone.falloff(1.0), 1.0);
        assert_eq!(cone.falloff(20f32.to_radians().cos() + 1e-6), 1.0);
        assert_eq!(cone.falloff(30f32.to_radians().cos()), 0.0);
        assert_eq!(cone.falloff(-1.0), 0.0);
        let c = 25f32.to_radians().cos();
        let (ci, co) = (20f32.to_radians().cos(), 30f32.to_radians().cos());
        let t = (c - co) / (ci - co);
        assert!((cone.falloff(c) - t * t).abs() < 1e-5);
        // A cone wholly within 0.001 of the axis in cosine: the ramp is cut by the axis, and
        // the weight is the ramp's part inside.
        let tiny = SpotCone::new(0.0, 1f32.to_radians());
        assert!(tiny.falloff(1.0) < 1.0 && tiny.falloff(1.0) > 0.0);
    }

    /// Directions drawn from the cone stay within its outer angle, and their histogram over
    /// the cosine matches the density, which integrates to one.
    #[test]
    fn samples_follow_the_falloff_and_the_density_integrates_to_one() {
        for (inner, outer) in [(18.0f32, 22.5f32), (0.0, 60.0), (10.0, 10.0)] {
            let cone = SpotCone::new(inner.to_radians(), outer.to_radians());
            let axis = Vec3A::new(0.3, -1.0, 0.2).normalize();
            let x_outer = 1.0 - cone.cos_outer;
            let bins = 20;
            let mut hist = vec![0u32; bins];
            let mut rng = Rng::new(9, Pass::Photon, 0);
            let n = 400_000;
            for _ in 0..n {
                let d = cone.sample(axis, (rng.next_f32(), rng.next_f32()));
                assert!((d.length() - 1.0).abs() < 1e-5);
                let cos = d.dot(axis);
                assert!(cos >= cone.cos_outer - 1e-6, "{inner}..{outer}: {cos}");
                let b = (((1.0 - cos) / x_outer) * bins as f32) as usize;
                hist[b.min(bins - 1)] += 1;
            }
            // The density's mass per bin: ∫ pdf dω = 2π ∫ pdf dx over the bin, by midpoints.
            let mut total = 0.0;
            for (b, &count) in hist.iter().enumerate() {
                let steps = 200;
                let dx = x_outer / (bins * steps) as f32;
                let mass: f32 = (0..steps)
                    .map(|k| {
                        let x = (b * steps + k) as f32 * dx + dx / 2.0;
                        cone.pdf(1.0 - x) * TAU * dx
                    })
                    .sum();
                total += mass;
                let got = count as f32 / n as f32;
                assert!(
                    (got - mass).abs() < 0.003 + 0.02 * mass,
                    "{inner}..{outer}, bin {b}: {got} against {mass}"
                );
            }
            assert!((total - 1.0).abs() < 2e-3, "{inner}..{outer}: {total}");
        }
    }

    #[test]
    fn bad_angles_are_refused() {
        let r = std::f32::consts::FRAC_PI_2;
        assert!(check_angles(0.0, r).is_ok());
        assert!(check_angles(0.3, 0.3).is_ok());
        for (i, o) in [
            (0.5, 0.4),
            (-0.1, 0.4),
            (0.1, r + 0.01),
            (f32::NAN, 0.4),
            (0.1, f32::INFINITY),
        ] {
            let e = check_angles(i, o).unwrap_err();
            assert!(e.contains("0 ≤ inner ≤ outer ≤ π/2"), "{e}");
        }
    }
}
