//! Transforms against matrices computed by hand.

use glam::{Mat4, Vec3, Vec4};

use super::{only, parse, scene};
use crate::load::mitsuba::Value;

/// The `to_world` of a shape with the operations `ops`.
fn to_world(ops: &str) -> Mat4 {
    let t = parse(&scene(&format!(
        r#"<shape type="x"><transform name="to_world">{ops}</transform></shape>"#
    )));
    match only(&t).value("to_world") {
        Some(Value::Transform(m)) => *m,
        other => panic!("{other:?}"),
    }
}

#[track_caller]
fn close(m: Mat4, cols: [[f32; 4]; 4]) {
    let want = Mat4::from_cols_array_2d(&cols);
    assert!(m.abs_diff_eq(want, 1e-6), "\n{m}\n!=\n{want}");
}

#[test]
fn an_empty_transform_is_the_identity() {
    assert_eq!(to_world(""), Mat4::IDENTITY);
}

#[test]
fn translate_in_both_forms() {
    let want = [
        [1., 0., 0., 0.],
        [0., 1., 0., 0.],
        [0., 0., 1., 0.],
        [1., -2., 3., 1.],
    ];
    close(to_world(r#"<translate x="1" y="-2" z="3"/>"#), want);
    close(to_world(r#"<translate value="1, -2 3"/>"#), want);
    // Missing components are 0; one value is all three.
    close(
        to_world(r#"<translate y="5"/>"#),
        [
            [1., 0., 0., 0.],
            [0., 1., 0., 0.],
            [0., 0., 1., 0.],
            [0., 5., 0., 1.],
        ],
    );
    close(
        to_world(r#"<translate value="2"/>"#),
        [
            [1., 0., 0., 0.],
            [0., 1., 0., 0.],
            [0., 0., 1., 0.],
            [2., 2., 2., 1.],
        ],
    );
}

#[test]
fn scale_uniform_and_per_axis() {
    let diag = |x: f32, y: f32, z: f32| {
        [
            [x, 0., 0., 0.],
            [0., y, 0., 0.],
            [0., 0., z, 0.],
            [0., 0., 0., 1.],
        ]
    };
    close(to_world(r#"<scale value="5"/>"#), diag(5., 5., 5.));
    close(to_world(r#"<scale value="2, 1, -1"/>"#), diag(2., 1., -1.));
    // Missing components are 1.
    close(to_world(r#"<scale x="3"/>"#), diag(3., 1., 1.));
}

#[test]
fn scale_then_translate_and_the_reverse() {
    // Each operation left-multiplies: scale first, then translate.
    let m = to_world(r#"<scale value="2"/><translate x="1"/>"#);
    close(
        m,
        [
            [2., 0., 0., 0.],
            [0., 2., 0., 0.],
            [0., 0., 2., 0.],
            [1., 0., 0., 1.],
        ],
    );
    assert_eq!(m.transform_point3(Vec3::ONE), Vec3::new(3.0, 2.0, 2.0));
    // Translate first: the offset is scaled too.
    let m = to_world(r#"<translate x="1"/><scale value="2"/>"#);
    close(
        m,
        [
            [2., 0., 0., 0.],
            [0., 2., 0., 0.],
            [0., 0., 2., 0.],
            [2., 0., 0., 1.],
        ],
    );
}

#[test]
fn rotate_counter_clockwise_in_degrees() {
    // 90° about +z: x -> y, y -> -x.
    close(
        to_world(r#"<rotate z="1" angle="90"/>"#),
        [
            [0., 1., 0., 0.],
            [-1., 0., 0., 0.],
            [0., 0., 1., 0.],
            [0., 0., 0., 1.],
        ],
    );
    // The axis is normalized, and value= works too.
    close(
        to_world(r#"<rotate value="0, 0, 7" angle="90"/>"#),
        [
            [0., 1., 0., 0.],
            [-1., 0., 0., 0.],
            [0., 0., 1., 0.],
            [0., 0., 0., 1.],
        ],
    );
    // 180° about y: x -> -x, z -> -z.
    close(
        to_world(r#"<rotate y="1" angle="180"/>"#),
        [
            [-1., 0., 0., 0.],
            [0., 1., 0., 0.],
            [0., 0., -1., 0.],
            [0., 0., 0., 1.],
        ],
    );
}

#[test]
fn rotate_about_a_tilted_axis() {
    // 120° about (1, 1, 1) cycles the axes: x -> y -> z -> x.
    close(
        to_world(r#"<rotate x="1" y="1" z="1" angle="120"/>"#),
        [
            [0., 1., 0., 0.],
            [0., 0., 1., 0.],
            [1., 0., 0., 0.],
            [0., 0., 0., 1.],
        ],
    );
    // 90° about (1, 1, 0)/√2 (Rodrigues by hand): c = 0, s = 1,
    // R = k kᵀ + [k]×, columns (½, ½, -1/√2), (½, ½, 1/√2), (1/√2, -1/√2, 0).
    let r = std::f32::consts::FRAC_1_SQRT_2;
    close(
        to_world(r#"<rotate value="1 1 0" angle="90"/>"#),
        [
            [0.5, 0.5, -r, 0.],
            [0.5, 0.5, r, 0.],
            [r, -r, 0., 0.],
            [0., 0., 0., 1.],
        ],
    );
}

#[test]
fn matrices_are_row_major() {
    let m = to_world(r#"<matrix value="1 2 3 4  5 6 7 8  9 10 11 12  0 0 0 1"/>"#);
    assert_eq!(m.row(0), Vec4::new(1., 2., 3., 4.));
    assert_eq!(m.row(1), Vec4::new(5., 6., 7., 8.));
    assert_eq!(m.col(3), Vec4::new(4., 8., 12., 1.));
    // Nine values: the upper-left 3×3 of an identity.
    let m = to_world(r#"<matrix value="0.57,0.2,0, 0.1,-1,0, 0,0,1"/>"#);
    assert_eq!(m.row(0), Vec4::new(0.57, 0.2, 0., 0.));
    assert_eq!(m.row(1), Vec4::new(0.1, -1., 0., 0.));
    assert_eq!(m.row(3), Vec4::new(0., 0., 0., 1.));
}

#[test]
fn lookat_with_mitsubas_handedness() {
    // Looking down -z from +5 z with y up: the camera's +x is the world's
    // -x (left), +y is up, +z is the view direction.
    close(
        to_world(r#"<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>"#),
        [
            [-1., 0., 0., 0.],
            [0., 1., 0., 0.],
            [0., 0., -1., 0.],
            [0., 0., 5., 1.],
        ],
    );
    // Looking along +x with z up: left = z × x = y.
    close(
        to_world(r#"<lookat origin="1,2,3" target="2,2,3" up="0,0,1"/>"#),
        [
            [0., 1., 0., 0.],
            [0., 0., 1., 0.],
            [1., 0., 0., 0.],
            [1., 2., 3., 1.],
        ],
    );
    // An up that is not perpendicular is made so: dir = (0, -1, 1)/√2,
    // left = up × dir = (1, 0, 0), up' = dir × left = (0, 1, 1)/√2.
    let r = std::f32::consts::FRAC_1_SQRT_2;
    close(
        to_world(r#"<lookat origin="0, 1, 0" target="0, 0, 1" up="0, 1, 0"/>"#),
        [
            [1., 0., 0., 0.],
            [0., r, r, 0.],
            [0., -r, r, 0.],
            [0., 1., 0., 1.],
        ],
    );
}

#[test]
fn lookat_without_up_uses_mitsubas_coordinate_system() {
    // dir = +z: coordinate_system gives (1, 0, 0) as up; left = up × dir =
    // (0, -1, 0); up' = dir × left = (1, 0, 0).
    let want = [
        [0., -1., 0., 0.],
        [1., 0., 0., 0.],
        [0., 0., 1., 0.],
        [0., 0., 0., 1.],
    ];
    close(to_world(r#"<lookat origin="0,0,0" target="0,0,2"/>"#), want);
    close(
        to_world(r#"<lookat origin="0,0,0" target="0,0,2" up="0 0 0"/>"#),
        want,
    );
}

#[test]
fn operations_compose_in_document_order() {
    // translate, then rotate 90° about z, then lookat (a pure translation
    // here): p -> Rz(p + x) + (0, 0, 3).
    let m = to_world(
        r#"<translate x="1"/><rotate z="1" angle="90"/>
        <lookat origin="0,0,3" target="0,0,4" up="0,1,0"/>"#,
    );
    let p = m.transform_point3(Vec3::ZERO);
    assert!(p.abs_diff_eq(Vec3::new(0.0, 1.0, 3.0), 1e-6), "{p}");
    let q = m.transform_point3(Vec3::X);
    assert!(q.abs_diff_eq(Vec3::new(0.0, 2.0, 3.0), 1e-6), "{q}");
}

#[test]
fn substitution_reaches_transform_operations() {
    let t = super::parse_with(
        &scene(
            r#"<shape type="x"><transform name="m"><rotate y="1" angle="$a"/><translate value="$t"/></transform></shape>"#,
        ),
        &[("a", "180"), ("t", "1 2 3")],
    );
    let Some(Value::Transform(m)) = only(&t).value("m") else {
        panic!()
    };
    close(
        *m,
        [
            [-1., 0., 0., 0.],
            [0., 1., 0., 0.],
            [0., 0., -1., 0.],
            [1., 2., 3., 1.],
        ],
    );
}
