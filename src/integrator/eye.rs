//! The eye path both integrators share: what one eye ray sees, by the course's deterministic
//! splitting (Whitted 1980), with the diffuse indirect term left to the integrator
//! ([`DiffuseTerm`]).
//!
//! At each hit the [`Bsdf`] (built once, [`Scene::interaction`]) weights:
//! - with `1 − t`, the opaque part: direct light from every light by shadow rays
//!   `Σ att(d)·I(θ)·(kd·max(0, n·l) + ks·max(0, r·v)^p)` (area and sphere lights averaged over
//!   `light_samples` stratified samples: soft shadows), the diffuse indirect term, and `ks` times
//!   the mirror-reflected radiance;
//! - with `t`, the dielectric interface: `F` times the reflected and `1 − F` times the refracted
//!   radiance, between the media on either side, the latter scaled by `(n_from/n_to)²` (radiance
//!   under water is n² times brighter than the same light seen from air).
//!
//! Area and sphere lights are seen by camera rays and by the specular paths that follow them
//! ([`nearest_emitter`]): their direct light on surfaces comes from shadow rays, so seeing them
//! only along eye paths counts nothing twice. Point lights stay invisible, as in the course.
//! A rough dielectric (frosted glass) does both: it samples the lights and follows its drawn
//! directions, and multiple importance sampling weighs the two ([`super::mis`]).
//!
//! Rays carry a [`MediumStack`], so nested and touching dielectrics refract with the ratio of the
//! two media at each interface, and the boundary of a solid inside a denser one (a water surface
//! inside a glass ball) is passed through untouched. Paths split deterministically for
//! [`MAX_DEPTH`] bounces, and stop sooner when their weight falls below [`MIN_WEIGHT`]. Deeper,
//! a path goes on by Russian roulette (pbrt-v4's path tracer): one lobe, chosen in proportion
//! to its weight, which survives with probability `q = min(1, weight)` and is then divided by
//! `q`, so the estimate stays unbiased (nested glass shells, a ray bouncing between mirrors).
//! There a mirror brighter than white (`ks` above 1 in a channel) is followed at `ks` over its
//! largest channel, so no bounce of the roulette adds weight (`crate::range`'s note): the
//! deterministic splitting keeps the course's `ks`.
//! [`MAX_PATH_DEPTH`] is a hard safety cap; paths stopped there are counted
//! ([`RayCounts::depth_capped`]) and reported by `--stats`.
//!
//! A split branch that leaves the path under [`WEAK_BRANCH`] of its sample (a Fresnel
//! reflection off water, a glossy tile's 4% mirror) is followed by one of every four samples of
//! the pixel, at four times its weight, and skipped by the others ([`Share`]): unbiased, and on
//! the final scene it removes 41% of the diffuse points, their caustic lookups and shadow rays,
//! for a few percent of the light.

use super::irradiance_cache::Probe;
use super::mis::Mis;
use super::photon_map::Prepass;
use crate::accel::counters::{self, RayKind};
use crate::camera::Camera;
use crate::geometry::{Ray, offset_ray_origin};
use crate::light::{Light, Seen};
use crate::material::bsdf::{Bsdf, Split};
use crate::material::medium::{Crossing, MediumStack};
use crate::render::{Radiance, Share, WEAK_BRANCH};
use crate::sampling::{Rng, stratified_2d};
use crate::scene::Scene;
use crate::scene::interaction::{Interaction, Needs};
use crate::stats::RayCounts;
use glam::Vec3A;

pub use crate::scene::MAX_DEPTH;
/// Deepest chain followed at all, even under roulette (a closed box of perfect mirrors never
/// loses weight).
pub const MAX_PATH_DEPTH: u32 = 1024;
/// How far behind the surface a ray meets (relative to its distance) a light still counts as
/// seen: a glTF emissive surface is both a surface and a light over the same triangles, met at
/// the same distance to within rounding, and the light must win.
pub const EMITTER_ON_SURFACE: f32 = 1e-4;
/// Paths whose weight falls below this are not traced further.
pub const MIN_WEIGHT: f32 = 1e-3;

