//! glTF 2.0 materials as the loader reads them: normal mapping with and
//! without the TANGENT attribute, alpha MASK holes for camera and shadow rays
//! and BLEND coverage, `KHR_materials_clearcoat`'s normal and factors,
//! `EXT_texture_webp` in place of its PNG fallback, and
//! `KHR_materials_iridescence`'s factors and textures. Every file is written
//! by the test itself (see `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::path::Path;

use builder::{Gltf, XY_SQUARE, assert_near, load, load_err, png, quad};
use glam::{Mat3, Quat, Vec2, Vec3, Vec3A, Vec4};
use raylab::materials::surface::MaterialKind;
use raylab::{Integrator, Ray, Scene};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// Normal mapping

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
// Alpha

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
// Material extensions

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
