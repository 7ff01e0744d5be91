//! Photon search on degenerate photon sets: every photon on one plane (a kd-tree with one flat
//! axis), all at one point (every split a tie), a single photon, none. Each query must be finite
//! and equal to brute force.

use caustic::photon::estimate::Filter;
use caustic::photon::{Photon, PhotonId, PhotonMap};
use caustic::sampling::{Pass, Rng};
use glam::Vec3A;

/// Deterministic photon and query positions in [-1, 1), from the renderer's own streams.
struct Gen(Rng);

impl Gen {
    fn new(index: u64) -> Gen {
        Gen(Rng::new(0, Pass::Photon, index))
    }

    fn next(&mut self) -> f32 {
        2.0 * self.0.next_f32() - 1.0
    }

    fn point(&mut self) -> Vec3A {
        Vec3A::new(self.next(), self.next(), self.next())
    }
}

/// Returns a photon at `position` with unit power, arriving straight down onto an upward face.
fn photon(position: Vec3A) -> Photon {
    Photon {
        position,
        power: Vec3A::ONE,
        dir: Vec3A::Y,
        normal: Vec3A::Y,
        direct: true,
    }
}

/// The four degenerate sets: 2000 photons on the plane y = 0.25, 2000 at one point, one, none.
fn photon_sets() -> Vec<(&'static str, Vec<Vec3A>)> {
    let mut g = Gen::new(7);
    let plane = (0..2000)
        .map(|_| Vec3A::new(g.next(), 0.25, g.next()))
        .collect();
    let point = vec![Vec3A::new(0.3, -0.2, 0.1); 2000];
    vec![
        ("plane", plane),
        ("point", point),
        ("single", vec![Vec3A::new(0.5, 0.5, 0.5)]),
        ("none", Vec::new()),
    ]
}

/// Returns the queries for a set: random points, points on the set's photons, and the origin.
fn queries(set: &[Vec3A]) -> Vec<Vec3A> {
    let mut g = Gen::new(11);
    let mut q: Vec<Vec3A> = (0..40).map(|_| g.point()).collect();
    q.extend(set.iter().step_by(97).copied());
    q.push(Vec3A::ZERO);
    q
}

/// Sorted squared distances from `p` of the photons of `map` within `max_d2`, by brute force.
fn brute(map: &PhotonMap, p: Vec3A, max_d2: f32) -> Vec<(f32, PhotonId)> {
    let mut all: Vec<(f32, PhotonId)> = (0..map.len() as u32)
        .map(|i| (map.position(PhotonId(i)).distance_squared(p), PhotonId(i)))
        .filter(|(d2, _)| *d2 <= max_d2)
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all
}

/// k-nearest, radius and nearest-where queries on each degenerate set equal brute force: the
/// same distances (ties at the k-th may pick other photons), the same photons within a radius,
/// the lowest-id nearest accepted photon; every distance and kernel weight finite. 4 sets,
/// 41–62 queries each, k in {1, 10, 50, 5000} and 3 radii.
#[test]
fn degenerate_photon_sets_search_like_brute_force() {
    let mut out = Vec::new();
    for (name, positions) in photon_sets() {
        let map = PhotonMap::build(positions.iter().map(|&p| photon(p)).collect());
        map.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(map.len(), positions.len());
        for p in queries(&positions) {
            for (k, max_d2) in [(1, f32::INFINITY), (10, 0.5), (50, 4.0), (5000, 12.0)] {
                let found = map.knn(p, k, max_d2, &mut out);
                let want = brute(&map, p, max_d2);
                let want_k: Vec<f32> = want.iter().take(k).map(|w| w.0).collect();
                let mut got: Vec<f32> = out.iter().map(|o| o.0).collect();
                got.sort_by(f32::total_cmp);
                assert_eq!(got, want_k, "{name}: knn({p}, {k}, {max_d2})");
                assert!(found.is_finite(), "{name}: knn radius {found}");
                assert_eq!(found, want_k.last().copied().unwrap_or(0.0), "{name}");
                for filter in [
                    Filter::Box,
                    Filter::Cone,
                    Filter::Epanechnikov,
                    Filter::Gaussian,
                ] {
                    let e: f32 = got.iter().map(|&d2| filter.weight(d2, found)).sum();
                    assert!(
                        e.is_finite(),
                        "{name}: {filter:?} estimate {e} at r² {found}"
                    );
                }
            }
            for r2 in [0.0, 0.01, 1.0] {
                map.within(p, r2, &mut out);
                let mut got: Vec<PhotonId> = out.iter().map(|o| o.1).collect();
                got.sort();
                let mut want: Vec<PhotonId> = brute(&map, p, r2).iter().map(|w| w.1).collect();
                want.sort();
                assert_eq!(got, want, "{name}: within({p}, {r2})");
            }
            let odd = |id: PhotonId| id.0 % 2 == 1;
            let got = map.nearest_where(p, f32::INFINITY, &mut |id| odd(id));
            let want = brute(&map, p, f32::INFINITY).into_iter().find(|w| odd(w.1));
            assert_eq!(got, want, "{name}: nearest_where({p})");
        }
    }
}
