//! What raylab's fuzz targets share: a scratch folder with small valid files the
//! inputs can refer to, and the oracle every target applies to what loaded.
//!
//! Every target writes its input where raylab would find a user's file and
//! goes through the same public entry point the command line uses
//! (`raylab::load::load`), so the fuzzers see the real code path, with the
//! file names and extensions that select it. What loads is then rendered, tiny,
//! with every integrator, so that the BVH build, tangent generation, light and
//! environment sampling and the materials run on whatever the parser let
//! through.
//!
//! The oracle: an error is one line; a render gives finite pixels and drops no
//! NaN/Inf samples in a scene of sane size.

pub mod bvh;
pub mod targets;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::Vec3A;
use raylab::camera::{Focus, FocusedLens};
use raylab::load::{EnvSource, LoadOptions};
use raylab::render::{RenderSettings, render};
use raylab::{Camera, Integrator};

/// The per-process scratch folder (in `/dev/shm` when there is one: every
/// execution writes its input there), filled once with the fixtures.
pub fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let base = if Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let dir = base.join(format!("raylab-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        write_fixtures(&dir);
        dir
    })
}

/// Writes `bytes` as `name` in the scratch folder and returns its path.
pub fn put(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch().join(name);
    std::fs::write(&path, bytes).expect("scratch write");
    path
}

/// A one-triangle OBJ with normals and texture coordinates, its material in
/// `fixture.mtl` (textured by `fixture.png`).
pub const FIXTURE_OBJ: &str = "mtllib fixture.mtl\nusemtl m\n\
v -1 -1 0\nv 1 -1 0\nv 0 1 0\nv 1 1 0\n\
vt 0 0\nvt 1 0\nvt 0.5 1\nvt 1 1\n\
vn 0 0 1\n\
f 1/1/1 2/2/1 3/3/1\nf 2/2/1 4/4/1 3/3/1\n";

/// A Mitsuba XML scene the `mitsuba_xml` inputs can include: a shared
/// material and a shape, with a default.
pub const FIXTURE_XML: &str = "<scene version=\"3.0.0\">\n\
<default name=\"r\" value=\"0.5\"/>\n\
<bsdf type=\"diffuse\" id=\"fixture_bsdf\"><rgb name=\"reflectance\" value=\"$r\"/></bsdf>\n\
<shape type=\"sphere\"><ref id=\"fixture_bsdf\"/><float name=\"radius\" value=\"2\"/></shape>\n\
</scene>\n";

/// The fixture OBJ's material.
pub const FIXTURE_MTL: &str = "newmtl m\nKd 0.8 0.7 0.6\nmap_Kd fixture.png\nnorm fixture.png\n\
newmtl lamp\nKe 2 2 2\n";

/// A glTF with one triangle whose buffer is `fixture.bin` (positions then
/// indices) and a base-colour texture `fixture.png`.
pub const FIXTURE_GLTF: &str = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
"textures":[{"source":0}],"images":[{"uri":"fixture.png"}],
"buffers":[{"uri":"fixture.bin","byteLength":44}],
"bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]}"#;

/// The bytes of `fixture.bin`: three positions and three u16 indices (and two
/// bytes of padding).
pub fn fixture_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

/// A 2×2 RGB PNG (the fixtures' texture), made without an image library: one
/// stored (uncompressed) deflate block.
pub fn fixture_png() -> Vec<u8> {
    fn crc32(data: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in data {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    fn adler32(data: &[u8]) -> u32 {
        let (mut a, mut b) = (1u32, 0u32);
        for &x in data {
            a = (a + x as u32) % 65521;
            b = (b + a) % 65521;
        }
        (b << 16) | a
    }
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    }
    let raw: Vec<u8> = [[0u8, 255, 0, 0, 0, 255, 0], [0u8, 0, 0, 255, 128, 128, 255]].concat();
    let mut z = vec![0x78, 0x01, 1];
    z.extend_from_slice(&(raw.len() as u16).to_le_bytes());
    z.extend_from_slice(&(!(raw.len() as u16)).to_le_bytes());
    z.extend_from_slice(&raw);
    z.extend_from_slice(&adler32(&raw).to_be_bytes());
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&2u32.to_be_bytes());
    ihdr.extend_from_slice(&2u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"IDAT", &z);
    chunk(&mut png, b"IEND", &[]);
    png
}

/// A 4×2 Radiance HDR sky, brighter at the top.
pub fn fixture_hdr() -> Vec<u8> {
    let image = raylab::lights::rgbe::RgbImage {
        width: 4,
        height: 2,
        pixels: vec![
            [2.0, 2.0, 2.5],
            [1.0, 1.0, 1.5],
            [8.0, 7.0, 5.0],
            [1.0, 1.0, 1.5],
            [0.2, 0.2, 0.2],
            [0.1, 0.1, 0.1],
            [0.3, 0.2, 0.1],
            [0.1, 0.1, 0.1],
        ],
    };
    let mut out = Vec::new();
    raylab::lights::rgbe::encode(&image, &mut out).expect("in memory");
    out
}

