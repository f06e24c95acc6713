//! Adaptive sampling (`--noise-threshold`): pixels stop where the render's own
//! estimate of their error (two halves of their samples) is below the
//! threshold, decided at fixed sample counts from exact sums, so that the
//! image is the same on any number of threads, merged from tiles and resumed;
//! a stopped pixel's error is below the threshold; the `samples` and `half`
//! AOVs hold what was taken.

use std::path::Path;

use raylab::Integrator;
use raylab::aov::{Aov, AovSet, in_half};
use raylab::camera::Camera;
use raylab::load::cornell;
use raylab::render::{Accumulator, Adaptive, Passes, RenderSettings, adaptive, render_passes};

mod common;

fn raylab(args: &[&str], dir: &Path) -> (i32, String) {
    let out = common::raylab(args, dir);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(args: &[&str], dir: &Path) -> String {
    let (code, err) = raylab(args, dir);
    assert_eq!(code, 0, "raylab {args:?}: {err}");
    err
}

/// The lab's box lit by its ceiling patch (`cornell-area`), 48×36.
fn scene_and_camera() -> (raylab::Scene, Camera) {
    let scene = cornell::area_scene();
    let camera = Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, 48, 36);
    (scene, camera)
}

fn adaptive_render(spp: u32, threshold: f32, passes_at: &[u32]) -> Accumulator {
    let (scene, camera) = scene_and_camera();
    let aovs = adaptive::AOVS;
    let mut acc = Accumulator::new(camera.width, camera.height, aovs);
    // In stages (as a render stopped and resumed at these counts).
    for &cap in passes_at.iter().chain([&spp]) {
        let settings = RenderSettings {
            integrator: Integrator::path(),
            spp: cap,
            seed: 3,
        };
        let passes = Passes {
            adaptive: Some(Adaptive::new(threshold)),
            ..Passes::default()
        };
        render_passes(
            &scene,
            &camera,
            &settings,
            &mut acc,
            &passes,
            &mut |_, _| {},
            &|_| {},
        );
    }
    acc
}

#[test]
fn stopped_pixels_are_below_the_threshold_and_the_others_take_every_sample() {
    let threshold = 0.05;
    let a = Adaptive::new(threshold);
    assert_eq!(a.min_spp, 40);
    let spp = 200;
    let acc = adaptive_render(spp, threshold, &[]);
    let counts = acc.sample_counts().unwrap();
    let mean = acc.mean_spp();
    // Some stopped, some went on to the cap; every one at a check's count.
    assert!(counts.iter().all(|&c| c >= a.min_spp && c <= spp));
    assert!(counts.contains(&spp), "none took every sample");
    assert!(counts.iter().any(|&c| c < spp), "none stopped");
    assert!(
        mean > f64::from(a.min_spp) && mean < f64::from(spp),
        "{mean}"
    );
    for &c in &counts {
        assert!(c == spp || a.checks_at(c), "stopped at {c}");
    }
    // A stopped pixel's estimated error (Cycles' measure, from its two
    // halves), averaged over its neighbours in its row tile, was below the
    // threshold when it stopped: checked where the neighbours stopped at the
    // same count (their sums are still those the decision saw).
    let rendered = acc.rendered();
    let aovs = rendered.aovs.unwrap();
    let half = &aovs.layer(Aov::Half).unwrap().values;
    let error = |i: usize| {
        let (x, h) = (rendered.film.pixels[i], &half[4 * i..4 * i + 4]);
        let diff: f32 = (0..3).map(|c| (x[c] - h[c]).abs()).sum();
        diff / (1e-4 + x.element_sum().max(0.0).sqrt())
    };
    let (w, h) = (48usize, 36usize);
    let mut checked = 0;
    for (i, &n) in counts.iter().enumerate() {
        if n == spp {
            continue;
        }
        assert!(half[4 * i + 3] >= 1.0 && half[4 * i + 3] < n as f32);
        let (x, y) = (i % w, i / w);
        let neighbours: Vec<usize> = (y.saturating_sub(1)..=(y + 1).min(h - 1))
            .filter(|ny| ny / raylab::render::TILE_ROWS == y / raylab::render::TILE_ROWS)
            .flat_map(|ny| (x.saturating_sub(1)..=(x + 1).min(w - 1)).map(move |nx| ny * w + nx))
            .collect();
        if neighbours.iter().any(|&j| counts[j] != n) {
            continue;
        }
        let mean = neighbours.iter().map(|&j| error(j)).sum::<f32>() / neighbours.len() as f32;
        assert!(
            mean < threshold * 1.001,
            "pixel {i}: error {mean} after {n} samples"
        );
        checked += 1;
    }
    assert!(checked > 0);
    // The half holds one sample of each pair: half of each pixel's samples.
    for (i, &n) in counts.iter().enumerate() {
        assert_eq!(half[4 * i + 3], (n / 2) as f32, "pixel {i}");
    }
}

