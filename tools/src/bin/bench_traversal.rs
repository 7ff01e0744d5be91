//! Traversal benchmark against the Embree reference harness (`../shared/bench/README.md`).
//!
//! ```text
//! bench_traversal [--reps N] [--build-reps N] [--verify K] [--mt N] [--tiles N] [--kernel K]
//!                 [--ab A,B] [--builder B] [--count] MESH RAYS [RAYS...]
//! ```
//!
//! Besides single rays, each set is traced on one thread through the stream API
//! ([`MeshGeom::intersect_stream`], [`MeshGeom::any_hit_stream`]) in streams of 256 rays, as the
//! harness passes them to Embree's `rtcIntersect1M` (modes `intersect1M`, `occluded1M`), with
//! the coherence the harness tells Embree: camera rays coherent, random rays incoherent.
//!
//! `--ab A,B` replaces the report with a comparison of two configurations in one process, each a
//! node-test kernel, traced ray by ray (`avx2`) or through the stream API (`avx2/1M`): passes
//! with `A` and `B` alternate, and `AB` lines give each one's times and the median of the
//! per-pair ratios. A shared VM drifts by 10-30% within minutes, so separate runs cannot
//! tell two kernels apart by a few percent; passes a fraction of a second apart can.
//!
//! `--count` turns on the traversal counters that `--stats` and `--heatmap` read
//! ([`caustic::accel::counters`]), to measure what counting costs: run with and without it. With
//! it, single-threaded `TRACE` lines also give `nodes_per_ray` and `tris_per_ray` (triangles tested).
//!
//! `--tiles N` also traces each image's rays (primary sets) on one thread in `N`×`N` tiles, the
//! order of a tiled renderer, to measure what ordering camera rays gains over scanlines (modes
//! `intersect1_tilesN` and `occluded1_tilesN`).
//!
//! `--kernel scalar|sse2|avx2` picks the BVH node test (default: the fastest the CPU runs);
//! `--builder sah|ploc` the BVH builder (default: `sah`, the one meshes use); the report's
//! `quality` names the build configuration and the kernel.
//!
//! Reads the harness's `.mesh` and `.rays` files, builds the mesh's BVH exactly as the renderer
//! does ([`MeshGeom::with_builder`] from a [`MeshData`]) and traces every ray set in file order: closest
//! hit (`mode=intersect1`) and any hit (`mode=occluded1`) on the calling thread, then the same on
//! `--mt` threads (`mode=intersect1_<N>t`, `occluded1_<N>t`; 0 skips them). Each mode runs one
//! untimed warm-up pass and `--reps` timed passes, timed by wall clock and by the tracing thread's
//! CPU time (multi-threaded modes: wall clock only). FTZ/DAZ are on in every tracing thread.
//! It prints `BUILD`, `TRACE` and `VERIFY` lines in the harness's key=value format
//! (`engine=caustic`), so `run.sh` (`EXTRA_BENCH`) and `make_table.py` put it beside Embree.
//!
//! Checksums: `sum_prim` sums the triangle index in the *file's* order (mapped back through the
//! BVH order) in the untimed warm-up pass, so it compares with Embree's `primID`; timed passes sum
//! the BVH-order index the tracer returns, as Embree's loop sums its `primID`, and must agree
//! among themselves. Our test accepts `t` in the open interval
//! `(tmin, tmax)`, the files' rays have `tmin = 0`, so only a ray starting exactly on the surface
//! could differ from Embree's closed interval.

use caustic::accel::mesh::MeshGeom;
use caustic::accel::stream::Coherence;
use caustic::accel::{Builder, Kernel};
use caustic::geometry::Ray;
use caustic::geometry::mesh::MeshData;
use caustic_tools::benchfile::{RayKind, RayRecord, RaySet, read_mesh, read_rays};
use caustic_tools::clock::{self, LoadProbe};
use glam::Vec3A;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

