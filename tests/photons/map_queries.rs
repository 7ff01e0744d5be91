//! The photon map against brute force: k-nearest and radius queries on random, coplanar, wavy and
//! duplicated points, quantisation round trips, build determinism across thread counts, and edge
//! cases (empty, single photon, bad positions).

use caustic::photon::stream::{BLOCK, PhotonStream, Staged};
use caustic::photon::{MAX_ANGLE_ERROR_DEG, MAX_POWER_REL_ERROR, Photon, PhotonId, PhotonMap};
use caustic::sampling::{Pass, Rng};
use glam::Vec3A;
use std::collections::HashMap;

/// Returns a uniformly random unit vector.
fn random_unit(r: &mut Rng) -> Vec3A {
    let z = 2.0 * r.next_f32() - 1.0;
    let phi = std::f32::consts::TAU * r.next_f32();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(s * phi.cos(), s * phi.sin(), z)
}

/// Returns photons at `positions` with random power, directions and flags.
fn photons_at(positions: &[Vec3A], seed: u64) -> Vec<Photon> {
    let mut r = Rng::new(seed, Pass::Photon, 0);
    positions
        .iter()
        .map(|&position| Photon {
            position,
            power: Vec3A::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1e-5,
            dir: random_unit(&mut r),
            normal: random_unit(&mut r),
            direct: r.next_u32() & 1 == 1,
        })
        .collect()
}

/// Names a point set and returns its positions (20 000 points around the unit cube).
fn point_set(name: &str) -> Vec<Vec3A> {
    let mut r = Rng::new(11, Pass::Photon, name.len() as u64);
    let n = 20_000;
    let mut u = move || r.next_f32();
    match name {
        "uniform" => (0..n).map(|_| Vec3A::new(u(), u(), u())).collect(),
        // A floor: every photon has y = 0 exactly.
        "floor" => (0..n).map(|_| Vec3A::new(u(), 0.0, u())).collect(),
        // A water surface: a smooth height field, plus a flat y = 0.25 pool floor on a grid.
        "water" => (0..n)
            .map(|i| {
                let (x, z) = (u(), u());
                if i % 4 == 0 {
                    Vec3A::new((x * 64.0).floor() / 64.0, 0.25, (z * 64.0).floor() / 64.0)
                } else {
                    Vec3A::new(x, 0.5 + 0.02 * (9.0 * x).sin() * (7.0 * z).cos(), z)
                }
            })
            .collect(),
        // Many exact duplicates: 300 distinct points, and one point repeated 2000 times.
        "duplicates" => {
            let distinct: Vec<Vec3A> = (0..300).map(|_| Vec3A::new(u(), u(), u())).collect();
            (0..n)
                .map(|i| {
                    if i % 10 == 0 {
                        Vec3A::splat(0.5)
                    } else {
                        distinct[(u() * 300.0) as usize % 300]
                    }
                })
                .collect()
        }
        _ => unreachable!("{name}"),
    }
}

const SETS: [&str; 4] = ["uniform", "floor", "water", "duplicates"];

/// Returns query points inside, on and outside the data.
fn queries(points: &[Vec3A]) -> Vec<Vec3A> {
    let mut r = Rng::new(12, Pass::Pixel, points.len() as u64);
    let mut u = move || r.next_f32();
    let mut q = Vec::new();
    for _ in 0..40 {
        q.push(Vec3A::new(u(), u(), u())); // inside the box
        q.push(points[(u() * points.len() as f32) as usize % points.len()]); // on a photon
        q.push(Vec3A::new(u(), 0.0, u())); // on the floor plane
        q.push(Vec3A::new(u() * 6.0 - 3.0, u() * 6.0 - 3.0, 3.5)); // outside
    }
    q.push(Vec3A::splat(0.5));
    q.push(Vec3A::new(1e6, -1e6, 0.0));
    q
}

/// Orders results by distance, then id.
fn by_distance(a: &(f32, PhotonId), b: &(f32, PhotonId)) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

