//! Substitution, includes and search paths (in temporary folders), the
//! scenes of `tests/data/mitsuba/`, and Mitsuba's own test scenes when a
//! checkout of `mitsuba-renderer/mitsuba-data` is given.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec4};

use super::{error_with, only, parse, parse_with, scene};
use crate::load::mitsuba::{MitsubaError, SceneTree, Spectrum, Tag, Value, read};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba")
        .join(name)
}

/// Writes `files` (name, text) into a new temporary folder.
fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

fn read_in(dir: &Path, name: &str, defines: &[(&str, &str)]) -> Result<SceneTree, MitsubaError> {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    read(&dir.join(name), &defines)
}

fn int(tree: &SceneTree, name: &str) -> Option<i64> {
    match only(tree).value(name) {
        Some(Value::Integer(i)) => Some(*i),
        _ => None,
    }
}

#[test]
fn defaults_and_overrides() {
    let text = scene(
        r#"<default name="n" value="4"/><default name="nn" value="7"/>
        <sampler type="$kind"><integer name="a" value="$n"/><integer name="b" value="$nn"/><string name="c" value="\$n$n"/></sampler>"#,
    );
    let t = parse_with(&text, &[("kind", "independent")]);
    assert_eq!(only(&t).plugin, "independent");
    // The longer name first: "$nn" is not "$n" followed by "n".
    assert_eq!((int(&t, "a"), int(&t, "b")), (Some(4), Some(7)));
    assert_eq!(only(&t).value("c"), Some(&Value::String("$n4".into())));
    // A definition wins over the default.
    let t = parse_with(&text, &[("kind", "x"), ("n", "12"), ("n", "13")]);
    assert_eq!((int(&t, "a"), int(&t, "b")), (Some(13), Some(7)));
}

#[test]
fn a_default_must_come_before_its_use() {
    let e = error_with(
        "<scene version=\"3.0.0\">\n<integer name=\"a\" value=\"$late\"/>\n<default name=\"late\" value=\"1\"/></scene>",
        &[],
    );
    assert_eq!(
        e,
        "/virtual/scene.xml:2: <integer>: undefined parameter $late (define it with -D late=… or a <default> before this line)"
    );
}

#[test]
fn an_unused_definition_is_an_error() {
    let e = error_with(
        &scene(r#"<default name="a" value="1"/><integer name="i" value="$a"/>"#),
        &[("a", "2"), ("zz", "3")],
    );
    assert_eq!(
        e,
        "/virtual/scene.xml: unused parameter -D zz=3 (no attribute uses it)"
    );
}

#[test]
fn includes_relative_to_the_including_file() {
    let dir = folder(&[
        (
            "main.xml",
            r#"<scene version="3.0.0">
  <default name="r" value="0.5"/>
  <include filename="parts/shapes.xml"/>
  <shape type="cube"><ref id="shared"/><float name="r" value="$r"/><float name="q" value="$q"/></shape>
</scene>"#,
        ),
        (
            "parts/shapes.xml",
            r#"<scene version="3.0.0">
  <default name="q" value="2"/>
  <bsdf type="diffuse" id="shared"/>
  <shape type="sphere"><ref id="shared"/></shape>
  <shape type="obj"><include filename="material.xml" name="bsdf"/></shape>
</scene>"#,
        ),
        (
            "parts/material.xml",
            r#"<bsdf version="3.0.0" type="conductor"><string name="material" value="Au"/></bsdf>"#,
        ),
    ]);
    let t = read_in(dir.path(), "main.xml", &[]).unwrap();
    // The included scene's objects join the main scene, in order.
    let kinds: Vec<&str> = t
        .root
        .children
        .iter()
        .map(|c| c.object.plugin.as_str())
        .collect();
    assert_eq!(kinds, ["diffuse", "sphere", "obj", "cube"]);
    let shapes: Vec<_> = t.root.children_of(Tag::Shape).collect();
    // A reference across files is the same object.
    assert!(Arc::ptr_eq(
        &shapes[0].children[0].object,
        &shapes[2].children[0].object
    ));
    // A non-scene root is one child, named by the include.
    let bsdf = shapes[1].child("bsdf").unwrap();
    assert_eq!(bsdf.value("material"), Some(&Value::String("Au".into())));
    assert!(bsdf.location.file.ends_with("parts/material.xml"));
    assert_eq!(bsdf.location.line, 1);
    // A default given in an included file holds after it.
    assert_eq!(shapes[2].value("q"), Some(&Value::Float(2.0)));
    assert_eq!(t.files.len(), 3);
    assert!(t.files[1].ends_with("parts/shapes.xml"));
}

#[test]
fn an_include_cycle_names_the_files() {
    let dir = folder(&[
        (
            "a.xml",
            "<scene version=\"3.0.0\">\n<include filename=\"b.xml\"/></scene>",
        ),
        (
            "b.xml",
            "<scene version=\"3.0.0\">\n\n<include filename=\"a.xml\"/></scene>",
        ),
    ]);
    let e = read_in(dir.path(), "a.xml", &[]).unwrap_err().to_string();
    let d = dir.path().display();
    assert_eq!(
        e,
        format!(
            "{d}/b.xml:3: <include>: include cycle: {d}/a.xml -> {d}/b.xml -> {d}/a.xml (included from {d}/a.xml:2)"
        )
    );
    // A file including itself.
    let dir = folder(&[(
        "s.xml",
        "<scene version=\"3.0.0\"><include filename=\"s.xml\"/></scene>",
    )]);
    let e = read_in(dir.path(), "s.xml", &[]).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "s.xml:1: <include>: include cycle: {d}/s.xml -> {d}/s.xml"
                .replace("{d}", &dir.path().display().to_string())
                .as_str()
        ),
        "{e}"
    );
}

