//! Mitsuba 3's `roughconductor`: a one-sided rough metal, Beckmann or GGX
//! microfacets (isotropic or anisotropic) with separable Smith masking and
//! the exact conductor Fresnel term, [`RoughConductor`].

use super::super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::super::frame::{Frame, above, reflect_z};
use super::super::fresnel::fresnel_conductor;
use super::super::microfacet::{MicrofacetDistribution, MicrofacetKind};
use super::common::Tangent;
use super::common::positive;
use glam::{Vec2, Vec3A};

/// Mitsuba's `roughconductor`:
/// `f cos θi = F(wo·h) D(h) G1(wo, h) G1(wi, h) / (4 cos θo) · specular_reflectance`,
/// sampled by the visible normals (`pdf = D(h) G1(wo, h) / (4 cos θo)`, so
/// the weight is `F G1(wi, h) · specular_reflectance`). One-sided: zero
/// unless both `wo.z > 0` and `wi.z > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// The microfacets (Mitsuba's `distribution`, `alpha` or
    /// `alpha_u`/`alpha_v`; its defaults are Beckmann, 0.1).
    pub distribution: MicrofacetDistribution,
    /// Real part of the relative complex index, per RGB channel.
    pub eta: Vec3A,
    /// Imaginary part, per channel.
    pub k: Vec3A,
    /// Tint (Mitsuba's `specular_reflectance`, default 1).
    pub specular_reflectance: Vec3A,
    /// Where `alpha_u`'s axis lies in the shading frame
    /// ([`RoughConductor::orient_anisotropy`]).
    pub tangent: Tangent,
}

impl RoughConductor {
    /// The rough conductor of microfacets `kind` with widths `alpha_u` along
    /// the tangent and `alpha_v` along the bitangent (equal: isotropic),
    /// complex index `eta + i k` and tint `specular_reflectance`.
    pub fn new(
        kind: MicrofacetKind,
        alpha_u: f32,
        alpha_v: f32,
        eta: Vec3A,
        k: Vec3A,
        specular_reflectance: Vec3A,
    ) -> Self {
        Self {
            distribution: MicrofacetDistribution::new(kind, alpha_u, alpha_v),
            eta,
            k,
            specular_reflectance,
            tangent: Tangent::X,
        }
    }

    /// Points `alpha_u`'s axis along the world tangent `t` (Mitsuba's
    /// `dp/du`), given the shading frame; nothing when isotropic.
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A) {
        if !self.distribution.is_isotropic() {
            self.tangent = Tangent::orient(frame, t);
        }
    }

    /// `f(wo, wi) cos θi`.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if !above(wo) || !above(wi) {
            return Vec3A::ZERO;
        }
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        let h = (wo + wi).normalize();
        let distr = &self.distribution;
        let d = distr.d(h);
        if d == 0.0 {
            return Vec3A::ZERO;
        }
        let g = distr.g(wo, wi, h);
        let f = fresnel_conductor(wo.dot(h), self.eta, self.k) * self.specular_reflectance;
        finite_or_zero(f * (d * g / (4.0 * wo.z)))
    }

    /// The density of [`RoughConductor::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !above(wo) || !above(wi) {
            return 0.0;
        }
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        let h = (wo + wi).normalize();
        if !(wo.dot(h) > 0.0 && wi.dot(h) > 0.0) {
            return 0.0;
        }
        let distr = &self.distribution;
        let p = distr.d(h) * distr.g1(wo, h) / (4.0 * wo.z);
        if p.is_finite() { p } else { 0.0 }
    }

    /// Reflects `wo` about a visible normal drawn with `u`.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if !above(wo) {
            return None;
        }
        let distr = &self.distribution;
        let wo_l = self.tangent.to_local(wo);
        let (m, pdf_m) = distr.sample(wo_l, u);
        if !positive(pdf_m) {
            return None;
        }
        let wi_l = (2.0 * wo_l.dot(m)) * m - wo_l;
        if !above(wi_l) {
            return None;
        }
        // The half vector as eval() and pdf() find it again, so that the
        // pdf equals pdf(wo, wi) and the weight eval / pdf.
        let h = (wo_l + wi_l).normalize();
        if !(wo_l.dot(h) > 0.0 && wi_l.dot(h) > 0.0) {
            return None;
        }
        let pdf = distr.d(h) * distr.g1(wo_l, h) / (4.0 * wo_l.z);
        let weight = fresnel_conductor(wo_l.dot(h), self.eta, self.k)
            * self.specular_reflectance
            * distr.g1(wi_l, h);
        if !positive(pdf) || !pdf.is_finite() || !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: self.tangent.to_shading(wi_l),
            weight,
            pdf,
            specular: false,
        })
    }

    /// The albedo guide: the tint `F(cos) · specular_reflectance`.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> Vec3A {
        fresnel_conductor(cos, self.eta, self.k) * self.specular_reflectance
    }

    /// The denoiser's guides: a specular reflection when both widths are at
    /// most [`GUIDE_ALPHA`], else a rough lobe.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if !above(wo) {
            return GuideLobes::NONE;
        }
        let r = self.reflectance(wo.z);
        let d = &self.distribution;
        if d.alpha_u.max(d.alpha_v) <= GUIDE_ALPHA {
            GuideLobes {
                reflect: GuideLobes::lobe(reflect_z(wo), r),
                ..GuideLobes::NONE
            }
        } else {
            GuideLobes::rough(r)
        }
    }
}