/// A surface point an eye path shades: the interaction there (the surface and its BSDF) and
/// the state of the path that reached it. The shading functions of every integrator take it
/// rather than the point, the BSDF and the path state one by one.
#[derive(Clone, Copy)]
pub struct ShadingPoint<'a> {
    pub it: &'a Interaction<'a>,
    pub state: PathState,
}

impl ShadingPoint<'_> {
    /// Returns the point's world-space position.
    pub fn p(&self) -> Vec3A {
        self.it.surf.p
    }

    /// Returns the BSDF at the point.
    pub fn bsdf(&self) -> &Bsdf<'_> {
        &self.it.bsdf
    }
}

/// Where an eye path stands: how deep, how much it still matters, which medium it is in.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub depth: u32,
    /// Largest channel of the product of weights so far.
    pub weight: f32,
    pub media: MediumStack,
    /// Whether an area or sphere light met along the ray shows its radiance: true for camera
    /// rays and specular paths from them, false after a reflection whose Phong highlight
    /// already stands for the lights' reflection.
    pub sees_emitters: bool,
    /// How this sample shares weak branches with the other samples of its pixel.
    pub share: Share,
    /// Set on a path drawn from a rough interface that also sampled the lights: how to weigh
    /// the light it meets against those samples ([`Mis`]).
    pub mis: Option<Mis>,
}

impl PathState {
    /// Returns the state of a camera ray of `scene` (in the camera's media).
    pub fn camera(scene: &Scene) -> PathState {
        PathState::camera_sample(scene, Share::All)
    }

    /// Returns the state of a camera ray of `scene` (in the camera's media,
    /// [`Scene::eye_media`]) of a sample that shares weak branches by `share`.
    pub fn camera_sample(scene: &Scene, share: Share) -> PathState {
        PathState {
            depth: 0,
            weight: 1.0,
            media: scene.eye_media.stack,
            sees_emitters: true,
            share,
            mis: None,
        }
    }

    /// Returns the factor on the radiance of a deterministically split branch of relative
    /// weight `weight`, and the branch's share. A branch that makes the path weak
    /// ([`WEAK_BRANCH`]) shades its surface in one sample of the pixel in
    /// [`WEAK_SHARERS`](crate::render::WEAK_SHARERS), at that many times its weight, and only
    /// counts the emitters it sees in the others ([`Share`]); below it, every branch is followed.
    fn branch(&self, weight: f32) -> (f32, Share) {
        if self.weight * weight >= WEAK_BRANCH {
            return (1.0, self.share);
        }
        match self.share {
            Share::Carry(n) => (n, Share::Surfaces(n)),
            Share::Skip => (1.0, Share::Emitters),
            Share::All | Share::Surfaces(_) | Share::Emitters => (1.0, Share::All),
        }
    }

    /// Returns whether the path still splits deterministically over lobes (else: roulette), for
    /// a scene whose plan splits `depth` specular bounces deep.
    fn splits(&self, depth: u32) -> bool {
        self.depth < depth
    }

    /// Decides by Russian roulette whether a path beyond [`MAX_DEPTH`] goes on into a child of
    /// relative weight `weight`: returns the survival probability `q` (the child's radiance is
    /// divided by it), or `None` when the path ends here.
    fn roulette(&self, weight: f32, rng: &mut Rng, counts: &mut RayCounts) -> Option<f32> {
        if self.depth >= MAX_PATH_DEPTH {
            counts.depth_capped += 1;
            return None;
        }
        let q = (self.weight * weight).min(1.0);
        (q > 0.0 && rng.next_f32() < q).then_some(q)
    }

    fn child(&self, weight: f32, media: MediumStack) -> PathState {
        PathState {
            depth: self.depth + 1,
            weight: self.weight * weight,
            media,
            sees_emitters: self.sees_emitters,
            share: self.share,
            mis: None,
        }
    }

