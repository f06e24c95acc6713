//! glTF files that the Khronos glTF-Validator reports without errors load,
//! though `gltf-json`'s types are stricter: integers written as `3.0`, an
//! animation channel whose target has no `node`, empty arrays, unused objects
//! and no `scene`; and a fraction where an integer is required (`1.5`) is
//! still refused, naming the file. Every file is written here by hand, its
//! buffer a data URI (or a GLB's binary chunk).

use std::path::{Path, PathBuf};

/// Two triangles of a unit square: four positions (f32 VEC3, bytes 0..48)
/// and six u16 indices (bytes 48..60), base64.
const SQUARE: &str =
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAAAAAAABAAIAAAACAAMA";

/// What a test adds to [`square`]: accessors and buffer views after the
/// square's two, and top-level members.
#[derive(Default)]
struct Extra<'a> {
    accessors: &'a str,
    views: &'a str,
    members: &'a str,
}

/// The square as a glTF file with `extra`; `n` writes each whole number of
/// the square's (`4` or `4.0`).
fn square(n: &dyn Fn(u32) -> String, extra: &Extra) -> String {
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": {zero},
  "scenes": [ {{ "nodes": [ {zero} ] }} ],
  "nodes": [ {{ "mesh": {zero} }} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": {zero} }}, "indices": {one} }} ] }} ],
  "accessors": [
    {{ "bufferView": {zero}, "byteOffset": {zero}, "componentType": {float}, "count": {four}, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": {one}, "componentType": {short}, "count": {six}, "type": "SCALAR" }}{accessors}
  ],
  "bufferViews": [
    {{ "buffer": {zero}, "byteOffset": {zero}, "byteLength": {b48}, "target": {array} }},
    {{ "buffer": {zero}, "byteOffset": {b48}, "byteLength": {b12}, "target": {element} }}{views}
  ],
  "buffers": [ {{ "byteLength": {b60}, "uri": "data:application/octet-stream;base64,{SQUARE}" }} ]{members}
}}"#,
        accessors = extra.accessors,
        views = extra.views,
        members = extra.members,
        zero = n(0),
        one = n(1),
        four = n(4),
        six = n(6),
        float = n(5126),
        short = n(5123),
        b48 = n(48),
        b12 = n(12),
        b60 = n(60),
        array = n(34962),
        element = n(34963),
    )
}

fn integers(x: u32) -> String {
    x.to_string()
}

