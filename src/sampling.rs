//! Deterministic random streams, keyed by what they are for rather than by who draws them.
//!
//! Every stream is identified by `(seed, pass, index)`: the `--seed`, a [`Pass`] naming the use
//! (pixel samples, photon emission, …) and the pixel or photon index. Streams never depend on the
//! thread that draws them or on time, so an image is bit-identical for any thread count, and a
//! tile rendered alone equals the same tile of a full render.
//!
//! The generator is PCG32 (O'Neill 2014; pbrt-v4's `RNG`), seeded by a 64-bit mix of the key.

/// What a random stream is used for; part of every stream's key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u64)]
pub enum Pass {
    /// Sub-pixel sample positions (anti-aliasing) and everything else an eye path draws.
    Pixel = 1,
    /// Photon emission and scattering.
    Photon = 2,
    /// Samples keyed by an image-plane position (adaptive anti-aliasing's corner and refinement
    /// rays), so that every tile computes the same value for a shared point.
    Point = 3,
}

/// Returns the key of image-plane position `(x, y)` for [`Pass::Point`] streams.
pub fn point_key(x: f32, y: f32) -> u64 {
    ((x.to_bits() as u64) << 32) | y.to_bits() as u64
}

/// A PCG32 random stream.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

const MULT: u64 = 0x5851_f42d_4c95_7f2d;

/// Returns a well-mixed 64-bit hash of `x` (splitmix64's finaliser).
pub fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

impl Rng {
    /// Returns the stream for `index` in `pass` under `seed`.
    pub fn new(seed: u64, pass: Pass, index: u64) -> Rng {
        let key =
            mix64(seed ^ mix64((pass as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ mix64(index)));
        let mut rng = Rng {
            state: 0,
            inc: (mix64(key ^ 0x632b_e59b_d9b4_e019) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(key);
        rng.next_u32();
        rng
    }

    /// Returns the next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Returns a uniform float in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Returns a uniform integer in [0, n) for `n > 0` (Lemire's nearly divisionless method).
    pub fn below(&mut self, n: u32) -> u32 {
        debug_assert!(n > 0);
        ((self.next_u32() as u64 * n as u64) >> 32) as u32
    }
}

/// Returns `n` jittered sample positions in the unit square, stratified in x and in y
/// ("n-rooks": sample `i` lies in column `i` and in row `perm(i)` of an `n × n` grid).
///
/// With `n = 1` the single sample is the square's centre, so one sample per pixel reproduces the
/// course's ray through the pixel centre exactly.
pub fn stratified_2d(rng: &mut Rng, n: u32) -> Vec<(f32, f32)> {
    if n == 1 {
        return vec![(0.5, 0.5)];
    }
    let mut rows: Vec<u32> = (0..n).collect();
    for i in (1..n).rev() {
        rows.swap(i as usize, rng.below(i + 1) as usize);
    }
    let inv = 1.0 / n as f32;
    (0..n)
        .map(|i| {
            (
                (i as f32 + rng.next_f32()) * inv,
                (rows[i as usize] as f32 + rng.next_f32()) * inv,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_depend_only_on_their_key() {
        let draw = |seed, pass, i| {
            let mut r = Rng::new(seed, pass, i);
            (0..4).map(|_| r.next_u32()).collect::<Vec<_>>()
        };
        assert_eq!(draw(7, Pass::Pixel, 42), draw(7, Pass::Pixel, 42));
        assert_ne!(draw(7, Pass::Pixel, 42), draw(7, Pass::Pixel, 43));
        assert_ne!(draw(7, Pass::Pixel, 42), draw(8, Pass::Pixel, 42));
        assert_ne!(draw(7, Pass::Pixel, 42), draw(7, Pass::Photon, 42));
    }

    #[test]
    fn uniform_floats_have_the_right_moments() {
        let mut r = Rng::new(0, Pass::Pixel, 0);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| r.next_f32() as f64).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        assert!(
            (mean - 0.5).abs() < 0.005 && (var - 1.0 / 12.0).abs() < 0.002,
            "{mean} {var}"
        );
    }

    #[test]
    fn stratified_samples_fill_every_row_and_column_once() {
        let mut r = Rng::new(3, Pass::Pixel, 9);
        let s = stratified_2d(&mut r, 16);
        let mut cols = [0; 16];
        let mut rows = [0; 16];
        for (x, y) in s {
            cols[(x * 16.0) as usize] += 1;
            rows[(y * 16.0) as usize] += 1;
        }
        assert_eq!((cols, rows), ([1; 16], [1; 16]));
        assert_eq!(stratified_2d(&mut r, 1), vec![(0.5, 0.5)]);
    }
}
