//! glTF 2.0 cameras: the camera convention (a perspective camera looks down
//! its local −z with row zero on top), cameras numbered in depth-first node
//! order, and the framing of a file without cameras. Every file is written by
//! the test itself (see `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use builder::{Gltf, add_floor, assert_near, load, load_with, quad};
use glam::{Quat, Vec3, Vec3A};
use raylab::Camera;
use raylab::camera::{Lens, Y_UP_TOWARDS_MINUS_Z};
use raylab::load::LoadOptions;
use serde_json::json;

#[test]
fn a_perspective_camera_looks_down_its_local_minus_z_with_row_zero_on_top() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    add_floor(&mut g, None);
    let yfov = 0.9f32;
    let cam = g.camera(json!({
        "type": "perspective",
        "perspective": { "yfov": yfov, "znear": 0.1, "aspectRatio": 1.5 }
    }));
    let (tp, qp) = (Vec3::new(0.5, 1.0, 0.0), Quat::from_rotation_y(0.6));
    let (tc, qc) = (Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_x(-0.3));
    let child = g.node(json!({
        "translation": tc.to_array(), "rotation": qc.to_array(), "camera": cam
    }));
    g.root(json!({ "translation": tp.to_array(), "rotation": qp.to_array(), "children": [child] }));
    let loaded = load(&g.write(dir.path(), "camera.gltf"));
    let view = loaded.view;
    let position = tp + qp * tc;
    let q = qp * qc;
    assert_near(view.position, position.into(), 1e-5, "camera position");
    assert_eq!(view.aspect_ratio, Some(1.5));
    // The output size sets the aspect (not the file's 1.5), as the command line.
    let (w, h) = (64u32, 48u32);
    let camera = Camera::with_lens(view.position, view.rotation, view.lens, w, h);
    let tan = (0.5 * yfov).tan();
    // Image point (px, py) in pixels → camera-space direction, +y up, −z ahead.
    let local = |px: f32, py: f32| {
        let k = 2.0 * tan / h as f32;
        Vec3::new((px - 0.5 * w as f32) * k, (0.5 * h as f32 - py) * k, -1.0).normalize()
    };
    let cases = [
        ("image centre", 32.0, 24.0, Vec3::NEG_Z),
        (
            "top edge, half the fov up",
            32.0,
            0.0,
            Vec3::new(0.0, (0.5 * yfov).sin(), -(0.5 * yfov).cos()),
        ),
        (
            "bottom edge",
            32.0,
            48.0,
            Vec3::new(0.0, -(0.5 * yfov).sin(), -(0.5 * yfov).cos()),
        ),
        ("left edge", 0.0, 24.0, local(0.0, 24.0)),
        ("centre of pixel (0, 0)", 0.5, 0.5, local(0.5, 0.5)),
        ("bottom-right corner", 64.0, 48.0, local(64.0, 48.0)),
    ];
    for (what, px, py, dir_cam) in cases {
        let ray = camera.ray(px, py);
        assert_near(ray.origin, position.into(), 1e-5, what);
        assert_near(ray.dir, (q * dir_cam).into(), 1e-5, what);
    }
    // Left is −x in the camera's frame, up +y: check against the frame too.
    let left = camera.ray(0.0, 24.0).dir;
    assert!(left.dot((q * Vec3::X).into()) < 0.0);
    let top = camera.ray(32.0, 0.0).dir;
    assert!(top.dot((q * Vec3::Y).into()) > 0.0);
    // The corner ray's horizontal half-angle follows the output's aspect 4:3.
    let corner = q.inverse() * Vec3::from(camera.ray(64.0, 24.0).dir);
    assert!((corner.x / -corner.z - tan * 64.0 / 48.0).abs() < 1e-5);
}

#[test]
fn cameras_are_numbered_in_depth_first_node_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let persp = |name: &str, yfov: f32| json!({ "name": name, "type": "perspective", "perspective": { "yfov": yfov, "znear": 0.01 } });
    // The cameras array is deliberately not in tree order.
    let c_third = g.camera(persp("third", 0.3));
    let c_first = g.camera(persp("first", 0.5));
    let c_second = g.camera(persp("second", 0.7));
    // Nodes: 0 root (children 3, 1); 3 "first" (child 2); 2 "second"; 1 "third".
    g.root(json!({ "children": [3, 1] }));
    g.node(json!({ "translation": [0.0, 0.0, 1.0], "camera": c_third }));
    g.node(json!({ "translation": [0.0, 1.0, 0.0], "camera": c_second }));
    g.node(json!({ "translation": [1.0, 0.0, 0.0], "camera": c_first, "children": [2] }));
    add_floor(&mut g, None);
    let path = g.write(dir.path(), "three-cameras.gltf");
    let loaded = load(&path);
    let names: Vec<&str> = loaded
        .scene
        .cameras
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(names, ["first", "second", "third"]);
    let want = [
        (Vec3A::new(1.0, 0.0, 0.0), 0.5),
        (Vec3A::new(1.0, 1.0, 0.0), 0.7),
        (Vec3A::new(0.0, 0.0, 1.0), 0.3),
    ];
    assert_eq!(loaded.view.position, want[0].0, "default: camera 0");
    for (i, (position, yfov)) in want.iter().enumerate() {
        let options = LoadOptions {
            camera: Some(i),
            ..LoadOptions::default()
        };
        let view = load_with(&path, &options).unwrap().view;
        assert_near(view.position, *position, 1e-6, &format!("--camera {i}"));
        assert_eq!(view.lens, Lens::from_yfov(*yfov), "--camera {i}");
    }
    let options = LoadOptions {
        camera: Some(3),
        ..LoadOptions::default()
    };
    let err = load_with(&path, &options).unwrap_err();
    assert!(err.contains("three-cameras.gltf"), "{err}");
    assert!(err.contains("3 cameras"), "{err}");
}

#[test]
fn a_file_without_cameras_is_framed_from_plus_z() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let corners = [
        [2.0, 1.0, -3.0],
        [4.0, 1.0, -3.0],
        [4.0, 2.0, -3.5],
        [2.0, 2.0, -3.5],
    ];
    let p = quad(&mut g, corners, &[]);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write(dir.path(), "no-camera.gltf"));
    let view = loaded.view;
    assert_eq!(view.rotation, Y_UP_TOWARDS_MINUS_Z);
    let (lo, hi) = loaded.scene.bounds();
    let centre = (lo + hi) * 0.5;
    assert!((view.position.x - centre.x).abs() < 1e-5);
    assert!((view.position.y - centre.y).abs() < 1e-5);
    assert!(view.position.z > hi.z);
    // The whole quad is in view, and the centre ray hits it.
    let camera = Camera::with_lens(view.position, view.rotation, view.lens, 80, 60);
    for c in corners {
        let d = camera.rotation.transpose() * (Vec3A::from(c) - camera.position);
        let (px, py) = (
            d.x / d.z * camera.focal_px + 40.0,
            d.y / d.z * camera.focal_px + 30.0,
        );
        assert!(d.z > 0.0 && (0.0..80.0).contains(&px) && (0.0..60.0).contains(&py));
    }
    assert!(
        loaded
            .scene
            .intersect(&camera.ray(40.0, 30.0), f32::INFINITY)
            .is_some()
    );
}