/// Rays per parallel work item: large enough to amortise scheduling, small enough to balance.
const CHUNK: usize = 4096;
/// Brute-force budget (triangle tests per ray set) for the default `--verify`, as `run.sh` uses.
const VERIFY_BUDGET: usize = 400_000_000;

struct Options {
    reps: usize,
    build_reps: usize,
    verify: Option<usize>,
    mt: usize,
    tiles: usize,
    kernel: Kernel,
    /// `--ab A,B`: compare two configurations pass by pass instead of the usual report.
    ab: Option<(Config, Config)>,
    builder: Builder,
    mesh: PathBuf,
    rays: Vec<PathBuf>,
}

const USAGE: &str = "usage: bench_traversal [--reps N] [--build-reps N] [--verify K] [--mt N] [--tiles N] \
                     [--kernel K] [--ab A,B] [--builder sah|ploc] [--count] MESH RAYS [RAYS...] \
                     (kernels K: scalar, sse2, avx2; configurations A, B: K or K/1M, the stream API)";

/// What `--ab` compares: a node-test kernel, ray by ray or through the stream API (`K/1M`).
#[derive(Clone, Copy, Debug)]
struct Config {
    kernel: Kernel,
    stream: bool,
}

impl std::fmt::Display for Config {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let k = format!("{:?}", self.kernel).to_lowercase();
        write!(f, "{k}{}", if self.stream { "/1M" } else { "" })
    }
}

impl Config {
    fn parse(s: &str) -> Result<Config, String> {
        let (k, stream) = match s.strip_suffix("/1M") {
            Some(k) => (k, true),
            None => (s, false),
        };
        Ok(Config {
            kernel: kernel(Some(k))?,
            stream,
        })
    }
}

/// Parses a kernel's name.
fn kernel(name: Option<&str>) -> Result<Kernel, String> {
    match name {
        Some("scalar") => Ok(Kernel::Scalar),
        Some("sse2") => Ok(Kernel::Sse2),
        Some("avx2") => Ok(Kernel::Avx2),
        k => Err(format!("a kernel is scalar, sse2 or avx2, got {k:?}")),
    }
}

fn parse_args() -> Result<Options, String> {
    let mut o = Options {
        reps: 5,
        build_reps: 3,
        verify: None,
        mt: 2,
        tiles: 0,
        kernel: Kernel::best(),
        ab: None,
        builder: Builder::BinnedSah,
        mesh: PathBuf::new(),
        rays: Vec::new(),
    };
    let mut pos = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut num = |name: &str| -> Result<usize, String> {
            let v = args.next().ok_or(format!("missing value for {name}"))?;
            v.parse()
                .map_err(|_| format!("{name} wants a whole number, got '{v}'"))
        };
        match a.as_str() {
            "--reps" => o.reps = num("--reps")?.max(1),
            "--build-reps" => o.build_reps = num("--build-reps")?.max(1),
            "--verify" => o.verify = Some(num("--verify")?),
            "--mt" => o.mt = num("--mt")?,
            "--tiles" => o.tiles = num("--tiles")?.clamp(1, 4096),
            "--kernel" => o.kernel = kernel(args.next().as_deref())?,
            "--ab" => {
                let v = args.next().unwrap_or_default();
                let (a, b) = v
                    .split_once(',')
                    .ok_or(format!("--ab wants two configurations as A,B, got '{v}'"))?;
                let (a, b) = (Config::parse(a)?, Config::parse(b)?);
                for c in [a, b] {
                    if c.kernel > Kernel::best() {
                        let k = c.kernel;
                        return Err(format!("--ab: this CPU cannot run the {k:?} kernel"));
                    }
                }
                o.ab = Some((a, b));
            }
            "--builder" => {
                o.builder = match args.next().as_deref() {
                    Some("sah") => Builder::BinnedSah,
                    Some("ploc") => Builder::Ploc,
                    b => return Err(format!("--builder wants sah or ploc, got {b:?}")),
                }
            }
            "--count" => caustic::accel::counters::enable(),
            "-h" | "--help" => return Err(USAGE.into()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}\n{USAGE}")),
            _ => pos.push(PathBuf::from(a)),
        }
    }
    if pos.len() < 2 {
        return Err(USAGE.into());
    }
    o.mesh = pos.remove(0);
    o.rays = pos;
    Ok(o)
}

