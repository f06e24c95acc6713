//! Compressed glTF files (tests/data/compressed/, written by
//! tools/make_compressed_models.py with gltfpack, gltf-transform and DracoPy): the compressed
//! and uncompressed versions of one model give identical triangles (world
//! positions, normals and texture coordinates, bit for bit where the
//! compression is lossless, within the filter's quantization step where it is
//! not; Draco's within its quantization step); `KHR_texture_basisu`'s KTX2
//! images decode exactly as Binomial's C++ transcoder decodes them, within the
//! codec's error of their source PNG.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Vec2, Vec3};
use raylab::load::gltf::{GltfScene, load_gltf};
use raylab::textures::{ColorSpace, Image};

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

// ---- KHR_texture_basisu: KTX2 images (Basis Universal), made by Binomial's
// encoder (v1.15) from basisu-tex.png, a 64×64 RGBA texture.

fn image(name: &str) -> Image {
    Image::decode(&std::fs::read(data(name)).unwrap(), name)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every channel of every texel as its stored 8-bit value.
fn bytes_of(image: &Image) -> Vec<u8> {
    let mut out = Vec::new();
    for y in 0..image.height() {
        for x in 0..image.width() {
            let t = image.texel(x, y, ColorSpace::Linear);
            out.extend(t.to_array().map(|v| (v * 255.0).round() as u8));
        }
    }
    out
}

/// PSNR (dB) and largest difference (in 8-bit steps) over every channel.
fn psnr_and_max(a: &Image, b: &Image) -> (f64, u8) {
    let (a, b) = (bytes_of(a), bytes_of(b));
    assert_eq!(a.len(), b.len());
    let mut sq = 0.0f64;
    let mut max = 0u8;
    for (&x, &y) in a.iter().zip(&b) {
        let d = x.abs_diff(y);
        sq += f64::from(d) * f64::from(d);
        max = max.max(d);
    }
    let mse = sq / a.len() as f64;
    (10.0 * (255.0f64 * 255.0 / mse).log10(), max)
}

#[test]
fn ktx2_images_decode_exactly_as_binomials_transcoder_does() {
    // The reference PNGs are the C++ tool's own decoding (`basisu -unpack`):
    // UASTC through its lossless transcode to ASTC 4×4, ETC1S through ETC2
    // (its ETC1 colour blocks and EAC alpha from the alpha slice). raylab's
    // pure-Rust transcoder must give the same bytes, alpha included.
    for (ktx2, reference) in [
        ("basisu-uastc.ktx2", "basisu-uastc.ref.png"),
        ("basisu-uastc-zstd.ktx2", "basisu-uastc.ref.png"),
        ("basisu-etc1s.ktx2", "basisu-etc1s.ref.png"),
    ] {
        let (ours, theirs) = (image(ktx2), image(reference));
        assert_eq!((ours.width(), ours.height(), ours.channels()), (64, 64, 4));
        assert_eq!(ours.channels(), theirs.channels());
        assert!(
            bytes_of(&ours) == bytes_of(&theirs),
            "{ktx2} differs from {reference}"
        );
    }
}

#[test]
fn ktx2_images_stay_within_their_codecs_error_of_the_source_png() {
    // UASTC (8 bits a texel) is near-lossless: the encoder's measured error
    // on this texture is 44.0 dB PSNR, 7 steps at most; ETC1S (here 2.7
    // bits a texel: 5-bit endpoint colours, one per 4×4 block with four
    // intensity offsets) is coarser: 31.8 dB, 31 steps. The bounds leave a
    // margin below those, and far above what a wrong decoding (a flipped,
    // swizzled or shifted image) gives: under 15 dB.
    let source = image("basisu-tex.png");
    for (ktx2, min_psnr, max_error) in [
        ("basisu-uastc.ktx2", 40.0, 8),
        ("basisu-uastc-zstd.ktx2", 40.0, 8),
        ("basisu-etc1s.ktx2", 30.0, 40),
    ] {
        let (psnr, max) = psnr_and_max(&image(ktx2), &source);
        eprintln!("{ktx2}: {psnr:.2} dB, at most {max} steps from the PNG");
        assert!(
            psnr >= min_psnr && max <= max_error,
            "{ktx2}: {psnr} dB, {max}"
        );
    }
    // The same picture flipped upside down is far from it (the bound above
    // tells orientations apart).
    let flipped = Image::from_u8(64, 64, 4, {
        let b = bytes_of(&source);
        b.chunks(64 * 4).rev().flatten().copied().collect()
    });
    assert!(psnr_and_max(&flipped, &source).0 < 20.0);
}

#[test]
fn zstd_supercompression_is_lossless() {
    assert!(bytes_of(&image("basisu-uastc-zstd.ktx2")) == bytes_of(&image("basisu-uastc.ktx2")));
}

#[test]
fn the_gltf_loader_uses_the_ktx2_image_over_the_core_one() {
    // basisu-fallback.gltf's texture names the ETC1S image in the extension
    // and the PNG as its core source: the extension's image wins.
    let scene = load("basisu-fallback.gltf");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.parts.textures.len(), 1);
    let loaded = scene.parts.textures.get(0);
    assert!(bytes_of(loaded) == bytes_of(&image("basisu-etc1s.ktx2")));
    // The same torus as the PNG file.
    assert!(triangles(&scene) == triangles(&load("basisu-png.gltf")));
}

