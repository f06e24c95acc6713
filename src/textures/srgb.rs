//! Decoding stored channel values to linear floats: the exact sRGB EOTF and the
//! lookup tables the texel fetches go through.

use std::sync::LazyLock;

/// The sRGB electro-optical transfer function (IEC 61966-2-1), evaluated in
/// `f64` and rounded once: `x ≤ 0.04045 ? x / 12.92 : ((x + 0.055) / 1.055)^2.4`.
fn eotf(x: f64) -> f64 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Decodes an sRGB-encoded value in [0, 1] to linear, with the exact sRGB
/// EOTF: `x ≤ 0.04045 ? x / 12.92 : ((x + 0.055) / 1.055)^2.4`.
///
/// Computed in `f64` and rounded once to `f32`, so `srgb_to_linear(0.0) == 0.0`
/// and `srgb_to_linear(1.0) == 1.0`. The lookup tables of the texture fetches
/// hold exactly this function's values of `byte as f32 / 255.0` and
/// `word as f32 / 65535.0`: what decoding every texel at load would store.
pub fn srgb_to_linear(x: f32) -> f32 {
    eotf(f64::from(x)) as f32
}

/// 8-bit sRGB: `srgb_to_linear(i / 255)`.
static SRGB8: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

/// 8-bit linear: `i / 255` (the same `f32` division a decode at load would do).
static LINEAR8: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|i| i as f32 / 255.0));

/// 16-bit sRGB: `srgb_to_linear(i / 65535)`, 256 KiB, built on first use.
static SRGB16: LazyLock<Box<[f32]>> = LazyLock::new(|| {
    (0..=u16::MAX)
        .map(|i| srgb_to_linear(f32::from(i) / 65535.0))
        .collect()
});

/// The table decoding an 8-bit sRGB value.
#[inline]
pub(super) fn srgb8() -> &'static [f32; 256] {
    &SRGB8
}

/// The table decoding an 8-bit linear value (and any 8-bit alpha).
#[inline]
pub(super) fn linear8() -> &'static [f32; 256] {
    &LINEAR8
}

/// The table decoding a 16-bit sRGB value.
#[inline]
pub(super) fn srgb16() -> &'static [f32] {
    &SRGB16
}

/// A 16-bit linear value (and any 16-bit alpha): `v / 65535`, no table needed.
#[inline]
pub(super) fn linear16(v: u16) -> f32 {
    f32::from(v) / 65535.0
}
