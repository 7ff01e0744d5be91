//! The numeric ranges the renderer can use: numbers finite in `f32` can still overflow once they
//! are multiplied together in intersection and shading, so every value that enters a scene is
//! checked against its range where it enters (the script line for `gr` arguments, the file and
//! line or accessor for mesh files, the node after its transforms in the scene build).
//!
//! | what | range | why |
//! |---|---|---|
//! | coordinates and lengths, object and world space | `|x| ≤ 1e8` ([`MAX_COORDINATE`]) | the watertight triangle test forms products of three coordinates (`1e24`), edge cross products are squared for normals (`3·(8·1e16)² ≈ 2e34`) and summed per vertex; `f32` holds `3.4e38`. At `1e8` single precision resolves only 8 units, so nothing useful is lost |
//! | light colour (intensity) and ambient, per channel | `[0, 1e8]` ([`MAX_INTENSITY`]) | a physical `1/d²` light `1e4` units away needs `1e8` to light anything; with the attenuation bound below, direct light from one light stays under `2e15` (times reflectance 10 at most `2e16`) and a light's flux (`4π²·rgb`) under `4e9`; the edge-of-range renders peak near `2e23` (a seen emitter of the smallest size, `rgb/R² = 1e20`, through mirrors) |
//! | falloff coefficients `c0, c1, c2` | each `0` or in `[1e-6, 1e6]` ([`MIN_FALLOFF`], [`MAX_FALLOFF`]), not all `0` | `1/c0` is the attenuation at the light: `c0 = 1e-30` made `rgb·1e30`; at most `1e6` keeps a photon's falloff ratio `d²/(c0 + …)` finite over the whole coordinate range |
//! | reflectances `kd`, `ks` (script and MTL) | `[0, 10]` ([`MAX_REFLECTANCE`]) | course scenes use up to `1.5`; see the note below on values above 1 |
//! | index of refraction of a transparent material (script; an MTL `Ni` above 10 is taken as 10, a glTF `ior` is clamped to `[1, 10]`) | `[0.1, 10]` ([`MIN_IOR`], [`MAX_IOR`]) | the radiance crossing an interface scales by the square of the indices' ratio: `ior = 1e-30` made it `1e60`, infinite in `f32`; eight nested relative indices of 0.1 still keep it finite |
//! | `gr.absorption`: the colour kept, the distance it is kept over (glTF `attenuationColor`, `attenuationDistance`) | colour in `(0, 1]` per channel (glTF: clamped to `[1e-6, 1]`), distance `≥ 1e-6` ([`MIN_LIGHT_SIZE`]; glTF: `> 0`, infinite is clear) | `σ = −ln(colour)/distance` must be finite and `≥ 0` |
//! | `gr.roughness` | `[0, 1]` | GGX's `alpha = roughness²`, clamped below at `1e-3` where the lobe is a mirror to `f32` precision |
//! | glTF emitted radiance `emissiveFactor × emissiveStrength`, per channel; a mesh light's `rgb = L·A/π` after placing | `[0, 1e8]` ([`MAX_INTENSITY`]) | a mesh light is an area light spread over triangles: the same bounds as a light's colour |
//! | light `power` | `[0, 1e30]` ([`MAX_POWER`]) | only a weight among lights: the sum over many lights must stay finite |
//! | sphere-light radius, area-light size `√|u × v|` | `≥ 1e-6` ([`MIN_LIGHT_SIZE`]) | an emitter's radiance is `rgb/R²` (`π·rgb/area`): a radius of `1e-30` was infinite |
//! | spot cone angles (`gr.spot_light` in degrees, glTF `innerConeAngle`, `outerConeAngle` in radians); spot and directional directions | `0 ≤ inner ≤ outer ≤ 90°`; a direction not zero | glTF's range: beyond 90° the cone's falloff is no longer one ramp in the cosine; a zero direction has no axis |
//! | photons one light emits for one map (`num_photons`, its share of `--photons`, times `--photon-scale`) | `≤ 1e9` ([`MAX_PHOTONS`]) | 10^9 stored photons would need 20 GB |
//!
//! A reflectance above 1 amplifies light at every bounce: a path between two facing mirrors of
//! `ks = 1.5` grows as `1.5ⁿ`, and photons in a closed room of `kd = 1.5` too. Such values are
//! accepted (the course's scenes use `kd + ks` a little above 1 for bright highlights), with a
//! warning at the script line where a material's total `(kd + ks)·(1 − t) + t` exceeds 1 in some
//! channel ([`excess_albedo`]), and the long paths are bounded where they would grow:
//! - a photon chooses its lobe as before, but at such a surface it is weighted as if the lobes
//!   were scaled to sum 1 ([`crate::material::bsdf`]): its power never grows at a bounce, and a
//!   `kd = 1.5` room carries light as a white one does;
//! - an eye path splits deterministically over the plan's specular depth with `ks` as given (the
//!   course's mirror weights); beyond it, Russian roulette follows a mirror of `ks` above 1 at
//!   `ks` over its largest channel ([`crate::integrator::eye`]), so a closed mirror box adds
//!   the same weight at each of its thousand bounces instead of `1.5¹⁰²⁴`.
//!
//! A sample that still overflows (`ks = 10` over the 66 split bounces a deep nest of glass
//! shells may get) is dropped and counted (`--stats`: "NaN or infinite samples dropped"), never
//! written to the image.

