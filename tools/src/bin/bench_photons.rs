//! Photon map benchmark: our [`PhotonMap`] against kiddo's `ImmutableKdTree` on the same points.
//!
//! ```text
//! bench_photons [--sizes N,N,...] [--sets uniform,floor] [--queries Q] [--k K] [--verify V] [--reps R]
//! ```
//!
//! For each point set and size it builds both trees on a 1-thread and a 2-thread rayon pool,
//! ours from the photons as the tracer stages them ([`PhotonStream`], directions already
//! encoded, which the renderer does while tracing) and kiddo's from a slice of positions,
//! reports build time (wall clock, the best of `--reps` builds interleaved between the
//! implementations), bytes per photon, and k-nearest query time per query for
//! queries in render order and in random order: on 1 thread by the thread's CPU time, on 2 threads
//! by wall clock divided by the number of queries, each the best of `--reps` runs, interleaved
//! between the implementations so that a slow spell of a shared machine hits them alike. The last column
//! is the load other processes put on the machine meanwhile (cores), which inflates wall clocks.
//! kiddo's bytes are the heap bytes live after its build minus those before (a counting global
//! allocator), so they include everything it owns. Then it checks, on the first `--verify`
//! render-order queries, that both return the same multiset of squared distances.
//!
//! Point sets, all in the unit box: `uniform` (uniform in the cube) and `floor` (uniform on the
//! plane y = 0 exactly, the case where kiddo's builder has panicked; a panic is caught and reported).
//! Queries: a 400 × 250 "camera" grid scanned row by row over the surface the points lie on (the
//! floor, or a wavy height field through the cube) seen in perspective, or the same points shuffled.
//! kiddo is queried with `nearest_n(k)` (sorted, as its docs show) and also `nearest_n(k)
//! .within(inf).unsorted()`, its fastest k-nearest form; our results are unsorted.

use caustic::photon::stream::PhotonStream;
use caustic::photon::{Photon, PhotonMap};
use caustic::sampling::{Pass, Rng};
use caustic_tools::clock::{self, LoadProbe};
use glam::Vec3A;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::num::NonZeroUsize;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// The system allocator, counting the bytes currently allocated.
struct CountingAlloc;

/// Heap bytes currently allocated by the whole process.
static LIVE: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call forwards to `System` with the caller's arguments unchanged; the counter is
// only bookkeeping and never affects the returned pointers.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as received; the caller upholds `alloc`'s contract.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as received; `ptr` came from `alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded as received; the caller upholds `realloc`'s contract.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_add(new_size, Ordering::Relaxed);
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

type Kiddo = ImmutableKdTree<f32, 3>;

struct Options {
    sizes: Vec<usize>,
    sets: Vec<String>,
    queries: usize,
    k: usize,
    verify: usize,
    reps: usize,
}

const USAGE: &str = "usage: bench_photons [--sizes N,N,...] [--sets uniform,floor] [--queries Q] [--k K] [--verify V] [--reps R]";

/// Returns the options from the command line.
fn parse_args() -> Result<Options, String> {
    let mut o = Options {
        sizes: vec![1_000_000, 10_000_000],
        sets: vec!["uniform".into(), "floor".into()],
        queries: 100_000,
        k: 50,
        verify: 5_000,
        reps: 3,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut val = || args.next().ok_or(format!("missing value for {a}"));
        let num = |v: &str| {
            v.replace('_', "")
                .parse::<f64>()
                .map(|x| x as usize)
                .map_err(|_| format!("not a number: '{v}'"))
        };
        match a.as_str() {
            "--sizes" => {
                o.sizes = val()?.split(',').map(num).collect::<Result<_, _>>()?;
            }
            "--sets" => o.sets = val()?.split(',').map(String::from).collect(),
            "--queries" => o.queries = num(&val()?)?.max(1),
            "--k" => o.k = num(&val()?)?.max(1),
            "--verify" => o.verify = num(&val()?)?,
            "--reps" => o.reps = num(&val()?)?.max(1),
            _ => return Err(USAGE.into()),
        }
    }
    if let Some(s) = o
        .sets
        .iter()
        .find(|s| !["uniform", "floor"].contains(&s.as_str()))
    {
        return Err(format!("unknown point set '{s}'\n{USAGE}"));
    }
    Ok(o)
}

