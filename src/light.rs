//! Lights: point, spot, directional, one-sided parallelogram (area), sphere and triangle-mesh
//! (emissive surface) lights, for direct lighting by shadow rays and for photon emission — one
//! lighting model for both.
//!
//! ```lua
//! gr.light({0, 0.5, 0}, {0.7, 0.5, 0.9}, {1, 0, 0}, 10000, 200000)          -- point
//! gr.area_light({0, 0.49, 0}, {1, 1, 1}, {1, 0, 0}, nil, 100000, {0.2, 0, 0}, {0, 0, 0.2})
//! gr.sphere_light({0, 0.4, 0}, {1, 1, 1}, {1, 0, 0}, nil, nil, 0.05)
//! gr.spot_light({0, 0.5, 0}, {0, -1, 0}, {1, 1, 1}, 15, 20)                  -- spot
//! gr.directional_light({-0.3, -1, -0.2}, {0.3, 0.3, 0.3})                   -- sun
//! ```
//!
//! # The lighting model
//! - The course shades with `kd·I·cos θ·att(d)`, i.e. it treats `kd` as a reflectance and `rgb` as
//!   `1/π` of a physical radiant intensity (a Lambertian surface of reflectance `kd` under
//!   irradiance `E` has radiance `kd·E/π`). caustic keeps that formula for direct light, so the
//!   A4 scenes look as they should, and gives lights the physical intensity it implies:
//!   `I_phys = π·rgb` (W/sr per channel) seen head-on. A point light sends `I_phys` in every
//!   direction; an area light sends `I_phys·cos θ` (a Lambertian emitter over its area, on the
//!   side of `u × v` only); a sphere light of radius `R` has radiance `I_phys/(πR²)`, so from afar
//!   it is a point light. [`Light::sample`] reports intensities in the course's units (`rgb`).
//! - Fluxes follow: `Φ = 4π·I_phys` for point and sphere lights, `Φ = π·I_phys` for area lights
//!   ([`Light::flux`]). Photon estimates turn irradiance into radiance with `kd·E/π`, so direct
//!   light and photon light agree; pbrt's closed sphere (kd 0.5, `I_phys = π`, that is `rgb = 1`)
//!   has radiance 1.
//! - `falloff = (c0, c1, c2)` replaces the physical `1/d²` of every light-to-surface transfer by
//!   `1/(c0 + c1·d + c2·d²)`, as the course does: direct irradiance is `I(θ)·cos θ_x / (c0 + c1·d +
//!   c2·d²)`. Photons honour it through the ratio `g(d) = d²/(c0 + c1·d + c2·d²)`
//!   ([`Light::falloff_ratio`]): a photon's power is multiplied by `g` of the distance from the light
//!   to its first hit, so the density of direct photons equals the direct-lighting term exactly (in
//!   expectation). `falloff = {0, 0, 1}` is physical (`g = 1`). Later bounces are physical.
//! - `power` and `num_photons` (the extended project's arguments) only steer the photon budget:
//!   `num_photons` is the light's photon count; lights without one share `--photons` in proportion
//!   to `power` (or, when absent, to their flux). Their absolute brightness always comes from `rgb`,
//!   so that direct and photon lighting agree.
//! - Attenuation applies to light from lights only, never to the ambient term.
//! - A mesh light ([`Shape::Mesh`]: one emissive primitive of a glTF file, placed) is a set of
//!   one-sided triangles of uniform radiance `L` and total area `A`, each emitting on the side its
//!   counter-clockwise winding faces. It is an area light spread over triangles: its `rgb` is
//!   `L·A/π`, so it is seen with radiance `π·rgb/A = L`, sheds `Φ = π·L·A`, and is sampled by
//!   choosing a triangle by its area and a point uniformly on it ([`Light::mesh`]).
//! - A spot light ([`Shape::Spot`]) is a point light whose intensity towards `ω` is
//!   `I_phys·t²(ω)`, glTF's falloff between its inner and outer cones ([`spot`]): its flux is
//!   `I_phys·∫ t² dω` (closed form, [`spot::SpotCone::solid_angle`]) and its photons leave in
//!   proportion to `t²`, each carrying `Φ/n` (none beyond the outer cone).
//! - A directional light ([`Shape::Directional`]) sends parallel light of irradiance
//!   `E_phys = π·rgb` on a surface facing it, so a Lambertian surface shows `kd·rgb·cos θ`, as
//!   under a point light: no distance and no falloff ([`Light::attenuation`] is 1). Its shadow
//!   rays end where they leave the sphere holding the scene's geometry, its photons leave a disc
//!   of that sphere's radius `R` facing it, and its flux is that disc's, `Φ = E_phys·πR²`
//!   ([`directional`]).

