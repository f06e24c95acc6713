//! The `ply` reader on PLY files written here (binary both ways and ASCII,
//! with known contents), every error it gives, and, when a checkout of
//! `mitsuba-renderer/mitsuba-data` is named by `RAYLAB_MITSUBA_DATA`, every
//! PLY file of it.

use std::path::Path;

use crate::memory::{Ledger, MemoryBudget};

use super::super::{MitsubaMesh, parse_ply, read_ply};

const FILE: &str = "/virtual/mesh.ply";

fn ply(bytes: &[u8], flip: bool) -> MitsubaMesh {
    match parse_ply(bytes, Path::new(FILE), flip, &Ledger::unlimited()) {
        Ok(m) => m,
        Err(e) => panic!("unexpected error: {e}"),
    }
}

fn ply_error(bytes: &[u8]) -> String {
    match parse_ply(bytes, Path::new(FILE), false, &Ledger::unlimited()) {
        Ok(_) => panic!("no error for {}", String::from_utf8_lossy(bytes)),
        Err(e) => {
            let m = e.to_string();
            assert!(!m.contains('\n'), "not one line: {m}");
            assert!(m.starts_with(FILE), "does not name the file: {m}");
            m
        }
    }
}

/// One value of a record: written as text or as bytes of its type.
#[derive(Clone, Copy)]
enum V {
    F32(f32),
    F64(f64),
    U8(u8),
    I32(i32),
    I16(i16),
}

impl V {
    fn bytes(self, big: bool) -> Vec<u8> {
        let mut b = match self {
            V::F32(x) => x.to_le_bytes().to_vec(),
            V::F64(x) => x.to_le_bytes().to_vec(),
            V::U8(x) => vec![x],
            V::I32(x) => x.to_le_bytes().to_vec(),
            V::I16(x) => x.to_le_bytes().to_vec(),
        };
        if big {
            b.reverse();
        }
        b
    }

    fn text(self) -> String {
        match self {
            V::F32(x) => x.to_string(),
            V::F64(x) => x.to_string(),
            V::U8(x) => x.to_string(),
            V::I32(x) => x.to_string(),
            V::I16(x) => x.to_string(),
        }
    }
}

/// A PLY file: `header` (the lines between `format` and `end_header`) and
/// the records, in `format` (`ascii`, `binary_little_endian`,
/// `binary_big_endian`).
fn write(format: &str, header: &str, records: &[Vec<V>]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by raylab's tests\n{header}end_header\n"
    )
    .into_bytes();
    for r in records {
        if format == "ascii" {
            let line: Vec<String> = r.iter().map(|v| v.text()).collect();
            out.extend(line.join(" ").bytes());
            out.push(b'\n');
        } else {
            for v in r {
                out.extend(v.bytes(format == "binary_big_endian"));
            }
        }
    }
    out
}

/// The header of the full test mesh: positions, normals, uvs, uchar
/// colours, a one-channel and a three-channel attribute, and faces with a
/// one-channel and a three-channel attribute.
const FULL_HEADER: &str = "element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
property uchar red
property uchar green
property uchar blue
property float temp_0
property double dir_x
property double dir_y
property double dir_z
element face 2
property list uchar int vertex_indices
property float weight_0
property float c_r
property float c_g
property float c_b
";

fn full_records() -> Vec<Vec<V>> {
    let mut r = Vec::new();
    for i in 0..4 {
        let f = i as f32;
        r.push(vec![
            V::F32(f),
            V::F32(f * 2.0 - 1.0),
            V::F32(-f),
            V::F32(0.0),
            V::F32(1.0),
            V::F32(f / 4.0),
            V::F32(f / 3.0),
            V::F32(0.25 + f / 8.0),
            V::U8(255),
            V::U8(128),
            V::U8(i as u8 * 10),
            V::F32(100.0 + f),
            V::F64(0.5 * i as f64),
            V::F64(-1.5),
            V::F64(1e-3),
        ]);
    }
    r.push(vec![
        V::U8(3),
        V::I32(0),
        V::I32(1),
        V::I32(2),
        V::F32(0.5),
        V::F32(0.1),
        V::F32(0.2),
        V::F32(0.3),
    ]);
    r.push(vec![
        V::U8(3),
        V::I32(0),
        V::I32(2),
        V::I32(3),
        V::F32(2.5),
        V::F32(0.4),
        V::F32(0.5),
        V::F32(0.6),
    ]);
    r
}

