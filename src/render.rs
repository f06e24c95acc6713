//! Rendering an image: tiles of rows on rayon, samples keyed by (seed, pixel,
//! sample) so the result is bit-identical for any number of threads.

use std::ops::Range;
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::aov::{AovImage, AovSet, AovSums, FirstHit, Layout};
use crate::camera::Camera;
use crate::film::Film;
use crate::geometry::ray::{Hit, Ray};
use crate::integrators::Integrator;
use crate::integrators::path::{self, PathOptions, PathSampler, SamplerKind};
use crate::materials::Material;
use crate::sampling::sampler::Rng;
use crate::scene::{Scene, SurfaceHit};

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

/// Renders `settings.spp` samples per pixel and averages them. `progress` is called
/// with the number of rows finished after each tile, from any thread.
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
    let mut film = Film::new(camera.width, camera.height);
    let mut aov_sums = (!aovs.is_empty()).then(|| AovSums::new(aovs, camera.width, camera.height));
    let tally = accumulate_into(
        scene,
        camera,
        settings.integrator,
        settings.seed,
        0..settings.spp.max(1),
        Target {
            film: &mut film,
            aovs: aov_sums.as_mut(),
        },
        progress,
    );
    film.average(settings.spp);
    Rendered {
        film,
        rays: tally.rays,
        dropped: tally.dropped,
        aovs: aov_sums.map(|a| a.average(settings.spp)),
    }
}

/// A render that took as many samples per pixel as fitted a time budget.
#[derive(Clone, Debug)]
pub struct Progressive {
    /// The image, its rays and dropped samples.
    pub rendered: Rendered,
    /// Samples per pixel taken.
    pub spp: u32,
}

/// Longest pass of a progressive render: short enough to stop close to the
/// budget and to report progress.
const MAX_PASS: Duration = Duration::from_millis(250);

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
/// samples taken; `settings.spp` is the most samples per pixel to take.
pub fn render_for_with_aovs(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    aovs: AovSet,
    budget: Duration,
    progress: &(dyn Fn(Duration) + Sync),
) -> Progressive {
    let start = Instant::now();
    let mut film = Film::new(camera.width, camera.height);
    let mut aov_sums = (!aovs.is_empty()).then(|| AovSums::new(aovs, camera.width, camera.height));
    let mut tally = Tally::default();
    let mut spp = 0u32;
    let max_spp = settings.spp.max(1);
    while spp < max_spp {
        let elapsed = start.elapsed();
        let remaining = budget.saturating_sub(elapsed);
        let per_sample = if spp == 0 {
            Duration::ZERO
        } else {
            elapsed / spp
        };
        let n = if spp == 0 {
            1
        } else if remaining < per_sample / 2 {
            break;
        } else {
            let fit = remaining.min(MAX_PASS).as_secs_f64() / per_sample.as_secs_f64().max(1e-9);
            (fit.round() as u32).clamp(1, max_spp - spp)
        };
        tally = tally
            + accumulate_into(
                scene,
                camera,
                settings.integrator,
                settings.seed,
                spp..spp + n,
                Target {
                    film: &mut film,
                    aovs: aov_sums.as_mut(),
                },
                &|_| progress(start.elapsed()),
            );
        spp += n;
    }
    film.average(spp);
    Progressive {
        rendered: Rendered {
            film,
            rays: tally.rays,
            dropped: tally.dropped,
            aovs: aov_sums.map(|a| a.average(spp)),
        },
        spp,
    }
}

/// Adds samples `samples` of every pixel to `sums`, in sample order, and returns
/// the number of rays cast and of samples dropped. For `flat` and `direct`, sample
/// 0 goes through the pixel centre and the others are uniformly jittered over the
/// pixel; `path` jitters every sample (a box filter, the pixel-area average, as
/// Mitsuba's `box`), its random numbers keyed by (seed, pixel, sample,
/// dimension). A sample that is NaN or infinite is dropped and counted. The viewer
/// refines by calls for `0..1`, `1..2`, ...; one call for `0..n` gives the same
/// sums up to f32 rounding.
pub fn accumulate(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    sums: &mut Film,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    let target = Target {
        film: sums,
        aovs: None,
    };
    accumulate_into(scene, camera, integrator, seed, samples, target, progress)
}

