//! glTF extensions beyond the first wave of materials, against numbers worked
//! out from their Khronos specifications: `KHR_materials_unlit` (the base
//! colour, whatever the integrator, and no light of its own),
//! `KHR_materials_pbrSpecularGlossiness` (the extension's BRDF inputs, and the
//! BRDF they make), `KHR_materials_variants` (`--variant`, in scene files too)
//! `EXT_mesh_gpu_instancing` (instances at their transforms, counts
//! checked), `KHR_materials_sheen` (factors, textures, layering) and
//! `KHR_node_visibility` (hidden subtrees). Every file is written by the test itself (see
//! `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

use builder::{Gltf, I16, assert_near, base64, load, load_with, png, quad, write_json};
use glam::{Quat, Vec3, Vec3A, Vec4};
use raylab::Camera;
use raylab::load::{DefaultLight, LoadOptions, Loaded};
use raylab::materials::Material;
use raylab::materials::surface::HitAttributes;
use raylab::render::{RenderSettings, probe_sample, render};
use raylab::textures::srgb_to_linear;
use raylab::{Integrator, Ray};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// Helpers

fn with_variant(variant: &str) -> LoadOptions {
    LoadOptions {
        variant: Some(variant.into()),
        ..LoadOptions::default()
    }
}

/// The square of side 2s centred on `c` in a z = c.z plane, front +z.
fn square(c: [f32; 3], s: f32) -> [[f32; 3]; 4] {
    [
        [c[0] - s, c[1] - s, c[2]],
        [c[0] + s, c[1] - s, c[2]],
        [c[0] + s, c[1] + s, c[2]],
        [c[0] - s, c[1] + s, c[2]],
    ]
}

/// One root node per material of `materials`, the k-th a square of side 2
/// centred on x = 3k in the z = 0 plane, front +z, with `attributes`.
fn squares_in_a_row(g: &mut Gltf, materials: &[usize], attributes: &[(&str, usize)]) {
    for (k, &m) in materials.iter().enumerate() {
        let mut p = quad(g, square([3.0 * k as f32, 0.0, 0.0], 1.0), attributes);
        p["material"] = json!(m);
        let mesh = g.mesh(vec![p]);
        g.root(json!({ "mesh": mesh }));
    }
}

/// Writes the file with `edit` applied to its JSON (the buffer as a data URI).
fn write_edited(g: &Gltf, dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let uri = format!("data:application/octet-stream;base64,{}", base64(&g.buffer));
    let mut root = g.to_json(Some(uri));
    edit(&mut root);
    write_json(dir, name, &root)
}

/// A ray from `z = 3` straight down −z through `(x, y)`.
fn down_z(x: f32, y: f32) -> Ray {
    Ray::new(Vec3A::new(x, y, 3.0), Vec3A::NEG_Z)
}

// ---------------------------------------------------------------------------
// 1. KHR_materials_unlit

/// An unlit square (factor × texture × COLOR_0, an emissive factor the
/// extension ignores) at z = 0 in front of a point light and a camera at
/// z = 2 looking down −z.
fn unlit_file(dir: &Path) -> (PathBuf, Vec3A) {
    let mut g = Gltf::new();
    // One texel, sRGB (128, 255, 64).
    g.png_texture(&png(1, 1, 3, &[128, 255, 64]), None);
    let factor = [0.5, 0.8, 0.9, 1.0];
    let m = g.material(json!({
        "pbrMetallicRoughness": {
            "baseColorFactor": factor, "baseColorTexture": { "index": 0 },
            "metallicFactor": 0.0, "roughnessFactor": 0.9
        },
        "emissiveFactor": [5.0, 5.0, 5.0],
        "extensions": { "KHR_materials_unlit": {} }
    }));
    let corners = square([0.0, 0.0, 0.0], 10.0);
    let uv = g.floats(&[[0.25, 0.25]; 4]);
    let colour = [0.5, 1.0, 0.75, 1.0];
    let colours = g.floats(&[colour; 4]);
    let mut p = quad(&mut g, corners, &[("TEXCOORD_0", uv), ("COLOR_0", colours)]);
    p["material"] = json!(m);
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    let cam =
        g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }));
    g.root(json!({ "camera": cam, "translation": [0.0, 0.0, 2.0] }));
    g.light(json!({ "type": "point", "intensity": 50.0 }));
    g.root(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } }, "translation": [0.0, 0.0, 1.0] }));
    g.extensions_used = vec!["KHR_materials_unlit".into(), "KHR_lights_punctual".into()];
    g.extensions_required = vec!["KHR_materials_unlit".into()];
    let tex = Vec3A::new(
        srgb_to_linear(128.0 / 255.0),
        1.0,
        srgb_to_linear(64.0 / 255.0),
    );
    let want = Vec3A::new(factor[0], factor[1], factor[2])
        * tex
        * Vec3A::new(colour[0], colour[1], colour[2]);
    (g.write(dir, "unlit.gltf"), want)
}