/// Returns the `k` photons nearest to `q` within squared distance `r2`, by brute force, sorted.
fn brute(map: &PhotonMap, q: Vec3A, r2: f32, k: usize) -> Vec<(f32, PhotonId)> {
    let mut all: Vec<(f32, PhotonId)> = (0..map.len() as u32)
        .map(|i| {
            (
                (map.position(PhotonId(i)) - q).length_squared(),
                PhotonId(i),
            )
        })
        .filter(|e| e.0 <= r2)
        .collect();
    if all.len() > k && k > 0 {
        all.select_nth_unstable_by(k - 1, by_distance);
    }
    all.truncate(k);
    all.sort_by(by_distance);
    all
}

/// Checks one knn query against brute force: the same distances, the same ids except among
/// those tied with the k-th distance, and a correct return value.
fn check_knn(map: &PhotonMap, q: Vec3A, k: usize, max_d2: f32, out: &mut Vec<(f32, PhotonId)>) {
    let worst = map.knn(q, k, max_d2, out);
    let expect = &brute(map, q, max_d2, k)[..];
    let mut got = out.clone();
    got.sort_by(by_distance);
    let ctx = format!("q = {q}, k = {k}, max_d2 = {max_d2}");
    assert_eq!(got.len(), expect.len(), "{ctx}");
    let dist = |v: &[(f32, PhotonId)]| v.iter().map(|e| e.0).collect::<Vec<_>>();
    assert_eq!(dist(&got), dist(expect), "{ctx}");
    assert_eq!(worst, expect.last().map_or(0.0, |e| e.0), "{ctx}");
    for &(d2, id) in &got {
        assert_eq!(d2, (map.position(id) - q).length_squared(), "{ctx}");
        if d2 < worst {
            assert!(expect.contains(&(d2, id)), "{ctx}: {id:?} at {d2}");
        }
    }
    got.dedup_by_key(|e| e.1);
    assert_eq!(got.len(), expect.len(), "{ctx}: an id is repeated");
}

/// Builds a map and checks its invariants.
fn build(photons: Vec<Photon>) -> PhotonMap {
    let n = photons.len();
    let map = PhotonMap::build(photons);
    assert_eq!(map.validate(), Ok(()));
    assert_eq!(map.len(), n);
    assert!(map.bytes() <= 20 * n + 256, "{} bytes for {n}", map.bytes());
    map
}

#[test]
fn knn_equals_brute_force_on_every_point_set() {
    let mut out = Vec::new();
    for set in SETS {
        let points = point_set(set);
        let map = build(photons_at(&points, 1));
        for q in queries(&points) {
            for k in [1, 8, 50] {
                check_knn(&map, q, k, f32::INFINITY, &mut out);
                check_knn(&map, q, k, 0.002, &mut out);
            }
            check_knn(&map, q, 3000, 0.01, &mut out);
        }
    }
}

#[test]
fn within_equals_brute_force_on_every_point_set() {
    let mut out = Vec::new();
    for set in SETS {
        let points = point_set(set);
        let map = build(photons_at(&points, 2));
        for q in queries(&points) {
            for r2 in [0.0, 1e-4, 0.003, 0.05] {
                map.within(q, r2, &mut out);
                out.sort_by(by_distance);
                assert_eq!(
                    out,
                    brute(&map, q, r2, usize::MAX),
                    "{set}: q = {q}, r2 = {r2}"
                );
            }
        }
    }
}

#[test]
fn nearest_where_equals_brute_force_on_every_point_set() {
    for set in SETS {
        let points = point_set(set);
        let map = build(photons_at(&points, 3));
        // A predicate that rejects about two photons in three, so the search must look past them.
        let keep = |id: PhotonId| map.normal(id).y > 0.3;
        for q in queries(&points) {
            for max_d2 in [f32::INFINITY, 0.002, 0.0] {
                let mut asked = 0;
                let got = map.nearest_where(q, max_d2, &mut |id| {
                    asked += 1;
                    keep(id)
                });
                let want = brute(&map, q, max_d2, usize::MAX)
                    .into_iter()
                    .find(|&(_, id)| keep(id));
                assert_eq!(got, want, "{set}: q = {q}, max_d2 = {max_d2}");
                assert!(asked < map.len() / 4, "{set}: asked {asked} photons");
            }
        }
    }
}

