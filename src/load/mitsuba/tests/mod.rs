//! Tests of the Mitsuba XML reader: values and references here,
//! transforms in `transforms.rs`, substitution and includes in `files.rs`
//! (with the scenes of `tests/data/mitsuba/` and, when a checkout is given,
//! Mitsuba's own test scenes), every error in `errors.rs`.

mod errors;
mod files;
mod meshes;
mod ply;
mod serialized;
mod transforms;

use std::path::Path;
use std::sync::Arc;

use glam::Vec3;

use super::{Object, SceneTree, Spectrum, Tag, Value, read_str};

/// `text` read as `/virtual/scene.xml` (no defines).
pub(super) fn parse(text: &str) -> SceneTree {
    parse_with(text, &[])
}

pub(super) fn parse_with(text: &str, defines: &[(&str, &str)]) -> SceneTree {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    match read_str(text, Path::new("/virtual/scene.xml"), &defines) {
        Ok(t) => t,
        Err(e) => panic!("unexpected error: {e}"),
    }
}

/// The one-line error of reading `text` as `/virtual/scene.xml`.
pub(super) fn error(text: &str) -> String {
    error_with(text, &[])
}

pub(super) fn error_with(text: &str, defines: &[(&str, &str)]) -> String {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    match read_str(text, Path::new("/virtual/scene.xml"), &defines) {
        Ok(_) => panic!("no error for {text}"),
        Err(e) => {
            let m = e.to_string();
            assert!(!m.contains('\n'), "not one line: {m}");
            m
        }
    }
}

/// `body` inside a version 3.0.0 `<scene>` (one line: the body starts on
/// line 1).
pub(super) fn scene(body: &str) -> String {
    format!("<scene version=\"3.0.0\">{body}</scene>")
}

/// The root's only child.
pub(super) fn only(tree: &SceneTree) -> &Arc<Object> {
    assert_eq!(tree.root.children.len(), 1, "{:?}", tree.root.children);
    &tree.root.children[0].object
}

#[test]
fn every_value_kind() {
    let t = parse(&scene(
        &r#"<bsdf type="x">
        <float name="f" value=" +1.5e1 "/>
        <integer name="i" value="-9223372036854775808"/>
        <boolean name="b" value="TRUE"/>
        <string name="s" value="a $$ b"/>
        <rgb name="grey" value="0.5"/>
        <rgb name="c" value="0.1,0.2  0.3"/>
        <point name="p" value="1"/>
        <vector name="v" x="1" y="-2" z=".5"/>
        <spectrum name="k" value="0.25"/>
        <spectrum name="w" value="400:0.5, 500:1, 600:0.25"/>
        </bsdf>"#
            .replace("$$", "\\$"),
    ));
    let o = only(&t);
    assert_eq!(o.tag, Tag::Bsdf);
    assert_eq!(o.plugin, "x");
    assert_eq!(o.value("f"), Some(&Value::Float(15.0)));
    assert_eq!(o.value("i"), Some(&Value::Integer(i64::MIN)));
    assert_eq!(o.value("b"), Some(&Value::Boolean(true)));
    assert_eq!(o.value("s"), Some(&Value::String("a $ b".into())));
    assert_eq!(o.value("grey"), Some(&Value::Rgb([0.5; 3])));
    assert_eq!(o.value("c"), Some(&Value::Rgb([0.1, 0.2, 0.3])));
    assert_eq!(o.value("p"), Some(&Value::Point(Vec3::ONE)));
    assert_eq!(
        o.value("v"),
        Some(&Value::Vector(Vec3::new(1.0, -2.0, 0.5)))
    );
    assert_eq!(
        o.value("k"),
        Some(&Value::Spectrum(Spectrum::Constant(0.25)))
    );
    assert_eq!(
        o.value("w"),
        Some(&Value::Spectrum(Spectrum::Sampled(vec![
            (400.0, 0.5),
            (500.0, 1.0),
            (600.0, 0.25)
        ])))
    );
    // Document order is kept, with the lines.
    let names: Vec<&str> = o.props.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["f", "i", "b", "s", "grey", "c", "p", "v", "k", "w"]);
    assert_eq!(o.prop("f").unwrap().location.line, 2);
    assert_eq!(o.prop("w").unwrap().location.line, 11);
}

