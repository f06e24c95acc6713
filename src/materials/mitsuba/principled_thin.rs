//! Mitsuba 3's `principledthin`: the Disney BSDF of a thin sheet (Burley
//! 2015), as Mitsuba defines it, [`PrincipledThin`].

use super::super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::super::frame::{Frame, reflect_z};
use super::super::fresnel::fresnel_mitsuba;
use super::super::microfacet::{MicrofacetDistribution, MicrofacetKind};
use super::common::{Tangent, positive};
use super::principled::PrincipledParam;
use super::principled_common::{
    Diffuse, agrees, cosine_hemisphere, mulsign, normalize, orient, reflect, sample_of, schlick,
    schlick_r0, tint, widths,
};
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// Mitsuba's `principledthin`: a sheet with no inside, the same from both
/// sides (both directions are turned so that `wo` is on top). With `t =
/// spec_trans`, `d = diff_trans / 2`, `F` the dielectric Fresnel term of
/// `eta` at `wo·m` (always entering), `m ∝ wo + wi'` the half vector of
/// `wo` and `wi` mirrored to `wo`'s side (`wi'`):
///
/// * specular reflection: `t F_t D G / (4 cos θo)`, `F_t = lerp(F,
///   Schlick(tint · R0(η)), spec_tint)`, with [`super::Principled`]'s GGX
///   of `roughness` and `anisotropic`;
/// * specular transmission (the reflection turned through the sheet):
///   `t base_color (1 − F) D' G' / (4 cos θo)` with the GGX of roughness
///   scaled by `0.65 η − 0.35` (Burley 2015, figure 15);
/// * [`super::Principled`]'s diffuse, retro reflection, fake subsurface
///   and sheen, weighted by `(1 − t)(1 − d)` (instead of `w_brdf` and
///   `1 − metallic`);
/// * Lambertian transmission `(1 − t) d base_color / π |cos θi|`.
///
/// (No `metallic`, `clearcoat` or radiance scaling: the sheet has the same
/// medium on both sides.) Sampling is Mitsuba's: the lobes with
/// probabilities `t s_r / 2`, `t s_t / 2`, `(1 − t)(1 − d) s_d` and
/// `(1 − t) d s_dt` (`s` the sampling rates), visible GGX normals for the
/// specular ones, cosine-distributed directions for the diffuse ones; the
/// density is the mixture and the weight eval / pdf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    /// `base_color` (default 0.5).
    pub base_color: Vec3A,
    /// `roughness` (default 0.5).
    pub roughness: f32,
    /// `anisotropic` (default 0).
    pub anisotropic: f32,
    /// `spec_trans` (default 0).
    pub spec_trans: f32,
    /// `eta`, the sheet's relative index (default 1.5).
    pub eta: f32,
    /// `spec_tint` (default 0).
    pub spec_tint: f32,
    /// `sheen` (default 0).
    pub sheen: f32,
    /// `sheen_tint` (default 0).
    pub sheen_tint: f32,
    /// `flatness` (default 0).
    pub flatness: f32,
    /// `diff_trans` as Mitsuba takes it, in `[0, 2]` (default 0); the
    /// diffuse transmission's share is half of it.
    pub diff_trans: f32,
    /// `specular_reflectance_sampling_rate` (default 1).
    pub specular_reflectance_sampling_rate: f32,
    /// `specular_transmittance_sampling_rate` (default 1).
    pub specular_transmittance_sampling_rate: f32,
    /// `diffuse_reflectance_sampling_rate` (default 1).
    pub diffuse_reflectance_sampling_rate: f32,
    /// `diffuse_transmittance_sampling_rate` (default 1).
    pub diffuse_transmittance_sampling_rate: f32,
    /// Where `α_u`'s axis lies in the shading frame.
    pub tangent: Tangent,
}

impl Default for PrincipledThin {
    /// Mitsuba's defaults.
    fn default() -> Self {
        Self {
            base_color: Vec3A::splat(0.5),
            roughness: 0.5,
            anisotropic: 0.0,
            spec_trans: 0.0,
            eta: 1.5,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            diff_trans: 0.0,
            specular_reflectance_sampling_rate: 1.0,
            specular_transmittance_sampling_rate: 1.0,
            diffuse_reflectance_sampling_rate: 1.0,
            diffuse_transmittance_sampling_rate: 1.0,
            tangent: Tangent::X,
        }
    }
}

/// The lobes' probabilities, normalised.
struct Probs {
    spec_reflect: f32,
    spec_transmit: f32,
    diffuse_reflect: f32,
    diffuse_transmit: f32,
}

