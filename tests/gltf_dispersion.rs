//! `KHR_materials_dispersion` end to end: a glass slab in front of a white
//! emitter, rendered by `path` from files the test writes. Through parallel
//! faces every wavelength leaves as it came, so the dispersive slab must look
//! the same in the mean (the wavelength's weight is white in expectation)
//! while its single samples are coloured; a dispersion of 0, or one on a
//! thin wall, changes nothing bit for bit; and the dispersive image is the
//! same on any number of threads. (The angles a prism splits light by are
//! checked on the BSDF: `materials::pbr`'s
//! `a_prism_splits_white_light_by_snells_law_with_the_abbe_ior`.)

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;
mod common;

use std::path::{Path, PathBuf};

use builder::{Gltf, load_with, quad};
use glam::Vec3A;
use raylab::film::Film;
use raylab::load::{DefaultLight, LoadOptions, Loaded};
use raylab::materials::surface::MaterialKind;
use raylab::render::{RenderSettings, probe_sample, render};
use raylab::{Camera, Integrator};
use serde_json::{Value, json};

/// The box `[lo, hi]` as six outward quads with `material`.
fn box_prims(g: &mut Gltf, lo: [f32; 3], hi: [f32; 3], material: usize) -> Vec<Value> {
    let [x0, y0, z0] = lo;
    let [x1, y1, z1] = hi;
    let faces: [[[f32; 3]; 4]; 6] = [
        [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
        [[x1, y0, z0], [x0, y0, z0], [x0, y1, z0], [x1, y1, z0]],
        [[x1, y0, z1], [x1, y0, z0], [x1, y1, z0], [x1, y1, z1]],
        [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],
        [[x0, y1, z1], [x1, y1, z1], [x1, y1, z0], [x0, y1, z0]],
        [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
    ];
    faces
        .into_iter()
        .map(|f| {
            let mut p = quad(g, f, &[]);
            p["material"] = json!(material);
            p
        })
        .collect()
}

/// A clear glass slab (z in [−0.6, −0.4]) before a white emitter at z = −2,
/// seen from z = 1 down −z; `glass` is the slab's `extensions` object.
fn slab_file(dir: &Path, name: &str, glass: Value) -> PathBuf {
    let mut g = Gltf::new();
    let light = g.material(json!({
        "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0] }
    }));
    let slab = g.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.0 },
        "extensions": glass
    }));
    let mut prims = vec![{
        let mut p = quad(
            &mut g,
            [
                [-4.0, -4.0, -2.0],
                [4.0, -4.0, -2.0],
                [4.0, 4.0, -2.0],
                [-4.0, 4.0, -2.0],
            ],
            &[],
        );
        p["material"] = json!(light);
        p
    }];
    prims.extend(box_prims(
        &mut g,
        [-2.0, -2.0, -0.6],
        [2.0, 2.0, -0.4],
        slab,
    ));
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    let cam =
        g.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.3, "znear": 0.1 } }));
    g.root(json!({ "camera": cam, "translation": [0.0, 0.0, 1.0] }));
    for ext in [
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_materials_dispersion",
    ] {
        g.extensions_used.push(ext.into());
    }
    g.write(dir, name)
}

fn load_slab(dir: &Path, name: &str, glass: Value) -> Loaded {
    let options = LoadOptions {
        default_light: DefaultLight::Off,
        ..LoadOptions::default()
    };
    load_with(&slab_file(dir, name, glass), &options).unwrap()
}

fn camera(loaded: &Loaded, size: u32) -> Camera {
    let view = loaded.view;
    Camera::with_lens(view.position, view.rotation, view.lens, size, size)
}

fn render_on(loaded: &Loaded, size: u32, spp: u32, threads: usize) -> Film {
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp,
        seed: 5,
    };
    let cam = camera(loaded, size);
    let rendered = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render(&loaded.scene, &cam, &settings, &|_| {}));
    assert_eq!(rendered.dropped, 0);
    rendered.film
}

fn mean(film: &Film) -> Vec3A {
    let sum: glam::DVec3 = film.pixels.iter().map(|p| p.as_dvec3()).sum();
    (sum / film.pixels.len() as f64).as_vec3a()
}

/// The slab's `extensions`: transmission, a volume if `volume`, and
/// `KHR_materials_dispersion` with `dispersion` if given.
fn glass(dispersion: Option<Value>, volume: bool) -> Value {
    let mut e = json!({
        "KHR_materials_transmission": { "transmissionFactor": 1.0 },
    });
    if volume {
        e["KHR_materials_volume"] = json!({ "thicknessFactor": 0.2 });
    }
    if let Some(d) = dispersion {
        e["KHR_materials_dispersion"] = json!({ "dispersion": d });
    }
    e
}

