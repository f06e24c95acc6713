//! The `serialized` reader on files written here (versions 3 and 4, single
//! and double precision, with and without normals, texture coordinates and
//! colours, several shapes), every error it gives, and, when a checkout of
//! `mitsuba-renderer/mitsuba-data` is named by `RAYLAB_MITSUBA_DATA`, every
//! `.serialized` file of it.

use std::io::{Read, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::ZlibEncoder;

use crate::memory::Ledger;

use super::super::{MitsubaMesh, parse_serialized, read_serialized};

const FILE: &str = "/virtual/mesh.serialized";

/// A shape to write.
#[derive(Clone, Default)]
struct Shape {
    name: String,
    positions: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    uvs: Option<Vec<[f64; 2]>>,
    colors: Option<Vec<[f64; 3]>>,
    indices: Vec<[u32; 3]>,
    double: bool,
}

/// A shape's uncompressed stream.
fn raw(shape: &Shape, version: u16) -> Vec<u8> {
    let mut flags = 0u32;
    if shape.normals.is_some() {
        flags |= 1;
    }
    if shape.uvs.is_some() {
        flags |= 2;
    }
    if shape.colors.is_some() {
        flags |= 8;
    }
    flags |= if shape.double { 0x2000 } else { 0x1000 };
    let mut out = flags.to_le_bytes().to_vec();
    if version == 4 {
        out.extend(shape.name.bytes());
        out.push(0);
    }
    out.extend((shape.positions.len() as u64).to_le_bytes());
    out.extend((shape.indices.len() as u64).to_le_bytes());
    let mut floats = |values: &mut dyn Iterator<Item = f64>| {
        for v in values {
            if shape.double {
                out.extend(v.to_le_bytes());
            } else {
                out.extend((v as f32).to_le_bytes());
            }
        }
    };
    floats(&mut shape.positions.iter().flatten().copied());
    if let Some(n) = &shape.normals {
        floats(&mut n.iter().flatten().copied());
    }
    if let Some(t) = &shape.uvs {
        floats(&mut t.iter().flatten().copied());
    }
    if let Some(c) = &shape.colors {
        floats(&mut c.iter().flatten().copied());
    }
    for i in shape.indices.iter().flatten() {
        out.extend(i.to_le_bytes());
    }
    out
}

fn zlib(data: &[u8]) -> Vec<u8> {
    let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
    z.write_all(data).unwrap();
    z.finish().unwrap()
}

/// A file of `streams` (compressed shape streams), each with its header,
/// then the dictionary of offsets and the count.
fn file(version: u16, streams: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for s in streams {
        offsets.push(out.len() as u64);
        out.extend(0x041Cu16.to_le_bytes());
        out.extend(version.to_le_bytes());
        out.extend(s);
    }
    for o in offsets {
        if version == 3 {
            out.extend((o as u32).to_le_bytes());
        } else {
            out.extend(o.to_le_bytes());
        }
    }
    out.extend((streams.len() as u32).to_le_bytes());
    out
}

fn write(version: u16, shapes: &[Shape]) -> Vec<u8> {
    let streams: Vec<Vec<u8>> = shapes.iter().map(|s| zlib(&raw(s, version))).collect();
    file(version, &streams)
}

fn read(bytes: &[u8], index: i64) -> MitsubaMesh {
    match parse_serialized(bytes, Path::new(FILE), index, &Ledger::unlimited()) {
        Ok(m) => m,
        Err(e) => panic!("unexpected error: {e}"),
    }
}

fn error(bytes: &[u8], index: i64) -> String {
    match parse_serialized(bytes, Path::new(FILE), index, &Ledger::unlimited()) {
        Ok(_) => panic!("no error"),
        Err(e) => {
            let m = e.to_string();
            assert!(!m.contains('\n'), "not one line: {m}");
            assert!(m.starts_with(FILE), "does not name the file: {m}");
            m
        }
    }
}

/// A shape of `n` vertices (and `n - 2` fanned triangles), with what
/// `with` asks for (`n`ormals, `u`vs, `c`olours), values distinct per shape
/// through `seed`.
fn shape(n: usize, seed: f64, with: &str, double: bool) -> Shape {
    let p = |i: usize, k: usize| seed + i as f64 * 1.25 + k as f64 * 0.1 + 1e-9;
    Shape {
        name: format!("shape {seed}"),
        positions: (0..n).map(|i| [p(i, 0), p(i, 1), -p(i, 2)]).collect(),
        normals: with
            .contains('n')
            .then(|| (0..n).map(|i| [0.0, 1.0, i as f64 / 8.0]).collect()),
        uvs: with.contains('u').then(|| {
            (0..n)
                .map(|i| [i as f64 / 4.0, 1.0 - seed / 16.0])
                .collect()
        }),
        colors: with
            .contains('c')
            .then(|| (0..n).map(|i| [0.5, i as f64 / 10.0, seed]).collect()),
        indices: (1..n as u32 - 1).map(|i| [0, i, i + 1]).collect(),
        double,
    }
}

/// Every value of `m` is `s`'s (as `f32`).
fn check(m: &MitsubaMesh, s: &Shape, version: u16) {
    let f3 = |v: &Vec<[f64; 3]>| v.iter().map(|a| a.map(|x| x as f32)).collect::<Vec<_>>();
    assert_eq!(m.positions, f3(&s.positions));
    assert_eq!(m.normals, s.normals.as_ref().map(f3));
    assert_eq!(m.colors, s.colors.as_ref().map(f3));
    assert_eq!(
        m.uvs,
        s.uvs
            .as_ref()
            .map(|v| v.iter().map(|a| a.map(|x| x as f32)).collect::<Vec<_>>())
    );
    assert_eq!(m.indices, s.indices);
    assert_eq!(m.name, if version == 4 { s.name.as_str() } else { "" });
    assert!(m.vertex_attributes.is_empty() && m.face_attributes.is_empty());
}

#[test]
fn every_layout_round_trips_in_both_versions() {
    for version in [3, 4] {
        for with in ["", "n", "u", "c", "nu", "nc", "uc", "nuc"] {
            for double in [false, true] {
                let s = shape(5, 2.0, with, double);
                let m = read(&write(version, std::slice::from_ref(&s)), 0);
                check(&m, &s, version);
            }
        }
    }
}

#[test]
fn shape_index_picks_a_shape_through_the_dictionary() {
    for version in [3, 4] {
        let shapes = [
            shape(3, 0.0, "nu", false),
            shape(7, 1.0, "", true),
            shape(4, 2.0, "nuc", false),
        ];
        let bytes = write(version, &shapes);
        for (i, s) in shapes.iter().enumerate() {
            check(&read(&bytes, i as i64), s, version);
        }
        let e = error(&bytes, 3);
        assert!(
            e.ends_with("shape index 3 out of range (the file holds 3 shapes, 0 to 2)"),
            "{e}"
        );
    }
}

#[test]
fn a_file_on_disk_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.serialized");
    let shapes = [shape(3, 0.0, "n", false), shape(4, 1.0, "u", false)];
    std::fs::write(&path, write(4, &shapes)).unwrap();
    check(
        &read_serialized(&path, 1, &Ledger::unlimited()).unwrap(),
        &shapes[1],
        4,
    );
}

