//! Spot and directional lights against closed forms: a sun's sharp shadow and dark far side,
//! the flux and the angular spread of a spot's photons, a sun's photons over a floor, and the
//! caustic photons either sends off a mirror.

use crate::common::{render_films_with, run_lua, whitted};
use caustic::photon::trace::{MapKind, trace_map};
use caustic::scene::build::build_scene;
use glam::Vec3A;
use std::f64::consts::{PI, TAU};
use std::path::Path;

/// A matte floor (top face y = 0, 40 × 40) and `more`, seen from `eye` towards `at`, lit by
/// `light` alone.
fn scene(more: &str, light: &str, eye: &str, at: &str) -> String {
    format!(
        "m = gr.material({{0.5, 0.5, 0.5}}, {{0, 0, 0}}, 0)\n\
         root = gr.node('root')\n\
         floor = gr.cube('floor'); floor:set_material(m); floor:scale(40, 1, 40)\n\
         floor:translate(-20, -1, -20); root:add_child(floor)\n\
         {more}\n\
         gr.render(root, 'x.png', 96, 72, {eye}, {at}, {{0, 1, 0}}, 50, {{0, 0, 0}}, {{{light}}})"
    )
}

/// Returns where the ray from `o` along `d` enters the box `[lo, hi]`, if it does (slab test).
fn enters(o: Vec3A, d: Vec3A, lo: Vec3A, hi: Vec3A) -> Option<f32> {
    let inv = d.recip();
    let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
    let (near, far) = (t0.min(t1).max_element(), t0.max(t1).min_element());
    (near <= far && far > 0.0).then_some(near.max(0.0))
}

/// Under a sun, a floating box's shadow on the floor is sharp: every floor pixel is either
/// exactly the unshadowed closed form `kd·rgb·cos θ` (an irradiance `π·rgb`, radiance
/// `kd/π·E·cos θ`) or exactly 0, except where its centre lies within a hair of the shadow's
/// edge; and the faces of the box turned from the sun are exactly 0, those turned to it lit.
#[test]
fn a_directional_shadow_is_sharp_and_the_far_side_dark() {
    let (lo, hi) = (Vec3A::new(-0.5, 1.0, -0.5), Vec3A::new(0.5, 2.0, 0.5));
    let src = scene(
        "b = gr.cube('box'); b:set_material(m); b:translate(-0.5, 1, -0.5); root:add_child(b)",
        "gr.directional_light({1, -2, 0.5}, {0.3, 0.2, 0.1})",
        "{0, 4, 6}",
        "{0, -3.5, -6}",
    );
    let films = render_films_with(src.as_bytes(), "sun.lua", Path::new("."), &whitted()).unwrap();
    let (_, camera, film) = &films[0];
    let travel = Vec3A::new(1.0, -2.0, 0.5).normalize();
    let rgb = Vec3A::new(0.3, 0.2, 0.1);
    let (mut lit, mut shadowed, mut edge, mut far, mut near) = (0, 0, 0, 0, 0);
    let grow = Vec3A::splat(2e-3);
    for y in 0..film.height {
        for x in 0..film.width {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let got = film.get(x, y);
            let floor_t = -ray.origin.y / ray.dir.y;
            match enters(ray.origin, ray.dir, lo, hi) {
                Some(t) if ray.dir.y >= 0.0 || t < floor_t => {
                    // The box: which face, unless the point is near an edge.
                    let p = ray.at(t);
                    let on = |a: f32, b: f32| (a - b).abs() < 1e-3;
                    let faces: Vec<Vec3A> = (0..3)
                        .flat_map(|k| {
                            let mut e = Vec3A::ZERO;
                            e[k] = 1.0;
                            [(on(p[k], lo[k]), -e), (on(p[k], hi[k]), e)]
                        })
                        .filter(|f| f.0)
                        .map(|f| f.1)
                        .collect();
                    let inner = |k: usize| p[k] > lo[k] + 2e-3 && p[k] < hi[k] - 2e-3;
                    if faces.len() != 1 || (0..3).filter(|&k| inner(k)).count() != 2 {
                        continue;
                    }
                    let cos = faces[0].dot(-travel);
                    if cos <= 0.0 {
                        assert_eq!(got, Vec3A::ZERO, "box face {} at {p}", faces[0]);
                        far += 1;
                    } else {
                        let want = 0.5 * rgb * cos;
                        assert!((got - want).abs().max_element() < 1e-5, "{p}: {got} {want}");
                        near += 1;
                    }
                }
                _ if ray.dir.y < 0.0 => {
                    let p = ray.at(floor_t);
                    if p.x.abs() > 19.0 || p.z.abs() > 19.0 {
                        continue;
                    }
                    let blocked = enters(p, -travel, lo + grow, hi - grow).is_some();
                    let clear = enters(p, -travel, lo - grow, hi + grow).is_none();
                    if blocked {
                        assert_eq!(got, Vec3A::ZERO, "{p} lies in the shadow");
                        shadowed += 1;
                    } else if clear {
                        let want = 0.5 * rgb * -travel.y;
                        assert!((got - want).abs().max_element() < 1e-5, "{p}: {got} {want}");
                        lit += 1;
                    } else {
                        edge += 1;
                    }
                }
                _ => {}
            }
        }
    }
    assert!(
        lit > 2000 && shadowed > 100 && far > 100 && near > 30,
        "lit {lit}, shadowed {shadowed}, far faces {far}, near faces {near}"
    );
    assert!(
        edge * 50 < shadowed,
        "{edge} pixels within a hair of the edge"
    );
}