#[test]
fn a_render_resumed_between_and_at_checks_decides_as_one_run() {
    let whole = adaptive_render(160, 0.05, &[]);
    // Stopped at a check's count (40), between checks (47) and after
    // another check (72): each continuation makes the same decisions.
    let resumed = adaptive_render(160, 0.05, &[40, 47, 72]);
    assert_eq!(whole.image_sums(), resumed.image_sums());
    assert_eq!(whole.aov_sums(), resumed.aov_sums());
}

#[test]
fn adaptive_images_are_the_same_on_any_thread_count_merged_from_tiles_and_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let common = [
        "cornell-area",
        "--integrator",
        "path",
        "--width",
        "40",
        "--height",
        "32",
        "--spp",
        "96",
        "--noise-threshold",
        "0.1",
        "--seed",
        "5",
    ];
    let run = |extra: &[&str]| {
        let mut args = vec!["render"];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        ok(&args, d)
    };
    let said = run(&["--threads", "1", "-o", "one.exr", "--aov", "samples"]);
    assert!(said.contains("spp on average"), "{said}");
    run(&["--threads", "2", "-o", "two.exr", "--aov", "samples"]);
    let bytes = |name: &str| std::fs::read(d.join(name)).unwrap();
    assert_eq!(bytes("one.exr"), bytes("two.exr"));
    // The samples AOV: whole counts between the minimum and the cap.
    let channels = raylab::film::read_exr_channels(&d.join("one.exr")).unwrap();
    let counts = channels
        .channels
        .iter()
        .find(|c| c.name == "samples.N")
        .expect("a samples.N channel");
    assert!(
        counts
            .values
            .iter()
            .all(|&n| (32.0..=96.0).contains(&n) && n.fract() == 0.0)
    );
    assert!(counts.values.iter().any(|&n| n < 96.0));
    // Three tiles, merged: the same file.
    for k in 0..3 {
        let part = format!("part{k}.exr");
        run(&["--tile", &format!("{k}/3"), "-o", &part, "--aov", "samples"]);
    }
    ok(
        &[
            "merge",
            "part0.exr",
            "part1.exr",
            "part2.exr",
            "-o",
            "merged.exr",
        ],
        d,
    );
    assert_eq!(bytes("one.exr"), bytes("merged.exr"));
    // Sample ranges cannot be adaptive: refused in one line.
    let (code, err) = raylab(
        &[
            "render",
            "--spp",
            "64",
            "--samples",
            "0..32",
            "--noise-threshold",
            "0.1",
            "-o",
            "p.exr",
        ],
        d,
    );
    assert_ne!(code, 0);
    assert!(
        err.contains("--noise-threshold") && err.trim().lines().count() == 1,
        "{err}"
    );
}

#[test]
fn a_scene_files_noise_threshold_is_used_and_a_bad_one_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = |t: &str| {
        format!(
            "[render]\nspp = 64\nintegrator = \"path\"\nwidth = 24\nheight = 16\nnoise_threshold = {t}\n\n\
             [[model]]\nbuiltin = \"cornell-area\"\n"
        )
    };
    std::fs::write(d.join("good.toml"), scene("0.2")).unwrap();
    let said = ok(&["render", "good.toml", "-o", "good.png"], d);
    assert!(said.contains("spp on average"), "{said}");
    std::fs::write(d.join("bad.toml"), scene("0")).unwrap();
    let (code, err) = raylab(&["render", "bad.toml", "-o", "bad.png"], d);
    assert_ne!(code, 0);
    assert!(
        err.contains("bad.toml") && err.contains("noise_threshold"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn each_pair_of_samples_gives_one_to_the_half_and_the_choice_is_not_the_parity() {
    let mut odd_in_half = 0;
    for pixel in 0..200u64 {
        for k in 0..50u32 {
            let (even, odd) = (in_half(9, pixel, 2 * k), in_half(9, pixel, 2 * k + 1));
            assert!(even != odd, "pixel {pixel}, pair {k}");
            odd_in_half += u32::from(odd);
        }
    }
    // About half of the odd samples (10,000 pairs: 5,000 ± 3σ = ± 150).
    assert!((4850..=5150).contains(&odd_in_half), "{odd_in_half}");
}

#[test]
fn the_half_of_a_render_without_adaptive_sampling_is_counted_exactly() {
    let (scene, camera) = scene_and_camera();
    let set = AovSet::new(&[Aov::Half]).unwrap();
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp: 7,
        seed: 1,
    };
    let rendered = raylab::render::render_with_aovs(&scene, &camera, &settings, set, &|_| {});
    let aovs = rendered.aovs.unwrap();
    let half = &aovs.layer(Aov::Half).unwrap().values;
    let width = camera.width as u64;
    for (i, n) in half.iter().skip(3).step_by(4).enumerate() {
        // Three whole pairs, and sample 6 if the hash gives it to the half.
        let expect = 3 + u32::from(in_half(1, i as u64, 6));
        assert_eq!(
            *n,
            expect as f32,
            "pixel {} {}",
            i as u64 % width,
            i as u64 / width
        );
    }
}
