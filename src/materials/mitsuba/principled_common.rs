//! What Mitsuba's `principled` and `principledthin` share (its
//! `principledhelpers.h`, written anew): Schlick's weight and Fresnel
//! approximation with Mitsuba's choice of angle, the widths of the main
//! GGX lobe, the clearcoat's GTR1 distribution and masking, the test that a
//! microfacet agrees with the macro surface, and the Disney diffuse, retro
//! reflection, fake subsurface and sheen terms.

use super::super::bsdf::BsdfSample;
use super::super::frame::Frame;
use super::common::{Tangent, positive};
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, PI};

/// Points a principled BSDF's `α_u` axis (`tangent`) along the world
/// tangent `t` (Mitsuba's `dp/du`), in the shading frame `frame`; nothing
/// when it is isotropic (`anisotropic` 0).
#[inline]
pub(super) fn orient(tangent: &mut Tangent, anisotropic: f32, frame: &Frame, t: Vec3A) {
    if anisotropic != 0.0 {
        *tangent = Tangent::orient(frame, t);
    }
}

/// The sample towards `wi` (the BSDF's frame) of density `pdf`, weighted
/// `f / pdf` as Mitsuba's `sample` weighs it (`f` its eval, evaluated only
/// for a positive density); `None` where the density is not positive or
/// the weight not finite.
#[inline]
pub(super) fn sample_of(
    tangent: Tangent,
    wi: Vec3A,
    pdf: f32,
    f: impl FnOnce() -> Vec3A,
) -> Option<BsdfSample> {
    if !positive(pdf) {
        return None;
    }
    let weight = f() / pdf;
    weight.is_finite().then_some(BsdfSample {
        wi: tangent.to_shading(wi),
        weight,
        pdf,
        specular: false,
    })
}

/// `v` times the sign of `s` (Dr.Jit's `mulsign`: the sign bit, so `-0.0`
/// counts as negative).
#[inline]
pub(super) fn mulsign(v: Vec3A, s: f32) -> Vec3A {
    if s.is_sign_negative() { -v } else { v }
}

/// `v` normalised as Dr.Jit does, `v · (1/√(v·v))` (glam divides by the
/// length): the clearcoat's GTR1 near its peak, `1 − (1 − α²) cos² θm`,
/// cancels, and there one ulp of `cos θm` moves it by 1e-4.
#[inline]
pub(super) fn normalize(v: Vec3A) -> Vec3A {
    v * (1.0 / (v.x * v.x + v.y * v.y + v.z * v.z).sqrt())
}

/// Mitsuba's `reflect(wi, m)`: `2 (wi·m) m − wi`.
#[inline]
pub(super) fn reflect(w: Vec3A, m: Vec3A) -> Vec3A {
    (2.0 * w.dot(m)) * m - w
}

/// A cosine-distributed direction above the surface (Mitsuba's
/// `square_to_cosine_hemisphere`: the concentric disk lifted onto the
/// hemisphere).
#[inline]
pub(super) fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let p = super::super::disk::concentric_disk(u);
    Vec3A::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
}

/// Dr.Jit's `lerp(a, b, t)`: `a` at `t = 0`, `b` at `t = 1`.
#[inline]
pub(super) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    b * t + (a - a * t)
}

/// [`lerp`] per channel.
#[inline]
fn lerp3(a: Vec3A, b: Vec3A, t: f32) -> Vec3A {
    b * t + (a - a * t)
}

/// The square root per channel (NaN below zero, as Dr.Jit's).
#[inline]
pub(super) fn sqrt3(v: Vec3A) -> Vec3A {
    Vec3A::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt())
}

