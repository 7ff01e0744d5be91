//! Photon storage and search: the [`PhotonMap`], a compact struct-of-arrays photon store ordered
//! as an implicit balanced kd-tree (Jensen 2001, *Realistic Image Synthesis Using Photon Mapping*,
//! ch. 6 and App. B), with k-nearest and fixed-radius queries.
//!
//! # Conventions
//! - Positions are world space. A photon's `dir` is a unit vector pointing *towards where the photon
//!   came from* (a `wi`), and its `normal` is the unit geometric normal at the hit, on the side the
//!   photon arrived from (so `dir · normal > 0` for a surface photon).
//! - `power` is flux in watts per RGB channel, `>= 0`, already divided by the number of photons
//!   emitted, so a density estimate sums the powers it gathers and divides by the gather area.
//! - `direct` is true for a photon's first surface hit after leaving the light.
//! - Squared distances are computed as `(photon - p).length_squared()` in f32, exactly as glam does,
//!   so a brute-force loop written that way finds the very same values.
//!
//! # What is stored where (20 bytes per photon, nothing else per photon)
//! | array | bytes | contents |
//! |---|---|---|
//! | `pos: Vec<[f32; 3]>` | 12 | position, full precision: the only array a search reads besides the split axis |
//! | `code: Vec<u32>` | 4 | bits 0–28 incident direction and normal (two octahedral codes, mixed radix), bits 29–30 kd split axis (3 = leaf), bit 31 `direct` |
//! | `power: Vec<u32>` | 4 | shared-exponent RGB: three 9-bit mantissas, 5-bit exponent counted from a per-map base |
//!
//! The map itself adds a fixed 128-byte exponent table and the three `Vec` headers. Quantisation
//! (see [`store`]): power within 2^-9 (0.2 %) of the photon's largest channel, directions within
//! [`MAX_ANGLE_ERROR_DEG`] degrees, axis directions exact.
//!
//! Photons reach a map through a [`stream::PhotonStream`] (28 bytes each, in blocks the build
//! frees as it goes), so building holds about 28 bytes per photon at its peak, not the 125 it
//! took when the tracer kept full [`Photon`]s (measured and explained in [`stream`]).
//!
//! # The tree (see [`kdtree`])
//! There are no nodes and no pointers: photons are reordered so that the index range `lo..hi` is
//! a subtree whose root is its median photon `m = lo + (hi - lo) / 2`, split on the axis of the
//! range's largest extent; `lo..m` holds photons at or below the split coordinate and `m + 1..hi`
//! photons at or above it (equal coordinates may fall on both sides). Ranges of at most
//! [`kdtree::LEAF_SIZE`] photons are leaf buckets, searched linearly. The depth is
//! `log2(n / LEAF_SIZE)`, about 18 for 10^7 photons, whatever the input (duplicates, coplanar
//! points), and [`PhotonMap::build`] gives the same map for any thread count. The arrays hold
//! that tree's top levels first, breadth-first, then its bottom subtrees (a permutation that
//! keeps a random query's descent in one compact region; see [`kdtree`]).
//!
//! # Bad input
//! Photons with a NaN or infinite position are skipped (debug builds assert), so [`PhotonMap::len`]
//! may be less than the number handed in; a bad power channel is stored as 0 and a degenerate
//! direction as +z. Nothing here panics on bad input. At most `u32::MAX` photons are kept.
//!
//! ```
//! use caustic::photon::{Photon, PhotonMap};
//! use glam::Vec3A;
//! let photons = (0..100)
//!     .map(|i| Photon {
//!         position: Vec3A::new(i as f32 * 0.01, 0.0, 0.0),
//!         power: Vec3A::splat(0.01),
//!         dir: Vec3A::Y,
//!         normal: Vec3A::Y,
//!         direct: true,
//!     })
//!     .collect();
//! let map = PhotonMap::build(photons);
//! let mut found = Vec::new();
//! let r2 = map.knn(Vec3A::ZERO, 8, f32::INFINITY, &mut found);
//! assert_eq!(found.len(), 8);
//! assert!((r2 - 0.0049).abs() < 1e-6);
//! ```

