//! `KHR_animation_pointer`: channels whose target is a JSON pointer, sampled
//! at moments before, at, between and after their keyframes, against
//! numbers worked out by hand — a material's factors and texture transform,
//! a light's colour, intensity and cone, a camera's field of view, a node's
//! visibility, and node transforms and weights through pointers (the same
//! scene, bit for bit, as the core channels give); STEP, LINEAR and
//! CUBICSPLINE; rendered pixels of `--frames`; and every kind of bad
//! pointer refused in one line naming the animation and channel. Every file
//! is written by the test itself (see `common/gltf_builder.rs`).

#[path = "common/gltf_animation.rs"]
mod anim;
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;
mod common;

use std::f32::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use anim::{edited, floats, hermite, load_at, posed, write_with};
use builder::{Gltf, U8, png, quad};
use glam::{Quat, Vec2, Vec3, Vec3A, Vec4};
use raylab::camera::Lens;
use raylab::lights::Light;
use raylab::load::Loaded;
use raylab::materials::surface::{GltfMaterial, MaterialKind};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// Helpers

/// The file posed by `animation` at `time`.
fn play(path: &Path, animation: &str, time: f32) -> Loaded {
    posed(path, Some(animation), Some(time))
}

/// An unsigned-byte scalar accessor over `values` (a bool's keyframes).
fn bytes(g: &mut Gltf, values: &[u8]) -> usize {
    let view = g.view(values, None);
    g.accessor(json!({
        "bufferView": view, "componentType": U8, "count": values.len(), "type": "SCALAR",
    }))
}

/// A channel of sampler `sampler` on `pointer`.
fn pointer_channel(sampler: usize, pointer: &str) -> Value {
    json!({ "sampler": sampler, "target": {
        "path": "pointer",
        "extensions": { "KHR_animation_pointer": { "pointer": pointer } },
    } })
}

/// A sampler.
fn sampler(input: usize, interpolation: &str, output: usize) -> Value {
    json!({ "input": input, "interpolation": interpolation, "output": output })
}

/// An animation named `name`: one channel per (pointer, sampler).
fn animation(name: &str, channels: &[(&str, Value)]) -> Value {
    json!({
        "name": name,
        "samplers": channels.iter().map(|c| c.1.clone()).collect::<Vec<_>>(),
        "channels": (0..channels.len()).map(|k| pointer_channel(k, channels[k].0)).collect::<Vec<_>>(),
    })
}

/// Material `k` of a loaded scene as a glTF material.
fn gltf_material(loaded: &Loaded, k: usize) -> &GltfMaterial {
    match &loaded.scene.materials()[k].kind {
        MaterialKind::Gltf(g) => g,
        other => panic!("material {k} is {other:?}"),
    }
}

