//! OpenVDB files written by OpenVDB itself (`tools/make_vdb_fixtures.py`:
//! Blosc-compressed, with mask compression; floats, half floats and
//! doubles; scale-translate and affine maps; tiles; two grids in a file)
//! read voxel for voxel as OpenVDB reads them back, and files raylab cannot
//! use refused in one line.

use std::path::{Path, PathBuf};

use raylab::load::vdb::{VdbGrid, parse_vdb, read_vdb};
use raylab::memory::{Ledger, MemoryBudget};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/vdb")
        .join(name)
}

fn check_against_openvdb(name: &str) -> VdbGrid {
    let path = fixture(name);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixture(&format!("{name}.json"))).unwrap()).unwrap();
    let read = read_vdb(&path, None, &Ledger::unlimited()).unwrap();
    assert_eq!(read.name, json["grid"].as_str().unwrap(), "{name}");
    let voxels = json["voxels"].as_array().unwrap();
    assert!(voxels.len() >= 400, "{name}");
    let mut nonzero = 0;
    for v in voxels {
        let v: Vec<f64> = v
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let p = [v[0] as i32, v[1] as i32, v[2] as i32];
        let want = v[3] as f32;
        assert_eq!(read.grid.voxel(p), want, "{name}: voxel {p:?}");
        nonzero += usize::from(want != 0.0);
    }
    assert!(
        nonzero > 40,
        "{name}: only {nonzero} voxels checked hold a value"
    );
    // The transform: row vectors in the file's convention.
    let rows = json["index_to_world_rows"].as_array().unwrap();
    let row = |i: usize| -> glam::Vec3 {
        let r: Vec<f32> = rows[i]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        glam::Vec3::new(r[0], r[1], r[2])
    };
    let m = read.index_to_world;
    for (k, axis) in [glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z]
        .iter()
        .enumerate()
    {
        let got = m.transform_vector3(*axis);
        assert!(
            (got - row(k)).abs().max_element() < 1e-6,
            "{name}: axis {k}: {got} vs {}",
            row(k)
        );
    }
    assert!(
        (glam::Vec3::from(m.translation) - row(3))
            .abs()
            .max_element()
            < 1e-6
    );
    read
}

#[test]
fn grids_read_as_openvdb_reads_them() {
    let puff = check_against_openvdb("puff.vdb");
    // Trilinear between voxels, 0 beyond the last one.
    let g = &puff.grid;
    let (lo, hi) = g.voxels();
    let at = [lo[0] + 11, lo[1] + 12, lo[2] + 10];
    let (a, b) = (g.voxel(at), g.voxel([at[0] + 1, at[1], at[2]]));
    let p = glam::Vec3A::new(at[0] as f32 + 0.25, at[1] as f32, at[2] as f32);
    assert!((g.eval(p) - (0.75 * a + 0.25 * b)).abs() < 1e-6);
    let outside = glam::Vec3A::new(hi[0] as f32 + 1.5, 0.0, 0.0);
    assert_eq!(g.eval(outside), 0.0);
    check_against_openvdb("puff-half.vdb");
    check_against_openvdb("rotated-double.vdb");
    let tiles = check_against_openvdb("tiles.vdb");
    assert_eq!(tiles.grid.voxel([100, 100, 100]), 0.25, "inside a tile");
    check_against_openvdb("two-grids.vdb");
    // Inactive voxels of values other than the background (mask
    // compression with one or two values stored, or all values).
    let inactive = check_against_openvdb("inactive.vdb");
    assert_eq!(inactive.grid.voxel([18, 18, 17]), 1.25);
    // By name.
    let bytes = std::fs::read(fixture("two-grids.vdb")).unwrap();
    let t = parse_vdb(&bytes, Some("temperature")).unwrap();
    assert_eq!(t.name, "temperature");
    assert!(t.grid.max() > 10.0);
    let e = parse_vdb(&bytes, Some("velocity")).unwrap_err();
    assert!(e.contains("no grid") && e.contains("velocity"), "{e}");
}

#[test]
fn files_raylab_cannot_use_are_refused_in_one_line() {
    let one_line = |e: &str| {
        assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    };
    let e = read_vdb(&fixture("level-set.vdb"), None, &Ledger::unlimited())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("level-set.vdb") && e.contains("level set"),
        "{e}"
    );
    one_line(&e);
    let bytes = std::fs::read(fixture("puff.vdb")).unwrap();
    // Every prefix: an error, never a panic.
    for n in (0..bytes.len()).step_by(97) {
        let e = parse_vdb(&bytes[..n], None).unwrap_err();
        one_line(&e);
    }
    // Flipped bytes: an error or a grid, never a panic.
    let mut state = 99u32;
    for _ in 0..300 {
        let mut b = bytes.clone();
        for _ in 0..4 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let i = (state >> 8) as usize % b.len();
            b[i] ^= (state >> 24) as u8 | 1;
        }
        if let Err(e) = parse_vdb(&b, None) {
            one_line(&e);
        }
    }
    let e = parse_vdb(b"not a vdb file at all", None).unwrap_err();
    assert!(e.contains("not an OpenVDB file"), "{e}");
    // A budget smaller than the file.
    let small = Ledger::new(MemoryBudget::bytes(1000));
    let e = read_vdb(&fixture("puff.vdb"), None, &small)
        .unwrap_err()
        .to_string();
    assert!(e.contains("puff.vdb"), "{e}");
    one_line(&e);
}