pub mod estimate;
pub mod file;
pub mod kdtree;
pub mod store;
pub mod stream;
pub mod trace;
pub mod view;

use glam::Vec3A;
pub use store::{MAX_ANGLE_ERROR_DEG, MAX_POWER_REL_ERROR};

/// Index of a photon in a PhotonMap (kd-tree order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PhotonId(pub u32);

/// A photon as the tracer hands it over (full precision).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where the photon hit, in world space.
    pub position: Vec3A,
    /// Flux in W per channel, `>= 0`, already divided by the photon count.
    pub power: Vec3A,
    /// Unit vector towards where the photon came from.
    pub dir: Vec3A,
    /// Unit surface normal at the hit, on the side the photon arrived from.
    pub normal: Vec3A,
    /// Whether this is the first surface hit after leaving the light.
    pub direct: bool,
}

/// What a stored photon reads back as (quantised fields decoded).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonView {
    /// Where the photon hit, exactly as handed in.
    pub position: Vec3A,
    /// Flux in W per channel, within [`MAX_POWER_REL_ERROR`] of the largest channel.
    pub power: Vec3A,
    /// Unit vector towards where the photon came from, within [`MAX_ANGLE_ERROR_DEG`].
    pub dir: Vec3A,
    /// Unit surface normal at the hit, within [`MAX_ANGLE_ERROR_DEG`].
    pub normal: Vec3A,
    /// Whether this is the first surface hit after leaving the light.
    pub direct: bool,
}

/// Photons in kd-tree order, stored as struct-of-arrays (see the module doc for the layout).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonMap {
    /// Positions, indexed by [`PhotonId`]; the tree's split coordinates are read from here.
    pos: Vec<[f32; 3]>,
    /// Direction, normal, split axis and `direct` flag, indexed by [`PhotonId`] ([`store`]).
    code: Vec<u32>,
    /// Shared-exponent power, indexed by [`PhotonId`] ([`store::PowerCodec`]).
    power: Vec<u32>,
    /// The map's power format.
    codec: store::PowerCodec,
    /// Number of top nodes stored first, breadth-first (`2^D - 1`, see [`kdtree`]).
    top_nodes: usize,
}

impl PhotonMap {
    /// Returns the number of photons stored.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// Returns whether the map holds no photons.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Returns the bytes the map owns: its arrays (by capacity) and the struct itself.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.pos.capacity() * std::mem::size_of::<[f32; 3]>()
            + self.code.capacity() * std::mem::size_of::<u32>()
            + self.power.capacity() * std::mem::size_of::<u32>()
    }

    /// Returns photon `id` with its quantised fields decoded.
    ///
    /// # Panics
    /// If `id` is not below [`PhotonMap::len`] (ids come from this map's queries).
    pub fn get(&self, id: PhotonId) -> PhotonView {
        let i = id.0 as usize;
        let (dir, normal, direct) = store::decode_code(self.code[i]);
        PhotonView {
            position: Vec3A::from_array(self.pos[i]),
            power: self.codec.decode(self.power[i]),
            dir,
            normal,
            direct,
        }
    }

    /// Returns the surface normal of photon `id` (as [`PhotonMap::get`] decodes it).
    ///
    /// # Panics
    /// If `id` is not below [`PhotonMap::len`].
    pub fn normal(&self, id: PhotonId) -> Vec3A {
        store::decode_normal(self.code[id.0 as usize])
    }

    /// Returns the power of photon `id` (as [`PhotonMap::get`] decodes it).
    ///
    /// # Panics
    /// If `id` is not below [`PhotonMap::len`].
    pub fn power(&self, id: PhotonId) -> Vec3A {
        self.codec.decode(self.power[id.0 as usize])
    }

    /// Returns the position of photon `id`, reading the position array only.
    ///
    /// # Panics
    /// If `id` is not below [`PhotonMap::len`].
    pub fn position(&self, id: PhotonId) -> Vec3A {
        Vec3A::from_array(self.pos[id.0 as usize])
    }
}
