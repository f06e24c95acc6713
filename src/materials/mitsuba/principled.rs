//! Mitsuba 3's `principled`: Burley's Disney BSDF (2012, with the 2015
//! transmission) as Mitsuba defines it, [`Principled`], and the names of
//! the two principled BSDFs' scalar parameters, [`PrincipledParam`].

use super::super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::super::frame::{Frame, reflect_z};
use super::super::fresnel::fresnel_mitsuba;
use super::super::microfacet::{MicrofacetDistribution, MicrofacetKind};
use super::common::{Tangent, positive};
use super::principled_common::{
    Diffuse, Gtr1, agrees, clearcoat_g, cosine_hemisphere, mulsign, normalize, orient, reflect,
    sample_of, schlick, schlick_r0, sqrt3, tint, widths,
};
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// A scalar parameter of [`Principled`] or [`super::PrincipledThin`], by
/// Mitsuba's name, for setting a textured value at each hit
/// ([`Principled::set`], [`super::PrincipledThin::set`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrincipledParam {
    /// `roughness`.
    Roughness,
    /// `anisotropic`.
    Anisotropic,
    /// `metallic` (`principled` only).
    Metallic,
    /// `spec_trans`.
    SpecTrans,
    /// `spec_tint`.
    SpecTint,
    /// `sheen`.
    Sheen,
    /// `sheen_tint`.
    SheenTint,
    /// `flatness`.
    Flatness,
    /// `clearcoat` (`principled` only).
    Clearcoat,
    /// `clearcoat_gloss` (`principled` only).
    ClearcoatGloss,
    /// `diff_trans`, in `[0, 2]` as Mitsuba takes it (`principledthin` only).
    DiffTrans,
    /// `eta` (a texture only in `principledthin`; `principled`'s is a float).
    Eta,
}

impl PrincipledParam {
    /// Every parameter.
    pub const ALL: [PrincipledParam; 12] = {
        use PrincipledParam::*;
        [
            Roughness,
            Anisotropic,
            Metallic,
            SpecTrans,
            SpecTint,
            Sheen,
            SheenTint,
            Flatness,
            Clearcoat,
            ClearcoatGloss,
            DiffTrans,
            Eta,
        ]
    };

    /// Mitsuba's name of the parameter.
    pub fn name(self) -> &'static str {
        use PrincipledParam::*;
        match self {
            Roughness => "roughness",
            Anisotropic => "anisotropic",
            Metallic => "metallic",
            SpecTrans => "spec_trans",
            SpecTint => "spec_tint",
            Sheen => "sheen",
            SheenTint => "sheen_tint",
            Flatness => "flatness",
            Clearcoat => "clearcoat",
            ClearcoatGloss => "clearcoat_gloss",
            DiffTrans => "diff_trans",
            Eta => "eta",
        }
    }
}