fn write_fixtures(dir: &Path) {
    let files: [(&str, Vec<u8>); 7] = [
        ("fixture.obj", FIXTURE_OBJ.into()),
        ("fixture.xml", FIXTURE_XML.into()),
        ("fixture.mtl", FIXTURE_MTL.into()),
        ("fixture.gltf", FIXTURE_GLTF.into()),
        ("fixture.bin", fixture_bin()),
        ("fixture.png", fixture_png()),
        ("fixture.hdr", fixture_hdr()),
    ];
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).expect("fixture");
    }
}

/// Splits `data` at its first NUL byte: the main file and, after it, a second
/// one (empty without a NUL).
pub fn split_nul(data: &[u8]) -> (&[u8], &[u8]) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[]),
    }
}

/// Loads `path` as the command line would and applies the oracle: an error is
/// one non-empty line; a scene renders, tiny, with every integrator.
pub fn load_and_render(path: &Path, options: &LoadOptions) {
    let name = path.to_str().expect("scratch paths are UTF-8");
    let verbose = std::env::var_os("RAYLAB_FUZZ_VERBOSE").is_some();
    match raylab::load::load(name, options) {
        Err(e) => {
            if verbose {
                eprintln!("error: {e}");
            }
            check_message(&e.to_string())
        }
        Ok(loaded) => {
            if verbose {
                eprintln!(
                    "loaded: {} triangles, {:?}",
                    loaded.scene.triangles().len(),
                    loaded.warnings
                );
            }
            for w in &loaded.warnings {
                check_message(w);
            }
            let v = loaded.view;
            let mut camera = Camera::with_lens(v.position, v.rotation, v.lens, 6, 4);
            // A scene file's thin lens with a focus distance (a focus pixel
            // needs the job's session): its rays from the fuzzed lens.
            let dof = v.depth_of_field;
            if let (Some(aperture), Some(Focus::Distance(focus_distance))) =
                (dof.aperture, dof.focus)
            {
                camera = camera.focused(FocusedLens {
                    aperture,
                    focus_distance,
                    blades: dof.blades.unwrap_or(0),
                });
            }
            for integrator in [Integrator::Flat, Integrator::Direct, Integrator::path()] {
                let settings = RenderSettings {
                    integrator,
                    spp: 2,
                    seed: 1,
                };
                let image = render(&loaded.scene, &camera, &settings, &|_| {});
                assert!(
                    image.film.pixels.iter().all(|p| p.is_finite()),
                    "{integrator}: a pixel is not finite"
                );
                if image.dropped > 0 && sane(&loaded.scene) {
                    panic!(
                        "{integrator}: {} NaN/Inf samples in a scene of sane size",
                        image.dropped
                    );
                }
            }
        }
    }
}

/// The memory the targets' loads may use: 64 MiB, e.g. 16 M texels of RGBA
/// texture. The instrumented build runs texel loops some 50 times slower than
/// a release build, so a few bytes of a losslessly compressed image that
/// declares 180 M texels (a size within raylab's limits, which a release build
/// decodes and uses in 2 s) would run past libFuzzer's 10 s: a timeout
/// that is no hang. Above this budget the load stops from the image's header,
/// as it does for a user's `--max-memory`.
pub fn fuzz_options() -> LoadOptions {
    LoadOptions {
        max_memory: raylab::memory::MemoryBudget::bytes(64 << 20),
        ..LoadOptions::default()
    }
}

/// Loads the fixture OBJ lit by the environment map `env`.
pub fn load_with_env(env: &Path) {
    let options = LoadOptions {
        environment: raylab::load::EnvironmentOptions {
            source: Some(EnvSource::File(env.to_path_buf())),
            strength: None,
            rotation: None,
        },
        ..fuzz_options()
    };
    load_and_render(&scratch().join("fixture.obj"), &options);
}

/// Whether the scene's coordinates are small enough that NaN/Inf samples are
/// raylab's fault, not f32 overflow of the file's numbers.
fn sane(scene: &raylab::Scene) -> bool {
    let limit = Vec3A::splat(1e12);
    scene
        .triangles()
        .iter()
        .all(|t| t.v.iter().all(|p| p.abs().cmplt(limit).all()))
}

/// An error or warning is one non-empty line.
pub fn check_message(message: &str) {
    assert!(!message.trim().is_empty(), "an empty message");
    assert!(
        !message.contains('\n'),
        "a message of several lines: {message:?}"
    );
}
