//! Mitsuba's `serialized` shape plugin: one shape of a `.serialized` file
//! read into a [`MitsubaMesh`], following `src/shapes/serialized.cpp` (of
//! v3.9.1 and `b45b0a9`, which read versions 3 and 4 alike).
//!
//! The format (little-endian): a `u16` identifier `0x041C` and a `u16`
//! version (3 or 4), then a zlib stream holding a `u32` flag word
//! (`0x0001` normals, `0x0002` texture coordinates, `0x0008` vertex colours,
//! `0x2000` double precision; `0x1000` single precision, `0x0010` face
//! normals, both ignored by Mitsuba 3), in version 4 the shape's name
//! (NUL-terminated), the `u64` vertex and triangle counts, then the
//! positions, normals, texture coordinates and colours (`f32`, or `f64`
//! converted to `f32`), and three `u32` indices a triangle. A file may hold
//! several shapes one after the other, each with its own 4-byte header; it
//! ends with the shapes' offsets (`u64` in version 4, `u32` in version 3)
//! and their count (`u32`). `shape_index` 0 is read from the start of the
//! file without the dictionary; another is found through the dictionary,
//! its 4-byte header skipped unread, and the first header's version used,
//! as Mitsuba does.
//!
//! Mitsuba 3 reads the colours past and drops them: they are returned in
//! [`MitsubaMesh::colors`] but are no attribute. The texture coordinates are
//! never flipped. Version 5 (Mitsuba's packed mesh records, after 3.9.1) is
//! refused.
//!
//! Where raylab differs: indices are checked against the vertex count; the
//! counts are checked against what the compressed bytes left in the file can
//! hold (deflate expands at most 1032 times) and against
//! [`MAX_MESH_VERTICES`](super::MAX_MESH_VERTICES) and
//! [`MAX_MESH_FACES`](super::MAX_MESH_FACES) before anything is allocated,
//! and the arrays grow only as the decompressed data arrives.

use std::io::Read;
use std::path::Path;

use flate2::bufread::ZlibDecoder;

use crate::memory::Ledger;

use super::error::MitsubaError;
use super::mesh::{MitsubaMesh, check_size, read_file};

/// The file format identifier of a `.serialized` file.
const MAGIC: u16 = 0x041C;

/// Flags of versions 3 and 4.
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;

/// The most a deflate stream expands: 1032 bytes out per byte in (and a
/// little for the stream's ends).
const MAX_DEFLATE_RATIO: u64 = 1032;

/// The longest shape name read (version 4).
const MAX_NAME_BYTES: usize = 1 << 16;

/// Reads shape `shape_index` of the `.serialized` file `path` as Mitsuba's
/// `serialized` plugin does, checking the memory it needs against `ledger`
/// (nothing is charged).
pub fn read_serialized(
    path: &Path,
    shape_index: i64,
    ledger: &Ledger,
) -> Result<MitsubaMesh, MitsubaError> {
    let bytes = read_file(path, ledger)?;
    parse_serialized(&bytes, path, shape_index, ledger)
}

/// Reads shape `shape_index` of `bytes` as the `.serialized` file `path`
/// (which errors name).
pub fn parse_serialized(
    bytes: &[u8],
    path: &Path,
    shape_index: i64,
    ledger: &Ledger,
) -> Result<MitsubaMesh, MitsubaError> {
    let err = |m: String| MitsubaError::mesh(path, m);
    if shape_index < 0 {
        return Err(err(format!("shape index {shape_index} is negative")));
    }
    if bytes.len() < 4 {
        return Err(err(
            "not a Mitsuba serialized mesh (shorter than its 4-byte header)".into(),
        ));
    }
    let magic = u16::from_le_bytes([bytes[0], bytes[1]]);
    if magic != MAGIC {
        return Err(err(format!(
            "not a Mitsuba serialized mesh (file format identifier {magic:#06x}, not 0x041c)"
        )));
    }
    let version = u16::from_le_bytes([bytes[2], bytes[3]]);
    match version {
        3 | 4 => {}
        5 => {
            return Err(err(
                "serialized version 5 (written by Mitsuba after 3.9.1) is not supported, only versions 3 and 4".into(),
            ));
        }
        v => {
            return Err(err(format!(
                "incompatible serialized file version {v} (3 and 4 are read)"
            )));
        }
    }
    let start = if shape_index == 0 {
        4
    } else {
        shape_offset(bytes, shape_index as u64, version).map_err(err)?
    };
    let shape = Shape {
        path,
        index: shape_index as u64,
        version,
        ledger,
    };
    shape.read(&bytes[start..])
}

