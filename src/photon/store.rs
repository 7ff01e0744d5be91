//! Quantisation of the per-photon data that a search never reads: power and the two directions.
//!
//! - **Power** ([`PowerCodec`]): one `u32` per photon, a shared-exponent format with 9-bit
//!   mantissas (bits 0–8 red, 9–17 green, 18–26 blue) and a 5-bit exponent (bits 27–31) counted
//!   from a per-map base exponent, so the 32 exponents cover the 2^31 range below the map's
//!   brightest photon. Mantissas are rounded to nearest: every channel is within 2^-9 (0.2 %) of
//!   the photon's largest channel, which is itself within 2^-9 relative (Ward's RGBE with rounding:
//!   2^-8). Photons more than 2^31 times dimmer than the brightest underflow gradually (absolute
//!   error at most 2^-40 of the brightest photon's largest channel).
//! - **Directions** ([`encode_code`]): the incident direction and the surface normal share one
//!   `u32` with the kd-tree split axis and the `direct` flag. Each direction is an octahedral map
//!   point (Meyer et al. 2010; Cigolle et al. 2014) on a 151 × 151 grid whose rows and columns
//!   include -1, 0 and 1, so the six axis directions (a floor's normal) decode exactly. The grid
//!   point is chosen among the four around the projection by the smallest angle ("precise"
//!   encoding), which bounds the angular error at [`MAX_ANGLE_ERROR_DEG`]. The two grid indices are
//!   packed in mixed radix, `dir * 151² + normal < 2^29`, in bits 0–28; bits 29–30 hold the split
//!   axis (0 = x, 1 = y, 2 = z, 3 = none: a leaf-bucket photon) and bit 31 the `direct` flag.
//!
//! Decoded directions are unit vectors. Inputs that are not finite or have no length encode as +z;
//! a negative, NaN or infinite power channel encodes as 0 (both are tracer bugs: debug builds assert).

use glam::Vec3A;

/// Grid points per axis of the octahedral map; odd, so that 0 lies on the grid.
const OCT_N: u32 = 151;
/// Number of codes per direction.
const OCT_CELLS: u32 = OCT_N * OCT_N;
/// Bit offset of the split axis in a code word.
const AXIS_SHIFT: u32 = 29;
/// Split-axis value of photons in a leaf bucket (no split plane).
pub(super) const AXIS_NONE: u32 = 3;
/// The `direct` flag in a code word.
const DIRECT_BIT: u32 = 1 << 31;
/// The bits of a code word holding the two directions.
const DIRS_MASK: u32 = (1 << AXIS_SHIFT) - 1;

/// Bounds the angle between a unit vector and its decoded code, in degrees (the round-trip test
/// measures 1.07° over 10^6 random directions, worst near the centres of the octahedron's faces,
/// where the map stretches most; a 7+7-bit octahedral grid is 1.17× coarser).
pub const MAX_ANGLE_ERROR_DEG: f32 = 1.1;
/// Bounds the error of each decoded power channel relative to the photon's largest channel.
pub const MAX_POWER_REL_ERROR: f32 = 1.0 / 512.0;

/// Returns the octahedral projection of a unit vector onto [-1, 1]², with z as the pole.
fn oct_project(v: Vec3A) -> (f32, f32) {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    let (x, y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        (
            (1.0 - y.abs()).copysign(x.signum()),
            (1.0 - x.abs()).copysign(y.signum()),
        )
    } else {
        (x, y)
    }
}

/// Returns a (not unit) vector along grid point `(i, j)` of the octahedral map.
fn oct_point(i: u32, j: u32) -> Vec3A {
    let half = (OCT_N - 1) as i32;
    let u = (2 * i as i32 - half) as f32 / half as f32;
    let v = (2 * j as i32 - half) as f32 / half as f32;
    let z = 1.0 - u.abs() - v.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - v.abs()).copysign(u.signum()),
            (1.0 - u.abs()).copysign(v.signum()),
        )
    } else {
        (u, v)
    };
    Vec3A::new(x, y, z)
}