fn srgb(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-6 * (1.0 + b.abs())
}

fn check_full(m: &MitsubaMesh, flip: bool) {
    assert_eq!(m.positions.len(), 4);
    let normals = m.normals.as_ref().unwrap();
    let uvs = m.uvs.as_ref().unwrap();
    let colors = m.colors.as_ref().unwrap();
    for i in 0..4 {
        let f = i as f32;
        assert_eq!(m.positions[i], [f, f * 2.0 - 1.0, -f]);
        assert_eq!(normals[i], [0.0, 1.0, f / 4.0]);
        let v = 0.25 + f / 8.0;
        assert_eq!(uvs[i], [f / 3.0, if flip { 1.0 - v } else { v }]);
        let want = [1.0, srgb(128.0 / 255.0), srgb(i as f32 * 10.0 / 255.0)];
        for c in 0..3 {
            assert!(
                close(colors[i][c], want[c]),
                "colour {i}: {:?} vs {want:?}",
                colors[i]
            );
        }
    }
    let names: Vec<(&str, usize)> = m
        .vertex_attributes
        .iter()
        .map(|a| (a.name.as_str(), a.channels))
        .collect();
    assert_eq!(
        names,
        [("vertex_color", 3), ("vertex_temp", 1), ("vertex_dir", 3)]
    );
    let color = m.attribute("vertex_color").unwrap();
    assert_eq!(color.values.len(), 12);
    assert!(close(color.values[4], srgb(128.0 / 255.0)));
    assert_eq!(
        m.attribute("vertex_temp").unwrap().values,
        [100.0, 101.0, 102.0, 103.0]
    );
    assert_eq!(
        m.attribute("vertex_dir").unwrap().values,
        [
            0.0, -1.5, 1e-3, 0.5, -1.5, 1e-3, 1.0, -1.5, 1e-3, 1.5, -1.5, 1e-3
        ]
    );
    assert_eq!(m.indices, [[0, 1, 2], [0, 2, 3]]);
    let names: Vec<(&str, usize)> = m
        .face_attributes
        .iter()
        .map(|a| (a.name.as_str(), a.channels))
        .collect();
    assert_eq!(names, [("face_weight", 1), ("face_c_color", 3)]);
    assert_eq!(m.attribute("face_weight").unwrap().values, [0.5, 2.5]);
    assert_eq!(
        m.attribute("face_c_color").unwrap().values,
        [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    );
    // The uchar colours are warned about, as Mitsuba does.
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    assert!(
        m.warnings[0].contains("\"vertex_color\" has integer fields"),
        "{:?}",
        m.warnings
    );
}

#[test]
fn binary_little_endian_round_trip() {
    let m = ply(
        &write("binary_little_endian", FULL_HEADER, &full_records()),
        false,
    );
    check_full(&m, false);
    assert_eq!(m.name, "");
}

#[test]
fn binary_big_endian_round_trip() {
    let m = ply(
        &write("binary_big_endian", FULL_HEADER, &full_records()),
        false,
    );
    check_full(&m, false);
}

#[test]
fn ascii_round_trip_and_flip_tex_coords() {
    let file = write("ascii", FULL_HEADER, &full_records());
    check_full(&ply(&file, false), false);
    check_full(&ply(&file, true), true);
}

#[test]
fn a_file_on_disk_is_read_and_its_size_checked_against_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("full.ply");
    std::fs::write(
        &path,
        write("binary_little_endian", FULL_HEADER, &full_records()),
    )
    .unwrap();
    check_full(
        &read_ply(&path, false, &Ledger::unlimited()).unwrap(),
        false,
    );
    let tight = Ledger::new(MemoryBudget::bytes(100));
    let e = read_ply(&path, false, &tight).unwrap_err().to_string();
    assert!(e.contains("more than --max-memory"), "{e}");
    let e = read_ply(&dir.path().join("missing.ply"), false, &Ledger::unlimited())
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.ply"), "{e}");
}