/// Where [`accumulate_into`] adds its samples: the image's sums and, if asked
/// for, the AOVs'.
struct Target<'a> {
    film: &'a mut Film,
    aovs: Option<&'a mut AovSums>,
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
    let sums = target.film;
    assert_eq!((sums.width, sums.height), (camera.width, camera.height));
    let tile_pixels = width * TILE_ROWS;
    let tiles = sums.pixels.len().div_ceil(tile_pixels);
    // Each tile's slice of the AOV sums (empty ones without AOVs, so that the
    // tiles still zip with them).
    let (layout, aov_tiles): (_, Vec<&mut [f32]>) = match target.aovs {
        Some(a) => {
            assert_eq!((a.width, a.height), (camera.width, camera.height));
            let layout = a.layout();
            (
                Some(layout),
                a.sums.chunks_mut(tile_pixels * layout.stride).collect(),
            )
        }
        None => (None, (0..tiles).map(|_| &mut [][..]).collect()),
    };
    sums.pixels
        .par_chunks_mut(tile_pixels)
        .zip(aov_tiles)
        .enumerate()
        // Each worker reuses one buffer for the tiles' AOV sums: a fresh one per
        // tile would be fresh pages from the system, and faulting those in cost
        // more than gathering the AOVs.
        .map_init(Vec::new, |aov_wide, (tile, (rows, aov_rows))| {
            let y0 = tile * TILE_ROWS;
            let n_rows = rows.len() / width;
            let mut dropped = 0u64;
            // Many samples are summed in f64 (one buffer per tile), so that even
            // 2^20 of them lose nothing to f32 rounding; one sample goes straight
            // into `sums`, which keeps progressive refinement exact.
            let mut wide = if samples.len() > 1 {
                vec![DVec3::ZERO; rows.len()]
            } else {
                Vec::new()
            };
            let mut add = |i: usize, v: Vec3A| {
                if !v.is_finite() {
                    dropped += 1;
                    return;
                }
                match wide.get_mut(i) {
                    Some(w) => *w += v.as_dvec3(),
                    None => rows[i] += v,
                }
            };
            // The AOVs are summed in f64 too, for any number of samples (one
            // sample's f64 sum rounds back to the same f32).
            aov_wide.clear();
            aov_wide.resize(aov_rows.len(), 0.0);
            let mut gather = |i: usize, ray: &Ray, hit: Option<Hit>, shaded: Option<&FirstHit>| {
                if let Some(layout) = &layout {
                    let record = &mut aov_wide[i * layout.stride..(i + 1) * layout.stride];
                    layout.gather(scene, camera, ray, hit, shaded, record);
                }
            };
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
            let rays = match &layout {
                Some(layout) => tile.trace::<true>(Some(layout), &mut add, &mut gather),
                None => tile.trace::<false>(None, &mut add, &mut gather),
            };
            for (sum, w) in rows.iter_mut().zip(&wide) {
                *sum += w.as_vec3a();
            }
            for (sum, w) in aov_rows.iter_mut().zip(aov_wide.iter()) {
                *sum += *w as f32;
            }
            progress(n_rows as u64);
            Tally { rays, dropped }
        })
        .sum()
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
        add: &mut impl FnMut(usize, Vec3A),
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>),
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
        if let Integrator::Path(options) = integrator {
            // One path from its camera ray's hit into pixel `i`, its AOVs
            // gathered from the first hit as the path shades it.
            let mut path_sample = |i: usize, start: &mut PathStart, hit, rays: &mut u64| {
                let layout = match aovs {
                    Some(layout) if AOVS => layout,
                    // Without AOVs the path alone, observed by nothing.
                    _ => {
                        add(i, start.trace(scene, hit, &options, rays, &mut |_, _| {}));
                        return;
                    }
                };
                // The path only copies what it shaded the hit with; the AOVs
                // are made of it afterwards, outside the path tracer's loop.
                let mut seen = None;
                let v = start.trace(scene, hit, &options, rays, &mut |s, b| {
                    seen = Some((*s, *b))
                });
                let shaded = seen.map(|(s, b)| layout.first_hit(&start.ray, &s, || b));
                gather(i, &start.ray, hit, shaded.as_ref());
                add(i, v);
            };
            for s in samples.clone() {
                // Camera rays of 4×2 pixel blocks traced together (eight AVX2
                // lanes), then each path on its own; the last columns as 2×2
                // quads, a last odd row or column alone.
                for qy in (0..n_rows).step_by(2) {
                    let blocks_end = if qy + 1 < n_rows { width / 4 * 4 } else { 0 };
                    for qx in (0..blocks_end).step_by(4) {
                        let pixel = |x: usize, y: usize| ((y0 + y) * width + x) as u64;
                        let block: [(usize, usize); 8] =
                            std::array::from_fn(|i| (qx + i % 4, qy + i / 4));
                        let mut starts = block
                            .map(|(x, y)| PathStart::new(camera, &options, seed, pixel(x, y), s));
                        let primary = starts.each_ref().map(|p| p.ray);
                        rays += 8;
                        let hits = scene.intersect8(&primary, f32::INFINITY);
                        for (((x, y), start), hit) in block.into_iter().zip(&mut starts).zip(hits) {
                            path_sample(y * width + x, start, hit, &mut rays);
                        }
                    }
                    for qx in (blocks_end..width).step_by(2) {
                        let pixel = |x: usize, y: usize| ((y0 + y) * width + x) as u64;
                        if qy + 1 < n_rows && qx + 1 < width {
                            let quad = [(qx, qy), (qx + 1, qy), (qx, qy + 1), (qx + 1, qy + 1)];
                            let mut starts = quad.map(|(x, y)| {
                                PathStart::new(camera, &options, seed, pixel(x, y), s)
                            });
                            let primary = starts.each_ref().map(|p| p.ray);
                            rays += 4;
                            let hits = scene.intersect4(&primary, f32::INFINITY);
                            for (((x, y), start), hit) in
                                quad.into_iter().zip(&mut starts).zip(hits)
                            {
                                path_sample(y * width + x, start, hit, &mut rays);
                            }
                        } else {
                            for y in qy..(qy + 2).min(n_rows) {
                                for x in qx..(qx + 2).min(width) {
                                    let mut start =
                                        PathStart::new(camera, &options, seed, pixel(x, y), s);
                                    rays += 1;
                                    let hit = scene.intersect(&start.ray, f32::INFINITY);
                                    path_sample(y * width + x, &mut start, hit, &mut rays);
                                }
                            }
                        }
                    }
                }
            }
        }
        let lab_samples = if integrator.is_physical() {
            0..0
        } else {
            samples.clone()
        };
        for s in lab_samples {
            // 4×2 pixel blocks traced together (eight AVX2 lanes), then the last
            // columns as 2×2 quads; a last odd row or column alone.
            for qy in (0..n_rows).step_by(2) {
                let blocks_end = if qy + 1 < n_rows { width / 4 * 4 } else { 0 };
                for qx in (0..blocks_end).step_by(4) {
                    let block: [(usize, usize); 8] =
                        std::array::from_fn(|i| (qx + i % 4, qy + i / 4));
                    let ray = |(x, y): (usize, usize)| pixel_ray(camera, seed, s, x, y0 + y, width);
                    let primary: [Ray; 8] = std::array::from_fn(|i| ray(block[i]));
                    rays += 8;
                    let hits = scene.intersect8(&primary, f32::INFINITY);
                    if AOVS {
                        for (((x, y), ray), hit) in block.into_iter().zip(&primary).zip(hits) {
                            gather(y * width + x, ray, hit, None);
                        }
                    }
                    let values = integrator.radiance8_from(scene, &primary, hits, &mut rays);
                    for ((x, y), v) in block.into_iter().zip(values) {
                        add(y * width + x, v);
                    }
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
                            for (((x, y), ray), hit) in quad.into_iter().zip(&primary).zip(hits) {
                                gather(y * width + x, ray, hit, None);
                            }
                            integrator.radiance4_from(scene, &primary, hits, &mut rays)
                        };
                        for ((x, y), v) in quad.into_iter().zip(values) {
                            add(y * width + x, v);
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
                                    gather(y * width + x, &ray, hit, None);
                                    integrator.radiance_from(scene, &ray, hit, &mut rays)
                                };
                                add(y * width + x, v);
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
    #[inline]
    fn new(camera: &Camera, options: &PathOptions, seed: u64, pixel: u64, s: u32) -> Self {
        let (x, y) = (
            (pixel % camera.width as u64) as f32,
            (pixel / camera.width as u64) as f32,
        );
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
    let (dx, dy) = if s == 0 {
        (0.5, 0.5)
    } else {
        let mut rng = Rng::for_sample(seed, (y * width + x) as u64, s);
        (rng.next_f32(), rng.next_f32())
    };
    camera.ray(x as f32 + dx, y as f32 + dy)
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
