//! glTF 2.0 files that must not load, or that load with a warning: each bad
//! file is refused with one line naming the file and the problem; an unknown
//! optional extension only warns; GLB files load and their lying lengths are
//! refused. Every file is written by the test itself (see
//! `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::path::Path;

use builder::{F32, FLOOR, Gltf, U16, add_floor, bytes_f32, load, load_err};
use glam::Vec3A;
use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// Bad files

/// A valid one-triangle file; `edit` changes its JSON before it is written.
fn bad_file(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> String {
    let mut g = Gltf::new();
    let pos = g.floats(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let idx = g.indices(U16, &[0, 1, 2]);
    let mesh = g.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    g.root(json!({ "mesh": mesh }));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        builder::base64(&g.buffer)
    );
    let mut v = g.to_json(Some(uri));
    edit(&mut v);
    let path = builder::write_json(dir, name, &v);
    load_err(&path)
}

/// The buffer of a file with `data` in it, as a data URI with its byte length.
fn buffer_of(data: &[u8]) -> Value {
    json!([{
        "byteLength": data.len(),
        "uri": format!("data:application/octet-stream;base64,{}", builder::base64(data))
    }])
}

#[track_caller]
fn assert_names(err: &str, file: &str, problem: &[&str]) {
    assert!(
        err.contains(file),
        "the message does not name {file}: {err}"
    );
    for p in problem {
        assert!(err.contains(p), "the message does not say '{p}': {err}");
    }
}

#[test]
fn bad_files_are_refused_with_the_file_and_the_problem_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();

    let err = bad_file(d, "missing-buffer.gltf", |v| {
        v["buffers"][0]["uri"] = json!("missing.bin");
    });
    assert_names(&err, "missing-buffer.gltf", &["missing.bin"]);

    let err = bad_file(d, "index-range.gltf", |v| {
        // Indices 0, 1, 7 of three vertices.
        v["buffers"] = buffer_of(
            &[
                bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
                [0u16, 1, 7, 0].map(u16::to_le_bytes).concat(),
            ]
            .concat(),
        );
    });
    assert_names(&err, "index-range.gltf", &["index 7", "out of range"]);

    let err = bad_file(d, "accessor-past-view.gltf", |v| {
        v["accessors"][0]["count"] = json!(4);
    });
    assert_names(
        &err,
        "accessor-past-view.gltf",
        &["4 elements", "do not fit"],
    );

    let err = bad_file(d, "accessor-offset-past-view.gltf", |v| {
        v["accessors"][0]["byteOffset"] = json!(4);
    });
    assert_names(&err, "accessor-offset-past-view.gltf", &["do not fit"]);

    let err = bad_file(d, "view-past-buffer.gltf", |v| {
        v["bufferViews"][1]["byteLength"] = json!(1000);
    });
    assert_names(&err, "view-past-buffer.gltf", &["buffer view 1", "outside"]);

    let err = bad_file(d, "short-buffer.gltf", |v| {
        v["buffers"][0]["byteLength"] = json!(4096);
    });
    assert_names(&err, "short-buffer.gltf", &["buffer 0", "4096"]);

    let err = bad_file(d, "required-extension.gltf", |v| {
        v["extensionsUsed"] = json!(["EXT_imaginary_compression"]);
        v["extensionsRequired"] = json!(["EXT_imaginary_compression"]);
    });
    assert_names(
        &err,
        "required-extension.gltf",
        &["EXT_imaginary_compression"],
    );

    let err = bad_file(d, "nan.gltf", |v| {
        v["buffers"] = buffer_of(
            &[
                bytes_f32(&[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0]),
                [0u16, 1, 2, 0].map(u16::to_le_bytes).concat(),
            ]
            .concat(),
        );
    });
    assert_names(&err, "nan.gltf", &["POSITION 1", "not finite"]);

    let err = bad_file(d, "cycle.gltf", |v| {
        v["nodes"] =
            json!([{ "children": [1] }, { "children": [2] }, { "children": [0], "mesh": 0 }]);
        v["scenes"] = json!([{ "nodes": [0] }]);
    });
    assert_names(&err, "cycle.gltf", &["node 0", "twice"]);

    let err = bad_file(d, "self-child.gltf", |v| {
        v["nodes"] = json!([{ "children": [0], "mesh": 0 }]);
    });
    assert_names(&err, "self-child.gltf", &["node 0"]);

    let err = bad_file(d, "huge-count.gltf", |v| {
        v["accessors"][0]["count"] = json!(1u64 << 31);
    });
    assert_names(&err, "huge-count.gltf", &["2147483648"]);

    let err = bad_file(d, "huge-index-count.gltf", |v| {
        v["accessors"][1]["count"] = json!(1u64 << 31);
    });
    assert_names(&err, "huge-index-count.gltf", &["2147483648"]);

    let err = bad_file(d, "huge-viewless.gltf", |v| {
        v["accessors"][0] = json!({ "componentType": F32, "count": 1u64 << 31, "type": "VEC3" });
    });
    assert_names(&err, "huge-viewless.gltf", &["2147483648"]);

    let err = bad_file(d, "missing-accessor.gltf", |v| {
        v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    });
    assert_names(&err, "missing-accessor.gltf", &["accessor 9"]);

    let err = bad_file(d, "missing-mesh.gltf", |v| {
        v["nodes"][0]["mesh"] = json!(4);
    });
    assert_names(&err, "missing-mesh.gltf", &["mesh 4"]);

    let err = bad_file(d, "missing-material.gltf", |v| {
        v["meshes"][0]["primitives"][0]["material"] = json!(3);
    });
    assert_names(&err, "missing-material.gltf", &["material 3"]);

    let err = bad_file(d, "bad-base64.gltf", |v| {
        v["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAA*AAAA");
    });
    assert_names(&err, "bad-base64.gltf", &["buffer 0", "base64"]);

    let err = bad_file(d, "not-json.gltf", |v| *v = json!("just a string"));
    assert_names(&err, "not-json.gltf", &["JSON"]);

    let err = bad_file(d, "sparse-too-many.gltf", |v| {
        v["accessors"][0]["sparse"] = json!({
            "count": 4,
            "indices": { "bufferView": 1, "componentType": U16 },
            "values": { "bufferView": 0 },
        });
    });
    assert_names(&err, "sparse-too-many.gltf", &["sparse", "4 of 3"]);

    let err = bad_file(d, "sparse-index-range.gltf", |v| {
        // Sparse indices 0, 1, 2 → the index view holds 0, 1, 2; make one 9.
        v["buffers"] = buffer_of(
            &[
                bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
                [0u16, 9, 2, 0].map(u16::to_le_bytes).concat(),
            ]
            .concat(),
        );
        v["accessors"][0]["sparse"] = json!({
            "count": 2,
            "indices": { "bufferView": 1, "componentType": U16 },
            "values": { "bufferView": 0 },
        });
    });
    assert_names(&err, "sparse-index-range.gltf", &["sparse index 9"]);

    let err = bad_file(d, "infinite-translation.gltf", |v| {
        v["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]);
    });
    assert_names(&err, "infinite-translation.gltf", &["node 0"]);

    let err = bad_file(d, "missing-image.gltf", |v| {
        v["images"] = json!([{ "uri": "missing.png" }]);
        v["textures"] = json!([{ "source": 0 }]);
        v["materials"] =
            json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
        v["meshes"][0]["primitives"][0]["material"] = json!(0);
    });
    assert_names(&err, "missing-image.gltf", &["missing.png"]);

    let err = bad_file(d, "not-an-image.gltf", |v| {
        let uri = format!(
            "data:image/png;base64,{}",
            builder::base64(b"GIF89a, not a PNG")
        );
        v["images"] = json!([{ "uri": uri }]);
        v["textures"] = json!([{ "source": 0 }]);
        v["materials"] =
            json!([{ "emissiveTexture": { "index": 0 }, "emissiveFactor": [1.0, 1.0, 1.0] }]);
        v["meshes"][0]["primitives"][0]["material"] = json!(0);
    });
    assert_names(&err, "not-an-image.gltf", &["image 0"]);
}

#[test]
fn an_unknown_optional_extension_only_warns() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    add_floor(&mut g, None);
    g.extensions_used.push("EXT_imaginary_sparkle".into());
    let loaded = load(&g.write(dir.path(), "optional-extension.gltf"));
    assert_eq!(loaded.scene.triangles().len(), 2);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("EXT_imaginary_sparkle")),
        "{:?}",
        loaded.warnings
    );
}