/// Returns `n` photons of point set `set`.
fn photons(set: &str, n: usize) -> Vec<Photon> {
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut r = Rng::new(1, Pass::Photon, i as u64);
            let (x, y, z) = (r.next_f32(), r.next_f32(), r.next_f32());
            let position = match set {
                "floor" => Vec3A::new(x, 0.0, z),
                _ => Vec3A::new(x, y, z),
            };
            Photon {
                position,
                power: Vec3A::splat(1.0 / n as f32),
                dir: Vec3A::Y,
                normal: Vec3A::Y,
                direct: true,
            }
        })
        .collect()
}

/// Returns query points in render order: a 400 × 250 perspective view of the set's surface.
fn render_order_queries(set: &str, q: usize) -> Vec<[f32; 3]> {
    let w = ((q as f64 * 1.6).sqrt().round() as usize).max(1);
    let h = q.div_ceil(w);
    let mut out = Vec::with_capacity(w * h);
    for py in 0..h {
        let v = (py as f32 + 0.5) / h as f32;
        // Rows nearer the camera cover less ground, as in a perspective view.
        let z = 0.05 + 0.9 * v * v;
        let half = 0.15 + 0.3 * v;
        for px in 0..w {
            let u = (px as f32 + 0.5) / w as f32;
            let x = 0.5 + (2.0 * u - 1.0) * half;
            let y = match set {
                "floor" => 0.0,
                _ => 0.5 + 0.2 * (6.0 * x).sin() * (5.0 * z).cos(),
            };
            out.push([x, y, z]);
        }
    }
    out.truncate(q);
    out
}

/// Returns `v` shuffled deterministically.
fn shuffled<T: Copy>(v: &[T]) -> Vec<T> {
    let mut out = v.to_vec();
    let mut r = Rng::new(2, Pass::Pixel, 0);
    for i in (1..out.len()).rev() {
        out.swap(i, r.below(i as u32 + 1) as usize);
    }
    out
}

/// Returns a rayon pool of `n` threads.
fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("a rayon pool")
}

/// Returns the seconds `f` takes on a pool of `threads` threads, and its result.
fn timed<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> (f64, R) {
    pool(threads).install(|| {
        let t = Instant::now();
        let r = f();
        (t.elapsed().as_secs_f64(), r)
    })
}

/// A k-nearest query of one implementation; returns a value that depends on its result.
type Query<'a> = &'a (dyn Fn(&[f32; 3]) -> f32 + Sync);

/// Returns the nanoseconds per query of one run of `one` over `queries`: on the calling thread
/// by its CPU time (`threads == 1`, robust to other load), or on a pool of `threads` threads by
/// wall clock.
fn per_query(threads: usize, queries: &[[f32; 3]], one: Query) -> f64 {
    let s = if threads == 1 {
        let t = clock::thread_cpu_s();
        std::hint::black_box(queries.iter().map(one).sum::<f32>());
        clock::thread_cpu_s() - t
    } else {
        let (s, sum) = timed(threads, || {
            queries
                .par_chunks(256)
                .map(|c| c.iter().map(one).sum::<f32>())
                .sum::<f32>()
        });
        std::hint::black_box(sum);
        s
    };
    s * 1e9 / queries.len() as f64
}

/// One implementation's figures for one point set and size.
#[derive(Default)]
struct Row {
    build_s: [f64; 2],
    bytes_per_photon: f64,
    /// ns per query: [render 1T, render 2T, random 1T, random 2T].
    query_ns: [f64; 4],
    note: String,
}

/// Measures the queries of every implementation: render order and random, 1 and 2 threads,
/// each the best of `reps` runs. The runs are interleaved (every implementation and case once,
/// then again), so that a slow spell of a shared machine hits all implementations alike.
fn query_figures(
    reps: usize,
    render: &[[f32; 3]],
    random: &[[f32; 3]],
    impls: &[Query],
) -> Vec<[f64; 4]> {
    let cases = [(1, render), (2, render), (1, random), (2, random)];
    for one in impls {
        per_query(1, &render[..render.len().min(2000)], *one); // warm-up
    }
    let mut best = vec![[f64::INFINITY; 4]; impls.len()];
    for _ in 0..reps.max(1) {
        for (one, best) in impls.iter().zip(&mut best) {
            for (b, &(threads, queries)) in best.iter_mut().zip(&cases) {
                *b = b.min(per_query(threads, queries, *one));
            }
        }
    }
    best
}

