//! The tiles' loops: one tile's rows traced sample by sample, the camera
//! rays of 4×2 pixel blocks (then 2×2 quads, then single pixels) traced
//! together, and each value handed to a [`Sink`]: the accumulator's exact
//! sums or an f32 film.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec3, Vec2, Vec3A};
use rayon::prelude::*;

use super::light_image::LightImage;
use super::output::Tally;
use super::sinks::{ExactSums, FilmSums, Sink, SplatSums};
use super::split::{Split, TILE_ROWS};
use crate::aov::{Aov, FirstHit, Layout, in_half};
use crate::camera::Camera;
use crate::film::Film;
use crate::fixed::{self, Fixed3};
use crate::geometry::ray::{Hit, Ray};
use crate::integrators::Integrator;
use crate::integrators::bdpt;
#[cfg(target_arch = "x86_64")]
use crate::integrators::direct;
use crate::integrators::path::{self, PathOptions, PathSampler, SamplerKind};
use crate::materials::Material;
#[cfg(target_arch = "x86_64")]
use crate::sampling::sampler::pixel_jitter8;
use crate::sampling::sampler::{Rng, lens_jitter, pixel_jitter};
use crate::sampling::splat::SplatWeights;
use crate::scene::{Scene, SurfaceHit};
#[cfg(target_arch = "x86_64")]
use crate::simd::F8;

/// Where [`accumulate_into`] adds its samples.
pub(super) enum Target<'a> {
    /// An f32 film (the viewer's refinement): one sample is added to it
    /// straight, several are summed in f64 per tile first.
    Narrow(&'a mut Film),
    /// Exact sums kept across calls ([`super::Accumulator`]), with the AOVs' if
    /// any, of the row tiles of `split`; only of the pixels `active` marks if
    /// given (adaptive sampling).
    Wide {
        image: &'a mut [Fixed3],
        aovs: Option<(Layout, &'a mut [i128])>,
        split: Split,
        active: Option<&'a [bool]>,
    },
}

impl Target<'_> {
    /// The same target, borrowed again (for one call of several).
    fn reborrow(&mut self) -> Target<'_> {
        match self {
            Target::Narrow(film) => Target::Narrow(film),
            Target::Wide {
                image,
                aovs,
                split,
                active,
            } => Target::Wide {
                image,
                aovs: aovs.as_mut().map(|(layout, sums)| (*layout, &mut **sums)),
                split: *split,
                active: *active,
            },
        }
    }
}

