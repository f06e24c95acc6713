//! OpenVDB files written by OpenVDB itself (`tools/make_vdb_fixtures.py`:
//! Blosc-compressed, with mask compression; floats, half floats and
//! doubles; scale-translate and affine maps; tiles; two grids in a file)
//! read voxel for voxel as OpenVDB reads them back, and files raylab cannot
//! use refused in one line.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3A;
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

/// A scene file's `[[medium]] type = "vdb"`: the grid, placed by the
/// file's transform then the section's, in an invisible box. Absorbing only
/// (colour 0), a path along a ray through it gets through with probability
/// `exp(−density ∫ grid)`: the mean of 20,000 paths against the integral
/// along the ray by the midpoint rule on the same grid (4 standard errors).
/// Bad sections are one line naming the scene file.
#[test]
fn a_scene_file_places_a_vdb_volume() {
    let dir = tempfile::tempdir().unwrap();
    let file = fixture("puff.vdb");
    let (density, scale, translate) = (4.0f32, 2.0f32, glam::Vec3::new(0.5, -0.25, 0.0));
    let toml = |extra: &str| {
        format!(
            "[environment]\ncolor = [1, 1, 1]\n\n[camera]\nposition = [0, 0, 8]\ntarget = [0, 0, 0]\n\n\
             [[medium]]\ntype = \"vdb\"\nfile = {:?}\ndensity = {density}\ncolor = [0, 0, 0]\n\
             scale = {scale}\ntranslate = [{}, {}, {}]\n{extra}",
            file.display().to_string(),
            translate.x,
            translate.y,
            translate.z
        )
    };
    let path = dir.path().join("puff.toml");
    std::fs::write(&path, toml("")).unwrap();
    let loaded = raylab::load::load(path.to_str().unwrap(), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    // The same field, placed by hand.
    let vdb = read_vdb(&file, None, &raylab::memory::Ledger::unlimited()).unwrap();
    let to_world = glam::Affine3A::from_translation(translate)
        * glam::Affine3A::from_scale(glam::Vec3::splat(scale));
    let field = raylab::media::Field::sparse(vdb.grid, to_world * vdb.index_to_world);
    let (lo, hi) = field.bounds;
    let centre = (lo + hi) * 0.5;
    let opts = raylab::integrators::path::PathOptions::default();
    for (k, offset) in [
        (0, Vec3A::ZERO),
        (1, (hi - lo) * Vec3A::new(0.15, -0.1, 0.0)),
    ] {
        let origin = centre + offset + Vec3A::new(0.0, 0.0, 10.0);
        let ray = raylab::Ray::new(origin, Vec3A::NEG_Z);
        // The optical depth by the midpoint rule, 20,000 steps over 20 units.
        let steps = 20_000;
        let tau: f64 = (0..steps)
            .map(|i| {
                let t = 20.0 * (i as f32 + 0.5) / steps as f32;
                f64::from(field.eval(origin + Vec3A::NEG_Z * t).x) * 20.0 / steps as f64
            })
            .sum::<f64>()
            * f64::from(density);
        let want = (-tau).exp();
        let n = 20_000u64;
        let mut rays = 0;
        let got = (0..n)
            .map(|i| {
                let mut rng = raylab::sampling::sampler::Rng::new(i, 5 + k);
                let l = raylab::integrators::path::radiance(
                    &loaded.scene,
                    &ray,
                    &opts,
                    &mut rng,
                    &mut rays,
                );
                f64::from(l.x)
            })
            .sum::<f64>()
            / n as f64;
        let se = (want * (1.0 - want) / n as f64).sqrt();
        eprintln!("ray {k}: through the puff {got}, exp(-tau) {want} (tau {tau})");
        assert!(tau > 0.05, "the ray misses the puff (tau {tau})");
        assert!(
            (got - want).abs() < 4.0 * se + 0.003,
            "ray {k}: {got} vs {want}"
        );
    }
    for (extra, says) in [
        ("grid = \"temperature\"\n", "temperature"),
        ("scale = 0\n", "scale"),
    ] {
        let text = toml(extra);
        // A second `scale` key replaces the first: write the bad one alone.
        let text = if extra.starts_with("scale") {
            text.replace(&format!("scale = {scale}\n"), "")
        } else {
            text
        };
        std::fs::write(&path, text).unwrap();
        let err = common::load_error(&path);
        assert!(err.contains(says), "{extra}: {err}");
    }
}
