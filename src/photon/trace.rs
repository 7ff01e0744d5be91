//! Photon tracing: emission from the lights, scattering by the materials, storage at diffuse
//! surfaces into the global and caustic maps (Jensen).
//!
//! - **Global photons** leave each light with its emission distribution ([`Light::emit`]), a
//!   point light's only through the directions that can meet the scene (its [`ProjectionMap`],
//!   Jensen's projection map: a lamp over a small table in empty space sends three quarters of
//!   its photons onto the table instead of 7%), and are stored at every surface with a diffuse
//!   part. A spot's photons leave in proportion to its falloff, all of the same power, never
//!   beyond its outer cone; a directional light's leave uniformly from a disc facing it that
//!   covers the sphere round the scene ([`crate::light`]). At each hit a photon takes one of
//!   the material's behaviours ([`crate::material::Material::lobes`]) with probability equal to its weight
//!   (Russian roulette on albedo), or is absorbed; its power is divided by that probability, so
//!   it stays an unbiased estimate. At a surface that reflects more than it receives (`kd`
//!   above 1) the lobes are scaled to sum 1, and the photon keeps its power rather than
//!   gaining ([`crate::material::bsdf`]).
//! - **Caustic photons** are aimed at the scene's specular objects (mirrors and dielectrics): each
//!   is sent into a cone around one of their bounding spheres, chosen in proportion to the cones'
//!   solid angles, and weighted by the inverse of the resulting direction density (a projection map
//!   without the map), the power carrying the light's intensity that way (a spot's falloff: a
//!   target outside its outer cone gets photons of no power, which are dropped). A directional
//!   light's are parallel: each starts on the disc a target's sphere casts along the light,
//!   the disc chosen by area and weighted by how many discs cover the point. Only paths
//!   light → specular⁺ → diffuse are kept: the photon is stored at the first diffuse surface
//!   after at least one specular bounce and stops there.
//! - Power is flux in watts, already divided by the light's photon count, and multiplied once by the
//!   light's falloff ratio `g(d)` at the first hit ([`Light::falloff_ratio`]).
//! - Media are tracked as for eye rays ([`MediumStack`]); false interfaces are crossed unchanged.
//! - Photon `k` of light `l` draws from the stream `(seed, Pass::Photon, l·2⁴⁰ + map·2³⁹ + k)`:
//!   the maps do not depend on the thread count, and tracing runs on all cores.
//! - A thread traces its chunk of photons sorted by where they head ([`Coherent`]), so that
//!   photons traced one after another meet the same triangles and texels instead of waiting on
//!   memory for each, and stores them back in index order: the maps are the same as tracing one
//!   photon after another.

use super::Photon;
use super::stream::{PhotonStream, Staged};
use crate::geometry::{Ray, offset_ray_origin};
use crate::light::Light;
use crate::material::bsdf::Lobe;
use crate::material::medium::MediumStack;
use crate::progress::{NoProgress, Progress};
use crate::sampling::{Pass, Rng};
use crate::scene::Scene;
use crate::scene::interaction::Needs;
use glam::Vec3A;
use std::collections::BTreeMap;
use std::f32::consts::TAU;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};

/// Most surface interactions a photon path may have: a safety bound only. Paths end by Russian
/// roulette on the lobe weights long before (a diffuse bounce survives with the albedo), and
/// interface crossings count too: a cap of 12 cut off light after three bounces under water,
/// 5% of the whole image of a water scene (tools/validate).
pub const MAX_BOUNCES: u32 = 256;
pub use crate::range::MAX_PHOTONS;
/// Least photons a light gets when the budget is shared, so a dim light over a pool still casts
/// caustics: this fraction of an equal share.
const MIN_SHARE: f64 = 0.1;

/// Which map a photon path is traced for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    Global = 0,
    Caustic = 1,
}

/// Counts for one light, printed by `--stats`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LightCounts {
    pub emitted: u64,
    pub stored: u64,
    /// Photons that the first surface they met reflected or refracted specularly (a mirror,
    /// a dielectric, or a Phong highlight's lobe, which photons take as a mirror's): for the
    /// caustic map, how well aiming at the specular objects works (Jensen's projection maps).
    /// A glossy tile is a specular object to aim at, but most photons that meet it take its
    /// diffuse lobe: they are not counted.
    pub first_hit_specular: u64,
    /// Photons that met any surface: for the global map, how well the projection map works
    /// (not kept in photon-map files: 0 for maps read from one).
    pub met_surface: u64,
    /// The share of the sphere of directions the light's projection map kept for global
    /// photons, in millionths (0: no map, every direction).
    pub kept_ppm: u32,
}

/// The photons of one map in the order they were traced (see [`PhotonMap::from_stream`]), with
/// per-light counts.
///
/// [`PhotonMap::from_stream`]: crate::photon::PhotonMap::from_stream
#[derive(Clone, Debug, Default)]
pub struct TracedMap {
    pub photons: PhotonStream,
    pub per_light: Vec<LightCounts>,
}

impl TracedMap {
    /// Returns the number of photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// Returns whether no photon was stored.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }
}

/// Returns each light's photon count: its own `num_photons`, or a share of `total` in proportion to
/// its `power` (its flux's mean when it has none), at least a tenth of an equal share.
pub fn photon_budget(lights: &[Light], total: u64) -> Vec<u64> {
    let weight = |l: &Light| {
        l.power
            .map(f64::from)
            .unwrap_or_else(|| l.flux().element_sum() as f64 / 3.0)
            .max(0.0)
    };
    let sharing: Vec<usize> = (0..lights.len())
        .filter(|&i| lights[i].photons.is_none())
        .collect();
    let sum: f64 = sharing.iter().map(|&i| weight(&lights[i])).sum();
    let floor = MIN_SHARE / sharing.len().max(1) as f64;
    lights
        .iter()
        .map(|l| match l.photons {
            Some(n) => n,
            None => {
                let share = if sum > 0.0 {
                    weight(l) / sum
                } else {
                    1.0 / sharing.len() as f64
                };
                (share.max(floor) * total as f64).round() as u64
            }
        })
        .collect()
}

/// A cone of directions around a specular object's bounding sphere, seen from an emission point.
#[derive(Clone, Copy, Debug)]
struct Cone {
    axis: Vec3A,
    cos_max: f32,
    solid_angle: f32,
}

impl Cone {
    fn towards(origin: Vec3A, centre: Vec3A, radius: f32) -> Cone {
        let to = centre - origin;
        let d = to.length();
        if d <= radius * 1.0001 {
            return Cone {
                axis: Vec3A::Z,
                cos_max: -1.0,
                solid_angle: 2.0 * TAU,
            };
        }
        let sin = radius / d;
        let cos_max = (1.0 - sin * sin).max(0.0).sqrt();
        Cone {
            axis: to / d,
            cos_max,
            solid_angle: TAU * (1.0 - cos_max),
        }
    }

