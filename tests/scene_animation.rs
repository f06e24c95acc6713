//! Animation in scene files: `[render] at` and `fps`, a `[[model]]`'s
//! `animation`, merged with the command line's `--at`, `--animation` and
//! `--fps` (the command line wins), against renders of the same scene posed
//! from the command line, byte for byte; bad values and scenes without an
//! animated glTF model are refused in one line naming the file. The animated
//! model is the repository's `scenes/animation/bend.gltf`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bend() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animation/bend.gltf")
}

/// A scene file of the bending column with `render` added to its
/// `[render]` and `model` to its `[[model]]`.
fn scene(dir: &Path, name: &str, render: &str, model: &str) -> PathBuf {
    let text = format!(
        "[render]\nwidth = 48\nheight = 48\nspp = 2\n{render}\n\n[[model]]\nfile = {:?}\n{model}\n",
        bend().display().to_string()
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `raylab render ARGS`: its output file's bytes, or its stderr on failure.
fn render(args: &[&str], out: &Path) -> Result<Vec<u8>, String> {
    let o = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .arg("render")
        .args(args)
        .args(["--threads", "2", "-q", "-o"])
        .arg(out)
        .output()
        .unwrap();
    if o.status.success() {
        Ok(std::fs::read(out).unwrap_or_default())
    } else {
        Err(String::from_utf8_lossy(&o.stderr).into_owned())
    }
}

#[test]
fn a_scene_files_moment_renders_as_the_command_lines_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = |n: &str| d.join(n);
    let plain = scene(d, "plain.toml", "", "");
    let at = scene(d, "at.toml", "at = 0.75", "");
    let plain_s = plain.to_str().unwrap();
    let at_s = at.to_str().unwrap();
    let from_file = render(&[at_s], &out("file.exr")).unwrap();
    let from_cli = render(&[plain_s, "--at", "0.75"], &out("cli.exr")).unwrap();
    assert!(
        from_file == from_cli,
        "[render] at = 0.75 differs from --at 0.75"
    );
    // The moment shows: unposed, the column stands straight.
    let unposed = render(&[plain_s], &out("unposed.exr")).unwrap();
    assert!(unposed != from_file, "at = 0.75 rendered the unposed scene");
    // The command line wins over the file.
    let over = render(&[at_s, "--at", "1.5"], &out("over.exr")).unwrap();
    let cli_15 = render(&[plain_s, "--at", "1.5"], &out("cli15.exr")).unwrap();
    assert!(
        over == cli_15 && over != from_file,
        "--at does not replace the file's at"
    );
    // A model's animation, by name and by index, is the one --animation picks.
    let named = scene(d, "named.toml", "at = 0.75", "animation = \"bend\"");
    let indexed = scene(d, "indexed.toml", "at = 0.75", "animation = 0");
    for s in [&named, &indexed] {
        let img = render(&[s.to_str().unwrap()], &out("named.exr")).unwrap();
        assert!(img == from_file, "{}", s.display());
    }
    // `fps` of the file times --frames: frame 3 at 4 fps is --at 0.75.
    let fps = scene(d, "fps.toml", "fps = 4", "");
    let pattern = out("frame-%d.exr");
    render(&[fps.to_str().unwrap(), "--frames", "3..4"], &pattern)
        .unwrap_or_else(|e| panic!("{e}"));
    let frame = std::fs::read(out("frame-3.exr")).unwrap();
    assert!(
        frame == from_file,
        "frame 3 at the file's 4 fps is not --at 0.75"
    );
}

#[test]
fn bad_animation_settings_are_refused_in_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("x.png");
    let cases = [
        (
            scene(d, "negative.toml", "at = -1.0", ""),
            vec!["negative.toml", "at = -1"],
        ),
        (
            scene(d, "late.toml", "at = 1e9", ""),
            vec!["late.toml", "at"],
        ),
        (
            scene(d, "fps.toml", "fps = 0.0", ""),
            vec!["fps.toml", "fps = 0"],
        ),
        (
            scene(d, "missing.toml", "", "animation = \"run\""),
            vec!["bend.gltf", "'run'", "no such animation"],
        ),
        (
            scene(d, "index.toml", "", "animation = 7"),
            vec!["bend.gltf", "7", "no such animation"],
        ),
    ];
    for (path, words) in &cases {
        let err = render(&[path.to_str().unwrap()], &out).unwrap_err();
        let err = err.trim_end();
        assert!(!err.contains('\n'), "more than one line: {err}");
        for w in words {
            assert!(err.contains(w), "{} lacks {w:?}: {err}", path.display());
        }
    }
    // A scene without an animated glTF model: a moment has nothing to pose.
    let boxed = d.join("box.toml");
    std::fs::write(
        &boxed,
        "[render]\nat = 1.0\n\n[[model]]\nbuiltin = \"cornell\"\n",
    )
    .unwrap();
    let err = render(&[boxed.to_str().unwrap()], &out).unwrap_err();
    assert!(
        err.contains("box.toml") && err.contains("no model") && err.trim_end().lines().count() == 1,
        "{err}"
    );
    std::fs::write(
        d.join("plainbox.toml"),
        "[[model]]\nbuiltin = \"cornell\"\n",
    )
    .unwrap();
    let err = render(
        &[d.join("plainbox.toml").to_str().unwrap(), "--at", "1"],
        &out,
    )
    .unwrap_err();
    assert!(
        err.contains("plainbox.toml") && err.contains("--at 1"),
        "{err}"
    );
    // A model's animation on a model that is not glTF.
    std::fs::write(
        d.join("boxanim.toml"),
        "[[model]]\nbuiltin = \"cornell\"\nanimation = \"walk\"\n",
    )
    .unwrap();
    let err = render(&[d.join("boxanim.toml").to_str().unwrap()], &out).unwrap_err();
    assert!(
        err.contains("boxanim.toml") && err.contains("not glTF"),
        "{err}"
    );
}
