//! Mitsuba 3's microfacet model, for the BSDFs that reproduce Mitsuba's
//! (`super::super::mitsuba`): the Beckmann and GGX distributions with
//! anisotropic widths `alpha_u` (along local `x`) and `alpha_v` (along `y`),
//! Smith's *separable* masking–shadowing `G = G1(wo) G1(wi)` (not the
//! height-correlated form of the glTF lobes), with Mitsuba's rational fit of
//! Beckmann's `G1`, and the sampling of the visible normals with Mitsuba's
//! slope-space routines (Heitz and d'Eon 2014; Jakob's numerical inversion
//! for Beckmann), always on (Mitsuba's default `sample_visible = true`).
//!
//! The formulas are Mitsuba 3's (`include/mitsuba/render/microfacet.h`),
//! written anew: the widths are clamped to at least `1e-4`, `D` is zero where
//! `D cos θm ≤ 1e-20`, and `G1(v, m)` is zero when `v` sees the back of the
//! microfacet (`(v·m) v.z ≤ 0`). Sampling expects `wo.z > 0`: a BSDF that
//! scatters from below (the rough dielectric) samples with `wo` mirrored to
//! the top, as Mitsuba does.

use super::super::disk::concentric_disk;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

/// `1 / √π`.
const INV_SQRT_PI: f32 = 0.564_189_6;

/// Which microfacet distribution (Mitsuba's `distribution`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetKind {
    /// Beckmann's (Gaussian slopes); Mitsuba's default.
    Beckmann,
    /// GGX / Trowbridge–Reitz.
    Ggx,
}

/// A Mitsuba microfacet distribution: its kind and widths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetDistribution {
    /// Beckmann or GGX.
    pub kind: MicrofacetKind,
    /// Width along the local `x` axis (the tangent).
    pub alpha_u: f32,
    /// Width along the local `y` axis (the bitangent).
    pub alpha_v: f32,
}

impl MicrofacetDistribution {
    /// The distribution of `kind` with widths `alpha_u`, `alpha_v`, each
    /// clamped to at least `1e-4` as Mitsuba does (NaN becomes `1e-4` too).
    pub fn new(kind: MicrofacetKind, alpha_u: f32, alpha_v: f32) -> Self {
        Self {
            kind,
            alpha_u: alpha_u.max(1e-4),
            alpha_v: alpha_v.max(1e-4),
        }
    }

