//! The exact Fresnel reflectance of a smooth dielectric interface
//! ([`fresnel_dielectric`]) and of a conductor with a complex index of
//! refraction, per RGB channel ([`fresnel_conductor`]), which is also
//! Mitsuba 3's `fresnel_conductor` (the same closed form; this one also
//! clamps `cos_i` and the result to `[0, 1]`, which Mitsuba's callers never
//! leave). Mitsuba's dielectric Fresnel with the refracted cosine
//! ([`fresnel_mitsuba`]) and its diffuse Fresnel reflectance
//! ([`fresnel_diffuse_reflectance`]) are here for the BSDFs that reproduce
//! Mitsuba's.

use glam::Vec3A;

/// Exact unpolarised Fresnel reflectance of a smooth dielectric interface.
///
/// `eta` is the index of the medium the normal points away from (inside) over
/// that of the medium it points into (outside): `ior` for glass in air. `cos_i` is
/// the cosine between the normal and the direction light arrives from (or leaves
/// to): positive on the outside, negative on the inside, where the media swap
/// roles. Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Exact unpolarised Fresnel reflectance of a conductor with complex index of
/// refraction `eta + i k` (relative to the outside medium), per channel, for light
/// arriving at angle `acos(cos_i)` (clamped to `[0, 1]`). A channel with infinite
/// `k` is a perfect conductor and reflects exactly 1.
///
/// This is the closed form of the complex Fresnel equations used by pbrt-v3
/// (`FrConductor`), exact for unpolarised light.
pub fn fresnel_conductor(cos_i: f32, eta: Vec3A, k: Vec3A) -> Vec3A {
    let c = cos_i.clamp(0.0, 1.0);
    let f = |eta: f32, k: f32| -> f32 {
        if k.is_infinite() {
            return 1.0;
        }
        let cos2 = c * c;
        let sin2 = 1.0 - cos2;
        let eta2 = eta * eta;
        let k2 = k * k;
        let t0 = eta2 - k2 - sin2;
        let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).max(0.0).sqrt();
        let t1 = a2_plus_b2 + cos2;
        let a = (0.5 * (a2_plus_b2 + t0)).max(0.0).sqrt();
        let t2 = 2.0 * c * a;
        let r_s = (t1 - t2) / (t1 + t2);
        let t3 = cos2 * a2_plus_b2 + sin2 * sin2;
        let t4 = t2 * sin2;
        let r_p = r_s * (t3 - t4) / (t3 + t4);
        let r = 0.5 * (r_p + r_s);
        // 0/0 only for the degenerate index 0 + 0i at grazing incidence.
        if r.is_finite() {
            r.clamp(0.0, 1.0)
        } else {
            1.0
        }
    };
    Vec3A::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

