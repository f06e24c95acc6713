//! `--nan-check` and `raylab::nan_check`: the first non-finite sample of a
//! render, found by re-evaluating samples, is the first by brute force, and
//! the path vertex named is where the bad number entered.

use std::process::Command;

use glam::Vec3A;
use raylab::integrators::path::PathEvent;
use raylab::load::cornell;
use raylab::nan_check::first_bad_sample;
use raylab::render::{RenderSettings, probe_sample, render};
use raylab::{Camera, Integrator, PointLight, Scene};

fn box_camera(w: u32, h: u32) -> Camera {
    Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, w, h)
}

/// The lab box with a point light of absurd power just above the floor:
/// radiance over r² overflows to infinity for floor points right under it.
const HOT_LIGHT: Vec3A = Vec3A::new(0.0, 0.9999, 0.0);

fn box_with_hot_light() -> Scene {
    let (tris, rho) = cornell::triangles();
    Scene::new(
        tris,
        rho,
        PointLight {
            position: HOT_LIGHT,
            power: Vec3A::splat(3e38),
        },
        Vec3A::ZERO,
    )
    .unwrap()
}

#[test]
fn probing_a_sample_gives_the_renders_value_bit_for_bit() {
    let scene = cornell::area_scene();
    let camera = box_camera(24, 24);
    for seed in [0, 9] {
        let settings = RenderSettings {
            integrator: Integrator::path(),
            spp: 1,
            seed,
        };
        let image = render(&scene, &camera, &settings, &|_| {});
        for y in 0..24 {
            for x in 0..24 {
                let v = probe_sample(&scene, &camera, settings.integrator, seed, x, y, 0, &mut ());
                let p = image.film.pixels[(y * 24 + x) as usize];
                assert_eq!(
                    v.to_array().map(f32::to_bits),
                    p.to_array().map(f32::to_bits),
                    "pixel ({x}, {y}), seed {seed}"
                );
            }
        }
    }
}

#[test]
fn the_first_bad_sample_is_the_first_by_brute_force_and_names_its_vertex() {
    let scene = box_with_hot_light();
    let camera = box_camera(40, 32);
    let integrator = Integrator::path();
    let settings = RenderSettings {
        integrator,
        spp: 3,
        seed: 5,
    };
    let image = render(&scene, &camera, &settings, &|_| {});
    assert!(image.dropped > 0, "the light must spoil some samples");
    assert!(image.film.pixels.iter().all(|p| p.is_finite()));

    // Brute force: every sample in pixel order, then sample order.
    let mut expected = None;
    'scan: for y in 0..32 {
        for x in 0..40 {
            for s in 0..3 {
                let v = probe_sample(&scene, &camera, integrator, 5, x, y, s, &mut ());
                if !v.is_finite() {
                    expected = Some((x, y, s));
                    break 'scan;
                }
            }
        }
    }
    let bad = first_bad_sample(&scene, &camera, integrator, 5, 0..3).expect("a bad sample");
    assert_eq!(Some((bad.x, bad.y, bad.sample)), expected);
    assert!(!bad.value.is_finite());
    // The infinity enters with a light sample (radiance over pdf) at a floor
    // point right under the light.
    let vertex = bad.vertex.expect("the path vertex");
    let PathEvent::Light { li, .. } = vertex.event else {
        panic!("unexpected event {:?}", vertex.event);
    };
    assert!(!li.is_finite());
    assert!(vertex.beta.is_finite(), "the throughput was fine before it");
    let Some(PathEvent::Surface { point, .. }) = vertex.surface else {
        panic!("no surface recorded");
    };
    // Intensity P/(4π) over r² overflows f32 there.
    let r2 = f64::from(point.distance_squared(HOT_LIGHT));
    assert!(
        3e38 / (4.0 * std::f64::consts::PI) / r2 > f64::from(f32::MAX),
        "the bad vertex {point} is too far from the light to overflow"
    );

    // No NaN anywhere: nothing found.
    let clean = cornell::scene();
    assert_eq!(first_bad_sample(&clean, &camera, integrator, 5, 0..3), None);
}

#[test]
fn nan_check_reports_the_first_bad_sample_and_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    // A point light of absurd power almost on the floor: radiance over r²
    // overflows for the floor points under it.
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args([
            "render",
            "--integrator",
            "path",
            "--light-power",
            "3e38",
            "--light-pos",
            "0,0.9999,0",
            "--spp",
            "2",
            "--width",
            "48",
            "--height",
            "48",
            "-o",
            "box.exr",
            "--nan-check",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("nan-check: "))
        .unwrap_or_else(|| panic!("no nan-check line in {stderr}"));
    assert!(
        line.contains("first NaN/Inf sample: pixel (")
            && line.contains("sample ")
            && line.contains("seed 0"),
        "{line}"
    );
    assert!(line.contains("a light sample"), "{line}");
    // The image is still written, finite.
    let image = raylab::film::read_exr(&dir.path().join("box.exr")).unwrap();
    assert!(image.pixels.iter().all(|p| p.is_finite()));

    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args([
            "render",
            "--integrator",
            "path",
            "--spp",
            "2",
            "--width",
            "32",
            "--height",
            "32",
            "-o",
            "ok.png",
            "--nan-check",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("nan-check: no NaN/Inf samples in 2 spp"),
        "{stderr}"
    );
}