fn with_fractions(x: u32) -> String {
    format!("{x}.0")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The triangles of the file at `path`, or the error message.
fn triangles(path: &Path) -> Result<usize, String> {
    raylab::load::gltf::load_gltf(path)
        .map(|g| g.parts.triangles.len())
        .map_err(|e| e.to_string())
}

#[test]
fn integers_written_with_a_fraction_load_as_integers() {
    let dir = tempfile::tempdir().unwrap();
    let plain = write(
        dir.path(),
        "plain.gltf",
        &square(&integers, &Extra::default()),
    );
    assert_eq!(triangles(&plain), Ok(2));
    // Every integer of the file as `N.0`: indices, counts, offsets, lengths,
    // enums; and `1e0`, an exponent, for the index accessor.
    let text = square(&with_fractions, &Extra::default())
        .replace(r#""indices": 1.0"#, r#""indices": 1e0"#);
    assert!(text.contains("\"count\": 4.0") && text.contains("\"mesh\": 0.0"));
    let fractions = write(dir.path(), "fractions.gltf", &text);
    assert_eq!(triangles(&fractions), Ok(2));
}

#[test]
fn a_fraction_where_an_integer_is_required_is_refused_with_the_file_named() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        square(&with_fractions, &Extra::default()).replace("\"count\": 4.0", "\"count\": 1.5");
    let path = write(dir.path(), "half-count.gltf", &text);
    let err = triangles(&path).unwrap_err();
    assert!(
        err.contains("half-count.gltf") && err.contains("1.5") && !err.contains('\n'),
        "{err}"
    );
    // Without the other numbers' fractions the strict reading's message
    // (with its line and column) is kept.
    let text = square(&integers, &Extra::default()).replace("\"count\": 4,", "\"count\": 1.5,");
    let path = write(dir.path(), "strict.gltf", &text);
    let err = triangles(&path).unwrap_err();
    assert!(
        err.contains("strict.gltf") && err.contains("1.5") && err.contains("line"),
        "{err}"
    );
    // And beyond 2⁶⁴, or negative, is no integer either.
    for bad in ["18446744073709551616.0", "-4.0"] {
        let text = square(&with_fractions, &Extra::default())
            .replace("\"count\": 4.0", &format!("\"count\": {bad}"));
        let path = write(dir.path(), "huge.gltf", &text);
        let err = triangles(&path).unwrap_err();
        assert!(err.contains("huge.gltf"), "{bad}: {err}");
    }
}

#[test]
fn animation_channels_without_a_node_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    // One channel targets the node, one has no node (as KHR_animation_pointer
    // writes them). The keyframe is the buffer's first 16 bytes: time 0 and
    // the translation (0, 0, 1).
    let animation = Extra {
        accessors: r#",
    { "bufferView": 2, "componentType": 5126, "count": 1, "type": "SCALAR", "min": [0], "max": [0] },
    { "bufferView": 2, "byteOffset": 4, "componentType": 5126, "count": 1, "type": "VEC3" }"#,
        views: r#",
    { "buffer": 0, "byteLength": 16 }"#,
        members: r#",
  "animations": [ {
    "channels": [
      { "sampler": 0, "target": { "node": 0, "path": "translation" } },
      { "sampler": 0, "target": { "path": "translation" } }
    ],
    "samplers": [ { "input": 2, "output": 3, "interpolation": "STEP" } ]
  } ]"#,
    };
    let path = write(dir.path(), "pointer.gltf", &square(&integers, &animation));
    assert_eq!(triangles(&path), Ok(2));
    // With integers written as `N.0` too: both tolerated at once.
    let path = write(
        dir.path(),
        "both.gltf",
        &square(&with_fractions, &animation),
    );
    assert_eq!(triangles(&path), Ok(2));
    // A channel whose target is not an object is still an error.
    let broken = Extra {
        members: r#",
  "animations": [ { "channels": [ { "sampler": 0, "target": 7 } ], "samplers": [] } ]"#,
        ..Extra::default()
    };
    let path = write(dir.path(), "broken.gltf", &square(&with_fractions, &broken));
    let err = triangles(&path).unwrap_err();
    assert!(err.contains("broken.gltf"), "{err}");
}

#[test]
fn empty_arrays_unused_objects_and_no_scene_load() {
    let dir = tempfile::tempdir().unwrap();
    let empty = r#"{ "asset": { "version": "2.0" }, "scenes": [], "nodes": [], "meshes": [],
        "accessors": [], "bufferViews": [], "buffers": [], "materials": [], "animations": [] }"#;
    assert_eq!(triangles(&write(dir.path(), "empty.gltf", empty)), Ok(0));
    let asset_only = r#"{ "asset": { "version": "2.0" } }"#;
    assert_eq!(
        triangles(&write(dir.path(), "asset.gltf", asset_only)),
        Ok(0)
    );
    let empty_scene =
        r#"{ "asset": { "version": "2.0" }, "scene": 0, "scenes": [ { "nodes": [] } ] }"#;
    assert_eq!(
        triangles(&write(dir.path(), "scene.gltf", empty_scene)),
        Ok(0)
    );
    // No `scene`: the first scene is shown; an unused node, mesh, material
    // and camera change nothing.
    let unused = square(
        &integers,
        &Extra {
            members: r#",
  "materials": [ { "name": "unused" } ],
  "cameras": [ { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } } ]"#,
            ..Extra::default()
        },
    )
    .replace("\"scene\": 0,\n", "")
    .replace(
        "\"nodes\": [ { \"mesh\": 0 } ]",
        "\"nodes\": [ { \"mesh\": 0 }, { \"mesh\": 1, \"camera\": 0 } ]",
    )
    .replace(
        "\"meshes\": [ {",
        "\"meshes\": [ { \"primitives\": [ { \"attributes\": { \"POSITION\": 0 }, \"indices\": 1, \"material\": 0 } ] }, {",
    )
    .replace("\"mesh\": 0 },", "\"mesh\": 1 },");
    assert!(!unused.contains("\"scene\""), "{unused}");
    assert_eq!(
        triangles(&write(dir.path(), "unused.gltf", &unused)),
        Ok(2),
        "{unused}"
    );
}