fn base_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |s| s.to_string_lossy().into())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench_traversal: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let o = parse_args()?;
    let ftz = clock::enable_ftz_daz();
    let t0 = Instant::now();
    let data = Arc::new(read_mesh(&o.mesh)?);
    let sets = o
        .rays
        .iter()
        .map(|p| read_rays(p))
        .collect::<Result<Vec<_>, _>>()?;
    let mesh = base_name(&o.mesh);
    let tris = data.triangles.len();
    println!(
        "INFO engine=caustic loaded mesh={mesh} vertices={} triangles={tris} ray_sets={} in {:.1} ms \
         ftz_daz={} threads_available={}",
        data.positions.len(),
        sets.len(),
        t0.elapsed().as_secs_f64() * 1e3,
        ftz as u8,
        rayon::current_num_threads()
    );
    let mut geom = build(
        &data,
        &mesh,
        o.builder,
        &quality(o.builder, o.kernel),
        o.build_reps,
    )?;
    if let Some(ab) = o.ab {
        for set in &sets {
            compare(&mut geom, &mesh, set, ab, o.reps);
        }
        return Ok(());
    }
    let kernel = geom.bvh.set_kernel(o.kernel);
    let quality = quality(o.builder, kernel);
    let ctx = Ctx {
        geom: &geom,
        order: geom.bvh.order(),
        mesh: &mesh,
        quality: &quality,
        tris,
        reps: o.reps,
    };
    let pool = (o.mt > 0)
        .then(|| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(o.mt)
                .start_handler(|_| {
                    clock::enable_ftz_daz();
                })
                .build()
        })
        .transpose()?;
    for set in &sets {
        ctx.trace_set(set, None, "");
        if o.tiles > 0 && set.width > 0 {
            ctx.trace_set(&in_tiles(set, o.tiles), None, &format!("_tiles{}", o.tiles));
        }
        if let Some(pool) = &pool {
            ctx.trace_set(set, Some((pool, o.mt)), "");
        }
        let k = o
            .verify
            .unwrap_or((VERIFY_BUDGET / tris.max(1)).clamp(10, 2000));
        verify(&ctx, &data, set, k);
    }
    Ok(())
}

