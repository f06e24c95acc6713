//! Mitsuba 3's `roughdielectric`: a rough interface between two
//! dielectrics (Walter et al. 2007), Beckmann or GGX, isotropic or
//! anisotropic, [`RoughDielectric`].

use super::super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::super::frame::{Frame, reflect_z};
use super::super::fresnel::fresnel_mitsuba;
use super::super::microfacet::{MicrofacetDistribution, MicrofacetKind};
use super::common::Tangent;
use super::common::positive;
use glam::{Vec2, Vec3A};

/// Mitsuba's `roughdielectric`. With `η` the relative index seen from `wo`'s
/// side (`eta` outside, `1/eta` inside) and the generalised half vector
/// `m ∝ wo + wi` (reflection) or `wo + η wi` (refraction), turned to `+z`:
///
/// * reflection: `f cos θi = F D G / (4 |cos θo|) · specular_reflectance`;
/// * refraction: `f cos θi = |(1 − F) D G (wo·m)(wi·m) / (cos θo (wo·m + η wi·m)²)|
///   · specular_transmittance`, Walter's `η²` cancelled by the radiance
///   scaling `1/η²` (see [the module documentation](super)),
///
/// `G = G1(wo, m) G1(wi, m)` separable and `F = F(wo·m)`. Sampling is
/// Mitsuba's: a normal visible from `wo` (mirrored to the top when
/// `wo.z < 0`), then reflection with probability `F(wo·m)`, refraction
/// otherwise; the density is the normal's times that probability times the
/// Jacobian of the half vector. (Mitsuba scales alpha while sampling only
/// when `sample_visible` is off, which is not supported here.) Two-sided:
/// `+z` is the outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// The microfacets (defaults: Beckmann, 0.1).
    pub distribution: MicrofacetDistribution,
    /// Relative index `int_ior / ext_ior` (must differ from 1).
    pub eta: f32,
    /// Tint of the reflection (`specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Tint of the refraction (`specular_transmittance`, default 1).
    pub specular_transmittance: Vec3A,
    /// Where `alpha_u`'s axis lies in the shading frame.
    pub tangent: Tangent,
}

/// What eval, pdf and sample share for one pair of directions (in the
/// BSDF's frame).
struct Half {
    /// The half vector, on the `+z` side.
    m: Vec3A,
    /// Whether `wi` is on `wo`'s side.
    reflect: bool,
    /// The relative index seen from `wo`'s side.
    eta: f32,
}

impl RoughDielectric {
    /// The rough interface of microfacets `kind` with widths `alpha_u`,
    /// `alpha_v`, relative index `eta = int_ior / ext_ior` and the two
    /// tints.
    pub fn new(
        kind: MicrofacetKind,
        alpha_u: f32,
        alpha_v: f32,
        eta: f32,
        specular_reflectance: Vec3A,
        specular_transmittance: Vec3A,
    ) -> Self {
        Self {
            distribution: MicrofacetDistribution::new(kind, alpha_u, alpha_v),
            eta,
            specular_reflectance,
            specular_transmittance,
            tangent: Tangent::X,
        }
    }

