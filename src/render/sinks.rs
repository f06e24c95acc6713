//! Where the tiles' loops hand their samples ([`Sink`]): a tile's exact
//! sums ([`ExactSums`]), its rows of an f32 film ([`FilmSums`]), or, when a
//! render splats ([`crate::sampling::filter::Reconstruction::Splat`]), its
//! rows and a border around them ([`SplatSums`]).

use glam::{DVec3, Vec2, Vec3A};

use crate::fixed::{self, Fixed3};
use crate::sampling::filter::MAX_SPLAT_BORDER;
use crate::sampling::splat::SplatWeights;

/// Where [`Tile::trace`] hands its samples: each with its pixel's index in the
/// tile, one at a time or the eight of a 4×2 block of the lab's integrators
/// at once. Non-finite samples are dropped and counted.
pub(super) trait Sink {
    /// Adds sample value `v` to pixel `i`.
    fn add(&mut self, i: usize, v: Vec3A);
    /// Adds `v[k]` to pixel `i[k]`, as eight [`Sink::add`] calls would.
    fn add8(&mut self, i: [usize; 8], v: [Vec3A; 8]) {
        for (i, v) in i.into_iter().zip(v) {
            self.add(i, v);
        }
    }
    /// Adds sample value `v` to pixel `i`, its image point `d` from the
    /// pixel's corner (which only [`SplatSums`] uses).
    #[inline]
    fn add_at(&mut self, i: usize, d: Vec2, v: Vec3A) {
        let _ = d;
        self.add(i, v);
    }
    /// [`Sink::add_at`] of eight samples.
    #[inline]
    fn add8_at(&mut self, i: [usize; 8], d: [Vec2; 8], v: [Vec3A; 8]) {
        let _ = d;
        self.add8(i, v);
    }
    /// Ends one sample of every pixel of the tile (the samples are traced in
    /// sample order).
    #[inline]
    fn end_sample(&mut self) {}
    /// [`Sink::add8`] of values given channel by channel (`v[c][k]` is
    /// channel `c` of sample `k`).
    fn add8_channels(&mut self, i: [usize; 8], v: &[[f32; 8]; 3]) {
        let at = |k: usize| Vec3A::new(v[0][k], v[1][k], v[2][k]);
        self.add8(i, [at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7)]);
    }
}

/// A tile's exact sums (see [`super::Accumulator`]).
pub(super) struct ExactSums<'a> {
    pub(super) sums: &'a mut [Fixed3],
    pub(super) dropped: &'a mut u64,
}

impl Sink for ExactSums<'_> {
    #[inline]
    fn add(&mut self, i: usize, v: Vec3A) {
        if v.is_finite() {
            fixed::add3(&mut self.sums[i], v);
        } else {
            *self.dropped += 1;
        }
    }

    /// The eight conversions in one call when all are finite (the usual case):
    /// one at a time they were an eighth of a `direct` frame's instructions.
    #[inline]
    fn add8(&mut self, i: [usize; 8], v: [Vec3A; 8]) {
        if v.iter().all(|v| v.is_finite()) {
            fixed::add8(self.sums, i, v);
        } else {
            for (i, v) in i.into_iter().zip(v) {
                self.add(i, v);
            }
        }
    }

    #[inline]
    fn add8_channels(&mut self, i: [usize; 8], v: &[[f32; 8]; 3]) {
        // (A fold, not `all`: without the early exit it is compiled to lanes.)
        let finite = v.iter().flatten().fold(true, |all, x| all & x.is_finite());
        if finite {
            fixed::add8_channels(self.sums, i, v);
        } else {
            for (k, &i) in i.iter().enumerate() {
                self.add(i, Vec3A::new(v[0][k], v[1][k], v[2][k]));
            }
        }
    }
}

