//! Mitsuba 3's `conductor`: a smooth, one-sided metal with a complex index
//! of refraction per RGB channel, [`Conductor`].

use super::super::bsdf::{BsdfSample, GuideLobes};
use super::super::frame::{above, reflect_z};
use super::super::fresnel::fresnel_conductor;
use glam::Vec3A;

/// Mitsuba's `conductor`: perfect specular reflection scaled by the exact
/// conductor Fresnel term `F(cos θo; η + ik)` and `specular_reflectance`.
/// One-sided: nothing for `wo.z ≤ 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the relative complex index, per RGB channel (Mitsuba's
    /// `eta`; its default without a `material` is 0).
    pub eta: Vec3A,
    /// Imaginary part, per channel (Mitsuba's `k`, default 1).
    pub k: Vec3A,
    /// Tint (Mitsuba's `specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
}

impl Conductor {
    /// The conductor of complex index `eta + i k` tinted by
    /// `specular_reflectance` (Mitsuba's defaults: `eta` 0, `k` 1, tint 1).
    pub fn new(eta: Vec3A, k: Vec3A, specular_reflectance: Vec3A) -> Self {
        Self {
            eta,
            k,
            specular_reflectance,
        }
    }

    /// The reflectance at cosine `cos`: `F · specular_reflectance`.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> Vec3A {
        fresnel_conductor(cos, self.eta, self.k) * self.specular_reflectance
    }

    /// The mirror direction with weight `F(cos θo) · specular_reflectance`.
    #[inline]
    pub fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        if !above(wo) {
            return None;
        }
        Some(BsdfSample {
            wi: reflect_z(wo),
            weight: self.reflectance(wo.z),
            pdf: 1.0,
            specular: true,
        })
    }

    /// The denoiser's guides: one specular reflection.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if !above(wo) {
            return GuideLobes::NONE;
        }
        GuideLobes {
            reflect: GuideLobes::lobe(reflect_z(wo), self.reflectance(wo.z)),
            ..GuideLobes::NONE
        }
    }
}