/// Returns the grid index (`i * OCT_N + j`) of the direction closest to `v` by angle.
fn oct_encode(v: Vec3A) -> u32 {
    let v = v.try_normalize().unwrap_or(Vec3A::Z);
    let (u, w) = oct_project(v);
    let scale = (OCT_N - 1) as f32 * 0.5;
    let top = OCT_N - 1;
    // The projection is in [-1, 1], so truncation is the floor.
    let i0 = (((u + 1.0) * scale) as u32).min(top);
    let j0 = (((w + 1.0) * scale) as u32).min(top);
    let mut best = (f32::NEG_INFINITY, 0);
    for i in [i0, (i0 + 1).min(top)] {
        for j in [j0, (j0 + 1).min(top)] {
            let c = oct_point(i, j);
            let cos = c.dot(v) / c.length();
            if cos > best.0 {
                best = (cos, i * OCT_N + j);
            }
        }
    }
    best.1
}

/// Returns the unit vector of a grid index made by [`oct_encode`], computed afresh.
fn oct_decode_slow(index: u32) -> Vec3A {
    oct_point(index / OCT_N, index % OCT_N).normalize()
}

/// The unit vector of every grid index ([`oct_decode_slow`] of each), 365 KB made once: a
/// density estimate decodes two directions per photon it weighs, and a table read costs a
/// fraction of the divisions and the square root (`kernel_sum` was 10% of the final scene's
/// render time).
static OCT_TABLE: std::sync::LazyLock<Box<[Vec3A]>> =
    std::sync::LazyLock::new(|| (0..OCT_CELLS).map(oct_decode_slow).collect());

/// Returns the unit vector of a grid index made by [`oct_encode`].
#[inline]
fn oct_decode_index(index: u32) -> Vec3A {
    OCT_TABLE[index as usize]
}

/// Returns the code word of a photon's incident direction, surface normal and `direct` flag,
/// with the split axis set to [`AXIS_NONE`].
pub(super) fn encode_code(dir: Vec3A, normal: Vec3A, direct: bool) -> u32 {
    debug_assert!(dir.is_finite() && normal.is_finite(), "{dir} {normal}");
    let dirs = oct_encode(dir) * OCT_CELLS + oct_encode(normal);
    dirs | (AXIS_NONE << AXIS_SHIFT) | if direct { DIRECT_BIT } else { 0 }
}

/// Returns `(dir, normal, direct)` decoded from a code word.
pub(super) fn decode_code(code: u32) -> (Vec3A, Vec3A, bool) {
    let dirs = code & DIRS_MASK;
    (
        oct_decode_index(dirs / OCT_CELLS),
        oct_decode_index(dirs % OCT_CELLS),
        code & DIRECT_BIT != 0,
    )
}

/// Returns the surface normal of a code word (the second half of [`decode_code`]).
pub(super) fn decode_normal(code: u32) -> Vec3A {
    oct_decode_index((code & DIRS_MASK) % OCT_CELLS)
}

/// Returns the split axis of a code word (0 = x, 1 = y, 2 = z, [`AXIS_NONE`] = no split).
#[inline(always)]
pub(super) fn code_axis(code: u32) -> u32 {
    (code >> AXIS_SHIFT) & 3
}

/// Returns `code` with its split axis replaced by `axis`.
pub(super) fn with_axis(code: u32, axis: u32) -> u32 {
    debug_assert!(axis <= AXIS_NONE);
    (code & !(3 << AXIS_SHIFT)) | (axis << AXIS_SHIFT)
}

/// Returns whether a code word's direction bits are a valid mixed-radix pair.
pub(super) fn code_is_valid(code: u32) -> bool {
    code & DIRS_MASK < OCT_CELLS * OCT_CELLS
}