const TRIANGLE: &str = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";

fn triangle_records() -> Vec<Vec<V>> {
    vec![
        vec![V::F32(0.0), V::F32(0.0), V::F32(0.0)],
        vec![V::F32(1.0), V::F32(0.0), V::F32(0.0)],
        vec![V::F32(0.0), V::F32(1.0), V::F32(0.0)],
    ]
}

/// The triangle with `extra` vertex properties (values `vals` for every
/// vertex) and one face.
fn triangle_with(extra: &str, vals: &[V]) -> Vec<Vec<V>> {
    let _ = extra;
    let mut r = triangle_records();
    for v in &mut r {
        v.extend_from_slice(vals);
    }
    r.push(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(2)]);
    r
}

#[test]
fn texture_coordinates_under_their_other_names() {
    for (u, v) in [("texture_u", "texture_v"), ("s", "t")] {
        let header = format!(
            "{TRIANGLE}property float {u}\nproperty float {v}\nelement face 1\nproperty list uchar int vertex_index\n"
        );
        let records = triangle_with("", &[V::F32(0.25), V::F32(0.75)]);
        let m = ply(&write("binary_little_endian", &header, &records), false);
        assert_eq!(m.uvs.unwrap(), [[0.25, 0.75]; 3]);
        let m = ply(&write("ascii", &header, &records), true);
        assert_eq!(m.uvs.unwrap(), [[0.25, 0.25]; 3]);
        assert!(m.vertex_attributes.is_empty());
    }
}

#[test]
fn a_mesh_without_normals_uvs_or_faces() {
    let m = ply(&write("ascii", TRIANGLE, &triangle_records()), false);
    assert_eq!(m.positions.len(), 3);
    assert!(m.normals.is_none() && m.uvs.is_none() && m.colors.is_none());
    assert!(m.indices.is_empty());
    // Normals need all three of nx, ny, nz.
    let header = format!("{TRIANGLE}property float nx\nproperty float ny\n");
    let m = ply(
        &write(
            "ascii",
            &header,
            &triangle_with("", &[V::F32(0.0), V::F32(1.0)])[..3],
        ),
        false,
    );
    assert!(m.normals.is_none());
}

#[test]
fn rgba_colours_integer_positions_and_half_values() {
    let header = format!(
        "{TRIANGLE}property uchar r\nproperty uchar g\nproperty uchar b\nproperty uchar a\nproperty short h_x\nproperty half q_0\nelement face 1\nproperty list uchar uint vertex_indices\n"
    );
    let records = triangle_with(
        "",
        &[
            V::U8(0),
            V::U8(51),
            V::U8(255),
            V::U8(255),
            V::I16(32767),
            V::U8(0),
        ],
    );
    // (the half is written as two bytes below: 0x3c00 = 1.0)
    let mut file = write("binary_little_endian", &header, &[]);
    for r in &records[..3] {
        for v in &r[..7] {
            file.extend(v.bytes(false));
        }
        file.extend(V::I16(32767).bytes(false));
        file.extend(0x3c00u16.to_le_bytes());
    }
    file.extend([3]);
    file.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let m = ply(&file, false);
    let color = m.attribute("vertex_color").unwrap();
    assert_eq!(color.channels, 4);
    assert!(close(color.values[1], srgb(0.2)));
    assert!(close(color.values[2], 1.0) && close(color.values[3], 1.0));
    assert_eq!(m.colors.as_ref().unwrap()[0][0], 0.0);
    // An integer property read as a float is normalised and sRGB-decoded.
    assert!(close(m.attribute("vertex_h").unwrap().values[0], 1.0));
    assert_eq!(m.attribute("vertex_q").unwrap().values, [1.0; 3]);
    // The ASCII half is rounded to half precision.
    let header = format!("{TRIANGLE}property float16 q_0\n");
    let m = ply(
        &write("ascii", &header, &triangle_with("", &[V::F32(0.1)])[..3]),
        false,
    );
    assert_eq!(m.attribute("vertex_q").unwrap().values[0], 0.099975586);
    let _ = records;
}