/// Returns the sorted squared distances of our k nearest photons to `q`.
fn ours_sorted(map: &PhotonMap, q: &[f32; 3], k: usize) -> Vec<f32> {
    let mut out = Vec::new();
    map.knn(Vec3A::from_array(*q), k, f32::INFINITY, &mut out);
    let mut d: Vec<f32> = out.iter().map(|e| e.0).collect();
    d.sort_by(f32::total_cmp);
    d
}

/// Runs one point set at one size; returns our row, kiddo's rows and the verification line.
fn bench(set: &str, n: usize, o: &Options) -> (Row, Vec<(String, Row)>, String) {
    let k = o.k;
    let input = photons(set, n);
    let render = render_order_queries(set, o.queries);
    let random = shuffled(&render);

    let mut ours = Row::default();
    let points: Vec<[f32; 3]> = input.iter().map(|p| p.position.to_array()).collect();
    // Builds, each the best of `reps`, interleaved like the queries: ours on 1 thread, kiddo's
    // on 1, ours on 2, kiddo's on 2, then again. A single build per process varied by ±30%:
    // whichever came first paid for faulting in fresh memory. Our build starts where the
    // renderer's does: from the tracer's staged photons (it encodes the directions as it stores
    // them, in parallel with tracing); kiddo's from a slice.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {})); // kiddo's builder may panic: silence its message
    let kiddo_build = |threads| {
        timed(threads, || {
            std::panic::catch_unwind(|| Kiddo::new_from_slice(&points))
        })
    };
    let mut kid = Row::default();
    let (mut ours_best, mut kid_best) = ([f64::INFINITY; 2], [f64::INFINITY; 2]);
    let (mut map, mut kid_tree) = (None, None);
    let mut kid_bytes = 0;
    for _ in 0..o.reps {
        for (slot, threads) in [(0, 1), (1, 2)] {
            let stream = PhotonStream::of(&input);
            drop(map.take()); // the last build's map, before this one
            let (b, m) = timed(threads, move || PhotonMap::from_stream(stream));
            ours_best[slot] = ours_best[slot].min(b);
            map = Some(m);
            drop(kid_tree.take());
            let before = LIVE.load(Ordering::Relaxed);
            let (k, t) = kiddo_build(threads);
            kid_bytes = LIVE.load(Ordering::Relaxed).saturating_sub(before);
            kid_best[slot] = kid_best[slot].min(k);
            kid_tree = Some(t);
        }
    }
    std::panic::set_hook(hook);
    drop(input);
    let map = map.expect("at least one build");
    ours.build_s = ours_best;
    ours.bytes_per_photon = map.bytes() as f64 / map.len() as f64;
    if let Err(e) = map.validate() {
        ours.note = format!("INVALID: {e}");
    }
    let ours_query = |q: &[f32; 3]| {
        thread_local!(static OUT: std::cell::RefCell<Vec<(f32, caustic::photon::PhotonId)>> =
            const { std::cell::RefCell::new(Vec::new()) });
        OUT.with_borrow_mut(|out| map.knn(Vec3A::from_array(*q), k, f32::INFINITY, out))
    };

    let tree = match kid_tree.expect("at least one build") {
        Ok(Ok(t)) => t,
        Ok(Err(e)) => {
            kid.note = format!("build error: {e:?}");
            ours.query_ns = query_figures(o.reps, &render, &random, &[&ours_query])[0];
            return (ours, vec![("kiddo".into(), kid)], String::new());
        }
        Err(_) => {
            kid.note = "panics".into();
            ours.query_ns = query_figures(o.reps, &render, &random, &[&ours_query])[0];
            return (ours, vec![("kiddo".into(), kid)], String::new());
        }
    };
    kid.build_s = kid_best;
    kid.bytes_per_photon = kid_bytes as f64 / n as f64;
    let nz = NonZeroUsize::new(k).expect("k >= 1");
    let mut kid_unsorted = Row {
        build_s: kid.build_s,
        bytes_per_photon: kid.bytes_per_photon,
        ..Row::default()
    };
    let kid_query = |q: &[f32; 3]| {
        let r = tree
            .query(q)
            .nearest_n::<SquaredEuclidean<f32>>(nz)
            .execute();
        r.last().map_or(0.0, |e| e.distance)
    };
    let kid_unsorted_query = |q: &[f32; 3]| {
        let r = tree
            .query(q)
            .nearest_n::<SquaredEuclidean<f32>>(nz)
            .within(f32::INFINITY)
            .unsorted()
            .execute();
        r.iter().map(|e| e.distance).fold(0.0, f32::max)
    };
    let figures = query_figures(
        o.reps,
        &render,
        &random,
        &[&ours_query, &kid_query, &kid_unsorted_query],
    );
    [ours.query_ns, kid.query_ns, kid_unsorted.query_ns] = [figures[0], figures[1], figures[2]];

    // Verification: the same multiset of distances, exactly.
    let checked = render.len().min(o.verify);
    let (same, worst) = render[..checked]
        .par_iter()
        .map(|q| {
            let a = ours_sorted(&map, q, k);
            let b: Vec<f32> = tree
                .query(q)
                .nearest_n::<SquaredEuclidean<f32>>(nz)
                .execute()
                .iter()
                .map(|e| e.distance)
                .collect();
            let diff = if a.len() != b.len() {
                f32::INFINITY
            } else {
                a.iter()
                    .zip(&b)
                    .map(|(x, y)| (x - y).abs() / x.max(*y).max(f32::MIN_POSITIVE))
                    .fold(0.0, f32::max)
            };
            ((a == b) as usize, diff)
        })
        .reduce(|| (0, 0.0f32), |x, y| (x.0 + y.0, x.1.max(y.1)));
    let verify = format!(
        "{set} n={n}: {same}/{checked} queries return identical k={k} distances (max relative difference {worst:e})"
    );
    (
        ours,
        vec![
            ("kiddo".into(), kid),
            ("kiddo unsorted".into(), kid_unsorted),
        ],
        verify,
    )
}