/// The smallest power base exponent of a map with power: the base of one whose brightest
/// photon is the smallest `f32`, 2^-149 W (its exponent -148, less 31).
pub(super) const MIN_BASE: i32 = -179;
/// The largest power base exponent a map read from a file may have: its brightest photon is
/// then below 2^(33 + 31) = 2^64 W (1.8e19 W), so that a density estimate's sum of many such
/// photons over a small disc, times a BSDF, stays far inside `f32` (2^128). A photon that bright
/// would take a light of more than 10^19 W per photon traced.
pub(super) const MAX_BASE: i32 = 33;

/// The shared-exponent power format of one photon map: 32 exponents counted up from a base.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct PowerCodec {
    /// Exponent of stored exponent 0: a photon with stored exponent `E` has quantum
    /// `2^(base + E - 9)` and its largest channel below `2^(base + E)`.
    base: i32,
    /// `2^(base + E - 9)` for each stored exponent `E`, the factor that decodes a mantissa.
    scale: [f32; 32],
}

/// Returns the channels of a power with negative, NaN and infinite values replaced by 0.
fn sanitise_power(p: Vec3A) -> [f64; 3] {
    debug_assert!(p.is_finite() && p.min_element() >= 0.0, "photon power {p}");
    p.to_array().map(|c| {
        if c.is_finite() && c > 0.0 {
            c as f64
        } else {
            0.0
        }
    })
}

/// Returns the smallest `e` with `m < 2^e`, for a finite `m > 0`.
fn exponent_above(m: f64) -> i32 {
    let biased = ((m.to_bits() >> 52) & 0x7ff) as i32;
    biased - 1023 + 1
}

/// Returns `2^e` for `|e| < 1000`.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// Returns the exponent a power needs after rounding its mantissas (`i32::MIN` for zero power).
///
/// Read off the largest channel's bits: a non-negative finite float orders as its bits, its
/// exponent field gives the smallest `e` with `m < 2^e`, and its mantissa rounds up to 512
/// quanta of `2^(e - 9)` (so it needs `e + 1`) exactly when the top nine of its 23 fraction bits
/// are all set (`256 (1 + f / 2^23) + 0.5 >= 512`). Equal to [`power_exponent_f64`] for every
/// power (a test compares them); subnormal channels take that path. Every photon of a map
/// calls this twice, for its block's tally and for its encode: with the f64 division it took
/// 15 ns a photon.
#[inline]
pub(super) fn power_exponent(p: Vec3A) -> i32 {
    debug_assert!(p.is_finite() && p.min_element() >= 0.0, "photon power {p}");
    // Negative (sign bit), NaN and infinite channels count as 0, as in `sanitise_power`.
    let bits = p.to_array().map(|c| {
        if c.to_bits() < 0x7f80_0000 {
            c.to_bits()
        } else {
            0
        }
    });
    let m = bits[0].max(bits[1]).max(bits[2]);
    if m < 0x0080_0000 {
        return power_exponent_f64(p); // zero or subnormal
    }
    let e = (m >> 23) as i32 - 126;
    const TOP_NINE: u32 = 0x007f_c000;
    if m & TOP_NINE == TOP_NINE { e + 1 } else { e }
}

/// [`power_exponent`] in f64 arithmetic, the definition.
fn power_exponent_f64(p: Vec3A) -> i32 {
    let m = sanitise_power(p).into_iter().fold(0.0, f64::max);
    if m == 0.0 {
        return i32::MIN;
    }
    let e = exponent_above(m);
    // A largest channel that rounds up to 512 quanta needs the next exponent.
    if m / pow2(e - 9) + 0.5 >= 512.0 {
        e + 1
    } else {
        e
    }
}

impl PowerCodec {
    /// Returns the codec for a map whose largest [`power_exponent`] is `max_exponent`.
    pub(super) fn new(max_exponent: i32) -> PowerCodec {
        let base = if max_exponent == i32::MIN {
            0
        } else {
            max_exponent.clamp(-1000 + 40, 1000) - 31
        };
        let scale = std::array::from_fn(|e| pow2(base + e as i32 - 9) as f32);
        PowerCodec { base, scale }
    }

