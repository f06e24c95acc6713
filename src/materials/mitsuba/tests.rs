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

fn referenced() -> Vec<Referenced> {
    use MicrofacetKind::{Beckmann, Ggx};
    vec![
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
    ]
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
    let mut nonzero = 0;
    for (name, m, evals, _) in referenced() {
        for r in evals {
            let (wo, wi, want, want_pdf) = (v3(&r[0..]), v3(&r[3..]), v3(&r[6..]), r[9]);
            let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
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
                worst = worst.max((f - want).abs().max_element() / want.max_element());
            }
        }
    }
    eprintln!("eval vs Mitsuba: {nonzero} non-zero values, worst relative error {worst:e}");
    assert!(nonzero >= 30, "{nonzero}");
}

#[test]
fn samples_match_mitsuba() {
    let mut checked = 0;
    for (name, m, _, samples) in referenced() {
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
            // The smooth plastic's specular lobe is its mirror direction.
            let mirror = (s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6;
            assert_eq!(s.specular, m.is_specular() || (name == "plastic" && mirror));
            checked += 1;
        }
    }
    eprintln!("samples vs Mitsuba: {checked} checked");
    assert!(checked >= 60, "{checked}");
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
    ]
}

#[test]
fn chi2_sampling_matches_pdf() {
    let thetas = [10.0f32, 60.0, 85.0];
    let materials = glossy();
    let tests = (materials.len() * thetas.len()) as u32 + 4 * thetas.len() as u32;
    let mut key = 900;
    let mut min_p = 1.0f64;
    for m in &materials {
        let sides: &[f32] = if m.transmits() { &[1.0, -1.0] } else { &[1.0] };
        for &side in sides {
            for theta in thetas {
                key += 1;
                let wo = dir(theta, 0.4) * Vec3A::new(1.0, 1.0, side);
                let p = chi2_p_value(*m, wo, key);
                eprintln!("chi2 {m:?} wo {wo}: p = {p:.4}");
                assert!(p > sidak_threshold(tests), "{m:?} wo {wo}: p = {p}");
                min_p = min_p.min(p);
            }
        }
    }
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
            let mut wo = sphere(&mut r);
            if !m.transmits() {
                wo.z = wo.z.abs();
            }
            if wo.z.abs() < 1e-3 {
                continue;
            }
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
            let (a, b) = if m.transmits() {
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
                _ => 1.0,
            };
            let n2 = |w: Vec3A| if w.z < 0.0 { eta * eta } else { 1.0 };
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
        if !m.transmits() {
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
    // The glTF BSDF is the largest variant: the Mitsuba ones fit beside it.
    assert_eq!(now, before);
}
