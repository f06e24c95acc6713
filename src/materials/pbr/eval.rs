//! Evaluation: `f |cos θi|` of the non-delta lobes (see [`pbr`](super)'s "The
//! model") and the density with which [`PbrBsdf::sample`] draws `wi` from
//! them, in the canonical frame and for the caller's directions, apart and
//! together (the same values bit for bit).

use super::lobes::Local;
use super::params::PbrBsdf;
use crate::materials::bsdf::finite_or_zero;
use crate::materials::microfacet::is_smooth;
use glam::Vec3A;
use std::f32::consts::FRAC_1_PI;

impl PbrBsdf {
    /// `f |cos θi|` of the non-delta lobes in the canonical frame (`l.wo.z > 0`).
    pub(super) fn eval_local(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let base = self.eval_base(l, wi);
        let base = if l.sheen {
            self.add_sheen(l, wi, base, 0.0).0
        } else {
            base
        };
        match &l.coat {
            Some(c) => base * (1.0 - c.weight) + Vec3A::splat(self.coat_eval_pdf(c, wi).0),
            None => base,
        }
    }

    /// [`PbrBsdf::eval_local`] of the material under the coat.
    fn eval_base(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let wo = l.wo;
        let (m, s) = (self.metallic, self.specular);
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let cos_oh = wo.dot(h).min(1.0);
            let fd = self.fresnel_d(l.f0, cos_oh, l.inside);
            let kd = 1.0 - s * fd.max_element();
            let mut f = self.reflected_diffuse() * (self.diffuse_scale() * kd * FRAC_1_PI * wi.z);
            if !l.smooth {
                // D G2 / (4 cos θo); the numerator first so that a subnormal
                // cos θo next to G2 = 0 gives 0, not 0 · ∞.
                let spec = (l.ggx.d(h) * l.ggx.g2(wo, wi)) / (4.0 * wo.z);
                f += (m * self.fresnel_m(cos_oh) + (1.0 - m) * s * fd) * spec;
            }
            f
        } else if wi.z < 0.0 {
            let f = if !l.smooth && self.transmission_scale() != 0.0 {
                self.eval_specular_transmission(l, wi)
            } else {
                Vec3A::ZERO
            };
            if self.transmits_diffusely() {
                f + self.eval_diffuse_transmission(l, wi)
            } else {
                f
            }
        } else {
            Vec3A::ZERO
        }
    }

    /// [`PbrBsdf::eval_local`] and [`PbrBsdf::pdf_local`] together, the
    /// reflection's half vector and `D` computed once: the same two values
    /// bit for bit.
    #[inline]
    fn eval_pdf_local(&self, l: &Local, wi: Vec3A) -> (Vec3A, f32) {
        let (f, p) = self.eval_pdf_base(l, wi);
        let (f, p) = if l.sheen {
            self.add_sheen(l, wi, f, p)
        } else {
            (f, p)
        };
        match &l.coat {
            Some(c) => {
                let (fc, pc) = self.coat_eval_pdf(c, wi);
                (f * (1.0 - c.weight) + Vec3A::splat(fc), p + l.p_coat * pc)
            }
            None => (f, p),
        }
    }

    /// [`PbrBsdf::eval_pdf_local`] of the material under the coat (its
    /// density already weighted by the lobes' probabilities).
    #[inline]
    fn eval_pdf_base(&self, l: &Local, wi: Vec3A) -> (Vec3A, f32) {
        if wi.z <= 0.0 {
            return (self.eval_base(l, wi), self.pdf_base(l, wi));
        }
        let wo = l.wo;
        let (m, s) = (self.metallic, self.specular);
        let h = (wo + wi).normalize();
        let cos_oh = wo.dot(h).min(1.0);
        let fd = self.fresnel_d(l.f0, cos_oh, l.inside);
        let kd = 1.0 - s * fd.max_element();
        let mut f = self.reflected_diffuse() * (self.diffuse_scale() * kd * FRAC_1_PI * wi.z);
        let mut p = l.p_diff * FRAC_1_PI * wi.z;
        if !l.smooth {
            let d = l.ggx.d(h);
            let spec = (d * l.ggx.g2(wo, wi)) / (4.0 * wo.z);
            f += (m * self.fresnel_m(cos_oh) + (1.0 - m) * s * fd) * spec;
            if l.p_spec > 0.0 {
                p += l.p_spec * ((l.ggx.g1(wo) * d) / (4.0 * wo.z));
            }
        }
        (f, p)
    }

    /// The mixture density of the non-delta lobes in the canonical frame.
    pub(super) fn pdf_local(&self, l: &Local, wi: Vec3A) -> f32 {
        let mut p = self.pdf_base(l, wi);
        if l.sheen && wi.z > 0.0 {
            p += l.p_sheen * FRAC_1_PI * wi.z;
        }
        match &l.coat {
            Some(c) if l.p_coat > 0.0 => p + l.p_coat * self.coat_eval_pdf(c, wi).1,
            _ => p,
        }
    }

    /// [`PbrBsdf::pdf_local`] of the lobes under the sheen and the coat.
    fn pdf_base(&self, l: &Local, wi: Vec3A) -> f32 {
        let wo = l.wo;
        if wi.z > 0.0 {
            let mut p = l.p_diff * FRAC_1_PI * wi.z;
            if !l.smooth && l.p_spec > 0.0 {
                let h = (wo + wi).normalize();
                // D_wo(h) / (4 |wo·h|) = G1(wo) D(h) / (4 cos θo).
                p += l.p_spec * ((l.ggx.g1(wo) * l.ggx.d(h)) / (4.0 * wo.z));
            }
            p
        } else if wi.z < 0.0 {
            let p = if !l.smooth && l.p_trans > 0.0 {
                self.pdf_specular_transmission(l, wi)
            } else {
                0.0
            };
            if l.p_dtrans > 0.0 {
                // The cosine lobe on the far side.
                p + l.p_dtrans * FRAC_1_PI * -wi.z
            } else {
                p
            }
        } else {
            0.0
        }
    }

    /// Whether `wo` and `wi` are on different sides (or one on the horizon) of a
    /// surface without a non-delta transmission lobe: nothing to evaluate (a
    /// shortcut past [`PbrBsdf::local`], e.g. for lights behind an opaque surface).
    #[inline]
    fn nothing_between(&self, wo: Vec3A, wi: Vec3A) -> bool {
        wo.z * wi.z <= 0.0
            && (self.transmission_scale() == 0.0 || is_smooth(self.alpha_t()))
            && !self.transmits_diffusely()
    }

    /// `f(wo, wi) |cos θi|` of the non-delta lobes (zero for the delta lobes of a
    /// smooth surface). Never negative or non-finite for valid inputs.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if self.nothing_between(wo, wi) {
            return Vec3A::ZERO;
        }
        let Some(l) = self.local(wo) else {
            return Vec3A::ZERO;
        };
        if !wi.is_finite() {
            return Vec3A::ZERO;
        }
        finite_or_zero(self.eval_local(&l, l.map(wi)))
    }

    /// [`PbrBsdf::eval`] and [`PbrBsdf::pdf`] of one pair of directions, the
    /// lobes' probabilities and the half vector worked out once (next-event
    /// estimation needs both): the same values bit for bit.
    pub fn eval_pdf(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        self.eval_pdf_at(self.local(wo).as_ref(), wo, wi)
    }

    /// [`PbrBsdf::eval_pdf`] with `local` = [`PbrBsdf::local`]`(wo)` already
    /// worked out (a path vertex's light sample and BSDF sample share it).
    #[inline]
    pub fn eval_pdf_at(&self, local: Option<&Local>, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        if self.nothing_between(wo, wi) {
            return (Vec3A::ZERO, 0.0);
        }
        let Some(&l) = local else {
            return (Vec3A::ZERO, 0.0);
        };
        if !wi.is_finite() {
            return (Vec3A::ZERO, 0.0);
        }
        let (f, p) = self.eval_pdf_local(&l, l.map(wi));
        (finite_or_zero(f), if p.is_finite() { p } else { 0.0 })
    }

    /// Solid-angle density with which [`PbrBsdf::sample`] produces `wi` from its
    /// non-delta lobes (their mixture, weighted by the selection probabilities).
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if self.nothing_between(wo, wi) {
            return 0.0;
        }
        let Some(l) = self.local(wo) else {
            return 0.0;
        };
        if !wi.is_finite() {
            return 0.0;
        }
        let p = self.pdf_local(&l, l.map(wi));
        if p.is_finite() { p } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::materials::material::Material;
    use crate::materials::test_util::*;

    // ---------------------------------------------- weights and densities

    #[test]
    fn eval_pdf_equals_eval_and_pdf_bit_for_bit() {
        // Random pairs on both sides, grazing and degenerate ones: the shared
        // computation must give exactly what the two separate calls give.
        let mut r = rng(17);
        let mut nonzero = 0;
        for p in every_test_material() {
            for k in 0..5_000 {
                let wo = sphere(&mut r);
                let wi = match k % 50 {
                    0 => Vec3A::new(wo.x, wo.y, 0.0),
                    1 => -wo,
                    2 => Vec3A::new(f32::NAN, 0.0, 1.0),
                    _ => sphere(&mut r),
                };
                let (f, pdf) = p.eval_pdf(wo, wi);
                let (f_alone, pdf_alone) = (p.eval(wo, wi), p.pdf(wo, wi));
                let bits = |f: Vec3A, pdf: f32| (f.to_array().map(f32::to_bits), pdf.to_bits());
                assert_eq!(
                    bits(f, pdf),
                    bits(f_alone, pdf_alone),
                    "{p:?} wo {wo:?} wi {wi:?}"
                );
                // And through the material seen from `wo`, sampling included.
                let m = Material::Pbr(p);
                let at = m.at(wo);
                let (f_at, pdf_at) = at.eval_and_pdf(wi);
                assert_eq!(bits(f_at, pdf_at.unwrap()), bits(f, pdf));
                let (u_lobe, u) = (r.next_f32(), u2(&mut r));
                assert_eq!(at.sample(u_lobe, u), m.sample(wo, u_lobe, u));
                nonzero += usize::from(pdf > 0.0 && f != Vec3A::ZERO);
            }
        }
        assert!(nonzero > 10_000, "only {nonzero} pairs with a value");
    }

    #[test]
    fn two_sided_and_reciprocal() {
        let mut r = rng(4);
        for p in every_test_material() {
            let m = Material::Pbr(p);
            let volume = p.transmission > 0.0 && !p.thin_walled;
            // Index of the medium a direction is in (1 for two-sided materials).
            let n = |w: Vec3A| if volume && w.z < 0.0 { p.ior } else { 1.0 };
            let mut checked = 0;
            for _ in 0..20_000 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                let f = m.eval(wo, wi);
                if f.max_element() < 1e-4 || wo.z.abs() < 1e-3 || wi.z.abs() < 1e-3 {
                    continue;
                }
                checked += 1;
                // f(wo, wi) / n(wi)² = f(wi, wo) / n(wo)²: symmetric but for the
                // 1/η² the transmitted radiance leaves out. (A clear coat's
                // layering weighs by the Fresnel term at `wo` alone, as
                // specified: not reciprocal.)
                // (Nor is the diffuse transmission through a volume's
                // boundary: a Lambertian lobe on the far side, as specified,
                // with no refraction to pair with 1/η².)
                let lambertian_across = volume && p.diffuse_transmission > 0.0 && wo.z * wi.z < 0.0;
                if p.coat == 0.0 && !lambertian_across {
                    let a = f / (wi.z.abs() * n(wi) * n(wi));
                    let b = m.eval(wi, wo) / (wo.z.abs() * n(wo) * n(wo));
                    assert!(rel_err(a, b) < 2e-3, "{p:?}: {wo} {wi}: {a} vs {b}");
                }
                // Mirrored, a tilted coat normal is the back's, not the same.
                if !volume && (p.coat == 0.0 || p.coat_normal == Vec3A::Z) {
                    let g = m.eval(flip(wo), flip(wi));
                    assert!(rel_err(g, f) < 1e-6, "{p:?}: not two-sided");
                    assert_eq!(m.pdf(flip(wo), flip(wi)), m.pdf(wo, wi));
                }
            }
            assert!(checked > 1000, "{p:?}: {checked}");
        }
    }

    // ------------------------------------------------ Appendix B as specified

    #[test]
    fn white_dielectric_is_brighter_than_white_at_grazing_angles() {
        // Appendix B as specified, unfixed: 1 − s max(F) of the diffuse base uses
        // the half vector of each pair, so at grazing incidence the specular lobe
        // (F near 1) and most of the diffuse lobe are both kept. (An independent
        // float64 quadrature of the formulas gives 1.0821 at roughness 0.5.)
        let wo = dir(80.0, 0.3);
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.5));
        let (a, se) = albedo(m, wo, 200_000, 800);
        let q = albedo_by_quadrature(m, wo);
        eprintln!("white dielectric r=0.5 θo=80°: MC {a:.5} ± {se:.5}, quadrature {q:.5}");
        assert!((a - q).abs() < 4.0 * se + 1e-3, "MC {a} vs quadrature {q}");
        assert!((q - 1.0821).abs() < 1e-3 && a > 1.05, "{a} {q}");
        // Smooth: the delta reflection's F(cos θo) plus the diffuse part, whose
        // eval the quadrature sees: 1.35.
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.0));
        let (a, se) = albedo(m, wo, 200_000, 801);
        let q = schlick1(0.04, wo.z) as f64 + albedo_by_quadrature(m, wo);
        eprintln!("white dielectric r=0 θo=80°: MC {a:.5} ± {se:.5}, F + quadrature {q:.5}");
        assert!(
            (a - q).abs() < 4.0 * se + 1e-3,
            "MC {a} vs F + quadrature {q}"
        );
        assert!(q > 1.3 && a > 1.3, "{a} {q}");
        // Head-on it is below 1.
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.5));
        let (a0, se0) = albedo(m, Vec3A::Z, 100_000, 802);
        eprintln!("white dielectric r=0.5 θo=0°: MC {a0:.5} ± {se0:.5}");
        assert!(a0 < 1.0);
    }

    #[test]
    fn exact_metallic_mix_at_a_hand_computed_point() {
        // α = 0.5² = 0.25, c = (0.8, 0.4, 0.2), m = 0.3, ior 1.5 (F0 = 0.04), s = 1.
        // wo = (0.6, 0, 0.8), wi = (−0.28, 0, 0.96): h = (0.32, 0, 1.76)/√3.2,
        //   wo·h = 1.6/√3.2 = 0.894427, (1 − wo·h)⁵ = 1.3114e-5, h_z = 0.983870.
        // D = α² / (π (h_z² (α² − 1) + 1)²) = 2.325127.
        // Λ(wo) = (√(1 + α² 0.6²/0.8²) − 1)/2 = 0.0087131,
        // Λ(wi) = (√(1 + α² 0.28²/0.96²) − 1)/2 = 0.0013274,
        // G2 = 1/(1 + Λo + Λi) = 0.990059, V = G2/(4·0.8·0.96) = 0.322285.
        // F_d = 0.04 + 0.96·1.3114e-5 = 0.0400126; F_m = c + (1 − c)·1.3114e-5.
        // f = 0.7 [(1 − F_d) c/π + F_d D V] + 0.3 F_m D V
        //   = (0.371955, 0.196473, 0.108732); f cos θi = f · 0.96:
        let expected = Vec3A::new(0.357_077, 0.188_614, 0.104_383);
        // The glTF sample viewer's shortcut (one F of the mixed F0 =
        // mix(0.04, c, m), diffuse (1 − F)(1 − m)c/π) gives instead
        let shortcut = Vec3A::new(0.318_061, 0.179_374, 0.102_330);
        let p = PbrBsdf::new(Vec3A::new(0.8, 0.4, 0.2), 0.3, 0.5);
        let (wo, wi) = (Vec3A::new(0.6, 0.0, 0.8), Vec3A::new(-0.28, 0.0, 0.96));
        let f = p.eval(wo, wi);
        eprintln!("hand-computed pbr f cos θi: {f} (expected {expected})");
        assert!(rel_err(f, expected) < 2e-5, "{f} vs {expected}");
        assert!(rel_err(shortcut, expected) > 0.01);
        // Both sides alike (a two-sided material), and reciprocal.
        assert!(rel_err(p.eval(flip(wo), flip(wi)), expected) < 2e-5);
        assert!(rel_err(p.eval(wi, wo) * (wi.z / wo.z), expected) < 2e-5);
    }
}
