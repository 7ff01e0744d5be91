//! Fresnel reflectance of a smooth dielectric interface, and refraction by Snell's law.
//!
//! Directions point away from the surface; `cos_i` is measured against the normal on the side
//! the light arrives from, and `eta = n_incident / n_transmitted`.

use glam::Vec3A;

/// Returns the unpolarised Fresnel reflectance for incidence cosine `cos_i` (in [0, 1]) and
/// relative index `eta = n_i / n_t`; 1 under total internal reflection.
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    if eta == 1.0 {
        // No interface at all (even at grazing incidence, where the formula below is 0/0-like).
        return 0.0;
    }
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // r_s and r_p with n_i and n_t expressed through eta (pbrt-v4 FrDielectric).
    let r_par = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_perp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// Returns the direction refracted from `wo` (pointing away, on the side of `n`) through a
/// surface with normal `n` and relative index `eta = n_i / n_t`, or `None` under total internal
/// reflection.
pub fn refract(wo: Vec3A, n: Vec3A, eta: f32) -> Option<Vec3A> {
    if eta == 1.0 {
        return Some(-wo);
    }
    let cos_i = n.dot(wo).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// Returns `wo` mirrored about `n`.
pub fn reflect(wo: Vec3A, n: Vec3A) -> Vec3A {
    2.0 * n.dot(wo) * n - wo
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_values() {
        // Normal incidence: ((n1 - n2) / (n1 + n2))² = 0.04 for glass.
        assert!((dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        assert!(
            (dielectric(1.0, 1.5) - 0.04).abs() < 1e-6,
            "same from inside"
        );
        // Grazing incidence reflects everything; a matched index reflects nothing.
        assert!((dielectric(0.0, 1.0 / 1.5) - 1.0).abs() < 1e-6);
        for k in 0..=100 {
            assert!(dielectric(k as f32 / 100.0, 1.0).abs() < 1e-7);
        }
        // Total internal reflection past the critical angle (sin θc = 1/1.5).
        let critical = (1.0f32 / 1.5).asin();
        assert_eq!(dielectric((critical + 0.01).cos(), 1.5), 1.0);
        assert!(dielectric((critical - 0.01).cos(), 1.5) < 1.0);
        // Brewster's angle: tan θB = n2/n1, where r_p vanishes and F = r_s²/2.
        let theta_b = 1.5f32.atan();
        let (ci, ct) = (theta_b.cos(), (theta_b.sin() / 1.5).asin().cos());
        let rs = (ci - 1.5 * ct) / (ci + 1.5 * ct);
        assert!((dielectric(ci, 1.0 / 1.5) - 0.5 * rs * rs).abs() < 1e-5);
    }

    #[test]
    fn reflectance_plus_transmittance_is_one_and_snell_holds() {
        for k in 0..=90 {
            let theta = (k as f32).to_radians();
            let wo = Vec3A::new(theta.sin(), 0.0, theta.cos());
            for eta in [1.0 / 1.33, 1.0 / 1.5, 1.5, 1.33, 1.0] {
                let f = dielectric(theta.cos(), eta);
                match refract(wo, Vec3A::Z, eta) {
                    None => assert_eq!(f, 1.0, "TIR must reflect everything"),
                    Some(wt) => {
                        assert!((0.0..=1.0).contains(&f) && f + (1.0 - f) == 1.0);
                        // Snell: eta · sin θi = sin θt, and the ray crosses the surface.
                        let sin_t = (wt.x * wt.x + wt.y * wt.y).sqrt();
                        assert!((eta * theta.sin() - sin_t).abs() < 1e-5, "k {k} eta {eta}");
                        assert!(wt.z < 1e-6, "the refracted ray must cross the surface");
                    }
                }
            }
        }
    }
}