    /// Returns the narrowest cone around `target` seen from `origin`: around its bounding
    /// sphere, or around the eight corners of its world box when that is narrower (a flat,
    /// wide water surface under a lamp, whose sphere is as wide as the box is long and takes
    /// in the walls above the water).
    fn around(origin: Vec3A, target: &Target) -> Cone {
        let sphere = Cone::towards(origin, target.centre, target.radius);
        let b = &target.bounds;
        let mid = (b.min + b.max) * 0.5;
        let to = mid - origin;
        let d = to.length();
        let inside = (origin.cmpge(b.min) & origin.cmple(b.max)).all();
        if inside || !d.is_finite() || d == 0.0 {
            return sphere;
        }
        let axis = to / d;
        let mut cos_max = 1.0f32;
        for k in 0..8 {
            let corner = Vec3A::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let Some(dir) = (corner - origin).try_normalize() else {
                return sphere;
            };
            cos_max = cos_max.min(dir.dot(axis));
        }
        // A cone is convex only below 90 degrees: holding the corners then means holding the
        // box. Shrink the cosine by a hair for rounding, as the spheres are grown.
        let cos_max = cos_max - 1e-5;
        if cos_max <= 0.0 {
            return sphere;
        }
        let boxed = Cone {
            axis,
            cos_max,
            solid_angle: TAU * (1.0 - cos_max),
        };
        if boxed.solid_angle < sphere.solid_angle {
            boxed
        } else {
            sphere
        }
    }

    /// Returns a cone holding `target` seen from `origin`: [`Cone::around`], or where that is
    /// every direction while `origin` is outside the target's box, the hemisphere beyond the
    /// box face that separates them (every point of the box lies past that face's plane).
    fn holding(origin: Vec3A, target: &Target) -> Cone {
        let cone = Cone::around(origin, target);
        match separating_axis(origin, &target.bounds) {
            Some(axis) if cone.cos_max <= -1.0 => Cone {
                axis,
                cos_max: 0.0,
                solid_angle: TAU,
            },
            _ => cone,
        }
    }

    fn contains(&self, dir: Vec3A) -> bool {
        dir.dot(self.axis) >= self.cos_max
    }

    fn sample(&self, u: (f32, f32)) -> Vec3A {
        let cos = 1.0 - u.0 * (1.0 - self.cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = TAU * u.1;
        let t = self.axis.any_orthonormal_vector();
        let b = self.axis.cross(t);
        (t * (sin * phi.cos()) + b * (sin * phi.sin()) + self.axis * cos).normalize()
    }
}

/// An instance that can scatter specularly, as caustic photons aim at it: a bounding sphere and
/// its world box (from each emission point the narrower cone is used, [`Cone::around`]).
#[derive(Clone, Copy, Debug)]
pub struct Target {
    pub centre: Vec3A,
    pub radius: f32,
    pub bounds: crate::accel::Bounds,
}

/// Returns every instance that can scatter specularly, with its bounding sphere and box.
///
/// Each sphere is the smaller of the sphere around the instance's world box and, for an analytic
/// primitive, its own bounding sphere carried into the world: for a sphere that is the sphere
/// itself, where the box's sphere is √3 times wider and would waste two thirds of the caustic
/// photons aimed at it (the share that meets it first is in `--stats`).
pub fn specular_targets(scene: &Scene) -> Vec<Target> {
    targets_where(scene, |inst| {
        scene
            .instance_materials(inst)
            .iter()
            .any(|&m| scene.materials[m as usize].is_specular())
    })
}

/// Returns the bounding sphere and box of every instance for which `keep` holds.
fn targets_where(scene: &Scene, keep: impl Fn(&crate::scene::Instance) -> bool) -> Vec<Target> {
    use crate::geometry::Analytic;
    use crate::scene::types::Shape;
    scene
        .instances
        .iter()
        .filter(|inst| keep(inst))
        .map(|inst| {
            let c = (inst.bounds.min + inst.bounds.max) * 0.5;
            let boxed = (c, (inst.bounds.max - c).length());
            let own = match inst.shape {
                Shape::Analytic(Analytic::Sphere) => Some((Vec3A::ZERO, 1.0)),
                Shape::Analytic(Analytic::Cube) => Some((Vec3A::splat(0.5), 0.75f32.sqrt())),
                Shape::Analytic(Analytic::Cylinder) => Some((Vec3A::ZERO, 2.0f32.sqrt())),
                Shape::Analytic(Analytic::Cone) => {
                    Some((Vec3A::new(0.0, 0.0, 0.5), 1.25f32.sqrt()))
                }
                Shape::Mesh(_) | Shape::Csg(_) => None,
            };
            let (centre, radius) = own
                .map(|(oc, r)| {
                    let m = inst.world_from_object;
                    (m.transform_point3a(oc), r * stretch(m.matrix3))
                })
                .filter(|own| own.1 < boxed.1)
                .unwrap_or(boxed);
            let grow =
                Vec3A::splat(1e-4 * (inst.bounds.max - inst.bounds.min).max_element() + 1e-6);
            Target {
                centre,
                radius: radius * 1.001 + 1e-6,
                bounds: crate::accel::Bounds {
                    min: inst.bounds.min - grow,
                    max: inst.bounds.max + grow,
                },
            }
        })
        .collect()
}

/// Returns a bound on how much `m` lengthens a vector: its longest column when the columns are
/// orthogonal (scales and rotations without shear: the exact bound), else the Frobenius norm
/// (always a bound).
fn stretch(m: glam::Mat3A) -> f32 {
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let orthogonal = (0..3).all(|i| {
        let (a, b) = (cols[i], cols[(i + 1) % 3]);
        a.dot(b).abs() <= 1e-5 * a.length() * b.length()
    });
    if orthogonal {
        cols.iter().map(|c| c.length()).fold(0.0, f32::max)
    } else {
        cols.iter().map(|c| c.length_squared()).sum::<f32>().sqrt()
    }
}

/// Returns the normal of the face of box `b` whose plane separates `origin` from the box most
/// widely, pointing away from `origin` (every direction from `origin` into the box is within
/// 90° of it), or `None` when `origin` is inside the box or on its surface.
fn separating_axis(origin: Vec3A, b: &crate::accel::Bounds) -> Option<Vec3A> {
    let (below, above) = (b.min - origin, origin - b.max);
    let (gap, axis) = (0..3)
        .flat_map(|a| {
            let mut e = Vec3A::ZERO;
            e[a] = 1.0;
            [(below[a], e), (above[a], -e)]
        })
        .fold(
            (0.0f32, Vec3A::ZERO),
            |best, g| if g.0 > best.0 { g } else { best },
        );
    (gap > 0.0).then_some(axis)
}

/// Cells per side of a [`ProjectionMap`]: 128 × 128 cells of 1/16384 of the sphere each
/// (about 1.6° across at the equator).
const PROJECTION_SIDE: u32 = 128;
/// Most instances a projection map tests one by one; beyond, it tests the box around them all.
const PROJECTION_TARGETS: usize = 4096;

/// Jensen's projection map (1996, §5) for a point light's global photons: the directions from
/// the light that can meet geometry, as cells of a grid over `(z, φ)`. Cells of equal `Δz` and
/// `Δφ` have equal solid angle (Archimedes), and a direction uniform in `(z, φ)` within a cell
/// is uniform in solid angle, so a photon sent through a cell chosen uniformly among the `m` of
/// `M` kept carries `Φ·(m/M)/n`: the flux into the kept directions, and none is lost, because a
/// cell is dropped only when its bounding cone misses the cone around every instance
/// ([`Cone::around`]). A small lamp over a large empty space then spends its photons on the
/// scene, not on the sky.
#[derive(Clone, Debug, PartialEq)]
pub struct ProjectionMap {
    /// The kept cells, `i·SIDE + j` for `z` row `i` and `φ` column `j`.
    cells: Vec<u32>,
}

impl ProjectionMap {
    /// Returns the map of the light at `origin` over `targets`, or `None` when every cell is
    /// kept (the map would only reorder the photons) or no cell is (nothing to light).
    pub fn new(origin: Vec3A, targets: &[Target]) -> Option<ProjectionMap> {
        let merged;
        let targets = if targets.len() > PROJECTION_TARGETS {
            let b = targets
                .iter()
                .fold(crate::accel::Bounds::EMPTY, |a, t| a.union(t.bounds));
            let c = (b.min + b.max) * 0.5;
            merged = [Target {
                centre: c,
                radius: (b.max - c).length() * 1.001 + 1e-6,
                bounds: b,
            }];
            &merged[..]
        } else {
            targets
        };
        let cones: Vec<Cone> = targets.iter().map(|t| Cone::holding(origin, t)).collect();
        if cones
            .iter()
            .any(|c| c.cos_max <= -1.0 || !c.cos_max.is_finite())
        {
            return None;
        }
        // Each cone's half-angle h, with its cosine and sine: a cell of spread s is seen when
        // the angle between the axes is at most h + s, i.e. their cosine at least
        // cos h·cos s − sin h·sin s (every direction once h + s reaches π).
        let half: Vec<(f32, f32, f32)> = cones
            .iter()
            .map(|c| {
                let cos = c.cos_max.clamp(-1.0, 1.0);
                (cos.acos(), cos, (1.0 - cos * cos).max(0.0).sqrt())
            })
            .collect();
        // And the side of each box facing the light: a cell is kept only if it also reaches
        // past that face's plane (a cone around a flat piece seen edge-on pokes above it).
        let sides: Vec<Option<Vec3A>> = targets
            .iter()
            .map(|t| separating_axis(origin, &t.bounds))
            .collect();
        let n = PROJECTION_SIDE;
        let at = |i: f32, j: f32| crate::sampling::uniform_sphere((i / n as f32, j / n as f32));
        // Rows in parallel (thousands of instances make it 4096 × 16384 cone tests).
        use rayon::prelude::*;
        let cells: Vec<u32> = (0..n * n)
            .into_par_iter()
            .filter(|&cell| {
                let (fi, fj) = ((cell / n) as f32, (cell % n) as f32);
                let axis = at(fi + 0.5, fj + 0.5);
                // The farthest point of a cell from its centre is a corner (along a parallel
                // or a meridian the distance grows towards the ends); grown for rounding.
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
                let spread = corners
                    .iter()
                    .map(|&(a, b)| axis.dot(at(fi + a, fj + b)).clamp(-1.0, 1.0).acos())
                    .fold(0.0f32, f32::max);
                let spread = spread * 1.01 + 1e-4;
                let (cs, ss) = (spread.cos(), spread.sin());
                cones
                    .iter()
                    .zip(&half)
                    .zip(&sides)
                    .any(|((c, &(h, ch, sh)), side)| {
                        let in_cone = h + spread >= std::f32::consts::PI
                            || axis.dot(c.axis) >= ch * cs - sh * ss - 1e-6;
                        // Within 90° + s of the face normal: cos at least cos(90° + s) = −sin s.
                        in_cone && side.is_none_or(|e| axis.dot(e) >= -ss - 1e-6)
                    })
            })
            .collect();
        let all = (n * n) as usize;
        (!cells.is_empty() && cells.len() < all).then_some(ProjectionMap { cells })
    }