#[test]
fn unknown_elements_are_skipped_with_a_warning() {
    // A binary element with lists of other lengths between vertices and faces.
    let header = format!(
        "{TRIANGLE}element edge 2\nproperty list uchar int vertices\nproperty uchar flag\nelement face 1\nproperty list uchar int vertex_indices\n"
    );
    let mut records = triangle_records();
    records.push(vec![V::U8(2), V::I32(0), V::I32(1), V::U8(7)]);
    records.push(vec![
        V::U8(5),
        V::I32(0),
        V::I32(1),
        V::I32(2),
        V::I32(0),
        V::I32(1),
        V::U8(7),
    ]);
    records.push(vec![V::U8(3), V::I32(2), V::I32(1), V::I32(0)]);
    for format in ["binary_little_endian", "ascii"] {
        let m = ply(&write(format, &header, &records), false);
        assert_eq!(m.indices, [[2, 1, 0]]);
        assert_eq!(
            m.warnings,
            [format!("{FILE}: skipping unknown element \"edge\"")]
        );
    }
}

#[test]
fn ignored_properties_are_warned_about_as_mitsuba_does() {
    let header = format!(
        "{TRIANGLE}property float confidence\nproperty float ab_x\nproperty float ab_y\nproperty float long_xy\nproperty float k_q\n"
    );
    let vals = [
        V::F32(1.0),
        V::F32(2.0),
        V::F32(3.0),
        V::F32(4.0),
        V::F32(5.0),
    ];
    let m = ply(
        &write("ascii", &header, &triangle_with("", &vals)[..3]),
        false,
    );
    assert!(m.vertex_attributes.is_empty());
    let w = m.warnings.join("\n");
    assert!(
        w.contains(
            "attributes without postfix are not handled for now: attribute \"confidence\" ignored"
        ),
        "{w}"
    );
    assert!(
        w.contains(
            "attribute must have either 1 or 3 fields (had 2): attribute \"vertex_ab\" ignored"
        ),
        "{w}"
    );
    assert!(
        w.contains("attribute postfix can only be one letter long: attribute \"long_xy\" ignored"),
        "{w}"
    );
    assert!(w.contains("attribute can't start with postfix q"), "{w}");
}

/// The error of `file`, which must contain `want`.
fn expect(file: &[u8], want: &str) {
    let e = ply_error(file);
    assert!(e.contains(want), "{e}\n  wanted: {want}");
}

