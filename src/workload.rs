//! Ray-casting workloads for `raylab bench`: the standard primary and incoherent
//! rays of `../shared/bench/README.md`, ray files, and casting them on all threads.

use std::path::Path;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::geometry::bvh::Bvh;
use crate::geometry::ray::{Hit, Ray};
use crate::geometry::triangle::Triangle;
use crate::sampling::sampler::Rng;

/// Rays handed to one thread at a time.
const CHUNK: usize = 1024;

/// The primary workload: a 1024×1024 pinhole view from `c + (0, 0, 2·ext)` along
/// −z, up +y, vertical field of view 45°, one ray per pixel centre, row-major
/// from the top row (computed in f64, as the reference generator does).
pub fn primary(lo: Vec3A, hi: Vec3A) -> Vec<Ray> {
    const SIZE: usize = 1024;
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let c = (lo + hi) / 2.0;
    let ext = (hi - lo).max_element();
    let eye = (c + DVec3::new(0.0, 0.0, 2.0 * ext)).as_vec3a();
    let tan = 22.5f64.to_radians().tan();
    (0..SIZE * SIZE)
        .map(|i| {
            let (x, y) = ((i % SIZE) as f64, (i / SIZE) as f64);
            let d = DVec3::new(
                (2.0 * (x + 0.5) / SIZE as f64 - 1.0) * tan,
                (1.0 - 2.0 * (y + 0.5) / SIZE as f64) * tan,
                -1.0,
            )
            .normalize();
            Ray::new(eye, d.as_vec3a())
        })
        .collect()
}

/// The incoherent workload: `n` rays with origins uniform in the box and
/// directions uniform on the sphere, from raylab's own generator.
pub fn incoherent(lo: Vec3A, hi: Vec3A, n: usize) -> Vec<Ray> {
    let mut rng = Rng::new(1234, 0);
    (0..n)
        .map(|_| {
            let u = Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let z = 1.0 - 2.0 * rng.next_f32();
            let phi = std::f32::consts::TAU * rng.next_f32();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(
                lo + u * (hi - lo),
                Vec3A::new(r * phi.cos(), r * phi.sin(), z),
            )
        })
        .collect()
}

/// Far end of the surface shadow rays, whose directions reach the light at 1.
pub const SURFACE_SHADOW_TFAR: f32 = 1.0 - 1e-4;

/// Rays that start on the mesh, as a path tracer's secondary rays do.
pub struct SurfaceRays {
    /// Closest-hit rays in cosine-distributed directions about the normal.
    pub bounce: Vec<Ray>,
    /// Any-hit rays to a point light, direction `light − origin` (not unit), to
    /// be traced over `(0, SURFACE_SHADOW_TFAR]`.
    pub shadow: Vec<Ray>,
}

/// The surface workloads, built as `tools/gen_surface_rays.py` builds them for
/// the shared data but from raylab's own hits and random numbers (so the same
/// distribution, not the same rays): from the hit point of every incoherent ray that hits, pushed
/// off the surface by 1e-4 × the largest extent along the geometric normal on
/// the side the ray came from, a diffuse bounce and a shadow ray to the point
/// light at `c + (0.3, 1.0, 0.6) · ext`.
pub fn surface(
    bvh: &Bvh,
    triangles: &[Triangle],
    incoherent: &[Ray],
    lo: Vec3A,
    hi: Vec3A,
) -> SurfaceRays {
    let (lo64, hi64) = (lo.as_dvec3(), hi.as_dvec3());
    let c = (lo64 + hi64) / 2.0;
    let ext = (hi64 - lo64).max_element();
    let light = c + DVec3::new(0.3, 1.0, 0.6) * ext;
    let mut rng = Rng::new(4321, 0);
    let (mut bounce, mut shadow) = (Vec::new(), Vec::new());
    for ray in incoherent {
        let Some(hit) = bvh.intersect(ray, f32::INFINITY) else {
            continue;
        };
        let [a, b, c] = triangles[hit.prim as usize].v.map(|v| v.as_dvec3());
        let d = ray.dir.as_dvec3();
        let mut n = (b - a).cross(c - a).normalize();
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let origin = ray.origin.as_dvec3() + d * hit.t as f64 + n * (1e-4 * ext);
        // Cosine-distributed about n (Malley: a uniform disc lifted to the hemisphere).
        let (u1, u2) = (rng.next_f32() as f64, rng.next_f32() as f64);
        let (r, phi) = (u1.sqrt(), std::f64::consts::TAU * u2);
        let t1 = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
        let t1 = t1.cross(n).normalize();
        let t2 = n.cross(t1);
        let dir = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt();
        bounce.push(Ray::new(origin.as_vec3a(), dir.normalize().as_vec3a()));
        shadow.push(Ray::new(origin.as_vec3a(), (light - origin).as_vec3a()));
    }
    SurfaceRays { bounce, shadow }
}

/// Reads a ray file: little-endian f32, six per ray (`ox oy oz dx dy dz`).
/// A file that is empty, not a whole number of rays, or holds a ray with a
/// non-finite coordinate or a zero direction is refused, naming the first bad
/// ray: the kernels assume finite rays, and a benchmark of garbage measures
/// nothing.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if bytes.is_empty() {
        return Err(format!("{}: the file holds no rays", path.display()));
    }
    if bytes.len() % 24 != 0 {
        return Err(format!(
            "{}: {} bytes is not a whole number of rays (24 bytes each)",
            path.display(),
            bytes.len()
        ));
    }
    bytes
        .chunks_exact(24)
        .enumerate()
        .map(|(i, r)| {
            let f =
                |i: usize| f32::from_le_bytes([r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]]);
            let (o, d) = (Vec3A::new(f(0), f(1), f(2)), Vec3A::new(f(3), f(4), f(5)));
            if !(o.is_finite() && d.is_finite()) {
                return Err(format!(
                    "{}: ray {i} has a NaN or infinite coordinate",
                    path.display()
                ));
            }
            if d == Vec3A::ZERO {
                return Err(format!("{}: ray {i} has a zero direction", path.display()));
            }
            Ok(Ray::new(o, d))
        })
        .collect()
}

