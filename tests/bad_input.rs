//! The bad-input suite (issue 12): every malformed file in `tests/data/bad/`
//! (written by `tools/make_bad_inputs.py`; the name says what is wrong) and a
//! few built here (too big or too deep to commit) must be refused quickly with
//! exactly one line on stderr that names the file and says why, a non-zero
//! exit code and no panic; `--max-memory` refuses what does not fit before
//! allocating it; and strange but valid files render a finite image.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The longest a refusal may take (several run at once on a busy machine;
/// each takes milliseconds alone).
const DEADLINE: Duration = Duration::from_secs(15);

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

fn ok_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ok")
}

/// Every committed bad file and the words its one-line error must contain
/// (besides its name): the reason, so that a file refused for another cause
/// than the one its name gives fails the test.
const CASES: &[(&str, &str)] = &[
    // Wavefront OBJ
    ("obj-index-zero.obj", ":4: face vertex index 0"),
    (
        "obj-index-past-end.obj",
        "refers to vertex 9 but the file has 3",
    ),
    (
        "obj-negative-index-before-start.obj",
        "face vertex -5 does not exist",
    ),
    (
        "obj-huge-negative-index.obj",
        "-9223372036854775808 does not exist",
    ),
    ("obj-index-2-40.obj", "1099511627776 does not exist"),
    ("obj-index-not-a-number.obj", "'x' is not an index"),
    ("obj-index-overflows-i64.obj", "is not an index"),
    ("obj-nan-vertex.obj", "'nan' is not a finite number"),
    ("obj-inf-vertex.obj", "'inf' is not a finite number"),
    (
        "obj-overflowing-vertex.obj",
        "'1e39' is not a finite number",
    ),
    ("obj-vertex-two-coordinates.obj", "vertex has 2 coordinates"),
    ("obj-face-one-vertex.obj", "face has 1 vertices, needs 3"),
    ("obj-face-two-vertices.obj", "face has 2 vertices, needs 3"),
    (
        "obj-texcoord-index-past-end.obj",
        "texture coordinate 5 but the file has 1",
    ),
    (
        "obj-normal-index-past-end.obj",
        "normal 7 but the file has 1",
    ),
    (
        "obj-normal-index-garbage.obj",
        "face normal 'x' is not an index",
    ),
    ("obj-nan-texcoord.obj", "texture coordinate 'nan'"),
    ("obj-non-utf8.obj", "valid UTF-8"),
    ("obj-binary-garbage.obj", "valid UTF-8"),
    // MTL (through the OBJ of the same name; the error names the .mtl)
    ("mtl-kd-not-a-number.obj", "mtl:2: Kd needs"),
    ("mtl-kd-nan.obj", "mtl:2: Kd needs 1 finite number"),
    ("mtl-newmtl-without-name.obj", "mtl:1: newmtl needs a name"),
    ("mtl-illum-garbage.obj", "mtl:2: illum needs a model number"),
    (
        "mtl-map-option-not-finite.obj",
        "texture option -bm needs a value",
    ),
    (
        "mtl-non-utf8.obj",
        "mtl: stream did not contain valid UTF-8",
    ),
    // glTF JSON
    ("gltf-empty-file.gltf", "not valid glTF JSON: EOF"),
    ("gltf-truncated.gltf", "not valid glTF JSON: EOF"),
    ("gltf-not-json.gltf", "not valid glTF JSON"),
    ("gltf-no-asset.gltf", "missing field `asset`"),
    (
        "gltf-accessors-wrong-type.gltf",
        "invalid type: string \"lots\"",
    ),
    ("gltf-count-negative.gltf", "invalid value: integer `-3`"),
    ("gltf-count-is-string.gltf", "invalid type: string \"3\""),
    ("gltf-accessor-past-buffer.gltf", "300 elements of 12 bytes"),
    (
        "gltf-accessor-offset-past-view.gltf",
        "offset 4000) do not fit",
    ),
    (
        "gltf-accessor-2-31-elements.gltf",
        "claims 2147483648 elements",
    ),
    (
        "gltf-accessor-2-32-elements.gltf",
        "claims 4294967295 elements",
    ),
    (
        "gltf-accessor-without-view-huge.gltf",
        "with no buffer view behind them",
    ),
    ("gltf-accessor-missing.gltf", "accessor 7 does not exist"),
    (
        "gltf-buffer-view-past-buffer.gltf",
        "lies outside buffer 0 of 44 bytes",
    ),
    (
        "gltf-buffer-view-offset-huge.gltf",
        "lies outside buffer 0 of 44 bytes",
    ),
    (
        "gltf-buffer-view-missing-buffer.gltf",
        "buffer 5 does not exist",
    ),
    (
        "gltf-stride-smaller-than-element.gltf",
        "byte stride 4 is smaller",
    ),
    (
        "gltf-buffer-shorter-than-declared.gltf",
        "declares 1048576 bytes but only 44",
    ),
    (
        "gltf-buffer-length-2-62.gltf",
        "declares 4611686018427387904 bytes",
    ),
    ("gltf-buffer-file-missing.gltf", "no-such-buffer.bin"),
    ("gltf-buffer-bad-base64.gltf", "not valid base64"),
    ("gltf-buffer-remote-uri.gltf", "is not a local file"),
    ("gltf-index-past-vertices.gltf", "index 99 is out of range"),
    (
        "gltf-indices-are-floats.gltf",
        "must hold unsigned integer scalars",
    ),
    (
        "gltf-positions-are-scalars.gltf",
        "has 1 components per element, expected 3",
    ),
    ("gltf-unknown-component-type.gltf", "unknown component type"),
    (
        "gltf-cyclic-nodes.gltf",
        "appears twice in the scene's node tree",
    ),
    (
        "gltf-node-own-child.gltf",
        "appears twice in the scene's node tree",
    ),
    ("gltf-node-missing.gltf", "node 12 does not exist"),
    ("gltf-mesh-missing.gltf", "mesh 4 does not exist"),
    ("gltf-scene-missing.gltf", "default scene 3 does not exist"),
    ("gltf-material-missing.gltf", "material 2 does not exist"),
    ("gltf-required-extension.gltf", "EXT_from_the_future"),
    (
        "gltf-sparse-count-over-count.gltf",
        "replaces 10 of 3 elements",
    ),
    (
        "gltf-sparse-index-outside.gltf",
        "sparse index 40 is outside",
    ),
    (
        "gltf-matrix-too-short.gltf",
        "expected an array of length 16",
    ),
    ("gltf-scale-overflows-f32.gltf", "transform is not finite"),
    (
        "gltf-instancing-counts-differ.gltf",
        "EXT_mesh_gpu_instancing: SCALE has 2 elements but TRANSLATION has 3",
    ),
    (
        "gltf-instancing-rotation-vec3.gltf",
        "ROTATION accessor 0 is not VEC4",
    ),
    (
        "gltf-variant-mapping-past-variants.gltf",
        "mapping names variant 5, but the file defines 1",
    ),
    ("gltf-variant-without-name.gltf", "missing field `name`"),
    (
        "gltf-camera-zero-yfov.gltf",
        "yfov 0 is not between 0 and π",
    ),
    (
        "gltf-image-65536-png-header.gltf",
        "65536×65536 texels is too large",
    ),
    (
        "gltf-image-not-an-image.gltf",
        "not a PNG, JPEG, WebP, BMP or KTX2 image",
    ),
    // GLB
    ("glb-header-truncated.glb", "GLB header is truncated"),
    ("glb-version-1.glb", "GLB version 1, expected 2"),
    ("glb-bad-magic.glb", "not valid glTF JSON"),
    (
        "glb-length-past-end.glb",
        "claims 1048576 bytes but the file has",
    ),
    ("glb-chunk-past-end.glb", "claims 4000 bytes past the end"),
    (
        "glb-chunk-4-gib.glb",
        "claims 4294967295 bytes past the end",
    ),
    ("glb-no-json-chunk.glb", "GLB has no JSON chunk"),
    ("glb-json-chunk-garbage.glb", "not valid glTF JSON"),
    ("glb-no-bin-chunk.glb", "no GLB binary chunk"),
    ("glb-bin-chunk-short.glb", "declares 44 bytes but only 20"),
    // Scene files
    ("shot-syntax-error.toml", ":1:9: unclosed array table"),
    (
        "shot-wrong-type.toml",
        ":2:9: invalid type: string \"wide\"",
    ),
    ("shot-unknown-key.toml", "unknown field `widht`"),
    ("shot-unknown-section.toml", "unknown field `lighting`"),
    ("shot-model-missing.toml", "no-such-model.obj: No such file"),
    (
        "shot-model-bad.toml",
        "obj-index-zero.obj:4: face vertex index 0",
    ),
    ("shot-absurd-width.toml", "width = 4000000000"),
    ("shot-negative-spp.toml", "invalid value: integer `-4`"),
    (
        "shot-light-overflow.toml",
        "[[light]] 1: intensity × color inf is more than 1e20",
    ),
    (
        "shot-time-1e300.toml",
        "time = 1e300: expected seconds > 0 and at most 604800",
    ),
    (
        "shot-spp-over-limit.toml",
        "spp = 4000000000: expected 1 to 1048576",
    ),
    (
        "shot-pixels-over-limit.toml",
        "16384 × 16384: expected at most 134217728 pixels",
    ),
    ("shot-nan-fov.toml", "fov = NaN"),
    (
        "shot-environment-missing.toml",
        "no-such-sky.hdr: No such file",
    ),
    ("shot-non-utf8.toml", "valid UTF-8"),
    ("shot-deep-arrays.toml", "recursion"),
    // Radiance HDR (as --env)
    ("hdr-empty.hdr", "not a Radiance HDR file"),
    ("hdr-no-magic.hdr", "does not start with '#?'"),
    ("hdr-header-never-ends.hdr", "the header does not end"),
    ("hdr-bad-format.hdr", "'32-bit_rle_xyze' is not supported"),
    ("hdr-no-resolution-line.hdr", "no resolution line"),
    ("hdr-resolution-garbage.hdr", "'many' is not a size"),
    ("hdr-zero-size.hdr", "the image is 16×0"),
    ("hdr-65536-square-10-bytes.hdr", "the image is 65536×65536"),
    (
        "hdr-lying-header-10-bytes.hdr",
        "says 16384×8192 but only 10 bytes",
    ),
    (
        "hdr-truncated-flat.hdr",
        "scanline 3 of 4: the file ends inside it",
    ),
    (
        "hdr-truncated-rle.hdr",
        "scanline 1 of 2: the file ends inside it",
    ),
    (
        "hdr-run-past-scanline.hdr",
        "a run passes the end of the scanline",
    ),
    ("hdr-literal-zero.hdr", "a literal of 0 bytes"),
    (
        "hdr-rle-width-mismatch.hdr",
        "scanline of width 32, expected 16",
    ),
    (
        "hdr-repeat-before-pixel.hdr",
        "a repeat marker before any pixel",
    ),
    // OpenEXR (as --env)
    ("exr-empty.exr", "missing bytes"),
    ("exr-not-exr.exr", "file identifier missing"),
    ("exr-truncated.exr", "missing bytes"),
    ("exr-65536-square-header.exr", "the image is 65536×65536"),
    ("exr-zero-channels.exr", "at least one channel"),
    ("exr-only-luminance.exr", "no layer in the image matched"),
    ("exr-offsets-past-end.exr", "missing bytes"),
    ("exr-inverted-window.exr", "invalid"),
    // PNG and JPEG (as an MTL map_Kd)
    ("png-truncated.png", "unexpected end of file"),
    (
        "png-65536-square-header.png",
        "65536×65536 texels is too large",
    ),
    (
        "png-16384-square-header-tiny.png",
        "says 16384×16384 texels but 68 bytes",
    ),
    ("png-crc-error.png", "CRC error"),
    ("png-palette-4-bytes.png", "PLTE chunk) is 4 bytes"),
    ("png-zero-by-zero.png", "Invalid image dimensions"),
    ("png-idat-garbage.png", "Corrupt deflate stream"),
    ("png-signature-only.png", "unexpected end of file"),
    ("jpg-truncated.jpg", "Not enough bytes"),
    (
        "jpg-65535-square-header.jpg",
        "65535×65535 texels is too large",
    ),
    (
        "jpg-not-jpeg.jpg",
        "not a PNG, JPEG, WebP, BMP or KTX2 image",
    ),
    // Ray files (raylab bench --rays)
    ("rays-empty.rays", "holds no rays"),
    (
        "rays-length-not-multiple-of-24.rays",
        "30 bytes is not a whole number of rays",
    ),
    (
        "rays-nan-origin.rays",
        "ray 0 has a NaN or infinite coordinate",
    ),
    (
        "rays-inf-direction.rays",
        "ray 0 has a NaN or infinite coordinate",
    ),
    ("rays-zero-direction.rays", "ray 0 has a zero direction"),
];

