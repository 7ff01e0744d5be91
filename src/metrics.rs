//! Image error metrics: one image against a reference, as `caustic diff` prints them and the
//! validation (`tools/validate/run.py`) computes them.
//!
//! Over all three channels of a region (a window in pixels):
//! - *mean ratio*: the image's mean over the reference's;
//! - *mean error*: the difference of the means over the reference's mean (signed);
//! - *RMSE*, and *relative RMSE* over the reference's mean;
//! - *block bias*: the RMS of the differences of the means of the 8x8-pixel blocks (aligned to
//!   the image, wholly inside the region) over the reference's mean. Pixel noise averages out in
//!   a block's mean and bias does not, so it separates the two (a density estimate's noise is
//!   correlated over its kernel and partly survives).
//!
//! With a second, independent reference ([`Metrics::against_two`]) every squared difference
//! `(a - r)²` becomes the product `(a - r1)(a - r2)`, whose expectation is the squared error
//! against the truth: the references' own noise drops out rather than adding to the error.

use glam::Vec3A;

/// A linear RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3A>,
}

impl Image {
    fn get(&self, x: u32, y: u32) -> Vec3A {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Returns how many pixels of `region` have a channel that is NaN or infinite, and the
    /// first of them in row order, or `None` when every value there is finite: the metrics of
    /// such an image mean nothing (a NaN even reads as an RMSE of 0).
    pub fn non_finite(&self, region: Region) -> Option<(u64, (u32, u32))> {
        let mut found = None;
        let mut count = 0u64;
        for y in region.y0..region.y1 {
            for x in region.x0..region.x1 {
                if !self.get(x, y).is_finite() {
                    count += 1;
                    found.get_or_insert((x, y));
                }
            }
        }
        found.map(|first| (count, first))
    }
}

/// A window of pixels `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Region {
    /// The whole of a `width × height` image.
    pub fn full(width: u32, height: u32) -> Region {
        Region {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
}

/// The metrics of one image against a reference over one region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub mean_ratio: f64,
    pub mean_error: f64,
    pub rmse: f64,
    pub rel_rmse: f64,
    /// NaN when no whole 8x8 block lies in the region.
    pub block_bias: f64,
    /// The reference's mean over the region.
    pub ref_mean: f64,
}

/// Block size of [`Metrics::block_bias`].
pub const BLOCK: u32 = 8;

impl Metrics {
    /// Returns `a`'s metrics against `r` over `region` (images of the same size).
    pub fn against(a: &Image, r: &Image, region: Region) -> Metrics {
        Metrics::against_two(a, r, r, region)
    }