#[test]
fn includes_deeper_than_fifteen_levels_are_refused() {
    let texts: Vec<String> = (0..16)
        .map(|i| {
            format!(
                "<scene version=\"3.0.0\"><include filename=\"f{}.xml\"/></scene>",
                i + 1
            )
        })
        .collect();
    let names: Vec<String> = (0..16).map(|i| format!("f{i}.xml")).collect();
    let mut files: Vec<(&str, &str)> = names
        .iter()
        .map(String::as_str)
        .zip(texts.iter().map(String::as_str))
        .collect();
    files.push(("f16.xml", "<scene version=\"3.0.0\"/>"));
    let dir = folder(&files);
    // f0 (level 0) to f14 (level 14) are read; f14's include is refused.
    let e = read_in(dir.path(), "f0.xml", &[]).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{}/f14.xml:1: <include>: includes nested deeper than 15 levels",
            dir.path().display()
        )),
        "{e}"
    );
    assert!(read_in(dir.path(), "f2.xml", &[]).is_ok());
}

#[test]
fn paths_are_searched_latest_first() {
    let dir = folder(&[
        (
            "scenes/main.xml",
            r#"<scene version="3.0.0">
  <path value="../lib"/>
  <include filename="common.xml"/>
  <spectrum name="s" filename="measured.spd"/>
</scene>"#,
        ),
        (
            "lib/common.xml",
            r#"<scene version="3.0.0"><emitter type="constant"/></scene>"#,
        ),
        ("lib/measured.spd", "400 1\n700 1\n"),
        ("lib/mesh.obj", ""),
    ]);
    let t = read_in(dir.path(), "scenes/main.xml", &[]).unwrap();
    assert_eq!(only(&t).plugin, "constant");
    let lib = dir.path().join("scenes/../lib");
    assert_eq!(t.search_paths, [lib.clone(), dir.path().join("scenes")]);
    assert_eq!(
        t.root.value("s"),
        Some(&Value::Spectrum(Spectrum::File(lib.join("measured.spd"))))
    );
    assert_eq!(t.resolve("mesh.obj"), Some(lib.join("mesh.obj")));
    assert_eq!(t.resolve("missing.obj"), None);
}

