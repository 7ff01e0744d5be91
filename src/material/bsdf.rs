//! The one scattering model: a [`Bsdf`] built once per hit, used by eye rays, final-gather rays
//! and photons alike, so the light and eye paths cannot disagree about a material.
//!
//! # What a surface does
//! A material `(kd, ks, p, t, ior)` mixes two surfaces ([`Lobes`]):
//! - with weight `1 − t`, an opaque one: a Lambertian lobe of reflectance `kd` (the texture's
//!   colour where there is one), a mirror lobe of weight `ks`, and, for light arriving straight
//!   from a light, the course's Phong highlight `ks·(r·v)^p` ([`Bsdf::phong`]);
//! - with weight `t`, a smooth dielectric interface between the media on either side
//!   ([`Bsdf::crossing`]): Fresnel reflectance `F` reflects, `1 − F` refracts
//!   ([`Bsdf::dielectric`]). Radiance refracted from index `n_to` into `n_from` (wo's side) is
//!   scaled by `(n_from/n_to)²`; flux (photons) is not.
//!
//! # Conventions
//! - Directions point away from the surface: `wo` towards where the ray came from, `wi` towards
//!   the light.
//! - [`Bsdf::n`] and [`Bsdf::ng`] are the shading and geometric normals turned to `wo`'s side, so
//!   both sides of a surface shade alike; [`Bsdf::front`] says whether `wo` is on the side the
//!   shape's normal points to (outside a solid).
//! - Building the BSDF applies what varies over the surface: the texture replaces `kd` (glTF's
//!   textures give `kd`, `ks` and the roughness, [`Material::reflectance`]), and the bump map
//!   and Perlin noise bend the shading normal ([`Material::shading_normal`]). Everything after
//!   reads [`Bsdf::kd`], [`Bsdf::ks`] and [`Bsdf::roughness`], never the material's fields.
//! - Mirror and dielectric lobes are deltas: they report directions, not densities.
//!
//! # Sampling
//! Eye rays split deterministically (they weight every lobe, as the course's ray tracer does);
//! photons choose one lobe by Russian roulette on the lobe weights ([`Bsdf::sample`]), with their
//! power divided by the choice's probability, so each estimate stays unbiased.
//!
//! A photon takes each lobe with probability its largest channel (the three divided by their
//! sum `S` where it exceeds 1); what is left is absorption ([`Choice`]).
//! - At a surface that reflects at most what it receives (its total `(kd + ks)·(1 − t) + t`,
//!   [`Lobes::total`], at most 1 in every channel) the chosen lobe is divided by its
//!   probability: unbiased, and no channel gains on average.
//! - At a surface that reflects more (`kd = 1.5`, warned about at the script line), unbiased
//!   photons would gain power at every bounce: `1.5ⁿ` over the up to
//!   [`MAX_BOUNCES`](crate::photon::trace::MAX_BOUNCES) of a closed room, until they overflow.
//!   There the lobes are scaled to sum 1 for the weight as well as for the choice, so the weight
//!   is the lobe over its largest channel, at most 1 in every channel: a photon's power never
//!   grows at the bounce, and a `kd = 1.5` room carries the photons of a `kd = 1` one. The sum
//!   `S` equals the total when the lobes peak in the same channel (grey highlights); where they
//!   peak in different ones (a red diffuse lobe, a blue mirror) `S` is larger and the scaled
//!   surface reflects less than 1 in every channel.

use super::medium::{Crossing, MediumStack};
use super::microfacet::{Frame, Ggx, RoughConductor, RoughDielectric};
use super::pbr::Reflectance;
use super::{Lobes, Material, fresnel};
use crate::geometry::hit::SurfaceHit;
use crate::range::MAX_ALBEDO;
use crate::sampling::Rng;
use crate::sampling::cosine_around;
use glam::Vec3A;

