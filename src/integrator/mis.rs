//! Multiple importance sampling of the lights at rough dielectric interfaces (frosted glass).
//!
//! A smooth interface reflects and refracts into two exact directions, so an eye path finds the
//! lights it shows only by following them. A rough one scatters into a lobe, and following one
//! drawn direction finds a small bright light by chance: a frosted ball under a lamp sparkled
//! with one-sample fireflies (`cornell_frosted`'s ball had a 5% block error against Mitsuba 3,
//! the glTF `frosted_sphere`'s caustic region 35%). So at a rough interface the eye path also
//! samples the lights, as it does at diffuse and rough-metal surfaces ([`direct`]), and the two
//! estimates of the light it shows are combined by Veach's power heuristic (Veach 1997, §9.2;
//! pbrt-v4's and Mitsuba 3's path tracers do the same):
//! - a shadow-ray sample towards a point `y` of a light, drawn with density `p_l` per steradian
//!   ([`Light::density_towards`]), counts `w_l = (n·p_l)² / ((n·p_l)² + p_b²)` of
//!   `f·|cos θi|·L/p_l`, where `n` is the shading's light samples per light and `p_b` the density
//!   with which the path's own draw would have gone towards `y`;
//! - a drawn direction that meets the light counts `w_b = p_b² / (p_b² + (n·p_l)²)` of the
//!   radiance seen ([`Mis::weight`]), the path carrying its vertex and `p_b` ([`Mis`]).
//!
//! `p_b` is the density of the branch the path follows: the eye splits every visible normal
//! into a reflected and a refracted branch, each drawn with [`RoughDielectric::side_pdf`];
//! beyond the splitting depth it chooses one by `F`, with [`RoughDielectric::pdf`]. The two
//! weights sum to one for every direction, so the sum is unbiased whatever the split.
//!
//! Only lights with extent and the physical falloff take part ([`Light::weighs_by_mis`]): the
//! course's falloff dims a shadow-ray estimate but not the light a path sees, so for those the
//! path's draw alone counts, as before. With soft shadows off (the plan's or `--disable`) lights
//! are sampled at their centres, a different estimate: then too the draw alone counts.
//!
//! [`direct`]: super::eye::Tracer::direct
//! [`RoughDielectric::side_pdf`]: crate::material::microfacet::RoughDielectric::side_pdf
//! [`RoughDielectric::pdf`]: crate::material::microfacet::RoughDielectric::pdf

use super::eye::{ShadingPoint, Tracer};
use crate::geometry::Ray;
use crate::light::{Light, Seen};
use crate::material::medium::Crossing;
use crate::sampling::{Rng, stratified_2d};
use crate::stats::RayCounts;
use glam::Vec3A;
use std::f32::consts::PI;

/// What a path drawn from a rough interface needs to weigh the light it meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mis {
    /// The interface's point, where the drawn direction leaves from.
    pub from: Vec3A,
    /// The density per steradian of the drawn direction.
    pub pdf: f32,
    /// The shadow-ray samples per light taken at `from` (0: none, the draw counts in full).
    pub samples: u32,
}

impl Mis {
    /// Returns the share `w_b` of the radiance a drawn path sees on `light` at `seen` (met along
    /// a ray from `from`, possibly through false interfaces) that it counts.
    pub fn weight(&self, light: &Light, ray: &Ray, seen: &Seen) -> f32 {
        if self.samples == 0 || !light.weighs_by_mis() || self.pdf.is_nan() || self.pdf <= 0.0 {
            return 1.0;
        }
        let y = ray.at(seen.t);
        let light_pdf = self.samples as f32 * light.density_towards(self.from, y, seen.normal);
        power_heuristic(self.pdf, light_pdf)
    }
}

/// Returns Veach's power heuristic (exponent 2) for a sample of density `a` against another
/// strategy's density `b` at the same direction: `a² / (a² + b²)`, 1 where `b` is zero or `a`
/// infinite and 0 where `b` is infinite.
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if b == 0.0 || a == f32::INFINITY {
        return 1.0;
    }
    if b == f32::INFINITY {
        return 0.0;
    }
    // Divided by the larger, so the squares neither overflow nor vanish.
    let m = a.max(b);
    let (a, b) = (a / m, b / m);
    a * a / (a * a + b * b)
}