#[test]
fn malformed_files_give_one_line_errors() {
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    let header = format!("{TRIANGLE}{face}");
    let good = |face: Vec<V>| {
        let mut r = triangle_records();
        r.push(face);
        r
    };
    // Quads (and any list not of three) are refused, binary and ASCII.
    let quad = good(vec![V::U8(4), V::I32(0), V::I32(1), V::I32(2), V::I32(0)]);
    for format in ["binary_little_endian", "ascii"] {
        expect(
            &write(format, &header, &quad),
            "face 0: list \"vertex_indices\" has 4 entries, not 3 (Mitsuba's ply reads triangles only)",
        );
    }
    let out_of_range = good(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(3)]);
    expect(
        &write("binary_little_endian", &header, &out_of_range),
        "face 0: vertex index 3 out of range (3 vertices)",
    );
    let negative = good(vec![V::U8(3), V::I32(0), V::I32(-1), V::I32(2)]);
    expect(
        &write("ascii", &header, &negative),
        "face 0: vertex index 4294967295 out of range (3 vertices)",
    );
    // Truncated: records beyond the bytes left are refused before they are
    // read; ASCII values (and a skipped element's lists) can still run out.
    let full = write(
        "binary_little_endian",
        &header,
        &good(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(2)]),
    );
    expect(
        &full[..full.len() - 2],
        "element \"face\": 1 records of at least 13 bytes each, but 11 bytes at most follow",
    );
    let ascii = write(
        "ascii",
        &header,
        &good(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(2)]),
    );
    let mut cut = ascii[..ascii.len() - 3].to_vec();
    cut.extend(b"      \n");
    expect(&cut, "face 0: the file ends early");
    let skipped = format!("{TRIANGLE}element edge 1\nproperty list uchar int vertices\n");
    let mut records = triangle_records();
    records.push(vec![V::U8(200), V::I32(0), V::I32(1)]);
    expect(
        &write("binary_little_endian", &skipped, &records),
        "edge 0: the file ends early",
    );
    // Trailing content.
    let mut long = full.clone();
    long.extend([0, 0]);
    expect(
        &long,
        "invalid file: 2 bytes of trailing content after the last element",
    );
    let mut long = ascii.clone();
    long.extend(b"7\n");
    expect(&long, "trailing tokens after the last element");
    // A count far beyond the bytes present: refused before any allocation.
    let huge = format!(
        "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n{face}"
    );
    expect(
        &write("binary_little_endian", &huge, &triangle_records()),
        "element \"vertex\": 4000000000 records of at least 12 bytes each, but 36 bytes at most follow",
    );
    expect(
        &write("ascii", &huge, &triangle_records()),
        "element \"vertex\": 4000000000 records of at least 3 values each",
    );
    let huge = format!(
        "{TRIANGLE}element face 18446744073709551615\nproperty list uchar int vertex_indices\n"
    );
    expect(
        &write("binary_little_endian", &huge, &triangle_records()),
        "element \"face\": 18446744073709551615 records",
    );
    // A property-less element of any count is nothing to read.
    let empty = format!("{TRIANGLE}element nothing 18446744073709551615\n");
    assert_eq!(
        ply(
            &write("binary_little_endian", &empty, &triangle_records()),
            false
        )
        .positions
        .len(),
        3
    );
    // Values.
    let bad = good(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(2)]);
    let mut text = write("ascii", &header, &bad);
    let at = text.len() - 10;
    text[at] = b'x';
    expect(
        &text,
        "vertex 2: could not parse \"float\" value \"x\" for property \"z\"",
    );
    expect(
        &write(
            "ascii",
            &header,
            &good(vec![V::I32(300), V::I32(0), V::I32(1), V::I32(2)]),
        ),
        "face 0: could not parse \"uchar\" value \"300\" for property \"vertex_indices\"",
    );
    let mut nan = triangle_records();
    nan[1][1] = V::F32(f32::NAN);
    nan.push(vec![V::U8(3), V::I32(0), V::I32(1), V::I32(2)]);
    expect(
        &write("binary_little_endian", &header, &nan),
        "vertex 1: position is not finite",
    );
    expect(
        &write("ascii", &header, &nan),
        "vertex 1: could not parse \"float\" value \"NaN\" for property \"y\"",
    );
    // The structure.
    expect(
        &write(
            "ascii",
            "element vertex 1\nproperty float x\nproperty float y\n",
            &[vec![V::F32(0.0), V::F32(0.0)]],
        ),
        "the vertex element has no property \"z\"",
    );
    expect(
        &write(
            "ascii",
            &format!("{TRIANGLE}element face 0\nproperty list uchar int corners\n"),
            &triangle_records(),
        ),
        "the face element has no vertex_index or vertex_indices list",
    );
    expect(
        &write("ascii", &format!("{TRIANGLE}{TRIANGLE}"), &[]),
        "more than one \"vertex\" element",
    );
    expect(
        &write(
            "ascii",
            &format!(
                "{}property float r\nproperty float g\nproperty float b\nproperty float color_x\nproperty float color_y\nproperty float color_z\n",
                TRIANGLE.replace("vertex 3", "vertex 0")
            ),
            &[],
        ),
        "attribute \"vertex_color\" already exists",
    );
}