#[test]
fn a_dispersive_slab_is_white_in_the_mean_and_coloured_per_sample() {
    let dir = tempfile::tempdir().unwrap();
    let plain = load_slab(dir.path(), "plain.gltf", glass(None, true));
    let zero = load_slab(dir.path(), "zero.gltf", glass(Some(json!(0.0)), true));
    let dispersive = load_slab(dir.path(), "dispersive.gltf", glass(Some(json!(1.0)), true));
    assert!(
        !dispersive.warnings.iter().any(|w| w.contains("dispersion")),
        "{:?}",
        dispersive.warnings
    );
    assert!(
        dispersive
            .scene
            .materials()
            .iter()
            .any(|m| matches!(&m.kind, MaterialKind::Gltf(g) if g.dispersion == 1.0))
    );
    // Dispersion 0 is no dispersion, bit for bit.
    let (size, spp) = (24, 384);
    let a = render_on(&plain, size, spp, 2);
    assert!(common::bit_identical(
        &render_on(&plain, size, 8, 2),
        &render_on(&zero, size, 8, 2)
    ));
    // The plain slab: white, (1 − F)² and the reflections between the faces.
    let m_plain = mean(&a);
    assert!(
        (m_plain - Vec3A::splat(m_plain.x)).abs().max_element() < 1e-6,
        "{m_plain}"
    );
    assert!(m_plain.x > 0.85 && m_plain.x < 0.95, "{m_plain}");
    // The dispersive slab: the same in the mean, within the colour noise of
    // 221,184 samples (0.5 % per channel) and the Fresnel terms' own
    // dependence on n(λ) (the red, of lower index, passes 0.4 % more than
    // the blue).
    let b = render_on(&dispersive, size, spp, 2);
    let m_disp = mean(&b);
    let off = ((m_disp - m_plain) / m_plain).abs().max_element();
    eprintln!(
        "mean: plain {m_plain}, dispersive {m_disp} ({:.2} %)",
        off * 100.0
    );
    assert!(off < 0.015, "plain {m_plain} vs dispersive {m_disp}");
    // ... while single samples carry one wavelength's colour.
    let cam = camera(&dispersive, size);
    let (mut coloured, n) = (0, 400);
    for s in 0..n {
        let v = probe_sample(
            &dispersive.scene,
            &cam,
            Integrator::path(),
            5,
            12,
            12,
            s,
            &mut (),
        );
        if (v.x - v.y).abs() > 0.05 || (v.y - v.z).abs() > 0.05 {
            coloured += 1;
        }
    }
    assert!(coloured > n / 2, "{coloured} of {n} samples coloured");
    // The same image on any number of threads.
    let one = render_on(&dispersive, size, 16, 1);
    assert!(common::bit_identical(
        &one,
        &render_on(&dispersive, size, 16, 2)
    ));
    assert!(common::bit_identical(
        &one,
        &render_on(&dispersive, size, 16, 3)
    ));
}

/// The extension builds on `KHR_materials_volume`: on a thin wall (no
/// volume) it changes nothing; and a value that is not finite is refused
/// with the material named.
#[test]
fn dispersion_without_a_volume_changes_nothing_and_bad_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let thin = load_slab(dir.path(), "thin.gltf", glass(None, false));
    let thin_dispersive = load_slab(
        dir.path(),
        "thin-dispersive.gltf",
        glass(Some(json!(1.0)), false),
    );
    assert!(common::bit_identical(
        &render_on(&thin, 16, 8, 2),
        &render_on(&thin_dispersive, 16, 8, 2)
    ));
    let options = LoadOptions {
        default_light: DefaultLight::Off,
        ..LoadOptions::default()
    };
    let bad = slab_file(dir.path(), "bad.gltf", glass(Some(json!(1e39)), true));
    let err = load_with(&bad, &options).expect_err("refused");
    assert!(
        err.contains("material 1") && err.contains("dispersion"),
        "{err}"
    );
    let bad = slab_file(
        dir.path(),
        "bad-type.gltf",
        glass(Some(json!("lots")), true),
    );
    let err = load_with(&bad, &options).expect_err("refused");
    assert!(err.contains("KHR_materials_dispersion"), "{err}");
}
