//! Rendering an image: tiles of rows on rayon, samples keyed by (seed, pixel,
//! sample) so the result is bit-identical for any number of threads.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3A};
use rayon::prelude::*;
use thiserror::Error;

use crate::aov::{Aov, AovImage, AovSet, AovSums, FirstHit, Layout};
use crate::camera::Camera;
use crate::film::Film;
use crate::fixed::{self, Fixed3};
use crate::geometry::ray::{Hit, Ray};
use crate::integrators::Integrator;
#[cfg(target_arch = "x86_64")]
use crate::integrators::direct;
use crate::integrators::path::{self, PathOptions, PathSampler, SamplerKind};
use crate::materials::Material;
#[cfg(target_arch = "x86_64")]
use crate::sampling::sampler::pixel_jitter8;
use crate::sampling::sampler::{Rng, pixel_jitter};
use crate::scene::{Scene, SurfaceHit};
#[cfg(target_arch = "x86_64")]
use crate::simd::F8;

/// Rows per tile: small enough to balance two cores on small images, large enough
/// that scheduling costs nothing; even, so that tiles hold whole pixel quads.
pub const TILE_ROWS: usize = 4;

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Light transport algorithm.
    pub integrator: Integrator,
    /// Samples per pixel (at least 1).
    pub spp: u32,
    /// Seed of the sample positions.
    pub seed: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            integrator: Integrator::Direct,
            spp: 1,
            seed: 0,
        }
    }
}

/// A rendered image and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Pixel values (box-filtered averages).
    pub film: Film,
    /// Rays cast (camera and shadow rays).
    pub rays: u64,
    /// Samples that came out NaN or infinite and were dropped (counted as black).
    pub dropped: u64,
    /// The AOVs asked for ([`render_with_aovs`]), averaged over the same samples;
    /// `None` when none were.
    pub aovs: Option<AovImage>,
}

/// What a call of [`accumulate`] cost and found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Rays cast (closest-hit and shadow rays).
    pub rays: u64,
    /// Samples that came out NaN or infinite: counted here and left out of the
    /// sums (so they count as black).
    pub dropped: u64,
}

impl std::ops::Add for Tally {
    type Output = Tally;
    fn add(self, o: Tally) -> Tally {
        Tally {
            rays: self.rays + o.rays,
            dropped: self.dropped + o.dropped,
        }
    }
}

impl std::iter::Sum for Tally {
    fn sum<I: Iterator<Item = Tally>>(iter: I) -> Tally {
        iter.fold(Tally::default(), |a, b| a + b)
    }
}

/// Renders `settings.spp` samples per pixel and averages them. `progress` is
/// called after each tile with the rows it finished times the samples it took
/// of them (the render is done at `height × spp`), from any thread.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Rendered {
    render_with_aovs(scene, camera, settings, AovSet::NONE, progress)
}

/// [`render`] that also gathers `aovs` from the camera rays' first hits (see
/// [`crate::aov`]); the image is the same as without them, bit for bit.
pub fn render_with_aovs(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    aovs: AovSet,
    progress: &(dyn Fn(u64) + Sync),
) -> Rendered {
    let mut acc = Accumulator::new(camera.width, camera.height, aovs);
    render_passes(
        scene,
        camera,
        settings,
        &mut acc,
        &Passes::default(),
        &mut |_, _| {},
        progress,
    );
    acc.rendered()
}

/// A render that took as many samples per pixel as fitted a time budget.
#[derive(Clone, Debug)]
pub struct Progressive {
    /// The image, its rays and dropped samples.
    pub rendered: Rendered,
    /// Samples per pixel taken.
    pub spp: u32,
}

/// Longest pass of a time-limited render: short enough to stop close to the
/// budget and to report progress.
const MAX_PASS: Duration = Duration::from_millis(250);

/// Longest pass of a render of a given number of samples: short enough that a
/// stop request (Ctrl-C) is answered within about half a second, long enough
/// that the pass's end (the last tiles on one core) costs under 1 %.
const MAX_SPP_PASS: Duration = Duration::from_millis(500);

/// Renders in passes of whole samples per pixel (sample `k` is the same as in a
/// render with `--spp` above `k`) until `budget` is spent or `max_spp` reached,
/// always at least one sample. A pass is only started when about half its
/// expected time still fits in the budget. `progress` is called with the time
/// spent so far after every tile.
pub fn render_for(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    budget: Duration,
    max_spp: u32,
    progress: &(dyn Fn(Duration) + Sync),
) -> Progressive {
    let settings = RenderSettings {
        integrator,
        spp: max_spp,
        seed,
    };
    render_for_with_aovs(scene, camera, &settings, AovSet::NONE, budget, progress)
}