/// `raylab render FILE` with the flat integrator (each pixel the mean base
/// colour its samples see): the image.
fn render_flat(file: &Path) -> raylab::film::Film {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .arg("render")
        .arg(file)
        .args(["--width", "48", "--height", "32", "--spp", "4"])
        .args(["--integrator", "flat", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    raylab::film::read_exr(&exr).unwrap()
}

#[test]
fn a_basisu_required_file_renders_as_the_png_file_within_the_codecs_error() {
    // Both renders take the same samples on the same torus; only the texels
    // differ. A flat pixel is a weighted mean (bilinear weights, samples) of
    // linear texel values, so it differs by at most the largest linear
    // difference of a texel (UASTC + Zstandard vs the PNG), measured here.
    let (ktx2, png) = (image("basisu-uastc-zstd.ktx2"), image("basisu-tex.png"));
    let mut bound = 0.0f32;
    for y in 0..64 {
        for x in 0..64 {
            let d = ktx2.texel(x, y, ColorSpace::Srgb) - png.texel(x, y, ColorSpace::Srgb);
            bound = bound.max(d.truncate().abs().max_element());
        }
    }
    let a = render_flat(&data("basisu-required.gltf"));
    let b = render_flat(&data("basisu-png.gltf"));
    let mut largest = 0.0f32;
    let mut covered = 0;
    for y in 0..32 {
        for x in 0..48 {
            let (pa, pb) = (a.get(x, y), b.get(x, y));
            largest = largest.max((pa - pb).abs().max_element());
            covered += usize::from(pb.max_element() > 0.0);
        }
    }
    eprintln!("renders differ by at most {largest} (texels by {bound})");
    assert!(covered > 100, "the torus covers only {covered} pixels");
    assert!(largest > 0.0, "the KTX2 image was not used");
    assert!(largest <= bound * 1.0001 + 1e-6, "{largest} > {bound}");
}

#[test]
fn a_corrupt_ktx2_image_is_refused_in_one_line() {
    let good = std::fs::read(data("basisu-uastc-zstd.ktx2")).unwrap();
    let doc = std::fs::read(data("basisu-required.gltf")).unwrap();
    let level_offset = u64::from_le_bytes(good[80..88].try_into().unwrap()) as usize;
    let corruptions: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "cut short",
            good[..good.len() - 100].to_vec(),
            "outside the file",
        ),
        ("header only", good[..60].to_vec(), "too few"),
        (
            "a huge width",
            patch(&good, 20, &u32::MAX.to_le_bytes()),
            "too large",
        ),
        (
            "a level count of 40",
            patch(&good, 40, &40u32.to_le_bytes()),
            "mip levels",
        ),
        (
            "three faces",
            patch(&good, 36, &3u32.to_le_bytes()),
            "2D image",
        ),
        (
            "an unknown supercompression",
            patch(&good, 44, &7u32.to_le_bytes()),
            "supercompression scheme 7",
        ),
        (
            "a lying uncompressed length",
            patch(&good, 96, &(1u64 << 40).to_le_bytes()),
            "not the 4096",
        ),
        (
            "a zstd frame header damaged",
            patch(&good, level_offset, &[0; 4]),
            "not a Zstandard frame",
        ),
        (
            // The last entry's padding one byte past kvdByteLength: the
            // transcoder's own scan (basisu 0.1.0) would panic on it.
            "key/value padding past its length",
            patch(&good, 60, &35u32.to_le_bytes()),
            "runs past the key/value data's 35 bytes",
        ),
        (
            "a key/value entry longer than the data",
            patch(&good, 148, &33u32.to_le_bytes()),
            "runs past the key/value data's 36 bytes",
        ),
        (
            "zstd data damaged",
            patch(&good, level_offset + 40, &[0xff; 16]),
            "does not transcode",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("basisu-required.gltf");
    std::fs::write(&file, &doc).unwrap();
    for (what, bytes, says) in corruptions {
        std::fs::write(dir.path().join("basisu-uastc-zstd.ktx2"), &bytes).unwrap();
        let err = load_gltf(&file).unwrap_err().to_string();
        assert_eq!(err.lines().count(), 1, "{what}: {err}");
        for part in [
            "basisu-required.gltf",
            "image 0",
            "KHR_texture_basisu",
            says,
        ] {
            assert!(err.contains(part), "{what}: no {part:?} in {err}");
        }
    }
    // Through the command line: exit code 1 and one line.
    let (code, err) = render(&file);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// `bytes` with `with` written at `at`.
fn patch(bytes: &[u8], at: usize, with: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out[at..at + with.len()].copy_from_slice(with);
    out
}

/// basisu-uastc.ktx2 with its one key/value entry (`KTXwriter`, 31 bytes)
/// rewritten in place as `key` = `value` (NUL-padded to the same length).
fn with_metadata(key: &str, value: &str) -> Vec<u8> {
    let mut bytes = std::fs::read(data("basisu-uastc.ktx2")).unwrap();
    let kvd = u32::from_le_bytes(bytes[56..60].try_into().unwrap()) as usize;
    assert_eq!(&bytes[kvd + 4..kvd + 14], b"KTXwriter\0");
    let mut entry = format!("{key}\0{value}\0").into_bytes();
    entry.resize(31, 0);
    bytes[kvd + 4..kvd + 35].copy_from_slice(&entry);
    bytes
}

#[test]
fn ktx2_orientation_is_honoured_and_other_swizzles_refused() {
    // "rd" (glTF's top-left origin) is the only orientation the extension
    // allows; the others mean the rows or columns are stored the other way.
    let upright = bytes_of(&image("basisu-uastc.ktx2"));
    let decode = |bytes: Vec<u8>| Image::decode(&bytes, "t.ktx2");
    let rd = decode(with_metadata("KTXorientation", "rd")).unwrap();
    assert!(bytes_of(&rd) == upright);
    let ru = decode(with_metadata("KTXorientation", "ru")).unwrap();
    let rows_reversed: Vec<u8> = upright.chunks(64 * 4).rev().flatten().copied().collect();
    assert!(bytes_of(&ru) == rows_reversed);
    let ld = decode(with_metadata("KTXorientation", "ld")).unwrap();
    let columns_reversed: Vec<u8> = upright
        .chunks(64 * 4)
        .flat_map(|row| row.chunks(4).rev().flatten().copied().collect::<Vec<_>>())
        .collect();
    assert!(bytes_of(&ld) == columns_reversed);
    assert!(decode(with_metadata("KTXswizzle", "rgba")).is_ok());
    let err = decode(with_metadata("KTXswizzle", "bgra"))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("t.ktx2: ") && err.contains("swizzle \"bgra\""),
        "{err}"
    );
}

// ------------------------------------------------------------------ Draco

/// Draco's quantization bits in the test files (gltf-transform's defaults,
/// and what tools/make_compressed_models.py asks of DracoPy).
const POSITION_BITS: i32 = 14;
const NORMAL_BITS: i32 = 10;
const TEXCOORD_BITS: i32 = 12;

/// How far a Draco-decoded value may lie from the original, componentwise,
/// for values quantized with `bits` bits over `range` (Draco's quantization
/// of positions and texture coordinates: one grid of 2^bits − 1 steps over
/// the largest extent of the attribute's bounding box, rounded to the
/// nearest step): half a step, plus f32 rounding of the values themselves.
fn grid_tolerance(range: f32, bits: i32, magnitude: f32) -> f32 {
    0.5 * range / ((1 << bits) - 1) as f32 + 4.0 * magnitude * f32::EPSILON
}

/// The same for unit normals, which Draco stores as octahedral coordinates
/// (s, t) in [−1, 1], quantized to steps of 2 / (2^bits − 2): each is off by
/// at most h = 1 / (2^bits − 2), which moves the point on the octahedron
/// |x| + |y| + |z| = 1 by at most √(h² + h² + (2h)²) = √6 h; that point lies
/// at least 1/√3 from the origin, so normalizing it moves the unit normal by
/// at most √3 · √6 h = √18 h.
fn normal_tolerance(bits: i32) -> f32 {
    18f32.sqrt() / ((1 << bits) - 2) as f32 + 4.0 * f32::EPSILON
}

/// The largest extent of the bounding box of some values.
fn extent<const N: usize>(values: impl Iterator<Item = [f32; N]>) -> f32 {
    let (mut lo, mut hi) = ([f32::MAX; N], [f32::MIN; N]);
    for v in values {
        for k in 0..N {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    (0..N).map(|k| hi[k] - lo[k]).fold(0.0, f32::max)
}

/// Pairs every triangle of `plain` with one of `draco` whose corners,
/// rotated (keeping the winding), are each within `tp` of its positions,
/// and returns the largest componentwise differences of positions, normals
/// and UVs over the pairs. Panics if some triangle has no partner: Draco's
/// edgebreaker renumbers the vertices and may rotate a triangle's corners,
/// so the two files are compared as sets of triangles, not index by index.
fn paired_differences(plain: &[[Corner; 3]], draco: &[[Corner; 3]], tp: f32) -> (f32, f32, f32) {
    assert_eq!(plain.len(), draco.len(), "triangle counts differ");
    let mut used = vec![false; draco.len()];
    let mut d = (0.0f32, 0.0f32, 0.0f32);
    let near = |a: &Corner, b: &Corner| (a.0 - b.0).abs().max_element() <= tp;
    for t in plain {
        let (j, r) = (0..draco.len())
            .filter(|&j| !used[j])
            .find_map(|j| {
                (0..3)
                    .find(|&r| (0..3).all(|k| near(&t[k], &draco[j][(k + r) % 3])))
                    .map(|r| (j, r))
            })
            .unwrap_or_else(|| panic!("no Draco triangle within {tp} of {t:?}"));
        used[j] = true;
        for k in 0..3 {
            let (a, b) = (&t[k], &draco[j][(k + r) % 3]);
            d.0 = d.0.max((a.0 - b.0).abs().max_element());
            d.1 = d.1.max((a.1 - b.1).abs().max_element());
            d.2 = d.2.max((a.2 - b.2).abs().max_element());
        }
    }
    d
}

/// Loads a Draco file without warnings and checks that it holds the plain
/// torus's triangles, each corner within the tolerance its quantization
/// implies (derived from the plain file's bounding boxes).
fn assert_draco_matches_plain(name: &str) {
    let scene = load(name);
    assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
    let plain = triangles(&load("plain-noq.glb"));
    let draco = triangles(&scene);
    let corners = || plain.iter().flatten();
    let p_range = extent(corners().map(|c| c.0.to_array()));
    let uv_range = extent(corners().map(|c| c.2.to_array()));
    let magnitude = corners()
        .map(|c| c.0.abs().max_element())
        .fold(0.0, f32::max);
    let (tp, tn, tuv) = (
        grid_tolerance(p_range, POSITION_BITS, magnitude),
        normal_tolerance(NORMAL_BITS),
        grid_tolerance(uv_range, TEXCOORD_BITS, 2.0),
    );
    let (dp, dn, duv) = paired_differences(&plain, &draco, tp);
    eprintln!(
        "{name}: positions within {dp} (allowed {tp}), normals {dn} ({tn}), UVs {duv} ({tuv})"
    );
    // Quantization did happen (the values are not the plain file's)...
    assert!(dp > 0.0 && dn > 0.0 && duv > 0.0, "{name}: not quantized?");
    // ...and stays within its step.
    assert!(dp <= tp && dn <= tn && duv <= tuv, "{name}");
}

/// The encoder method of the (first) Draco stream in a GLB: 0 sequential,
/// 1 edgebreaker (the byte after the header's version and geometry type).
fn draco_method(name: &str) -> u8 {
    let bytes = std::fs::read(data(name)).unwrap();
    let at = bytes.windows(5).position(|w| w == b"DRACO").unwrap();
    bytes[at + 8]
}

#[test]
fn gltf_transform_edgebreaker_draco_gives_the_plain_triangles_within_quantization() {
    assert_eq!(draco_method("draco-eb.glb"), 1);
    assert_draco_matches_plain("draco-eb.glb");
}

#[test]
fn gltf_transform_sequential_draco_gives_the_plain_triangles_within_quantization() {
    assert_eq!(draco_method("draco-seq.glb"), 0);
    assert_draco_matches_plain("draco-seq.glb");
}

#[test]
fn dracopy_streams_give_the_plain_triangles_within_quantization() {
    // Sequential without core data (required), edgebreaker beside the core
    // data (used only): the Draco data is what is read, not the core data.
    assert_draco_matches_plain("draco-required.gltf");
    assert_draco_matches_plain("draco-fallback.gltf");
    let (code, err) = render(&data("draco-required.gltf"));
    assert_eq!(code, Some(0), "{err}");
}

/// The bytes of a base64 data URI's payload (standard alphabet).
fn unbase64(text: &str) -> Vec<u8> {
    let digit = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let digits: Vec<u8> = text.bytes().filter(|&c| c != b'=').map(digit).collect();
    let mut out = Vec::new();
    for chunk in digits.chunks(4) {
        let v = chunk
            .iter()
            .enumerate()
            .fold(0u32, |v, (k, &d)| v | (d as u32) << (18 - 6 * k));
        out.extend(&v.to_be_bytes()[1..chunk.len()]);
    }
    out
}

/// `draco-required.gltf` with its JSON edited by `edit` and its buffer (the
/// Draco stream) by `corrupt`, written to `dir` with the buffer beside it:
/// the file's path.
fn edited_draco(
    dir: &Path,
    edit: impl FnOnce(&mut serde_json::Value),
    corrupt: impl FnOnce(&mut Vec<u8>),
) -> PathBuf {
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data("draco-required.gltf")).unwrap()).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap();
    let mut bin = unbase64(uri.split_once(',').unwrap().1);
    assert_eq!(&bin[..5], b"DRACO");
    corrupt(&mut bin);
    std::fs::write(dir.join("edited.bin"), &bin).unwrap();
    doc["buffers"][0]["uri"] = "edited.bin".into();
    doc["buffers"][0]["byteLength"] = bin.len().into();
    edit(&mut doc);
    let file = dir.join("edited.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    file
}

#[test]
fn a_bad_draco_primitive_is_refused_in_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let refuse = |file: &Path, why: &str| {
        let err = load_gltf(file).unwrap_err().to_string();
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("mesh 0 primitive 0 (KHR_draco_mesh_compression)") && err.contains(why),
            "{err}"
        );
        let (code, msg) = render(file);
        assert_eq!(code, Some(1), "{msg}");
        assert_eq!(msg.trim_end().lines().count(), 1, "{msg}");
        assert!(msg.contains("edited.gltf") && msg.contains(why), "{msg}");
    };
    // The stream's bytes after its header scrambled, every few bytes.
    let f = edited_draco(
        dir.path(),
        |_| {},
        |bin| {
            for b in bin.iter_mut().skip(20).step_by(5) {
                *b ^= 0x5a;
            }
        },
    );
    refuse(&f, "malformed");
    // Its header's magic broken.
    let f = edited_draco(dir.path(), |_| {}, |bin| bin[0] = b'X');
    refuse(&f, "no DRACO header");
    // The stream cut short (the view one byte past its buffer).
    let f = edited_draco(
        dir.path(),
        |d| {
            let len = d["bufferViews"][0]["byteLength"].as_u64().unwrap();
            d["bufferViews"][0]["byteLength"] = (len + 1).into();
        },
        |_| {},
    );
    refuse(&f, "lies outside buffer 0");
    // Accessors claiming another number of triangles or vertices.
    let f = edited_draco(
        dir.path(),
        |d| d["accessors"][3]["count"] = 3.into(),
        |_| {},
    );
    refuse(&f, "holds 576 triangles, the indices accessor 1");
    let f = edited_draco(
        dir.path(),
        |d| {
            for a in 0..3 {
                d["accessors"][a]["count"] = 324.into();
            }
        },
        |_| {},
    );
    refuse(&f, "holds 325 vertices, the accessors 324");
    // An attribute id the stream does not have.
    let f = edited_draco(
        dir.path(),
        |d| {
            let ext = &mut d["meshes"][0]["primitives"][0]["extensions"];
            ext["KHR_draco_mesh_compression"]["attributes"]["NORMAL"] = 7.into();
        },
        |_| {},
    );
    refuse(&f, "no single attribute of id 7");
    // Accessors far larger than the stream could decode to: refused before
    // anything is decoded or allocated.
    // A stream whose head claims 2^25 triangles (its face count, the varint
    // after the 11-byte header, made 4 bytes long), with an indices accessor
    // that agrees.
    let f = edited_draco(
        dir.path(),
        |d| {
            d["accessors"][3]["count"] = (3u64 << 25).into();
            let len = d["bufferViews"][0]["byteLength"].as_u64().unwrap();
            d["bufferViews"][0]["byteLength"] = (len + 2).into();
        },
        |bin| {
            assert_eq!(bin[11..13], [0xc0, 0x04], "576 triangles");
            bin.splice(11..13, [0x80, 0x80, 0x80, 0x10]);
        },
    );
    refuse(&f, "cannot come from");
}

#[test]
fn an_edgebreaker_primitive_with_morph_targets_is_refused_in_one_line() {
    // draco-fallback.gltf's primitive is edgebreaker-coded; a morph target
    // (core data, indexed like the decoded vertices) needs Google's vertex
    // order, which the decoder does not promise.
    let dir = tempfile::tempdir().unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data("draco-fallback.gltf")).unwrap()).unwrap();
    doc["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{"POSITION": 1}]);
    let file = dir.path().join("targets.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let err = load_gltf(&file).unwrap_err().to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("mesh 0 primitive 0 (KHR_draco_mesh_compression)")
            && err.contains("morph targets"),
        "{err}"
    );
}
