//! Mitsuba 3's `sdfgrid` as raylab reads it: a `.vol` grid of a sphere's
//! signed distances (written here to a temporary folder) over the unit
//! cube, placed by `to_world` or by an instance of a shape group, is an
//! exact surface (cells of the analytic shapes, no triangles) whose hits
//! lie within the interpolation's error of the sphere, with the sphere's
//! normals and Mitsuba's texture coordinates (0, 0); the plugin's bad
//! inputs are one-line errors. Mitsuba's own statistical test against its
//! image is `tools/mitsuba_suite.py --only various_shapes`.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3A};
use raylab::geometry::ray::Ray;

/// Samples per side of the test grid.
const N: i32 = 24;
/// The sphere's radius in object units (centre (0.5, 0.5, 0.5)).
const RADIUS: f64 = 0.35;

/// The bytes of a `.vol` file (version 3, float32, one channel) of `n³`
/// samples of the sphere's signed distance, x fastest.
fn sphere_vol(n: i32) -> Vec<u8> {
    let mut b = b"VOL".to_vec();
    b.push(3);
    for v in [1, n, n, n, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let h = 1.0 / f64::from(n - 1);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z].map(|i| f64::from(i) * h - 0.5);
                let d = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - RADIUS;
                b.extend_from_slice(&(d as f32).to_le_bytes());
            }
        }
    }
    b
}

/// Loads `body` as a Mitsuba scene in a folder holding `sphere.vol`.
fn load(dir: &Path, body: &str) -> Result<raylab::load::Loaded, String> {
    std::fs::write(dir.join("sphere.vol"), sphere_vol(N)).unwrap();
    let path = dir.join("sdf.xml");
    let xml = common::mitsuba_scene(body);
    std::fs::write(&path, xml).unwrap();
    raylab::load::load(path.to_str().unwrap(), &Default::default()).map_err(|e| e.to_string())
}

/// How far the interpolated surface may lie from the sphere, in object
/// units: trilinear interpolation of the distance (curvature 1/R across
/// the surface) is off by about h²/(2R) for cells of size h.
fn interpolation_bound() -> f64 {
    let h = 1.0 / f64::from(N - 1);
    h * h / (2.0 * RADIUS)
}

/// Rays straight down (−z) onto the sphere of world centre `centre` and
/// radius `r` (object units times `scale`): hits within the bound of the
/// true sphere, the sphere's normal, texture coordinates (0, 0); rays
/// passing outside the silhouette by more than the bound miss.
fn check_sphere(loaded: &raylab::load::Loaded, centre: Vec3A, scale: f64) {
    let scene = &loaded.scene;
    assert!(scene.triangles().is_empty(), "{}", scene.triangles().len());
    assert!(
        scene.analytic_shape_count() > 500,
        "{}",
        scene.analytic_shape_count()
    );
    let r = RADIUS * scale;
    let bound = interpolation_bound() * scale;
    let down = |x: f64, y: f64| Ray::new(centre + Vec3A::new(x as f32, y as f32, 5.0), -Vec3A::Z);
    let mut checked = 0;
    for i in 0..40 {
        for j in 0..40 {
            let (x, y) = (
                (f64::from(i) / 39.0 * 2.0 - 1.0) * r,
                (f64::from(j) / 39.0 * 2.0 - 1.0) * r,
            );
            let rho = x.hypot(y);
            let hit = scene.intersect(&down(x, y), f32::INFINITY);
            if rho > r + bound + 1e-4 {
                assert!(hit.is_none(), "({x}, {y}) outside the sphere hits");
                continue;
            }
            if rho > r - bound - 1e-4 {
                continue; // within the interpolation's error of the rim
            }
            let hit = hit.unwrap_or_else(|| panic!("({x}, {y}) inside the outline misses"));
            // The height of the sphere's top there, and the allowance for
            // the surface's offset along a slope.
            let top = (r * r - rho * rho).sqrt();
            let slope = rho / top;
            let z = 5.0 - f64::from(hit.t);
            assert!(
                (z - top).abs() < bound * (1.0 + slope) + 1e-4,
                "({x}, {y}): z {z} vs {top}"
            );
            let s = scene.surface(&hit);
            let radial = Vec3A::new(x as f32, y as f32, top as f32).normalize();
            assert!(s.ng.dot(radial) > 0.99, "{} vs {radial}", s.ng);
            assert!(s.ns.dot(radial) > 0.99, "{} vs {radial}", s.ns);
            assert_eq!(scene.attributes(&hit).uv[0], Vec2::ZERO);
            checked += 1;
        }
    }
    assert!(checked > 800, "{checked}");
}

