//! The glTF 2.0 loader and the scene it builds, against numbers worked out by
//! hand from the glTF specification and `../shared/specs/scene-conventions.md`:
//! node transforms and winding, primitive modes and index types, sparse,
//! normalized and interleaved accessors, cameras, normal mapping, alpha holes,
//! punctual lights, emitters' sides, and bad files. Every file is written by the
//! test itself (see `common/gltf_builder.rs`).

#[path = "common/gltf_builder.rs"]
mod builder;

use std::f32::consts::{FRAC_PI_2, PI};
use std::path::Path;

use builder::{F32, Gltf, I8, I16, U8, U16, U32, assert_near, load, load_with, png, quad};
use glam::{Mat3, Quat, Vec2, Vec3, Vec3A, Vec4};
use raylab::camera::{Lens, Y_UP_TOWARDS_MINUS_Z};
use raylab::integrators::path::PathOptions;
use raylab::lights::Incident;
use raylab::load::{LoadOptions, Loaded};
use raylab::materials::surface::MaterialKind;
use raylab::render::sample_pixel;
use raylab::scene::Facing;
use raylab::{Camera, Hit, Integrator, LightSample, Ray, Scene};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// Helpers

/// The error message of a file that must not load.
fn load_err(path: &Path) -> String {
    match load_with(path, &LoadOptions::default()) {
        Ok(_) => panic!("{} loaded but should not have", path.display()),
        Err(e) => e,
    }
}

/// `t + q·(s ∘ p)`: a glTF TRS node applied to a point, written out.
fn trs(t: Vec3, q: Quat, s: Vec3, p: Vec3) -> Vec3 {
    t + q * (s * p)
}

/// A column-major glTF `matrix` applied to a point, written out.
fn apply_matrix(m: &[f32; 16], p: Vec3) -> Vec3 {
    let col = |c: usize| Vec3::new(m[4 * c], m[4 * c + 1], m[4 * c + 2]);
    col(0) * p.x + col(1) * p.y + col(2) * p.z + col(3)
}

/// The linear part of a map of points `f` (columns: images of the axes).
fn linear_part(f: impl Fn(Vec3) -> Vec3) -> Mat3 {
    let o = f(Vec3::ZERO);
    Mat3::from_cols(f(Vec3::X) - o, f(Vec3::Y) - o, f(Vec3::Z) - o)
}

/// A hit on triangle `prim` at barycentrics (b1, b2).
fn hit_at(prim: u32, b1: f32, b2: f32) -> Hit {
    Hit {
        t: 1.0,
        prim,
        b1,
        b2,
    }
}

/// The square of side 2 centred on the origin in the z = 0 plane, front +z.
const XY_SQUARE: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// A 20 × 20 floor in the y = 0 plane, front +y.
const FLOOR: [[f32; 3]; 4] = [
    [-10.0, 0.0, 10.0],
    [10.0, 0.0, 10.0],
    [10.0, 0.0, -10.0],
    [-10.0, 0.0, -10.0],
];

fn bytes_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

// ---------------------------------------------------------------------------
// 1. Node transforms

#[test]
fn a_three_level_hierarchy_composes_parent_times_child() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let local = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.3, -0.7, 2.0],
    ];
    let pos = g.floats(&local);
    let idx = g.indices(U16, &[0, 1, 2, 1, 3, 2]);
    let mesh = g.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    // Leaf (node 0): TRS with a non-uniform scale.
    let (tc, qc, sc) = (
        Vec3::new(-0.5, 0.25, 2.0),
        Quat::from_axis_angle(Vec3::new(0.0, 1.0, 0.0), 1.1),
        Vec3::new(1.0, 3.0, 0.2),
    );
    let c = g.node(json!({
        "translation": tc.to_array(), "rotation": qc.to_array(), "scale": sc.to_array(), "mesh": mesh
    }));
    // Middle (node 1): a matrix with shear, column-major.
    let mb: [f32; 16] = [
        0.9, 0.1, -0.2, 0.0, 0.3, 1.1, 0.0, 0.0, 0.0, -0.4, 0.8, 0.0, 3.0, 0.5, -1.0, 1.0,
    ];
    let b = g.node(json!({ "matrix": mb, "children": [c] }));
    // Root (node 2): TRS, rotation about a skew axis, non-uniform scale.
    let (ta, qa, sa) = (
        Vec3::new(1.0, -2.0, 0.5),
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
        Vec3::new(2.0, 0.5, 1.5),
    );
    g.root(json!({
        "translation": ta.to_array(), "rotation": qa.to_array(), "scale": sa.to_array(), "children": [b]
    }));
    let loaded = load(&g.write(dir.path(), "hierarchy.gltf"));
    let scene = &loaded.scene;

    let world = |p: Vec3| trs(ta, qa, sa, apply_matrix(&mb, trs(tc, qc, sc, p)));
    let tris = scene.triangles();
    assert_eq!(tris.len(), 2);
    for (t, idx) in tris.iter().zip([[0, 1, 2], [1, 3, 2]]) {
        for k in 0..3 {
            let want = Vec3A::from(world(Vec3::from(local[idx[k]])));
            assert_near(t.v[k], want, 1e-4, &format!("vertex {k} of {idx:?}"));
        }
    }
    // The front normal is the object normal (+z) under the inverse transpose.
    let linear = linear_part(world);
    assert!(linear.determinant() > 0.0);
    let n = Vec3A::from((linear.inverse().transpose() * Vec3::Z).normalize());
    assert_near(scene.normal(0), n, 1e-5, "front normal");
}

#[test]
fn a_mirroring_node_flips_the_front_face() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let local = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    // Counter-clockwise seen from +z: the front normal in object space is +z.
    let pos = g.floats(&local);
    let mesh = g.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    let rot = Quat::from_rotation_x(FRAC_PI_2);
    let nodes = [
        (json!({ "mesh": mesh }), Mat3::IDENTITY),
        (
            json!({ "scale": [-1.0, 1.0, 1.0], "mesh": mesh }),
            Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0)),
        ),
        (
            json!({ "scale": [1.0, 1.0, -1.0], "mesh": mesh }),
            Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0)),
        ),
        (
            json!({ "rotation": rot.to_array(), "scale": [-2.0, 1.0, 0.5], "mesh": mesh }),
            Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::new(-2.0, 1.0, 0.5)),
        ),
        (
            json!({ "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -3.0, 0.0, 0.0, 0.0, 5.0, 1.0],
                    "mesh": mesh }),
            Mat3::from_diagonal(Vec3::new(1.0, 1.0, -3.0)),
        ),
    ];
    for (node, _) in &nodes {
        g.root(node.clone());
    }
    // Two mirrors in a row: no mirror.
    let child = g.node(json!({ "scale": [1.0, -1.0, 1.0], "mesh": mesh }));
    g.root(json!({ "scale": [-1.0, 1.0, 1.0], "children": [child] }));
    let loaded = load(&g.write(dir.path(), "mirrors.gltf"));
    let scene = &loaded.scene;
    let mut cases: Vec<Mat3> = nodes.iter().map(|(_, m)| *m).collect();
    cases.push(Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0)));
    assert_eq!(scene.triangles().len(), cases.len());
    for (prim, m) in cases.iter().enumerate() {
        let v = scene.triangles()[prim].v;
        let want_n = Vec3A::from((m.inverse().transpose() * Vec3::Z).normalize());
        let winding = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let mirrored = m.determinant() < 0.0;
        // The test bites: a mirror makes the world winding clockwise seen from
        // the front, so the naive cross product points the other way.
        assert_near(
            winding,
            if mirrored { -want_n } else { want_n },
            1e-5,
            "winding",
        );
        assert_near(
            scene.normal(prim as u32),
            want_n,
            1e-5,
            &format!("front normal of case {prim} (mirrored: {mirrored})"),
        );
        assert_near(
            scene.surface(&hit_at(prim as u32, 0.2, 0.3)).ng,
            want_n,
            1e-5,
            "surface ng",
        );
    }
}

// ---------------------------------------------------------------------------
// 2. Primitive modes and index types

