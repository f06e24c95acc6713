//! OpenVDB files (`.vdb`): the float grids of a cloud, smoke or fire, read
//! into a [`SparseGrid`] with the transform from its index space to the
//! world. [`read_vdb`] reads a file, [`parse_vdb`] bytes.
//!
//! What is read (the layout of OpenVDB's `io/Archive.cc`, `tree/RootNode.h`,
//! `InternalNode.h`, `LeafNode.h` and `io/Compression.h`, file format 222
//! and later, i.e. OpenVDB 3 to 13): the header, each grid's descriptor,
//! compression flags, metadata (its `class` is checked: a level set is no
//! density) and transform (the linear maps: scale, translation, affine;
//! not the frustum map), then the tree `Tree_float_5_4_3` or
//! `Tree_double_5_4_3`, stored as float, double or half floats, without
//! compression, zipped (zlib) or with Blosc (LZ4, byte-shuffled): the root's
//! tiles and children, the internal nodes' masks and tile values, and the
//! leaves' masks and values with OpenVDB's mask compression (inactive values
//! restored from the background or the values stored for them).
//!
//! Every count that sizes an allocation is checked first against what the
//! tree's shape allows and the bytes left in the file; a wrong byte gives one
//! line naming the file and what was wrong, never a panic.

mod blosc;

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, DAffine3, DMat3, DVec3};

use crate::media::sparse::{LEAF_VOXELS, SparseGrid, Tile};
use crate::memory::{Ledger, Needs};

/// The file's first 8 bytes: `" BDV"` and four zero bytes.
const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];
/// The oldest file format read (OpenVDB 3.0's: mask compression).
const OLDEST: u32 = 222;
/// Compression flags of a grid.
const COMPRESS_ZIP: u32 = 0x1;
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
const COMPRESS_BLOSC: u32 = 0x4;

/// A grid read from a `.vdb` file.
#[derive(Clone, Debug)]
pub struct VdbGrid {
    /// Its name in the file (`density`, `temperature`, …).
    pub name: String,
    /// Its values.
    pub grid: Arc<SparseGrid>,
    /// From index space to the file's world space.
    pub index_to_world: Affine3A,
}

/// Why a `.vdb` file cannot be used: its path and one line.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbError {
    /// The file.
    pub path: std::path::PathBuf,
    /// What is wrong with it.
    pub message: String,
}

impl std::fmt::Display for VdbError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The whole path (a quoted word would be cut to 40 characters and
        // lose the file's name), control characters escaped.
        let path = self.path.display().to_string();
        let path = crate::guard::one_line(&path);
        write!(f, "{path}: {}", crate::guard::one_line(&self.message))
    }
}

impl std::error::Error for VdbError {}

/// Reads the float grid `grid` (or, without a name, the file's `density`
/// grid, else its first float grid) of the `.vdb` file `path`, charging the
/// grid's memory to `ledger` (the file's size is checked against it first).
pub fn read_vdb(path: &Path, grid: Option<&str>, ledger: &Ledger) -> Result<VdbGrid, VdbError> {
    let error = |message: String| VdbError {
        path: path.to_owned(),
        message,
    };
    read_vdb_unnamed(path, grid, ledger).map_err(error)
}

fn read_vdb_unnamed(path: &Path, grid: Option<&str>, ledger: &Ledger) -> Result<VdbGrid, String> {
    let shown = path.display().to_string();
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?;
    let needs = |bytes: u64| Needs {
        geometry: bytes,
        ..Default::default()
    };
    // What a grid takes is at most some 16 times its file's bytes (a leaf
    // of 2 KiB takes at least 129 bytes of the file).
    ledger
        .fits(&shown, needs(meta.len()))
        .map_err(|e| e.to_string())?;
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let read = parse_vdb(&bytes, grid)?;
    ledger
        .charge(&shown, needs(read.grid.bytes()))
        .map_err(|e| e.to_string())?;
    Ok(read)
}

/// Reads the bytes of a `.vdb` file as [`read_vdb`] does; errors do not
/// name the file.
pub fn parse_vdb(bytes: &[u8], grid: Option<&str>) -> Result<VdbGrid, String> {
    // Names from the file are quoted (cut short); control characters in
    // them are escaped here, so that an error is one line.
    parse(bytes, grid).map_err(|e| crate::guard::one_line(&e).into_owned())
}