/// `--ab`: traces `set` with configurations `a` and `b` in turn, pass after pass on this
/// thread, `reps` pairs per query (after one untimed pass of each), and prints an `AB` line per
/// query: each one's best and median CPU time and the median of the per-pair ratios `a / b`
/// (above 1: `b` is faster). A shared VM's speed drifts by 10-30% within minutes, so two
/// configurations timed in separate runs cannot be told apart by a few percent; passes a
/// fraction of a second apart can. Both must find the same hits (`same=0` flags a difference).
fn compare(geom: &mut MeshGeom, mesh: &str, set: &RaySet, (a, b): (Config, Config), reps: usize) {
    for occluded in [false, true] {
        let mut pass = |c: Config| {
            geom.bvh.set_kernel(c.kernel);
            let ctx = Ctx {
                geom,
                order: geom.bvh.order(),
                mesh,
                quality: "",
                tris: 0,
                reps: 1,
            };
            let c0 = clock::thread_cpu_s();
            let s = ctx.pass(
                &set.rays,
                Query {
                    occluded,
                    stream: c.stream.then_some(set_coherence(set)),
                },
                false,
                None,
            );
            (clock::thread_cpu_s() - c0, s)
        };
        let same = pass(a).1 == pass(b).1;
        let (mut ta, mut tb, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..reps {
            // Alternate which goes first, so neither always follows the other.
            let (x, y) = if i % 2 == 0 {
                (pass(a).0, pass(b).0)
            } else {
                let y = pass(b).0;
                (pass(a).0, y)
            };
            ta.push(x);
            tb.push(y);
            ratio.push(x / y);
        }
        println!(
            "AB mesh={mesh} rays={} kind={} mode={} a={a} b={b} reps={reps} a_best_s={:.6} \
             a_med_s={:.6} b_best_s={:.6} b_med_s={:.6} ratio_a_over_b_med={:.4} ratio_min={:.4} \
             ratio_max={:.4} same={}",
            base_name(&set.path),
            set.kind.name(),
            if occluded { "occluded1" } else { "intersect1" },
            clock::min(&ta),
            clock::median(&ta),
            clock::min(&tb),
            clock::median(&tb),
            clock::median(&ratio),
            clock::min(&ratio),
            ratio.iter().cloned().fold(f64::MIN, f64::max),
            same as u8,
        );
    }
}

/// Returns an image's rays reordered into `n`×`n` tiles, tile after tile in rows and each tile's
/// rays row by row: the order in which a tiled renderer traces its camera rays. Its `TRACE`
/// lines have modes `intersect1_tilesN` and `occluded1_tilesN`, which `make_table.py` puts in
/// columns of their own; `sum_t` may differ in the last digits from file order (the same hits,
/// added in another order).
fn in_tiles(set: &RaySet, n: usize) -> RaySet {
    let (w, h) = (set.width as usize, set.height as usize);
    let mut rays = Vec::with_capacity(set.rays.len());
    for ty in (0..h).step_by(n) {
        for tx in (0..w).step_by(n) {
            for y in ty..(ty + n).min(h) {
                rays.extend_from_slice(&set.rays[y * w + tx..y * w + (tx + n).min(w)]);
            }
        }
    }
    RaySet {
        path: set.path.clone(),
        kind: set.kind,
        width: set.width,
        height: set.height,
        rays,
    }
}

/// Returns the report's `quality`: the build configuration and the node-test kernel.
fn quality(builder: Builder, kernel: Kernel) -> String {
    format!(
        "{}-{}",
        builder.name(),
        format!("{kernel:?}").to_lowercase()
    )
}

/// Times [`MeshGeom::with_builder`] on one thread (process CPU time) and on all threads (wall time),
/// prints a `BUILD` line for each and returns the last BVH built.
fn build(
    data: &Arc<MeshData>,
    mesh: &str,
    builder: Builder,
    quality: &str,
    reps: usize,
) -> Result<MeshGeom, Box<dyn std::error::Error>> {
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut geom = None;
    for (threads, pool) in [(1, Some(&one)), (0, None)] {
        let (mut wall, mut cpu) = (Vec::new(), Vec::new());
        let l0 = LoadProbe::now();
        while wall.len() < reps || (wall.iter().sum::<f64>() < 0.25 && wall.len() < 100) {
            drop(geom.take());
            let (c0, w0) = (clock::process_cpu_s(), Instant::now());
            let g = match pool {
                Some(p) => p.install(|| MeshGeom::with_builder(Arc::clone(data), 0, builder)),
                None => MeshGeom::with_builder(Arc::clone(data), 0, builder),
            };
            wall.push(w0.elapsed().as_secs_f64());
            cpu.push(clock::process_cpu_s() - c0);
            geom = Some(g);
        }
        let load = l0.other_load(&LoadProbe::now());
        let g = geom.as_ref().ok_or("no build ran")?;
        let (accel, shared) = sizes(g);
        let tris = data.triangles.len().max(1) as f64;
        println!(
            "BUILD engine=caustic mesh={mesh} tris={} quality={quality} threads={threads} reps={} \
             build_ms_min={:.2} build_ms_med={:.2} build_cpu_ms_min={:.2} accel_MB={:.2} \
             accel_B_per_tri={:.1} mesh_MB={:.2} mesh_B_per_tri={:.1} other_load={load:.2}",
            data.triangles.len(),
            wall.len(),
            clock::min(&wall) * 1e3,
            clock::median(&wall) * 1e3,
            clock::min(&cpu) * 1e3,
            accel as f64 / 1048576.0,
            accel as f64 / tris,
            shared as f64 / 1048576.0,
            shared as f64 / tris,
        );
    }
    geom.ok_or_else(|| "no build ran".into())
}

/// Returns the bytes only the tracer needs (BVH nodes, BVH-order index, tracer-only triangle
/// data: `accel_MB`) and the bytes of the attributes shading shares (positions, vertex indices).
fn sizes(g: &MeshGeom) -> (usize, usize) {
    let shared = std::mem::size_of_val(g.data().positions.as_slice())
        + std::mem::size_of_val(g.data().triangles.as_slice());
    (g.bvh.bytes() + g.tracer_bytes(), shared)
}

/// What every trace needs: the mesh, its BVH order and the report's fixed fields.
struct Ctx<'a> {
    geom: &'a MeshGeom,
    order: &'a [u32],
    mesh: &'a str,
    quality: &'a str,
    tris: usize,
    reps: usize,
}

