//! Helpers shared by the tests of the material modules: deterministic random
//! numbers, directions, the χ² goodness-of-fit machinery (pbrt/Mitsuba style) and
//! albedo estimators.
//!
//! The χ² bins cover the **whole sphere** (`cos θ ∈ [−1, 1]`, `φ ∈ [0, 2π)`), so
//! transmitted directions below the horizon are binned and integrated like the
//! reflected ones; the horizon `cos θ = 0` is a bin edge.

use super::material::Material;
use crate::sampling::sampler::Rng;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;
use std::f64::consts::PI as PI64;

/// A deterministic PCG32 stream for test `key`.
pub(crate) fn rng(key: u64) -> Rng {
    Rng::new(0x5eed, key)
}

/// A 2D sample in `[0, 1)²`.
pub(crate) fn u2(r: &mut Rng) -> Vec2 {
    Vec2::new(r.next_f32(), r.next_f32())
}

/// A uniformly distributed unit vector.
pub(crate) fn sphere(r: &mut Rng) -> Vec3A {
    let z = 1.0 - 2.0 * r.next_f32();
    let s = (1.0 - z * z).max(0.0).sqrt();
    let (sp, cp) = (2.0 * PI * r.next_f32()).sin_cos();
    Vec3A::new(s * cp, s * sp, z)
}

/// A uniformly distributed `wo`, turned above the surface if `one_sided`;
/// `None` within 1e-3 of the horizon.
pub(crate) fn random_wo(r: &mut Rng, one_sided: bool) -> Option<Vec3A> {
    let mut wo = sphere(r);
    if one_sided {
        wo.z = wo.z.abs();
    }
    (wo.z.abs() >= 1e-3).then_some(wo)
}

/// The direction at polar angle `theta_deg` and azimuth `phi` (radians).
pub(crate) fn dir(theta_deg: f32, phi: f32) -> Vec3A {
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3A::new(st * cp, st * sp, ct)
}

/// Largest per-channel relative error of `a` against `b`.
pub(crate) fn rel_err(a: Vec3A, b: Vec3A) -> f32 {
    ((a - b).abs() / b.abs().max(Vec3A::splat(1e-20))).max_element()
}

/// χ² bins in `cos θ` over `[−1, 1]` (the whole sphere).
pub(crate) const COS_BINS: usize = 10;
/// χ² bins in `φ` over `[0, 2π)`.
pub(crate) const PHI_BINS: usize = 20;
/// Draws per χ² test.
pub(crate) const CHI2_SAMPLES: usize = 500_000;

/// The χ² bin of the unit direction `w`.
pub(crate) fn bin_of(w: Vec3A) -> usize {
    let c = ((w.z.clamp(-1.0, 1.0) + 1.0) * 0.5 * COS_BINS as f32) as usize;
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = (phi / (2.0 * PI) * PHI_BINS as f32) as usize;
    c.min(COS_BINS - 1) * PHI_BINS + p.min(PHI_BINS - 1)
}

/// ∫ pdf dω over each (cos θ, φ) bin (dω = d cos θ dφ): composite 3-point
/// Gauss–Legendre (open, so the pdf's jump at the horizon, a bin edge, is
/// never sampled), 48 × 96 panels per bin: fine in φ because near grazing
/// incidence the reflected lobe is narrow in azimuth (the half vector moves by
/// δφ / |wo + wi|, about α / 14 at θo = 88°).
pub(crate) fn integrate_bins(pdf: impl Fn(Vec3A) -> f32) -> Vec<f64> {
    const GL_X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const GL_W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    const PC: usize = 48;
    const PP: usize = 96;
    let dc = 2.0 / COS_BINS as f64;
    let dp = 2.0 * PI64 / PHI_BINS as f64;
    let (hc, hp) = (dc / PC as f64, dp / PP as f64);
    // The azimuths' (cos φ, sin φ, weight) once for all cos θ rows (the same
    // nodes as evaluating them in the loop, without its 10⁷ sin/cos calls).
    let phis: Vec<(f64, f64, f64)> = (0..PHI_BINS * PP)
        .flat_map(|k| {
            let (pi, b) = (k / PP, k % PP);
            GL_X.iter().zip(GL_W).map(move |(xb, wb)| {
                let p = pi as f64 * dp + (b as f64 + 0.5 + 0.5 * xb) * hp;
                (p.cos(), p.sin(), wb)
            })
        })
        .collect();
    let mut out = vec![0.0; COS_BINS * PHI_BINS];
    for ci in 0..COS_BINS {
        for (pi, phis) in phis.chunks_exact(3 * PP).enumerate() {
            let mut sum = 0.0;
            for a in 0..PC {
                for (xa, wa) in GL_X.iter().zip(GL_W) {
                    let c = -1.0 + ci as f64 * dc + (a as f64 + 0.5 + 0.5 * xa) * hc;
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    let mut row = 0.0;
                    for &(cp, sp, wb) in phis {
                        let w = Vec3A::new((s * cp) as f32, (s * sp) as f32, c as f32);
                        row += wb * pdf(w) as f64;
                    }
                    sum += wa * row;
                }
            }
            out[ci * PHI_BINS + pi] = sum * 0.25 * hc * hp;
        }
    }
    out
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI64).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes §6.2).
pub(crate) fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let lg = ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut del) = (a, 1.0 / a);
        let mut sum = del;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - lg).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - lg).exp() * h
    }
}