impl PrincipledThin {
    /// Sets the scalar parameter `p` to `v`; false (and nothing changed)
    /// if `p` is not one of `principledthin`'s (`Metallic`, `Clearcoat`,
    /// `ClearcoatGloss`).
    #[inline]
    pub fn set(&mut self, p: PrincipledParam, v: f32) -> bool {
        use PrincipledParam::*;
        let field = match p {
            Roughness => &mut self.roughness,
            Anisotropic => &mut self.anisotropic,
            SpecTrans => &mut self.spec_trans,
            SpecTint => &mut self.spec_tint,
            Sheen => &mut self.sheen,
            SheenTint => &mut self.sheen_tint,
            Flatness => &mut self.flatness,
            DiffTrans => &mut self.diff_trans,
            Eta => &mut self.eta,
            Metallic | Clearcoat | ClearcoatGloss => return false,
        };
        *field = v;
        true
    }

    /// Points `α_u`'s axis along the world tangent `t` (Mitsuba's `dp/du`);
    /// nothing when isotropic (set `anisotropic` first).
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A) {
        orient(&mut self.tangent, self.anisotropic, frame, t);
    }

    /// Whether light passes through (specular or diffuse transmission).
    #[inline]
    pub fn transmits(&self) -> bool {
        self.spec_trans > 0.0 || self.diff_trans > 0.0
    }

    /// The diffuse transmission's share, `diff_trans / 2`.
    #[inline]
    fn d(&self) -> f32 {
        self.diff_trans / 2.0
    }

    /// The specular reflection's GGX.
    #[inline]
    fn reflect_distribution(&self) -> MicrofacetDistribution {
        let (au, av) = widths(self.roughness, self.anisotropic);
        MicrofacetDistribution::new(MicrofacetKind::Ggx, au, av)
    }

    /// The specular transmission's GGX, of roughness scaled by
    /// `0.65 η − 0.35`.
    #[inline]
    fn transmit_distribution(&self) -> MicrofacetDistribution {
        let (au, av) = widths((0.65 * self.eta - 0.35) * self.roughness, self.anisotropic);
        MicrofacetDistribution::new(MicrofacetKind::Ggx, au, av)
    }

    /// The lobes' probabilities.
    #[inline]
    fn probs(&self) -> Probs {
        let (t, d) = (self.spec_trans, self.d());
        let sr = t * self.specular_reflectance_sampling_rate / 2.0;
        let st = t * self.specular_transmittance_sampling_rate / 2.0;
        let dr = self.diffuse_reflectance_sampling_rate * (1.0 - t) * (1.0 - d);
        let dt = self.diffuse_transmittance_sampling_rate * (1.0 - t) * d;
        let rcp = 1.0 / (sr + st + dr + dt);
        Probs {
            spec_reflect: sr * rcp,
            spec_transmit: st * rcp,
            diffuse_reflect: dr * rcp,
            diffuse_transmit: dt * rcp,
        }
    }

    /// `wo` and `wi` turned so that `wo` is on top, `wi` mirrored to the
    /// top, and their half vector; `None` for a grazing `wo`.
    #[inline]
    fn turned(wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, Vec3A, Vec3A)> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let (wo_t, wi_t) = (mulsign(wo, wo.z), mulsign(wi, wo.z));
        let wi_r = Vec3A::new(wi_t.x, wi_t.y, wi_t.z.abs());
        Some((wo_t, wi_t, normalize(wo_t + wi_r)))
    }

    /// `f(wo, wi) |cos θi|`.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        self.eval_local(wo, wi)
    }

    /// [`PrincipledThin::eval`] in the BSDF's frame.
    fn eval_local(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let Some((wo, wi, m)) = Self::turned(wo, wi) else {
            return Vec3A::ZERO;
        };
        let (cos_o, cos_i) = (wo.z, wi.z);
        let (reflect, transmit) = (cos_i > 0.0, cos_i < 0.0);
        let (t, d) = (self.spec_trans, self.d());
        let mut v = Vec3A::ZERO;
        if t > 0.0 {
            let f = fresnel_mitsuba(wo.dot(m), self.eta).0;
            if reflect && agrees(m, wo, wi, cos_o, true) {
                let distr = self.reflect_distribution();
                let ft = if self.spec_tint != 0.0 {
                    let f0 = tint(self.base_color) * schlick_r0(self.eta);
                    let s = schlick(f0, wo.dot(m), self.eta);
                    s * self.spec_tint + Vec3A::splat(f - f * self.spec_tint)
                } else {
                    Vec3A::splat(f)
                };
                v += ft * (t * distr.d(m) * distr.g(wo, wi, m) / (4.0 * cos_o));
            }
            if transmit && agrees(m, wo, wi, cos_o, false) {
                let distr = self.transmit_distribution();
                v += self.base_color
                    * (t * (1.0 - f) * distr.d(m) * distr.g(wo, wi, m) / (4.0 * cos_o));
            }
        }
        if reflect && t < 1.0 && d < 1.0 {
            let lobes = Diffuse {
                base_color: self.base_color,
                roughness: self.roughness,
                flatness: self.flatness,
                sheen: self.sheen,
                sheen_tint: self.sheen_tint,
            };
            let (diffuse, sheen) = lobes.eval(cos_o, cos_i.abs(), m.dot(wi));
            v += diffuse * ((1.0 - t) * cos_i * (1.0 - d));
            v += sheen * ((1.0 - t) * (1.0 - d) * cos_i.abs());
        }
        if transmit && t < 1.0 && d > 0.0 {
            v += self.base_color * ((1.0 - t) * d * FRAC_1_PI * cos_i.abs());
        }
        finite_or_zero(v)
    }

    /// The density of [`PrincipledThin::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        self.pdf_local(wo, wi)
    }

    /// [`PrincipledThin::pdf`] in the BSDF's frame.
    fn pdf_local(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let Some((wo, wi, m)) = Self::turned(wo, wi) else {
            return 0.0;
        };
        let cos_i = wi.z;
        let (reflect, transmit) = (cos_i > 0.0, cos_i < 0.0);
        let p = self.probs();
        let mut pdf = 0.0;
        if self.spec_trans > 0.0 {
            let wi_r = Vec3A::new(wi.x, wi.y, wi.z.abs());
            let jacobian = (1.0 / (4.0 * wi_r.dot(m))).abs();
            if reflect && p.spec_reflect > 0.0 && agrees(m, wo, wi, wo.z, true) {
                pdf += p.spec_reflect * self.reflect_distribution().pdf(wo, m) * jacobian;
            }
            if transmit && p.spec_transmit > 0.0 && agrees(m, wo, wi, wo.z, false) {
                pdf += p.spec_transmit * self.transmit_distribution().pdf(wo, m) * jacobian;
            }
        }
        if reflect && p.diffuse_reflect > 0.0 {
            pdf += p.diffuse_reflect * (FRAC_1_PI * cos_i);
        }
        if transmit && p.diffuse_transmit > 0.0 {
            pdf += p.diffuse_transmit * (FRAC_1_PI * -cos_i);
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Chooses a lobe with `u_lobe` and draws its direction with `u`
    /// (visible normals for the specular lobes, cosine-distributed
    /// directions for the diffuse ones); weight = eval / pdf.
    #[inline]
    pub fn sample(&self, wo_s: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let wo_l = self.tangent.to_local(wo_s);
        let cos_o = wo_l.z;
        if cos_o == 0.0 || !wo_l.is_finite() {
            return None;
        }
        let wo = mulsign(wo_l, cos_o);
        let p = self.probs();
        let after_transmit = p.spec_reflect + p.spec_transmit;
        let wi = if u_lobe < p.spec_reflect {
            let m = self.reflect_distribution().sample(wo, u).0;
            let wi = reflect(wo, m);
            if !(wi.z > 0.0 && agrees(m, wo, wi, wo.z, true)) {
                return None;
            }
            wi
        } else if u_lobe < after_transmit {
            let m = self.transmit_distribution().sample(wo, u).0;
            let r = reflect(wo, m);
            let wi = Vec3A::new(r.x, r.y, -r.z);
            if !(wi.z < 0.0 && agrees(m, wo, wi, wo.z, false)) {
                return None;
            }
            wi
        } else if u_lobe < after_transmit + p.diffuse_reflect {
            cosine_hemisphere(u)
        } else if self.d() > 0.0 {
            -cosine_hemisphere(u)
        } else {
            return None;
        };
        let wi = mulsign(wi, cos_o);
        if !wi.is_finite() {
            return None;
        }
        sample_of(self.tangent, wi, self.pdf_local(wo_l, wi), || {
            self.eval_local(wo_l, wi)
        })
    }

    /// The albedo guide at cosine `cos`: the specular lobes'
    /// `t (F + (1 − F) base_color)` and the diffuse ones'
    /// `(1 − t) base_color` (`F` at the macro normal).
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let f = fresnel_mitsuba(cos.abs(), self.eta).0;
        let t = self.spec_trans;
        Vec3A::splat(t * f) + self.base_color * (t * (1.0 - f) + (1.0 - t))
    }

    /// The denoiser's guides: the mirror reflection and the straight
    /// transmission when both specular lobes' widths are at most
    /// [`GUIDE_ALPHA`], the rest (or everything) rough.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if wo.z == 0.0 || !wo.is_finite() {
            return GuideLobes::NONE;
        }
        let all = self.albedo(wo.z);
        let (ru, rv) = widths(self.roughness, self.anisotropic);
        let (tu, tv) = widths((0.65 * self.eta - 0.35) * self.roughness, self.anisotropic);
        if ru.max(rv).max(tu).max(tv) > GUIDE_ALPHA || !positive(self.spec_trans) {
            return GuideLobes::rough(all);
        }
        let t = self.spec_trans;
        let f = fresnel_mitsuba(wo.z.abs(), self.eta).0;
        let reflected = Vec3A::splat(t * f);
        let transmitted = self.base_color * (t * (1.0 - f));
        GuideLobes {
            reflect: GuideLobes::lobe(reflect_z(wo), reflected),
            transmit: GuideLobes::lobe(-wo, transmitted),
            ..GuideLobes::rough(all - reflected - transmitted)
        }
    }
}