    /// Whether the two widths are equal.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// The distribution of normals `D(m)` (per unit projected area).
    #[inline]
    pub fn d(&self, m: Vec3A) -> f32 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let sx = m.x / au;
        let sy = m.y / av;
        let r = match self.kind {
            MicrofacetKind::Beckmann => {
                (-(sx * sx + sy * sy) / cos2).exp() / (PI * au * av * cos2 * cos2)
            }
            MicrofacetKind::Ggx => {
                let s = sx * sx + sy * sy + cos2;
                1.0 / (PI * au * av * s * s)
            }
        };
        // Also zero below the horizon and for NaN.
        if r * m.z > 1e-20 { r } else { 0.0 }
    }

    /// Smith's masking `G1(v, m)` of direction `v` for the microfacet `m`;
    /// zero when `v` would see the microfacet's back.
    #[inline]
    pub fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        let xy = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        if xy == 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        match self.kind {
            MicrofacetKind::Beckmann => {
                // Mitsuba's rational fit (relative error below 0.35 %).
                let a = 1.0 / tan2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            MicrofacetKind::Ggx => 2.0 / (1.0 + (1.0 + tan2).sqrt()),
        }
    }

    /// The separable masking–shadowing `G1(wo, m) G1(wi, m)`.
    #[inline]
    pub fn g(&self, wo: Vec3A, wi: Vec3A, m: Vec3A) -> f32 {
        self.g1(wo, m) * self.g1(wi, m)
    }

    /// The density of [`MicrofacetDistribution::sample`] (visible normals):
    /// `D(m) G1(wo, m) |wo·m| / cos θo`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, m: Vec3A) -> f32 {
        self.d(m) * self.g1(wo, m) * wo.dot(m).abs() / wo.z
    }

    /// A normal drawn from the normals visible from `wo` (`wo.z > 0`), with
    /// its density ([`MicrofacetDistribution::pdf`]).
    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> (Vec3A, f32) {
        let (au, av) = (self.alpha_u, self.alpha_v);
        // Stretch to the configuration of unit width.
        let w = Vec3A::new(au * wo.x, av * wo.y, wo.z).normalize();
        let sin2 = w.x * w.x + w.y * w.y;
        let (cos_phi, sin_phi) = if sin2 <= 4.0 * f32::EPSILON * 0.5 {
            (1.0, 0.0)
        } else {
            let inv = 1.0 / sin2.sqrt();
            ((w.x * inv).clamp(-1.0, 1.0), (w.y * inv).clamp(-1.0, 1.0))
        };
        let s = self.sample_visible_11(w.z, u);
        // Rotate the slope to φ and unstretch it.
        let sx = (cos_phi * s.x - sin_phi * s.y) * au;
        let sy = (sin_phi * s.x + cos_phi * s.y) * av;
        let m = Vec3A::new(-sx, -sy, 1.0).normalize();
        (m, self.pdf(wo, m))
    }

    /// A slope `(x, y)` of the unit-width distribution seen from a direction
    /// at cosine `cos_theta` in the `xz` plane, drawn in proportion to its
    /// visible projected area.
    fn sample_visible_11(&self, cos_theta: f32, u: Vec2) -> Vec2 {
        match self.kind {
            MicrofacetKind::Beckmann => {
                // Jakob's numerical inversion of the visible slope's
                // marginal CDF, parameterised in erf's range.
                let tan = safe_sqrt(1.0 - cos_theta * cos_theta) / cos_theta;
                let cot = 1.0 / tan;
                let maxval = erf(cot);
                let u = u.clamp(Vec2::splat(1e-6), Vec2::splat(1.0 - 1e-6));
                // Start at the exact solution for grazing incidence.
                let mut x = maxval - (maxval + 1.0) * erf((-u.x.ln()).sqrt());
                let target = u.x * (1.0 + maxval + INV_SQRT_PI * tan * (-cot * cot).exp());
                for _ in 0..3 {
                    let slope = erfinv(x);
                    let value = 1.0 + x + INV_SQRT_PI * tan * (-slope * slope).exp() - target;
                    let derivative = 1.0 - slope * tan;
                    x -= value / derivative;
                }
                Vec2::new(erfinv(x), erfinv(2.0 * u.y - 1.0))
            }
            MicrofacetKind::Ggx => {
                // A point of the disk, squeezed onto the projection of the
                // visible hemisphere, lifted onto it and turned into a slope.
                let mut p = concentric_disk(u);
                let s = 0.5 * (1.0 + cos_theta);
                p.y = (1.0 - s) * safe_sqrt(1.0 - p.x * p.x) + s * p.y;
                let z = safe_sqrt(1.0 - p.length_squared());
                let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
                let norm = 1.0 / (sin_theta * p.y + cos_theta * z);
                Vec2::new((cos_theta * p.y - sin_theta * z) * norm, p.x * norm)
            }
        }
    }
}

/// `√max(x, 0)`.
#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// The error function, to about `1.2e-7` relative in `erfc` (Numerical
/// Recipes' Chebyshev fit of `erfc`, evaluated in f64).
pub(crate) fn erf(x: f32) -> f32 {
    let z = (x as f64).abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    let r = 1.0 - erfc;
    (if x < 0.0 { -r } else { r }) as f32
}

