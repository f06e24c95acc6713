//! `KHR_materials_diffuse_transmission` against numbers worked out from its
//! Khronos specification: a thin plate lit from behind passes
//! `diffuseTransmission × diffuseTransmissionColor × E cos θ / π` of the
//! light (factor × texture alpha, colour factor × texture RGB in sRGB), lit
//! from the front it reflects the rest of its diffuse part, and factors that
//! are not finite are refused in one line naming the material. Every file is
//! written by the test itself (see `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use builder::{Gltf, assert_near, load, load_with, png, quad};
use glam::{Quat, Vec3, Vec3A};
use raylab::integrators::path::PathOptions;
use raylab::load::LoadOptions;
use raylab::textures::srgb_to_linear;
use raylab::{Integrator, Ray};
use serde_json::{Value, json};

const BASE: [f32; 3] = [0.2, 0.8, 0.3];
const FACTOR: f32 = 0.6;
const COLOR: [f32; 3] = [1.0, 0.5, 0.25];
/// The texture's one texel: RGB (sRGB) for the colour, A for the factor.
const TEXEL: [u8; 4] = [255, 200, 64, 128];
/// The light's irradiance and colour.
const E: f32 = 3.0;
const LIGHT: [f32; 3] = [1.0, 0.9, 0.8];

