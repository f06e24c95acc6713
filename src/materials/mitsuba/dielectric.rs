//! Mitsuba 3's `dielectric`: a smooth interface between two dielectrics,
//! [`SmoothDielectric`].

use super::super::bsdf::{BsdfSample, GuideLobes};
use super::super::frame::reflect_z;
use super::super::fresnel::fresnel_mitsuba;
use super::common::positive;
use glam::Vec3A;

/// Mitsuba's `dielectric`: reflection with probability `F`, refraction
/// otherwise (Mitsuba's sampling); the reflected weight is
/// `specular_reflectance`, the refracted one `specular_transmittance / η²`
/// with `η` the relative index in the direction the path travels (see [the
/// module documentation](super) on radiance scaling). Two-sided: `+z` is
/// the outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothDielectric {
    /// Relative index `int_ior / ext_ior` (Mitsuba's defaults: BK7 in air,
    /// 1.5046).
    pub eta: f32,
    /// Tint of the reflection (Mitsuba's `specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Tint of the refraction (`specular_transmittance`, default 1).
    pub specular_transmittance: Vec3A,
}

impl SmoothDielectric {
    /// The interface of relative index `eta = int_ior / ext_ior` with the
    /// two tints.
    pub fn new(eta: f32, specular_reflectance: Vec3A, specular_transmittance: Vec3A) -> Self {
        Self {
            eta,
            specular_reflectance,
            specular_transmittance,
        }
    }

    /// Reflects (`u_lobe ≤ F`) or refracts `wo`.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() || !positive(self.eta) {
            return None;
        }
        let (r, cos_t, _, eta_ti) = fresnel_mitsuba(wo.z, self.eta);
        let t = 1.0 - r;
        if (u_lobe <= r && r > 0.0) || t <= 0.0 {
            return Some(BsdfSample {
                wi: reflect_z(wo),
                weight: self.specular_reflectance,
                pdf: r,
                specular: true,
            });
        }
        Some(BsdfSample {
            wi: Vec3A::new(-eta_ti * wo.x, -eta_ti * wo.y, cos_t),
            weight: self.specular_transmittance * (eta_ti * eta_ti),
            pdf: t,
            specular: true,
        })
    }

    /// The denoiser's guides: the reflection and the refraction, with their
    /// tinted Fresnel terms.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if wo.z == 0.0 || !wo.is_finite() || !positive(self.eta) {
            return GuideLobes::NONE;
        }
        let (r, cos_t, _, eta_ti) = fresnel_mitsuba(wo.z, self.eta);
        let transmit = (r < 1.0)
            .then(|| Vec3A::new(-eta_ti * wo.x, -eta_ti * wo.y, cos_t))
            .and_then(|wi| GuideLobes::lobe(wi, (1.0 - r) * self.specular_transmittance));
        GuideLobes {
            rough: Vec3A::ZERO,
            reflect: GuideLobes::lobe(reflect_z(wo), r * self.specular_reflectance),
            transmit,
        }
    }

    /// The albedo guide at cosine `cos` (outside): `F R + (1 − F) T`.
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let r = fresnel_mitsuba(cos, self.eta).0;
        r * self.specular_reflectance + (1.0 - r) * self.specular_transmittance
    }
}