#[test]
fn glb_files_are_read_as_tolerantly() {
    let dir = tempfile::tempdir().unwrap();
    let decode = |b64: &str| raylab::load::gltf::decode_base64(b64).unwrap();
    let json = square(&with_fractions, &Extra::default()).replace(
        &format!(", \"uri\": \"data:application/octet-stream;base64,{SQUARE}\""),
        "",
    );
    assert!(!json.contains("uri"), "{json}");
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let bin = decode(SQUARE);
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    let path = dir.path().join("fractions.glb");
    std::fs::write(&path, &glb).unwrap();
    assert_eq!(triangles(&path), Ok(2));
}

#[test]
fn scenes_without_nodes_and_extras_of_any_type_load() {
    let dir = tempfile::tempdir().unwrap();
    // A scene's `nodes` is optional; `extras` may be any JSON value.
    let no_nodes = r#"{ "asset": { "version": "2.0" }, "scenes": [ { "name": "empty" } ] }"#;
    assert_eq!(triangles(&write(dir.path(), "scene.gltf", no_nodes)), Ok(0));
    for extras in ["42", "\"text\"", "true", "[1, 2]", "null", "{ \"a\": 1 }"] {
        let text = square(&integers, &Extra::default()).replace(
            "\"nodes\": [ { \"mesh\": 0 } ]",
            &format!(
                "\"nodes\": [ {{ \"mesh\": 0, \"extras\": {extras} }} ], \"extras\": {extras}"
            ),
        );
        assert!(text.contains("extras"), "{text}");
        assert_eq!(
            triangles(&write(dir.path(), "extras.gltf", &text)),
            Ok(2),
            "extras {extras}"
        );
    }
}

#[test]
fn buffers_that_cannot_be_read_matter_only_when_used() {
    let dir = tempfile::tempdir().unwrap();
    // Unused buffers raylab cannot read: without a URI in a .gltf, remote,
    // a data URI that is not base64, a missing file. The square still loads.
    let unused = r#"{ "byteLength": 4 }, { "byteLength": 4, "uri": "https://example.com/b.bin" },
    { "byteLength": 1, "uri": "data:application/gltf-buffer,0" }, { "byteLength": 4, "uri": "missing.bin" }"#;
    let text = square(&integers, &Extra::default())
        .replace("\"buffers\": [ {", &format!("\"buffers\": [ {unused}, {{"));
    // The square's own buffer is now the fifth.
    let text = text.replace("\"buffer\": 0,", "\"buffer\": 4,");
    assert_eq!(triangles(&write(dir.path(), "unused.gltf", &text)), Ok(2));
    // Vertices in the buffer without a URI, which has no data at all (a
    // placeholder, which the glTF-Validator accepts): nothing to render, the
    // primitive skipped with a warning.
    let placeholder = text.replacen("\"buffer\": 4,", "\"buffer\": 0,", 1);
    let loaded =
        raylab::load::gltf::load_gltf(&write(dir.path(), "placeholder.gltf", &placeholder))
            .unwrap();
    assert_eq!(loaded.parts.triangles.len(), 0);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("buffer 0, which has no data")),
        "{:?}",
        loaded.warnings
    );
    // Indices there (the vertices readable): refused, as are the other
    // buffers used at all, each in one line naming the file, the view and
    // why.
    let second = text.match_indices("\"buffer\": 4,").nth(1).unwrap().0;
    let indices = format!(
        "{}\"buffer\": 0,{}",
        &text[..second],
        &text[second + "\"buffer\": 4,".len()..]
    );
    let err = triangles(&write(dir.path(), "indices.gltf", &indices)).unwrap_err();
    assert!(
        err.contains("indices.gltf")
            && err.contains("buffer view 1")
            && err.contains("buffer 0 has no URI"),
        "{err}"
    );
    for (k, why) in [
        (1, "https://example.com/b.bin is not a local file"),
        (2, "not base64"),
        (3, "missing.bin"),
    ] {
        let used = text.replacen("\"buffer\": 4,", &format!("\"buffer\": {k},"), 1);
        let err = triangles(&write(dir.path(), "used.gltf", &used)).unwrap_err();
        assert!(
            err.contains("used.gltf") && err.contains("buffer view 0") && err.contains(why),
            "buffer {k}: {err}"
        );
        assert!(!err.contains('\n'), "{err}");
    }
}