/// A case: arguments, the exit code, and what the one line must contain.
struct Case {
    label: String,
    args: Vec<String>,
    code: i32,
    needles: Vec<String>,
}

/// A tetrahedron for `bench` and textured triangles for the image cases.
fn scaffold(dir: &Path) {
    std::fs::write(
        dir.join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
}

/// The command that reads `file` as what its extension says; `dir` holds
/// the scaffolding.
fn case_for(file: &Path, dir: &Path, says: &str) -> Case {
    let name = file.file_name().unwrap().to_str().unwrap().to_string();
    let path = file.to_str().unwrap().to_string();
    let small = [
        "--width", "16", "--height", "16", "--spp", "1", "-o", "out.png",
    ];
    let render = |args: &[&str]| -> Vec<String> {
        ["render"]
            .iter()
            .chain(args)
            .chain(&small)
            .map(|s| s.to_string())
            .collect()
    };
    let (args, code, named) = match file.extension().and_then(|e| e.to_str()) {
        Some("hdr" | "exr") => (render(&["cornell", "--env", &path]), 1, name.clone()),
        Some("png" | "jpg") => {
            // A one-triangle OBJ whose material's map_Kd is the image.
            let stem = file.file_stem().unwrap().to_str().unwrap();
            let obj = dir.join(format!("{stem}.obj"));
            std::fs::write(
                dir.join(format!("{stem}.mtl")),
                format!("newmtl m\nmap_Kd {path}\n"),
            )
            .unwrap();
            std::fs::write(
                &obj,
                format!(
                    "mtllib {stem}.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                     usemtl m\nf 1/1 2/2 3/3\n"
                ),
            )
            .unwrap();
            (render(&[obj.to_str().unwrap()]), 1, name.clone())
        }
        // Refused before any ray is cast: no benchmark runs.
        Some("rays") => (
            ["bench", "tet.obj", "--rays", &path, "--repeat", "1"]
                .map(String::from)
                .to_vec(),
            1,
            name.clone(),
        ),
        // An MTL case's error names its library.
        _ if name.starts_with("mtl-") => (render(&[&path]), 1, name.replace(".obj", ".mtl")),
        _ => (render(&[&path]), 1, name.clone()),
    };
    let named = match name.as_str() {
        // The error is in the file the scene file names.
        "shot-model-missing.toml" => "no-such-model.obj".to_string(),
        "shot-model-bad.toml" => "obj-index-zero.obj".to_string(),
        "shot-environment-missing.toml" => "no-such-sky.hdr".to_string(),
        _ => named,
    };
    Case {
        label: name,
        args,
        code,
        needles: vec![named, says.to_string()],
    }
}

/// Runs `raylab` in `dir`, killing it at [`DEADLINE`]: (exit code, stderr,
/// time taken), the code `None` when killed.
fn run(args: &[String], dir: &Path) -> (Option<i32>, String, Duration) {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run raylab");
    // stderr is read on a thread so that a flood of output cannot block the
    // child (the deadline then catches it).
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        std::io::Read::read_to_end(&mut pipe, &mut text).ok();
        String::from_utf8_lossy(&text).into_owned()
    });
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > DEADLINE {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let elapsed = start.elapsed();
    (code, reader.join().unwrap(), elapsed)
}

