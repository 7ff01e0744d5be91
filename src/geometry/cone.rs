//! The capped cone of `gr.cone` (dsu1995's convention): apex at the origin, axis +z, radius 1 at
//! z = 1, z in [0, 1], closed by a base cap at z = 1.
//!
//! ```lua
//! c = gr.cone('c'); c:scale(3, 3, 3.5)
//! ```
//!
//! Faces: 0 the side, 1 the base cap. The solid is convex, so a line meets it in one interval.

use super::{Crossing, Interval};
use glam::{DVec3, Vec3A};

/// Returns where the full line `o + t·d` enters and leaves the closed cone.
pub fn interval(o: Vec3A, d: Vec3A) -> Option<Interval> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    // The slab 0 <= z <= 1 (its z = 0 side touches the solid only at the apex).
    let (s0, s1) = if d.z == 0.0 {
        if !(0.0..=1.0).contains(&o.z) {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        let (a, b) = (-o.z / d.z, (1.0 - o.z) / d.z);
        (a.min(b), a.max(b))
    };
    // f(t) = x² + y² − z² <= 0 is the double cone; within the slab only the upper nappe remains.
    let a = d.x * d.x + d.y * d.y - d.z * d.z;
    let b = o.x * d.x + o.y * d.y - o.z * d.z;
    let c = o.x * o.x + o.y * o.y - o.z * o.z;
    let scale = d.length_squared();
    let mut pieces: [(f64, f64); 2] = [(f64::NAN, f64::NAN); 2];
    if a.abs() <= 1e-12 * scale {
        // Parallel to a generator: f is linear, 2bt + c <= 0.
        if b.abs() <= 1e-300 {
            if c > 0.0 {
                return None;
            }
            pieces[0] = (f64::NEG_INFINITY, f64::INFINITY);
        } else {
            let r = -c / (2.0 * b);
            pieces[0] = if b > 0.0 {
                (f64::NEG_INFINITY, r)
            } else {
                (r, f64::INFINITY)
            };
        }
    } else {
        let disc = b * b - a * c;
        if disc < 0.0 {
            if a > 0.0 {
                return None;
            }
            pieces[0] = (f64::NEG_INFINITY, f64::INFINITY);
        } else {
            let q = -b - b.signum() * disc.sqrt();
            let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
            let (r0, r1) = (r0.min(r1), r0.max(r1));
            if a > 0.0 {
                pieces[0] = (r0, r1);
            } else {
                pieces[0] = (f64::NEG_INFINITY, r0);
                pieces[1] = (r1, f64::INFINITY);
            }
        }
    }
    // Keep the piece that overlaps the slab with positive length (the convex solid).
    let (t0, t1) = pieces
        .iter()
        .filter(|p| !p.0.is_nan())
        .map(|&(lo, hi)| (lo.max(s0), hi.min(s1)))
        .filter(|&(lo, hi)| lo < hi)
        .max_by(|x, y| (x.1 - x.0).total_cmp(&(y.1 - y.0)))?;
    if !(t0.is_finite() && t1.is_finite()) {
        return None;
    }
    let crossing = |t: f64| {
        let p = o + d * t;
        if (p.z - 1.0).abs() <= 1e-9 * (1.0 + p.length()) && p.x * p.x + p.y * p.y <= 1.0 + 1e-9 {
            Crossing {
                t,
                normal: Vec3A::Z,
                face: 1,
            }
        } else {
            Crossing {
                t,
                normal: side_normal(p),
                face: 0,
            }
        }
    };
    Some(Interval {
        enter: crossing(t0),
        exit: crossing(t1),
    })
}

/// Returns the outward normal of the side at `p`: the gradient of x² + y² − z².
fn side_normal(p: DVec3) -> Vec3A {
    let n = DVec3::new(p.x, p.y, -p.z);
    if n.length_squared() == 0.0 {
        -Vec3A::Z
    } else {
        Vec3A::from(n.as_vec3())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_cap_and_apex() {
        // Along x at z = 0.5: the cone's radius there is 0.5.
        let iv = interval(Vec3A::new(-2.0, 0.0, 0.5), Vec3A::X).unwrap();
        assert!((iv.enter.t - 1.5).abs() < 1e-9 && (iv.exit.t - 2.5).abs() < 1e-9);
        assert_eq!((iv.enter.face, iv.exit.face), (0, 0));
        let n = iv.enter.normal.normalize();
        assert!(
            (n - Vec3A::new(-1.0, 0.0, -1.0).normalize()).length() < 1e-6,
            "{n}"
        );
        // Down the axis: in through the cap at z = 1, out at the apex.
        let iv = interval(Vec3A::new(0.0, 0.0, 3.0), -Vec3A::Z).unwrap();
        assert!((iv.enter.t - 2.0).abs() < 1e-9 && (iv.exit.t - 3.0).abs() < 1e-9);
        assert_eq!((iv.enter.face, iv.enter.normal), (1, Vec3A::Z));
        // Below the apex, and beside the cone: misses (the lower nappe is not part of the solid).
        assert!(interval(Vec3A::new(-2.0, 0.0, -0.5), Vec3A::X).is_none());
        assert!(interval(Vec3A::new(-2.0, 0.9, 0.5), Vec3A::X).is_none());
        // Up the axis from below passes through the apex and leaves through the cap.
        let iv = interval(Vec3A::new(0.0, 0.0, -1.0), Vec3A::Z).unwrap();
        assert!((iv.enter.t - 1.0).abs() < 1e-9 && (iv.exit.t - 2.0).abs() < 1e-9);
        // A slanted ray from inside: the exit is on the side where x² + y² = z².
        let iv = interval(Vec3A::new(0.0, 0.0, 0.8), Vec3A::new(1.0, 0.0, -1.0)).unwrap();
        assert!((iv.exit.t - 0.4).abs() < 1e-6 && iv.enter.t < 0.0, "{iv:?}");
    }

    #[test]
    fn agrees_with_point_sampling() {
        // Points along random lines are inside the solid exactly between enter and exit.
        let inside = |p: DVec3| p.z >= 0.0 && p.z <= 1.0 && p.x * p.x + p.y * p.y <= p.z * p.z;
        let mut seed = 1u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64) * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let o = Vec3A::new(rnd() as f32 * 2.0, rnd() as f32 * 2.0, rnd() as f32 * 2.0);
            let d = Vec3A::new(rnd() as f32, rnd() as f32, rnd() as f32);
            let iv = interval(o, d);
            for k in 0..200 {
                let t = -4.0 + 8.0 * k as f64 / 199.0;
                let p = o.as_dvec3() + d.as_dvec3() * t;
                let by_interval =
                    iv.is_some_and(|iv| t > iv.enter.t + 1e-6 && t < iv.exit.t - 1e-6);
                let near_edge = iv.is_some_and(|iv| {
                    (t - iv.enter.t).abs() < 1e-6 || (t - iv.exit.t).abs() < 1e-6
                });
                if !near_edge && !by_interval {
                    // Outside the interval: not strictly inside (allow boundary rounding).
                    let shrunk = p.z > 1e-6
                        && p.z < 1.0 - 1e-6
                        && (p.x * p.x + p.y * p.y).sqrt() < p.z - 1e-6;
                    assert!(!shrunk, "o {o} d {d} t {t} is inside but outside {iv:?}");
                } else if by_interval {
                    assert!(
                        inside(p) || (p.x * p.x + p.y * p.y).sqrt() - p.z < 1e-6,
                        "o {o} d {d} t {t}"
                    );
                }
            }
        }
    }
}