/// A tile's rows of an f32 film: many samples are summed in f64 in `local`
/// first (when it is not empty), one goes straight into the film.
pub(super) struct FilmSums<'a> {
    pub(super) rows: &'a mut [Vec3A],
    pub(super) local: &'a mut [DVec3],
    pub(super) dropped: &'a mut u64,
}

impl Sink for FilmSums<'_> {
    #[inline]
    fn add(&mut self, i: usize, v: Vec3A) {
        if !v.is_finite() {
            *self.dropped += 1;
        } else if let Some(w) = self.local.get_mut(i) {
            *w += v.as_dvec3();
        } else {
            self.rows[i] += v;
        }
    }
}

/// Largest magnitude of one weighted contribution a splat adds to a pixel:
/// a pixel takes at most (2·[`MAX_SPLAT_BORDER`] + 1)² = 81 of them a sample,
/// which stays below [`fixed::MAX_SAMPLE`], the bound the sums' headroom
/// (and a farm's damage check) counts on.
const MAX_CONTRIBUTION: f32 = fixed::MAX_SAMPLE / 128.0;

const _: () = assert!((2 * MAX_SPLAT_BORDER + 1) * (2 * MAX_SPLAT_BORDER + 1) <= 128);

/// A tile's splatted samples: exact sums of its rows and of `border` rows
/// above and below ([`SplatWeights::border`]), row-major, `width` a row;
/// row `border` is the tile's first. The weighted contributions of one
/// sample of every pixel are summed in f32 in `scratch` (the same shape)
/// in the tile's fixed order and added to the exact sums at the sample's
/// end: one conversion a pixel and sample, where a splat reaches 9 to 25
/// pixels, and the sums still do not depend on how the samples fell into
/// passes or parts.
pub(super) struct SplatSums<'a> {
    pub(super) sums: &'a mut [Fixed3],
    pub(super) scratch: &'a mut [Vec3A],
    pub(super) weights: &'a SplatWeights,
    pub(super) width: usize,
    /// The tile's first row in the image.
    pub(super) y0: usize,
    pub(super) dropped: &'a mut u64,
}

impl Sink for SplatSums<'_> {
    /// Never called: a splat needs the sample's point ([`Sink::add_at`]).
    fn add(&mut self, i: usize, v: Vec3A) {
        debug_assert!(false, "a splatted sample without its image point");
        self.add_at(i, Vec2::splat(0.5), v);
    }

    #[inline]
    fn add_at(&mut self, i: usize, d: Vec2, v: Vec3A) {
        if !v.is_finite() {
            *self.dropped += 1;
            return;
        }
        let (x, y) = (i % self.width, i / self.width);
        let b = self.weights.border();
        let wx = self.weights.columns(x, d.x);
        let wy = self.weights.rows(self.y0 + y, d.y);
        let limit = Vec3A::splat(MAX_CONTRIBUTION);
        for (ky, &wy) in wy.iter().enumerate().take(2 * b + 1) {
            if wy == 0.0 {
                continue;
            }
            // Row y + ky − b of the tile is row y + ky of the sums.
            let row = (y + ky) * self.width;
            for (kx, &wx) in wx.iter().enumerate().take(2 * b + 1) {
                let w = wy * wx;
                if w == 0.0 {
                    continue;
                }
                // (A non-zero weight is inside the image: x + kx ≥ b.)
                let at = row + x + kx - b;
                self.scratch[at] += (v * w).clamp(-limit, limit);
            }
        }
    }

    #[inline]
    fn add8_at(&mut self, i: [usize; 8], d: [Vec2; 8], v: [Vec3A; 8]) {
        for k in 0..8 {
            self.add_at(i[k], d[k], v[k]);
        }
    }

    fn end_sample(&mut self) {
        for (s, sum) in self.scratch.iter_mut().zip(self.sums.iter_mut()) {
            if *s != Vec3A::ZERO {
                fixed::add3(sum, *s);
                *s = Vec3A::ZERO;
            }
        }
    }
}
