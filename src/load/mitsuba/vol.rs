//! Mitsuba's grid volume files (`.vol`, read by its `VolumeGrid`, for
//! `gridvolume` and `sdfgrid`): [`read_vol`] reads one as it is; an
//! `sdfgrid` takes its samples as a signed distance grid
//! ([`read_sdf_vol`]).
//!
//! The format (little-endian, `src/render/volumegrid.cpp` of Mitsuba
//! 3.7.1): the bytes `VOL`, a version byte (3), an `i32` encoding (1:
//! `float32`, the only one Mitsuba 3 reads), the `i32` sample counts along
//! x, y and z, the `i32` channel count, a bounding box of six `f32`
//! (`xmin ymin zmin xmax ymax zmax`), then the values, `f32`, channels
//! fastest, then x, then y, then z. An `sdfgrid` takes one channel and
//! ignores the bounding box: its samples span the unit cube.
//!
//! Where raylab is stricter than Mitsuba: the file must be exactly as long
//! as its header says (Mitsuba reads past a shorter one into an error and
//! ignores bytes after the values), the counts must be positive and their
//! product must not overflow, and every value must be finite. Nothing is
//! allocated from the header's numbers before they are checked against the
//! file's length, which the memory budget has checked.

use std::path::Path;

use crate::geometry::sdfgrid::SdfGrid;
use crate::memory::Ledger;

use super::error::MitsubaError;
use super::mesh::read_file;

/// Bytes before the values: magic, version, encoding, three sizes, channel
/// count, bounding box.
const HEADER_BYTES: usize = 3 + 1 + 4 + 12 + 4 + 24;

/// A `.vol` file's contents.
#[derive(Clone, Debug, PartialEq)]
pub struct VolFile {
    /// Samples along x, y and z (each ≥ 1).
    pub res: [u32; 3],
    /// Channels a sample (≥ 1).
    pub channels: u32,
    /// The bounding box the header gives (min, max).
    pub bounds: ([f32; 3], [f32; 3]),
    /// The values, channels fastest, then x, y, z.
    pub values: Vec<f32>,
}

/// Reads the `.vol` file `path` as an `sdfgrid`'s samples, checking its size
/// against `ledger` first (nothing is charged).
pub fn read_sdf_vol(path: &Path, ledger: &Ledger) -> Result<SdfGrid, MitsubaError> {
    let bytes = read_file(path, ledger)?;
    parse_sdf_vol(&bytes, path)
}

/// Reads the `.vol` file `path`, checking its size against `ledger` first
/// (nothing is charged).
pub fn read_vol(path: &Path, ledger: &Ledger) -> Result<VolFile, MitsubaError> {
    let bytes = read_file(path, ledger)?;
    parse_vol(&bytes, path)
}

/// Reads `bytes` as the `.vol` file `path` (which errors name) holding an
/// `sdfgrid`'s samples: one channel of `float32`.
pub fn parse_sdf_vol(bytes: &[u8], path: &Path) -> Result<SdfGrid, MitsubaError> {
    let vol = parse_vol(bytes, path)?;
    if vol.channels != 1 {
        return Err(MitsubaError::mesh(
            path,
            format!(
                "an SDF grid has 1 channel, this volume grid has {}",
                vol.channels
            ),
        ));
    }
    SdfGrid::new(vol.res, vol.values).map_err(|m| MitsubaError::mesh(path, m))
}

