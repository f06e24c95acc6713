//! The guard: the denoised image only where the render's own estimate says
//! it is better than the noisy one.
//!
//! A denoiser trades noise for bias, and where a render has (nearly)
//! converged, or where the guides miss a feature (a caustic, a small bright
//! light seen through glass, a texture finer than the noise), its output is
//! worse than its input. No rule fitted to a few scenes can say where; the
//! render itself can, because it controls every sample. Each pixel's samples
//! are split into two halves `A` and `B` (one sample of each pair
//! `2k, 2k + 1`, [`crate::aov::in_half`]), two estimates of the pixel with
//! half the samples each, and the denoiser runs a second time, on `A` alone
//! (cross-validation, as in Bitterli et al. 2016, "Nonlinearly weighted
//! first-order regression for denoising Monte Carlo renderings", and
//! Rousselle et al. 2012). `B` is independent of `A` and of `f(A)`, so per
//! pixel
//!
//! `s = (f(A) − B)² − (A − B)²` has mean `M_A − V_A`,
//!
//! the denoised half's squared error minus the noisy half's: `B`'s own noise
//! cancels. Over a window of pixels the sum `S` of `s` and the sum `Q` of
//! `s²` give the evidence `t = −S / √Q` (in standard errors) that the
//! denoiser beats the noise, and the denoised value's weight is `t` clamped
//! to `[0, 1]`: whole where it wins by a standard error or more, none where
//! it does not win. This is measured twice, and the smaller weight is taken:
//!
//! * per pixel, relative to the pixel's value (each channel's difference
//!   over `g² + ε`, `ε` 1 % of the denoised image's squared mean, `g` the
//!   guess of the truth [`truth_guess`] makes: the denoised value, but no
//!   more than the mean of `A` over the pixel and its neighbours, since a
//!   denoiser that spreads a bright light into the dark pixels around it
//!   must not make those pixels' errors look small), both squared
//!   differences clamped at the
//!   [`CLAMP_QUANTILE`] of the pixels' `(A − B)²` (a firefly counts as that
//!   quantile, as in the clamped relative MSE): what a relative MSE sees,
//!   over windows of (2 [`RADIUS`] + 1)² pixels;
//! * as a viewer sees it: the differences in an opponent colour space
//!   (luminance, red − green, blue − yellow), each channel blurred by FLIP's
//!   contrast-sensitivity filter at its standard 67 pixels per degree
//!   ([`CSF_SIGMA`]), relative to the same guess and clamped at the same
//!   quantile, over windows of (2 [`SEEN_RADIUS`] + 1)² pixels. A
//!   denoiser's faint bias over a smooth region, or a fine texture it
//!   blurs, shows there even where it removed far more noise than it added
//!   per pixel.
//!
//! What is compared is the two halves: the decision assumes that what holds
//! between `f(A)` and `A` holds between `f(x)` and `x` (both made of twice
//! the samples). There is no constant tuned to a scene: the windows set how
//! many pixels an estimate averages, the standard error how sure it must be,
//! FLIP's published filters what a viewer sees.
//!
//! Caveats, measured (docs/denoising.md): the halves of a stratified
//! (Sobol') render are not quite independent, so `(A − B)²` overestimates
//! the halves' variance by up to a third, and the full image converges
//! faster than two halves would suggest; both favour the denoiser a little.
//! The heuristic blend ([`super::heuristic`]) still lowers the weight where
//! it would (the weight is the smaller of the two).
//!
//! **One sample per pixel** has no second half: nothing is known of the
//! noise, and the heuristic blend decides alone (with the variance unknown
//! it keeps the noisy value only where escaped camera rays see the
//! environment). A single path per pixel is the noisiest image a render
//! makes; on every scene of `tools/compare_cycles.py` it is many times worse
//! than the denoised image in both measures. With two samples each half is
//! one sample: the estimates are noisy, and the standard error says so.
//!
//! Deterministic: every pixel is computed from the same inputs in the same
//! order whatever the number of threads.

use glam::Vec3A;
use rayon::prelude::*;

use crate::aov::luminance;
use crate::film::Film;

/// Half the width of the window the per-pixel estimates are averaged over.
pub const RADIUS: usize = 8;