use std::fmt::{Display, LowerExp};

/// Largest magnitude of a coordinate or a length, in object or world space.
pub const MAX_COORDINATE: f64 = 1e8;
/// Largest light colour (head-on intensity) or ambient light, per channel.
pub const MAX_INTENSITY: f64 = 1e8;
/// Largest diffuse or specular reflectance, per channel.
pub const MAX_REFLECTANCE: f64 = 10.0;
/// Smallest index of refraction of a transparent material (an index below 1 is relative to the
/// solid around, [`crate::material::medium`]): air in diamond is 0.41.
pub const MIN_IOR: f64 = 0.1;
/// Largest index of refraction of a transparent material: germanium is 4.
pub const MAX_IOR: f64 = 10.0;
/// Smallest non-zero falloff coefficient.
pub const MIN_FALLOFF: f64 = 1e-6;
/// Largest falloff coefficient.
pub const MAX_FALLOFF: f64 = 1e6;
/// Largest light power (the photon budget's weight).
pub const MAX_POWER: f64 = 1e30;
/// Smallest sphere-light radius, and smallest square root of an area light's area.
pub const MIN_LIGHT_SIZE: f64 = 1e-6;
/// Largest total reflectance `(kd + ks)·(1 − t) + t` that counts as 1: a surface that reflects
/// all it receives can sum to a hair above 1 in `f32` (`0.7 + 0.3`).
pub const MAX_ALBEDO: f32 = 1.0 + 1e-6;
/// Most photons one light may emit for one map: 10^9 stored photons would need 20 GB, most of
/// a workstation's memory. Script counts, `--photons` and `--photon-scale` are checked against
/// it.
pub const MAX_PHOTONS: u64 = 1_000_000_000;

/// Returns the message for a point with a coordinate outside `±MAX_COORDINATE`, if it has one.
pub fn coordinate<T: Copy + Into<f64> + Display + LowerExp>(p: [T; 3]) -> Result<(), String> {
    match p
        .iter()
        .find(|&&x| !(-MAX_COORDINATE..=MAX_COORDINATE).contains(&x.into()))
    {
        Some(&x) => Err(format!(
            "coordinate {} is outside the renderer's range [-{}, {}]",
            show_value(x),
            show(MAX_COORDINATE),
            show(MAX_COORDINATE)
        )),
        None => Ok(()),
    }
}