/// Returns glTF's falloff `t²` at cosine `c` for a spot of `inner` and `outer` radians.
fn falloff(c: f64, inner: f64, outer: f64) -> f64 {
    let t = ((c - outer.cos()) / (inner.cos() - outer.cos()).max(0.001)).clamp(0.0, 1.0);
    t * t
}

/// A spot's global photons carry its flux, the closed form `π·rgb·2π(1 − cos o − 2w/3)` (`w =
/// cos i − cos o`), all of it onto a floor under it (none beyond the outer cone), spread over
/// the angle from its axis as the falloff says: the power in each of ten bands of `cos θ` is
/// `∫ t² dω` over the band, within its sampling noise.
#[test]
fn spot_photons_carry_the_closed_form_flux_spread_as_the_falloff() {
    let src = scene(
        "",
        "gr.spot_light({0, 1, 0}, {0, -1, 0}, {1, 0.5, 0.25}, 20, 30)",
        "{0, 4, 6}",
        "{0, -4, -6}",
    );
    let d = run_lua(&src).unwrap();
    let scene = build_scene(&d, &d.renders[0]).unwrap();
    let n = 200_000u64;
    let traced = trace_map(&scene, &[n], MapKind::Global, 5);
    let (inner, outer) = (20f64.to_radians(), 30f64.to_radians());
    let w = inner.cos() - outer.cos();
    let flux = PI * TAU * (1.0 - outer.cos() - 2.0 * w / 3.0);
    assert!((f64::from(scene.lights[0].flux().x) / flux - 1.0).abs() < 1e-5);
    let bands = 10;
    let x_outer = 1.0 - outer.cos();
    let mut power = vec![0.0f64; bands];
    let mut direct = 0;
    for p in traced.photons.iter().map(|p| p.view()) {
        if !p.direct {
            continue;
        }
        direct += 1;
        let to = Vec3A::new(0.0, 1.0, 0.0) - p.position;
        let c = f64::from(to.y / to.length());
        assert!(
            c >= outer.cos() - 1e-4,
            "a photon at {} beyond the cone",
            p.position
        );
        let b = (((1.0 - c) / x_outer) * bands as f64) as usize;
        power[b.min(bands - 1)] += f64::from(p.power.x);
        assert!((p.power.y / p.power.x - 0.5).abs() < 1e-5);
    }
    assert_eq!(direct, n, "every photon meets the floor");
    let total: f64 = power.iter().sum();
    assert!((total / flux - 1.0).abs() < 1e-4, "{total} against {flux}");
    // Each band's share, by the midpoint rule over x = 1 − cos θ.
    let steps = 1000;
    let share = |b: usize| {
        let dx = x_outer / (bands * steps) as f64;
        (0..steps)
            .map(|k| {
                let x = (b * steps + k) as f64 * dx + dx / 2.0;
                PI * TAU * falloff(1.0 - x, inner, outer) * dx
            })
            .sum::<f64>()
    };
    for (b, got) in power.iter().enumerate() {
        let want = share(b);
        let sigma = (want / flux * (1.0 - want / flux) / n as f64).sqrt() * flux;
        assert!(
            (got - want).abs() < 5.0 * sigma + 1e-9,
            "band {b}: {got} against {want} (σ {sigma})"
        );
    }
}

