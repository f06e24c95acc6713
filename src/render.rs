//! Rendering an image: tiles of rows on rayon, samples keyed by (seed, pixel,
//! sample) so the result is bit-identical for any number of threads.

use std::ops::Range;

use glam::Vec3A;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::Film;
use crate::integrator::Integrator;
use crate::sampler::Rng;
use crate::scene::Scene;

/// Rows per tile: small enough to balance two cores on small images, large enough
/// that scheduling costs nothing.
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
}

/// Renders `settings.spp` samples per pixel and averages them. `progress` is called
/// with the number of rows finished after each tile, from any thread.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Rendered {
    let mut film = Film::new(camera.width, camera.height);
    let rays = accumulate(
        scene,
        camera,
        settings.integrator,
        settings.seed,
        0..settings.spp.max(1),
        &mut film,
        progress,
    );
    film.scale(1.0 / settings.spp.max(1) as f32);
    Rendered { film, rays }
}

/// Adds samples `samples` of every pixel to `sums`, in sample order, and returns
/// the number of rays cast. Sample 0 goes through the pixel centre; the others are
/// uniformly jittered over the pixel. Calling it for `0..1`, then `1..2`, ... gives
/// exactly the sums of one call for `0..n` (the viewer refines that way).
pub fn accumulate(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
    sums: &mut Film,
    progress: &(dyn Fn(u64) + Sync),
) -> u64 {
    let width = camera.width as usize;
    assert_eq!((sums.width, sums.height), (camera.width, camera.height));
    sums.pixels
        .par_chunks_mut(width * TILE_ROWS)
        .enumerate()
        .map(|(tile, rows)| {
            let mut rays = 0u64;
            let first = tile * TILE_ROWS * width;
            for (i, sum) in rows.iter_mut().enumerate() {
                let index = first + i;
                let (x, y) = ((index % width) as f32, (index / width) as f32);
                for s in samples.clone() {
                    let (dx, dy) = if s == 0 {
                        (0.5, 0.5)
                    } else {
                        let mut rng = Rng::for_sample(seed, index as u64, s);
                        (rng.next_f32(), rng.next_f32())
                    };
                    let ray = camera.ray(x + dx, y + dy);
                    *sum += integrator.radiance(scene, &ray, &mut rays);
                }
            }
            progress((rows.len() / width) as u64);
            rays
        })
        .sum()
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
