//! Local radii for the progressive integrator: each map's first-pass radius as a function of
//! where the estimate is made, set by a pilot photon map's density there, then shrunk pass by
//! pass as the one global radius was (see [`super::progressive`]).
//!
//! # Why
//! One radius for the whole image holds about `k` photons where photons typically land, and
//! many fewer where they rarely do: a wall lit only by light that bounced, the dim side of a
//! caustic. There the estimate's relative noise is larger by the square root of the density
//! ratio, at every pass, so dim regions need ten times the passes for the same relative error
//! where the density is ten times lower. A radius that holds `k` photons everywhere gives every
//! region the same relative noise, and kernel bias where the density is flat stays small.
//!
//! # Why a field over space, not pbrt-v4's per-pixel statistics
//! pbrt-v4's SPPM keeps each pixel's radius and photon count and shrinks the radius by what
//! that pixel's visible point has seen: each pass depends on every pass before it. caustic's
//! passes are independent (a render farm runs passes `P..P+N` on one machine and others
//! elsewhere, `caustic merge` adds them up; tiles are bit-identical to the full frame; the even
//! and odd passes estimate the noise). A pixel's radius would also be ill-defined here: a pixel
//! of water has two visible points (the reflection's and the refraction's, both followed).
//!
//! So the radius is a function of position, not of pixel or pass history: at `p` it is the
//! distance from the pilot point nearest `p` (on a surface facing the same way) to its `k`-th
//! nearest photon of a *pilot* map, traced with a seed of its own (no pass uses it), at most
//! the photon mapper's largest search radius and at least the field's median (the one radius
//! a map would have).
//!
//! # Why never below the median
//! A radius that holds `k` photons everywhere shrinks the disc where the image is brightest:
//! the relative noise is then the same everywhere, but the absolute noise, which is what an
//! image's RMSE counts, grows where the light is strongest. On `glass_in_water`'s caustic under
//! the ball (`docs/accuracy/local_radii.md`) pure `k`-nearest radii left 9% more error than one
//! radius after 64 passes, the focus's noise outweighing its lower blur. Bright regions keep
//! the one radius's disc (more than `k` photons in it); dim ones get the larger disc they need. Every process computes the same field from the
//! same seed, so passes stay independent and the field is independent of every pass's photons:
//! each pass is a fixed-radius estimate, the one Knaus & Zwicker analyse, with the radius
//! varying over the surface. The shrink schedule is the global radius's, so both parts of the
//! error still fall as `N^(−1/3)` everywhere, from a level that no longer depends on how bright
//! the region is. `--radius` scales the field so that its median is the fraction it gives.

use crate::photon::{PhotonId, PhotonMap};
use glam::Vec3A;
use rayon::prelude::*;

/// Most pilot photons the field keeps as its points (the map is thinned by a stride to this).
pub const MAX_POINTS: usize = 1 << 16;

/// Smallest cosine between a query's normal and a field point's for the point to stand for the
/// query's surface (the photon estimate's own normal test).
const SAME_SURFACE_COS: f32 = 0.7;

/// A map's first-pass radius over space: points of a pilot map, each with the distance to its
/// `k`-th nearest pilot photon.
#[derive(Debug)]
pub struct RadiusField {
    points: PhotonMap,
    radius: Vec<f32>,
    /// The radius beyond which nothing is searched: the field's largest value, and its value
    /// where no point is near.
    max: f32,
    median: f32,
}

impl RadiusField {
    /// Returns the field of `pilot`: at up to [`MAX_POINTS`] of its photons, spread through it,
    /// the distance to the `k`-th nearest other photon, at most `max` (`max` where fewer than `k`
    /// are that near, and everywhere for an empty map).
    pub fn new(pilot: &PhotonMap, k: usize, max: f32) -> RadiusField {
        let n = pilot.len();
        let stride = n.div_ceil(MAX_POINTS).max(1);
        let points = pilot.thinned(|id| (id.0 as usize).is_multiple_of(stride));
        let radius: Vec<f32> = (0..points.len())
            .into_par_iter()
            .map_init(Vec::new, |found, i| {
                let p = points.position(PhotonId(i as u32));
                kth_distance(pilot, p, k, max, found)
            })
            .collect();
        let median = median_or(radius.clone(), max);
        RadiusField {
            points,
            radius,
            max,
            median,
        }
    }

    /// Returns the field's median over its points: the radius a single global one would have.
    pub fn median(&self) -> f32 {
        self.median
    }

    /// Returns the radius at `p` on a surface of unit normal `n`: that of the nearest point
    /// facing within [`SAME_SURFACE_COS`] of `n` within the field's largest radius, at least
    /// the median; else that largest radius (no pilot photon is near, so the region is dark).
    pub fn at(&self, p: Vec3A, n: Vec3A) -> f32 {
        let found = self
            .points
            .nearest_where(p, self.max * self.max, &mut |id: PhotonId| {
                self.points.normal(id).dot(n) >= SAME_SURFACE_COS
            });
        found.map_or(self.max, |(_, id)| {
            self.radius[id.0 as usize].max(self.median)
        })
    }
}