/// Where the data of shape `index` (> 0) starts: after its offset in the
/// dictionary at the end of the file, and its 4-byte header.
fn shape_offset(bytes: &[u8], index: u64, version: u16) -> Result<usize, String> {
    let len = bytes.len() as u64;
    let tail = |at: u64, n: usize| -> Option<u64> {
        let at = usize::try_from(at).ok()?;
        let b = bytes.get(at..at.checked_add(n)?)?;
        let mut v = [0u8; 8];
        v[..n].copy_from_slice(b);
        Some(u64::from_le_bytes(v))
    };
    let count = len
        .checked_sub(4)
        .and_then(|at| tail(at, 4))
        .ok_or("the file is too short for its dictionary of shapes")?;
    if index >= count {
        return Err(format!(
            "shape index {index} out of range (the file holds {count} shapes, 0 to {})",
            count as i64 - 1
        ));
    }
    let entry = if version >= 4 { 8 } else { 4 };
    // Version 4: `len − 8 (count − index) − 4`; version 3: `len − 4 (count −
    // index + 1)`: the same place for both.
    let offset = (count - index)
        .checked_mul(entry)
        .and_then(|back| len.checked_sub(back)?.checked_sub(4))
        .and_then(|at| tail(at, entry as usize))
        .ok_or_else(|| {
            format!("shape {index}: its offset lies before the start of the file (the dictionary claims {count} shapes)")
        })?;
    match offset.checked_add(4) {
        Some(start) if start <= len => Ok(start as usize),
        _ => Err(format!(
            "shape {index}: offset {offset} lies beyond the end of the file ({len} bytes)"
        )),
    }
}

/// One shape being read.
struct Shape<'a> {
    path: &'a Path,
    index: u64,
    version: u16,
    ledger: &'a Ledger,
}

/// The decompressed stream of a shape.
struct Stream<'a> {
    z: ZlibDecoder<&'a [u8]>,
    buf: Vec<u8>,
}