/// The scattering at one surface point, for one outgoing direction.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'a> {
    pub material: &'a Material,
    /// The material's index in the scene (what [`MediumStack`] records).
    pub material_id: u32,
    /// Diffuse reflectance at the hit (the texture's colour, or `kd`), before the `1 − t` weight.
    pub kd: Vec3A,
    /// Mirror colour at the hit (the material's `ks`, or its glTF textures'), before the
    /// `1 − t` weight.
    pub ks: Vec3A,
    /// GGX roughness at the hit (the material's, or its glTF textures'): 0 is a smooth mirror
    /// and a smooth interface.
    pub roughness: f32,
    /// Unit direction towards where the ray came from.
    pub wo: Vec3A,
    /// Whether `wo` lies on the side the shape's geometric normal points to.
    pub front: bool,
    /// Unit shading normal (bent by bump map and noise), on `wo`'s side.
    pub n: Vec3A,
    /// Unit geometric normal, on `wo`'s side.
    pub ng: Vec3A,
    /// Another transparent solid's surface at the same place (glass resting on water), crossed
    /// together with this one ([`Bsdf::crossing`]); set by `Scene::interaction`.
    pub touching: Option<Touching>,
}

/// The surface of a second transparent solid that touches the one hit, within rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touching {
    /// The solid's material index in the scene.
    pub material_id: u32,
    pub ior: f32,
    /// Whether the ray goes into that solid (against its outward normal).
    pub entering: bool,
}

/// Where one sampled photon goes next ([`Bsdf::sample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Unit direction of travel.
    pub dir: Vec3A,
    /// What the path's power is multiplied by (the lobe's weight over its probability).
    pub weight: Vec3A,
    /// The lobe chosen.
    pub lobe: Lobe,
    /// The media beyond the surface when the path refracted into them.
    pub media: Option<MediumStack>,
    /// What radiance (not flux) is multiplied by on the way: `(n_from/n_to)²` where the path
    /// refracted (radiance is compressed into a denser medium's narrower cone), else 1.
    /// Photons carry flux and ignore it.
    pub radiance_scale: f32,
}

/// The lobes a path can scatter by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    Diffuse,
    Mirror,
    /// Fresnel reflection or refraction at a dielectric interface.
    Dielectric,
}

/// The two directions a dielectric interface splits a ray into ([`Bsdf::dielectric`]): about
/// the shading normal for a smooth one, about one visible micro-normal for a rough one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Fresnel reflectance: the reflected share (1 under total internal reflection).
    pub f: f32,
    /// The mirror direction.
    pub reflected: Vec3A,
    /// The refracted direction, `None` under total internal reflection or when a bent shading
    /// normal would send it back out.
    pub refracted: Option<Vec3A>,
    /// `(n_from/n_to)²`: what the radiance arriving along the refracted direction is multiplied
    /// by when it crosses to `wo`'s side (pbrt-v4's radiance-mode BTDF scaling, Veach 1997
    /// §5.2). Light entering a denser medium is squeezed into a narrower cone, so radiance under
    /// water is n² times what it was in air; seen from above it is divided by n² again.
    pub radiance_scale: f32,
    /// What the reflected branch's weight `F` is multiplied by: 1 for a smooth interface; for
    /// a rough one the microfacets' `G2/G1(wo)` (0 where the direction leaves below).
    pub reflect_weight: f32,
    /// The same for the refracted branch's `1 − F`.
    pub refract_weight: f32,
}

impl<'a> Bsdf<'a> {
    /// Returns the BSDF of `material` at `surf` seen from `wo` (unit, pointing away), with the
    /// texture applied and, when `bend` is set, the shading normal bent by the bump map and noise
    /// (lookups that read only `kd` and the geometric normal skip it).
    pub fn new(material: &'a Material, surf: &SurfaceHit, wo: Vec3A, bend: bool) -> Bsdf<'a> {
        if bend {
            Bsdf::kernel::<true, true, true>(material, surf, wo)
        } else {
            Bsdf::kernel::<true, false, false>(material, surf, wo)
        }
    }

    /// [`Bsdf::new`] compiled for the effects a scene's plan keeps ([`crate::scene::Features`]):
    /// the texture lookup only with `TEX`, the bump map only with `BUMP`, Perlin noise only with
    /// `NOISE`. A kernel without an effect gives the same BSDF as the general one wherever no
    /// material has the effect (tests/light_transport/effect_plan.rs renders both, bit for bit).
    pub fn kernel<const TEX: bool, const BUMP: bool, const NOISE: bool>(
        material: &'a Material,
        surf: &SurfaceHit,
        wo: Vec3A,
    ) -> Bsdf<'a> {
        let Reflectance { kd, ks, roughness } = if TEX {
            material.reflectance(surf.uv)
        } else {
            Reflectance {
                kd: material.kd,
                ks: material.ks,
                roughness: material.roughness,
            }
        };
        let bends = (BUMP && material.bump.is_some()) || (NOISE && material.perlin_scale > 0.0);
        let ns = if bends {
            material
                .shading_normal_with::<BUMP, NOISE>(surf.ns, surf.ng, surf.p, surf.uv, surf.dpdu)
        } else {
            surf.ns
        };
        let front = surf.ng.dot(wo) > 0.0;
        let (n, ng) = if front {
            (ns, surf.ng)
        } else {
            (-ns, -surf.ng)
        };
        Bsdf {
            material,
            material_id: surf.material,
            kd,
            ks,
            roughness,
            wo,
            front,
            n,
            ng,
            touching: None,
        }
    }