    /// Returns the codec whose stored exponent 0 is `base` ([`PowerCodec::base`]), or None for
    /// a base no map has (a damaged file).
    pub(super) fn from_base(base: i32) -> Option<PowerCodec> {
        (base == 0 || (-1000 + 40 - 31..=1000 - 31).contains(&base)).then(|| {
            let scale = std::array::from_fn(|e| pow2(base + e as i32 - 9) as f32);
            PowerCodec { base, scale }
        })
    }

    /// Returns the exponent of stored exponent 0.
    pub(super) fn base(&self) -> i32 {
        self.base
    }

    /// Returns the 32-bit code of a power (each channel rounded to nearest).
    pub(super) fn encode(&self, p: Vec3A) -> u32 {
        let c = sanitise_power(p);
        let e = power_exponent(p).clamp(self.base, self.base + 31);
        // Rounds half up; channels are not negative. `x * 2^(9 - e)` is `x / 2^(e - 9)` exactly
        // (both round the same real number; |e| < 1000, so both powers are normal f64).
        let inv_q = pow2(9 - e);
        let m = c.map(|x| ((x * inv_q + 0.5) as u32).min(511));
        m[0] | (m[1] << 9) | (m[2] << 18) | (((e - self.base) as u32) << 27)
    }

    /// Returns an error naming the first photon whose power code `words[i]` this map could not
    /// have written, or whose power the renderer cannot use: see [`MIN_BASE`] and
    /// [`MAX_BASE`] for the base, and the encoder's invariants for the codes: a code with a
    /// stored exponent above 0 has a largest mantissa of at least 256 (it is normalised:
    /// only photons dimmer than the base underflow to exponent 0), the map's brightest photon
    /// has stored exponent 31, and a map whose codes are all 0 has base 0.
    pub(super) fn validate(&self, words: &[u32]) -> Result<(), String> {
        let mantissa = |w: u32| (w & 511).max((w >> 9) & 511).max((w >> 18) & 511);
        if words.iter().all(|&w| w == 0) {
            return match self.base {
                0 => Ok(()),
                b => Err(format!(
                    "power base exponent {b}, but every photon's power is 0"
                )),
            };
        }
        if !(MIN_BASE..=MAX_BASE).contains(&self.base) {
            return Err(format!(
                "power base exponent {} (a map's is in [{MIN_BASE}, {MAX_BASE}]: its brightest \
                 photon between 2^-149 W and 2^64 W)",
                self.base
            ));
        }
        if let Some(i) = words.iter().position(|&w| w >> 27 > 0 && mantissa(w) < 256) {
            return Err(format!(
                "photon {i}'s power code {:#010x} is not normalised",
                words[i]
            ));
        }
        if !words.iter().any(|&w| w >> 27 == 31) {
            return Err("no photon has the map's top power exponent (31)".into());
        }
        Ok(())
    }

