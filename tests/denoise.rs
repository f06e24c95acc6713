//! Denoising: the guides on scenes whose answer is known without the
//! renderer (a mirror showing a coloured wall, glass in front of one, the
//! sky), the variance AOV against the samples it summarises, and then Open
//! Image Denoise itself: the lab box denoised against Mitsuba's reference,
//! the EXR's layers, `merge --denoise` against `render --denoise`, the same
//! bits on any thread count, and the one-line error without the library.
//!
//! The tests that need OIDN look for it as raylab does (`RAYLAB_OIDN`, the
//! system, `pip install pyoidn`); without it they say so on stderr and pass,
//! unless `RAYLAB_REQUIRE_OIDN=1` (set by `.ci/run`, which installs it), when
//! they fail.

#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;
mod common;

use std::path::Path;

use builder::{Gltf, U16};
use glam::Vec3A;
use raylab::aov::{Aov, AovSet};
use raylab::camera::{Lens, Y_UP_TOWARDS_MINUS_Z};
use raylab::denoise::{DenoiseOptions, Denoiser, GUIDES};
use raylab::film::{read_exr, read_exr_channels, read_exr_metadata, rel_mse};
use raylab::load::cornell;
use raylab::render::{RenderSettings, Rendered, render_with_aovs};
use raylab::{Camera, Integrator, Scene};
use serde_json::json;

/// A denoiser if OIDN can be loaded; `None` (said on stderr) if not, unless
/// the environment requires it.
fn denoiser(threads: usize) -> Option<Denoiser> {
    let options = DenoiseOptions {
        threads,
        ..DenoiseOptions::default()
    };
    match Denoiser::new(&options) {
        Ok(d) => Some(d),
        Err(e) if std::env::var_os("RAYLAB_REQUIRE_OIDN").is_some_and(|v| v == "1") => {
            panic!("RAYLAB_REQUIRE_OIDN=1 but {e}")
        }
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

fn render(scene: &Scene, camera: &Camera, spp: u32, aovs: AovSet, threads: usize) -> Rendered {
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp,
        seed: 3,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render_with_aovs(scene, camera, &settings, aovs, &|_| {}))
}

fn vec3(v: &[f32]) -> Vec3A {
    Vec3A::new(v[0], v[1], v[2])
}

#[track_caller]
fn assert_near(got: Vec3A, want: Vec3A, tol: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

/// A quad primitive over `corners` (counter-clockwise seen from its front).
fn quad(g: &mut Gltf, corners: [[f32; 3]; 4], material: usize) -> serde_json::Value {
    let pos = g.floats(&corners);
    let idx = g.indices(U16, &[0, 1, 2, 0, 2, 3]);
    json!({ "attributes": { "POSITION": pos }, "indices": idx, "material": material })
}

/// A rough dielectric of colour `c` without a specular layer
/// (`KHR_materials_specular` 0): its albedo is exactly `c`.
fn matte(g: &mut Gltf, c: Vec3A) -> usize {
    g.material(json!({
        "pbrMetallicRoughness": {
            "baseColorFactor": [c.x, c.y, c.z, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 1.0 },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } } }))
}

/// Loads a glTF written by `g`, with the extensions its materials use.
fn load(g: &mut Gltf, dir: &Path, extensions: &[&str]) -> Scene {
    g.extensions_used = extensions.iter().map(|e| e.to_string()).collect();
    let path = g.write(dir, "scene.gltf");
    // No default sky: what escapes sees black.
    let options = raylab::load::LoadOptions {
        default_light: raylab::load::DefaultLight::Off,
        ..Default::default()
    };
    raylab::load::load(path.to_str().unwrap(), &options)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene
}

/// An orthographic camera at `(0, 0, 5)` looking along −z at a small patch
/// around the axis.
fn front_camera() -> Camera {
    let lens = Lens::Orthographic { half_height: 0.2 };
    Camera::with_lens(Vec3A::new(0.0, 0.0, 5.0), Y_UP_TOWARDS_MINUS_Z, lens, 8, 6)
}

const WALL_COLOUR: Vec3A = Vec3A::new(0.8, 0.3, 0.1);

#[test]
fn a_mirror_gives_the_albedo_and_normal_of_the_wall_it_shows() {
    let dir = tempfile::tempdir().unwrap();
    // A polished white metal in the plane z = x, facing (−1, 0, 1): the
    // camera's rays (−z) leave it along −x, towards a matte wall in the
    // plane x = −3 that faces +x and that the camera does not see.
    let polished = json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0 } });
    let scene = metal_and_wall(dir.path(), polished);
    let aovs = render(&scene, &front_camera(), 4, GUIDES, 1).aovs.unwrap();
    for (x, y) in [(0, 0), (4, 3), (7, 5)] {
        let what = format!("pixel ({x}, {y})");
        // The mirror reflects all (Schlick of a white metal is 1).
        assert_near(
            vec3(aovs.get(Aov::Albedo, x, y).unwrap()),
            WALL_COLOUR,
            1e-5,
            &what,
        );
        // The wall's normal, facing the reflected ray.
        assert_near(
            vec3(aovs.get(Aov::Normal, x, y).unwrap()),
            Vec3A::X,
            1e-5,
            &what,
        );
    }
    // Through a rough metal (roughness 0.6, α = 0.36 > 0.075) the guides
    // stop at the metal itself: its own tint and normal.
    let rough = json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.6 } });
    let scene = metal_and_wall(dir.path(), rough);
    let aovs = render(&scene, &front_camera(), 4, GUIDES, 1).aovs.unwrap();
    // Schlick at 45°: 0.9 + 0.1 (1 − cos 45°)⁵.
    let tint = 0.9 + 0.1 * (1.0 - std::f32::consts::FRAC_1_SQRT_2).powi(5);
    assert_near(
        vec3(aovs.get(Aov::Albedo, 4, 3).unwrap()),
        Vec3A::splat(tint),
        1e-5,
        "rough",
    );
    let n = Vec3A::new(-1.0, 0.0, 1.0).normalize();
    assert_near(
        vec3(aovs.get(Aov::Normal, 4, 3).unwrap()),
        n,
        1e-5,
        "rough normal",
    );
}

