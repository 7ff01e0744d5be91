//! The capped cylinder of `gr.cylinder` (the original project's): axis z, radius 1, z in [-1, 1].
//!
//! Faces: 0 the side, 1 the cap at z = -1, 2 the cap at z = +1.

use super::{Crossing, Interval};
use glam::Vec3A;

/// Returns where the full line `o + t·d` enters and leaves the closed cylinder.
pub fn interval(o: Vec3A, d: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    // The infinite tube x² + y² <= 1.
    let a = d.x * d.x + d.y * d.y;
    let (side0, side1) = if a == 0.0 {
        if o.x * o.x + o.y * o.y > 1.0 {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        let b = o.x * d.x + o.y * d.y;
        // Closest approach to the axis, to avoid cancellation for distant origins.
        let cx = o.x - d.x * (b / a);
        let cy = o.y - d.y * (b / a);
        let disc = 1.0 - (cx * cx + cy * cy);
        if disc < 0.0 {
            return None;
        }
        let c = o.x * o.x + o.y * o.y - 1.0;
        let q = -b - b.signum() * (a * disc).sqrt();
        let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
        (r0.min(r1), r0.max(r1))
    };
    // The slab -1 <= z <= 1.
    let (cap0, cap1, face_lo, face_hi) = if d.z == 0.0 {
        if o.z.abs() > 1.0 {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY, 1, 2)
    } else {
        let lo = (-1.0 - o.z) / d.z;
        let hi = (1.0 - o.z) / d.z;
        if lo < hi {
            (lo, hi, 1, 2)
        } else {
            (hi, lo, 2, 1)
        }
    };
    let side_normal = |t: f64| {
        let p = o + d * t;
        Vec3A::new(p.x as f32, p.y as f32, 0.0)
    };
    let cap_normal = |face: u8| if face == 1 { -Vec3A::Z } else { Vec3A::Z };
    let enter = if side0 > cap0 {
        Crossing {
            t: side0,
            normal: side_normal(side0),
            face: 0,
        }
    } else {
        Crossing {
            t: cap0,
            normal: cap_normal(face_lo),
            face: face_lo,
        }
    };
    let exit = if side1 < cap1 {
        Crossing {
            t: side1,
            normal: side_normal(side1),
            face: 0,
        }
    } else {
        Crossing {
            t: cap1,
            normal: cap_normal(face_hi),
            face: face_hi,
        }
    };
    (enter.t <= exit.t && enter.t.is_finite() && exit.t.is_finite())
        .then_some(Interval { enter, exit })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_and_caps() {
        let iv = interval(Vec3A::new(-3.0, 0.0, 0.5), Vec3A::X).unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (2.0, 4.0));
        assert_eq!((iv.enter.face, iv.exit.face), (0, 0));
        assert!((iv.enter.normal - (-Vec3A::X)).length() < 1e-6);
        let iv = interval(Vec3A::new(0.5, 0.0, 5.0), -Vec3A::Z).unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (4.0, 6.0));
        assert_eq!((iv.enter.normal, iv.exit.normal), (Vec3A::Z, -Vec3A::Z));
        // Through a cap and out of the side.
        let iv = interval(Vec3A::new(0.0, 0.0, 2.0), Vec3A::new(0.5, 0.0, -1.0)).unwrap();
        assert_eq!((iv.enter.t, iv.enter.face), (1.0, 2));
        assert!((iv.exit.t - 2.0).abs() < 1e-12 && iv.exit.face == 0);
        assert!(interval(Vec3A::new(0.0, 0.0, 2.0), Vec3A::X).is_none());
    }
}