fn parse(bytes: &[u8], grid: Option<&str>) -> Result<VdbGrid, String> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8)? != MAGIC {
        return Err("not an OpenVDB file (it does not start with \" BDV\")".into());
    }
    let version = r.u32()?;
    if version < OLDEST {
        return Err(format!(
            "file format {version} is older than raylab reads ({OLDEST}, OpenVDB 3.0); save it again with a newer OpenVDB"
        ));
    }
    let _library = (r.u32()?, r.u32()?);
    let has_offsets = r.u8()? != 0;
    r.take(36)?; // The UUID.
    skip_metadata(&mut r)?;
    let count = r.u32()?;
    let mut found = Vec::new();
    for _ in 0..count {
        let unique = r.string()?;
        // A duplicate name carries a suffix after U+001E.
        let gname = unique.split('\u{1e}').next().unwrap_or("").to_string();
        let mut gtype = r.string()?;
        let half = gtype.ends_with("_HalfFloat");
        if half {
            gtype.truncate(gtype.len() - "_HalfFloat".len());
        }
        let parent = r.string()?;
        let end = if has_offsets {
            let _grid_pos = r.u64()?;
            let _block_pos = r.u64()?;
            Some(r.u64()?)
        } else {
            None
        };
        let value = match gtype.as_str() {
            "Tree_float_5_4_3" => Some(Value::F32),
            "Tree_double_5_4_3" => Some(Value::F64),
            _ => None,
        };
        let wanted = match grid {
            Some(n) => n == gname,
            None => value.is_some(),
        };
        if !wanted && end.is_none() {
            return Err(format!(
                "grid {} comes before the one wanted in a file without grid offsets",
                crate::guard::quote(&gname)
            ));
        }
        if wanted {
            let Some(value) = value else {
                return Err(format!(
                    "grid {} is a {}; raylab reads float and double grids (Tree_float_5_4_3, Tree_double_5_4_3)",
                    crate::guard::quote(&gname),
                    crate::guard::quote(&gtype)
                ));
            };
            if !parent.is_empty() {
                return Err(format!(
                    "grid {} is an instance of grid {}; instanced grids are not supported",
                    crate::guard::quote(&gname),
                    crate::guard::quote(&parent)
                ));
            }
            let read = GridReader {
                value: if half { Value::F16 } else { value },
                full: value,
                compression: 0,
                background: 0.0,
            }
            .read(&mut r)
            .map_err(|e| format!("grid {}: {e}", crate::guard::quote(&gname)))?;
            found.push((gname, read));
            if grid.is_some() || found.iter().any(|(n, _)| n == "density") {
                break;
            }
        }
        if let Some(end) = end {
            r.seek(end)?;
        }
    }
    let pick = match grid {
        Some(_) => found.pop(),
        None => {
            let d = found.iter().position(|(n, _)| n == "density");
            d.map(|i| found.swap_remove(i))
                .or_else(|| found.into_iter().next())
        }
    };
    match pick {
        Some((name, (grid, index_to_world))) => Ok(VdbGrid {
            name,
            grid: Arc::new(grid),
            index_to_world,
        }),
        None => Err(match grid {
            Some(n) => format!("the file has no grid {}", crate::guard::quote(n)),
            None => "the file has no float grid".into(),
        }),
    }
}

/// How values are stored.
#[derive(Clone, Copy, PartialEq)]
enum Value {
    F16,
    F32,
    F64,
}

impl Value {
    fn size(self) -> usize {
        match self {
            Value::F16 => 2,
            Value::F32 => 4,
            Value::F64 => 8,
        }
    }

    fn decode(self, b: &[u8]) -> f32 {
        match self {
            Value::F16 => half::f16::from_le_bytes([b[0], b[1]]).to_f32(),
            Value::F32 => f32::from_le_bytes(b[..4].try_into().unwrap()),
            Value::F64 => f64::from_le_bytes(b[..8].try_into().unwrap()) as f32,
        }
    }
}