/// The coherence the harness tells Embree of a set: camera rays coherent, random rays not.
fn set_coherence(set: &RaySet) -> Coherence {
    match set.kind {
        RayKind::Primary => Coherence::Coherent,
        RayKind::Incoherent => Coherence::Incoherent,
    }
}

/// Rays per stream in the `1M` modes, as the harness passes to `rtcIntersect1M`.
const STREAM: usize = 256;

/// Runs `f` on the file's rays as streams of [`STREAM`] rays, in order.
fn in_streams(rays: &[RayRecord], mut f: impl FnMut(&[Ray])) {
    let mut buf = Vec::with_capacity(STREAM);
    for c in rays.chunks(STREAM) {
        buf.clear();
        buf.extend(c.iter().map(to_ray));
        f(&buf);
    }
}

/// What a pass asks of each ray.
#[derive(Clone, Copy, Debug)]
struct Query {
    /// Any hit (`occluded`) rather than the closest.
    occluded: bool,
    /// Through the stream API, as Embree's `1M` modes, or ray by ray (`None`).
    stream: Option<Coherence>,
}

/// Closest-hit checksums of a pass, in file order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sums {
    hits: u64,
    sum_t: f64,
    sum_prim: u64,
}

impl Sums {
    fn add(self, o: Sums) -> Sums {
        Sums {
            hits: self.hits + o.hits,
            sum_t: self.sum_t + o.sum_t,
            sum_prim: self.sum_prim + o.sum_prim,
        }
    }
}

#[inline(always)]
fn to_ray(r: &RayRecord) -> Ray {
    Ray {
        origin: Vec3A::from_array(r.origin),
        dir: Vec3A::from_array(r.dir),
        tmin: r.tmin,
        tmax: r.tmax,
    }
}

