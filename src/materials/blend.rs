//! Mitsuba 3's `blendbsdf`: the mixture `(1 − w)·f₀ + w·f₁` of two BSDFs
//! ([`Blend`]), each one of Mitsuba's BSDFs ([`BlendPart`]).
//!
//! Its density is the same mixture of the parts' densities, and a sample
//! picks part 1 with probability `w` (Mitsuba's rule: part 1 when
//! `u_lobe ≤ w`, the number then rescaled for the part's own choice). A
//! sample from a part's non-delta lobes weighs the mixture's value over the
//! mixture's density at the direction drawn (so `weight × pdf = eval`, and
//! the `pdf` is the one [`Material::pdf`](super::Material::pdf) gives for
//! multiple importance sampling); one from a part's delta lobe keeps the
//! part's weight and has the part's probability times its share as its
//! `pdf`. This is the one-sample mixture estimator Mitsuba uses since 3.8.0;
//! Mitsuba 3.7.1 returned the chosen part's own density, which biases its
//! MIS where the two parts differ (see docs/mitsuba-scenes.md).
//!
//! The parts are stored inline (a [`BlendPart`] is one of Mitsuba's BSDF
//! types, not a [`Material`](super::Material)), so a blend is `Copy` like
//! every other BSDF and nothing is allocated per ray; a blend cannot be a
//! part. [`Material`](super::Material) evaluates the parts through its own
//! variants (`Material::from(part)`); this file holds the mixing.

use super::bsdf::{BsdfSample, GuideLobes, finite_or_zero};
use super::mitsuba::{
    Conductor, Plastic, Principled, PrincipledThin, RoughConductor, RoughDielectric, RoughPlastic,
    SmoothDielectric, ThinDielectric,
};
use glam::Vec3A;

/// One of the two BSDFs of a [`Blend`]: Mitsuba's BSDFs (its `diffuse` is
/// the Lambertian reflector).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BlendPart {
    /// `diffuse` of this reflectance.
    Diffuse(Vec3A),
    /// `conductor`.
    Conductor(Conductor),
    /// `roughconductor`.
    RoughConductor(RoughConductor),
    /// `dielectric`.
    Dielectric(SmoothDielectric),
    /// `thindielectric`.
    ThinDielectric(ThinDielectric),
    /// `roughdielectric`.
    RoughDielectric(RoughDielectric),
    /// `plastic`.
    Plastic(Plastic),
    /// `roughplastic`.
    RoughPlastic(RoughPlastic),
    /// `principled`.
    Principled(Principled),
    /// `principledthin`.
    PrincipledThin(PrincipledThin),
}

/// Mitsuba's `blendbsdf`: part 0 with share `1 − weight`, part 1 with
/// share `weight`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    /// The share of part 1, in `[0, 1]` (Mitsuba's `weight`, clipped).
    pub weight: f32,
    /// The two BSDFs.
    pub parts: [BlendPart; 2],
}

/// The largest `f32` below 1 (a rescaled number stays in `[0, 1)`).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

impl Blend {
    /// The blend of `a` (at `weight` 0) and `b` (at 1) with `weight`
    /// clipped to `[0, 1]` (NaN: 0).
    pub fn new(weight: f32, a: BlendPart, b: BlendPart) -> Self {
        let mut blend = Self {
            weight: 0.0,
            parts: [a, b],
        };
        blend.set_weight(weight);
        blend
    }

    /// Sets the weight (a texture's value at a hit), clipped to `[0, 1]` as
    /// Mitsuba clips it (NaN: 0).
    #[inline]
    pub fn set_weight(&mut self, weight: f32) {
        self.weight = if weight.is_nan() {
            0.0
        } else {
            weight.clamp(0.0, 1.0)
        };
    }

    /// The parts' shares, `[1 − w, w]`.
    #[inline]
    pub fn shares(&self) -> [f32; 2] {
        [1.0 - self.weight, self.weight]
    }