    /// Returns this state with `share`.
    fn shared(self, share: Share) -> PathState {
        PathState { share, ..self }
    }
}

/// Returns the background seen along `dir`: a vertical gradient in the camera's frame, so objects
/// stand out against it wherever they are.
pub fn background(camera: &Camera, dir: Vec3A) -> Vec3A {
    let s = (0.5 * (dir.normalize().dot(camera.v) + 1.0)).clamp(0.0, 1.0);
    let bottom = Vec3A::new(0.02, 0.02, 0.08);
    let top = Vec3A::new(0.30, 0.42, 0.75);
    bottom + (top - bottom) * s
}

/// Returns the nearest light `ray` meets before `tmax` and where ([`Light::seen`]).
pub fn nearest_emitter<'s>(scene: &'s Scene, ray: &Ray, tmax: f32) -> Option<(&'s Light, Seen)> {
    let mut best: Option<(&Light, Seen)> = None;
    for light in &scene.lights {
        let limit = best.map_or(tmax, |b| b.1.t);
        if let Some(seen) = light.seen(ray, limit) {
            best = Some((light, seen));
        }
    }
    best
}

/// What a diffuse surface receives besides direct light: the integrator's part of the eye path.
#[derive(Clone, Copy, Debug)]
pub enum DiffuseTerm<'a> {
    /// The course's ambient term `ambient·kd` (Whitted).
    Ambient(Vec3A),
    /// Caustics and indirect light from photon maps (Jensen).
    Photons(&'a Prepass),
    /// [`DiffuseTerm::Photons`] with the cache's interpolation error taken out where it serves,
    /// one record at a time, drawn with the salt ([`Prepass::diffuse_with`]): the planner's
    /// pilot.
    Unbiased(&'a Prepass, u64),
    /// The caustic map's estimate alone, from the `k` nearest photons
    /// ([`Prepass::caustic_diffuse`]): the planner's pilot.
    Caustic(&'a Prepass, usize),
    /// No light: the irradiance cache's record pass, which only follows the eye paths to find
    /// where final gathering happens ([`super::irradiance_cache`]).
    Caching(&'a Probe<'a>),
}

/// Everything an eye path needs besides the ray.
#[derive(Clone, Copy)]
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// Shadow-ray samples per area or sphere light at each shaded point (0: no direct light,
    /// for passes that only follow eye paths).
    pub light_samples: u32,
    pub diffuse: DiffuseTerm<'a>,
}

impl Radiance for Tracer<'_> {
    fn radiance(&self, ray: &Ray, share: Share, rng: &mut Rng, counts: &mut RayCounts) -> Vec3A {
        self.radiance(
            ray,
            PathState::camera_sample(self.scene, share),
            rng,
            counts,
        )
    }
}

