//! glTF animation: node TRS channels of each interpolation sampled at and
//! between keyframes and outside them, skins, morph targets and animated
//! cameras, against numbers worked out by hand; `--animation`'s lookup and
//! its errors; `--frames` of an animated file against `--at`. Every file is
//! written by the test itself (see `common/gltf_builder.rs` and `common/gltf_animation.rs`).

#[path = "common/gltf_animation.rs"]
mod anim;
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;
mod common;

use std::f32::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use anim::{edited, floats, hermite, load_at, posed, write_with};
use builder::{F32, Gltf, U8, U16};
use glam::{Quat, Vec3, Vec3A};
use raylab::Hit;
use raylab::load::Loaded;
use serde_json::{Value, json};

#[track_caller]
fn assert_near(got: Vec3A, want: Vec3, tol: f32, what: &str) {
    let want = Vec3A::from(want);
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

fn bytes_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A sampler (input, interpolation, output) and a channel of it on
/// `node`'s `path`, as one animation named `name`.
fn animation(name: &str, node: usize, path: &str, sampler: Value) -> Value {
    json!({
        "name": name,
        "samplers": [sampler],
        "channels": [{ "sampler": 0, "target": { "node": node, "path": path } }],
    })
}

/// The triangle (0,0,0), (1,0,0), (0,1,0).
const TRIANGLE: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

const CUBIC_B0: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const CUBIC_V1: Vec3 = Vec3::new(4.0, 0.0, 0.0);
const CUBIC_A1: Vec3 = Vec3::new(0.0, 2.0, 0.0);

/// Three nodes showing the triangle, each moved by an animation of its own:
/// `step` (translation, STEP at 0, 1, 2 s), `turn` (rotation, LINEAR from
/// none to 90° about +y between 1 and 3 s) and `spline` (translation,
/// CUBICSPLINE between 0 and 2 s); and a camera node at (0, 0, 10) that
/// `dolly` moves to (0, 0, 20) between 0 and 1 s.
fn trs_file(dir: &Path) -> PathBuf {
    let mut g = Gltf::new();
    let pos = floats(&mut g, &TRIANGLE, 3);
    let mesh = g.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    for _ in 0..3 {
        g.root(json!({ "mesh": mesh }));
    }
    let camera = g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1, "aspectRatio": 1.0 } }));
    g.root(json!({ "camera": camera, "translation": [0.0, 0.0, 10.0] }));

    let step_in = floats(&mut g, &[0.0, 1.0, 2.0], 1);
    let step_out = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 0.0, 0.0], 3);
    let turn_in = floats(&mut g, &[1.0, 3.0], 1);
    let q = Quat::from_rotation_y(FRAC_PI_2);
    let turn_out = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, q.x, q.y, q.z, q.w], 4);
    let spline_in = floats(&mut g, &[0.0, 2.0], 1);
    let mut spline = vec![0.0; 3]; // keyframe 0: in-tangent,
    spline.extend([0.0; 3]); // value,
    spline.extend(CUBIC_B0.to_array()); // out-tangent
    spline.extend(CUBIC_A1.to_array()); // keyframe 1: in-tangent,
    spline.extend(CUBIC_V1.to_array()); // value,
    spline.extend([9.0; 3]); // out-tangent (unused)
    let spline_out = floats(&mut g, &spline, 3);
    let dolly_in = floats(&mut g, &[0.0, 1.0], 1);
    let dolly_out = floats(&mut g, &[0.0, 0.0, 10.0, 0.0, 0.0, 20.0], 3);
    let sampler = |input, interpolation: &str, output| json!({ "input": input, "interpolation": interpolation, "output": output });
    write_with(
        &g,
        dir,
        "trs.gltf",
        json!({ "animations": [
            animation("step", 0, "translation", sampler(step_in, "STEP", step_out)),
            animation("turn", 1, "rotation", sampler(turn_in, "LINEAR", turn_out)),
            animation("spline", 2, "translation", sampler(spline_in, "CUBICSPLINE", spline_out)),
            animation("dolly", 3, "translation", sampler(dolly_in, "LINEAR", dolly_out)),
        ]}),
    )
}

/// Where vertex (1, 0, 0) of node `node`'s triangle is.
fn corner(loaded: &Loaded, node: usize) -> Vec3A {
    loaded.scene.triangles()[node].v[1]
}