impl Shape<'_> {
    fn err(&self, m: impl std::fmt::Display) -> MitsubaError {
        MitsubaError::mesh(self.path, format!("shape {}: {m}", self.index))
    }

    /// `n` bytes of the stream, as `what`.
    fn bytes<'s>(&self, s: &'s mut Stream, n: usize, what: &str) -> Result<&'s [u8], MitsubaError> {
        s.buf.resize(n, 0);
        s.z.read_exact(&mut s.buf).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                self.err(format!("the compressed data ends early (reading {what})"))
            } else {
                self.err(format!("corrupt compressed data (reading {what}): {e}"))
            }
        })?;
        Ok(&s.buf)
    }

    fn u32(&self, s: &mut Stream, what: &str) -> Result<u32, MitsubaError> {
        let b = self.bytes(s, 4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&self, s: &mut Stream, what: &str) -> Result<u64, MitsubaError> {
        let b = self.bytes(s, 8, what)?;
        Ok(u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
    }

    /// `n` records of `K` floats (`f32`, or `f64` when `double`), read in
    /// chunks so that memory grows only with the data present.
    fn floats<const K: usize>(
        &self,
        s: &mut Stream,
        n: u64,
        double: bool,
        what: &str,
    ) -> Result<Vec<[f32; K]>, MitsubaError> {
        const CHUNK: u64 = 1 << 14;
        let size = if double { 8 } else { 4 };
        let mut out = Vec::with_capacity(n.min(CHUNK) as usize);
        let mut left = n;
        while left > 0 {
            let k = left.min(CHUNK) as usize;
            let b = self.bytes(s, k * K * size, what)?;
            if double {
                out.extend(b.chunks_exact(K * 8).map(|r| {
                    std::array::from_fn(|j| {
                        f64::from_le_bytes(r[j * 8..j * 8 + 8].try_into().unwrap_or([0; 8])) as f32
                    })
                }));
            } else {
                out.extend(b.chunks_exact(K * 4).map(|r| {
                    std::array::from_fn(|j| {
                        f32::from_le_bytes([r[j * 4], r[j * 4 + 1], r[j * 4 + 2], r[j * 4 + 3]])
                    })
                }));
            }
            left -= k as u64;
        }
        Ok(out)
    }

    fn read(&self, data: &[u8]) -> Result<MitsubaMesh, MitsubaError> {
        let mut s = Stream {
            z: ZlibDecoder::new(data),
            buf: Vec::new(),
        };
        let flags = self.u32(&mut s, "the flags")?;
        let mut name = Vec::new();
        if self.version == 4 {
            loop {
                let c = self.bytes(&mut s, 1, "the name")?[0];
                if c == 0 {
                    break;
                }
                if name.len() == MAX_NAME_BYTES {
                    return Err(self.err(format!("a name longer than {MAX_NAME_BYTES} bytes")));
                }
                name.push(c);
            }
        }
        let vertices = self.u64(&mut s, "the vertex count")?;
        let faces = self.u64(&mut s, "the triangle count")?;
        let double = flags & DOUBLE_PRECISION != 0;
        let normals = flags & HAS_NORMALS != 0;
        let uvs = flags & HAS_TEXCOORDS != 0;
        let colors = flags & HAS_COLORS != 0;

        // What the header asks for, against what the compressed bytes left
        // can hold, before anything is allocated.
        let floats_per_vertex = 3 + 3 * normals as u64 + 2 * uvs as u64 + 3 * colors as u64;
        let size = if double { 8 } else { 4 };
        let needed = (vertices as u128) * (floats_per_vertex * size) as u128 + (faces as u128) * 12;
        let room = (data.len() as u128) * MAX_DEFLATE_RATIO as u128 + 1024;
        if needed > room {
            return Err(self.err(format!(
                "{vertices} vertices and {faces} triangles need {needed} bytes of data, more than the {} compressed bytes left in the file can hold",
                data.len()
            )));
        }
        check_size(
            self.path,
            &format!("shape {}: ", self.index),
            vertices,
            faces,
            floats_per_vertex * 4,
            self.ledger,
        )?;

        let positions = self.floats::<3>(&mut s, vertices, double, "the positions")?;
        let normals = if normals {
            Some(self.floats::<3>(&mut s, vertices, double, "the normals")?)
        } else {
            None
        };
        let uvs = if uvs {
            Some(self.floats::<2>(&mut s, vertices, double, "the texture coordinates")?)
        } else {
            None
        };
        let colors = if colors {
            Some(self.floats::<3>(&mut s, vertices, double, "the vertex colours")?)
        } else {
            None
        };
        let mut indices = Vec::with_capacity(faces.min(1 << 14) as usize);
        let mut left = faces;
        while left > 0 {
            let k = left.min(1 << 14);
            let b = self.bytes(&mut s, k as usize * 12, "the indices")?;
            for (j, t) in b.chunks_exact(12).enumerate() {
                let tri: [u32; 3] = std::array::from_fn(|c| {
                    u32::from_le_bytes([t[c * 4], t[c * 4 + 1], t[c * 4 + 2], t[c * 4 + 3]])
                });
                if let Some(&bad) = tri.iter().find(|&&i| i as u64 >= vertices) {
                    let face = faces - left + j as u64;
                    return Err(self.err(format!(
                        "triangle {face}: vertex index {bad} out of range ({vertices} vertices)"
                    )));
                }
                indices.push(tri);
            }
            left -= k;
        }
        Ok(MitsubaMesh {
            name: String::from_utf8_lossy(&name).into_owned(),
            positions,
            normals,
            uvs,
            colors,
            indices,
            ..Default::default()
        })
    }
}
