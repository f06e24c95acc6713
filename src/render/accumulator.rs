//! A render's exact per-pixel sums ([`Accumulator`]), of the whole image or
//! of a part of it that is rendered apart and merged ([`Split`]).

use glam::Vec3A;
use rayon::prelude::*;
use thiserror::Error;

use super::output::{Rendered, Tally};
use super::split::Split;
use super::tile::{Target, accumulate_into};
use crate::aov::{Aov, AovSet, AovSums, Layout};
use crate::camera::Camera;
use crate::film::Film;
use crate::fixed::{self, Fixed3};
use crate::integrators::Integrator;
use crate::scene::Scene;

/// The per-pixel sums of a render in progress: samples `first..first + spp` of
/// every pixel in its [`Split`] (the whole image unless made by
/// [`Accumulator::part`]), summed exactly in fixed point ([`crate::fixed`]),
/// so that any split of the samples into calls of [`Accumulator::add`]
/// (passes, a render stopped, saved and resumed) or into parts rendered apart
/// and merged gives the same sums bit for bit. 48 bytes a pixel, and 16 per
/// AOV channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    width: u32,
    height: u32,
    split: Split,
    first: u32,
    pub(super) spp: u32,
    image: Vec<Fixed3>,
    aovs: Option<(AovSet, Vec<i128>)>,
    tally: Tally,
}

/// Why [`Accumulator::from_parts`] refused its parts.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("{0}")]
pub struct PartsError(String);

impl Accumulator {
    /// No samples yet of a `width × height` image, with the AOVs `aovs`.
    pub fn new(width: u32, height: u32, aovs: AovSet) -> Self {
        Self::part(width, height, aovs, Split::WHOLE, 0)
    }

    /// No samples yet of the rows of `split`, whose samples start at `first`
    /// (a part of a render, to be merged with the others: see
    /// [`crate::farm`]). The sums of rows outside `split` stay zero, but
    /// for those within a splatting filter's reach of its tiles
    /// ([`crate::sampling::filter::Reconstruction::Splat`]).
    pub fn part(width: u32, height: u32, aovs: AovSet, split: Split, first: u32) -> Self {
        let pixels = width as usize * height as usize;
        let aovs = (!aovs.is_empty()).then(|| (aovs, zeroed(pixels * Self::aov_stride(aovs))));
        Self {
            width,
            height,
            split,
            first,
            spp: 0,
            image: vec![[0; 3]; pixels],
            aovs,
            tally: Tally::default(),
        }
    }

    /// Sums read back (e.g. from a checkpoint) of samples `0..spp` of the
    /// whole image: `image` holds `width × height` RGB sums, `aov_sums` the AOV
    /// records (see [`Accumulator::aov_sums`]). [`Accumulator::into_part`]
    /// makes them a part's.
    pub fn from_parts(
        width: u32,
        height: u32,
        aovs: AovSet,
        spp: u32,
        tally: Tally,
        image: Vec<Fixed3>,
        aov_sums: Vec<i128>,
    ) -> Result<Self, PartsError> {
        let mut acc = Self {
            width,
            height,
            split: Split::WHOLE,
            first: 0,
            spp,
            image,
            aovs: None,
            tally,
        };
        let pixels = width as usize * height as usize;
        if acc.image.len() != pixels {
            return Err(PartsError(format!(
                "{} image sums for {width}×{height} pixels",
                acc.image.len()
            )));
        }
        let want = pixels * Self::aov_stride(aovs);
        if aov_sums.len() != want {
            return Err(PartsError(format!(
                "{} AOV sums where {aovs} need {want}",
                aov_sums.len()
            )));
        }
        acc.aovs = (!aovs.is_empty()).then_some((aovs, aov_sums));
        Ok(acc)
    }