#[test]
fn step_holds_each_translation_until_the_next_keyframe() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    let x = Vec3::X;
    for (t, want) in [
        (0.0, x),
        (0.5, x),
        (1.0, x + Vec3::X),
        (1.99, x + Vec3::X),
        (2.0, x + 3.0 * Vec3::X),
        (7.0, x + 3.0 * Vec3::X),
    ] {
        let loaded = posed(&path, Some("step"), Some(t));
        assert_near(corner(&loaded, 0), want, 0.0, &format!("step at {t} s"));
        // The other animations' nodes stay as the file writes them.
        assert_near(corner(&loaded, 1), x, 0.0, "turn's node under step");
    }
}

#[test]
fn linear_rotation_at_a_quarter_of_a_right_angle_is_22_5_degrees_and_clamps() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    let a = 22.5f32.to_radians();
    // A rotation by θ about +y takes (1, 0, 0) to (cos θ, 0, −sin θ).
    for (t, want) in [
        (0.0, Vec3::X),
        (1.0, Vec3::X),
        (1.5, Vec3::new(a.cos(), 0.0, -a.sin())),
        (2.0, Vec3::new(0.5f32.sqrt(), 0.0, -(0.5f32.sqrt()))),
        (3.0, Vec3::new(0.0, 0.0, -1.0)),
        (30.0, Vec3::new(0.0, 0.0, -1.0)),
    ] {
        let loaded = posed(&path, Some("turn"), Some(t));
        assert_near(corner(&loaded, 1), want, 1e-6, &format!("turn at {t} s"));
    }
}

#[test]
fn cubic_spline_translation_follows_the_hermite_curve() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    for (t, s) in [(0.5, 0.25), (1.0, 0.5), (1.5, 0.75)] {
        let want = Vec3::X + hermite(Vec3::ZERO, CUBIC_B0, CUBIC_V1, CUBIC_A1, 2.0, s);
        let loaded = posed(&path, Some("spline"), Some(t));
        assert_near(corner(&loaded, 2), want, 1e-5, &format!("spline at {t} s"));
    }
    // s = 0.25 written out: x = 0.140625·2·1 + 0.15625·4, y = −0.046875·2·2.
    let loaded = posed(&path, Some("2"), Some(0.5));
    assert_near(
        corner(&loaded, 2),
        Vec3::new(1.90625, -0.1875, 0.0),
        1e-6,
        "spline by index at 0.5 s",
    );
    // Outside the keyframes: the values, never the tangents.
    assert_near(
        corner(&posed(&path, Some("spline"), Some(5.0)), 2),
        Vec3::X + CUBIC_V1,
        0.0,
        "after",
    );
}

#[test]
fn an_animated_camera_node_moves_the_view() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    let view = |t| posed(&path, Some("dolly"), Some(t)).view.position;
    assert_near(view(0.0), Vec3::new(0.0, 0.0, 10.0), 0.0, "dolly at 0 s");
    assert_near(view(0.5), Vec3::new(0.0, 0.0, 15.0), 1e-6, "dolly at 0.5 s");
    assert_near(
        view(4.0),
        Vec3::new(0.0, 0.0, 20.0),
        0.0,
        "dolly after its end",
    );
}

#[test]
fn without_at_the_file_is_as_written_and_at_alone_plays_the_first_animation() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    let loaded = posed(&path, None, None);
    assert_eq!(loaded.animations, ["step", "turn", "spline", "dolly"]);
    assert_near(corner(&loaded, 0), Vec3::X, 0.0, "unanimated");
    // `--at 2` without --animation: the first, `step`.
    assert_near(
        corner(&posed(&path, None, Some(2.0)), 0),
        4.0 * Vec3::X,
        0.0,
        "first",
    );
}

#[test]
fn an_unknown_animation_is_one_line_listing_the_files_animations() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    for asked in ["walk", "4"] {
        let err = load_at(&path, Some(asked), None).unwrap_err();
        assert!(!err.contains('\n'), "{err}");
        assert!(err.contains("trs.gltf"), "{err}");
        assert!(err.contains("no such animation"), "{err}");
        assert!(
            err.contains("0 'step' (2 s), 1 'turn' (3 s), 2 'spline' (2 s), 3 'dolly' (1 s)"),
            "{err}"
        );
    }
}

/// A file of one triangle and no animation.
fn still_file(dir: &Path) -> PathBuf {
    let mut g = Gltf::new();
    let pos = floats(&mut g, &TRIANGLE, 3);
    let mesh = g.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    g.root(json!({ "mesh": mesh }));
    g.write(dir, "still.gltf")
}

