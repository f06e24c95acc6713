//! The heuristic blend that came before the guard ([`super::blend`]), kept
//! where the guard's estimate allows the denoised value: a weight from the
//! variance AOV, the difference the denoiser made, a gate on the relative
//! noise and the share of samples that hit a surface.
//!
//! Its constants were chosen on three scenes; on its own it let a denoiser
//! double the error of a scene it was not tuned on. It now only lowers the
//! guard's weight (the weight of a pixel is the smaller of the two), which
//! keeps what it was tuned for, FLIP's sensitivity to a denoiser's faint
//! shifts of nearly converged pixels, without being trusted to find a
//! denoiser's failures: the guard's estimate does that.
//!
//! How it weighs:
//!
//! A denoiser trades noise for bias: where a render has converged, or where
//! the guides miss a feature, its output can be worse than its input, and a
//! perceptual measure sees even a shift of a fifth of a percent spread over
//! a smooth region (measured: the HDRI-lit helmet's mean FLIP doubles when
//! its noisy image is scaled by 1.002, more than its noise costs at 64 spp).
//! So the denoised value `y` of a pixel is only taken as far as it helps:
//! the output is `x + w (y − x)`, `x` the noisy value, with
//!
//! `w = min(1, 4V/D) · gate(√min(V, D) / L) · c`,
//!
//! where, as means over a window of (2 [`RADIUS`] + 1)² pixels (a pixel's
//! own numbers are too noisy to weigh by, and a weight that followed a
//! pixel's own noise would bias the image), `V` is the noisy value's
//! variance (the `variance` AOV), `D` the squared difference `(y − x)²` and
//! `L` the noisy luminance, all of luminance:
//!
//! * `min(1, 4V/D)`: `y − x` is the noise plus the denoiser's bias `b`, so
//!   `D ≈ V + b²`, and `V/(V + b²)` would be the weight of least expected
//!   squared error: 1 where the difference is all noise, falling where the
//!   denoiser changed more than the noise explains. The factor
//!   [`TOLERANCE`] (the change may be twice the noise's standard deviation
//!   before the weight falls) allows for the variance estimate's own error:
//!   a few samples of heavy-tailed path contributions mostly underestimate
//!   it (on the showcase at 4 spp, `V/D` gave 1.5× the relMSE of `4V/D`);
//! * `gate`: 0 below a relative noise of [`GATE_LOW`], 1 above [`GATE_HIGH`],
//!   linear between: where the noise (or the change the denoiser would make,
//!   whichever is smaller) is a percent or two of the value, it is not worth
//!   a denoiser's subtle shifts;
//! * `c`: the share of the pixel's samples whose camera ray hit a surface. A
//!   sample that escaped shows the environment straight, with no path noise;
//!   its only noise is antialiasing, which the denoiser keeps too (its guides
//!   have the same samples), so a pixel of sky is kept as it is.
//!
//! With fewer than two samples the variance is unknown (`+∞`): `V/D` is then
//! 1, and the gate looks at `D` alone. The constants were chosen on the
//! helmet under the Venice HDRI and the showcase at 1 to 1024 spp against
//! 4096-spp renders (`docs/denoising.md`): with them the output is never
//! worse than the noisy image there in clamped relMSE or mean FLIP.
//!
//! Deterministic: every pixel is computed from the same inputs in the same
//! order whatever the number of threads.

use rayon::prelude::*;

use crate::aov::luminance;
use crate::film::Film;

/// Half the width of the window the weights are averaged over.
pub const RADIUS: usize = 3;
/// How many times the noise's variance the squared change may be before
/// the denoised value's weight falls (see the module documentation).
pub const TOLERANCE: f64 = 4.0;
/// Relative noise below which the noisy value is kept.
pub const GATE_LOW: f64 = 0.02;
/// Relative noise above which the denoised value is taken (as far as `V/D`
/// allows).
pub const GATE_HIGH: f64 = 0.06;
/// Luminance below which the gate's relative noise is taken relative to
/// this instead (black pixels are all noise).
const DARK: f64 = 1e-4;

/// Each pixel's weight of `denoised` against `noisy` (see the module
/// documentation); `variance` holds the variance AOV and `coverage` the
/// share of samples that hit a surface, one value per pixel each.
pub fn weights(noisy: &Film, denoised: &Film, variance: &[f32], coverage: &[f32]) -> Vec<f32> {
    let (w, h) = (noisy.width as usize, noisy.height as usize);
    assert_eq!(noisy.pixels.len(), w * h);
    assert_eq!(denoised.pixels.len(), w * h);
    assert_eq!(variance.len(), w * h);
    assert_eq!(coverage.len(), w * h);
    let diff2: Vec<f64> = noisy
        .pixels
        .par_iter()
        .zip(&denoised.pixels)
        .map(|(x, y)| {
            let d = f64::from(luminance(*y - *x));
            d * d
        })
        .collect();
    let var: Vec<f64> = variance
        .par_iter()
        .map(|&v| f64::from(v.max(0.0)))
        .collect();
    let lum: Vec<f64> = noisy
        .pixels
        .par_iter()
        .map(|x| f64::from(luminance(*x).max(0.0)))
        .collect();
    let d = box_mean(&diff2, w, h, RADIUS);
    let v = box_mean(&var, w, h, RADIUS);
    let l = box_mean(&lum, w, h, RADIUS);
    (0..w * h)
        .into_par_iter()
        .map(|i| weight(v[i], d[i], l[i]) * coverage[i].clamp(0.0, 1.0))
        .collect()
}