#[track_caller]
fn assert_close(got: f32, want: f32, tol: f32, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

// ---------------------------------------------------------------------------
// The scene

/// A textured square (material 0: white base colour × a 2×2 texture whose
/// transform the file writes, emissive (1, 1, 1) × strength 1, metallic 0)
/// on node 0, which `KHR_node_visibility` shows; a camera (yfov 0.8, aspect
/// 1.5) at (0, 0, 5) on node 1; a spot light (white, 10 W/sr, cones 0.2 and
/// 0.6) at (0, 0, 3) on node 2. The animations are added by each test.
fn scene() -> Gltf {
    let mut g = Gltf::new();
    let texels = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
    let texture = g.png_texture(&png(2, 2, 3, &texels), None);
    g.material(json!({
        "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "baseColorTexture": { "index": texture, "extensions": { "KHR_texture_transform": {
                "offset": [0.0, 0.0], "rotation": 0.0, "scale": [1.0, 1.0],
            } } },
            "metallicFactor": 0.0,
        },
        "emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 1.0 } },
    }));
    let uv = floats(&mut g, &[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], 2);
    let corners = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let mut square = quad(&mut g, corners, &[("TEXCOORD_0", uv)]);
    square["material"] = json!(0);
    let mesh = g.mesh(vec![square]);
    g.root(json!({ "mesh": mesh, "extensions": { "KHR_node_visibility": { "visible": true } } }));
    let camera = g.camera(json!({ "type": "perspective", "perspective": {
        "yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1,
    } }));
    g.root(json!({ "camera": camera, "translation": [0.0, 0.0, 5.0] }));
    let light = g.light(
        json!({ "type": "spot", "color": [1.0, 1.0, 1.0], "intensity": 10.0,
        "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } }),
    );
    g.root(json!({ "translation": [0.0, 0.0, 3.0],
        "extensions": { "KHR_lights_punctual": { "light": light } } }));
    g
}

/// The scene's spot light: (intensity, cos inner, cos outer).
fn spot(loaded: &Loaded) -> (Vec3A, f32, f32) {
    match loaded.scene.lights() {
        [
            Light::Spot {
                intensity,
                cos_inner,
                cos_outer,
                ..
            },
        ] => (*intensity, *cos_inner, *cos_outer),
        other => panic!("lights: {other:?}"),
    }
}

/// `scene()` with animations: `colors` (LINEAR base colour from red at 1 s
/// to blue at 3 s; STEP emissive strength 1, 4, 2 at 1, 2, 3 s;
/// CUBICSPLINE metallic factor from 0 to 1 between 1 and 3 s), `uv` (LINEAR
/// texture offset (0, 0) → (1, 0.5) and rotation 0 → π/2 between 0 and 2
/// s), `light` (LINEAR colour white → (1, 0.5, 0), intensity 10 → 30 and
/// outer cone 0.6 → 1.0 between 0 and 1 s), `camera` (LINEAR yfov 0.8 → 0.4
/// and aspect ratio 1.5 → 2 between 0 and 2 s) and `blink` (STEP
/// visibility: hidden from 1 s, shown again from 2 s).
fn animated_file(dir: &Path) -> PathBuf {
    let mut g = scene();
    let t13 = floats(&mut g, &[1.0, 3.0], 1);
    let t123 = floats(&mut g, &[1.0, 2.0, 3.0], 1);
    let t02 = floats(&mut g, &[0.0, 2.0], 1);
    let t01 = floats(&mut g, &[0.0, 1.0], 1);
    let colour = floats(&mut g, &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0], 4);
    let strength = floats(&mut g, &[1.0, 4.0, 2.0], 1);
    // CUBICSPLINE: (in-tangent, value, out-tangent) per keyframe.
    let metallic = floats(&mut g, &[9.0, 0.0, 0.5, 0.25, 1.0, 9.0], 1);
    let offset = floats(&mut g, &[0.0, 0.0, 1.0, 0.5], 2);
    let rotation = floats(&mut g, &[0.0, FRAC_PI_2], 1);
    let light_colour = floats(&mut g, &[1.0, 1.0, 1.0, 1.0, 0.5, 0.0], 3);
    let intensity = floats(&mut g, &[10.0, 30.0], 1);
    let cone = floats(&mut g, &[0.6, 1.0], 1);
    let yfov = floats(&mut g, &[0.8, 0.4], 1);
    let aspect = floats(&mut g, &[1.5, 2.0], 1);
    let visible = bytes(&mut g, &[1, 0, 255]);
    let m = "/materials/0";
    let tt = "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform";
    let l = "/extensions/KHR_lights_punctual/lights/0";
    let pointers = [
        format!("{m}/pbrMetallicRoughness/baseColorFactor"),
        format!("{m}/extensions/KHR_materials_emissive_strength/emissiveStrength"),
        format!("{m}/pbrMetallicRoughness/metallicFactor"),
        format!("{tt}/offset"),
        format!("{tt}/rotation"),
        format!("{l}/color"),
        format!("{l}/intensity"),
        format!("{l}/spot/outerConeAngle"),
    ];
    write_with(
        &g,
        dir,
        "animated.gltf",
        json!({ "animations": [
            animation("colors", &[
                (&pointers[0], sampler(t13, "LINEAR", colour)),
                (&pointers[1], sampler(t123, "STEP", strength)),
                (&pointers[2], sampler(t13, "CUBICSPLINE", metallic)),
            ]),
            animation("uv", &[
                (&pointers[3], sampler(t02, "LINEAR", offset)),
                (&pointers[4], sampler(t02, "LINEAR", rotation)),
            ]),
            animation("light", &[
                (&pointers[5], sampler(t01, "LINEAR", light_colour)),
                (&pointers[6], sampler(t01, "LINEAR", intensity)),
                (&pointers[7], sampler(t01, "LINEAR", cone)),
            ]),
            animation("camera", &[
                ("/cameras/0/perspective/yfov", sampler(t02, "LINEAR", yfov)),
                ("/cameras/0/perspective/aspectRatio", sampler(t02, "LINEAR", aspect)),
            ]),
            animation("blink", &[
                ("/nodes/0/extensions/KHR_node_visibility/visible", sampler(t123, "STEP", visible)),
            ]),
        ]}),
    )
}