    /// AOV values per pixel that [`Accumulator::aov_sums`] holds for `aovs`:
    /// their channels in the set's order, then the number of samples that hit.
    pub fn aov_stride(aovs: AovSet) -> usize {
        if aovs.is_empty() {
            0
        } else {
            Layout::new(aovs).stride
        }
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Samples per pixel summed: samples `first..first + spp` of every pixel
    /// (see [`Accumulator::first_sample`]).
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// The first sample summed (0 but for a part of a render).
    pub fn first_sample(&self) -> u32 {
        self.first
    }

    /// The rows summed.
    pub fn split(&self) -> Split {
        self.split
    }

    /// These sums as those of samples `first..first + spp` of the rows of
    /// `split` (which they must be: the rows outside it zero).
    pub fn into_part(mut self, split: Split, first: u32) -> Self {
        self.split = split;
        self.first = first;
        self
    }

    /// Rays cast and samples dropped so far.
    pub fn tally(&self) -> Tally {
        self.tally
    }

    /// The AOVs gathered.
    pub fn aov_set(&self) -> AovSet {
        self.aovs.as_ref().map_or(AovSet::NONE, |(set, _)| *set)
    }

    /// The image's per-pixel sums ([`crate::fixed`]), row-major from the
    /// top-left.
    pub fn image_sums(&self) -> &[Fixed3] {
        &self.image
    }

    /// The AOVs' per-pixel records ([`Accumulator::aov_stride`] fixed-point
    /// values each), row-major; empty without AOVs.
    pub fn aov_sums(&self) -> &[i128] {
        self.aovs.as_ref().map_or(&[], |(_, s)| s)
    }

    /// Adds `other`'s sums, rays and dropped samples to these (parts of one
    /// render; [`crate::farm::merge`] checks that they are). Exact: the result
    /// does not depend on the order of the parts.
    pub(crate) fn add_sums(&mut self, other: &Accumulator) -> Result<(), String> {
        let overflow = || "its sums overflow those of the other parts".to_string();
        for (a, b) in self.image.iter_mut().zip(&other.image) {
            for c in 0..3 {
                a[c] = a[c].checked_add(b[c]).ok_or_else(overflow)?;
            }
        }
        if let (Some((_, a)), Some((_, b))) = (&mut self.aovs, &other.aovs) {
            for (a, b) in a.iter_mut().zip(b) {
                *a = a.checked_add(*b).ok_or_else(overflow)?;
            }
        }
        self.tally = Tally {
            rays: self.tally.rays.saturating_add(other.tally.rays),
            dropped: self.tally.dropped.saturating_add(other.tally.dropped),
        };
        Ok(())
    }

    /// Sets the samples these sums hold (after [`Accumulator::add_sums`]).
    pub(crate) fn set_samples(&mut self, split: Split, first: u32, spp: u32) {
        (self.split, self.first, self.spp) = (split, first, spp);
    }

    /// Adds samples `spp..spp + n` of every pixel (see [`accumulate`](super::accumulate) for what a
    /// sample is) and returns what they cost. `progress` as for [`render`](super::render).
    pub fn add(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        integrator: Integrator,
        seed: u64,
        n: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Tally {
        self.add_active(scene, camera, integrator, seed, n, None, progress)
    }

    /// [`Accumulator::add`] of the pixels `active` marks (row-major, the
    /// whole image) only, if given: the others keep their sums. Each pixel's
    /// samples are then counted in the [`Aov::Samples`] AOV, which these sums
    /// must gather (adaptive sampling, `render::adaptive`).
    #[allow(clippy::too_many_arguments)]
    pub fn add_active(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        integrator: Integrator,
        seed: u64,
        n: u32,
        active: Option<&[bool]>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Tally {
        assert_eq!((self.width, self.height), (camera.width, camera.height));
        if let Some(active) = active {
            assert_eq!(active.len(), self.image.len());
            assert!(
                self.aov_set().contains(Aov::Samples),
                "an adaptive render counts its samples"
            );
        }
        let start = self.first + self.spp;
        let samples = start..start.saturating_add(n);
        let k = samples.len() as u64;
        let aovs = self
            .aovs
            .as_mut()
            .map(|(set, sums)| (Layout::new(*set), &mut sums[..]));
        let tally = accumulate_into(
            scene,
            camera,
            integrator,
            seed,
            samples.clone(),
            Target::Wide {
                image: &mut self.image,
                aovs,
                split: self.split,
                active,
            },
            &|rows| progress(rows * k),
        );
        self.spp = samples.end - self.first;
        self.tally = self.tally + tally;
        tally
    }

    /// The image and AOVs averaged over the samples taken. The sums are rounded
    /// to f32 and then averaged, as a render in one call always did, so that
    /// renders keep their values bit for bit.
    pub fn rendered(&self) -> Rendered {
        let film = self.film();
        let aovs = self.aovs.as_ref().map(|(set, wide)| {
            let mut sums = AovSums::new(*set, self.width, self.height);
            sums.sums
                .par_iter_mut()
                .zip(wide.par_iter())
                .for_each(|(s, w)| *s = 0.0 + fixed::to_f64(*w) as f32);
            if let Some(at) = Layout::new(*set).offset(Aov::Variance) {
                // The estimate from the exact sums, in f64 (Σ L² − (Σ L)²/n
                // cancels where a pixel's noise is small), kept in the record.
                let stride = Layout::new(*set).stride;
                let counted = Layout::new(*set).offset(Aov::Samples);
                sums.sums
                    .par_chunks_mut(stride)
                    .zip(wide.par_chunks(stride))
                    .zip(self.image.par_iter())
                    .for_each(|((record, exact), image)| {
                        let spp = counted.map_or(self.spp, |c| count(exact[c]));
                        let n = f64::from(spp);
                        record[at] = if spp < 2 {
                            f32::INFINITY
                        } else {
                            let sum = image.map(fixed::to_f64);
                            let l = 0.2126 * sum[0] + 0.7152 * sum[1] + 0.0722 * sum[2];
                            let squares = fixed::to_f64(exact[at]);
                            ((squares - l * l / n).max(0.0) / (n * (n - 1.0))) as f32
                        };
                    });
            }
            sums.average_of(self.first, self.spp)
        });
        Rendered {
            film,
            rays: self.tally.rays,
            dropped: self.tally.dropped,
            aovs,
        }
    }
}

impl Accumulator {
    /// The image averaged over the samples taken, as [`Accumulator::rendered`]
    /// gives it (without the AOVs).
    pub fn film(&self) -> Film {
        let mut film = Film::new(self.width, self.height);
        film.pixels
            .par_iter_mut()
            .zip(self.image.par_iter())
            // `0 + x`, not `x`: what adding the sum to a zeroed f32 film gave.
            .for_each(|(p, w)| {
                *p = Vec3A::ZERO + Vec3A::from_array(w.map(|c| fixed::to_f64(c) as f32))
            });
        match self.sample_counts() {
            // Each pixel over its own samples, as `Film::average` divides.
            Some(counts) if counts.iter().any(|&c| c != self.spp) => {
                film.pixels
                    .par_iter_mut()
                    .zip(counts.par_iter())
                    .for_each(|(p, &c)| *p *= 1.0 / c.max(1) as f32);
                film.clamp_to_finite();
            }
            _ => film.average(self.spp),
        }
        film
    }

    /// Each pixel's number of samples, if the sums count them
    /// ([`Aov::Samples`]: adaptive sampling), row-major.
    pub fn sample_counts(&self) -> Option<Vec<u32>> {
        let (set, sums) = self.aovs.as_ref()?;
        let layout = Layout::new(*set);
        let at = layout.offset(Aov::Samples)?;
        Some(
            sums.par_chunks(layout.stride)
                .map(|record| count(record[at]))
                .collect(),
        )
    }

    /// The mean number of samples the pixels of the sums' rows took: their
    /// [`Accumulator::spp`] but for an adaptive render.
    pub fn mean_spp(&self) -> f64 {
        let Some(counts) = self.sample_counts() else {
            return f64::from(self.spp);
        };
        let width = self.width.max(1) as usize;
        let (mut sum, mut pixels) = (0u64, 0u64);
        for (row, counts) in counts.chunks(width).enumerate() {
            if self.split.has_tile((row / super::split::TILE_ROWS) as u32) {
                sum += counts.iter().map(|&c| u64::from(c)).sum::<u64>();
                pixels += counts.len() as u64;
            }
        }
        sum as f64 / pixels.max(1) as f64
    }
}

/// A count kept as a fixed-point sum of ones.
fn count(sum: i128) -> u32 {
    (sum >> fixed::FRACTION_BITS).clamp(0, i128::from(u32::MAX)) as u32
}

/// `len` zeros, written rather than lazily zeroed (see [`AovSums::new`]).
#[allow(clippy::slow_vector_initialization)]
fn zeroed(len: usize) -> Vec<i128> {
    let mut v = Vec::with_capacity(len);
    v.resize(len, 0);
    v
}