    /// Returns the weights of the material's lobes at this hit.
    pub fn lobes(&self) -> Lobes {
        self.material.lobes(self.kd, self.ks)
    }

    /// Returns the crossing of this surface for a path in `media`, or `None` for an opaque
    /// material (`t = 0`). A crossing that [`Crossing::is_false`] is no surface at all: the
    /// boundary of a solid inside a denser one, passed straight through.
    ///
    /// Where another transparent solid touches this surface ([`Bsdf::touching`]) the ray
    /// crosses both boundaries at once: one interface between the media before and after both
    /// (glass to water where a glass cube rests on water), not a film of air between them, which
    /// a ray spawned past both surfaces would otherwise see by the rounding of the two hits.
    pub fn crossing(&self, media: &MediumStack) -> Option<Crossing> {
        if self.material.transparency <= 0.0 {
            return None;
        }
        let first = media.cross(self.material_id, self.material.ior, self.front);
        Some(match self.touching {
            // Two solids of one material meeting face to face: no interface at all.
            Some(t) if t.material_id == self.material_id && t.entering != self.front => Crossing {
                n_to: first.n_from,
                after: *media,
                ..first
            },
            Some(t) => Crossing {
                n_from: first.n_from,
                ..first.after.cross(t.material_id, t.ior, t.entering)
            },
            None => first,
        })
    }

    /// Returns the course's direct-light term per unit of light intensity arriving along `wi`
    /// (unit, towards the light): `kd·cos θ + ks·(r·wo)^p`, the Lambertian lobe and the Phong
    /// highlight, before the light's intensity and attenuation.
    pub fn phong(&self, wi: Vec3A) -> Vec3A {
        let m = self.material;
        let cos = self.n.dot(wi);
        if let Some((lobe, frame)) = self.glossy() {
            // The rough conductor's BRDF in the course's units: a light of colour `rgb` has
            // intensity `π·rgb`, so the term is `π·f·cos θ` (as `kd·cos θ` is `π·(kd/π)·cos θ`).
            let f = lobe.eval(frame.to_local(self.wo), frame.to_local(wi));
            return self.kd * cos + self.ks * (std::f32::consts::PI * f * cos);
        }
        let rv = fresnel::reflect(wi, self.n).dot(self.wo);
        let spec = if rv > 0.0 && m.shininess > 0.0 {
            self.ks * rv.powf(m.shininess)
        } else {
            Vec3A::ZERO
        };
        self.kd * cos + spec
    }

    /// Returns the mirror direction of `wo`.
    pub fn reflected(&self) -> Vec3A {
        reflect_above(self.wo, self.n, self.ng)
    }

    /// Returns the rough conductor that replaces the mirror lobe and the Phong highlight of a
    /// material with roughness, with its frame around the shading normal; `None` when smooth.
    pub fn glossy(&self) -> Option<(RoughConductor, Frame)> {
        (self.roughness > 0.0).then(|| {
            (
                RoughConductor {
                    ggx: Ggx::from_roughness(self.roughness),
                },
                Frame::around(self.n),
            )
        })
    }

    /// Returns the direction the mirror lobe sends a path in and the factor on its weight: the
    /// mirror direction and 1 for a smooth material; for a rough one a direction drawn from
    /// the rough conductor by `u` and its weight `G2/G1 ≤ 1`, or `None` when the draw falls
    /// below the surface (geometric or shading).
    pub fn mirror_sample(&self, u: (f32, f32)) -> Option<(Vec3A, f32)> {
        let Some((lobe, frame)) = self.glossy() else {
            return Some((self.reflected(), 1.0));
        };
        let s = lobe.sample(frame.to_local(self.wo), u)?;
        let wi = frame.to_world(s.wi);
        (wi.dot(self.ng) > 0.0).then_some((wi, s.weight))
    }