/// [`render_for`] that also gathers `aovs` (see [`crate::aov`]) over the
/// samples taken; `settings.spp` is the most samples per pixel to take. The
/// image is the one [`render_with_aovs`] gives for the samples taken, bit for
/// bit.
pub fn render_for_with_aovs(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    aovs: AovSet,
    budget: Duration,
    progress: &(dyn Fn(Duration) + Sync),
) -> Progressive {
    let start = Instant::now();
    let mut acc = Accumulator::new(camera.width, camera.height, aovs);
    let passes = Passes {
        budget: Some(budget),
        ..Passes::default()
    };
    render_passes(
        scene,
        camera,
        settings,
        &mut acc,
        &passes,
        &mut |_, _| {},
        &|_| progress(start.elapsed()),
    );
    Progressive {
        rendered: acc.rendered(),
        spp: acc.spp(),
    }
}

/// Which rows of the image a render takes: the `index`-th of `count` parts,
/// made of the image's row tiles ([`TILE_ROWS`] rows each, from the top)
/// `index`, `index + count`, `index + 2·count`, ...: interleaved, so that every
/// part has rows from all over the image and costs about the same. The whole
/// image is part 0 of 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Split {
    /// Which part (from 0).
    pub index: u32,
    /// Parts in all (at least 1).
    pub count: u32,
}

impl Split {
    /// The whole image.
    pub const WHOLE: Split = Split { index: 0, count: 1 };

    /// Row tiles of an image `height` pixels high.
    pub fn row_tiles(height: u32) -> u32 {
        height.div_ceil(TILE_ROWS as u32)
    }

    /// Part `index` of `count` of an image `height` rows high, if every part
    /// gets at least one row tile.
    pub fn new(index: u32, count: u32, height: u32) -> Result<Split, String> {
        if count == 0 || index >= count {
            return Err(format!(
                "tile {index}/{count}: the tile number must be below the number of tiles"
            ));
        }
        let tiles = Self::row_tiles(height);
        if count > tiles {
            return Err(format!(
                "tile {index}/{count}: an image {height} pixels high has at most {tiles} tiles (one per {TILE_ROWS} rows)"
            ));
        }
        Ok(Split { index, count })
    }

    /// Whether row tile `tile` is in this part.
    pub fn has_tile(&self, tile: u32) -> bool {
        tile % self.count == self.index
    }

    /// Whether this is the whole image.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

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
    spp: u32,
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
    /// [`crate::farm`]). The sums of rows outside `split` stay zero.
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

    /// Adds samples `spp..spp + n` of every pixel (see [`accumulate`] for what a
    /// sample is) and returns what they cost. `progress` as for [`render`].
    pub fn add(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        integrator: Integrator,
        seed: u64,
        n: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Tally {
        assert_eq!((self.width, self.height), (camera.width, camera.height));
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
                let n = f64::from(self.spp);
                sums.sums
                    .par_chunks_mut(stride)
                    .zip(wide.par_chunks(stride))
                    .zip(self.image.par_iter())
                    .for_each(|((record, exact), image)| {
                        record[at] = if self.spp < 2 {
                            f32::INFINITY
                        } else {
                            let sum = image.map(fixed::to_f64);
                            let l = 0.2126 * sum[0] + 0.7152 * sum[1] + 0.0722 * sum[2];
                            let squares = fixed::to_f64(exact[at]);
                            ((squares - l * l / n).max(0.0) / (n * (n - 1.0))) as f32
                        };
                    });
            }
            sums.average(self.spp)
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
        film.average(self.spp);
        film
    }
}

/// `len` zeros, written rather than lazily zeroed (see [`AovSums::new`]).
#[allow(clippy::slow_vector_initialization)]
fn zeroed(len: usize) -> Vec<i128> {
    let mut v = Vec::with_capacity(len);
    v.resize(len, 0);
    v
}

/// How [`render_passes`] goes about its passes.
#[derive(Clone, Copy, Debug, Default)]
pub struct Passes<'a> {
    /// Stop when this much time is spent (counting `spent`), rather than
    /// only at `settings.spp`; at least one sample is always taken.
    pub budget: Option<Duration>,
    /// Time already spent on the accumulator (by an earlier, stopped run).
    pub spent: Duration,
    /// Checked between passes: when set, the render stops after the samples in
    /// flight, with whole samples of every pixel.
    pub stop: Option<&'a AtomicBool>,
}

/// How [`render_passes`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// Every sample asked for was taken.
    Complete,
    /// The time budget was spent.
    Budget,
    /// The stop flag was set.
    Stopped,
}

