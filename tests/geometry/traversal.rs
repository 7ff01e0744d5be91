//! Mesh traversal against brute force, and watertightness through the BVH.
//!
//! Agreement: for random rays, [`MeshGeom::intersect`] must report the same `t` (bit for bit) as a
//! loop over every triangle with the same watertight test, and the same triangle unless another
//! triangle is hit at exactly that `t` (a ray through a shared edge or vertex); `any_hit` must
//! agree on hit or miss. Every node-test kernel ([`Kernel`]: scalar with scalar triangle tests,
//! SSE2 and AVX2 with 4-wide triangle tests) must give bit-identical hits. Watertightness: rays
//! aimed exactly at shared vertices and edge midpoints of a closed mesh (from inside) and of a
//! height field (from above) must all hit, with every kernel.

use caustic::accel::Kernel;
use caustic::accel::mesh::MeshGeom;
use caustic::accel::stream::Coherence;
use caustic::geometry::Ray;
use caustic::geometry::mesh::MeshData;
use caustic::geometry::triangle::{self, RayShear, TriangleHit};
use glam::{DMat3, DVec3, Vec3, Vec3A};
use std::collections::{BTreeSet, HashMap};

/// A small deterministic generator (splitmix64), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Returns a uniform number in `[lo, hi)`.
    fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }

    fn unit_vector(&mut self) -> Vec3A {
        let z = self.uniform(-1.0, 1.0);
        let phi = self.uniform(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
}

fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> MeshData {
    MeshData {
        positions,
        triangles,
        ..MeshData::default()
    }
}

/// Returns every hit `(file triangle, t)` of the closest `t`, by brute force with the watertight test.
fn brute_force(data: &MeshData, ray: &Ray) -> (f32, Vec<u32>) {
    let shear = RayShear::new(ray);
    let mut best = (f32::INFINITY, Vec::new());
    for (i, t) in data.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| Vec3A::from(data.positions[v as usize]));
        if let Some(h) = triangle::intersect(&shear, a, b, c, ray.tmin, ray.tmax) {
            if h.t < best.0 {
                best = (h.t, vec![i as u32]);
            } else if h.t == best.0 {
                best.1.push(i as u32);
            }
        }
    }
    best
}

/// The kernels to test: all three, clamped to what this CPU runs (duplicates are harmless).
const KERNELS: [Kernel; 3] = [Kernel::Scalar, Kernel::Sse2, Kernel::Avx2];

/// Returns a hit as bits, for exact comparison.
fn bits(h: Option<(u32, TriangleHit)>) -> Option<(u32, [u32; 3])> {
    h.map(|(i, h)| (i, [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()]))
}

/// Checks `rays` through the BVH against brute force with every kernel, and the kernels against
/// each other bit for bit; returns how many rays hit.
/// Asserts that the mesh's bounds are those of its triangles' corners (made as the blocks are).
fn assert_bounds(data: &MeshData, geom: &MeshGeom) {
    let (lo, hi) = data.triangles.iter().flatten().fold(
        (Vec3A::INFINITY, Vec3A::NEG_INFINITY),
        |(lo, hi), &i| {
            let p = Vec3A::from(data.positions[i as usize]);
            (lo.min(p), hi.max(p))
        },
    );
    let got = (geom.bounds.min, geom.bounds.max);
    assert_eq!(got, (lo, hi), "the mesh's bounds");
    assert_eq!(geom.validate(), Ok(()), "the mesh's BVH");
    for builder in [
        caustic::accel::Builder::Ploc,
        caustic::accel::Builder::BinnedSah,
    ] {
        let other = MeshGeom::with_builder(data.clone(), 0, builder);
        assert_eq!(other.validate(), Ok(()), "the {builder:?} BVH");
    }
}