    /// Returns how the dielectric interface of `crossing` splits `wo` (Fresnel weight and the two
    /// directions).
    /// A rough interface (`gr.roughness` on a transparent material) splits about a visible
    /// micro-normal drawn from `u` (Walter et al. 2007, `super::microfacet::RoughDielectric`);
    /// a smooth one ignores `u`.
    pub fn dielectric(&self, crossing: &Crossing, u: (f32, f32)) -> Split {
        let eta = crossing.n_from / crossing.n_to;
        if self.roughness > 0.0 {
            return self.rough_dielectric(eta, u);
        }
        let f = fresnel::dielectric(self.n.dot(self.wo).max(0.0), eta);
        Split {
            f,
            reflected: self.reflected(),
            refracted: fresnel::refract(self.wo, self.n, eta).filter(|wt| wt.dot(self.ng) < 0.0),
            radiance_scale: eta * eta,
            reflect_weight: 1.0,
            refract_weight: 1.0,
        }
    }

    /// Returns the rough dielectric a rough material's interface is for a ray crossing by
    /// `crossing`, with its frame around the shading normal; `None` when the interface is smooth.
    pub fn rough_interface(&self, crossing: &Crossing) -> Option<(RoughDielectric, Frame)> {
        (self.roughness > 0.0).then(|| {
            (
                RoughDielectric {
                    ggx: Ggx::from_roughness(self.roughness),
                    eta: crossing.n_from / crossing.n_to,
                },
                Frame::around(self.n),
            )
        })
    }

    /// [`Bsdf::dielectric`] for a rough interface of relative index `eta`.
    fn rough_dielectric(&self, eta: f32, u: (f32, f32)) -> Split {
        let frame = Frame::around(self.n);
        let ggx = Ggx::from_roughness(self.roughness);
        let wo = frame.to_local(self.wo);
        let h = ggx.sample_visible(wo, u);
        let f = fresnel::dielectric(wo.dot(h).max(0.0), eta);
        let weight = |wi: Vec3A, below: bool| {
            let l = frame.to_local(wi);
            let ok = if below {
                wi.dot(self.ng) < 0.0 && l.z < 0.0
            } else {
                wi.dot(self.ng) > 0.0 && l.z > 0.0
            };
            if ok { ggx.g2(wo, l) / ggx.g1(wo) } else { 0.0 }
        };
        let hw = frame.to_world(h);
        let reflected = fresnel::reflect(self.wo, hw);
        let refracted = fresnel::refract(self.wo, hw, eta);
        Split {
            f,
            reflected,
            refracted,
            radiance_scale: eta * eta,
            reflect_weight: weight(reflected, false),
            refract_weight: refracted.map_or(0.0, |wt| weight(wt, true)),
        }
    }

    /// Returns a cosine-distributed direction around the shading normal for `u` in `[0, 1)²`, or
    /// `None` when it falls below the geometric surface.
    pub fn sample_diffuse(&self, u: (f32, f32)) -> Option<Vec3A> {
        let d = cosine_around(self.n, u);
        (d.dot(self.ng) > 0.0).then_some(d)
    }

    /// Chooses one lobe by Russian roulette on the lobe weights and samples it, as photons do;
    /// `crossing` is [`Bsdf::crossing`]'s answer for the path's media. Returns `None` when the
    /// path is absorbed or its sampled direction falls below the surface.
    pub fn sample(&self, crossing: Option<&Crossing>, rng: &mut Rng) -> Option<Sample> {
        let lobes = self.lobes();
        let choice = Choice::new(
            [
                lobes.diffuse.max_element(),
                lobes.mirror.max_element(),
                lobes.dielectric,
            ],
            lobes.total(),
        );
        let xi = rng.next_f32();
        if xi < choice.p[0] {
            let weight = lobes.diffuse / choice.divisor[0];
            let dir = self.sample_diffuse((rng.next_f32(), rng.next_f32()))?;
            Some(Sample {
                dir,
                weight,
                lobe: Lobe::Diffuse,
                media: None,
                radiance_scale: 1.0,
            })
        } else {
            self.specular(&lobes, xi, &choice, crossing, rng)
        }
    }