/// A sun's global photons leave a disc that covers the scene: the power they bring to the top
/// of a 4 × 4 slab is its irradiance `π·rgb` times the area times `cos θ`.
#[test]
fn directional_photons_bring_the_irradiance_times_the_area() {
    let src = "m = gr.material({0.5, 0.5, 0.5}, {0, 0, 0}, 0)\n\
         slab = gr.cube('slab'); slab:set_material(m); slab:scale(4, 0.1, 4)\n\
         slab:translate(-2, -0.1, -2)\n\
         gr.render(slab, 'x.png', 8, 8, {0, 4, 6}, {0, -4, -6}, {0, 1, 0}, 50, {0, 0, 0},\n\
                   {gr.directional_light({1, -2, 0.5}, {0.3, 0.3, 0.3})})";
    let d = run_lua(src).unwrap();
    let scene = build_scene(&d, &d.renders[0]).unwrap();
    let traced = trace_map(&scene, &[200_000], MapKind::Global, 2);
    let top: f64 = traced
        .photons
        .iter()
        .map(|p| p.view())
        .filter(|p| p.direct && p.normal.y > 0.9)
        .map(|p| f64::from(p.power.x))
        .sum();
    let cos = 2.0 / (1.0f64 + 4.0 + 0.25).sqrt();
    let want = PI * 0.3 * 16.0 * cos;
    assert!((top / want - 1.0).abs() < 0.01, "{top} against {want}");
}

/// A vertical mirror (ks 1) at x = 1 facing −x, 1 × 1, floating over the floor.
const MIRROR: &str = "mirror = gr.material({0, 0, 0}, {1, 1, 1}, 0)\n\
     mm = gr.cube('mirror'); mm:set_material(mirror); mm:scale(0.01, 1, 1)\n\
     mm:translate(1, 0.5, -0.5); root:add_child(mm)";

/// Returns the power caustic photons of the scene's only light store on the floor.
fn caustic_power(src: &str) -> f64 {
    let d = run_lua(src).unwrap();
    let scene = build_scene(&d, &d.renders[0]).unwrap();
    let traced = trace_map(&scene, &[200_000], MapKind::Caustic, 3);
    traced
        .photons
        .iter()
        .map(|p| p.view())
        .filter(|p| p.position.y.abs() < 1e-3)
        .map(|p| f64::from(p.power.x))
        .sum()
}

/// What a mirror receives, it sends on: the caustic photons a sun and a spot send off a mirror
/// onto the floor carry the flux the mirror's lit face receives, the sun's `π·rgb·A·cos θ`
/// and the spot's `∫ π·rgb·t²·cos/d² dA` over the face (a fine midpoint sum), so the
/// caustic photons' aim (discs along the sun, cones from the spot) and the spot's falloff on
/// them are unbiased.
#[test]
fn caustic_photons_off_a_mirror_carry_what_it_receives() {
    // The sun travels along (0.8, −0.6, 0): the face at x = 1 receives E·1·0.8 and sends it
    // down onto the floor; the mirror's top face sends its share up, away.
    let sun = caustic_power(&scene(
        MIRROR,
        "gr.directional_light({0.8, -0.6, 0}, {0.5, 0.5, 0.5})",
        "{0, 4, 6}",
        "{0, -4, -6}",
    ));
    let want = PI * 0.5 * 0.8;
    assert!(
        (sun / want - 1.0).abs() < 0.015,
        "sun: {sun} against {want}"
    );

    // A spot above and left of the mirror, aimed at its centre, whose ramp crosses the face.
    let (spot, axis) = (
        glam::DVec3::new(-1.0, 2.5, 0.0),
        glam::DVec3::new(2.0, -1.5, 0.0).normalize(),
    );
    let (inner, outer) = (8f64.to_radians(), 16f64.to_radians());
    let got = caustic_power(&scene(
        MIRROR,
        "gr.spot_light({-1, 2.5, 0}, {2, -1.5, 0}, {1, 1, 1}, 8, 16)",
        "{0, 4, 6}",
        "{0, -4, -6}",
    ));
    let steps = 400;
    let h = 1.0 / steps as f64;
    let mut want = 0.0;
    for i in 0..steps {
        for j in 0..steps {
            let y = glam::DVec3::new(1.0, 0.5 + (i as f64 + 0.5) * h, -0.5 + (j as f64 + 0.5) * h);
            let to = y - spot;
            let d = to.length();
            let cos_face = to.x / d;
            want += PI * falloff(axis.dot(to / d), inner, outer) * cos_face / (d * d) * h * h;
        }
    }
    assert!(want > 0.1, "the spot lights the mirror: {want}");
    assert!(
        (got / want - 1.0).abs() < 0.015,
        "spot: {got} against {want}"
    );
}