    /// Returns the fraction of the sphere of directions the kept cells cover.
    pub fn fraction(&self) -> f32 {
        self.cells.len() as f32 / (PROJECTION_SIDE * PROJECTION_SIDE) as f32
    }

    /// Returns a direction uniform over the kept cells from `u` in [0, 1)³: `u.2` picks the
    /// cell, `u.0` and `u.1` place the direction in it as [`crate::sampling::uniform_sphere`] does.
    fn sample(&self, u: (f32, f32, f32)) -> Vec3A {
        let k = ((u.2 * self.cells.len() as f32) as usize).min(self.cells.len() - 1);
        let (i, j) = (
            self.cells[k] / PROJECTION_SIDE,
            self.cells[k] % PROJECTION_SIDE,
        );
        let n = PROJECTION_SIDE as f32;
        crate::sampling::uniform_sphere(((i as f32 + u.0) / n, (j as f32 + u.1) / n))
    }
}

/// Most targets whose boxes a projection map cuts into pieces.
const PROJECTION_SPLIT_TARGETS: usize = 64;

/// Returns `t`'s box cut into 4 pieces along each side at least a quarter of its longest
/// (at most 64 pieces), each a target of its own.
fn split_target(t: &Target) -> Vec<Target> {
    let b = t.bounds;
    let size = b.max - b.min;
    let longest = size.max_element();
    let parts = |e: f32| if e >= 0.25 * longest { 4 } else { 1 };
    let n = [parts(size.x), parts(size.y), parts(size.z)];
    let mut out = Vec::new();
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let lo = Vec3A::new(i as f32, j as f32, k as f32);
                let count = Vec3A::new(n[0] as f32, n[1] as f32, n[2] as f32);
                let min = b.min + size * lo / count;
                let max = (b.min + size * (lo + 1.0) / count).min(b.max);
                // Grown a hair so the pieces overlap: rounding leaves no gap between them.
                let grow = Vec3A::splat(1e-4 * longest + 1e-6);
                let (min, max) = (min - grow, max + grow);
                let c = (min + max) * 0.5;
                out.push(Target {
                    centre: c,
                    radius: (max - c).length() * 1.001 + 1e-6,
                    bounds: crate::accel::Bounds { min, max },
                });
            }
        }
    }
    out
}