/// A square of the metal `metal` (a glTF material) in the plane z = x,
/// facing (−1, 0, 1), and a matte wall of [`WALL_COLOUR`] in the plane
/// x = −3, facing +x.
fn metal_and_wall(dir: &Path, metal: serde_json::Value) -> Scene {
    let mut g = Gltf::new();
    let metal = g.material(metal);
    let wall = matte(&mut g, WALL_COLOUR);
    let prims = vec![
        quad(
            &mut g,
            [
                [-1.0, -1.0, -1.0],
                [1.0, -1.0, 1.0],
                [1.0, 1.0, 1.0],
                [-1.0, 1.0, -1.0],
            ],
            metal,
        ),
        quad(
            &mut g,
            [
                [-3.0, -2.0, 3.0],
                [-3.0, -2.0, -3.0],
                [-3.0, 2.0, -3.0],
                [-3.0, 2.0, 3.0],
            ],
            wall,
        ),
    ];
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    load(&mut g, dir, &["KHR_materials_specular"])
}

#[test]
fn glass_gives_the_wall_behind_it_weighed_by_what_gets_through() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // A slab of clear glass (a volume, IOR 1.5) from z = −0.5 to 0.5, seen
    // head-on, in front of a matte wall at z = −3 facing the camera.
    let glass = g.material(json!({
        "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
        "extensions": {
            "KHR_materials_transmission": { "transmissionFactor": 1.0 },
            "KHR_materials_volume": { "thicknessFactor": 1.0 } } }));
    let wall = matte(&mut g, WALL_COLOUR);
    let prims = vec![
        quad(
            &mut g,
            [
                [-1.0, -1.0, 0.5],
                [1.0, -1.0, 0.5],
                [1.0, 1.0, 0.5],
                [-1.0, 1.0, 0.5],
            ],
            glass,
        ),
        quad(
            &mut g,
            [
                [-1.0, -1.0, -0.5],
                [-1.0, 1.0, -0.5],
                [1.0, 1.0, -0.5],
                [1.0, -1.0, -0.5],
            ],
            glass,
        ),
        quad(
            &mut g,
            [
                [-3.0, -3.0, -3.0],
                [3.0, -3.0, -3.0],
                [3.0, 3.0, -3.0],
                [-3.0, 3.0, -3.0],
            ],
            wall,
        ),
    ];
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    let scene = load(
        &mut g,
        dir.path(),
        &[
            "KHR_materials_specular",
            "KHR_materials_transmission",
            "KHR_materials_volume",
        ],
    );
    let aovs = render(&scene, &front_camera(), 4, GUIDES, 2).aovs.unwrap();
    // Head-on, F0 = 0.04: the front face reflects 0.04 towards the black sky
    // and lets 0.96 in; inside, the back face's reflection (0.04) and
    // transmission (0.96) together carry all of it on to the wall.
    for (x, y) in [(0, 0), (4, 3)] {
        let what = format!("pixel ({x}, {y})");
        assert_near(
            vec3(aovs.get(Aov::Albedo, x, y).unwrap()),
            0.96 * WALL_COLOUR,
            1e-5,
            &what,
        );
        // The wall's normal, by the share that went through.
        assert_near(
            vec3(aovs.get(Aov::Normal, x, y).unwrap()),
            0.96 * Vec3A::Z,
            1e-5,
            &what,
        );
    }
}

