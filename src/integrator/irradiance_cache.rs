//! Irradiance caching for final gathering (Ward, Rubinstein & Clear, *A ray tracing solution for
//! diffuse interreflection*, SIGGRAPH 1988), with the smooth weights of Tabellion & Lamorlette
//! (*An approximate global illumination system for computer generated films*, SIGGRAPH 2004).
//!
//! Indirect diffuse light changes slowly across a surface, except near other geometry. Instead of
//! final-gathering at every camera sample (16 gather rays a pixel on the final scene, a third of
//! its render time), the photon mapper gathers at a sparse set of *records*, each with many rays
//! ([`CacheSettings::rays`]), and every shaded point interpolates the records near it. Where no
//! record is valid the point is gathered as before: the cache never replaces a gather by
//! nothing, so its worst case is the cost and the image without it.
//!
//! # A record and where it is valid
//! A record at `p_i` with geometric normal `n_i` holds the indirect irradiance `E_i` (photons'
//! light reaching `p_i` after at least one bounce, as the gather measures it) and `R_i`, the
//! harmonic mean of its gather rays' first-hit distances: near a wall or an object, `R_i` is small
//! and so is the region where `E_i` can stand for its neighbours'. At a point `p` with normal `n`
//! its error estimate is Ward's `ε_i = |p − p_i| / R_i + √(1 − n·n_i)` and its weight
//! `w_i = 1 − ε_i / a` for the accuracy `a` ([`CacheSettings::accuracy`]); records with `w_i ≤ 0`,
//! and records in front of the point (`(p − p_i)·(n + n_i)/2 < −a R_i / 10`: they may see light
//! the point's side does not), are not used. The estimate is `Σ w_i E_i / Σ w_i`. Ward's own
//! weight `1/ε_i` jumps from `1/a` to 0 at the edge of a record's region; `1 − ε_i/a` falls to 0
//! there, so the interpolated light has no seams where records end.
//!
//! `R_i` is clamped to `[R_MIN_PIXELS · D / max(w, h), R_MAX_FRACTION · D]` for the scene's
//! diagonal `D` and the image size: contact regions get records a few pixels apart rather than
//! without bound, and open walls still get several records.
//!
//! Records use the geometric normal: a normal map's detail (the tiles' bevels, the rock) reaches
//! the image through the direct light and the caustics, which are computed at every sample; the
//! indirect light, smooth by nature, is interpolated as if the surface were flat.
//!
//! # Gradients
//! Each record keeps two first-order changes of its irradiance (Ward & Heckbert, *Irradiance
//! gradients*, 1992), and a lookup applies both before weighting ([`Record::at`]): the
//! *rotational* gradient, for a point whose shading normal turns from the record's, and the
//! *translational* gradient, for a point that lies elsewhere in the record's region. Without the
//! second, a lookup is a weighted mean of neighbours' values, which is biased wherever the light
//! changes along the surface (towards a corner, across a soft shadow); with it, the error is
//! second order in the distance. On the diffuse box at long budgets it takes a quarter of the
//! cache's bias against Mitsuba (`docs/validation.md`).
//!
//! The translational gradient is estimated from how each cell of the gather's hemisphere would
//! gain or lose what its neighbour sees as the origin moves ([`Gather::translation`]), so a
//! record's rays are stratified on a grid of rings and wedges rather than as n-rooks (which
//! also leaves a record less noise: a seed's spread of the boxes' ceilings fell by 40%). Two
//! guards keep a noisy or near-singular gradient from extrapolating a record to black or to a
//! glare: distances under the smallest region count as that (`1/t` beside a corner), and a
//! gradient is shortened so that across the record's region it moves the light by at most the
//! record's own value.
//!
//! The accuracy stays 0.3 with the gradients: at 0.5 the final scene kept its error with half the
//! records, but the validation scene seen from under water doubled its block error, where the
//! records' regions reach over surfaces seen through the water's surface.
//!
//! # Where records are made: a deterministic, coarse-to-fine pass
//! Ward's cache inserts a record wherever a lookup finds none, during the render: the records then
//! depend on the order in which threads reach pixels, and so would every image. Here records are
//! made before the camera pass, over the *whole* image whatever window is rendered (so tiles of a
//! farm job agree with the full frame), in levels: at level `s` (pixel strides 32, 16, 8, 4, 2) the
//! centre ray of every pixel on the stride-`s` lattice not on a coarser one follows the eye path's
//! specular splitting ([`super::eye::Tracer`], no shading) and, at every point that would be
//! final-gathered, makes a record if the records of the coarser levels cover it nowhere. A
//! level's records are made in parallel against the frozen cache of the levels before and added in
//! pixel order. The cache is thus a function of the scene, the camera, the seed and the settings,
//! and is the same for any thread count or tile. Each record's rays come from a stream keyed by its
//! pixel ([`crate::sampling::Pass::Cache`]).
//!
//! # Lookups
//! A uniform grid whose cells are as wide as the largest region (`a · R_max`) lists, per cell, every
//! record whose region's bounding cube meets it; a lookup reads the one cell holding the point.
//!
//! The progressive integrator does not use the cache: its estimate must converge, and the cache's
//! interpolation is a bias that more passes would not remove.

use super::eye::{DiffuseTerm, PathState, ShadingPoint, Tracer};
use super::photon_map::{GatherAt, Prepass};
use crate::camera::Camera;
use crate::progress::Progress;
use crate::sampling::{Pass, Rng};
use crate::scene::Scene;
use crate::stats::RayCounts;
use glam::Vec3A;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The accuracy `a` by default: a record serves points within `a · R` of it.
pub const DEFAULT_ACCURACY: f32 = 0.3;
/// Gather rays per record by default.
pub const DEFAULT_RECORD_RAYS: u32 = 256;
/// The pixel strides of the record levels, coarse to fine.
const STRIDES: [u32; 5] = [32, 16, 8, 4, 2];
/// Smallest `R`, in pixels' worth of the scene's diagonal. It was 4 before the translational
/// gradient; at 2 the validation boxes' ceilings, whose concave edges the records at the
/// smallest `R` serve, lost a fifth to a third of their bias (`docs/validation.md`).
const R_MIN_PIXELS: f32 = 2.0;
/// Largest `R`, as a fraction of the scene's diagonal.
const R_MAX_FRACTION: f32 = 0.1;
/// Smallest image side (pixels) for which a frame builds a cache. Below it a record's smallest
/// region ([`R_MIN_PIXELS`] pixels) is a large part of the image, and interpolation smears what
/// a few pixels should resolve: a 24-pixel test of a mirror ball on a floor came out 10%
/// brighter than the map's own estimate with the cache, within 6% without. Such images gather
/// everywhere, which costs little at that size.
pub const MIN_IMAGE_SIZE: u32 = 48;
/// Most grid cells.
const MAX_CELLS: usize = 1 << 20;