#[test]
fn asking_a_file_without_animations_for_one_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = still_file(dir.path());
    let err = load_at(&path, None, Some(1.0)).unwrap_err();
    assert!(
        err.contains("still.gltf") && err.contains("--at 1: the file has no animations"),
        "{err}"
    );
    let err = load_at(&path, Some("walk"), None).unwrap_err();
    assert!(
        err.contains("--animation 'walk': the file has no animations"),
        "{err}"
    );
}

#[test]
fn keyframe_times_that_do_not_increase_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (name, times) in [
        ("equal", [0.0, 1.0, 1.0]),
        ("back", [0.0, 2.0, 1.0]),
        ("nan", [0.0, f32::NAN, 2.0]),
    ] {
        let mut g = Gltf::new();
        let pos = floats(&mut g, &TRIANGLE, 3);
        let mesh = g.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
        g.root(json!({ "mesh": mesh }));
        let input = floats(&mut g, &times, 1);
        let output = floats(&mut g, &[0.0; 9], 3);
        let file = format!("{name}.gltf");
        let path = write_with(
            &g,
            dir.path(),
            &file,
            json!({ "animations": [animation("bad", 0, "translation", json!({ "input": input, "output": output }))] }),
        );
        let err = load_at(&path, None, Some(0.5)).unwrap_err();
        assert!(
            err.contains(&file) && err.contains("animation 0 'bad' sampler 0"),
            "{err}"
        );
        assert!(
            err.contains("keyframe time 2") || err.contains("keyframe time 1"),
            "{err}"
        );
    }
}

/// Two joints (joint 0 at the origin, joint 1 its child at (1, 0, 0)) skin a
/// triangle whose node (2) stands at (5, 5, 5), ignored as glTF says. Set 0
/// (u8 joints, float weights) and set 1 (u16 joints, normalized u8 weights)
/// each carry part of the weights: vertex 0 at (2, 0, 0) is about half on
/// each joint, vertex 1 at the origin all on joint 0, vertex 2 at (2, 0, 1)
/// all on joint 1. Animation `bend` turns joint 1 from nothing to 90° about
/// +z between 0 and 1 s.
fn skinned_file(dir: &Path) -> PathBuf {
    let mut g = Gltf::new();
    let pos = floats(&mut g, &[2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0], 3);
    let normals = floats(&mut g, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0], 3);
    let j0_view = g.view(&[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], None);
    let joints0 = g.accessor(
        json!({ "bufferView": j0_view, "componentType": U8, "count": 3, "type": "VEC4" }),
    );
    let weights0 = floats(
        &mut g,
        &[0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        4,
    );
    let j1: Vec<u8> = [1u16, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0]
        .iter()
        .flat_map(|j| j.to_le_bytes())
        .collect();
    let j1_view = g.view(&j1, None);
    let joints1 = g.accessor(
        json!({ "bufferView": j1_view, "componentType": U16, "count": 3, "type": "VEC4" }),
    );
    // Set 1's weights are normalized u8: 128/255 for vertex 0 (not quite ½,
    // so its weights sum to a little over 1 and are divided by the sum).
    let w1_view = g.view(&[128, 0, 0, 0, 0, 0, 0, 0, 255, 0, 0, 0], None);
    let weights1 = g.accessor(json!({ "bufferView": w1_view, "componentType": U8, "normalized": true, "count": 3, "type": "VEC4" }));
    let mesh = g.mesh(vec![json!({ "attributes": {
        "POSITION": pos, "NORMAL": normals,
        "JOINTS_0": joints0, "WEIGHTS_0": weights0, "JOINTS_1": joints1, "WEIGHTS_1": weights1,
    } })]);
    // Joint 1 is node 0, joint 0 (its parent) node 1.
    let joint1 = g.node(json!({ "translation": [1.0, 0.0, 0.0] }));
    let joint0 = g.root(json!({ "children": [joint1] }));
    g.root(json!({ "mesh": mesh, "skin": 0, "translation": [5.0, 5.0, 5.0] }));
    let mut ibm = glam::Mat4::IDENTITY.to_cols_array().to_vec();
    ibm.extend(glam::Mat4::from_translation(Vec3::new(-1.0, 0.0, 0.0)).to_cols_array());
    let ibm_view = g.view(&bytes_f32(&ibm), None);
    let ibm = g.accessor(
        json!({ "bufferView": ibm_view, "componentType": F32, "count": 2, "type": "MAT4" }),
    );
    let input = floats(&mut g, &[0.0, 1.0], 1);
    let q = Quat::from_rotation_z(FRAC_PI_2);
    let output = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, q.x, q.y, q.z, q.w], 4);
    write_with(
        &g,
        dir,
        "skinned.gltf",
        json!({
            "skins": [{ "joints": [joint0, joint1], "inverseBindMatrices": ibm }],
            "animations": [animation("bend", joint1, "rotation", json!({ "input": input, "output": output }))],
        }),
    )
}

