//! Mitsuba 3's `plastic`: a diffuse base under a smooth dielectric coating,
//! [`Plastic`].

use super::super::bsdf::{BsdfSample, GuideLobes, finite_or_zero};
use super::super::disk::concentric_disk;
use super::super::frame::{above, reflect_z};
use super::super::fresnel::{fresnel_diffuse_reflectance, fresnel_mitsuba};
use super::common::positive;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// Mitsuba's specular sampling weight `s / (d + s)` of the means `d` of the
/// diffuse and `s` of the specular reflectance (over the texture, or the
/// RGB channels of a constant). Both plastics take it.
pub fn specular_sampling_weight(diffuse_mean: f32, specular_mean: f32) -> f32 {
    specular_mean / (diffuse_mean + specular_mean)
}

/// The mean of a constant RGB reflectance as Mitsuba takes it (of its
/// channels).
#[inline]
pub(super) fn mean(v: Vec3A) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

/// The diffuse base's reflectance seen through a coating that reflects the
/// fraction `fdr` of the light inside back down: `ρ / (1 − F_dr)`, or with
/// `nonlinear` `ρ / (1 − ρ F_dr)` (Mitsuba's two models).
#[inline]
pub(super) fn base_reflectance(rho: Vec3A, fdr: f32, nonlinear: bool) -> Vec3A {
    if nonlinear {
        rho / (Vec3A::ONE - rho * fdr)
    } else {
        rho / (1.0 - fdr)
    }
}

/// Mitsuba's `plastic`: a smooth specular reflection `F(cos θo) ·
/// specular_reflectance` over a Lambertian base seen through the interface,
/// `f cos θi = ρ' cos θi / π · (1 − F(cos θo))(1 − F(cos θi)) / η²` with `ρ'`
/// the base's reflectance after its internal reflections
/// (`base_reflectance` with `F_dr(1/η)`). The specular lobe is chosen
/// with probability `F(cos θo) w / (F w + (1 − F)(1 − w))`, `w` the specular
/// sampling weight. One-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Relative index `int_ior / ext_ior` (default polypropylene in air, 1.49).
    pub eta: f32,
    /// The base's reflectance ρ (`diffuse_reflectance`, default 0.5).
    pub diffuse_reflectance: Vec3A,
    /// Tint of the specular reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Mitsuba's `nonlinear` (default false).
    pub nonlinear: bool,
    /// The probability weight of the specular lobe
    /// ([`specular_sampling_weight`]).
    pub specular_sampling_weight: f32,
    /// `F_dr(1/η)`, the internal diffuse reflectance of the coating.
    pub fdr_int: f32,
}

impl Plastic {
    /// The plastic of relative index `eta = int_ior / ext_ior`, base
    /// `diffuse_reflectance`, tint `specular_reflectance` and Mitsuba's
    /// `nonlinear`, with the specular sampling weight of these constants.
    /// For textured reflectances, set [`Plastic::specular_sampling_weight`]
    /// from the textures' means.
    pub fn new(
        eta: f32,
        diffuse_reflectance: Vec3A,
        specular_reflectance: Vec3A,
        nonlinear: bool,
    ) -> Self {
        Self {
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight: specular_sampling_weight(
                mean(diffuse_reflectance),
                mean(specular_reflectance),
            ),
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
        }
    }

    /// The probability of the specular lobe given `F(cos θo)`.
    #[inline]
    fn prob_specular(&self, f_o: f32) -> f32 {
        let w = self.specular_sampling_weight;
        let s = f_o * w;
        let d = (1.0 - f_o) * (1.0 - w);
        s / (s + d)
    }

    /// `ρ' (1 − F(cos θo)) / η²`, the diffuse lobe's factor before
    /// `(1 − F(cos θi)) cos θi / π`.
    #[inline]
    fn diffuse_factor(&self, f_o: f32) -> Vec3A {
        base_reflectance(self.diffuse_reflectance, self.fdr_int, self.nonlinear)
            * ((1.0 - f_o) / (self.eta * self.eta))
    }

    /// `f(wo, wi) cos θi` of the diffuse lobe (the specular one is a delta).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if !above(wo) || !above(wi) {
            return Vec3A::ZERO;
        }
        let f_o = fresnel_mitsuba(wo.z, self.eta).0;
        let f_i = fresnel_mitsuba(wi.z, self.eta).0;
        finite_or_zero(self.diffuse_factor(f_o) * ((1.0 - f_i) * wi.z * FRAC_1_PI))
    }

    /// The density of a diffuse sample: `(1 − P_spec) cos θi / π`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !above(wo) || !above(wi) {
            return 0.0;
        }
        let p = 1.0 - self.prob_specular(fresnel_mitsuba(wo.z, self.eta).0);
        let p = p * wi.z * FRAC_1_PI;
        if p.is_finite() { p } else { 0.0 }
    }

    /// The specular reflection (`u_lobe < P_spec`) or a cosine-distributed
    /// direction of the base.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if !above(wo) {
            return None;
        }
        let f_o = fresnel_mitsuba(wo.z, self.eta).0;
        let p_spec = self.prob_specular(f_o);
        if !p_spec.is_finite() {
            return None;
        }
        if u_lobe < p_spec {
            return Some(BsdfSample {
                wi: reflect_z(wo),
                weight: self.specular_reflectance * (f_o / p_spec),
                pdf: p_spec,
                specular: true,
            });
        }
        let p = concentric_disk(u);
        let wi = Vec3A::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt());
        let p_diff = 1.0 - p_spec;
        let pdf = p_diff * wi.z * FRAC_1_PI;
        if !positive(pdf) {
            return None;
        }
        let f_i = fresnel_mitsuba(wi.z, self.eta).0;
        let weight = self.diffuse_factor(f_o) * ((1.0 - f_i) / p_diff);
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
        })
    }

    /// The denoiser's guides: the specular reflection, and the base's albedo
    /// `ρ' (1 − F(cos θo)) (1 − F_dr(η)) / η²` as the rough part.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if !above(wo) {
            return GuideLobes::NONE;
        }
        let f_o = fresnel_mitsuba(wo.z, self.eta).0;
        GuideLobes {
            reflect: GuideLobes::lobe(reflect_z(wo), f_o * self.specular_reflectance),
            ..GuideLobes::rough(self.diffuse_albedo(f_o))
        }
    }

    /// The base's directional albedo given `F(cos θo)`.
    fn diffuse_albedo(&self, f_o: f32) -> Vec3A {
        self.diffuse_factor(f_o) * (1.0 - fresnel_diffuse_reflectance(self.eta))
    }

    /// The albedo guide at cosine `cos`: both lobes' albedo.
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let f_o = fresnel_mitsuba(cos, self.eta).0;
        f_o * self.specular_reflectance + self.diffuse_albedo(f_o)
    }
}
