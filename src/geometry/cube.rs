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
/// A line that passes within the rounding error of the object-space ray of an edge counts as
/// touching it: two boxes meeting only along an edge then leave no crack between them (each box
/// alone would put such a ray just outside itself by rounding). The error of each coordinate is
/// a few `f32` ulps of `o_size` on that axis, the size of the terms it was computed from
/// ([`super::origin_size`]): a slab scaled thin in y must not grow in x by the ulps of the
/// origin's huge y.
pub fn interval(o: Vec3A, d: Vec3A, o_size: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let slack = (o_size.as_dvec3().max(o.abs()) + 1.0) * OBJECT_RAY_ERROR;
    // A line parallel to a slab's planes misses the cube unless it lies within the slab.
    let parallel = d.cmpeq(DVec3::ZERO);
    if (parallel & (o.cmplt(-slack) | o.cmpgt(slack + 1.0))).any() {
        return None;
    }
    // Each slab's entry and exit, the three at once; a parallel slab takes no part.
    let inv = DVec3::ONE / d;
    let (lo, hi) = (-o * inv, (DVec3::ONE - o) * inv);
    let neg = inv.cmplt(DVec3::ZERO);
    let near = DVec3::select(parallel, DVec3::NEG_INFINITY, DVec3::select(neg, hi, lo));
    let far = DVec3::select(parallel, DVec3::INFINITY, DVec3::select(neg, lo, hi));
    let neg = neg.bitmask();
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut face0, mut face1) = (u8::MAX, u8::MAX);
    for axis in 0..3 {
        let flip = ((neg >> axis) & 1) as u8;
        if near[axis] > t0 {
            t0 = near[axis];
            face0 = 2 * axis as u8 + flip;
        }
        if far[axis] < t1 {
            t1 = far[axis];
            face1 = 2 * axis as u8 + 1 - flip;
        }
    }
    closed(o, d, slack, (t0, face0), (t1, face1))
}

/// Returns the interval from the slabs' latest entry `t0` and earliest exit `t1` (each with
/// its face, `u8::MAX` when no slab set it): none when the line misses the cube, else the
/// two crossings.
fn closed(o: DVec3, d: DVec3, slack: DVec3, enter: (f64, u8), exit: (f64, u8)) -> Option<Interval> {
    let ((t0, face0), (mut t1, face1)) = (enter, exit);
    if face0 == u8::MAX || face1 == u8::MAX {
        return None;
    }
    if t0 > t1 {
        // Outside, unless the entry point lies within the slack of every slab: an edge grazed.
        let p = o + d * t0;
        if p.cmplt(-slack).any() || p.cmpgt(slack + 1.0).any() {
            return None;
        }
        t1 = t0;
    }
    let crossing = |t, face| Crossing {
        t,
        normal: face_normal(face),
        face,
    };
    Some(Interval {
        enter: crossing(t0, face0),
        exit: crossing(t1, face1),
    })
}

/// The outward unit normals of the six faces, by face number.
const FACE_NORMALS: [Vec3A; 6] = [
    Vec3A::NEG_X,
    Vec3A::X,
    Vec3A::NEG_Y,
    Vec3A::Y,
    Vec3A::NEG_Z,
    Vec3A::Z,
];