// ---------------------------------------------------------------------------
// 1. Values at moments

#[test]
fn a_material_s_factors_follow_linear_step_and_cubic_spline_keyframes() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let at = |t| play(&path, "colors", t);
    // Base colour, LINEAR red → blue between 1 and 3 s; clamped outside.
    for (t, want) in [
        (0.0, Vec4::new(1.0, 0.0, 0.0, 1.0)),
        (1.0, Vec4::new(1.0, 0.0, 0.0, 1.0)),
        (1.5, Vec4::new(0.75, 0.0, 0.25, 1.0)),
        (2.0, Vec4::new(0.5, 0.0, 0.5, 1.0)),
        (3.0, Vec4::new(0.0, 0.0, 1.0, 1.0)),
        (9.0, Vec4::new(0.0, 0.0, 1.0, 1.0)),
    ] {
        let got = gltf_material(&at(t), 0).base_color;
        assert!(
            (got - want).abs().max_element() <= 1e-6,
            "base colour at {t} s: {got}"
        );
    }
    // Emissive strength, STEP 1, 4, 2 at 1, 2, 3 s (emission = factor × strength).
    for (t, want) in [
        (0.0, 1.0),
        (1.0, 1.0),
        (1.99, 1.0),
        (2.0, 4.0),
        (2.5, 4.0),
        (3.0, 2.0),
        (5.0, 2.0),
    ] {
        let got = at(t).scene.materials()[0].emission;
        assert_eq!(got, Vec3A::splat(want), "emission at {t} s");
    }
    // Metallic, CUBICSPLINE from 0 (out-tangent 0.5) to 1 (in-tangent 0.25),
    // keyframes 2 s apart; the tangents never show outside the keyframes.
    for (t, s) in [(1.5, 0.25), (2.0, 0.5), (2.5, 0.75)] {
        let want = hermite(0.0, 0.5, 1.0, 0.25, 2.0, s);
        assert_close(
            gltf_material(&at(t), 0).metallic,
            want,
            1e-6,
            &format!("metallic at {t} s"),
        );
    }
    // s = 0.5 written out: 0.125·2·0.5 + 0.5·1 + (−0.125)·2·0.25 = 0.5625.
    assert_close(
        gltf_material(&at(2.0), 0).metallic,
        0.5625,
        1e-6,
        "metallic at 2 s",
    );
    assert_eq!(gltf_material(&at(0.0), 0).metallic, 0.0, "before");
    assert_eq!(gltf_material(&at(4.0), 0).metallic, 1.0, "after");
}

#[test]
fn a_texture_transform_s_offset_and_rotation_move() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let transform = |t| {
        let loaded = play(&path, "uv", t);
        gltf_material(&loaded, 0)
            .base_color_texture
            .unwrap()
            .transform
    };
    for (t, offset, rotation) in [
        (0.0, Vec2::ZERO, 0.0),
        (0.5, Vec2::new(0.25, 0.125), FRAC_PI_2 / 4.0),
        (1.0, Vec2::new(0.5, 0.25), FRAC_PI_2 / 2.0),
        (2.0, Vec2::new(1.0, 0.5), FRAC_PI_2),
        (3.0, Vec2::new(1.0, 0.5), FRAC_PI_2),
    ] {
        let got = transform(t);
        assert!(
            (got.offset - offset).abs().max_element() <= 1e-6,
            "offset at {t} s: {}",
            got.offset
        );
        assert_close(got.rotation, rotation, 1e-6, &format!("rotation at {t} s"));
        assert_eq!(got.scale, Vec2::ONE, "scale at {t} s");
    }
}