/// Adds samples to `acc` in passes of whole samples per pixel, each pass sized
/// to take about half a second (or a quarter under a budget) by the time
/// per sample so far, until `settings.spp` samples are taken, the budget is
/// spent or `passes.stop` is set (checked before every pass). After each pass
/// `after_pass` is given the sums and the time spent in all (with
/// `passes.spent`), e.g. to save them. `progress` as for [`render`]. The
/// sums, and so the image, do not depend on how the samples fell into passes.
pub fn render_passes(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    acc: &mut Accumulator,
    passes: &Passes<'_>,
    after_pass: &mut dyn FnMut(&Accumulator, Duration),
    progress: &(dyn Fn(u64) + Sync),
) -> Ended {
    let start = Instant::now();
    let max_spp = settings.spp.max(1);
    let longest = if passes.budget.is_some() {
        MAX_PASS
    } else {
        MAX_SPP_PASS
    };
    loop {
        if acc.spp >= max_spp {
            return Ended::Complete;
        }
        if passes.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Ended::Stopped;
        }
        let spent = passes.spent + start.elapsed();
        let n = if acc.spp == 0 {
            1
        } else {
            let per_sample = spent / acc.spp;
            let mut room = longest;
            if let Some(budget) = passes.budget {
                let remaining = budget.saturating_sub(spent);
                if remaining < per_sample / 2 {
                    return Ended::Budget;
                }
                room = room.min(remaining);
            }
            let fit = room.as_secs_f64() / per_sample.as_secs_f64().max(1e-9);
            (fit.round().min(u32::MAX as f64) as u32).clamp(1, max_spp - acc.spp)
        };
        acc.add(
            scene,
            camera,
            settings.integrator,
            settings.seed,
            n,
            progress,
        );
        after_pass(acc, passes.spent + start.elapsed());
    }
}

/// Adds samples `samples` of every pixel to `sums`, in sample order, and returns
/// the number of rays cast and of samples dropped. For `flat` and `direct`, sample
/// 0 goes through the pixel centre and the others are uniformly jittered over the
/// pixel; `path` jitters every sample (a box filter, the pixel-area average, as
/// Mitsuba's `box`), its random numbers keyed by (seed, pixel, sample,
/// dimension). A sample that is NaN or infinite is dropped and counted. The viewer
/// refines by calls for `0..1`, `1..2`, ...; one call for `0..n` gives the same
/// sums up to f32 rounding ([`Accumulator`] keeps them exact).
pub fn accumulate(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    sums: &mut Film,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    accumulate_into(
        scene,
        camera,
        integrator,
        seed,
        samples,
        Target::Narrow(sums),
        progress,
    )
}