#[test]
fn the_sky_is_squashed_into_the_albedo_and_has_no_normal() {
    // Nothing but a constant sky of radiance 1: every camera ray escapes.
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let wall = matte(&mut g, WALL_COLOUR);
    let prims = vec![quad(
        &mut g,
        [
            [50.0, 50.0, 0.0],
            [51.0, 50.0, 0.0],
            [51.0, 51.0, 0.0],
            [50.0, 51.0, 0.0],
        ],
        wall,
    )];
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    g.extensions_used = vec!["KHR_materials_specular".into()];
    let path = g.write(dir.path(), "sky.gltf");
    let options = raylab::load::LoadOptions {
        environment: raylab::load::EnvironmentOptions {
            source: Some(raylab::load::EnvSource::Color(Vec3A::splat(1.0))),
            ..Default::default()
        },
        ..Default::default()
    };
    let scene = raylab::load::load(path.to_str().unwrap(), &options)
        .unwrap()
        .scene;
    let aovs = render(&scene, &front_camera(), 2, GUIDES, 1).aovs.unwrap();
    // L/(1 + L) of radiance 1.
    assert_near(
        vec3(aovs.get(Aov::Albedo, 3, 3).unwrap()),
        Vec3A::splat(0.5),
        1e-6,
        "sky",
    );
    assert_eq!(vec3(aovs.get(Aov::Normal, 3, 3).unwrap()), Vec3A::ZERO);
    assert_eq!(aovs.coverage[0], 0.0, "no sample hit a surface");
}

#[test]
fn the_variance_aov_is_the_variance_of_the_pixels_mean() {
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 12, 10);
    let spp = 16;
    let set: AovSet = "variance".parse().unwrap();
    let rendered = render(&scene, &camera, spp, set, 2);
    let aovs = rendered.aovs.unwrap();
    let lum = |c: Vec3A| f64::from(c.dot(Vec3A::new(0.2126, 0.7152, 0.0722)));
    let mut checked = 0;
    for y in 0..camera.height {
        for x in 0..camera.width {
            // The pixel's samples, each exactly as the render computed it.
            let values: Vec<f64> = (0..spp)
                .map(|s| {
                    let v = raylab::render::probe_sample(
                        &scene,
                        &camera,
                        Integrator::path(),
                        3,
                        x,
                        y,
                        s,
                        &mut (),
                    );
                    lum(v)
                })
                .collect();
            let n = f64::from(spp);
            let mean = values.iter().sum::<f64>() / n;
            let sample_variance =
                values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let want = sample_variance / n;
            let got = f64::from(aovs.get(Aov::Variance, x, y).unwrap()[0]);
            assert!(
                (got - want).abs() <= 1e-4 * want + 1e-12,
                "pixel ({x}, {y}): {got} against {want}"
            );
            checked += usize::from(want > 0.0);
        }
    }
    assert!(checked > 60, "{checked} pixels with noise");
    // With one sample the variance is unknown.
    let one = render(&scene, &camera, 1, set, 1).aovs.unwrap();
    assert!(one.layers[0].values.iter().all(|v| v.is_infinite()));
}