/// The quantile of the pixels' `(A − B)²` at which both squared differences
/// are clamped: that of the clamped relative MSE the comparisons measure by
/// (`tools/compare_cycles.py`: per-pixel errors clamped at their 99.9th
/// percentile).
pub const CLAMP_QUANTILE: f64 = 0.999;

/// The standard deviations, in pixels, of FLIP's contrast-sensitivity
/// filters (Andersson et al. 2020) at its standard 67 pixels per degree, of
/// the achromatic, red–green and blue–yellow channels: `√(b / 2π²) · 67` for
/// their widths `b` = 0.0047, 0.0053 and 0.04 deg².
pub const CSF_SIGMA: [f64; 3] = [1.03, 1.10, 3.0];

/// Half the width of the window the filtered estimates are averaged over:
/// wider, as filtered values are correlated over the filters' widths.
pub const SEEN_RADIUS: usize = 16;

/// The two halves of each pixel's samples, `A` and `B`: from the image `x`
/// (the mean of all `n` samples) and the [`crate::aov::Aov::Half`] layer
/// (`B`'s mean and count `n_B`, four values a pixel), `A = (n x − n_B B) /
/// (n − n_B)`. `counts` gives each pixel's `n` where it differs (adaptive
/// sampling), else `samples` is every pixel's. `None` where a half is empty
/// (one sample) or a value is not finite.
pub fn halves(
    image: &Film,
    half: &[f32],
    counts: Option<&[f32]>,
    samples: u32,
) -> Vec<Option<(Vec3A, Vec3A)>> {
    image
        .pixels
        .par_iter()
        .enumerate()
        .map(|(i, &x)| {
            let h = &half[4 * i..4 * i + 4];
            let n = counts.map_or(samples as f32, |c| c[i]);
            let (b, n_b) = (Vec3A::new(h[0], h[1], h[2]), h[3]);
            let n_a = n - n_b;
            if n_b < 1.0 || n_a < 1.0 || !b.is_finite() {
                return None;
            }
            // In f64: `n x` and `n_B B` nearly cancel where A ≈ B.
            let (x64, b64) = (x.as_dvec3(), b.as_dvec3());
            let a = (x64 * f64::from(n) - b64 * f64::from(n_b)) / f64::from(n_a);
            let a = a.max(glam::DVec3::ZERO).as_vec3a();
            a.is_finite().then_some((a, b))
        })
        .collect()
}

/// The guard's weight of `denoised` (`y`, the denoiser's output for the
/// noisy image `noisy`, `x`) in each pixel, estimated from the `halves` and
/// `denoised_a` (the denoiser's output for `A`, from the same guides); see
/// the module documentation. The output is `x + w (y − x)`
/// ([`super::heuristic::apply`]).
pub fn guard(
    noisy: &Film,
    denoised: &Film,
    halves: &[Option<(Vec3A, Vec3A)>],
    denoised_a: &Film,
) -> Vec<f32> {
    let (w, h) = (noisy.width as usize, noisy.height as usize);
    assert_eq!(noisy.pixels.len(), w * h);
    assert_eq!(denoised.pixels.len(), w * h);
    assert_eq!(halves.len(), w * h);
    assert_eq!(denoised_a.pixels.len(), w * h);
    let eps = epsilon(denoised);
    let guess = truth_guess(denoised, halves);
    // Per pixel, (f(A) − B)² − (A − B)²: its mean is M_A − V_A. Both are
    // clamped at the 99.9th percentile of (A − B)², as the clamped relative
    // MSE clamps its per-pixel errors: a firefly counts as that quantile, so
    // removing one does not buy blurring everything around it.
    let (dx, dy) = squared_differences(denoised, &guess, halves, denoised_a);
    let cap = quantile(&dx, CLAMP_QUANTILE);
    let s: Vec<f64> = dx
        .par_iter()
        .zip(&dy)
        .map(|(&x, &y)| y.min(cap) - x.min(cap))
        .collect();
    let sharp = weights(&s, w, h, RADIUS);
    // The same through the eye's filters (FLIP's): the differences in an
    // opponent space, each channel blurred by its contrast sensitivity.
    let opponent = |d: Vec3A| [luminance(d), d.x - d.y, d.z - 0.5 * (d.x + d.y)];
    let channels = |pick: &(dyn Fn(&(Vec3A, Vec3A), Vec3A) -> Vec3A + Sync)| -> [Vec<f64>; 3] {
        let o: Vec<[f32; 3]> = halves
            .par_iter()
            .zip(&denoised_a.pixels)
            .map(|(halves, &ya)| match halves {
                Some(ab) => opponent(pick(ab, ya)),
                None => [0.0; 3],
            })
            .collect();
        std::array::from_fn(|c| {
            let plane: Vec<f64> = o.iter().map(|v| f64::from(v[c])).collect();
            gaussian(&plane, w, h, CSF_SIGMA[c])
        })
    };
    let noisy_seen = channels(&|(a, b), _| *a - *b);
    let denoised_seen = channels(&|(_, b), ya| ya - *b);
    let scale: Vec<f64> = guess
        .par_iter()
        .map(|&y| {
            let l = f64::from(luminance(y));
            1.0 / (l * l + eps)
        })
        .collect();
    let (noisy_seen, denoised_seen): (Vec<f64>, Vec<f64>) = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let square = |c: &[Vec<f64>; 3]| c.iter().map(|p| p[i] * p[i]).sum::<f64>();
            (
                square(&noisy_seen) * scale[i],
                square(&denoised_seen) * scale[i],
            )
        })
        .unzip();
    // Clamped as above: FLIP's per-pixel error is bounded too, and a few
    // fireflies' squares would otherwise decide a whole window.
    let cap = quantile(&noisy_seen, CLAMP_QUANTILE);
    let seen: Vec<f64> = (noisy_seen.par_iter())
        .zip(&denoised_seen)
        .map(|(&x, &y)| y.min(cap) - x.min(cap))
        .collect();
    let seen = weights(&seen, w, h, SEEN_RADIUS);
    sharp.iter().zip(&seen).map(|(a, b)| a.min(*b)).collect()
}