/// Where [`accumulate_into`] adds its samples.
enum Target<'a> {
    /// An f32 film (the viewer's refinement): one sample is added to it
    /// straight, several are summed in f64 per tile first.
    Narrow(&'a mut Film),
    /// Exact sums kept across calls ([`Accumulator`]), with the AOVs' if
    /// any, of the row tiles of `split`.
    Wide {
        image: &'a mut [Fixed3],
        aovs: Option<(Layout, &'a mut [i128])>,
        split: Split,
    },
}

/// One tile's part of a [`Target`].
enum TileSums<'a> {
    Narrow(&'a mut [Vec3A]),
    Wide(&'a mut [Fixed3]),
}

/// [`accumulate`] into `target`, gathering the AOVs (if any) from the same
/// camera rays and their closest hits, which the render finds anyway: the
/// image does not change, and no ray is added.
fn accumulate_into(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    target: Target<'_>,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    let width = camera.width as usize;
    let tile_pixels = width * TILE_ROWS;
    // Each tile's slice of the sums and of the AOV sums (empty ones without
    // AOVs, so that the tiles still zip with them).
    let mut split = Split::WHOLE;
    let (tiles, layout, aov_tiles): (Vec<TileSums>, _, Vec<&mut [i128]>) = match target {
        Target::Narrow(film) => {
            assert_eq!((film.width, film.height), (camera.width, camera.height));
            let tiles: Vec<_> = film
                .pixels
                .chunks_mut(tile_pixels)
                .map(TileSums::Narrow)
                .collect();
            let empty = (0..tiles.len()).map(|_| &mut [][..]).collect();
            (tiles, None, empty)
        }
        Target::Wide {
            image,
            aovs,
            split: s,
        } => {
            split = s;
            assert_eq!(image.len(), width * camera.height as usize);
            let tiles: Vec<_> = image.chunks_mut(tile_pixels).map(TileSums::Wide).collect();
            match aovs {
                Some((layout, sums)) => {
                    let aov_tiles = sums.chunks_mut(tile_pixels * layout.stride).collect();
                    (tiles, Some(layout), aov_tiles)
                }
                None => {
                    let empty = (0..tiles.len()).map(|_| &mut [][..]).collect();
                    (tiles, None, empty)
                }
            }
        }
    };
    tiles
        .into_par_iter()
        .zip(aov_tiles)
        .enumerate()
        .filter(|(tile, _)| split.has_tile(*tile as u32))
        .map(|(tile, (sums, aov_rows))| {
            let y0 = tile * TILE_ROWS;
            let mut dropped = 0u64;
            // The AOVs are summed exactly, into the accumulator's sums.
            let mut gather =
                |i: usize, ray: &Ray, hit: Option<Hit>, shaded: Option<&FirstHit>, value: Vec3A| {
                    if let Some(layout) = &layout {
                        let record = &mut aov_rows[i * layout.stride..(i + 1) * layout.stride];
                        layout.gather(scene, camera, ray, hit, shaded, value, record);
                    }
                };
            let n_rows = match &sums {
                TileSums::Wide(w) => w.len(),
                TileSums::Narrow(r) => r.len(),
            } / width;
            let tile = Tile {
                scene,
                camera,
                integrator,
                seed,
                samples: samples.clone(),
                width,
                y0,
                n_rows,
            };
            // Each target with its own copy of the loop (no per-sample test of
            // which target it is).
            let rays = match sums {
                // Into the accumulator's exact sums.
                TileSums::Wide(exact) => {
                    let mut add = ExactSums {
                        sums: exact,
                        dropped: &mut dropped,
                    };
                    match &layout {
                        Some(layout) => tile.trace::<true>(Some(layout), &mut add, &mut gather),
                        None => tile.trace::<false>(None, &mut add, &mut gather),
                    }
                }
                // Into an f32 film: many samples are summed in f64 in one
                // buffer per tile first, so that even 2^20 of them lose nothing
                // to f32 rounding, while one sample goes straight into the
                // film, which keeps progressive refinement exact.
                TileSums::Narrow(rows) => {
                    let mut local = if samples.len() > 1 {
                        vec![DVec3::ZERO; rows.len()]
                    } else {
                        Vec::new()
                    };
                    let mut add = FilmSums {
                        rows,
                        local: &mut local,
                        dropped: &mut dropped,
                    };
                    let rays = tile.trace::<false>(None, &mut add, &mut gather);
                    let FilmSums { rows, local, .. } = add;
                    for (sum, w) in rows.iter_mut().zip(local.iter()) {
                        *sum += w.as_vec3a();
                    }
                    rays
                }
            };
            progress(n_rows as u64);
            Tally { rays, dropped }
        })
        .sum()
}

/// Where [`Tile::trace`] hands its samples: each with its pixel's index in the
/// tile, one at a time or the eight of a 4×2 block of the lab's integrators
/// at once. Non-finite samples are dropped and counted.
trait Sink {
    /// Adds sample value `v` to pixel `i`.
    fn add(&mut self, i: usize, v: Vec3A);
    /// Adds `v[k]` to pixel `i[k]`, as eight [`Sink::add`] calls would.
    fn add8(&mut self, i: [usize; 8], v: [Vec3A; 8]) {
        for (i, v) in i.into_iter().zip(v) {
            self.add(i, v);
        }
    }
    /// [`Sink::add8`] of values given channel by channel (`v[c][k]` is
    /// channel `c` of sample `k`).
    fn add8_channels(&mut self, i: [usize; 8], v: &[[f32; 8]; 3]) {
        let at = |k: usize| Vec3A::new(v[0][k], v[1][k], v[2][k]);
        self.add8(i, [at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7)]);
    }
}

/// A tile's exact sums (see [`Accumulator`]).
struct ExactSums<'a> {
    sums: &'a mut [Fixed3],
    dropped: &'a mut u64,
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
struct FilmSums<'a> {
    rows: &'a mut [Vec3A],
    local: &'a mut [DVec3],
    dropped: &'a mut u64,
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

/// One tile's share of a call of [`accumulate_into`]: its rows and the samples.
struct Tile<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    /// Image width in pixels.
    width: usize,
    /// First row.
    y0: usize,
    /// Rows.
    n_rows: usize,
}

