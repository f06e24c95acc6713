//! Whole-image properties of the lab renders: agreement with an independent
//! reference, no shadow acne, determinism, and progressive refinement.

mod common;

use glam::Vec3A;
use raylab::film::Film;
use raylab::load::cornell::{self, colors};
use raylab::render::{RenderSettings, accumulate, render, sample_pixel};
use raylab::{Camera, Integrator, Scene};

/// The seven reflectances of the box.
const PALETTE: [Vec3A; 7] = [
    colors::GREEN,
    colors::PURPLE,
    colors::YELLOW,
    colors::CYAN,
    colors::WHITE,
    colors::RED,
    colors::BLUE,
];

fn lab_camera(w: u32, h: u32) -> Camera {
    Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, w, h)
}

fn render_with(scene: &Scene, cam: &Camera, settings: RenderSettings, threads: usize) -> Film {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render(scene, cam, &settings, &|_| {}).film)
}

/// The blocks' bounding boxes, grown by 0.01.
fn block_boxes(scene: &Scene) -> Vec<(Vec3A, Vec3A)> {
    [cornell::parts::SHORT_BLOCK, cornell::parts::TALL_BLOCK]
        .into_iter()
        .map(|r| {
            let (lo, hi) = raylab::geometry::triangle::bounds(&scene.triangles()[r]);
            (lo - 0.01, hi + 0.01)
        })
        .collect()
}

/// Whether the segment from `a` to `b` meets the box.
fn segment_hits_box(a: Vec3A, b: Vec3A, (lo, hi): (Vec3A, Vec3A)) -> bool {
    let d = b - a;
    let (t0, t1) = ((lo - a) / d, (hi - a) / d);
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(1.0);
    near <= far
}

/// The lab's `direct` value at point `p` of triangle `prim`, with the light in view.
fn analytic_direct(scene: &Scene, prim: u32, p: Vec3A) -> Vec3A {
    let to_light = scene.light.position - p;
    let cos = to_light.normalize().dot(scene.normal(prim)).max(0.0);
    let d = scene.light.power * cos / (4.0 * std::f32::consts::PI * to_light.length_squared());
    scene.reflectance(prim) * (d + scene.ambient)
}

/// The lab's `direct` image against assets/refs/cornell-direct-lab-500.exr, made
/// by Embree ray casting and the lab formula. They may differ only where a pixel
/// centre's ray is an exact tie: through the box's edges (the image diagonals),
/// along silhouettes and exactly on shadow boundaries.
#[test]
fn direct_matches_the_independent_reference() {
    let reference = common::reference_image("cornell-direct-lab-500.exr");
    let scene = cornell::scene();
    let ours = render(
        &scene,
        &lab_camera(500, 500),
        &RenderSettings::default(),
        &|_| {},
    )
    .film;
    assert_eq!((reference.width, reference.height), (500, 500));
    let mut differ = 0;
    let mut worst_off_diagonal = 0usize;
    for y in 0..500 {
        for x in 0..500 {
            let (a, b) = (ours.get(x, y), reference.get(x, y));
            let rel = ((a - b).abs() / b.abs().max(Vec3A::splat(1e-3))).max_element();
            if rel > 1e-4 {
                differ += 1;
                if x != y && x + y != 499 {
                    worst_off_diagonal += 1;
                }
            }
        }
    }
    eprintln!("{differ} pixels differ, {worst_off_diagonal} off the diagonals");
    // Measured: 386 to 469 differing pixels (by traversal order), all but one on
    // the 1000 diagonal pixels, whose rays run exactly along the box's edges, where
    // the two walls meeting there tie and each renderer may pick either.
    assert!(differ <= 600, "{differ} of 250000 pixels differ");
    assert!(
        worst_off_diagonal <= 5,
        "{worst_off_diagonal} pixels off the diagonals differ"
    );
}