#[test]
fn every_primitive_mode_and_index_type_gives_the_specified_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let positions: Vec<[f32; 3]> = (0..6)
        .map(|i| {
            let i = i as f32;
            [i, 0.25 * i * i, 1.0 - 0.5 * i]
        })
        .collect();
    let pos = g.floats(&positions);
    let i_u8 = g.indices(U8, &[5, 3, 1, 0, 2, 4]);
    let i_u16 = g.indices(U16, &[4, 0, 5, 1, 3]);
    let i_u32 = g.indices(U32, &[2, 5, 0, 4]);
    let i_u32_tri = g.indices(U32, &[1, 2, 3]);
    let i_lines = g.indices(U16, &[0, 1, 2, 3]);
    let prim = |mode: Option<u32>, indices: Option<usize>| {
        let mut p = json!({ "attributes": { "POSITION": pos } });
        if let Some(m) = mode {
            p["mode"] = json!(m);
        }
        if let Some(i) = indices {
            p["indices"] = json!(i);
        }
        p
    };
    let mesh = g.mesh(vec![
        prim(Some(4), None),          // TRIANGLES, non-indexed
        prim(Some(0), None),          // POINTS: skipped
        prim(Some(4), Some(i_u8)),    // TRIANGLES, u8
        prim(Some(5), None),          // TRIANGLE_STRIP, non-indexed
        prim(Some(1), Some(i_lines)), // LINES: skipped
        prim(Some(5), Some(i_u16)),   // TRIANGLE_STRIP, u16
        prim(Some(6), None),          // TRIANGLE_FAN, non-indexed
        prim(Some(6), Some(i_u32)),   // TRIANGLE_FAN, u32
        prim(Some(3), None),          // LINE_STRIP: skipped
        prim(Some(2), None),          // LINE_LOOP: skipped
        prim(None, Some(i_u32_tri)),  // mode omitted: TRIANGLES, u32
    ]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write(dir.path(), "modes.gltf"));
    // The glTF specification (§3.7.2.1): strips p_i = {v_i, v_(i+(1+i%2)),
    // v_(i+(2−i%2))}, fans p_i = {v_(i+1), v_(i+2), v_0}, written out.
    let want: Vec<[usize; 3]> = vec![
        // TRIANGLES 0..6
        [0, 1, 2],
        [3, 4, 5],
        // TRIANGLES [5 3 1 0 2 4]
        [5, 3, 1],
        [0, 2, 4],
        // TRIANGLE_STRIP 0..6
        [0, 1, 2],
        [1, 3, 2],
        [2, 3, 4],
        [3, 5, 4],
        // TRIANGLE_STRIP [4 0 5 1 3]
        [4, 0, 5],
        [0, 1, 5],
        [5, 1, 3],
        // TRIANGLE_FAN 0..6
        [1, 2, 0],
        [2, 3, 0],
        [3, 4, 0],
        [4, 5, 0],
        // TRIANGLE_FAN [2 5 0 4]
        [5, 0, 2],
        [0, 4, 2],
        // TRIANGLES [1 2 3]
        [1, 2, 3],
    ];
    let tris = loaded.scene.triangles();
    assert_eq!(tris.len(), want.len());
    for (i, (t, w)) in tris.iter().zip(&want).enumerate() {
        let expected = w.map(|k| Vec3A::from(positions[k]));
        assert_eq!(t.v, expected, "triangle {i} should be {w:?}");
    }
    // The four skipped modes are each named once in a warning.
    let skipped: Vec<String> = loaded
        .warnings
        .iter()
        .map(|w| w.to_lowercase().replace('_', ""))
        .filter(|w| w.contains("skip"))
        .collect();
    assert_eq!(skipped.len(), 4, "{:?}", loaded.warnings);
    for mode in ["points", "lines", "linestrip", "lineloop"] {
        assert!(
            skipped
                .iter()
                .any(|w| w.split(|c: char| !c.is_alphanumeric()).any(|x| x == mode)),
            "no warning names {mode}: {:?}",
            loaded.warnings
        );
    }
}

#[test]
fn a_file_of_points_only_loads_empty_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let pos = g.floats(&[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
    let mesh = g.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "mode": 0 }),
    ]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write(dir.path(), "points.gltf"));
    assert_eq!(loaded.scene.triangles().len(), 0);
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.view.position.is_finite());
}

// ---------------------------------------------------------------------------
// 3. Sparse, normalized and interleaved accessors

#[test]
fn sparse_accessors_substitute_values_with_and_without_a_base_view() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // (a) A base view of four positions; elements 1 and 3 replaced (u16 indices).
    let base = g.view(
        &bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]),
        None,
    );
    let sparse_idx = g.view(&[1u16, 3].map(u16::to_le_bytes).concat(), None);
    let sparse_val = g.view(&bytes_f32(&[5.0, 0.0, 0.0, 7.0, 7.0, 7.0]), None);
    let a = g.accessor(json!({
        "bufferView": base, "componentType": F32, "count": 4, "type": "VEC3",
        "sparse": {
            "count": 2,
            "indices": { "bufferView": sparse_idx, "componentType": U16 },
            "values": { "bufferView": sparse_val },
        }
    }));
    // (b) No base view: zeros, elements 0 and 2 replaced (u8 indices).
    let idx_b = g.view(&[0u8, 2], None);
    let val_b = g.view(&bytes_f32(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), None);
    let b = g.accessor(json!({
        "componentType": F32, "count": 3, "type": "VEC3",
        "sparse": {
            "count": 2,
            "indices": { "bufferView": idx_b, "componentType": U8 },
            "values": { "bufferView": val_b },
        }
    }));
    // (c) u32 sparse indices and values at byte offsets within their views,
    // over a base accessor at an offset in its view.
    let base_c = g.view(
        &bytes_f32(&[9.0, 9.0, 9.0, 0.0, 0.0, 1.0, 2.0, 0.0, 1.0, 0.0, 2.0, 1.0]),
        None,
    );
    let idx_c = g.view(&[77u32, 2].map(u32::to_le_bytes).concat(), None);
    let val_c = g.view(&bytes_f32(&[-1.0, -1.0, -1.0, 0.5, 0.5, 3.0]), None);
    let c = g.accessor(json!({
        "bufferView": base_c, "byteOffset": 12, "componentType": F32, "count": 3, "type": "VEC3",
        "sparse": {
            "count": 1,
            "indices": { "bufferView": idx_c, "byteOffset": 4, "componentType": U32 },
            "values": { "bufferView": val_c, "byteOffset": 12 },
        }
    }));
    let i4 = g.indices(U8, &[0, 1, 2, 1, 3, 2]);
    // (d) A sparse index accessor: element 4 (3) of a u16 list becomes 0.
    let base_d = g.view(&[0u16, 1, 2, 1, 3, 2].map(u16::to_le_bytes).concat(), None);
    let idx_d = g.view(&[4u8], None);
    let val_d = g.view(&0u16.to_le_bytes(), None);
    let d = g.accessor(json!({
        "bufferView": base_d, "componentType": U16, "count": 6, "type": "SCALAR",
        "sparse": {
            "count": 1,
            "indices": { "bufferView": idx_d, "componentType": U8 },
            "values": { "bufferView": val_d },
        }
    }));
    let mesh = g.mesh(vec![
        json!({ "attributes": { "POSITION": a }, "indices": i4 }),
        json!({ "attributes": { "POSITION": b } }),
        json!({ "attributes": { "POSITION": c } }),
        json!({ "attributes": { "POSITION": a }, "indices": d }),
    ]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write(dir.path(), "sparse.gltf"));
    let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
    let want = [
        [v(0.0, 0.0, 0.0), v(5.0, 0.0, 0.0), v(0.0, 1.0, 0.0)],
        [v(5.0, 0.0, 0.0), v(7.0, 7.0, 7.0), v(0.0, 1.0, 0.0)],
        [v(1.0, 2.0, 3.0), v(0.0, 0.0, 0.0), v(4.0, 5.0, 6.0)],
        [v(0.0, 0.0, 1.0), v(2.0, 0.0, 1.0), v(0.5, 0.5, 3.0)],
        [v(0.0, 0.0, 0.0), v(5.0, 0.0, 0.0), v(0.0, 1.0, 0.0)],
        [v(5.0, 0.0, 0.0), v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0)],
    ];
    let tris = loaded.scene.triangles();
    assert_eq!(tris.len(), want.len());
    for (i, (t, w)) in tris.iter().zip(&want).enumerate() {
        assert_eq!(t.v, *w, "triangle {i}");
    }
}