/// Runs every case on a few threads; returns one line per failure.
fn check_all(cases: Vec<Case>, dir: &Path) -> Vec<String> {
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                while let Some(case) = cases.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let (code, err, took) = run(&case.args, dir);
                    let mut wrong = Vec::new();
                    if code != Some(case.code) {
                        wrong.push(format!("exit code {code:?}, expected {}", case.code));
                    }
                    if err.trim_end().lines().count() != 1 || !err.ends_with('\n') {
                        wrong.push("not exactly one line".into());
                    }
                    if err.len() > 1000 {
                        wrong.push(format!("a line of {} bytes", err.len()));
                    }
                    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
                        wrong.push("a panic".into());
                    }
                    for n in &case.needles {
                        if !err.contains(n.as_str()) {
                            wrong.push(format!("no '{n}'"));
                        }
                    }
                    if took > DEADLINE {
                        wrong.push(format!("took {took:?}"));
                    }
                    if !wrong.is_empty() {
                        let shown: String = err.chars().take(600).collect();
                        failures.lock().unwrap().push(format!(
                            "{}: {} — stderr: {shown}",
                            case.label,
                            wrong.join(", ")
                        ));
                    }
                }
            });
        }
    });
    failures.into_inner().unwrap()
}

#[test]
fn every_bad_file_is_refused_in_one_line_naming_it() {
    // Every committed file has a case, and every case a file.
    let mut on_disk: Vec<String> = std::fs::read_dir(bad_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| !(n.starts_with("mtl-") && n.ends_with(".mtl")))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = CASES.iter().map(|(f, _)| f.to_string()).collect();
    listed.sort();
    assert_eq!(on_disk, listed, "tests/data/bad and CASES differ");
    assert!(CASES.len() >= 60);

    let dir = tempfile::tempdir().unwrap();
    scaffold(dir.path());
    let cases = CASES
        .iter()
        .map(|(f, says)| case_for(&bad_dir().join(f), dir.path(), says))
        .collect();
    let failures = check_all(cases, dir.path());
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Files too big or too deep to commit, built here.
#[test]
fn huge_and_deep_files_are_refused_in_milliseconds() {
    let dir = tempfile::tempdir().unwrap();
    scaffold(dir.path());
    let d = dir.path();
    let write = |name: &str, text: &[u8]| std::fs::write(d.join(name), text).unwrap();
    // A 100 MB token: the message quotes it cut short.
    let mut long = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 ".to_vec();
    long.extend(std::iter::repeat_n(b'7', 100 << 20));
    long.extend(b"x 0\nf 1 2 3\n");
    write("obj-100-mb-token.obj", &long);
    drop(long);
    // A JSON nesting bomb, bare and inside a field (serde_json stops at 128).
    write("gltf-nesting-bomb.gltf", &b"[".repeat(1_000_000));
    let mut bomb = br#"{"asset":{"version":"2.0"},"extras":"#.to_vec();
    bomb.extend(b"[".repeat(1_000_000));
    write("gltf-nesting-bomb-in-extras.gltf", &bomb);
    // A node chain 100 000 deep.
    let n = 100_000;
    let nodes: Vec<String> = (0..n)
        .map(|i| match i + 1 < n {
            true => format!("{{\"children\":[{}]}}", i + 1),
            false => "{}".to_string(),
        })
        .collect();
    write(
        "gltf-node-depth-100000.gltf",
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{}]}}"#,
            nodes.join(",")
        )
        .as_bytes(),
    );
    // A TOML nesting bomb.
    let mut toml = b"x = ".to_vec();
    toml.extend(b"[".repeat(1_000_000));
    write("shot-nesting-bomb.toml", &toml);
    let cases = [
        ("obj-100-mb-token.obj", "vertex coordinate '777"),
        ("gltf-nesting-bomb.gltf", "not valid glTF JSON"),
        ("gltf-nesting-bomb-in-extras.gltf", "not valid glTF JSON"),
        ("gltf-node-depth-100000.gltf", "deeper than 1024 levels"),
        ("shot-nesting-bomb.toml", "shot-nesting-bomb.toml:1:"),
    ]
    .iter()
    .map(|(f, says)| case_for(&d.join(f), d, says))
    .collect();
    let failures = check_all(cases, d);
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn bad_command_lines_are_refused_in_one_line_naming_the_argument() {
    let dir = tempfile::tempdir().unwrap();
    scaffold(dir.path());
    std::fs::write(dir.path().join("sky.txt"), "not a map").unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["render", "--max-memory", "3X"], 2, "--max-memory"),
        // A file name with a newline is quoted escaped: still one line (found
        // by the cli fuzz target).
        (&["render", "bad\nname.obj"], 1, "bad\\nname.obj"),
        (&["render", "--max-memory", "-1G"], 2, "--max-memory"),
        (&["render", "--width", "0"], 2, "--width"),
        (&["render", "--width", "99999999999999999999"], 2, "--width"),
        (&["render", "--spp", "nan"], 2, "--spp"),
        (&["render", "no-such-model.obj"], 1, "no-such-model.obj"),
        (&["render", "model.fbx"], 1, "model.fbx"),
        (
            &["render", "--env", "no-such-sky.hdr"],
            1,
            "no-such-sky.hdr",
        ),
        (&["render", "--env", "sky.txt"], 1, "sky.txt"),
        (
            &["render", "-o", "no-such-folder/x.png"],
            1,
            "no-such-folder",
        ),
        (&["render", "-o", "image.bmp"], 1, "image.bmp"),
        (
            &["bench", "tet.obj", "--rays", "no-such.rays"],
            1,
            "no-such.rays",
        ),
    ];
    let cases = cases
        .iter()
        .map(|(args, code, says)| Case {
            label: args.join(" "),
            args: args.iter().map(|s| s.to_string()).collect(),
            code: *code,
            needles: vec![says.to_string()],
        })
        .collect();
    let failures = check_all(cases, dir.path());
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Renders `args` (plus a small size and an EXR output) in `dir`: stderr and
/// the image, after checking the exit code is 0.
fn render_ok(args: &[&str], dir: &Path, integrator: &str) -> (String, raylab::film::Film) {
    let out = dir.join(format!("ok-{integrator}.exr"));
    let mut all: Vec<String> = ["render"]
        .iter()
        .chain(args)
        .map(|s| s.to_string())
        .collect();
    for a in [
        "--integrator",
        integrator,
        "--width",
        "16",
        "--height",
        "16",
    ] {
        all.push(a.into());
    }
    all.extend([
        "--spp".into(),
        "4".into(),
        "-o".into(),
        out.display().to_string(),
    ]);
    let (code, err, _) = run(&all, dir);
    assert_eq!(code, Some(0), "{args:?} {integrator}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    let film = raylab::film::read_exr(&out).unwrap();
    (err, film)
}

#[test]
fn strange_but_valid_files_render_finite_images() {
    let dir = tempfile::tempdir().unwrap();
    let ok = ok_dir();
    let file = |n: &str| ok.join(n).display().to_string();
    let hdr = file("one-texel.hdr");
    // (arguments, a warning the render must give, or "")
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec![file("empty.obj")], "no triangles"),
        (vec![file("empty.gltf")], ""),
        (vec![file("empty-scene.gltf")], ""),
        (vec![file("one-triangle.obj")], ""),
        (vec![file("all-degenerate.obj")], ""),
        (
            vec![file("nan-normals.obj")],
            "2 'vn' normals are not finite",
        ),
        (vec![file("nan-normals.gltf")], ""),
        (vec![file("zero-area-uvs.obj")], ""),
        (vec![file("huge-coordinates.obj")], ""),
        (vec![file("tiny-extent.obj")], ""),
        (vec![file("missing-mtllib.obj")], "no-such-library.mtl"),
        (vec![file("one-triangle.obj"), "--env".into(), hdr], ""),
    ];
    for (args, warning) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        for integrator in ["path", "direct"] {
            let (err, film) = render_ok(&args, dir.path(), integrator);
            assert_eq!((film.width, film.height), (16, 16));
            assert!(
                film.pixels.iter().all(|p| p.is_finite()),
                "{args:?} {integrator}: a pixel is not finite"
            );
            if integrator == "path" {
                assert!(
                    err.contains(", 0 NaN/Inf samples dropped"),
                    "{args:?}: {err}"
                );
            }
            assert!(err.contains(warning), "{args:?}: no '{warning}' in {err}");
        }
    }
    // The degenerate and NaN-normal meshes are seen: lit, not black.
    for name in ["one-triangle.obj", "nan-normals.obj", "nan-normals.gltf"] {
        let (_, film) = render_ok(&[&file(name)], dir.path(), "path");
        let lit = film.pixels.iter().filter(|p| p.max_element() > 0.0).count();
        assert!(lit > 0, "{name}: all black");
    }
}