pub mod directional;
pub mod spot;

use crate::accel::Bounds;
use crate::desc::{LightDesc, LightShape};
use crate::geometry::Ray;
use crate::geometry::triangle::{self, RayShear};
use crate::sampling::{cosine_around, uniform_sphere};
use directional::SceneSphere;
use glam::Vec3A;
use spot::SpotCone;
use std::f32::consts::{PI, TAU};
use std::sync::Arc;

/// One triangle of a mesh light in world space: its corners, counter-clockwise seen from the
/// emitting side, and the unit normal of that side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterTriangle {
    pub corners: [Vec3A; 3],
    pub normal: Vec3A,
}

impl EmitterTriangle {
    /// Returns the triangle with corners `a`, `b`, `c` (counter-clockwise seen from the front).
    pub fn new(a: Vec3A, b: Vec3A, c: Vec3A) -> EmitterTriangle {
        EmitterTriangle {
            corners: [a, b, c],
            normal: (b - a).cross(c - a).normalize_or_zero(),
        }
    }

    /// Returns the triangle's area.
    pub fn area(&self) -> f32 {
        let [a, b, c] = self.corners;
        0.5 * (b - a).cross(c - a).length()
    }

    /// Returns the point of barycentric square root parametrisation `u` in [0, 1)²: uniform
    /// over the triangle's area.
    fn point(&self, u: (f32, f32)) -> Vec3A {
        let [a, b, c] = self.corners;
        let s = u.0.sqrt();
        a + (b - a) * (s * (1.0 - u.1)) + (c - a) * (s * u.1)
    }
}

/// The triangles of a mesh light with what sampling them needs, shared by the light's clones.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterMesh {
    pub triangles: Vec<EmitterTriangle>,
    /// Running sums of the triangles' areas divided by the total: `cdf[i]` is the probability
    /// of choosing a triangle up to `i`; the last entry is 1.
    pub cdf: Vec<f32>,
    /// The total area.
    pub area: f32,
    /// The area-weighted centroid of the triangles.
    pub centroid: Vec3A,
    /// The area-weighted mean of the normals (shorter than 1 where the surface curves).
    pub mean_normal: Vec3A,
    /// World bounds of the triangles, for a quick miss in [`Light::seen_by`].
    pub min: Vec3A,
    pub max: Vec3A,
}

impl EmitterMesh {
    /// Returns the triangle chosen by `u` in [0, 1) in proportion to area, and `u` rescaled to
    /// [0, 1) within that triangle's share.
    fn choose(&self, u: f32) -> (&EmitterTriangle, f32) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.triangles.len() - 1);
        let below = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let width = self.cdf[i] - below;
        let v = if width > 0.0 {
            ((u - below) / width).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (&self.triangles[i], v)
    }

    /// Returns whether `ray` can meet the mesh's bounds before `tmax` (a slab test).
    fn may_hit(&self, ray: &Ray, tmax: f32) -> bool {
        let inv = ray.dir.recip();
        let t0 = (self.min - ray.origin) * inv;
        let t1 = (self.max - ray.origin) * inv;
        let near = t0.min(t1).max_element().max(ray.tmin);
        let far = t0.max(t1).min_element().min(tmax);
        // NaN (a zero direction component on a slab's plane) lets the triangles decide.
        near.partial_cmp(&far) != Some(std::cmp::Ordering::Greater)
    }
}

/// A light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub shape: Shape,
    /// Head-on radiant intensity `I` per channel.
    pub colour: Vec3A,
    pub falloff: [f32; 3],
    /// The script's `power`, if any (photon budget weight).
    pub power: Option<f32>,
    /// The script's `num_photons`, if any.
    pub photons: Option<u64>,
}

