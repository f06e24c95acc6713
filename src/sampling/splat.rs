//! The weights of splatting ([`Reconstruction::Splat`]): a sample at image
//! point `(q + u)` (pixel `q`, `u` uniform in `[0, 1)`) is added to pixel `p`
//! with weight `f(q + u − p − ½) / G(p)` in x times the same in y, where `f`
//! is the 1-D filter ([`PixelFilter::eval_1d`]) and `G(p)` is `f`'s integral
//! over the image row (or column) around `p`'s centre: `∫₀ⁿ f(x − p − ½) dx`.
//!
//! With every pixel's samples uniform over the pixel and `N` of them a
//! pixel, the mean of `N⁻¹ Σ w·L` at `p` is then exactly
//! `∫ f f L / ∫ f f` over the image: the filter-weighted mean of the radiance
//! around `p`, normalised over the image, which is what Mitsuba's splatting
//! (dividing by the weights' sum) converges to, edges included. No weight sum
//! is kept: a pixel stays a plain sum over `N`, so raylab's exact per-pixel
//! sums, passes, checkpoints and farms keep working unchanged.
//!
//! `f` is tabulated ([`SEGMENTS`] linear segments over the radius) and both
//! the weights and the normalisers use the same piecewise-linear `f`, so the
//! normalisation is exact for the function the weights use (it differs from
//! the analytic filter by below 1e-6 of its peak).

use std::ops::Range;

use super::filter::{MAX_SPLAT_BORDER, PixelFilter, Reconstruction};

/// Linear segments of the tabulated filter over its radius.
pub const SEGMENTS: usize = 1024;

/// Weights of one sample along one axis: entry `k` for pixel `q + k − border`.
pub type AxisWeights = [f32; 2 * MAX_SPLAT_BORDER + 1];

/// The splatting weights of one filter on an image of a given size.
#[derive(Clone, Debug)]
pub struct SplatWeights {
    radius: f32,
    border: usize,
    /// `f(i·radius/SEGMENTS)` for `i` in `0..=SEGMENTS`.
    table: Vec<f32>,
    /// `SEGMENTS / radius`.
    scale: f32,
    /// `1/G` of each column.
    columns: Vec<f32>,
    /// `1/G` of each row.
    rows: Vec<f32>,
    /// The columns and the rows whose `1/G` is the whole filter's
    /// (`inner.0` for columns, `inner.1` for rows).
    inner: (Range<usize>, Range<usize>),
}

impl SplatWeights {
    /// The weights of `filter` on a `width × height` image, if
    /// `reconstruction` splats with it ([`PixelFilter::splats`]).
    pub fn new(
        filter: PixelFilter,
        reconstruction: Reconstruction,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        if !filter.splats(reconstruction) {
            return None;
        }
        let radius = filter.radius();
        let step = f64::from(radius) / SEGMENTS as f64;
        let table: Vec<f32> = (0..=SEGMENTS)
            .map(|i| filter.eval_1d((i as f64 * step) as f32))
            .collect();
        // ∫₀ˣ of the piecewise-linear f, at the nodes.
        let mut cumulative = vec![0.0f64; SEGMENTS + 1];
        for i in 0..SEGMENTS {
            let (a, b) = (f64::from(table[i]), f64::from(table[i + 1]));
            cumulative[i + 1] = cumulative[i] + 0.5 * (a + b) * step;
        }
        // ∫₀ˣ for any x (odd in x, constant beyond the radius).
        let from_zero = |x: f64| -> f64 {
            let t = (x.abs() / step).min(SEGMENTS as f64);
            let i = (t as usize).min(SEGMENTS - 1);
            let frac = t - i as f64;
            let (a, b) = (f64::from(table[i]), f64::from(table[i + 1]));
            let part = cumulative[i] + step * (a * frac + 0.5 * (b - a) * frac * frac);
            part.copysign(x)
        };
        let normalisers = |n: u32| -> Vec<f32> {
            (0..n)
                .map(|p| {
                    let centre = f64::from(p) + 0.5;
                    let g = from_zero(f64::from(n) - centre) - from_zero(-centre);
                    (1.0 / g) as f32
                })
                .collect()
        };
        let (columns, rows) = (normalisers(width), normalisers(height));
        // The whole filter's 1/G, as an inner pixel's is computed (both ends
        // clamped to the radius).
        let whole = (1.0 / (from_zero(f64::INFINITY) - from_zero(f64::NEG_INFINITY))) as f32;
        let inner = |g: &[f32]| -> Range<usize> {
            match g.iter().position(|&v| v == whole) {
                Some(lo) => lo..g.len() - g.iter().rev().position(|&v| v == whole).unwrap_or(0),
                None => 0..0,
            }
        };
        Some(Self {
            radius,
            border: filter.splat_border(),
            table,
            scale: (SEGMENTS as f64 / f64::from(radius)) as f32,
            inner: (inner(&columns), inner(&rows)),
            columns,
            rows,
        })
    }

    /// How many pixels beyond a sample's own (each way) it reaches.
    pub fn border(&self) -> usize {
        self.border
    }

