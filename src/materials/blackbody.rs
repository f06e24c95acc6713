//! The colour of a blackbody: Planck's law, normalised as pbrt-v4's
//! `BlackbodySpectrum` is (its peak is 1, whatever the temperature), taken
//! to linear Rec. 709 through the CIE 1931 2° tables ([`super::cie`]), in
//! pbrt-v4's two conventions:
//!
//! - [`blackbody_rgb`]: the radiance of that spectrum, `∫ B̂(λ) (x̄, ȳ, z̄)
//!   dλ` with `λ` in nm, as pbrt-v4's film records a temperature grid's
//!   emission (its `nanovdb` and `uniformgrid` media: `Le = Lescale · B̂((T −
//!   offset) · scale)`). Cooler is much dimmer: luminance 0.36 at 1500 K,
//!   5.2 at 2000 K, 17 at 2400 K, 44 at 3000 K, 95 at 6500 K.
//! - [`blackbody_color`]: the same colour at luminance 1, as pbrt-v4 takes a
//!   `"blackbody Le"` spectrum given to a medium or a light (it divides by
//!   the spectrum's luminance; a scale then says how bright).
//!
//! [`blackbody_rgb`] reads a table every [`STEP`] K up to [`TABLE_MAX`] K,
//! interpolated linearly (within 0.5 % of the exact integral where the
//! colour is bright enough to see, tested), and integrates exactly above
//! it.

use std::sync::OnceLock;

use glam::Vec3A;

use super::cie::{LAMBDA_MAX, LAMBDA_MIN, SAMPLES, XYZ, tabulated};
use super::spectrum::xyz_to_rec709;

/// Spacing of the table, in kelvin.
pub const STEP: f32 = 2.0;

/// Hottest temperature in the table, in kelvin.
pub const TABLE_MAX: f32 = 12_000.0;

/// Planck's law: the spectral radiance of a blackbody at `kelvin` at
/// wavelength `lambda_nm` (W·sr⁻¹·m⁻³); 0 for temperatures ≤ 0.
#[inline]
pub fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    if kelvin <= 0.0 {
        return 0.0;
    }
    // CODATA 2018 (exact since the 2019 SI).
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_070_15e-34;
    const KB: f64 = 1.380_649e-23;
    let l = lambda_nm * 1e-9;
    2.0 * H * C * C / (l.powi(5) * ((H * C / (l * KB * kelvin)).exp_m1()))
}

/// The wavelength (nm) at which a blackbody at `kelvin` peaks (Wien's law).
#[inline]
fn wien_peak_nm(kelvin: f64) -> f64 {
    2.897_771_955e-3 / kelvin * 1e9
}

/// CIE XYZ of the peak-normalised blackbody at `kelvin` (`∫ B̂ (x̄, ȳ, z̄)
/// dλ`, 1 nm steps over 360–830 nm, `λ` in nm); zero at or below 0 K and
/// for NaN.
fn blackbody_xyz(kelvin: f32) -> Vec3A {
    let t = f64::from(kelvin);
    if t.is_nan() || t <= 0.0 {
        return Vec3A::ZERO;
    }
    let t = t.min(f64::from(f32::MAX));
    let peak = planck(wien_peak_nm(t), t);
    let mut xyz = [0.0f64; 3];
    let steps = (LAMBDA_MAX - LAMBDA_MIN) as usize;
    for i in 0..=steps {
        let lambda = f64::from(LAMBDA_MIN) + i as f64;
        let b = planck(lambda, t) / peak;
        for (c, s) in xyz.iter_mut().enumerate() {
            *s += b * f64::from(tabulated(
                &XYZ[c * SAMPLES..(c + 1) * SAMPLES],
                lambda as f32,
            ));
        }
    }
    Vec3A::new(xyz[0] as f32, xyz[1] as f32, xyz[2] as f32)
}

/// The linear Rec. 709 radiance of the peak-normalised blackbody at
/// `kelvin` (pbrt-v4's temperature grids; [module docs](self)), clamped at
/// 0 (out of gamut below about 1900 K, where its blue would be a little
/// negative). Black at or below 0 K and for NaN; exact, not tabulated.
pub fn blackbody_rgb_exact(kelvin: f32) -> Vec3A {
    xyz_to_rec709(blackbody_xyz(kelvin)).max(Vec3A::ZERO)
}

/// The colour of a blackbody at `kelvin` at luminance 1 (pbrt-v4's
/// `"blackbody Le"`; [module docs](self)), in linear Rec. 709 clamped at 0;
/// black where the blackbody has no luminance to speak of (below some
/// 400 K).
pub fn blackbody_color(kelvin: f32) -> Vec3A {
    let xyz = blackbody_xyz(kelvin);
    if xyz.y.is_nan() || xyz.y <= 1e-30 {
        return Vec3A::ZERO;
    }
    xyz_to_rec709(xyz / xyz.y).max(Vec3A::ZERO)
}

