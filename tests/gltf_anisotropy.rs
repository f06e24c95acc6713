//! `KHR_materials_anisotropy` read from files the test writes (see
//! `common/gltf_builder.rs`): the factors, the rotation and the texture as the
//! specification defines them, the direction carried by the mesh's tangent
//! frame (`TANGENT`, or MikkTSpace without it) into the shading frame, an
//! isotropic fallback with a warning where there is no tangent frame, and
//! non-finite numbers refused with the material named.

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::path::Path;

use builder::{Gltf, assert_near, load, load_with, png, quad};
use glam::{Vec2, Vec3A};
use raylab::load::LoadOptions;
use raylab::materials::surface::MaterialKind;
use raylab::materials::{Frame, Material};
use raylab::scene::SurfaceHit;
use raylab::{Ray, Scene};
use serde_json::{Value, json};

const EXT: &str = "KHR_materials_anisotropy";

/// The anisotropy texture's one texel: direction (1, 0.0039) (red 255, green
/// 128), strength 128/255 (blue).
const TEXEL: [u8; 3] = [255, 128, 128];

/// A unit square at `x` in the z = 0 plane facing +z, with material
/// `material`, texture coordinates equal to its (x, y) when `uv`, and
/// `tangent` as its TANGENT attribute if given.
fn square(g: &mut Gltf, x: f32, material: usize, uv: bool, tangent: Option<[f32; 4]>) {
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut extra = vec![("NORMAL", g.floats(&[[0.0, 0.0, 1.0]; 4]))];
    if uv {
        let uvs: Vec<[f32; 2]> = corners.iter().map(|c| [c[0], c[1]]).collect();
        extra.push(("TEXCOORD_0", g.floats(&uvs)));
    }
    if let Some(t) = tangent {
        extra.push(("TANGENT", g.floats(&[t; 4])));
    }
    let mut p = quad(g, corners, &extra);
    p["material"] = json!(material);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh, "translation": [x, 0.0, 0.0] }));
}

/// A metal of roughness 0.3 with the extension's object `ext` (none if null).
fn material(ext: Value) -> Value {
    let mut m = json!({
        "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.3 }
    });
    if !ext.is_null() {
        m["extensions"] = json!({ EXT: ext });
    }
    m
}

/// The file of the tests: squares 0–4 at x = 0, 2, 4, 6, 8.
/// 0: strength 0.6, rotation 30°, TANGENT +y (w = 1);
/// 1: the texture, strength 1, rotation 30°, TANGENT +y (w = −1);
/// 2: no extension, TANGENT +y;
/// 3: strength 0.6 without TANGENT: MikkTSpace on its texture coordinates;
/// 4: strength 0.6 without TANGENT or texture coordinates.
fn file(dir: &Path) -> (Gltf, std::path::PathBuf) {
    let mut g = Gltf::new();
    g.png_texture(&png(1, 1, 3, &TEXEL), None);
    let rotation = 30f32.to_radians();
    g.material(material(json!({
        "anisotropyStrength": 0.6, "anisotropyRotation": rotation
    })));
    g.material(material(json!({
        "anisotropyStrength": 1.0, "anisotropyRotation": rotation,
        "anisotropyTexture": { "index": 0 }
    })));
    g.material(material(Value::Null));
    square(&mut g, 0.0, 0, true, Some([0.0, 1.0, 0.0, 1.0]));
    square(&mut g, 2.0, 1, true, Some([0.0, 1.0, 0.0, -1.0]));
    square(&mut g, 4.0, 2, true, Some([0.0, 1.0, 0.0, 1.0]));
    square(&mut g, 6.0, 0, true, None);
    square(&mut g, 8.0, 0, false, None);
    g.extensions_used.push(EXT.into());
    let path = g.write(dir, "anisotropy.gltf");
    (g, path)
}

/// The surface at the middle of square `i`'s first triangle.
fn surface(scene: &Scene, i: u32) -> SurfaceHit {
    let t = scene.triangles()[2 * i as usize];
    let centre = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
    let hit = scene
        .intersect(&Ray::new(centre + Vec3A::Z, -Vec3A::Z), 2.0)
        .expect("the ray hits the square");
    scene.surface(&hit)
}

/// The anisotropy strength and world direction at square `i`, as the path
/// tracer orients them (`None`: isotropic there).
fn oriented(scene: &Scene, i: u32) -> Option<(f32, Vec3A)> {
    let s = surface(scene, i);
    let m = &scene.materials()[s.material as usize];
    let mut bsdf = m.bsdf(&s.attrs, scene.textures());
    let frame = Frame::from_normal(s.ns);
    bsdf.orient_anisotropy(&frame, s.tangent, s.bitangent);
    let Material::Pbr(p) = bsdf else {
        panic!("square {i}: not the glTF BSDF");
    };
    (p.anisotropy > 0.0).then(|| {
        let d = p.anisotropy_direction;
        (p.anisotropy, frame.to_world(Vec3A::new(d.x, d.y, 0.0)))
    })
}

