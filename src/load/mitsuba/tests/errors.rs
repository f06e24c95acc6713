//! Every error the reader gives: one line naming the file, the line and
//! what is wrong (and the object, where there is one).

use super::{error, error_with, scene};

/// The error of `body` inside a scene whose body starts on line 2.
fn at_2(body: &str) -> String {
    error(&format!("<scene version=\"3.0.0\">\n{body}\n</scene>"))
}

#[test]
fn malformed_xml() {
    assert_eq!(
        error("<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n</scene>"),
        "/virtual/scene.xml:3: malformed XML: expected 'shape' tag, not 'scene' at 3:1"
    );
    assert_eq!(
        error("<scene version=\"3.0.0\">\n<shape type=\"a\" type=\"b\"/></scene>"),
        "/virtual/scene.xml:2: malformed XML: attribute 'type' at 2:17 is already defined"
    );
    assert!(error("").starts_with("/virtual/scene.xml:1: malformed XML: "));
    // The element left open is named by its line.
    assert_eq!(
        error("<scene version=\"3.0.0\">\n\n"),
        "/virtual/scene.xml:1: malformed XML: the root node was opened but never closed"
    );
}

#[test]
fn the_root() {
    assert_eq!(
        error("<scene>\n</scene>"),
        "/virtual/scene.xml:1: missing version attribute in the root element <scene> (e.g. <scene version=\"3.0.0\">)"
    );
    assert_eq!(
        error("<scene version=\"3.0\"/>"),
        "/virtual/scene.xml:1: invalid version number \"3.0\" (expected major.minor.patch, e.g. \"3.0.0\")"
    );
    assert_eq!(
        error("<float version=\"3.0.0\" name=\"a\" value=\"1\"/>"),
        "/virtual/scene.xml:1: <float name=\"a\">: the root element must be an object such as <scene>"
    );
    assert_eq!(
        error("<scene version=\"3.0.0\" foo=\"1\"/>"),
        "/virtual/scene.xml:1: <scene>: unexpected attribute \"foo\""
    );
}

#[test]
fn unknown_elements() {
    assert_eq!(
        at_2("<foo/>"),
        "/virtual/scene.xml:2: <foo>: unsupported XML element"
    );
    assert_eq!(
        at_2("<shape type=\"s\"><srgb name=\"c\" value=\"#fff\"/></shape>"),
        "/virtual/scene.xml:2: <srgb name=\"c\">: unsupported XML element (in shape 's')"
    );
    assert_eq!(
        at_2("<rotate y=\"1\" angle=\"3\"/>"),
        "/virtual/scene.xml:2: <rotate>: a transform operation can only appear inside a <transform>"
    );
    assert_eq!(
        at_2("<shape type=\"s\"><transform name=\"m\"><shear/></transform></shape>"),
        "/virtual/scene.xml:2: <shear> in <transform name=\"m\">: unexpected <shear> element inside <transform> (expected translate, rotate, scale, matrix or lookat) (in shape 's')"
    );
    assert_eq!(
        at_2("<float name=\"a\" value=\"1\">\n<float name=\"b\" value=\"2\"/></float>"),
        "/virtual/scene.xml:3: <float> cannot occur inside <float name=\"a\">"
    );
}

#[test]
fn missing_and_unexpected_attributes() {
    assert_eq!(
        at_2("<shape id=\"x\"/>"),
        "/virtual/scene.xml:2: <shape>: missing required attribute \"type\""
    );
    assert_eq!(
        at_2("<bsdf type=\"diffuse\"><float name=\"alpha\"/></bsdf>"),
        "/virtual/scene.xml:2: <float name=\"alpha\">: missing required attribute \"value\" (in bsdf 'diffuse')"
    );
    assert_eq!(
        at_2("<bsdf type=\"diffuse\"><rgb name=\"c\" value=\"1\" alpha=\"1\"/></bsdf>"),
        "/virtual/scene.xml:2: <rgb name=\"c\">: unexpected attribute \"alpha\" (in bsdf 'diffuse')"
    );
    assert_eq!(
        at_2(
            "<shape type=\"s\"><transform name=\"m\"><lookat origin=\"0 0 0\"/></transform></shape>"
        ),
        "/virtual/scene.xml:2: <lookat> in <transform name=\"m\">: missing required attribute \"target\" (in shape 's')"
    );
    assert_eq!(
        at_2("<shape type=\"s\"><point name=\"p\" x=\"1\" y=\"2\"/></shape>"),
        "/virtual/scene.xml:2: <point name=\"p\">: missing required attribute \"z\" (in shape 's')"
    );
}