/// Returns the outward unit normal of face `face` (0 to 5), read from a table: writing one lane
/// of a vector on the stack and reading the vector back stalled the store forwarding, the
/// largest cost in `interval`'s profile.
pub fn face_normal(face: u8) -> Vec3A {
    FACE_NORMALS[face as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_face_normal_points_out_along_its_axis() {
        for face in 0..6u8 {
            let mut n = Vec3A::ZERO;
            n[(face / 2) as usize] = if face % 2 == 0 { -1.0 } else { 1.0 };
            assert_eq!(face_normal(face), n, "face {face}");
        }
    }

    #[test]
    fn slab_entry_and_exit_faces() {
        let iv = interval(
            Vec3A::new(0.5, 0.5, 3.0),
            Vec3A::new(0.0, 0.0, -1.0),
            Vec3A::ZERO,
        )
        .unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (2.0, 3.0));
        assert_eq!(iv.enter.normal, Vec3A::Z);
        assert_eq!(iv.exit.normal, -Vec3A::Z);
        // Diagonal ray through the corner region, and a ray parallel to a face outside the slab.
        let iv = interval(
            Vec3A::new(-1.0, 0.5, 0.5),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::ZERO,
        )
        .unwrap();
        assert_eq!((iv.enter.t, iv.exit.t), (1.0, 2.0));
        assert_eq!(iv.enter.normal, -Vec3A::X);
        assert!(
            interval(
                Vec3A::new(2.0, 0.5, 0.5),
                Vec3A::new(0.0, 1.0, 0.0),
                Vec3A::ZERO
            )
            .is_none()
        );
    }

    /// The slabs one axis at a time, as `interval` took them before it took the three at
    /// once: the reference the test below holds it to.
    fn interval_by_axis(o: Vec3A, d: Vec3A, o_size: Vec3A) -> Option<Interval> {
        let (o, d) = (o.as_dvec3(), d.as_dvec3());
        let slack = (o_size.as_dvec3().max(o.abs()) + 1.0) * OBJECT_RAY_ERROR;
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut face0, mut face1) = (u8::MAX, u8::MAX);
        for axis in 0..3 {
            if d[axis] == 0.0 {
                if !(-slack[axis]..=1.0 + slack[axis]).contains(&o[axis]) {
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
        closed(o, d, slack, (t0, face0), (t1, face1))
    }

    /// The three slabs at once give what the slab test one axis at a time gives, bit for bit:
    /// over 200000 lines from a fixed stream (origins inside, outside and on the faces and
    /// edges, directions with components of either sign, zero, negative zero, subnormal, and
    /// lines parallel to a face within and beyond its slack), and four special directions (along
    /// an axis either way, with a negative zero, none) from a corner, an edge's midpoint and a
    /// face's centre.
    #[test]
    fn three_slabs_at_once_match_one_at_a_time() {
        let mut rng = crate::sampling::Rng::new(7, crate::sampling::Pass::Pixel, 0);
        let specials = [0.0, -0.0, 1.0, -1.0, 1e-40, -1e-40, 0.5, -2.0, 1e-7, 3e7];
        let places = [-1e-7, 0.0, 0.5, 1.0, 1.0 + 1e-7, -3.0, 4.0];
        let pick = |options: &[f32], rng: &mut crate::sampling::Rng| {
            options[rng.below(options.len() as u32) as usize]
        };
        let mut checked = 0;
        for _ in 0..200_000 {
            let mut o = Vec3A::ZERO;
            let mut d = Vec3A::ZERO;
            for k in 0..3 {
                o[k] = match rng.below(3) {
                    0 => pick(&places, &mut rng),
                    _ => rng.next_f32() * 6.0 - 2.5,
                };
                d[k] = match rng.below(4) {
                    0 => pick(&specials, &mut rng),
                    _ => rng.next_f32() * 2.0 - 1.0,
                };
            }
            let size = Vec3A::splat(pick(&[0.0, 1.0, 1e4], &mut rng));
            assert_eq!(
                interval(o, d, size),
                interval_by_axis(o, d, size),
                "o {o}, d {d}, size {size}"
            );
            checked += 1;
        }
        for o in [
            Vec3A::ZERO,
            Vec3A::new(0.5, 0.0, 0.0),
            Vec3A::new(0.5, 0.5, 1.0),
        ] {
            for d in [Vec3A::X, -Vec3A::Y, Vec3A::new(-0.0, 1.0, 0.0), Vec3A::ZERO] {
                assert_eq!(
                    interval(o, d, Vec3A::ZERO),
                    interval_by_axis(o, d, Vec3A::ZERO)
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 200_012);
    }

    /// A slab scaled 10⁴ times thinner in y has the width it was given: a ray from 0.95 above
    /// it (object y 9500) that passes 0.005 beside its edge misses, though 0.005 is below the
    /// ulps of 9500; the slack follows each axis's own rounding ([`crate::geometry::origin_size`]).
    /// The old slack, from the largest coordinate, took in 0.9% more on every side: 3.6% more
    /// light on a thin table under a lamp than the closed form.
    #[test]
    fn a_thin_slab_does_not_grow_sideways() {
        let m = glam::Affine3A::from_scale_rotation_translation(
            glam::Vec3::new(1.0, 1e-4, 1.0),
            glam::Quat::IDENTITY,
            glam::Vec3::new(-0.5, -1e-4, -0.5),
        )
        .inverse();
        for (x, hit) in [(0.499, true), (0.505, false), (-0.505, false)] {
            let world = Vec3A::new(x, 0.95, 0.0);
            let d = m.transform_vector3a(Vec3A::new(0.0, -1.0, 0.0));
            let o = m.transform_point3a(world);
            let got = interval(o, d, crate::geometry::origin_size(&m, world)).is_some();
            assert_eq!(got, hit, "x = {x}: object origin {o}");
        }
        // Slanted by 0.01 per unit of height: from x = 0.49 it lands at 0.4995 (on the slab),
        // from 0.499 at 0.5085 (beside it).
        for (x, hit) in [(0.49, true), (0.499, false)] {
            let world = Vec3A::new(x, 0.95, 0.0);
            let d = m.transform_vector3a(Vec3A::new(0.01, -1.0, 0.0));
            let o = m.transform_point3a(world);
            let got = interval(o, d, crate::geometry::origin_size(&m, world)).is_some();
            assert_eq!(got, hit, "slanted, x = {x}");
        }
    }
}