/// Mitsuba's `principled`. Its lobes, with weights `w_brdf = (1 − metallic)
/// (1 − spec_trans)` and `w_bsdf = (1 − metallic) spec_trans`, `F` the
/// dielectric Fresnel term of `eta` at `wo·m` and `D`, `G` those of the
/// main GGX lobe (separable Smith `G`; widths `α_u = roughness² / a` along
/// the tangent and `α_v = roughness² a`, `a = √(1 − 0.9 anisotropic)`, each
/// at least 0.001), `m` the half vector:
///
/// * main specular reflection, both sides: `F_p D G / (4 |cos θo|)` with
///   `F_p = (1 − metallic)(1 − spec_tint) F + metallic · Schlick(base_color)
///   + (1 − metallic) spec_tint · Schlick(tint · R0(η))` on the front and
///   `w_bsdf F` from below;
/// * main specular transmission (Walter et al.), both sides:
///   `√base_color · w_bsdf · |(1 − F) D G (wo·m)(wi·m) / (cos θo (wo·m + η wi·m)²)|`
///   (`η` seen from `wo`'s side; Walter's `η²` cancelled by the radiance
///   scaling `1/η²`, as in [`super::RoughDielectric`]);
/// * clearcoat, front only: `0.25 clearcoat · Schlick(0.04) · D_GTR1 ·
///   G_0.25 · |cos θi|` (Mitsuba's: no `1/(4 cos θo cos θi)`);
/// * diffuse, retro reflection and fake subsurface, front only:
///   `w_brdf base_color / π · lerp(f_d + f_r, f_ss, flatness) |cos θi|`
///   with Burley's diffuse `f_d = (1 − F_o/2)(1 − F_i/2)`, its retro
///   reflection `f_r = R (F_o + F_i + F_o F_i (R − 1))`, `R = 2 roughness
///   (m·wi)²`, and the fake subsurface `f_ss = 1.25 (F_ss (1/(cos θo +
///   cos θi) − 0.5) + 0.5)`, `F_ss = lerp(1, R/2, F_o) lerp(1, R/2, F_i)`
///   (`F_x = (1 − cos θx)⁵`, Schlick's weights);
/// * sheen, front only: `sheen (1 − metallic) lerp(1, c_tint, sheen_tint)
///   (1 − m·wi)⁵ |cos θi|` (no `1/π`, as Burley's), `c_tint` the base
///   colour over its luminance; only where the diffuse weight `w_brdf` is
///   positive (Mitsuba's scalar variants evaluate it inside the diffuse
///   lobe's branch).
///
/// The `+z` side is the outside. Sampling is Mitsuba's: a visible GGX
/// normal `m` is drawn first (seen from `wo` turned to the top) and `F(wo·m)`
/// sets the lobe probabilities: on the front, diffuse `w_brdf s_d`,
/// clearcoat `0.25 clearcoat s_c`, transmission `s_s w_bsdf (1 − F)` and
/// reflection `s_s (1 − w_bsdf (1 − F))` (`s` the sampling rates; their sum
/// does not depend on `F`), from below reflection `F` and transmission
/// `1 − F`. The density is the mixture at the half vector of the sampled
/// pair, and the weight is eval / pdf, as in Mitsuba.
///
/// One deviation, where it changes no image: seen from below with
/// `w_bsdf = 0`, Mitsuba's `pdf` is not zero (its `eval` is, and its
/// `sample` returns nothing); here it is zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    /// `base_color` (default 0.5).
    pub base_color: Vec3A,
    /// `roughness` (default 0.5).
    pub roughness: f32,
    /// `anisotropic` (default 0): the main lobe's `α_u` (along the tangent)
    /// over `α_v` is `1/(1 − 0.9 anisotropic)`.
    pub anisotropic: f32,
    /// `metallic` (default 0).
    pub metallic: f32,
    /// `spec_trans` (default 0): the share of the dielectric part that is
    /// transmitting.
    pub spec_trans: f32,
    /// The relative index of refraction, inside over outside: Mitsuba's
    /// `eta`, or from its `specular` ([`Principled::eta_of_specular`];
    /// default `specular` 0.5, `eta` 1.5).
    pub eta: f32,
    /// `spec_tint` (default 0).
    pub spec_tint: f32,
    /// `sheen` (default 0).
    pub sheen: f32,
    /// `sheen_tint` (default 0).
    pub sheen_tint: f32,
    /// `flatness` (default 0): the fake subsurface's share of the diffuse.
    pub flatness: f32,
    /// `clearcoat` (default 0).
    pub clearcoat: f32,
    /// `clearcoat_gloss` (default 0): GTR1 width 0.1 at 0, 0.001 at 1.
    pub clearcoat_gloss: f32,
    /// `main_specular_sampling_rate` (default 1).
    pub main_specular_sampling_rate: f32,
    /// `clearcoat_sampling_rate` (default 1 in Mitsuba's code; its
    /// documentation says 0).
    pub clearcoat_sampling_rate: f32,
    /// `diffuse_reflectance_sampling_rate` (default 1).
    pub diffuse_reflectance_sampling_rate: f32,
    /// Where `α_u`'s axis lies in the shading frame.
    pub tangent: Tangent,
}

impl Default for Principled {
    /// Mitsuba's defaults.
    fn default() -> Self {
        Self {
            base_color: Vec3A::splat(0.5),
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            spec_trans: 0.0,
            eta: Self::eta_of_specular(0.5),
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            main_specular_sampling_rate: 1.0,
            clearcoat_sampling_rate: 1.0,
            diffuse_reflectance_sampling_rate: 1.0,
            tangent: Tangent::X,
        }
    }
}

/// The half vector of a pair of directions, and what goes with it (BSDF
/// frame).
struct Half {
    /// The half vector, on the `+z` side.
    m: Vec3A,
    /// `wi` on `wo`'s side.
    reflect: bool,
    /// The relative index seen from `wo`'s side.
    eta_path: f32,
    /// The dielectric Fresnel term at `wo·m`.
    f: f32,
}