fn check_agreement(data: &MeshData, rays: &[Ray]) -> usize {
    let mut geom = MeshGeom::new(data.clone(), 0);
    assert_bounds(data, &geom);
    let mut first: Option<Vec<_>> = None;
    let mut hits = 0;
    for kernel in KERNELS {
        let used = geom.bvh.set_kernel(kernel);
        hits = check_kernel(data, &geom, rays);
        let results: Vec<_> = rays
            .iter()
            .map(|r| (bits(geom.intersect(r)), geom.any_hit(r).map(f32::to_bits)))
            .collect();
        assert_streams_agree(&geom, rays, &results, used);
        match &first {
            None => first = Some(results),
            Some(f) => {
                for (k, (a, b)) in f.iter().zip(&results).enumerate() {
                    assert_eq!(a, b, "ray {k}: {used:?} differs from the scalar kernel");
                }
            }
        }
    }
    hits
}

/// A ray's closest hit ([`bits`]) and any hit (`t`'s bits).
type RayResult = (Option<(u32, [u32; 3])>, Option<u32>);

/// Asserts that the stream queries give the single-ray `results` (`intersect`, `any_hit`), for
/// the whole of `rays` as one stream and cut into streams of lengths that leave lanes idle,
/// refill them mid-stream, or hold one ray: incoherent streams bit for bit; coherent ones
/// (packets of eight, here of rays going anywhere: the hardest case for them) the same closest
/// `t` bit for bit by a triangle really hit there, and the same occlusion.
fn assert_streams_agree(geom: &MeshGeom, rays: &[Ray], results: &[RayResult], kernel: Kernel) {
    let runs = [rays.len().max(1), 1, 3, 8, 37].map(|n| (n, Coherence::Incoherent));
    let packets = [rays.len().max(1), 5, 64].map(|n| (n, Coherence::Coherent));
    for (len, coherence) in runs.into_iter().chain(packets) {
        for (c, (rays, want)) in rays.chunks(len).zip(results.chunks(len)).enumerate() {
            let mut closest = vec![
                Some((
                    7,
                    TriangleHit {
                        t: 1.0,
                        b1: 0.0,
                        b2: 0.0
                    }
                ));
                rays.len()
            ];
            let mut any = vec![Some(1.0); rays.len()];
            geom.intersect_stream(rays, &mut closest, coherence);
            geom.any_hit_stream(rays, &mut any, coherence);
            for (k, w) in want.iter().enumerate() {
                let got = (bits(closest[k]), any[k].map(f32::to_bits));
                let what = format!(
                    "{kernel:?}: ray {} in {coherence:?} streams of {len}",
                    c * len + k
                );
                if coherence == Coherence::Incoherent {
                    assert_eq!(&got, w, "{what}: the stream differs from ray by ray");
                } else {
                    // Packets: the same `t`, by the same or another triangle hit at exactly
                    // that `t`; the same occlusion.
                    assert_eq!(got.1.is_some(), w.1.is_some(), "{what}: any hit");
                    if got.0 != w.0 {
                        let (Some((tri, h)), Some((_, [t, _, _]))) = (closest[k], w.0) else {
                            panic!("{what}: hit or miss differs from ray by ray");
                        };
                        assert_eq!(h.t.to_bits(), t, "{what}: t differs");
                        let [a, b, c] = geom.corners(tri);
                        let own = triangle::intersect(
                            &RayShear::new(&rays[k]),
                            a,
                            b,
                            c,
                            rays[k].tmin,
                            rays[k].tmax,
                        );
                        assert_eq!(
                            own.map(|o| [o.t, o.b1, o.b2].map(f32::to_bits)),
                            Some([h.t, h.b1, h.b2].map(f32::to_bits)),
                            "{what}: the hit is not its triangle's"
                        );
                    }
                }
            }
        }
    }
}