#[test]
fn an_unlit_square_shows_its_base_colour_in_every_integrator() {
    let dir = tempfile::tempdir().unwrap();
    let (file, want) = unlit_file(dir.path());
    let loaded = load(&file);
    let scene = &loaded.scene;
    // The emissive factor is ignored: no emitter, nothing for light sampling.
    assert_eq!(scene.emitter_count(), 0);
    let mut rays = 0;
    for (x, y) in [(0.0, 0.0), (0.3, -0.2), (-1.5, 2.0)] {
        let ray = down_z(x, y);
        let flat = Integrator::Flat.radiance(scene, &ray, &mut rays);
        assert_near(flat, want, 1e-6, "flat");
        // `direct` gives π × the colour, which its glTF display divides by π.
        let direct = Integrator::Direct.radiance(scene, &ray, &mut rays);
        assert_near(direct, want * PI, 1e-5, "direct");
        // `path`: the colour itself, however bright the light beside it.
        let path = Integrator::path().radiance(scene, &ray, &mut rays);
        assert_eq!(path, flat, "path at ({x}, {y})");
    }
    // A whole render through the file's camera (the lab's integrators on
    // pixel quads and blocks): every pixel the colour (π × it for `direct`),
    // at any sample count (each sample is exactly it).
    let view = loaded.view;
    let camera = Camera::with_lens(view.position, view.rotation, view.lens, 12, 8);
    for (integrator, spp, want) in [
        (Integrator::path(), 1, want),
        (Integrator::path(), 4, want),
        (Integrator::Flat, 1, want),
        (Integrator::Direct, 2, want * PI),
    ] {
        let settings = RenderSettings {
            integrator,
            spp,
            seed: 3,
        };
        let image = render(scene, &camera, &settings, &|_| {});
        for (i, p) in image.film.pixels.iter().enumerate() {
            // (Interpolating the vertices' equal colours and coordinates
            // gives them back to within a rounding.)
            assert_near(
                *p,
                want,
                4e-6,
                &format!("{integrator} pixel {i} at {spp} spp"),
            );
        }
    }
}

#[test]
fn an_unlit_room_lights_a_lambertian_plate_by_its_colour_once() {
    // A closed cube of unlit walls of colour c around a Lambertian plate of
    // albedo ρ (KHR_materials_specular's factor 0 leaves Appendix B's diffuse
    // lobe alone): the plate's radiance is ρ·c, all of it found by BSDF
    // sampling. Counting the walls twice (as lights and when hit) would give
    // 2ρ·c; ignoring them, 0.
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let c = [0.5, 0.25, 1.0];
    let rho = 0.6;
    let walls = g.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [c[0], c[1], c[2], 1.0] },
        "extensions": { "KHR_materials_unlit": {} }
    }));
    let plate = g.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [rho, rho, rho, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } }
    }));
    // The cube [−2, 2]³, six faces as quads (orientation does not matter:
    // unlit surfaces show from both sides).
    let s = 2.0;
    let faces: [[[f32; 3]; 4]; 6] = [
        [[-s, -s, -s], [s, -s, -s], [s, s, -s], [-s, s, -s]],
        [[-s, -s, s], [s, -s, s], [s, s, s], [-s, s, s]],
        [[-s, -s, -s], [-s, s, -s], [-s, s, s], [-s, -s, s]],
        [[s, -s, -s], [s, s, -s], [s, s, s], [s, -s, s]],
        [[-s, -s, -s], [s, -s, -s], [s, -s, s], [-s, -s, s]],
        [[-s, s, -s], [s, s, -s], [s, s, s], [-s, s, s]],
    ];
    let mut prims = Vec::new();
    for f in faces {
        let mut p = quad(&mut g, f, &[]);
        p["material"] = json!(walls);
        prims.push(p);
    }
    let mut p = quad(&mut g, square([0.0, 0.0, -1.0], 0.5), &[]);
    p["material"] = json!(plate);
    prims.push(p);
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    let cam =
        g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.3, "znear": 0.1 } }));
    g.root(json!({ "camera": cam, "translation": [0.0, 0.0, 1.0] }));
    let file = g.write(dir.path(), "unlit-room.gltf");
    let options = LoadOptions {
        default_light: DefaultLight::Off,
        ..LoadOptions::default()
    };
    let loaded = load_with(&file, &options).unwrap();
    let scene = &loaded.scene;
    assert_eq!(scene.emitter_count(), 0);
    let view = loaded.view;
    let camera = Camera::with_lens(view.position, view.rotation, view.lens, 9, 9);
    let n = 4000;
    let sum: Vec3A = (0..n)
        .map(|s| probe_sample(scene, &camera, Integrator::path(), 11, 4, 4, s, &mut ()))
        .sum();
    let mean = sum / n as f32;
    let want = Vec3A::from(c) * rho;
    assert_near(
        mean,
        want,
        0.02 * want.max_element(),
        "the plate's radiance",
    );
}

