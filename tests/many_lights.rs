//! Many emitters: ten thousand emitting triangles chosen by power through the
//! alias table, against choosing them uniformly, at equal time.

mod common;

use std::time::Instant;

use glam::Vec3A;
use raylab::camera::{Lens, look_at};
use raylab::film::{Film, rel_mse};
use raylab::materials::surface::SurfaceMaterial;
use raylab::scene::LightSelection;
use raylab::{Camera, Scene, Triangle};

/// A grey floor under 100 × 100 small emitters facing down; one in a hundred
/// is a thousand times brighter than the rest (about 90 % of the power in
/// 1 % of the lights).
fn city_at_night() -> (Scene, Camera) {
    let s = 6.0;
    let mut tris = vec![
        Triangle::new(
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(s, 0.0, s),
            Vec3A::new(s, 0.0, -s),
        ),
        Triangle::new(
            Vec3A::new(-s, 0.0, -s),
            Vec3A::new(-s, 0.0, s),
            Vec3A::new(s, 0.0, s),
        ),
    ];
    let mut material_of = vec![0, 0];
    let size = 0.05;
    for k in 0..10_000u32 {
        let (x, z) = (-5.0 + 0.1 * (k % 100) as f32, -5.0 + 0.1 * (k / 100) as f32);
        let a = Vec3A::new(x, 1.0, z);
        // Counter-clockwise seen from below: the front faces the floor.
        tris.push(Triangle::new(a, a + Vec3A::X * size, a + Vec3A::Z * size));
        // A scattered one in a hundred is bright.
        let bright = (k.wrapping_mul(2_654_435_761) >> 16) % 100 == 0;
        material_of.push(if bright { 2 } else { 1 });
    }
    let emitter = |le: f32| SurfaceMaterial {
        emission: Vec3A::splat(le),
        ..SurfaceMaterial::diffuse(Vec3A::ZERO)
    };
    let materials = vec![
        SurfaceMaterial::diffuse(Vec3A::splat(0.5)),
        emitter(2.0),
        emitter(2000.0),
    ];
    let scene = common::two_sided_scene(tris, material_of, materials);
    // From above: the emitters show their dark backs, the floor their light.
    let position = Vec3A::new(0.0, 4.0, 4.0);
    let rotation = look_at(position, Vec3A::ZERO, Vec3A::Y).unwrap();
    let camera = Camera::with_lens(position, rotation, Lens::from_yfov(1.0), 64, 48);
    (scene, camera)
}

fn mean(film: &Film) -> f64 {
    film.pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum())
        .sum::<f64>()
        / (3 * film.pixels.len()) as f64
}

#[test]
fn ten_thousand_emitters_converge_faster_chosen_by_power() {
    let (mut scene, cam) = city_at_night();
    assert_eq!(scene.emitter_count(), 10_000);
    let reference = common::path_film(&scene, &cam, 1024, 99);
    let spp = 8;
    let mut cost = Vec::new();
    let mut means = Vec::new();
    for selection in [LightSelection::Power, LightSelection::Uniform] {
        scene.set_light_selection(selection);
        let _ = common::path_film(&scene, &cam, 1, 5);
        let (mut best, mut film) = (f64::INFINITY, Film::new(1, 1));
        for round in 0..3 {
            let start = Instant::now();
            film = common::path_film(&scene, &cam, spp, 7 + round);
            best = best.min(start.elapsed().as_secs_f64());
        }
        let e = rel_mse(&film, &reference);
        eprintln!(
            "{selection:?}: relMSE {e:.3e} at {spp} spp in {:.1} ms (relMSE × s = {:.3e})",
            best * 1e3,
            e * best
        );
        cost.push(e * best);
        // A long render of each converges to the same image: the choice's
        // probability is divided out (and MIS-weighted) correctly either way.
        means.push(mean(&common::path_film(&scene, &cam, 256, 3)));
    }
    let ratio = cost[1] / cost[0];
    eprintln!(
        "equal-time relMSE: uniform / power = {ratio:.1}; means {means:?} vs {}",
        mean(&reference)
    );
    assert!(
        ratio >= 3.0,
        "power selection only {ratio:.1}× better at equal time"
    );
    // The image mean's noise at 256 spp: about 0.4 % chosen by power, 3 %
    // chosen uniformly (its relMSE is 60 times larger); tolerances are 5 and 3 σ.
    for (m, tolerance) in means.into_iter().zip([0.02, 0.1]) {
        let off = m / mean(&reference) - 1.0;
        assert!(off.abs() < tolerance, "mean {m} vs {}", mean(&reference));
    }
}