#[test]
fn the_box_fixture() {
    let t = read(&fixture("box.xml"), &[("spp".into(), "16".into())]).unwrap();
    assert!(t.warnings.is_empty());
    let sensor = t.root.children_of(Tag::Sensor).next().unwrap();
    assert_eq!(sensor.value("fov"), Some(&Value::Float(39.3077)));
    assert_eq!(sensor.id.as_deref(), Some("camera"));
    let film = sensor.children_of(Tag::Film).next().unwrap();
    assert_eq!(film.value("width"), Some(&Value::Integer(256)));
    let sampler = sensor.children_of(Tag::Sampler).next().unwrap();
    assert_eq!(sampler.value("sample_count"), Some(&Value::Integer(16)));
    let Some(Value::Transform(m)) = sensor.value("to_world") else {
        panic!()
    };
    assert_eq!(
        *m,
        Mat4::from_cols(-Vec4::X, Vec4::Y, -Vec4::Z, Vec4::new(0., 0., 3.9, 1.))
    );
    let shapes: Vec<_> = t.root.children_of(Tag::Shape).collect();
    assert_eq!(shapes.len(), 5);
    assert_eq!(
        shapes[0].value("filename"),
        Some(&Value::String("meshes/floor.obj".into()))
    );
    let white = &shapes[0].children[0].object;
    assert_eq!(
        white.value("reflectance"),
        Some(&Value::Rgb([0.885809, 0.698859, 0.666422]))
    );
    // The included light refers back to the main file's material.
    let light = shapes[4];
    assert!(light.location.file.ends_with("fragments/lights.xml"));
    assert!(Arc::ptr_eq(white, &light.children[0].object));
    let emitter = light.children_of(Tag::Emitter).next().unwrap();
    assert_eq!(
        emitter.value("radiance"),
        Some(&Value::Spectrum(Spectrum::Sampled(vec![
            (400., 0.),
            (500., 8.),
            (600., 15.6),
            (700., 18.4)
        ])))
    );
    // The glass is declared after the sphere that refers to it.
    assert_eq!(
        shapes[2].children[0].object.value("int_ior"),
        Some(&Value::String("bk7".into()))
    );
    assert_eq!(
        t.summary(),
        "1 integrator (path), 1 sensor (perspective), 1 film (hdrfilm), 1 rfilter (gaussian), \
         1 sampler (independent), 5 shapes (cube, obj ×2, rectangle, sphere), \
         4 bsdfs (dielectric, diffuse ×2, twosided), 1 emitter (area)"
    );
}

#[test]
fn a_version_0_6_file_is_upgraded() {
    let t = read(&fixture("old-0.6.xml"), &[]).unwrap();
    assert_eq!(t.version.to_string(), "0.6.0");
    let integrator = t.root.children_of(Tag::Integrator).next().unwrap();
    assert_eq!(integrator.value("max_depth"), Some(&Value::Integer(5)));
    assert_eq!(
        integrator.value("strict_normals"),
        Some(&Value::Boolean(true))
    );
    let sensor = t.root.children_of(Tag::Sensor).next().unwrap();
    assert_eq!(sensor.value("fov_axis"), Some(&Value::String("x".into())));
    let Some(Value::Transform(m)) = sensor.value("to_world") else {
        panic!("{sensor:?}")
    };
    assert_eq!(
        *m,
        Mat4::from_cols(-Vec4::X, Vec4::Y, -Vec4::Z, Vec4::new(0., 0., 5., 1.))
    );
    let bsdfs: Vec<_> = t.root.children_of(Tag::Bsdf).collect();
    let texture = bsdfs[0]
        .child("reflectance")
        .expect("diffuse_reflectance renamed");
    assert_eq!(texture.name.as_deref(), Some("diffuse_reflectance"));
    assert_eq!(texture.value("uscale"), None);
    // to_uv = scale(4, 2, 1) · translate(0.5, 0, 0).
    let Some(Value::Transform(uv)) = texture.value("to_uv") else {
        panic!("{texture:?}")
    };
    assert_eq!(
        *uv,
        Mat4::from_cols(
            4. * Vec4::X,
            2. * Vec4::Y,
            Vec4::Z,
            Vec4::new(2., 0., 0., 1.)
        )
    );
    assert_eq!(bsdfs[1].value("alpha_u"), Some(&Value::Float(0.1)));
    assert_eq!(
        bsdfs[1].value("specular_reflectance"),
        Some(&Value::Spectrum(Spectrum::Constant(1.0)))
    );
}

