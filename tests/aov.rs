//! AOVs against numbers known without the renderer: the lab box's reflectances,
//! its walls' normals and planes (the box is `[-1, 1]³`, the camera at
//! `(0, 0, -3)` looking along +z, so the back wall lies at depth 4), glTF
//! materials' albedos worked out from the BSDF's formula, misses; and
//! determinism across thread counts, the image unchanged, and `--time`. The
//! command line's EXR channels are tested in `tests/cli.rs`.

// Shared with the glTF tests (tests/gltf_*.rs); this file uses a part.
#[allow(dead_code)]
#[path = "common/gltf_builder.rs"]
mod builder;

use std::ops::Range;
use std::time::Duration;

use glam::{Mat3A, Vec3A};
use raylab::aov::{Aov, AovImage, AovSet};
use raylab::camera::{Lens, Y_UP_TOWARDS_MINUS_Z};
use raylab::load::cornell::{self, colors, parts};
use raylab::render::{RenderSettings, Rendered, render, render_for_with_aovs, render_with_aovs};
use raylab::{Camera, Integrator, Scene};
use serde_json::json;

const ALL: &str = "albedo,normal,depth,position";

fn lab_camera(w: u32, h: u32) -> Camera {
    Camera::lab(cornell::CAMERA_POSITION, 0.0, 0.0, w, h)
}

fn render_aovs(
    scene: &Scene,
    cam: &Camera,
    integrator: Integrator,
    spp: u32,
    threads: usize,
) -> Rendered {
    let settings = RenderSettings {
        integrator,
        spp,
        seed: 5,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render_with_aovs(scene, cam, &settings, ALL.parse().unwrap(), &|_| {}))
}

/// A wall of the box: its triangles, the axis and coordinate of its plane, the
/// unit normal facing into the box (towards the camera) and its reflectance.
struct Wall {
    name: &'static str,
    tris: Range<usize>,
    axis: usize,
    at: f32,
    normal: Vec3A,
    albedo: Vec3A,
}

fn walls() -> [Wall; 5] {
    [
        // y points down: the floor is at y = +1.
        Wall {
            name: "floor",
            tris: parts::FLOOR,
            axis: 1,
            at: 1.0,
            normal: Vec3A::NEG_Y,
            albedo: colors::GREEN,
        },
        Wall {
            name: "ceiling",
            tris: parts::CEILING,
            axis: 1,
            at: -1.0,
            normal: Vec3A::Y,
            albedo: colors::CYAN,
        },
        Wall {
            name: "left",
            tris: parts::LEFT_WALL,
            axis: 0,
            at: -1.0,
            normal: Vec3A::X,
            albedo: colors::PURPLE,
        },
        Wall {
            name: "right",
            tris: parts::RIGHT_WALL,
            axis: 0,
            at: 1.0,
            normal: Vec3A::NEG_X,
            albedo: colors::YELLOW,
        },
        Wall {
            name: "back",
            tris: parts::BACK_WALL,
            axis: 2,
            at: 1.0,
            normal: Vec3A::NEG_Z,
            albedo: colors::WHITE,
        },
    ]
}

/// The wall every sample of pixel `(x, y)` sees: probes on a 5 × 5 grid over the
/// closed pixel all hit the same wall (none of the blocks in between).
fn interior_wall(scene: &Scene, cam: &Camera, x: u32, y: u32) -> Option<Wall> {
    let mut seen = None;
    for i in 0..5 {
        for j in 0..5 {
            let ray = cam.ray(x as f32 + i as f32 / 4.0, y as f32 + j as f32 / 4.0);
            let prim = scene.intersect(&ray, f32::INFINITY)?.prim as usize;
            let w = walls().into_iter().position(|w| w.tris.contains(&prim))?;
            if *seen.get_or_insert(w) != w {
                return None;
            }
        }
    }
    seen.map(|w| walls().into_iter().nth(w).unwrap())
}