/// The inverse error function on `(−1, 1)` (Giles 2010, "Approximating the
/// erfinv function", single precision), refined by one Newton step on
/// [`erf`]; `±∞` at `±1`.
pub(crate) fn erfinv(x: f32) -> f32 {
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_4e-8f32;
        for c in [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            2.185_808_7e-4,
            -1.253_725e-3,
            -4.177_681_6e-3,
            2.466_407_3e-1,
            1.501_409_4,
        ] {
            p = c + p * w;
        }
        p
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -2.002_142_6e-4f32;
        for c in [
            1.009_505_6e-4,
            1.349_343_2e-3,
            -3.673_428_4e-3,
            5.739_507_7e-3,
            -7.622_461e-3,
            9.438_870_5e-3,
            1.001_674,
            2.832_976_8,
        ] {
            p = c + p * w;
        }
        p
    };
    let y = p * x;
    if !y.is_finite() || y.abs() > 3.5 {
        return y;
    }
    let d = 2.0 * INV_SQRT_PI * (-y * y).exp();
    y - (erf(y) - x) / d
}

/// The nodes and weights of the `n`-point Gauss–Legendre rule on `[−1, 1]`
/// (Newton's iteration on the Legendre polynomial, in f64).
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::test_util::*;

    #[test]
    fn erf_erfinv_and_gauss_legendre_are_accurate() {
        // erf(0.5) = 0.520499877813047, erf(1.5) = 0.966105146475311,
        // erf(2.5) = 0.999593047982555.
        for (x, want) in [
            (0.5f32, 0.520_499_877_813_047f64),
            (1.5, 0.966_105_146_475_311),
            (2.5, 0.999_593_047_982_555),
            (-1.5, -0.966_105_146_475_311),
        ] {
            assert!((erf(x) as f64 - want).abs() < 3e-7, "erf({x})");
        }
        for y in [-0.999_9f32, -0.9, -0.3, 0.0, 0.2, 0.7, 0.99, 0.999_99] {
            let x = erfinv(y);
            assert!((erf(x) - y).abs() < 1e-6, "erfinv({y}) = {x}");
        }
        // ∫ x⁴ on [−1, 1] = 2/5; 5 points are exact to degree 9.
        let q: f64 = gauss_legendre(5).iter().map(|(x, w)| w * x.powi(4)).sum();
        assert!((q - 0.4).abs() < 1e-14, "{q}");
        let w: f64 = gauss_legendre(128).iter().map(|(_, w)| w).sum();
        assert!((w - 2.0).abs() < 1e-12, "{w}");
    }

    /// `∫ D(m) cos θm dm = 1` and `∫ G1(v, m) max(0, v·m) D(m) dm = cos θv`
    /// (the projected area of the visible microfacets equals the surface's),
    /// by quadrature over the sphere of normals.
    #[test]
    fn distributions_are_normalised_and_g1_matches_them() {
        for kind in [MicrofacetKind::Beckmann, MicrofacetKind::Ggx] {
            for (au, av) in [(0.3f32, 0.3f32), (0.15, 0.5), (0.8, 0.8)] {
                let d = MicrofacetDistribution::new(kind, au, av);
                let proj: f64 = integrate_bins(|m| d.d(m) * m.z.max(0.0)).iter().sum();
                assert!(
                    (proj - 1.0).abs() < 2e-3,
                    "{kind:?} {au} {av}: ∫D cos = {proj}"
                );
                for theta in [30.0f32, 70.0] {
                    let v = dir(theta, 0.7);
                    let vis: f64 = integrate_bins(|m| d.g1(v, m) * v.dot(m).max(0.0) * d.d(m))
                        .iter()
                        .sum();
                    // Beckmann's G1 is a fit (0.35 %).
                    let tol = if kind == MicrofacetKind::Beckmann {
                        6e-3
                    } else {
                        2e-3
                    };
                    assert!(
                        (vis / v.z as f64 - 1.0).abs() < tol,
                        "{kind:?} {au} {av} θ {theta}: {vis} vs {}",
                        v.z
                    );
                }
            }
        }
    }
}