#[test]
fn the_factors_rotation_and_texture_turn_the_tangent_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (_, path) = file(dir.path());
    let loaded = load(&path);
    let scene = &loaded.scene;
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    // The factors as written, the rotation as its cosine and sine.
    let gltf = |i: usize| match &scene.materials()[i].kind {
        MaterialKind::Gltf(g) => g.clone(),
        _ => panic!("material {i} is not glTF's"),
    };
    let g0 = gltf(0);
    assert_eq!(g0.anisotropy_strength, 0.6);
    assert!((g0.anisotropy_rotation - Vec2::new(c, s)).length() < 1e-6);
    assert!(g0.anisotropy_texture.is_none() && gltf(1).anisotropy_texture.is_some());
    assert_eq!(gltf(2).anisotropy_strength, 0.0);
    assert!(!scene.materials()[2].has_anisotropy());

    // Square 0: t = +y, b = w (n × t) = −x; the direction is the tangent
    // turned 30° towards the bitangent: c t + s b = (−s, c, 0).
    let s0 = surface(scene, 0);
    assert_near(s0.tangent, Vec3A::Y, 1e-6, "square 0 tangent");
    assert_near(s0.bitangent, -Vec3A::X, 1e-6, "square 0 bitangent");
    let (k, d) = oriented(scene, 0).expect("square 0 is anisotropic");
    assert_eq!(k, 0.6);
    assert_near(d, Vec3A::new(-s, c, 0.0), 1e-5, "square 0 direction");

    // Square 1: w = −1 flips the bitangent to +x; the texel's direction
    // (1, 2·128/255 − 1) normalized, turned by 30°; strength 1 × 128/255.
    let s1 = surface(scene, 1);
    assert_near(s1.bitangent, Vec3A::X, 1e-6, "square 1 bitangent");
    let tx = Vec2::new(1.0, 2.0 * 128.0 / 255.0 - 1.0).normalize();
    let turned = Vec2::new(c * tx.x - s * tx.y, s * tx.x + c * tx.y);
    let (k, d) = oriented(scene, 1).expect("square 1 is anisotropic");
    assert!((k - 128.0 / 255.0).abs() < 1e-6, "strength {k}");
    assert_near(d, turned.x * Vec3A::Y + turned.y * Vec3A::X, 1e-5, "texel");

    // Square 2: no extension, no tangent frame carried, isotropic.
    assert_eq!(surface(scene, 2).tangent, Vec3A::ZERO);
    assert!(oriented(scene, 2).is_none());

    // Square 3: no TANGENT but texture coordinates: MikkTSpace, tangent
    // along +u (+x), bitangent towards decreasing v (−y).
    let s3 = surface(scene, 3);
    assert_near(s3.tangent, Vec3A::X, 1e-5, "MikkTSpace tangent");
    assert_near(s3.bitangent, -Vec3A::Y, 1e-5, "MikkTSpace bitangent");
    let (_, d) = oriented(scene, 3).expect("square 3 is anisotropic");
    assert_near(d, Vec3A::new(c, -s, 0.0), 1e-5, "square 3 direction");

    // Square 4: no frame at all: isotropic, with one warning naming it.
    assert!(oriented(scene, 4).is_none());
    let warned: Vec<_> = loaded.warnings.iter().filter(|w| w.contains(EXT)).collect();
    assert_eq!(warned.len(), 1, "{:?}", loaded.warnings);
    assert!(warned[0].contains("mesh 4 primitive 0"), "{}", warned[0]);
}

#[test]
fn non_finite_numbers_are_refused_naming_the_material() {
    let dir = tempfile::tempdir().unwrap();
    let (g, _) = file(dir.path());
    for (name, value) in [
        ("anisotropyStrength", json!(1e39)),
        ("anisotropyRotation", json!(-1e39)),
        ("anisotropyStrength", json!("strong")),
    ] {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            builder::base64(&g.buffer)
        );
        let mut bad = g.to_json(Some(uri));
        bad["materials"][1]["extensions"][EXT][name] = value.clone();
        let path = builder::write_json(dir.path(), "bad.gltf", &bad);
        let err = match load_with(&path, &LoadOptions::default()) {
            Ok(_) => panic!("{name} = {value} loaded"),
            Err(e) => e,
        };
        // (A wrong type is named by serde's message, "expected f32".)
        let named = err.contains(name) || (value.is_string() && err.contains("f32"));
        assert!(
            err.contains("material 1") && err.contains(EXT) && named,
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}
