//! The sums of light splatted anywhere on the image ([`LightImage`]):
//! `bdpt`'s light subpaths seen by the camera, which land on pixels of any
//! tile. Every render thread adds to the one image at once, exactly: each
//! fixed-point sum ([`crate::fixed`]) is kept as two atomic 64-bit words,
//! and integer addition with carries gives the same bits in any order.

use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};

use glam::{Vec2, Vec3A};

use crate::fixed::{self, Fixed3};

/// Exact sums of values splatted onto a `width × height` image, added to
/// from many threads.
#[derive(Debug)]
pub(super) struct LightImage {
    width: usize,
    height: usize,
    /// The low 64 bits of each channel's sum, wrapping.
    low: Vec<AtomicU64>,
    /// The high bits, with the carries out of `low`.
    high: Vec<AtomicI64>,
}

impl LightImage {
    /// No light yet on a `width × height` image.
    pub(super) fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize * 3;
        Self {
            width: width as usize,
            height: height as usize,
            low: (0..n).map(|_| AtomicU64::new(0)).collect(),
            high: (0..n).map(|_| AtomicI64::new(0)).collect(),
        }
    }

    /// Adds `value` to the pixel containing image point `at` (pixels are
    /// unit squares from the top-left corner); a point outside the image or
    /// a value that is not finite adds nothing and returns `false`.
    pub(super) fn add(&self, at: Vec2, value: Vec3A) -> bool {
        if !value.is_finite() || at.x.is_nan() || at.y.is_nan() || at.x < 0.0 || at.y < 0.0 {
            return false;
        }
        let (x, y) = (at.x as usize, at.y as usize);
        if x >= self.width || y >= self.height {
            return false;
        }
        let k = (y * self.width + x) * 3;
        for c in 0..3 {
            self.add_fixed(k + c, fixed::fixed(value[c]));
        }
        true
    }

    /// Adds the fixed-point `v` to sum `k`: its low word with a carry into
    /// the high word when the low word wraps.
    #[inline]
    fn add_fixed(&self, k: usize, v: i128) {
        if v == 0 {
            return;
        }
        let low = v as u64;
        let high = (v >> 64) as i64;
        let before = self.low[k].fetch_add(low, Ordering::Relaxed);
        let carry = i64::from(before.checked_add(low).is_none());
        self.high[k].fetch_add(high.wrapping_add(carry), Ordering::Relaxed);
    }

    /// The sums, one per pixel, row-major.
    pub(super) fn into_sums(self) -> Vec<Fixed3> {
        let value = |k: usize| {
            let low = self.low[k].load(Ordering::Relaxed);
            let high = self.high[k].load(Ordering::Relaxed);
            (i128::from(high) << 64) | i128::from(low)
        };
        (0..self.width * self.height)
            .map(|i| [value(3 * i), value(3 * i + 1), value(3 * i + 2)])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// Values added from many threads in any order sum to exactly what one
    /// thread adding them in turn gets in `i128`, carries and negative
    /// values included.
    #[test]
    fn sums_from_many_threads_are_exact() {
        let image = LightImage::new(3, 2);
        let mut rng = crate::sampling::sampler::Rng::new(9, 1);
        let values: Vec<(Vec2, Vec3A)> = (0..20000)
            .map(|i| {
                let at = Vec2::new(rng.next_f32() * 3.0, rng.next_f32() * 2.0);
                let m = if i % 7 == 0 { 1e9 } else { 1.0 };
                let v = Vec3A::new(rng.next_f32() - 0.3, rng.next_f32() * m, -rng.next_f32());
                (at, v)
            })
            .collect();
        values.par_iter().for_each(|(at, v)| {
            image.add(*at, *v);
        });
        let mut expect = vec![[0i128; 3]; 6];
        for (at, v) in &values {
            let k = at.y as usize * 3 + at.x as usize;
            for c in 0..3 {
                expect[k][c] += fixed::fixed(v[c]);
            }
        }
        assert_eq!(image.into_sums(), expect);
        let outside = LightImage::new(2, 2);
        assert!(!outside.add(Vec2::new(2.0, 0.5), Vec3A::ONE));
        assert!(!outside.add(Vec2::new(0.5, -0.1), Vec3A::ONE));
        assert!(!outside.add(Vec2::new(0.5, 0.5), Vec3A::NAN));
        assert!(outside.add(Vec2::new(1.5, 1.5), Vec3A::ONE));
    }
}