/// Schlick's weight `(1 − cos)⁵`, `1 − cos` clamped to `[0, 1]`.
#[inline]
pub(super) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel approximation `R0 + (1 − R0)(1 − cos)⁵` as Mitsuba's
/// principled BSDFs take it (`calc_schlick`): `cos` is the cosine of the
/// incident direction `cos_i` (either side: the side picks the relative
/// index) when light goes into the denser medium, else the refracted
/// direction's (0 beyond the critical angle).
#[inline]
pub(super) fn schlick(r0: Vec3A, cos_i: f32, eta: f32) -> Vec3A {
    let outside = cos_i >= 0.0;
    let rcp = 1.0 / eta;
    let (eta_it, eta_ti) = if outside { (eta, rcp) } else { (rcp, eta) };
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti);
    let cos_t = cos_t2.max(0.0).sqrt();
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        schlick_weight(cos_t)
    };
    // Dr.Jit's lerp(w, 1, R0).
    r0 + (Vec3A::splat(w) - w * r0)
}

/// Schlick's reflectance at normal incidence of relative index `eta`:
/// `((η − 1)/(η + 1))²`.
#[inline]
pub(super) fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Mitsuba's luminance of a linear sRGB colour (`mitsuba::luminance`).
#[inline]
pub(super) fn luminance(c: Vec3A) -> f32 {
    0.212_671 * c.x + 0.715_160 * c.y + 0.072_169 * c.z
}

/// The colour's hue, `c / luminance(c)` (white for a black `c`), which
/// `spec_tint` and `sheen_tint` tint towards.
#[inline]
pub(super) fn tint(c: Vec3A) -> Vec3A {
    let lum = luminance(c);
    if lum > 0.0 { c / lum } else { Vec3A::ONE }
}

/// The GGX widths `(α_u, α_v)` of the main specular lobe of `roughness`
/// and `anisotropic` (Burley's mapping): `roughness² / a` and
/// `roughness² a`, `a = √(1 − 0.9 anisotropic)`, each at least 0.001.
#[inline]
pub(super) fn widths(roughness: f32, anisotropic: f32) -> (f32, f32) {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

/// Whether the microfacet `m` agrees with the macro surface for `wo` and
/// `wi` (Mitsuba's `mac_mic_compatibility`): both on `m`'s side (turned to
/// `wo`'s side of the surface, `cos_o` its cosine) for a `reflection`;
/// otherwise `wo` on it and `wi` on the other.
#[inline]
pub(super) fn agrees(m: Vec3A, wo: Vec3A, wi: Vec3A, cos_o: f32, reflection: bool) -> bool {
    let m = mulsign(m, cos_o);
    if reflection {
        wo.dot(m) > 0.0 && wi.dot(m) > 0.0
    } else {
        wo.dot(m) > 0.0 && wi.dot(-m) > 0.0
    }
}

/// The clearcoat's normals: Burley's GTR1 ("generalised Trowbridge–Reitz"
/// with exponent 1), isotropic, of width `alpha`, sampled by its normals
/// (not the visible ones, as Mitsuba does).
#[derive(Clone, Copy, Debug)]
pub(super) struct Gtr1 {
    /// The width.
    alpha: f32,
}

impl Gtr1 {
    /// The clearcoat distribution of `clearcoat_gloss`: widths from 0.1
    /// (gloss 0) to 0.001 (gloss 1).
    #[inline]
    pub(super) fn of_gloss(gloss: f32) -> Gtr1 {
        Gtr1 {
            alpha: lerp(0.1, 0.001, gloss),
        }
    }

    /// `D(m) = (α² − 1) / (π ln α² (1 + (α² − 1) cos² θm))`, zero where
    /// `D cos θm ≤ 1e-20`.
    #[inline]
    pub(super) fn d(&self, m: Vec3A) -> f32 {
        let a2 = self.alpha * self.alpha;
        // (cos² first: near the peak 1 − (1 − α²) cos² cancels, and
        // Mitsuba's rounding is this one.)
        let cos2 = m.z * m.z;
        let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * cos2));
        if r * m.z > 1e-20 { r } else { 0.0 }
    }

    /// The density of [`Gtr1::sample`]: `D(m) cos θm` (zero below).
    #[inline]
    pub(super) fn pdf(&self, m: Vec3A) -> f32 {
        if m.z < 0.0 { 0.0 } else { m.z * self.d(m) }
    }

    /// A normal drawn with density `D(m) cos θm`.
    #[inline]
    pub(super) fn sample(&self, u: Vec2) -> Vec3A {
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin = (1.0 - cos2).max(0.0).sqrt();
        let cos = cos2.max(0.0).sqrt();
        Vec3A::new(cos_phi * sin, sin_phi * sin, cos)
    }
}

