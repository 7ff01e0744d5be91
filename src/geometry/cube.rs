//! The axis-aligned unit cube from (0,0,0) to (1,1,1) of `gr.cube`; `gr.nh_box` is an instance of it.
//!
//! Faces are numbered `2·axis + (0 for the low side, 1 for the high side)`.

use super::{Crossing, Interval};
use glam::{DVec3, Vec3A};

/// Relative error of a ray moved into object space in single precision, in units of the size of
/// its origin's coordinates: a few ulps of `f32`.
const OBJECT_RAY_ERROR: f64 = 8.0 * f32::EPSILON as f64;

/// Returns where the full line `o + t·d` enters and leaves the unit cube (slab test in double precision).
///
/// A line that passes within the rounding error of the object-space ray (a few `f32` ulps of
/// `o`'s size) of an edge counts as touching it: two boxes meeting only along an edge then leave
/// no crack between them (each box alone would put such a ray just outside itself by rounding).
pub fn interval(o: Vec3A, d: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let slack = OBJECT_RAY_ERROR * (1.0 + o.abs().max_element());
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut face0, mut face1) = (u8::MAX, u8::MAX);
    for axis in 0..3 {
        if d[axis] == 0.0 {
            if !(-slack..=1.0 + slack).contains(&o[axis]) {
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
    if face0 == u8::MAX || face1 == u8::MAX {
        return None;
    }
    if t0 > t1 {
        // Outside, unless the entry point lies within the slack of every slab: an edge grazed.
        let p = o + d * t0;
        if p.cmplt(DVec3::splat(-slack)).any() || p.cmpgt(DVec3::splat(1.0 + slack)).any() {
            return None;
        }
        t1 = t0;
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