#[test]
fn malformed_files_give_one_line_errors() {
    let good = write(4, &[shape(4, 0.0, "nu", false), shape(3, 1.0, "", false)]);
    let expect = |bytes: &[u8], index: i64, want: &str| {
        let e = error(bytes, index);
        assert!(e.contains(want), "{e}\n  wanted: {want}");
    };
    expect(&good, -1, "shape index -1 is negative");
    expect(
        b"\x1c\x04",
        0,
        "not a Mitsuba serialized mesh (shorter than its 4-byte header)",
    );
    expect(
        b"ply\nformat",
        0,
        "file format identifier 0x6c70, not 0x041c",
    );
    let mut v = good.clone();
    v[2] = 5;
    expect(
        &v,
        0,
        "serialized version 5 (written by Mitsuba after 3.9.1) is not supported",
    );
    v[2] = 2;
    expect(&v, 0, "incompatible serialized file version 2");
    // The compressed data cut short, or corrupted.
    let one = write(4, &[shape(40, 0.0, "nu", false)]);
    expect(
        &one[..one.len() / 2],
        0,
        "shape 0: the compressed data ends early (reading the",
    );
    let mut bad = one.clone();
    bad[4] ^= 0xff;
    expect(
        &bad,
        0,
        "shape 0: corrupt compressed data (reading the flags)",
    );
    // A stream that holds less than its header says.
    let mut s = shape(4, 0.0, "", false);
    let mut short = raw(&s, 4);
    short.truncate(short.len() - 12);
    expect(
        &file(4, &[zlib(&short)]),
        0,
        "shape 0: the compressed data ends early (reading the indices)",
    );
    // Indices out of range.
    s.indices[1] = [0, 4, 1];
    expect(
        &write(4, &[s]),
        0,
        "shape 0: triangle 1: vertex index 4 out of range (4 vertices)",
    );
    // A zip bomb's header: counts far beyond what the stream can hold.
    let mut bomb = 0x1000u32.to_le_bytes().to_vec();
    bomb.push(0);
    bomb.extend((1u64 << 27).to_le_bytes());
    bomb.extend((1u64 << 27).to_le_bytes());
    expect(
        &file(4, &[zlib(&bomb)]),
        0,
        "shape 0: 134217728 vertices and 134217728 triangles need 3221225472 bytes of data, more than the",
    );
    let mut bomb = 0x1000u32.to_le_bytes().to_vec();
    bomb.push(0);
    bomb.extend(u64::MAX.to_le_bytes());
    bomb.extend(0u64.to_le_bytes());
    expect(
        &file(4, &[zlib(&bomb)]),
        0,
        "shape 0: 18446744073709551615 vertices and 0 triangles need",
    );
    // The dictionary.
    let mut d = good.clone();
    let n = d.len();
    d[n - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    expect(
        &d,
        1,
        "shape 1: its offset lies before the start of the file (the dictionary claims 4294967295 shapes)",
    );
    let mut d = good.clone();
    d[n - 12..n - 4].copy_from_slice(&u64::MAX.to_le_bytes());
    expect(
        &d,
        1,
        "shape 1: offset 18446744073709551615 lies beyond the end of the file",
    );
    // A name without its end.
    let mut name = 0x1000u32.to_le_bytes().to_vec();
    name.extend(std::iter::repeat_n(b'a', 70_000));
    expect(
        &file(4, &[zlib(&name)]),
        0,
        "shape 0: a name longer than 65536 bytes",
    );
}

/// Every `.serialized` file of a checkout of `mitsuba-renderer/mitsuba-data`
/// named by `RAYLAB_MITSUBA_DATA`: every shape of it is read and its counts
/// compared with its own header, decompressed here independently of the
/// reader; a file that is no serialized mesh (Mitsuba's test of its
/// annotated streams) is refused. Skipped without the variable.
#[test]
fn mitsuba_data_serialized_files() {
    let Some(root) = std::env::var_os("RAYLAB_MITSUBA_DATA") else {
        eprintln!("RAYLAB_MITSUBA_DATA not set: Mitsuba's serialized files not read");
        return;
    };
    let files = super::meshes::files_with_extension(Path::new(&root), "serialized");
    assert!(!files.is_empty());
    let mut shapes_read = 0;
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        if bytes[..2] != [0x1c, 0x04] {
            let e = read_serialized(path, 0, &Ledger::unlimited())
                .unwrap_err()
                .to_string();
            assert!(e.contains("not a Mitsuba serialized mesh"), "{e}");
            continue;
        }
        let version = u16::from_le_bytes([bytes[2], bytes[3]]);
        let n = bytes.len();
        let count = u32::from_le_bytes(bytes[n - 4..].try_into().unwrap()) as usize;
        for i in 0..count {
            let offset = if version == 3 {
                let at = n - 4 * (count - i + 1);
                u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize
            } else {
                let at = n - 8 * (count - i) - 4;
                u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize
            };
            let mut z = flate2::read::ZlibDecoder::new(&bytes[offset + 4..]);
            let mut head = vec![0u8; 4];
            z.read_exact(&mut head).unwrap();
            if version == 4 {
                let mut c = [1u8];
                while c[0] != 0 {
                    z.read_exact(&mut c).unwrap();
                }
            }
            let mut counts = [0u8; 16];
            z.read_exact(&mut counts).unwrap();
            let v = u64::from_le_bytes(counts[..8].try_into().unwrap());
            let f = u64::from_le_bytes(counts[8..].try_into().unwrap());
            let m = match read_serialized(path, i as i64, &Ledger::unlimited()) {
                Ok(m) => m,
                Err(e) => panic!("{e}"),
            };
            assert_eq!((m.positions.len() as u64, m.indices.len() as u64), (v, f));
            let flags = u32::from_le_bytes(head.try_into().unwrap());
            assert_eq!(m.normals.is_some(), flags & 1 != 0);
            assert_eq!(m.uvs.is_some(), flags & 2 != 0);
            eprintln!(
                "{} shape {i}: {v} vertices, {f} triangles, flags {flags:#x}",
                path.display()
            );
            shapes_read += 1;
        }
    }
    eprintln!("{shapes_read} shapes read");
}
