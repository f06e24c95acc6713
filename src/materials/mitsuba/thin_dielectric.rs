//! Mitsuba 3's `thindielectric`: a thin dielectric sheet, [`ThinDielectric`].

use super::super::bsdf::{BsdfSample, GuideLobes};
use super::super::frame::reflect_z;
use super::super::fresnel::fresnel_mitsuba;
use super::common::positive;
use glam::Vec3A;

/// Mitsuba's `thindielectric`: a sheet whose two faces reflect back and
/// forth without absorbing, so that it reflects `R = 2F / (1 + F)` (the sum
/// of the inter-reflections, `F = F(|cos θo|)`) and lets the rest through
/// along `−wo`, undeviated. Reflect with probability `R`, pass otherwise;
/// the weights are the tints. Two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// Relative index `int_ior / ext_ior` (default BK7 in air).
    pub eta: f32,
    /// Tint of the reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Tint of the transmission (`specular_transmittance`, default 1).
    pub specular_transmittance: Vec3A,
}

impl ThinDielectric {
    /// The sheet of relative index `eta = int_ior / ext_ior` with the two
    /// tints.
    pub fn new(eta: f32, specular_reflectance: Vec3A, specular_transmittance: Vec3A) -> Self {
        Self {
            eta,
            specular_reflectance,
            specular_transmittance,
        }
    }

    /// The sheet's reflectance `2F / (1 + F)` at `wo`.
    #[inline]
    fn reflectance(&self, wo: Vec3A) -> f32 {
        let f = fresnel_mitsuba(wo.z.abs(), self.eta).0;
        f * (2.0 / (1.0 + f))
    }

    /// What passes straight through at `|cos θ| = cos` (Mitsuba's
    /// `eval_null_transmission`, which its `volpath` weighs shadow rays by):
    /// `(1 − R) · specular_transmittance`.
    #[inline]
    pub fn null_transmission(&self, cos: f32) -> Vec3A {
        if !positive(self.eta) {
            return Vec3A::ZERO;
        }
        (1.0 - self.reflectance(Vec3A::new(0.0, 0.0, cos))) * self.specular_transmittance
    }

    /// Reflects (`u_lobe ≤ R`) or passes straight through.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() || !positive(self.eta) {
            return None;
        }
        let r = self.reflectance(wo);
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
            wi: -wo,
            weight: self.specular_transmittance,
            pdf: t,
            specular: true,
        })
    }

    /// The denoiser's guides: the reflection and the straight transmission.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if wo.z == 0.0 || !wo.is_finite() || !positive(self.eta) {
            return GuideLobes::NONE;
        }
        let r = self.reflectance(wo);
        GuideLobes {
            rough: Vec3A::ZERO,
            reflect: GuideLobes::lobe(reflect_z(wo), r * self.specular_reflectance),
            transmit: GuideLobes::lobe(-wo, (1.0 - r) * self.specular_transmittance),
        }
    }

    /// The albedo guide at cosine `cos`: `R · reflectance + (1 − R) · transmittance`.
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let r = self.reflectance(Vec3A::new(0.0, 0.0, cos));
        r * self.specular_reflectance + (1.0 - r) * self.specular_transmittance
    }
}