    /// `Σ share · f(part)` over the parts with a share (a part without one
    /// is not evaluated: a weight of 0 or 1 is exactly the one part).
    #[inline]
    pub fn mix(&self, f: impl Fn(&BlendPart) -> Vec3A) -> Vec3A {
        let [a, b] = self.shares();
        match (a > 0.0, b > 0.0) {
            (true, true) => f(&self.parts[0]) * a + f(&self.parts[1]) * b,
            (true, false) => f(&self.parts[0]),
            _ => f(&self.parts[1]),
        }
    }

    /// [`Blend::mix`] of a scalar (a density).
    #[inline]
    pub fn mix_scalar(&self, f: impl Fn(&BlendPart) -> f32) -> f32 {
        self.mix(|p| Vec3A::splat(f(p))).x
    }

    /// Which part a sample takes for `u_lobe` (part 1 when `u_lobe ≤ w`, as
    /// in Mitsuba), and the number rescaled to `[0, 1)` for the part's own
    /// choice of lobe.
    #[inline]
    pub fn choose(&self, u_lobe: f32) -> (usize, f32) {
        let w = self.weight;
        if w <= 0.0 {
            (0, u_lobe)
        } else if w >= 1.0 {
            (1, u_lobe)
        } else if u_lobe <= w {
            (1, (u_lobe / w).min(ONE_MINUS_EPSILON))
        } else {
            (0, ((u_lobe - w) / (1.0 - w)).min(ONE_MINUS_EPSILON))
        }
    }