/// Returns the range `(R_min, R_max)` the records' radii of a `width × height` frame of `scene`
/// are clamped to (see the module doc).
pub fn radius_range(scene: &Scene, (width, height): (u32, u32)) -> (f32, f32) {
    let extent = scene.extent().max(f32::MIN_POSITIVE);
    // A tiny image's pixels are wide: its smallest R may not exceed the largest.
    let r_max = R_MAX_FRACTION * extent;
    let r_min = (R_MIN_PIXELS * extent / width.max(height).max(1) as f32).min(r_max);
    (r_min, r_max)
}

/// How final gathering uses the cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheSettings {
    /// Whether final gathering interpolates cached records (`--irradiance-cache`).
    pub enabled: bool,
    /// The accuracy `a` in `(0, 1]`: smaller is more records, closer to gathering everywhere
    /// (`--cache-accuracy`).
    pub accuracy: f32,
    /// Gather rays per record (`--cache-rays`).
    pub rays: u32,
}

impl Default for CacheSettings {
    fn default() -> CacheSettings {
        CacheSettings {
            enabled: true,
            accuracy: DEFAULT_ACCURACY,
            rays: DEFAULT_RECORD_RAYS,
        }
    }
}

/// One cached gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    pub p: Vec3A,
    /// Unit geometric normal, on the side the record was seen from.
    pub n: Vec3A,
    /// Indirect irradiance.
    pub e: Vec3A,
    /// The rotational gradient, per colour channel ([`Gather::gradient`]).
    pub rotation: [Vec3A; 3],
    /// The translational gradient, per colour channel ([`Gather::translation`]).
    pub translation: [Vec3A; 3],
    /// Harmonic mean distance of the gather rays' first hits, clamped.
    pub r: f32,
}

impl Record {
    /// Returns the record's irradiance moved to `p` and turned to face unit normal `n`:
    /// `E_i (n·n_i) + (n − n_i)·T_i + (p − p_i)·G_i` per channel, the first-order change of the
    /// irradiance with the normal (a normal map's bevel, a sphere's curvature) and with the
    /// position (light falling off towards a corner, a shadow's edge).
    pub fn at(&self, p: Vec3A, n: Vec3A) -> Vec3A {
        let (dn, dp) = (n - self.n, p - self.p);
        let (t, g) = (&self.rotation, &self.translation);
        let turned = Vec3A::new(dn.dot(t[0]), dn.dot(t[1]), dn.dot(t[2]));
        let moved = Vec3A::new(dp.dot(g[0]), dp.dot(g[1]), dp.dot(g[2]));
        self.e * n.dot(self.n) + turned + moved
    }
}

/// A record's `R` is at most this many times its nearest first hit.
const NEAREST_FACTOR: f32 = 1.5;

/// Largest `tan θ` a gather ray's rotational-gradient term takes (θ ≈ 76°): the estimator's
/// `tan θ` has a logarithmically infinite variance at the horizon.
const MAX_TAN: f32 = 4.0;

/// The sums of one gather: irradiance, rotational gradient, first-hit distances and, for a
/// record's gather, the translational gradient.
///
/// With `N` cosine-distributed rays about `n` bringing radiance `L_j` along `ω_j`:
/// - the irradiance `E(n) = ∫ L(ω) (n·ω) dω ≈ (π/N) Σ L_j`;
/// - its rotational gradient (Ward & Heckbert, *Irradiance gradients*, 1992): turning the normal
///   to `n'` changes it by about `(n' − n)·∫ L(ω) ω dω`, whose part along `n` is `E` and whose
///   tangential part `T = ∫ L(ω) (ω − (ω·n) n) dω ≈ (π/N) Σ L_j tan θ_j u_j` (`u_j` the unit
///   tangential direction of `ω_j`), with `tan θ` clamped at [`MAX_TAN`];
/// - `R`, the harmonic mean of the first-hit distances (rays that leave the scene count 1/∞ = 0);
/// - with [`Gather::with_translation`], the translational gradient ([`Gather::translation`]).
#[derive(Clone, Debug, Default)]
pub struct Gather {
    n: Vec3A,
    rays: u32,
    sum: Vec3A,
    tangential: [Vec3A; 3],
    inverse: f32,
    nearest: f32,
    /// The `M × N` grid of a gather with a translational gradient: rings of equal projected
    /// solid angle (`sin²θ` in `[j/M, (j+1)/M)`) by wedges of `φ`, ring-major, each cell's
    /// radiance and first-hit distance.
    grid: Option<Cells>,
}

/// A gather's cells ([`Gather::with_translation`]).
#[derive(Clone, Debug, Default)]
struct Cells {
    rings: u32,
    wedges: u32,
    cells: Vec<(Vec3A, f32)>,
}

impl Gather {
    /// Starts the sums of a gather of `rays` rays about unit normal `n`, sampled as n-rooks
    /// ([`crate::sampling::stratified_2d`]).
    pub fn new(n: Vec3A, rays: u32) -> Gather {
        Gather {
            n,
            rays,
            nearest: f32::INFINITY,
            ..Gather::default()
        }
    }

    /// Starts a gather about unit normal `n` sampled on a grid of `M` rings by `N ≈ πM` wedges,
    /// `M·N` at most `rays` (at least one), which also gives the translational gradient.
    pub fn with_translation(n: Vec3A, rays: u32) -> Gather {
        let rings = ((rays as f32 / std::f32::consts::PI).sqrt().round() as u32).max(1);
        let wedges = (rays / rings).max(1);
        let count = rings * wedges;
        Gather {
            grid: Some(Cells {
                rings,
                wedges,
                cells: vec![(Vec3A::ZERO, f32::INFINITY); count as usize],
            }),
            ..Gather::new(n, count)
        }
    }

    /// Returns the gather's rays: unit directions cosine-distributed about its normal, from its
    /// sample points ([`crate::sampling::cosine_around`], whose frame about the normal
    /// [`Gather::translation`] shares). [`Gather::add`] takes each ray with its index.
    pub fn directions(&self, rng: &mut Rng) -> Vec<Vec3A> {
        let n = self.n;
        let points = self.points(rng);
        points
            .into_iter()
            .map(|u| crate::sampling::cosine_around(n, u))
            .collect()
    }

    /// Returns the gather's sample points in `[0, 1)²`, the first coordinate `sin²θ` and the
    /// second `φ/2π`: n-rooks, or with a grid one point in each cell, ring-major.
    fn points(&self, rng: &mut Rng) -> Vec<(f32, f32)> {
        let Some(g) = &self.grid else {
            return crate::sampling::stratified_2d(rng, self.rays);
        };
        let (m, n) = (g.rings as f32, g.wedges as f32);
        (0..g.rings)
            .flat_map(|j| (0..g.wedges).map(move |k| (j, k)))
            .map(|(j, k)| {
                let u = ((j as f32 + rng.next_f32()) / m).min(1.0 - f32::EPSILON);
                let v = ((k as f32 + rng.next_f32()) / n).min(1.0 - f32::EPSILON);
                (u, v)
            })
            .collect()
    }

