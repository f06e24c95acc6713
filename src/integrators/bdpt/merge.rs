//! Vertex merging (Georgiev, Křivánek, Davidovič & Slusallek 2012,
//! "Light transport simulation with vertex connection and merging";
//! Hachisuka, Pantaleoni & Jensen 2012's unified path sampling): the light
//! subpaths of one iteration (one sample of every pixel) kept with a hash
//! grid over their surface vertices, so that a camera subpath's vertex can
//! take the light of every light vertex within a radius of it, a density
//! estimate (photon mapping's) weighed against bidirectional path
//! tracing's connections by multiple importance sampling.
//!
//! The radius shrinks from iteration to iteration as `r_i = r_1 i^((α−1)/2)`
//! with `α = 3/4` (progressive photon mapping's schedule, Knaus & Zwicker
//! 2011), so the merges' bias vanishes and the render converges to the
//! complete image: `bdpt`'s plus the specular–diffuse–specular light only
//! merging finds (consistent, not unbiased). `r_1` is
//! [`DEFAULT_RADIUS_PIXELS`] pixel footprints at the median distance the
//! camera sees.
//!
//! Deterministic: each light subpath's random numbers are keyed by (seed,
//! pixel, iteration), the vertices are stored in pixel order and the grid
//! lists them in that order, so a merge sums the same values in the same
//! order whatever the threads.

use glam::{IVec3, Vec3A};
use rayon::prelude::*;

use super::vertex::{Kind, MAX_VERTICES, Vertex};
use super::walk::light_subpath;
use crate::camera::Camera;
use crate::integrators::path::PathOptions;
use crate::sampling::sampler::Rng;
use crate::scene::Scene;

/// The exponent of the radius schedule: the merges' share of the variance
/// and of the bias shrink alike (Knaus & Zwicker 2011).
const ALPHA: f32 = 0.75;

/// What the seed of a light subpath's random numbers is mixed with, so that
/// they differ from the camera subpath's of the same pixel and sample.
const LIGHT_STREAM: u64 = 0x6d65_7267_6520_6c69;

/// The default first radius, in pixel footprints.
pub const DEFAULT_RADIUS_PIXELS: f32 = 2.0;

/// One iteration's light subpaths, one per pixel, and the grid over their
/// vertices that can be merged with. Its buffers are kept from iteration
/// to iteration ([`LightPaths::trace`] refills them).
#[derive(Debug, Default)]
pub struct LightPaths {
    /// Every image row's subpaths' vertices, pixel after pixel.
    rows: Vec<Vec<Vertex>>,
    /// Where pixel `p`'s subpath starts in its row's vertices.
    starts: Vec<u32>,
    /// The image's width.
    width: usize,
    /// The square of the merge radius.
    radius2: f32,
    /// The light subpaths per image times the merge disk's area: a merged
    /// light vertex's weight is `1 / eta`, and the merges' density is
    /// `eta` times that of the connection they stand in for.
    eta: f64,
    /// The grid: cells of side `2 r` hashed into buckets, each bucket's
    /// mergeable vertices at `cells[bucket_start[b]..bucket_start[b + 1]]`.
    cell: f32,
    bucket_start: Vec<u32>,
    cells: Vec<Entry>,
}

/// A mergeable light vertex in the grid: its row, its index in the row's
/// vertices, and where its subpath starts there.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    row: u32,
    index: u32,
    start: u32,
}