#[test]
fn normalized_integer_attributes_follow_the_gltf_rules() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let pos = g.floats(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    // i8 normals, padded to 4 bytes per element; −128 clamps to −1.
    let normals: [[i8; 3]; 3] = [[0, 0, 127], [64, 0, 110], [-128, 0, 127]];
    let nbytes: Vec<u8> = normals
        .iter()
        .flat_map(|n| [n[0] as u8, n[1] as u8, n[2] as u8, 0])
        .collect();
    let nview = g.view(&nbytes, Some(4));
    let nacc = g.accessor(json!({
        "bufferView": nview, "componentType": I8, "normalized": true, "count": 3, "type": "VEC3"
    }));
    // u16 texture coordinates.
    let uv: [[u16; 2]; 3] = [[0, 65535], [32768, 16384], [65535, 0]];
    let uview = g.view(
        &uv.iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect::<Vec<_>>(),
        None,
    );
    let uacc = g.accessor(json!({
        "bufferView": uview, "componentType": U16, "normalized": true, "count": 3, "type": "VEC2"
    }));
    // i8 second set (KHR_mesh_quantization allows it).
    let uv1: [[i8; 2]; 3] = [[-128, 127], [0, -64], [32, 127]];
    let u1bytes: Vec<u8> = uv1
        .iter()
        .flat_map(|t| [t[0] as u8, t[1] as u8, 0, 0])
        .collect();
    let u1view = g.view(&u1bytes, Some(4));
    let u1acc = g.accessor(json!({
        "bufferView": u1view, "componentType": I8, "normalized": true, "count": 3, "type": "VEC2"
    }));
    // u8 colours.
    let colors: [[u8; 4]; 3] = [[255, 0, 51, 255], [0, 255, 102, 128], [10, 20, 30, 0]];
    let cview = g.view(colors.as_flattened(), None);
    let cacc = g.accessor(json!({
        "bufferView": cview, "componentType": U8, "normalized": true, "count": 3, "type": "VEC4"
    }));
    let mesh = g.mesh(vec![json!({ "attributes": {
        "POSITION": pos, "NORMAL": nacc, "TEXCOORD_0": uacc, "TEXCOORD_1": u1acc, "COLOR_0": cacc
    } })]);
    g.root(json!({ "mesh": mesh }));
    g.extensions_used.push("KHR_mesh_quantization".into());
    g.extensions_required.push("KHR_mesh_quantization".into());
    let loaded = load(&g.write(dir.path(), "normalized.gltf"));
    let scene = &loaded.scene;
    let want_n = [
        Vec3::Z,
        Vec3::new(64.0 / 127.0, 0.0, 110.0 / 127.0).normalize(),
        Vec3::new(-1.0, 0.0, 1.0).normalize(),
    ];
    let corner = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
    for (k, &(b1, b2)) in corner.iter().enumerate() {
        let hit = hit_at(0, b1, b2);
        let s = scene.surface(&hit);
        assert_near(s.ns, want_n[k].into(), 1e-5, &format!("normal {k}"));
        let a = scene.attributes(&hit);
        let want_uv = Vec2::new(uv[k][0] as f32, uv[k][1] as f32) / 65535.0;
        assert!((a.uv[0] - want_uv).abs().max_element() < 1e-6, "uv {k}");
        let want_uv1 = Vec2::new(
            (uv1[k][0] as f32 / 127.0).max(-1.0),
            (uv1[k][1] as f32 / 127.0).max(-1.0),
        );
        assert!(
            (a.uv[1] - want_uv1).abs().max_element() < 1e-6,
            "uv1 {k}: {} vs {want_uv1}",
            a.uv[1]
        );
        let want_c = Vec4::from_array(colors[k].map(|c| c as f32 / 255.0));
        assert!((a.color - want_c).abs().max_element() < 1e-6, "colour {k}");
    }
    // In between, attributes interpolate barycentrically.
    let mid = scene.attributes(&hit_at(0, 0.25, 0.5));
    let want_mid = (Vec2::new(0.0, 65535.0) * 0.25
        + Vec2::new(32768.0, 16384.0) * 0.25
        + Vec2::new(65535.0, 0.0) * 0.5)
        / 65535.0;
    assert!((mid.uv[0] - want_mid).abs().max_element() < 1e-6);
}

#[test]
fn quantized_positions_are_read_as_integers_or_normalized() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let int_pos: [[i16; 3]; 3] = [[100, -200, 300], [-32768, 0, 5], [0, 32767, -1]];
    let norm_pos: [[i16; 3]; 3] = [[-32768, 16384, 0], [32767, 0, 0], [0, -16384, 100]];
    // VEC3 of i16 is 6 bytes; vertex attributes are 4-byte aligned: stride 8.
    let bytes = |v: &[[i16; 3]; 3]| -> Vec<u8> {
        v.iter()
            .flat_map(|p| [p[0], p[1], p[2], 0])
            .flat_map(i16::to_le_bytes)
            .collect()
    };
    let view_i = g.view(&bytes(&int_pos), Some(8));
    let acc_i = g.accessor(json!({
        "bufferView": view_i, "componentType": I16, "count": 3, "type": "VEC3"
    }));
    let view_n = g.view(&bytes(&norm_pos), Some(8));
    let acc_n = g.accessor(json!({
        "bufferView": view_n, "componentType": I16, "normalized": true, "count": 3, "type": "VEC3"
    }));
    let mi = g.mesh(vec![json!({ "attributes": { "POSITION": acc_i } })]);
    let mn = g.mesh(vec![json!({ "attributes": { "POSITION": acc_n } })]);
    // The dequantization scale sits on the node, as KHR_mesh_quantization does it.
    g.root(json!({ "mesh": mi, "scale": [0.01, 0.01, 0.01] }));
    g.root(json!({ "mesh": mn }));
    g.extensions_used.push("KHR_mesh_quantization".into());
    g.extensions_required.push("KHR_mesh_quantization".into());
    let loaded = load(&g.write(dir.path(), "quantized.gltf"));
    let tris = loaded.scene.triangles();
    assert_eq!(tris.len(), 2);
    for k in 0..3 {
        let want = Vec3A::from_array(int_pos[k].map(|x| x as f32 * 0.01));
        assert_near(tris[0].v[k], want, 1e-5, "integer position");
        let want = Vec3A::from_array(norm_pos[k].map(|x| (x as f32 / 32767.0).max(-1.0)));
        assert_near(tris[1].v[k], want, 1e-6, "normalized position");
    }
    assert_eq!(tris[1].v[0].x, -1.0, "−32768 clamps to −1");
}

#[test]
fn interleaved_views_are_read_with_their_stride() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // Per vertex: position (12 bytes), normal (12), uv (8), 4 bytes of padding;
    // preceded by 8 bytes the accessors skip with their byteOffset.
    let verts: [([f32; 3], [f32; 3], [f32; 2]); 4] = [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.9]),
        ([2.0, 0.0, 0.0], [0.6, 0.0, 0.8], [0.8, 0.7]),
        ([2.0, 1.0, 0.0], [0.0, 0.6, 0.8], [0.6, 0.2]),
        ([0.0, 1.0, 0.5], [-0.6, 0.0, 0.8], [0.3, 0.4]),
    ];
    let mut bytes = vec![0xAB; 8];
    for (p, n, t) in &verts {
        bytes.extend(bytes_f32(p));
        bytes.extend(bytes_f32(n));
        bytes.extend(bytes_f32(t));
        bytes.extend([0xCD; 4]);
    }
    // Something before the view, so that its own offset in the buffer is not 0.
    g.view(&[1, 2, 3, 4, 5, 6, 7, 8], None);
    let view = g.view(&bytes, Some(36));
    let acc = |g: &mut Gltf, offset: usize, ty: &str| {
        g.accessor(json!({
            "bufferView": view, "byteOffset": 8 + offset, "componentType": F32, "count": 4, "type": ty
        }))
    };
    let (p, n, t) = (
        acc(&mut g, 0, "VEC3"),
        acc(&mut g, 12, "VEC3"),
        acc(&mut g, 24, "VEC2"),
    );
    let idx = g.indices(U8, &[0, 1, 2, 0, 2, 3]);
    let mesh = g.mesh(vec![json!({
        "attributes": { "POSITION": p, "NORMAL": n, "TEXCOORD_0": t }, "indices": idx
    })]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write_with_bin(
        dir.path(),
        "interleaved.gltf",
        "inter leaved.bin",
        "inter%20leaved.bin",
    ));
    let scene = &loaded.scene;
    let tris = scene.triangles();
    assert_eq!(tris.len(), 2);
    for (prim, idx) in [[0usize, 1, 2], [0, 2, 3]].iter().enumerate() {
        for k in 0..3 {
            let (p, n, t) = verts[idx[k]];
            assert_eq!(tris[prim].v[k], Vec3A::from(p));
            let (b1, b2) = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][k];
            let hit = hit_at(prim as u32, b1, b2);
            assert_near(scene.surface(&hit).ns, Vec3A::from(n), 1e-6, "normal");
            assert!((scene.attributes(&hit).uv[0] - Vec2::from(t)).length() < 1e-6);
        }
    }
}