/// A cursor over the file's bytes; every read checks what is left.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| {
                format!(
                    "ends early: {n} bytes needed at byte {} of {}",
                    self.at,
                    self.bytes.len()
                )
            })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn i32(&mut self) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn dvec3(&mut self) -> Result<DVec3, String> {
        Ok(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    fn seek(&mut self, to: u64) -> Result<(), String> {
        if to > self.bytes.len() as u64 || (to as usize) < self.at {
            return Err(format!(
                "a grid's end offset {to} lies outside the file (at byte {} of {})",
                self.at,
                self.bytes.len()
            ));
        }
        self.at = to as usize;
        Ok(())
    }
}

/// Skips a metadata table (the file's), returning nothing.
fn skip_metadata(r: &mut Reader) -> Result<(), String> {
    let n = r.u32()?;
    for _ in 0..n {
        r.string()?;
        r.string()?;
        let size = r.u32()? as usize;
        r.take(size)?;
    }
    Ok(())
}

/// One node's bit mask of `bits` bits (a multiple of 64).
struct Mask(Vec<u64>);

impl Mask {
    fn read(r: &mut Reader, bits: usize) -> Result<Mask, String> {
        let b = r.take(bits / 8)?;
        Ok(Mask(
            b.chunks_exact(8)
                .map(|w| u64::from_le_bytes(w.try_into().unwrap()))
                .collect(),
        ))
    }
    fn on(&self, i: usize) -> bool {
        self.0[i >> 6] >> (i & 63) & 1 != 0
    }
    fn count(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }
}

/// Reads one grid.
struct GridReader {
    /// How the tree's buffers store values (half floats when saved so).
    value: Value,
    /// How the background, tiles and inactive values are stored.
    full: Value,
    compression: u32,
    background: f32,
}

/// Children along a side of the upper internal node (2⁵) and of the lower
/// one (2⁴), as log2: the `5_4` of `Tree_float_5_4_3`.
const LOG2_5: u32 = 5;
const LOG2_4: u32 = 4;

impl GridReader {
    fn read(mut self, r: &mut Reader) -> Result<(SparseGrid, Affine3A), String> {
        self.compression = r.u32()?;
        // Metadata: the class decides whether this is a density at all.
        let n = r.u32()?;
        for _ in 0..n {
            let name = r.string()?;
            let _ty = r.string()?;
            let size = r.u32()? as usize;
            let v = r.take(size)?;
            if name == "class" && v == b"level set" {
                return Err(
                    "is a level set (a signed distance), not a fog volume's density".into(),
                );
            }
        }
        let index_to_world = transform(r)?;
        let buffers = r.u32()?;
        if buffers != 1 {
            return Err(format!(
                "a tree of {buffers} buffers (files since OpenVDB 3 have 1)"
            ));
        }
        // The root: background, tiles, children.
        self.background = self.full.decode(r.take(self.full.size())?);
        if self.background != 0.0 {
            return Err(format!(
                "its background is {}; a medium's density grid must be 0 outside its voxels",
                self.background
            ));
        }
        let tiles_n = r.u32()? as usize;
        let children_n = r.u32()? as usize;
        // Each root tile takes at least 13 bytes in the file, each child
        // more than 8 KiB: the counts are checked against what is left.
        let left = r.bytes.len() - r.at;
        if tiles_n > left / 13 || children_n > left / 8192 {
            return Err(format!(
                "its root claims {tiles_n} tiles and {children_n} children, more than the file holds"
            ));
        }
        let mut tiles = Vec::new();
        for _ in 0..tiles_n {
            let origin = [r.i32()?, r.i32()?, r.i32()?];
            let value = self.full.decode(r.take(self.full.size())?);
            let _active = r.u8()?;
            if value != 0.0 {
                tiles.push(Tile {
                    origin,
                    dim: 1 << (3 + LOG2_4 + LOG2_5),
                    value,
                });
            }
        }
        let mut leaves = Vec::new();
        for _ in 0..children_n {
            let origin = [r.i32()?, r.i32()?, r.i32()?];
            self.internal(r, origin, LOG2_5, &mut tiles, &mut leaves)?;
        }
        // The leaves' buffers, in the order their nodes were read.
        let mut values = vec![0.0f32; leaves.len() * LEAF_VOXELS];
        for (i, chunk) in values.chunks_exact_mut(LEAF_VOXELS).enumerate() {
            let mask = Mask::read(r, LEAF_VOXELS)?;
            self.values(r, &mask, chunk)
                .map_err(|e| format!("the leaf at {:?}: {e}", leaves[i]))?;
        }
        let grid = SparseGrid::new(&leaves, values, &tiles)?;
        Ok((grid, index_to_world))
    }

    /// An internal node of `2^log2`³ children at `origin`: its masks and tile
    /// values, then its children (internal nodes of the next level, or
    /// leaves, whose values come later).
    fn internal(
        &self,
        r: &mut Reader,
        origin: [i32; 3],
        log2: u32,
        tiles: &mut Vec<Tile>,
        leaves: &mut Vec<[i32; 3]>,
    ) -> Result<(), String> {
        let n = 1usize << (3 * log2);
        let children = Mask::read(r, n)?;
        let active = Mask::read(r, n)?;
        let mut values = vec![0.0f32; n];
        self.values(r, &active, &mut values)
            .map_err(|e| format!("the node at {origin:?}: {e}"))?;
        // The side of a child, in voxels.
        let child_log2 = if log2 == LOG2_5 { 3 + LOG2_4 } else { 3 };
        let dim = 1i32 << log2;
        let child_origin = |i: usize| {
            let (x, y, z) = (
                i as i32 >> (2 * log2),
                (i as i32 >> log2) & (dim - 1),
                i as i32 & (dim - 1),
            );
            [
                origin[0].wrapping_add(x << child_log2),
                origin[1].wrapping_add(y << child_log2),
                origin[2].wrapping_add(z << child_log2),
            ]
        };
        for (i, &v) in values.iter().enumerate() {
            if !children.on(i) && v != 0.0 {
                tiles.push(Tile {
                    origin: child_origin(i),
                    dim: 1 << child_log2,
                    value: v,
                });
            }
        }
        for i in (0..n).filter(|&i| children.on(i)) {
            if log2 == LOG2_5 {
                self.internal(r, child_origin(i), LOG2_4, tiles, leaves)?;
            } else {
                // A leaf's topology is its mask; the values follow the tree.
                r.take(LEAF_VOXELS / 8)?;
                leaves.push(child_origin(i));
            }
        }
        Ok(())
    }

    /// A node's values as `io::readCompressedValues` stores them: a byte
    /// saying what of the inactive values is stored, those values, and the
    /// values (all, or the active ones only), compressed as the grid says.
    fn values(&self, r: &mut Reader, active: &Mask, out: &mut [f32]) -> Result<(), String> {
        let metadata = r.u8()?;
        let full = self.full;
        let (mut inactive0, mut inactive1) = (
            if metadata == 0 {
                self.background
            } else {
                -self.background
            },
            self.background,
        );
        if matches!(metadata, 2 | 4 | 5) {
            inactive0 = full.decode(r.take(full.size())?);
            if metadata == 5 {
                inactive1 = full.decode(r.take(full.size())?);
            }
        }
        if metadata > 6 {
            return Err(format!("unknown value-mask code {metadata}"));
        }
        let selection = if matches!(metadata, 3..=5) {
            Some(Mask::read(r, out.len())?)
        } else {
            None
        };
        let masked = self.compression & COMPRESS_ACTIVE_MASK != 0 && metadata != 6;
        let count = if masked { active.count() } else { out.len() };
        let size = self.value.size();
        let bytes = count * size;
        // Half floats: nothing at all is stored for no values (OpenVDB's
        // `HalfReader`/`HalfWriter` return at once), not even a chunk size.
        let data = if count == 0 && self.value == Value::F16 {
            Vec::new()
        } else if self.compression & (COMPRESS_BLOSC | COMPRESS_ZIP) != 0 {
            let n = r.u64()? as i64;
            if n <= 0 {
                if n.unsigned_abs() != bytes as u64 {
                    return Err(format!(
                        "{} stored bytes where {bytes} are expected",
                        n.unsigned_abs()
                    ));
                }
                r.take(bytes)?.to_vec()
            } else {
                let src = r.take(usize::try_from(n).map_err(|_| "a chunk too long")?)?;
                if self.compression & COMPRESS_BLOSC != 0 {
                    blosc::decompress(src, bytes)?
                } else {
                    let mut out = vec![0u8; bytes];
                    blosc::zlib(src, &mut out)?;
                    out
                }
            }
        } else {
            r.take(bytes)?.to_vec()
        };
        let mut stored = data.chunks_exact(size).map(|b| self.value.decode(b));
        for (i, o) in out.iter_mut().enumerate() {
            *o = if !masked || active.on(i) {
                stored.next().unwrap_or(0.0)
            } else if selection.as_ref().is_some_and(|s| s.on(i)) {
                inactive1
            } else {
                inactive0
            };
        }
        Ok(())
    }
}

/// A grid's transform: the name of its map, then the map's numbers.
fn transform(r: &mut Reader) -> Result<Affine3A, String> {
    let map = r.string()?;
    let d = match map.as_str() {
        "UniformScaleMap" | "ScaleMap" => {
            let scale = r.dvec3()?;
            for _ in 0..4 {
                r.dvec3()?; // voxel size, inverse scale, 1/scale², 1/(2 scale)
            }
            DAffine3::from_scale(scale)
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let translation = r.dvec3()?;
            let scale = r.dvec3()?;
            for _ in 0..4 {
                r.dvec3()?;
            }
            DAffine3::from_translation(translation) * DAffine3::from_scale(scale)
        }
        "TranslationMap" => DAffine3::from_translation(r.dvec3()?),
        "AffineMap" | "UnitaryMap" => {
            // Row vectors (p' = p M): M's rows are the images of the axes,
            // its last row the translation.
            let mut m = [0.0f64; 16];
            for v in &mut m {
                *v = r.f64()?;
            }
            let row = |i: usize| DVec3::new(m[4 * i], m[4 * i + 1], m[4 * i + 2]);
            DAffine3::from_mat3_translation(DMat3::from_cols(row(0), row(1), row(2)), row(3))
        }
        other => {
            return Err(format!(
                "its transform is a {}; raylab reads linear ones (scale, translation, affine), not frustum maps",
                crate::guard::quote(other)
            ));
        }
    };
    let a = Affine3A::from_mat3_translation(d.matrix3.as_mat3(), d.translation.as_vec3());
    if !(a.is_finite() && a.matrix3.determinant().abs() > 0.0) {
        return Err(format!("its transform ({map}) is not invertible"));
    }
    Ok(a)
}