/// A stream of several blocks, appended in uneven pieces with photons at non-finite positions
/// among them, becomes a map that satisfies the tree's invariants and holds exactly the finite
/// photons, each as it was handed in (position exact, power and directions within the stored
/// precision), whatever the block boundaries.
#[test]
fn a_map_from_a_stream_of_many_blocks_holds_exactly_its_finite_photons() {
    let mut r = Rng::new(5, Pass::Photon, 1);
    let n = 3 * BLOCK + 1234;
    let positions: Vec<Vec3A> = (0..n)
        .map(|i| match i % 5000 {
            17 => Vec3A::new(f32::NAN, 0.0, 0.0),
            4999 => Vec3A::new(0.0, f32::INFINITY, 0.0),
            _ => Vec3A::new(r.next_f32(), r.next_f32(), r.next_f32()),
        })
        .collect();
    let photons = photons_at(&positions, 9);
    let staged: Vec<Staged> = photons.iter().map(Staged::new).collect();
    let mut stream = PhotonStream::new();
    let mut rest = &staged[..];
    for len in [0, 1, 999, 0, BLOCK + 7, 2 * BLOCK - 3] {
        let (a, b) = rest.split_at(len.min(rest.len()));
        stream.extend_from_slice(a);
        rest = b;
    }
    stream.extend_from_slice(rest);
    assert_eq!(stream.len(), n);
    let map = PhotonMap::from_stream(stream);
    map.validate().unwrap();
    let key = |p: Vec3A| p.to_array().map(f32::to_bits);
    let mut want: HashMap<[u32; 3], &Photon> = HashMap::new();
    for p in photons.iter().filter(|p| p.position.is_finite()) {
        want.insert(key(p.position), p);
    }
    assert_eq!(map.len(), want.len(), "finite photons kept");
    assert!(map.len() < n, "the set holds non-finite photons");
    for i in 0..map.len() as u32 {
        let got = map.get(PhotonId(i));
        let p = want
            .remove(&key(got.position))
            .expect("a photon handed in, once");
        let err = (got.power - p.power).abs().max_element();
        assert!(
            err <= MAX_POWER_REL_ERROR * p.power.max_element(),
            "photon {i}: power"
        );
        assert!(got.dir.angle_between(p.dir).to_degrees() <= MAX_ANGLE_ERROR_DEG);
        assert!(got.normal.angle_between(p.normal).to_degrees() <= MAX_ANGLE_ERROR_DEG);
        assert_eq!(got.direct, p.direct);
    }
}

/// The thinned map holds exactly the photons chosen, as the full map stores them.
#[test]
fn a_thinned_map_holds_the_chosen_photons() {
    let map = PhotonMap::build(photons_at(&point_set("water"), 3));
    let keep = |id: PhotonId| id.0 % 3 == 1;
    let thin = map.thinned(keep);
    thin.validate().unwrap();
    let mut want: Vec<_> = (0..map.len() as u32)
        .map(PhotonId)
        .filter(|&id| keep(id))
        .map(|id| map.get(id))
        .map(|v| {
            (
                v.position.to_array().map(f32::to_bits),
                v.normal.to_array().map(f32::to_bits),
            )
        })
        .collect();
    let mut got: Vec<_> = (0..thin.len() as u32)
        .map(|i| thin.get(PhotonId(i)))
        .map(|v| {
            (
                v.position.to_array().map(f32::to_bits),
                v.normal.to_array().map(f32::to_bits),
            )
        })
        .collect();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want);
}

#[test]
fn a_photon_exactly_on_the_radius_is_found() {
    let points = [
        Vec3A::ZERO,
        Vec3A::X,
        Vec3A::NEG_X,
        Vec3A::Y,
        Vec3A::Z * 2.0,
    ];
    let pts: Vec<Vec3A> = points.iter().cycle().take(100).copied().collect();
    let map = build(photons_at(&pts, 3));
    let mut out = Vec::new();
    map.within(Vec3A::ZERO, 1.0, &mut out);
    assert_eq!(out.len(), 80);
    assert_eq!(map.knn(Vec3A::ZERO, 70, 1.0, &mut out), 1.0);
    assert_eq!(out.len(), 70);
}