// ---------------------------------------------------------------------------
// 4. Cameras

/// A floor for scenes that only need something to look at.
fn add_floor(g: &mut Gltf, material: Option<usize>) -> usize {
    let mut p = quad(g, FLOOR, &[]);
    if let Some(m) = material {
        p["material"] = json!(m);
    }
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }))
}

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

// ---------------------------------------------------------------------------
// 5. Normal mapping

/// The texel of the constant normal map and the tangent-space normal it
/// encodes (linear, [0, 1] → [−1, 1], x and y scaled).
const NORMAL_TEXEL: [u8; 3] = [200, 80, 230];

fn mapped_normal(scale: f32) -> Vec3 {
    let f = NORMAL_TEXEL.map(|b| 2.0 * b as f32 / 255.0 - 1.0);
    Vec3::new(f[0] * scale, f[1] * scale, f[2])
}

/// A unit square in the z = 0 plane with the constant normal map (material 0,
/// made by the first call with `normalTexture.scale` = `scale`), texture
/// coordinates `uv_of(corner)`, and optional normals and tangents, as the mesh
/// of a new root node `node` (TRS JSON).
fn normal_mapped_square(
    g: &mut Gltf,
    uv_of: impl Fn(Vec2) -> Vec2,
    tangent: Option<Vec4>,
    with_normals: bool,
    scale: f32,
    mut node: Value,
) {
    if g.textures.is_empty() {
        let png = png(2, 2, 3, &NORMAL_TEXEL.repeat(4));
        g.png_texture(&png, None);
        g.material(json!({
            "pbrMetallicRoughness": { "metallicFactor": 0.0 },
            "normalTexture": { "index": 0, "scale": scale }
        }));
    }
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let uvs: Vec<[f32; 2]> = corners
        .iter()
        .map(|c| uv_of(Vec2::new(c[0], c[1])).to_array())
        .collect();
    let uv = g.floats(&uvs);
    let mut extra = vec![("TEXCOORD_0", uv)];
    if with_normals {
        extra.push(("NORMAL", g.floats(&[[0.0, 0.0, 1.0]; 4])));
    }
    if let Some(t) = tangent {
        extra.push(("TANGENT", g.floats(&[t.to_array(); 4])));
    }
    let mut p = quad(g, corners, &extra);
    p["material"] = json!(0);
    node["mesh"] = json!(g.mesh(vec![p]));
    g.root(node);
}

/// The shading normal at the middle of the first triangle of instance `i`
/// (two triangles per instance), found by a ray from the front.
fn shading_normal_at(scene: &Scene, i: u32) -> Vec3A {
    let prim = 2 * i;
    let t = scene.triangles()[prim as usize];
    let centre = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
    let n = scene.normal(prim);
    let ray = Ray::new(centre + n, -n);
    let hit = scene.intersect(&ray, 2.0).expect("the ray hits the square");
    assert_eq!(hit.prim, prim);
    scene.surface(&hit).ns
}

#[test]
fn normal_maps_use_the_tangent_attribute_and_the_node_transform() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let scale = 0.6;
    let a = 0.4f32;
    let tangent = Vec4::new(a.cos(), a.sin(), 0.0, -1.0);
    let uv_of = |c: Vec2| Vec2::new(c.x, 1.0 - c.y);
    let rot = Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 0.5);
    // Instance 0: rotation and non-uniform scale; instance 1: a mirror with a
    // rotation; instance 2: no normals (the face normal is N).
    let m0 = Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::new(2.0, 0.5, 1.0));
    let m1 = Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
    let node = |s: [f32; 3], t: [f32; 3]| json!({ "rotation": rot.to_array(), "scale": s, "translation": t });
    normal_mapped_square(
        &mut g,
        uv_of,
        Some(tangent),
        true,
        scale,
        node([2.0, 0.5, 1.0], [0.0, 0.0, 0.0]),
    );
    normal_mapped_square(
        &mut g,
        uv_of,
        Some(tangent),
        true,
        scale,
        node([-1.0, 1.0, 1.0], [5.0, 0.0, 0.0]),
    );
    normal_mapped_square(
        &mut g,
        uv_of,
        Some(tangent),
        false,
        scale,
        node([2.0, 0.5, 1.0], [0.0, 5.0, 0.0]),
    );
    let loaded = load(&g.write(dir.path(), "normal-map-tangents.gltf"));
    let scene = &loaded.scene;
    let m = mapped_normal(scale);
    // The glTF frame: T = linear part × TANGENT.xyz, N = inverse transpose ×
    // NORMAL, B = w · sign(det) · (N × T).
    let expected = |linear: Mat3| {
        let n = (linear.inverse().transpose() * Vec3::Z).normalize();
        let t = (linear * tangent.truncate()).normalize();
        assert!(n.dot(t).abs() < 1e-6);
        let w = tangent.w * linear.determinant().signum();
        let b = w * n.cross(t);
        Vec3A::from((m.x * t + m.y * b + m.z * n).normalize())
    };
    for (i, linear) in [m0, m1, m0].into_iter().enumerate() {
        let ns = shading_normal_at(scene, i as u32);
        assert_near(ns, expected(linear), 1e-3, &format!("instance {i}"));
    }
    // For the mirror (an orthogonal map) that is the mirrored object-space normal.
    let t = tangent.truncate();
    let b = tangent.w * Vec3::Z.cross(t);
    let object = (m.x * t + m.y * b + m.z * Vec3::Z).normalize();
    assert_near(
        shading_normal_at(scene, 1),
        (m1 * object).into(),
        1e-3,
        "mirrored",
    );
    // The map really tilts the normal (and scale matters).
    assert!(shading_normal_at(scene, 0).dot(scene.normal(0)) < 0.95);
}

/// A square's texture coordinates as a function of its corner, with the
/// directions of increasing u and of decreasing v (up in the image).
type UvLayout = (fn(Vec2) -> Vec2, Vec3, Vec3);

#[test]
fn without_tangents_mikktspace_runs_on_u_and_one_minus_v() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let scale_xy = 1.7;
    // Texture layouts of the square, with the directions of increasing u and of
    // decreasing v (up in the image) in the square's plane.
    let layouts: [UvLayout; 4] = [
        // The usual: u along +x, image up along +y.
        (|c| Vec2::new(c.x, 1.0 - c.y), Vec3::X, Vec3::Y),
        // v flipped (a mirrored layout): image up along −y.
        (|c| Vec2::new(c.x, c.y), Vec3::X, Vec3::NEG_Y),
        // Turned: u along +y, v along +x, so image up is −x.
        (|c| Vec2::new(c.y, c.x), Vec3::Y, Vec3::NEG_X),
        // Scaled and offset: u along −x, image up along +y.
        (
            |c| Vec2::new(2.0 - 3.0 * c.x, 0.5 - 0.5 * c.y),
            Vec3::NEG_X,
            Vec3::Y,
        ),
    ];
    let rot = Quat::from_rotation_z(0.3) * Quat::from_rotation_x(-0.8);
    let mirror = Vec3::new(-1.0, 1.0, 1.0);
    // Every layout under a rotation, then the first two under a mirror too.
    let cases: Vec<(UvLayout, Mat3)> = layouts
        .iter()
        .map(|&l| (l, Mat3::from_quat(rot)))
        .chain(
            layouts[..2]
                .iter()
                .map(|&l| (l, Mat3::from_quat(rot) * Mat3::from_diagonal(mirror))),
        )
        .collect();
    for (i, ((uv_of, _, _), m)) in cases.iter().enumerate() {
        let scale = if m.determinant() < 0.0 {
            mirror
        } else {
            Vec3::ONE
        };
        let node = json!({
            "rotation": rot.to_array(), "scale": scale.to_array(), "translation": [3.0 * i as f32, 0.0, 0.0]
        });
        normal_mapped_square(&mut g, uv_of, None, i % 2 == 0, scale_xy, node);
    }
    let loaded = load(&g.write(dir.path(), "normal-map-mikktspace.gltf"));
    let scene = &loaded.scene;
    let n = mapped_normal(scale_xy);
    for (i, ((_, t, b), m)) in cases.iter().enumerate() {
        // The object-space normal, carried by the (orthogonal) node transform.
        let object = n.x * *t + n.y * *b + n.z * Vec3::Z;
        let want = Vec3A::from((*m * object).normalize());
        let ns = shading_normal_at(scene, i as u32);
        assert_near(ns, want, 1e-3, &format!("case {i}"));
        // Raw-UV MikkTSpace would flip the bitangent: clearly different.
        let flipped = (*m * (n.x * *t - n.y * *b + n.z * Vec3::Z)).normalize();
        assert!((ns - Vec3A::from(flipped)).length() > 0.1);
    }
}