/// Smith's GGX masking of `v` for the microfacet `m`, isotropic of width
/// `alpha` (the clearcoat's, Mitsuba's `smith_ggx1`): 1 straight up, 0 when
/// `v` sees `m`'s back.
#[inline]
fn smith_ggx1(v: Vec3A, m: Vec3A, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let cos2 = v.z * v.z;
    let tan2 = (1.0 - cos2) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The clearcoat's separable masking–shadowing, GGX of width 0.25.
#[inline]
pub(super) fn clearcoat_g(wo: Vec3A, wi: Vec3A, m: Vec3A) -> f32 {
    smith_ggx1(wo, m, 0.25) * smith_ggx1(wi, m, 0.25)
}

/// The reflection lobes under the specular ones, per unit weight, for a
/// reflection at cosines `cos_o`, `cos_i` (absolute) with `cos_d = m·wi`
/// (`m` the half vector): `(diffuse, sheen)`, to be scaled by the lobes'
/// weights and `|cos θi|`.
///
/// * diffuse: `base_color / π · lerp(f_d + f_r, f_ss, flatness)`, Burley's
///   diffuse `f_d = (1 − F_o/2)(1 − F_i/2)` with its retro reflection
///   `f_r = R (F_o + F_i + F_o F_i (R − 1))`, `R = 2 roughness cos² θd`,
///   and the Hanrahan–Krueger-like fake subsurface
///   `f_ss = 1.25 (F_ss (1/(cos θo + cos θi) − 0.5) + 0.5)`,
///   `F_ss = lerp(1, R/2, F_o) lerp(1, R/2, F_i)` (`F` Schlick weights);
/// * sheen: `sheen · lerp(1, tint(base_color), sheen_tint) · (1 − cos θd)⁵`
///   (no `1/π`: Burley's).
#[derive(Clone, Copy, Debug)]
pub(super) struct Diffuse {
    /// The base colour.
    pub base_color: Vec3A,
    /// The main lobe's roughness (for the retro reflection).
    pub roughness: f32,
    /// The fake subsurface's share.
    pub flatness: f32,
    /// The sheen's strength.
    pub sheen: f32,
    /// How far the sheen is tinted by the base colour.
    pub sheen_tint: f32,
}

impl Diffuse {
    /// `(diffuse, sheen)` as described on [`Diffuse`].
    #[inline]
    pub(super) fn eval(&self, cos_o: f32, cos_i: f32, cos_d: f32) -> (Vec3A, Vec3A) {
        let f_o = schlick_weight(cos_o);
        let f_i = schlick_weight(cos_i);
        let f_diff = (1.0 - 0.5 * f_o) * (1.0 - 0.5 * f_i);
        let rr = 2.0 * self.roughness * (cos_d * cos_d);
        let f_retro = rr * (f_i + f_o + f_i * f_o * (rr - 1.0));
        let mut lobe = f_diff + f_retro;
        if self.flatness != 0.0 {
            let fss90 = rr / 2.0;
            let fss = lerp(1.0, fss90, f_i) * lerp(1.0, fss90, f_o);
            let f_ss = 1.25 * (fss * (1.0 / (cos_i + cos_o) - 0.5) + 0.5);
            lobe = lerp(lobe, f_ss, self.flatness);
        }
        let diffuse = self.base_color * (FRAC_1_PI * lobe);
        let sheen = if self.sheen > 0.0 {
            let fd = schlick_weight(cos_d.abs());
            let c = if self.sheen_tint != 0.0 {
                lerp3(Vec3A::ONE, tint(self.base_color), self.sheen_tint)
            } else {
                Vec3A::ONE
            };
            c * (self.sheen * fd)
        } else {
            Vec3A::ZERO
        };
        (diffuse, sheen)
    }
}