/// A one-leaf file as OpenVDB lays it out, uncompressed or zipped, with or
/// without mask compression: the paths OpenVDB's Python writer (always
/// Blosc) does not produce.
fn one_leaf_file(compression: u32, values: &[f32; 512]) -> Vec<u8> {
    use std::io::Write;
    let mut f = Vec::new();
    let string = |f: &mut Vec<u8>, s: &str| {
        f.extend((s.len() as u32).to_le_bytes());
        f.extend(s.as_bytes());
    };
    f.extend([0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0]);
    f.extend(224u32.to_le_bytes());
    f.extend(10u32.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    f.push(0); // no grid offsets
    f.extend(b"01234567-89AB-CDEF-0123-456789ABCDEF");
    f.extend(0u32.to_le_bytes()); // file metadata
    f.extend(1u32.to_le_bytes()); // one grid
    string(&mut f, "density");
    string(&mut f, "Tree_float_5_4_3");
    string(&mut f, ""); // no instance parent
    f.extend(compression.to_le_bytes());
    f.extend(1u32.to_le_bytes());
    string(&mut f, "class");
    string(&mut f, "string");
    string(&mut f, "fog volume");
    string(&mut f, "UniformScaleMap");
    for v in [
        0.5f64, 0.5, 0.5, 0.5, 0.5, 0.5, 2.0, 2.0, 2.0, 4.0, 4.0, 4.0, 1.0, 1.0, 1.0,
    ] {
        f.extend(v.to_le_bytes());
    }
    f.extend(1u32.to_le_bytes()); // buffers
    f.extend(0f32.to_le_bytes()); // background
    f.extend(0u32.to_le_bytes()); // tiles
    f.extend(1u32.to_le_bytes()); // children
    f.extend([0u8; 12]); // origin (0, 0, 0)
    let data = |f: &mut Vec<u8>, bytes: &[u8]| {
        if compression & 1 != 0 {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(bytes).unwrap();
            let z = z.finish().unwrap();
            f.extend((z.len() as i64).to_le_bytes());
            f.extend(z);
        } else {
            f.extend(bytes);
        }
    };
    let masked = compression & 2 != 0;
    for side in [32usize, 16] {
        let n = side * side * side;
        let mut child = vec![0u8; n / 8];
        child[0] = 1;
        f.extend(&child);
        f.extend(vec![0u8; n / 8]); // no active tiles
        f.push(0); // inactive values: the background
        let count = if masked { 0 } else { n };
        if compression & 1 != 0 && count == 0 {
            f.extend(0i64.to_le_bytes());
        } else {
            data(&mut f, &vec![0u8; count * 4]);
        }
    }
    f.extend([0xffu8; 64]); // the leaf's topology: every voxel active
    f.extend([0xffu8; 64]); // its buffer: the mask again, then the values
    f.push(6);
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    data(&mut f, &bytes);
    f
}

#[test]
fn uncompressed_and_zipped_files_read_alike() {
    let mut values = [0.0f32; 512];
    for (i, v) in values.iter_mut().enumerate() {
        *v = (i % 97) as f32 * 0.25;
    }
    for compression in [0u32, 1, 2, 3] {
        let file = one_leaf_file(compression, &values);
        let read =
            parse_vdb(&file, None).unwrap_or_else(|e| panic!("compression {compression}: {e}"));
        for x in 0..8 {
            for y in 0..8 {
                for z in 0..8 {
                    let i = (x << 6 | y << 3 | z) as usize;
                    assert_eq!(
                        read.grid.voxel([x, y, z]),
                        values[i],
                        "compression {compression}"
                    );
                }
            }
        }
        assert_eq!(read.grid.voxel([8, 0, 0]), 0.0);
        let to_world = read
            .index_to_world
            .transform_point3(glam::Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(to_world, glam::Vec3::new(0.5, 1.0, 1.5));
        // Cut anywhere: an error, never a panic.
        for n in (0..file.len()).step_by(37) {
            assert!(parse_vdb(&file[..n], None).is_err());
        }
    }
}
