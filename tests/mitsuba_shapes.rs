//! Mitsuba 3's `disk` and `cylinder` as raylab reads them: analytic
//! primitives (exact silhouettes: a ray just inside a scaled disk's rim or
//! a cylinder's outline hits, one just outside misses; Mitsuba's texture
//! coordinates at known points), in shape groups too (placed by each
//! instance; tessellated only where an instance scales a sphere unevenly,
//! and the load says so). Mitsuba's own statistical test against its images is
//! `tools/mitsuba_suite.py` (`tests/data/mitsuba/suite/disk_cylinder_path.xml`).

mod common;

use glam::{Vec2, Vec3A};
use raylab::geometry::ray::Ray;

/// Loads `body` as a Mitsuba scene (with a camera and a sky).
fn load(body: &str) -> raylab::load::Loaded {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shapes.xml");
    let xml = common::mitsuba_scene(body);
    std::fs::write(&path, xml).unwrap();
    raylab::load::load(path.to_str().unwrap(), &Default::default()).unwrap()
}

/// A disk scaled to an ellipse of half axes 2 (x) and 0.5 (y) at z = 1,
/// and a cylinder of radius 0.5 along x from (−1, 3, 0) to (1, 3, 0).
const SHAPES: &str = r#"
    <shape type="disk">
        <transform name="to_world"><scale x="2" y="0.5"/><translate z="1"/></transform>
    </shape>
    <shape type="cylinder">
        <point name="p0" x="-1" y="3" z="0"/>
        <point name="p1" x="1" y="3" z="0"/>
        <float name="radius" value="0.5"/>
    </shape>"#;

#[test]
fn disks_and_cylinders_are_analytic_with_exact_outlines() {
    let loaded = load(SHAPES);
    let scene = &loaded.scene;
    assert!(scene.has_analytic_shapes());
    assert!(scene.triangles().is_empty(), "{}", scene.triangles().len());
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("approximated")),
        "{:?}",
        loaded.warnings
    );
    let down = |x: f32, y: f32| Ray::new(Vec3A::new(x, y, 5.0), -Vec3A::Z);
    let hit = |ray: Ray| scene.intersect(&ray, f32::INFINITY);
    // The ellipse's rim, exactly (a polygon would cut it short).
    for (x, y) in [(1.9995, 0.0), (-1.9995, 0.0), (0.0, 0.4999), (0.0, -0.4999)] {
        let h = hit(down(x, y)).unwrap_or_else(|| panic!("{x} {y}"));
        assert!((h.t - 4.0).abs() < 1e-6);
    }
    for (x, y) in [(2.0005, 0.0), (0.0, 0.5005), (1.5, 0.35)] {
        assert!(hit(down(x, y)).is_none(), "{x} {y}");
    }
    // Mitsuba's disk coordinates (r, φ/2π): at (1, 0.25) r = 0.5·√2, φ = 45°.
    let h = hit(down(1.0, 0.25)).unwrap();
    let uv = Vec2::new(h.b1, h.b2);
    assert!(
        (uv - Vec2::new(0.5f32.sqrt(), 0.125)).length() < 1e-5,
        "{uv}"
    );
    // The cylinder's outline, seen from +z: |y − 3| < 0.5, |x| ≤ 1.
    assert!(hit(down(0.0, 3.4999)).is_some());
    assert!(hit(down(0.0, 3.5001)).is_none());
    assert!(hit(down(1.01, 3.0)).is_none());
    let top = hit(down(0.5, 3.0)).unwrap();
    assert!((top.t - 4.5).abs() < 1e-6);
    // Mitsuba's frame about +x (coordinate_system(x): s = −z, t = y):
    // the top (+z) is φ = 180°, and v = 0.75 at x = 0.5.
    let uv = Vec2::new(top.b1, top.b2);
    assert!((uv - Vec2::new(0.5, 0.75)).length() < 1e-5, "{uv}");
    // From inside the tube, sideways: the wall; along the axis: nothing.
    let inside = Vec3A::new(0.0, 3.0, 0.0);
    let wall = hit(Ray::new(inside, Vec3A::Y)).unwrap();
    assert!((wall.t - 0.5).abs() < 1e-6);
    assert!(hit(Ray::new(inside, Vec3A::X)).is_none());
}