/// Returns a table cell for a time in ns per query (or blank).
fn ns(x: f64) -> String {
    if x > 0.0 {
        format!("{x:.0}")
    } else {
        "-".into()
    }
}

fn main() -> ExitCode {
    let o = match parse_args() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    println!(
        "k = {}, {} queries; query times are ns per query (wall clock / queries); ratio = kiddo / ours (> 1: ours faster)",
        o.k, o.queries
    );
    println!(
        "{:<8} {:>9} {:<15} {:>9} {:>9} {:>8} {:>10} {:>10} {:>10} {:>10}  note",
        "set",
        "photons",
        "impl",
        "build 1T",
        "build 2T",
        "B/photon",
        "render 1T",
        "render 2T",
        "random 1T",
        "random 2T"
    );
    let mut checks = Vec::new();
    for set in &o.sets {
        for &n in &o.sizes {
            let probe = LoadProbe::now();
            let (mut ours, kids, verify) = bench(set, n, &o);
            let load = probe.other_load(&LoadProbe::now());
            ours.note = format!("{} other load {load:.1} cores", ours.note);
            let line = |name: &str, r: &Row| {
                println!(
                    "{:<8} {:>9} {:<15} {:>8.3}s {:>8.3}s {:>8.1} {:>10} {:>10} {:>10} {:>10}  {}",
                    set,
                    n,
                    name,
                    r.build_s[0],
                    r.build_s[1],
                    r.bytes_per_photon,
                    ns(r.query_ns[0]),
                    ns(r.query_ns[1]),
                    ns(r.query_ns[2]),
                    ns(r.query_ns[3]),
                    r.note
                )
            };
            line("caustic", &ours);
            for (name, kid) in &kids {
                line(name, kid);
                if kid.query_ns[0] > 0.0 {
                    let ratio = |a: f64, b: f64| format!("{:.2}x", a / b);
                    println!(
                        "{:<8} {:>9} {:<15} {:>9} {:>9} {:>8} {:>10} {:>10} {:>10} {:>10}",
                        "",
                        "",
                        format!("  ratio {}", if name.contains("uns") { "uns." } else { "" }),
                        ratio(kid.build_s[0], ours.build_s[0]),
                        ratio(kid.build_s[1], ours.build_s[1]),
                        ratio(kid.bytes_per_photon, ours.bytes_per_photon),
                        ratio(kid.query_ns[0], ours.query_ns[0]),
                        ratio(kid.query_ns[1], ours.query_ns[1]),
                        ratio(kid.query_ns[2], ours.query_ns[2]),
                        ratio(kid.query_ns[3], ours.query_ns[3]),
                    );
                }
            }
            if !verify.is_empty() {
                checks.push(verify);
            }
        }
    }
    for c in checks {
        println!("check: {c}");
    }
    ExitCode::SUCCESS
}