#[test]
fn a_light_s_colour_intensity_and_cone_follow_their_keyframes() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    for (t, colour, intensity, outer) in [
        (0.0, Vec3A::ONE, 10.0, 0.6f32),
        (0.25, Vec3A::new(1.0, 0.875, 0.75), 15.0, 0.7),
        (0.5, Vec3A::new(1.0, 0.75, 0.5), 20.0, 0.8),
        (1.0, Vec3A::new(1.0, 0.5, 0.0), 30.0, 1.0),
        (2.0, Vec3A::new(1.0, 0.5, 0.0), 30.0, 1.0),
    ] {
        let (got, cos_inner, cos_outer) = spot(&play(&path, "light", t));
        builder::assert_near(
            got,
            colour * intensity,
            1e-5,
            &format!("intensity at {t} s"),
        );
        assert_eq!(cos_inner, 0.2f32.cos(), "inner cone at {t} s");
        assert_close(
            cos_outer,
            outer.cos(),
            1e-6,
            &format!("outer cone at {t} s"),
        );
    }
    // Unanimated, the file's light.
    let still = load_at(&path, None, None).unwrap();
    assert_eq!(
        spot(&still),
        (Vec3A::splat(10.0), 0.2f32.cos(), 0.6f32.cos())
    );
}

#[test]
fn a_camera_s_field_of_view_and_aspect_ratio_follow_their_keyframes() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    for (t, yfov, aspect) in [
        (0.0, 0.8f32, 1.5),
        (0.5, 0.7, 1.625),
        (1.0, 0.6, 1.75),
        (2.0, 0.4, 2.0),
        (4.0, 0.4, 2.0),
    ] {
        let loaded = play(&path, "camera", t);
        let camera = &loaded.scene.cameras[0];
        let Lens::Perspective { focal_scale } = camera.lens else {
            panic!("{:?}", camera.lens);
        };
        assert_close(
            focal_scale,
            0.5 / (yfov / 2.0).tan(),
            1e-5,
            &format!("focal scale at {t} s"),
        );
        assert_close(
            camera.aspect_ratio.unwrap(),
            aspect,
            1e-6,
            &format!("aspect at {t} s"),
        );
    }
}

#[test]
fn visibility_is_a_bool_held_until_the_next_keyframe() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    for (t, shown) in [
        (0.0, true),
        (1.0, true),
        (1.5, true),
        (2.0, false),
        (2.9, false),
        (3.0, true),
        (8.0, true),
    ] {
        let loaded = play(&path, "blink", t);
        // The square's two triangles hide; the light, on a node of its own,
        // stays.
        let triangles = loaded.scene.triangles().len();
        assert_eq!(triangles, if shown { 2 } else { 0 }, "triangles at {t} s");
        assert_eq!(loaded.scene.lights().len(), 1, "the light at {t} s");
    }
}

#[test]
fn pointer_only_animations_are_listed_with_their_durations() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let loaded = load_at(&path, None, None).unwrap();
    assert_eq!(
        loaded.animations,
        ["colors", "uv", "light", "camera", "blink"]
    );
    let err = load_at(&path, Some("walk"), None).unwrap_err();
    assert!(
        err.contains(
            "0 'colors' (3 s), 1 'uv' (2 s), 2 'light' (1 s), 3 'camera' (2 s), 4 'blink' (3 s)"
        ),
        "{err}"
    );
    // Without --at or --animation the file is as written.
    assert_eq!(gltf_material(&loaded, 0).base_color, Vec4::ONE);
    // --at alone plays the first animation.
    let first = load_at(&path, None, Some(2.0)).unwrap();
    assert_eq!(
        gltf_material(&first, 0).base_color,
        Vec4::new(0.5, 0.0, 0.5, 1.0)
    );
}

// ---------------------------------------------------------------------------
// 2. Nodes through pointers, against core channels