impl Ctx<'_> {
    /// Closest-hit checksums; `sum_prim` in file order with `file_order`, else in BVH order.
    fn closest(&self, rays: &[RayRecord], file_order: bool) -> Sums {
        let mut s = Sums::default();
        for r in rays {
            if let Some((tri, h)) = self.geom.intersect(&to_ray(r)) {
                s.hits += 1;
                s.sum_t += h.t as f64;
                s.sum_prim += if file_order {
                    self.order[tri as usize]
                } else {
                    tri
                } as u64;
            }
        }
        s
    }

    fn occluded(&self, rays: &[RayRecord]) -> Sums {
        let hits = rays
            .iter()
            .filter(|r| self.geom.any_hit(&to_ray(r)).is_some())
            .count() as u64;
        Sums {
            hits,
            ..Sums::default()
        }
    }

    /// Closest-hit checksums of a stream pass ([`MeshGeom::intersect_stream`], in streams of
    /// [`STREAM`] rays), as [`Ctx::closest`].
    fn closest_stream(&self, rays: &[RayRecord], file_order: bool, coherence: Coherence) -> Sums {
        let mut s = Sums::default();
        let mut out = vec![None; STREAM];
        in_streams(rays, |rays| {
            let out = &mut out[..rays.len()];
            self.geom.intersect_stream(rays, out, coherence);
            for (tri, h) in out.iter().flatten() {
                s.hits += 1;
                s.sum_t += h.t as f64;
                s.sum_prim += if file_order {
                    self.order[*tri as usize]
                } else {
                    *tri
                } as u64;
            }
        });
        s
    }

    fn occluded_stream(&self, rays: &[RayRecord], coherence: Coherence) -> Sums {
        let mut hits = 0;
        let mut out = vec![None; STREAM];
        in_streams(rays, |rays| {
            let out = &mut out[..rays.len()];
            self.geom.any_hit_stream(rays, out, coherence);
            hits += out.iter().flatten().count() as u64;
        });
        Sums {
            hits,
            ..Sums::default()
        }
    }

    /// Runs one closest-hit or any-hit pass over `rays`, ray by ray or in streams, on this
    /// thread or on `pool`, with `sum_prim` in file order or BVH order (see [`Ctx::closest`]).
    fn pass(
        &self,
        rays: &[RayRecord],
        q: Query,
        file_order: bool,
        pool: Option<&rayon::ThreadPool>,
    ) -> Sums {
        let f = |c: &[RayRecord]| match (q.occluded, q.stream) {
            (false, None) => self.closest(c, file_order),
            (true, None) => self.occluded(c),
            (false, Some(k)) => self.closest_stream(c, file_order, k),
            (true, Some(k)) => self.occluded_stream(c, k),
        };
        match pool {
            None => f(rays),
            // Chunk sums are added in file order, so the checksum does not depend on scheduling.
            Some(p) => p.install(|| {
                let parts: Vec<Sums> = rays.par_chunks(CHUNK).map(f).collect();
                parts.into_iter().fold(Sums::default(), Sums::add)
            }),
        }
    }

    /// Times both queries over one ray set and prints their `TRACE` lines.
    /// `order` names the ray order in the mode (`""` for file order).
    fn trace_set(&self, set: &RaySet, mt: Option<(&rayon::ThreadPool, usize)>, order: &str) {
        let mut queries = vec![
            Query {
                occluded: false,
                stream: None,
            },
            Query {
                occluded: true,
                stream: None,
            },
        ];
        if mt.is_none() && order.is_empty() {
            // Streams, as Embree's `rtcIntersect1M` / `rtcOccluded1M` (modes `1M`), told the
            // rays' coherence as the harness tells Embree.
            queries.extend(queries.clone().into_iter().map(|q| Query {
                stream: Some(set_coherence(set)),
                ..q
            }));
        }
        for q in queries {
            let occluded = q.occluded;
            let pool = mt.map(|m| m.0);
            // The untimed warm-up gives the checksums in file order, as Embree's primID. The
            // timed passes sum BVH-order indices, which is what a tracer hands its caller (as
            // Embree's primID): mapping each hit back through the 8 MB order table is the
            // harness's business, and cost random rays a cache miss Embree's loop does not pay.
            let first = self.pass(&set.rays, q, true, pool);
            let timed = self.pass(&set.rays, q, false, pool);
            let (mut wall, mut cpu) = (Vec::new(), Vec::new());
            let mut consistent = timed.hits == first.hits && timed.sum_t == first.sum_t;
            let l0 = LoadProbe::now();
            let _ = caustic::accel::counters::thread_total_reset();
            for _ in 0..self.reps {
                let (c0, w0) = (clock::thread_cpu_s(), Instant::now());
                let s = self.pass(&set.rays, q, false, pool);
                wall.push(w0.elapsed().as_secs_f64());
                cpu.push(clock::thread_cpu_s() - c0);
                consistent &= s == timed;
            }
            let load = l0.other_load(&LoadProbe::now());
            let n = set.rays.len() as f64;
            let base = if occluded { "occluded1" } else { "intersect1" };
            let mode = match mt {
                None if q.stream.is_some() => format!("{base}M"),
                None => format!("{base}{order}"),
                Some((_, k)) => format!("{base}_{k}t"),
            };
            let (best, med) = (clock::min(&wall), clock::median(&wall));
            let mut line = format!(
                "TRACE engine=caustic mesh={} tris={} quality={} rays={} kind={} mode={mode} \
                 nrays={} reps={} med_s={med:.6} best_s={best:.6} mrays_med={:.3} mrays_best={:.3} ",
                self.mesh,
                self.tris,
                self.quality,
                base_name(&set.path),
                set.kind.name(),
                set.rays.len(),
                self.reps,
                n / med * 1e-6,
                n / best * 1e-6,
            );
            if mt.is_none() {
                // The calling thread's CPU time means nothing when other threads trace.
                let (cb, cm) = (clock::min(&cpu), clock::median(&cpu));
                line += &format!(
                    "cpu_med_s={cm:.6} cpu_best_s={cb:.6} mrays_cpu_med={:.3} mrays_cpu_best={:.3} ",
                    n / cm * 1e-6,
                    n / cb * 1e-6
                );
            }
            if caustic::accel::counters::enabled() && mt.is_none() {
                // What the timed passes visited, per ray: the calling thread counted them all.
                let (nodes, tris) = caustic::accel::counters::thread_total_reset();
                let per = n * self.reps as f64;
                line += &format!(
                    "nodes_per_ray={:.2} tris_per_ray={:.2} ",
                    nodes as f64 / per,
                    tris as f64 / per
                );
            }
            line += &format!("other_load={load:.2} ");
            line += &if occluded {
                format!("occluded={}", first.hits)
            } else {
                format!(
                    "hits={} sum_t={:.9e} sum_prim={}",
                    first.hits, first.sum_t, first.sum_prim
                )
            };
            if !consistent {
                line += " WARNING=checksum_changed_between_reps";
            }
            println!("{line}");
        }
    }
}

