//! Photons on their way from the tracer to a [`PhotonMap`]: the [`PhotonStream`], which holds
//! them in the order they were traced, 28 bytes each, in blocks that are freed one by one as the
//! map takes them.
//!
//! # Why (peak memory per stored photon)
//! A map keeps 20 bytes per photon ([`super`]), but the photons first exist as the tracer makes
//! them, and the peak of a render is whichever phase holds the most at once. Before the stream,
//! the tracing tasks kept full [`Photon`]s (80 bytes with `Vec3A`'s alignment, up to twice that
//! in `Vec` growth), the build copied them into 20-byte records, and the map's arrays were
//! gathered from those records through a 4-byte order array: about 125 bytes per stored photon
//! at the peak (`room2.lua`, 52 M photons, 6.6 GB). Now:
//! - the tracing threads claim chunks of photons in turn and keep each chunk's photons as
//!   [`Staged`] records (position, the map's code word, power in f32: 28 bytes); a finished
//!   chunk is appended here as soon as every chunk before it is, and its buffer freed, so only
//!   the few chunks in flight are held twice;
//! - the records live in blocks of [`BLOCK`] photons (1.75 MiB, above the 1 MiB threshold from
//!   which the allocator maps a block of its own and unmaps it when freed, see
//!   [`crate::mem::return_big_blocks`]), so the build, which converts and frees them block by
//!   block, holds at most the 28 bytes of a photon not yet converted or the 20 of one that is;
//! - each block keeps a [`Tally`] of its finite photons and their largest power exponent as
//!   photons are appended, so the build starts converting without a pass of its own over them;
//! - the build orders 20-byte records in place and copies them into the map's arrays from the
//!   end, giving the records' pages back to the system as it goes ([`crate::mem::discard`]).
//!
//! The peak is then about 28 bytes per photon of the map being built, plus the 20 of the maps
//! already built. Power stays f32 here because a map's power format needs its brightest photon,
//! which is known only once every photon is traced; the code word (directions, `direct`) is
//! final, so the map is the one [`PhotonMap::build`] makes of the same photons, bit for bit.
//!
//! [`PhotonMap`]: super::PhotonMap
//! [`PhotonMap::build`]: super::PhotonMap::build

use super::store;
use super::{Photon, PhotonView};
use glam::Vec3A;

/// Photons per block (`2^16` × 28 bytes = 1.75 MiB).
pub const BLOCK: usize = 1 << 16;

/// A photon as the stream holds it: position and power exact, directions already in the map's
/// code word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Staged {
    pub(super) pos: [f32; 3],
    pub(super) code: u32,
    pub(super) power: [f32; 3],
}

impl Staged {
    /// Returns the staged form of `p` (directions quantised as a map stores them).
    pub fn new(p: &Photon) -> Staged {
        Staged {
            pos: p.position.to_array(),
            code: store::encode_code(p.dir, p.normal, p.direct),
            power: p.power.to_array(),
        }
    }

    /// Returns the photon with its code word decoded (power exact, directions as a map has them).
    pub fn view(&self) -> PhotonView {
        let (dir, normal, direct) = store::decode_code(self.code);
        PhotonView {
            position: Vec3A::from_array(self.pos),
            power: Vec3A::from_array(self.power),
            dir,
            normal,
            direct,
        }
    }

    /// Returns whether the position is finite (a map skips photons that are not).
    pub(super) fn is_finite(&self) -> bool {
        self.pos.iter().all(|x| x.is_finite())
    }
}

/// What a map's build needs of a block before it converts it: how many of its photons have a
/// finite position (the map keeps those) and their largest [`store::power_exponent`], which
/// sets the map's power format. Kept as photons are appended, while they are in cache: counted
/// by the build, it was a pass over every staged photon, a ninth of a 10^6-photon build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Tally {
    pub(super) finite: usize,
    pub(super) max_exponent: i32,
}

impl Tally {
    const EMPTY: Tally = Tally {
        finite: 0,
        max_exponent: i32::MIN,
    };

    /// Counts `photons` in.
    fn add(&mut self, photons: &[Staged]) {
        for s in photons.iter().filter(|s| s.is_finite()) {
            self.finite += 1;
            let e = store::power_exponent(Vec3A::from_array(s.power));
            self.max_exponent = self.max_exponent.max(e);
        }
    }
}

/// Photons in the order they were appended, in blocks of [`BLOCK`], each with its [`Tally`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonStream {
    pub(super) blocks: Vec<Vec<Staged>>,
    pub(super) tallies: Vec<Tally>,
    len: usize,
}

impl PhotonStream {
    /// Returns an empty stream.
    pub fn new() -> PhotonStream {
        PhotonStream::default()
    }