impl Tile<'_> {
    /// Traces the tile's samples in sample order, handing each value to `add`
    /// (with the pixel's index in the tile) and, when `aovs` is given, each
    /// camera ray with its hit to `gather` (with the hit's shading where `path`
    /// found it); returns the rays cast. `AOVS` says whether `aovs` is given:
    /// the loop without AOVs is then compiled free of their code, which even
    /// as an untaken branch slowed the lab's cheap integrators by 5 %.
    fn trace<const AOVS: bool>(
        &self,
        aovs: Option<&Layout>,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A),
    ) -> u64 {
        if let Integrator::Path(options) = self.integrator {
            return self.trace_path::<AOVS>(options, aovs, add, gather);
        }
        // The lab's loop compiled twice, and with AVX2 where the CPU has it:
        // three-operand instructions and fewer register copies took 6 % off a
        // `direct` frame's instructions (the same values: no fused
        // multiply-adds are made, and the library calls are the same).
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2.
            return unsafe { self.trace_lab_avx2::<AOVS>(add, gather) };
        }
        self.trace_lab::<AOVS, false>(add, gather)
    }

    /// [`Tile::trace`] for `path`.
    fn trace_path<const AOVS: bool>(
        &self,
        options: PathOptions,
        aovs: Option<&Layout>,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A),
    ) -> u64 {
        // Eight paths shaded at once where the scene allows (fixed materials,
        // no textures): the same values, a fifth to a quarter less time on the
        // lab box, less on `cornell-area` (docs/performance.md).
        #[cfg(target_arch = "x86_64")]
        if !AOVS
            && options.sampler == SamplerKind::Sobol
            && std::arch::is_x86_feature_detected!("avx2")
            && self.scene.path_lanes_apply()
        {
            // SAFETY: the CPU has AVX2.
            return unsafe { self.trace_path_lanes(options, add) };
        }
        let (scene, camera, seed, samples) = (self.scene, self.camera, self.seed, &self.samples);
        let (width, y0, n_rows) = (self.width, self.y0, self.n_rows);
        let mut rays = 0u64;
        // One path from its camera ray's hit into pixel `i`, its AOVs
        // gathered from the first hit as the path shades it.
        // (It returns the value, which the caller adds: a block's eight in
        // one `add8`.)
        let mut path_sample = |i: usize, start: &mut PathStart, hit, rays: &mut u64| {
            let layout = match aovs {
                Some(layout) if AOVS => layout,
                // Without AOVs the path alone, observed by nothing.
                _ => return start.trace(scene, hit, &options, rays, &mut |_, _| {}),
            };
            // The path only copies what it shaded the hit with; the AOVs
            // are made of it afterwards, outside the path tracer's loop.
            let mut seen = None;
            let v = start.trace(scene, hit, &options, rays, &mut |s, b| {
                seen = Some((*s, *b))
            });
            let shaded = seen.map(|(s, b)| layout.first_hit(scene, &start.ray, &s, || b));
            gather(i, &start.ray, hit, shaded.as_ref(), v);
            v
        };
        for s in samples.clone() {
            // Camera rays of 4×2 pixel blocks traced together (eight AVX2
            // lanes), then each path on its own; the last columns as 2×2
            // quads, a last odd row or column alone.
            for qy in (0..n_rows).step_by(2) {
                let blocks_end = if qy + 1 < n_rows { width / 4 * 4 } else { 0 };
                for qx in (0..blocks_end).step_by(4) {
                    let block: [(usize, usize); 8] =
                        std::array::from_fn(|i| (qx + i % 4, qy + i / 4));
                    // (Written out: `block.map` here was left as a call, its
                    // eight samplers copied out of it, 0.4 % of the box's `path`.)
                    macro_rules! start {
                        ($i:expr) => {
                            PathStart::new(
                                camera,
                                &options,
                                seed,
                                (block[$i].0, y0 + block[$i].1),
                                s,
                            )
                        };
                    }
                    let mut starts = [
                        start!(0),
                        start!(1),
                        start!(2),
                        start!(3),
                        start!(4),
                        start!(5),
                        start!(6),
                        start!(7),
                    ];
                    let primary = starts.each_ref().map(|p| p.ray);
                    rays += 8;
                    let hits = scene.intersect8(&primary, f32::INFINITY);
                    let mut pixels = [0; 8];
                    let mut values = [Vec3A::ZERO; 8];
                    for (k, (((x, y), start), hit)) in
                        block.into_iter().zip(&mut starts).zip(hits).enumerate()
                    {
                        pixels[k] = y * width + x;
                        values[k] = path_sample(pixels[k], start, hit, &mut rays);
                    }
                    add.add8(pixels, values);
                }
                for qx in (blocks_end..width).step_by(2) {
                    if qy + 1 < n_rows && qx + 1 < width {
                        let quad = [(qx, qy), (qx + 1, qy), (qx, qy + 1), (qx + 1, qy + 1)];
                        let mut starts = quad
                            .map(|(x, y)| PathStart::new(camera, &options, seed, (x, y0 + y), s));
                        let primary = starts.each_ref().map(|p| p.ray);
                        rays += 4;
                        let hits = scene.intersect4(&primary, f32::INFINITY);
                        for (((x, y), start), hit) in quad.into_iter().zip(&mut starts).zip(hits) {
                            let v = path_sample(y * width + x, start, hit, &mut rays);
                            add.add(y * width + x, v);
                        }
                    } else {
                        for y in qy..(qy + 2).min(n_rows) {
                            for x in qx..(qx + 2).min(width) {
                                let mut start =
                                    PathStart::new(camera, &options, seed, (x, y0 + y), s);
                                rays += 1;
                                let hit = scene.intersect(&start.ray, f32::INFINITY);
                                let v = path_sample(y * width + x, &mut start, hit, &mut rays);
                                add.add(y * width + x, v);
                            }
                        }
                    }
                }
            }
        }
        rays
    }

    /// [`Tile::trace_path`] with eight paths in AVX2 lanes ([`path::lanes`]): the
    /// tile's samples in sample order, each lane taking the next when its path
    /// ends. Only for scenes where [`Scene::path_lanes_apply`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn trace_path_lanes(&self, options: PathOptions, add: &mut impl Sink) -> u64 {
        let (scene, camera, seed) = (self.scene, self.camera, self.seed);
        let (width, y0, n_rows) = (self.width, self.y0, self.n_rows);
        let mut rays = 0u64;
        // The camera rays of eight pixels of a row are traced as one packet
        // (the last pixels of a row one by one), then handed out in turn.
        let mut samples = self.samples.clone();
        let mut sample = if width > 0 && n_rows > 0 {
            samples.next()
        } else {
            None
        };
        let (mut x, mut y) = (0, 0);
        let mut ready: [Option<path::lanes::Start>; 8] = [const { None }; 8];
        let (mut taken, mut made) = (0, 0);
        let mut next = || {
            if taken == made {
                let s = sample?;
                let n = (width - x).min(8);
                let mut primary = [Ray::new(Vec3A::ZERO, Vec3A::Z); 8];
                for (k, (slot, ray)) in ready.iter_mut().zip(&mut primary).take(n).enumerate() {
                    let px = x + k;
                    let start = PathStart::new(camera, &options, seed, (px, y0 + y), s);
                    let AnySampler::Sobol(sampler) = start.sampler else {
                        unreachable!("the lanes take Sobol' samples only");
                    };
                    *ray = start.ray;
                    *slot = Some(path::lanes::Start {
                        tag: y * width + px,
                        sampler,
                        ray: start.ray,
                        hit: None,
                    });
                }
                if n == 8 {
                    let hits = scene.intersect8(&primary, f32::INFINITY);
                    for (slot, hit) in ready.iter_mut().zip(hits) {
                        if let Some(start) = slot {
                            start.hit = hit;
                        }
                    }
                } else {
                    for (slot, ray) in ready.iter_mut().zip(&primary).take(n) {
                        if let Some(start) = slot {
                            start.hit = scene.intersect(ray, f32::INFINITY);
                        }
                    }
                }
                rays += n as u64;
                (taken, made) = (0, n);
                x += n;
                if x == width {
                    x = 0;
                    y += 1;
                    if y == n_rows {
                        y = 0;
                        sample = samples.next();
                    }
                }
            }
            taken += 1;
            ready[taken - 1].take()
        };
        let traced = path::lanes::trace(scene, options.max_depth, &mut next, &mut |i, v| {
            add.add(i, v)
        });
        rays + traced
    }

    /// [`Tile::trace_lab`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn trace_lab_avx2<const AOVS: bool>(
        &self,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A),
    ) -> u64 {
        self.trace_lab::<AOVS, true>(add, gather)
    }

    /// [`Tile::trace`] for the lab's integrators (`flat`, `direct`); with
    /// `LANES` (only in [`Tile::trace_lab_avx2`]) its 4×2 blocks are shaded in
    /// AVX2 lanes from the camera rays to the values (`integrators::direct::lanes`)
    /// where the scene allows it.
    #[inline(always)]
    fn trace_lab<const AOVS: bool, const LANES: bool>(
        &self,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A),
    ) -> u64 {
        let &Tile {
            scene,
            camera,
            integrator,
            seed,
            ref samples,
            width,
            y0,
            n_rows,
        } = self;
        let mut rays = 0u64;
        // Whether the blocks are shaded in lanes (checked once a tile; pixel
        // coordinates below 2²⁴, which `block_points` counts on being exact
        // in f32).
        #[cfg(target_arch = "x86_64")]
        let lanes =
            LANES && !AOVS && width < 1 << 24 && y0 + n_rows < 1 << 24 && scene.lab_lanes_apply();
        for s in samples.clone() {
            // 4×2 pixel blocks traced together (eight AVX2 lanes), then the last
            // columns as 2×2 quads; a last odd row or column alone.
            for qy in (0..n_rows).step_by(2) {
                let blocks_end = if qy + 1 < n_rows { width / 4 * 4 } else { 0 };
                for qx in (0..blocks_end).step_by(4) {
                    // (Written out: `array::from_fn` here was left as a call
                    // in the AVX2 copy of this loop.)
                    let block: [(usize, usize); 8] = [
                        (qx, qy),
                        (qx + 1, qy),
                        (qx + 2, qy),
                        (qx + 3, qy),
                        (qx, qy + 1),
                        (qx + 1, qy + 1),
                        (qx + 2, qy + 1),
                        (qx + 3, qy + 1),
                    ];
                    // (Written out: `block.map` here was left as a call.)
                    let (top, below) = (qy * width + qx, (qy + 1) * width + qx);
                    let pixels = [
                        top,
                        top + 1,
                        top + 2,
                        top + 3,
                        below,
                        below + 1,
                        below + 2,
                        below + 3,
                    ];
                    // The image points, their jitter in lanes where the block is.
                    #[cfg(target_arch = "x86_64")]
                    let (px, py) = if lanes {
                        // SAFETY: `lanes` is only set in `trace_lab_avx2`
                        // (`LANES`), called only when the CPU has AVX2.
                        unsafe { block_points(seed, s, (qx, y0 + qy), width) }
                    } else {
                        block_points_one_by_one(seed, s, &block, y0, width)
                    };
                    #[cfg(not(target_arch = "x86_64"))]
                    let (px, py) = block_points_one_by_one(seed, s, &block, y0, width);
                    #[cfg(target_arch = "x86_64")]
                    if lanes {
                        let direct = integrator == Integrator::Direct;
                        // SAFETY: as above.
                        let shaded =
                            unsafe { direct::lanes::radiance8(scene, camera, &px, &py, direct) };
                        if let Some((values, shadow_rays)) = shaded {
                            rays += 8 + u64::from(shadow_rays);
                            add.add8_channels(pixels, &values);
                            continue;
                        }
                    }
                    let top_rays =
                        camera.rays4([px[0], px[1], px[2], px[3]], [py[0], py[1], py[2], py[3]]);
                    let bottom_rays =
                        camera.rays4([px[4], px[5], px[6], px[7]], [py[4], py[5], py[6], py[7]]);
                    let (t, b) = (top_rays, bottom_rays);
                    let primary: [Ray; 8] = [t[0], t[1], t[2], t[3], b[0], b[1], b[2], b[3]];
                    rays += 8;
                    let hits = scene.intersect8(&primary, f32::INFINITY);
                    let values = integrator.radiance8_from(scene, &primary, hits, &mut rays);
                    if AOVS {
                        for (k, ((x, y), ray)) in block.into_iter().zip(&primary).enumerate() {
                            gather(y * width + x, ray, hits[k], None, values[k]);
                        }
                    }
                    add.add8(pixels, values);
                }
                for qx in (blocks_end..width).step_by(2) {
                    if qy + 1 < n_rows && qx + 1 < width {
                        let quad = [(qx, qy), (qx + 1, qy), (qx, qy + 1), (qx + 1, qy + 1)];
                        // Four plain calls, not `quad.map`: the compiler did not
                        // always inline the closure through it (3 % of `flat`).
                        let ray =
                            |(x, y): (usize, usize)| pixel_ray(camera, seed, s, x, y0 + y, width);
                        let primary = [ray(quad[0]), ray(quad[1]), ray(quad[2]), ray(quad[3])];
                        let values = if !AOVS {
                            integrator.radiance4(scene, &primary, &mut rays)
                        } else {
                            rays += 4;
                            let hits = scene.intersect4(&primary, f32::INFINITY);
                            let values =
                                integrator.radiance4_from(scene, &primary, hits, &mut rays);
                            for (k, ((x, y), ray)) in quad.into_iter().zip(&primary).enumerate() {
                                gather(y * width + x, ray, hits[k], None, values[k]);
                            }
                            values
                        };
                        for ((x, y), v) in quad.into_iter().zip(values) {
                            add.add(y * width + x, v);
                        }
                    } else {
                        for y in qy..(qy + 2).min(n_rows) {
                            for x in qx..(qx + 2).min(width) {
                                let ray = pixel_ray(camera, seed, s, x, y0 + y, width);
                                let v = if !AOVS {
                                    integrator.radiance(scene, &ray, &mut rays)
                                } else {
                                    rays += 1;
                                    let hit = scene.intersect(&ray, f32::INFINITY);
                                    let v = integrator.radiance_from(scene, &ray, hit, &mut rays);
                                    gather(y * width + x, &ray, hit, None, v);
                                    v
                                };
                                add.add(y * width + x, v);
                            }
                        }
                    }
                }
            }
        }
        rays
    }
}