#[test]
fn bad_values() {
    let cases = [
        (
            "<float name=\"f\" value=\"1.5x\"/>",
            "<float name=\"f\">: could not parse floating point value \"1.5x\"",
        ),
        (
            "<float name=\"f\" value=\"inf\"/>",
            "<float name=\"f\">: could not parse floating point value \"inf\"",
        ),
        (
            "<float name=\"f\" value=\"-1e400\"/>",
            "<float name=\"f\">: floating point value \"-1e400\" is not finite",
        ),
        (
            "<float name=\"f\" value=\"1e39\"/>",
            "<float name=\"f\">: value \"1e39\" is beyond single precision",
        ),
        (
            "<integer name=\"i\" value=\"9223372036854775808\"/>",
            "<integer name=\"i\">: integer value \"9223372036854775808\" does not fit in 64 bits",
        ),
        (
            "<integer name=\"i\" value=\"+3\"/>",
            "<integer name=\"i\">: could not parse integer value \"+3\"",
        ),
        (
            "<integer name=\"i\" value=\"1.0\"/>",
            "<integer name=\"i\">: could not parse integer value \"1.0\"",
        ),
        (
            "<boolean name=\"b\" value=\"yes\"/>",
            "<boolean name=\"b\">: could not parse boolean value \"yes\" (must be \"true\" or \"false\")",
        ),
        (
            "<rgb name=\"c\" value=\"1 2\"/>",
            "<rgb name=\"c\">: <rgb> needs one or three values, not 2 (\"1 2\")",
        ),
        (
            "<vector name=\"v\" value=\"1 2\"/>",
            "<vector name=\"v\">: \"value\" must have 1 or 3 elements, not 2 (\"1 2\")",
        ),
        (
            "<vector name=\"v\" value=\"1\" x=\"2\"/>",
            "<vector name=\"v\">: cannot mix \"value\" and \"x\"/\"y\"/\"z\" attributes",
        ),
        (
            "<spectrum name=\"s\" value=\"500:1, 400:2\"/>",
            "<spectrum name=\"s\">: spectrum wavelengths must increase: 400 after 500",
        ),
        (
            "<spectrum name=\"s\" value=\"500:1\"/>",
            "<spectrum name=\"s\">: a spectrum needs one value or at least two wavelength:value pairs (\"500:1\")",
        ),
        (
            "<spectrum name=\"s\" value=\"1\" filename=\"a.spd\"/>",
            "<spectrum name=\"s\">: needs either a \"value\" or a \"filename\" attribute (not both)",
        ),
        (
            "<spectrum name=\"s\" filename=\"nowhere.spd\"/>",
            "<spectrum name=\"s\">: spectrum file \"nowhere.spd\" not found",
        ),
    ];
    for (body, message) in cases {
        let e = at_2(&format!("<bsdf type=\"b\">{body}</bsdf>"));
        assert_eq!(e, format!("/virtual/scene.xml:2: {message} (in bsdf 'b')"));
    }
}

#[test]
fn bad_transforms() {
    let cases = [
        (
            "<rotate angle=\"30\"/>",
            "<rotate> in <transform name=\"m\">: rotation axis cannot be zero",
        ),
        (
            "<rotate x=\"1\" angle=\"a\"/>",
            "<rotate> in <transform name=\"m\">: could not parse angle value \"a\"",
        ),
        (
            "<matrix value=\"1 2 3\"/>",
            "<matrix> in <transform name=\"m\">: matrix must have 9 or 16 values, got 3",
        ),
        (
            "<lookat origin=\"0 0 0\" target=\"0 0 0\"/>",
            "<lookat> in <transform name=\"m\">: invalid lookat transformation (origin equals target, or up is parallel to the view direction)",
        ),
        (
            "<lookat origin=\"0 0 0\" target=\"0 1 0\" up=\"0 2 0\"/>",
            "<lookat> in <transform name=\"m\">: invalid lookat transformation (origin equals target, or up is parallel to the view direction)",
        ),
        (
            "<lookat origin=\"0 0\" target=\"0 1 0\"/>",
            "<lookat> in <transform name=\"m\">: expected 3 values, got 2 (\"0 0\")",
        ),
        (
            "<scale value=\"1e30\"/><scale value=\"1e30\"/>",
            "<transform name=\"m\">: the matrix is not finite in single precision",
        ),
    ];
    for (ops, message) in cases {
        let e = at_2(&format!(
            "<shape type=\"s\"><transform name=\"m\">{ops}</transform></shape>"
        ));
        assert_eq!(e, format!("/virtual/scene.xml:2: {message} (in shape 's')"));
    }
}