// ---------------------------------------------------------------------------
// 2. KHR_materials_pbrSpecularGlossiness

/// GGX `D` for `cos θh = nh` and width `a`.
fn ggx_d(nh: f32, a: f32) -> f32 {
    let a2 = a * a;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's height-correlated visibility `V = G2 / (4 |n·l| |n·v|)` (glTF
/// specification, Appendix B).
fn smith_v(nl: f32, nv: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl)
}

/// The extension's BRDF × cos θi from its inputs: `c_diff = diffuse ·
/// (1 − max(specular))`, `F0 = specular`, `α = (1 − glossiness)²`, on
/// Appendix B's lobes with Schlick's Fresnel, the diffuse lobe weighted by
/// `1 − max(F)` (as `KHR_materials_specular` has it, which raylab follows).
fn spec_gloss_brdf_cos(
    diffuse: Vec3A,
    specular: Vec3A,
    glossiness: f32,
    wo: Vec3A,
    wi: Vec3A,
) -> Vec3A {
    let c_diff = diffuse * (1.0 - specular.max_element());
    let a = (1.0 - glossiness) * (1.0 - glossiness);
    let h = (wo + wi).normalize();
    let f = specular + (Vec3A::ONE - specular) * (1.0 - wo.dot(h)).powi(5);
    let (nl, nv) = (wi.z, wo.z);
    let brdf = (1.0 - f.max_element()) * c_diff / PI + f * ggx_d(h.z, a) * smith_v(nl, nv, a);
    brdf * nl
}

#[test]
fn specular_glossiness_converts_to_the_extensions_brdf_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // The textures: diffuse sRGB (200, 100, 50) with alpha 255, specular
    // sRGB (150, 120, 90) with glossiness 128/255 (linear).
    g.png_texture(&png(1, 1, 4, &[200, 100, 50, 255]), None);
    g.png_texture(&png(1, 1, 4, &[150, 120, 90, 128]), None);
    let factors = g.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 1.0 },
        "extensions": { "KHR_materials_pbrSpecularGlossiness": {
            "diffuseFactor": [0.8, 0.6, 0.4, 1.0],
            "specularFactor": [0.2, 0.1, 0.05],
            "glossinessFactor": 0.7
        } }
    }));
    let textured = g.material(json!({
        "extensions": { "KHR_materials_pbrSpecularGlossiness": {
            "diffuseFactor": [0.5, 1.0, 1.0, 1.0],
            "diffuseTexture": { "index": 0 },
            "specularFactor": [1.0, 0.5, 1.0],
            "glossinessFactor": 0.9,
            "specularGlossinessTexture": { "index": 1 }
        } }
    }));
    let uv = g.floats(&[[0.5, 0.5]; 4]);
    squares_in_a_row(&mut g, &[factors, textured], &[("TEXCOORD_0", uv)]);
    g.extensions_used = vec!["KHR_materials_pbrSpecularGlossiness".into()];
    let loaded = load(&g.write(dir.path(), "spec-gloss.gltf"));
    let scene = &loaded.scene;
    let srgb = |b: u8| srgb_to_linear(b as f32 / 255.0);
    let cases = [
        (
            Vec3A::new(0.8, 0.6, 0.4),
            Vec3A::new(0.2, 0.1, 0.05),
            0.7f32,
        ),
        (
            Vec3A::new(0.5, 1.0, 1.0) * Vec3A::new(srgb(200), srgb(100), srgb(50)),
            Vec3A::new(1.0, 0.5, 1.0) * Vec3A::new(srgb(150), srgb(120), srgb(90)),
            0.9 * 128.0 / 255.0,
        ),
    ];
    for (k, (diffuse, specular, glossiness)) in cases.into_iter().enumerate() {
        let material = scene.material(2 * k as u32);
        let attrs = HitAttributes {
            uv: [glam::Vec2::splat(0.5); 2],
            color: Vec4::ONE,
        };
        let Material::Pbr(p) = material.bsdf(&attrs, scene.textures()) else {
            panic!("material {k} is not the glTF BSDF");
        };
        // The extension's inputs, by its formulas.
        let c_diff = diffuse * (1.0 - specular.max_element());
        assert_near(p.base_color, c_diff, 1e-6, "c_diff");
        assert_eq!(p.metallic, 0.0, "metallic");
        let roughness = 1.0 - glossiness;
        assert!(
            (p.alpha - roughness * roughness).abs() < 1e-6,
            "α {} vs (1 − glossiness)² {}",
            p.alpha,
            roughness * roughness
        );
        let f0 = ((p.ior - 1.0) / (p.ior + 1.0)).powi(2) * p.specular_color * p.specular;
        assert_near(f0, specular, 1e-6, "F0");
        // And the BRDF those inputs make, at three pairs of directions.
        for (wo, wi) in [
            (Vec3A::new(0.3, 0.1, 0.9), Vec3A::new(-0.2, 0.3, 0.8)),
            (Vec3A::new(0.0, 0.0, 1.0), Vec3A::new(0.6, 0.0, 0.5)),
            (Vec3A::new(0.8, -0.3, 0.3), Vec3A::new(-0.5, 0.4, 0.6)),
        ] {
            let (wo, wi) = (wo.normalize(), wi.normalize());
            let got = Material::Pbr(p).eval(wo, wi);
            let want = spec_gloss_brdf_cos(diffuse, specular, glossiness, wo, wi);
            assert_near(
                got,
                want,
                2e-5 * want.max_element().max(1.0),
                &format!("material {k}: f cos at {wo} {wi}"),
            );
        }
    }
}

