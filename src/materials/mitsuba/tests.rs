//! Tests of Mitsuba's BSDFs: against Mitsuba 3.7.1's own numbers
//! (`reference.rs`), χ² of the sampling against the pdf, weight = eval / pdf,
//! energy, reciprocity and guards.

// Mitsuba's f32 values as printed, to 9 digits.
#[allow(clippy::excessive_precision, clippy::approx_constant)]
#[path = "reference.rs"]
mod reference;

use super::*;
use crate::materials::test_util::*;
use crate::materials::{Frame, Material, MicrofacetDistribution, MicrofacetKind, PbrBsdf};
use glam::{Vec2, Vec3A};
use reference::*;

const ETA: Vec3A = Vec3A::new(0.2, 0.9, 1.5);
const K: Vec3A = Vec3A::new(3.9, 2.4, 1.6);
const RHO: Vec3A = Vec3A::new(0.6, 0.3, 0.2);
const TINT: Vec3A = Vec3A::new(0.9, 0.8, 0.7);

/// The BSDFs of `tools/mitsuba_bsdf_reference.py`, by its names, with their
/// eval and sample tables.
/// A referenced BSDF: its name, the material, its eval and sample rows.
type Referenced = (
    &'static str,
    Material,
    &'static [[f32; 10]],
    &'static [[f32; 13]],
);

fn rgb(r: f32, g: f32, b: f32) -> Vec3A {
    Vec3A::new(r, g, b)
}

/// `tools/mitsuba_bsdf_reference.py`'s `pr_full`: every lobe but the
/// transmission.
fn pr_full() -> Principled {
    Principled {
        base_color: rgb(0.8, 0.4, 0.2),
        metallic: 0.3,
        eta: Principled::eta_of_specular(0.6),
        roughness: 0.3,
        spec_tint: 0.4,
        anisotropic: 0.5,
        sheen: 0.6,
        sheen_tint: 0.5,
        clearcoat: 0.7,
        clearcoat_gloss: 0.4,
        flatness: 0.3,
        ..Principled::default()
    }
}

/// `pr_trans`: with transmission.
fn pr_trans() -> Principled {
    Principled {
        base_color: rgb(0.9, 0.7, 0.5),
        spec_trans: 0.7,
        eta: 1.4,
        roughness: 0.25,
        metallic: 0.1,
        anisotropic: 0.3,
        sheen: 0.2,
        clearcoat: 0.5,
        spec_tint: 0.2,
        ..Principled::default()
    }
}

/// `pr_metal`: metallic, anisotropic.
fn pr_metal() -> Principled {
    Principled {
        base_color: rgb(0.9, 0.6, 0.3),
        metallic: 1.0,
        roughness: 0.4,
        anisotropic: 0.8,
        ..Principled::default()
    }
}

/// `pr_glass`: transmission only.
fn pr_glass() -> Principled {
    Principled {
        base_color: Vec3A::ONE,
        spec_trans: 1.0,
        roughness: 0.2,
        eta: 1.5,
        ..Principled::default()
    }
}

/// `pr_rates`: sampling rates.
fn pr_rates() -> Principled {
    Principled {
        base_color: rgb(0.3, 0.6, 0.9),
        spec_trans: 0.3,
        clearcoat: 1.0,
        clearcoat_gloss: 0.8,
        main_specular_sampling_rate: 0.5,
        clearcoat_sampling_rate: 2.0,
        diffuse_reflectance_sampling_rate: 0.7,
        eta: Principled::eta_of_specular(0.3),
        roughness: 0.6,
        ..Principled::default()
    }
}

/// `pt_full`: every lobe of the thin sheet.
fn pt_full() -> PrincipledThin {
    PrincipledThin {
        base_color: rgb(0.7, 0.5, 0.3),
        spec_trans: 0.4,
        diff_trans: 0.6,
        eta: 1.33,
        roughness: 0.35,
        anisotropic: 0.4,
        spec_tint: 0.3,
        sheen: 0.5,
        sheen_tint: 0.4,
        flatness: 0.5,
        ..PrincipledThin::default()
    }
}

/// `pt_glass`: specular only.
fn pt_glass() -> PrincipledThin {
    PrincipledThin {
        base_color: Vec3A::ONE,
        spec_trans: 1.0,
        roughness: 0.2,
        eta: 1.5,
        ..PrincipledThin::default()
    }
}

/// `pt_rates`: sampling rates.
fn pt_rates() -> PrincipledThin {
    PrincipledThin {
        base_color: rgb(0.6, 0.8, 0.4),
        spec_trans: 0.2,
        diff_trans: 1.2,
        specular_reflectance_sampling_rate: 0.5,
        specular_transmittance_sampling_rate: 2.0,
        diffuse_reflectance_sampling_rate: 0.8,
        diffuse_transmittance_sampling_rate: 1.5,
        roughness: 0.45,
        eta: 1.2,
        ..PrincipledThin::default()
    }
}

