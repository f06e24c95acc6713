//! Single wavelengths for `KHR_materials_dispersion`: the index of
//! refraction at a wavelength, the choice of a path's wavelength, and the
//! RGB weight that turns a path carried at one wavelength back into the
//! renderer's linear Rec. 709.
//!
//! # The wavelength's weight
//!
//! A path that meets a dispersive surface is carried from there on at one
//! wavelength `λ`, drawn with density `p(λ)` on
//! `[`[`LAMBDA_MIN`]`, `[`LAMBDA_MAX`]`]` nm, and its throughput is multiplied
//! by `W(λ) = r(λ) / p(λ)`, where `r` are the CIE 1931 2° colour-matching
//! functions `(x̄, ȳ, z̄)` taken to linear Rec. 709 (the sRGB primaries, D65)
//! and scaled per channel so that `∫ r(λ) dλ = (1, 1, 1)`: an equal-energy
//! spectrum is white. So `E[W] = (1, 1, 1)`: a path that disperses nothing
//! (every wavelength goes the same way) has, in expectation, the weight it
//! would have had in RGB. `r` has negative lobes (no RGB primary set spans
//! the spectral colours: the red channel below 0 in the cyan), so single
//! samples may be negative in a channel; their mean is not.
//!
//! `x̄, ȳ, z̄` are Wyman, Sloan and Shirley's multi-lobe Gaussian fit ("Simple
//! Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT
//! 2(2), 2013), within a few per cent of the tabulated functions: a formula,
//! not a table. The per-channel normalisation is integrated numerically once
//! ([`rgb_norm`]).
//!
//! `p` is pbrt-v4's density for visible wavelengths, `∝ 1 / cosh²(0.0072 (λ −
//! 538))`, sampled by inverting its CDF exactly. It follows the luminance
//! rather than the blue, so `|W|` reaches 7.7 in the blue at 440 nm (the
//! second moments of `W` are 6.7, 3.4 and 6.3 per channel; a density
//! proportional to `Σ |r|`, which would need a tabulated inverse, would give
//! 5.0, 2.9 and 3.9).
//!
//! Nothing here allocates (but [`rgb_norm`]'s one-time integral).

use glam::Vec3A;
use std::sync::OnceLock;

/// Shortest wavelength a path is carried at, in nm.
pub const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength a path is carried at, in nm.
pub const LAMBDA_MAX: f32 = 830.0;

/// Fraunhofer's d line (helium), in nm: where `ior` is the index.
pub const LAMBDA_D: f32 = 587.56;
/// Fraunhofer's F line (hydrogen), in nm.
pub const LAMBDA_F: f32 = 486.13;
/// Fraunhofer's C line (hydrogen), in nm.
pub const LAMBDA_C: f32 = 656.27;

/// The index of refraction at wavelength `lambda` (nm) of a material of
/// index `ior` at the d line and `KHR_materials_dispersion` value
/// `dispersion = 20 / V_d` (`V_d` the Abbe number), by the extension's
/// two-term Cauchy equation:
///
/// `n(λ) = max(ior + (ior − 1) / V_d (523655 / λ² − 1.5168), 1)`.
///
/// `dispersion` 0 gives `ior` at every wavelength. A result that is not
/// finite (absurd inputs) is `ior`.
#[inline]
pub fn dispersed_ior(ior: f32, dispersion: f32, lambda: f32) -> f32 {
    let n = ior + (ior - 1.0) * (dispersion / 20.0) * (523_655.0 / (lambda * lambda) - 1.5168);
    if n.is_finite() { n.max(1.0) } else { ior }
}

/// The width parameter of the wavelength density `∝ 1/cosh²(K (λ − 538))`.
const K: f32 = 0.0072;
/// Its centre, in nm.
const CENTRE: f32 = 538.0;

/// The CDF's two halves, `tanh(K (centre − LAMBDA_MIN))` and
/// `tanh(K (LAMBDA_MAX − centre))`: the CDF is `(tanh(K (λ − centre)) + lo)
/// / (lo + hi)`.
#[inline]
fn cdf_ends() -> (f32, f32) {
    (
        (K * (CENTRE - LAMBDA_MIN)).tanh(),
        (K * (LAMBDA_MAX - CENTRE)).tanh(),
    )
}

