//! Smooth glass, [`Material::Dielectric`](super::Material::Dielectric): the
//! interface's Fresnel term and refracted direction, shared by its sampling
//! and its guides, and its sampling (reflect with probability `F`, refract
//! otherwise).

use super::bsdf::BsdfSample;
use super::frame::reflect_z;
use super::fresnel::fresnel_dielectric;
use glam::Vec3A;

/// Smooth glass: reflect with probability `F`, refract otherwise; both weights
/// are exactly 1 (see [the module documentation](super) on radiance scaling).
pub(super) fn sample_dielectric(ior: f32, wo: Vec3A, u_lobe: f32) -> Option<BsdfSample> {
    if wo.z == 0.0 || !wo.is_finite() || ior.is_nan() || ior <= 0.0 {
        return None;
    }
    let (eta, sin2_t, f) = dielectric_interface(ior, wo);
    if sin2_t >= 1.0 || u_lobe < f {
        return Some(BsdfSample {
            wi: reflect_z(wo),
            weight: Vec3A::ONE,
            pdf: f,
            specular: true,
        });
    }
    Some(BsdfSample {
        wi: dielectric_refraction(wo, eta, sin2_t),
        weight: Vec3A::ONE,
        pdf: 1.0 - f,
        specular: true,
    })
}

/// For `wo` at a smooth dielectric interface of index `ior` (inside, on the
/// `−z` side): the relative index across it as seen from `wo`'s side, the
/// refracted sine squared (at least 1 under total internal reflection) and
/// the Fresnel reflectance.
#[inline]
pub(super) fn dielectric_interface(ior: f32, wo: Vec3A) -> (f32, f32, f32) {
    let (eta, cos_o) = if wo.z > 0.0 {
        (ior, wo.z)
    } else {
        (1.0 / ior, -wo.z)
    };
    let cos_o = cos_o.min(1.0);
    let sin2_t = (1.0 - cos_o * cos_o) / (eta * eta);
    (eta, sin2_t, fresnel_dielectric(cos_o, eta))
}

/// The direction `wo` refracts to through a smooth dielectric interface (the
/// local `z = 0` plane), `eta` the index across it as seen from `wo`'s side
/// and `sin2_t < 1` the refracted sine squared.
#[inline]
pub(super) fn dielectric_refraction(wo: Vec3A, eta: f32, sin2_t: f32) -> Vec3A {
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // Snell: the tangential part shrinks by 1/eta, the normal part flips side.
    let side = wo.z.signum();
    Vec3A::new(-wo.x / eta, -wo.y / eta, -side * cos_t).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;
    use glam::Vec2;

    #[test]
    fn dielectric_total_internal_reflection_from_inside() {
        let ior = 1.5f32;
        let critical = (1.0 / ior).asin().to_degrees(); // 41.81°
        let m = Material::Dielectric { ior };
        for theta in [critical + 0.05, 50.0, 70.0, 89.0] {
            let wo = -dir(theta, 0.4); // inside: wo.z < 0
            assert!(wo.z < 0.0);
            assert_eq!(fresnel_dielectric(wo.z, ior), 1.0);
            for ul in [0.0, 0.5, 0.999_999] {
                let s = m.sample(wo, ul, Vec2::ZERO).unwrap();
                assert_eq!(s.pdf, 1.0);
                assert!(s.wi.z < 0.0, "TIR stays inside: {s:?}");
                assert!((s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
            }
        }
        // Just inside the critical angle, some light still escapes.
        let wo = -dir(critical - 0.5, 0.4);
        let s = m.sample(wo, 0.999, Vec2::ZERO).unwrap();
        assert!(s.wi.z > 0.0 && s.pdf > 0.0 && s.pdf < 1.0, "{s:?}");
    }

    #[test]
    fn dielectric_refraction_obeys_snell() {
        let mut worst = 0.0f32;
        for ior in [1.33f32, 1.5, 2.4] {
            let m = Material::Dielectric { ior };
            for theta in [0.0f32, 10.0, 30.0, 60.0, 85.0] {
                for (outside, wo) in [(true, dir(theta, 1.1)), (false, -dir(theta * 0.5, 1.1))] {
                    let Some(s) = m.sample(wo, 0.999_999, Vec2::ZERO) else {
                        panic!("no sample");
                    };
                    if s.wi.z * wo.z > 0.0 {
                        continue; // total internal reflection
                    }
                    let (n_o, n_i) = if outside { (1.0, ior) } else { (ior, 1.0) };
                    let sin_o = (wo.x * wo.x + wo.y * wo.y).sqrt();
                    let sin_i = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
                    assert!((s.wi.length() - 1.0).abs() < 1e-6);
                    assert!(
                        (n_o * sin_o - n_i * sin_i).abs() < 1e-5,
                        "Snell {ior} {theta}"
                    );
                    // In the plane of incidence, on the other side of the normal.
                    if sin_o > 1e-6 {
                        let c = wo.x * s.wi.y - wo.y * s.wi.x;
                        assert!(c.abs() < 1e-6 && wo.x * s.wi.x + wo.y * s.wi.y < 0.0);
                        worst = worst.max((sin_o / sin_i - n_i / n_o).abs());
                    }
                    assert!(s.pdf > 0.0 && s.weight == Vec3A::ONE);
                }
            }
        }
        eprintln!("Snell: worst |sin ratio − index ratio| {worst:e}");
    }

    #[test]
    fn dielectric_conserves_energy_at_normal_and_grazing_incidence() {
        let m = Material::Dielectric { ior: 1.5 };
        for theta in [0.0, 45.0, 85.0, 89.9] {
            for wo in [dir(theta, 0.2), -dir(theta * 0.4, 0.2)] {
                let f = fresnel_dielectric(wo.z, 1.5);
                // R + T: the two lobes' probabilities add to one and each weight
                // is 1, so the mean weight is exactly 1.
                let r = m.sample(wo, 0.0, Vec2::ZERO).unwrap();
                let t = m.sample(wo, 0.999_999, Vec2::ZERO).unwrap();
                assert_eq!(r.weight, Vec3A::ONE);
                assert_eq!(t.weight, Vec3A::ONE);
                if f < 1.0 {
                    assert!((r.pdf + t.pdf - 1.0).abs() < 1e-6 && r.wi != t.wi);
                }
                // The fraction reflected is F.
                let mut rg = rng(41);
                let n = 200_000;
                let mut reflected = 0usize;
                let mut total = 0.0f64;
                for _ in 0..n {
                    let s = m.sample(wo, rg.next_f32(), Vec2::ZERO).unwrap();
                    total += s.weight.x as f64;
                    reflected += (s.wi.z * wo.z > 0.0) as usize;
                }
                let frac = reflected as f64 / n as f64;
                let sigma = (f as f64 * (1.0 - f as f64) / n as f64).sqrt();
                assert_eq!(total / n as f64, 1.0);
                assert!(
                    (frac - f as f64).abs() < 5.0 * sigma + 1e-6,
                    "{frac} vs F {f}"
                );
            }
        }
        eprintln!("dielectric furnace: R + T = 1 (exact) at θ = 0°, 45°, 85°, 89.9°, both sides");
    }
}
