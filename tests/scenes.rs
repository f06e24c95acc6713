//! Scene files: the examples in `scenes/` render, a composed file puts models,
//! lights and the camera where it says, errors name the line and column, and
//! the command line overrides the file.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3A;
use raylab::film::Film;
use raylab::load::{LoadOptions, Loaded, load};
use raylab::{Camera, Scene};

fn project(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn load_file(path: &Path) -> Loaded {
    load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn camera_of(loaded: &Loaded, w: u32, h: u32) -> Camera {
    let v = &loaded.view;
    Camera::with_lens(v.position, v.rotation, v.lens, w, h)
}

fn mean(film: &Film) -> Vec3A {
    let sum: glam::DVec3 = film.pixels.iter().map(|p| p.as_dvec3()).sum();
    (sum / film.pixels.len() as f64).as_vec3a()
}

/// Every example in `scenes/` loads and renders (small, a few samples): finite,
/// not black, the same on one and three threads.
#[test]
fn every_example_scene_renders() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(project("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "examples: {files:?}");
    for path in &files {
        let loaded = load_file(path);
        assert!(!loaded.default_light, "{}: lights itself", path.display());
        let cam = camera_of(&loaded, 48, 36);
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| common::path_film(&loaded.scene, &cam, 2, 5));
        let three = pool(3).install(|| common::path_film(&loaded.scene, &cam, 2, 5));
        assert!(common::bit_identical(&one, &three), "{}", path.display());
        assert!(one.pixels.iter().all(|p| p.is_finite()));
        let m = mean(&one);
        eprintln!("{}: mean {m}", path.display());
        assert!(m.min_element() > 0.01, "{}: mean {m}", path.display());
    }
}

/// The HDRI-lit helmet: the environment is the background, exactly the map's
/// radiance where camera rays miss.
#[test]
fn the_hdri_is_the_background() {
    let loaded = load_file(&project("scenes/helmet-hdri.toml"));
    let scene: &Scene = &loaded.scene;
    let cam = camera_of(&loaded, 40, 30);
    let film = common::path_film(scene, &cam, 4, 1);
    // The top-left pixel sees sky (the helmet is in the middle): its value is
    // the map's, averaged over the pixel; compare with the pixel centre's.
    let centre = cam.ray(0.5, 0.5);
    assert!(scene.intersect(&centre, f32::INFINITY).is_none());
    let want = scene.environment_radiance(centre.dir);
    let got = film.get(0, 0);
    assert!(
        ((got - want) / want).abs().max_element() < 0.05,
        "{got} vs {want}"
    );
    assert_eq!(loaded.settings.spp, Some(128));
}

/// A composed file: a glTF quad placed by its transform, an OBJ, an area light
/// seen face on, a spot and an environment colour, the camera looking at it.
#[test]
fn a_composed_file_puts_everything_where_it_says() {
    let dir = tempfile::tempdir().unwrap();
    // An OBJ triangle and a small glTF file made by hand.
    std::fs::write(
        dir.path().join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let text = r#"
        [render]
        width = 32
        height = 32
        spp = 3
        [camera]
        position = [0, 0, 5]
        target = [0, 0, 0]
        fov = 20
        [environment]
        color = [0.25, 0.5, 1.0]
        [[model]]
        file = "tri.obj"
        translate = [10, 0, 0]   # out of view
        [[light]]
        type = "area"
        corner = [-1, -1, 0]
        u = [2, 0, 0]
        v = [0, 2, 0]
        radiance = [3, 2, 1]
        [[light]]
        type = "point"
        position = [0, 3, 3]
        intensity = 1
    "#;
    let path = dir.path().join("shot.toml");
    std::fs::write(&path, text).unwrap();
    let loaded = load_file(&path);
    let scene = &loaded.scene;
    // The area quad fills the view (fov 20° at distance 5 is 1.76 wide): every
    // pixel is its radiance exactly (camera rays hit its front).
    let cam = camera_of(&loaded, 16, 16);
    let film = common::path_film(scene, &cam, 2, 1);
    for p in &film.pixels {
        assert!(
            (*p - Vec3A::new(3.0, 2.0, 1.0)).abs().max_element() < 1e-5,
            "{p}"
        );
    }
    // Its back (camera behind it) shows no emission, and beside it the sky.
    assert_eq!(scene.emitter_count(), 2);
    assert_eq!(
        scene.environment_radiance(Vec3A::Y),
        Vec3A::new(0.25, 0.5, 1.0)
    );
    // The point light is the key light; the OBJ's triangle is where translate put it.
    assert!((scene.light.position - Vec3A::new(0.0, 3.0, 3.0)).length() < 1e-6);
    assert!((scene.light.power - Vec3A::splat(4.0 * std::f32::consts::PI)).length() < 1e-4);
    assert!(scene.triangles()[0].v.iter().all(|v| v.x >= 10.0));
    assert_eq!(loaded.settings.width, Some(32));
}

#[test]
fn material_overrides_change_the_named_parts() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.toml");
    std::fs::write(
        &path,
        r#"
        [[model]]
        builtin = "cornell"
        materials = { tall = "mirror", floor = "red" }
        [[material]]
        name = "red"
        base_color = [0.9, 0.1, 0.1]
        "#,
    )
    .unwrap();
    let loaded = load_file(&path);
    let scene = &loaded.scene;
    let tall = raylab::load::cornell::part("tall").unwrap();
    let floor = raylab::load::cornell::part("floor").unwrap();
    for prim in tall {
        assert!(matches!(
            scene.material(prim as u32).kind,
            raylab::materials::surface::MaterialKind::Fixed(m) if m.is_specular()
        ));
    }
    for prim in floor {
        assert_eq!(scene.material(prim as u32).name, "red");
    }
    // The box stands +y up: its floor is at y = −1, its light above the centre.
    assert!(
        scene.triangles()[0]
            .v
            .iter()
            .all(|v| (v.y + 1.0).abs() < 1e-5)
    );
    assert!(scene.light.position.y > 0.0);
    // Unknown names are refused, listing what there is.
    std::fs::write(
        &path,
        "[[model]]\nbuiltin = \"cornell\"\nmaterials = { roof = \"mirror\" }\n",
    )
    .unwrap();
    let err = load(path.to_str().unwrap(), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("roof") && err.contains("tall"), "{err}");
}

#[test]
fn bad_files_exit_1_with_the_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str)] = &[
        (
            "[render]\nspp = 4\nsamples = 3\n",
            "bad.toml:3:1: unknown field `samples`",
        ),
        ("[render\nspp = 4\n", "bad.toml:1:"),
        ("[render]\nspp = \"many\"\n", "bad.toml:2:7:"),
        (
            "[[model]]\nbuiltin = \"cornell\"\n[[light]]\ntype = \"lamp\"\n",
            "bad.toml:4:8: unknown variant `lamp`",
        ),
        (
            "[[model]]\nbuiltin = \"attic\"\n",
            "unknown builtin 'attic'",
        ),
        ("[[model]]\nfile = \"missing.glb\"\n", "missing.glb"),
        (
            "[render]\nwidth = 0\n[[model]]\nbuiltin = \"cornell\"\n",
            "width = 0",
        ),
    ];
    for (text, want) in cases {
        std::fs::write(dir.path().join("bad.toml"), text).unwrap();
        let out = common::raylab(&["render", "bad.toml", "-o", "x.png"], dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{text}: {err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(err.contains(want), "{text}: {err}");
        assert!(!dir.path().join("x.png").exists());
    }
}

#[test]
fn the_command_line_overrides_the_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "[render]\nwidth = 40\nheight = 30\nspp = 2\nintegrator = \"flat\"\n[[model]]\nbuiltin = \"cornell\"\n",
    )
    .unwrap();
    let size = |png: &str| image::image_dimensions(dir.path().join(png)).unwrap();
    let out = common::raylab(&["render", "s.toml", "-o", "a.png"], dir.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(size("a.png"), (40, 30));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("flat, 2 spp"), "{err}");
    let out = common::raylab(
        &[
            "render",
            "s.toml",
            "--width",
            "20",
            "--spp",
            "3",
            "--integrator",
            "direct",
            "-o",
            "b.png",
        ],
        dir.path(),
    );
    assert!(out.status.success());
    // One side given: the other follows the file's 40×30, not its height.
    assert_eq!(size("b.png"), (20, 15));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("direct, 3 spp"), "{err}");
    let out = common::raylab(
        &["render", "s.toml", "--height", "60", "-o", "c.png"],
        dir.path(),
    );
    assert!(out.status.success());
    assert_eq!(size("c.png"), (80, 60));
    let out = common::raylab(
        &[
            "render", "s.toml", "--width", "10", "--height", "50", "-o", "d.png",
        ],
        dir.path(),
    );
    assert!(out.status.success());
    assert_eq!(size("d.png"), (10, 50));
}

/// The full example of docs/scene-files.md is a valid scene file that
/// composes (its paths are relative to `scenes/`).
#[test]
fn the_documented_example_composes() {
    let readme = std::fs::read_to_string(project("docs/scene-files.md")).unwrap();
    let section = &readme[readme.find("A full example").expect("a full example")..];
    let start = section.find("```toml\n").expect("a toml block") + 8;
    let text = &section[start..start + section[start..].find("```").unwrap()];
    let path = project("scenes/readme-example.toml");
    let file = raylab::load::shot::parse(text, &path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(file.models.len(), 3);
    assert_eq!(file.lights.len(), 4);
    let shot = raylab::load::shot::compose(file, &path).unwrap_or_else(|e| panic!("{e}"));
    // The box's point light and the file's first point light: the box's is the key.
    assert!(shot.parts.light.power.max_element() > 0.0);
    assert_eq!(shot.settings.max_depth, Some(16));
    assert!(shot.settings.fog.is_some(), "the example's [[medium]] fog");
}