/// Returns the projection map of each light for global photons: point lights only (an area
/// light's photons leave from every point of it, and it mostly faces the scene anyway; a
/// spot's leave through its own cone, and a directional light's disc is the scene's shadow).
pub fn projection_maps(scene: &Scene) -> Vec<Option<ProjectionMap>> {
    let whole = targets_where(scene, |inst| inst.bounds.is_finite());
    // A few objects: each box cut into up to 4 × 4 × 4 pieces along its long sides, whose
    // cones hug it closer than one cone around its corners (a square's corner cone is half as
    // wide again as the square).
    let targets = if whole.len() <= PROJECTION_SPLIT_TARGETS {
        whole.iter().flat_map(split_target).collect()
    } else {
        whole
    };
    let unbounded = scene.instances.iter().any(|i| !i.bounds.is_finite());
    scene
        .lights
        .iter()
        .map(|l| match l.shape {
            crate::light::Shape::Point { position } if !unbounded => {
                ProjectionMap::new(position, &targets)
            }
            _ => None,
        })
        .collect()
}

/// Traces the photons of `kind` for every light: `budget[l]` emitted by light `l`.
pub fn trace_map(scene: &Scene, budget: &[u64], kind: MapKind, seed: u64) -> TracedMap {
    trace_map_with(scene, budget, kind, seed, &NoProgress)
}

/// [`trace_map`], reporting photons emitted to `progress` (one phase per map).
pub fn trace_map_with(
    scene: &Scene,
    budget: &[u64],
    kind: MapKind,
    seed: u64,
    progress: &dyn Progress,
) -> TracedMap {
    trace_map_part(scene, budget, (kind, seed), Part::WHOLE, progress)
}

/// Most parts a photon pass is split into ([`Part`]).
pub const MAX_PARTS: u32 = 4096;

/// A share of a photon pass that one process traces (`caustic photons --part i/N`): of each
/// light's `n` photons, those of index `n·i/N` up to `n·(i+1)/N`. Every photon's random stream
/// is keyed by its index, so the parts' streams, each light's shares put back in part order,
/// are the one stream a whole pass traces, photon for photon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// Which part, below `count`.
    pub index: u32,
    /// How many parts the pass is split into, 1 to [`MAX_PARTS`].
    pub count: u32,
}

impl Part {
    /// The whole pass as one part.
    pub const WHOLE: Part = Part { index: 0, count: 1 };

    /// Returns the photon indices of this part among a light's `n`.
    pub fn range(self, n: u64) -> std::ops::Range<u64> {
        let at = |i: u32| (u128::from(n) * u128::from(i) / u128::from(self.count)) as u64;
        at(self.index)..at(self.index + 1)
    }
}

/// Traces part `part` ([`Part`]) of the photons of `kind` for every light, `budget[l]` in all
/// for light `l`, with `seed`; each light's counts are its part's (`emitted` the part's share),
/// and the photons go in light order, each light's in index order.
pub fn trace_map_part(
    scene: &Scene,
    budget: &[u64],
    (kind, seed): (MapKind, u64),
    part: Part,
    progress: &dyn Progress,
) -> TracedMap {
    let targets = if kind == MapKind::Caustic {
        specular_targets(scene)
    } else {
        Vec::new()
    };
    let projections = if kind == MapKind::Global {
        projection_maps(scene)
    } else {
        vec![None; scene.lights.len()]
    };
    let mut out = TracedMap::default();
    if kind == MapKind::Caustic && targets.is_empty() {
        out.per_light = vec![LightCounts::default(); scene.lights.len()];
        return out;
    }
    let what = match kind {
        MapKind::Global => "tracing global photons",
        MapKind::Caustic => "tracing caustic photons",
    };
    let share = |l: usize| part.range(budget.get(l).copied().unwrap_or(0));
    let total = (0..scene.lights.len()).map(|l| share(l).end - share(l).start);
    progress.start(what, total.sum());
    for (l, light) in scene.lights.iter().enumerate() {
        let pass = LightPass {
            scene,
            light,
            n: budget.get(l).copied().unwrap_or(0),
            kind,
            targets: &targets,
            projection: projections[l].as_ref(),
            media: scene.light_media.get(l).copied().unwrap_or_default(),
        };
        let stream = std::mem::take(&mut out.photons);
        let (stream, counts) = trace_light(&pass, (l, seed), share(l), stream, progress);
        out.photons = stream;
        out.per_light.push(counts);
    }
    out
}

/// Photons a tracing thread claims at a time, at most: enough that, sorted ([`Coherent`]), one
/// photon's neighbour lands a few triangles away on the final scene's water (4096 left them
/// tens of triangles apart and gained nothing; 262144 was no faster and balances small maps
/// worse).
const CHUNK: u64 = 65536;
/// Fewest photons a thread claims at a time.
const MIN_CHUNK: u64 = 4096;
/// Photons in flight, all threads together, that the chunk size keeps under: a sorted chunk
/// holds about 100 bytes a photon besides what it stores, and up to `2T + 2` finished chunks
/// wait for the stream, so on a machine of many threads the chunks shrink instead of the
/// memory growing with the threads (64 threads: 16384 photons a chunk).
const IN_FLIGHT: u64 = 1 << 20;

/// Fewest chunks a thread gets of a light's photons, where they are enough for [`MIN_CHUNK`]:
/// a small pass (a progressive pass's 100k photons) keeps small chunks, so the threads share
/// it evenly and few photons wait for the stream (a 64-pass render's peak memory then does not
/// depend on how the threads were scheduled in its worst pass).
const CHUNKS_PER_THREAD: u64 = 16;

/// Returns the photons a thread claims at a time of a light's `photons` with `threads`
/// threads (see [`CHUNK`], [`IN_FLIGHT`] and [`CHUNKS_PER_THREAD`]).
fn chunk_size(threads: usize, photons: u64) -> u64 {
    let threads = threads.max(1) as u64;
    (IN_FLIGHT / threads)
        .min(photons / (CHUNKS_PER_THREAD * threads))
        .clamp(MIN_CHUNK, CHUNK)
}

