//! Mitsuba 3's `disk` and `cylinder` as raylab reads them: analytic
//! primitives (exact silhouettes: a ray just inside a scaled disk's rim or
//! a cylinder's outline hits, one just outside misses; Mitsuba's texture
//! coordinates at known points), tessellated only inside a shape group (the
//! load says so). Mitsuba's own statistical test against its images is
//! `tools/mitsuba_suite.py` (`tests/data/mitsuba/suite/disk_cylinder_path.xml`).

use glam::{Vec2, Vec3A};
use raylab::geometry::ray::Ray;

/// Loads `body` as a Mitsuba scene (with a camera and a sky).
fn load(body: &str) -> raylab::load::Loaded {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shapes.xml");
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 10" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
    {body}
</scene>"#
    );
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

#[test]
fn in_a_shape_group_they_are_tessellated_and_the_load_says_so() {
    let loaded = load(
        r#"
    <shape type="shapegroup" id="group">
        <shape type="disk"/>
        <shape type="cylinder"/>
    </shape>
    <shape type="instance"><ref id="group"/></shape>"#,
    );
    assert!(!loaded.scene.has_analytic_shapes());
    assert!(!loaded.scene.triangles().is_empty());
    assert!(
        loaded.warnings.iter().any(|w| w.contains("approximated")
            && w.contains("disk ×1")
            && w.contains("cylinder ×1")),
        "{:?}",
        loaded.warnings
    );
}
