//! Render farms: a render split into tiles, sample ranges or frames and
//! rendered in separate processes merges into exactly the file one process
//! writes (PNG and EXR, byte for byte), and `raylab merge` refuses a set that
//! is incomplete, overlaps or mixes renders, with one line naming the problem.
//! The library's merge is checked the same way without processes, and on
//! AOVs. (The Slurm and Kubernetes drivers are tested end to end by
//! `.ci/slurm-test.sh` and `tools/farm/k8s_local.py`.)

use std::path::{Path, PathBuf};
use std::process::Command;

use raylab::Integrator;
use raylab::aov::AovSet;
use raylab::camera::Camera;
use raylab::farm::{self, Part, Render};
use raylab::film::Display;
use raylab::render::{Accumulator, RenderSettings, Split, render_with_aovs};

fn raylab(args: &[&str], dir: &Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(args: &[&str], dir: &Path) {
    let (code, err) = raylab(args, dir);
    assert_eq!(code, 0, "raylab {args:?}: {err}");
}

/// Runs `raylab merge`, expecting a refusal: exit 1 and one line containing `want`.
fn refused(parts: &[&str], dir: &Path, want: &str) {
    let mut args = vec!["merge"];
    args.extend_from_slice(parts);
    args.extend_from_slice(&["-o", "refused.png"]);
    let (code, err) = raylab(&args, dir);
    assert_eq!(code, 1, "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.contains(want), "{args:?}: expected '{want}' in: {err}");
    assert!(!dir.join("refused.png").exists());
}

fn same_bytes(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

/// The lab box with `path` (its random numbers depend on pixel and sample)
/// at a size whose last tile is short (102 = 25·4 + 2 rows).
const BOX: [&str; 8] = [
    "--integrator",
    "path",
    "--width",
    "90",
    "--height",
    "102",
    "--spp",
    "12",
];

fn render(dir: &Path, extra: &[&str], out: &str) {
    let mut args = vec!["render", "-q"];
    args.extend_from_slice(&BOX);
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out]);
    ok(&args, dir);
}

#[test]
fn tiles_and_sample_ranges_merge_into_the_single_render_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    render(d, &[], "whole.png");
    render(d, &[], "whole.exr");
    // Tiles: 3 of them.
    for k in 0..3 {
        render(
            d,
            &["--tile", &format!("{k}/3")],
            &format!("tile{k}.part.exr"),
        );
    }
    // Sample ranges, one of them split into tiles again (4 of them).
    render(d, &["--samples", "0..5"], "s0.part.exr");
    for k in 0..4 {
        render(
            d,
            &["--samples", "5..12", "--tile", &format!("{k}/4")],
            &format!("s1t{k}.part.exr"),
        );
    }
    let tiles = ["tile0.part.exr", "tile1.part.exr", "tile2.part.exr"];
    let ranges = [
        "s0.part.exr",
        "s1t0.part.exr",
        "s1t1.part.exr",
        "s1t2.part.exr",
        "s1t3.part.exr",
    ];
    for (set, name) in [(&tiles[..], "tiles"), (&ranges[..], "ranges")] {
        for ext in ["png", "exr"] {
            let out = format!("{name}.{ext}");
            let mut args = vec!["merge", "-q"];
            args.extend_from_slice(set);
            args.extend_from_slice(&["-o", &out]);
            ok(&args, d);
            same_bytes(&d.join(format!("whole.{ext}")), &d.join(&out));
        }
    }
    // The order of the parts does not matter (exact sums).
    let mut args = vec!["merge", "-q", "-o", "reversed.exr"];
    args.extend(ranges.iter().rev());
    ok(&args, d);
    same_bytes(&d.join("whole.exr"), &d.join("reversed.exr"));

    // Refusals, one line each.
    refused(
        &tiles[..2],
        d,
        "incomplete: no part holds samples 0..12 of tile 2/3",
    );
    refused(
        &ranges[..4],
        d,
        "incomplete: no part holds samples 5..12 of rows 12..16",
    );
    render(d, &["--samples", "3..12"], "late.part.exr");
    refused(
        &["s0.part.exr", "late.part.exr"],
        d,
        "overlap: s0.part.exr and late.part.exr both hold samples 3..5",
    );
    render(d, &["--samples", "5..12", "--seed", "7"], "seed7.part.exr");
    refused(
        &["s0.part.exr", "seed7.part.exr"],
        d,
        "seed7.part.exr: not a part of the same render as s0.part.exr: another seed",
    );
    ok(
        &[
            "render",
            "-q",
            "--integrator",
            "path",
            "--spp",
            "12",
            "--width",
            "90",
            "--height",
            "102",
            "--samples",
            "5..12",
            "--material",
            "tall=mirror",
            "-o",
            "mirror.part.exr",
        ],
        d,
    );
    refused(&["s0.part.exr", "mirror.part.exr"], d, "another scene");
    refused(
        &["s0.part.exr", "whole.exr"],
        d,
        "whole.exr: not a part of a render",
    );
    refused(
        &["s0.part.exr", "s0.part.exr"],
        d,
        "s0.part.exr is named twice",
    );
    refused(&["missing.part.exr"], d, "missing.part.exr: cannot read it");
    // Over the memory budget: refused from the first part's header.
    let (code, err) = raylab(
        &["merge", "s0.part.exr", "-o", "x.png", "--max-memory", "64K"],
        d,
    );
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(
        err.contains("s0.part.exr: needs about") && err.contains("more than --max-memory 64 KiB"),
        "{err}"
    );
    // A damaged part: its sums outside its tile.
    std::fs::write(d.join("junk.part.exr"), b"not an exr").unwrap();
    refused(&["junk.part.exr"], d, "junk.part.exr: not an OpenEXR file");
}