/// Node 0 shows the triangle (0,0,0), (1,0,0), (0,1,0) with two morph
/// targets (all lifted by +z; vertex 1 pushed by +x; mesh weights (0.5,
/// 0)); node 1, given by a matrix (a translation by (0, 5, 0)), shows it
/// too. Animation `move` animates node 0's translation (LINEAR), rotation
/// (LINEAR: a quarter turn about +y), scale (CUBICSPLINE) and weights
/// (STEP), through core channels when `core`, else through pointers; `one`
/// animates node 0's second weight alone and node 1's translation.
fn node_file(dir: &Path, core: bool) -> PathBuf {
    let mut g = Gltf::new();
    let pos = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], 3);
    let lift = floats(&mut g, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], 3);
    let push = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 3);
    g.meshes.push(json!({
        "primitives": [{ "attributes": { "POSITION": pos }, "targets": [{ "POSITION": lift }, { "POSITION": push }] }],
        "weights": [0.5, 0.0],
    }));
    g.root(json!({ "mesh": 0 }));
    g.root(json!({ "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 5, 0, 1] }));
    let t02 = floats(&mut g, &[0.0, 2.0], 1);
    let t012 = floats(&mut g, &[0.0, 1.0, 2.0], 1);
    let translation = floats(&mut g, &[0.0, 0.0, 0.0, 2.0, 4.0, -6.0], 3);
    let q = Quat::from_rotation_y(FRAC_PI_2);
    let rotation = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, q.x, q.y, q.z, q.w], 4);
    let mut scale = vec![0.0; 3];
    scale.extend([
        1.0, 1.0, 1.0, 0.5, 0.0, -0.5, 0.25, 0.5, 0.75, 3.0, 2.0, 1.0, 9.0, 9.0, 9.0,
    ]);
    let scale = floats(&mut g, &scale, 3);
    let weights = floats(&mut g, &[0.0, 0.0, 1.0, 0.5, 0.25, 1.0], 1);
    let one_weight = floats(&mut g, &[0.0, 1.0], 1);
    let matrix_move = floats(&mut g, &[0.0, 5.0, 0.0, 3.0, 5.0, 0.0], 3);
    let samplers = json!([
        sampler(t02, "LINEAR", translation),
        sampler(t02, "LINEAR", rotation),
        sampler(t02, "CUBICSPLINE", scale),
        sampler(t012, "STEP", weights),
    ]);
    let paths = ["translation", "rotation", "scale", "weights"];
    let channels: Vec<Value> = (0..4)
        .map(|k| {
            if core {
                json!({ "sampler": k, "target": { "node": 0, "path": paths[k] } })
            } else {
                pointer_channel(k, &format!("/nodes/0/{}", paths[k]))
            }
        })
        .collect();
    write_with(
        &g,
        dir,
        if core { "core.gltf" } else { "pointer.gltf" },
        json!({ "animations": [
            { "name": "move", "samplers": samplers, "channels": channels },
            animation("one", &[
                ("/nodes/0/weights/1", sampler(t02, "LINEAR", one_weight)),
                ("/nodes/1/translation", sampler(t02, "LINEAR", matrix_move)),
            ]),
        ]}),
    )
}

#[test]
fn node_transforms_and_weights_through_pointers_equal_the_core_channels_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let core = node_file(dir.path(), true);
    let pointer = node_file(dir.path(), false);
    for t in [0.0, 0.3, 0.5, 1.0, 1.25, 1.999, 2.0, 5.0] {
        let a = play(&core, "move", t);
        let b = play(&pointer, "move", t);
        let (ta, tb) = (a.scene.triangles(), b.scene.triangles());
        assert_eq!(ta.len(), 2);
        for (x, y) in ta.iter().zip(tb) {
            assert_eq!(x.v, y.v, "triangles at {t} s");
        }
    }
    // And they move: at 1 s half the translation, half the turn, the
    // spline's middle scale, the second weights (1, 0.5).
    let moved = play(&pointer, "move", 1.0);
    let still = load_at(&pointer, None, None).unwrap();
    assert_ne!(moved.scene.triangles()[0].v, still.scene.triangles()[0].v);
    // Vertex 0 sits at the origin plus 1 × lift, (0, 0, 1), scaled and
    // turned, then translated by (1, 2, −3): half a quarter turn about +y
    // takes (0, 0, z) to (z sin 45°, 0, z cos 45°).
    let s = Vec3::new(
        hermite(1.0, 0.5, 3.0, 0.25, 2.0, 0.5),
        hermite(1.0, 0.0, 2.0, 0.5, 2.0, 0.5),
        hermite(1.0, -0.5, 1.0, 0.75, 2.0, 0.5),
    );
    let z = s.z;
    let h = 0.5f32.sqrt();
    builder::assert_near(
        moved.scene.triangles()[0].v[0],
        Vec3A::new(1.0 + z * h, 2.0, -3.0 + z * h),
        1e-5,
        "vertex 0 at 1 s",
    );
}

