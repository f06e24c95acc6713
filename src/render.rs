//! Rendering an image: tiles of rows on rayon, samples keyed by (seed, pixel,
//! sample) so the result is bit-identical for any number of threads.

use std::ops::Range;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::Film;
use crate::integrator::Integrator;
use crate::ray::Ray;
use crate::sampler::Rng;
use crate::scene::Scene;

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
/// uniformly jittered over the pixel. The viewer refines by calls for `0..1`,
/// `1..2`, ...; one call for `0..n` gives the same sums up to f32 rounding.
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
            let y0 = tile * TILE_ROWS;
            let n_rows = rows.len() / width;
            let mut rays = 0u64;
            // Many samples are summed in f64 (one buffer per tile), so that even
            // 2^20 of them lose nothing to f32 rounding; one sample goes straight
            // into `sums`, which keeps progressive refinement exact.
            let mut wide = if samples.len() > 1 {
                vec![DVec3::ZERO; rows.len()]
            } else {
                Vec::new()
            };
            let mut add = |i: usize, v: Vec3A| match wide.get_mut(i) {
                Some(w) => *w += v.as_dvec3(),
                None => rows[i] += v,
            };
            for s in samples.clone() {
                // 2×2 pixel quads traced together; a last odd row or column alone.
                for qy in (0..n_rows).step_by(2) {
                    for qx in (0..width).step_by(2) {
                        if qy + 1 < n_rows && qx + 1 < width {
                            let quad = [(qx, qy), (qx + 1, qy), (qx, qy + 1), (qx + 1, qy + 1)];
                            let primary =
                                quad.map(|(x, y)| pixel_ray(camera, seed, s, x, y0 + y, width));
                            let values = integrator.radiance4(scene, &primary, &mut rays);
                            for ((x, y), v) in quad.into_iter().zip(values) {
                                add(y * width + x, v);
                            }
                        } else {
                            for y in qy..(qy + 2).min(n_rows) {
                                for x in qx..(qx + 2).min(width) {
                                    let ray = pixel_ray(camera, seed, s, x, y0 + y, width);
                                    add(y * width + x, integrator.radiance(scene, &ray, &mut rays));
                                }
                            }
                        }
                    }
                }
            }
            for (sum, w) in rows.iter_mut().zip(&wide) {
                *sum += w.as_vec3a();
            }
            progress(n_rows as u64);
            rays
        })
        .sum()
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