    /// Points `alpha_u`'s axis along the world tangent `t`; nothing when
    /// isotropic.
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A) {
        if !self.distribution.is_isotropic() {
            self.tangent = Tangent::orient(frame, t);
        }
    }

    /// The half vector of `wo` and `wi` (BSDF frame).
    #[inline]
    fn half(&self, wo: Vec3A, wi: Vec3A) -> Option<Half> {
        if wo.z == 0.0 || !positive(self.eta) {
            return None;
        }
        let reflect = wo.z * wi.z > 0.0;
        let eta = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = (wo + wi * if reflect { 1.0 } else { eta }).normalize();
        let m = if m.z.is_sign_negative() { -m } else { m };
        m.is_finite().then_some(Half { m, reflect, eta })
    }

    /// `f(wo, wi) |cos θi|`.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        let Some(Half { m, reflect, eta }) = self.half(wo, wi) else {
            return Vec3A::ZERO;
        };
        let distr = &self.distribution;
        let d = distr.d(m);
        let g = distr.g(wo, wi, m);
        let (om, im) = (wo.dot(m), wi.dot(m));
        let f = fresnel_mitsuba(om, self.eta).0;
        let v = if reflect {
            self.specular_reflectance * (f * d * g / (4.0 * wo.z.abs()))
        } else {
            let den = om + eta * im;
            self.specular_transmittance * ((1.0 - f) * d * g * om * im / (wo.z * den * den)).abs()
        };
        finite_or_zero(v)
    }

    /// The density of [`RoughDielectric::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        self.pdf_local(wo, wi)
    }

    /// [`RoughDielectric::pdf`] in the BSDF's frame.
    #[inline]
    fn pdf_local(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let Some(Half { m, reflect, eta }) = self.half(wo, wi) else {
            return 0.0;
        };
        let (om, im) = (wo.dot(m), wi.dot(m));
        if !(om * wo.z > 0.0 && im * wi.z > 0.0) {
            return 0.0;
        }
        let jacobian = if reflect {
            1.0 / (4.0 * im)
        } else {
            let den = om + eta * im;
            eta * eta * im / (den * den)
        };
        let wo_top = if wo.z < 0.0 { -wo } else { wo };
        let f = fresnel_mitsuba(om, self.eta).0;
        let lobe = if reflect { f } else { 1.0 - f };
        let p = self.distribution.pdf(wo_top, m) * lobe * jacobian.abs();
        if p.is_finite() { p } else { 0.0 }
    }

    /// Draws a visible normal with `u`, then reflects (`u_lobe ≤ F`) or
    /// refracts about it.
    #[inline]
    pub fn sample(&self, wo_s: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo_s.z == 0.0 || !wo_s.is_finite() || !positive(self.eta) {
            return None;
        }
        let wo = self.tangent.to_local(wo_s);
        let wo_top = if wo.z < 0.0 { -wo } else { wo };
        let distr = &self.distribution;
        let (m, pdf_m) = distr.sample(wo_top, u);
        if !positive(pdf_m) {
            return None;
        }
        let om = wo.dot(m);
        let (f, cos_t, _, eta_ti) = fresnel_mitsuba(om, self.eta);
        let reflect = (u_lobe <= f && f > 0.0) || f >= 1.0;
        let wi = if reflect {
            (2.0 * om) * m - wo
        } else {
            m * (om * eta_ti + cos_t) - wo * eta_ti
        };
        // A direction on the wrong side has G1(wi, m) = 0 (Mitsuba's weight
        // is 0 there).
        if reflect != (wi.z * wo.z > 0.0) || wi.z == 0.0 || !wi.is_finite() {
            return None;
        }
        // Density and weight at the half vector that pdf() and eval() find
        // again: weight = f cos / pdf = G1(wi, m) (/ η² refracted) · tint.
        let Half { m, eta, .. } = self.half(wo, wi)?;
        let pdf = self.pdf_local(wo, wi);
        let g1 = distr.g1(wi, m);
        let weight = if reflect {
            self.specular_reflectance * g1
        } else {
            self.specular_transmittance * (g1 / (eta * eta))
        };
        if !positive(pdf) || !weight.is_finite() || g1 <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: self.tangent.to_shading(wi),
            weight,
            pdf,
            specular: false,
        })
    }

    /// The denoiser's guides: the mirror reflection and the refraction of
    /// the smooth interface when both widths are at most [`GUIDE_ALPHA`],
    /// else one rough lobe of the tinted `F R + (1 − F) T`.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if wo.z == 0.0 || !wo.is_finite() || !positive(self.eta) {
            return GuideLobes::NONE;
        }
        let d = &self.distribution;
        let (r, cos_t, _, eta_ti) = fresnel_mitsuba(wo.z, self.eta);
        if d.alpha_u.max(d.alpha_v) > GUIDE_ALPHA {
            return GuideLobes::rough(
                r * self.specular_reflectance + (1.0 - r) * self.specular_transmittance,
            );
        }
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