#[test]
fn one_weight_and_a_matrix_node_s_translation_are_animatable() {
    let dir = tempfile::tempdir().unwrap();
    let path = node_file(dir.path(), false);
    // Node 0's weights start from its mesh's (0.5, 0); the second goes 0 → 1
    // over 2 s: vertex 1 = (1, 0, 0) + 0.5·(0, 0, 1) + w·(1, 0, 0).
    for (t, w) in [(0.0, 0.0), (0.5, 0.25), (2.0, 1.0), (3.0, 1.0)] {
        let loaded = play(&path, "one", t);
        let tris = loaded.scene.triangles();
        builder::assert_near(
            tris[0].v[1],
            Vec3A::new(1.0 + w, 0.0, 0.5),
            1e-6,
            &format!("weight at {t} s"),
        );
        // Node 1's matrix moves from (0, 5, 0) to (3, 5, 0).
        builder::assert_near(
            tris[1].v[0],
            Vec3A::new(1.5 * t.min(2.0), 5.0, 0.5),
            1e-6,
            &format!("matrix node at {t} s"),
        );
    }
}

// ---------------------------------------------------------------------------
// 3. Pixels and --frames

#[test]
fn frames_render_the_animated_material_and_equal_at() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    // No texture: the base colour alone.
    let path = edited(&path, "flat.gltf", |r| {
        r["materials"][0]["pbrMetallicRoughness"]
            .as_object_mut()
            .unwrap()
            .remove("baseColorTexture");
    });
    let file = path.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            file,
            "--integrator",
            "flat",
            "--width",
            "30",
            "--height",
            "20",
            "--spp",
            "1",
            "--animation",
            "colors",
        ];
        args.extend(extra);
        let out = common::raylab(&args, dir.path());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&["--frames", "0..4", "--fps", "1", "-o", "f-%d.png"]);
    run(&["--at", "2", "-o", "at.png"]);
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert_eq!(read("f-2.png"), read("at.png"), "frame 2 against --at 2");
    let centre = |name: &str| {
        let img = image::open(dir.path().join(name)).unwrap().to_rgb8();
        img.get_pixel(15, 10).0
    };
    // Red, then between red and blue, then blue (as the display's tone
    // map shows them): the square fills the centre of the camera's view.
    let (f1, f2, f3) = (centre("f-1.png"), centre("f-2.png"), centre("f-3.png"));
    assert!(f1[0] > 200 && f1[1] < 60 && f1[2] < 60, "frame 1: {f1:?}");
    assert!(f2[0] > 100 && f2[2] > 100 && f2[1] < 60, "frame 2: {f2:?}");
    assert!(f3[2] > 200 && f3[0] < 60 && f3[1] < 60, "frame 3: {f3:?}");
    assert!(f2[0] < f1[0] && f2[2] > f1[2] && f3[0] < f2[0] && f3[2] > f2[2]);
    assert_eq!(
        read("f-0.png"),
        read("f-1.png"),
        "before the first keyframe"
    );
}

// ---------------------------------------------------------------------------
// 4. Warnings and refusals

#[test]
fn unrendered_properties_and_extras_are_skipped_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let path = edited(&path, "skipped.gltf", |r| {
        let channels = r["animations"][3]["channels"].as_array_mut().unwrap();
        channels[0] = pointer_channel(0, "/cameras/0/perspective/znear");
        channels[1] = pointer_channel(1, "/materials/0/extras/glow");
    });
    let loaded = play(&path, "camera", 1.0);
    let warnings = loaded.warnings.join("\n");
    assert!(
        warnings
            .contains("/cameras/{}/perspective/znear: raylab's cameras have no clipping planes"),
        "{warnings}"
    );
    assert!(
        warnings.contains("/materials/{}/extras/glow: raylab reads no extras"),
        "{warnings}"
    );
    // The field of view is the file's.
    let Lens::Perspective { focal_scale } = loaded.scene.cameras[0].lens else {
        panic!()
    };
    assert_close(focal_scale, 0.5 / 0.4f32.tan(), 1e-6, "the file's yfov");
}