#[test]
fn a_skinned_vertex_halfway_between_two_joints_moves_halfway() {
    let dir = tempfile::tempdir().unwrap();
    let path = skinned_file(dir.path());
    // At rest the joints are at their bind poses: the vertices as written,
    // not moved by the mesh node's (5, 5, 5).
    let rest = posed(&path, None, None);
    let v = rest.scene.triangles()[0].v;
    assert_near(v[0], Vec3::new(2.0, 0.0, 0.0), 1e-6, "rest vertex 0");
    assert_near(v[2], Vec3::new(2.0, 0.0, 1.0), 1e-6, "rest vertex 2");
    // Joint 1 turned 90° about +z round (1, 0, 0): its matrix takes (2, 0, 0)
    // to (1, 1, 0) and (2, 0, 1) to (1, 1, 1). Vertex 0 is (nearly) half on
    // each joint: w₀(2, 0, 0) + w₁(1, 1, 0) with the weights 0.5 and 128/255
    // divided by their sum.
    let bent = posed(&path, Some("bend"), Some(1.0));
    let v = bent.scene.triangles()[0].v;
    let w1 = (128.0 / 255.0) / (0.5 + 128.0 / 255.0);
    let w0 = 1.0 - w1;
    assert_near(
        v[0],
        Vec3::new(2.0 * w0 + w1, w1, 0.0),
        1e-6,
        "vertex 0 at 90°",
    );
    assert!((v[0] - Vec3A::new(1.5, 0.5, 0.0)).length() < 2e-3);
    assert_near(v[1], Vec3::ZERO, 1e-6, "vertex 1 at 90°");
    assert_near(v[2], Vec3::new(1.0, 1.0, 1.0), 1e-6, "vertex 2 at 90°");
    // Halfway, 45°: (2, 0, 1) → (1 + cos 45°, sin 45°, 1).
    let c = 0.5f32.sqrt();
    let half = posed(&path, Some("bend"), Some(0.5));
    assert_near(
        half.scene.triangles()[0].v[2],
        Vec3::new(1.0 + c, c, 1.0),
        1e-6,
        "vertex 2 at 45°",
    );
    // Vertex 2's normal, +x, turns with joint 1 to +y.
    let hit = Hit {
        t: 1.0,
        prim: 0,
        b1: 0.0,
        b2: 1.0,
    };
    let ns = bent.scene.surface(&hit).ns;
    assert_near(ns, Vec3::Y, 1e-6, "vertex 2's normal at 90°");
}

/// The triangle with two morph targets: target 0 lifts every vertex by
/// (0, 0, 1), target 1 moves vertex 1 by (1, 0, 0). The mesh's weights are
/// (0.5, 0); the node, at (0, 0, 10), gives its own when `node_weights`;
/// animation `morph` takes them from (0, 0) to (1, 0.5) between 0 and 2 s.
fn morph_file(dir: &Path, node_weights: Option<[f32; 2]>) -> PathBuf {
    let mut g = Gltf::new();
    let pos = floats(&mut g, &TRIANGLE, 3);
    let lift = floats(&mut g, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], 3);
    let push = floats(&mut g, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 3);
    g.meshes.push(json!({
        "primitives": [{ "attributes": { "POSITION": pos }, "targets": [{ "POSITION": lift }, { "POSITION": push }] }],
        "weights": [0.5, 0.0],
    }));
    let mut node = json!({ "mesh": 0, "translation": [0.0, 0.0, 10.0] });
    if let Some(w) = node_weights {
        node["weights"] = json!(w);
    }
    g.root(node);
    let input = floats(&mut g, &[0.0, 2.0], 1);
    let output = floats(&mut g, &[0.0, 0.0, 1.0, 0.5], 1);
    write_with(
        &g,
        dir,
        "morph.gltf",
        json!({ "animations": [animation("morph", 0, "weights", json!({ "input": input, "output": output }))] }),
    )
}