/// The guard's per-pixel estimates, for a look at them: over each pixel's
/// window of (2 [`RADIUS`] + 1)² pixels, the mean relative squared error of
/// the noisy half `A` (`V_A ≈ (A − B)² / 2`) and of the denoised half `f(A)`
/// (`M_A ≈ (f(A) − B)² − (A − B)² / 2`), measured as [`guard`] measures them
/// per pixel. `true_error` gives the same means of `(v − truth)²` for a
/// reference image, to set beside them.
pub fn estimates(
    denoised: &Film,
    halves: &[Option<(Vec3A, Vec3A)>],
    denoised_a: &Film,
) -> (Vec<f64>, Vec<f64>) {
    let (w, h) = (denoised.width as usize, denoised.height as usize);
    let guess = truth_guess(denoised, halves);
    let (dx, dy) = squared_differences(denoised, &guess, halves, denoised_a);
    let (dx, dy) = (
        window_mean(&dx, w, h, RADIUS),
        window_mean(&dy, w, h, RADIUS),
    );
    let noisy = dx.iter().map(|d| d / 2.0).collect();
    let denoised = dx.iter().zip(&dy).map(|(x, y)| y - x / 2.0).collect();
    (noisy, denoised)
}

/// The window means (as [`estimates`]) of the relative squared error of
/// `image` against `truth`, relative to the guess of the truth the guard
/// measures by ([`truth_guess`] of `denoised` and `halves`).
pub fn true_error(
    image: &Film,
    truth: &Film,
    denoised: &Film,
    halves: &[Option<(Vec3A, Vec3A)>],
) -> Vec<f64> {
    let (w, h) = (denoised.width as usize, denoised.height as usize);
    let relative = relative_to(denoised);
    let guess = truth_guess(denoised, halves);
    let e: Vec<f64> = (image.pixels.par_iter())
        .zip(&truth.pixels)
        .zip(&guess)
        .map(|((&v, &t), &g)| relative(v - t, g))
        .collect();
    window_mean(&e, w, h, RADIUS)
}

/// Per pixel, the squared differences `(A − B)²` and `(f(A) − B)²` relative
/// to `guess` ([`relative_to`]; zero where the pixel has no halves).
fn squared_differences(
    denoised: &Film,
    guess: &[Vec3A],
    halves: &[Option<(Vec3A, Vec3A)>],
    denoised_a: &Film,
) -> (Vec<f64>, Vec<f64>) {
    let relative = relative_to(denoised);
    halves
        .par_iter()
        .zip(guess)
        .zip(&denoised_a.pixels)
        .map(|((halves, &g), &ya)| match halves {
            Some((a, b)) => (relative(*a - *b, g), relative(ya - *b, g)),
            None => (0.0, 0.0),
        })
        .unzip()
}