/// How a bad file is made from a good one.
enum Edit {
    /// Channel `c` of animation `a` gets this pointer.
    Pointer(usize, usize, &'static str),
    /// Animation `a` gets one more channel, of sampler `s` on this pointer.
    Push(usize, usize, &'static str),
    /// Sampler `s` of animation `a`: the interpolation.
    Interpolation(usize, usize, &'static str),
    /// Sampler `s` of animation `a`: the output of sampler `from` of
    /// animation `of`.
    Output(usize, usize, usize, usize),
    /// Channel `c` of animation `a`: its target.
    Target(usize, usize, Value),
    /// Channel `c` of animation `a`: its sampler.
    Sampler(usize, usize, usize),
}

impl Edit {
    fn apply(&self, r: &mut Value) {
        let animations = &mut r["animations"];
        match self {
            Edit::Pointer(a, c, p) => {
                animations[a]["channels"][c]["target"]["extensions"]["KHR_animation_pointer"]["pointer"] =
                    json!(p)
            }
            Edit::Push(a, s, p) => animations[a]["channels"]
                .as_array_mut()
                .unwrap()
                .push(pointer_channel(*s, p)),
            Edit::Interpolation(a, s, i) => {
                animations[a]["samplers"][s]["interpolation"] = json!(i)
            }
            Edit::Output(a, s, of, from) => {
                animations[a]["samplers"][s]["output"] =
                    animations[of]["samplers"][from]["output"].clone()
            }
            Edit::Target(a, c, t) => animations[a]["channels"][c]["target"] = t.clone(),
            Edit::Sampler(a, c, s) => animations[a]["channels"][c]["sampler"] = json!(s),
        }
    }
}

/// Each case of `cases` (a file name, the channel it breaks as the error
/// names it, the edit, and what the error must say) applied to `path`: the
/// edited file, loaded at 0.5 s of the channel's animation, must be refused
/// in one line naming the file, the animation and the channel.
#[track_caller]
fn refuse_all(path: &Path, cases: &[(&str, String, Edit, &str)]) {
    for (name, channel, edit, want) in cases {
        let bad = edited(path, name, |r| edit.apply(r));
        let animation = channel.split('\'').nth(1).unwrap();
        let err = load_at(&bad, Some(animation), Some(0.5)).unwrap_err();
        assert!(!err.contains('\n'), "{err}");
        assert!(err.contains(name) && err.contains(channel), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
    }
}

#[test]
fn bad_pointers_are_refused_in_one_line_naming_the_channel() {
    use Edit::*;
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let (colors, uv, light, camera, blink) = (
        "animation 0 'colors' channel",
        "animation 1 'uv' channel",
        "animation 2 'light' channel",
        "animation 3 'camera' channel",
        "animation 4 'blink' channel",
    );
    let channel = |prefix: &str, c: usize| format!("{prefix} {c}");
    let cases = [
        // Not a JSON pointer.
        (
            "syntax.gltf",
            channel(colors, 1),
            Pointer(0, 1, "materials/0/alphaCutoff"),
            "not a valid JSON pointer: a JSON pointer starts with '/'",
        ),
        (
            "escape.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/0/a~2"),
            "not a valid JSON pointer: '~' must be followed by 0 or 1",
        ),
        // No such object.
        (
            "range.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/7/alphaCutoff"),
            "material 7 does not exist (the file has 1 materials)",
        ),
        (
            "node-range.gltf",
            channel(blink, 0),
            Pointer(4, 0, "/nodes/9/extensions/KHR_node_visibility/visible"),
            "node 9 does not exist (the file has 3 nodes)",
        ),
        (
            "light-range.gltf",
            channel(light, 1),
            Pointer(2, 1, "/extensions/KHR_lights_punctual/lights/1/intensity"),
            "light 1 does not exist (the file has 1 lights)",
        ),
        (
            "index.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/00/alphaCutoff"),
            "'00' is not an array index",
        ),
        // Not animatable.
        (
            "read-only.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/0/doubleSided"),
            "names no animatable property",
        ),
        (
            "component.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/0/emissiveFactor/0"),
            "names no animatable property",
        ),
        (
            "mesh.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/meshes/0/weights"),
            "names no animatable property",
        ),
        // Not defined by the file.
        (
            "absent.gltf",
            channel(colors, 1),
            Pointer(
                0,
                1,
                "/materials/0/extensions/KHR_materials_clearcoat/clearcoatFactor",
            ),
            "material 0 has no extensions/KHR_materials_clearcoat",
        ),
        (
            "no-default.gltf",
            channel(camera, 1),
            Pointer(3, 1, "/cameras/0/perspective/zfar"),
            "camera 0 has no perspective/zfar (it has no default value",
        ),
        (
            "no-ortho.gltf",
            channel(camera, 1),
            Pointer(3, 1, "/cameras/0/orthographic/xmag"),
            "camera 0 has no orthographic",
        ),
        (
            "no-weights.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/nodes/0/weights"),
            "node 0 has no mesh with morph targets",
        ),
        // The accessor's type: a float4 on a scalar, a float on a VEC4.
        (
            "type.gltf",
            channel(uv, 1),
            Pointer(1, 1, "/materials/0/pbrMetallicRoughness/baseColorFactor"),
            "has 1 components per element, but pbrMetallicRoughness/baseColorFactor is a float4",
        ),
        (
            "type4.gltf",
            channel(colors, 0),
            Pointer(0, 0, "/materials/0/alphaCutoff"),
            "has 4 components per element, but alphaCutoff is a float (1 per element)",
        ),
        // Too many values for the keyframes (a CUBICSPLINE sampler read as LINEAR).
        (
            "count.gltf",
            channel(colors, 2),
            Interpolation(0, 2, "LINEAR"),
            "6 values for 2 keyframes of 1 value (expected 2)",
        ),
        // A bool animated LINEAR, and a bool of floats.
        (
            "bool-linear.gltf",
            channel(blink, 0),
            Interpolation(4, 0, "LINEAR"),
            "is a bool, which only STEP interpolation animates (sampler 0 is LINEAR)",
        ),
        (
            "bool-float.gltf",
            channel(blink, 0),
            Output(4, 0, 0, 1),
            "must hold unsigned bytes for a bool",
        ),
        // Twice in one animation.
        (
            "twice.gltf",
            channel(colors, 1),
            Pointer(0, 1, "/materials/0/pbrMetallicRoughness/baseColorFactor"),
            "channel 0 animates this property too",
        ),
        // A "pointer" path without the extension's pointer; no such sampler.
        (
            "no-pointer.gltf",
            channel(uv, 0),
            Target(1, 0, json!({ "path": "pointer" })),
            "has no KHR_animation_pointer pointer",
        ),
        (
            "sampler.gltf",
            channel(uv, 1),
            Sampler(1, 1, 7),
            "sampler 7 does not exist",
        ),
    ];
    refuse_all(&path, &cases);
}