/// The referenced principled BSDFs.
fn referenced_principled() -> Vec<Referenced> {
    use Material::{MiPrincipled as P, MiPrincipledThin as T};
    vec![
        (
            "pr_default",
            P(Principled::default()),
            PR_DEFAULT_EVAL,
            PR_DEFAULT_SAMPLE,
        ),
        ("pr_full", P(pr_full()), PR_FULL_EVAL, PR_FULL_SAMPLE),
        ("pr_trans", P(pr_trans()), PR_TRANS_EVAL, PR_TRANS_SAMPLE),
        ("pr_metal", P(pr_metal()), PR_METAL_EVAL, PR_METAL_SAMPLE),
        ("pr_glass", P(pr_glass()), PR_GLASS_EVAL, PR_GLASS_SAMPLE),
        ("pr_rates", P(pr_rates()), PR_RATES_EVAL, PR_RATES_SAMPLE),
        (
            "pt_default",
            T(PrincipledThin::default()),
            PT_DEFAULT_EVAL,
            PT_DEFAULT_SAMPLE,
        ),
        ("pt_full", T(pt_full()), PT_FULL_EVAL, PT_FULL_SAMPLE),
        ("pt_glass", T(pt_glass()), PT_GLASS_EVAL, PT_GLASS_SAMPLE),
        ("pt_rates", T(pt_rates()), PT_RATES_EVAL, PT_RATES_SAMPLE),
    ]
}

/// Whether `m` scatters nothing from below (and nothing from above to
/// below): the one-sided BSDFs. (The thin sheet is the same from both
/// sides even when it does not transmit.)
fn one_sided(m: &Material) -> bool {
    !m.transmits() && !matches!(m, Material::MiPrincipledThin(_))
}

fn referenced() -> Vec<Referenced> {
    use MicrofacetKind::{Beckmann, Ggx};
    let mut all = vec![
        (
            "rc_beckmann",
            Material::MiRoughConductor(RoughConductor::new(Beckmann, 0.2, 0.2, ETA, K, TINT)),
            RC_BECKMANN_EVAL,
            RC_BECKMANN_SAMPLE,
        ),
        (
            "rc_ggx_aniso",
            Material::MiRoughConductor(RoughConductor::new(Ggx, 0.1, 0.4, ETA, K, Vec3A::ONE)),
            RC_GGX_ANISO_EVAL,
            RC_GGX_ANISO_SAMPLE,
        ),
        (
            "rd_beckmann",
            Material::MiRoughDielectric(RoughDielectric::new(
                Beckmann,
                0.3,
                0.3,
                1.5,
                Vec3A::ONE,
                TINT,
            )),
            RD_BECKMANN_EVAL,
            RD_BECKMANN_SAMPLE,
        ),
        (
            "rd_ggx_aniso",
            Material::MiRoughDielectric(RoughDielectric::new(
                Ggx,
                0.2,
                0.05,
                1.33,
                Vec3A::ONE,
                Vec3A::ONE,
            )),
            RD_GGX_ANISO_EVAL,
            RD_GGX_ANISO_SAMPLE,
        ),
        (
            "plastic",
            Material::MiPlastic(Plastic::new(1.49, RHO, Vec3A::ONE, true)),
            PLASTIC_EVAL,
            PLASTIC_SAMPLE,
        ),
        (
            "rp_beckmann",
            Material::MiRoughPlastic(RoughPlastic::new(
                Beckmann,
                0.2,
                1.5,
                RHO,
                Vec3A::ONE,
                false,
            )),
            RP_BECKMANN_EVAL,
            RP_BECKMANN_SAMPLE,
        ),
        (
            "rp_ggx",
            Material::MiRoughPlastic(RoughPlastic::new(
                Ggx,
                0.3,
                1.49,
                RHO,
                Vec3A::new(0.8, 0.8, 0.9),
                true,
            )),
            RP_GGX_EVAL,
            RP_GGX_SAMPLE,
        ),
        (
            "dielectric",
            Material::MiDielectric(SmoothDielectric::new(1.5, TINT, Vec3A::ONE)),
            DIELECTRIC_EVAL,
            DIELECTRIC_SAMPLE,
        ),
        (
            "thin",
            Material::MiThinDielectric(ThinDielectric::new(1.5, Vec3A::ONE, Vec3A::ONE)),
            THIN_EVAL,
            THIN_SAMPLE,
        ),
        (
            "conductor",
            Material::MiConductor(Conductor::new(ETA, K, Vec3A::ONE)),
            CONDUCTOR_EVAL,
            CONDUCTOR_SAMPLE,
        ),
    ];
    all.extend(referenced_principled());
    all
}

fn v3(r: &[f32]) -> Vec3A {
    Vec3A::new(r[0], r[1], r[2])
}

/// Whether `a` is within `rel` of `b` (relative to the largest channel of
/// `b`, so that a channel far below the others does not set the bar).
fn close(a: Vec3A, b: Vec3A, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element() + 1e-30
}

