//! The unit sphere (centre 0, radius 1) of `gr.sphere`; `gr.nh_sphere` is an instance of it.

use super::{Crossing, Interval};
use glam::Vec3A;

/// Returns where the full line `o + t·d` enters and leaves the unit sphere, if it meets it.
///
/// Solved in double precision with the numerically stable quadratic formula, so a ray from far
/// away (the course's cameras sit 800 units from spheres of radius 1000) keeps its accuracy.
pub fn interval(o: Vec3A, d: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let a = d.dot(d);
    let b = o.dot(d);
    // c computed from the ray's closest approach avoids cancellation when |o| >> 1.
    let closest = o - d * (b / a);
    let disc = 1.0 - closest.length_squared();
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let c = o.length_squared() - 1.0;
    let q = -b - b.signum() * (a * disc).sqrt();
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let normal = |t: f64| Vec3A::from((o + d * t).as_vec3());
    Some(Interval {
        enter: Crossing {
            t: t0,
            normal: normal(t0),
            face: 0,
        },
        exit: Crossing {
            t: t1,
            normal: normal(t1),
            face: 0,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn hits_from_outside_and_inside() {
        let iv = interval(Vec3A::new(0.0, 0.0, 5.0), Vec3A::new(0.0, 0.0, -1.0)).unwrap();
        assert!((iv.enter.t - 4.0).abs() < 1e-12 && (iv.exit.t - 6.0).abs() < 1e-12);
        assert!((iv.enter.normal - Vec3A::Z).length() < 1e-6);
        let iv = interval(Vec3A::ZERO, Vec3A::new(2.0, 0.0, 0.0)).unwrap();
        assert!((iv.enter.t + 0.5).abs() < 1e-12 && (iv.exit.t - 0.5).abs() < 1e-12);
    }

    #[test]
    fn misses_and_far_rays_stay_accurate() {
        assert!(interval(Vec3A::new(0.0, 1.5, 5.0), Vec3A::new(0.0, 0.0, -1.0)).is_none());
        // Origin 1e4 radii away: the entry point must still lie on the sphere.
        let o = Vec3A::new(0.3, 0.2, 1e4);
        let iv = interval(o, Vec3A::new(0.0, 0.0, -1.0)).unwrap();
        let p = o.as_dvec3() + DVec3::new(0.0, 0.0, -1.0) * iv.enter.t;
        assert!((p.length() - 1.0).abs() < 1e-6, "{}", p.length());
    }
}