/// The lab report's noisy image came from shadow rays hitting the surface they
/// start on. Every floor pixel whose view and light paths provably miss both blocks
/// must get the full analytic value ρ(D + N): a speckle of acne would drop D.
#[test]
fn lit_floor_has_no_acne() {
    let scene = cornell::scene();
    let (w, h) = (500, 500);
    let cam = lab_camera(w, h);
    let film = render(&scene, &cam, &RenderSettings::default(), &|_| {}).film;
    let block_boxes = block_boxes(&scene);
    let light = scene.light.position;
    let mut checked = 0;
    for y in 320..h {
        for x in 0..w {
            let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            // Where the ray meets the floor plane y = 1, computed independently.
            let t = (1.0 - ray.origin.y) / ray.dir.y;
            let p = ray.at(t);
            // Right up to the walls, whose concave edges with the floor are where
            // rounding puts points behind the other surface; only the last 1e-4,
            // where the wall and the floor tie for the camera ray, is left out.
            if p.x.abs() > 0.9999 || p.z.abs() > 0.9999 {
                continue;
            }
            if block_boxes
                .iter()
                .any(|&b| segment_hits_box(ray.origin, p, b) || segment_hits_box(p, light, b))
            {
                continue;
            }
            let want = analytic_direct(&scene, 0, p);
            let got = film.get(x, y);
            assert!(
                ((got - want).abs() / want).max_element() < 1e-4,
                "pixel ({x}, {y}): {got} vs analytic {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > 15_000, "only {checked} floor pixels checked");
}

/// On the image diagonals of the lab view, pixel-centre rays run exactly along the
/// box's edges, where two walls meet at a right angle. Rounding can put such a
/// point just behind the other wall; its shadow ray must still reach the light.
#[test]
fn concave_edges_of_the_box_are_lit() {
    let scene = cornell::scene();
    let cam = lab_camera(500, 500);
    let boxes = block_boxes(&scene);
    let light = scene.light.position;
    let mut checked = 0;
    for i in 0..500 {
        for (x, y) in [(i, i), (i, 499 - i)] {
            let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            let hit = scene.intersect(&ray, f32::INFINITY).unwrap();
            let p = ray.at(hit.t);
            if (hit.prim as usize) >= 10
                || boxes
                    .iter()
                    .any(|&b| segment_hits_box(ray.origin, p, b) || segment_hits_box(p, light, b))
            {
                continue;
            }
            let want = analytic_direct(&scene, hit.prim, p);
            // One ray at a time, so that the value comes from the same triangle as
            // `hit` (the two walls tie here; a pixel quad may report the other).
            let got = sample_pixel(&scene, &cam, Integrator::Direct, x, y);
            assert!(
                ((got - want).abs() / want).max_element() < 1e-3,
                "pixel ({x}, {y}) on triangle {}: {got} vs {want}",
                hit.prim
            );
            checked += 1;
        }
    }
    assert!(checked > 400, "only {checked} edge pixels checked");
}

#[test]
fn same_seed_gives_identical_images_on_any_thread_count() {
    let scene = cornell::scene();
    let cam = lab_camera(96, 80);
    let settings = RenderSettings {
        integrator: Integrator::Direct,
        spp: 5,
        seed: 1234,
    };
    let one = render_with(&scene, &cam, settings, 1);
    for threads in [2, 3, 7] {
        let other = render_with(&scene, &cam, settings, threads);
        assert!(
            common::bit_identical(&one, &other),
            "{threads} threads differ from 1"
        );
    }
    // Another seed moves the jittered samples, so edge pixels change.
    let reseeded = render_with(
        &scene,
        &cam,
        RenderSettings {
            seed: 99,
            ..settings
        },
        2,
    );
    assert_ne!(one, reseeded);
}

#[test]
fn one_sample_goes_through_the_pixel_centre_and_flat_shows_reflectance() {
    let scene = cornell::scene();
    let cam = lab_camera(64, 48);
    // The lab's integrators (`path` jitters every sample, see tests/path.rs).
    for integrator in [Integrator::Flat, Integrator::Direct] {
        let settings = RenderSettings {
            integrator,
            ..RenderSettings::default()
        };
        let film = render(&scene, &cam, &settings, &|_| {}).film;
        for (y, x) in [(0, 0), (10, 31), (47, 63), (30, 5)] {
            assert_eq!(film.get(x, y), sample_pixel(&scene, &cam, integrator, x, y));
        }
    }
    // Flat: every pixel is exactly one of the seven reflectances, or black where
    // the wide image sees past the box's open front.
    let flat = render(
        &scene,
        &cam,
        &RenderSettings {
            integrator: Integrator::Flat,
            ..RenderSettings::default()
        },
        &|_| {},
    )
    .film;
    assert!(
        flat.pixels
            .iter()
            .all(|p| PALETTE.contains(p) || *p == Vec3A::ZERO)
    );
    // The bottom-centre pixel sees the floor.
    assert_eq!(flat.get(32, 47), colors::GREEN);
}

#[test]
fn progressive_refinement_matches_a_single_render() {
    let scene = cornell::scene();
    let cam = lab_camera(40, 30);
    let settings = RenderSettings {
        integrator: Integrator::Direct,
        spp: 6,
        seed: 5,
    };
    let whole = render(&scene, &cam, &settings, &|_| {}).film;
    let mut sums = Film::new(40, 30);
    for k in 0..6 {
        accumulate(
            &scene,
            &cam,
            settings.integrator,
            settings.seed,
            k..k + 1,
            &mut sums,
            &|_| {},
        );
    }
    sums.scale(1.0 / 6.0);
    // The one-shot render sums in f64, the viewer's one sample at a time in f32.
    for (a, b) in whole.pixels.iter().zip(&sums.pixels) {
        assert!(
            (*a - *b).abs().max_element() <= 1e-6 * a.max_element().max(1e-3),
            "{a} {b}"
        );
    }
}

#[test]
fn more_samples_antialias_edges() {
    // At 1 spp an edge pixel takes one side's colour; at 64 spp it blends.
    let scene = cornell::scene();
    let cam = lab_camera(50, 50);
    let flat = |spp| {
        render(
            &scene,
            &cam,
            &RenderSettings {
                integrator: Integrator::Flat,
                spp,
                seed: 0,
            },
            &|_| {},
        )
        .film
    };
    let (one, many) = (flat(1), flat(64));
    let blended = many.pixels.iter().filter(|p| {
        !PALETTE
            .iter()
            .any(|c| (**p - *c).abs().max_element() < 1e-6)
    });
    assert!(blended.count() > 100);
    // Away from edges the average equals the flat colour.
    assert!((many.get(25, 5) - one.get(25, 5)).abs().max_element() < 1e-6);
}

#[test]
fn many_samples_average_without_drift() {
    // Every sample of this view sees the left (purple) wall: the average of 20,000
    // equal values must be that value, which f32 running sums miss by ~1e-4.
    let scene = cornell::scene();
    let cam = Camera::lab(Vec3A::new(-0.8, 0.0, 0.0), -90.0, 0.0, 8, 8);
    let settings = RenderSettings {
        integrator: Integrator::Flat,
        spp: 20_000,
        seed: 3,
    };
    let film = render(&scene, &cam, &settings, &|_| {}).film;
    for p in &film.pixels {
        assert!((*p - colors::PURPLE).abs().max_element() < 1e-6, "{p}");
    }
}