/// Where the ray through image point `(px, py)` meets the wall's plane.
fn on_plane(cam: &Camera, wall: &Wall, px: f32, py: f32) -> Vec3A {
    let ray = cam.ray(px, py);
    let t = (wall.at - ray.origin[wall.axis]) / ray.dir[wall.axis];
    ray.origin + t * ray.dir
}

fn vec3(values: &[f32]) -> Vec3A {
    Vec3A::from_slice(values)
}

#[track_caller]
fn assert_near(got: Vec3A, want: Vec3A, tol: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: got {got}, want {want}"
    );
}

#[test]
fn the_box_walls_have_their_planes_and_normals() {
    // What the analytic checks below rely on, from the triangles themselves.
    let scene = cornell::scene();
    for wall in walls() {
        for t in &scene.triangles()[wall.tris.clone()] {
            for v in t.v {
                assert!((v[wall.axis] - wall.at).abs() < 1e-6, "{}: {v}", wall.name);
            }
        }
        for prim in wall.tris.clone() {
            assert_near(scene.normal(prim as u32), wall.normal, 1e-6, wall.name);
            assert_eq!(scene.reflectance(prim as u32), wall.albedo, "{}", wall.name);
        }
    }
}

#[test]
fn lab_box_aovs_match_the_walls_reflectances_normals_and_planes() {
    // One sample per pixel through its centre (`direct`), so that the position
    // is the centre ray's intersection with the wall's plane.
    let scene = cornell::scene();
    let cam = lab_camera(64, 48);
    let r = render_aovs(&scene, &cam, Integrator::Direct, 1, 2);
    let aovs = r.aovs.expect("AOVs asked for");
    let mut checked = [0usize; 5];
    for y in 0..cam.height {
        for x in 0..cam.width {
            let Some(wall) = interior_wall(&scene, &cam, x, y) else {
                continue;
            };
            let what = format!("{} wall at pixel ({x}, {y})", wall.name);
            let p = on_plane(&cam, &wall, x as f32 + 0.5, y as f32 + 0.5);
            assert_eq!(
                vec3(aovs.get(Aov::Albedo, x, y).unwrap()),
                wall.albedo,
                "{what}"
            );
            assert_eq!(
                vec3(aovs.get(Aov::Normal, x, y).unwrap()),
                wall.normal,
                "{what}"
            );
            let depth = aovs.get(Aov::Depth, x, y).unwrap()[0];
            // Camera-space depth: along the view axis (+z), from z = -3.
            assert!((depth - (p.z + 3.0)).abs() < 1e-4, "{what}: depth {depth}");
            assert_near(vec3(aovs.get(Aov::Position, x, y).unwrap()), p, 1e-4, &what);
            checked[walls().iter().position(|w| w.name == wall.name).unwrap()] += 1;
        }
    }
    assert!(
        checked.iter().all(|&n| n > 20),
        "pixels per wall: {checked:?}"
    );
}

#[test]
fn path_aovs_are_noise_free_where_the_geometry_is() {
    // 16 jittered samples a pixel: the image is noisy, the AOVs of a pixel
    // inside a wall are its constants; the back wall's depth is exactly 4
    // wherever a sample lands on it.
    let scene = cornell::scene();
    let cam = lab_camera(40, 40);
    let r = render_aovs(&scene, &cam, Integrator::path(), 16, 2);
    let aovs = r.aovs.unwrap();
    let mut back = 0;
    for y in 0..cam.height {
        for x in 0..cam.width {
            let Some(wall) = interior_wall(&scene, &cam, x, y) else {
                continue;
            };
            let what = format!("{} wall at pixel ({x}, {y})", wall.name);
            assert_near(
                vec3(aovs.get(Aov::Albedo, x, y).unwrap()),
                wall.albedo,
                1e-6,
                &what,
            );
            assert_near(
                vec3(aovs.get(Aov::Normal, x, y).unwrap()),
                wall.normal,
                1e-6,
                &what,
            );
            let p = vec3(aovs.get(Aov::Position, x, y).unwrap());
            assert!((p[wall.axis] - wall.at).abs() < 1e-5, "{what}: {p}");
            // The mean of points inside the pixel's footprint.
            let (lo, hi) = (
                on_plane(&cam, &wall, x as f32, y as f32),
                on_plane(&cam, &wall, x as f32 + 1.0, y as f32 + 1.0),
            );
            assert!(
                p.cmpge(lo.min(hi) - 1e-5).all() && p.cmple(lo.max(hi) + 1e-5).all(),
                "{what}: {p} outside {lo}..{hi}"
            );
            if wall.name == "back" {
                let depth = aovs.get(Aov::Depth, x, y).unwrap()[0];
                assert!((depth - 4.0).abs() < 1e-5, "{what}: depth {depth}");
                back += 1;
            }
        }
    }
    assert!(back > 50, "{back} back-wall pixels");
}