/// The density with which [`sample_wavelength`] draws `lambda` (per nm; 0
/// outside `[LAMBDA_MIN, LAMBDA_MAX]`).
#[inline]
pub fn wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let (lo, hi) = cdf_ends();
    let c = (K * (lambda - CENTRE)).cosh();
    K / ((lo + hi) * c * c)
}

/// A wavelength (nm) for `u ∈ [0, 1)`, by inverting the CDF of
/// [`wavelength_pdf`]: monotonic in `u`, so stratified `u` give stratified
/// wavelengths.
#[inline]
pub fn sample_wavelength(u: f32) -> f32 {
    let (lo, hi) = cdf_ends();
    let x = (u.clamp(0.0, 1.0) * (lo + hi) - lo).clamp(-lo, hi);
    (CENTRE + x.atanh() / K).clamp(LAMBDA_MIN, LAMBDA_MAX)
}

/// A piecewise Gaussian lobe: `exp(−½ ((λ − μ)/σ)²)` with `σ = s1` below `μ`
/// and `s2` above.
#[inline]
fn lobe(lambda: f32, mu: f32, s1: f32, s2: f32) -> f32 {
    let t = (lambda - mu) / if lambda < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// The CIE 1931 2° colour-matching functions `(x̄, ȳ, z̄)` at `lambda` (nm),
/// by Wyman, Sloan and Shirley's multi-lobe fit (their equation 2).
#[inline]
pub fn cie_xyz(lambda: f32) -> Vec3A {
    let x = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
        - 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
    Vec3A::new(x, y, z)
}

/// CIE XYZ to linear Rec. 709 (sRGB primaries, D65 white), the usual matrix.
#[inline]
pub fn xyz_to_rec709(c: Vec3A) -> Vec3A {
    Vec3A::new(
        3.240_454_2 * c.x - 1.537_138_5 * c.y - 0.498_531_4 * c.z,
        -0.969_266 * c.x + 1.876_010_8 * c.y + 0.041_556 * c.z,
        0.055_643_4 * c.x - 0.204_025_9 * c.y + 1.057_225_2 * c.z,
    )
}

/// `∫ xyz_to_rec709(cie_xyz(λ)) dλ` over `[LAMBDA_MIN, LAMBDA_MAX]` per
/// channel, integrated once (midpoint rule, 0.05 nm steps, in f64): what
/// [`rgb_response`] divides by.
pub fn rgb_norm() -> Vec3A {
    static NORM: OnceLock<Vec3A> = OnceLock::new();
    *NORM.get_or_init(|| {
        const STEPS: usize = 9400;
        let h = f64::from(LAMBDA_MAX - LAMBDA_MIN) / STEPS as f64;
        let mut sum = [0.0f64; 3];
        for i in 0..STEPS {
            let lambda = f64::from(LAMBDA_MIN) + (i as f64 + 0.5) * h;
            let c = xyz_to_rec709(cie_xyz(lambda as f32));
            for (s, v) in sum.iter_mut().zip(c.to_array()) {
                *s += f64::from(v) * h;
            }
        }
        Vec3A::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
    })
}

/// The linear Rec. 709 response `r(λ)` to light of wavelength `lambda`
/// (per nm), normalised so that `∫ r dλ = (1, 1, 1)` over the sampled range.
#[inline]
pub fn rgb_response(lambda: f32) -> Vec3A {
    xyz_to_rec709(cie_xyz(lambda)) / rgb_norm()
}

/// A path's wavelength for `u ∈ [0, 1)` and its weight `r(λ) / p(λ)`, whose
/// expectation over `u` is `(1, 1, 1)`.
#[inline]
pub fn sample_weighted(u: f32) -> (f32, Vec3A) {
    let lambda = sample_wavelength(u);
    let pdf = wavelength_pdf(lambda);
    let w = rgb_response(lambda) / pdf;
    (lambda, if w.is_finite() { w } else { Vec3A::ZERO })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// n(d) is the ior, and n(F) − n(C) = (ior − 1)/V_d: the Abbe number's
    /// definition (to the rounding of the spec's 523655 and 1.5168).
    #[test]
    fn cauchy_ior_matches_the_abbe_number() {
        for ior in [1.33f32, 1.5, 1.7, 2.42] {
            for dispersion in [0.0f32, 0.2, 0.36, 1.0, 2.04] {
                let n_d = dispersed_ior(ior, dispersion, LAMBDA_D);
                assert!((n_d - ior).abs() < 2e-5, "n(d) = {n_d}, ior {ior}");
                let spread = dispersed_ior(ior, dispersion, LAMBDA_F)
                    - dispersed_ior(ior, dispersion, LAMBDA_C);
                let want = (ior - 1.0) * dispersion / 20.0;
                assert!(
                    (spread - want).abs() <= 2e-3 * want + 1e-6,
                    "n(F) − n(C) = {spread}, (ior − 1)/V = {want}"
                );
                // Blue bends more than red.
                if dispersion > 0.0 {
                    assert!(
                        dispersed_ior(ior, dispersion, 450.0)
                            > dispersed_ior(ior, dispersion, 650.0)
                    );
                }
            }
        }
        // Clamped at 1 far into the red with an absurd dispersion.
        assert_eq!(dispersed_ior(1.1, 50.0, 830.0), 1.0);
        assert_eq!(dispersed_ior(1.5, f32::INFINITY, 400.0), 1.5);
    }

    /// The density integrates to 1, and the sampler's CDF is the density's:
    /// the share of draws below λ (on a regular grid of u) matches ∫ p.
    #[test]
    fn wavelength_sampling_matches_its_density() {
        let n = 200_000;
        let h = (LAMBDA_MAX - LAMBDA_MIN) as f64 / n as f64;
        let total: f64 = (0..n)
            .map(|i| wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * h) as f32) as f64 * h)
            .sum();
        assert!((total - 1.0).abs() < 1e-4, "∫ p = {total}");
        for lambda in [400.0f32, 480.0, 538.0, 600.0, 700.0] {
            let below = (0..100_000)
                .filter(|&i| sample_wavelength((i as f32 + 0.5) / 100_000.0) < lambda)
                .count() as f64
                / 100_000.0;
            let steps = 20_000;
            let hh = (lambda - LAMBDA_MIN) as f64 / steps as f64;
            let cdf: f64 = (0..steps)
                .map(|i| wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * hh) as f32) as f64 * hh)
                .sum();
            assert!(
                (below - cdf).abs() < 1e-3,
                "λ {lambda}: {below} drawn below, CDF {cdf}"
            );
        }
        assert_eq!(sample_wavelength(0.0), LAMBDA_MIN);
        assert!(sample_wavelength(0.999_999_9) <= LAMBDA_MAX);
    }

    /// The expectation of the wavelength's weight is white: by quadrature of
    /// `W p` in u (the sampler's own map), and the fit is the CIE's where it
    /// matters (the ȳ peak, the x̄ and z̄ peaks, within the fit's few per cent).
    #[test]
    fn wavelength_weight_is_white_in_expectation() {
        let n = 1_000_000;
        let mut sum = [0.0f64; 3];
        for i in 0..n {
            let (_, w) = sample_weighted((i as f32 + 0.5) / n as f32);
            for (s, v) in sum.iter_mut().zip(w.to_array()) {
                *s += f64::from(v) / n as f64;
            }
        }
        for (c, s) in sum.iter().enumerate() {
            assert!((s - 1.0).abs() < 2e-3, "E[W] channel {c} = {s}");
        }
        // The weights stay bounded (the density follows the response).
        let most = (0..10_000)
            .map(|i| {
                sample_weighted((i as f32 + 0.5) / 1e4)
                    .1
                    .abs()
                    .max_element()
            })
            .fold(0.0f32, f32::max);
        assert!(most < 8.0, "largest |W| = {most}");
        // Tabulated CIE 1931 values (ȳ(555) = 1.0002, x̄(600) = 1.0622,
        // z̄(445) = 1.7826 at 5 nm resolution).
        let xyz = cie_xyz(555.0);
        assert!((xyz.y - 1.0).abs() < 0.03, "ȳ(555) = {}", xyz.y);
        assert!((cie_xyz(600.0).x - 1.0622).abs() < 0.05);
        assert!((cie_xyz(445.0).z - 1.7826).abs() < 0.09);
        // Red, green and blue where they should be.
        let (r, g, b) = (
            rgb_response(620.0),
            rgb_response(530.0),
            rgb_response(450.0),
        );
        assert!(r.x > r.y && r.x > r.z && g.y > g.x && g.y > g.z && b.z > b.x && b.z > b.y);
    }
}
