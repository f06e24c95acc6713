//! The glTF 2.0 loader's geometry, against numbers worked out by hand from the
//! glTF specification and `docs/scene-conventions.md`: node
//! transforms and winding, primitive modes and index types, and sparse,
//! normalized and interleaved accessors. Every file is written by the test
//! itself (see `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::f32::consts::FRAC_PI_2;

use builder::{F32, Gltf, I8, I16, U8, U16, U32, assert_near, bytes_f32, load};
use glam::{Mat3, Quat, Vec2, Vec3, Vec3A, Vec4};
use raylab::Hit;
use serde_json::json;

// ---------------------------------------------------------------------------
// Helpers

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

// ---------------------------------------------------------------------------
// Node transforms

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
// Primitive modes and index types

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
// Sparse, normalized and interleaved accessors

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