/// Traces the photons of indices `mine` of `pass`'s light (light `l`, streams keyed by `seed`)
/// on every thread, appending them to `stream` in index order; returns the stream and the
/// light's counts for them.
fn trace_light(
    pass: &LightPass,
    (l, seed): (usize, u64),
    mine: std::ops::Range<u64>,
    stream: PhotonStream,
    progress: &dyn Progress,
) -> (PhotonStream, LightCounts) {
    let kind = pass.kind;
    let chunk = chunk_size(rayon::current_num_threads(), mine.end - mine.start);
    let chunks = (mine.end - mine.start).div_ceil(chunk);
    // Every thread claims the next chunk in turn, and whoever finishes the chunk next in
    // order appends it and any finished after it: the stream takes the chunks in order,
    // and only the few chunks in flight wait outside it (see `crate::photon::stream`).
    let next = AtomicU64::new(0);
    let done = Mutex::new(InOrder {
        next: 0,
        waiting: BTreeMap::new(),
        counts: LightCounts {
            emitted: mine.end - mine.start,
            kept_ppm: pass
                .projection
                .map_or(0, |p| (p.fraction() * 1e6).round() as u32),
            ..LightCounts::default()
        },
        stream,
    });
    // A thread more than this many chunks ahead of the stream waits for it: a thread the
    // system stops for a while (another program, a loaded machine) would otherwise let the
    // others finish and hold chunk after chunk outside the stream, unbounded.
    let ahead = 2 * rayon::current_num_threads() as u64 + 2;
    let caught_up = Condvar::new();
    let reach = Coherent::reach(pass.scene);
    rayon::broadcast(|_| {
        // The cones a chunk's caustic photons aim through (see `leave_light`).
        let mut cones = Vec::new();
        let mut coherent = Coherent::new(reach);
        loop {
            let c = next.fetch_add(1, Ordering::Relaxed);
            if c >= chunks {
                break;
            }
            {
                // The chunk the stream takes next is claimed by a thread that is not
                // waiting (it is fewer than `ahead` chunks ahead), so this wait ends.
                let mut d = done.lock().unwrap_or_else(|e| e.into_inner());
                while c >= d.next + ahead {
                    d = caught_up.wait(d).unwrap_or_else(|e| e.into_inner());
                }
            }
            let (mut photons, mut on_specular, mut met) = (Vec::new(), 0, 0);
            cones.clear();
            // Asked to stop: the chunks left are not traced (the frame is dropped).
            if !progress.should_stop() {
                let first = mine.start + c * chunk;
                let keys = first..(first + chunk).min(mine.end);
                let rng = |k: u64| {
                    Rng::new(
                        seed,
                        Pass::Photon,
                        ((l as u64) << 40) | ((kind as u64) << 39) | k,
                    )
                };
                let hits = coherent.trace(pass, &mut cones, keys.map(rng), &mut photons);
                on_specular += hits.0;
                met += hits.1;
                progress.advance(chunk.min(mine.end - first));
            }
            let mut done = done.lock().unwrap_or_else(|e| e.into_inner());
            done.finish(c, photons, (on_specular, met));
            caught_up.notify_all();
        }
    });
    let done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    debug_assert!(done.waiting.is_empty() && done.next == chunks);
    (done.stream, done.counts)
}

/// A chunk's photons traced in an order that keeps neighbours near (see [`Coherent::trace`]),
/// with the buffers it reuses from chunk to chunk.
struct Coherent {
    /// How far along its ray a photon's sort key is taken ([`Coherent::reach`]).
    reach: f32,
    /// Each photon's ray and power as it leaves the light, with its stream, its index in the
    /// chunk and its sort key.
    starts: Vec<(u32, u32, Ray, Vec3A, Rng)>,
    /// The photons stored, in tracing order, and each photon's range of them by index.
    traced: Vec<Staged>,
    spans: Vec<(u32, std::ops::Range<usize>)>,
}

impl Coherent {
    /// Returns a tracer of chunks whose keys are taken `reach` along each ray.
    fn new(reach: f32) -> Coherent {
        Coherent {
            reach,
            starts: Vec::new(),
            traced: Vec::new(),
            spans: Vec::new(),
        }
    }

    /// Returns half of `scene`'s size (1 when it has none): how far along its ray a photon's
    /// sort key is taken. Made once a pass: the size is a fold over every instance.
    fn reach(scene: &Scene) -> f32 {
        match scene.extent() {
            e if e.is_finite() && e > 0.0 => 0.5 * e,
            _ => 1.0,
        }
    }

    /// Traces one photon for each of `rngs` (each photon's own stream, in index order),
    /// appending what they store to `out` in index order, as leaving the light and [`bounce`]
    /// one photon after another would; returns how many bounced specularly off the first
    /// surface and how many met one.
    ///
    /// Why not one after another: photons drawn at random land at random on a 2M-triangle water
    /// mesh and on the textures under it, and every hit waited for its triangle's vertices and
    /// its texels from memory (`Scene::surface` and `bilinear_bytes` were a quarter of the
    /// caustic pass). So all of a chunk's photons first leave the light (in index order, as
    /// the streams and a point light's shared cones require), then are traced sorted by the
    /// Morton code of where each would be after half the scene's size along its ray: photons
    /// traced one after another meet the same triangles, texels and BVH nodes. Each photon's
    /// path depends only on its own stream, so the photons stored are the same, and they are
    /// put back in index order: the map is the same bit for bit.
    fn trace(
        &mut self,
        pass: &LightPass,
        cones: &mut Vec<Cone>,
        rngs: impl Iterator<Item = Rng>,
        out: &mut Vec<Staged>,
    ) -> (u64, u64) {
        self.starts.clear();
        for (i, mut rng) in rngs.enumerate() {
            if let Some((ray, power)) = leave_light(pass, cones, &mut rng) {
                self.starts.push((0, i as u32, ray, power, rng));
            }
        }
        let reach = self.reach;
        let ahead = |r: &Ray| r.origin + r.dir * reach;
        let (lo, hi) = self
            .starts
            .iter()
            .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(ahead(&s.2)), hi.max(ahead(&s.2)))
            });
        let scale = Vec3A::splat(1023.0) / (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
        for s in &mut self.starts {
            s.0 = morton3(((ahead(&s.2) - lo) * scale).to_array());
        }
        self.starts.sort_unstable_by_key(|s| (s.0, s.1));
        self.traced.clear();
        self.spans.clear();
        let (mut on_specular, mut met) = (0, 0);
        for (_, i, ray, power, rng) in &mut self.starts {
            let begin = self.traced.len();
            let hit = bounce(pass, *ray, *power, rng, &mut self.traced);
            on_specular += u64::from(hit == FirstHit::Specular);
            met += u64::from(hit != FirstHit::Nothing);
            self.spans.push((*i, begin..self.traced.len()));
        }
        self.spans.sort_unstable_by_key(|s| s.0);
        for (_, span) in &self.spans {
            out.extend_from_slice(&self.traced[span.clone()]);
        }
        (on_specular, met)
    }
}

/// Returns the 30-bit Morton code of a point whose coordinates are in `[0, 1023]` (outside:
/// clamped; NaN: 0).
fn morton3(p: [f32; 3]) -> u32 {
    let spread = |x: f32| {
        let mut v = x.clamp(0.0, 1023.0) as u32;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    };
    spread(p[0]) | (spread(p[1]) << 1) | (spread(p[2]) << 2)
}

/// The chunks of one light's photons, taken into the stream in chunk order as they finish.
struct InOrder {
    /// The chunk the stream takes next.
    next: u64,
    /// Chunks finished before `next`: their photons, how many bounced specularly off the first
    /// surface and how many met any surface.
    waiting: BTreeMap<u64, (Vec<Staged>, (u64, u64))>,
    counts: LightCounts,
    stream: PhotonStream,
}

