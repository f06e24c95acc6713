//! `KHR_materials_sheen`'s sheen lobe: the "Charlie" microfibre BRDF of
//! Conty & Kulla (2017) as the extension's implementation notes write it,
//! and the directional albedos of its albedo-scaling layering.
//!
//! With `ρ` the sheen roughness, `α = max(ρ², ALPHA_MIN)`, `h` the half
//! vector and `μ` cosines to the normal:
//!
//! * `D(h) = (2 + 1/α) (1 − h_z²)^(1/(2α)) / (2π)`;
//! * `G = 1 / (1 + Λ(μo) + Λ(μi))` with the specification's fit of `Λ`;
//! * `f_charlie = D G / (4 μo μi)`.
//!
//! That fit's `Λ` is too small near the horizon for a narrow lobe: the
//! albedo `E_charlie(μo, ρ)` exceeds 1 at grazing angles below `ρ ≈ 0.3`
//! (1.75 at `μo = 1/64`, `ρ = 0.1`; `tools/make_sheen_table.py`), so that
//! sheen alone would reflect more light than it receives. raylab's sheen is
//!
//! `f_sheen = f_charlie / max(1, E_charlie(μo), E_charlie(μi))`,
//!
//! the specification's BRDF wherever its albedo is at most 1 both ways,
//! reciprocal, and never reflecting more than it receives. Its albedo
//! `E(μo, ρ)` is the `E` of the specification's layering:
//!
//! `f = C f_sheen + f_base min(1 − max(C) E(μo), 1 − max(C) E(μi))`.
//!
//! Both albedos are tables made by `tools/make_sheen_table.py`
//! ([`sheen_table`](super::sheen_table)), looked up bilinearly.

use super::sheen_table::{ALPHA_MIN, E, E_CHARLIE, SIZE};
use glam::Vec3A;
use std::f32::consts::PI;

/// The sheen's `α` for the sheen roughness `ρ` (the specification's
/// `alpha_g = sheenRoughness²`, at least [`ALPHA_MIN`]).
#[inline]
pub fn alpha(roughness: f32) -> f32 {
    (roughness * roughness).max(ALPHA_MIN)
}

/// The specification's `l(x, alpha_g)`.
#[inline]
fn l_fit(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let (a, b, c) = (
        mix(21.5473, 25.3245),
        mix(3.82987, 3.32435),
        mix(0.19823, 0.16801),
    );
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// The specification's `lambda_sheen(cos θ, alpha_g)` (`cos ≥ 0`).
#[inline]
fn lambda(cos: f32, alpha: f32) -> f32 {
    if cos < 0.5 {
        l_fit(cos, alpha).exp()
    } else {
        (2.0 * l_fit(0.5, alpha) - l_fit(1.0 - cos, alpha)).exp()
    }
}

/// The Charlie distribution `D(h)` for `cos = h·n`.
#[inline]
fn charlie_d(alpha: f32, cos: f32) -> f32 {
    let inv = alpha.recip();
    let sin2 = (1.0 - cos * cos).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) * (0.5 / PI)
}

/// `table` at `(μ, ρ)`: bilinear between the cells' centres
/// `μ = (i + ½)/SIZE` and the rows `ρ = j/(SIZE − 1)`, extended linearly
/// over the half cells at `μ = 0` and `μ = 1` (the same lookup as the
/// tool's).
#[inline]
fn lookup(table: &[[f32; SIZE]; SIZE], cos: f32, roughness: f32) -> f32 {
    let last = (SIZE - 1) as f32;
    let x = (cos * SIZE as f32 - 0.5).clamp(-0.5, last + 0.5);
    let y = (roughness * last).clamp(0.0, last);
    // (NaN inputs clamp to NaN and index 0 through `as`; the result is NaN.)
    let i = (x.max(0.0) as usize).min(SIZE - 2);
    let j = (y as usize).min(SIZE - 2);
    let (tx, ty) = (x - i as f32, y - j as f32);
    let row = |r: &[f32; SIZE]| r[i] + (r[i + 1] - r[i]) * tx;
    let (a, b) = (row(&table[j]), row(&table[j + 1]));
    a + (b - a) * ty
}

/// The directional albedo `E(μ, ρ)` of the white sheen lobe, in `[0, 1]`.
#[inline]
pub fn albedo(cos: f32, roughness: f32) -> f32 {
    lookup(&E, cos, roughness).clamp(0.0, 1.0)
}