/// The emitting geometry of a light.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Point {
        position: Vec3A,
    },
    /// A point light shining about unit `axis` with glTF's falloff ([`spot`]).
    Spot {
        position: Vec3A,
        axis: Vec3A,
        cone: SpotCone,
    },
    /// Parallel light travelling along unit `dir` from beyond `sphere`, which holds the
    /// scene's geometry ([`directional`]); the light's colour is its irradiance over π.
    Directional {
        dir: Vec3A,
        sphere: SceneSphere,
    },
    /// A parallelogram centred at `centre` with edges `u`, `v`, emitting on the side of `u × v`.
    Area {
        centre: Vec3A,
        u: Vec3A,
        v: Vec3A,
        normal: Vec3A,
        area: f32,
    },
    Sphere {
        centre: Vec3A,
        radius: f32,
    },
    /// One-sided emitting triangles of one radiance ([`Light::mesh`]).
    Mesh(Arc<EmitterMesh>),
}

/// A point sampled on a light, as seen from a shaded point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The point on the light.
    pub position: Vec3A,
    /// Radiant intensity towards the shaded point, already divided by the sample's density
    /// (so averaging samples estimates the light's intensity).
    pub intensity: Vec3A,
    /// The light's unit normal at the point (zero for a point light and a centre stand-in).
    pub normal: Vec3A,
}

/// Where a ray meets a light's emitting surface ([`Light::seen`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// The distance along the ray, in units of its direction.
    pub t: f32,
    /// The radiance seen there (black on the back of a one-sided light).
    pub radiance: Vec3A,
    /// The surface's unit normal there (the emitting side's for area and mesh lights).
    pub normal: Vec3A,
}

/// A photon leaving a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub origin: Vec3A,
    /// Unit direction of travel.
    pub dir: Vec3A,
    /// Normal of the emitting surface at `origin` (for ray offsets), or zero for point, spot
    /// and directional lights (a directional light's disc lies outside the scene).
    pub normal: Vec3A,
}

impl Light {
    /// Returns the light a script described, in a scene whose geometry `world` holds (the
    /// union of its instances' boxes: where a directional light's photons must reach).
    pub fn from_desc(d: &LightDesc, world: Bounds) -> Light {
        let shape = match d.shape {
            LightShape::Point => Shape::Point {
                position: d.position.into(),
            },
            LightShape::Spot {
                direction,
                inner,
                outer,
            } => Shape::Spot {
                position: d.position.into(),
                axis: Vec3A::from(direction).normalize_or(Vec3A::NEG_Y),
                cone: SpotCone::new(inner, outer),
            },
            LightShape::Directional { direction } => Shape::Directional {
                dir: Vec3A::from(direction).normalize_or(Vec3A::NEG_Y),
                sphere: SceneSphere::holding(world),
            },
            LightShape::Area { u, v } => {
                let (u, v) = (Vec3A::from(u), Vec3A::from(v));
                let n = u.cross(v);
                Shape::Area {
                    centre: d.position.into(),
                    u,
                    v,
                    normal: n.normalize_or_zero(),
                    area: n.length(),
                }
            }
            LightShape::Sphere { radius } => Shape::Sphere {
                centre: d.position.into(),
                radius,
            },
        };
        Light {
            shape,
            colour: d.colour.into(),
            falloff: d.falloff,
            power: d.power,
            photons: d.photons,
        }
    }

    /// Returns a point light at `position` with intensity `colour` and the course's falloff.
    pub fn point(position: Vec3A, colour: Vec3A, falloff: [f32; 3]) -> Light {
        Light {
            shape: Shape::Point { position },
            colour,
            falloff,
            power: None,
            photons: None,
        }
    }