    /// Returns the power a 32-bit code stands for.
    pub(super) fn decode(&self, code: u32) -> Vec3A {
        let s = self.scale[(code >> 27) as usize];
        Vec3A::new(
            (code & 511) as f32,
            ((code >> 9) & 511) as f32,
            ((code >> 18) & 511) as f32,
        ) * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    fn random_unit(r: &mut Rng) -> Vec3A {
        let z = 2.0 * r.next_f32() - 1.0;
        let phi = std::f32::consts::TAU * r.next_f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3A::new(s * phi.cos(), s * phi.sin(), z)
    }

    fn angle_deg(a: Vec3A, b: Vec3A) -> f32 {
        // atan2 of |a×b| and a·b is accurate at small angles, unlike acos.
        a.cross(b).length().atan2(a.dot(b)).to_degrees()
    }

    /// The bit-level exponent equals the f64 definition: on random bit patterns of every
    /// exponent, on mantissas either side of the rounding threshold, on subnormals, zeros,
    /// negative, NaN and infinite channels; and the encode with the reciprocal equals the
    /// encode that divides.
    #[test]
    fn power_exponent_from_bits_equals_the_f64_definition() {
        let mut r = Rng::new(3, Pass::Photon, 0);
        let mut channels: Vec<f32> = (0..200_000).map(|_| f32::from_bits(r.next_u32())).collect();
        for exp in 0..=255u32 {
            for frac in [0, 1, 0x7f_bfff, 0x7f_c000, 0x7f_c001, 0x7f_ffff, 0x40_0000] {
                channels.push(f32::from_bits(exp << 23 | frac));
            }
        }
        channels.extend([0.0, -0.0, f32::MIN_POSITIVE, 1e-45, f32::MAX, 511.5 / 256.0]);
        // Powers with NaN or infinite channels are outside the debug assertion's domain.
        let finite = |c: f32| {
            if cfg!(debug_assertions) && !c.is_finite() {
                0.0
            } else {
                c
            }
        };
        let (mut checked, mut rounded_up) = (0, 0);
        for (k, &c) in channels.iter().enumerate() {
            let others = [channels[(k * 7 + 3) % channels.len()], 0.0];
            for p in [
                Vec3A::new(c, 0.0, 0.0),
                Vec3A::new(0.0, c, c * 0.5),
                Vec3A::new(others[0], c, others[1]),
            ] {
                let p = Vec3A::from_array(p.to_array().map(finite));
                let p = if cfg!(debug_assertions) {
                    p.max(Vec3A::ZERO)
                } else {
                    p
                };
                let (fast, exact) = (power_exponent(p), power_exponent_f64(p));
                assert_eq!(fast, exact, "{:?}", p.to_array().map(f32::to_bits));
                checked += 1;
                let m = sanitise_power(p).into_iter().fold(0.0, f64::max);
                rounded_up += (m > 0.0 && exact > exponent_above(m)) as u32;
                if exact != i32::MIN {
                    let codec = PowerCodec::new(exact);
                    let divided = {
                        let e = exact.clamp(codec.base, codec.base + 31);
                        let q = pow2(e - 9);
                        let m = sanitise_power(p).map(|x| ((x / q + 0.5) as u32).min(511));
                        m[0] | (m[1] << 9) | (m[2] << 18) | (((e - codec.base) as u32) << 27)
                    };
                    assert_eq!(codec.encode(p), divided, "{p}");
                }
            }
        }
        assert!(
            checked > 600_000 && rounded_up > 1000,
            "{checked} {rounded_up}"
        );
    }

    #[test]
    fn axis_directions_decode_exactly() {
        for v in [
            Vec3A::X,
            Vec3A::Y,
            Vec3A::Z,
            Vec3A::NEG_X,
            Vec3A::NEG_Y,
            Vec3A::NEG_Z,
        ] {
            assert_eq!(oct_decode_index(oct_encode(v)), v);
        }
    }

    #[test]
    fn the_decode_table_holds_every_index_decoded_afresh() {
        assert_eq!(OCT_TABLE.len(), OCT_CELLS as usize);
        for i in 0..OCT_CELLS {
            let (fresh, table) = (oct_decode_slow(i), oct_decode_index(i));
            assert_eq!(
                fresh.to_array().map(f32::to_bits),
                table.to_array().map(f32::to_bits),
                "{i}"
            );
        }
    }

    #[test]
    fn directions_round_trip_within_the_stated_angle() {
        let mut r = Rng::new(1, Pass::Photon, 0);
        let mut worst = 0.0f32;
        let mut dirs: Vec<Vec3A> = (0..1_000_000).map(|_| random_unit(&mut r)).collect();
        // The octahedron's edges and the fold (z = 0) are where the map is most stretched.
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            for s in [1.0, -1.0] {
                dirs.push(Vec3A::new(t, 1.0 - t, 0.0).normalize() * s);
                dirs.push(Vec3A::new(t, 0.0, (1.0 - t) * s).normalize());
                dirs.push(Vec3A::new(-t, t - 1.0, 1e-3 * s).normalize());
            }
        }
        for v in dirs {
            worst = worst.max(angle_deg(oct_decode_index(oct_encode(v)), v));
        }
        assert!(worst <= MAX_ANGLE_ERROR_DEG, "worst angle {worst}°");
        assert!(
            worst > 0.5 * MAX_ANGLE_ERROR_DEG,
            "bound is loose: {worst}°"
        );
    }