/// Splatted samples reach the rows of the tiles beside their own: parts
/// cut by tiles and by samples still merge into the single render byte for
/// byte (the gaussian reaches 2 rows beyond a sample's pixel, a tent of
/// radius 4 reaches 4, a whole tile).
#[test]
fn splatted_parts_merge_into_the_single_render_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for filter in ["gaussian", "tent:4"] {
        let splat = ["--filter", filter, "--reconstruction", "splat"];
        render(d, &splat, "whole.exr");
        let mut parts = Vec::new();
        for k in 0..3 {
            let name = format!("t{k}.part.exr");
            let tile = format!("{k}/3");
            let mut args = splat.to_vec();
            args.extend_from_slice(&["--samples", "0..5", "--tile", &tile]);
            render(d, &args, &name);
            parts.push(name);
        }
        let mut args = splat.to_vec();
        args.extend_from_slice(&["--samples", "5..12"]);
        render(d, &args, "rest.part.exr");
        parts.push("rest.part.exr".to_string());
        let mut args = vec!["merge", "-q", "-o", "merged.exr"];
        args.extend(parts.iter().map(String::as_str));
        ok(&args, d);
        same_bytes(&d.join("whole.exr"), &d.join("merged.exr"));
        // And it is not the sampled image.
        let mut args = vec!["--filter", filter];
        args.extend_from_slice(&["--reconstruction", "sample"]);
        render(d, &args, "sampled.exr");
        let bytes = |name: &str| std::fs::read(d.join(name)).unwrap();
        assert_ne!(bytes("whole.exr"), bytes("sampled.exr"));
    }
}

#[test]
fn parts_need_an_exr_and_a_valid_split() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], i32, &str); 6] = [
        (
            &["--tile", "0/2", "-o", "a.png"],
            2,
            "the output must be .exr",
        ),
        (&["--tile", "0/2"], 2, "name it with -o PART.exr"),
        (&["--tile", "2/2", "-o", "a.exr"], 2, "K counts from 0"),
        (&["--tile", "0/30", "-o", "a.exr"], 1, "at most 26 tiles"),
        (&["--samples", "0..4", "-o", "a.exr"], 2, "needs --spp"),
        (
            &[
                "--samples",
                "0..4",
                "--spp",
                "12",
                "--time",
                "1",
                "-o",
                "a.exr",
            ],
            2,
            "cannot be combined with --time",
        ),
    ];
    for (extra, code, want) in cases {
        let mut args = vec!["render", "-q", "--width", "90", "--height", "102"];
        args.extend_from_slice(extra);
        let (c, err) = raylab(&args, d);
        assert_eq!(c, code, "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(want), "{args:?}: expected '{want}' in {err}");
    }
}

#[test]
fn frames_rendered_apart_equal_one_run_of_all_of_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/stanford-bunny.obj");
    let bunny = bunny.to_str().unwrap();
    let base = [
        "render",
        "-q",
        bunny,
        "--integrator",
        "path",
        "--spp",
        "2",
        "--width",
        "48",
        "--height",
        "36",
        "--orbit",
        "45",
    ];
    let mut all = base.to_vec();
    all.extend_from_slice(&["--frames", "0..4", "-o", "all-%02d.png"]);
    ok(&all, d);
    for f in 0..4 {
        let frame = f.to_string();
        let mut one = base.to_vec();
        one.extend_from_slice(&["--frames", &frame, "-o", "one-%d.png"]);
        ok(&one, d);
        same_bytes(
            &d.join(format!("all-{f:02}.png")),
            &d.join(format!("one-{f}.png")),
        );
    }
    // The camera turns: frames differ, and frame 0 is the scene's own view.
    let frame = |name: &str| std::fs::read(d.join(name)).unwrap();
    assert_ne!(frame("all-00.png"), frame("all-01.png"));
    // The same render without --orbit and --frames.
    let still = [&base[..base.len() - 2], &["-o", "still.png"]].concat();
    ok(&still, d);
    same_bytes(&d.join("still.png"), &d.join("all-00.png"));
    // 8 frames of 45° come back round: frame 8 is frame 0 (up to the rounding
    // of the rotation, so compare the pictures, not the bytes).
    let (code, err) = raylab(
        &[&base[..], &["--frames", "8", "-o", "f%d.png"]].concat(),
        d,
    );
    assert_eq!(code, 0, "{err}");
    let a = image_of(&d.join("f8.png"));
    let b = image_of(&d.join("all-00.png"));
    let differ = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.abs_diff(**y) > 2)
        .count();
    assert!(
        differ * 100 < a.len(),
        "{differ} of {} values differ",
        a.len()
    );
}