/// The mesh's bounding box in double precision: `[min, max]` per axis.
type Box3 = [[f64; 2]; 3];

fn mesh_box(data: &MeshData) -> Box3 {
    let mut b = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
    for p in &data.positions {
        for (a, v) in b.iter_mut().zip(p.to_array()) {
            a[0] = a[0].min(v as f64);
            a[1] = a[1].max(v as f64);
        }
    }
    b
}

/// Returns the ray's parameter interval inside the slab `[lo, hi]` of one axis.
fn slab(o: f64, d: f64, lo: f64, hi: f64) -> (f64, f64) {
    if d == 0.0 {
        return if o < lo || o > hi {
            (f64::INFINITY, f64::NEG_INFINITY)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        };
    }
    let (a, b) = ((lo - o) / d, (hi - o) / d);
    (a.min(b), a.max(b))
}

/// Returns the interval `[t_in, t_out]` a hit must lie in when the height field (y over the xz
/// footprint) must be crossed by `r`, as the harness's `must_hit` decides it.
fn must_hit(b: &Box3, r: &RayRecord) -> Option<(f64, f64)> {
    const EPS: f64 = 1e-4; // height margin
    const MAR: f64 = 1e-4; // footprint margin
    if r.dir[1].is_nan() || r.dir[1] >= 0.0 {
        return None;
    }
    let [ox, oy, oz] = r.origin.map(f64::from);
    let [dx, dy, dz] = r.dir.map(f64::from);
    let (ax0, ax1) = slab(ox, dx, b[0][0], b[0][1]);
    let (az0, az1) = slab(oz, dz, b[2][0], b[2][1]);
    let te = ax0.max(az0).max(r.tmin as f64);
    if te > ax1.min(az1) || oy + te * dy < b[1][1] + EPS {
        return None;
    }
    let tb = (b[1][0] - EPS - oy) / dy;
    if tb > r.tmax as f64 {
        return None;
    }
    let (sx0, sx1) = slab(ox, dx, b[0][0] + MAR, b[0][1] - MAR);
    let (sz0, sz1) = slab(oz, dz, b[2][0] + MAR, b[2][1] - MAR);
    if tb < sx0.max(sz0) || tb > sx1.min(sz1) {
        return None;
    }
    Some((te, tb))
}