/// Checks `rays` through the BVH, with its current kernel, against brute force; returns how
/// many hit.
fn check_kernel(data: &MeshData, geom: &MeshGeom, rays: &[Ray]) -> usize {
    let order = geom.bvh.order();
    let kernel = geom.bvh.kernel();
    let mut hits = 0;
    for (k, ray) in rays.iter().enumerate() {
        let (t, tris) = brute_force(data, ray);
        let got = geom.intersect(ray);
        match got {
            None => assert!(
                tris.is_empty(),
                "ray {k}, {kernel:?}: BVH missed, brute force hit {tris:?} at {t}"
            ),
            Some((tri, h)) => {
                hits += 1;
                assert_eq!(h.t, t, "ray {k}, {kernel:?}: t differs");
                let file_tri = order[tri as usize];
                assert!(
                    tris.contains(&file_tri),
                    "ray {k}, {kernel:?}: triangle {file_tri} not in {tris:?}"
                );
            }
        }
        assert_eq!(
            geom.any_hit(ray).is_some(),
            got.is_some(),
            "ray {k}, {kernel:?}: any_hit"
        );
    }
    hits
}

/// Returns a height field over `[-1, 1]²` in xz with `n × n` vertices, wave heights in y.
fn height_field(n: u32) -> MeshData {
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
            let z = -1.0 + 2.0 * j as f64 / (n - 1) as f64;
            let y = 0.05 * ((4.0 * x + 1.0).sin() + (9.0 * z + 2.0).sin())
                + 0.05 * (23.0 * (0.6 * x + 0.8 * z) + 3.0).sin();
            positions.push(Vec3::new(x as f32, y as f32, z as f32));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b) = (j * n + i, j * n + i + 1);
            let (c, d) = (a + n, b + n);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    mesh(positions, triangles)
}