#[test]
fn misses_are_zero_albedo_and_normal_and_infinite_depth_and_position() {
    // Turned round, the camera looks out of the open front of the box.
    let scene = cornell::scene();
    let cam = Camera::lab(cornell::CAMERA_POSITION, 180.0, 0.0, 8, 6);
    let aovs = render_aovs(&scene, &cam, Integrator::path(), 2, 1)
        .aovs
        .unwrap();
    for layer in &aovs.layers {
        let want = match layer.aov {
            Aov::Albedo | Aov::Normal => 0.0,
            Aov::Depth | Aov::Position => f32::INFINITY,
            // (Not gathered here.)
            Aov::Variance | Aov::Half | Aov::Samples => unreachable!(),
        };
        assert!(layer.values.iter().all(|&v| v == want), "{:?}", layer.aov);
    }
    // Further back, the box's open front edges lie inside the view: a pixel on
    // the left wall's front edge (z = -1, depth 3) is partly covered. Albedo
    // and normal are diluted alike by the misses; depth averages the hits only.
    let cam = Camera::lab(Vec3A::new(0.0, 0.0, -4.0), 0.0, 0.0, 40, 40);
    let aovs = render_aovs(&scene, &cam, Integrator::path(), 64, 1)
        .aovs
        .unwrap();
    // Columns 0 to 9 see only the left wall (from x = 6.7, the edge at 40·(1/3)
    // pixels left of the centre; its back corner is at 40·(1/5)) or nothing.
    let mut partial = 0;
    for x in 0..10 {
        let n = vec3(aovs.get(Aov::Normal, x, 20).unwrap());
        let coverage = n.length();
        if coverage == 0.0 || coverage > 0.999 {
            continue;
        }
        partial += 1;
        assert_near(n / coverage, Vec3A::X, 1e-6, "normal direction");
        let albedo = vec3(aovs.get(Aov::Albedo, x, 20).unwrap());
        assert_near(albedo, coverage * colors::PURPLE, 1e-5, "diluted albedo");
        let depth = aovs.get(Aov::Depth, x, 20).unwrap()[0];
        assert!((depth - 3.0).abs() < 0.05, "edge depth {depth}");
        let p = vec3(aovs.get(Aov::Position, x, 20).unwrap());
        assert!((p.x + 1.0).abs() < 1e-5, "edge position {p}");
    }
    assert!(partial >= 1, "no partly covered pixel on the edge");
}

#[test]
fn orthographic_depth_is_the_distance_along_the_view_axis() {
    let scene = cornell::scene();
    let cam = Camera::with_lens(
        cornell::CAMERA_POSITION,
        Mat3A::IDENTITY,
        Lens::Orthographic { half_height: 0.9 },
        30,
        30,
    );
    let aovs = render_aovs(&scene, &cam, Integrator::Flat, 4, 1)
        .aovs
        .unwrap();
    // The centre of the view sees the back wall head-on, between the blocks
    // (which stand in the lower half).
    for (x, y) in [(15, 3), (3, 5), (26, 6)] {
        assert_eq!(
            interior_wall(&scene, &cam, x, y).map(|w| w.name),
            Some("back")
        );
        let depth = aovs.get(Aov::Depth, x, y).unwrap()[0];
        assert!((depth - 4.0).abs() < 1e-5, "({x}, {y}): {depth}");
    }
}

