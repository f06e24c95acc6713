//! Adaptive sampling: pixels whose estimated error is below a threshold stop
//! taking samples ([`Adaptive`]), decided from the render's own exact sums.
//!
//! Each pixel's error is estimated from its two halves of samples: the image
//! is the mean `x` of all of them, [`Aov::Half`] the mean `h` of one sample
//! of each pair `2k, 2k + 1` ([`crate::aov::in_half`]), two estimates of the
//! same value whose difference is noise. The measure is Cycles' (Dammertz et
//! al. 2010, "A hierarchical automatic stopping condition for Monte Carlo
//! global illumination", as Blender's "noise threshold" uses it), so that a
//! threshold means what it means in Blender:
//!
//! `e = (|x_r − h_r| + |x_g − h_g| + |x_b − h_b|) / (10⁻⁴ + √(x_r + x_g + x_b))`,
//!
//! the error relative to the square root of the pixel's brightness: a
//! relative error that, like the eye and every tone map, forgives dark pixels
//! more (a plain relative error would keep near-black pixels sampling
//! forever). One pixel's `e` is a single difference, below the threshold by
//! chance as often as not, so a pixel counts as converged when the mean of
//! `e` over it and its eight neighbours is below `T`, and it stops when it
//! and its neighbours are all converged (a stopped pixel next to a noisy one
//! would show as a speck). Neighbours are taken only within the pixel's row
//! tile ([`TILE_ROWS`] rows), so that a part of a split render decides
//! exactly as the whole render does.
//!
//! When: after a minimum of samples (Cycles' automatic rule, `16 / T^0.3`
//! rounded up to an even number: 32 at `T = 0.1`, 64 at `0.01`, 128 at
//! `0.001`), then every [`STEP`] samples. Decisions are made only at those
//! fixed counts, from exact sums, so they are the same on any number of
//! threads, in every part of a split render and after a resume: a stopped
//! pixel is one whose count is below the render's, and the check at a count is
//! made again from the same sums when a render resumes there.

use super::accumulator::Accumulator;
use super::split::TILE_ROWS;
use crate::aov::{Aov, AovSet, Layout};
use crate::fixed;

/// The AOVs an adaptive render gathers: the half and the sample counts.
pub const AOVS: AovSet = AovSet::of(&[Aov::Half, Aov::Samples]);

/// Samples between two checks after the first (Cycles' step).
pub const STEP: u32 = 16;

/// Adaptive sampling's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Pixels whose estimated error (see the module documentation) is below
    /// this stop.
    pub threshold: f32,
    /// Samples every pixel takes before the first check (even).
    pub min_spp: u32,
}

impl Adaptive {
    /// Noise threshold `threshold` with Cycles' automatic minimum of samples.
    pub fn new(threshold: f32) -> Self {
        let min = (16.0 / f64::from(threshold).powf(0.3))
            .ceil()
            .clamp(4.0, 1e6) as u32;
        Self {
            threshold,
            min_spp: min.next_multiple_of(2),
        }
    }

    /// Whether pixels are checked after `spp` samples.
    pub fn checks_at(&self, spp: u32) -> bool {
        spp >= self.min_spp && (spp - self.min_spp).is_multiple_of(STEP)
    }

    /// The next count after `spp` at which pixels are checked.
    pub fn next_check(&self, spp: u32) -> u32 {
        if spp < self.min_spp {
            self.min_spp
        } else {
            spp + STEP - (spp - self.min_spp) % STEP
        }
    }
}

/// The pixels of `acc` that go on taking samples, or `None` while all do
/// (before the first check): those that took all of `acc`'s samples so far
/// and, where `acc`'s count is a check's, whose error is not yet below the
/// threshold. `acc` must gather [`Aov::Half`] and [`Aov::Samples`].
pub fn active_pixels(acc: &Accumulator, adaptive: &Adaptive) -> Option<Vec<bool>> {
    let spp = acc.spp();
    if spp < adaptive.min_spp {
        return None;
    }
    let set = acc.aov_set();
    let layout = Layout::new(set);
    let (Some(half), Some(count)) = (layout.offset(Aov::Half), layout.offset(Aov::Samples)) else {
        panic!("adaptive sampling needs the half and samples AOVs");
    };
    let stride = layout.stride;
    let records = acc.aov_sums();
    let counted = |i: usize| (records[i * stride + count] >> fixed::FRACTION_BITS) as u64;
    let mut active: Vec<bool> = (0..acc.image_sums().len())
        .map(|i| counted(i) == u64::from(spp))
        .collect();
    if !adaptive.checks_at(spp) {
        return Some(active);
    }
    let width = acc.width() as usize;
    let image = acc.image_sums();
    // Each pixel's error (f64::INFINITY where its halves are not both
    // there).
    let errors: Vec<f64> = (0..image.len())
        .map(|i| {
            let record = &records[i * stride..(i + 1) * stride];
            let n_half = (record[half + 3] >> fixed::FRACTION_BITS) as f64;
            let n = counted(i) as f64;
            if n_half <= 0.0 || n_half >= n {
                return f64::INFINITY;
            }
            let mut diff = 0.0;
            let mut sum = 0.0;
            for c in 0..3 {
                let x = fixed::to_f64(image[i][c]) / n;
                let h = fixed::to_f64(record[half + c]) / n_half;
                diff += (x - h).abs();
                sum += x;
            }
            let error = diff / (1e-4 + sum.max(0.0).sqrt());
            // (A NaN error counts as noisy.)
            if error.is_nan() { f64::INFINITY } else { error }
        })
        .collect();
    let height = image.len() / width.max(1);
    // A pixel is noisy where the mean error of it and its neighbours (in its
    // row tile) is not below the threshold: one pixel's own estimate is a
    // single difference, below the threshold by chance as often as not.
    let noisy: Vec<bool> = (0..image.len())
        .map(|i| {
            if !active[i] {
                return false;
            }
            let (x, y) = (i % width, i / width);
            let tile = y / TILE_ROWS;
            let (mut sum, mut count) = (0.0, 0.0);
            for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                if ny / TILE_ROWS != tile {
                    continue;
                }
                for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                    sum += errors[ny * width + nx];
                    count += 1.0;
                }
            }
            sum / count >= f64::from(adaptive.threshold) || sum.is_nan()
        })
        .collect();
    // A pixel goes on if it or a neighbour (in its row tile) is still noisy.
    for y in 0..height {
        let tile = y / TILE_ROWS;
        for x in 0..width {
            let i = y * width + x;
            if !active[i] {
                continue;
            }
            let mut go_on = false;
            for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                if ny / TILE_ROWS != tile {
                    continue;
                }
                for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                    go_on |= noisy[ny * width + nx];
                }
            }
            active[i] = go_on;
        }
    }
    Some(active)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_minimum_follows_cycles_rule_and_checks_come_every_step() {
        assert_eq!(Adaptive::new(0.1).min_spp, 32);
        assert_eq!(Adaptive::new(0.01).min_spp, 64);
        assert_eq!(Adaptive::new(0.001).min_spp, 128);
        assert_eq!(Adaptive::new(0.5).min_spp, 20);
        let a = Adaptive::new(0.01);
        assert!(!a.checks_at(32) && a.checks_at(64) && !a.checks_at(70) && a.checks_at(80));
        assert_eq!(a.next_check(0), 64);
        assert_eq!(a.next_check(64), 80);
        assert_eq!(a.next_check(70), 80);
    }
}
