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
//! | light `power` | `[0, 1e30]` ([`MAX_POWER`]) | only a weight among lights: the sum over many lights must stay finite |
//! | sphere-light radius, area-light size `√|u × v|` | `≥ 1e-6` ([`MIN_LIGHT_SIZE`]) | an emitter's radiance is `rgb/R²` (`π·rgb/area`): a radius of `1e-30` was infinite |
//! | photons one light emits for one map (`num_photons`, its share of `--photons`, times `--photon-scale`) | `≤ 1e9` ([`MAX_PHOTONS`]) | 10^9 stored photons would need 20 GB |
//!
//! A reflectance above 1 amplifies light at every bounce: a path between two facing mirrors of
//! `ks = 1.5` grows as `1.5ⁿ` and no finite bound above 1 keeps every path finite. Such values are
//! accepted (the course's scenes use them for bright highlights), and a sample that still
//! overflows is dropped and counted (`--stats`: "NaN or infinite samples dropped"), never
//! written to the image.

use std::fmt::{Display, LowerExp};

/// Largest magnitude of a coordinate or a length, in object or world space.
pub const MAX_COORDINATE: f64 = 1e8;
/// Largest light colour (head-on intensity) or ambient light, per channel.
pub const MAX_INTENSITY: f64 = 1e8;
/// Largest diffuse or specular reflectance, per channel.
pub const MAX_REFLECTANCE: f64 = 10.0;
/// Smallest non-zero falloff coefficient.
pub const MIN_FALLOFF: f64 = 1e-6;
/// Largest falloff coefficient.
pub const MAX_FALLOFF: f64 = 1e6;
/// Largest light power (the photon budget's weight).
pub const MAX_POWER: f64 = 1e30;
/// Smallest sphere-light radius, and smallest square root of an area light's area.
pub const MIN_LIGHT_SIZE: f64 = 1e-6;
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
}