impl InOrder {
    /// Takes chunk `c`, and appends it with every waiting chunk after it once it is next.
    fn finish(&mut self, c: u64, photons: Vec<Staged>, first: (u64, u64)) {
        self.waiting.insert(c, (photons, first));
        while let Some((photons, (on_specular, met))) = self.waiting.remove(&self.next) {
            self.counts.stored += photons.len() as u64;
            self.counts.first_hit_specular += on_specular;
            self.counts.met_surface += met;
            self.stream.extend_from_slice(&photons);
            self.next += 1;
        }
    }
}

/// What a photon met first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FirstHit {
    /// Nothing: it left the scene, or carried no power.
    Nothing,
    /// A surface that reflected or refracted it specularly (the lobe drawn there).
    Specular,
    /// Any other surface.
    Other,
}

/// What every photon of one light's share of a map has in common.
struct LightPass<'a> {
    scene: &'a Scene,
    light: &'a Light,
    /// The light's photons for the map: each carries `1/n` of what it emits.
    n: u64,
    kind: MapKind,
    /// The specular objects caustic photons aim at.
    targets: &'a [Target],
    /// The light's projection map, for global photons of a point light that has one.
    projection: Option<&'a ProjectionMap>,
    /// The media the light is in, where its photons start ([`Scene::light_media`]).
    media: MediumStack,
}

/// Traces one photon of `pass` ([`leave_light`], then [`bounce`]), appending what it stores to
/// `out`; returns what it met first. The tests' reference for [`Coherent::trace`].
#[cfg(test)]
fn trace_one(
    pass: &LightPass,
    cones: &mut Vec<Cone>,
    rng: &mut Rng,
    out: &mut Vec<Staged>,
) -> FirstHit {
    match leave_light(pass, cones, rng) {
        Some((ray, power)) => bounce(pass, ray, power, rng, out),
        None => FirstHit::Nothing,
    }
}

/// Returns the ray a photon of `pass` leaves its light along and the power it carries, or
/// `None` when it carries none. A global photon of a point light leaves through the light's
/// projection map when it has one ([`ProjectionMap`]). A caustic photon aims through the cones
/// around the pass's targets from where it leaves the light, kept in `cones`: made afresh for
/// each photon of an area or sphere light, and once for a point light, whose photons all leave
/// from the same place (so a chunk's photons leave in index order).
fn leave_light(pass: &LightPass, cones: &mut Vec<Cone>, rng: &mut Rng) -> Option<(Ray, Vec3A)> {
    let LightPass {
        light,
        n,
        kind,
        targets,
        projection,
        ..
    } = *pass;
    let u = [
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
    ];
    let e = light.emit(u);
    let (dir, power) = match kind {
        // Through the projection map's cells, with the flux of the directions it keeps.
        MapKind::Global => match projection {
            Some(map) => (
                map.sample((u[0], u[1], u[2])),
                light.flux() * (map.fraction() / n as f32),
            ),
            None => (e.dir, light.flux() / n as f32),
        },
        MapKind::Caustic => {
            if let crate::light::Shape::Directional { dir, sphere } = light.shape {
                return parallel_to_targets(light, (dir, sphere), targets, n, rng);
            }
            // Aim at one specular object's cone, chosen by solid angle; weight by 1 / density.
            if cones.is_empty() || light.is_area() {
                cones.clear();
                cones.extend(targets.iter().map(|t| Cone::around(e.origin, t)));
            }
            let total: f32 = cones.iter().map(|c| c.solid_angle).sum();
            let mut pick = rng.next_f32() * total;
            let cone = cones
                .iter()
                .find(|c| {
                    pick -= c.solid_angle;
                    pick < 0.0
                })
                .unwrap_or(&cones[cones.len() - 1]);
            let dir = cone.sample((rng.next_f32(), rng.next_f32()));
            let covering = cones.iter().filter(|c| c.contains(dir)).count().max(1) as f32;
            // Intensity towards dir: the light's emitted radiance integrated over its area, per
            // steradian (see `Light::sample`, which uses the same definition); a spot's falloff.
            let intensity = light.sample(e.origin + dir, (u[0], u[1])).intensity;
            // Physical intensity is π times the course's (see crate::light).
            (
                dir,
                intensity * (std::f32::consts::PI * total / (covering * n as f32)),
            )
        }
    };
    if power.max_element() <= 0.0 {
        return None;
    }
    let start = if e.normal == Vec3A::ZERO {
        e.origin
    } else {
        offset_ray_origin(e.origin, e.normal, dir)
    };
    Some((Ray::new(start, dir), power))
}

/// Returns the ray and power of a caustic photon of directional light `light` (travelling
/// along `dir`, from beyond `sphere`), aimed at the specular `targets` of a pass of `n`
/// photons: the parallel counterpart of the cones. Seen along `dir`, each target's bounding
/// sphere is a disc of area `πr²`; a disc is chosen by its area and a point uniformly on it,
/// moved back along `dir` to the plane the light's disc lies in. The point's density over that
/// plane is `covering / Σ πr²` (the number of discs holding it), so the photon carries
/// `E_phys·Σ πr² / (covering·n)`, and every line of the light that meets a target is drawn.
fn parallel_to_targets(
    light: &Light,
    (dir, sphere): (Vec3A, crate::light::directional::SceneSphere),
    targets: &[Target],
    n: u64,
    rng: &mut Rng,
) -> Option<(Ray, Vec3A)> {
    let area = |t: &Target| t.radius * t.radius;
    let total: f32 = targets.iter().map(area).sum();
    let mut pick = rng.next_f32() * total;
    let target = targets
        .iter()
        .find(|t| {
            pick -= area(t);
            pick < 0.0
        })
        .or(targets.last())?;
    let (u0, u1) = (rng.next_f32(), rng.next_f32());
    let (r, phi) = (target.radius * u0.sqrt(), TAU * u1);
    let t = dir.any_orthonormal_vector();
    let b = dir.cross(t);
    let q = target.centre + (t * phi.cos() + b * phi.sin()) * r;
    let covering = targets
        .iter()
        .filter(|k| {
            let rel = q - k.centre;
            (rel - dir * rel.dot(dir)).length_squared() <= k.radius * k.radius
        })
        .count()
        .max(1) as f32;
    // Back along dir to the plane of the light's disc, outside the scene's sphere.
    let origin = q + dir * ((sphere.centre - q).dot(dir) - sphere.radius);
    let irradiance = std::f32::consts::PI * light.colour;
    let power = irradiance * (std::f32::consts::PI * total / (covering * n as f32));
    (power.max_element() > 0.0).then(|| (Ray::new(origin, dir), power))
}