/// The sampler of one `path` sample.
enum AnySampler {
    Sobol(path::SobolSampler),
    Independent(Rng),
}

/// One sample of the `path` integrator for pixel number `pixel`: its sampler and
/// its camera ray, through a uniformly chosen point of the pixel.
struct PathStart {
    sampler: AnySampler,
    ray: Ray,
}

impl PathStart {
    /// (Inlined: as a call it copied the sampler's sixteen pairs out again,
    /// 0.7 % of the box's `path`.)
    #[inline(always)]
    fn new(
        camera: &Camera,
        options: &PathOptions,
        seed: u64,
        (x, y): (usize, usize),
        s: u32,
    ) -> Self {
        // (The pixel's column and row given, not divided out of its index: a
        // 64-bit division per sample.)
        let pixel = (y * camera.width as usize + x) as u64;
        let (x, y) = (x as f32, y as f32);
        let mut sampler = match options.sampler {
            SamplerKind::Sobol => AnySampler::Sobol(path::SobolSampler::new(pixel, s, seed)),
            SamplerKind::Independent => AnySampler::Independent(Rng::for_sample(seed, pixel, s)),
        };
        let d = match &mut sampler {
            AnySampler::Sobol(smp) => smp.next_2d(),
            AnySampler::Independent(rng) => rng.next_2d(),
        };
        let ray = camera.ray(x + d.x, y + d.y);
        Self { sampler, ray }
    }