    /// A sample of the blend: `sample_part` draws from the chosen part with
    /// the rescaled `u_lobe`, `eval_pdf` is the blend's value and density
    /// towards a direction. A delta sample keeps its weight and has its
    /// probability times the part's share; any other weighs the mixture's
    /// value over its density there. A weight of 0 or 1 is the part's own
    /// sample.
    #[inline]
    pub fn sample(
        &self,
        u_lobe: f32,
        sample_part: impl FnOnce(&BlendPart, f32) -> Option<BsdfSample>,
        eval_pdf: impl FnOnce(Vec3A) -> (Vec3A, f32),
    ) -> Option<BsdfSample> {
        let (i, u) = self.choose(u_lobe);
        let s = sample_part(&self.parts[i], u)?;
        let share = self.shares()[i];
        if share >= 1.0 {
            return Some(s);
        }
        if s.specular {
            return Some(BsdfSample {
                pdf: s.pdf * share,
                ..s
            });
        }
        let (f, pdf) = eval_pdf(s.wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi: s.wi,
            weight: finite_or_zero(f / pdf),
            pdf,
            specular: false,
        })
    }

    /// The denoiser's guides of the blend from the parts' (`g`): the rough
    /// albedos mixed; a specular lobe that both parts have (reflection
    /// about the same normal, or two refractions) is one, in the direction
    /// of the stronger, with the mixed value.
    pub fn mix_guides(&self, g: [GuideLobes; 2]) -> GuideLobes {
        let [a, b] = self.shares();
        let merge = |x: Option<(Vec3A, Vec3A)>, y: Option<(Vec3A, Vec3A)>| match (x, y) {
            (Some((dx, vx)), Some((dy, vy))) => {
                let (vx, vy) = (vx * a, vy * b);
                let d = if vx.max_element() >= vy.max_element() {
                    dx
                } else {
                    dy
                };
                GuideLobes::lobe(d, vx + vy)
            }
            (Some((d, v)), None) => GuideLobes::lobe(d, v * a),
            (None, Some((d, v))) => GuideLobes::lobe(d, v * b),
            (None, None) => None,
        };
        GuideLobes {
            rough: super::bsdf::unit_range(g[0].rough * a + g[1].rough * b),
            reflect: merge(g[0].reflect, g[1].reflect),
            transmit: merge(g[0].transmit, g[1].transmit),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::test_util::*;
    use crate::materials::{Material, MicrofacetKind};
    use glam::Vec2;

    const ETA: Vec3A = Vec3A::new(0.2, 0.9, 1.5);
    const K: Vec3A = Vec3A::new(3.9, 2.4, 1.6);
    const RHO: Vec3A = Vec3A::new(0.6, 0.3, 0.2);

    fn diffuse(rho: Vec3A) -> BlendPart {
        BlendPart::Diffuse(rho)
    }

    fn gold(kind: MicrofacetKind, alpha: f32) -> BlendPart {
        BlendPart::RoughConductor(RoughConductor::new(kind, alpha, alpha, ETA, K, Vec3A::ONE))
    }

    fn blend(w: f32, a: BlendPart, b: BlendPart) -> Material {
        Material::MiBlend(Blend::new(w, a, b))
    }

    /// Blends without delta lobes: Lambertian and metal (the suite's
    /// floor), plastic and glass (one part one-sided, the other an
    /// interface), a principled BSDF and a Lambertian. (GGX plastic:
    /// Mitsuba's Beckmann `G1` is a fit that its sampling does not follow
    /// exactly, see `mitsuba/tests.rs`; blended at 60° with the glass, a
    /// Beckmann plastic's p values over 12 seeds were all below 0.6, a GGX
    /// one's spread over [0.25, 0.9].)
    fn glossy() -> Vec<Material> {
        use MicrofacetKind::Ggx;
        vec![
            blend(0.35, diffuse(Vec3A::splat(0.7)), gold(Ggx, 0.3)),
            blend(
                0.5,
                BlendPart::RoughPlastic(RoughPlastic::new(Ggx, 0.3, 1.5, RHO, Vec3A::ONE, false)),
                BlendPart::RoughDielectric(RoughDielectric::new(
                    Ggx,
                    0.4,
                    0.4,
                    1.33,
                    Vec3A::ONE,
                    Vec3A::ONE,
                )),
            ),
            blend(
                0.8,
                BlendPart::Principled(Principled {
                    base_color: RHO,
                    metallic: 0.5,
                    roughness: 0.4,
                    ..Principled::default()
                }),
                diffuse(Vec3A::ONE),
            ),
        ]
    }

    /// A blend with a delta part: a smooth metal and a rough plastic (the
    /// documentation's `bsdf_blendbsdf`).
    fn with_delta() -> Material {
        blend(
            0.4,
            BlendPart::RoughPlastic(RoughPlastic::new(
                MicrofacetKind::Ggx,
                0.3,
                1.49,
                Vec3A::ZERO,
                Vec3A::ONE,
                false,
            )),
            BlendPart::Conductor(Conductor::new(ETA, K, Vec3A::ONE)),
        )
    }

    fn one_sided(m: &Material) -> bool {
        !m.transmits()
    }

    #[test]
    fn chi2_sampling_matches_pdf() {
        let min_p = chi2_all(&glossy(), &[10.0, 60.0, 85.0], one_sided, 1300, 0);
        eprintln!("chi2 blends: min p = {min_p:.4}");
        // And it can fail: sampled with one weight, claimed with another.
        let (a, b) = (diffuse(Vec3A::ONE), gold(MicrofacetKind::Ggx, 0.2));
        let p = chi2_p_value_of(blend(0.3, a, b), blend(0.4, a, b), dir(40.0, 0.4), 1299);
        assert!(p < 1e-6, "weight 0.3 against 0.4's pdf: p = {p}");
    }

    #[test]
    fn weight_is_eval_over_pdf_and_delta_samples_keep_their_part() {
        let mut r = rng(1377);
        let mut worst = 0.0f32;
        let mut all = glossy();
        all.push(with_delta());
        for m in all {
            let (mut hits, mut deltas) = (0, 0);
            for _ in 0..20_000 {
                let Some(wo) = random_wo(&mut r, one_sided(&m)) else {
                    continue;
                };
                let ul = r.next_f32();
                let Some(s) = m.sample(wo, ul, u2(&mut r)) else {
                    continue;
                };
                if s.specular {
                    // The smooth metal's mirror direction, with its share
                    // as the probability and its own weight.
                    let Material::MiBlend(b) = m else {
                        unreachable!()
                    };
                    let part = Material::from(b.parts[1]).sample(wo, 0.5, Vec2::ZERO);
                    let part = part.expect("the metal reflects");
                    assert_eq!(s.wi, part.wi);
                    assert_eq!(s.weight, part.weight);
                    assert!((s.pdf - b.weight * part.pdf).abs() < 1e-6, "{s:?}");
                    deltas += 1;
                    continue;
                }
                hits += 1;
                let (f, pdf) = (m.eval(wo, s.wi), m.pdf(wo, s.wi));
                assert_eq!(s.pdf, pdf, "{m:?} wo {wo}: the returned pdf is pdf()'s");
                let e = rel_err(s.weight, f / pdf);
                assert!(e < 1e-5, "{m:?} wo {wo}: {} vs {}", s.weight, f / pdf);
                worst = worst.max(e);
            }
            assert!(hits > 5_000, "{m:?}: {hits}");
            if matches!(m, Material::MiBlend(b) if b.parts[1] == with_delta_metal()) {
                // About the metal's share of the samples.
                assert!((deltas as f32 / 20_000.0 - 0.4).abs() < 0.02, "{deltas}");
            }
        }
        eprintln!("blends, weight vs eval/pdf: worst relative error {worst:e}");
    }

    fn with_delta_metal() -> BlendPart {
        let Material::MiBlend(b) = with_delta() else {
            unreachable!()
        };
        b.parts[1]
    }

    #[test]
    fn eval_and_pdf_are_the_mixtures_and_the_ends_are_the_parts() {
        let mut r = rng(1401);
        for m in glossy() {
            let Material::MiBlend(b) = m else {
                unreachable!()
            };
            let [p0, p1] = b.parts.map(Material::from);
            for _ in 0..500 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                let want = p0.eval(wo, wi) * (1.0 - b.weight) + p1.eval(wo, wi) * b.weight;
                assert!((m.eval(wo, wi) - want).abs().max_element() <= 1e-6 * want.max_element());
                let want = p0.pdf(wo, wi) * (1.0 - b.weight) + p1.pdf(wo, wi) * b.weight;
                assert!((m.pdf(wo, wi) - want).abs() <= 1e-6 * want);
                // Weights 0 and 1 are exactly the parts, samples too.
                for (w, part) in [(0.0, p0), (1.0, p1)] {
                    let end = Material::MiBlend(Blend { weight: w, ..b });
                    assert_eq!(end.eval(wo, wi), part.eval(wo, wi));
                    assert_eq!(end.pdf(wo, wi), part.pdf(wo, wi));
                    let (ul, u) = (r.next_f32(), u2(&mut r));
                    assert_eq!(end.sample(wo, ul, u), part.sample(wo, ul, u));
                }
            }
        }
        // The weight is clipped as Mitsuba clips it.
        let (a, b) = (diffuse(Vec3A::ONE), gold(MicrofacetKind::Ggx, 0.2));
        assert_eq!(Blend::new(1.5, a, b).weight, 1.0);
        assert_eq!(Blend::new(-0.5, a, b).weight, 0.0);
        assert_eq!(Blend::new(f32::NAN, a, b).weight, 0.0);
        // Mitsuba's choice: part 1 when u ≤ w, the number rescaled.
        let bl = Blend::new(0.25, a, b);
        assert_eq!(bl.choose(0.125), (1, 0.5));
        assert_eq!(bl.choose(0.625), (0, 0.5));
        assert!(bl.choose(0.999_999_9).1 < 1.0);
    }

    #[test]
    fn furnaces() {
        // Two lossless parts keep everything: a white Lambertian and a
        // perfect smooth mirror (every sample 1), and each part's albedo
        // mixes by the weight.
        let inf = Vec3A::splat(f32::INFINITY);
        let mirror = BlendPart::Conductor(Conductor::new(Vec3A::ZERO, inf, Vec3A::ONE));
        let m = blend(0.3, diffuse(Vec3A::ONE), mirror);
        for theta in [0.0f32, 45.0, 85.0] {
            let (a, _) = albedo(m, dir(theta, 0.2), 20_000, 1501);
            assert!((a - 1.0).abs() < 1e-6, "θ {theta}: {a}");
        }
        for m in glossy() {
            let Material::MiBlend(b) = m else {
                unreachable!()
            };
            let wo = dir(40.0, 0.7);
            let (a, se) = albedo(m, wo, 200_000, 1502);
            let (a0, se0) = albedo(Material::from(b.parts[0]), wo, 200_000, 1503);
            let (a1, se1) = albedo(Material::from(b.parts[1]), wo, 200_000, 1504);
            let want = a0 * (1.0 - b.weight as f64) + a1 * b.weight as f64;
            let se = (se * se + se0 * se0 + se1 * se1).sqrt();
            eprintln!("blend furnace {m:?}: {a:.4} vs parts' {want:.4} ± {se:.4}");
            assert!((a - want).abs() < 4.0 * se + 1e-4, "{m:?}: {a} vs {want}");
            assert!(a <= 1.0 + 4.0 * se);
        }
    }

    #[test]
    fn reciprocity() {
        // The reflecting blends: f(a, b) = f(b, a), f = eval / cos θi.
        let mut r = rng(1601);
        let mut all = glossy();
        all.retain(one_sided);
        all.push(with_delta());
        for m in all {
            for _ in 0..2000 {
                let (a, b) = (sphere(&mut r).abs(), sphere(&mut r).abs());
                if a.z < 0.05 || b.z < 0.05 {
                    continue;
                }
                let fab = m.eval(a, b) / b.z;
                let fba = m.eval(b, a) / a.z;
                if fab.max_element() < 1e-3 {
                    continue;
                }
                let e = rel_err(fab, fba);
                assert!(e < 2e-3, "{m:?} {a} {b}: {fab} vs {fba}");
            }
        }
    }

    #[test]
    fn degenerate_inputs_are_safe_and_guides_stay_in_range() {
        let mut all = glossy();
        all.push(with_delta());
        for m in all {
            for wo in [
                Vec3A::Z,
                -Vec3A::Z,
                dir(89.99, 0.1),
                Vec3A::ZERO,
                Vec3A::NAN,
            ] {
                for u in [Vec2::ZERO, Vec2::splat(0.999_999_9)] {
                    for wi in [Vec3A::Z, -wo, dir(89.99, 3.0)] {
                        let (f, p) = (m.eval(wo, wi), m.pdf(wo, wi));
                        assert!(f.is_finite() && p.is_finite() && f.min_element() >= 0.0);
                    }
                    for ul in [0.0, 0.5, 0.999_999] {
                        if let Some(s) = m.sample(wo, ul, u) {
                            assert!(s.weight.is_finite() && s.pdf > 0.0, "{m:?} {s:?}");
                        }
                    }
                }
                let g = m.guide_lobes(wo);
                assert!(g.rough.cmple(Vec3A::ONE).all() && g.rough.cmpge(Vec3A::ZERO).all());
                let a = m.albedo(wo.z);
                assert!(a.cmple(Vec3A::ONE).all() && a.cmpge(Vec3A::ZERO).all());
            }
        }
        // The smooth metal's reflection is the blend's specular guide.
        let g = with_delta().guide_lobes(dir(30.0, 0.0));
        assert!(g.reflect.is_some() && with_delta().chooses_lobe());
        assert!(!with_delta().is_specular());
    }
}