#[test]
fn specular_glossiness_equals_its_metallic_roughness_twin() {
    // The extension's two examples of one material in both models: a metal
    // (diffuse black, specular = the metal's colour) and a plastic (diffuse
    // c / (1 − 0.04), specular 0.04). Their BSDFs must agree everywhere.
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let gold = [1.0, 0.766, 0.336];
    let plastic = [0.6, 0.2, 0.1];
    let materials = [
        json!({ "pbrMetallicRoughness": {
            "baseColorFactor": [gold[0], gold[1], gold[2], 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3 } }),
        json!({ "extensions": { "KHR_materials_pbrSpecularGlossiness": {
            "diffuseFactor": [0.0, 0.0, 0.0, 1.0], "specularFactor": gold, "glossinessFactor": 0.7 } } }),
        json!({ "pbrMetallicRoughness": {
            "baseColorFactor": [plastic[0], plastic[1], plastic[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5 } }),
        json!({ "extensions": { "KHR_materials_pbrSpecularGlossiness": {
            "diffuseFactor": [plastic[0] / 0.96, plastic[1] / 0.96, plastic[2] / 0.96, 1.0],
            "specularFactor": [0.04, 0.04, 0.04], "glossinessFactor": 0.5 } } }),
    ];
    let materials: Vec<usize> = materials.into_iter().map(|m| g.material(m)).collect();
    squares_in_a_row(&mut g, &materials, &[]);
    let loaded = load(&g.write(dir.path(), "twins.gltf"));
    let scene = &loaded.scene;
    let bsdf = |k: u32| {
        scene
            .material(2 * k)
            .bsdf(&HitAttributes::default(), scene.textures())
    };
    for (mr, sg, what) in [(0, 1, "gold"), (2, 3, "plastic")] {
        let (a, b) = (bsdf(mr), bsdf(sg));
        for (wo, wi) in [
            (Vec3A::new(0.3, 0.1, 0.9), Vec3A::new(-0.2, 0.3, 0.8)),
            (Vec3A::new(0.0, 0.0, 1.0), Vec3A::new(0.6, 0.0, 0.5)),
            (Vec3A::new(0.8, -0.3, 0.3), Vec3A::new(-0.5, 0.4, 0.6)),
            (Vec3A::new(0.9, 0.0, 0.1), Vec3A::new(-0.9, 0.0, 0.12)),
        ] {
            let (wo, wi) = (wo.normalize(), wi.normalize());
            let (fa, fb) = (a.eval(wo, wi), b.eval(wo, wi));
            assert_near(
                fb,
                fa,
                1e-5 * fa.max_element().max(1e-3),
                &format!("{what} at {wo} {wi}"),
            );
        }
    }
}

// ---------------------------------------------------------------------------
// 3. KHR_materials_variants

/// A square whose own material is red, with variants "blue" → material 1,
/// "green" and "sea" → material 2, and "plain" mapped to nothing.
fn variants_file(dir: &Path) -> PathBuf {
    let mut g = Gltf::new();
    for c in [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]] {
        g.material(
            json!({ "pbrMetallicRoughness": { "baseColorFactor": [c[0], c[1], c[2], 1.0] } }),
        );
    }
    let mut p = quad(&mut g, square([0.0, 0.0, 0.0], 1.0), &[]);
    p["material"] = json!(0);
    p["extensions"] = json!({ "KHR_materials_variants": { "mappings": [
        { "material": 1, "variants": [0] },
        { "material": 2, "variants": [1, 3] }
    ] } });
    let mesh = g.mesh(vec![p]);
    g.root(json!({ "mesh": mesh }));
    g.extensions_used = vec!["KHR_materials_variants".into()];
    write_edited(&g, dir, "variants.gltf", |root| {
        root["extensions"] = json!({ "KHR_materials_variants": { "variants": [
            { "name": "blue" }, { "name": "green" }, { "name": "plain" }, { "name": "sea" }
        ] } });
    })
}

fn flat_colour(loaded: &Loaded) -> Vec3A {
    let mut rays = 0;
    Integrator::Flat.radiance(&loaded.scene, &down_z(0.1, 0.2), &mut rays)
}

#[test]
fn variants_switch_a_primitives_material() {
    let dir = tempfile::tempdir().unwrap();
    let file = variants_file(dir.path());
    let default = load(&file);
    assert_eq!(
        flat_colour(&default),
        Vec3A::X,
        "the primitive's own material"
    );
    assert_eq!(
        default.summary.variants,
        ["blue", "green", "plain", "sea"].map(String::from)
    );
    assert_eq!(default.summary.variant, None);
    for (variant, colour) in [
        ("blue", Vec3A::Z),
        ("green", Vec3A::Y),
        ("sea", Vec3A::Y),
        ("plain", Vec3A::X),
    ] {
        let loaded = load_with(&file, &with_variant(variant)).unwrap();
        assert_eq!(flat_colour(&loaded), colour, "variant {variant}");
        assert_eq!(loaded.summary.variant.as_deref(), Some(variant));
        // Only the material shown is in the table.
        assert_eq!(loaded.scene.materials().len(), 1, "variant {variant}");
    }
    let err = load_with(&file, &with_variant("purple")).unwrap_err();
    assert!(
        err.contains("variants.gltf")
            && err.contains("'purple'")
            && err.contains("blue, green, plain, sea")
            && !err.contains('\n'),
        "{err}"
    );
}

#[test]
fn a_mapping_to_a_missing_variant_or_material_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = variants_file(dir.path());
    let mut root: Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    root["meshes"][0]["primitives"][0]["extensions"]["KHR_materials_variants"]["mappings"][0]["variants"] =
        json!([7]);
    let bad = write_json(dir.path(), "bad-variant.gltf", &root);
    let err = load_with(&bad, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("bad-variant.gltf") && err.contains("variant 7"),
        "{err}"
    );
    root["meshes"][0]["primitives"][0]["extensions"]["KHR_materials_variants"]["mappings"][0] =
        json!({ "material": 9, "variants": [0] });
    let bad = write_json(dir.path(), "bad-material.gltf", &root);
    assert!(
        load_with(&bad, &LoadOptions::default()).is_ok(),
        "not shown: not read"
    );
    let err = load_with(&bad, &with_variant("blue")).unwrap_err();
    assert!(err.contains("material 9 does not exist"), "{err}");
}

#[test]
fn scene_files_pick_a_variant_per_model_and_the_command_line_wins() {
    let dir = tempfile::tempdir().unwrap();
    variants_file(dir.path());
    let shot = |name: &str, variant: &str| {
        let path = dir.path().join(name);
        std::fs::write(
            &path,
            format!("[[model]]\nfile = \"variants.gltf\"\n{variant}\n"),
        )
        .unwrap();
        path
    };
    let green = shot("green.toml", "variant = \"green\"");
    assert_eq!(flat_colour(&load(&green)), Vec3A::Y);
    let loaded = load_with(&green, &with_variant("blue")).unwrap();
    assert_eq!(
        flat_colour(&loaded),
        Vec3A::Z,
        "--variant replaces the model's"
    );
    assert_eq!(loaded.summary.variants.len(), 4);
    let err = load_with(&green, &with_variant("purple")).unwrap_err();
    assert!(
        err.contains("green.toml") && err.contains("'purple'") && err.contains("blue, green"),
        "{err}"
    );
    let unknown = shot("unknown.toml", "variant = \"purple\"");
    let err = load_with(&unknown, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("variants.gltf") && err.contains("'purple'") && err.contains("blue, green"),
        "{err}"
    );
    let err = load_with(Path::new("cornell"), &with_variant("blue")).unwrap_err();
    assert!(err.contains("--variant"), "{err}");
}

#[test]
fn the_command_line_lists_the_variants_and_refuses_an_unknown_one_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let file = variants_file(dir.path());
    let raylab = env!("CARGO_BIN_EXE_raylab");
    let out = Command::new(raylab)
        .arg("render")
        .arg(&file)
        .args(["--variant", "green", "--width", "8", "--height", "6"])
        .args(["--spp", "1", "--integrator", "flat", "-o"])
        .arg(dir.path().join("green.exr"))
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("material variants: blue, green, plain, sea (showing green)"),
        "{text}"
    );
    let out = Command::new(raylab)
        .arg("render")
        .arg(&file)
        .args(["--variant", "purple", "-o"])
        .arg(dir.path().join("purple.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("variants.gltf")
            && err.contains("purple")
            && err.contains("blue, green, plain, sea"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------
// 4. EXT_mesh_gpu_instancing

/// `t + q·(s ∘ p)`: one instance's TRS applied to a point, written out.
fn trs(t: Vec3, q: Quat, s: Vec3, p: Vec3) -> Vec3 {
    t + q * (s * p)
}

/// A quaternion as KHR_mesh_quantization's normalized i16: round(q × 32767).
fn quantize(q: Quat) -> [i16; 4] {
    q.to_array().map(|c| (c * 32767.0).round() as i16)
}

#[test]
fn gpu_instancing_places_every_instance_of_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    let local = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let p = quad(&mut g, local, &[]);
    let mesh = g.mesh(vec![p]);
    let translations = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 5.0, -2.0]];
    let scales = [[1.0, 1.0, 1.0], [2.0, 3.0, 1.0], [1.0, 1.0, 1.0]];
    let quats = [
        Quat::IDENTITY,
        Quat::from_rotation_z(PI / 2.0),
        Quat::from_rotation_y(PI / 2.0),
    ];
    let t = g.floats(&translations);
    let s = g.floats(&scales);
    // Rotation as normalized i16 (KHR_mesh_quantization).
    let bytes: Vec<u8> = quats
        .iter()
        .flat_map(|q| quantize(*q))
        .flat_map(i16::to_le_bytes)
        .collect();
    let view = g.view(&bytes, None);
    let r = g.accessor(json!({
        "bufferView": view, "componentType": I16, "normalized": true, "count": 3, "type": "VEC4"
    }));
    let node_t = Vec3::new(0.0, 0.0, -3.0);
    g.root(json!({
        "mesh": mesh,
        "translation": node_t.to_array(),
        "extensions": { "EXT_mesh_gpu_instancing": { "attributes": {
            "TRANSLATION": t, "ROTATION": r, "SCALE": s
        } } }
    }));
    g.extensions_used = vec![
        "EXT_mesh_gpu_instancing".into(),
        "KHR_mesh_quantization".into(),
    ];
    g.extensions_required = vec!["EXT_mesh_gpu_instancing".into()];
    let file = g.write(dir.path(), "instancing.gltf");
    let loaded = load(&file);
    let scene = &loaded.scene;
    let tris = scene.triangles();
    assert_eq!(tris.len(), 3 * 2, "three instances of two triangles");
    // Each instance's triangles at node × instance TRS, in instance order.
    let index = [[0, 1, 2], [0, 2, 3]];
    for k in 0..3 {
        // The rotation as the file stores it (quantized), normalized.
        let q = Quat::from_array(quantize(quats[k]).map(|c| (c as f32 / 32767.0).max(-1.0)))
            .normalize();
        for (j, idx) in index.iter().enumerate() {
            let tri = &tris[2 * k + j];
            for (v, &i) in idx.iter().enumerate() {
                let want = node_t
                    + trs(
                        Vec3::from(translations[k]),
                        q,
                        Vec3::from(scales[k]),
                        Vec3::from(local[i]),
                    );
                assert_near(
                    tri.v[v],
                    Vec3A::from(want),
                    1e-4,
                    &format!("instance {k} triangle {j} vertex {v}"),
                );
            }
        }
    }
    // The bounds: instance 0 spans [0, 1]², instance 1 (turned a quarter about
    // z, scaled 2 × 3) x ∈ [7, 10], y ∈ [0, 2]; instance 2 (turned about y)
    // lies in the x = 0 plane, y ∈ [5, 6], z ∈ [−3, −2] before the node's −3.
    let (lo, hi) = scene.bounds();
    assert_near(lo, Vec3A::new(0.0, 0.0, -6.0), 1e-4, "lower bound");
    assert_near(hi, Vec3A::new(10.0, 6.0, -3.0), 1e-4, "upper bound");
    // A ray down −z hits the second instance at z = −3.
    let hit = scene
        .intersect(&down_z(8.5, 1.0), f32::INFINITY)
        .expect("a hit");
    assert!((hit.t - 6.0).abs() < 1e-4, "{hit:?}");
    assert!((2..4).contains(&hit.prim), "{hit:?}");
}