#[test]
fn floats_are_read_in_double_then_rounded() {
    // 16777217 is not a float: rounded once from the decimal (as Mitsuba's
    // double then float), to even.
    let t = parse(&scene(
        r#"<bsdf type="x"><float name="f" value="16777217"/><float name="g" value="0.1"/></bsdf>"#,
    ));
    assert_eq!(only(&t).value("f"), Some(&Value::Float(16777216.0)));
    assert_eq!(only(&t).value("g"), Some(&Value::Float(0.1)));
}

#[test]
fn a_spectrum_with_a_type_is_an_object() {
    let t = parse(&scene(
        r#"<emitter type="area"><spectrum name="radiance" type="blackbody"><float name="temperature" value="5000"/></spectrum></emitter>"#,
    ));
    let s = only(&t).child("radiance").unwrap();
    assert_eq!((s.tag, s.plugin.as_str()), (Tag::Spectrum, "blackbody"));
    assert_eq!(s.value("temperature"), Some(&Value::Float(5000.0)));
}

#[test]
fn references_share_one_object_before_and_after_it() {
    let t = parse(&scene(
        r#"
        <shape type="sphere"><ref id="m"/></shape>
        <bsdf type="diffuse" id="m"><texture name="reflectance" type="checkerboard" id="tex"/></bsdf>
        <shape type="cube"><ref name="bsdf" id="m"/></shape>
        <alias id="m" as="m2"/>
        <shape type="disk"><ref id="m2"/><ref name="other" id="tex"/></shape>"#,
    ));
    let shapes: Vec<_> = t.root.children_of(Tag::Shape).collect();
    assert_eq!(shapes.len(), 3);
    let first = &shapes[0].children[0];
    assert!(first.by_ref && first.name.is_none());
    assert_eq!(first.location.line, 2);
    let m = &first.object;
    assert_eq!((m.plugin.as_str(), m.id.as_deref()), ("diffuse", Some("m")));
    assert!(Arc::ptr_eq(m, shapes[1].child("bsdf").unwrap()));
    assert!(Arc::ptr_eq(m, &shapes[2].children[0].object));
    // The nested texture, named "reflectance" in its bsdf, is "other" here.
    assert!(Arc::ptr_eq(
        m.child("reflectance").unwrap(),
        shapes[2].child("other").unwrap()
    ));
    // The declaration itself is a child of the scene too (not by ref).
    let declared = t.root.children_of(Tag::Bsdf).next().unwrap();
    assert!(Arc::ptr_eq(m, declared));
    // Shared objects count once.
    assert_eq!(t.objects().len(), 1 + 3 + 1 + 1);
    assert_eq!(
        t.summary(),
        "3 shapes (cube, disk, sphere), 1 bsdf (diffuse), 1 texture (checkerboard)"
    );
}

#[test]
fn a_root_may_be_any_object() {
    let t = parse(
        r#"<bsdf version="2.1.0" type="diffuse" id="b"><rgb name="reflectance" value="1"/></bsdf>"#,
    );
    assert_eq!((t.root.tag, t.root.plugin.as_str()), (Tag::Bsdf, "diffuse"));
    assert_eq!(t.version.to_string(), "2.1.0");
    let t = parse(r#"<scene version="3.0.0"/>"#);
    assert_eq!((t.root.tag, t.root.plugin.as_str()), (Tag::Scene, "scene"));
    assert_eq!(t.summary(), "no objects");
}

#[test]
fn text_and_comments_are_ignored_and_lines_counted() {
    let t = parse(
        "\u{feff}<?xml version=\"1.0\"?>\n<!-- c -->\n<scene version=\"3.0.0\">\n  text\n  <!-- <bogus/> -->\n  <shape type=\"sphere\"/>\n</scene>\n",
    );
    assert_eq!(only(&t).location.line, 6);
    assert_eq!(t.root.location.line, 3);
}