/// Pearson's χ² test of `sample` against `pdf` (pbrt/Mitsuba style): cells of
/// expected count < 5 are pooled; draws that return `None` form one more cell
/// whose expected count is the probability mass the pdf misses. Returns the
/// p-value.
pub(crate) fn chi2_p_value(m: Material, wo: Vec3A, key: u64) -> f64 {
    chi2_p_value_of(m, m, wo, key)
}

/// [`chi2_p_value`] of the directions `m.sample` draws against the pdf of
/// `claimed` (a different material makes the test able to fail).
pub(crate) fn chi2_p_value_of(m: Material, claimed: Material, wo: Vec3A, key: u64) -> f64 {
    let expected_density = integrate_bins(|wi| claimed.pdf(wo, wi));
    let n = CHI2_SAMPLES as f64;
    let mut expected: Vec<f64> = expected_density.iter().map(|p| p * n).collect();
    let covered: f64 = expected.iter().sum();
    expected.push((n - covered).max(0.0));
    let mut observed = vec![0.0f64; expected.len()];
    let mut r = rng(key);
    for _ in 0..CHI2_SAMPLES {
        let ul = r.next_f32();
        match m.sample(wo, ul, u2(&mut r)) {
            Some(s) => observed[bin_of(s.wi)] += 1.0,
            None => *observed.last_mut().unwrap() += 1.0,
        }
    }
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut chi2, mut dof) = (0.0, 0i32);
    let (mut pool_obs, mut pool_exp, mut pooled) = (0.0, 0.0, 0);
    for i in order {
        let (o, e) = (observed[i], expected[i]);
        if e == 0.0 {
            assert!(
                o <= n * 1e-5,
                "{m:?} wo {wo:?}: {o} samples in cell {i} of zero pdf"
            );
            pool_obs += o;
        } else if e < 5.0 || (pooled > 0 && pool_exp < 5.0) {
            pool_obs += o;
            pool_exp += e;
            pooled += 1;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_exp > 0.0 {
        chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        dof += 1;
    }
    dof -= 1;
    assert!(dof > 0, "{m:?}: too few cells");
    gamma_q(dof as f64 / 2.0, chi2 / 2.0)
}

/// The per-test p-value threshold of `tests` independent χ² tests whose
/// family-wise false-rejection rate is 1 % (Šidák correction).
/// The χ² test of every material of `materials` seen from each polar angle
/// of `thetas` (at azimuth 0.4), from above and, for those not `one_sided`,
/// from below, with keys from `key + 1` on; each must pass the Šidák
/// threshold of all of them and `extra` tests more. The smallest p value.
pub(crate) fn chi2_all(
    materials: &[Material],
    thetas: &[f32],
    one_sided: impl Fn(&Material) -> bool,
    mut key: u64,
    extra: u32,
) -> f64 {
    let sides = |m: &Material| if one_sided(m) { 1 } else { 2 };
    let tests = materials.iter().map(sides).sum::<u32>() * thetas.len() as u32 + extra;
    let mut min_p = 1.0f64;
    for m in materials {
        let sides: &[f32] = if one_sided(m) { &[1.0] } else { &[1.0, -1.0] };
        for &side in sides {
            for &theta in thetas {
                key += 1;
                let wo = dir(theta, 0.4) * Vec3A::new(1.0, 1.0, side);
                let p = chi2_p_value(*m, wo, key);
                eprintln!("chi2 {m:?} wo {wo}: p = {p:.4}");
                assert!(p > sidak_threshold(tests), "{m:?} wo {wo}: p = {p}");
                min_p = min_p.min(p);
            }
        }
    }
    min_p
}

pub(crate) fn sidak_threshold(tests: u32) -> f64 {
    1.0 - (1.0 - 0.01f64).powf(1.0 / tests as f64)
}

/// Mean sample weight (the albedo estimate) and its standard error.
pub(crate) fn albedo(m: Material, wo: Vec3A, n: usize, key: u64) -> (f64, f64) {
    let mut r = rng(key);
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let ul = r.next_f32();
        if let Some(s) = m.sample(wo, ul, u2(&mut r)) {
            let w = s.weight.x as f64;
            assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
            s1 += w;
            s2 += w * w;
        }
    }
    let mean = s1 / n as f64;
    (
        mean,
        ((s2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt(),
    )
}

/// ∫ eval dω over the whole sphere by quadrature (independent of sample()):
/// the reflected and, for transmitting materials, the transmitted albedo.
pub(crate) fn albedo_by_quadrature(m: Material, wo: Vec3A) -> f64 {
    let f = integrate_bins(|wi| m.eval(wo, wi).x);
    f.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_p_value_matches_known_quantiles() {
        // χ²(1) at 3.841459 and χ²(10) at 23.209251 have p = 0.05 and 0.01.
        assert!((gamma_q(0.5, 3.841_459 / 2.0) - 0.05).abs() < 1e-6);
        assert!((gamma_q(5.0, 23.209_251 / 2.0) - 0.01).abs() < 1e-6);
        assert!((gamma_q(50.0, 135.807 / 2.0) - 0.01).abs() < 1e-5);
        assert!((gamma_q(15.0, 43.773 / 2.0) - 0.05).abs() < 1e-5);
    }
}