#[test]
fn the_denoised_lab_box_at_4_spp_is_ten_times_closer_to_mitsuba() {
    let Some(mut denoiser) = denoiser(0) else {
        return;
    };
    let reference = common::reference_image("cornell-path-mitsuba-256.exr");
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 256, 256);
    let rendered = render(&scene, &camera, 4, GUIDES, 2);
    let noisy = rel_mse(&rendered.film, &reference);
    let clean = denoiser
        .denoise(&rendered.film, rendered.aovs.as_ref().unwrap())
        .unwrap();
    let denoised = rel_mse(&clean, &reference);
    eprintln!("relMSE against Mitsuba: noisy {noisy:.3e}, denoised {denoised:.3e}");
    assert!(
        denoised * 10.0 <= noisy,
        "noisy {noisy:.3e}, denoised {denoised:.3e}"
    );
}

#[test]
fn the_guarded_image_is_never_worse_than_the_noisy_one_from_few_samples_to_many() {
    let Some(mut denoiser) = denoiser(0) else {
        return;
    };
    let reference = common::reference_image("cornell-path-mitsuba-256.exr");
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 256, 256);
    for spp in [2, 16, 128] {
        let rendered = render(&scene, &camera, spp, GUIDES, 2);
        let guarded = denoiser
            .denoise_guarded(&rendered.film, rendered.aovs.as_ref().unwrap())
            .unwrap();
        let check = guarded
            .check
            .as_ref()
            .expect("two halves from two samples on");
        assert_eq!(check.halves.iter().filter(|h| h.is_none()).count(), 0);
        let noisy = rel_mse(&rendered.film, &reference);
        let out = rel_mse(&guarded.image, &reference);
        let unguarded = rel_mse(&guarded.denoised, &reference);
        let weights = guarded.weights.unwrap();
        let mean = weights.iter().map(|&w| f64::from(w)).sum::<f64>() / weights.len() as f64;
        eprintln!(
            "{spp} spp: relMSE against Mitsuba noisy {noisy:.3e}, denoised {unguarded:.3e}, \
             guarded {out:.3e} (mean weight {mean:.2})"
        );
        assert!(
            out <= noisy * 1.002,
            "{spp} spp: noisy {noisy:.3e}, guarded {out:.3e}"
        );
    }
}

#[test]
fn denoised_images_are_the_same_on_any_thread_count() {
    let Some(mut one) = denoiser(1) else {
        return;
    };
    let mut two = denoiser(2).unwrap();
    let scene = cornell::scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 96, 72);
    let a = render(&scene, &camera, 8, GUIDES, 1);
    let b = render(&scene, &camera, 8, GUIDES, 3);
    assert!(common::bit_identical(&a.film, &b.film));
    assert_eq!(a.aovs, b.aovs);
    let da = one.denoise(&a.film, a.aovs.as_ref().unwrap()).unwrap();
    let db = two.denoise(&b.film, b.aovs.as_ref().unwrap()).unwrap();
    assert!(common::bit_identical(&da, &db), "OIDN on 1 and 2 threads");
    // And again on the same denoiser (its filter is reused).
    let again = one.denoise(&a.film, a.aovs.as_ref().unwrap()).unwrap();
    assert!(common::bit_identical(&da, &again));
    assert!(
        !common::bit_identical(&da, &a.film),
        "something was denoised"
    );
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const BOX: [&str; 8] = [
    "render",
    "--integrator",
    "path",
    "--spp",
    "4",
    "--width",
    "48",
    "--height=36",
];

#[test]
fn without_the_library_denoise_is_one_line_and_nothing_is_rendered() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    for args in [
        [&BOX[..], &["--denoise", "-o", "x.png"]].concat(),
        vec!["merge", "--denoise", "part.exr", "-o", "x.exr"],
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(&args)
            .current_dir(dir.path())
            .env("RAYLAB_OIDN", &empty)
            .env_remove("DISPLAY")
            .output()
            .unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        for needle in [
            "--denoise",
            "Open Image Denoise",
            "pip install pyoidn",
            "RAYLAB_OIDN",
        ] {
            assert!(err.contains(needle), "{needle}: {err}");
        }
        assert!(!dir.path().join("x.png").exists() && !dir.path().join("x.exr").exists());
    }
}