/// The guess of each pixel's true value the guard's relative errors are
/// measured by: the denoised value `y`, but per channel no more than the
/// mean of the half `A` over the pixel and its eight neighbours (those that
/// have halves; `y` where none has).
///
/// The denoised value is the best guess where the denoiser is right, and
/// where it is wrong it is most often too bright: it spreads a small bright
/// light (a lamp, a highlight) into a glow over the dark, already converged
/// pixels around it. Measured relative to that glow, the glow's own error
/// looks small, and the guard would keep it. `A` knows nothing of the
/// denoiser and, being an unbiased mean, is not too bright on average; its
/// mean over the nine pixels (four and a half times a pixel's samples) is
/// the smallest neighbourhood that tames its noise. Neither guess depends on
/// `B`, so each pixel's `(f(A) − B)² − (A − B)²` keeps its mean (`y` does,
/// but only through the denoiser's average over many pixels). (Measured in
/// docs/denoising.md: on the street, the guard with `y` alone made the
/// image worse than the noisy one at 8–32 spp, and with this guess it is
/// better at every count.)
pub fn truth_guess(denoised: &Film, halves: &[Option<(Vec3A, Vec3A)>]) -> Vec<Vec3A> {
    let (w, h) = (denoised.width as usize, denoised.height as usize);
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (mut sum, mut n) = (Vec3A::ZERO, 0u32);
            for ny in y.saturating_sub(1)..(y + 2).min(h) {
                for nx in x.saturating_sub(1)..(x + 2).min(w) {
                    if let Some((a, _)) = halves[ny * w + nx] {
                        sum += a;
                        n += 1;
                    }
                }
            }
            let v = denoised.pixels[i];
            if n == 0 { v } else { v.min(sum / n as f32) }
        })
        .collect()
}

/// `ε`: 1 % of the squared mean of `denoised` (over pixels and channels).
fn epsilon(denoised: &Film) -> f64 {
    let n = (3 * denoised.pixels.len()).max(1) as f64;
    let mean = denoised
        .pixels
        .iter()
        .map(|p| f64::from(p.element_sum()))
        .sum::<f64>()
        / n;
    0.01 * mean * mean
}

/// Each channel's squared difference over `g² + ε` (`g` a guess of the
/// truth), summed; `ε` from `denoised` ([`epsilon`]).
fn relative_to(denoised: &Film) -> impl Fn(Vec3A, Vec3A) -> f64 + Sync + use<> {
    let eps = epsilon(denoised);
    move |d: Vec3A, y: Vec3A| {
        let (d, y) = (d.as_dvec3(), y.as_dvec3());
        (d * d / (y * y + eps)).element_sum()
    }
}

/// [`box_sum`] over the number of pixels in each clipped window.
pub(super) fn window_mean(values: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    let ones = vec![1.0; values.len()];
    let (sum, count) = (box_sum(values, w, h, r), box_sum(&ones, w, h, r));
    sum.iter().zip(&count).map(|(s, c)| s / c).collect()
}

/// The `q`-quantile of `values` (the lower of the two around it), ignoring
/// values that are not finite; +∞ if there is none.
fn quantile(values: &[f64], q: f64) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.is_empty() {
        return f64::INFINITY;
    }
    sorted.sort_unstable_by(f64::total_cmp);
    let at = ((sorted.len() - 1) as f64 * q).floor() as usize;
    sorted[at]
}

/// The weights [`weight`] gives each pixel's window (of `(2r + 1)²`
/// pixels) of the per-pixel differences `s`.
fn weights(s: &[f64], w: usize, h: usize, r: usize) -> Vec<f32> {
    let squares: Vec<f64> = s.par_iter().map(|s| s * s).collect();
    let (sum, squares) = (box_sum(s, w, h, r), box_sum(&squares, w, h, r));
    sum.par_iter()
        .zip(&squares)
        .map(|(&s, &q)| weight(s, q))
        .collect()
}