fn image_of(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgb8().into_raw()
}

/// The library's merge, without processes: parts of a render with AOVs
/// (whose sums are exact too) add up to the render's accumulator exactly.
#[test]
fn library_parts_with_aovs_add_up_to_the_whole_render() {
    let scene = raylab::load::cornell::scene();
    let camera = Camera::lab(raylab::load::cornell::CAMERA_POSITION, 0.0, 0.0, 40, 30);
    let aovs: AovSet = "albedo,normal,depth".parse().unwrap();
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp: 6,
        seed: 11,
    };
    let whole = render_with_aovs(&scene, &camera, &settings, aovs, &|_| {});
    let dir = tempfile::tempdir().unwrap();
    let render = Render {
        key: Default::default(),
        spp: 6,
        seed: 11,
        integrator: "path".into(),
        display: Display::clamped(1.0),
        frame: None,
        layers: aovs,
        denoise: false,
    };
    let mut paths: Vec<PathBuf> = Vec::new();
    for (tile, samples) in [(0, 0..2), (1, 0..2), (0, 2..6), (1, 2..6)] {
        let split = Split::new(tile, 2, camera.height).unwrap();
        let mut acc = Accumulator::part(camera.width, camera.height, aovs, split, samples.start);
        acc.add(
            &scene,
            &camera,
            settings.integrator,
            11,
            samples.len() as u32,
            &|_| {},
        );
        let path = dir
            .path()
            .join(format!("{tile}-{}.part.exr", samples.start));
        farm::write_part(
            &path,
            &Part {
                render: render.clone(),
                acc,
            },
        )
        .unwrap();
        // Read back as written.
        let back = farm::read_part(&path).unwrap();
        assert_eq!(back.render, render);
        assert_eq!(back.acc.split(), split);
        assert_eq!(back.acc.first_sample(), samples.start);
        paths.push(path);
    }
    let merged = farm::merge(&paths).unwrap();
    let got = merged.acc.rendered();
    assert_eq!(got.film.pixels, whole.film.pixels);
    assert_eq!(got.rays, whole.rays);
    let (a, b) = (got.aovs.unwrap(), whole.aovs.unwrap());
    assert_eq!(a.into_channels(), b.into_channels());
}

/// `--cache DIR`: the second load reads the decoded textures and the BVH
/// back, and the image is the same byte for byte as without a cache; a
/// damaged entry is a miss, never a wrong image.
#[test]
fn the_cache_gives_the_same_image_and_survives_damage() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/models/TextureCoordinateTest/TextureCoordinateTest.gltf");
    let model = model.to_str().unwrap();
    let run = |out: &str, cache: bool| {
        let mut args = vec![
            "render", model, "--spp", "2", "--width", "64", "--height", "48", "-o", out,
        ];
        if cache {
            args.extend_from_slice(&["--cache", "c"]);
        }
        let (code, err) = raylab(&args, d);
        assert_eq!(code, 0, "{err}");
        err
    };
    run("plain.png", false);
    let first = run("first.png", true);
    assert!(first.contains("cache c: 0 of 2 entries found"), "{first}");
    let second = run("second.png", true);
    assert!(second.contains("cache c: 2 of 2 entries found"), "{second}");
    same_bytes(&d.join("plain.png"), &d.join("first.png"));
    same_bytes(&d.join("plain.png"), &d.join("second.png"));
    let mut entries: Vec<String> = std::fs::read_dir(d.join("c"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    entries.sort();
    assert_eq!(entries.len(), 2, "{entries:?}");
    assert!(entries[0].starts_with("bvh-") && entries[1].starts_with("texture-"));
    // Damage both entries: misses, rebuilt, the same image.
    for e in &entries {
        let path = d.join("c").join(e);
        let mut bytes = std::fs::read(&path).unwrap();
        let mid = bytes.len() / 2;
        bytes[mid] ^= 1;
        std::fs::write(&path, bytes).unwrap();
    }
    let third = run("third.png", true);
    assert!(third.contains("cache c: 0 of 2 entries found"), "{third}");
    same_bytes(&d.join("plain.png"), &d.join("third.png"));
    let fourth = run("fourth.png", true);
    assert!(fourth.contains("cache c: 2 of 2 entries found"), "{fourth}");
}