/// A model of `assets/models`.
fn model(name: &str) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/models")
        .join(name)
        .display()
        .to_string()
}

/// `--max-memory`: over the budget is one line naming the scene and what it
/// needs, before the big allocation.
#[test]
fn the_memory_budget_refuses_what_does_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ok = ok_dir();
    let tri = ok.join("one-triangle.obj").display().to_string();
    let small = [
        "--width", "16", "--height", "16", "--spp", "1", "-o", "o.png",
    ];
    let args = |extra: &[&str]| -> Vec<String> {
        ["render"]
            .iter()
            .chain(extra)
            .chain(&small)
            .map(|s| s.to_string())
            .collect()
    };
    // Fits by default and with room to spare.
    for budget in [None, Some("64M"), Some("none"), Some("0")] {
        let mut a = args(&[&tri]);
        if let Some(b) = budget {
            a.extend(["--max-memory".into(), b.into()]);
        }
        let (code, err, _) = run(&a, d);
        assert_eq!(code, Some(0), "{budget:?}: {err}");
    }
    // A texture of 4096×4096 RGBA (64 MiB decoded, a few KiB of file): refused
    // from its header under 16M, before decoding.
    let texels = vec![0u8; 4096 * 4096 * 4];
    image::save_buffer(
        d.join("big.png"),
        &texels,
        4096,
        4096,
        image::ExtendedColorType::Rgba8,
    )
    .unwrap();
    std::fs::write(d.join("big.mtl"), "newmtl m\nmap_Kd big.png\n").unwrap();
    std::fs::write(
        d.join("big.obj"),
        "mtllib big.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n",
    )
    .unwrap();
    // 2^27 pixels, the most --width and --height allow: 5 GiB of film.
    let huge_film: Vec<String> = [
        "render",
        "cornell",
        "--width",
        "16384",
        "--height",
        "8192",
        "--max-memory",
        "1G",
        "-o",
        "o.png",
    ]
    .map(String::from)
    .to_vec();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            args(&[&tri, "--max-memory", "1K"]),
            "one-triangle.obj: needs about 16.2 KiB (film 16 KiB, geometry 160 B), more than --max-memory 1 KiB",
        ),
        (
            huge_film,
            "cornell: needs about 8.0 GiB (film 8 GiB, geometry 4.7 KiB), more than --max-memory 1 GiB",
        ),
        (
            args(&["big.obj", "--max-memory", "16M"]),
            "big.obj: needs about 64 MiB (textures 64 MiB), more than --max-memory 16 MiB",
        ),
        (
            args(&[&tri, "--env", "sky.hdr", "--max-memory", "16M"]),
            "sky.hdr: needs about 48 MiB (environment 48 MiB), more than --max-memory 16 MiB",
        ),
        // The file's bytes, before they are read and parsed: an OBJ's text,
        // a glTF's buffer.
        (
            args(&[&model("stanford-bunny.obj"), "--max-memory", "1M"]),
            "stanford-bunny.obj: needs about 2.3 MiB (geometry 2.3 MiB), more than --max-memory 1 MiB",
        ),
        (
            args(&[
                &model("DamagedHelmet/DamagedHelmet.gltf"),
                "--max-memory",
                "300K",
            ]),
            "DamagedHelmet.bin: needs about 549.8 KiB (geometry 549.8 KiB), more than --max-memory 300 KiB",
        ),
    ];
    // A 2048×1024 map of one run-length scanline each (48 MiB with its tables).
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1024 +X 2048\n".to_vec();
    for _ in 0..1024 {
        hdr.extend([2, 2, 8, 0]);
        for _ in 0..4 {
            for _ in 0..16 {
                hdr.extend([128 + 127, 128]);
            }
            hdr.extend([128 + 16, 128]);
        }
    }
    std::fs::write(d.join("sky.hdr"), hdr).unwrap();
    let (code, err, _) = run(&args(&[&tri, "--env", "sky.hdr"]), d);
    assert_eq!(code, Some(0), "the map itself is valid: {err}");
    let cases = cases
        .into_iter()
        .map(|(args, says)| Case {
            label: args.join(" "),
            args,
            code: 1,
            needles: vec![says.to_string()],
        })
        .collect();
    let failures = check_all(cases, d);
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