/// Follows a photon of `pass` from `ray` with `power` through the scene by Russian roulette over
/// the one BSDF's lobes, appending what it stores to `out` (every diffuse hit of a global
/// photon; a caustic photon's first diffuse hit after a specular bounce, where it ends);
/// returns what it met first.
fn bounce(
    pass: &LightPass,
    mut ray: Ray,
    mut power: Vec3A,
    rng: &mut Rng,
    out: &mut Vec<Staged>,
) -> FirstHit {
    let LightPass {
        scene, light, kind, ..
    } = *pass;
    let mut media = pass.media;
    let mut first = true;
    let mut diffuse_bounced = false;
    let mut specular_bounced = false;
    let mut met = FirstHit::Nothing;
    // Every ray of the path is a photon ray (nothing below casts another kind).
    crate::accel::counters::kind(crate::accel::counters::RayKind::Photon);
    for _ in 0..MAX_BOUNCES {
        let Some(hit) = scene.intersect(&ray) else {
            return met;
        };
        if first {
            power *= light.falloff_ratio(hit.t * ray.dir.length());
            first = false;
        }
        power *= scene.kept_along(&media, &ray, hit.t);
        if power.max_element() <= 0.0 {
            return met;
        }
        let it = scene.interaction(&ray, &hit, Needs::Full, None);
        let (surf, bsdf) = (&it.surf, &it.bsdf);
        let crossing = bsdf.crossing(&media);
        if let Some(c) = crossing
            && c.is_false()
        {
            media = c.after;
            ray = Ray::new(offset_ray_origin(surf.p, surf.ng, ray.dir), ray.dir);
            continue;
        }
        // What the first surface did with it is known once its lobe is drawn, below.
        let first_surface = met == FirstHit::Nothing;
        if first_surface {
            met = FirstHit::Other;
        }
        let store = match kind {
            MapKind::Global => true,
            MapKind::Caustic => specular_bounced,
        };
        if store && bsdf.lobes().diffuse.max_element() > 0.0 {
            out.push(Staged::new(&Photon {
                position: surf.p,
                power,
                dir: bsdf.wo,
                normal: bsdf.ng,
                direct: !diffuse_bounced,
            }));
        }
        // Russian roulette over the material's lobes.
        let Some(next) = bsdf.sample(crossing.as_ref(), rng) else {
            return met;
        };
        if first_surface && matches!(next.lobe, Lobe::Mirror | Lobe::Dielectric) {
            met = FirstHit::Specular;
        }
        match next.lobe {
            // Caustic paths end at their first diffuse surface.
            Lobe::Diffuse if kind == MapKind::Caustic => return met,
            Lobe::Diffuse => diffuse_bounced = true,
            Lobe::Mirror | Lobe::Dielectric => specular_bounced = true,
        }
        power *= next.weight;
        if let Some(after) = next.media {
            media = after;
        }
        ray = Ray::new(offset_ray_origin(surf.p, bsdf.ng, next.dir), next.dir);
    }
    met
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tracing a chunk sorted by where its photons head ([`Coherent`]) stores exactly what
    /// tracing them one after another in index order does, photon for photon and in the same
    /// order, for caustic photons of an area light (cones made per photon) and of a point light
    /// (cones shared by the chunk) and for global photons, with the same first-hit counts.
    #[test]
    fn a_sorted_chunk_stores_what_one_photon_after_another_does() {
        let src = b"floor = gr.cube('floor') floor:set_material(gr.material({0.6, 0.5, 0.4}, {0, 0, 0}, 0))
            floor:scale(4, 0.1, 4) floor:translate(-2, -1.1, -2)
            glass = gr.sphere('glass') glass:set_material(gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5))
            glass:scale(0.4, 0.4, 0.4) glass:translate(-0.5, -0.5, 0)
            mirror = gr.sphere('mirror') mirror:set_material(gr.material({0, 0, 0}, {0.9, 0.9, 0.9}, 500))
            mirror:scale(0.3, 0.3, 0.3) mirror:translate(0.6, -0.7, 0.2)
            root = gr.node('root') root:add_child(floor) root:add_child(glass) root:add_child(mirror)
            gr.render(root, 'x.png', 8, 8, {0, 0, 4}, {0, 0, -1}, {0, 1, 0}, 50, {0, 0, 0},
              {gr.area_light({0, 1.5, 0}, {4, 4, 4}, {1, 0, 0}, nil, 1000, {0.4, 0, 0}, {0, 0, 0.4}),
               gr.light({0.3, 1.2, 0.5}, {2, 2, 2}, {1, 0, 0})})";
        let (scene, _) = crate::lua::test_scene(src);
        let targets = specular_targets(&scene);
        assert_eq!(targets.len(), 2);
        let mut coherent = Coherent::new(Coherent::reach(&scene));
        for (l, light) in scene.lights.iter().enumerate() {
            for kind in [MapKind::Caustic, MapKind::Global] {
                let pass = LightPass {
                    scene: &scene,
                    light,
                    n: 3000,
                    kind,
                    targets: &targets,
                    projection: None,
                    media: scene.light_media.get(l).copied().unwrap_or_default(),
                };
                let rngs = || (0..3000).map(|k| Rng::new(9, Pass::Photon, k));
                let (mut want, mut cones) = (Vec::new(), Vec::new());
                let (mut on_specular, mut met) = (0, 0);
                for mut rng in rngs() {
                    let hit = trace_one(&pass, &mut cones, &mut rng, &mut want);
                    on_specular += u64::from(hit == FirstHit::Specular);
                    met += u64::from(hit != FirstHit::Nothing);
                }
                let mut got = Vec::new();
                cones.clear();
                let counts = coherent.trace(&pass, &mut cones, rngs(), &mut got);
                assert!(
                    want.len() > 100,
                    "light {l} {kind:?}: {} stored",
                    want.len()
                );
                assert_eq!(got, want, "light {l}, {kind:?}");
                assert_eq!(counts, (on_specular, met), "light {l}, {kind:?}");
            }
        }
    }

    /// Chunks are as large as [`CHUNK`] on a few threads and shrink with many, keeping the
    /// photons in flight under [`IN_FLIGHT`], and with small passes, giving each thread
    /// [`CHUNKS_PER_THREAD`]; never below [`MIN_CHUNK`].
    #[test]
    fn chunks_shrink_with_many_threads() {
        let many = 4_000_000;
        assert_eq!(chunk_size(0, many), CHUNK);
        assert_eq!(chunk_size(2, many), CHUNK);
        assert_eq!(chunk_size(16, many), 15625);
        assert_eq!(chunk_size(64, 1 << 30), 16384);
        assert_eq!(chunk_size(100_000, many), MIN_CHUNK);
        assert_eq!(chunk_size(2, 200_000), 6250);
        assert_eq!(chunk_size(2, 10), MIN_CHUNK);
        for t in 1..512 {
            let c = chunk_size(t, 1 << 30);
            assert!((MIN_CHUNK..=CHUNK).contains(&c));
            assert!(
                c * t as u64 <= IN_FLIGHT.max(MIN_CHUNK * t as u64),
                "{t} threads"
            );
        }
    }

    /// The Morton code interleaves the three coordinates' bits, x lowest, and clamps.
    #[test]
    fn morton_codes_interleave_x_y_z() {
        assert_eq!(morton3([1.0, 0.0, 0.0]), 0b001);
        assert_eq!(morton3([0.0, 1.0, 0.0]), 0b010);
        assert_eq!(morton3([0.0, 0.0, 1.0]), 0b100);
        assert_eq!(morton3([2.0, 3.0, 0.0]), 0b011_010);
        assert_eq!(morton3([1023.0; 3]), (1 << 30) - 1);
        assert_eq!(
            morton3([5000.0, -3.0, f32::NAN]),
            morton3([1023.0, 0.0, 0.0])
        );
    }

    /// The parts of a pass cover each light's photons once, in order: part `i`'s range ends
    /// where part `i + 1`'s starts, the first starts at 0 and the last ends at `n`, for counts
    /// from 0 to beyond `u64::MAX / MAX_PARTS` and splits from 1 to `MAX_PARTS`.
    #[test]
    fn the_parts_of_a_pass_cover_its_photons_once() {
        for n in [0u64, 1, 5, 4096, 1_000_003, u64::MAX / 3, u64::MAX] {
            for count in [1u32, 2, 3, 7, 64, MAX_PARTS] {
                let mut next = 0;
                for index in 0..count {
                    let r = Part { index, count }.range(n);
                    assert_eq!(r.start, next, "n {n}, part {index}/{count}");
                    assert!(r.end >= r.start);
                    next = r.end;
                }
                assert_eq!(next, n, "n {n}, {count} parts");
            }
        }
    }

    /// A projection map keeps every direction that meets the scene (brute force over 200,000
    /// random directions, each tested against the boxes exactly), and little more: a lamp 3
    /// above a 40 × 40 floor and 1 above a small box keeps under 65% of the sphere (the floor
    /// is 47% of it seen from there).
    #[test]
    fn a_projection_map_keeps_every_direction_that_meets_a_box() {
        use crate::accel::Bounds;
        let boxes = [
            Bounds {
                min: Vec3A::new(-20.0, -1.0, -20.0),
                max: Vec3A::new(20.0, 0.0, 20.0),
            },
            Bounds {
                min: Vec3A::new(1.0, 0.0, -0.5),
                max: Vec3A::new(2.0, 2.0, 0.5),
            },
        ];
        let targets: Vec<Target> = boxes
            .iter()
            .map(|&b| {
                let c = (b.min + b.max) * 0.5;
                Target {
                    centre: c,
                    radius: (b.max - c).length(),
                    bounds: b,
                }
            })
            .flat_map(|t| split_target(&t))
            .collect();
        let origin = Vec3A::new(0.0, 3.0, 0.0);
        let map = ProjectionMap::new(origin, &targets).expect("a map");
        let kept: std::collections::HashSet<u32> = map.cells.iter().copied().collect();
        let hits = |d: Vec3A, b: &Bounds| {
            let inv = d.recip();
            let (t0, t1) = ((b.min - origin) * inv, (b.max - origin) * inv);
            t0.min(t1).max_element() <= t0.max(t1).min_element() && t0.max(t1).min_element() > 0.0
        };
        let mut rng = Rng::new(3, Pass::Photon, 0);
        let n = PROJECTION_SIDE as f32;
        let mut met = 0;
        for _ in 0..200_000 {
            let u = (rng.next_f32(), rng.next_f32());
            let d = crate::sampling::uniform_sphere(u);
            if boxes.iter().any(|b| hits(d, b)) {
                met += 1;
                let cell = ((u.0 * n) as u32) * PROJECTION_SIDE + (u.1 * n) as u32;
                assert!(
                    kept.contains(&cell),
                    "direction {d} meets a box, its cell was dropped"
                );
            }
        }
        let share = met as f32 / 200_000.0;
        assert!(
            map.fraction() > share && map.fraction() < 0.65,
            "kept {} of the sphere for a scene seen in {share} of it",
            map.fraction()
        );
    }

    /// `stretch` bounds how far a matrix moves unit vectors, exactly for scales and rotations
    /// and safely for shears: 2000 random unit vectors through a rotated non-uniform scale and
    /// through a shear never come out longer than it says.
    #[test]
    fn stretch_bounds_every_vector_and_is_exact_without_shear() {
        let rotated = glam::Mat3A::from_rotation_y(0.7)
            * glam::Mat3A::from_diagonal(glam::Vec3::new(3.0, 1.0, 0.5));
        let sheared = glam::Mat3A::from_cols(Vec3A::X, Vec3A::new(2.0, 1.0, 0.0), Vec3A::Z);
        assert!((stretch(rotated) - 3.0).abs() < 1e-5);
        let mut rng = Rng::new(1, Pass::Photon, 0);
        for m in [rotated, sheared] {
            for _ in 0..1000 {
                let v = Vec3A::new(
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                )
                .normalize_or(Vec3A::X);
                assert!((m * v).length() <= stretch(m) * (1.0 + 1e-6));
            }
        }
    }

    #[test]
    fn budgets_follow_power_with_a_floor_and_explicit_counts() {
        let mut a = Light::point(Vec3A::ZERO, Vec3A::ONE, [1.0, 0.0, 0.0]);
        let mut b = a.clone();
        a.power = Some(99.0);
        b.power = Some(1.0);
        let mut c = a.clone();
        c.photons = Some(1234);
        let budget = photon_budget(&[a, b, c], 100_000);
        assert_eq!(budget[2], 1234, "an explicit count wins");
        assert_eq!(budget[0], 99_000);
        assert_eq!(
            budget[1], 5_000,
            "the dim light gets at least a tenth of an equal share"
        );
    }

    #[test]
    fn cone_samples_stay_inside_and_cover_it_uniformly() {
        let cone = Cone::towards(Vec3A::ZERO, Vec3A::new(0.0, 0.0, 10.0), 2.0);
        let mut rng = Rng::new(0, Pass::Photon, 1);
        let n = 100_000;
        let mut mean_cos = 0.0f64;
        for _ in 0..n {
            let d = cone.sample((rng.next_f32(), rng.next_f32()));
            assert!(cone.contains(d) || d.dot(cone.axis) > cone.cos_max - 1e-6);
            mean_cos += d.dot(cone.axis) as f64;
        }
        // Uniform in solid angle: cos θ uniform on [cos_max, 1].
        let want = (1.0 + cone.cos_max as f64) / 2.0;
        assert!(
            (mean_cos / n as f64 - want).abs() < 1e-4,
            "{} vs {want}",
            mean_cos / n as f64
        );
        assert!((cone.solid_angle - TAU * (1.0 - (1.0f32 - 0.04).sqrt())).abs() < 1e-5);
    }
}