#[test]
fn morph_targets_add_their_deltas_times_the_weights() {
    let dir = tempfile::tempdir().unwrap();
    let tri = |l: &Loaded| l.scene.triangles()[0].v;
    // The mesh's weights (0.5, 0): lifted by 0.5, then the node's +10 in z.
    let v = tri(&posed(&morph_file(dir.path(), None), None, None));
    assert_near(
        v[0],
        Vec3::new(0.0, 0.0, 10.5),
        1e-6,
        "mesh weights, vertex 0",
    );
    assert_near(
        v[1],
        Vec3::new(1.0, 0.0, 10.5),
        1e-6,
        "mesh weights, vertex 1",
    );
    // The node's (0.25, 1) win over the mesh's.
    let path = morph_file(dir.path(), Some([0.25, 1.0]));
    let v = tri(&posed(&path, None, None));
    assert_near(
        v[1],
        Vec3::new(2.0, 0.0, 10.25),
        1e-6,
        "node weights, vertex 1",
    );
    assert_near(
        v[2],
        Vec3::new(0.0, 1.0, 10.25),
        1e-6,
        "node weights, vertex 2",
    );
    // Animated at 0.5 s: a quarter of the way, (0.25, 0.125).
    let v = tri(&posed(&path, Some("morph"), Some(0.5)));
    assert_near(
        v[1],
        Vec3::new(1.125, 0.0, 10.25),
        1e-6,
        "animated, vertex 1",
    );
    assert_near(v[0], Vec3::new(0.0, 0.0, 10.25), 1e-6, "animated, vertex 0");
    // After the end: (1, 0.5).
    let v = tri(&posed(&path, Some("morph"), Some(9.0)));
    assert_near(v[1], Vec3::new(1.5, 0.0, 11.0), 1e-6, "clamped, vertex 1");
}

#[test]
fn frames_of_an_animated_file_equal_renders_at_their_times_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let path = trs_file(dir.path());
    let file = path.to_str().unwrap();
    let size = ["--width", "40", "--height", "30", "--spp", "2"];
    let run = |extra: &[&str]| {
        let mut args = vec!["render", file];
        args.extend(size);
        args.extend(extra);
        let out = common::raylab(&args, dir.path());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&[
        "--animation",
        "turn",
        "--frames",
        "2..5",
        "--fps",
        "2",
        "-o",
        "f-%d.png",
        "--threads",
        "1",
    ]);
    run(&[
        "--animation",
        "turn",
        "--at",
        "1.5",
        "-o",
        "at.png",
        "--threads",
        "2",
    ]);
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    // Frame 3 at 2 fps is 1.5 s.
    assert_eq!(read("f-3.png"), read("at.png"), "frame 3 against --at 1.5");
    assert_ne!(
        read("f-2.png"),
        read("f-4.png"),
        "the triangle turns between frames"
    );
    // --at and --frames together are refused.
    let out = common::raylab(
        &[
            "render", file, "--at", "1", "--frames", "0..2", "-o", "x-%d.png",
        ],
        dir.path(),
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--at 1 renders one moment"), "{err}");
}

#[test]
fn bad_skins_and_channels_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let skinned = skinned_file(dir.path());
    // The skin loses joint 1, which vertices 0 and 2 name.
    let path = edited(&skinned, "one-joint.gltf", |r| {
        r["skins"][0]["joints"] = json!([1]);
    });
    let err = load_at(&path, None, None).unwrap_err();
    assert!(!err.contains('\n'), "{err}");
    assert!(
        err.contains("one-joint.gltf") && err.contains("names joint 1, but the skin has 1"),
        "{err}"
    );
    // Fewer inverse bind matrices than joints.
    let path = edited(&skinned, "short-ibm.gltf", |r| {
        r["skins"][0]["joints"] = json!([1, 0, 1]);
    });
    let err = load_at(&path, None, None).unwrap_err();
    assert!(err.contains("2 matrices for 3 joints"), "{err}");
    // A channel on a node given by a matrix.
    let trs = trs_file(dir.path());
    let path = edited(&trs, "matrix.gltf", |r| {
        r["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    });
    let err = load_at(&path, Some("step"), Some(1.0)).unwrap_err();
    assert!(err.contains("node 0 has a matrix"), "{err}");
    // Too few output values for the keyframes.
    let path = edited(&trs, "short-output.gltf", |r| {
        let out = r["animations"][0]["samplers"][0]["output"]
            .as_u64()
            .unwrap() as usize;
        r["accessors"][out]["count"] = json!(2);
    });
    let err = load_at(&path, Some("step"), Some(1.0)).unwrap_err();
    assert!(
        err.contains("6 values for 3 keyframes of 3 values (expected 9)"),
        "{err}"
    );
}