/// Returns a closed cube surface with an `n × n` grid per face, vertices welded, rotated so no
/// edge is axis-aligned.
fn closed_cube(n: i32) -> MeshData {
    let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 1.1);
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |p: [i32; 3]| {
        *index.entry(p).or_insert_with(|| {
            let q = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * (2.0 / n as f64) - 1.0;
            positions.push((rot * q).as_vec3());
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            let lattice = |u: i32, v: i32| {
                let mut p = [0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                p
            };
            for v in 0..n {
                for u in 0..n {
                    let a = vertex(lattice(u, v));
                    let b = vertex(lattice(u + 1, v));
                    let c = vertex(lattice(u, v + 1));
                    let d = vertex(lattice(u + 1, v + 1));
                    triangles.push([a, b, d]);
                    triangles.push([a, d, c]);
                }
            }
        }
    }
    mesh(positions, triangles)
}

/// Returns the mesh's shared vertices and the midpoints of its edges (each once).
fn targets(data: &MeshData, keep: impl Fn(Vec3A) -> bool) -> Vec<Vec3A> {
    let mut edges = BTreeSet::new();
    for t in &data.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    let p = |i: u32| Vec3A::from(data.positions[i as usize]);
    let mut out: Vec<Vec3A> = (0..data.positions.len() as u32).map(p).collect();
    out.extend(edges.iter().map(|&(a, b)| (p(a) + p(b)) * 0.5));
    out.retain(|&q| keep(q));
    out
}

#[test]
fn random_triangle_soup_matches_brute_force() {
    let mut rng = Rng(7);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for t in 0..2000u32 {
        let c = Vec3::new(
            rng.uniform(-5.0, 5.0),
            rng.uniform(-5.0, 5.0),
            rng.uniform(-5.0, 5.0),
        );
        let size = rng.uniform(0.05, 1.0);
        for _ in 0..3 {
            positions.push(c + Vec3::from(rng.unit_vector()) * size);
        }
        triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    let data = mesh(positions, triangles);
    let rays: Vec<Ray> = (0..3000)
        .map(|_| {
            let o = Vec3A::new(
                rng.uniform(-7.0, 7.0),
                rng.uniform(-7.0, 7.0),
                rng.uniform(-7.0, 7.0),
            );
            let d = rng.unit_vector() * rng.uniform(0.5, 2.0); // t is in units of |d|
            Ray::new(o, d)
        })
        .collect();
    let hits = check_agreement(&data, &rays);
    assert!(
        hits > 500,
        "only {hits} of 3000 rays hit: the test is too weak"
    );
}

#[test]
fn wave_height_field_matches_brute_force() {
    let data = height_field(65);
    let mut rng = Rng(11);
    let rays: Vec<Ray> = (0..2000)
        .map(|k| {
            let o = Vec3A::new(
                rng.uniform(-1.2, 1.2),
                rng.uniform(0.2, 1.0),
                rng.uniform(-1.2, 1.2),
            );
            let mut d = rng.unit_vector();
            if k % 4 != 0 {
                d.y = -d.y.abs().max(0.3); // mostly downwards and steep, so most of those hit
            }
            let ray = Ray::new(o, d);
            if k % 5 == 0 { ray.with_tmax(0.5) } else { ray }
        })
        .collect();
    let hits = check_agreement(&data, &rays);
    assert!(
        hits > 500,
        "only {hits} of 2000 rays hit: the test is too weak"
    );
}

/// A mesh long enough that the builder opens its top nodes by parallel halving (2^18
/// references or more) agrees with brute force, and builds the same tree on one and two threads.
#[test]
fn large_height_field_matches_brute_force_and_builds_alike_on_one_and_two_threads() {
    let data = height_field(380); // 2 · 379² = 287 282 triangles
    assert!(data.triangles.len() >= 1 << 18);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| MeshGeom::new(data.clone(), 0))
    };
    let (one, two) = (build(1), build(2));
    assert_eq!(one.validate(), Ok(()));
    assert_eq!(
        one.bvh.order(),
        two.bvh.order(),
        "the triangle order differs"
    );
    assert_bounds(&data, &two);
    let leaves = |g: &MeshGeom| {
        g.bvh
            .leaves()
            .iter()
            .map(|l| (l.first, l.count))
            .collect::<Vec<_>>()
    };
    assert_eq!(leaves(&one), leaves(&two), "the leaves differ");
    let mut rng = Rng(17);
    let rays: Vec<Ray> = (0..300)
        .map(|_| {
            let o = Vec3A::new(rng.uniform(-0.6, 0.6), 0.5, rng.uniform(-0.6, 0.6));
            let mut d = rng.unit_vector();
            d.y = -d.y.abs().max(0.6); // steep enough to meet the surface inside [-1, 1]²
            Ray::new(o, d)
        })
        .collect();
    let hits = check_kernel(&data, &two, &rays);
    let results: Vec<_> = rays
        .iter()
        .map(|r| (bits(two.intersect(r)), two.any_hit(r).map(f32::to_bits)))
        .collect();
    assert_streams_agree(&two, &rays, &results, two.bvh.kernel());
    assert!(
        hits > 200,
        "only {hits} of 300 rays hit: the test is too weak"
    );
}

/// A mesh of one triangle (a BVH without nodes) and an empty stream: the stream queries still
/// answer ray by ray as the single-ray ones do.
#[test]
fn streams_over_a_single_triangle_and_empty_streams() {
    let data = mesh(
        vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ],
        vec![[0, 1, 2]],
    );
    let geom = MeshGeom::new(data.clone(), 0);
    let mut rng = Rng(23);
    let rays: Vec<Ray> = (0..50)
        .map(|_| {
            let o = Vec3A::new(rng.uniform(-1.5, 1.5), 1.0, rng.uniform(-1.5, 1.5));
            Ray::new(o, Vec3A::new(0.0, -1.0, 0.0))
        })
        .collect();
    let results: Vec<_> = rays
        .iter()
        .map(|r| (bits(geom.intersect(r)), geom.any_hit(r).map(f32::to_bits)))
        .collect();
    let hits = results.iter().filter(|r| r.0.is_some()).count();
    assert!(
        (10..50).contains(&hits),
        "{hits} of 50 rays hit: the test is too weak"
    );
    assert_streams_agree(&geom, &rays, &results, geom.bvh.kernel());
    geom.intersect_stream(&[], &mut [], Coherence::Incoherent);
    geom.any_hit_stream(&[], &mut [], Coherence::Incoherent);
}