/// [`blackbody_rgb_exact`], from a table below [`TABLE_MAX`] (built on first
/// use, in a few milliseconds).
#[inline]
pub fn blackbody_rgb(kelvin: f32) -> Vec3A {
    static TABLE: OnceLock<Vec<Vec3A>> = OnceLock::new();
    if kelvin.is_nan() || kelvin <= 0.0 {
        return Vec3A::ZERO;
    }
    if kelvin >= TABLE_MAX {
        return blackbody_rgb_exact(kelvin);
    }
    let table = TABLE.get_or_init(|| {
        let n = (TABLE_MAX / STEP) as usize;
        (0..=n)
            .map(|i| blackbody_rgb_exact(i as f32 * STEP))
            .collect()
    });
    let x = kelvin / STEP;
    let i = (x as usize).min(table.len() - 2);
    let w = x - i as f32;
    table[i] * (1.0 - w) + table[i + 1] * w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chromaticity `(x, y)` of a blackbody from XYZ (Rec. 709 taken back).
    fn xy(kelvin: f32) -> (f32, f32) {
        let c = blackbody_rgb_exact(kelvin);
        // Rec. 709 → XYZ, the usual matrix (the inverse of xyz_to_rec709).
        let x = 0.412_456_4 * c.x + 0.357_576_1 * c.y + 0.180_437_5 * c.z;
        let y = 0.212_672_9 * c.x + 0.715_152_2 * c.y + 0.072_175 * c.z;
        let z = 0.019_333_9 * c.x + 0.119_192 * c.y + 0.950_304_1 * c.z;
        let s = x + y + z;
        (x / s, y / s)
    }

    /// The Planckian locus as the CIE publishes it: illuminant A (2856 K,
    /// x = 0.44757, y = 0.40745) and the locus at 6500 K (0.3135, 0.3236),
    /// 4000 K (0.3805, 0.3768) and 10000 K (0.2807, 0.2884), from the
    /// 5 nm tables within 0.001.
    #[test]
    fn the_planckian_locus_matches_the_cies() {
        for (t, want) in [
            (2856.0, (0.44757, 0.40745)),
            (4000.0, (0.3805, 0.3768)),
            (6500.0, (0.3135, 0.3236)),
            (10000.0, (0.2807, 0.2884)),
        ] {
            let (x, y) = xy(t);
            assert!(
                (x - want.0).abs() < 1e-3 && (y - want.1).abs() < 1e-3,
                "{t} K: ({x}, {y}) vs {want:?}"
            );
        }
    }

    /// Peak-normalised: the luminance is `∫ ȳ` (106.86, CIE 1931) times
    /// a little less than 1 where the visible range is all near the peak,
    /// less elsewhere; `blackbody_color` has luminance 1; hotter is bluer,
    /// and cold is black.
    #[test]
    fn brightness_and_colour_follow_the_temperature() {
        let y = |c: Vec3A| 0.212_672_9 * c.x + 0.715_152_2 * c.y + 0.072_175 * c.z;
        let y_integral: f32 = (0..=470)
            .map(|i| tabulated(&XYZ[SAMPLES..2 * SAMPLES], 360.0 + i as f32))
            .sum();
        assert!((y_integral - 106.857).abs() < 0.2, "{y_integral}");
        // At 5800 K the peak (500 nm) is mid-visible.
        let sun = y(blackbody_rgb_exact(5800.0)) / y_integral;
        assert!((0.85..1.0).contains(&sun), "Y(5800 K) = {sun}");
        for t in [2000.0, 3000.0, 6500.0, 15000.0] {
            let c = blackbody_color(t);
            let ratio = blackbody_rgb_exact(t) / c;
            assert!((y(c) - 1.0).abs() < 1e-3, "{t} K: {c:?}");
            assert!(
                ratio.max_element() - ratio.min_element() < 1e-3 * ratio.x,
                "{t} K"
            );
        }
        let warm = blackbody_rgb_exact(1800.0);
        assert!(
            warm.x > warm.y && warm.y > warm.z && warm.z == 0.0,
            "{warm:?}"
        );
        let cool = blackbody_rgb_exact(15000.0);
        assert!(cool.z > cool.x, "{cool:?}");
        assert_eq!(blackbody_rgb(0.0), Vec3A::ZERO);
        assert_eq!(blackbody_rgb(-5.0), Vec3A::ZERO);
        assert_eq!(blackbody_rgb(f32::NAN), Vec3A::ZERO);
        assert_eq!(blackbody_color(f32::NAN), Vec3A::ZERO);
        assert_eq!(blackbody_color(50.0), Vec3A::ZERO);
        assert!(y(blackbody_rgb(300.0)) < 1e-18);
    }

    /// The table is within 0.5 % of the exact integral (per channel, of the
    /// brightest channel) wherever the colour is above 1e-4, and exact at
    /// its knots and beyond it.
    #[test]
    fn the_table_matches_the_integral() {
        let mut worst = 0.0f32;
        let mut t = 400.0f32;
        while t < TABLE_MAX + 500.0 {
            let (a, b) = (blackbody_rgb(t), blackbody_rgb_exact(t));
            if b.max_element() > 1e-4 {
                let e = (a - b).abs().max_element() / b.max_element();
                worst = worst.max(e);
            }
            t += 7.3;
        }
        assert!(worst < 5e-3, "worst relative error {worst}");
        assert_eq!(blackbody_rgb(3000.0), blackbody_rgb_exact(3000.0));
        assert_eq!(blackbody_rgb(20000.0), blackbody_rgb_exact(20000.0));
    }
}
