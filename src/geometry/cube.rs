//! The axis-aligned unit cube from (0,0,0) to (1,1,1) of `gr.cube`; `gr.nh_box` is an instance of it.
//!
//! Faces are numbered `2·axis + (0 for the low side, 1 for the high side)`.

use super::{Crossing, Interval};
use glam::Vec3A;

/// Returns where the full line `o + t·d` enters and leaves the unit cube (slab test in double precision).
pub fn interval(o: Vec3A, d: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut face0, mut face1) = (u8::MAX, u8::MAX);
    for axis in 0..3 {
        if d[axis] == 0.0 {
            if !(0.0..=1.0).contains(&o[axis]) {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[axis];
        let (mut lo, mut hi) = (-o[axis] * inv, (1.0 - o[axis]) * inv);
        let (mut flo, mut fhi) = (2 * axis as u8, 2 * axis as u8 + 1);
        if inv < 0.0 {
            std::mem::swap(&mut lo, &mut hi);
            std::mem::swap(&mut flo, &mut fhi);
        }
        if lo > t0 {
            t0 = lo;
            face0 = flo;
        }
        if hi < t1 {
            t1 = hi;
            face1 = fhi;
        }
    }
    if t0 > t1 || face0 == u8::MAX || face1 == u8::MAX {
        return None;
    }
    Some(Interval {
        enter: Crossing {
            t: t0,
            normal: face_normal(face0),
            face: face0,
        },
        exit: Crossing {
            t: t1,
            normal: face_normal(face1),
            face: face1,
        },
    })
}

/// Returns the outward unit normal of face `face`.
pub fn face_normal(face: u8) -> Vec3A {
    let mut n = Vec3A::ZERO;
    n[(face / 2) as usize] = if face.is_multiple_of(2) { -1.0 } else { 1.0 };
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_entry_and_exit_faces() {
        let iv = interval(Vec3A::new(0.5, 0.5, 3.0), Vec3A::new(0.0, 0.0, -1.0)).unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (2.0, 3.0));
        assert_eq!(iv.enter.normal, Vec3A::Z);
        assert_eq!(iv.exit.normal, -Vec3A::Z);
        // Diagonal ray through the corner region, and a ray parallel to a face outside the slab.
        let iv = interval(Vec3A::new(-1.0, 0.5, 0.5), Vec3A::new(1.0, 0.0, 0.0)).unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (1.0, 2.0));
        assert_eq!(iv.enter.normal, -Vec3A::X);
        assert!(interval(Vec3A::new(2.0, 0.5, 0.5), Vec3A::new(0.0, 1.0, 0.0)).is_none());
    }
}