#[test]
fn gpu_instancing_counts_are_checked_before_the_instances_are_made() {
    let dir = tempfile::tempdir().unwrap();
    let base = |attributes: Value| {
        let mut g = Gltf::new();
        // 65535 zero positions: 21845 triangles with no bytes behind them.
        let pos = g.accessor(json!({ "componentType": 5126, "count": 65535, "type": "VEC3" }));
        let mesh = g.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
        let t = g.accessor(json!({ "componentType": 5126, "count": 65536, "type": "VEC3" }));
        let t3 = g.floats(&[[0.0, 0.0, 0.0]; 3]);
        let r3 = g.floats(&[[0.0, 0.0, 0.0]; 3]);
        let mut attributes = attributes;
        for (key, value) in [("T65536", t), ("T3", t3), ("R3", r3)] {
            for v in attributes.as_object_mut().unwrap().values_mut() {
                if v == key {
                    *v = json!(value);
                }
            }
        }
        g.root(json!({ "mesh": mesh, "extensions": { "EXT_mesh_gpu_instancing": { "attributes": attributes } } }));
        g
    };
    let cases = [
        (
            json!({ "TRANSLATION": "T65536" }),
            "more than 67108864 triangles",
        ),
        (
            json!({ "TRANSLATION": "T3", "SCALE": "T65536" }),
            "SCALE has 65536 elements but TRANSLATION has 3",
        ),
        (json!({ "ROTATION": "R3" }), "ROTATION accessor"),
        (json!({}), "none of TRANSLATION, ROTATION and SCALE"),
        (json!({ "TRANSLATION": 99 }), "accessor 99 does not exist"),
        (
            json!({ "TRANSLATION": "x" }),
            "TRANSLATION is not an accessor index",
        ),
    ];
    for (k, (attributes, words)) in cases.into_iter().enumerate() {
        let g = base(attributes);
        let name = format!("instancing-{k}.gltf");
        let file = g.write(dir.path(), &name);
        let err = load_with(&file, &LoadOptions::default()).unwrap_err();
        assert!(
            err.contains(&name) && err.contains("EXT_mesh_gpu_instancing") && err.contains(words),
            "case {k}: {err}"
        );
    }
}