/// `values` (a `w × h` image) blurred by a Gaussian of standard deviation
/// `sigma` pixels, truncated at 3σ and renormalised at the image's edges.
fn gaussian(values: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as usize;
    let kernel: Vec<f64> = (0..=r)
        .map(|k| (-((k * k) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let row_len = w.max(1);
    let pass = |get: &(dyn Fn(usize, usize) -> f64 + Sync), along_x: bool| -> Vec<f64> {
        let mut out = vec![0.0; w * h];
        out.par_chunks_mut(row_len)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, o) in row.iter_mut().enumerate() {
                    let (at, len) = if along_x { (x, w) } else { (y, h) };
                    let (mut sum, mut total) = (0.0, 0.0);
                    for j in at.saturating_sub(r)..(at + r + 1).min(len) {
                        let k = kernel[j.abs_diff(at)];
                        sum += k * if along_x { get(j, y) } else { get(x, j) };
                        total += k;
                    }
                    *o = sum / total;
                }
            });
        out
    };
    let rows = pass(&|x, y| values[y * w + x], true);
    pass(&|x, y| rows[y * w + x], false)
}

/// The denoised value's weight from a window's sum `s` of the per-pixel
/// differences `(f(A) − B)² − (A − B)²` (whose mean is `M_A − V_A`) and the
/// sum `q` of their squares: the evidence `t = −s / √q` that the denoised
/// half is better (`s` in units of its own standard error, were the pixels
/// independent), clamped to `[0, 1]`. So the denoised value is taken whole
/// where it is better by at least a standard error, not at all where it is
/// not better, and in proportion between.
#[inline]
pub fn weight(s: f64, q: f64) -> f32 {
    if q.is_nan() || q <= 0.0 || q.is_infinite() || s.is_nan() {
        return 0.0;
    }
    (-s / q.sqrt()).clamp(0.0, 1.0) as f32
}