impl Tracer<'_> {
    /// Returns the shadow-ray samples per light that a rough interface takes for multiple
    /// importance sampling here (0 when lights are not sampled: no direct light, or lights
    /// taken at their centres).
    pub fn mis_samples(&self) -> u32 {
        if self.scene.features.soft_shadows {
            self.light_samples
        } else {
            0
        }
    }

    /// Returns the light that reaches `wo` at the rough interface `at` straight
    /// from every light that [weighs by MIS](Light::weighs_by_mis), by shadow rays weighted
    /// against the path's draw. `split` says whether the path splits both branches (else it
    /// chooses one by `F`). Zero for a smooth interface.
    pub fn rough_interface_direct(
        &self,
        at: &ShadingPoint,
        crossing: &Crossing,
        split: bool,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let samples = self.mis_samples();
        let (bsdf, state) = (at.bsdf(), &at.state);
        let Some((lobe, frame)) = bsdf.rough_interface(crossing) else {
            return Vec3A::ZERO;
        };
        if samples == 0 {
            return Vec3A::ZERO;
        }
        let (p, ng) = (at.p(), bsdf.ng);
        let wo = frame.to_local(bsdf.wo);
        let mut colour = Vec3A::ZERO;
        for light in self.scene.lights.iter().filter(|l| l.weighs_by_mis()) {
            let mut sum = Vec3A::ZERO;
            for u in stratified_2d(rng, samples) {
                let ls = light.sample(p, u);
                let to_light = ls.position - p;
                let d = to_light.length();
                if d.is_nan() || d <= 0.0 || ls.intensity == Vec3A::ZERO {
                    continue;
                }
                let wi = to_light / d;
                let l = frame.to_local(wi);
                let reflect = wi.dot(ng) > 0.0;
                // The shading side must agree with the geometric one (as the draws require).
                if reflect != (l.z > 0.0) {
                    continue;
                }
                let f = lobe.eval(wo, l);
                if f.is_nan() || f <= 0.0 {
                    continue;
                }
                if !self.sees_light(p, ng, wi, ls.position, counts) {
                    continue;
                }
                // Radiance refracted towards `wo` is scaled by eta², as the drawn branch's is.
                let (scale, media) = if reflect {
                    (1.0, &state.media)
                } else {
                    (lobe.eta * lobe.eta, &crossing.after)
                };
                let drawn = if split {
                    lobe.side_pdf(wo, l)
                } else {
                    lobe.pdf(wo, l)
                };
                let light_pdf = samples as f32 * light.density_towards(p, ls.position, ls.normal);
                let w = power_heuristic(light_pdf, drawn);
                let kept = self.scene.transmittance(media, d);
                // In the course's units a light of colour `rgb` has intensity `π·rgb`, as in
                // `Bsdf::phong`'s rough conductor.
                sum += w * scale * PI * f * l.z.abs() * ls.intensity * light.attenuation(d) * kept;
            }
            colour += sum / samples as f32;
        }
        colour
    }

    /// Returns what a path drawn from the rough interface `at` towards `wi` carries to
    /// weigh the lights it meets, `split` as for [`Tracer::rough_interface_direct`]; `None` for
    /// a smooth interface.
    pub fn drawn_from(
        &self,
        at: &ShadingPoint,
        crossing: &Crossing,
        wi: Vec3A,
        split: bool,
    ) -> Option<Mis> {
        let bsdf = at.bsdf();
        let (lobe, frame) = bsdf.rough_interface(crossing)?;
        let (wo, l) = (frame.to_local(bsdf.wo), frame.to_local(wi));
        let pdf = if split {
            lobe.side_pdf(wo, l)
        } else {
            lobe.pdf(wo, l)
        };
        Some(Mis {
            from: at.p(),
            pdf,
            samples: self.mis_samples(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two weights of one direction sum to 1, and the limits are the single strategies.
    #[test]
    fn the_power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0f32, 2.0), (3e-20, 4e-20), (1e30, 5e29), (0.5, 0.5)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(1.0, f32::INFINITY), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
        assert!((power_heuristic(1.0, 2.0) - 0.2).abs() < 1e-6);
    }
}