/// Returns the message for a value of `what` outside `[0, max]`, if one of `values` is.
pub fn within<T: Copy + Into<f64> + Display + LowerExp>(
    values: &[T],
    what: &str,
    max: f64,
) -> Result<(), String> {
    match values.iter().find(|&&x| !(0.0..=max).contains(&x.into())) {
        Some(&x) => Err(format!(
            "{what} {} is outside [0, {}]",
            show_value(x),
            show(max)
        )),
        None => Ok(()),
    }
}

/// Returns the message for a material of diffuse and mirror reflectances `kd`, `ks` and
/// transparency `t` that reflects more light than it receives (its total
/// `(kd + ks)·(1 − t) + t` above [`MAX_ALBEDO`] in some channel), if it does.
pub fn excess_albedo(kd: [f32; 3], ks: [f32; 3], t: f32) -> Option<String> {
    let total = |c: usize| (kd[c] + ks[c]) * (1.0 - t) + t;
    let c = (1..3).fold(0, |best, c| if total(c) > total(best) { c } else { best });
    if total(c) <= MAX_ALBEDO {
        return None;
    }
    let what = if t > 0.0 {
        "(kd + ks)·(1 − t) + t"
    } else {
        "kd + ks"
    };
    // Six decimals show what was written (`1.7`, not the `f32` sum 1.7000000476837158).
    let shown = (f64::from(total(c)) * 1e6).round() / 1e6;
    Some(format!(
        "{what} reaches {shown} ({}), above 1: the surface reflects more light than it \
         receives; photon paths keep their power instead of growing",
        ["red", "green", "blue"][c]
    ))
}

/// Returns a bound as people write it: `10`, `1e8`, `1e-6`.
pub fn show(x: f64) -> String {
    show_value(x)
}

/// Returns a value in its own precision as people write it: `0.5`, `-2e30`, `NaN`.
fn show_value<T: Copy + Into<f64> + Display + LowerExp>(x: T) -> String {
    let magnitude = x.into().abs();
    if (1e-3..1e4).contains(&magnitude) || magnitude == 0.0 || !magnitude.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_name_the_value_and_the_bounds() {
        assert_eq!(coordinate([0.0f32, -1e8, 1e8]), Ok(()));
        assert_eq!(
            coordinate([0.0f64, 2e8, 0.0]).unwrap_err(),
            "coordinate 2e8 is outside the renderer's range [-1e8, 1e8]"
        );
        assert!(coordinate([f32::NAN, 0.0, 0.0]).is_err());
        assert_eq!(within(&[0.5f32, 10.0], "kd", 10.0), Ok(()));
        assert_eq!(
            within(&[0.5f32, 11.0], "kd", 10.0).unwrap_err(),
            "kd 11 is outside [0, 10]"
        );
    }

    /// A material warns when `kd + ks` (weighted by `1 − t`, plus `t`) passes 1 in a channel,
    /// naming the largest total and its channel; sums of exactly 1 in decimal, which round to a
    /// hair above 1 in `f32`, do not.
    #[test]
    fn materials_that_reflect_more_than_they_receive_are_named() {
        let warned = excess_albedo([1.2, 0.5, 0.5], [0.5, 0.5, 0.5], 0.0).unwrap();
        assert!(
            warned.starts_with("kd + ks reaches 1.7 (red), above 1"),
            "{warned}"
        );
        let warned = excess_albedo([0.5, 0.5, 1.0], [0.5, 0.5, 0.5], 0.5).unwrap();
        assert!(
            warned.starts_with("(kd + ks)·(1 − t) + t reaches 1.25 (blue), above 1"),
            "{warned}"
        );
        for (kd, ks, t) in [
            ([0.6, 0.2, 0.1], [0.3, 0.3, 0.3], 0.0),
            ([0.7, 0.7, 0.7], [0.3, 0.3, 0.3], 0.0),
            ([0.1, 0.2, 0.6], [0.9, 0.8, 0.4], 0.3),
            ([5.0, 5.0, 5.0], [5.0, 5.0, 5.0], 1.0),
        ] {
            assert_eq!(excess_albedo(kd, ks, t), None, "{kd:?} {ks:?} {t}");
        }
    }
}