    /// The weights in x of a sample in column `q` at `u` across the pixel
    /// (entry `k` for column `q + k − border`; zero outside the image).
    #[inline]
    pub fn columns(&self, q: usize, u: f32) -> AxisWeights {
        self.axis(&self.columns, &self.inner.0, q, u)
    }

    /// The weights in y of a sample in row `q` at `u` down the pixel.
    #[inline]
    pub fn rows(&self, q: usize, u: f32) -> AxisWeights {
        self.axis(&self.rows, &self.inner.1, q, u)
    }

    #[inline(always)]
    fn axis(&self, normalisers: &[f32], inner: &Range<usize>, q: usize, u: f32) -> AxisWeights {
        let mut w = [0.0; 2 * MAX_SPLAT_BORDER + 1];
        let b = self.border;
        // Away from the edges every pixel's normaliser is the whole
        // filter's (the same number).
        let inside = q >= inner.start + b && q + b < inner.end;
        let table = &self.table[..SEGMENTS + 1];
        for (k, w) in w.iter_mut().enumerate().take(2 * b + 1) {
            // Pixel q + k − b, whose centre is k − b + ½ from the pixel's corner.
            let d = u - 0.5 - (k as f32 - b as f32);
            let t = d.abs() * self.scale;
            if d.abs() < self.radius && t < SEGMENTS as f32 {
                let g = if inside {
                    normalisers[q]
                } else {
                    match (q + k).checked_sub(b).and_then(|p| normalisers.get(p)) {
                        Some(&g) => g,
                        None => continue,
                    }
                };
                // The tabulated f(|d|), 0 from the radius on.
                let i = t as usize;
                let frac = t - i as f32;
                let (a, c) = (table[i], table[i + 1]);
                *w = (a + (c - a) * frac) * g;
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian(width: u32, height: u32) -> SplatWeights {
        SplatWeights::new(
            PixelFilter::gaussian(0.5),
            Reconstruction::Splat,
            width,
            height,
        )
        .unwrap()
    }

    #[test]
    fn borders_follow_the_radius() {
        let border = |f: PixelFilter| f.splat_border();
        assert_eq!(border(PixelFilter::gaussian(0.5)), 2);
        assert_eq!(border(PixelFilter::tent(1.0)), 1);
        assert_eq!(border(PixelFilter::tent(1.5)), 1);
        assert_eq!(border(PixelFilter::tent(1.51)), 2);
        assert!(!PixelFilter::gaussian(2.0).splats(Reconstruction::Splat));
        assert!(!PixelFilter::Box.splats(Reconstruction::Splat));
        assert!(!PixelFilter::gaussian(0.5).splats(Reconstruction::Sample));
    }

    /// Every pixel's weights, over samples spread uniformly over the image,
    /// average to one (the estimator's mean is the normalised filter's
    /// integral), at the edges as well as inside; and no weight reaches a
    /// pixel outside the filter's radius.
    #[test]
    fn each_pixel_receives_unit_weight_on_average() {
        for filter in [
            PixelFilter::gaussian(0.5),
            PixelFilter::tent(1.0),
            PixelFilter::tent(2.3),
        ] {
            let n = 9u32;
            let s = SplatWeights::new(filter, Reconstruction::Splat, n, 1).unwrap();
            let mut got = vec![0.0f64; n as usize];
            const PER_PIXEL: usize = 20_000;
            for q in 0..n as usize {
                for i in 0..PER_PIXEL {
                    let u = (i as f32 + 0.5) / PER_PIXEL as f32;
                    let w = s.columns(q, u);
                    for (k, w) in w.iter().enumerate() {
                        if *w == 0.0 {
                            continue;
                        }
                        let p = q + k - s.border();
                        let d = (q as f32 + u) - (p as f32 + 0.5);
                        assert!(d.abs() < filter.radius(), "{filter:?}: weight at {d}");
                        got[p] += f64::from(*w) / PER_PIXEL as f64;
                    }
                }
            }
            for (p, g) in got.iter().enumerate() {
                assert!((g - 1.0).abs() < 1e-4, "{filter:?}: pixel {p} gets {g}");
            }
        }
    }

    /// The weights are the filter's (up to normalisation) at the offsets.
    #[test]
    fn weights_are_the_filter_normalised() {
        let s = gaussian(64, 64);
        let f = PixelFilter::gaussian(0.5);
        // Inside: G = ∫ f, about σ√(2π) less the lowering.
        let g: f64 = (0..200_000)
            .map(|i| f64::from(f.eval_1d(-2.0 + 4.0 * (i as f32 + 0.5) / 200_000.0)) * 2.0e-5)
            .sum();
        for u in [0.1f32, 0.5, 0.93] {
            let w = s.columns(30, u);
            for (k, w) in w.iter().enumerate().take(5) {
                let d = u - 0.5 - (k as f32 - 2.0);
                let want = f64::from(f.eval_1d(d)) / g;
                assert!(
                    (f64::from(*w) - want).abs() < 1e-5,
                    "u {u} k {k}: {w} vs {want}"
                );
            }
        }
    }
}