/// The white sheen's `f_sheen |cos θi|` for `wo`, `wi` above the surface
/// (`+z`), roughness `ρ`; zero otherwise.
#[inline]
pub fn eval(wo: Vec3A, wi: Vec3A, roughness: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let a = alpha(roughness);
    let (cos_o, cos_i) = (wo.z.min(1.0), wi.z.min(1.0));
    let h = (wo + wi).normalize();
    let g = 1.0 / (1.0 + lambda(cos_o, a) + lambda(cos_i, a));
    let cap = lookup(&E_CHARLIE, cos_o, roughness)
        .max(lookup(&E_CHARLIE, cos_i, roughness))
        .max(1.0);
    let f = (charlie_d(a, h.z.min(1.0)) * g) / (4.0 * cos_o * cap);
    if f.is_finite() { f } else { 0.0 }
}

/// The Charlie BRDF of the specification without raylab's cap,
/// `f_charlie |cos θi|`: for tests of the tables.
#[cfg(test)]
pub fn eval_charlie(wo: Vec3A, wi: Vec3A, roughness: f32) -> f32 {
    let a = alpha(roughness);
    let h = (wo + wi).normalize();
    let g = 1.0 / (1.0 + lambda(wo.z, a) + lambda(wi.z, a));
    (charlie_d(a, h.z) * g) / (4.0 * wo.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ eval cos dω` over the hemisphere by stratified uniform sampling
    /// (independent of the tool's Gauss–Legendre rule on `μ = t²`).
    fn integrate(f: impl Fn(Vec3A) -> f32, n: usize) -> f64 {
        let mut sum = 0.0f64;
        for a in 0..n {
            for b in 0..n {
                let z = (a as f64 + 0.5) / n as f64;
                let phi = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let wi = Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                sum += f(wi) as f64;
            }
        }
        sum * 2.0 * std::f64::consts::PI / (n * n) as f64
    }

    fn wo(cos: f32) -> Vec3A {
        Vec3A::new((1.0 - cos * cos).sqrt(), 0.0, cos)
    }

    #[test]
    fn distribution_is_normalised() {
        // ∫ D(h) cos θh dω = 1 for every α.
        for rho in [0.3f32, 0.6, 1.0] {
            let a = alpha(rho);
            let total = integrate(|h| charlie_d(a, h.z) * h.z, 800);
            assert!((total - 1.0).abs() < 2e-3, "ρ {rho}: ∫D cos = {total}");
        }
    }

    #[test]
    fn tables_match_a_fresh_integration() {
        // The tool's tables against a different quadrature of the Rust BRDF,
        // at cell centres (no interpolation error): E_CHARLIE to 0.5 %,
        // raylab's E (with its cap's kinks) to 2e-3.
        for (j, i) in [
            (31usize, 16usize),
            (20, 4),
            (10, 24),
            (9, 1),
            (3, 8),
            (31, 0),
        ] {
            let rho = j as f32 / 31.0;
            let mu = (i as f32 + 0.5) / 32.0;
            let o = wo(mu);
            let charlie = integrate(|wi| eval_charlie(o, wi, rho), 1200);
            let table = E_CHARLIE[j][i] as f64;
            assert!(
                (charlie - table).abs() < 5e-3 * table.max(0.05),
                "E_charlie(μ {mu}, ρ {rho}): {charlie} vs table {table}"
            );
            let used = integrate(|wi| eval(o, wi, rho), 1200);
            let table = E[j][i] as f64;
            assert!(
                (used - table).abs() < 2e-3,
                "E(μ {mu}, ρ {rho}): {used} vs table {table}"
            );
        }
    }

    #[test]
    fn charlie_exceeds_one_at_grazing_and_raylabs_sheen_never_does() {
        // Why the cap: the specification's BRDF gains energy at grazing
        // angles for small roughness, the capped one nowhere.
        assert!(E_CHARLIE[3][0] > 1.3, "{}", E_CHARLIE[3][0]);
        for row in E.iter() {
            for &e in row {
                assert!((0.0..=1.0 + 1e-4).contains(&e), "E {e}");
            }
        }
        // The capped BRDF is the specification's where both albedos are ≤ 1.
        let (o, i) = (wo(0.8), Vec3A::new(-0.8, 0.0, 0.6));
        for rho in [0.4f32, 0.7, 1.0] {
            assert_eq!(eval(o, i, rho), eval_charlie(o, i, rho));
        }
        // Reciprocal.
        let (a, b) = (wo(0.05), Vec3A::new(-0.3, 0.4, 0.2).normalize());
        for rho in [0.05f32, 0.2, 0.5] {
            let (ab, ba) = (eval(a, b, rho) / b.z, eval(b, a, rho) / a.z);
            assert!((ab - ba).abs() <= 1e-5 * ab.max(1e-3), "{ab} vs {ba}");
        }
    }
}
