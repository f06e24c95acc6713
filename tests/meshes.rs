//! The BVH on real meshes (assets/models) against brute force: the same
//! hit or miss, `t` within 1e-5 relative, the same triangle except on exact ties,
//! and any-hit agreeing with closest-hit.

use std::path::Path;

use glam::Vec3A;
use raylab::geometry::bvh::{Bvh, brute_force};
use raylab::geometry::ray::Ray;
use raylab::geometry::triangle::bounds;
use raylab::workload;

fn check_mesh(name: &str, stride: usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/models")
        .join(name);
    let mesh = raylab::load::obj::load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
    let tris = &mesh.triangles;
    let bvh = Bvh::build(tris);
    assert_eq!(
        bvh.triangle_count(),
        tris.iter().filter(|t| t.area() > 0.0).count()
    );
    let (lo, hi) = bounds(tris);
    // Every stride-th ray of both standard workloads: coherent and incoherent.
    let rays: Vec<Ray> = workload::primary(lo, hi)
        .into_iter()
        .step_by(stride)
        .chain(
            workload::incoherent(lo, hi, 1 << 20)
                .into_iter()
                .step_by(stride),
        )
        .collect();
    let mut hits = 0;
    for ray in &rays {
        let want = brute_force(tris, ray, f32::INFINITY);
        let got = bvh.intersect(ray, f32::INFINITY);
        assert_eq!(got.is_some(), want.is_some(), "{name}: {ray:?}");
        assert_eq!(
            bvh.occluded(ray, f32::INFINITY),
            want.is_some(),
            "{name}: {ray:?}"
        );
        if let (Some(g), Some(w)) = (got, want) {
            hits += 1;
            assert!((g.t - w.t).abs() <= 1e-5 * w.t, "{name}: {g:?} vs {w:?}");
            assert!(g.prim == w.prim || g.t == w.t, "{name}: {g:?} vs {w:?}");
            // Shadow rays just short of the hit see nothing; just past it, something.
            assert!(!bvh.occluded(ray, w.t * 0.999), "{name}: {ray:?}");
            assert!(bvh.occluded(ray, w.t * 1.001), "{name}: {ray:?}");
        }
    }
    assert!(
        hits > rays.len() / 5,
        "{name}: only {hits} of {} rays hit",
        rays.len()
    );
}

#[test]
fn bunny_agrees_with_brute_force() {
    check_mesh("stanford-bunny.obj", 2048);
}

#[test]
fn teapot_agrees_with_brute_force() {
    // Not a manifold: open edges, coincident and sliver triangles.
    check_mesh("teapot.obj", 256);
}

#[test]
fn rays_starting_inside_the_box_and_nan_rays() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/teapot.obj");
    let tris = raylab::load::obj::load_obj(&path).unwrap().triangles;
    let bvh = Bvh::build(&tris);
    let (lo, hi) = bounds(&tris);
    let centre = (lo + hi) / 2.0;
    for dir in [Vec3A::X, -Vec3A::Y, Vec3A::new(0.3, 0.4, -0.5).normalize()] {
        let ray = Ray::new(centre, dir);
        assert_eq!(
            bvh.intersect(&ray, f32::INFINITY),
            brute_force(&tris, &ray, f32::INFINITY)
        );
    }
    for ray in [
        Ray::new(Vec3A::splat(f32::NAN), Vec3A::X),
        Ray::new(centre, Vec3A::new(f32::INFINITY, 0.0, 0.0)),
        Ray::new(centre, Vec3A::ZERO),
    ] {
        assert!(bvh.intersect(&ray, f32::INFINITY).is_none());
        assert!(!bvh.occluded(&ray, f32::INFINITY));
    }
}