#[test]
fn aovs_are_bit_identical_on_any_number_of_threads_and_leave_the_image_alone() {
    let mut scene = cornell::scene();
    cornell::MaterialChoice::parse("glass")
        .unwrap()
        .apply(&mut scene, parts::TALL_BLOCK);
    let cam = lab_camera(37, 29);
    for integrator in [Integrator::path(), Integrator::Direct, Integrator::Flat] {
        let one = render_aovs(&scene, &cam, integrator, 3, 1);
        let three = render_aovs(&scene, &cam, integrator, 3, 3);
        let (a, b) = (one.aovs.as_ref().unwrap(), three.aovs.as_ref().unwrap());
        assert!(
            bits(a) == bits(b),
            "{integrator}: AOVs differ across threads"
        );
        assert_eq!(one.film, three.film);
        let plain = render(
            &scene,
            &cam,
            &RenderSettings {
                integrator,
                spp: 3,
                seed: 5,
            },
            &|_| {},
        );
        assert_eq!(plain.film, one.film, "{integrator}: AOVs changed the image");
        assert_eq!(plain.rays, one.rays, "{integrator}: AOVs cast rays");
        assert!(plain.aovs.is_none());
    }
}

fn bits(a: &AovImage) -> Vec<u32> {
    a.layers
        .iter()
        .flat_map(|l| l.values.iter().map(|v| v.to_bits()))
        .collect()
}

#[test]
fn time_limited_renders_gather_aovs_over_the_samples_taken() {
    let scene = cornell::scene();
    let cam = lab_camera(24, 24);
    let settings = RenderSettings {
        integrator: Integrator::path(),
        spp: 6,
        seed: 5,
    };
    let set: AovSet = "depth,albedo".parse().unwrap();
    let done = render_for_with_aovs(
        &scene,
        &cam,
        &settings,
        set,
        Duration::from_secs(60),
        &|_| {},
    );
    assert_eq!(done.spp, 6);
    let aovs = done.rendered.aovs.unwrap();
    assert_eq!(
        aovs.layers.iter().map(|l| l.aov).collect::<Vec<_>>(),
        [Aov::Depth, Aov::Albedo]
    );
    // The same as one render of those samples, bit for bit: the passes' sums
    // are kept in f64, in sample order.
    let whole = render_with_aovs(&scene, &cam, &settings, set, &|_| {})
        .aovs
        .unwrap();
    assert_eq!(aovs, whole);
}