/// `noisy` moved towards `denoised` by `weights`.
pub fn apply(noisy: &Film, denoised: &Film, weights: &[f32]) -> Film {
    let mut out = Film::new(noisy.width, noisy.height);
    out.pixels
        .par_iter_mut()
        .zip(&noisy.pixels)
        .zip(&denoised.pixels)
        .zip(weights)
        .for_each(|(((o, &x), &y), &w)| *o = x + (y - x) * w);
    out
}

/// The weight of the denoised value for window means `v` (variance), `d`
/// (squared difference) and `l` (luminance), before coverage.
#[inline]
pub fn weight(v: f64, d: f64, l: f64) -> f32 {
    let mse = if d > 0.0 && TOLERANCE * v < d {
        TOLERANCE * v / d
    } else {
        1.0
    };
    let relative = v.min(d).sqrt() / l.max(DARK);
    let gate = ((relative - GATE_LOW) / (GATE_HIGH - GATE_LOW)).clamp(0.0, 1.0);
    (mse * gate) as f32
}

/// The mean of `values` (a `w × h` image) over the window of `(2r + 1)²`
/// pixels around each pixel, clipped to the image.
fn box_mean(values: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    super::blend::window_mean(values, w, h, r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn film(w: u32, h: u32, f: impl Fn(usize) -> Vec3A) -> Film {
        let mut film = Film::new(w, h);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            *p = f(i);
        }
        film
    }

    #[test]
    fn the_weight_is_the_share_of_the_difference_that_noise_explains() {
        // Noise of 20 % of the value: the gate is open, the MSE weight rules.
        let l = 1.0;
        assert_eq!(weight(0.01, 0.16, l), 0.25);
        assert_eq!(weight(0.04, 0.16, l), 1.0);
        assert_eq!(weight(0.16, 0.04, l), 1.0);
        assert_eq!(weight(f64::INFINITY, 0.04, l), 1.0);
        // Noise of 1 %: below the gate, the noisy value stays.
        assert_eq!(weight(1e-4, 1e-4, l), 0.0);
        // Halfway up the gate (4 %).
        assert!((weight(16e-4, 16e-4, l) - 0.5).abs() < 1e-6);
        // Nothing changed, nothing known: 0 (the gate sees no change).
        assert_eq!(weight(f64::INFINITY, 0.0, l), 0.0);
    }

    #[test]
    fn a_denoised_image_within_the_noise_is_kept_and_a_biased_one_is_not() {
        let (w, h) = (16u32, 12u32);
        let n = (w * h) as usize;
        let noisy = film(w, h, |i| Vec3A::splat(if i % 2 == 0 { 1.2 } else { 0.8 }));
        let clean = film(w, h, |_| Vec3A::ONE);
        let all = vec![1.0f32; n];
        // Noise of standard deviation 0.2 per pixel: the denoised image's
        // difference is all noise, so it is taken whole.
        let variance = vec![0.04f32; n];
        let out = apply(&noisy, &clean, &weights(&noisy, &clean, &variance, &all));
        assert!(
            out.pixels
                .iter()
                .all(|p| (*p - Vec3A::ONE).abs().max_element() < 1e-6)
        );
        // A denoiser that darkened the image to 0.5 is partly undone: at
        // (8, 6) the window's columns 5..=11 hold three of 1.2 and four of
        // 0.8, so D = (3 · 0.7² + 4 · 0.3²)/7 and w = 4 · 0.04 / D.
        let dark = film(w, h, |_| Vec3A::splat(0.5));
        let out = apply(&noisy, &dark, &weights(&noisy, &dark, &variance, &all));
        let centre = out.get(8, 6);
        let d = (3.0 * 0.49 + 4.0 * 0.09) / 7.0f32;
        let expect = 1.2 + (0.5 - 1.2) * (0.16 / d);
        assert!((centre.x - expect).abs() < 2e-3, "{centre} {expect}");
        // Sky (no sample hit): kept as it is.
        let sky = vec![0.0f32; n];
        assert_eq!(
            apply(&noisy, &clean, &weights(&noisy, &clean, &variance, &sky)).pixels,
            noisy.pixels
        );
        // Unknown variance (one sample): the denoised image where it changed
        // more than the gate.
        let unknown = vec![f32::INFINITY; n];
        assert_eq!(
            apply(&noisy, &clean, &weights(&noisy, &clean, &unknown, &all)).pixels,
            clean.pixels
        );
    }

    #[test]
    fn box_means_average_over_the_clipped_window() {
        let (w, h) = (5, 4);
        let values: Vec<f64> = (0..w * h).map(|i| i as f64).collect();
        let m = box_mean(&values, w, h, 1);
        // Corner (0, 0): the mean of 0, 1, 5, 6.
        assert_eq!(m[0], 3.0);
        // Inside (2, 1): the mean of rows 0..3, columns 1..4.
        let inside: f64 = [1, 2, 3, 6, 7, 8, 11, 12, 13].iter().sum::<i32>() as f64 / 9.0;
        assert_eq!(m[w + 2], inside);
    }
}