#[test]
fn eval_and_pdf_match_mitsuba() {
    let mut worst = 0.0f32;
    let mut worst_pdf = 0.0f32;
    let mut nonzero = 0;
    for (name, m, evals, _) in referenced() {
        let (mut worst_here, mut worst_pdf_here) = (0.0f32, 0.0f32);
        for r in evals {
            let (wo, wi, want, want_pdf) = (v3(&r[0..]), v3(&r[3..]), v3(&r[6..]), r[9]);
            let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
            // Seen from below, a principled BSDF that does not transmit
            // scatters nothing: Mitsuba's eval is zero there and its sample
            // returns nothing, but its pdf is not zero; raylab's is.
            let want_pdf = match m {
                Material::MiPrincipled(p) if !p.transmits() && wo.z < 0.0 => {
                    assert_eq!(want, Vec3A::ZERO, "{name} wo {wo} wi {wi}");
                    0.0
                }
                _ => want_pdf,
            };
            // Far out in a Beckmann tail (values ~1e-15) exp() amplifies the
            // directions' rounding: 1e-3 there, 2e-5 elsewhere.
            let tol = if want.max_element() < 1e-6 {
                1e-3
            } else {
                2e-5
            };
            assert!(
                close(f, want, tol),
                "{name} wo {wo} wi {wi}: eval {f} vs Mitsuba {want}"
            );
            assert!(
                (pdf - want_pdf).abs() <= tol * want_pdf,
                "{name} wo {wo} wi {wi}: pdf {pdf} vs Mitsuba {want_pdf}"
            );
            if want != Vec3A::ZERO {
                nonzero += 1;
                let e = (f - want).abs().max_element() / want.max_element();
                worst = worst.max(e);
                worst_here = worst_here.max(e);
            }
            if want_pdf > 0.0 {
                let e = (pdf - want_pdf).abs() / want_pdf;
                worst_pdf = worst_pdf.max(e);
                worst_pdf_here = worst_pdf_here.max(e);
            }
        }
        eprintln!(
            "eval vs Mitsuba, {name}: worst relative error {worst_here:e} (pdf {worst_pdf_here:e})"
        );
    }
    eprintln!(
        "eval vs Mitsuba: {nonzero} non-zero values, worst relative error {worst:e} (pdf {worst_pdf:e})"
    );
    assert!(nonzero >= 30, "{nonzero}");
}