#[test]
fn snake_case_as_mitsuba() {
    use crate::load::mitsuba::upgrade::snake_case;
    assert_eq!(snake_case("maxDepth"), "max_depth");
    assert_eq!(snake_case("intIOR"), "int_ior");
    assert_eq!(snake_case("toWorld"), "to_world");
    assert_eq!(snake_case("fooBarBAZQux"), "foo_bar_bazqux");
    assert_eq!(snake_case("IOR"), "IOR");
    assert_eq!(snake_case("already_snake"), "already_snake");
}

#[test]
fn a_0_6_name_keeps_its_form_when_the_new_one_is_taken() {
    let t = parse(
        r#"<scene version="0.5.0"><bsdf type="diffuse"><float name="fooBar" value="1"/><float name="foo_bar" value="2"/></bsdf></scene>"#,
    );
    let names: Vec<&str> = only(&t).props.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["fooBar", "foo_bar"]);
}

/// Every scene of Mitsuba's render tests (`tests/scenes/` of a checkout of
/// `mitsuba-renderer/mitsuba-data` named by `RAYLAB_MITSUBA_DATA`) is read,
/// and a few values checked; skipped without the variable.
#[test]
fn mitsuba_data_scenes() {
    let Some(root) = std::env::var_os("RAYLAB_MITSUBA_DATA") else {
        eprintln!("RAYLAB_MITSUBA_DATA not set: Mitsuba's test scenes not read");
        return;
    };
    let scenes = Path::new(&root).join("tests/scenes");
    // The scenes of each group (`tests/scenes/<group>/*.xml`, as Mitsuba's
    // test_renders.py finds them); the fragments they include are read
    // through them (alone, some name files relative to their includer).
    let mut read_ok = 0;
    for group in std::fs::read_dir(&scenes).unwrap() {
        let group = group.unwrap().path();
        if !group.is_dir() {
            continue;
        }
        for entry in std::fs::read_dir(&group).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|e| e == "xml") {
                if let Err(e) = read(&p, &[]) {
                    panic!("{e}");
                }
                read_ok += 1;
            }
        }
    }
    assert!(read_ok >= 30, "{read_ok} scenes");
    let spot = read(&scenes.join("spot_light/test_spot_direct.xml"), &[]).unwrap();
    let sensor = spot.root.children_of(Tag::Sensor).next().unwrap();
    assert_eq!(sensor.value("fov"), Some(&Value::Float(50.0)));
    let light = spot
        .root
        .children_of(Tag::Emitter)
        .find(|e| e.plugin == "spot")
        .unwrap();
    assert_eq!(light.value("cutoff_angle"), Some(&Value::Float(20.0)));
    let texture = light.child("texture").unwrap();
    let Some(Value::String(f)) = texture.value("filename") else {
        panic!()
    };
    assert!(
        spot.resolve(f)
            .unwrap()
            .ends_with("spot_light/textures/de_bruijn_pattern.png")
    );
    let wood = read(
        &scenes.join("bsdf_spheres/test_textured_diffuse_path.xml"),
        &[],
    )
    .unwrap();
    let shape = wood.root.children_of(Tag::Shape).next().unwrap();
    assert_eq!(
        shape.value("filename"),
        Some(&Value::String("meshes/sphere.obj".into()))
    );
    let bsdf = shape.children_of(Tag::Bsdf).next().unwrap();
    assert_eq!(bsdf.child("reflectance").unwrap().plugin, "bitmap");
    let inst = read(&scenes.join("instancing/test_instancing_path.xml"), &[]).unwrap();
    let instances: Vec<_> = inst
        .root
        .children_of(Tag::Shape)
        .filter(|s| s.plugin == "instance")
        .collect();
    assert!(instances.len() >= 2);
    assert!(Arc::ptr_eq(
        &instances[0].children[0].object,
        &instances[1].children[0].object
    ));
    eprintln!("{read_ok} Mitsuba test scenes read");
}