    #[test]
    fn code_words_keep_axis_flag_and_both_directions() {
        let mut r = Rng::new(2, Pass::Photon, 0);
        for i in 0..10_000 {
            let (d, n, direct) = (random_unit(&mut r), random_unit(&mut r), i % 2 == 0);
            let code = encode_code(d, n, direct);
            assert_eq!(code_axis(code), AXIS_NONE);
            for axis in 0..=AXIS_NONE {
                let c = with_axis(code, axis);
                assert!(code_is_valid(c));
                assert_eq!(code_axis(c), axis);
                let (d2, n2, f2) = decode_code(c);
                assert_eq!(f2, direct);
                assert!(angle_deg(d2, d) <= MAX_ANGLE_ERROR_DEG);
                assert!(angle_deg(n2, n) <= MAX_ANGLE_ERROR_DEG);
                let (d0, n0, _) = decode_code(code);
                assert_eq!((d2, n2), (d0, n0));
            }
        }
    }

    #[test]
    fn degenerate_directions_encode_as_plus_z() {
        assert_eq!(oct_decode_index(oct_encode(Vec3A::ZERO)), Vec3A::Z);
    }

    #[test]
    fn power_round_trips_within_the_stated_error() {
        let mut r = Rng::new(3, Pass::Photon, 0);
        let powers: Vec<Vec3A> = (0..100_000)
            .map(|_| {
                let scale = 2f32.powf(-20.0 * r.next_f32()) * 1e-6;
                Vec3A::new(r.next_f32(), r.next_f32(), r.next_f32()) * scale
            })
            .chain([
                Vec3A::new(1e-6, 0.0, 0.0),
                Vec3A::new(1e-6, 1e-6, 1e-6),
                Vec3A::new(0.9999999e-6, 0.0, 5e-7),
            ])
            .collect();
        let codec = PowerCodec::new(powers.iter().map(|&p| power_exponent(p)).max().unwrap());
        for p in powers {
            let d = codec.decode(codec.encode(p));
            let err = (d - p).abs().max_element() / p.max_element();
            assert!(err <= MAX_POWER_REL_ERROR, "{p} -> {d}: {err}");
        }
    }

    #[test]
    fn zero_and_bad_power_encode_as_zero() {
        let codec = PowerCodec::new(power_exponent(Vec3A::ONE));
        assert_eq!(codec.decode(codec.encode(Vec3A::ZERO)), Vec3A::ZERO);
        let empty = PowerCodec::new(i32::MIN);
        assert_eq!(empty.decode(empty.encode(Vec3A::ZERO)), Vec3A::ZERO);
        // Debug builds assert on these; release builds store them as black.
        if !cfg!(debug_assertions) {
            for bad in [f32::NAN, f32::INFINITY, -1.0] {
                let p = Vec3A::new(bad, 0.5, 0.25);
                let d = codec.decode(codec.encode(p));
                assert_eq!(d.x, 0.0);
                assert!((d.y - 0.5).abs() < 1e-3 && (d.z - 0.25).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn very_dim_photons_underflow_gradually() {
        let codec = PowerCodec::new(power_exponent(Vec3A::ONE));
        let dim = Vec3A::splat(1e-12);
        let d = codec.decode(codec.encode(dim));
        assert!((d - dim).abs().max_element() <= 2f32.powi(-40));
    }
}