#[test]
fn gltf_albedo_follows_the_bsdf_and_normals_face_the_camera() {
    use builder::{Gltf, U16};
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::new();
    // Two squares side by side in the z = 0 plane, front +z: a rough
    // dielectric and a metal.
    let (dielectric, metal) = (Vec3A::new(0.8, 0.4, 0.2), Vec3A::new(0.9, 0.6, 0.3));
    let m0 = g.material(json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [dielectric.x, dielectric.y, dielectric.z, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.5 } }));
    let m1 = g.material(json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [metal.x, metal.y, metal.z, 1.0],
        "metallicFactor": 1.0, "roughnessFactor": 0.3 } }));
    let mut prims = Vec::new();
    for (x0, m) in [(-2.0f32, m0), (0.0, m1)] {
        let corners = [
            [x0, -1.0, 0.0],
            [x0 + 2.0, -1.0, 0.0],
            [x0 + 2.0, 1.0, 0.0],
            [x0, 1.0, 0.0],
        ];
        let pos = g.floats(&corners);
        let idx = g.indices(U16, &[0, 1, 2, 0, 2, 3]);
        prims.push(json!({ "attributes": { "POSITION": pos }, "indices": idx, "material": m }));
    }
    let mesh = g.mesh(prims);
    g.root(json!({ "mesh": mesh }));
    let path = g.write(dir.path(), "two.gltf");
    let scene = raylab::load::load(path.to_str().unwrap(), &Default::default())
        .unwrap()
        .scene;
    // Orthographic, head-on (cos θo = 1): Schlick's terms are their F0, so the
    // dielectric's albedo is F0 + (1 − F0) c with F0 = ((1.5 − 1)/(1.5 + 1))² =
    // 0.04, and the metal's is its base colour.
    let lens = Lens::Orthographic { half_height: 1.2 };
    let front = Camera::with_lens(
        Vec3A::new(0.0, 0.0, 5.0),
        Y_UP_TOWARDS_MINUS_Z,
        lens,
        40,
        20,
    );
    let aovs = render_aovs(&scene, &front, Integrator::path(), 4, 2)
        .aovs
        .unwrap();
    let f0 = 0.04;
    for (x, want) in [(8, f0 + (1.0 - f0) * dielectric), (31, metal)] {
        assert_near(
            vec3(aovs.get(Aov::Albedo, x, 10).unwrap()),
            want,
            1e-5,
            "albedo",
        );
        assert_eq!(vec3(aovs.get(Aov::Normal, x, 10).unwrap()), Vec3A::Z);
        assert!((aovs.get(Aov::Depth, x, 10).unwrap()[0] - 5.0).abs() < 1e-5);
    }
    // From behind (the scene is two-sided): the normal turns to the camera.
    let back = Camera::with_lens(Vec3A::new(0.0, 0.0, -5.0), Mat3A::IDENTITY, lens, 40, 20);
    let aovs = render_aovs(&scene, &back, Integrator::Flat, 1, 1)
        .aovs
        .unwrap();
    assert_eq!(vec3(aovs.get(Aov::Normal, 20, 10).unwrap()), Vec3A::NEG_Z);
}

/// In fog, the guides are what a path meets first, in expectation: the fog's
/// albedo where it scatters, the surface behind where it does not. The lab
/// box filled with fog of density σ and albedo `a` (the fog fills the box,
/// `[-1, 1]³`): a ray to the back wall crosses `d = 2 / dir.z` of it, so each
/// back-wall pixel's albedo guide is `(1 − T) a + T ρ` and its normal `T n`
/// with `T = exp(−σ d)` (at the pixel's centre: its samples' `d` differ by
/// under 1e-3).
#[test]
fn fog_guides_blend_the_fog_albedo_with_the_surface_behind() {
    let mut scene = cornell::scene();
    let (sigma, a) = (0.4f32, Vec3A::new(0.9, 0.8, 0.7));
    scene.add_fog(sigma, a).unwrap();
    let cam = lab_camera(64, 48);
    let r = render_aovs(&scene, &cam, Integrator::path(), 8, 2);
    let aovs = r.aovs.expect("AOVs asked for");
    let mut checked = 0;
    for y in 0..cam.height {
        for x in 0..cam.width {
            let Some(wall) = interior_wall(&scene, &cam, x, y).filter(|w| w.name == "back") else {
                continue;
            };
            let dir = cam.ray(x as f32 + 0.5, y as f32 + 0.5).dir;
            let t = (-sigma * 2.0 / dir.z).exp();
            let want = (Vec3A::ONE - Vec3A::splat(t)) * a + t * wall.albedo;
            let what = format!("pixel ({x}, {y})");
            assert_near(
                vec3(aovs.get(Aov::Albedo, x, y).unwrap()),
                want,
                2e-3,
                &what,
            );
            assert_near(
                vec3(aovs.get(Aov::Normal, x, y).unwrap()),
                t * wall.normal,
                2e-3,
                &what,
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked} back-wall pixels");
}