/// The lobes' probabilities, normalised.
struct Probs {
    diffuse: f32,
    clearcoat: f32,
    transmit: f32,
    reflect: f32,
}

impl Principled {
    /// Mitsuba's index of `specular`: `2 / (1 − √(0.08 specular)) − 1`
    /// (1.5 at the default 0.5).
    pub fn eta_of_specular(specular: f32) -> f32 {
        2.0 * (1.0 / (1.0 - (0.08 * specular).sqrt())) - 1.0
    }

    /// Sets the scalar parameter `p` to `v`; false (and nothing changed)
    /// if `p` is not one of `principled`'s (`DiffTrans`).
    #[inline]
    pub fn set(&mut self, p: PrincipledParam, v: f32) -> bool {
        use PrincipledParam::*;
        let field = match p {
            Roughness => &mut self.roughness,
            Anisotropic => &mut self.anisotropic,
            Metallic => &mut self.metallic,
            SpecTrans => &mut self.spec_trans,
            SpecTint => &mut self.spec_tint,
            Sheen => &mut self.sheen,
            SheenTint => &mut self.sheen_tint,
            Flatness => &mut self.flatness,
            Clearcoat => &mut self.clearcoat,
            ClearcoatGloss => &mut self.clearcoat_gloss,
            Eta => &mut self.eta,
            DiffTrans => return false,
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

    /// The transmitting weight `w_bsdf = (1 − metallic) spec_trans`.
    #[inline]
    fn w_bsdf(&self) -> f32 {
        (1.0 - self.metallic) * self.spec_trans
    }

    /// The diffuse weight `w_brdf = (1 − metallic)(1 − spec_trans)`.
    #[inline]
    fn w_brdf(&self) -> f32 {
        (1.0 - self.metallic) * (1.0 - self.spec_trans)
    }

    /// Whether light passes through (`w_bsdf > 0`): the surface is then an
    /// interface seen from both sides; otherwise it is one-sided.
    #[inline]
    pub fn transmits(&self) -> bool {
        positive(self.w_bsdf())
    }

    /// The main lobe's GGX distribution.
    #[inline]
    fn distribution(&self) -> MicrofacetDistribution {
        let (au, av) = widths(self.roughness, self.anisotropic);
        MicrofacetDistribution::new(MicrofacetKind::Ggx, au, av)
    }

    /// The half vector of `wo`, `wi` (BSDF frame); `None` where nothing
    /// scatters (grazing `wo` or `wi`, or from below without
    /// transmission).
    #[inline]
    fn half(&self, wo: Vec3A, wi: Vec3A) -> Option<Half> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 || !(cos_o > 0.0 || self.transmits()) {
            return None;
        }
        let reflect = cos_o * cos_i > 0.0;
        let eta_path = if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let m = normalize(wo + wi * if reflect { 1.0 } else { eta_path });
        let m = mulsign(m, m.z);
        let f = fresnel_mitsuba(wo.dot(m), self.eta).0;
        m.is_finite().then_some(Half {
            m,
            reflect,
            eta_path,
            f,
        })
    }

    /// The lobes' probabilities from `wo`'s side (`front`) with the
    /// dielectric Fresnel term `f`.
    #[inline]
    fn probs(&self, front: bool, f: f32) -> Probs {
        let (bsdf, s) = (self.w_bsdf(), self.main_specular_sampling_rate);
        let (reflect, transmit, clearcoat, diffuse) = if front {
            (
                s * (1.0 - bsdf * (1.0 - f)),
                s * bsdf * (1.0 - f),
                0.25 * self.clearcoat * self.clearcoat_sampling_rate,
                self.w_brdf() * self.diffuse_reflectance_sampling_rate,
            )
        } else {
            (f, 1.0 - f, 0.0, 0.0)
        };
        let rcp = 1.0 / (reflect + transmit + clearcoat + diffuse);
        Probs {
            diffuse: diffuse * rcp,
            clearcoat: clearcoat * rcp,
            transmit: transmit * rcp,
            reflect: reflect * rcp,
        }
    }

    /// The front side's main reflection Fresnel term `F_p` at `cos = wo·m`
    /// with the dielectric term `f` (Mitsuba's `principled_fresnel`).
    #[inline]
    fn fresnel_front(&self, f: f32, cos: f32) -> Vec3A {
        let (metallic, spec_tint) = (self.metallic, self.spec_tint);
        let mut schlick_part = Vec3A::ZERO;
        if metallic != 0.0 {
            schlick_part += metallic * schlick(self.base_color, cos, self.eta);
        }
        if spec_tint != 0.0 {
            let eta_it = if cos >= 0.0 { self.eta } else { 1.0 / self.eta };
            let f0 = tint(self.base_color) * schlick_r0(eta_it);
            schlick_part += (1.0 - metallic) * spec_tint * schlick(f0, cos, self.eta);
        }
        Vec3A::splat((1.0 - metallic) * (1.0 - spec_tint) * f) + schlick_part
    }

    /// `f(wo, wi) |cos θi|`.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        self.eval_local(wo, wi)
    }

