//! OBJ/MTL scenes: a textured quad shows its texture the right way up, a `Ke`
//! emitter shows its radiance and lights the floor by the amount its solid
//! angle gives, and the examples' materials load.

mod common;

use std::path::Path;

use glam::Vec3A;
use raylab::load::obj::load_obj_scene;
use raylab::render::{RenderSettings, render};
use raylab::textures::srgb_to_linear;
use raylab::{Integrator, Scene};

fn scene_of(path: &Path) -> Scene {
    let obj = load_obj_scene(path).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_parts(obj.parts).unwrap()
}

/// A 2×2 texture: top-left red, top-right green, bottom-left blue, bottom-right
/// white (sRGB 200).
fn write_texture(path: &Path) {
    let texels = [[200, 0, 0], [0, 200, 0], [0, 0, 200], [200, 200, 200]];
    let img = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(texels[(y * 2 + x) as usize]));
    img.save(path).unwrap();
}

#[test]
fn a_textured_quad_shows_its_texture_the_right_way_up() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(&dir.path().join("tex.png"));
    std::fs::write(
        dir.path().join("q.mtl"),
        "newmtl t\nKd 1 1 1\nKs 0 0 0\nmap_Kd -clamp on tex.png\n",
    )
    .unwrap();
    // A unit quad facing +z, vt (0,0) at its bottom-left as OBJ has it.
    std::fs::write(
        dir.path().join("q.obj"),
        "mtllib q.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    let scene = scene_of(&dir.path().join("q.obj"));
    // The quad fills a 30° view exactly at distance 1/tan 15°.
    let d = 1.0 / 15f32.to_radians().tan();
    let cam = common::look_camera(Vec3A::new(0.0, 0.0, d), Vec3A::ZERO, 30.0, 64, 64);
    let settings = RenderSettings {
        integrator: Integrator::Flat,
        spp: 1,
        seed: 0,
    };
    let film = render(&scene, &cam, &settings, &|_| {}).film;
    let c = srgb_to_linear(200.0 / 255.0);
    // With `-clamp on`, the outer quarter of each side is its corner texel
    // exactly (bilinear blending happens between the texel centres only).
    let at = |x: u32, y: u32| film.get(x, y);
    let check = |p: Vec3A, want: Vec3A, what: &str| {
        assert!(
            (p - want).abs().max_element() < 1e-6,
            "{what}: {p} vs {want}"
        );
    };
    check(at(4, 4), Vec3A::new(c, 0.0, 0.0), "top-left red");
    check(at(59, 4), Vec3A::new(0.0, c, 0.0), "top-right green");
    check(at(4, 59), Vec3A::new(0.0, 0.0, c), "bottom-left blue");
    check(at(59, 59), Vec3A::splat(c), "bottom-right white");
}

/// Irradiance at the origin (normal +y) from a square emitter of radiance 1,
/// side `s`, centred `h` above it and facing down: ∫ cos θ cos θ' / r² dA.
fn square_irradiance(s: f64, h: f64) -> f64 {
    let n = 400;
    let mut e = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = (i as f64 + 0.5) / n as f64 * s - s / 2.0;
            let z = (j as f64 + 0.5) / n as f64 * s - s / 2.0;
            let r2 = x * x + z * z + h * h;
            e += h * h / (r2 * r2) * (s / n as f64).powi(2);
        }
    }
    e
}

#[test]
fn a_ke_emitter_shows_its_radiance_and_lights_the_floor() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("r.mtl"),
        "newmtl floor\nKd 1 1 1\nKs 0 0 0\nnewmtl lamp\nKd 0 0 0\nKs 0 0 0\nKe 6 4 2\n",
    )
    .unwrap();
    // A large white floor and a 0.5 × 0.5 lamp 1 above the origin, facing down
    // (counter-clockwise seen from below).
    std::fs::write(
        dir.path().join("r.obj"),
        "mtllib r.mtl\nv -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n\
         v -0.25 1 -0.25\nv 0.25 1 -0.25\nv 0.25 1 0.25\nv -0.25 1 0.25\n\
         usemtl floor\nf 1 4 3 2\nusemtl lamp\nf 5 6 7 8\n",
    )
    .unwrap();
    let scene = scene_of(&dir.path().join("r.obj"));
    assert_eq!(scene.emitter_count(), 2);
    // Seen from below, the lamp is exactly its radiance.
    let up = common::look_camera(
        Vec3A::new(0.0, 0.5, 0.0),
        Vec3A::new(0.0, 1.0, 0.001),
        10.0,
        8,
        8,
    );
    let film = common::path_film(&scene, &up, 1, 0);
    for p in &film.pixels {
        assert!(
            (*p - Vec3A::new(6.0, 4.0, 2.0)).abs().max_element() < 1e-5,
            "{p}"
        );
    }
    // The floor under it: radiance Kd/π · E, E from the square's solid angle.
    // One pixel, a narrow view, many samples (the floor is the only reflector
    // and the lamp is black: nothing bounces twice).
    let eye = Vec3A::new(0.0, 0.6, 2.0);
    let down = common::look_camera(eye, Vec3A::ZERO, 0.05, 1, 1);
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp: 16_384,
        seed: 3,
    };
    let got = render(&scene, &down, &settings, &|_| {}).film.get(0, 0);
    let e = square_irradiance(0.5, 1.0) as f32;
    let want = Vec3A::new(6.0, 4.0, 2.0) * e / std::f32::consts::PI;
    eprintln!("floor under the lamp: {got} vs {want}");
    assert!(
        ((got - want) / want).abs().max_element() < 0.01,
        "{got} vs {want}"
    );
}

