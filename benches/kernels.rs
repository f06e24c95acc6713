//! `cargo bench --bench kernels`: Criterion benchmarks of the ray-casting kernels:
//! the triangle test (one ray against one triangle), the BVH build, and closest-hit
//! and any-hit traversal on a generated sphere mesh (so that they run anywhere;
//! `raylab bench` measures the shared real meshes).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3A;
use raylab::geometry::bvh::Bvh;
use raylab::geometry::ray::Ray;
use raylab::geometry::triangle::{RayShear, Triangle, bounds, intersect};
use raylab::workload;

/// A UV sphere of about `2·n²` triangles with a bumpy radius.
fn sphere(n: usize) -> Vec<Triangle> {
    let p = |i: usize, j: usize| {
        let (th, ph) = (
            std::f32::consts::PI * i as f32 / n as f32,
            std::f32::consts::TAU * j as f32 / (2 * n) as f32,
        );
        let r = 1.0 + 0.05 * (7.0 * ph).sin() * (5.0 * th).cos();
        Vec3A::new(
            r * th.sin() * ph.cos(),
            r * th.cos(),
            r * th.sin() * ph.sin(),
        )
    };
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..2 * n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    tris
}

fn triangle_test(c: &mut Criterion) {
    let tri = Triangle::new(
        Vec3A::new(-1.0, -1.0, 3.0),
        Vec3A::new(1.0, -1.0, 3.0),
        Vec3A::new(0.0, 1.0, 3.0),
    );
    let rays: Vec<Ray> = (0..1024)
        .map(|i| {
            let x = (i % 32) as f32 / 16.0 - 1.0;
            let y = (i / 32) as f32 / 16.0 - 1.0;
            Ray::new(Vec3A::ZERO, Vec3A::new(x, y, 3.0).normalize())
        })
        .collect();
    let shears: Vec<RayShear> = rays.iter().map(RayShear::new).collect();
    let mut g = c.benchmark_group("triangle");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("watertight_1024_rays", |b| {
        b.iter(|| {
            shears
                .iter()
                .filter(|s| intersect(s, black_box(&tri.v), f32::INFINITY).is_some())
                .count()
        })
    });
    g.finish();
}

fn bvh(c: &mut Criterion) {
    let tris = sphere(128); // 65,536 triangles
    let mut g = c.benchmark_group("bvh");
    g.sample_size(20);
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("build_65536_triangles", |b| {
        b.iter(|| Bvh::build(black_box(&tris)))
    });
    let bvh = Bvh::build(&tris);
    let (lo, hi) = bounds(&tris);
    let incoherent = workload::incoherent(lo, hi, 1 << 16);
    let primary: Vec<Ray> = workload::primary(lo, hi).into_iter().step_by(16).collect();
    let diag = (hi - lo).length();
    g.throughput(Throughput::Elements(incoherent.len() as u64));
    g.bench_function("closest_hit_incoherent_65536_rays", |b| {
        b.iter(|| {
            incoherent
                .iter()
                .filter(|r| bvh.intersect(r, f32::INFINITY).is_some())
                .count()
        })
    });
    g.bench_function("any_hit_incoherent_65536_rays", |b| {
        b.iter(|| incoherent.iter().filter(|r| bvh.occluded(r, diag)).count())
    });
    g.throughput(Throughput::Elements(primary.len() as u64));
    g.bench_function("closest_hit_primary_65536_rays", |b| {
        b.iter(|| {
            primary
                .iter()
                .filter(|r| bvh.intersect(r, f32::INFINITY).is_some())
                .count()
        })
    });
    g.finish();
}

criterion_group!(kernels, triangle_test, bvh);
criterion_main!(kernels);