// ---------------------------------------------------------------------------
// 6. Alpha

/// A masked or blended square at z = 0 in front of an opaque one at z = −1.
fn alpha_scene(dir: &Path, name: &str, material: Value, texture: Option<&[u8]>) -> Scene {
    let mut g = Gltf::new();
    if let Some(png) = texture {
        // Clamped, so that the halves do not blend across the wrap.
        g.png_texture(png, Some(json!({ "wrapS": 33071, "wrapT": 33071 })));
    }
    let front = g.material(material);
    let back =
        g.material(json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.2, 0.2, 1.0] } }));
    // u = (x + 1)/2, v = (1 − y)/2.
    let uv = g.floats(&XY_SQUARE.map(|c| [(c[0] + 1.0) / 2.0, (1.0 - c[1]) / 2.0]));
    let mut p = quad(&mut g, XY_SQUARE, &[("TEXCOORD_0", uv)]);
    p["material"] = json!(front);
    let m = g.mesh(vec![p]);
    g.root(json!({ "mesh": m }));
    let mut p = quad(&mut g, XY_SQUARE, &[]);
    p["material"] = json!(back);
    let m = g.mesh(vec![p]);
    g.root(json!({ "mesh": m, "translation": [0.0, 0.0, -1.0] }));
    load(&g.write(dir, name)).scene
}

#[test]
fn alpha_mask_holes_let_camera_and_shadow_rays_through() {
    let dir = tempfile::tempdir().unwrap();
    // Two texels: alpha 0 on the left (u < 0.5), 1 on the right.
    let png = png(2, 1, 4, &[255, 255, 255, 0, 255, 255, 255, 255]);
    let scene = alpha_scene(
        dir.path(),
        "mask.gltf",
        json!({ "alphaMode": "MASK", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }),
        Some(&png),
    );
    let dir_v = Vec3A::new(0.05, -0.1, -1.0).normalize();
    // From z = 2: the front square at t = 2/|dz|, the back one at 3/|dz|.
    let (t_front, t_back) = (2.0 / -dir_v.z, 3.0 / -dir_v.z);
    // Through the hole: crosses z = 0 at x = −0.4 (u = 0.3, alpha 0.1).
    let hole = Ray::new(Vec3A::new(-0.5, 0.3, 2.0), dir_v);
    let hit = scene
        .intersect(&hole, f32::INFINITY)
        .expect("the back square");
    assert!(hit.prim >= 2, "{hit:?}");
    assert!(
        (hit.t - t_back).abs() < 1e-5 * t_back,
        "{} vs {t_back}",
        hit.t
    );
    assert!((hole.at(hit.t).z + 1.0).abs() < 1e-5);
    assert!(!scene.occluded(&hole, t_back - 0.01));
    assert!(scene.occluded(&hole, t_back + 0.01));
    assert!(scene.intersect(&hole, t_back - 0.01).is_none());
    // Through the solid half: crosses z = 0 at x = 0.6 (u = 0.8, alpha 1).
    let solid = Ray::new(Vec3A::new(0.5, 0.3, 2.0), dir_v);
    let hit = scene
        .intersect(&solid, f32::INFINITY)
        .expect("the front square");
    assert!(hit.prim < 2, "{hit:?}");
    assert!((hit.t - t_front).abs() < 1e-5 * t_front);
    assert!(scene.occluded(&solid, t_front + 0.01));
    assert!(!scene.occluded(&solid, t_front - 0.01));
    // From between the squares looking back at the front one: holes work from
    // behind as well.
    let back_hole = Ray::new(Vec3A::new(-0.5, 0.0, -0.5), Vec3A::Z);
    assert!(scene.intersect(&back_hole, f32::INFINITY).is_none());
    assert!(!scene.occluded(&back_hole, 10.0));
    let back_solid = Ray::new(Vec3A::new(0.5, 0.0, -0.5), Vec3A::Z);
    assert_eq!(
        scene
            .intersect(&back_solid, f32::INFINITY)
            .map(|h| h.prim < 2),
        Some(true)
    );
    // The flat integrator sees the back square's grey through the hole.
    let mut rays = 0;
    let through = Integrator::Flat.radiance(&scene, &hole, &mut rays);
    assert_near(through, Vec3A::splat(0.2), 1e-6, "flat through the hole");
}

#[test]
fn alpha_mask_cutoff_applies_to_the_factor_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let ray = Ray::new(Vec3A::new(0.3, 0.2, 2.0), Vec3A::NEG_Z);
    for (cutoff, alpha, hole) in [(0.5, 0.6, false), (0.7, 0.6, true), (0.25, 0.2, true)] {
        let scene = alpha_scene(
            dir.path(),
            &format!("cutoff-{cutoff}.gltf"),
            json!({ "alphaMode": "MASK", "alphaCutoff": cutoff,
                    "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, alpha] } }),
            None,
        );
        let hit = scene.intersect(&ray, f32::INFINITY).unwrap();
        assert_eq!(hit.prim >= 2, hole, "cutoff {cutoff}, alpha {alpha}");
    }
    // OPAQUE ignores alpha 0.
    let scene = alpha_scene(
        dir.path(),
        "opaque.gltf",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 0.0] } }),
        None,
    );
    assert!(scene.intersect(&ray, f32::INFINITY).unwrap().prim < 2);
}

#[test]
fn alpha_blend_passes_the_uncovered_fraction_of_rays() {
    let dir = tempfile::tempdir().unwrap();
    let scene = alpha_scene(
        dir.path(),
        "blend.gltf",
        json!({ "alphaMode": "BLEND", "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 0.3] } }),
        None,
    );
    // Jittered rays over the square (a fixed 64-bit LCG).
    let mut state = 0x853c_49e6_748f_ea9bu64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let n = 20_000;
    let (mut passed, mut shadow_passed) = (0, 0);
    for _ in 0..n {
        let origin = Vec3A::new(1.6 * next() - 0.8, 1.6 * next() - 0.8, 2.0);
        let dir = Vec3A::new(0.1 * next() - 0.05, 0.1 * next() - 0.05, -1.0).normalize();
        let ray = Ray::new(origin, dir);
        let hit = scene
            .intersect(&ray, f32::INFINITY)
            .expect("one of the squares");
        if hit.prim >= 2 {
            passed += 1;
        }
        // Shadow rays that stop between the squares.
        if !scene.occluded(&ray, 2.5 / -dir.z) {
            shadow_passed += 1;
        }
    }
    // 0.7 ± 5 standard deviations.
    let sigma = (0.7f64 * 0.3 / n as f64).sqrt();
    for (what, k) in [("camera rays", passed), ("shadow rays", shadow_passed)] {
        let f = k as f64 / n as f64;
        assert!((f - 0.7).abs() < 5.0 * sigma, "{what}: {f} pass, want 0.7");
    }
}

// ---------------------------------------------------------------------------
// 7. Punctual lights

fn lit_floor(g: &mut Gltf) {
    let m = g.material(json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [0.8, 0.6, 0.4, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0
    } }));
    add_floor(g, Some(m));
}