#[test]
fn a_grid_placed_by_to_world_is_the_sphere_it_samples() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = load(
        dir.path(),
        r#"<shape type="sdfgrid">
        <string name="filename" value="sphere.vol"/>
        <string name="normals" value="analytic"/>
        <transform name="to_world"><scale value="4"/><translate x="-2" y="-2" z="-2"/></transform>
    </shape>"#,
    )
    .unwrap();
    check_sphere(&loaded, Vec3A::ZERO, 4.0);
}

/// As in Mitsuba's `various_shapes` test: the grid in a shape group placed
/// by an instance that rotates, scales and moves it (smooth normals).
#[test]
fn a_grid_in_an_instanced_shape_group_is_placed_by_the_instance() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = load(
        dir.path(),
        r#"<shape type="shapegroup" id="group">
        <shape type="sdfgrid">
            <string name="filename" value="sphere.vol"/>
            <string name="normals" value="smooth"/>
        </shape>
    </shape>
    <shape type="instance">
        <ref id="group"/>
        <transform name="to_world">
            <translate x="-0.5" y="-0.5" z="-0.5"/>
            <scale value="3"/>
            <rotate value="0.3, -0.7, 0.2" angle="50"/>
            <translate x="1" y="2" z="-1"/>
        </transform>
    </shape>"#,
    )
    .unwrap();
    check_sphere(&loaded, Vec3A::new(1.0, 2.0, -1.0), 3.0);
}

/// Bad input is one line naming what is wrong: an area emitter (Mitsuba's
/// `sdfgrid` cannot be one), an unknown normal mode, a missing file name,
/// a truncated or foreign `.vol` file.
#[test]
fn bad_grids_are_refused_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let shape = |inner: &str| format!(r#"<shape type="sdfgrid">{inner}</shape>"#);
    let file = r#"<string name="filename" value="sphere.vol"/>"#;
    let mut truncated = sphere_vol(N);
    truncated.truncate(truncated.len() - 10);
    std::fs::write(dir.path().join("short.vol"), truncated).unwrap();
    std::fs::write(
        dir.path().join("foreign.vol"),
        b"PLY and then some more bytes than a header has, surely enough",
    )
    .unwrap();
    let cases = [
        (
            shape(&format!(r#"{file}<emitter type="area"/>"#)),
            "sdfgrid cannot be an area emitter",
        ),
        (
            shape(&format!(r#"{file}<string name="normals" value="flat"/>"#)),
            "'flat' is not one of analytic, smooth",
        ),
        (shape(""), "needs a 'filename'"),
        (
            shape(r#"<string name="filename" value="short.vol"/>"#),
            "short.vol: volume grid of 24x24x24 float32 samples needs 55344 bytes, the file has 55334 (truncated)",
        ),
        (
            shape(r#"<string name="filename" value="foreign.vol"/>"#),
            "foreign.vol: not a Mitsuba volume grid",
        ),
    ];
    for (body, want) in cases {
        let e = match load(dir.path(), &body) {
            Ok(_) => panic!("{body} loads"),
            Err(e) => e,
        };
        assert!(e.contains(want), "{e} (wanted {want})");
        assert!(!e.contains('\n'), "{e}");
    }
}