    /// [`Principled::eval`] in the BSDF's frame.
    fn eval_local(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let Some(Half {
            m,
            reflect,
            eta_path,
            f,
        }) = self.half(wo, wi)
        else {
            return Vec3A::ZERO;
        };
        let (cos_o, cos_i) = (wo.z, wi.z);
        let front = cos_o > 0.0;
        let (bsdf, brdf) = (self.w_bsdf(), self.w_brdf());
        let distr = self.distribution();
        let (om, im) = (wo.dot(m), wi.dot(m));
        let mut v = Vec3A::ZERO;
        if reflect && agrees(m, wo, wi, cos_o, true) {
            if f > 0.0 {
                let fp = if front {
                    self.fresnel_front(f, om)
                } else {
                    Vec3A::splat(bsdf * f)
                };
                v += fp * (distr.d(m) * distr.g(wo, wi, m) / (4.0 * cos_o.abs()));
            }
        } else if !reflect && positive(bsdf) && agrees(m, wo, wi, cos_o, false) && f < 1.0 {
            let scale = 1.0 / (eta_path * eta_path);
            let den = om + eta_path * im;
            let t =
                scale * (1.0 - f) * distr.d(m) * distr.g(wo, wi, m) * eta_path * eta_path * om * im
                    / (cos_o * (den * den));
            v += sqrt3(self.base_color) * (bsdf * t.abs());
        }
        if !(front && reflect) {
            return finite_or_zero(v);
        }
        if self.clearcoat > 0.0 && agrees(m, wo, wi, cos_o, true) {
            let fcc = schlick(Vec3A::splat(0.04), om, self.eta).x;
            let dcc = Gtr1::of_gloss(self.clearcoat_gloss).d(m);
            v += Vec3A::splat(
                self.clearcoat * 0.25 * fcc * dcc * clearcoat_g(wo, wi, m) * cos_i.abs(),
            );
        }
        if brdf > 0.0 {
            let lobes = Diffuse {
                base_color: self.base_color,
                roughness: self.roughness,
                flatness: self.flatness,
                sheen: if 1.0 - self.metallic > 0.0 {
                    self.sheen
                } else {
                    0.0
                },
                sheen_tint: self.sheen_tint,
            };
            let (diffuse, sheen) = lobes.eval(cos_o.abs(), cos_i.abs(), m.dot(wi));
            v += diffuse * (brdf * cos_i.abs());
            v += sheen * ((1.0 - self.metallic) * cos_i.abs());
        }
        finite_or_zero(v)
    }