    /// Adds ray `i` of [`Gather::directions`], along unit `d`, which brought radiance `l` and
    /// first met a surface at distance `t`.
    pub fn add(&mut self, i: usize, d: Vec3A, l: Vec3A, t: f32) {
        self.sum += l;
        let cos = d.dot(self.n);
        if cos > 0.0 {
            let tangent = d - cos * self.n;
            let len = tangent.length();
            let tan = (len / cos).min(MAX_TAN);
            if len > 0.0 {
                let u = tangent * (tan / len);
                self.tangential[0] += l.x * u;
                self.tangential[1] += l.y * u;
                self.tangential[2] += l.z * u;
            }
        }
        let t = if t > 0.0 {
            self.inverse += 1.0 / t;
            self.nearest = self.nearest.min(t);
            t
        } else {
            f32::INFINITY
        };
        if let Some(cell) = self.grid.as_mut().and_then(|g| g.cells.get_mut(i)) {
            *cell = (l, t);
        }
    }

    fn scale(&self) -> f32 {
        std::f32::consts::PI / self.rays.max(1) as f32
    }

    /// Returns the irradiance estimate.
    pub fn irradiance(&self) -> Vec3A {
        self.sum * self.scale()
    }

    /// Returns the tangential rotational gradient, per colour channel.
    pub fn gradient(&self) -> [Vec3A; 3] {
        self.tangential.map(|v| v * self.scale())
    }

    /// Returns the translational gradient `∂E/∂p` in the tangent plane, per colour channel (zero
    /// for a gather without a grid), by Ward & Heckbert's estimate: moving the gather's origin
    /// shifts what each cell sees, at the rate `1/R` of the nearer of two neighbouring cells'
    /// hits, so the projected solid angle along each boundary between cells passes from one
    /// cell's radiance to the other's.
    ///
    /// With `sin θ_j = √(j/M)` the rings' edges, `φ_k = 2πk/N` the wedges' and `u(φ)`, `v(φ)` the
    /// tangent plane's radial and azimuthal directions at `φ`:
    /// - a ring edge `θ_j` (`j ≥ 1`) in wedge `k` moves by `cos θ_j · δ·u / R` under a move `δ`, so
    ///   adds `u(φ_k + π/N) · (2π/N) sin θ_j cos² θ_j (L_{j,k} − L_{j−1,k}) / min(R_{j,k}, R_{j−1,k})`;
    /// - a wedge edge `φ_k` in ring `j` moves by `δ·v / (R sin θ)`, so adds
    ///   `v(φ_k) (sin θ_{j+1} − sin θ_j)(L_{j,k} − L_{j,k−1}) / min(R_{j,k}, R_{j,k−1})`, `k − 1`
    ///   taken round the circle.
    ///
    /// Distances below `r_min` count as `r_min`: a ray that meets the wall beside a corner a
    /// hair's breadth away would otherwise make the gradient as large as `1/t` (the smallest
    /// region a record serves is `r_min` wide, so no finer change could be followed anyway).
    ///
    /// `tests::a_gather_under_a_half_plane_light_has_its_irradiance_gradient` holds it against
    /// the closed form of a half-plane light's irradiance.
    pub fn translation(&self, r_min: f32) -> [Vec3A; 3] {
        let Some(g) = &self.grid else {
            return [Vec3A::ZERO; 3];
        };
        let t = self.n.any_orthonormal_vector();
        let b = self.n.cross(t);
        let (m, n) = (g.rings as usize, g.wedges as usize);
        let sin = |j: usize| (j as f32 / m as f32).sqrt();
        let cell = |j: usize, k: usize| g.cells[j * n + k];
        let wedge = std::f32::consts::TAU / n as f32;
        let mut sum = [Vec3A::ZERO; 3];
        let mut push = |dir: Vec3A, weight: f32, a: (Vec3A, f32), c: (Vec3A, f32)| {
            let r = a.1.min(c.1).max(r_min);
            if !(r.is_finite() && r > 0.0) {
                return;
            }
            let dl = (a.0 - c.0) * (weight / r);
            sum[0] += dl.x * dir;
            sum[1] += dl.y * dir;
            sum[2] += dl.z * dir;
        };
        for k in 0..n {
            // The ring edges' radial direction over the wedge: `∫ u(φ) dφ = 2 sin(w/2) u(mid)`.
            let mid = (k as f32 + 0.5) * wedge;
            let u = (t * mid.cos() + b * mid.sin()) * (2.0 * (0.5 * wedge).sin() / wedge);
            let edge = k as f32 * wedge;
            let v = b * edge.cos() - t * edge.sin();
            let prev = (k + n - 1) % n;
            for j in 0..m {
                if j > 0 {
                    let (s, c2) = (sin(j), 1.0 - j as f32 / m as f32);
                    push(u, wedge * s * c2, cell(j, k), cell(j - 1, k));
                }
                if n > 1 {
                    push(v, sin(j + 1) - sin(j), cell(j, k), cell(j, prev));
                }
            }
        }
        sum
    }

    /// Returns the record's `R`: the harmonic mean first-hit distance, but at most
    /// [`NEAREST_FACTOR`] times the nearest (infinite when no ray hit).
    pub fn mean_distance(&self) -> f32 {
        if self.inverse > 0.0 {
            (self.rays as f32 / self.inverse).min(NEAREST_FACTOR * self.nearest)
        } else {
            f32::INFINITY
        }
    }
}

/// What building the cache did, for `--stats`.
#[derive(Clone, Debug, Default)]
pub struct CacheStats {
    pub records: usize,
    /// Records made at each level, coarse to fine.
    pub per_level: Vec<usize>,
    /// Centre rays traced to find where records are needed.
    pub probes: u64,
    /// The pass's rays (probes' specular paths and the records' gather rays).
    pub rays: RayCounts,
    pub time: Duration,
    /// The records a build over the whole image would make, estimated level by level from
    /// the records each probe made (equal to `records` when it was such a build).
    pub whole_records: f64,
}

impl CacheStats {
    /// Returns the seconds a build over the whole image would take: this build's time per
    /// record (each record's gather rays are its cost) times [`CacheStats::whole_records`].
    pub fn whole_seconds(&self) -> f64 {
        match self.records {
            0 => self.time.as_secs_f64(),
            n => self.time.as_secs_f64() * self.whole_records / n as f64,
        }
    }
}

/// Which pixels' centre rays a cache build probes: the whole image's lattices, or only the
/// lattice points near some pixels (the planner's pilot, which reads the cache at those pixels
/// only).
#[derive(Clone, Copy, Debug)]
pub enum Probes<'a> {
    Whole,
    Near(&'a [(u32, u32)]),
}