impl Tracer<'_> {
    /// Returns the radiance arriving along `ray` (towards its origin).
    pub fn radiance(
        &self,
        ray: &Ray,
        state: PathState,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let (mut ray, mut state, mut scale) = (*ray, state, Vec3A::ONE);
        // A weak branch of the sample that shades it: what it sees before a surface counts once
        // over the pixel's samples, as in those that do not shade it (see `Share`).
        let seen_scale = match state.share {
            Share::Surfaces(n) => 1.0 / n,
            _ => 1.0,
        };
        // A loop, not recursion, across false interfaces: a hundred nested shells of index 1
        // must not take a hundred stack frames.
        loop {
            counters::kind(RayKind::Camera);
            let hit = self.scene.intersect(&ray);
            // What the medium the ray crosses keeps of the light over `t` (Beer–Lambert).
            let kept = |t: f32| self.scene.kept_along(&state.media, &ray, t);
            if state.sees_emitters {
                let tmax = hit.map_or(ray.tmax, |h| h.t * (1.0 + EMITTER_ON_SURFACE));
                if let Some((light, seen)) = nearest_emitter(self.scene, &ray, tmax) {
                    if state.depth == 0 {
                        crate::render::scope::light_seen();
                    }
                    let w = state.mis.map_or(1.0, |m| m.weight(light, &ray, &seen));
                    return w * seen_scale * scale * kept(seen.t) * seen.radiance;
                }
            }
            let Some(hit) = hit else {
                let kept = kept(f32::INFINITY);
                return seen_scale * scale * kept * background(self.camera, ray.dir);
            };
            scale *= kept(hit.t);
            let skip = state.share == Share::Emitters;
            // Only a transparent surface can be a false interface to see through.
            let mat = &self.scene.materials[hit.material as usize];
            if skip && mat.transparency <= 0.0 {
                counts.weak_skipped += 1;
                return Vec3A::ZERO;
            }
            let (needs, clock) = if skip {
                (Needs::Albedo, None)
            } else {
                (
                    Needs::Full,
                    counts.timing.then_some(&mut counts.material_nanos),
                )
            };
            let it = self.scene.interaction(&ray, &hit, needs, clock);
            let crossing = it.bsdf.crossing(&state.media);
            if let Some(c) = crossing.as_ref().filter(|c| c.is_false()) {
                // The boundary of a solid inside a denser one: no surface here, go straight on.
                let q = if state.splits(self.scene.features.specular_depth) {
                    1.0
                } else {
                    match state.roulette(1.0, rng, counts) {
                        Some(q) => q,
                        None => return Vec3A::ZERO,
                    }
                };
                ray = Ray::new(offset_ray_origin(it.surf.p, it.surf.ng, ray.dir), ray.dir);
                counts.secondary += 1;
                // Straight on: a drawn path still weighs the light it meets from its vertex.
                state = PathState {
                    mis: state.mis,
                    ..state.child(1.0 / q, c.after)
                };
                scale /= q;
                continue;
            }
            if skip {
                counts.weak_skipped += 1;
                return Vec3A::ZERO;
            }
            // The surface a carried weak branch reaches: shaded in full, every branch below.
            if let Share::Surfaces(_) = state.share {
                state.share = Share::All;
            }
            let t = it.bsdf.material.transparency;
            let at = ShadingPoint { it: &it, state };
            let mut out = Vec3A::ZERO;
            if let Some(crossing) = &crossing {
                out += t * self.dielectric(at, crossing, rng, counts);
            }
            if t < 1.0 {
                out += (1.0 - t) * self.opaque(at, rng, counts);
            }
            return scale * out;
        }
    }

    /// Returns the direct light from every light at the surface of `bsdf` (at `p`, in `media`)
    /// towards its `wo`, by shadow rays. A shadow ray meets no surface, so it crosses only the
    /// point's own medium, which absorbs along it.
    pub fn direct(
        &self,
        p: Vec3A,
        bsdf: &Bsdf,
        media: &MediumStack,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let (n, ng) = (bsdf.n, bsdf.ng);
        let mut colour = Vec3A::ZERO;
        if self.light_samples == 0 {
            return colour;
        }
        for light in &self.scene.lights {
            let soft = light.is_area() && self.scene.features.soft_shadows;
            let samples = if soft {
                stratified_2d(rng, self.light_samples)
            } else {
                vec![(0.5, 0.5)]
            };
            let mut sum = Vec3A::ZERO;
            for &u in &samples {
                let ls = if soft {
                    light.sample(p, u)
                } else {
                    light.centre_sample(p)
                };
                let to_light = ls.position - p;
                let d = to_light.length();
                if d == 0.0 || ls.intensity == Vec3A::ZERO {
                    continue;
                }
                let wi = to_light / d;
                if n.dot(wi) <= 0.0 || ng.dot(wi) <= 0.0 {
                    continue;
                }
                if !self.sees_light(p, ng, wi, ls.position, counts) {
                    continue;
                }
                let kept = self.scene.transmittance(media, d);
                sum += kept * ls.intensity * light.attenuation(d) * bsdf.phong(wi);
            }
            colour += sum / samples.len() as f32;
        }
        colour
    }

    /// Returns whether the point `y` of a light is in sight of the surface point `p` (geometric
    /// normal `ng`) along the unit direction `wi` towards it, by one shadow ray.
    pub fn sees_light(
        &self,
        p: Vec3A,
        ng: Vec3A,
        wi: Vec3A,
        y: Vec3A,
        counts: &mut RayCounts,
    ) -> bool {
        let origin = offset_ray_origin(p, ng, wi);
        let shadow = Ray::new(origin, y - origin).with_tmax(1.0 - 1e-4);
        counts.shadow += 1;
        counters::kind(RayKind::Shadow);
        !self.scene.occluded(&shadow)
    }

    /// Returns the light the opaque part of a surface sends towards its `wo`.
    fn opaque(&self, at: ShadingPoint, rng: &mut Rng, counts: &mut RayCounts) -> Vec3A {
        let (p, bsdf, state) = (at.p(), at.bsdf(), at.state);
        let mat = bsdf.material;
        // At an opaque surface inside a transparent solid, with every light outside all of
        // them, every shadow ray would meet the solid's boundary: no light arrives directly.
        // A partly transparent surface is that boundary itself, not inside it: it keeps its rays.
        let inside = !state.media.is_air() && mat.transparency <= 0.0;
        let mut colour = if !inside || !self.scene.lights_clear_of_media {
            self.direct(p, bsdf, &state.media, rng, counts)
        } else {
            Vec3A::ZERO
        };
        match self.diffuse {
            DiffuseTerm::Ambient(ambient) => colour += ambient * bsdf.kd,
            DiffuseTerm::Photons(gi) => {
                if bsdf.kd.max_element() > 0.0 {
                    colour += gi.diffuse(self.scene, &at, rng, counts);
                }
            }
            DiffuseTerm::Unbiased(gi, salt) => {
                if bsdf.kd.max_element() > 0.0 {
                    colour += gi.diffuse_with(self.scene, &at, rng, Some(salt), counts);
                }
            }
            DiffuseTerm::Caustic(gi, k) => {
                if bsdf.kd.max_element() > 0.0 {
                    colour += gi.caustic_diffuse(&at, k, counts);
                }
            }
            DiffuseTerm::Caching(probe) => {
                if bsdf.kd.max_element() > 0.0 {
                    probe.visit(self.scene, &at, rng, counts);
                }
            }
        }
        // The mirror colour at this hit: the material's, or its glTF textures'.
        if bsdf.ks.max_element() <= 0.0 {
            return colour;
        }
        let splits = state.splits(self.scene.features.specular_depth);
        // Beyond the splitting depth a mirror brighter than white (ks above 1) is followed at
        // ks over its largest channel: a closed box of such mirrors keeps the path's weight
        // over its thousand bounces instead of multiplying it by ks at each.
        let ks = match bsdf.ks.max_element() {
            largest if !splits && largest > 1.0 => bsdf.ks / largest,
            _ => bsdf.ks,
        };
        let weight = ks.max_element();
        let (q, gain, share) = if splits {
            let (gain, share) = state.branch(weight);
            (
                (state.weight * weight > MIN_WEIGHT).then_some(1.0),
                gain,
                share,
            )
        } else {
            (state.roulette(weight, rng, counts), 1.0, state.share)
        };
        // A rough material's mirror lobe is a rough conductor: one direction drawn from it.
        let drawn = q.and_then(|q| Some((q, bsdf.mirror_sample(bsdf.glossy_numbers(rng))?)));
        if let Some((q, (wr, glossy))) = drawn {
            let ray = Ray::new(offset_ray_origin(p, bsdf.ng, wr), wr);
            counts.secondary += 1;
            let mut child = state.child(weight * glossy / q, state.media).shared(share);
            // A Phong highlight (or a rough lobe, which `direct` evaluates for every light)
            // already reflects the lights; the mirror image would count them twice.
            child.sees_emitters &= mat.shininess <= 0.0 && bsdf.roughness <= 0.0;
            colour += gain * ks / q * glossy * self.radiance(&ray, child, rng, counts);
        }
        colour
    }

    /// Returns the light a dielectric interface sends towards its `wo`: Fresnel-weighted
    /// reflection and refraction between the media on either side of `crossing`.
    fn dielectric(
        &self,
        at: ShadingPoint,
        crossing: &Crossing,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let (p, ng, state) = (at.p(), at.bsdf().ng, at.state);
        let split = at
            .bsdf()
            .dielectric(crossing, at.bsdf().glossy_numbers(rng));
        let f = split.f;
        if !state.splits(self.scene.features.specular_depth) {
            return self.dielectric_lobe(at, crossing, &split, rng, counts);
        }
        // A rough interface also samples the lights, weighed against its branches' draws.
        let mut out = self.rough_interface_direct(&at, crossing, true, rng, counts);
        // A rough interface's branches carry the microfacets' G2/G1 (1 when smooth).
        let (wr_weight, wt_weight) = (split.reflect_weight, split.refract_weight);
        if f > 0.0 && wr_weight > 0.0 && state.weight * f * wr_weight > MIN_WEIGHT {
            let (gain, share) = state.branch(f * wr_weight);
            let wr = split.reflected;
            let ray = Ray::new(offset_ray_origin(p, ng, wr), wr);
            counts.secondary += 1;
            let child = PathState {
                mis: self.drawn_from(&at, crossing, wr, true),
                ..state.child(f * wr_weight, state.media).shared(share)
            };
            out += gain * f * self.radiance(&ray, child, rng, counts) * wr_weight;
        }
        if f < 1.0
            && wt_weight > 0.0
            && state.weight * (1.0 - f) * wt_weight > MIN_WEIGHT
            && let Some(wt) = split.refracted
        {
            let (gain, share) = state.branch((1.0 - f) * wt_weight);
            let ray = Ray::new(offset_ray_origin(p, ng, wt), wt);
            counts.secondary += 1;
            let child = PathState {
                mis: self.drawn_from(&at, crossing, wt, true),
                ..state
                    .child((1.0 - f) * wt_weight, crossing.after)
                    .shared(share)
            };
            let radiance = self.radiance(&ray, child, rng, counts);
            out += gain * (1.0 - f) * split.radiance_scale * radiance * wt_weight;
        }
        out
    }

    /// Returns [`Tracer::dielectric`]'s estimate beyond [`MAX_DEPTH`]: one lobe, reflection
    /// with probability `F` (always when nothing refracts), then Russian roulette.
    fn dielectric_lobe(
        &self,
        at: ShadingPoint,
        crossing: &Crossing,
        split: &Split,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let (it, state) = (at.it, at.state);
        let p_reflect = if split.refracted.is_some() {
            split.f
        } else {
            1.0
        };
        let (dir, weight, media, radiance_scale) = match split.refracted {
            Some(wt) if rng.next_f32() >= p_reflect => (
                wt,
                (1.0 - split.f) / (1.0 - p_reflect) * split.refract_weight,
                crossing.after,
                split.radiance_scale,
            ),
            _ => (
                split.reflected,
                split.f / p_reflect * split.reflect_weight,
                state.media,
                1.0,
            ),
        };
        let direct = self.rough_interface_direct(&at, crossing, false, rng, counts);
        let Some(q) = state.roulette(weight, rng, counts) else {
            return direct;
        };
        let ray = Ray::new(offset_ray_origin(it.surf.p, it.bsdf.ng, dir), dir);
        counts.secondary += 1;
        let child = PathState {
            mis: self.drawn_from(&at, crossing, dir, false),
            ..state.child(weight / q, media)
        };
        let radiance = self.radiance(&ray, child, rng, counts);
        direct + weight * radiance_scale / q * radiance
    }
}
