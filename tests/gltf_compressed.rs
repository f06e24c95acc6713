//! Compressed glTF files (tests/data/compressed/, written by
//! tools/make_compressed_models.py with gltfpack and DracoPy): the compressed
//! and uncompressed versions of one model give identical triangles (world
//! positions, normals and texture coordinates, bit for bit where the
//! compression is lossless, within the filter's quantization step where it is
//! not); what raylab cannot decode (Draco, Basis Universal) is refused in one
//! line naming the extension and the file when required, and read from the
//! core data otherwise.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Vec2, Vec3};
use raylab::load::gltf::{GltfScene, load_gltf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/compressed")
        .join(name)
}

fn load(name: &str) -> GltfScene {
    load_gltf(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// One triangle's corners in the world: position, unit normal, first UV set.
type Corner = (Vec3, Vec3, Vec2);

/// Every triangle of every instance, as a set (see [`canonical`]).
fn triangles(scene: &GltfScene) -> Vec<[Corner; 3]> {
    let parts = &scene.parts;
    let mut out = Vec::new();
    for inst in &parts.instances {
        let m = &parts.meshes[inst.mesh as usize];
        for tri in &m.indices {
            out.push(tri.map(|i| {
                let i = i as usize;
                let p = Vec3::from(inst.to_world.transform_point3a(m.positions[i].into()));
                let n =
                    Vec3::from(inst.normal_to_world * glam::Vec3A::from(m.normals[i])).normalize();
                (p, n, m.uvs[0][i])
            }));
        }
    }
    canonical(out)
}

/// The bits of a corner, for ordering.
fn key(c: &Corner) -> [u32; 8] {
    let (p, n, t) = c;
    [p.x, p.y, p.z, n.x, n.y, n.z, t.x, t.y].map(f32::to_bits)
}

/// The triangles as a set: each rotated (keeping its winding) to start at
/// its smallest corner, then sorted. gltfpack orders triangles and vertices
/// for its codec when it compresses (`-c`), so the two files hold the same
/// triangles in different orders.
fn canonical(mut tris: Vec<[Corner; 3]>) -> Vec<[Corner; 3]> {
    for t in &mut tris {
        let first = (0..3).min_by_key(|&k| key(&t[k])).unwrap();
        t.rotate_left(first);
    }
    tris.sort_by_key(|t| t.each_ref().map(key));
    tris
}

/// The largest difference, over every triangle corner, of positions, normals
/// and UVs (componentwise), after checking both have the same triangles.
fn largest_differences(a: &[[Corner; 3]], b: &[[Corner; 3]]) -> (f32, f32, f32) {
    assert_eq!(a.len(), b.len(), "triangle counts differ");
    let mut d = (0.0f32, 0.0f32, 0.0f32);
    for (ta, tb) in a.iter().zip(b) {
        for (ca, cb) in ta.iter().zip(tb) {
            d.0 = d.0.max((ca.0 - cb.0).abs().max_element());
            d.1 = d.1.max((ca.1 - cb.1).abs().max_element());
            d.2 = d.2.max((ca.2 - cb.2).abs().max_element());
        }
    }
    d
}

/// The torus has 24 × 12 quads.
const TRIANGLES: usize = 2 * 24 * 12;

/// Loads two files without warnings and checks that they hold the torus's
/// triangles, bit for bit the same f32s (not merely close ones).
fn assert_same_triangles(a: &str, b: &str) {
    let (sa, sb) = (load(a), load(b));
    for (name, s) in [(a, &sa), (b, &sb)] {
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
    let (ta, tb) = (triangles(&sa), triangles(&sb));
    assert_eq!(ta.len(), TRIANGLES);
    assert!(ta == tb, "{a} vs {b}: {:?}", largest_differences(&ta, &tb));
}

#[test]
fn meshopt_lossless_float_data_gives_identical_triangles() {
    assert_same_triangles("plain-noq.glb", "meshopt-noq.glb");
}

#[test]
fn meshopt_quantized_data_gives_identical_triangles() {
    assert_same_triangles("plain-q.glb", "meshopt-q.glb");
}

#[test]
fn meshopt_octahedral_normals_stay_within_their_quantization_step() {
    // gltfpack -cc stores the normals with the octahedral filter (8-bit
    // components): positions and UVs are the same integers as the plain
    // file's, normals differ by the octahedral encoding's rounding.
    let plain = triangles(&load("plain-q.glb"));
    let packed = triangles(&load("meshopt-cc.glb"));
    let (dp, dn, duv) = largest_differences(&plain, &packed);
    assert_eq!((dp, duv), (0.0, 0.0));
    // One step of an 8-bit signed normalized component is 1/127 ≈ 0.0079;
    // the octahedral map at 8 bits is coarser near the octahedron's edges.
    eprintln!("octahedral normals differ by at most {dn}");
    assert!(dn > 0.0, "the filter was not applied");
    assert!(dn <= 3.0 / 127.0, "normals differ by {dn}");
}

#[test]
fn khr_meshopt_version_1_codec_gives_the_same_triangles_as_ext() {
    assert_same_triangles("meshopt-cc.glb", "meshopt-khr.glb");
}

#[test]
fn meshopt_fallback_buffers_are_never_read() {
    assert_same_triangles("meshopt-q.glb", "meshopt-fallback.gltf");
    let packed = triangles(&load("meshopt-q.glb"));
    // Without its fallback file the model loads the same.
    let dir = tempfile::tempdir().unwrap();
    for f in ["meshopt-fallback.gltf", "meshopt-fallback.bin"] {
        std::fs::copy(data(f), dir.path().join(f)).unwrap();
    }
    let scene = load_gltf(&dir.path().join("meshopt-fallback.gltf")).unwrap();
    assert!(triangles(&scene) == packed);
}

#[test]
fn a_meshopt_placeholder_buffer_without_a_uri_is_not_read() {
    // The fallback file made into one that requires the extension, with a
    // placeholder buffer (no URI, no `fallback` mark), as the spec allows.
    let dir = tempfile::tempdir().unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data("meshopt-fallback.gltf")).unwrap()).unwrap();
    let b = &mut doc["buffers"][1];
    b.as_object_mut().unwrap().remove("uri");
    b.as_object_mut().unwrap().remove("extensions");
    doc["extensionsRequired"]
        .as_array_mut()
        .unwrap()
        .push("EXT_meshopt_compression".into());
    std::fs::copy(
        data("meshopt-fallback.bin"),
        dir.path().join("meshopt-fallback.bin"),
    )
    .unwrap();
    let file = dir.path().join("required.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = load_gltf(&file).unwrap();
    assert!(triangles(&scene) == triangles(&load("meshopt-q.glb")));
}

#[test]
fn a_corrupt_meshopt_stream_is_refused_in_one_line() {
    // The first compressed view's header byte (0xa0) flipped.
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data("meshopt-fallback.gltf")).unwrap()).unwrap();
    let view = doc["bufferViews"][1]["extensions"]["EXT_meshopt_compression"].clone();
    let offset = view["byteOffset"].as_u64().unwrap() as usize;
    let mut bin = std::fs::read(data("meshopt-fallback.bin")).unwrap();
    assert_eq!(bin[offset], 0xa0);
    bin[offset] = 0x55;
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("meshopt-fallback.bin"), &bin).unwrap();
    doc["buffers"][1]["uri"] = "missing.bin".into();
    let file = dir.path().join("corrupt.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let err = load_gltf(&file).unwrap_err().to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("buffer view 1") && err.contains("EXT_meshopt_compression"),
        "{err}"
    );
    // A stream cut short (its declared length one byte less).
    let mut doc2 = doc.clone();
    bin[offset] = 0xa0;
    std::fs::write(dir.path().join("meshopt-fallback.bin"), &bin).unwrap();
    let len = view["byteLength"].as_u64().unwrap();
    doc2["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
        (len - 1).into();
    std::fs::write(&file, serde_json::to_vec(&doc2).unwrap()).unwrap();
    let err = load_gltf(&file).unwrap_err().to_string();
    assert!(err.contains("malformed"), "{err}");
    // A count far beyond what the compressed bytes can hold is refused
    // before anything is allocated.
    let mut doc3 = doc.clone();
    let huge = 1u64 << 40;
    doc3["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["count"] = huge.into();
    doc3["bufferViews"][1]["byteLength"] = (huge * 8).into();
    std::fs::write(&file, serde_json::to_vec(&doc3).unwrap()).unwrap();
    let err = load_gltf(&file).unwrap_err().to_string();
    assert!(err.contains("cannot come from"), "{err}");
}

/// `raylab render FILE` to a tiny image: its exit code and stderr.
fn render(file: &Path) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .arg("render")
        .arg(file)
        .args([
            "--width",
            "8",
            "--height",
            "6",
            "--spp",
            "1",
            "--integrator",
            "flat",
            "-o",
        ])
        .arg(dir.path().join("out.exr"))
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn required_draco_and_basisu_are_refused_in_one_line_naming_the_extension_and_file() {
    for (file, ext) in [
        ("draco-required.gltf", "KHR_draco_mesh_compression"),
        ("basisu-required.gltf", "KHR_texture_basisu"),
    ] {
        let err = load_gltf(&data(file)).unwrap_err().to_string();
        assert!(err.contains(ext), "{err}");
        let (code, err) = render(&data(file));
        assert_eq!(code, Some(1), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(file) && err.contains(ext), "{err}");
    }
}

#[test]
fn used_but_not_required_draco_and_basisu_fall_back_to_the_core_data() {
    // Both files carry the source torus's core accessors and its PNG; they
    // give the same triangles as each other, and the PNG's 8×8 texture.
    let draco = load("draco-fallback.gltf");
    let basisu = load("basisu-fallback.gltf");
    for (scene, ext) in [
        (&draco, "KHR_draco_mesh_compression"),
        (&basisu, "KHR_texture_basisu"),
    ] {
        assert!(
            scene.warnings.iter().any(|w| w.contains(ext)),
            "{:?}",
            scene.warnings
        );
        assert_eq!(scene.parts.textures.len(), 1);
    }
    let (a, b) = (triangles(&draco), triangles(&basisu));
    assert_eq!(a.len(), TRIANGLES);
    assert!(a == b);
    for (code, err) in [
        render(&data("draco-fallback.gltf")),
        render(&data("basisu-fallback.gltf")),
    ] {
        assert_eq!(code, Some(0), "{err}");
    }
}