#[test]
fn unknown_parameters() {
    assert_eq!(
        at_2("<shape type=\"$shape\"/>"),
        "/virtual/scene.xml:2: <shape>: undefined parameter $shape (define it with -D shape=… or a <default> before this line)"
    );
    // Defined, it is fine.
    let ok = super::parse_with(&scene("<shape type=\"$shape\"/>"), &[("shape", "sphere")]);
    assert_eq!(super::only(&ok).plugin, "sphere");
    assert_eq!(
        at_2("<default name=\"\" value=\"1\"/>"),
        "/virtual/scene.xml:2: <default>: name must be non-empty"
    );
}

#[test]
fn substitution_cannot_grow_without_bound() {
    // Each default holds eight escaped references to the next shorter name,
    // which the later (shorter) names then replace: 8^11 bytes unchecked.
    let mut body = String::new();
    for n in (2..=12).rev() {
        let inner = format!("\\${}", "k".repeat(n - 1)).repeat(8);
        body.push_str(&format!(
            "<default name=\"{}\" value=\"{inner}\"/>",
            "k".repeat(n)
        ));
    }
    body.push_str(
        "<default name=\"k\" value=\"x\"/>\n<string name=\"s\" value=\"$kkkkkkkkkkkk\"/>",
    );
    let e = at_2(&body);
    assert_eq!(
        e,
        "/virtual/scene.xml:3: <string>: an attribute grows beyond 1048576 bytes by $name substitution"
    );
    // Many attributes of 64 KiB each: 16 MiB in all, then an error.
    let body = format!(
        "<default name=\"big\" value=\"{}\"/>\n{}",
        "x".repeat(1 << 16),
        "<bsdf type=\"b\"><string name=\"s\" value=\"$big\"/></bsdf>".repeat(300)
    );
    let e = at_2(&body);
    assert_eq!(
        e,
        "/virtual/scene.xml:3: <string>: $name substitution grows the scene's attributes beyond 16777216 bytes"
    );
}

#[test]
fn missing_include() {
    assert_eq!(
        at_2("<include filename=\"parts/none.xml\"/>"),
        "/virtual/scene.xml:2: <include>: included file \"parts/none.xml\" not found (looked in /virtual, /virtual)"
    );
}

#[test]
fn ids_and_references() {
    assert_eq!(
        at_2("<bsdf type=\"a\" id=\"m\"/>\n<bsdf type=\"b\" id=\"m\"/>"),
        "/virtual/scene.xml:3: <bsdf type=\"b\">: duplicate id \"m\" (first at /virtual/scene.xml:2)"
    );
    assert_eq!(
        at_2("<shape type=\"s\">\n<ref name=\"bsdf\" id=\"nothing\"/></shape>"),
        "/virtual/scene.xml:3: <ref \"bsdf\"> to unknown id \"nothing\" (in shape 's'; no object has id=\"nothing\")"
    );
    assert_eq!(
        at_2("<alias id=\"m\" as=\"n\"/>"),
        "/virtual/scene.xml:2: <alias>: alias source id \"m\" not found (it must come before)"
    );
    assert_eq!(
        at_2("<bsdf type=\"a\" id=\"m\"/><bsdf type=\"b\" id=\"n\"/><alias id=\"m\" as=\"n\"/>"),
        "/virtual/scene.xml:2: <alias>: alias destination id \"n\" already exists (at /virtual/scene.xml:2)"
    );
    assert_eq!(
        at_2(
            "<bsdf type=\"twosided\" id=\"a\">\n<bsdf type=\"mask\" id=\"b\">\n<ref id=\"a\"/></bsdf></bsdf>"
        ),
        "/virtual/scene.xml:4: circular reference: \"a\" -> \"b\" -> \"a\""
    );
    assert_eq!(
        at_2("<bsdf type=\"a\" id=\"self\"><ref id=\"self\"/></bsdf>"),
        "/virtual/scene.xml:2: circular reference: \"self\" -> \"self\""
    );
}