    /// The density of [`Principled::sample`].
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let (wo, wi) = (self.tangent.to_local(wo), self.tangent.to_local(wi));
        self.pdf_local(wo, wi)
    }

    /// [`Principled::pdf`] in the BSDF's frame.
    fn pdf_local(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let Some(Half {
            m,
            reflect,
            eta_path,
            f,
        }) = self.half(wo, wi)
        else {
            return 0.0;
        };
        let cos_o = wo.z;
        let p = self.probs(cos_o > 0.0, f);
        let (om, im) = (wo.dot(m), wi.dot(m));
        // dm/dwi: the reflection's and the refraction's Jacobians.
        let jacobian = if reflect {
            1.0 / (4.0 * im)
        } else {
            let den = om + eta_path * im;
            eta_path * eta_path * im / (den * den)
        }
        .abs();
        let wo_top = mulsign(wo, cos_o);
        let distr = self.distribution();
        let mut pdf = 0.0;
        if reflect {
            let facing = agrees(m, wo, wi, cos_o, true);
            if facing && p.reflect > 0.0 {
                pdf += p.reflect * distr.pdf(wo_top, m) * jacobian;
            }
            if p.diffuse > 0.0 {
                pdf += p.diffuse * (FRAC_1_PI * wi.z);
            }
            if facing && p.clearcoat > 0.0 {
                pdf += p.clearcoat * Gtr1::of_gloss(self.clearcoat_gloss).pdf(m) * jacobian;
            }
        } else if p.transmit > 0.0 && agrees(m, wo, wi, cos_o, false) {
            pdf += p.transmit * distr.pdf(wo_top, m) * jacobian;
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Draws a visible GGX normal with `u`, then with `u_lobe` one of the
    /// lobes (diffuse: a cosine-distributed direction from `u`; clearcoat:
    /// a GTR1 normal from `u`; transmission and reflection: about the
    /// visible normal); weight = eval / pdf.
    #[inline]
    pub fn sample(&self, wo_s: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let wo = self.tangent.to_local(wo_s);
        let cos_o = wo.z;
        if cos_o == 0.0 || !wo.is_finite() || !(cos_o > 0.0 || self.transmits()) {
            return None;
        }
        let distr = self.distribution();
        let m = distr.sample(mulsign(wo, cos_o), u).0;
        let om = wo.dot(m);
        let (f, cos_t, _, eta_ti) = fresnel_mitsuba(om, self.eta);
        let p = self.probs(cos_o > 0.0, f);
        let after_clearcoat = p.diffuse + p.clearcoat;
        // The direction, and whether it must be a reflection about `m`.
        let (wi, about) = if u_lobe < p.diffuse {
            (cosine_hemisphere(u), None)
        } else if u_lobe < after_clearcoat {
            let m = Gtr1::of_gloss(self.clearcoat_gloss).sample(u);
            (reflect(wo, m), Some((m, true)))
        } else if u_lobe < after_clearcoat + p.transmit {
            (m * (om * eta_ti + cos_t) - wo * eta_ti, Some((m, false)))
        } else {
            (reflect(wo, m), Some((m, true)))
        };
        let reflection = about.is_none_or(|(_, r)| r);
        let side = cos_o * wi.z;
        if !(if reflection { side > 0.0 } else { side < 0.0 }) || !wi.is_finite() {
            return None;
        }
        if let Some((m, r)) = about
            && !agrees(m, wo, wi, cos_o, r)
        {
            return None;
        }
        sample_of(self.tangent, wi, self.pdf_local(wo, wi), || {
            self.eval_local(wo, wi)
        })
    }

    /// The albedo guide at cosine `cos` (outside): the main reflection's
    /// Fresnel term, the transmission's `w_bsdf (1 − F) √base_color` and
    /// the diffuse `w_brdf base_color` (`F` at the macro normal).
    pub fn albedo(&self, cos: f32) -> Vec3A {
        let f = fresnel_mitsuba(cos, self.eta).0;
        self.fresnel_front(f, cos)
            + sqrt3(self.base_color) * (self.w_bsdf() * (1.0 - f))
            + self.base_color * self.w_brdf()
    }

    /// The denoiser's guides: the main lobe's mirror reflection and
    /// refraction when both widths are at most [`GUIDE_ALPHA`], the rest
    /// (or everything) rough.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if wo.z == 0.0 || !wo.is_finite() || !(wo.z > 0.0 || self.transmits()) {
            return GuideLobes::NONE;
        }
        let (au, av) = widths(self.roughness, self.anisotropic);
        let all = self.albedo(wo.z.abs());
        if au.max(av) > GUIDE_ALPHA {
            return GuideLobes::rough(all);
        }
        let (f, cos_t, _, eta_ti) = fresnel_mitsuba(wo.z, self.eta);
        let (reflected, transmitted) = if wo.z > 0.0 {
            (
                self.fresnel_front(f, wo.z),
                sqrt3(self.base_color) * (self.w_bsdf() * (1.0 - f)),
            )
        } else {
            let b = self.w_bsdf();
            (
                Vec3A::splat(b * f),
                sqrt3(self.base_color) * (b * (1.0 - f)),
            )
        };
        let transmit = (f < 1.0 && self.transmits())
            .then(|| Vec3A::new(-eta_ti * wo.x, -eta_ti * wo.y, cos_t))
            .and_then(|wi| GuideLobes::lobe(wi, transmitted));
        let rough = if wo.z > 0.0 {
            all - reflected - transmitted
        } else {
            Vec3A::ZERO
        };
        GuideLobes {
            reflect: GuideLobes::lobe(reflect_z(wo), reflected),
            transmit,
            ..GuideLobes::rough(rough)
        }
    }
}