/// Returns the probes of each level, coarse to fine, in row-major order: every pixel of the
/// level's lattice not on a coarser one, or with [`Probes::Near`] those within one stride
/// (each axis) of a listed pixel; and each level's count over the whole image.
fn level_probes(probes: Probes, (width, height): (u32, u32)) -> Vec<(Vec<(u32, u32)>, u64)> {
    STRIDES
        .iter()
        .enumerate()
        .map(|(l, &s)| {
            let coarser =
                |x: u32, y: u32| l > 0 && x.is_multiple_of(2 * s) && y.is_multiple_of(2 * s);
            let lattice = |n: u32| n.div_ceil(s) as u64;
            let coarse = |n: u32| n.div_ceil(2 * s) as u64;
            let whole = lattice(width) * lattice(height)
                - if l > 0 {
                    coarse(width) * coarse(height)
                } else {
                    0
                };
            let mut pixels: Vec<(u32, u32)> = match probes {
                Probes::Whole => (0..height)
                    .step_by(s as usize)
                    .flat_map(|y| (0..width).step_by(s as usize).map(move |x| (x, y)))
                    .collect(),
                Probes::Near(near) => {
                    let around = |c: u32, n: u32| {
                        let lo = c.saturating_sub(s).div_ceil(s) * s;
                        (lo..=(c + s).min(n - 1)).step_by(s as usize)
                    };
                    let mut v: Vec<(u32, u32)> = near
                        .iter()
                        .filter(|&&(x, y)| x < width && y < height)
                        .flat_map(|&(px, py)| {
                            around(py, height)
                                .flat_map(move |y| around(px, width).map(move |x| (x, y)))
                        })
                        .collect();
                    v.sort_unstable_by_key(|&(x, y)| (y, x));
                    v.dedup();
                    v
                }
            };
            pixels.retain(|&(x, y)| !coarser(x, y));
            (pixels, whole)
        })
        .collect()
}

/// Records and the grid that finds them.
#[derive(Clone, Debug)]
pub struct IrradianceCache {
    records: Vec<Record>,
    /// The random stream each record's gather drew from, by record (empty for a cache read from
    /// a file): [`IrradianceCache::pick`] gives it, for a gather elsewhere with the same
    /// numbers.
    streams: Vec<[u64; 2]>,
    accuracy: f32,
    grid: Grid,
}