/// Returns the distance from photon position `p` of `map` to its `k`-th nearest other photon,
/// at most `max` (`max` where fewer than `k` others are that near); `found` is scratch.
pub fn kth_distance(
    map: &PhotonMap,
    p: Vec3A,
    k: usize,
    max: f32,
    found: &mut Vec<(f32, PhotonId)>,
) -> f32 {
    // The photon at `p` is its own nearest: k + 1 of them.
    let r2 = map.knn(p, k + 1, max * max, found);
    if found.len() <= k {
        max
    } else {
        r2.sqrt().min(max)
    }
}

/// Returns the median of `values`, or `empty` when there are none.
pub fn median_or(mut values: Vec<f32>, empty: f32) -> f32 {
    if values.is_empty() {
        return empty;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The two maps' fields, and the factor every radius is scaled by (the shrink of the passes
/// so far, times `--radius`'s scaling of the medians).
#[derive(Debug)]
pub struct LocalRadii {
    pub global: RadiusField,
    pub caustic: Option<RadiusField>,
}

impl LocalRadii {
    /// Returns the first pass's radius of the global (`caustic` false) or caustic map at `p`
    /// (unit normal `n`); without a caustic field the caustic map's radius is the global one's
    /// half, as for one global radius.
    pub fn at(&self, caustic: bool, p: Vec3A, n: Vec3A) -> f32 {
        match (caustic, &self.caustic) {
            (false, _) => self.global.at(p, n),
            (true, Some(c)) => c.at(p, n),
            (true, None) => 0.5 * self.global.at(p, n),
        }
    }

    /// Returns the medians of the global and caustic fields (the caustic's is the global's half
    /// without a caustic field).
    pub fn medians(&self) -> (f32, f32) {
        let g = self.global.median();
        (g, self.caustic.as_ref().map_or(0.5 * g, |c| c.median()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::Photon;

    /// Photons on the plane y = 0, facing up, on a jittered grid: `per_side` × `per_side` of them
    /// over x in [x0, x0 + 1], z in [0, 1].
    fn plane(x0: f32, per_side: u32, seed: u64, out: &mut Vec<Photon>) {
        let mut rng = crate::sampling::Rng::new(seed, crate::sampling::Pass::Point, 0);
        for j in 0..per_side {
            for i in 0..per_side {
                let (u, v) = (rng.next_f32(), rng.next_f32());
                let x = x0 + (i as f32 + u) / per_side as f32;
                let z = (j as f32 + v) / per_side as f32;
                out.push(Photon {
                    position: Vec3A::new(x, 0.0, z),
                    dir: Vec3A::Y,
                    normal: Vec3A::Y,
                    power: Vec3A::ONE,
                    direct: false,
                });
            }
        }
    }

    /// On a plane whose left half has 16 times the photon density of its right half, the field
    /// is the closed form `r = √(k / (π ρ))` on each half within 15% (away from the halves'
    /// edges): 4 times larger on the sparse half. Its median is the dense half's, the largest
    /// radius stands where no photon is near, and a point on a surface facing elsewhere (a wall
    /// at the plane's edge) does not take the plane's radius.
    #[test]
    fn the_field_holds_k_photons_at_every_density() {
        let mut photons = Vec::new();
        plane(0.0, 400, 1, &mut photons);
        plane(1.0, 100, 2, &mut photons);
        let map = PhotonMap::build(photons);
        let k = 50;
        let field = RadiusField::new(&map, k, 0.5);
        for (x, per_side) in [(0.5f32, 400.0f32), (1.5, 100.0)] {
            let expected = (k as f32 / (std::f32::consts::PI * per_side * per_side)).sqrt();
            for z in [0.3f32, 0.5, 0.7] {
                let r = field.at(Vec3A::new(x, 0.0, z), Vec3A::Y);
                assert!(
                    (r / expected - 1.0).abs() < 0.15,
                    "at x {x}, z {z}: radius {r}, closed form {expected}"
                );
            }
        }
        // Most points are on the dense half, so the median is its radius.
        let dense = (k as f32 / (std::f32::consts::PI * 160_000.0)).sqrt();
        assert!(
            (field.median() / dense - 1.0).abs() < 0.15,
            "median {}",
            field.median()
        );
        assert_eq!(field.at(Vec3A::new(10.0, 0.0, 0.5), Vec3A::Y), 0.5);
        assert_eq!(field.at(Vec3A::new(0.5, 0.0, 0.5), Vec3A::X), 0.5);
        let empty = RadiusField::new(&PhotonMap::build(Vec::new()), k, 0.25);
        assert_eq!(empty.at(Vec3A::ZERO, Vec3A::Y), 0.25);
        assert_eq!(empty.median(), 0.25);
    }
}
