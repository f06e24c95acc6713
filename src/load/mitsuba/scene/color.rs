//! Colours as Mitsuba 3's RGB variants read them: an `<rgb>` as it is, a
//! `<float>` as a grey, a constant `<spectrum>` as a grey (or, for an
//! emitter, `value × xyz_to_srgb(1, 1, 1)`: Mitsuba's RGB variants give a
//! flat emission spectrum the tint it has in its spectral variants), and a
//! `wavelength:value` list integrated against the CIE 1931 curves
//! (weighted by D65 unless it is an emitter's) and turned into linear sRGB
//! (Mitsuba's `spectrum_list_to_srgb`, `src/core/spectrum.cpp`), clamped to
//! `[0, 1]` for bounded quantities (reflectances) and at 0 otherwise.

use glam::{Mat3, Vec3, Vec3A};

use crate::materials::cie::{D65, LAMBDA_MAX, LAMBDA_MIN, SAMPLES, XYZ, tabulated};

/// What a colour is, which decides how a spectrum becomes RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    /// A reflectance or transmittance: bounded to `[0, 1]`, D65-weighted.
    Reflectance,
    /// An unbounded material quantity (an index of refraction): D65-weighted,
    /// clamped at 0 only.
    Unbounded,
    /// Emitted radiance, intensity or irradiance: unbounded, not weighted.
    Emission,
}

/// CIE XYZ to linear sRGB (Rec. 709 primaries, D65 white), the matrix
/// Mitsuba uses (`xyz_to_srgb`), digits as Mitsuba writes them.
#[allow(clippy::excessive_precision)]
pub(super) fn xyz_to_srgb(xyz: Vec3) -> Vec3 {
    let m = Mat3::from_cols(
        Vec3::new(3.240479, -0.969256, 0.055648),
        Vec3::new(-1.537150, 1.875991, -0.204043),
        Vec3::new(-0.498535, 0.041556, 1.057311),
    );
    m * xyz
}

/// `∫ xyz(λ) s(λ) dλ` normalised so that a flat 1 has luminance 1 (Mitsuba's
/// 1000-point rule over 360–830 nm), of the piecewise-linear `s` through
/// `points` (zero outside them), times D65 if `d65`.
fn integrate(points: &[(f32, f32)], d65: bool) -> Vec3 {
    const STEPS: usize = 1000;
    // Mitsuba's MI_CIE_Y_NORMALIZATION and the D65 table's normalisation.
    const Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
    const D65_NORMALIZATION: f32 = (1.0 / 98.997_417_518_762_55) as f32;
    let mut xyz = Vec3::ZERO;
    let (first, last) = (points[0].0, points[points.len() - 1].0);
    for i in 0..STEPS {
        let w = LAMBDA_MIN + (i as f32 / (STEPS - 1) as f32) * (LAMBDA_MAX - LAMBDA_MIN);
        if w < first || w > last {
            continue;
        }
        // The interval [w0, w1] holding w (the last one for w = last).
        let k = points
            .partition_point(|p| p.0 <= w)
            .clamp(1, points.len() - 1)
            - 1;
        let ((w0, v0), (w1, v1)) = (points[k], points[k + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let cie = Vec3::new(
            tabulated(&XYZ[..SAMPLES], w),
            tabulated(&XYZ[SAMPLES..2 * SAMPLES], w),
            tabulated(&XYZ[2 * SAMPLES..], w),
        );
        let weight = if d65 {
            tabulated(&D65, w) * D65_NORMALIZATION
        } else {
            1.0
        };
        xyz += cie * v * weight;
    }
    xyz * ((f64::from(LAMBDA_MAX - LAMBDA_MIN) * Y_NORMALIZATION / STEPS as f64) as f32)
}

/// The RGB of a `wavelength:value` list (at least two points, wavelengths
/// increasing) in the role `role`.
pub(super) fn sampled_to_rgb(points: &[(f32, f32)], role: Role) -> Vec3A {
    let rgb = xyz_to_srgb(integrate(points, role != Role::Emission));
    let rgb = match role {
        Role::Reflectance => rgb.clamp(Vec3::ZERO, Vec3::ONE),
        Role::Unbounded | Role::Emission => rgb.max(Vec3::ZERO),
    };
    rgb.into()
}

/// The RGB of a constant spectrum `value` in the role `role`.
pub(super) fn constant_to_rgb(value: f32, role: Role) -> Vec3A {
    match role {
        Role::Emission => Vec3A::from(xyz_to_srgb(Vec3::ONE)) * value,
        Role::Reflectance | Role::Unbounded => Vec3A::splat(value),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_reflectance_spectrum_is_grey() {
        // D65-weighted and normalised, a flat spectrum is D65's own colour,
        // which sRGB's white point makes grey (to the tables' precision).
        let rgb = sampled_to_rgb(&[(360.0, 0.78), (830.0, 0.78)], Role::Reflectance);
        for c in rgb.to_array() {
            assert!((c - 0.78).abs() < 0.01, "{rgb}");
        }
    }

    #[test]
    fn a_flat_emission_has_luminance_one_and_mitsubas_tint() {
        let rgb = sampled_to_rgb(&[(360.0, 1.0), (830.0, 1.0)], Role::Emission);
        let y = 0.212671 * rgb.x + 0.715160 * rgb.y + 0.072169 * rgb.z;
        assert!((y - 1.0).abs() < 0.01, "{rgb} has luminance {y}");
        // The constant form is xyz_to_srgb(1, 1, 1) = (1.205, 0.948, 0.909).
        let c = constant_to_rgb(1.0, Role::Emission);
        assert!((c - rgb).abs().max_element() < 0.02, "{c} vs {rgb}");
        assert!(
            (c - Vec3A::new(1.2048, 0.9483, 0.9089)).abs().max_element() < 1e-3,
            "{c}"
        );
    }

    #[test]
    fn a_spectrum_is_zero_outside_its_points() {
        // Only 600–700 nm (red): red dominates; nothing below 600 nm.
        let rgb = sampled_to_rgb(&[(600.0, 1.0), (700.0, 1.0)], Role::Emission);
        assert!(rgb.x > 3.0 * rgb.y && rgb.z == 0.0, "{rgb}");
    }
}
