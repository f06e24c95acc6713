//! glTF 2.0 lights: `KHR_lights_punctual` point, spot and directional lights
//! against the inverse-square formula, the cone falloff and the irradiance,
//! light samples unbiased over the light choice, and emitting triangles
//! lighting their front face or both. Every file is written by the test
//! itself (see `common/gltf_builder.rs`).

// Shared by the glTF tests (tests/gltf_*.rs); each uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::f32::consts::{FRAC_PI_2, PI};
use std::path::Path;

use builder::{Gltf, XY_SQUARE, add_floor, assert_near, load, load_with, quad};
use glam::{Quat, Vec2, Vec3, Vec3A};
use raylab::integrators::path::PathOptions;
use raylab::lights::Incident;
use raylab::load::{LoadOptions, Loaded};
use raylab::render::sample_pixel;
use raylab::scene::Facing;
use raylab::{Camera, Integrator, LightSample, Ray};
use serde_json::json;

// ---------------------------------------------------------------------------
// Punctual lights

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
        let incident = scene.lights()[0].incident(p, scene.textures());
        if factor == 0.0 {
            assert_eq!(sample, None, "θ = {theta}");
            assert_eq!(incident, None, "θ = {theta}");
            continue;
        }
        let Some(LightSample::Point {
            position,
            intensity: i,
            ..
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
                        ..
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
// Emission

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