#[test]
fn a_pointer_and_a_core_channel_on_one_node_property_and_a_matrix_rotation_are_refused() {
    use Edit::*;
    let dir = tempfile::tempdir().unwrap();
    let path = node_file(dir.path(), true);
    refuse_all(
        &path,
        &[
            (
                "both.gltf",
                "animation 0 'move' channel 4".into(),
                Push(0, 0, "/nodes/0/translation"),
                "pointer /nodes/0/translation: channel 0 animates this property too",
            ),
            // One weight and the whole weights.
            (
                "weights.gltf",
                "animation 0 'move' channel 4".into(),
                Push(0, 3, "/nodes/0/weights/1"),
                "channel 3 animates this property too",
            ),
            (
                "matrix.gltf",
                "animation 1 'one' channel 1".into(),
                Pointer(1, 1, "/nodes/1/rotation"),
                "node 1 is given by a matrix: only its translation is animatable",
            ),
            (
                "weight-range.gltf",
                "animation 1 'one' channel 0".into(),
                Pointer(1, 0, "/nodes/0/weights/2"),
                "node 0's mesh has 2 morph targets: weight 2 does not exist",
            ),
        ],
    );
}

#[test]
fn a_pointer_channel_that_names_a_node_too_is_applied_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = animated_file(dir.path());
    let path = edited(&path, "node-too.gltf", |r| {
        r["animations"][0]["channels"][0]["target"]["node"] = json!(0);
    });
    let loaded = play(&path, "colors", 2.0);
    assert_eq!(
        gltf_material(&loaded, 0).base_color,
        Vec4::new(0.5, 0.0, 0.5, 1.0)
    );
    let warnings = loaded.warnings.join("\n");
    assert!(warnings.contains("names a node too"), "{warnings}");
    assert!(!warnings.contains("unknown target paths"), "{warnings}");
}