#[test]
fn a_point_light_gives_direct_the_inverse_square_irradiance() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    lit_floor(&mut g);
    let (intensity, color) = (5.0f32, Vec3A::new(1.0, 0.5, 0.25));
    let light_pos = Vec3A::new(0.5, 2.0, 0.3);
    // `range` is ignored: every hit point below is farther than 1 from the light.
    let l = g.light(json!({
        "type": "point", "intensity": intensity, "color": color.to_array(), "range": 1.0
    }));
    g.root(json!({ "translation": light_pos.to_array(), "extensions": { "KHR_lights_punctual": { "light": l } } }));
    let cam =
        g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }));
    let q = Quat::from_rotation_x(-0.7);
    g.root(json!({ "translation": [0.0, 3.0, 4.0], "rotation": q.to_array(), "camera": cam }));
    let path = g.write(dir.path(), "point-light.gltf");
    let rho = Vec3A::new(0.8, 0.6, 0.4);
    for ambient in [0.0f32, 0.25] {
        let options = LoadOptions {
            ambient: Some(ambient),
            ..LoadOptions::default()
        };
        let loaded = load_with(&path, &options).unwrap();
        assert!(!loaded.default_light);
        assert!(loaded.warnings.iter().any(|w| w.contains("range")));
        let scene = &loaded.scene;
        // The first point light is the key light, of power 4πI.
        assert_near(
            scene.light.power,
            4.0 * PI * intensity * color,
            1e-4,
            "power",
        );
        assert_near(scene.light.position, light_pos, 1e-6, "position");
        let view = loaded.view;
        let (w, h) = (32, 24);
        let camera = Camera::with_lens(view.position, view.rotation, view.lens, w, h);
        for (x, y) in [(16, 12), (3, 20), (29, 2), (20, 9)] {
            // The hit point, by intersecting the pixel-centre ray with y = 0.
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let p = ray.origin - ray.dir * (ray.origin.y / ray.dir.y);
            assert!(p.x.abs() < 10.0 && p.z.abs() < 10.0, "{p}");
            let to = light_pos - p;
            let r2 = to.length_squared();
            let cos = to.y / r2.sqrt();
            let want = rho * (intensity * color * cos / r2 + Vec3A::splat(ambient));
            let got = sample_pixel(scene, &camera, Integrator::Direct, x, y);
            assert_near(
                got,
                want,
                1e-4 * want.max_element(),
                &format!("pixel {x},{y}"),
            );
        }
    }
}

#[test]
fn spot_light_samples_follow_the_cone_falloff() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    lit_floor(&mut g);
    let (intensity, color) = (8.0f32, Vec3A::new(1.0, 1.0, 0.5));
    let (inner, outer) = (0.3f32, 0.6f32);
    let l = g.light(json!({
        "type": "spot", "intensity": intensity, "color": color.to_array(),
        "spot": { "innerConeAngle": inner, "outerConeAngle": outer }
    }));
    // Local −z turned to point straight down.
    let q = Quat::from_rotation_x(-FRAC_PI_2);
    let light_pos = Vec3A::new(0.0, 2.0, 0.0);
    g.root(json!({
        "translation": light_pos.to_array(), "rotation": q.to_array(),
        "extensions": { "KHR_lights_punctual": { "light": l } }
    }));
    let loaded = load(&g.write(dir.path(), "spot.gltf"));
    let scene = &loaded.scene;
    assert!(!loaded.default_light);
    assert_eq!(scene.point_power(), 0.0, "a spot is not the key light");
    assert_eq!(scene.lights().len(), 1);
    let t = |theta: f32| (theta.cos() - outer.cos()) / (inner.cos() - outer.cos());
    for (theta, factor) in [
        (0.0f32, 1.0f32),
        (0.2, 1.0),
        (0.35, t(0.35).powi(2)),
        (0.45, t(0.45).powi(2)),
        (0.55, t(0.55).powi(2)),
        (0.65, 0.0),
        (1.2, 0.0),
    ] {
        // A floor point at angle θ from the axis, at azimuth 1 rad.
        let rho = 2.0 * theta.tan();
        let p = Vec3A::new(rho * 1f32.cos(), 0.0, rho * 1f32.sin());
        let sample = scene.sample_light(p, Facing::Any, Vec2::new(0.5, 0.5), Vec2::new(0.25, 0.75));
        let incident = scene.lights()[0].incident(p);
        if factor == 0.0 {
            assert_eq!(sample, None, "θ = {theta}");
            assert_eq!(incident, None, "θ = {theta}");
            continue;
        }
        let Some(LightSample::Point {
            position,
            intensity: i,
        }) = sample
        else {
            panic!("θ = {theta}: {sample:?}");
        };
        assert_near(position, light_pos, 1e-6, "spot position");
        let want = intensity * color * factor;
        assert_near(i, want, 1e-4 * want.max_element(), &format!("θ = {theta}"));
        let Some(Incident::FromPoint { intensity: i2, .. }) = incident else {
            panic!("θ = {theta}: {incident:?}");
        };
        assert_near(i2, want, 1e-4 * want.max_element(), "incident");
    }
}

#[test]
fn directional_light_samples_carry_the_irradiance() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    lit_floor(&mut g);
    let (e, color) = (2.5f32, Vec3A::new(1.0, 0.8, 0.6));
    let l = g.light(json!({ "type": "directional", "intensity": e, "color": color.to_array() }));
    let travel = Vec3::new(0.3, -1.0, 0.2).normalize();
    let q = Quat::from_rotation_arc(Vec3::NEG_Z, travel);
    g.root(json!({
        "translation": [100.0, 100.0, 100.0], "rotation": q.to_array(),
        "extensions": { "KHR_lights_punctual": { "light": l } }
    }));
    let loaded = load(&g.write(dir.path(), "sun.gltf"));
    let scene = &loaded.scene;
    let (lo, hi) = scene.bounds();
    for p in [
        Vec3A::ZERO,
        Vec3A::new(9.0, 0.0, -9.0),
        Vec3A::new(-9.9, 0.0, 9.9),
    ] {
        let sample = scene.sample_light(p, Facing::Any, Vec2::new(0.3, 0.5), Vec2::new(0.5, 0.5));
        let Some(LightSample::Directional {
            to_light,
            irradiance,
            distance,
        }) = sample
        else {
            panic!("{sample:?}");
        };
        assert_near(to_light, (-travel).into(), 1e-5, "to_light");
        assert_near(irradiance, e * color, 1e-5, "irradiance");
        // A shadow ray of that length leaves the scene's bounds.
        let end = p + to_light * distance;
        assert!(
            end.cmplt(lo).any() || end.cmpgt(hi).any(),
            "{end} inside the bounds"
        );
    }
}