    /// The path's radiance given the camera ray's closest hit; `observe` sees
    /// the first hit's shading (see [`path::radiance_observed`]).
    #[inline]
    fn trace(
        &mut self,
        scene: &Scene,
        hit: Option<Hit>,
        options: &PathOptions,
        rays: &mut u64,
        observe: &mut impl FnMut(&SurfaceHit, &Material),
    ) -> Vec3A {
        let ray = &self.ray;
        match &mut self.sampler {
            AnySampler::Sobol(smp) => {
                path::radiance_observed(scene, ray, hit, options, smp, rays, observe)
            }
            AnySampler::Independent(rng) => {
                path::radiance_observed(scene, ray, hit, options, rng, rays, observe)
            }
        }
    }
}

/// The camera ray of sample `s` of pixel `(x, y)`: through the centre for sample
/// 0, uniformly jittered by the (seed, pixel, sample) generator otherwise.
#[inline]
fn pixel_ray(camera: &Camera, seed: u64, s: u32, x: usize, y: usize, width: usize) -> Ray {
    let (px, py) = pixel_point(seed, s, x, y, width);
    camera.ray(px, py)
}

/// [`pixel_point`] of the 4×2 block of pixels from `(x, y)`, its jitter in
/// AVX2 lanes (`pixel_jitter8`), bit for bit.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn block_points(seed: u64, s: u32, (x, y): (usize, usize), width: usize) -> ([f32; 8], [f32; 8]) {
    // Pixel coordinates below 2²⁴ are exact in f32, and so are their sums
    // with 1, 2 and 3.
    let column = F8::splat(x as f32) + F8::from_array([0.0, 1.0, 2.0, 3.0, 0.0, 1.0, 2.0, 3.0]);
    let row = F8::splat(y as f32) + F8::from_array([0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
    let (dx, dy) = if s == 0 {
        (F8::splat(0.5), F8::splat(0.5))
    } else {
        let first = (y * width + x) as u64;
        pixel_jitter8(seed, [first, first + width as u64], s)
    };
    ((column + dx).to_array(), (row + dy).to_array())
}

/// [`pixel_point`] of the pixels of `block` (rows from `y0`), one by one.
#[inline(always)]
fn block_points_one_by_one(
    seed: u64,
    s: u32,
    block: &[(usize, usize); 8],
    y0: usize,
    width: usize,
) -> ([f32; 8], [f32; 8]) {
    let (mut px, mut py) = ([0.0; 8], [0.0; 8]);
    for (i, &(x, y)) in block.iter().enumerate() {
        (px[i], py[i]) = pixel_point(seed, s, x, y0 + y, width);
    }
    (px, py)
}

/// The image point of [`pixel_ray`].
#[inline]
fn pixel_point(seed: u64, s: u32, x: usize, y: usize, width: usize) -> (f32, f32) {
    let (dx, dy) = if s == 0 {
        (0.5, 0.5)
    } else {
        pixel_jitter(seed, (y * width + x) as u64, s)
    };
    (x as f32 + dx, y as f32 + dy)
}

/// The value of one pixel sample, for tests and tools that probe single pixels.
pub fn sample_pixel(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    x: u32,
    y: u32,
) -> Vec3A {
    let mut rays = 0;
    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
    integrator.radiance(scene, &ray, &mut rays)
}

/// Sample `s` of pixel `(x, y)` exactly as a render with `seed` computes it (the
/// same camera ray, random numbers and hit), its path shown to `tracer`
/// (`path` only; `flat` and `direct` have no path). For `--nan-check` and for
/// reproducing one sample of an image.
#[allow(clippy::too_many_arguments)]
pub fn probe_sample(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    x: u32,
    y: u32,
    s: u32,
    tracer: &mut impl path::PathTracer,
) -> Vec3A {
    let mut rays = 0;
    let width = camera.width as usize;
    match integrator {
        Integrator::Path(options) => {
            let start = PathStart::new(camera, &options, seed, (x as usize, y as usize), s);
            let hit = scene.intersect(&start.ray, f32::INFINITY);
            let ray = start.ray;
            let mut observe = |_: &SurfaceHit, _: &Material| {};
            match start.sampler {
                AnySampler::Sobol(mut smp) => path::radiance_traced(
                    scene,
                    &ray,
                    hit,
                    &options,
                    &mut smp,
                    &mut rays,
                    &mut observe,
                    tracer,
                ),
                AnySampler::Independent(mut rng) => path::radiance_traced(
                    scene,
                    &ray,
                    hit,
                    &options,
                    &mut rng,
                    &mut rays,
                    &mut observe,
                    tracer,
                ),
            }
        }
        _ => {
            let ray = pixel_ray(camera, seed, s, x as usize, y as usize, width);
            integrator.radiance(scene, &ray, &mut rays)
        }
    }
}