/// The sum of `values` (a `w × h` image) over the window of `(2r + 1)²`
/// pixels around each pixel, clipped to the image, summed directly (no
/// running sums, whose cancellation a firefly's huge value would ruin).
/// Infinities spread to the windows they are in.
fn box_sum(values: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    let row_len = w.max(1);
    // Rows first: each row's sums over its horizontal windows.
    let mut rows = vec![0.0f64; w * h];
    rows.par_chunks_mut(row_len)
        .zip(values.par_chunks(row_len))
        .for_each(|(out, row)| {
            for (x, o) in out.iter_mut().enumerate() {
                let (a, b) = (x.saturating_sub(r), (x + r + 1).min(w));
                *o = row[a..b].iter().sum::<f64>();
            }
        });
    let mut out = vec![0.0f64; w * h];
    out.par_chunks_mut(row_len)
        .enumerate()
        .for_each(|(y, out)| {
            let (a, b) = (y.saturating_sub(r), (y + r + 1).min(h));
            for (x, o) in out.iter_mut().enumerate() {
                *o = (a..b).map(|yy| rows[yy * w + x]).sum();
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(w: u32, h: u32, f: impl Fn(usize) -> Vec3A) -> Film {
        let mut film = Film::new(w, h);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            *p = f(i);
        }
        film
    }

    #[test]
    fn the_weight_is_the_evidence_that_the_denoised_half_is_better() {
        // Better by 1.5 standard errors: whole.
        assert_eq!(weight(-3.0, 4.0), 1.0);
        // Better by half a standard error: half.
        assert_eq!(weight(-1.0, 4.0), 0.5);
        // Worse: not at all.
        assert_eq!(weight(1.0, 4.0), 0.0);
        // No halves, no noise or no number: the noisy image stays.
        assert_eq!(weight(0.0, 0.0), 0.0);
        assert_eq!(weight(f64::NAN, 1.0), 0.0);
        assert_eq!(weight(-1.0, f64::INFINITY), 0.0);
    }

    #[test]
    fn halves_recover_both_means() {
        // 4 samples: A = {1, 3}, B = {5, 7}: x = 4, B = 6, n_B = 2.
        let image = film(1, 1, |_| Vec3A::splat(4.0));
        let half = [6.0, 6.0, 6.0, 2.0];
        let h = halves(&image, &half, None, 4);
        assert_eq!(h[0], Some((Vec3A::splat(2.0), Vec3A::splat(6.0))));
        // One sample: no second half.
        let one = [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0];
        assert_eq!(halves(&image, &one, None, 1)[0], None);
        // Counts per pixel (adaptive): 8 samples of mean 4, B = 3 of mean 6.
        let h = halves(&image, &[6.0, 6.0, 6.0, 3.0], Some(&[8.0]), 64);
        let a = (4.0 * 8.0 - 6.0 * 3.0) / 5.0;
        assert!((h[0].unwrap().0 - Vec3A::splat(a)).abs().max_element() < 1e-6);
    }

    /// Halves of a value with noise: `truth` ± `noise` in each half, the
    /// signs drawn independently per pixel and half (white noise, which the
    /// eye's filters do not remove either).
    fn noisy_halves(w: u32, h: u32, truth: f32, noise: f32) -> (Film, Vec<Option<(Vec3A, Vec3A)>>) {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut sign = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if state & 1 == 0 { noise } else { -noise }
        };
        let halves: Vec<_> = (0..(w * h) as usize)
            .map(|_| Some((Vec3A::splat(truth + sign()), Vec3A::splat(truth + sign()))))
            .collect();
        let noisy = film(w, h, |i| {
            let (a, b) = halves[i].unwrap();
            (a + b) * 0.5
        });
        (noisy, halves)
    }

    #[test]
    fn a_good_denoiser_is_taken_and_a_biased_one_is_not() {
        let (w, h) = (48u32, 40u32);
        let (noisy, halves) = noisy_halves(w, h, 1.0, 0.3);
        // A denoiser that finds the truth from either input.
        let truth = film(w, h, |_| Vec3A::ONE);
        let weights = guard(&noisy, &truth, &halves, &truth);
        assert!(weights.iter().all(|&w| w == 1.0));
        // One that darkens everything by 40 %: its error (0.16) is far above
        // the noisy image's, so the noisy image stays.
        let dark = film(w, h, |_| Vec3A::splat(0.6));
        let weights = guard(&noisy, &dark, &halves, &dark);
        assert!(weights.iter().all(|&w| w == 0.0), "{weights:?}");
    }

    #[test]
    fn the_truth_is_guessed_no_brighter_than_the_neighbourhood_of_a() {
        // A 4 × 3 image: half A is 0.03 everywhere but for a light of 9 at
        // (0, 0); the denoiser spreads the light into a glow of 0.5 and
        // finds 0.01 at (3, 2); (3, 0) has no halves.
        let (w, h) = (4u32, 3u32);
        let halves: Vec<_> = (0..12)
            .map(|i| match i {
                0 => Some((Vec3A::splat(9.0), Vec3A::splat(9.0))),
                3 => None,
                _ => Some((Vec3A::splat(0.03), Vec3A::splat(0.03))),
            })
            .collect();
        let denoised = film(w, h, |i| match i {
            0 => Vec3A::splat(9.0),
            11 => Vec3A::splat(0.01),
            _ => Vec3A::splat(0.5),
        });
        let g = truth_guess(&denoised, &halves);
        let close = |v: Vec3A, e: f32| (v - Vec3A::splat(e)).abs().max_element() < 1e-6;
        // Beside the light, A's mean over the clipped window is above the
        // glow ((9 + 5 · 0.03) / 6 at (1, 0)): the glow.
        assert!(close(g[1], 0.5), "{}", g[1]);
        // (1, 1): (9 + 8 · 0.03) / 9 = 1.027 > 0.5: the glow.
        assert!(close(g[5], 0.5), "{}", g[5]);
        // Two pixels away, A's mean (0.03) bounds the glow.
        assert!(close(g[2], 0.03), "{}", g[2]);
        assert!(close(g[6], 0.03), "{}", g[6]);
        // Where the denoiser is darker than A's mean, its value.
        assert!(close(g[11], 0.01), "{}", g[11]);
        // No halves at (3, 0): its neighbours' A.
        assert!(close(g[3], 0.03), "{}", g[3]);
    }

    #[test]
    fn box_sums_add_over_the_clipped_window() {
        let (w, h) = (5, 4);
        let values: Vec<f64> = (0..w * h).map(|i| i as f64).collect();
        let m = box_sum(&values, w, h, 1);
        // Corner (0, 0): 0 + 1 + 5 + 6.
        assert_eq!(m[0], 12.0);
        // Inside (2, 1): rows 0..3, columns 1..4.
        let inside: f64 = [1, 2, 3, 6, 7, 8, 11, 12, 13].iter().sum::<i32>() as f64;
        assert_eq!(m[w + 2], inside);
    }
}