    /// Chooses one of the specular lobes (mirror or dielectric) by Russian roulette on their
    /// weights and samples it: how a radiance path (a final-gather ray) continues through a
    /// specular surface whose diffuse lobe it has already evaluated.
    pub fn sample_specular(&self, crossing: Option<&Crossing>, rng: &mut Rng) -> Option<Sample> {
        let lobes = self.lobes();
        let specular = Lobes {
            diffuse: Vec3A::ZERO,
            ..lobes
        };
        let choice = Choice::new(
            [0.0, lobes.mirror.max_element(), lobes.dielectric],
            specular.total(),
        );
        let xi = rng.next_f32();
        self.specular(&lobes, xi, &choice, crossing, rng)
    }

    /// The specular choices of [`Bsdf::sample`]: `xi` against the lobe probabilities of
    /// `choice`.
    fn specular(
        &self,
        lobes: &Lobes,
        xi: f32,
        choice: &Choice,
        crossing: Option<&Crossing>,
        rng: &mut Rng,
    ) -> Option<Sample> {
        let p = choice.p;
        if xi < p[0] + p[1] {
            let (dir, glossy) = self.mirror_sample(self.glossy_numbers(rng))?;
            Some(Sample {
                dir,
                weight: lobes.mirror / choice.divisor[1] * glossy,
                lobe: Lobe::Mirror,
                media: None,
                radiance_scale: 1.0,
            })
        } else if xi < p[0] + p[1] + p[2] {
            let c = crossing?;
            if self.roughness > 0.0 {
                return self.rough_dielectric_sample(c, lobes.dielectric / choice.divisor[2], rng);
            }
            let eta = c.n_from / c.n_to;
            let f = fresnel::dielectric(self.n.dot(self.wo).max(0.0), eta);
            let (dir, media, radiance_scale) = match fresnel::refract(self.wo, self.n, eta) {
                Some(wt) if rng.next_f32() >= f && wt.dot(self.ng) < 0.0 => {
                    (wt, Some(c.after), eta * eta)
                }
                _ => (self.reflected(), None, 1.0),
            };
            // Probability p[2] of the lobe, times F or 1 − F for the branch, against weight t
            // times F or 1 − F: t / p[2] (1 unless the lobes' weights were scaled down).
            Some(Sample {
                dir,
                weight: Vec3A::splat(lobes.dielectric / choice.divisor[2]),
                lobe: Lobe::Dielectric,
                media,
                radiance_scale,
            })
        } else {
            None
        }
    }
}

impl Bsdf<'_> {
    /// The rough interface's photon sample: one visible micro-normal, then reflection with
    /// probability `F` or refraction, the chosen branch's weight `G2/G1` on top of `weight`
    /// (the lobe's over its probability).
    fn rough_dielectric_sample(&self, c: &Crossing, weight: f32, rng: &mut Rng) -> Option<Sample> {
        let split = self.dielectric(c, self.glossy_numbers(rng));
        let refract = split.refracted.filter(|_| rng.next_f32() >= split.f);
        let (dir, w, media, radiance_scale) = match refract {
            Some(wt) => (
                wt,
                split.refract_weight,
                Some(c.after),
                split.radiance_scale,
            ),
            None => (split.reflected, split.reflect_weight, None, 1.0),
        };
        (w > 0.0).then(|| Sample {
            dir,
            weight: Vec3A::splat(weight * w),
            lobe: Lobe::Dielectric,
            media,
            radiance_scale,
        })
    }
}

/// How a path picks one lobe ([`Bsdf::sample`]): each lobe's probability, and what its weight is
/// divided by once chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Choice {
    /// Probabilities of the diffuse, mirror and dielectric lobes; what is left is absorption.
    p: [f32; 3],
    /// What each lobe's weight is divided by: its probability (an unbiased estimate), or, at a
    /// surface that reflects more than it receives, its largest channel (a weight of at most 1).
    divisor: [f32; 3],
}

impl Choice {
    /// Returns the choice among lobes whose largest channels are `largest` (diffuse, mirror,
    /// dielectric) and whose sum's largest channel is `total` ([`Lobes::total`]).
    ///
    /// The probabilities are the largest channels, divided by their sum `S` where it exceeds 1.
    /// Where `total` exceeds 1 ([`MAX_ALBEDO`]) the lobes are divided by `S` too: a lobe's
    /// weight over its probability is then the lobe over its largest channel, at most 1 in
    /// every channel, so the path's power never grows at the bounce (`S ≥ total`, and
    /// `S = total` when the lobes peak in the same channel, as grey highlights do).
    fn new(largest: [f32; 3], total: f32) -> Choice {
        let scale = (largest[0] + largest[1] + largest[2]).max(1.0);
        let p = largest.map(|x| x / scale);
        let divisor = if total > MAX_ALBEDO { largest } else { p };
        Choice { p, divisor }
    }
}