/// A uniform grid of record indices, in compressed rows: cell `c` lists
/// `items[start[c]..start[c + 1]]`.
#[derive(Clone, Debug, Default)]
struct Grid {
    origin: Vec3A,
    inv_cell: f32,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    /// Returns the grid over `records`, each listed in every cell its region `a · r` meets.
    fn build(records: &[Record], accuracy: f32) -> Grid {
        if records.is_empty() {
            return Grid::default();
        }
        let reach = |r: &Record| accuracy * r.r;
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        let mut widest = 0.0f32;
        for r in records {
            lo = lo.min(r.p - reach(r));
            hi = hi.max(r.p + reach(r));
            widest = widest.max(reach(r));
        }
        let size = (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
        let mut cell = (2.0 * widest).max(size.max_element() * 1e-6);
        let dims = loop {
            let d = (size / cell).ceil().max(Vec3A::ONE);
            let dims = [d.x as usize, d.y as usize, d.z as usize];
            if dims.iter().product::<usize>() <= MAX_CELLS {
                break dims;
            }
            cell *= 2.0;
        };
        let mut grid = Grid {
            origin: lo,
            inv_cell: 1.0 / cell,
            dims,
            start: vec![0; dims.iter().product::<usize>() + 1],
            items: Vec::new(),
        };
        let cells_of = |g: &Grid, r: &Record| {
            let (a, b) = (g.coords(r.p - reach(r)), g.coords(r.p + reach(r)));
            (a[0]..=b[0]).flat_map(move |x| {
                (a[1]..=b[1]).flat_map(move |y| (a[2]..=b[2]).map(move |z| [x, y, z]))
            })
        };
        for r in records {
            for c in cells_of(&grid, r) {
                let i = grid.index(c);
                grid.start[i + 1] += 1;
            }
        }
        for i in 1..grid.start.len() {
            grid.start[i] += grid.start[i - 1];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![0; *grid.start.last().unwrap_or(&0) as usize];
        for (j, r) in records.iter().enumerate() {
            for c in cells_of(&grid, r) {
                let i = grid.index(c);
                grid.items[fill[i] as usize] = j as u32;
                fill[i] += 1;
            }
        }
        grid
    }

    /// Returns the cell holding `p`, clamped to the grid.
    fn coords(&self, p: Vec3A) -> [usize; 3] {
        let c = ((p - self.origin) * self.inv_cell).max(Vec3A::ZERO);
        [
            (c.x as usize).min(self.dims[0] - 1),
            (c.y as usize).min(self.dims[1] - 1),
            (c.z as usize).min(self.dims[2] - 1),
        ]
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Returns the records listed in the cell holding `p` (none outside the grid).
    fn cell(&self, p: Vec3A) -> &[u32] {
        if self.start.is_empty() {
            return &[];
        }
        let c = (p - self.origin) * self.inv_cell;
        let cell = [c.x as usize, c.y as usize, c.z as usize];
        let inside = c.cmpge(Vec3A::ZERO).all() && (0..3).all(|k| cell[k] < self.dims[k]);
        if !inside {
            return &[];
        }
        let i = self.index(cell);
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

impl IrradianceCache {
    /// Returns the records, in the order they were made.
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// Returns the accuracy the records serve points with.
    pub fn accuracy(&self) -> f32 {
        self.accuracy
    }

    /// Returns a cache of `records` with accuracy `accuracy`.
    pub fn new(records: Vec<Record>, accuracy: f32) -> IrradianceCache {
        let grid = Grid::build(&records, accuracy);
        IrradianceCache {
            records,
            streams: Vec::new(),
            accuracy,
            grid,
        }
    }

    /// Returns a record that serves `p` (unit geometric normal `n`), chosen with probability
    /// its weight over theirs by `u` in `[0, 1)`, with the stream its gather drew from; `None`
    /// where none serves or the streams are not known. The lookup there is the expectation of
    /// the chosen record's value (moved to `p`) over this choice.
    pub fn pick(&self, p: Vec3A, n: Vec3A, u: f32) -> Option<(&Record, Rng)> {
        if self.streams.len() != self.records.len() {
            return None;
        }
        let total: f32 = self.serving_indices(p, n).map(|(_, w)| w).sum();
        let mut left = u * total;
        let mut chosen = None;
        for (i, w) in self.serving_indices(p, n) {
            chosen = Some(i);
            if left < w {
                break;
            }
            left -= w;
        }
        let i = chosen?;
        Some((&self.records[i], Rng::resume(self.streams[i])))
    }

    /// Returns the number of records.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Returns true when there are no records.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Returns the interpolated indirect irradiance at `p` on a surface with unit geometric
    /// normal `n` and unit shading normal `ns`, or `None` when no record is valid there (see the
    /// module doc).
    pub fn lookup(&self, p: Vec3A, n: Vec3A, ns: Vec3A) -> Option<Vec3A> {
        let (mut sum, mut weight) = (Vec3A::ZERO, 0.0f32);
        for (r, w) in self.serving(p, n) {
            sum += w * r.at(p, ns);
            weight += w;
        }
        (weight > 0.0).then(|| (sum / weight).max(Vec3A::ZERO))
    }

    /// Returns whether some record serves `p` (unit geometric normal `n`): whether
    /// [`IrradianceCache::lookup`] would answer there.
    pub fn covers(&self, p: Vec3A, n: Vec3A) -> bool {
        self.serving(p, n).next().is_some()
    }

    /// Returns the records that serve `p` (unit geometric normal `n`) with their weights
    /// `1 − ε/a > 0`, in the order of the grid cell's list (see the module doc).
    ///
    /// Most of a cell's records are too far to serve (a cell is as wide as the largest region),
    /// so each is first tested by its squared distance against `(a R)²`, grown by a few ulps so
    /// that no record the exact weight would take is dropped by rounding: the weight's two
    /// square roots and division are then only computed for the few that may serve.
    fn serving(&self, p: Vec3A, n: Vec3A) -> impl Iterator<Item = (&Record, f32)> {
        self.serving_indices(p, n)
            .map(|(i, w)| (&self.records[i], w))
    }

    /// [`IrradianceCache::serving`], with the records' indices.
    fn serving_indices(&self, p: Vec3A, n: Vec3A) -> impl Iterator<Item = (usize, f32)> {
        let a = self.accuracy;
        self.grid.cell(p).iter().filter_map(move |&i| {
            let r = &self.records[i as usize];
            let d = p - r.p;
            let reach = a * r.r;
            if d.length_squared() > reach * reach * (1.0 + 1e-5) {
                return None;
            }
            let cos = n.dot(r.n);
            if cos <= 0.0 || d.dot(n + r.n) * 0.5 < -0.1 * a * r.r {
                return None;
            }
            let eps = d.length() / r.r + (1.0 - cos).max(0.0).sqrt();
            let w = 1.0 - eps / a;
            (w > 0.0).then_some((i as usize, w))
        })
    }

    /// Builds the cache of a frame of `scene` through `camera` (its whole image, or with
    /// [`Probes::Near`] the parts near some pixels) with `gi`'s maps, level by level (see the
    /// module doc).
    pub fn build(
        scene: &Scene,
        camera: &Camera,
        gi: &Prepass,
        settings: &CacheSettings,
        (seed, probes): (u64, Probes),
        progress: &dyn Progress,
    ) -> (IrradianceCache, CacheStats) {
        use rayon::prelude::*;
        let start = Instant::now();
        let (width, height) = camera.size();
        let r_range = radius_range(scene, (width, height));
        let levels = level_probes(probes, (width, height));
        let total: u64 = levels.iter().map(|l| l.0.len() as u64).sum();
        progress.start("caching irradiance", total);
        let mut cache = IrradianceCache::new(Vec::new(), settings.accuracy);
        let mut stats = CacheStats::default();
        for (pixels, whole) in &levels {
            if progress.should_stop() {
                break;
            }
            let found: Vec<(Vec<Made>, RayCounts)> = pixels
                .par_iter()
                .with_min_len(16)
                .map(|&(x, y)| {
                    let probe = Probe {
                        gi,
                        cache: &cache,
                        rays: settings.rays,
                        r_range,
                        out: Mutex::new(Vec::new()),
                    };
                    let tracer = Tracer {
                        scene,
                        camera,
                        light_samples: 0,
                        diffuse: DiffuseTerm::Caching(&probe),
                    };
                    let index = u64::from(y) * u64::from(width) + u64::from(x);
                    let mut rng = Rng::new(seed, Pass::Cache, index);
                    let mut counts = RayCounts::default();
                    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                    tracer.radiance(&ray, PathState::camera(tracer.scene), &mut rng, &mut counts);
                    progress.advance(1);
                    (probe.out.into_inner().unwrap_or_default(), counts)
                })
                .collect();
            let (mut records, mut streams) = (cache.records, cache.streams);
            let before = records.len();
            for (r, counts) in found {
                for (record, stream) in r {
                    records.push(record);
                    streams.push(stream);
                }
                stats.rays.add(&counts);
            }
            let made = records.len() - before;
            stats.per_level.push(made);
            stats.probes += pixels.len() as u64;
            if !pixels.is_empty() {
                stats.whole_records += made as f64 * *whole as f64 / pixels.len() as f64;
            }
            cache = IrradianceCache::new(records, settings.accuracy);
            cache.streams = streams;
        }
        stats.records = cache.len();
        stats.time = start.elapsed();
        (cache, stats)
    }
}

/// A record a probe made, with the state of the stream its gather drew from.
type Made = (Record, [u64; 2]);

/// What the record pass's eye paths do at a diffuse surface: make a record where the final
/// gather would run and the coarser levels' records do not reach.
#[derive(Debug)]
pub struct Probe<'a> {
    gi: &'a Prepass,
    cache: &'a IrradianceCache,
    rays: u32,
    r_range: (f32, f32),
    /// The records this probe made, each with the stream its gather drew from (one pixel's,
    /// so never contended; a `Mutex` because the tracer is `Sync`).
    out: Mutex<Vec<Made>>,
}

impl Probe<'_> {
    /// Visits the diffuse surface at `at` on an eye path.
    pub fn visit(&self, scene: &Scene, at: &ShadingPoint, rng: &mut Rng, counts: &mut RayCounts) {
        let (p, bsdf) = (at.p(), at.bsdf());
        if !self.gi.gathers(&at.state) || self.cache.covers(p, bsdf.ng) {
            return;
        }
        let (ng, media) = (bsdf.ng, at.state.media);
        let stream = rng.state();
        let g = self.gi.gather(
            scene,
            GatherAt { p, ng, media },
            Gather::with_translation(ng, self.rays),
            rng,
            counts,
        );
        let (e, r) = (
            g.irradiance(),
            g.mean_distance().clamp(self.r_range.0, self.r_range.1),
        );
        let record = Record {
            p,
            n: bsdf.ng,
            e,
            rotation: g.gradient(),
            translation: limited(g.translation(self.r_range.0), e, self.cache.accuracy() * r),
            r,
        };
        if let Ok(mut out) = self.out.lock() {
            out.push((record, stream));
        }
    }
}

/// Returns translational gradients `g` (per channel) shortened where needed so that across a
/// record's region (`reach` from it) each channel's irradiance `e` moves by at most its own value:
/// the interpolated light stays between none and twice the record's. A gather's gradient is a
/// noisy difference of a few cells, and a record near a corner sees large differences at short
/// range; without the limit, one such record extrapolated far brighter or to black.
fn limited(g: [Vec3A; 3], e: Vec3A, reach: f32) -> [Vec3A; 3] {
    let e = e.to_array();
    std::array::from_fn(|c| {
        let most = e[c].max(0.0) / reach.max(f32::MIN_POSITIVE);
        let len = g[c].length();
        if len > most {
            g[c] * (most / len)
        } else {
            g[c]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probes near some pixels are the whole image's probes within one stride of them
    /// (checked against a brute-force filter of the whole lattice), in the same row-major
    /// order, and each level's count over the whole image is the whole build's.
    #[test]
    fn probes_near_pixels_are_the_whole_lattices_within_a_stride() {
        let size = (203, 97);
        let near = [(0, 0), (100, 50), (202, 96), (37, 95), (101, 50), (500, 5)];
        let whole = level_probes(Probes::Whole, size);
        let part = level_probes(Probes::Near(&near), size);
        let mut kept = 0;
        for (l, ((all, n_all), (some, n_some))) in whole.iter().zip(&part).enumerate() {
            assert_eq!(*n_all, all.len() as u64, "level {l}");
            assert_eq!(n_some, n_all, "level {l}");
            let s = STRIDES[l];
            let close = |&(x, y): &(u32, u32)| {
                near.iter().any(|&(px, py)| {
                    px < size.0 && py < size.1 && x.abs_diff(px) <= s && y.abs_diff(py) <= s
                })
            };
            let brute: Vec<(u32, u32)> = all.iter().copied().filter(close).collect();
            assert_eq!(some, &brute, "level {l}");
            kept += some.len();
        }
        assert!(kept > 0 && kept < whole.iter().map(|l| l.0.len()).sum::<usize>());
    }

    fn record(p: Vec3A, n: Vec3A, e: f32, r: f32) -> Record {
        Record {
            p,
            n,
            e: Vec3A::splat(e),
            rotation: [Vec3A::ZERO; 3],
            translation: [Vec3A::ZERO; 3],
            r,
        }
    }

    /// Every record keeps the stream its gather drew from: a gather at the record's own point,
    /// about its normal, from that stream, gives its irradiance bit for bit (on a lit box at
    /// 64², every record of the whole build). And `pick` chooses among the records that serve
    /// a point in proportion to their weights: over 4000 evenly spaced `u`, each record's
    /// share is its weight's within 1/4000; where none serves, and for a cache without streams,
    /// it chooses none.
    #[test]
    fn a_records_stream_gathers_its_irradiance_again_and_picks_follow_the_weights() {
        let src = b"white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
            root = gr.node('root')
            floor = gr.cube('floor'); floor:set_material(white); floor:scale(4, 0.1, 4); floor:translate(-2, -1.1, -6)
            back = gr.cube('back'); back:set_material(white); back:scale(4, 4, 0.1); back:translate(-2, -1, -6.1)
            left = gr.cube('left'); left:set_material(white); left:scale(0.1, 4, 4); left:translate(-2.1, -1, -6)
            root:add_child(floor) root:add_child(back) root:add_child(left)
            gr.render(root, 'b.png', 64, 64, {0, 1, 1.5}, {0, -0.2, -1}, {0, 1, 0}, 55, {0, 0, 0},
              {gr.area_light({0, 2.8, -4}, {6, 6, 6}, {1, 0, 0}, nil, 20000, {0.5, 0, 0}, {0, 0, 0.5})})";
        let (scene, camera) = crate::lua::test_scene(src);
        let gi = crate::integrator::photon_map::GiSettings {
            photons: 20_000,
            caustic_photons: 0,
            cache: CacheSettings {
                rays: 64,
                ..CacheSettings::default()
            },
            ..Default::default()
        };
        let progress = crate::progress::NoProgress;
        let prepass =
            Prepass::build_with(&scene, &gi, &progress).with_cache(&scene, &camera, &progress);
        let cache = prepass.cache.as_ref().expect("a cache");
        assert!(cache.len() > 20, "{} records", cache.len());
        let media = PathState::camera(&scene).media;
        let mut counts = RayCounts::default();
        for (i, r) in cache.records().iter().enumerate() {
            let at = GatherAt {
                p: r.p,
                ng: r.n,
                media,
            };
            let g = Gather::with_translation(r.n, gi.cache.rays);
            let mut stream = Rng::resume(cache.streams[i]);
            let again = prepass.gather(&scene, at, g, &mut stream, &mut counts);
            assert_eq!(again.irradiance(), r.e, "record {i}");
        }
        // A point between records: the picks' shares against the weights.
        let (p, n) = (
            cache.records()[cache.len() / 2].p + Vec3A::splat(0.01),
            cache.records()[cache.len() / 2].n,
        );
        let weights: Vec<(usize, f32)> = cache.serving_indices(p, n).collect();
        let total: f32 = weights.iter().map(|w| w.1).sum();
        let draws = 4000;
        let mut picked = vec![0u32; cache.len()];
        for k in 0..draws {
            let (r, _) = cache
                .pick(p, n, (k as f32 + 0.5) / draws as f32)
                .expect("a pick");
            let i = cache
                .records()
                .iter()
                .position(|x| std::ptr::eq(x, r))
                .unwrap();
            picked[i] += 1;
        }
        for &(i, w) in &weights {
            let share = picked[i] as f32 / draws as f32;
            assert!(
                (share - w / total).abs() <= 1.5 / draws as f32,
                "record {i}: {share} against {}",
                w / total
            );
        }
        assert_eq!(picked.iter().sum::<u32>(), draws);
        assert!(cache.pick(Vec3A::splat(1e6), n, 0.5).is_none());
        let without = IrradianceCache::new(cache.records().to_vec(), cache.accuracy());
        assert!(without.pick(p, n, 0.5).is_none());
    }

    #[test]
    fn one_record_serves_its_region_and_nothing_beyond() {
        let cache = IrradianceCache::new(vec![record(Vec3A::ZERO, Vec3A::Y, 2.0, 1.0)], 0.3);
        assert_eq!(
            cache.lookup(Vec3A::ZERO, Vec3A::Y, Vec3A::Y),
            Some(Vec3A::splat(2.0))
        );
        assert_eq!(
            cache.lookup(Vec3A::new(0.29, 0.0, 0.0), Vec3A::Y, Vec3A::Y),
            Some(Vec3A::splat(2.0))
        );
        assert_eq!(
            cache.lookup(Vec3A::new(0.31, 0.0, 0.0), Vec3A::Y, Vec3A::Y),
            None
        );
        // The other side of the surface, and a normal 90° away.
        assert_eq!(cache.lookup(Vec3A::ZERO, Vec3A::NEG_Y, Vec3A::NEG_Y), None);
        assert_eq!(cache.lookup(Vec3A::ZERO, Vec3A::X, Vec3A::X), None);
        // Tilted by θ: √(1 − cos θ) < 0.3 holds to θ ≈ 24.5°.
        let tilt = |deg: f32| {
            let t = deg.to_radians();
            Vec3A::new(t.sin(), t.cos(), 0.0)
        };
        assert!(cache.lookup(Vec3A::ZERO, tilt(24.0), tilt(24.0)).is_some());
        assert!(cache.lookup(Vec3A::ZERO, tilt(25.0), tilt(25.0)).is_none());
        // A point below the record's plane (the record is in front of it) is not served.
        assert_eq!(
            cache.lookup(Vec3A::new(0.0, -0.05, 0.0), Vec3A::Y, Vec3A::Y),
            None
        );
        assert!(
            cache
                .lookup(Vec3A::new(0.0, 0.05, 0.0), Vec3A::Y, Vec3A::Y)
                .is_some()
        );
    }

    #[test]
    fn weights_fall_smoothly_to_zero_at_the_edge_of_a_region() {
        // Two records 0.4 apart, each valid for 0.3: between them the estimate moves from one
        // value to the other without a jump, by the weights 1 − ε/a.
        let cache = IrradianceCache::new(
            vec![
                record(Vec3A::ZERO, Vec3A::Y, 1.0, 1.0),
                record(Vec3A::new(0.4, 0.0, 0.0), Vec3A::Y, 3.0, 1.0),
            ],
            0.3,
        );
        let at = |x: f32| {
            cache
                .lookup(Vec3A::new(x, 0.0, 0.0), Vec3A::Y, Vec3A::Y)
                .unwrap()
                .x
        };
        assert_eq!(at(0.05), 1.0);
        assert_eq!(at(0.35), 3.0);
        assert!((at(0.2) - 2.0).abs() < 1e-5);
        // x = 0.15: weights 1 − 0.15/0.3 = 0.5 and 1 − 0.25/0.3 = 1/6.
        let expected = (0.5 * 1.0 + 3.0 / 6.0) / (0.5 + 1.0 / 6.0);
        assert!((at(0.15) - expected).abs() < 1e-5, "{}", at(0.15));
        let mut last = at(0.05);
        for i in 1..=60 {
            let v = at(0.05 + i as f32 * 0.005);
            assert!(
                v >= last - 1e-6 && v - last < 0.1,
                "a step of {} at {i}",
                v - last
            );
            last = v;
        }
    }

    /// The distance pre-test drops no record the weight itself would take: at points within a
    /// few ulps of a region's edge, over radii from 10⁻³ to 10³ and tilted normals, a record
    /// serves exactly when Ward's weight `1 − ε/a`, computed in full, is positive, and with that
    /// weight.
    #[test]
    fn records_at_the_edge_of_their_region_serve_exactly_when_their_weight_is_positive() {
        let mut rng = Rng::new(11, Pass::Cache, 0);
        let a = 0.3;
        let (mut inside, mut outside) = (0, 0);
        for trial in 0..400 {
            let r = 10f32.powf(rng.next_f32() * 6.0 - 3.0);
            let centre = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
            // Half with the record's own normal, where the edge is the distance test's (aR).
            let tilt = Vec3A::new(rng.next_f32() - 0.5, 0.0, rng.next_f32() - 0.5);
            let n = if trial % 2 == 0 {
                Vec3A::Y
            } else {
                (Vec3A::Y + tilt).normalize()
            };
            let cache = IrradianceCache::new(vec![record(centre, Vec3A::Y, 1.0, r)], a);
            let along = Vec3A::new(rng.next_f32() - 0.5, 0.0, rng.next_f32() - 0.5).normalize();
            for k in -40..=40 {
                let reach = a * r * (1.0 - (1.0 - n.dot(Vec3A::Y)).max(0.0).sqrt() / a);
                let p = centre + along * (reach * (1.0 + k as f32 * 2e-7));
                let d = p - centre;
                let eps = d.length() / r + (1.0 - n.dot(Vec3A::Y)).max(0.0).sqrt();
                let w = 1.0 - eps / a;
                let in_front = d.dot(n + Vec3A::Y) * 0.5 < -0.1 * a * r;
                let got: Vec<f32> = cache.serving(p, n).map(|(_, w)| w).collect();
                if w > 0.0 && !in_front {
                    assert_eq!(got, vec![w], "r {r}, k {k}");
                    inside += 1;
                } else {
                    assert!(got.is_empty(), "r {r}, k {k}: served with {got:?}");
                    outside += 1;
                }
            }
        }
        assert!(
            inside > 1000 && outside > 1000,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn the_grid_finds_the_same_records_as_a_scan_of_all() {
        let mut rng = Rng::new(5, Pass::Cache, 0);
        let records: Vec<Record> = (0..2000)
            .map(|_| {
                let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0;
                let r = 0.05 + 1.5 * rng.next_f32().powi(3);
                record(p, Vec3A::Z, rng.next_f32(), r)
            })
            .collect();
        let cache = IrradianceCache::new(records.clone(), 0.3);
        let brute = IrradianceCache {
            grid: Grid {
                origin: Vec3A::splat(-100.0),
                inv_cell: 1.0 / 1000.0,
                dims: [1, 1, 1],
                start: vec![0, records.len() as u32],
                items: (0..records.len() as u32).collect(),
            },
            ..cache.clone()
        };
        let mut served = 0;
        for _ in 0..5000 {
            let p = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.4 - 0.2;
            let (a, b) = (
                cache.lookup(p, Vec3A::Z, Vec3A::Z),
                brute.lookup(p, Vec3A::Z, Vec3A::Z),
            );
            assert_eq!(a.is_some(), b.is_some(), "at {p}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a - b).abs().max_element() < 1e-5, "at {p}: {a} vs {b}");
                served += 1;
            }
        }
        assert!(served > 500, "only {served} points served");
    }

    #[test]
    fn a_gather_estimates_irradiance_and_its_change_with_the_normal() {
        // Radiance over the upper hemisphere of +z, brighter towards k; the truth by quadrature.
        let k = Vec3A::new(0.6, 0.0, 0.8);
        let colour = Vec3A::new(1.0, 0.5, 0.25);
        let radiance = |w: Vec3A| colour * (1.0 + 2.0 * w.dot(k).max(0.0));
        let truth = |n: Vec3A| {
            let (mut e, steps) = (Vec3A::ZERO, 400);
            for i in 0..steps {
                let theta = (i as f32 + 0.5) / steps as f32 * std::f32::consts::FRAC_PI_2;
                for j in 0..4 * steps {
                    let phi = (j as f32 + 0.5) / (4 * steps) as f32 * std::f32::consts::TAU;
                    let w = Vec3A::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    );
                    let dw = theta.sin()
                        * (std::f32::consts::FRAC_PI_2 / steps as f32)
                        * (std::f32::consts::TAU / (4 * steps) as f32);
                    e += radiance(w) * n.dot(w).max(0.0) * dw;
                }
            }
            e
        };
        let rays = 1 << 16;
        let mut g = Gather::new(Vec3A::Z, rays);
        let mut rng = Rng::new(3, Pass::Cache, 1);
        for (i, d) in g.directions(&mut rng).into_iter().enumerate() {
            g.add(i, d, radiance(d), 2.0);
        }
        let e0 = truth(Vec3A::Z);
        assert!((g.irradiance() - e0).abs().max_element() < 0.005 * e0.max_element());
        assert!((g.mean_distance() - 2.0).abs() < 1e-3);
        let record = Record {
            p: Vec3A::ZERO,
            n: Vec3A::Z,
            e: g.irradiance(),
            rotation: g.gradient(),
            translation: g.translation(0.0),
            r: 1.0,
        };
        // Tilting the normal 10° towards or away from the bright side changes the irradiance by
        // about ±6%; the gradient follows it to within 1% (the rest: the horizon, the tan clamp).
        for deg in [-10.0f32, 10.0] {
            let t = deg.to_radians();
            let n = Vec3A::new(t.sin(), 0.0, t.cos());
            let (want, got) = (truth(n), record.at(Vec3A::ZERO, n));
            assert!((want - e0).x.abs() > 0.04 * e0.x, "{deg}: {want} vs {e0}");
            assert!(
                (got - want).abs().max_element() < 0.01 * want.max_element(),
                "{deg}: {got} vs {want}"
            );
        }
    }

    /// A point on the plane `z = 0` under a light filling the half of the plane `z = h` where
    /// `p·e > 0` (`e` a unit direction in the plane, radiance 1): its irradiance is
    /// `(π/2)(1 + x/√(x² + h²))` with `x = p·e`, whose gradient is `(π/2) h²/(x² + h²)^{3/2}`
    /// along `e`. Over edges in eight directions (the gather's own frame is fixed, so the edge
    /// crosses its rings and wedges every way) and points under the light, beside it and under
    /// its edge, a 256-ray gather's translational gradient (the mean of 64) holds it within 12%
    /// (measured: 0.5% under the edge, 10% where the edge is 50° from the normal), with no
    /// component along the edge beyond 2% of it. The estimate is a difference over the grid's
    /// cells, so its error is first order in the cells' size: at 1024 rays (twice the rings
    /// and wedges) the worst error is at most 0.6 of the 256 rays'.
    #[test]
    fn a_gather_under_a_half_plane_light_has_its_irradiance_gradient() {
        let h = 1.0f32;
        let mut rng = Rng::new(7, Pass::Cache, 2);
        let mut worst = [0.0f32; 2];
        for (n, rays) in [256, 1024].into_iter().enumerate() {
            for turn in 0..8 {
                let a = turn as f32 * std::f32::consts::TAU / 8.0 + 0.1;
                let e = Vec3A::new(a.cos(), a.sin(), 0.0);
                for x in [-0.8f32, -0.2, 0.0, 0.3, 1.2] {
                    let p = e * x;
                    let mut sums = (Vec3A::ZERO, 0.0f32);
                    let tries = 64;
                    for _ in 0..tries {
                        let mut g = Gather::with_translation(Vec3A::Z, rays);
                        for (i, d) in g.directions(&mut rng).into_iter().enumerate() {
                            let t = h / d.z;
                            let lit = (p + d * t).dot(e) > 0.0;
                            g.add(i, d, Vec3A::splat(if lit { 1.0 } else { 0.0 }), t);
                        }
                        sums.0 += g.translation(0.0)[1];
                        sums.1 += g.irradiance().y;
                    }
                    let (grad, irradiance) = (sums.0 / tries as f32, sums.1 / tries as f32);
                    let half_pi = std::f32::consts::FRAC_PI_2;
                    let want_e = half_pi * (1.0 + x / (x * x + h * h).sqrt());
                    let want = half_pi * h * h / (x * x + h * h).powf(1.5);
                    assert!((irradiance - want_e).abs() < 0.01 * half_pi, "{irradiance}");
                    let along = grad.dot(e);
                    let across = (grad - along * e).length();
                    worst[n] = worst[n].max((along / want - 1.0).abs());
                    assert!(
                        (along - want).abs() < 0.12 * want && across < 0.02 * want,
                        "{rays} rays, edge at {a}, x {x}: {grad} against {want} along {e}"
                    );
                    assert!(grad.z.abs() < 1e-4, "{grad}");
                }
            }
        }
        assert!(worst[1] <= 0.6 * worst[0], "worst errors {worst:?}");
    }

    /// Records every 0.2 along a line under the half-plane light of the test above (`x` from
    /// −2 to 0, regions 0.3 wide), each with the closed form's irradiance and gradient, and
    /// lookups from −2 to 0.25, the last stretch served from one side only (a record region's
    /// edge, as at a wall). With the gradient the lookups follow `E(x)` to within 0.5% of its
    /// largest value, and the worst error is at most a tenth of the same records' without it
    /// (the weighted mean of neighbours' values; measured 0.0117 against 0.381, at the edge).
    /// Between records on both sides the mean of neighbours already cancels most of the
    /// first-order change (on a line of records from −2 to 2: 0.0103 against 0.0169), so the
    /// gain is at the edges of the records' regions. The shading point's normal is the records', so only the translational
    /// term acts.
    #[test]
    fn records_moved_by_their_gradient_follow_the_light_between_them() {
        let half_pi = std::f32::consts::FRAC_PI_2;
        let e = |x: f32| half_pi * (1.0 + x / (x * x + 1.0).sqrt());
        let de = |x: f32| half_pi / (x * x + 1.0).powf(1.5);
        let cache = |gradient: bool| {
            let records = (-10..=0)
                .map(|i| {
                    let x = i as f32 * 0.2;
                    let g = if gradient {
                        Vec3A::X * de(x)
                    } else {
                        Vec3A::ZERO
                    };
                    Record {
                        translation: [g; 3],
                        ..record(Vec3A::new(x, 0.0, 0.0), Vec3A::Z, e(x), 1.0)
                    }
                })
                .collect();
            IrradianceCache::new(records, 0.3)
        };
        let worst = |c: &IrradianceCache| {
            (0..=225)
                .map(|k| -2.0 + k as f32 * 0.01)
                .map(|x| {
                    let got = c
                        .lookup(Vec3A::new(x, 0.0, 0.0), Vec3A::Z, Vec3A::Z)
                        .unwrap();
                    (got.x - e(x)).abs()
                })
                .fold(0.0f32, f32::max)
        };
        let (with, without) = (worst(&cache(true)), worst(&cache(false)));
        assert!(
            with < 0.005 * 2.0 * half_pi,
            "with the gradient {with}, without {without}"
        );
        assert!(with < 0.1 * without, "with {with}, without {without}");
    }

    /// A gather sampled as n-rooks has no translational gradient; the grid's rays number at
    /// most the rays asked for, with `N ≈ πM`.
    #[test]
    fn only_a_grid_gather_has_a_translational_gradient() {
        let mut rng = Rng::new(1, Pass::Cache, 3);
        let mut g = Gather::new(Vec3A::Z, 64);
        for (i, d) in g.directions(&mut rng).into_iter().enumerate() {
            g.add(i, d, Vec3A::splat(d.x.max(0.0)), 1.0);
        }
        assert_eq!(g.translation(0.0), [Vec3A::ZERO; 3]);
        for (rays, rings, wedges) in [(256, 9, 28), (170, 7, 24), (1, 1, 1), (3, 1, 3)] {
            let g = Gather::with_translation(Vec3A::Z, rays);
            let c = g.grid.as_ref().unwrap();
            assert_eq!((c.rings, c.wedges, g.rays), (rings, wedges, rings * wedges));
            assert_eq!(g.directions(&mut rng).len() as u32, rings * wedges);
        }
    }

    #[test]
    fn an_empty_cache_serves_nothing() {
        let cache = IrradianceCache::new(Vec::new(), 0.3);
        assert!(cache.is_empty());
        assert_eq!(cache.lookup(Vec3A::ZERO, Vec3A::Y, Vec3A::Y), None);
    }
}
