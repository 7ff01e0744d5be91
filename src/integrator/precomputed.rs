//! The precomputation points of final gathering (Christensen 1999): the irradiance at a random
//! quarter of the global photons, each estimated once, when a gather ray first reads it or all
//! up front, kept with the radius its estimate gathered over, beyond which it is not read
//! ([`super::photon_map`] explains why, and reads them).

use crate::photon::{PhotonId, PhotonMap};
use glam::Vec3A;
use std::sync::atomic::{AtomicU32, Ordering};

/// About one global photon in this many carries a precomputed irradiance estimate (see
/// [`super::photon_map::GiSettings::precompute`] and [`is_precompute_point`]).
pub const PRECOMPUTE_STRIDE: usize = 4;

/// Returns whether global photon `id` is a precomputation point: a pseudo-random choice of one
/// in [`PRECOMPUTE_STRIDE`], independent of where the photon is (ids follow the kd-tree's
/// spatial order, so a stride over ids would pick points that are spread like the photons
/// near them, correlated with the estimate; see `super::photon_map::Prepass`'s `point_irradiance`).
pub fn is_precompute_point(id: PhotonId) -> bool {
    crate::sampling::mix64(u64::from(id.0) ^ 0x9e37_79b9_7f4a_7c15)
        .is_multiple_of(PRECOMPUTE_STRIDE as u64)
}

/// Irradiance at the precomputation points ([`is_precompute_point`]: about one global photon in
/// [`PRECOMPUTE_STRIDE`]) with the radius it gathered over ([`PointEstimate`]), each estimated
/// the first time a gather ray reads it and kept (or all up front for an image with at least as
/// many pixels, [`super::photon_map::Prepass::precompute_for`]).
///
/// Why lazily: a frame's gather rays land near a fraction of the points (on `room2.lua` at
/// 128², 10^6 global photons: 1.6 M points, most of them on surfaces no gather ray from the
/// visible points reaches), and estimating all of them up front took most of a preview's time.
/// An estimate depends only on its point (the others' `k` nearest), so estimating on demand
/// gives every point the value an up-front pass would, whichever thread asks first or how many
/// ask at once; the image is the same for any thread count.
#[derive(Debug)]
pub struct Precomputed {
    /// The points: the chosen global photons, as a map of their own (positions and normals).
    pub points: PhotonMap,
    /// Each point's estimate as f32 bits: the irradiance's red, green and blue, then the
    /// squared radius it gathered over; red is [`NOT_YET`] until the point is estimated.
    values: Vec<[AtomicU32; 4]>,
}

/// A precomputation point's estimate: the irradiance and the squared radius of the disc it
/// gathered photons over, the region where the value stands for the light
/// (`super::photon_map::Prepass::gathered_irradiance` reads it nowhere else).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEstimate {
    pub irradiance: Vec3A,
    /// Squared radius, world units; finite and >= 0 (0 when no photon was found).
    pub r2: f32,
}

/// The red channel of a point not yet estimated: a NaN pattern that no estimate produces
/// (estimates are finite sums of finite powers).
const NOT_YET: u32 = u32::MAX;

impl Precomputed {
    /// Returns the points of `global`'s precomputation points, none estimated yet.
    pub(super) fn new(global: &PhotonMap) -> Precomputed {
        let points = global.thinned(is_precompute_point);
        let values = (0..points.len())
            .map(|_| [NOT_YET, 0, 0, 0].map(AtomicU32::new))
            .collect();
        Precomputed { points, values }
    }

    /// Returns point `id`'s estimate, computing it with `estimate` if no thread has yet.
    pub(super) fn value(
        &self,
        id: PhotonId,
        estimate: impl FnOnce() -> PointEstimate,
    ) -> PointEstimate {
        let v = &self.values[id.0 as usize];
        let r = v[0].load(Ordering::Acquire);
        if r != NOT_YET {
            let [g, b, r2] =
                [&v[1], &v[2], &v[3]].map(|c| f32::from_bits(c.load(Ordering::Relaxed)));
            return PointEstimate {
                irradiance: Vec3A::new(f32::from_bits(r), g, b),
                r2,
            };
        }
        let e = estimate();
        debug_assert!(e.r2.is_finite() && e.r2 >= 0.0, "radius² {}", e.r2);
        // The others first, red last with release: a thread that sees red sees the others.
        // Two threads estimating the same point at once store the same bits.
        v[1].store(e.irradiance.y.to_bits(), Ordering::Relaxed);
        v[2].store(e.irradiance.z.to_bits(), Ordering::Relaxed);
        v[3].store(e.r2.to_bits(), Ordering::Relaxed);
        v[0].store(e.irradiance.x.to_bits(), Ordering::Release);
        e
    }

    /// Returns how many points have been estimated.
    pub fn evaluated(&self) -> usize {
        self.values
            .iter()
            .filter(|v| v[0].load(Ordering::Relaxed) != NOT_YET)
            .count()
    }
}