    /// Returns the light of emitting triangles of radiance `radiance` (per channel), or `None`
    /// when their total area is zero (nothing emits). The falloff is physical, and the light's
    /// `power` is its flux summed over the channels: it takes part in photon mapping, as a
    /// physical light does, with a share of the photons in proportion to its flux.
    pub fn mesh(triangles: Vec<EmitterTriangle>, radiance: Vec3A) -> Option<Light> {
        let areas: Vec<f64> = triangles.iter().map(|t| f64::from(t.area())).collect();
        let total: f64 = areas.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut sum = 0.0;
        let mut cdf: Vec<f32> = areas
            .iter()
            .map(|a| {
                sum += a;
                (sum / total) as f32
            })
            .collect();
        // Rounding must not leave a sliver above the last triangle.
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let weighted = |f: &dyn Fn(&EmitterTriangle) -> Vec3A| {
            triangles
                .iter()
                .zip(&areas)
                .map(|(t, &a)| f(t) * (a / total) as f32)
                .sum::<Vec3A>()
        };
        let centroid = weighted(&|t| t.corners.iter().sum::<Vec3A>() / 3.0);
        let mean_normal = weighted(&|t| t.normal);
        let corners = triangles.iter().flat_map(|t| t.corners);
        let (min, max) = corners.fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        );
        let area = total as f32;
        Some(Light {
            shape: Shape::Mesh(Arc::new(EmitterMesh {
                triangles,
                cdf,
                area,
                centroid,
                mean_normal,
                min,
                max,
            })),
            colour: radiance * area / PI,
            falloff: [0.0, 0.0, 1.0],
            // A physical light: it takes part in photon mapping, its photon share by its flux.
            power: Some(PI * (radiance * area).element_sum()),
            photons: None,
        })
    }

    /// Returns the attenuation `1 / (c0 + c1·d + c2·d²)` at distance `d`; 1 for a directional
    /// light, whose light does not spread.
    pub fn attenuation(&self, d: f32) -> f32 {
        if let Shape::Directional { .. } = self.shape {
            return 1.0;
        }
        let [c0, c1, c2] = self.falloff;
        1.0 / (c0 + c1 * d + c2 * d * d)
    }

    /// Returns `g(d) = d² / (c0 + c1·d + c2·d²)`, the course's falloff relative to inverse
    /// square; 1 for a directional light, whose photons are parallel.
    pub fn falloff_ratio(&self, d: f32) -> f32 {
        if let Shape::Directional { .. } = self.shape {
            return 1.0;
        }
        d * d * self.attenuation(d)
    }

    /// Returns true for lights with extent (soft shadows need several samples).
    pub fn is_area(&self) -> bool {
        matches!(
            self.shape,
            Shape::Area { .. } | Shape::Sphere { .. } | Shape::Mesh(_)
        )
    }

    /// Returns the total emitted flux `Φ` per channel (physical units: `I_phys = π·rgb`); a
    /// directional light's is the flux through its disc ([`directional`]).
    pub fn flux(&self) -> Vec3A {
        match self.shape {
            Shape::Area { .. } | Shape::Mesh(_) => PI * PI * self.colour,
            Shape::Point { .. } | Shape::Sphere { .. } => 2.0 * TAU * PI * self.colour,
            Shape::Spot { cone, .. } => PI * cone.solid_angle() * self.colour,
            Shape::Directional { sphere, .. } => {
                PI * PI * sphere.radius * sphere.radius * self.colour
            }
        }
    }

    /// Returns the light as a point at its centre seen from `p`, for hard shadows (the plan's
    /// soft shadows off): a point, spot or directional light itself; an area light's centre
    /// with its cosine falloff; a sphere light's centre with its intensity from afar (the mean
    /// of [`Light::sample`]); a mesh light's area-weighted centroid with the cosine of its mean
    /// normal.
    pub fn centre_sample(&self, p: Vec3A) -> LightSample {
        match &self.shape {
            Shape::Point { .. }
            | Shape::Spot { .. }
            | Shape::Directional { .. }
            | Shape::Area { .. } => self.sample(p, (0.5, 0.5)),
            Shape::Sphere { centre, .. } => LightSample {
                position: *centre,
                intensity: self.colour,
                normal: Vec3A::ZERO,
            },
            Shape::Mesh(m) => LightSample {
                position: m.centroid,
                intensity: self.colour
                    * m.mean_normal
                        .dot((p - m.centroid).normalize_or_zero())
                        .max(0.0),
                normal: Vec3A::ZERO,
            },
        }
    }

    /// Returns a sample of the light for shading point `p`, from a uniform pair `u` in [0, 1)².
    /// A directional light's is where the shadow ray leaves the scene's sphere, with its
    /// irradiance over π as the intensity (its attenuation is 1).
    pub fn sample(&self, p: Vec3A, u: (f32, f32)) -> LightSample {
        match self.shape {
            Shape::Point { position } => LightSample {
                position,
                intensity: self.colour,
                normal: Vec3A::ZERO,
            },
            Shape::Spot {
                position,
                axis,
                cone,
            } => {
                let cos = axis.dot((p - position).normalize_or_zero());
                LightSample {
                    position,
                    intensity: self.colour * cone.falloff(cos),
                    normal: Vec3A::ZERO,
                }
            }
            Shape::Directional { dir, sphere } => LightSample {
                position: sphere.exit(p, -dir),
                intensity: self.colour,
                normal: Vec3A::ZERO,
            },
            Shape::Mesh(ref m) => {
                // Uniform over the total area, as an area light's parallelogram is.
                let (t, u0) = m.choose(u.0);
                let y = t.point((u0, u.1));
                let to_p = (p - y).normalize_or_zero();
                LightSample {
                    position: y,
                    intensity: self.colour * t.normal.dot(to_p).max(0.0),
                    normal: t.normal,
                }
            }
            Shape::Area {
                centre,
                u: eu,
                v: ev,
                normal,
                ..
            } => {
                let y = centre + eu * (u.0 - 0.5) + ev * (u.1 - 0.5);
                let to_p = (p - y).normalize_or_zero();
                LightSample {
                    position: y,
                    intensity: self.colour * normal.dot(to_p).max(0.0),
                    normal,
                }
            }
            Shape::Sphere { centre, radius } => {
                let n = uniform_sphere(u);
                let y = centre + n * radius;
                let to_p = (p - y).normalize_or_zero();
                // Uniform area sampling: I(θ) · 4 (see the module doc) averages to I from afar.
                LightSample {
                    position: y,
                    intensity: self.colour * 4.0 * n.dot(to_p).max(0.0),
                    normal: n,
                }
            }
        }
    }

    /// Returns where `ray` first meets the light's emitting surface within `(tmin, tmax)` and the
    /// radiance it sees there: `I_phys/A` (that is `π·rgb/A`) on the emitting side of an area
    /// light and black on its back, `I_phys/(πR²)` (that is `rgb/R²`) on a sphere light. Point,
    /// spot and directional lights are never seen; a mesh light is seen as an area light is,
    /// `π·rgb/A` on the front of its triangles. The course's falloff does not apply to seen
    /// emitters: only the light they shed on surfaces is attenuated.
    pub fn seen_by(&self, ray: &Ray, tmax: f32) -> Option<(f32, Vec3A)> {
        self.seen(ray, tmax).map(|s| (s.t, s.radiance))
    }

    /// [`Light::seen_by`] with the emitting surface's unit normal where the ray meets it.
    pub fn seen(&self, ray: &Ray, tmax: f32) -> Option<Seen> {
        let (t, radiance, normal) = match self.shape {
            Shape::Point { .. } | Shape::Spot { .. } | Shape::Directional { .. } => return None,
            Shape::Mesh(ref m) => {
                if !m.may_hit(ray, tmax) {
                    return None;
                }
                // The meshes' watertight test: no crack along the edges the triangles share.
                let shear = RayShear::new(ray);
                let mut best: Option<(f32, &EmitterTriangle)> = None;
                for tri in &m.triangles {
                    let [a, b, c] = tri.corners;
                    let limit = best.map_or(tmax, |b| b.0);
                    if let Some(hit) = triangle::intersect(&shear, a, b, c, ray.tmin, limit) {
                        best = Some((hit.t, tri));
                    }
                }
                let (t, tri) = best?;
                let front = ray.dir.dot(tri.normal) < 0.0;
                (
                    t,
                    if front {
                        PI * self.colour / m.area
                    } else {
                        Vec3A::ZERO
                    },
                    tri.normal,
                )
            }
            Shape::Area {
                centre,
                u,
                v,
                normal,
                area,
            } => {
                let denom = ray.dir.dot(normal);
                if denom == 0.0 || area <= 0.0 {
                    return None;
                }
                let t = (centre - ray.origin).dot(normal) / denom;
                let q = ray.at(t) - centre;
                // Coordinates along the edges by the dual basis: |s|, |r| <= 1/2 inside.
                let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
                let det = uu * vv - uv * uv;
                let (qu, qv) = (q.dot(u), q.dot(v));
                let s = (qu * vv - qv * uv) / det;
                let r = (qv * uu - qu * uv) / det;
                if !(s.abs() <= 0.5 && r.abs() <= 0.5) {
                    return None;
                }
                // Arriving at the emitting side means travelling against the normal.
                let front = denom < 0.0;
                (
                    t,
                    if front {
                        PI * self.colour / area
                    } else {
                        Vec3A::ZERO
                    },
                    normal,
                )
            }
            Shape::Sphere { centre, radius } => {
                let oc = ray.origin - centre;
                let a = ray.dir.dot(ray.dir);
                let b = oc.dot(ray.dir);
                let c = oc.dot(oc) - radius * radius;
                let disc = b * b - a * c;
                if disc < 0.0 || radius <= 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                let t0 = (-b - root) / a;
                let t = if t0 > ray.tmin { t0 } else { (-b + root) / a };
                let normal = ((ray.at(t) - centre) / radius).normalize_or_zero();
                (t, self.colour / (radius * radius), normal)
            }
        };
        (t > ray.tmin && t < tmax).then_some(Seen {
            t,
            radiance,
            normal,
        })
    }

    /// Returns whether shading may weigh this light's samples against a BSDF's by multiple
    /// importance sampling ([`crate::integrator::mis`]): a light with extent whose falloff is
    /// physical, so that its shadow-ray estimate and the radiance a path sees on it estimate the
    /// same light (the course's falloff dims only the former).
    pub fn weighs_by_mis(&self) -> bool {
        self.is_area() && self.falloff == [0.0, 0.0, 1.0]
    }

    /// Returns the density per steradian, seen from `from`, with which [`Light::sample`] draws
    /// the point `y` of normal `normal` on the light (uniform over its area, the whole sphere's
    /// for a sphere light): `d² / (A·|cos θ_y|)`; infinite for a point, spot or directional
    /// light, which has no area.
    pub fn density_towards(&self, from: Vec3A, y: Vec3A, normal: Vec3A) -> f32 {
        let area = match &self.shape {
            Shape::Point { .. } | Shape::Spot { .. } | Shape::Directional { .. } => {
                return f32::INFINITY;
            }
            Shape::Area { area, .. } => *area,
            Shape::Mesh(m) => m.area,
            Shape::Sphere { radius, .. } => 2.0 * TAU * radius * radius,
        };
        let to = y - from;
        let d2 = to.length_squared();
        let cos = normal.dot(to).abs() / d2.sqrt();
        d2 / (area * cos)
    }

    /// Returns a photon's emission from four uniform numbers in [0, 1): a spot's in proportion
    /// to its falloff, a directional light's from a point uniform over its disc.
    pub fn emit(&self, u: [f32; 4]) -> Emission {
        match self.shape {
            Shape::Point { position } => Emission {
                origin: position,
                dir: uniform_sphere((u[0], u[1])),
                normal: Vec3A::ZERO,
            },
            Shape::Spot {
                position,
                axis,
                cone,
            } => Emission {
                origin: position,
                dir: cone.sample(axis, (u[0], u[1])),
                normal: Vec3A::ZERO,
            },
            Shape::Directional { dir, sphere } => Emission {
                origin: sphere.disc_point(dir, (u[0], u[1])),
                dir,
                normal: Vec3A::ZERO,
            },
            Shape::Mesh(ref m) => {
                let (t, u0) = m.choose(u[0]);
                Emission {
                    origin: t.point((u0, u[1])),
                    dir: cosine_around(t.normal, (u[2], u[3])),
                    normal: t.normal,
                }
            }
            Shape::Area {
                centre,
                u: eu,
                v: ev,
                normal,
                ..
            } => Emission {
                origin: centre + eu * (u[0] - 0.5) + ev * (u[1] - 0.5),
                dir: cosine_around(normal, (u[2], u[3])),
                normal,
            },
            Shape::Sphere { centre, radius } => {
                let n = uniform_sphere((u[0], u[1]));
                Emission {
                    origin: centre + n * radius,
                    dir: cosine_around(n, (u[2], u[3])),
                    normal: n,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Pass, Rng};

    /// Drawing points uniformly on an area light and dividing by their density towards a
    /// point estimates the solid angle the light subtends: `4·asin(ab/√((a² + d²)(b² + d²)))`
    /// for a `2a × 2b` rectangle seen on its axis from `d`, within 0.5% over 256² stratified
    /// draws.
    #[test]
    fn an_area_lights_density_is_its_solid_angle_measure() {
        let light = area(1.0);
        let p = Vec3A::new(0.0, -0.7, 0.0);
        let n = 256;
        let mut omega = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let u = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let s = light.sample(p, u);
                omega += 1.0 / light.density_towards(p, s.position, s.normal) as f64;
            }
        }
        omega /= (n * n) as f64;
        let (a, b, d) = (0.25f64, 1.0f64, 0.7f64);
        let want = 4.0 * (a * b / ((a * a + d * d) * (b * b + d * d)).sqrt()).asin();
        assert!((omega / want - 1.0).abs() < 0.005, "{omega} against {want}");
    }

    fn area(colour: f32) -> Light {
        Light {
            shape: Shape::Area {
                centre: Vec3A::ZERO,
                u: Vec3A::X * 0.5,
                v: Vec3A::Z * 2.0,
                normal: -Vec3A::Y,
                area: 1.0,
            },
            colour: Vec3A::splat(colour),
            falloff: [0.0, 0.0, 1.0],
            power: None,
            photons: None,
        }
    }

    #[test]
    fn samples_average_to_the_intensity_the_model_defines() {
        let mut rng = Rng::new(1, Pass::Pixel, 0);
        let n = 200_000;
        // Area light seen from straight below at distance 1000: I·cos 0 = I.
        let l = area(2.0);
        let p = Vec3A::new(0.0, -1000.0, 0.0);
        let mean: Vec3A = (0..n)
            .map(|_| l.sample(p, (rng.next_f32(), rng.next_f32())).intensity)
            .sum::<Vec3A>()
            / n as f32;
        assert!((mean.x - 2.0).abs() < 0.01, "{mean}");
        // From 60° off the normal: I·cos 60°.
        let p = Vec3A::new(
            1000.0 * 60f32.to_radians().sin(),
            -1000.0 * 60f32.to_radians().cos(),
            0.0,
        );
        let mean: Vec3A = (0..n)
            .map(|_| l.sample(p, (rng.next_f32(), rng.next_f32())).intensity)
            .sum::<Vec3A>()
            / n as f32;
        assert!((mean.x - 1.0).abs() < 0.01, "{mean}");
        // Behind the one-sided light: nothing.
        assert_eq!(
            l.sample(Vec3A::new(0.0, 5.0, 0.0), (0.3, 0.6)).intensity,
            Vec3A::ZERO
        );
        // A sphere light from afar is a point light of intensity I.
        let s = Light {
            shape: Shape::Sphere {
                centre: Vec3A::ZERO,
                radius: 0.5,
            },
            ..area(3.0)
        };
        let p = Vec3A::new(0.0, 0.0, 1e4);
        let mean: Vec3A = (0..n)
            .map(|_| s.sample(p, (rng.next_f32(), rng.next_f32())).intensity)
            .sum::<Vec3A>()
            / n as f32;
        assert!((mean.x - 3.0).abs() < 0.03, "{mean}");
    }

    /// A unit square at height 1 facing down, as two triangles, of radiance `l`.
    fn square(l: f32) -> Light {
        let (a, b, c, d) = (
            Vec3A::new(-0.5, 1.0, -0.5),
            Vec3A::new(0.5, 1.0, -0.5),
            Vec3A::new(0.5, 1.0, 0.5),
            Vec3A::new(-0.5, 1.0, 0.5),
        );
        // Counter-clockwise seen from below: the normal points down.
        let tris = vec![EmitterTriangle::new(a, b, c), EmitterTriangle::new(a, c, d)];
        Light::mesh(tris, Vec3A::splat(l)).unwrap()
    }

    #[test]
    fn a_mesh_light_is_the_area_light_of_its_shape_and_radiance() {
        let mesh = square(3.0);
        assert_eq!(mesh.colour, Vec3A::splat(3.0 / PI));
        let Shape::Mesh(m) = &mesh.shape else {
            unreachable!()
        };
        assert_eq!(m.triangles[0].normal, -Vec3A::Y);
        assert_eq!((m.area, m.cdf.clone()), (1.0, vec![0.5, 1.0]));
        // The area light of the same square and rgb (L·A/π): the same flux, the same mean
        // intensity seen from any point, in closed form for the area light.
        let area = Light {
            shape: Shape::Area {
                centre: Vec3A::Y,
                u: Vec3A::X,
                v: Vec3A::Z,
                normal: -Vec3A::Y,
                area: 1.0,
            },
            ..mesh.clone()
        };
        assert_eq!(mesh.flux(), area.flux());
        let mut rng = Rng::new(3, Pass::Pixel, 0);
        let n = 200_000;
        for p in [
            Vec3A::ZERO,
            Vec3A::new(2.0, -1.0, 0.3),
            Vec3A::new(0.1, 0.2, 0.0),
        ] {
            let mut sum = 0.0f64;
            let mut sum_area = 0.0f64;
            for _ in 0..n {
                let u = (rng.next_f32(), rng.next_f32());
                let s = mesh.sample(p, u);
                let d2 = (s.position - p).length_squared();
                let cos = (s.position - p).normalize().y.max(0.0);
                sum += f64::from(s.intensity.x * cos / d2);
                let s = area.sample(p, u);
                let d2 = (s.position - p).length_squared();
                let cos = (s.position - p).normalize().y.max(0.0);
                sum_area += f64::from(s.intensity.x * cos / d2);
            }
            // The same uniform density over the square: irradiances agree to their noise.
            let (e, e_area) = (sum / n as f64, sum_area / n as f64);
            assert!(
                (e - e_area).abs() < 0.01 * e_area,
                "{p}: {e} against {e_area}"
            );
        }
        // Seen from below: the radiance L; from above: black, and it still stops the ray.
        let up = Ray::new(Vec3A::new(0.2, 0.0, 0.1), Vec3A::Y);
        assert_eq!(mesh.seen_by(&up, 10.0), Some((1.0, Vec3A::splat(3.0))));
        assert_eq!(area.seen_by(&up, 10.0), Some((1.0, Vec3A::splat(3.0))));
        let down = Ray::new(Vec3A::new(0.2, 2.0, 0.1), -Vec3A::Y);
        assert_eq!(mesh.seen_by(&down, 10.0), Some((1.0, Vec3A::ZERO)));
        // On the diagonal the two triangles share: no crack.
        let diagonal = Ray::new(Vec3A::new(0.2, 0.0, 0.2), Vec3A::Y);
        assert_eq!(
            mesh.seen_by(&diagonal, 10.0),
            Some((1.0, Vec3A::splat(3.0)))
        );
        let beside = Ray::new(Vec3A::new(0.7, 0.0, 0.1), Vec3A::Y);
        assert_eq!(mesh.seen_by(&beside, 10.0), None);
        assert_eq!(mesh.seen_by(&up, 0.9), None);
        // Photons leave from the square, downwards, cosine-distributed: E[cos] = 2/3.
        let mut cos = 0.0;
        for _ in 0..n {
            let u = [
                rng.next_f32(),
                rng.next_f32(),
                rng.next_f32(),
                rng.next_f32(),
            ];
            let e = mesh.emit(u);
            assert!(e.origin.x.abs() <= 0.5 + 1e-6 && e.origin.z.abs() <= 0.5 + 1e-6);
            assert_eq!((e.origin.y, e.normal), (1.0, -Vec3A::Y));
            cos += -e.dir.y;
        }
        assert!((cos / n as f32 - 2.0 / 3.0).abs() < 0.005);
    }

    #[test]
    fn a_mesh_light_chooses_triangles_in_proportion_to_area() {
        // Areas 1 and 3: a quarter of the samples on the first.
        let small = EmitterTriangle::new(Vec3A::ZERO, Vec3A::X * 2.0, Vec3A::Z);
        let large =
            EmitterTriangle::new(Vec3A::X * 10.0, Vec3A::X * 12.0, Vec3A::new(10.0, 0.0, 3.0));
        let light = Light::mesh(vec![small, large], Vec3A::ONE).unwrap();
        let mut rng = Rng::new(5, Pass::Pixel, 0);
        let n = 100_000;
        let first = (0..n)
            .filter(|_| {
                let s = light.sample(Vec3A::Y, (rng.next_f32(), rng.next_f32()));
                s.position.x < 5.0
            })
            .count();
        assert!((first as f32 / n as f32 - 0.25).abs() < 0.005, "{first}");
        // Degenerate triangles alone emit nothing: no light.
        let flat = EmitterTriangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::X * 2.0);
        assert!(Light::mesh(vec![flat], Vec3A::ONE).is_none());
    }

    #[test]
    fn falloff_ratio_makes_photons_agree_with_direct_light() {
        let l = Light::point(Vec3A::ZERO, Vec3A::ONE, [1.0, 0.5, 0.25]);
        for d in [0.1f32, 1.0, 7.0] {
            // Photon irradiance Φ/(4π d²)·g(d) equals π·I/(c0 + c1 d + c2 d²) for rgb I = 1, whose
            // Lambertian radiance kd·E/π is the course's kd·I·att(d).
            let photon = l.flux().x / (4.0 * PI * d * d) * l.falloff_ratio(d);
            assert!((photon - PI * l.attenuation(d)).abs() < 1e-5 * l.attenuation(d).max(1.0));
        }
        assert_eq!(area(1.0).flux(), Vec3A::splat(PI * PI));
    }
}