#[test]
fn glb_files_load_and_lying_lengths_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    add_floor(&mut g, None);
    let glb = g.glb();
    let good = dir.path().join("good.glb");
    std::fs::write(&good, &glb).unwrap();
    let loaded = load(&good);
    assert_eq!(loaded.scene.triangles()[0].v[0], Vec3A::from(FLOOR[0]));

    // The header claims more bytes than the file has.
    let mut lie = glb.clone();
    lie[8..12].copy_from_slice(&(glb.len() as u32 + 100).to_le_bytes());
    let path = dir.path().join("long-header.glb");
    std::fs::write(&path, &lie).unwrap();
    assert_names(&load_err(&path), "long-header.glb", &["GLB"]);

    // The JSON chunk claims to run past the end.
    let mut lie = glb.clone();
    lie[12..16].copy_from_slice(&(glb.len() as u32).to_le_bytes());
    let path = dir.path().join("long-chunk.glb");
    std::fs::write(&path, &lie).unwrap();
    assert_names(&load_err(&path), "long-chunk.glb", &["GLB", "chunk"]);

    // The binary chunk (consistently) shorter than buffer 0's byteLength.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let bin_len = u32::from_le_bytes(glb[bin_at..bin_at + 4].try_into().unwrap()) as usize;
    let mut lie = glb.clone();
    lie.truncate(glb.len() - 8);
    lie[8..12].copy_from_slice(&(glb.len() as u32 - 8).to_le_bytes());
    lie[bin_at..bin_at + 4].copy_from_slice(&(bin_len as u32 - 8).to_le_bytes());
    let path = dir.path().join("short-bin.glb");
    std::fs::write(&path, &lie).unwrap();
    assert_names(&load_err(&path), "short-bin.glb", &["buffer 0", "declares"]);

    // Cut off inside the header.
    let path = dir.path().join("truncated.glb");
    std::fs::write(&path, &glb[..6]).unwrap();
    assert_names(&load_err(&path), "truncated.glb", &["GLB"]);
}