#[test]
fn samples_match_mitsuba() {
    let mut checked = 0;
    let (mut worst_w, mut worst_pdf) = (0.0f32, 0.0f32);
    for (name, m, _, samples) in referenced() {
        let (mut w_here, mut pdf_here) = (0.0f32, 0.0f32);
        for r in samples {
            let (wo, u_lobe, u) = (v3(&r[0..]), r[3], Vec2::new(r[4], r[5]));
            let (want_wi, want_w, want_pdf) = (v3(&r[6..]), v3(&r[9..]), r[12]);
            let Some(s) = m.sample(wo, u_lobe, u) else {
                panic!("{name} wo {wo} u {u_lobe} {u}: no sample, Mitsuba's {want_wi}");
            };
            // The rough plastic's weight goes through its table, which
            // raylab sums in f64 (Mitsuba in f32); Beckmann's sampling
            // through erf⁻¹, whose approximations differ.
            assert!(
                (s.wi - want_wi).abs().max_element() < 2e-5,
                "{name} wo {wo} u {u_lobe} {u}: wi {} vs Mitsuba {want_wi}",
                s.wi
            );
            assert!(
                close(s.weight, want_w, 2e-4),
                "{name} wo {wo} u {u_lobe} {u}: weight {} vs Mitsuba {want_w}",
                s.weight
            );
            assert!(
                (s.pdf - want_pdf).abs() <= 2e-4 * want_pdf,
                "{name} wo {wo} u {u_lobe} {u}: pdf {} vs Mitsuba {want_pdf}",
                s.pdf
            );
            w_here = w_here.max((s.weight - want_w).abs().max_element() / want_w.max_element());
            pdf_here = pdf_here.max((s.pdf - want_pdf).abs() / want_pdf);
            // The smooth plastic's specular lobe is its mirror direction.
            let mirror = (s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6;
            assert_eq!(s.specular, m.is_specular() || (name == "plastic" && mirror));
            checked += 1;
        }
        eprintln!(
            "samples vs Mitsuba, {name}: {} rows, worst relative error of the weights {w_here:e}, of the pdfs {pdf_here:e}",
            samples.len()
        );
        worst_w = worst_w.max(w_here);
        worst_pdf = worst_pdf.max(pdf_here);
    }
    eprintln!(
        "samples vs Mitsuba: {checked} checked, worst relative error of the weights {worst_w:e}, of the pdfs {worst_pdf:e}"
    );
    assert!(checked >= 300, "{checked}");
}

/// The non-delta BSDFs of the statistical tests.
///
/// Mitsuba's Beckmann `G1` is a rational fit, up to 0.3 % off the exact
/// one, and its visible-normal pdf `D G1 (wo·m) / cos θo` is off by as much
/// from what its sampling draws (the exact visible normals): enough for
/// 500,000 samples to see. The Beckmann BSDFs here have `α = 0.3`, where at
/// the χ² test's angles the fit is within 0.05 % (`a = 1/(α tan θ)` = 18.9,
/// 1.92 and 0.29 at 10°, 60° and 85°).
fn glossy() -> Vec<Material> {
    use MicrofacetKind::{Beckmann, Ggx};
    vec![
        Material::MiRoughConductor(RoughConductor::new(Beckmann, 0.3, 0.3, ETA, K, TINT)),
        Material::MiRoughConductor(RoughConductor::new(Ggx, 0.1, 0.4, ETA, K, Vec3A::ONE)),
        Material::MiRoughDielectric(RoughDielectric::new(
            Beckmann,
            0.3,
            0.3,
            1.5,
            Vec3A::ONE,
            Vec3A::ONE,
        )),
        Material::MiRoughDielectric(RoughDielectric::new(
            Ggx,
            0.4,
            0.15,
            1.33,
            Vec3A::ONE,
            Vec3A::ONE,
        )),
        Material::MiRoughPlastic(RoughPlastic::new(
            Beckmann,
            0.3,
            1.5,
            RHO,
            Vec3A::ONE,
            false,
        )),
        Material::MiRoughPlastic(RoughPlastic::new(Ggx, 0.5, 1.49, RHO, TINT, true)),
        // Only the diffuse lobe is sampled with a zero specular weight.
        Material::MiPlastic(Plastic {
            specular_sampling_weight: 0.0,
            ..Plastic::new(1.49, RHO, Vec3A::ONE, false)
        }),
        // The principled BSDFs, with a clearcoat wide enough for the
        // quadrature of the expected counts.
        Material::MiPrincipled(Principled {
            clearcoat_gloss: 0.0,
            roughness: 0.4,
            ..pr_full()
        }),
        Material::MiPrincipled(Principled {
            clearcoat_gloss: 0.0,
            roughness: 0.4,
            ..pr_trans()
        }),
        Material::MiPrincipled(pr_metal()),
        Material::MiPrincipledThin(pt_full()),
        Material::MiPrincipledThin(PrincipledThin {
            roughness: 0.5,
            ..pt_glass()
        }),
    ]
}

#[test]
fn chi2_sampling_matches_pdf() {
    let min_p = chi2_all(&glossy(), &[10.0, 60.0, 85.0], one_sided, 900, 1);
    eprintln!("chi2 Mitsuba BSDFs: min p = {min_p:.4}");
    // And it can fail: Beckmann sampled against GGX's pdf of the same width.
    let beckmann = RoughConductor::new(MicrofacetKind::Beckmann, 0.3, 0.3, ETA, K, TINT);
    let ggx = RoughConductor {
        distribution: MicrofacetDistribution::new(MicrofacetKind::Ggx, 0.3, 0.3),
        ..beckmann
    };
    let p = chi2_p_value_of(
        Material::MiRoughConductor(beckmann),
        Material::MiRoughConductor(ggx),
        dir(40.0, 0.4),
        899,
    );
    assert!(p < 1e-6, "Beckmann against GGX's pdf: p = {p}");
}

#[test]
fn weight_is_eval_over_pdf_and_pdf_is_the_returned_one() {
    let mut r = rng(77);
    let mut worst = 0.0f32;
    for m in glossy() {
        let mut hits = 0;
        for _ in 0..20_000 {
            let Some(wo) = random_wo(&mut r, one_sided(&m)) else {
                continue;
            };
            let Some(s) = m.sample(wo, r.next_f32(), u2(&mut r)) else {
                continue;
            };
            if s.specular {
                continue;
            }
            hits += 1;
            let (f, pdf) = (m.eval(wo, s.wi), m.pdf(wo, s.wi));
            assert!(
                ((s.pdf - pdf) / pdf).abs() < 1e-4,
                "{m:?} wo {wo}: pdf {} vs {pdf}",
                s.pdf
            );
            let e = rel_err(s.weight, f / pdf);
            assert!(
                e < 1e-3,
                "{m:?} wo {wo} wi {}: weight {} vs {}",
                s.wi,
                s.weight,
                f / pdf
            );
            worst = worst.max(e);
        }
        assert!(hits > 10_000, "{m:?}: {hits}");
    }
    eprintln!("Mitsuba BSDFs, weight vs eval/pdf: worst relative error {worst:e}");
}

/// The mean of `weight × n²` over samples, `n` the index on the side the
/// sample goes to over that of `wo`'s (undoing the radiance scaling, so
/// that a lossless interface gives 1).
fn energy(m: Material, eta: f32, wo: Vec3A, n: usize, key: u64) -> f64 {
    let mut r = rng(key);
    let mut sum = 0.0f64;
    for _ in 0..n {
        let ul = r.next_f32();
        if let Some(s) = m.sample(wo, ul, u2(&mut r)) {
            let scale = if s.wi.z * wo.z < 0.0 {
                if wo.z > 0.0 {
                    eta * eta
                } else {
                    1.0 / (eta * eta)
                }
            } else {
                1.0
            };
            sum += (s.weight.x * scale) as f64;
        }
    }
    sum / n as f64
}

#[test]
fn furnaces() {
    use MicrofacetKind::{Beckmann, Ggx};
    let inf = Vec3A::splat(f32::INFINITY);
    for kind in [Beckmann, Ggx] {
        for theta in [0.0f32, 50.0, 80.0] {
            let wo = dir(theta, 0.3);
            // A perfect rough conductor: only masking loses energy.
            for alpha in [0.01f32, 0.5] {
                let m = Material::MiRoughConductor(RoughConductor::new(
                    kind,
                    alpha,
                    alpha,
                    Vec3A::ZERO,
                    inf,
                    Vec3A::ONE,
                ));
                let (a, se) = albedo(m, wo, 100_000, 61);
                assert!(a <= 1.0 + 4.0 * se, "{m:?}: {a}");
                if alpha == 0.01 {
                    assert!(a > 0.99, "{kind:?} θ {theta}: {a}");
                } else {
                    // The quadrature resolves the wide lobe only.
                    let q = albedo_by_quadrature(m, wo);
                    assert!((a - q).abs() < 4.0 * se + 2e-3, "{m:?}: {a} vs {q}");
                    eprintln!("perfect rough conductor {kind:?} α 0.5 θ {theta}: {a:.4}");
                }
            }
            // Smooth glass and the thin sheet keep everything, exactly.
            for side in [1.0f32, -1.0] {
                let wo = wo * Vec3A::new(1.0, 1.0, side);
                let glass =
                    Material::MiDielectric(SmoothDielectric::new(1.5, Vec3A::ONE, Vec3A::ONE));
                assert!((energy(glass, 1.5, wo, 20_000, 62) - 1.0).abs() < 1e-6);
                let thin =
                    Material::MiThinDielectric(ThinDielectric::new(1.5, Vec3A::ONE, Vec3A::ONE));
                assert!((energy(thin, 1.0, wo, 20_000, 63) - 1.0).abs() < 1e-6);
                // A nearly smooth rough interface nearly so (R + T ≤ 1).
                let rough = Material::MiRoughDielectric(RoughDielectric::new(
                    kind,
                    0.01,
                    0.01,
                    1.5,
                    Vec3A::ONE,
                    Vec3A::ONE,
                ));
                let e = energy(rough, 1.5, wo, 100_000, 64);
                assert!(
                    e <= 1.0 + 1e-3 && e > 0.985,
                    "{kind:?} θ {theta} side {side}: {e}"
                );
            }
        }
    }
    // A white plastic: the coating's fits make it close to 1 (Mitsuba's
    // `F_dr` fits; the exact model conserves energy), from every angle.
    for nonlinear in [false, true] {
        let m = Material::MiPlastic(Plastic::new(1.5, Vec3A::ONE, Vec3A::ONE, nonlinear));
        for theta in [0.0f32, 45.0, 80.0] {
            let (a, se) = albedo(m, dir(theta, 1.0), 200_000, 65);
            eprintln!("white plastic θ {theta}: {a:.4} ± {se:.4}");
            assert!((a - 1.0).abs() < 0.01 + 4.0 * se, "θ {theta}: {a}");
        }
    }
    // A white rough plastic never gains, and loses what Mitsuba's model
    // loses: its internal reflectance, integrated with single scattering,
    // is below the smooth coating's: it keeps 88–91 % at α = 0.1.
    let m = Material::MiRoughPlastic(RoughPlastic::new(
        Ggx,
        0.1,
        1.5,
        Vec3A::ONE,
        Vec3A::ONE,
        false,
    ));
    for theta in [0.0f32, 45.0, 80.0] {
        let (a, se) = albedo(m, dir(theta, 1.0), 200_000, 66);
        eprintln!("white rough plastic α 0.1 θ {theta}: {a:.4} ± {se:.4}");
        assert!(a < 1.0 + 0.01 && a > 0.86, "θ {theta}: {a}");
    }
}

#[test]
fn rough_plastic_table_is_the_rough_dielectric_transmittance() {
    // T(μ) is the rough interface's directional transmittance: the rough
    // dielectric's transmitted albedo with the radiance scaling undone, by
    // quadrature over the sphere (an independent integration of the same
    // model).
    for (kind, alpha) in [
        (MicrofacetKind::Beckmann, 0.2f32),
        (MicrofacetKind::Ggx, 0.5),
    ] {
        let table = RoughPlasticTable::get(kind, alpha, 1.5);
        let d = RoughDielectric::new(kind, alpha, alpha, 1.5, Vec3A::ONE, Vec3A::ONE);
        for j in [9usize, 32, 50, 63] {
            let mu = j as f32 / 63.0;
            let wo = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let t: f64 = integrate_bins(|wi| if wi.z < 0.0 { d.eval(wo, wi).x } else { 0.0 })
                .iter()
                .sum::<f64>()
                * 2.25;
            let got = table.external_transmittance[j] as f64;
            assert!(
                (got - t).abs() < 2e-3,
                "{kind:?} α {alpha} μ {mu}: table {got} vs {t}"
            );
        }
        // Below the smooth interface's F_dr(1/1.5) = 0.597: rougher
        // interfaces let more of the light inside out (and single scattering
        // loses some). (Its value is checked against Mitsuba's through the
        // rough plastics' eval.)
        let r = table.internal_reflectance;
        assert!(r > 0.2 && r < 0.597, "{kind:?} α {alpha}: {r}");
        // Built once and shared.
        assert!(std::ptr::eq(
            table,
            RoughPlasticTable::get(kind, alpha, 1.5)
        ));
    }
}

#[test]
fn reciprocity() {
    let mut r = rng(88);
    for m in glossy() {
        for _ in 0..2000 {
            let (a, b) = (sphere(&mut r), sphere(&mut r));
            let (a, b) = if !one_sided(&m) {
                (a, b)
            } else {
                (
                    a * Vec3A::new(1.0, 1.0, a.z.signum()),
                    b * Vec3A::new(1.0, 1.0, b.z.signum()),
                )
            };
            if a.z.abs() < 0.05 || b.z.abs() < 0.05 {
                continue;
            }
            // f(a, b) n_b² = f(b, a) n_a² (n the index on each side; 1 for
            // reflection), with f = eval / |cos θi|.
            let eta = match m {
                Material::MiRoughDielectric(d) => d.eta,
                Material::MiPrincipled(p) => p.eta,
                _ => 1.0,
            };
            let n2 = |w: Vec3A| if w.z < 0.0 { eta * eta } else { 1.0 };
            // The thin sheet's specular transmission is not reciprocal
            // (see principled_thin_transmission_is_not_reciprocal).
            if matches!(m, Material::MiPrincipledThin(_)) && a.z * b.z < 0.0 {
                continue;
            }
            // A refraction that grazes its microfacet is at the critical
            // angle, where f32 cannot resolve 1 − F (cos θt² of order
            // 1e-5): both sides' values are off by up to a percent there.
            if a.z * b.z < 0.0 {
                let eta_a = if a.z > 0.0 { eta } else { 1.0 / eta };
                let m = (a + eta_a * b).normalize();
                if a.dot(m).abs().min(b.dot(m).abs()) < 0.05 {
                    continue;
                }
            }
            let fab = m.eval(a, b) / b.z.abs() * n2(b);
            let fba = m.eval(b, a) / a.z.abs() * n2(a);
            if fab.max_element() < 1e-3 {
                continue;
            }
            assert!(close(fab, fba, 2e-3), "{m:?} {a} {b}: {fab} vs {fba}");
        }
    }
}

#[test]
fn anisotropy_turns_with_the_tangent() {
    // Widths (0.1, 0.4) with the tangent along the frame's y are widths
    // (0.4, 0.1) along x.
    let frame = Frame::from_normal(Vec3A::Z);
    let mut a = RoughConductor::new(MicrofacetKind::Ggx, 0.1, 0.4, ETA, K, Vec3A::ONE);
    a.orient_anisotropy(&frame, frame.b);
    let b = RoughConductor::new(MicrofacetKind::Ggx, 0.4, 0.1, ETA, K, Vec3A::ONE);
    let mut r = rng(5);
    for _ in 0..100 {
        let (wo, wi) = (
            sphere(&mut r).abs(),
            sphere(&mut r) * Vec3A::new(1.0, -1.0, 1.0),
        );
        let wi = wi * Vec3A::new(1.0, 1.0, wi.z.signum());
        assert!(close(a.eval(wo, wi), b.eval(wo, wi), 1e-4));
        assert!((a.pdf(wo, wi) - b.pdf(wo, wi)).abs() <= 1e-4 * b.pdf(wo, wi));
    }
    let u = Vec2::new(0.3, 0.8);
    let (sa, sb) = (
        a.sample(Vec3A::new(0.3, 0.4, 0.866), u),
        b.sample(Vec3A::new(0.3, 0.4, 0.866), u),
    );
    assert!(sa.is_some() && sb.is_some());
    // Untouched when isotropic.
    let mut iso = RoughConductor::new(MicrofacetKind::Ggx, 0.3, 0.3, ETA, K, Vec3A::ONE);
    iso.orient_anisotropy(&frame, frame.b);
    assert_eq!(iso.tangent, Tangent::X);
}

#[test]
fn one_sided_back_faces_and_degenerate_inputs_are_safe() {
    let mut r = rng(99);
    let mut all: Vec<Material> = referenced().into_iter().map(|(_, m, _, _)| m).collect();
    all.extend(glossy());
    for m in all {
        if one_sided(&m) {
            for _ in 0..100 {
                let wo = sphere(&mut r) * Vec3A::new(1.0, 1.0, -1.0);
                let wo = wo * Vec3A::new(1.0, 1.0, if wo.z > 0.0 { -1.0 } else { 1.0 });
                let wi = sphere(&mut r);
                assert!(m.sample(wo, 0.5, u2(&mut r)).is_none(), "{m:?}");
                assert_eq!(m.eval(wo, wi), Vec3A::ZERO);
                assert_eq!(m.pdf(wo, wi), 0.0);
                // And nothing towards the back from the front.
                let wo = wo * Vec3A::new(1.0, 1.0, -1.0);
                let wi = wi * Vec3A::new(1.0, 1.0, if wi.z > 0.0 { -1.0 } else { 1.0 });
                assert_eq!(m.eval(wo, wi), Vec3A::ZERO, "{m:?}");
                assert_eq!(m.pdf(wo, wi), 0.0);
            }
        }
        for wo in [
            Vec3A::Z,
            -Vec3A::Z,
            dir(89.99, 0.1),
            Vec3A::new(1.0, 0.0, 1e-30).normalize(),
            Vec3A::ZERO,
            Vec3A::NAN,
        ] {
            for u in [Vec2::ZERO, Vec2::splat(0.999_999_9), Vec2::new(0.5, 0.0)] {
                for wi in [
                    Vec3A::Z,
                    -wo,
                    Vec3A::new(-wo.x, -wo.y, wo.z),
                    dir(89.99, 3.0),
                ] {
                    let (f, p) = (m.eval(wo, wi), m.pdf(wo, wi));
                    assert!(f.is_finite() && p.is_finite(), "{m:?} {wo} {wi}");
                    assert!(f.min_element() >= 0.0 && p >= 0.0);
                }
                for ul in [0.0, 0.5, 0.999_999] {
                    if let Some(s) = m.sample(wo, ul, u) {
                        assert!(
                            s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                            "{m:?} {s:?}"
                        );
                        assert!(
                            s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4,
                            "{m:?} {s:?}"
                        );
                    }
                }
            }
        }
        // The guides stay in range.
        for wo in [Vec3A::Z, dir(60.0, 1.0), -dir(30.0, 2.0)] {
            let g = m.guide_lobes(wo);
            assert!(g.rough.cmple(Vec3A::ONE).all() && g.rough.cmpge(Vec3A::ZERO).all());
            let a = m.albedo(wo.z);
            assert!(
                a.cmple(Vec3A::ONE).all() && a.cmpge(Vec3A::ZERO).all(),
                "{m:?}: {a}"
            );
        }
    }
}

#[test]
fn material_stays_small() {
    /// `Material` as it was before the Mitsuba variants (the same
    /// variants and fields, so the same layout).
    #[allow(dead_code)]
    enum Before {
        Diffuse { reflectance: Vec3A },
        Mirror { reflectance: Vec3A },
        Dielectric { ior: f32 },
        RoughConductor { alpha: f32, eta: Vec3A, k: Vec3A },
        Pbr(PbrBsdf),
    }
    let (now, before) = (
        std::mem::size_of::<Material>(),
        std::mem::size_of::<Before>(),
    );
    eprintln!("size_of::<Material>() = {now} (before the Mitsuba BSDFs: {before})");
    // The blend of two Mitsuba BSDFs, held inline (so that a material
    // stays `Copy` and nothing is allocated per ray), is the largest
    // variant, its tag in the parts' niche; every other Mitsuba BSDF fits
    // beside the glTF one.
    assert_eq!(now, std::mem::size_of::<crate::materials::Blend>());
    assert!(std::mem::size_of::<crate::materials::BlendPart>() <= before);
}

#[test]
fn principled_furnaces() {
    // Lossless configurations keep (nearly) everything from every angle
    // and side: glass (transmission only, the 1/η² undone), a white metal
    // (Schlick's F of a white base colour is 1) and the thin sheet's
    // specular lobes; the thin sheet's Lambertian transmission exactly.
    let glass = Material::MiPrincipled(Principled {
        roughness: 0.1,
        ..pr_glass()
    });
    let metal = Material::MiPrincipled(Principled {
        base_color: Vec3A::ONE,
        metallic: 1.0,
        roughness: 0.1,
        ..Principled::default()
    });
    let thin = Material::MiPrincipledThin(PrincipledThin {
        roughness: 0.1,
        ..pt_glass()
    });
    let lambert = Material::MiPrincipledThin(PrincipledThin {
        base_color: Vec3A::ONE,
        diff_trans: 2.0,
        ..PrincipledThin::default()
    });
    for theta in [0.0f32, 45.0, 80.0] {
        for side in [1.0f32, -1.0] {
            let wo = dir(theta, 0.3) * Vec3A::new(1.0, 1.0, side);
            let g = energy(glass, 1.5, wo, 100_000, 71);
            eprintln!("principled glass α 0.01 θ {theta} side {side}: {g:.4}");
            assert!(
                g <= 1.0 + 2e-3 && g > 0.98,
                "glass θ {theta} side {side}: {g}"
            );
            let t = energy(thin, 1.0, wo, 100_000, 72);
            eprintln!("principledthin glass θ {theta} side {side}: {t:.4}");
            assert!(
                t <= 1.0 + 2e-3 && t > 0.98,
                "thin θ {theta} side {side}: {t}"
            );
            let l = energy(lambert, 1.0, wo, 20_000, 73);
            assert!((l - 1.0).abs() < 1e-5, "thin Lambertian θ {theta}: {l}");
        }
        let (a, se) = albedo(metal, dir(theta, 0.3), 100_000, 74);
        eprintln!("principled white metal α 0.01 θ {theta}: {a:.4} ± {se:.4}");
        assert!(a <= 1.0 + 4.0 * se && a > 0.98, "metal θ {theta}: {a}");
    }
    // A white default principled is not energy conserving: its Burley
    // diffuse (with the retro reflection) is added to the full specular
    // reflection with no (1 − F) between them. The sampled albedo equals
    // the quadrature of eval (the estimator is right) and exceeds 1 at
    // grazing angles.
    let white = Material::MiPrincipled(Principled {
        base_color: Vec3A::ONE,
        ..Principled::default()
    });
    let mut most = 0.0f64;
    for theta in [0.0f32, 45.0, 70.0, 85.0] {
        let wo = dir(theta, 0.3);
        let (a, se) = albedo(white, wo, 200_000, 75);
        let q = albedo_by_quadrature(white, wo);
        eprintln!("white principled θ {theta}: {a:.4} ± {se:.4} (quadrature {q:.4})");
        assert!((a - q).abs() < 4.0 * se + 5e-3, "θ {theta}: {a} vs {q}");
        most = most.max(a);
    }
    assert!(most > 1.02, "{most}");
}

#[test]
fn principled_thin_is_the_same_from_both_sides() {
    let mut r = rng(41);
    for m in [pt_full(), pt_rates(), PrincipledThin::default()] {
        let m = Material::MiPrincipledThin(m);
        for _ in 0..500 {
            let (wo, wi) = (sphere(&mut r), sphere(&mut r));
            assert_eq!(m.eval(wo, wi), m.eval(-wo, -wi), "{m:?}");
            assert_eq!(m.pdf(wo, wi), m.pdf(-wo, -wi));
            let (ul, u) = (r.next_f32(), u2(&mut r));
            let (a, b) = (m.sample(wo, ul, u), m.sample(-wo, ul, u));
            assert_eq!(a.map(|s| -s.wi), b.map(|s| s.wi));
        }
    }
    // principled without transmission: nothing from below (checked with
    // the other one-sided BSDFs); with it, from below only the main
    // specular lobes (reflection weighted by w_bsdf F, no diffuse).
    let p = pr_trans();
    let below = dir(30.0, 0.2) * Vec3A::new(1.0, 1.0, -1.0);
    let rough = Principled {
        roughness: 1.0,
        ..p
    };
    let diffuse_only = dir(70.0, 2.5) * Vec3A::new(1.0, 1.0, -1.0);
    assert!(p.transmits() && rough.eval(below, diffuse_only).max_element() > 0.0);
    let no_spec = Principled {
        spec_trans: 0.0,
        ..rough
    };
    assert_eq!(no_spec.eval(below, diffuse_only), Vec3A::ZERO);
}

#[test]
fn principled_anisotropy_turns_with_the_tangent() {
    // The tangent along the frame's y: the BSDF sees (y, −x, z).
    let frame = Frame::from_normal(Vec3A::Z);
    let turn = |v: Vec3A| Vec3A::new(v.y, -v.x, v.z);
    let mut r = rng(6);
    for (a, b) in [
        (
            Material::MiPrincipled(pr_trans()),
            Material::MiPrincipled(pr_trans()),
        ),
        (
            Material::MiPrincipledThin(pt_full()),
            Material::MiPrincipledThin(pt_full()),
        ),
    ] {
        let mut a = a;
        a.orient_anisotropy(&frame, frame.b, frame.t);
        assert_ne!(a, b);
        for _ in 0..200 {
            let (wo, wi) = (sphere(&mut r), sphere(&mut r));
            assert!(close(a.eval(wo, wi), b.eval(turn(wo), turn(wi)), 1e-5));
            let (pa, pb) = (a.pdf(wo, wi), b.pdf(turn(wo), turn(wi)));
            assert!((pa - pb).abs() <= 1e-5 * pb, "{pa} vs {pb}");
        }
    }
    // Isotropic ones are not turned.
    let mut iso = Material::MiPrincipled(pr_glass());
    iso.orient_anisotropy(&frame, frame.b, frame.t);
    assert_eq!(iso, Material::MiPrincipled(pr_glass()));
}

#[test]
fn principled_parameters_are_set_by_name() {
    use PrincipledParam::*;
    let names: Vec<&str> = PrincipledParam::ALL.iter().map(|p| p.name()).collect();
    assert_eq!(names[0], "roughness");
    assert_eq!(names[11], "eta");
    for (i, p) in PrincipledParam::ALL.into_iter().enumerate() {
        let v = 0.01 * (i + 1) as f32;
        let mut m = Material::MiPrincipled(Principled::default());
        let mut t = Material::MiPrincipledThin(PrincipledThin::default());
        assert_eq!(Principled::default().set(p, v), p != DiffTrans);
        assert_eq!(
            PrincipledThin::default().set(p, v),
            !matches!(p, Metallic | Clearcoat | ClearcoatGloss)
        );
        m.set_param(Param::Principled(p), v);
        t.set_param(Param::Principled(p), v);
        let (Material::MiPrincipled(m), Material::MiPrincipledThin(t)) = (m, t) else {
            unreachable!()
        };
        let got_m = [
            m.roughness,
            m.anisotropic,
            m.metallic,
            m.spec_trans,
            m.spec_tint,
            m.sheen,
            m.sheen_tint,
            m.flatness,
            m.clearcoat,
            m.clearcoat_gloss,
            v,
            m.eta,
        ];
        let got_t = [
            t.roughness,
            t.anisotropic,
            v,
            t.spec_trans,
            t.spec_tint,
            t.sheen,
            t.sheen_tint,
            t.flatness,
            v,
            v,
            t.diff_trans,
            t.eta,
        ];
        assert_eq!(got_m[i], v, "{p:?}");
        assert_eq!(got_t[i], v, "{p:?}");
    }
    // Other materials are left alone.
    let mut d = Material::Diffuse {
        reflectance: Vec3A::ONE,
    };
    d.set_param(Param::Principled(Roughness), 0.3);
    assert_eq!(
        d,
        Material::Diffuse {
            reflectance: Vec3A::ONE
        }
    );
    // A textured base colour replaces the reflectance.
    let rho = Vec3A::new(0.1, 0.2, 0.3);
    let with = crate::materials::surface::with_reflectance;
    let Material::MiPrincipled(p) = with(Material::MiPrincipled(pr_full()), rho) else {
        unreachable!()
    };
    assert_eq!(p.base_color, rho);
    let Material::MiPrincipledThin(t) = with(Material::MiPrincipledThin(pt_full()), rho) else {
        unreachable!()
    };
    assert_eq!(t.base_color, rho);
    // Mitsuba's default specular 0.5 is eta 1.5.
    assert!((Principled::eta_of_specular(0.5) - 1.5).abs() < 1e-6);
}

#[test]
fn principled_thin_transmission_is_not_reciprocal() {
    // Mitsuba's thin sheet finds the half vector of `wo` and `wi` mirrored
    // to `wo`'s side, but tests the microfacet's sides (and masks) with
    // the real `wi`: swapping the two directions can switch the specular
    // transmission off. Here it is off from `a` and on from `b`.
    let m = PrincipledThin {
        diff_trans: 0.0,
        ..pt_full()
    };
    let a = Vec3A::new(0.25660595, 0.7305452, 0.6328168);
    let b = Vec3A::new(0.670731, -0.58183914, -0.45998168);
    assert_eq!(m.eval(a, b), Vec3A::ZERO);
    assert!(m.eval(b, a).min_element() > 0.0);
}