    /// Returns `a`'s metrics against the truth as estimated from two independent references
    /// `r1` and `r2` (see the module doc; with `r1 == r2` this is [`Metrics::against`]).
    pub fn against_two(a: &Image, r1: &Image, r2: &Image, region: Region) -> Metrics {
        let Region { x0, y0, x1, y1 } = region;
        let (mut sa, mut sr, mut sq, mut n) = (0.0f64, 0.0f64, 0.0f64, 0u64);
        for y in y0..y1 {
            for x in x0..x1 {
                let (p, q1, q2) = (a.get(x, y), r1.get(x, y), r2.get(x, y));
                for c in 0..3 {
                    let (p, q1, q2) = (p[c] as f64, q1[c] as f64, q2[c] as f64);
                    sa += p;
                    sr += 0.5 * (q1 + q2);
                    sq += (p - q1) * (p - q2);
                    n += 1;
                }
            }
        }
        let n = n.max(1) as f64;
        let (mean_a, mean_r) = (sa / n, sr / n);
        let rmse = (sq / n).max(0.0).sqrt();
        let block_bias = block_cross(a, a, r1, r2, region) / mean_r;
        Metrics {
            mean_ratio: mean_a / mean_r,
            mean_error: (mean_a - mean_r) / mean_r,
            rmse,
            rel_rmse: rmse / mean_r,
            block_bias,
            ref_mean: mean_r,
        }
    }
}

/// Returns the block error between two independent renders `a1` and `a2` of the same setting
/// and two references over `region`: the root of the mean over the 8x8 blocks of
/// `(a1 − r1)(a2 − r2)` of the block means, over the references' mean. Its expectation is the
/// squared bias of the blocks: the renders' noise and the references' drop out (NaN without a
/// whole block in the region).
pub fn pair_block_bias(a1: &Image, a2: &Image, r1: &Image, r2: &Image, region: Region) -> f64 {
    let ref_mean = Metrics::against_two(r1, r1, r2, region).ref_mean;
    block_cross(a1, a2, r1, r2, region) / ref_mean
}

/// Returns the root of the mean over the 8x8 blocks wholly inside `region` of
/// `(m(a1) − m(r1))(m(a2) − m(r2))`, `m` a block's mean over its pixels and channels (NaN
/// without a whole block; negative means clamped to zero).
fn block_cross(a1: &Image, a2: &Image, r1: &Image, r2: &Image, region: Region) -> f64 {
    let Region { x0, y0, x1, y1 } = region;
    let mut blocks = (0.0f64, 0u64);
    let block_mean = |img: &Image, bx: u32, by: u32| {
        let mut s = 0.0f64;
        for y in by..by + BLOCK {
            for x in bx..bx + BLOCK {
                s += img.get(x, y).element_sum() as f64;
            }
        }
        s / (3 * BLOCK * BLOCK) as f64
    };
    let first = |v: u32| v.div_ceil(BLOCK) * BLOCK;
    let mut by = first(y0);
    while by + BLOCK <= y1 {
        let mut bx = first(x0);
        while bx + BLOCK <= x1 {
            blocks.0 += (block_mean(a1, bx, by) - block_mean(r1, bx, by))
                * (block_mean(a2, bx, by) - block_mean(r2, bx, by));
            blocks.1 += 1;
            bx += BLOCK;
        }
        by += BLOCK;
    }
    if blocks.1 == 0 {
        f64::NAN
    } else {
        (blocks.0 / blocks.1 as f64).max(0.0).sqrt()
    }
}

/// Returns a false-colour picture of `a - r`: red where `a` is brighter, blue where darker, at
/// `gain` times the contrast relative to the reference's 99th-percentile luminance, as 8-bit RGB.
pub fn difference_image(a: &Image, r: &Image, gain: f32) -> Vec<u8> {
    let mut lum: Vec<f32> = r.pixels.iter().map(|p| p.element_sum() / 3.0).collect();
    lum.sort_by(f32::total_cmp);
    let scale = lum
        .get(((lum.len() as f64 * 0.99) as usize).min(lum.len().saturating_sub(1)))
        .copied()
        .unwrap_or(1.0)
        .max(1e-9);
    let mut out = Vec::with_capacity(a.pixels.len() * 3);
    for (p, q) in a.pixels.iter().zip(&r.pixels) {
        let d = (*p - *q).element_sum() / 3.0 / scale * gain;
        let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0) as u8;
        out.extend([to8(d), to8(d.abs() * 0.2), to8(-d)]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Image {
        let pixels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| Vec3A::splat(f(x, y)))
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    #[test]
    fn a_uniform_offset_is_its_own_mean_error_rmse_and_block_bias() {
        let r = image(16, 16, |_, _| 2.0);
        let a = image(16, 16, |_, _| 2.5);
        let m = Metrics::against(&a, &r, Region::full(16, 16));
        assert!((m.mean_ratio - 1.25).abs() < 1e-12);
        assert!((m.mean_error - 0.25).abs() < 1e-12);
        assert!((m.rmse - 0.5).abs() < 1e-12);
        assert!((m.rel_rmse - 0.25).abs() < 1e-12);
        assert!((m.block_bias - 0.25).abs() < 1e-12);
    }

    #[test]
    fn zero_mean_pixel_noise_averages_out_of_the_block_bias() {
        // A checkerboard of ±1 on a reference of 4: every 8x8 block's mean is exact.
        let r = image(16, 16, |_, _| 4.0);
        let a = image(16, 16, |x, y| if (x + y) % 2 == 0 { 5.0 } else { 3.0 });
        let m = Metrics::against(&a, &r, Region::full(16, 16));
        assert!((m.rmse - 1.0).abs() < 1e-12);
        assert!(m.block_bias.abs() < 1e-12);
        assert!((m.mean_ratio - 1.0).abs() < 1e-12);
    }

    #[test]
    fn two_references_remove_their_own_noise() {
        // The truth is 1; the references err by ±0.1 in patterns that are uncorrelated with
        // each other (by column parity and by row parity) and average to zero; the image errs
        // by +0.2 everywhere. Against the truth its RMSE is exactly 0.2; against one reference
        // the reference's noise adds in quadrature: sqrt(0.2² + 0.1²).
        let sign = |v: u32| if v.is_multiple_of(2) { 1.0 } else { -1.0 };
        let r1 = image(8, 8, |x, _| 1.0 + 0.1 * sign(x));
        let r2 = image(8, 8, |_, y| 1.0 + 0.1 * sign(y));
        let a = image(8, 8, |_, _| 1.2);
        let m = Metrics::against_two(&a, &r1, &r2, Region::full(8, 8));
        assert!((m.rmse - 0.2).abs() < 1e-6, "{m:?}");
        let one = Metrics::against(&a, &r1, Region::full(8, 8));
        assert!((one.rmse - 0.05f64.sqrt()).abs() < 1e-6, "{one:?}");
    }

    #[test]
    fn blocks_lie_wholly_inside_the_region() {
        // A 12-wide region from x = 2 holds no aligned block of 8 (8..16 ends past 14).
        let r = image(16, 16, |_, _| 1.0);
        let region = Region {
            x0: 2,
            y0: 0,
            x1: 14,
            y1: 16,
        };
        assert!(Metrics::against(&r, &r, region).block_bias.is_nan());
    }
}
