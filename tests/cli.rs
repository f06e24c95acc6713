//! The `raylab` command as users and scripts drive it: exit codes, one-line
//! messages, output formats and atomic writes.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

mod common;

use common::raylab;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn bad_arguments_exit_2_with_one_line_naming_the_argument() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["render", "--integrator", "bogus"], "--integrator"),
        (
            &["render", "--integrator", "path", "--max-depth", "0"],
            "--max-depth",
        ),
        (&["render", "--max-depth", "-1"], "--max-depth"),
        (&["render", "--max-depth", "nan"], "--max-depth"),
        (&["render", "--time", "0"], "--time"),
        (&["render", "--time", "-2"], "--time"),
        (&["render", "--noise-threshold", "0"], "--noise-threshold"),
        (&["render", "--noise-threshold", "1.5"], "--noise-threshold"),
        (&["render", "--noise-threshold", "nan"], "--noise-threshold"),
        (&["render", "--exposure", "nan"], "--exposure"),
        (&["render", "--material", "wall=mirror"], "--material"),
        (&["render", "--material", "tall=plastic"], "--material"),
        (&["render", "--material", "floor=gold:2"], "--material"),
        (&["render", "--material", "tall"], "--material"),
        (&["render", "--sampler", "halton"], "--sampler"),
        (&["render", "--width", "0"], "--width"),
        (&["render", "--height", "-5"], "--height"),
        (&["render", "--width", "100000"], "--width"),
        (&["render", "--spp", "0"], "--spp"),
        (&["render", "--camera-pos", "1,2"], "--camera-pos"),
        (&["render", "--camera-pos", "NaN,0,0"], "--camera-pos"),
        (&["render", "--light-pos", "0,inf,0"], "--light-pos"),
        (&["render", "--yaw", "nan"], "--yaw"),
        (&["render", "--pitch", "95"], "--pitch"),
        (&["render", "--light-power", "-1"], "--light-power"),
        (&["render", "--threads", "0"], "--threads"),
        (&["render", "--spp", "-3"], "--spp"),
        (&["render", "--seed", "-1"], "--seed"),
        (&["render", "--ambient", "-0.5"], "--ambient"),
        (&["render", "--bogus"], "--bogus"),
        (&["view", "--width", "0"], "--width"),
        (
            &["render", "--width", "16000", "--height", "16000"],
            "--width",
        ),
        (&["frobnicate"], "frobnicate"),
    ];
    for (args, name) in cases {
        let out = raylab(args, dir.path());
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(name),
            "{args:?}: {err}"
        );
    }
    // Nothing was written by any of them.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn runtime_failures_exit_1_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["render", "-o", "no/such/dir/x.png"], "no/such/dir/x.png"),
        (&["render", "-o", "picture.jpg"], "picture.jpg"),
        (&["render", "nosuchscene"], "nosuchscene"),
        (&["view"], "display"),
    ];
    for (args, needle) in cases {
        let out = raylab(args, dir.path());
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(needle),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn render_writes_the_default_png_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(&["render", "--width", "64", "--height", "48"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    // One summary line with size, integrator, spp, time, rays and speed.
    assert_eq!(err.lines().count(), 1, "{err}");
    for needle in [
        "cornell.png",
        "64x48",
        "direct",
        "1 spp",
        " ms",
        "rays",
        "Mrays/s",
    ] {
        assert!(err.contains(needle), "{needle} missing from {err}");
    }
    let img = image::open(dir.path().join("cornell.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // Quiet prints nothing; only the output file is left in the folder.
    let out = raylab(&["render", "--quiet", "-o", "q.png"], dir.path());
    assert!(out.status.success() && out.stderr.is_empty());
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["cornell.png", "q.png"]);
}

#[test]
fn exr_holds_the_linear_values_unchanged_and_png_the_srgb_encoding() {
    use raylab::render::{RenderSettings, render};
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "render",
        "--width",
        "40",
        "--height",
        "30",
        "--spp",
        "3",
        "--seed",
        "7",
        "--camera-pos=-0.3,0.2,-2",
        "--yaw",
        "-10",
        "--pitch",
        "5",
        "--light-pos",
        "0.2,-0.6,-0.5",
        "--light-power",
        "20",
        "--ambient",
        "0.25",
        "--threads",
        "1",
    ];
    for file in ["a.exr", "a.png"] {
        let mut all = args.to_vec();
        all.extend(["-o", file, "--quiet"]);
        let out = raylab(&all, dir.path());
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let mut scene = raylab::load::cornell::scene();
    scene.light.position = glam::Vec3A::new(0.2, -0.6, -0.5);
    scene.light.power = glam::Vec3A::splat(20.0);
    scene.ambient = glam::Vec3A::splat(0.25);
    let cam = raylab::Camera::lab(glam::Vec3A::new(-0.3, 0.2, -2.0), -10.0, 5.0, 40, 30);
    let settings = RenderSettings {
        spp: 3,
        seed: 7,
        ..RenderSettings::default()
    };
    let want = render(&scene, &cam, &settings, &|_| {}).film;
    let exr = raylab::film::read_exr(&dir.path().join("a.exr")).unwrap();
    assert_eq!(exr, want);
    let png = image::open(dir.path().join("a.png")).unwrap().to_rgb8();
    assert_eq!(
        png.as_raw(),
        &want.to_srgb8(raylab::film::Display::clamped(1.0))
    );
}

#[test]
fn an_interrupted_render_leaves_the_old_image_and_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("big.png");
    std::fs::write(&target, b"the earlier image").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args([
            "render", "-o", "big.png", "--width", "4000", "--height", "4000", "--spp", "64",
        ])
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the render should still be running"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"the earlier image");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn help_and_version_exit_0() {
    let dir = tempfile::tempdir().unwrap();
    for args in [&["--help"][..], &["render", "--help"], &["--version"]] {
        let out = raylab(args, dir.path());
        assert_eq!(out.status.code(), Some(0));
        assert!(!out.stdout.is_empty());
    }
    let help = String::from_utf8(raylab(&["render", "--help"], dir.path()).stdout).unwrap();
    for flag in [
        "--width",
        "--height",
        "--integrator",
        "--spp",
        "--seed",
        "--threads",
        "--camera-pos",
        "--yaw",
        "--pitch",
        "--light-pos",
        "--light-power",
        "--ambient",
        "--quiet",
        "--output",
    ] {
        assert!(help.contains(flag), "{flag}");
    }
}

#[test]
fn without_a_display_the_default_command_renders_and_explains() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(&[], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.path().join("cornell.png").exists());
    let err = stderr(&out);
    assert!(
        err.contains("cornell.png") && err.contains("raylab view"),
        "{err}"
    );
}

/// A small closed mesh: a unit tetrahedron at the origin.
fn write_tetrahedron(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("tet.obj");
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    path
}

#[test]
fn bench_prints_key_value_lines_and_writes_hits() {
    let dir = tempfile::tempdir().unwrap();
    write_tetrahedron(dir.path());
    // Two rays: one through the tetrahedron's base (prim 0) and one past it.
    let rays: Vec<f32> = vec![0.2, 0.2, -1.0, 0.0, 0.0, 1.0, 5.0, 5.0, -1.0, 0.0, 0.0, 1.0];
    let bytes: Vec<u8> = rays.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(dir.path().join("r.rays"), bytes).unwrap();
    let out = raylab(
        &[
            "bench",
            "tet.obj",
            "--rays",
            "r.rays",
            "--hits",
            "h.bin",
            "--threads",
            "1,2",
            "--repeat",
            "2",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(
        lines[0].starts_with("build triangles=4 build_ms=")
            && lines[0].contains("bytes_per_triangle=")
    );
    for (line, threads) in lines[1..].iter().zip([1, 2]) {
        assert!(
            line.starts_with(&format!(
                "workload=rays threads={threads} rays=2 mrays_per_s="
            )),
            "{line}"
        );
        assert!(line.contains(" median_ms="), "{line}");
    }
    let hits = std::fs::read(dir.path().join("h.bin")).unwrap();
    assert_eq!(hits.len(), 16);
    assert_eq!(f32::from_le_bytes(hits[0..4].try_into().unwrap()), 1.0);
    assert_eq!(u32::from_le_bytes(hits[4..8].try_into().unwrap()), 0);
    assert_eq!(
        f32::from_le_bytes(hits[8..12].try_into().unwrap()),
        f32::INFINITY
    );
    assert_eq!(
        u32::from_le_bytes(hits[12..16].try_into().unwrap()),
        u32::MAX
    );
    // Shadow queries over [0, 0.5] miss the base at t = 1; over [0, 2] they hit.
    for (tfar, want) in [("0.5", 0u8), ("2", 1u8)] {
        let out = raylab(
            &[
                "bench", "tet.obj", "--rays", "r.rays", "--shadow", "--tfar", tfar, "--hits",
                "o.bin", "--repeat", "1",
            ],
            dir.path(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(
            String::from_utf8(out.stdout)
                .unwrap()
                .contains("workload=shadow")
        );
        assert_eq!(std::fs::read(dir.path().join("o.bin")).unwrap(), [want, 0]);
    }
}

#[test]
fn bench_refuses_bad_input_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    write_tetrahedron(dir.path());
    std::fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(dir.path().join("odd.rays"), [0u8; 30]).unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["bench", "missing.obj"], 1, "missing.obj"),
        (
            &["bench", "bad.obj"],
            1,
            "bad.obj:3: face refers to vertex 9",
        ),
        (&["bench", "tet.obj", "--rays", "odd.rays"], 1, "odd.rays"),
        (&["bench", "tet.obj", "--hits", "h.bin"], 2, "--rays"),
        (&["bench", "tet.obj", "--threads", "0"], 2, "--threads"),
        (&["bench", "tet.obj", "--tfar", "-1"], 2, "--tfar"),
        (&["bench", "tet.obj", "--repeat", "0"], 2, "--repeat"),
    ];
    for (args, code, needle) in cases {
        let out = raylab(args, dir.path());
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(*code), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn a_mesh_renders_framed_and_lit_into_its_own_png() {
    let dir = tempfile::tempdir().unwrap();
    write_tetrahedron(dir.path());
    let out = raylab(
        &["render", "tet.obj", "--width", "64", "--height", "64"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let img = image::open(dir.path().join("tet.png")).unwrap().to_rgb8();
    // The mesh fills part of the frame: black around it, lit faces inside.
    let lum: Vec<u32> = img
        .pixels()
        .map(|p| p.0.iter().map(|&c| c as u32).sum())
        .collect();
    assert_eq!(lum[0], 0, "the corner sees no mesh");
    let lit = lum.iter().filter(|&&l| l > 3 * 120).count();
    assert!(lit > 200, "only {lit} lit pixels");
    // Flat shows the default grey reflectance 0.75 (sRGB 225) where the mesh is.
    let out = raylab(
        &["render", "tet.obj", "--integrator", "flat", "-o", "f.png"],
        dir.path(),
    );
    assert!(out.status.success());
    let flat = image::open(dir.path().join("f.png")).unwrap().to_rgb8();
    assert!(flat.pixels().any(|p| p.0 == [225, 225, 225]));
    assert!(
        flat.pixels()
            .all(|p| p.0 == [225, 225, 225] || p.0 == [0, 0, 0])
    );
}

#[test]
fn meshes_can_be_placed_in_the_lab_box() {
    let dir = tempfile::tempdir().unwrap();
    write_tetrahedron(dir.path());
    let place = [
        "--add",
        "tet.obj",
        "--transform",
        "fit 0.5; rotate x 180; translate 0 1 -0.5",
    ];
    let mut args = vec![
        "render",
        "--integrator",
        "flat",
        "--width",
        "100",
        "--height",
        "100",
        "-o",
        "b.png",
    ];
    args.extend(place);
    let out = raylab(&args, dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let with = image::open(dir.path().join("b.png")).unwrap().to_rgb8();
    let out = raylab(
        &args[..9]
            .iter()
            .map(|a| if *a == "b.png" { "a.png" } else { a })
            .collect::<Vec<_>>(),
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let without = image::open(dir.path().join("a.png")).unwrap().to_rgb8();
    // The pixels the mesh changed are its grey, below the image centre (on the
    // floor). The diagonals are left out: their rays run along the box's edges,
    // where the two walls tie and a different tree may report the other one.
    let changed: Vec<(u32, u32)> = with
        .enumerate_pixels()
        .filter(|(x, y, _)| x != y && x + y != 99)
        .filter(|(x, y, p)| p.0 != without.get_pixel(*x, *y).0)
        .map(|(x, y, p)| {
            assert_eq!(p.0, [225, 225, 225], "({x}, {y})");
            (x, y)
        })
        .collect();
    assert!(changed.len() > 100, "{} pixels changed", changed.len());
    assert!(changed.iter().all(|&(_, y)| y > 50));
    // Transforms must pair with meshes; a bad one names itself.
    for (extra, needle) in [
        (&["--transform", "fit 1"][..], "--transform"),
        (&["--add", "tet.obj", "--transform", "spin 3"], "spin 3"),
        (
            &[
                "--add",
                "tet.obj",
                "--transform",
                "fit 1",
                "--transform",
                "fit 2",
                "--add",
                "tet.obj",
                "--transform",
                "fit 3",
            ],
            "--transform",
        ),
    ] {
        let mut args = vec!["render"];
        args.extend(extra);
        let out = raylab(&args, dir.path());
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(needle), "{}", stderr(&out));
    }
    let out = raylab(&["render", "--add", "missing.obj"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("missing.obj"));
}

#[test]
fn path_renders_for_a_time_budget_and_reports_dropped_samples() {
    let dir = tempfile::tempdir().unwrap();
    let start = std::time::Instant::now();
    let args = [
        "render",
        "--integrator",
        "path",
        "--time",
        "0.5",
        "--width",
        "32",
        "--height",
        "24",
        "-o",
        "p.exr",
    ];
    let out = raylab(&args, dir.path());
    let took = start.elapsed();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for needle in [
        "p.exr",
        "32x24",
        "path",
        " spp",
        "0 NaN/Inf samples dropped",
    ] {
        assert!(err.contains(needle), "{needle} missing from {err}");
    }
    // Whole samples per pixel until the budget is spent: many of them, on time.
    let spp: u32 = err
        .split(" spp")
        .next()
        .unwrap()
        .rsplit(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(spp > 4, "{err}");
    assert!(
        took > Duration::from_millis(400) && took < Duration::from_secs(5),
        "{took:?}"
    );
    let film = raylab::film::read_exr(&dir.path().join("p.exr")).unwrap();
    assert!(film.pixels.iter().all(|p| p.is_finite()) && film.get(16, 12).max_element() > 0.0);

    // The area-light box with a glass block, and a scene without light: black
    // image, with a warning.
    let out = raylab(
        &[
            "render",
            "cornell-area",
            "--integrator",
            "path",
            "--material",
            "short=glass",
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "16",
            "-o",
            "a.png",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = raylab(
        &[
            "render",
            "--integrator",
            "path",
            "--light-power",
            "0",
            "--width",
            "8",
            "--height",
            "8",
            "-o",
            "dark.exr",
        ],
        dir.path(),
    );
    let err = stderr(&out);
    assert!(
        out.status.success() && err.starts_with("warning: ") && err.contains("no light"),
        "{err}"
    );
    let dark = raylab::film::read_exr(&dir.path().join("dark.exr")).unwrap();
    assert!(dark.pixels.iter().all(|p| *p == glam::Vec3A::ZERO));
}

#[test]
fn path_png_exposure_is_pi_times_two_to_the_e() {
    // The same render as EXR and as PNG at two exposures: PNG = sRGB(π·2^E·EXR).
    let dir = tempfile::tempdir().unwrap();
    let base = [
        "render",
        "--integrator",
        "path",
        "--spp",
        "2",
        "--width",
        "8",
        "--height",
        "8",
    ];
    for (file, exposure) in [("e.exr", "0"), ("e0.png", "0"), ("e1.png", "-1")] {
        let mut args = base.to_vec();
        args.extend(["--exposure", exposure, "-o", file]);
        let out = raylab(&args, dir.path());
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let exr = raylab::film::read_exr(&dir.path().join("e.exr")).unwrap();
    for (file, scale) in [("e0.png", 1.0f32), ("e1.png", 0.5)] {
        let png = image::open(dir.path().join(file)).unwrap().to_rgb8();
        for (p, e) in png.pixels().zip(&exr.pixels) {
            let want = *e * (std::f32::consts::PI * scale);
            let want = [want.x, want.y, want.z].map(raylab::film::srgb8);
            assert_eq!(p.0, want, "{file}");
        }
    }
}

/// `raylab bench ... | head -1`: a reader that closes the pipe early ends the
/// command quietly with success, not with a panic about a broken pipe.
#[test]
fn bench_into_a_closed_pipe_exits_quietly() {
    let dir = tempfile::tempdir().unwrap();
    write_tetrahedron(dir.path());
    let rays: Vec<u8> = [0.2f32, 0.2, -1.0, 0.0, 0.0, 1.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(dir.path().join("r.rays"), rays).unwrap();
    for _ in 0..3 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["bench", "tet.obj", "--rays", "r.rays", "--threads", "1,1,1"])
            .current_dir(dir.path())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run raylab");
        // Close the read end before the first line is written (the build comes
        // first and takes longer than this).
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stderr(&out).is_empty(), "{}", stderr(&out));
    }
}

/// A pixel whose samples are huge (an absurd light, whose sum would overflow
/// f32) is written finite: samples are clamped to ±2⁴² before they are
/// summed (`raylab::fixed`).
#[test]
fn exr_output_is_finite_even_when_a_pixel_overflows() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "render",
        "--integrator",
        "path",
        "--light-power",
        "5e37",
        "--light-pos",
        "0,0.9,0",
        "--spp",
        "16",
        "--width",
        "64",
        "--height",
        "64",
        "-o",
        "a.exr",
    ];
    let o = raylab(&args, dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let film = raylab::film::read_exr(&dir.path().join("a.exr")).unwrap();
    assert!(film.pixels.iter().all(|p| p.is_finite()));
    let max = raylab::fixed::MAX_SAMPLE;
    assert!(film.pixels.iter().any(|p| p.max_element() > 1e12));
    assert!(film.pixels.iter().all(|p| p.max_element() <= max));
}

/// The same render gives the same EXR bytes (the writer once compressed blocks on
/// a thread pool and stored them in the order they finished).
#[test]
fn exr_files_are_byte_for_byte_repeatable() {
    let dir = tempfile::tempdir().unwrap();
    for out in ["a.exr", "b.exr", "c.exr"] {
        let o = raylab(&["render", "-o", out], dir.path());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let bytes = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
    assert_eq!(bytes("a.exr"), bytes("b.exr"));
    assert_eq!(bytes("a.exr"), bytes("c.exr"));
}

/// `direct` on a scene whose point light is off says why the image is dark.
#[test]
fn direct_without_a_point_light_warns() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(
        &["render", "cornell-area", "--width", "32", "--height", "32"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("warning: the point light is off"),
        "{}",
        stderr(&out)
    );
    // And options that only `path` reads are not silently dropped.
    let out = raylab(
        &[
            "render",
            "--max-depth",
            "3",
            "--width",
            "32",
            "--height",
            "32",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("--max-depth, --material and --fog only change `path`"));
}

/// The showcase glTF scene committed with the project.
fn showcase() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase/showcase.gltf")
}

#[test]
fn gltf_scenes_render_the_same_on_any_thread_count_with_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let scene = showcase();
    let scene = scene.to_str().unwrap();
    let mut images = Vec::new();
    for threads in ["1", "3"] {
        let out = format!("t{threads}.exr");
        let o = raylab(
            &[
                "render",
                scene,
                "--width",
                "48",
                "--height",
                "32",
                "--spp",
                "2",
                "--threads",
                threads,
                "-o",
                &out,
            ],
            dir.path(),
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 2, "{err}");
        assert!(
            lines[0].starts_with("loaded ") && lines[0].contains("24012 triangles"),
            "{err}"
        );
        assert!(lines[1].contains("48x32, path, 2 spp"), "{err}");
        images.push(std::fs::read(dir.path().join(&out)).unwrap());
    }
    assert!(
        images[0] == images[1],
        "EXR differs between 1 and 3 threads"
    );
    // PNGs are tone mapped with Khronos PBR Neutral by default: brighter
    // highlights than clamping keeps, so the two PNGs differ.
    for (name, tonemap) in [("neutral.png", None), ("clamp.png", Some("clamp"))] {
        let mut args = vec![
            "render", scene, "--width", "48", "--height", "32", "--quiet", "-o", name,
        ];
        if let Some(t) = tonemap {
            args.extend(["--tonemap", t]);
        }
        let o = raylab(&args, dir.path());
        assert!(o.status.success() && o.stderr.is_empty(), "{}", stderr(&o));
    }
    let a = image::open(dir.path().join("neutral.png"))
        .unwrap()
        .to_rgb8();
    let b = image::open(dir.path().join("clamp.png")).unwrap().to_rgb8();
    assert_eq!(a.dimensions(), (48, 32));
    assert_ne!(a.as_raw(), b.as_raw());
}

#[test]
fn bad_gltf_files_and_cameras_exit_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("broken.gltf", "{ \"asset\": ");
    write(
        "needs.gltf",
        r#"{"asset":{"version":"2.0"},"extensionsRequired":["EXT_future"],"extensionsUsed":["EXT_future"]}"#,
    );
    write(
        "nobuffer.gltf",
        // (A buffer that nothing uses may be missing: this one holds a
        // mesh's positions.)
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"missing.bin","byteLength":36}],
            "bufferViews":[{"buffer":0,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}]}"#,
    );
    let cases: &[(&str, &str)] = &[
        ("absent.gltf", "absent.gltf"),
        ("broken.gltf", "not valid glTF JSON"),
        ("needs.gltf", "EXT_future"),
        ("nobuffer.gltf", "missing.bin"),
    ];
    for (file, says) in cases {
        let o = raylab(&["render", file, "-o", "x.png"], dir.path());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{file}: {err}");
        assert_eq!(err.lines().count(), 1, "{file}: {err}");
        assert!(err.contains(file) && err.contains(says), "{file}: {err}");
    }
    assert!(!dir.path().join("x.png").exists());
    // --camera belongs to glTF files, and must exist there.
    let o = raylab(&["render", "--camera", "0"], dir.path());
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let scene = showcase();
    let o = raylab(
        &[
            "render",
            scene.to_str().unwrap(),
            "--camera",
            "3",
            "--quiet",
        ],
        dir.path(),
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("has 1 camera"), "{}", stderr(&o));
}

#[test]
fn render_writes_aovs_as_named_exr_channels_beside_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let size = [
        "--width", "30", "--height", "20", "--spp", "2", "--seed", "5",
    ];
    let mut args = vec!["render", "--aov", "albedo,depth", "-o", "x.exr", "--quiet"];
    args.extend(size);
    let out = raylab(&args, dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let file = dir.path().join("x.exr");
    let channels = raylab::film::read_exr_channels(&file).unwrap();
    assert_eq!((channels.width, channels.height), (30, 20));
    assert_eq!(
        channels.names(),
        ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z"]
    );
    // The same image and AOVs as the library's, and the image still reads as
    // the plain RGB picture.
    let settings = raylab::render::RenderSettings {
        integrator: raylab::Integrator::Direct,
        spp: 2,
        seed: 5,
    };
    let set = "albedo,depth".parse().unwrap();
    let scene = raylab::load::cornell::scene();
    let cam = raylab::Camera::lab(raylab::load::cornell::CAMERA_POSITION, 0.0, 0.0, 30, 20);
    let want = raylab::render::render_with_aovs(&scene, &cam, &settings, set, &|_| {});
    assert_eq!(raylab::film::read_exr(&file).unwrap(), want.film);
    for channel in want.aovs.unwrap().into_channels() {
        assert_eq!(
            channels.get(&channel.name),
            Some(&channel.values[..]),
            "{}",
            channel.name
        );
    }
    // Inside the back wall, above the blocks: albedo 0.75, depth 4.
    let at = 6 * 30 + 15;
    assert_eq!(channels.get("albedo.G").unwrap()[at], 0.75);
    assert!((channels.get("depth.Z").unwrap()[at] - 4.0).abs() < 1e-5);

    // Without -o: SCENE.exr, since only EXR holds AOVs.
    let mut args = vec!["render", "--aov", "normal", "--quiet"];
    args.extend(size);
    let out = raylab(&args, dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let names = raylab::film::read_exr_channels(&dir.path().join("cornell.exr")).unwrap();
    assert!(names.get("normal.X").is_some(), "{:?}", names.names());
}

#[test]
fn aov_errors_are_one_line_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needle) in [
        (
            vec!["render", "--aov", "albedo", "-o", "x.png"],
            "the output must be .exr",
        ),
        (
            vec!["render", "--aov", "albedo,colour", "-o", "x.exr"],
            "unknown AOV 'colour' (expected albedo, normal, depth, position, variance, half, samples)",
        ),
        (
            vec!["render", "--aov", "depth,depth", "-o", "x.exr"],
            "given twice",
        ),
    ] {
        let out = raylab(&args, dir.path());
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing written"
    );
}