impl LightPaths {
    /// Traces iteration `iteration`'s light subpaths (one per pixel, keyed
    /// by `seed`, pixel and iteration) of at most `options.max_depth`
    /// segments, with merge radius `radius`, in place of the last
    /// iteration's; `rays` counts the rays cast.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        options: &PathOptions,
        seed: u64,
        iteration: u32,
        radius: f32,
        rays: &mut u64,
    ) {
        let (width, height) = (camera.width as usize, camera.height as usize);
        let pixels = width * height;
        let max = (options.max_depth.min(2 * MAX_VERTICES as u32) as usize).min(MAX_VERTICES);
        let seed = seed ^ LIGHT_STREAM;
        self.width = width;
        self.rows.resize_with(height, Vec::new);
        self.starts.resize(pixels, 0);
        // Rows in parallel, each into its own buffer.
        *rays += self
            .rows
            .par_iter_mut()
            .zip(self.starts.par_chunks_mut(width))
            .enumerate()
            .map(|(y, (row, starts))| {
                row.clear();
                let mut path = Vec::new();
                let mut rays = 0u64;
                for (x, start) in starts.iter_mut().enumerate() {
                    let pixel = (y * width + x) as u64;
                    let mut rng = Rng::for_sample(seed, pixel, iteration);
                    light_subpath(scene, max, &mut rng, &mut path, &mut rays);
                    *start = row.len() as u32;
                    row.extend_from_slice(&path);
                }
                rays
            })
            .sum::<u64>();
        self.radius2 = radius * radius;
        self.eta = pixels as f64 * std::f64::consts::PI * f64::from(radius) * f64::from(radius);
        self.cell = 2.0 * radius;
        self.build_grid();
    }

    /// Where pixel `pixel`'s subpath lies: its row and the range of its
    /// vertices there.
    #[inline]
    fn span(&self, pixel: usize) -> (usize, usize, usize) {
        let row = pixel / self.width;
        let end = if (pixel + 1).is_multiple_of(self.width) {
            self.rows[row].len()
        } else {
            self.starts[pixel + 1] as usize
        };
        (row, self.starts[pixel] as usize, end)
    }

    /// Whether a light subpath's vertex can be merged with: a surface the
    /// walk reached from another vertex (not the light's own point).
    fn mergeable(v: &Vertex) -> bool {
        matches!(v.kind, Kind::Surface) && v.scatter.is_some()
    }

    /// Fills the hash grid (a counting sort by bucket, vertices in order).
    fn build_grid(&mut self) {
        let mut entries = std::mem::take(&mut self.cells);
        entries.clear();
        for pixel in 0..self.starts.len() {
            let (row, a, b) = self.span(pixel);
            for i in a + 1..b {
                if Self::mergeable(&self.rows[row][i]) {
                    entries.push(Entry {
                        row: row as u32,
                        index: i as u32,
                        start: a as u32,
                    });
                }
            }
        }
        let buckets = entries.len().next_power_of_two().max(1);
        let keys: Vec<usize> = entries
            .iter()
            .map(|e| self.bucket(self.cell_of(self.vertex(e).point.p), buckets))
            .collect();
        let mut count = std::mem::take(&mut self.bucket_start);
        count.clear();
        count.resize(buckets + 1, 0);
        for &k in &keys {
            count[k + 1] += 1;
        }
        for b in 0..buckets {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut cells = vec![Entry::default(); entries.len()];
        for (entry, &k) in entries.iter().zip(&keys) {
            cells[fill[k] as usize] = *entry;
            fill[k] += 1;
        }
        self.bucket_start = count;
        self.cells = cells;
    }

    /// The vertex of a grid entry.
    #[inline]
    fn vertex(&self, e: &Entry) -> &Vertex {
        &self.rows[e.row as usize][e.index as usize]
    }

    /// The grid cell of point `p`.
    #[inline]
    fn cell_of(&self, p: Vec3A) -> IVec3 {
        let c = (p / self.cell).floor();
        IVec3::new(c.x as i32, c.y as i32, c.z as i32)
    }

    /// The bucket of cell `c` among `buckets` (a power of two).
    #[inline]
    fn bucket(&self, c: IVec3, buckets: usize) -> usize {
        let h = (c.x as u32).wrapping_mul(73_856_093)
            ^ (c.y as u32).wrapping_mul(19_349_663)
            ^ (c.z as u32).wrapping_mul(83_492_791);
        h as usize & (buckets - 1)
    }

    /// Pixel `pixel`'s light subpath.
    #[inline]
    pub(super) fn path(&self, pixel: usize) -> &[Vertex] {
        let (row, a, b) = self.span(pixel);
        &self.rows[row][a..b]
    }

    /// The light subpaths per image times the merge disk's area.
    #[inline]
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// Calls `found` with every mergeable light vertex within the radius of
    /// `p`: its subpath up to and including it (the vertex last).
    pub(super) fn near(&self, p: Vec3A, mut found: impl FnMut(&[Vertex])) {
        let buckets = self.bucket_start.len() - 1;
        if self.cells.is_empty() {
            return;
        }
        // The 2 × 2 × 2 cells of side 2r the sphere of radius r about p
        // can reach: those on p's side of the middle of its cell.
        let q = p / self.cell;
        let base = q.floor();
        let lo = IVec3::new(
            base.x as i32 - i32::from(q.x - base.x < 0.5),
            base.y as i32 - i32::from(q.y - base.y < 0.5),
            base.z as i32 - i32::from(q.z - base.z < 0.5),
        );
        // Distinct buckets only (two cells may hash alike).
        let mut seen = [usize::MAX; 8];
        let mut n = 0;
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let b = self.bucket(lo + IVec3::new(dx, dy, dz), buckets);
                    if seen[..n].contains(&b) {
                        continue;
                    }
                    seen[n] = b;
                    n += 1;
                    let (a, e) = (self.bucket_start[b], self.bucket_start[b + 1]);
                    for entry in &self.cells[a as usize..e as usize] {
                        let v = self.vertex(entry);
                        if (v.point.p - p).length_squared() <= self.radius2 {
                            let row = &self.rows[entry.row as usize];
                            found(&row[entry.start as usize..=entry.index as usize]);
                        }
                    }
                }
            }
        }
    }
}

/// The merge radius of iteration `iteration` (from 0) for a first radius
/// `first`.
pub fn radius_at(first: f32, iteration: u32) -> f32 {
    first * ((iteration + 1) as f32).powf(0.5 * (ALPHA - 1.0))
}

/// The first merge radius of `pixels` pixel footprints: the width one pixel
/// covers at the median distance of what the camera sees (from a grid of
/// rays through the image), times `pixels`; the scene's radius over 1000
/// times `pixels` if the camera sees nothing.
pub fn first_radius(scene: &Scene, camera: &Camera, pixels: f32) -> f32 {
    const N: usize = 16;
    let mut distances = Vec::with_capacity(N * N);
    for j in 0..N {
        for i in 0..N {
            let px = (i as f32 + 0.5) / N as f32 * camera.width as f32;
            let py = (j as f32 + 0.5) / N as f32 * camera.height as f32;
            let ray = camera.ray(px, py);
            if let Some(hit) = scene.intersect(&ray, f32::INFINITY) {
                // The footprint: the distance between this ray's hit and
                // that of the ray one pixel over, at the same distance.
                let next = camera.ray(px + 1.0, py);
                distances.push((next.dir - ray.dir).length() * hit.t);
            }
        }
    }
    if distances.is_empty() {
        return scene.radius() * 1e-3 * pixels;
    }
    distances.sort_by(f32::total_cmp);
    distances[distances.len() / 2] * pixels
}