#[test]
fn the_example_room_loads_its_materials() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/obj-room/room.obj");
    let obj = load_obj_scene(&path).unwrap();
    assert!(obj.warnings.is_empty(), "{:?}", obj.warnings);
    let names: Vec<&str> = obj
        .parts
        .materials
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    for want in [
        "floor",
        "wall",
        "bumpy_wall",
        "light",
        "glass",
        "mirror",
        "gold",
        "leaf",
    ] {
        assert!(names.contains(&want), "{want} in {names:?}");
    }
    assert_eq!(obj.parts.textures.len(), 3);
    assert!(obj.named_parts.iter().any(|(n, _)| n == "glass_ball"));
    let scene = Scene::from_parts(obj.parts).unwrap();
    assert_eq!(scene.emitter_count(), 2);
}

/// `Scene::fingerprint` (what checkpoints key their samples by) sees every
/// texel and coordinate, and is the same for the same files on any thread
/// count.
#[test]
fn the_scene_fingerprint_sees_every_texel_and_coordinate() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let write_texture = |corner: u8| {
        let mut texels = vec![200u8; 8 * 8 * 3];
        texels[0] = corner;
        image::save_buffer(
            d.join("t.png"),
            &texels,
            8,
            8,
            image::ExtendedColorType::Rgb8,
        )
        .unwrap();
    };
    let write_obj = |x: &str| {
        std::fs::write(d.join("m.mtl"), "newmtl m\nmap_Kd t.png\n").unwrap();
        std::fs::write(
            d.join("m.obj"),
            format!("mtllib m.mtl\nv 0 0 0\nv {x} 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n"),
        )
        .unwrap();
    };
    let fingerprint = |threads: usize| {
        let path = d.join("m.obj");
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                raylab::load::load(path.to_str().unwrap(), &Default::default())
                    .unwrap()
                    .scene
                    .fingerprint()
            })
    };
    write_texture(10);
    write_obj("1");
    let base = fingerprint(2);
    assert_eq!(
        fingerprint(1),
        base,
        "the same files on another thread count"
    );
    write_texture(11);
    assert_ne!(fingerprint(2), base, "one texel changed, same size");
    write_texture(10);
    assert_eq!(fingerprint(2), base);
    write_obj("1.0000001");
    assert_ne!(fingerprint(2), base, "one coordinate moved by an ulp");
    assert_ne!(
        raylab::load::cornell::scene().fingerprint(),
        raylab::load::cornell::area_scene().fingerprint()
    );
}

/// A smooth-shaded OBJ quad (vertex normals tilted a little either way) seen
/// from behind under a white sky reflects it as from the front: meshes are
/// two-sided, and a one-sided BSDF turned to the viewer must still take the
/// sky's light there. (It showed black: the test that keeps light from
/// leaking through shading normals compared directions with the front
/// geometric normal after the shading normal had been turned to the back.)
#[test]
fn a_smooth_quad_seen_from_behind_reflects_as_from_the_front() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvn 0 0.05 1\nvn 0 -0.05 1\nvn 0 0.05 1\nvn 0 -0.05 1\nf 1//1 2//2 3//3\nf 1//1 3//3 4//4\n",
    )
    .unwrap();
    let centre = |z: f32| {
        let toml = dir.path().join(format!("s{z}.toml"));
        std::fs::write(
            &toml,
            format!(
                "[render]\nwidth = 8\nheight = 8\nspp = 64\nintegrator = \"path\"\n[camera]\nposition = [0, 0, {z}]\ntarget = [0, 0, 0]\n[environment]\ncolor = [1, 1, 1]\n[[model]]\nfile = \"quad.obj\"\n"
            ),
        )
        .unwrap();
        let options = raylab::job::JobOptions::new(toml.to_str().unwrap());
        let mut job = raylab::job::Job::new(options).unwrap();
        let film = job
            .render_with(&raylab::job::Hooks::default())
            .unwrap()
            .finished
            .image;
        film.get(4, 4)
    };
    let (front, back) = (centre(3.0), centre(-3.0));
    // A Lambertian quad open to a white sky on its side: ρ (0.8 by
    // default) less what grazing directions lose; both sides alike.
    assert!(front.x > 0.6, "front {front}");
    assert!(
        (back - front).abs().max_element() < 0.05,
        "back {back}, front {front}"
    );
}