#[test]
fn light_samples_are_unbiased_over_the_light_choice() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    lit_floor(&mut g);
    let point = g.light(json!({ "type": "point", "intensity": 5.0, "color": [1.0, 0.5, 0.25] }));
    let point2 = g.light(json!({ "type": "point", "intensity": 1.5 }));
    let spot = g.light(json!({
        "type": "spot", "intensity": 8.0, "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.6 }
    }));
    let sun = g.light(json!({ "type": "directional", "intensity": 2.5, "color": [1.0, 0.8, 0.6] }));
    let ext = |l: usize| json!({ "KHR_lights_punctual": { "light": l } });
    let down = Quat::from_rotation_x(-FRAC_PI_2);
    let travel = Vec3::new(0.3, -1.0, 0.2).normalize();
    let sun_q = Quat::from_rotation_arc(Vec3::NEG_Z, travel);
    g.root(json!({ "translation": [0.5, 2.0, 0.3], "extensions": ext(point) }));
    g.root(json!({ "translation": [-1.0, 1.0, 0.0], "extensions": ext(point2) }));
    g.root(json!({ "translation": [0.0, 2.0, 0.0], "rotation": down.to_array(), "extensions": ext(spot) }));
    g.root(json!({ "rotation": sun_q.to_array(), "extensions": ext(sun) }));
    let loaded = load(&g.write(dir.path(), "lights.gltf"));
    let scene = &loaded.scene;
    assert_eq!(
        scene.lights().len(),
        3,
        "point2, spot and sun beside the key light"
    );
    let p = Vec3A::new(0.2, 0.0, -0.1);
    let n = Vec3A::Y;
    // Irradiance on the floor at p from each light, by the formulas.
    let from_point = |pos: Vec3A, i: Vec3A| {
        let to = pos - p;
        i * (to.dot(n).max(0.0) / to.length()) / to.length_squared()
    };
    let spot_pos = Vec3A::new(0.0, 2.0, 0.0);
    let cos = (p - spot_pos).normalize().dot(Vec3A::NEG_Y);
    let t = ((cos - 0.6f32.cos()) / (0.3f32.cos() - 0.6f32.cos())).clamp(0.0, 1.0);
    let want = from_point(Vec3A::new(0.5, 2.0, 0.3), Vec3A::new(5.0, 2.5, 1.25))
        + from_point(Vec3A::new(-1.0, 1.0, 0.0), Vec3A::splat(1.5))
        + from_point(spot_pos, Vec3A::splat(8.0 * t * t))
        + Vec3A::new(2.5, 2.0, 1.5) * (-Vec3A::from(travel)).dot(n);
    // The mean over a fine grid of light choices: each light's share of the
    // grid is its selection probability, which its sample divides out.
    // The points are 3D (the second number settles the alias table's coin,
    // and a light with a small share needs it finely resolved; the third
    // picks among the punctual lights by what they send to `p`): Roberts' R3
    // sequence, whose error falls almost as 1/k. With the floor's normal
    // (the weighing by cosine) and without.
    for facing in [Facing::Side(n), Facing::Any] {
        let k = 4_000_000;
        let mut sum = glam::DVec3::ZERO;
        for j in 0..k {
            let r3 = |a: f64| ((0.5 + j as f64 * a).fract()) as f32;
            let u = Vec2::new(r3(0.819_172_513_396_164_4), r3(0.671_043_606_703_789_2));
            let e =
                match scene.sample_light(p, facing, u, Vec2::new(r3(0.549_700_477_901_970_4), 0.5))
                {
                    None => Vec3A::ZERO,
                    Some(LightSample::Point {
                        position,
                        intensity,
                    }) => from_point(position, intensity),
                    Some(LightSample::Directional {
                        to_light,
                        irradiance,
                        ..
                    }) => irradiance * to_light.dot(n).max(0.0),
                    Some(other) => panic!("{other:?}"),
                };
            sum += e.as_dvec3();
        }
        let mean = (sum / k as f64).as_vec3a();
        assert_near(
            mean,
            want,
            1e-3 * want.max_element(),
            &format!("mean light sample, {facing:?}"),
        );
    }
}

// ---------------------------------------------------------------------------
// 8. Emission

/// A 2 × 2 emitting square, rotated to face down (−y) at y = 2 (its
/// counter-clockwise side), optionally mirrored by scale z −1 (so facing up).
/// The file has no punctual light.
fn emitter(dir: &Path, name: &str, double_sided: bool, mirror: bool) -> Loaded {
    let mut g = Gltf::new();
    let m = g.material(json!({
        "emissiveFactor": [1.0, 0.5, 0.25],
        "doubleSided": double_sided,
        "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0] },
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } }
    }));
    g.extensions_used
        .push("KHR_materials_emissive_strength".into());
    let mut p = quad(&mut g, XY_SQUARE, &[]);
    p["material"] = json!(m);
    let mesh = g.mesh(vec![p]);
    let q = Quat::from_rotation_x(FRAC_PI_2);
    let scale = if mirror { [1.0, 1.0, -1.0] } else { [1.0; 3] };
    g.root(json!({
        "translation": [0.0, 2.0, 0.0], "rotation": q.to_array(), "scale": scale, "mesh": mesh
    }));
    load(&g.write(dir, name))
}

#[test]
fn emitters_light_their_front_face_or_both() {
    let dir = tempfile::tempdir().unwrap();
    let le = Vec3A::new(4.0, 2.0, 1.0);
    let seen_only_emission = Integrator::Path(PathOptions {
        max_depth: 1,
        ..PathOptions::default()
    });
    for (double_sided, mirror) in [(false, false), (true, false), (false, true)] {
        let what = format!("double-sided {double_sided}, mirrored {mirror}");
        let loaded = emitter(
            dir.path(),
            &format!("emitter-{double_sided}-{mirror}.gltf"),
            double_sided,
            mirror,
        );
        // The emitter is the scene's light: no default key light beside it.
        assert!(!loaded.default_light, "{what}");
        assert_eq!(loaded.scene.point_power(), 0.0, "{what}");
        let scene = &loaded.scene;
        let front = if mirror { Vec3A::Y } else { Vec3A::NEG_Y };
        assert_eq!(scene.emitter_count(), 2);
        for prim in 0..2 {
            assert_near(scene.emission(prim), le, 1e-6, &what);
            assert_near(scene.normal(prim), front, 1e-6, &what);
        }
        // A light sample seen from the square's front (below it, or above
        // the mirrored one).
        let p = if mirror {
            Vec3A::new(0.1, 4.0, 0.2)
        } else {
            Vec3A::new(0.1, 0.0, 0.2)
        };
        let sample = scene.sample_light(p, Facing::Any, Vec2::new(0.3, 0.5), Vec2::new(0.4, 0.7));
        let Some(LightSample::Area {
            position,
            normal,
            radiance,
            two_sided,
            pdf_area,
        }) = sample
        else {
            panic!("{what}: {sample:?}");
        };
        assert!((position.y - 2.0).abs() < 1e-5 && position.x.abs() <= 1.0);
        assert!(position.z.abs() <= 1.0);
        assert_near(normal, front, 1e-6, &what);
        assert_near(radiance, le, 1e-6, &what);
        assert_eq!(two_sided, double_sided, "{what}");
        // One light (two triangles of equal area and distance, each chosen
        // half the time): the density is 1 over the square's area.
        assert!((pdf_area - 0.25).abs() < 1e-6, "{what}: pdf {pdf_area}");
        // Rays from below (up) and above (down) through the square.
        let mut rays = 0;
        let up = Ray::new(Vec3A::new(0.3, 0.0, -0.2), Vec3A::Y);
        let down = Ray::new(Vec3A::new(0.3, 4.0, -0.2), Vec3A::NEG_Y);
        let from_below = seen_only_emission.radiance(scene, &up, &mut rays);
        let from_above = seen_only_emission.radiance(scene, &down, &mut rays);
        // Whatever the emission does, both faces are hit (no back-face culling).
        assert!(scene.intersect(&up, 10.0).is_some() && scene.intersect(&down, 10.0).is_some());
        let (want_below, want_above) = match (double_sided, mirror) {
            (true, _) => (le, le),
            (false, false) => (le, Vec3A::ZERO),
            (false, true) => (Vec3A::ZERO, le),
        };
        assert_near(from_below, want_below, 1e-6, &format!("{what}, from below"));
        assert_near(from_above, want_above, 1e-6, &format!("{what}, from above"));
    }
}

// ---------------------------------------------------------------------------
// 9. Bad files

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