/// In a shape group each instance places its disks, cylinders and spheres
/// as analytic shapes under the composed placement (exact outlines); only
/// where that placement does not suit (a sphere scaled unevenly) is the
/// shape tessellated, and the load says so.
#[test]
fn in_a_shape_group_each_instance_places_them_exactly() {
    let loaded = load(
        r#"
    <shape type="shapegroup" id="group">
        <shape type="disk"><transform name="to_world"><scale x="2" y="0.5"/></transform></shape>
        <shape type="sphere">
            <point name="center" x="0" y="3" z="0"/><float name="radius" value="0.5"/>
        </shape>
    </shape>
    <shape type="instance"><ref id="group"/>
        <transform name="to_world"><translate z="1"/></transform>
    </shape>
    <shape type="instance"><ref id="group"/>
        <transform name="to_world"><scale y="2"/><translate x="6"/></transform>
    </shape>"#,
    );
    let scene = &loaded.scene;
    let down = |x: f32, y: f32| Ray::new(Vec3A::new(x, y, 5.0), -Vec3A::Z);
    let hit = |x: f32, y: f32| scene.intersect(&down(x, y), f32::INFINITY);
    // The first instance: the ellipse at z = 1 and the sphere at (0, 3, 1).
    assert!((hit(1.9995, 0.0).unwrap().t - 4.0).abs() < 1e-6);
    assert!(hit(2.0005, 0.0).is_none());
    assert!((hit(0.0, 3.0).unwrap().t - 3.5).abs() < 1e-6);
    assert!(hit(0.0, 3.4999).is_some() && hit(0.0, 3.5001).is_none());
    // The second: the ellipse of half axes 2 and 1 at z = 0, x = 6.
    assert!((hit(7.9995, 0.0).unwrap().t - 5.0).abs() < 1e-6);
    assert!(hit(6.0, 0.9995).is_some() && hit(6.0, 1.0005).is_none());
    // Its sphere, stretched in y, is the one shape tessellated.
    assert!(!scene.triangles().is_empty());
    assert!(hit(6.0, 6.0).is_some());
    assert!(
        loaded.warnings.iter().any(|w| w.contains("approximated")
            && w.contains("sphere ×1")
            && !w.contains("disk ×")),
        "{:?}",
        loaded.warnings
    );
}

/// A mesh's front under a placement that mirrors (here x ↦ −x) is the side
/// its shading normals point to, as in Mitsuba (a one-sided BSDF shows it,
/// an area light emits to it): a mesh's own normals (the file's) are carried
/// by the inverse transpose and keep pointing up (+z) while the mirrored
/// triangles' winding turns down; normals Mitsuba makes for a mesh without
/// them come from the placed triangles, so that mesh's front turns down
/// with its winding. (Mitsuba's `various_shapes` test places three
/// rectangles so.)
#[test]
fn a_mirrored_mesh_faces_where_its_normals_point() {
    let dir = tempfile::tempdir().unwrap();
    let quad = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n";
    std::fs::write(
        dir.path().join("with.obj"),
        format!("{quad}vn 0 0 1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n"),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("without.obj"),
        format!("{quad}f 1 2 3\nf 1 3 4\n"),
    )
    .unwrap();
    let path = dir.path().join("mirrored.xml");
    std::fs::write(
        &path,
        r#"<scene version="3.0.0">
    <emitter type="constant"/>
    <shape type="obj">
        <string name="filename" value="with.obj"/>
        <transform name="to_world"><scale x="-1"/><translate x="-3"/></transform>
    </shape>
    <shape type="obj">
        <string name="filename" value="without.obj"/>
        <transform name="to_world"><scale x="-1"/><translate x="3"/></transform>
    </shape>
</scene>"#,
    )
    .unwrap();
    let loaded = raylab::load::load(path.to_str().unwrap(), &Default::default()).unwrap();
    let scene = &loaded.scene;
    let front = |x: f32| {
        let ray = Ray::new(Vec3A::new(x, 0.2, 5.0), -Vec3A::Z);
        let hit = scene.intersect(&ray, f32::INFINITY).expect("a hit");
        let s = scene.surface(&hit);
        (s.ng.z, s.ns.z)
    };
    assert_eq!(front(-3.0), (1.0, 1.0), "the file's normals");
    assert_eq!(
        front(3.0),
        (-1.0, -1.0),
        "normals made from the placed triangles"
    );
}