/// Returns the closest hit `(t, file triangle)` by double-precision Möller–Trumbore over every
/// triangle, as the harness's `brute_force` computes it.
fn brute_force(data: &MeshData, r: &RayRecord) -> Option<(f64, u32)> {
    let o = glam::DVec3::from_array(r.origin.map(f64::from));
    let d = glam::DVec3::from_array(r.dir.map(f64::from));
    let mut best = (r.tmax as f64, None);
    for (p, t) in data.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| data.positions[i as usize].as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det == 0.0 {
            continue;
        }
        let inv = 1.0 / det;
        let tv = o - a;
        let u = tv.dot(pv) * inv;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let qv = tv.cross(e1);
        let v = d.dot(qv) * inv;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let t = e2.dot(qv) * inv;
        if t >= r.tmin as f64 && t < best.0 {
            best = (t, Some(p as u32));
        }
    }
    best.1.map(|p| (best.0, p))
}

/// Compares `k` evenly spaced rays with brute force and runs the must-hit watertightness check
/// over every ray; prints a `VERIFY` line.
fn verify(ctx: &Ctx, data: &MeshData, set: &RaySet, k: usize) {
    let n = set.rays.len();
    let k = k.min(n);
    let sample: Vec<usize> = (0..k).map(|j| j * n / k.max(1)).collect();
    let results: Vec<(bool, bool, f64)> = sample
        .par_iter()
        .map(|&i| {
            let r = &set.rays[i];
            let got = ctx.geom.intersect(&to_ray(r));
            match (got, brute_force(data, r)) {
                (Some((tri, h)), Some((t, p))) => (
                    false,
                    ctx.order[tri as usize] != p,
                    (h.t as f64 - t).abs() / t.abs().max(1e-30),
                ),
                (None, None) => (false, false, 0.0),
                _ => (true, false, 0.0),
            }
        })
        .collect();
    let mismatch = results.iter().filter(|r| r.0).count();
    let prim_diff = results.iter().filter(|r| r.1).count();
    let max_rel = results.iter().map(|r| r.2).fold(0.0, f64::max);
    let b = mesh_box(data);
    let (mut n_must, mut leaks, mut bad_t) = (0u64, 0u64, 0u64);
    for r in &set.rays {
        let Some((t_in, t_out)) = must_hit(&b, r) else {
            continue;
        };
        n_must += 1;
        match ctx.geom.intersect(&to_ray(r)) {
            None => leaks += 1,
            Some((_, h)) => {
                let t = h.t as f64;
                if t < t_in * (1.0 - 1e-5) || t > t_out * (1.0 + 1e-5) {
                    bad_t += 1;
                }
            }
        }
    }
    println!(
        "VERIFY engine=caustic mesh={} rays={} quality={} checked={k} hit_mismatch={mismatch} \
         prim_diff={prim_diff} max_rel_t_err={max_rel:.3e} must_hit={n_must} leaks={leaks} bad_t={bad_t}",
        ctx.mesh,
        base_name(&set.path),
        ctx.quality,
    );
}