/// Reads `bytes` as the `.vol` file `path` (which errors name).
pub fn parse_vol(bytes: &[u8], path: &Path) -> Result<VolFile, MitsubaError> {
    let err = |m: String| MitsubaError::mesh(path, m);
    if bytes.len() < HEADER_BYTES {
        return Err(err(format!(
            "truncated volume grid: {} bytes, shorter than the {HEADER_BYTES}-byte header",
            bytes.len()
        )));
    }
    if &bytes[..3] != b"VOL" {
        return Err(err(
            "not a Mitsuba volume grid (the file does not start with 'VOL')".into(),
        ));
    }
    if bytes[3] != 3 {
        return Err(err(format!(
            "volume grid version {} (only version 3 is read)",
            bytes[3]
        )));
    }
    let int =
        |at: usize| i32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let encoding = int(4);
    if encoding != 1 {
        return Err(err(format!(
            "volume grid encoding {encoding} (only 1, float32, is read, as by Mitsuba 3)"
        )));
    }
    let (nx, ny, nz, channels) = (int(8), int(12), int(16), int(20));
    if nx <= 0 || ny <= 0 || nz <= 0 || channels <= 0 {
        return Err(err(format!(
            "volume grid of {nx}x{ny}x{nz} samples and {channels} channels (each must be positive)"
        )));
    }
    let values = [nx, ny, nz, channels]
        .iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
    let need = values
        .and_then(|v| v.checked_mul(4))
        .and_then(|b| b.checked_add(HEADER_BYTES as u64));
    match need {
        Some(need) if need == bytes.len() as u64 => {}
        Some(need) => {
            return Err(err(format!(
                "volume grid of {nx}x{ny}x{nz} float32 samples{} needs {need} bytes, the file has {}{}",
                if channels == 1 {
                    String::new()
                } else {
                    format!(" of {channels} channels")
                },
                bytes.len(),
                if (bytes.len() as u64) < need {
                    " (truncated)"
                } else {
                    ""
                }
            )));
        }
        None => {
            return Err(err(format!(
                "volume grid of {nx}x{ny}x{nz} samples is too large (its size overflows)"
            )));
        }
    }
    let float =
        |at: usize| f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let bounds = (
        [float(24), float(28), float(32)],
        [float(36), float(40), float(44)],
    );
    let values: Vec<f32> = bytes[HEADER_BYTES..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok(VolFile {
        res: [nx as u32, ny as u32, nz as u32],
        channels: channels as u32,
        bounds,
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `.vol` file's bytes: header fields as given, then `values`.
    fn vol_bytes(
        magic: &[u8; 3],
        version: u8,
        encoding: i32,
        res: [i32; 3],
        channels: i32,
        values: &[f32],
    ) -> Vec<u8> {
        let mut b = magic.to_vec();
        b.push(version);
        for v in [encoding, res[0], res[1], res[2], channels] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in values {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }

    fn parse(bytes: &[u8]) -> Result<SdfGrid, String> {
        parse_sdf_vol(bytes, Path::new("grid.vol")).map_err(|e| e.to_string())
    }

    #[test]
    fn a_good_file_reads_x_fastest() {
        let values: Vec<f32> = (0..2 * 3 * 2).map(|i| i as f32 - 5.5).collect();
        let g = parse(&vol_bytes(b"VOL", 3, 1, [2, 3, 2], 1, &values)).unwrap();
        assert_eq!(g.resolution(), [2, 3, 2]);
        assert_eq!(g.sample(1, 0, 0), values[1]);
        assert_eq!(g.sample(0, 1, 0), values[2]);
        assert_eq!(g.sample(1, 2, 1), values[11]);
    }

    /// Every bad file gives one line naming the file and what is wrong.
    #[test]
    fn bad_files_are_refused_with_one_line() {
        let v8 = [1.0f32, -1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let good = vol_bytes(b"VOL", 3, 1, [2, 2, 2], 1, &v8);
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (good[..20].to_vec(), "shorter than the 48-byte header"),
            (good[..good.len() - 3].to_vec(), "(truncated)"),
            ([good.clone(), vec![0; 4]].concat(), "the file has 84"),
            (
                vol_bytes(b"VOX", 3, 1, [2, 2, 2], 1, &v8),
                "does not start with 'VOL'",
            ),
            (vol_bytes(b"VOL", 2, 1, [2, 2, 2], 1, &v8), "version 2"),
            (vol_bytes(b"VOL", 3, 3, [2, 2, 2], 1, &v8), "encoding 3"),
            (
                vol_bytes(b"VOL", 3, 1, [2, -2, 2], 1, &v8),
                "must be positive",
            ),
            (
                vol_bytes(b"VOL", 3, 1, [2, 2, 2], 3, &v8),
                "of 3 channels needs",
            ),
            (
                vol_bytes(b"VOL", 3, 1, [i32::MAX, i32::MAX, i32::MAX], 1, &v8),
                "overflows",
            ),
            (
                vol_bytes(b"VOL", 3, 1, [65536, 65536, 2], 1, &v8),
                "needs 34359738416 bytes",
            ),
            (
                vol_bytes(b"VOL", 3, 1, [1, 2, 4], 1, &v8),
                "at least 2 samples",
            ),
            (
                vol_bytes(b"VOL", 3, 1, [2, 2, 2], 1, &[f32::NAN; 8]),
                "not finite",
            ),
        ];
        for (bytes, what) in cases {
            let e = parse(&bytes).unwrap_err();
            assert!(
                e.starts_with("grid.vol: ") && e.contains(what),
                "{e} (wanted {what})"
            );
            assert!(!e.contains('\n'), "{e}");
        }
        assert!(parse(&good).is_ok());
    }
}