/// Closest hits of all rays within `(0, t_max]`, one ray at a time on every
/// thread of the current pool.
pub fn cast_closest(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = bvh.intersect(r, t_max);
            }
        });
}

/// Closest hits as [`cast_closest`], tracing each four consecutive rays together
/// (coherent for the primary workload's scanlines).
pub fn cast_closest4(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| {
            let mut quads = rays.chunks_exact(4);
            let mut outs = out.chunks_exact_mut(4);
            for (o, r) in (&mut outs).zip(&mut quads) {
                o.copy_from_slice(&bvh.intersect4(r.try_into().expect("four rays"), t_max));
            }
            for (o, r) in outs.into_remainder().iter_mut().zip(quads.remainder()) {
                *o = bvh.intersect(r, t_max);
            }
        });
}

/// Closest hits as [`cast_closest`], tracing each eight consecutive rays together
/// ([`Bvh::intersect8`]: AVX2 lanes where the CPU has them).
pub fn cast_closest8(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| {
            let mut groups = rays.chunks_exact(8);
            let mut outs = out.chunks_exact_mut(8);
            for (o, r) in (&mut outs).zip(&mut groups) {
                o.copy_from_slice(&bvh.intersect8(r.try_into().expect("eight rays"), t_max));
            }
            for (o, r) in outs.into_remainder().iter_mut().zip(groups.remainder()) {
                *o = bvh.intersect(r, t_max);
            }
        });
}

/// Closest hits as [`cast_closest`] through the stream API
/// ([`Bvh::intersect_stream`]: several rays in flight per thread).
pub fn cast_closest_stream(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| bvh.intersect_stream(rays, &[t_max], out));
}

/// Any hits as [`cast_occluded`] through the stream API ([`Bvh::occluded_stream`]).
pub fn cast_occluded_stream(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [bool]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| bvh.occluded_stream(rays, &[t_max], out));
}

/// Whether each ray is blocked within `(0, t_max]`, one ray at a time.
pub fn cast_occluded(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [bool]) {
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .for_each(|(out, rays)| {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = bvh.occluded(r, t_max);
            }
        });
}

/// Hits in the bench file format: per ray `f32 t, u32 prim`, a miss as
/// `(+inf, 0xFFFFFFFF)`, little-endian.
pub fn encode_hits(hits: &[Option<Hit>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hits.len() * 8);
    for h in hits {
        let (t, prim) = h.map_or((f32::INFINITY, u32::MAX), |h| (h.t, h.prim));
        out.extend_from_slice(&t.to_le_bytes());
        out.extend_from_slice(&prim.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workloads_follow_the_definitions() {
        let (lo, hi) = (Vec3A::new(-1.0, 0.0, -2.0), Vec3A::new(3.0, 1.0, 0.0));
        let p = primary(lo, hi);
        assert_eq!(p.len(), 1 << 20);
        // Eye at c + (0, 0, 2·ext) = (1, 0.5, -1 + 8); the centre rays look along -z.
        assert_eq!(p[0].origin, Vec3A::new(1.0, 0.5, 7.0));
        let mid = p[512 * 1024 + 512].dir;
        assert!(mid.z < -0.99999 && mid.x > 0.0 && mid.y < 0.0);
        // Top-left ray: 22.5° up and left at the corner.
        let tl = p[0].dir;
        assert!(tl.x < 0.0 && tl.y > 0.0);
        assert!((tl.y / -tl.z - (1.0 - 1.0 / 1024.0) * 22.5f32.to_radians().tan()).abs() < 1e-6);
        let inc = incoherent(lo, hi, 100_000);
        let mean = inc.iter().map(|r| r.dir).sum::<Vec3A>() / 100_000.0;
        assert!(mean.length() < 0.02, "directions not uniform: mean {mean}");
        for r in &inc {
            assert!((r.dir.length() - 1.0).abs() < 1e-5);
            assert!(r.origin.cmpge(lo).all() && r.origin.cmple(hi).all());
        }
    }

    #[test]
    fn ray_files_round_trip_and_hits_encode() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.rays");
        let values = [
            1.0f32, 2.0, 3.0, 0.0, 0.0, -1.0, 0.5, 0.5, 0.5, 1.0, 0.0, 0.0,
        ];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, &bytes).unwrap();
        let rays = read_rays(&path).unwrap();
        assert_eq!(rays.len(), 2);
        assert_eq!(rays[1].origin, Vec3A::splat(0.5));
        std::fs::write(&path, &bytes[..30]).unwrap();
        assert!(read_rays(&path).unwrap_err().contains("24 bytes"));
        let hit = Hit {
            t: 2.5,
            prim: 7,
            b1: 0.0,
            b2: 0.0,
        };
        let enc = encode_hits(&[Some(hit), None]);
        assert_eq!(
            &enc[..8],
            &[2.5f32.to_le_bytes(), 7u32.to_le_bytes()].concat()[..]
        );
        assert_eq!(
            &enc[8..],
            &[f32::INFINITY.to_le_bytes(), u32::MAX.to_le_bytes()].concat()[..]
        );
    }
}