/// A square plate at z = 0 (front +z) of the diffusely transmitting
/// material `extension` (none: the plain material), without a specular
/// layer (`KHR_materials_specular` factor 0, so the diffuse part's Fresnel
/// weight is exactly 1), and a directional light at `theta` degrees from
/// the plate's normal on the side `from_behind` says.
fn plate(
    dir: &Path,
    name: &str,
    extension: Option<Value>,
    theta: f32,
    from_behind: bool,
) -> PathBuf {
    let mut g = Gltf::new();
    g.png_texture(&png(1, 1, 4, &TEXEL), None);
    let mut extensions = json!({ "KHR_materials_specular": { "specularFactor": 0.0 } });
    g.extensions_used = vec![
        "KHR_materials_specular".into(),
        "KHR_lights_punctual".into(),
    ];
    if let Some(e) = extension {
        extensions["KHR_materials_diffuse_transmission"] = e;
        g.extensions_used
            .push("KHR_materials_diffuse_transmission".into());
    }
    let m = g.material(json!({
        "pbrMetallicRoughness": {
            "baseColorFactor": [BASE[0], BASE[1], BASE[2], 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.5
        },
        "doubleSided": true,
        "extensions": extensions
    }));
    let uv = g.floats(&[[0.5, 0.5]; 4]);
    let corners = [
        [-10.0, -10.0, 0.0],
        [10.0, -10.0, 0.0],
        [10.0, 10.0, 0.0],
        [-10.0, 10.0, 0.0],
    ];
    let mut p = quad(&mut g, corners, &[("TEXCOORD_0", uv)]);
    p["material"] = json!(m);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    let l = g.light(json!({ "type": "directional", "intensity": E, "color": LIGHT }));
    let t = theta.to_radians();
    // The direction the light travels: towards the plate from its side.
    let travel = if from_behind {
        Vec3::new(t.sin(), 0.0, t.cos())
    } else {
        Vec3::new(t.sin(), 0.0, -t.cos())
    };
    let q = Quat::from_rotation_arc(Vec3::NEG_Z, travel);
    g.root(json!({
        "rotation": q.to_array(),
        "extensions": { "KHR_lights_punctual": { "light": l } }
    }));
    g.write(dir, name)
}

/// The extension with factor, colour and both textures (the same texel).
fn textured() -> Value {
    json!({
        "diffuseTransmissionFactor": FACTOR,
        "diffuseTransmissionTexture": { "index": 0 },
        "diffuseTransmissionColorFactor": COLOR,
        "diffuseTransmissionColorTexture": { "index": 0 }
    })
}

/// `path` with one bounce (direct light only) along a ray straight down
/// onto the plate at `(x, y)`: with a directional light and no sky it is
/// exact, the same for every sample.
fn direct_path(path: &Path, x: f32, y: f32) -> Vec3A {
    let loaded = load(path);
    let options = PathOptions {
        max_depth: 2,
        ..PathOptions::default()
    };
    let ray = Ray::new(Vec3A::new(x, y, 3.0), Vec3A::NEG_Z);
    let mut rays = 0;
    Integrator::Path(options).radiance(&loaded.scene, &ray, &mut rays)
}

/// The share (factor × texture alpha) and colour (factor × texture RGB,
/// sRGB-decoded) the plate's texel gives.
fn share_and_colour() -> (f32, Vec3A) {
    let a = TEXEL[3] as f32 / 255.0;
    let rgb = Vec3A::new(
        srgb_to_linear(TEXEL[0] as f32 / 255.0),
        srgb_to_linear(TEXEL[1] as f32 / 255.0),
        srgb_to_linear(TEXEL[2] as f32 / 255.0),
    );
    (FACTOR * a, Vec3A::from(COLOR) * rgb)
}

#[test]
fn a_plate_lit_from_behind_passes_the_share_times_the_colour_times_the_cosine() {
    let dir = tempfile::tempdir().unwrap();
    let (dt, ct) = share_and_colour();
    let light = Vec3A::from(LIGHT) * E;
    for theta in [0.0f32, 60.0] {
        let cos = theta.to_radians().cos();
        // Behind: dt c_t E cos θ / π (kd = 1 without a specular layer).
        let behind = plate(dir.path(), "behind.gltf", Some(textured()), theta, true);
        let want = ct * light * (dt * cos / PI);
        for (x, y) in [(0.0, 0.0), (2.5, -1.0), (-4.0, 3.0)] {
            let got = direct_path(&behind, x, y);
            eprintln!("backlit plate θ={theta}: {got} (hand: {want})");
            assert_near(got, want, 1e-5 * want.max_element().max(1e-3), "behind");
        }
        // In front: (1 − dt) c E cos θ / π.
        let front = plate(dir.path(), "front.gltf", Some(textured()), theta, false);
        let want_front = Vec3A::from(BASE) * light * ((1.0 - dt) * cos / PI);
        let got = direct_path(&front, 1.0, 1.0);
        assert_near(got, want_front, 1e-5, "in front");
        // Without the extension nothing comes through, and all is reflected.
        let opaque = plate(dir.path(), "opaque.gltf", None, theta, true);
        assert_eq!(direct_path(&opaque, 1.0, 1.0), Vec3A::ZERO);
        let opaque_front = plate(dir.path(), "opaque-front.gltf", None, theta, false);
        let want_opaque = Vec3A::from(BASE) * light * (cos / PI);
        assert_near(
            direct_path(&opaque_front, 1.0, 1.0),
            want_opaque,
            1e-5,
            "opaque",
        );
    }
    // Read without a warning.
    let loaded = load(&plate(
        dir.path(),
        "quiet.gltf",
        Some(textured()),
        0.0,
        true,
    ));
    assert!(
        !loaded
            .warnings
            .iter()
            .any(|w| w.contains("diffuse_transmission")),
        "{:?}",
        loaded.warnings
    );
}

#[test]
fn factors_that_are_not_finite_are_refused_naming_the_material() {
    let dir = tempfile::tempdir().unwrap();
    for (key, value) in [
        ("diffuseTransmissionFactor", json!(1e39)),
        ("diffuseTransmissionColorFactor", json!([1.0, 1e39, 1.0])),
    ] {
        let mut e = textured();
        e[key] = value;
        let path = plate(dir.path(), "bad.gltf", Some(e), 0.0, true);
        let err = load_with(&path, &LoadOptions::default()).unwrap_err();
        eprintln!("{err}");
        assert!(
            err.contains("bad.gltf")
                && err.contains("material 0")
                && err.contains(key)
                && !err.contains('\n'),
            "{err}"
        );
    }
    // Out of range is clamped, not refused: a factor of 2 transmits all.
    let mut e = textured();
    e["diffuseTransmissionFactor"] = json!(2.0);
    e["diffuseTransmissionTexture"] = Value::Null;
    let path = plate(dir.path(), "two.gltf", Some(e), 0.0, false);
    assert_eq!(direct_path(&path, 0.0, 0.0), Vec3A::ZERO);
}