#[test]
fn malformed_headers_give_one_line_errors() {
    let cases: [(&[u8], &str); 13] = [
        (
            b"",
            "invalid PLY header: the file ends before \"end_header\"",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 0\n",
            "the file ends before \"end_header\"",
        ),
        (
            b"ply\nformat binary 1.0\nend_header\n",
            "invalid PLY header: unknown format \"binary\"",
        ),
        (
            b"ply\nformat ascii 2.0\nend_header\n",
            "PLY file has unknown version number \"2.0\"",
        ),
        (
            b"ply\nformat ascii\nend_header\n",
            "missing version number after \"format\"",
        ),
        (
            b"format ascii 1.0\nend_header\n",
            "\"format\" before \"ply\" tag",
        ),
        (b"ply\nply\n", "duplicate \"ply\" tag"),
        (
            b"ply\nend_header\n",
            "invalid PLY file: no header information",
        ),
        (
            b"ply\nformat ascii 1.0\nobj_info x\nend_header\n",
            "unknown token \"obj_info\"",
        ),
        (
            b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            "encountered \"property\" before \"element\"",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
            "unknown format type \"quad\"",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
            "element \"vertex\": count \"-1\" is not a number",
        ),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x y\nend_header\n",
            "excess token \"y\" after \"property\"",
        ),
    ];
    for (file, want) in cases {
        expect(file, want);
    }
}

/// The element counts a PLY header declares (read here independently of
/// the reader: `element NAME COUNT` lines up to `end_header`).
fn header_counts(bytes: &[u8]) -> (u64, u64) {
    let end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
    let text = String::from_utf8_lossy(&bytes[..end]);
    let (mut v, mut f) = (0, 0);
    for line in text.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() == 3 && t[0] == "element" {
            match t[1] {
                "vertex" => v = t[2].parse().unwrap(),
                "face" => f = t[2].parse().unwrap(),
                _ => {}
            }
        }
    }
    (v, f)
}

/// Every PLY file of a checkout of `mitsuba-renderer/mitsuba-data` named by
/// `RAYLAB_MITSUBA_DATA` is read, its counts compared with its header's;
/// skipped without the variable.
#[test]
fn mitsuba_data_ply_files() {
    let Some(root) = std::env::var_os("RAYLAB_MITSUBA_DATA") else {
        eprintln!("RAYLAB_MITSUBA_DATA not set: Mitsuba's PLY files not read");
        return;
    };
    let files = super::meshes::files_with_extension(Path::new(&root), "ply");
    assert!(
        !files.is_empty(),
        "no .ply files under {}",
        Path::new(&root).display()
    );
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let (v, f) = header_counts(&bytes);
        let m = match read_ply(path, false, &Ledger::unlimited()) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(m.positions.len() as u64, v, "{}", path.display());
        assert_eq!(m.indices.len() as u64, f, "{}", path.display());
        for a in &m.vertex_attributes {
            assert_eq!(a.values.len() as u64, v * a.channels as u64, "{}", a.name);
        }
        for a in &m.face_attributes {
            assert_eq!(a.values.len() as u64, f * a.channels as u64, "{}", a.name);
        }
        eprintln!(
            "{}: {v} vertices, {f} triangles, attributes {:?}",
            path.display(),
            m.vertex_attributes
                .iter()
                .chain(&m.face_attributes)
                .map(|a| &a.name)
                .collect::<Vec<_>>()
        );
    }
    eprintln!("{} PLY files read", files.len());
}