#[test]
fn stored_photons_read_back_within_the_stated_errors() {
    let points = point_set("uniform");
    let photons = photons_at(&points, 4);
    let by_pos: HashMap<[u32; 3], Photon> = photons
        .iter()
        .map(|p| (p.position.to_array().map(f32::to_bits), *p))
        .collect();
    assert_eq!(by_pos.len(), photons.len(), "positions must be unique here");
    let map = build(photons);
    let angle = |a: Vec3A, b: Vec3A| a.cross(b).length().atan2(a.dot(b)).to_degrees();
    for i in 0..map.len() as u32 {
        let v = map.get(PhotonId(i));
        assert_eq!(v.position, map.position(PhotonId(i)));
        let p = by_pos[&v.position.to_array().map(f32::to_bits)];
        assert_eq!(v.direct, p.direct);
        let err = (v.power - p.power).abs().max_element() / p.power.max_element();
        assert!(err <= MAX_POWER_REL_ERROR, "{} -> {}", p.power, v.power);
        assert!(angle(v.dir, p.dir) <= MAX_ANGLE_ERROR_DEG);
        assert!(angle(v.normal, p.normal) <= MAX_ANGLE_ERROR_DEG);
        assert!((v.dir.length() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn a_floor_normal_reads_back_exactly() {
    let mut photons = photons_at(&point_set("floor"), 5);
    for p in &mut photons {
        p.normal = Vec3A::Y;
    }
    let map = build(photons);
    assert!((0..map.len() as u32).all(|i| map.get(PhotonId(i)).normal == Vec3A::Y));
}

#[test]
fn the_build_is_the_same_for_one_and_two_threads() {
    let mut points = point_set("uniform");
    points.extend(point_set("floor"));
    points.extend(point_set("duplicates"));
    let photons = photons_at(&points, 6);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| PhotonMap::build(photons.clone()));
    let two = pool(2).install(|| PhotonMap::build(photons.clone()));
    assert_eq!(one.validate(), Ok(()));
    assert!(one == two, "the two builds differ");
}

#[test]
fn empty_and_single_photon_maps_answer_queries() {
    let mut out = vec![(1.0, PhotonId(7))];
    let empty = build(Vec::new());
    assert!(empty.is_empty());
    assert_eq!(empty.knn(Vec3A::ZERO, 50, f32::INFINITY, &mut out), 0.0);
    assert!(out.is_empty());
    empty.within(Vec3A::ZERO, f32::INFINITY, &mut out);
    assert!(out.is_empty());

    let one = build(photons_at(&[Vec3A::new(1.0, 2.0, 3.0)], 7));
    assert_eq!(one.knn(Vec3A::new(1.0, 2.0, 4.0), 50, 2.0, &mut out), 1.0);
    assert_eq!(out, [(1.0, PhotonId(0))]);
    assert_eq!(one.knn(Vec3A::ZERO, 50, 2.0, &mut out), 0.0);
    assert!(out.is_empty());
    assert_eq!(one.knn(Vec3A::ZERO, 0, f32::INFINITY, &mut out), 0.0);
    assert!(out.is_empty());
}

#[test]
fn bad_queries_find_nothing() {
    let map = build(photons_at(&point_set("uniform"), 8));
    let mut out = Vec::new();
    assert_eq!(map.knn(Vec3A::splat(f32::NAN), 8, 1.0, &mut out), 0.0);
    assert!(out.is_empty());
    assert_eq!(map.knn(Vec3A::ZERO, 8, f32::NAN, &mut out), 0.0);
    assert_eq!(map.knn(Vec3A::ZERO, 8, -1.0, &mut out), 0.0);
    map.within(Vec3A::ZERO, f32::NAN, &mut out);
    assert!(out.is_empty());
}

#[test]
fn photons_at_bad_positions_are_skipped_in_release_builds() {
    if cfg!(debug_assertions) {
        return; // Debug builds assert on them, as tracer bugs.
    }
    let mut photons = photons_at(&point_set("uniform")[..1000], 9);
    photons[3].position.x = f32::NAN;
    photons[500].position.z = f32::INFINITY;
    photons[999].position.y = f32::NEG_INFINITY;
    let map = PhotonMap::build(photons);
    assert_eq!(map.validate(), Ok(()));
    assert_eq!(map.len(), 997);
}
