//! Environment lighting: the mapping convention, importance sampling against
//! its density (χ²), HDR and EXR files, a furnace, and the sun patch that
//! importance sampling exists for.

mod common;
#[path = "common/sampling_scenes.rs"]
mod sampling_scenes;

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};
use raylab::film::{Film, rel_mse};
use raylab::lights::environment::{EnvMap, EnvSampling, Environment, direction_to_uv};
use raylab::lights::rgbe::{self, RgbImage};
use raylab::materials::surface::SurfaceMaterial;
use raylab::sampling::sampler::Rng;

use sampling_scenes::map_of;

/// The convention's direction of map point `(u, v)`, written out again here.
fn direction(u: f32, v: f32) -> Vec3A {
    let (phi, theta) = (2.0 * PI * (u - 0.5), PI * v);
    Vec3A::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    )
}

fn close(a: Vec3A, b: Vec3A, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol * b.abs().max_element().max(1.0)
}

#[test]
fn directions_find_their_texels_as_the_conventions_say() {
    let (w, h) = (8, 4);
    let env = Environment::map(map_of(w, h, |i, j| [i as f32, j as f32, 1.0]));
    for j in 0..h {
        for i in 0..w {
            let d = direction((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let got = env.radiance(d);
            assert!(
                close(got, Vec3A::new(i as f32, j as f32, 1.0), 1e-4),
                "texel ({i}, {j}): {got}"
            );
        }
    }
    // The named directions: −z is the centre, +x three quarters across, +y the top.
    let uv = |d: Vec3A| direction_to_uv(d);
    assert!((uv(Vec3A::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    assert!((uv(Vec3A::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    assert!((uv(Vec3A::NEG_X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
    assert!(uv(Vec3A::Y).y.abs() < 1e-6 && (uv(Vec3A::NEG_Y).y - 1.0).abs() < 1e-6);
    // Bilinear between texel centres, wrapping in u: halfway between the last
    // and the first column of row 1.
    let seam = env.radiance(direction(0.0, 1.5 / h as f32));
    assert!(close(seam, Vec3A::new(3.5, 1.0, 1.0), 1e-4), "{seam}");
    // Clamped in v: straight up is row 0 (mean of columns 3 and 4 at u = 0.5).
    assert!(close(
        env.radiance(Vec3A::new(0.0, 1.0, -1e-7).normalize()),
        Vec3A::new(3.5, 0.0, 1.0),
        1e-3
    ));
    // A 90° turn (counter-clockwise seen from above) brings +x's light to −z,
    // and strength scales it.
    let turned = env.clone().with_rotation(90.0).with_strength(2.0);
    for d in [Vec3A::X, Vec3A::new(0.3, 0.5, 0.8).normalize()] {
        let to = Vec3A::new(d.z, d.y, -d.x); // +x → −z
        assert!(
            close(turned.radiance(to), 2.0 * env.radiance(d), 1e-4),
            "{d}"
        );
    }
}

/// The power estimate's integral `∫ L dω`: 4πL for a uniform map, 2πL for a
/// sky that is bright above the horizon only (to the resolution of the map,
/// whose bilinear filter spreads the horizon's edge over one texel).
#[test]
fn the_radiance_integral_is_exact_for_simple_maps() {
    let uniform = Environment::map(map_of(64, 32, |_, _| [2.0, 2.0, 2.0]));
    let want = 8.0 * PI;
    assert!((uniform.radiance_integral() - want).abs() < 1e-3 * want);
    let sky = Environment::map(map_of(
        64,
        32,
        |_, j| if j < 16 { [1.0; 3] } else { [0.0; 3] },
    ));
    let want = 2.0 * PI;
    assert!(
        (sky.radiance_integral() - want).abs() < 1e-3 * want,
        "{}",
        sky.radiance_integral()
    );
    assert_eq!(
        Environment::constant(Vec3A::ONE)
            .with_strength(0.5)
            .radiance_integral(),
        2.0 * PI
    );
}

#[test]
fn importance_sampling_follows_its_density() {
    let (w, h) = (64, 32);
    let mut rng = Rng::for_sample(3, 1, 4);
    let noise: Vec<f32> = (0..w * h).map(|_| rng.next_f32()).collect();
    let map = map_of(w, h, |i, j| {
        let sun = if (40..43).contains(&i) && (9..11).contains(&j) {
            500.0
        } else {
            0.0
        };
        let sky = if j < h / 2 {
            1.0 + noise[j * w + i]
        } else {
            0.1 * noise[j * w + i]
        };
        [sky + sun, 0.5 * sky + sun, sky]
    });
    let env = Environment::map(map).with_rotation(30.0);
    // The density integrates to one over the sphere (midpoint rule on a grid
    // 64 times finer than the texels: the rotation puts texel edges inside the
    // grid's cells, and a coarser grid's error shows in the χ² below).
    let (nu, nv) = (4096, 2048);
    let mut integral = 0.0f64;
    for b in 0..nv {
        for a in 0..nu {
            let (u, v) = ((a as f32 + 0.5) / nu as f32, (b as f32 + 0.5) / nv as f32);
            let d_omega = 2.0 * PI * PI * (PI * v).sin() / (nu * nv) as f32;
            integral += (env.pdf(direction(u, v)) * d_omega) as f64;
        }
    }
    assert!((integral - 1.0).abs() < 2e-3, "∫ pdf dω = {integral}");
    // Samples against the density, in 32 × 16 bins of the (rotated) sphere.
    let (bu, bv) = (32, 16);
    let mut expected = vec![0.0f64; bu * bv];
    let (sub_u, sub_v) = (nu / bu, nv / bv);
    for b in 0..nv {
        for a in 0..nu {
            let (u, v) = ((a as f32 + 0.5) / nu as f32, (b as f32 + 0.5) / nv as f32);
            let d_omega = 2.0 * PI * PI * (PI * v).sin() / (nu * nv) as f32;
            expected[(b / sub_v) * bu + a / sub_u] += (env.pdf(direction(u, v)) * d_omega) as f64;
        }
    }
    let n = 400_000;
    let mut counts = vec![0u32; bu * bv];
    let mut edge_cases = 0;
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let (d, radiance, pdf) = env.sample(u).expect("a sample");
        assert!((d.length() - 1.0).abs() < 1e-5);
        // The density looked up again from the direction agrees, except where
        // rounding moves a sample on a texel's edge into its neighbour.
        if (pdf - env.pdf(d)).abs() > 1e-4 * pdf {
            edge_cases += 1;
        }
        assert!(close(radiance, env.radiance(d), 1e-3));
        let uv = direction_to_uv(d);
        let (a, b) = (
            ((uv.x * bu as f32) as usize).min(bu - 1),
            ((uv.y * bv as f32) as usize).min(bv - 1),
        );
        counts[b * bu + a] += 1;
    }
    assert!(
        edge_cases < n / 1000,
        "{edge_cases} samples disagree with pdf()"
    );
    let (mut chi2, mut dof) = (0.0, 0);
    let (mut pooled_e, mut pooled_c) = (0.0, 0.0);
    for (e, &c) in expected.iter().zip(&counts) {
        let e = e * n as f64;
        if e < 5.0 {
            pooled_e += e;
            pooled_c += c as f64;
            continue;
        }
        chi2 += (c as f64 - e).powi(2) / e;
        dof += 1;
    }
    if pooled_e > 0.0 {
        chi2 += (pooled_c - pooled_e).powi(2) / pooled_e.max(1.0);
        dof += 1;
    }
    // χ² with dof − 1 degrees of freedom: mean dof, sd √(2 dof); 5 sd is p < 1e-6.
    let bound = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
    eprintln!("χ² = {chi2:.1} over {dof} bins (bound {bound:.1})");
    assert!(chi2 < bound, "χ² = {chi2:.1} over {dof} bins");
    // The sun (6 of 2,048 texels) holds a fifth of the light: its bin gets a
    // fifth of the samples.
    let sun_share = expected.iter().cloned().fold(0.0, f64::max);
    eprintln!("{edge_cases} samples on texel edges; the sun's bin: {sun_share:.3}");
    assert!(sun_share > 0.2, "largest bin {sun_share}");
}

#[test]
fn hdr_and_exr_files_load_to_the_same_radiance() {
    let hdr = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/envmaps/venice_sunset_1k.hdr");
    let from_hdr = EnvMap::load(&hdr).expect("assets/envmaps holds the map");
    assert_eq!((from_hdr.width(), from_hdr.height()), (1024, 512));
    let dir = tempfile::tempdir().unwrap();
    // The same texels as OpenEXR (f32, exact) and again as Radiance HDR.
    let mut film = Film::new(1024, 512);
    for j in 0..512 {
        for i in 0..1024 {
            film.pixels[j * 1024 + i] = from_hdr.texel(i, j);
        }
    }
    let exr = dir.path().join("venice.exr");
    raylab::film::write_image(&film, &exr).unwrap();
    let again = dir.path().join("venice.hdr");
    let image = RgbImage {
        width: 1024,
        height: 512,
        pixels: film.pixels.iter().map(|p| p.to_array()).collect(),
    };
    rgbe::encode(&image, &mut std::fs::File::create(&again).unwrap()).unwrap();
    let a = Environment::load(&hdr).unwrap();
    for path in [&exr, &again] {
        let b = Environment::load(path).unwrap();
        let m = b.env_map().unwrap();
        for (i, j) in [(0, 0), (511, 100), (1023, 511), (700, 260)] {
            assert_eq!(
                m.texel(i, j),
                from_hdr.texel(i, j),
                "{} texel ({i}, {j})",
                path.display()
            );
        }
        let mut rng = Rng::for_sample(1, 1, 1);
        for _ in 0..1000 {
            let d = raylab::lights::environment::uniform_sphere(Vec2::new(
                rng.next_f32(),
                rng.next_f32(),
            ));
            assert_eq!(a.radiance(d), b.radiance(d));
            assert_eq!(a.pdf(d), b.pdf(d));
        }
    }
    // A sunset: the brightest texels are far brighter than 1 (HDR, decoded right).
    let max = (0..512 * 1024)
        .map(|k| from_hdr.texel(k % 1024, k / 1024).max_element())
        .fold(0.0, f32::max);
    assert!(max > 50.0, "brightest texel {max}");
    // Files that are not environment maps are refused with their name.
    let bad = dir.path().join("bad.hdr");
    std::fs::write(
        &bad,
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01\x01",
    )
    .unwrap();
    let err = Environment::load(&bad).unwrap_err().to_string();
    assert!(
        err.contains("bad.hdr") && err.contains("scanline 0"),
        "{err}"
    );
    let png = dir.path().join("sky.png");
    std::fs::write(&png, b"x").unwrap();
    assert!(
        Environment::load(&png)
            .unwrap_err()
            .to_string()
            .contains(".hdr or OpenEXR")
    );
}

fn mean(film: &Film) -> Vec3A {
    let sum: glam::DVec3 = film.pixels.iter().map(|p| p.as_dvec3()).sum();
    (sum / film.pixels.len() as f64).as_vec3a()
}

/// A white Lambertian sphere (convex: every point sees its whole upper
/// hemisphere) in a uniform environment of radiance L has radiance exactly L
/// everywhere, whatever the sampling: the furnace. Checked for a constant
/// environment and for a uniform map, which goes through importance sampling.
#[test]
fn white_sphere_in_a_uniform_environment_is_the_environment() {
    let l = Vec3A::new(0.8, 0.5, 0.25);
    let tris = common::sphere_triangles(Vec3A::ZERO, 1.0, 48, 24);
    let n = tris.len();
    let mut scene =
        common::two_sided_scene(tris, vec![0; n], vec![SurfaceMaterial::diffuse(Vec3A::ONE)]);
    let cam = common::look_camera(Vec3A::new(0.0, 0.5, 3.0), Vec3A::ZERO, 45.0, 32, 32);
    for env in [
        Environment::constant(l),
        Environment::map(map_of(16, 8, |_, _| [1.6, 1.0, 0.5])).with_strength(0.5),
    ] {
        scene.set_environment(env);
        let film = common::path_film(&scene, &cam, 64, 1);
        let m = mean(&film);
        let worst = film
            .pixels
            .iter()
            .map(|p| ((*p - l) / l).abs().max_element())
            .fold(0.0, f32::max);
        eprintln!(
            "furnace: mean {m} (L = {l}), worst pixel {:.1} % off",
            worst * 100.0
        );
        assert!(close(m, l, 4e-3), "mean {m} vs {l}");
        assert!(worst < 0.25, "a pixel is {:.0} % off", worst * 100.0);
    }
}

/// relMSE at equal samples: importance sampling the map against uniform
/// sphere sampling, the mean of three seeds each. Renders are bit-exact, so the
/// numbers are the same in every run; the time per sample (about equal for the
/// two) and the equal-time ratio are measured by `cargo bench --bench
/// sampling`, which times both in one run.
#[test]
fn a_sun_patch_converges_far_faster_with_importance_sampling() {
    let (mut scene, cam) = sampling_scenes::sun_patch();
    let reference = common::path_film(&scene, &cam, 1024, 99);
    let spp = 16;
    let mut errors = Vec::new();
    for sampling in [EnvSampling::Importance, EnvSampling::Uniform] {
        let env = scene.environment().clone().with_sampling(sampling);
        scene.set_environment(env);
        let e = (0..3)
            .map(|round| rel_mse(&common::path_film(&scene, &cam, spp, 7 + round), &reference))
            .sum::<f64>()
            / 3.0;
        eprintln!("{sampling:?}: relMSE {e:.3e} at {spp} spp");
        errors.push(e);
    }
    let ratio = errors[1] / errors[0];
    eprintln!("equal-sample relMSE: uniform / importance = {ratio:.1}");
    assert!(
        ratio >= EQUAL_SAMPLE_GAIN,
        "importance sampling is only {ratio:.1}× better at equal samples"
    );
    // And it converges to the right answer: the reference's mean matches an
    // independent importance-sampled render.
    scene.set_environment(
        scene
            .environment()
            .clone()
            .with_sampling(EnvSampling::Importance),
    );
    let check = common::path_film(&scene, &cam, 256, 1234);
    assert!(close(mean(&check), mean(&reference), 1e-2));
}

/// How much less relMSE importance sampling must give than uniform sampling
/// on the sun patch at equal samples (measured 1,765; the bench times the two
/// within 6 % of each other per sample and measures 1,666× at equal time).
const EQUAL_SAMPLE_GAIN: f64 = 100.0;

#[test]
fn environment_renders_are_bit_identical_on_any_thread_count() {
    let (scene, cam) = sampling_scenes::sun_patch();
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| common::path_film(&scene, &cam, 4, 3));
    let three = pool(3).install(|| common::path_film(&scene, &cam, 4, 3));
    assert!(common::bit_identical(&one, &three));
    assert!(mean(&one).max_element() > 0.0);
}

#[test]
fn command_line_environments() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| common::raylab(args, dir.path());
    let err = |o: &std::process::Output| String::from_utf8_lossy(&o.stderr).into_owned();
    // Far from the box, the corner pixels see the sky: exactly its radiance.
    let out = run(&[
        "render",
        "--integrator",
        "path",
        "--env-color",
        "0.25,0.5,0.75",
        "--env-strength",
        "2",
        "--camera-pos",
        "0,0,-30",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        "sky.exr",
    ]);
    assert!(out.status.success(), "{}", err(&out));
    let film = raylab::film::read_exr(&dir.path().join("sky.exr")).unwrap();
    assert_eq!(film.get(0, 0), Vec3A::new(0.5, 1.0, 1.5));
    // A map given by file, turned: loads and says so.
    let hdr = project_file("assets/envmaps/venice_sunset_1k.hdr");
    let out = run(&[
        "render",
        "--integrator",
        "path",
        "--env",
        &hdr,
        "--env-rotate",
        "90",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        "map.png",
    ]);
    assert!(out.status.success(), "{}", err(&out));
    // Mistakes: one line each, naming what is wrong.
    for (args, code, want) in [
        (
            &["render", "--env-strength", "2", "-o", "x.png"][..],
            1,
            "--env-strength",
        ),
        (
            &["render", "--env", "missing.hdr", "-o", "x.png"][..],
            1,
            "missing.hdr",
        ),
        (
            &["render", "--env-color", "1,2", "-o", "x.png"][..],
            2,
            "--env-color",
        ),
        (
            &["render", "--env-strength", "-1", "-o", "x.png"][..],
            2,
            "--env-strength",
        ),
        (
            &[
                "render",
                "--env",
                "a.hdr",
                "--env-color",
                "1,1,1",
                "-o",
                "x.png",
            ][..],
            2,
            "--env",
        ),
    ] {
        let out = run(args);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {}", err(&out));
        assert_eq!(
            err(&out).trim().lines().count(),
            1,
            "{args:?}: {}",
            err(&out)
        );
        assert!(err(&out).contains(want), "{args:?}: {}", err(&out));
    }
}

fn project_file(rel: &str) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(rel)
        .to_string_lossy()
        .into_owned()
}