impl Bsdf<'_> {
    /// Returns the two numbers a rough mirror lobe or interface draws its direction from; a
    /// smooth one draws none, so smooth scenes keep their random streams (and images) bit for
    /// bit.
    pub fn glossy_numbers(&self, rng: &mut Rng) -> (f32, f32) {
        if self.roughness > 0.0 {
            (rng.next_f32(), rng.next_f32())
        } else {
            (0.0, 0.0)
        }
    }
}

/// Returns `wo` mirrored about the shading normal `n`, or about the geometric normal `ng` when a
/// bent shading normal would send it below the surface.
pub fn reflect_above(wo: Vec3A, n: Vec3A, ng: Vec3A) -> Vec3A {
    let wr = fresnel::reflect(wo, n);
    if wr.dot(ng) > 0.0 {
        wr
    } else {
        fresnel::reflect(wo, ng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pass;
    use glam::Vec2;

    fn flat(material: u32) -> SurfaceHit {
        SurfaceHit {
            p: Vec3A::ZERO,
            ng: Vec3A::Z,
            ns: Vec3A::Z,
            uv: Vec2::ZERO,
            dpdu: Vec3A::X,
            material,
        }
    }

    #[test]
    fn normals_face_wo_on_both_sides() {
        let m = Material::fallback();
        let wo = Vec3A::new(0.3, 0.0, -1.0).normalize();
        let b = Bsdf::new(&m, &flat(0), wo, true);
        assert!(!b.front);
        assert_eq!((b.n, b.ng), (-Vec3A::Z, -Vec3A::Z));
        let b = Bsdf::new(&m, &flat(0), -wo, true);
        assert!(b.front && b.n == Vec3A::Z);
    }

    #[test]
    fn phong_is_the_courses_lambert_plus_highlight() {
        let mut m = Material::fallback();
        m.kd = Vec3A::splat(0.5);
        m.ks = Vec3A::splat(0.25);
        m.shininess = 10.0;
        let wo = Vec3A::Z;
        let b = Bsdf::new(&m, &flat(0), wo, true);
        let a = 0.3f32;
        let wi = Vec3A::new(a.sin(), 0.0, a.cos());
        // r = reflect(wi) has r·wo = cos a.
        let want = 0.5 * a.cos() + 0.25 * a.cos().powf(10.0);
        assert!((b.phong(wi).x - want).abs() < 1e-6);
    }

    #[test]
    fn roulette_weights_are_unbiased_for_every_lobe() {
        // E[weight · 1{lobe}] must equal the lobe's weight for each lobe.
        let mut m = Material::fallback();
        m.kd = Vec3A::new(0.6, 0.3, 0.1);
        m.ks = Vec3A::new(0.2, 0.2, 0.4);
        m.transparency = 0.3;
        m.ior = 1.5;
        let wo = Vec3A::new(0.2, 0.1, 1.0).normalize();
        let b = Bsdf::new(&m, &flat(7), wo, true);
        let crossing = b.crossing(&MediumStack::air()).expect("transparent");
        assert!(!crossing.is_false() && crossing.n_to == 1.5);
        let mut rng = Rng::new(1, Pass::Photon, 0);
        let n = 400_000;
        let (mut d, mut mirror, mut t) = (Vec3A::ZERO, Vec3A::ZERO, 0.0f64);
        for _ in 0..n {
            if let Some(s) = b.sample(Some(&crossing), &mut rng) {
                match s.lobe {
                    Lobe::Diffuse => d += s.weight,
                    Lobe::Mirror => mirror += s.weight,
                    Lobe::Dielectric => t += s.weight.x as f64,
                }
            }
        }
        let lobes = b.lobes();
        // The diffuse lobe loses the directions below the surface (none for a flat normal).
        let close = |a: Vec3A, b: Vec3A| ((a / n as f32) - b).abs().max_element() < 0.01;
        assert!(close(d, lobes.diffuse), "{}", d / n as f32);
        assert!(close(mirror, lobes.mirror), "{}", mirror / n as f32);
        assert!((t / n as f64 - 0.3).abs() < 0.01);
    }

    /// Returns a random material: `kd` and `ks` each channel in `[0, 2)` (zero a quarter of the
    /// time, so single lobes come up), transparency 0 a third of the time, else in `[0, 1)`;
    /// with `fit`, `kd` and `ks` divided so that `kd + ks` is at most 1 in every channel.
    fn random_material(rng: &mut Rng, fit: bool) -> Material {
        let colour = |rng: &mut Rng| {
            if rng.next_f32() < 0.25 {
                Vec3A::ZERO
            } else {
                2.0 * Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
            }
        };
        let mut m = Material::fallback();
        (m.kd, m.ks) = (colour(rng), colour(rng));
        if fit {
            let largest = (m.kd + m.ks).max_element().max(1.0);
            (m.kd, m.ks) = (m.kd / largest, m.ks / largest);
        }
        m.transparency = if rng.next_f32() < 1.0 / 3.0 {
            0.0
        } else {
            rng.next_f32()
        };
        m.ior = 1.5;
        m
    }

    /// The photon sampling before surfaces reflecting more than they receive were scaled: the
    /// lobe `xi` chooses and its weight, lobe over probability; `specular` leaves the diffuse
    /// lobe out, as [`Bsdf::sample_specular`] does.
    fn previous(b: &Bsdf, xi: f32, specular: bool) -> Option<(Lobe, Vec3A)> {
        let lobes = b.lobes();
        let pd = if specular {
            0.0
        } else {
            lobes.diffuse.max_element()
        };
        let (pm, pt) = (lobes.mirror.max_element(), lobes.dielectric);
        let scale = (pd + pm + pt).max(1.0);
        let p = [pd / scale, pm / scale, pt / scale];
        if xi < p[0] {
            Some((Lobe::Diffuse, lobes.diffuse / p[0]))
        } else if xi < p[0] + p[1] {
            Some((Lobe::Mirror, lobes.mirror / p[1]))
        } else if xi < p[0] + p[1] + p[2] {
            Some((Lobe::Dielectric, Vec3A::splat(lobes.dielectric / p[2])))
        } else {
            None
        }
    }

    /// Materials that reflect at most what they receive (total at most 1; a tenth of them with
    /// a lobe sum `S` above 1, where the lobes peak in different channels) sample photons bit
    /// for bit as before: the same lobe and the same weight for every draw, 400 materials × 500
    /// draws each of [`Bsdf::sample`] and [`Bsdf::sample_specular`].
    #[test]
    fn photon_sampling_is_unchanged_where_a_surface_reflects_at_most_what_it_receives() {
        let mut rng = Rng::new(11, Pass::Photon, 0);
        let wo = Vec3A::new(0.2, 0.1, 1.0).normalize();
        let mut peaks_apart = 0;
        for _ in 0..400 {
            let m = random_material(&mut rng, true);
            let b = Bsdf::new(&m, &flat(3), wo, true);
            let lobes = b.lobes();
            assert!(lobes.total() <= MAX_ALBEDO, "{m:?}");
            let sum = lobes.diffuse.max_element() + lobes.mirror.max_element() + lobes.dielectric;
            peaks_apart += usize::from(sum > 1.0);
            let crossing = b.crossing(&MediumStack::air());
            for draw in 0..1000 {
                let specular = draw % 2 == 1;
                let want = previous(&b, rng.clone().next_f32(), specular);
                let got = if specular {
                    b.sample_specular(crossing.as_ref(), &mut rng)
                } else {
                    b.sample(crossing.as_ref(), &mut rng)
                };
                assert_eq!(got.map(|s| (s.lobe, s.weight)), want, "{m:?}");
            }
        }
        assert!(
            peaks_apart >= 40,
            "only {peaks_apart} materials with S above 1"
        );
    }

    /// Materials that reflect more than they receive (total above 1) never make a photon gain
    /// power: over 400 random materials × 1000 draws of [`Bsdf::sample`] and
    /// [`Bsdf::sample_specular`] every weight is at most 1 in every channel (the unscaled
    /// weights reached 3.3 here), and the mean weight per channel is the lobes' sum over `S`
    /// (the lobes scaled to sum 1) within 0.05 (each weight is at most 1, so the standard error
    /// of 1000 draws is under 0.016).
    #[test]
    fn photon_weights_never_exceed_one_where_a_surface_reflects_more_than_it_receives() {
        let mut rng = Rng::new(12, Pass::Photon, 0);
        let wo = Vec3A::new(0.2, 0.1, 1.0).normalize();
        let mut tested = 0;
        while tested < 400 {
            let m = random_material(&mut rng, false);
            let b = Bsdf::new(&m, &flat(3), wo, true);
            let lobes = b.lobes();
            if lobes.total() <= 1.001 {
                continue;
            }
            tested += 1;
            let crossing = b.crossing(&MediumStack::air());
            for specular in [false, true] {
                let diffuse = if specular { Vec3A::ZERO } else { lobes.diffuse };
                let sum = diffuse.max_element() + lobes.mirror.max_element() + lobes.dielectric;
                let scaled = (diffuse + lobes.mirror + Vec3A::splat(lobes.dielectric)) / sum;
                let (n, mut mean) = (1000, Vec3A::ZERO);
                for _ in 0..n {
                    let s = if specular {
                        b.sample_specular(crossing.as_ref(), &mut rng)
                    } else {
                        b.sample(crossing.as_ref(), &mut rng)
                    };
                    if let Some(s) = s {
                        assert!(s.weight.max_element() <= 1.0, "{m:?}: weight {}", s.weight);
                        mean += s.weight / n as f32;
                    }
                }
                // A specular total of at most 1 is sampled as before: unbiased, unscaled.
                let total = (lobes.mirror + Vec3A::splat(lobes.dielectric)).max_element();
                let want = if specular && total <= 1.0 {
                    lobes.mirror + Vec3A::splat(lobes.dielectric)
                } else {
                    scaled
                };
                assert!(
                    (mean - want).abs().max_element() < 0.05,
                    "{m:?}, specular {specular}: mean weight {mean}, want {want}"
                );
            }
        }
    }

    /// Two transparent solids touching are crossed as one interface: glass (material 1) resting
    /// on water (material 2) goes straight from glass to water, and two blocks of one material
    /// face to face are no interface at all.
    #[test]
    fn touching_surfaces_are_crossed_together() {
        let mut glass = Material::fallback();
        (glass.transparency, glass.ior) = (1.0, 1.5);
        let dir = Vec3A::new(0.3, 0.0, 1.0).normalize();
        let in_glass = MediumStack::air().cross(1, 1.5, true).after;
        // A ray along `dir` leaves the glass through its face (normal +z) and enters the water's.
        let mut b = Bsdf::new(&glass, &flat(1), -dir, true);
        assert!(!b.front);
        b.touching = Some(Touching {
            material_id: 2,
            ior: 1.33,
            entering: true,
        });
        let c = b.crossing(&in_glass).unwrap();
        assert_eq!((c.n_from, c.n_to), (1.5, 1.33));
        assert_eq!(c.after, MediumStack::air().cross(2, 1.33, true).after);
        // One glass block resting on another: the stack and the index stay.
        b.touching = Some(Touching {
            material_id: 1,
            ior: 1.5,
            entering: true,
        });
        let c = b.crossing(&in_glass).unwrap();
        assert!(c.is_false());
        assert_eq!(c.after, in_glass);
    }

    #[test]
    fn dielectric_split_follows_fresnel_and_snell() {
        let mut m = Material::fallback();
        m.transparency = 1.0;
        m.ior = 1.5;
        let a = 0.5f32;
        let wo = Vec3A::new(a.sin(), 0.0, a.cos());
        let b = Bsdf::new(&m, &flat(1), wo, true);
        let c = b.crossing(&MediumStack::air()).unwrap();
        let s = b.dielectric(&c, (0.0, 0.0));
        assert!((s.f - fresnel::dielectric(a.cos(), 1.0 / 1.5)).abs() < 1e-7);
        let wt = s.refracted.expect("no TIR entering glass");
        assert!((wt.x.abs() - a.sin() / 1.5).abs() < 1e-5 && wt.z < 0.0);
        assert_eq!(s.reflected, Vec3A::new(-a.sin(), 0.0, a.cos()));
        // Leaving glass past the critical angle: everything reflects.
        let inside = c.after;
        let b = Bsdf::new(
            &m,
            &flat(1),
            -Vec3A::new(0.9f32.sin(), 0.0, 0.9f32.cos()),
            true,
        );
        let out = b.dielectric(&b.crossing(&inside).unwrap(), (0.0, 0.0));
        assert_eq!((out.f, out.refracted), (1.0, None));
    }
}