/// One tile's part of a [`Target`].
enum TileSums<'a> {
    Narrow(&'a mut [Vec3A]),
    Wide(&'a mut [Fixed3]),
}

/// [`accumulate`] into `target`, gathering the AOVs (if any) from the same
/// camera rays and their closest hits, which the render finds anyway: the
/// image does not change, and no ray is added.
pub(super) fn accumulate_into(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    target: Target<'_>,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    // Vertex merging goes iteration by iteration: each sample's light
    // subpaths are traced (for every pixel) before its camera subpaths.
    let Integrator::Vcm(options) = integrator else {
        return accumulate_tiles(
            scene, camera, integrator, seed, samples, target, None, progress,
        );
    };
    let k = samples.len() as u64;
    let rows = AtomicU64::new(0);
    // `progress` counts rows times samples of the whole call.
    let each = |n: u64| {
        let before = rows.fetch_add(n, Ordering::Relaxed);
        let steps = (before + n) / k - before / k;
        if steps > 0 {
            progress(steps * k);
        }
    };
    let first = bdpt::first_radius(scene, camera, bdpt::DEFAULT_RADIUS_PIXELS);
    let mut paths = bdpt::LightPaths::default();
    let mut target = target;
    let mut tally = Tally::default();
    for s in samples {
        let mut rays = 0;
        let radius = bdpt::radius_at(first, s);
        paths.trace(scene, camera, &options, seed, s, radius, &mut rays);
        tally = tally
            + Tally { rays, dropped: 0 }
            + accumulate_tiles(
                scene,
                camera,
                integrator,
                seed,
                s..s + 1,
                target.reborrow(),
                Some(&paths),
                &each,
            );
    }
    tally
}

/// [`accumulate_into`] tile by tile, with `vcm`'s light subpaths of the
/// one sample if it merges.
#[allow(clippy::too_many_arguments)]
fn accumulate_tiles(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    target: Target<'_>,
    merging: Option<&bdpt::LightPaths>,
    progress: &(dyn Fn(u64) + Sync),
) -> Tally {
    let width = camera.width as usize;
    let tile_pixels = width * TILE_ROWS;
    // Splatting, where the render asks for it and keeps exact sums of all
    // pixels' samples alike (not the viewer's film; not adaptive sampling or
    // the variance AOV, whose per-pixel statistics are of the pixel's own
    // samples).
    let splat = match (&target, integrator) {
        (
            Target::Wide {
                aovs, active: None, ..
            },
            Integrator::Path(options),
        ) if !aovs.as_ref().is_some_and(|(layout, _)| {
            layout.offset(Aov::Variance).is_some() || layout.offset(Aov::Samples).is_some()
        }) =>
        {
            SplatWeights::new(
                options.filter,
                options.reconstruction,
                camera.width,
                camera.height,
            )
        }
        _ => None,
    };
    // Each tile's slice of the sums and of the AOV sums (empty ones without
    // AOVs, so that the tiles still zip with them).
    let mut split = Split::WHOLE;
    let mut active = None;
    let mut whole: Option<&mut [Fixed3]> = None;
    let mut whole_film: Option<&mut [Vec3A]> = None;
    // `bdpt`'s light subpaths seen by the camera land anywhere on the image.
    let light = integrator
        .is_bidirectional()
        .then(|| LightImage::new(camera.width, camera.height));
    // ... and those of the samples in each pixel's half ([`Aov::Half`]).
    let mut whole_aovs: Option<&mut [i128]> = None;
    let light_half = match (&light, &target) {
        (
            Some(_),
            Target::Wide {
                aovs: Some((layout, _)),
                ..
            },
        ) if layout.offset(Aov::Half).is_some() => {
            Some(LightImage::new(camera.width, camera.height))
        }
        _ => None,
    };
    let (tiles, layout, aov_tiles): (Vec<TileSums>, _, Vec<&mut [i128]>) = match target {
        Target::Narrow(film) => {
            assert_eq!((film.width, film.height), (camera.width, camera.height));
            let pixels = whole_film.insert(&mut film.pixels[..]);
            let tiles: Vec<_> = pixels
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
            active: a,
        } => {
            split = s;
            active = a;
            assert_eq!(image.len(), width * camera.height as usize);
            let image = whole.insert(image);
            let tiles: Vec<_> = image.chunks_mut(tile_pixels).map(TileSums::Wide).collect();
            match aovs {
                Some((layout, sums)) => {
                    let sums = whole_aovs.insert(sums);
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
    let done: Vec<(Tally, Option<Borders>)> = tiles
        .into_par_iter()
        .zip(aov_tiles)
        .enumerate()
        .filter(|(tile, _)| split.has_tile(*tile as u32))
        .map(|(tile, (sums, aov_rows))| {
            let y0 = tile * TILE_ROWS;
            let mut dropped = 0u64;
            let halves = layout.is_some_and(|l| l.offset(Aov::Half).is_some());
            // The AOVs are summed exactly, into the accumulator's sums.
            let mut gather = |i: usize,
                              ray: &Ray,
                              hit: Option<Hit>,
                              shaded: Option<&FirstHit>,
                              value: Vec3A,
                              sample: u32| {
                if let Some(layout) = &layout {
                    let record = &mut aov_rows[i * layout.stride..(i + 1) * layout.stride];
                    let half = halves && in_half(seed, (y0 * width + i) as u64, sample);
                    layout.gather(scene, camera, ray, hit, shaded, value, sample, half, record);
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
                active: active.map(|a| &a[y0 * width..(y0 + n_rows) * width]),
                splat: splat.is_some(),
                light: light.as_ref(),
                light_half: light_half.as_ref(),
                merging,
            };
            let mut borders = None;
            // Each target with its own copy of the loop (no per-sample test of
            // which target it is).
            let rays = match sums {
                // Splatted: into sums of the tile's rows and a border around
                // them; its own rows are added to the accumulator's here, the
                // borders (other tiles' rows) after all tiles are done.
                TileSums::Wide(exact) if splat.is_some() => {
                    let weights = splat.as_ref().expect("splatting");
                    let b = weights.border();
                    let mut local = vec![[0i128; 3]; (n_rows + 2 * b) * width];
                    let mut scratch = vec![Vec3A::ZERO; local.len()];
                    let mut add = SplatSums {
                        sums: &mut local,
                        scratch: &mut scratch,
                        weights,
                        width,
                        y0,
                        dropped: &mut dropped,
                    };
                    let rays = match &layout {
                        Some(layout) => tile.trace::<true>(Some(layout), &mut add, &mut gather),
                        None => tile.trace::<false>(None, &mut add, &mut gather),
                    };
                    let own = &local[b * width..(b + n_rows) * width];
                    for (sum, add) in exact.iter_mut().zip(own) {
                        for c in 0..3 {
                            sum[c] += add[c];
                        }
                    }
                    let mut edge = local[..b * width].to_vec();
                    edge.extend_from_slice(&local[(b + n_rows) * width..]);
                    borders = Some(Borders {
                        y0,
                        n_rows,
                        border: b,
                        sums: edge,
                    });
                    rays
                }
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
            (Tally { rays, dropped }, borders)
        })
        .collect();
    // The light splatted by `bdpt`, onto the whole image (exact sums: the
    // order does not matter; the viewer's film takes it rounded).
    if let Some(light) = light {
        let sums = light.into_sums();
        if let Some(image) = whole.as_deref_mut() {
            for (sum, add) in image.iter_mut().zip(&sums) {
                for c in 0..3 {
                    sum[c] += add[c];
                }
            }
        }
        if let Some(film) = whole_film {
            for (pixel, add) in film.iter_mut().zip(&sums) {
                *pixel += Vec3A::from_array(add.map(|v| fixed::to_f64(v) as f32));
            }
        }
    }
    if let (Some(half), Some(layout), Some(aovs)) = (light_half, &layout, whole_aovs) {
        let at = layout.offset(Aov::Half).expect("a half");
        for (record, add) in aovs.chunks_mut(layout.stride).zip(half.into_sums()) {
            for c in 0..3 {
                record[at + c] += add[c];
            }
        }
    }
    // The splatted tiles' borders, into the rows of the tiles around them
    // (exact sums: the order does not matter).
    if let Some(image) = whole {
        let height = camera.height as usize;
        for borders in done.iter().filter_map(|(_, b)| b.as_ref()) {
            let b = borders.border;
            let above = (0..b).map(|k| borders.y0 as isize - (b - k) as isize);
            let below = (0..b).map(|k| (borders.y0 + borders.n_rows + k) as isize);
            for (row, sums) in above.chain(below).zip(borders.sums.chunks(width)) {
                if row < 0 || row as usize >= height {
                    continue;
                }
                let at = row as usize * width;
                for (sum, add) in image[at..at + width].iter_mut().zip(sums) {
                    for c in 0..3 {
                        sum[c] += add[c];
                    }
                }
            }
        }
    }
    done.into_iter().map(|(tally, _)| tally).sum()
}

/// A splatted tile's sums of the rows around it: `border` rows above its
/// first, `y0`, then `border` below its `n_rows`, `width` sums each.
struct Borders {
    y0: usize,
    n_rows: usize,
    border: usize,
    sums: Vec<Fixed3>,
}

/// The one walk over a tile's pixels, for one sample: rows in pairs, each
/// pair as 4×2 blocks (`block(qx, qy)`: the block's top-left pixel), then its
/// last columns as 2×2 quads (`quad(quad)`: the four pixels, row by row); a
/// last odd row or column pixel by pixel (`pixel(x, y)`). Pixels are in the
/// tile's coordinates; `continue` in `block` goes on to the next block.
///
/// A macro, not a function taking closures: both loops that use it inline
/// their bodies into it, and the lab's copy is compiled with AVX2 inside
/// [`Tile::trace_lab_avx2`], which closures are not (see `crate::simd`); the
/// notes in the bodies measure what a call left in them costs.
macro_rules! for_each_block {
    (
        $width:ident, $n_rows:ident,
        block($qx:ident, $qy:ident) $block:block
        quad($quad:ident) $quad_body:block
        pixel($x:ident, $y:ident) $pixel:block
    ) => {
        for $qy in (0..$n_rows).step_by(2) {
            let blocks_end = if $qy + 1 < $n_rows { $width / 4 * 4 } else { 0 };
            for $qx in (0..blocks_end).step_by(4) $block
            for qx in (blocks_end..$width).step_by(2) {
                if $qy + 1 < $n_rows && qx + 1 < $width {
                    let $quad = [(qx, $qy), (qx + 1, $qy), (qx, $qy + 1), (qx + 1, $qy + 1)];
                    $quad_body
                } else {
                    for $y in $qy..($qy + 2).min($n_rows) {
                        for $x in qx..(qx + 2).min($width) $pixel
                    }
                }
            }
        }
    };
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
    /// The pixels (of the tile) that take samples, if not all.
    active: Option<&'a [bool]>,
    /// Whether the samples are splatted: `path`'s image points uniform in
    /// their pixels, handed over with [`Sink::add_at`].
    splat: bool,
    /// Where `bdpt` splats the light its light subpaths bring to the camera.
    light: Option<&'a LightImage>,
    /// Where it splats that of the samples in the target pixel's half
    /// ([`Aov::Half`]), when that AOV is gathered.
    light_half: Option<&'a LightImage>,
    /// `vcm`'s light subpaths of this iteration (the one sample).
    merging: Option<&'a bdpt::LightPaths>,
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
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A, u32),
    ) -> u64 {
        if let Integrator::Path(options) = self.integrator {
            return self.trace_path::<AOVS>(options, aovs, add, gather);
        }
        if let Integrator::Bdpt(options) | Integrator::Vcm(options) = self.integrator {
            return self.trace_bdpt::<AOVS>(options, aovs, add, gather);
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

    /// [`Tile::trace`] for `bdpt`: pixel by pixel, each sample's camera
    /// subpath from the pixel's camera ray (as `path`'s), its value into the
    /// pixel and its light subpath's splats onto the light image. The AOVs
    /// take the camera ray's first hit, traced for them.
    fn trace_bdpt<const AOVS: bool>(
        &self,
        options: PathOptions,
        aovs: Option<&Layout>,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A, u32),
    ) -> u64 {
        let (scene, camera, seed) = (self.scene, self.camera, self.seed);
        let light = self.light.expect("bdpt renders with a light image");
        let mut scratch = bdpt::Scratch::default();
        let mut rays = 0u64;
        let width = camera.width as usize;
        for s in self.samples.clone() {
            // A splat counts in the half of the pixel it lands on that
            // sample `s` of that pixel belongs to.
            let mut splat = |at: Vec2, v: Vec3A| {
                if light.add(at, v)
                    && let Some(half) = self.light_half
                {
                    let pixel = at.y as usize * width + at.x as usize;
                    if in_half(seed, pixel as u64, s) {
                        half.add(at, v);
                    }
                }
            };
            for y in 0..self.n_rows {
                for x in 0..self.width {
                    let mut start = PathStart::new(camera, &options, seed, (x, self.y0 + y), s);
                    let ray = start.ray;
                    let merging = self.merging.map(|p| (p, (self.y0 + y) * width + x));
                    let v = match &mut start.sampler {
                        AnySampler::Sobol(smp) => bdpt::sample(
                            scene,
                            camera,
                            &ray,
                            &options,
                            smp,
                            &mut scratch,
                            merging,
                            &mut rays,
                            &mut splat,
                        ),
                        AnySampler::Independent(rng) => bdpt::sample(
                            scene,
                            camera,
                            &ray,
                            &options,
                            rng,
                            &mut scratch,
                            merging,
                            &mut rays,
                            &mut splat,
                        ),
                    };
                    let i = y * self.width + x;
                    if let Some(layout) = aovs.filter(|_| AOVS) {
                        let hit = scene.intersect(&ray, f32::INFINITY);
                        let shaded = hit.map(|h| {
                            let surface = scene.surface(&h);
                            let material = &scene.materials()[surface.material as usize];
                            layout.first_hit(scene, &ray, &surface, s, || {
                                material.bsdf(&surface.attrs, scene.textures())
                            })
                        });
                        gather(i, &ray, hit, shaded.as_ref(), v, s);
                    }
                    add.add_at(i, start.offset, v);
                }
            }
            add.end_sample();
        }
        rays
    }

    /// [`Tile::trace`] for `path`.
    fn trace_path<const AOVS: bool>(
        &self,
        options: PathOptions,
        aovs: Option<&Layout>,
        add: &mut impl Sink,
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A, u32),
    ) -> u64 {
        // Eight paths shaded at once where the scene allows (fixed materials,
        // no textures): the same values, a fifth to a quarter less time on the
        // lab box, less on `cornell-area` (docs/performance.md).
        #[cfg(target_arch = "x86_64")]
        if !AOVS
            && !self.splat
            && self.active.is_none()
            && options.sampler == SamplerKind::Sobol
            && options.filter == crate::sampling::filter::PixelFilter::Box
            && options.hide_emitters == path::HideEmitters::No
            && !options.counts_direct()
            && std::arch::is_x86_feature_detected!("avx2")
            && self.scene.path_lanes_apply()
        {
            // SAFETY: the CPU has AVX2.
            return unsafe { self.trace_path_lanes(options, add) };
        }
        let (scene, camera, seed, samples) = (self.scene, self.camera, self.seed, &self.samples);
        let (width, y0, n_rows) = (self.width, self.y0, self.n_rows);
        // Splatted samples' image points are uniform in their pixels (the
        // box's), the filter weighing them where they are added.
        let mut options = options;
        if self.splat {
            options.filter = crate::sampling::filter::PixelFilter::Box;
        }
        let mut rays = 0u64;
        // One path from its camera ray's hit into pixel `i`, its AOVs
        // gathered from the first hit as the path shades it.
        // (It returns the value, which the caller adds: a block's eight in
        // one `add8`.)
        let mut path_sample =
            |i: usize, start: &mut PathStart, hit, sample: u32, rays: &mut u64| {
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
                let shaded =
                    seen.map(|(s, b)| layout.first_hit(scene, &start.ray, &s, sample, || b));
                gather(i, &start.ray, hit, shaded.as_ref(), v, sample);
                v
            };
        if let Some(active) = self.active {
            // Only the active pixels, eight camera rays at a time (the
            // samples' values do not depend on which pixels share a packet).
            let pixels = active_pixels(active, width);
            for s in samples.clone() {
                for chunk in pixels.chunks(8) {
                    if let &[a, b, c, d, e, f, g, h] = chunk {
                        let block = [a, b, c, d, e, f, g, h];
                        let mut starts = block
                            .map(|(x, y)| PathStart::new(camera, &options, seed, (x, y0 + y), s));
                        let primary = starts.each_ref().map(|p| p.ray);
                        rays += 8;
                        let hits = scene.intersect8(&primary, f32::INFINITY);
                        for (((x, y), start), hit) in block.into_iter().zip(&mut starts).zip(hits) {
                            let v = path_sample(y * width + x, start, hit, s, &mut rays);
                            add.add_at(y * width + x, start.offset, v);
                        }
                    } else {
                        for &(x, y) in chunk {
                            let mut start = PathStart::new(camera, &options, seed, (x, y0 + y), s);
                            rays += 1;
                            let hit = scene.intersect(&start.ray, f32::INFINITY);
                            let v = path_sample(y * width + x, &mut start, hit, s, &mut rays);
                            add.add_at(y * width + x, start.offset, v);
                        }
                    }
                }
                add.end_sample();
            }
            return rays;
        }
        for s in samples.clone() {
            // Camera rays of 4×2 pixel blocks traced together (eight AVX2
            // lanes), then each path on its own; the last columns as 2×2
            // quads, a last odd row or column alone.
            for_each_block!(width, n_rows,
                block(qx, qy) {
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
                        values[k] = path_sample(pixels[k], start, hit, s, &mut rays);
                    }
                    add.add8_at(pixels, starts.each_ref().map(|p| p.offset), values);
                }
                quad(quad) {
                    let mut starts = quad
                        .map(|(x, y)| PathStart::new(camera, &options, seed, (x, y0 + y), s));
                    let primary = starts.each_ref().map(|p| p.ray);
                    rays += 4;
                    let hits = scene.intersect4(&primary, f32::INFINITY);
                    for (((x, y), start), hit) in quad.into_iter().zip(&mut starts).zip(hits) {
                        let v = path_sample(y * width + x, start, hit, s, &mut rays);
                        add.add_at(y * width + x, start.offset, v);
                    }

                }
                pixel(x, y) {
                    let mut start = PathStart::new(camera, &options, seed, (x, y0 + y), s);
                    rays += 1;
                    let hit = scene.intersect(&start.ray, f32::INFINITY);
                    let v = path_sample(y * width + x, &mut start, hit, s, &mut rays);
                    add.add_at(y * width + x, start.offset, v);
                }
            );
            add.end_sample();
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
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A, u32),
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
        gather: &mut impl FnMut(usize, &Ray, Option<Hit>, Option<&FirstHit>, Vec3A, u32),
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
            active,
            splat: _,
            light: _,
            light_half: _,
            merging: _,
        } = self;
        let mut rays = 0u64;
        if let Some(active) = active {
            // Only the active pixels, one ray at a time (the lanes' values are
            // these bit for bit).
            let pixels = active_pixels(active, width);
            for s in samples.clone() {
                for &(x, y) in &pixels {
                    let ray = pixel_ray(camera, seed, s, x, y0 + y, width);
                    rays += 1;
                    let hit = scene.intersect(&ray, f32::INFINITY);
                    let v = integrator.radiance_from(scene, &ray, hit, &mut rays);
                    if AOVS {
                        gather(y * width + x, &ray, hit, None, v, s);
                    }
                    add.add(y * width + x, v);
                }
            }
            return rays;
        }
        // Whether the blocks are shaded in lanes (checked once a tile; pixel
        // coordinates below 2²⁴, which `block_points` counts on being exact
        // in f32; the lanes make pinhole rays only).
        #[cfg(target_arch = "x86_64")]
        let lanes = LANES
            && !AOVS
            && width < 1 << 24
            && y0 + n_rows < 1 << 24
            && camera.thin_lens.is_none()
            && scene.lab_lanes_apply();
        for s in samples.clone() {
            // 4×2 pixel blocks traced together (eight AVX2 lanes), then the last
            // columns as 2×2 quads; a last odd row or column alone.
            for_each_block!(width, n_rows,
                block(qx, qy) {
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
                    let primary: [Ray; 8] = if camera.thin_lens.is_none() {
                        let top_rays = camera
                            .rays4([px[0], px[1], px[2], px[3]], [py[0], py[1], py[2], py[3]]);
                        let bottom_rays = camera
                            .rays4([px[4], px[5], px[6], px[7]], [py[4], py[5], py[6], py[7]]);
                        let (t, b) = (top_rays, bottom_rays);
                        [t[0], t[1], t[2], t[3], b[0], b[1], b[2], b[3]]
                    } else {
                        lens_rays8(camera, seed, s, (y0 * width) as u64, &pixels, &px, &py)
                    };
                    rays += 8;
                    let hits = scene.intersect8(&primary, f32::INFINITY);
                    let values = integrator.radiance8_from(scene, &primary, hits, &mut rays);
                    if AOVS {
                        for (k, ((x, y), ray)) in block.into_iter().zip(&primary).enumerate() {
                            gather(y * width + x, ray, hits[k], None, values[k], s);
                        }
                    }
                    add.add8(pixels, values);
                }
                quad(quad) {
                    // Four plain calls, not `quad.map`: the compiler did not
                    // always inline the closure through it (3 % of `flat`).
                    let ray = |(x, y): (usize, usize)| pixel_ray(camera, seed, s, x, y0 + y, width);
                    let primary = [ray(quad[0]), ray(quad[1]), ray(quad[2]), ray(quad[3])];
                    let values = if !AOVS {
                        integrator.radiance4(scene, &primary, &mut rays)
                    } else {
                        rays += 4;
                        let hits = scene.intersect4(&primary, f32::INFINITY);
                        let values = integrator.radiance4_from(scene, &primary, hits, &mut rays);
                        for (k, ((x, y), ray)) in quad.into_iter().zip(&primary).enumerate() {
                            gather(y * width + x, ray, hits[k], None, values[k], s);
                        }
                        values
                    };
                    for ((x, y), v) in quad.into_iter().zip(values) {
                        add.add(y * width + x, v);
                    }

                }
                pixel(x, y) {
                    let ray = pixel_ray(camera, seed, s, x, y0 + y, width);
                    let v = if !AOVS {
                        integrator.radiance(scene, &ray, &mut rays)
                    } else {
                        rays += 1;
                        let hit = scene.intersect(&ray, f32::INFINITY);
                        let v = integrator.radiance_from(scene, &ray, hit, &mut rays);
                        gather(y * width + x, &ray, hit, None, v, s);
                        v
                    };
                    add.add(y * width + x, v);
                }
            );
        }
        rays
    }
}

/// The `(x, y)` (in the tile) of the pixels `active` marks, row by row.
fn active_pixels(active: &[bool], width: usize) -> Vec<(usize, usize)> {
    (active.iter().enumerate())
        .filter(|(_, a)| **a)
        .map(|(i, _)| (i % width, i / width))
        .collect()
}

/// The sampler of one `path` sample.
pub(super) enum AnySampler {
    Sobol(path::SobolSampler),
    Independent(Rng),
}

/// One sample of the `path` integrator for pixel number `pixel`: its sampler and
/// its camera ray, through a uniformly chosen point of the pixel.
pub(super) struct PathStart {
    pub(super) sampler: AnySampler,
    pub(super) ray: Ray,
    /// The image point from the pixel's corner.
    pub(super) offset: Vec2,
}

impl PathStart {
    /// (Inlined: as a call it copied the sampler's sixteen pairs out again,
    /// 0.7 % of the box's `path`.)
    #[inline(always)]
    pub(super) fn new(
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
        let d = options.filter.offset(d);
        let ray = if camera.thin_lens.is_none() {
            camera.ray(x + d.x, y + d.y)
        } else {
            Self::lens_ray(camera, &mut sampler, x + d.x, y + d.y)
        };
        Self {
            sampler,
            ray,
            offset: d,
        }
    }

    /// The camera ray through image point `(px, py)` and the thin lens's
    /// point that `sampler` gives (out of line: the pinhole's samples do
    /// not carry its code).
    #[cold]
    #[inline(never)]
    fn lens_ray(camera: &Camera, sampler: &mut AnySampler, px: f32, py: f32) -> Ray {
        let lens = match sampler {
            AnySampler::Sobol(smp) => smp.lens_2d(),
            AnySampler::Independent(rng) => rng.next_2d(),
        };
        camera.lens_ray(px, py, lens)
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
pub(super) fn pixel_ray(
    camera: &Camera,
    seed: u64,
    s: u32,
    x: usize,
    y: usize,
    width: usize,
) -> Ray {
    let (px, py) = pixel_point(seed, s, x, y, width);
    if camera.thin_lens.is_none() {
        return camera.ray(px, py);
    }
    lens_pixel_ray(camera, seed, s, (y * width + x) as u64, px, py)
}

/// [`pixel_ray`] through a thin lens, for pixel number `pixel` and its image
/// point `(px, py)` (out of line, as [`lens_rays8`]).
#[cold]
#[inline(never)]
fn lens_pixel_ray(camera: &Camera, seed: u64, s: u32, pixel: u64, px: f32, py: f32) -> Ray {
    camera.lens_ray(px, py, lens_point(seed, s, pixel))
}

/// The camera rays of a 4×2 block of the lab's integrators through a thin
/// lens: image points `px`, `py` of the pixels `first + pixels[k]`. Each
/// has its own origin, and the eight are still traced as one packet. Out of
/// line: inlined into the block loop, it cost the pinhole's blocks 1 % more
/// instructions.
#[cold]
#[inline(never)]
fn lens_rays8(
    camera: &Camera,
    seed: u64,
    s: u32,
    first: u64,
    pixels: &[usize; 8],
    px: &[f32; 8],
    py: &[f32; 8],
) -> [Ray; 8] {
    std::array::from_fn(|k| {
        let lens = lens_point(seed, s, first + pixels[k] as u64);
        camera.lens_ray(px[k], py[k], lens)
    })
}

/// The point of a thin lens for sample `s` of pixel number `pixel` of the
/// lab's integrators: the lens's centre for sample 0 (as the pixel's), else
/// uniformly jittered by the (seed, pixel, sample) generator of the lens.
#[inline]
fn lens_point(seed: u64, s: u32, pixel: u64) -> Vec2 {
    if s == 0 {
        return Vec2::splat(0.5);
    }
    let (u, v) = lens_jitter(seed, pixel, s);
    Vec2::new(u, v)
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