/// `KHR_materials_clearcoat`: the coat's normal is the interpolated normal
/// without the base's normal map (square 0), or the coat's own normal map
/// when it has one (square 1: the same map, so the same normal as the
/// base's); the factors are read; a material without the extension has no
/// coat; a factor that is not finite is refused naming the material.
#[test]
fn a_clear_coat_takes_its_own_normal_and_its_factors() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let tangent = Some(Vec4::new(1.0, 0.0, 0.0, 1.0));
    let node = |x: f32| json!({ "translation": [x, 0.0, 0.0] });
    normal_mapped_square(&mut g, |c| c, tangent, true, 1.0, node(0.0));
    normal_mapped_square(&mut g, |c| c, tangent, true, 1.0, node(3.0));
    let coat = |normal: bool| {
        let mut c = json!({ "clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.25 });
        if normal {
            c["clearcoatNormalTexture"] = json!({ "index": 0 });
        }
        c
    };
    g.materials[0]["extensions"] = json!({ "KHR_materials_clearcoat": coat(false) });
    let mut with_map = g.materials[0].clone();
    with_map["extensions"] = json!({ "KHR_materials_clearcoat": coat(true) });
    g.materials.push(with_map);
    g.meshes[1]["primitives"][0]["material"] = json!(1);
    g.extensions_used.push("KHR_materials_clearcoat".into());
    let loaded = load(&g.write(dir.path(), "clearcoat.gltf"));
    let scene = &loaded.scene;
    let surface = |i: u32| {
        let prim = 2 * i;
        let t = scene.triangles()[prim as usize];
        let centre = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        let hit = scene
            .intersect(&Ray::new(centre + Vec3A::Z, -Vec3A::Z), 2.0)
            .expect("the ray hits the square");
        scene.surface(&hit)
    };
    let (plain, mapped) = (surface(0), surface(1));
    assert_near(plain.nc, Vec3A::Z, 1e-6, "coat without a normal map");
    assert!(plain.ns.dot(Vec3A::Z) < 0.95, "the base's map tilts ns");
    assert_near(mapped.nc, mapped.ns, 1e-6, "the coat's map");
    for (i, m) in scene.materials().iter().enumerate() {
        let MaterialKind::Gltf(g) = &m.kind else {
            panic!("material {i} is not glTF's");
        };
        assert_eq!((g.clearcoat, g.clearcoat_roughness), (0.8, 0.25));
        assert_eq!(g.clearcoat_normal_texture.is_some(), i == 1);
        assert!(m.has_coat());
    }
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("clearcoat")),
        "{:?}",
        loaded.warnings
    );
    // Emission under the coat is dimmed by 1 − w F_c(|dir·n_c|) (square 0's
    // coat normal is +z): head-on, and at 60°.
    let fresnel = |cos: f32| 0.04 + 0.96 * (1.0 - cos).powi(5);
    for (dir, cos) in [
        (Vec3A::Z, 1.0f32),
        (Vec3A::new(0.75f32.sqrt(), 0.0, 0.5), 0.5),
    ] {
        let dim = scene.coat_dimming(0, 0.3, 0.3, dir * 2.0);
        assert!((dim - (1.0 - 0.8 * fresnel(cos))).abs() < 1e-6, "{dim}");
    }
    // Not finite (as f32): refused with the material named.
    g.materials[0]["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"] = json!(1e39);
    let err = load_err(&g.write(dir.path(), "clearcoat-inf.gltf"));
    assert!(
        err.contains("material 0") && err.contains("clearcoatFactor"),
        "{err}"
    );
}

/// `EXT_texture_webp`: a texture's WebP image (its extension's `source`) is
/// used in place of its core PNG fallback.
#[test]
fn a_webp_texture_replaces_its_png_fallback() {
    use image::ImageEncoder;
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let (fallback, webp_texel) = ([255u8, 0, 0], [0u8, 200, 40]);
    let texture = g.png_texture(&png(1, 1, 3, &fallback), None);
    let mut webp = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut webp)
        .write_image(&webp_texel, 1, 1, image::ExtendedColorType::Rgb8)
        .unwrap();
    g.images
        .push(json!({ "uri": format!("data:image/webp;base64,{}", builder::base64(&webp)) }));
    g.textures[texture]["extensions"] =
        json!({ "EXT_texture_webp": { "source": g.images.len() - 1 } });
    g.extensions_used.push("EXT_texture_webp".into());
    g.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": texture } }
    }));
    let uv = g.floats(&[[0.5f32, 0.5]; 4]);
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut p = quad(&mut g, corners, &[("TEXCOORD_0", uv)]);
    p["material"] = json!(0);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    let loaded = load(&g.write(dir.path(), "webp.gltf"));
    let hit = loaded
        .scene
        .intersect(&Ray::new(Vec3A::new(0.3, 0.3, 1.0), -Vec3A::Z), 2.0)
        .expect("the ray hits the square");
    // sRGB 200 and 40, linear.
    let srgb = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let want = Vec3A::new(0.0, srgb(webp_texel[1]), srgb(webp_texel[2]));
    assert_near(loaded.scene.base_color(&hit), want, 1e-4, "the WebP texel");
    // A file that requires the extension may leave the core `source` out.
    g.textures[texture]
        .as_object_mut()
        .unwrap()
        .remove("source");
    g.extensions_required.push("EXT_texture_webp".into());
    let loaded = load(&g.write(dir.path(), "webp-only.gltf"));
    let hit = loaded
        .scene
        .intersect(&Ray::new(Vec3A::new(0.3, 0.3, 1.0), -Vec3A::Z), 2.0)
        .expect("the ray hits the square");
    assert_near(loaded.scene.base_color(&hit), want, 1e-4, "WebP only");
}

/// `KHR_materials_iridescence`: the factors and textures are read (the
/// weight from the texture's red channel, the thickness mixed between the
/// minimum and the maximum by its green channel), the schema's defaults
/// apply, the extension is not reported as ignored, and a value that is not
/// finite is refused naming the material.
#[test]
fn iridescence_reads_its_factors_and_textures() {
    let dir = tempfile::tempdir().unwrap();
    // One texel: red 204 (0.8), green 51 (0.2), linear.
    let texel = png(1, 1, 4, &[204, 51, 0, 255]);
    let film = json!({
        "iridescenceFactor": 0.5,
        "iridescenceTexture": { "index": 0 },
        "iridescenceIor": 1.8,
        "iridescenceThicknessMinimum": 200.0,
        "iridescenceThicknessMaximum": 700.0,
        "iridescenceThicknessTexture": { "index": 0 }
    });
    let material = json!({
        "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.5 },
        "extensions": { "KHR_materials_iridescence": film }
    });
    let scene = alpha_scene(dir.path(), "film.gltf", material, Some(&texel));
    let hit = scene
        .intersect(&Ray::new(Vec3A::new(0.1, 0.2, 2.0), -Vec3A::Z), 3.0)
        .expect("the ray hits the square");
    let m = scene.material(hit.prim);
    let MaterialKind::Gltf(g) = &m.kind else {
        panic!("not a glTF material");
    };
    assert_eq!(
        (g.iridescence, g.iridescence_ior),
        (0.5, 1.8),
        "the factors"
    );
    assert_eq!(
        (g.iridescence_thickness_min, g.iridescence_thickness_max),
        (200.0, 700.0)
    );
    assert!(g.iridescence_texture.is_some() && g.iridescence_thickness_texture.is_some());
    let s = scene.surface(&hit);
    let raylab::materials::Material::Pbr(p) = m.bsdf(&s.attrs, scene.textures()) else {
        panic!("not the glTF BSDF");
    };
    assert!((p.iridescence - 0.5 * 0.8).abs() < 1e-6, "{p:?}");
    assert!(
        (p.film_thickness - (200.0 + 500.0 * 0.2)).abs() < 1e-3,
        "{p:?}"
    );
    assert_eq!(p.film_ior, 1.8);
    // The defaults: index 1.3, 100–400 nm, the maximum without a texture.
    let dir2 = tempfile::tempdir().unwrap();
    let material = json!({
        "extensions": { "KHR_materials_iridescence": { "iridescenceFactor": 1.0 } }
    });
    let scene = alpha_scene(dir2.path(), "film-defaults.gltf", material, None);
    let hit = scene
        .intersect(&Ray::new(Vec3A::new(0.1, 0.2, 2.0), -Vec3A::Z), 3.0)
        .unwrap();
    let m = scene.material(hit.prim);
    let raylab::materials::Material::Pbr(p) = m.bsdf(&scene.surface(&hit).attrs, scene.textures())
    else {
        panic!("not the glTF BSDF");
    };
    assert_eq!(
        (p.iridescence, p.film_ior, p.film_thickness),
        (1.0, 1.3, 400.0)
    );
    // Not finite (as f32): refused with the material and the value named;
    // the extension is known (no warning).
    let mut g = Gltf::new();
    let mat = g.material(json!({
        "extensions": { "KHR_materials_iridescence": { "iridescenceThicknessMaximum": 1e39 } }
    }));
    let mut p = quad(&mut g, XY_SQUARE, &[]);
    p["material"] = json!(mat);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    g.extensions_used.push("KHR_materials_iridescence".into());
    let err = load_err(&g.write(dir.path(), "film-inf.gltf"));
    assert!(
        err.contains("material 0") && err.contains("iridescenceThicknessMaximum"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    g.materials[0]["extensions"]["KHR_materials_iridescence"] = json!({ "iridescenceFactor": 0.7 });
    let loaded = load(&g.write(dir.path(), "film-ok.gltf"));
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("iridescence")),
        "{:?}",
        loaded.warnings
    );
}