#[test]
fn the_exr_holds_the_denoised_image_the_noisy_one_and_the_aovs_asked_for() {
    if denoiser(0).is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let args = [&BOX[..], &["--denoise", "--aov", "depth", "-o", "x.exr"]].concat();
    let out = common::raylab(&args, dir.path());
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("; denoised in ") && err.contains(" by OIDN 2."),
        "{err}"
    );
    let exr = read_exr_channels(&dir.path().join("x.exr")).unwrap();
    // The guides and the variance were gathered but not asked for.
    assert_eq!(
        exr.names(),
        ["B", "G", "R", "depth.Z", "noisy.B", "noisy.G", "noisy.R"]
    );
    let changed = exr
        .get("R")
        .unwrap()
        .iter()
        .zip(exr.get("noisy.R").unwrap())
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 48 * 36 / 2, "{changed} pixels denoised");
    let meta = read_exr_metadata(&dir.path().join("x.exr")).unwrap();
    assert!(format!("{meta:?}").contains("denoised=1"), "{meta:?}");
    // The noisy layer is the image `render` writes without --denoise.
    let plain = [&BOX[..], &["-o", "plain.exr"]].concat();
    assert!(common::raylab(&plain, dir.path()).status.success());
    let plain = read_exr(&dir.path().join("plain.exr")).unwrap();
    let noisy: Vec<f32> = exr.get("noisy.R").unwrap().to_vec();
    let red: Vec<f32> = plain.pixels.iter().map(|p| p.x).collect();
    assert_eq!(noisy, red);
    // A scene file can ask for it too.
    std::fs::write(
        dir.path().join("box.toml"),
        "[render]\nwidth = 48\nheight = 36\nspp = 4\nintegrator = \"path\"\ndenoise = true\n\n[[model]]\nbuiltin = \"cornell\"\n",
    )
    .unwrap();
    let out = common::raylab(&["render", "box.toml", "-o", "file.exr"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let exr = read_exr_channels(&dir.path().join("file.exr")).unwrap();
    assert!(exr.get("noisy.R").is_some(), "{:?}", exr.names());
    // ... which the command line turns off.
    let out = common::raylab(
        &["render", "box.toml", "--denoise=false", "-o", "off.exr"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let exr = read_exr_channels(&dir.path().join("off.exr")).unwrap();
    assert_eq!(exr.names(), ["B", "G", "R"]);
}

#[test]
fn merge_denoise_equals_render_denoise_bit_for_bit() {
    if denoiser(0).is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str]| {
        let args = [&BOX[..], &["--denoise", "--seed", "7"], extra].concat();
        let out = common::raylab(&args, dir.path());
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        out
    };
    run(&["-o", "whole.exr"]);
    run(&["--threads", "1", "-o", "whole1.exr"]);
    run(&["--tile", "0/3", "-o", "a.exr"]);
    let part = run(&["--tile", "1/3", "-o", "b.exr"]);
    assert!(
        stderr(&part).contains("with the guides for `raylab merge --denoise`"),
        "{}",
        stderr(&part)
    );
    run(&["--tile", "2/3", "-o", "c.exr"]);
    let out = common::raylab(
        &[
            "merge",
            "--denoise",
            "a.exr",
            "b.exr",
            "c.exr",
            "-o",
            "merged.exr",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("denoised in"), "{}", stderr(&out));
    let bytes = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert!(
        bytes("whole.exr") == bytes("merged.exr"),
        "merge --denoise differs"
    );
    assert!(
        bytes("whole.exr") == bytes("whole1.exr"),
        "--threads 1 differs"
    );
    // The parts remember that they are of a --denoise render: a plain merge
    // (a farm's) denoises too, and --denoise=false does not.
    let out = common::raylab(
        &["merge", "a.exr", "b.exr", "c.exr", "-o", "plain.exr"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        bytes("whole.exr") == bytes("plain.exr"),
        "a plain merge differs"
    );
    let out = common::raylab(
        &[
            "merge",
            "--denoise=false",
            "a.exr",
            "b.exr",
            "c.exr",
            "-o",
            "noisy.exr",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let noisy = read_exr(&dir.path().join("noisy.exr")).unwrap();
    let whole = read_exr_channels(&dir.path().join("whole.exr")).unwrap();
    let red: Vec<f32> = noisy.pixels.iter().map(|p| p.x).collect();
    assert_eq!(whole.get("noisy.R").unwrap(), red.as_slice());
    // Parts without the guides cannot be denoised: one line.
    let plain = [&BOX[..], &["--tile", "0/1", "-o", "part.exr"]].concat();
    assert!(common::raylab(&plain, dir.path()).status.success());
    let out = common::raylab(
        &["merge", "--denoise", "part.exr", "-o", "p.exr"],
        dir.path(),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("render them with --denoise"), "{err}");
}