/// Camera rays over a height field, the packets' own case: a 64 x 64 image from a pinhole above,
/// a fifth of the rays stopped short, through every kernel, as one coherent stream and as
/// single rays, both against brute force.
#[test]
fn camera_ray_packets_match_single_rays() {
    let data = height_field(65);
    let eye = Vec3A::new(0.1, 1.5, 2.5);
    let rays: Vec<Ray> = (0..64 * 64)
        .map(|k| {
            let (x, y) = ((k % 64) as f32 / 63.0 - 0.5, (k / 64) as f32 / 63.0 - 0.5);
            let dir = Vec3A::new(1.6 * x, -0.55 - 1.2 * y, -1.0);
            let ray = Ray::new(eye, dir);
            if k % 5 == 0 { ray.with_tmax(2.6) } else { ray }
        })
        .collect();
    let hits = check_agreement(&data, &rays);
    assert!(
        (1000..4000).contains(&hits),
        "{hits} of 4096 camera rays hit: the test is too weak"
    );
}

#[test]
fn rays_at_closed_cube_vertices_and_edges_never_escape() {
    let data = closed_cube(24);
    let mut geom = MeshGeom::new(data.clone(), 0);
    let aims = targets(&data, |_| true);
    let mut rng = Rng(3);
    let (mut rays, mut escaped, mut pass) = (0, 0, 0);
    while rays < 1_000_000 {
        geom.bvh.set_kernel(KERNELS[pass % KERNELS.len()]);
        pass += 1;
        for &target in &aims {
            // From anywhere well inside the cube (half-width 1, rotated), every ray must hit.
            let o = rng.unit_vector() * rng.uniform(0.0, 0.5);
            let ray = Ray::new(o, target - o);
            rays += 1;
            if geom.intersect(&ray).is_none() || geom.any_hit(&ray).is_none() {
                escaped += 1;
            }
        }
    }
    assert_eq!(
        escaped, 0,
        "{escaped} of {rays} rays escaped the closed cube"
    );
}

#[test]
fn rays_at_height_field_vertices_and_edges_never_escape() {
    let data = height_field(129);
    let mut geom = MeshGeom::new(data.clone(), 0);
    // Interior targets only: a ray aimed at the outer boundary may pass outside the mesh.
    let aims = targets(&data, |q| q.x.abs() < 0.999 && q.z.abs() < 0.999);
    let mut rng = Rng(5);
    let (mut rays, mut escaped, mut pass) = (0, 0, 0);
    while rays < 1_000_000 {
        geom.bvh.set_kernel(KERNELS[pass % KERNELS.len()]);
        pass += 1;
        for &target in &aims {
            // From above the highest point (0.15) through a target on the surface to below the
            // lowest (-0.15), inside the footprint all along: the ray must cross the surface.
            let inside = |p: Vec3A| p.x.abs() < 1.0 && p.z.abs() < 1.0;
            let (o, d) = loop {
                let mut d = rng.unit_vector();
                d.y = -d.y.abs().max(0.2);
                let o = target - d * ((0.3 - target.y) / -d.y);
                if inside(o) && inside(o + d * (0.5 / -d.y)) {
                    break (o, d);
                }
            };
            let ray = Ray::new(o, d);
            rays += 1;
            if geom.intersect(&ray).is_none() || geom.any_hit(&ray).is_none() {
                escaped += 1;
            }
        }
    }
    assert_eq!(
        escaped, 0,
        "{escaped} of {rays} rays escaped the height field"
    );
}