/// `KHR_materials_sheen`: the factors times the textures (colour in sRGB
/// RGB, roughness in the alpha channel) reach the BSDF, clamped to
/// `[0, 1]`; a material without the extension has no sheen; a sheen makes
/// a black, non-specular square reflect (its colour × `E`); a factor that is
/// not finite is refused naming the material and the factor.
#[test]
fn a_sheen_takes_its_factors_and_textures() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // Colour sRGB (200, 100, 50), roughness alpha 128/255 (linear).
    let color = g.png_texture(&png(1, 1, 4, &[200, 100, 50, 255]), None);
    let rough = g.png_texture(&png(1, 1, 4, &[0, 0, 0, 128]), None);
    let black = json!({ "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 });
    let factors = g.material(json!({
        "pbrMetallicRoughness": black.clone(),
        "extensions": { "KHR_materials_sheen": {
            "sheenColorFactor": [0.9, 0.4, 2.0],
            "sheenRoughnessFactor": 0.7
        } }
    }));
    let textured = g.material(json!({
        "pbrMetallicRoughness": black.clone(),
        "extensions": { "KHR_materials_sheen": {
            "sheenColorFactor": [1.0, 0.5, 1.0],
            "sheenColorTexture": { "index": color },
            "sheenRoughnessFactor": 0.8,
            "sheenRoughnessTexture": { "index": rough }
        } }
    }));
    let plain = g.material(json!({ "pbrMetallicRoughness": black }));
    let uv = g.floats(&[[0.5, 0.5]; 4]);
    squares_in_a_row(&mut g, &[factors, textured, plain], &[("TEXCOORD_0", uv)]);
    g.extensions_used = vec!["KHR_materials_sheen".into()];
    let loaded = load(&g.write(dir.path(), "sheen.gltf"));
    let scene = &loaded.scene;
    let srgb = |b: u8| srgb_to_linear(b as f32 / 255.0);
    let cases = [
        (Vec3A::new(0.9, 0.4, 1.0), 0.7f32),
        (
            Vec3A::new(srgb(200), 0.5 * srgb(100), srgb(50)),
            0.8 * 128.0 / 255.0,
        ),
        (Vec3A::ZERO, 0.0),
    ];
    let attrs = HitAttributes {
        uv: [glam::Vec2::splat(0.5); 2],
        color: Vec4::ONE,
    };
    for (k, (color, roughness)) in cases.into_iter().enumerate() {
        let material = scene.material(2 * k as u32);
        let Material::Pbr(p) = material.bsdf(&attrs, scene.textures()) else {
            panic!("material {k} is not the glTF BSDF");
        };
        assert_near(p.sheen_color, color, 1e-6, "sheen colour");
        assert!((p.sheen_roughness - roughness).abs() < 1e-6, "{k}: {p:?}");
        // Head-on light, view at 60°: the black base reflects only its
        // specular part; the sheen adds C f_sheen, by channel.
        let wo = Vec3A::new(0.75f32.sqrt(), 0.0, 0.5);
        let f = Material::Pbr(p).eval(wo, Vec3A::Z);
        let no_sheen = raylab::materials::PbrBsdf {
            sheen_color: Vec3A::ZERO,
            ..p
        };
        let base = Material::Pbr(no_sheen).eval(wo, Vec3A::Z);
        let value = raylab::materials::sheen::eval(wo, Vec3A::Z, roughness);
        let scaling = (1.0
            - color.max_element() * raylab::materials::sheen::albedo(0.5, roughness))
        .min(1.0 - color.max_element() * raylab::materials::sheen::albedo(1.0, roughness));
        assert_near(f, base * scaling + color * value, 1e-6, "layering");
        if k < 2 {
            assert!(value > 0.0 && (f - base).max_element() > 0.0, "{k}: {f}");
        }
    }
    // Not finite (as f32): refused with the material named.
    g.materials[0]["extensions"]["KHR_materials_sheen"]["sheenRoughnessFactor"] = json!(1e39);
    let Err(err) = load_with(
        &g.write(dir.path(), "sheen-inf.gltf"),
        &LoadOptions::default(),
    ) else {
        panic!("an infinite sheenRoughnessFactor loaded");
    };
    assert!(
        err.contains("material 0") && err.contains("sheenRoughnessFactor"),
        "{err}"
    );
}

/// `KHR_node_visibility`: a hidden node hides its mesh, its light and every
/// descendant's, even one marked visible; its camera still sees; a node
/// without the extension, or `visible: true`, shows; a `visible` that is not
/// a boolean is refused naming the node.
#[test]
fn hidden_nodes_hide_their_meshes_and_lights_and_all_below() {
    let dir = tempfile::tempdir().unwrap();
    let visibility = |v: Value| json!({ "KHR_node_visibility": { "visible": v } });
    let mut g = Gltf::new();
    // Four squares at x = 0, 3, 6, 9 (two triangles each).
    let meshes: Vec<usize> = (0..4)
        .map(|k| {
            let p = quad(&mut g, square([3.0 * k as f32, 0.0, 0.0], 1.0), &[]);
            g.mesh(vec![p])
        })
        .collect();
    // Directional: a file's first point light would be the key light, not
    // one of `lights()`.
    let light = g.light(json!({ "type": "directional", "intensity": 5.0 }));
    let camera =
        g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }));
    // Hidden parent 0 (mesh 0, a light, a camera) above a child marked
    // visible (mesh 1) and its grandchild (mesh 2); node 3 visible: true.
    let grandchild = g.node(json!({ "mesh": meshes[2] }));
    let child = g.node(json!({ "mesh": meshes[1], "children": [grandchild], "extensions": visibility(json!(true)) }));
    g.root(json!({
        "mesh": meshes[0], "children": [child], "camera": camera, "translation": [0.0, 0.0, 10.0],
        "extensions": { "KHR_node_visibility": { "visible": false }, "KHR_lights_punctual": { "light": light } }
    }));
    g.root(json!({ "mesh": meshes[3], "extensions": visibility(json!(true)) }));
    g.extensions_used = vec!["KHR_node_visibility".into(), "KHR_lights_punctual".into()];
    g.extensions_required = vec!["KHR_node_visibility".into()];
    let hidden = load(&g.write(dir.path(), "hidden.gltf"));
    let tris = hidden.scene.triangles();
    assert_eq!(tris.len(), 2, "only the fourth square shows");
    assert!(tris.iter().all(|t| t.v[0].x > 7.0), "{tris:?}");
    assert_eq!(hidden.scene.lights().len(), 0, "the hidden node's light");
    assert_eq!(hidden.scene.cameras.len(), 1, "the hidden node's camera");
    // Shown: every square and the light.
    let shown_file = write_edited(&g, dir.path(), "shown.gltf", |root| {
        root["nodes"][2]["extensions"]["KHR_node_visibility"]["visible"] = json!(true);
    });
    let shown = load(&shown_file);
    assert_eq!(shown.scene.triangles().len(), 8);
    assert_eq!(shown.scene.lights().len(), 1);
    // Not a boolean: refused in one line naming the file and the node.
    let bad = write_edited(&g, dir.path(), "bad.gltf", |root| {
        root["nodes"][2]["extensions"]["KHR_node_visibility"]["visible"] = json!(0);
    });
    let err = load_with(&bad, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("bad.gltf") && err.contains("node 2") && err.contains("KHR_node_visibility"),
        "{err}"
    );
}