#[test]
fn names_given_twice() {
    assert_eq!(
        at_2(
            "<bsdf type=\"d\"><float name=\"a\" value=\"1\"/>\n<rgb name=\"a\" value=\"1\"/></bsdf>"
        ),
        "/virtual/scene.xml:3: <rgb name=\"a\">: \"a\" is given twice in bsdf 'd' (first at /virtual/scene.xml:2) (in bsdf 'd')"
    );
    assert_eq!(
        at_2(
            "<shape type=\"s\"><bsdf type=\"x\" name=\"m\"/>\n<ref name=\"m\" id=\"q\"/></shape><bsdf type=\"y\" id=\"q\"/>"
        ),
        "/virtual/scene.xml:3: <ref name=\"m\">: \"m\" is given twice in shape 's' (first at /virtual/scene.xml:2) (in shape 's')"
    );
}

#[test]
fn path_only_at_the_root() {
    assert_eq!(
        at_2("<shape type=\"s\"><path value=\".\"/></shape>"),
        "/virtual/scene.xml:2: <path>: <path> can only be a child of the root element (in shape 's')"
    );
    assert_eq!(
        at_2("<path value=\"no/such/folder\"/>"),
        "/virtual/scene.xml:2: <path>: folder \"/virtual/no/such/folder\" not found"
    );
}

#[test]
fn nesting_is_limited() {
    let deep = "<bsdf type=\"b\">".repeat(120) + &"</bsdf>".repeat(120);
    let e = at_2(&deep);
    assert_eq!(
        e,
        "/virtual/scene.xml:2: <bsdf type=\"b\">: objects nested more than 100 deep"
    );
    // Through references.
    let mut chain = String::from("<bsdf type=\"b\" id=\"b0\"/>");
    for i in 1..=120 {
        chain.push_str(&format!(
            "<bsdf type=\"b\" id=\"b{i}\"><ref id=\"b{}\"/></bsdf>",
            i - 1
        ));
    }
    let e = at_2(&chain);
    assert!(
        e.starts_with(
            "/virtual/scene.xml:2: bsdf 'b': objects nested more than 100 deep (through references)"
        ),
        "{e}"
    );
}

#[test]
fn not_utf8_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latin1.xml");
    std::fs::write(
        &path,
        b"<scene version=\"3.0.0\">\n<string name=\"s\" value=\"caf\xe9\"/></scene>",
    )
    .unwrap();
    let e = crate::load::mitsuba::read(&path, &[])
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "{}:2: the file is not UTF-8 text (raylab reads UTF-8 and ASCII scenes)",
            path.display()
        )
    );
    let e = crate::load::mitsuba::read(&dir.path().join("none.xml"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("{}: ", dir.path().join("none.xml").display())),
        "{e}"
    );
}

#[test]
fn an_error_inside_an_include_names_both_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("main.xml"),
        "<scene version=\"3.0.0\">\n\n<include filename=\"inner.xml\"/></scene>",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("inner.xml"),
        "<scene version=\"3.0.0\">\n<float name=\"x\" value=\"nope\"/></scene>",
    )
    .unwrap();
    let e = crate::load::mitsuba::read(&dir.path().join("main.xml"), &[])
        .unwrap_err()
        .to_string();
    let d = dir.path().display();
    assert_eq!(
        e,
        format!(
            "{d}/inner.xml:2: <float name=\"x\">: could not parse floating point value \"nope\" (included from {d}/main.xml:3)"
        )
    );
}

#[test]
fn messages_stay_one_line() {
    // A line break in an attribute is a space (XML), unless written as a
    // character reference: then the message escapes it.
    let e = error_with(
        &scene("<shape type=\"a&#10;b\"><float name=\"x&#10;y\" value=\"$x\"/></shape>"),
        &[("x", "z&#10;")],
    );
    assert_eq!(
        e,
        "/virtual/scene.xml:1: <float name=\"x\\ny\">: could not parse floating point value \"z&#10;\" (in shape 'a\\nb')"
    );
}