    /// Returns the stream of `photons`, in their order (converted in parallel, a block a task).
    pub fn of(photons: &[Photon]) -> PhotonStream {
        use rayon::prelude::*;
        let (blocks, tallies) = photons
            .par_chunks(BLOCK)
            .map(|c| {
                let mut b = Vec::with_capacity(BLOCK);
                b.extend(c.iter().map(Staged::new));
                let mut t = Tally::EMPTY;
                t.add(&b);
                (b, t)
            })
            .unzip();
        PhotonStream {
            blocks,
            tallies,
            len: photons.len(),
        }
    }

    /// Returns the number of photons appended.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Returns whether no photon was appended.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends `photons`, in order, filling the last block before starting another.
    pub fn extend_from_slice(&mut self, mut photons: &[Staged]) {
        while !photons.is_empty() {
            if self.blocks.last().is_none_or(|b| b.len() == BLOCK) {
                self.blocks.push(Vec::with_capacity(BLOCK));
                self.tallies.push(Tally::EMPTY);
            }
            let last = self.blocks.len() - 1;
            let block = &mut self.blocks[last];
            let (now, rest) = photons.split_at((BLOCK - block.len()).min(photons.len()));
            block.extend_from_slice(now);
            self.tallies[last].add(now);
            self.len += now.len();
            photons = rest;
        }
    }

    /// Returns the photons in order.
    pub fn iter(&self) -> impl Iterator<Item = &Staged> {
        self.blocks.iter().flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(i: usize) -> Photon {
        Photon {
            position: Vec3A::new(i as f32, 0.5, -1.0),
            power: Vec3A::new(0.25, i as f32, 1e-9),
            dir: Vec3A::Y,
            normal: Vec3A::Z,
            direct: i.is_multiple_of(2),
        }
    }

    #[test]
    fn a_staged_photon_is_28_bytes() {
        assert_eq!(std::mem::size_of::<Staged>(), 28);
    }

    #[test]
    fn appends_of_any_size_keep_order_and_fill_whole_blocks() {
        let photons: Vec<Staged> = (0..3 * BLOCK + 17)
            .map(|i| Staged::new(&photon(i)))
            .collect();
        let mut s = PhotonStream::new();
        let mut rest = &photons[..];
        for len in [0, 1, BLOCK - 1, 5, 2 * BLOCK, 3] {
            let (a, b) = rest.split_at(len.min(rest.len()));
            s.extend_from_slice(a);
            rest = b;
        }
        for p in rest.chunks(1) {
            s.extend_from_slice(p);
        }
        assert_eq!(s.len(), photons.len());
        assert!(s.iter().eq(photons.iter()));
        let sizes: Vec<usize> = s.blocks.iter().map(Vec::len).collect();
        assert_eq!(sizes, [BLOCK, BLOCK, BLOCK, 17]);
        assert!(s.blocks.iter().all(|b| b.capacity() == BLOCK));
        assert_eq!(
            s,
            PhotonStream::of(&(0..3 * BLOCK + 17).map(photon).collect::<Vec<_>>())
        );
    }

    /// A block's tally, kept through appends of any size, is its count of finite photons and
    /// their largest power exponent, counted afresh.
    #[test]
    fn tallies_count_the_finite_photons_and_their_largest_exponent() {
        let photons: Vec<Staged> = (0..2 * BLOCK + 5)
            .map(|i| {
                let mut p = photon(i);
                if i % 1000 == 3 {
                    p.position.y = f32::NAN; // skipped by the map, so not counted
                }
                p.power = Vec3A::splat(((i * 7919) % 100_003) as f32 * 0.37);
                Staged::new(&p)
            })
            .collect();
        let mut s = PhotonStream::new();
        for c in photons.chunks(777) {
            s.extend_from_slice(c);
        }
        assert_eq!(s.tallies.len(), s.blocks.len());
        let counted: usize = s.tallies.iter().map(|t| t.finite).sum();
        assert!(
            counted < photons.len() - 100,
            "{counted}: too few NaN positions"
        );
        for (b, t) in s.blocks.iter().zip(&s.tallies) {
            let finite: Vec<&Staged> = b.iter().filter(|p| p.is_finite()).collect();
            let e = finite
                .iter()
                .map(|p| store::power_exponent(Vec3A::from_array(p.power)))
                .max()
                .unwrap();
            assert_eq!((t.finite, t.max_exponent), (finite.len(), e));
        }
        // The brightest photon is not in the last block: the tallies differ by block.
        assert_ne!(s.tallies[0].max_exponent, s.tallies[2].max_exponent);
    }

    #[test]
    fn a_staged_photon_keeps_position_and_power_exactly() {
        let p = photon(7);
        let v = Staged::new(&p).view();
        assert_eq!(
            (v.position, v.power, v.direct),
            (p.position, p.power, p.direct)
        );
        assert_eq!((v.dir, v.normal), (Vec3A::Y, Vec3A::Z));
    }
}