/// The Fresnel term of a dielectric interface as Mitsuba 3 computes it
/// (`fresnel` in its `fresnel.h`), with what refraction needs: returns
/// `(F, cos θt, η_it, η_ti)`.
///
/// `eta` is the relative index inside over outside (the normal points
/// outside); `cos_i` the cosine of the direction light leaves along (either
/// side). `cos θt` is the refracted direction's cosine, of the sign opposite
/// to `cos_i` (0 under total internal reflection, where `F = 1`); `η_it` is
/// the relative index across the interface in the direction of travel and
/// `η_ti = 1/η_it` scales the tangential part of the refracted direction.
/// `eta = 1` gives `F = 0`; `cos_i = 0` gives `F = 1`.
#[inline]
pub fn fresnel_mitsuba(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let (eta_it, eta_ti) = if cos_i >= 0.0 {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti);
    let ci = cos_i.abs();
    let ct = cos_t2.max(0.0).sqrt();
    let r = if eta == 1.0 {
        0.0
    } else if ci == 0.0 {
        1.0
    } else {
        let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        let a_p = (eta_it * ci - ct) / (eta_it * ci + ct);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    (r, -ct.copysign(cos_i), eta_it, eta_ti)
}

/// Mitsuba 3's diffuse Fresnel reflectance `F_dr(η)`: the fraction of
/// uniformly diffuse light reflected by a dielectric interface of relative
/// index `eta`, by its fits (Egan and Hilgeman 1973 for `η < 1`, d'Eon and
/// Irving 2011 otherwise).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + (eta * (eta * -1.4399 + 0.7099) + 0.6681)
    } else {
        0.919_317
            + inv
                * (-3.4793
                    + inv * (6.753_35 + inv * (-7.809_89 + inv * (4.985_54 + inv * -1.368_81))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;
    use glam::Vec2;

    #[test]
    fn dielectric_fresnel_at_normal_incidence() {
        for ior in [1.0f32, 1.33, 1.5, 2.4] {
            let r0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, ior) - r0).abs() < 1e-6);
            assert!(
                (fresnel_dielectric(-1.0, ior) - r0).abs() < 1e-6,
                "from inside"
            );
            if ior == 1.0 {
                continue; // F = 0: no reflection lobe to check
            }
            // The reflected lobe's probability is F.
            let m = Material::Dielectric { ior };
            let s = m.sample(Vec3A::Z, 0.0, Vec2::ZERO).unwrap();
            assert!(s.specular && (s.pdf - r0).abs() < 1e-6, "{s:?}");
            assert_eq!(s.wi, Vec3A::Z);
        }
        // F(glass, 1.5) at normal incidence is 0.04; at 60° it is 0.0892 (s 0.1774,
        // p 0.0018), and grazing reflects everything.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(0.5, 1.5) - 0.089_6).abs() < 5e-4);
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn mitsuba_fresnel_matches_the_exact_one_and_fdr_its_average() {
        for eta in [1.5f32, 1.0 / 1.33, 2.4] {
            for c in [1.0f32, 0.7, 0.3, 0.01, -0.2, -0.9, -1.0] {
                let (f, ct, eta_it, eta_ti) = fresnel_mitsuba(c, eta);
                assert!((f - fresnel_dielectric(c, eta)).abs() < 1e-6, "{eta} {c}");
                assert_eq!(eta_it * eta_ti, eta_it * (1.0 / eta_it));
                if f < 1.0 {
                    // Snell: η_it sin θt = sin θi, and the sides swap.
                    let st = (1.0 - ct * ct).sqrt();
                    let si = (1.0 - c * c).sqrt();
                    assert!((eta_it * st - si).abs() < 1e-5 && ct * c <= 0.0);
                }
            }
        }
        assert_eq!(fresnel_mitsuba(0.5, 1.0).0, 0.0);
        assert_eq!(fresnel_mitsuba(0.0, 1.5).0, 1.0);
        // F_dr(η) = 2 ∫ F(μ, η) μ dμ over the incident hemisphere: the fits
        // are within 0.6 % of the integral for 1.33 and 1.5, from both sides.
        for eta in [1.33f32, 1.5, 1.0 / 1.5] {
            let n = 20_000;
            let fdr: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * fresnel_dielectric(mu as f32, eta) as f64 * mu / n as f64
                })
                .sum();
            let fit = fresnel_diffuse_reflectance(eta) as f64;
            assert!(
                (fit - fdr).abs() < 6e-3 * fdr.max(0.1),
                "η {eta}: {fit} vs {fdr}"
            );
        }
    }

    #[test]
    fn conductor_fresnel_known_values() {
        // Normal incidence: ((n−1)² + k²) / ((n+1)² + k²).
        let (eta, k) = (Vec3A::new(0.2, 0.9, 1.5), Vec3A::new(3.9, 2.4, 0.0));
        let f = fresnel_conductor(1.0, eta, k);
        let r0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!(rel_err(f, r0) < 1e-5, "{f:?} vs {r0:?}");
        // k = 0 is a dielectric, at every angle.
        for c in [1.0f32, 0.8, 0.5, 0.2, 0.01] {
            let fc = fresnel_conductor(c, Vec3A::splat(1.5), Vec3A::ZERO).x;
            assert!((fc - fresnel_dielectric(c, 1.5)).abs() < 1e-5, "cos {c}");
        }
        // Grazing reflects everything; a perfect conductor reflects everything always.
        assert!(
            (fresnel_conductor(0.0, eta, k) - Vec3A::ONE)
                .abs()
                .max_element()
                < 1e-5
        );
        for c in [0.0f32, 0.3, 1.0] {
            assert_eq!(
                fresnel_conductor(c, Vec3A::ONE, Vec3A::splat(f32::INFINITY)),
                Vec3A::ONE
            );
        }
        // Gold is yellow: red reflects more than blue at normal incidence.
        let Material::RoughConductor { eta, k, .. } = Material::gold(0.1) else {
            unreachable!()
        };
        let g = fresnel_conductor(1.0, eta, k);
        eprintln!("gold F0 = {g:?}");
        assert!(g.x > 0.9 && g.z < 0.5, "{g:?}");
    }
}
