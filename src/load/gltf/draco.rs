//! `KHR_draco_mesh_compression`: primitives whose attributes and indices are
//! stored as one Draco mesh (bitstream 2.2) in a buffer view. Each such
//! primitive is decoded once after the buffers are read, its values written
//! into a fresh buffer in the component types its accessors declare, and the
//! primitive pointed at new accessors over them, so that every reader
//! downstream sees plain accessors.
//!
//! The bitstream is decoded by `draco-oxide-decoder` (pure Rust), which also
//! dequantizes as Draco does (`min + q · range / (2^bits − 1)` for positions
//! and texture coordinates, the octahedral map for normals). Before it is
//! called, the few counts at the head of the stream are read here and checked
//! against the accessors the JSON declares, and what the accessors will hold
//! is charged to the memory ledger, so that no allocation is sized by a count
//! nothing has checked.
//!
//! The accessors' `componentType`, `type` and `normalized` stay as the file
//! declares them (the extension says they describe the decoded data); their
//! `bufferView`/`byteOffset` are ignored. Their `count` is kept too, with one
//! exception: `draco-oxide` numbers the vertices of an edgebreaker-coded mesh
//! differently from Google's decoder (which the files' accessors were written
//! from), sometimes splitting a few more vertices at attribute seams. The
//! triangles are the same, so when every attribute of the primitive comes from
//! the Draco data (nothing else indexes its vertices) the decoded count is
//! used; a primitive with morph targets or uncompressed attributes beside an
//! edgebreaker mesh, whose vertex order must be Google's, is refused.

use std::collections::BTreeMap;

use gltf::json::validation::{Checked, USize64};
use gltf::json::{self, accessor::ComponentType, accessor::Type, mesh::Semantic};
use serde::Deserialize;

use super::accessor::type_components;
use super::buffers::{Buffers, Unreadable};
use super::error::GltfError;

/// The extension's name.
pub const EXT: &str = "KHR_draco_mesh_compression";

/// The most bytes of decoded attributes and indices one compressed byte may
/// stand for. This is no bound of the format (its entropy coder can code a
/// perfectly regular mesh in almost no bits) but far above what encoders
/// produce: gltf-transform's defaults give 5.7 on the test torus and 7.1 on
/// DamagedHelmet, 6-bit positions 17 on DamagedHelmet. A primitive claiming
/// more is refused as malformed before anything is allocated.
const MAX_EXPANSION: u64 = 1024;

/// The primitive's extension object.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Extension {
    /// The view holding the Draco stream.
    buffer_view: u32,
    /// Draco attribute unique id of each attribute semantic.
    attributes: BTreeMap<String, u32>,
}

/// Whether the file uses the extension.
pub fn used(root: &json::Root) -> bool {
    root.extensions_used.iter().any(|e| e == EXT)
}

/// The triangles and vertices the head of a Draco mesh stream declares
/// (for an edgebreaker stream, the coded vertices plus the split ones, which
/// the decoded vertices may differ from), or `None` if its head is not one
/// this module reads. The fuzz target writes accessors that agree with it.
pub fn stream_counts(bytes: &[u8]) -> Option<(u64, u64)> {
    let head = Head::read(bytes).ok()?;
    match head.vertices {
        Vertices::Exactly(n) | Vertices::AtMost(n) => Some((head.faces, n)),
    }
}

/// One accessor the decoded data fills.
struct Target {
    /// The primitive's attribute semantic, or `None` for the indices.
    semantic: Option<Checked<Semantic>>,
    /// The Draco attribute's unique id (unused for the indices).
    id: u32,
    /// The accessor's index.
    accessor: usize,
    /// Its component type.
    component: ComponentType,
    /// Its components per element.
    components: usize,
}

/// Decodes every primitive that carries the extension: its decoded values
/// are appended to `data` as a new buffer, with views and accessors over
/// them, and the primitive's `attributes`/`indices` are pointed at those.
/// `budget` is called with the bytes each primitive adds before they are
/// allocated; `unreadable` says why buffers left empty could not be read.
pub fn decode_primitives(
    root: &mut json::Root,
    data: &mut Vec<Vec<u8>>,
    unreadable: &[Option<Unreadable>],
    mut budget: impl FnMut(u64) -> Result<(), GltfError>,
) -> Result<(), GltfError> {
    for m in 0..root.meshes.len() {
        for p in 0..root.meshes[m].primitives.len() {
            let prim = &root.meshes[m].primitives[p];
            let Some(value) = prim.extensions.as_ref().and_then(|e| e.others.get(EXT)) else {
                continue;
            };
            let what = match &root.meshes[m].name {
                Some(name) => format!(
                    "mesh {m} ('{}') primitive {p} ({EXT})",
                    crate::guard::one_line(name)
                ),
                None => format!("mesh {m} primitive {p} ({EXT})"),
            };
            let ext = Extension::deserialize(value)
                .map_err(|e| GltfError::invalid(format!("{what}: {e}")))?;
            decode_primitive(root, (data, unreadable), &mut budget, (m, p), &ext)
                .map_err(|e| GltfError::invalid(format!("{what}: {e}")))?;
        }
    }
    Ok(())
}

/// Decodes one primitive (see [`decode_primitives`]); the error is the
/// reason, without the primitive's name.
fn decode_primitive(
    root: &mut json::Root,
    (data, unreadable): (&mut Vec<Vec<u8>>, &[Option<Unreadable>]),
    budget: &mut impl FnMut(u64) -> Result<(), GltfError>,
    (m, p): (usize, usize),
    ext: &Extension,
) -> Result<(), String> {
    let prim = &root.meshes[m].primitives[p];
    if prim.mode != Checked::Valid(json::mesh::Mode::Triangles) {
        return Err("only TRIANGLES primitives can be Draco-compressed here".into());
    }
    // The accessors to fill: the indices, then each attribute the extension
    // names (which must be among the primitive's).
    let index = prim
        .indices
        .ok_or("the primitive has no indices accessor")?
        .value();
    let mut targets = vec![target(root, None, 0, index)?];
    for (name, &id) in &ext.attributes {
        let semantic = prim
            .attributes
            .iter()
            .find(|(s, _)| semantic_name(s).as_deref() == Some(name.as_str()))
            .map(|(s, a)| (s.clone(), a.value()))
            .ok_or_else(|| format!("the extension's attribute {name} is not the primitive's"))?;
        targets.push(target(root, Some(semantic.0), id, semantic.1)?);
    }
    let indices = &targets[0];
    if indices.components != 1
        || !matches!(
            indices.component,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        )
    {
        return Err("the indices accessor is not SCALAR unsigned integers".into());
    }
    let index_count = root.accessors[index].count.0;
    if !index_count.is_multiple_of(3) {
        return Err(format!(
            "{index_count} indices are not a whole number of triangles"
        ));
    }
    let faces = index_count / 3;
    let vertices = root.accessors[targets
        .get(1)
        .ok_or("the extension names no attributes")?
        .accessor]
        .count
        .0;
    for t in &targets[1..] {
        if root.accessors[t.accessor].count.0 != vertices {
            return Err(format!(
                "its attributes' accessors disagree on the vertex count ({} and {vertices})",
                root.accessors[t.accessor].count.0
            ));
        }
    }
    // Whether anything besides the Draco data indexes the vertices (then
    // their number and order must be the file's).
    let others_index_vertices = prim.targets.as_ref().is_some_and(|t| !t.is_empty())
        || prim.attributes.len() > ext.attributes.len();

    let buffers = Buffers {
        root,
        data,
        unreadable,
    };
    let (source, _) = buffers
        .view(ext.buffer_view as usize)
        .map_err(|e| e.to_string())?;
    let head = Head::read(source)?;
    if head.faces != faces {
        return Err(format!(
            "the Draco data holds {} triangles, the indices accessor {faces}",
            head.faces
        ));
    }
    match head.vertices {
        Vertices::Exactly(n) if n != vertices => {
            return Err(format!(
                "the Draco data holds {n} vertices, the accessors {vertices}"
            ));
        }
        Vertices::AtMost(n) if n > 3 * faces => {
            return Err(format!(
                "the Draco data claims {n} vertices for {faces} triangles"
            ));
        }
        Vertices::AtMost(_) if others_index_vertices => {
            return Err(
                "an edgebreaker-coded primitive with morph targets or uncompressed \
                        attributes is not supported (its vertex order is the reference \
                        decoder's)"
                    .into(),
            );
        }
        _ => {}
    }
    // What the accessors will hold, charged before anything is decoded. An
    // edgebreaker mesh may decode to more vertices than the accessors say:
    // up to its corners, charged after decoding.
    let vertex_bytes: u64 = targets[1..].iter().map(element_size).sum();
    let claimed = index_count
        .checked_mul(element_size(&targets[0]))
        .and_then(|i| {
            vertices
                .checked_mul(vertex_bytes)
                .and_then(|v| v.checked_add(i))
        })
        .ok_or("its accessors' sizes overflow")?;
    if claimed > MAX_EXPANSION.saturating_mul(source.len() as u64 + 64) {
        return Err(format!(
            "{claimed} bytes of accessors cannot come from {} compressed bytes",
            source.len()
        ));
    }
    budget(claimed).map_err(|e| e.to_string())?;
    let mesh = crate::guard::catch("draco-oxide-decoder", || {
        draco_oxide_decoder::decode_mesh(source)
    })?
    .map_err(|e| format!("the Draco data is malformed ({e})"))?;

    // The decoded mesh, checked against the accessors.
    if mesh.faces.len() as u64 != faces {
        return Err(format!(
            "the Draco data decodes to {} triangles, the indices accessor {faces}",
            mesh.faces.len()
        ));
    }
    let mut points = None;
    let mut attributes = Vec::with_capacity(targets.len() - 1);
    for t in &targets[1..] {
        let mut found = mesh
            .attributes
            .iter()
            .filter(|a| a.get_id().as_usize() == t.id as usize);
        let (Some(a), None) = (found.next(), found.next()) else {
            return Err(format!(
                "the Draco data has no single attribute of id {}",
                t.id
            ));
        };
        let n = a.len() as u64;
        if *points.get_or_insert(n) != n {
            return Err("the Draco attributes disagree on the vertex count".into());
        }
        if a.get_num_components() != t.components {
            return Err(format!(
                "Draco attribute {} has {} components, its accessor {}",
                t.id,
                a.get_num_components(),
                t.components
            ));
        }
        attributes.push(a);
    }
    let points = points.unwrap_or(0);
    if points != vertices {
        if others_index_vertices || points > 3 * faces {
            return Err(format!(
                "the Draco data decodes to {points} vertices, the accessors say {vertices}"
            ));
        }
        if points > vertices {
            budget((points - vertices) * vertex_bytes).map_err(|e| e.to_string())?;
        }
    }

    // The new buffer: the indices, then each attribute, 4-byte aligned.
    let mut bytes = Vec::new();
    let mut placed = Vec::with_capacity(targets.len());
    let start = bytes.len();
    for f in &mesh.faces {
        for &i in f {
            let i = usize::from(i) as u64;
            if i >= points {
                return Err(format!("a Draco triangle uses vertex {i} of {points}"));
            }
            put_index(&mut bytes, i, targets[0].component)
                .ok_or_else(|| format!("index {i} does not fit the indices accessor's type"))?;
        }
    }
    placed.push((start, bytes.len(), index_count));
    for (t, a) in targets[1..].iter().zip(&attributes) {
        bytes.resize(bytes.len().next_multiple_of(4), 0);
        let start = bytes.len();
        put_attribute(&mut bytes, a, t, points)?;
        placed.push((start, bytes.len(), points));
    }
    let buffer = data.len();
    data.push(bytes);
    for (t, (start, end, count)) in targets.iter().zip(placed) {
        let view = root.buffer_views.len();
        root.buffer_views.push(json::buffer::View {
            buffer: json::Index::new(buffer as u32),
            byte_length: USize64((end - start) as u64),
            byte_offset: Some(USize64(start as u64)),
            byte_stride: None,
            name: None,
            target: None,
            extensions: None,
            extras: Default::default(),
        });
        let mut accessor = root.accessors[t.accessor].clone();
        accessor.buffer_view = Some(json::Index::new(view as u32));
        accessor.byte_offset = Some(USize64(0));
        accessor.count = USize64(count);
        accessor.sparse = None;
        let new = json::Index::new(root.accessors.len() as u32);
        root.accessors.push(accessor);
        let prim = &mut root.meshes[m].primitives[p];
        match &t.semantic {
            None => prim.indices = Some(new),
            Some(s) => {
                prim.attributes.insert(s.clone(), new);
            }
        }
    }
    Ok(())
}

/// The glTF name of an attribute semantic (`POSITION`, `TEXCOORD_0`, …).
fn semantic_name(s: &Checked<Semantic>) -> Option<String> {
    match s {
        Checked::Valid(s) => Some(s.to_string()),
        Checked::Invalid => None,
    }
}

/// The accessor `accessor` as a [`Target`], checked to exist and to have a
/// valid component type and type.
fn target(
    root: &json::Root,
    semantic: Option<Checked<Semantic>>,
    id: u32,
    accessor: usize,
) -> Result<Target, String> {
    let a = root
        .accessors
        .get(accessor)
        .ok_or_else(|| format!("accessor {accessor} does not exist"))?;
    let (Checked::Valid(c), Checked::Valid(ty)) = (a.component_type, a.type_) else {
        return Err(format!("accessor {accessor} has an invalid type"));
    };
    if matches!(ty, Type::Mat2 | Type::Mat3 | Type::Mat4) {
        return Err(format!("accessor {accessor} is a matrix"));
    }
    Ok(Target {
        semantic,
        id,
        accessor,
        component: c.0,
        components: type_components(ty),
    })
}

/// Bytes per component.
fn component_size(c: ComponentType) -> u64 {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Bytes per element of a target's accessor.
fn element_size(t: &Target) -> u64 {
    component_size(t.component) * t.components as u64
}

/// What the head of a Draco mesh stream says of the vertices.
#[derive(Debug, PartialEq)]
enum Vertices {
    /// Sequential coding: the decoded mesh has exactly this many.
    Exactly(u64),
    /// Edgebreaker coding: this many are coded (plus split vertices); the
    /// decoded mesh has at most as many as corners.
    AtMost(u64),
}

/// The counts at the head of a Draco mesh stream (after its header and any
/// metadata), read to check them before the decoder allocates by them.
#[derive(Debug, PartialEq)]
struct Head {
    /// Triangles.
    faces: u64,
    /// Vertices.
    vertices: Vertices,
}

impl Head {
    /// Reads the header (bitstream 2.2, a triangular mesh), skips the
    /// metadata, and reads the connectivity's counts.
    fn read(bytes: &[u8]) -> Result<Head, String> {
        let bad = |why: &str| format!("the Draco data is malformed ({why})");
        let mut r = Reader { bytes, at: 0 };
        if r.take(5).ok_or_else(|| bad("too short"))? != b"DRACO" {
            return Err(bad("no DRACO header"));
        }
        let [major, minor, geometry, method] =
            [r.u8(), r.u8(), r.u8(), r.u8()].map(|b| b.unwrap_or(0xff));
        if (major, minor) != (2, 2) {
            return Err(format!(
                "the Draco data is bitstream {major}.{minor}; the extension uses 2.2"
            ));
        }
        if geometry != 1 {
            return Err(bad("not a triangular mesh"));
        }
        let flags = r.take(2).ok_or_else(|| bad("too short"))?;
        if flags[1] & 0x80 != 0 {
            r.skip_metadata().ok_or_else(|| bad("bad metadata"))?;
        }
        let short = || bad("its connectivity header is cut short");
        match method {
            0 => {
                let faces = r.varint().ok_or_else(short)?;
                let points = r.varint().ok_or_else(short)?;
                Ok(Head {
                    faces,
                    vertices: Vertices::Exactly(points),
                })
            }
            1 => {
                let _traversal = r.u8().ok_or_else(short)?;
                let vertices = r.varint().ok_or_else(short)?;
                let faces = r.varint().ok_or_else(short)?;
                let _attribute_data = r.u8().ok_or_else(short)?;
                let _symbols = r.varint().ok_or_else(short)?;
                let splits = r.varint().ok_or_else(short)?;
                Ok(Head {
                    faces,
                    vertices: Vertices::AtMost(vertices.saturating_add(splits)),
                })
            }
            _ => Err(bad("unknown encoder method")),
        }
    }
}

/// A cursor over a Draco stream's bytes.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.bytes.get(self.at..end)?;
        self.at = end;
        Some(s)
    }

    fn u8(&mut self) -> Option<u8> {
        self.take(1).map(|b| b[0])
    }

    /// An unsigned LEB128 number (at most 64 bits).
    fn varint(&mut self) -> Option<u64> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.u8()?;
            v |= u64::from(b & 0x7f).checked_shl(shift)?;
            if b & 0x80 == 0 {
                return Some(v);
            }
        }
        None
    }

    /// The metadata section: per-attribute blocks, then the geometry's.
    fn skip_metadata(&mut self) -> Option<()> {
        for _ in 0..self.varint()? {
            self.varint()?;
            self.skip_block(0)?;
        }
        self.skip_block(0)
    }

    /// One metadata block: named entries, then named sub-blocks (nested at
    /// most as deep as Draco's own decoder allows).
    fn skip_block(&mut self, depth: u32) -> Option<()> {
        if depth > 1000 {
            return None;
        }
        for _ in 0..self.varint()? {
            let name = self.u8()?;
            self.take(name as usize)?;
            let size = self.varint()?;
            self.take(usize::try_from(size).ok()?)?;
        }
        for _ in 0..self.varint()? {
            let name = self.u8()?;
            self.take(name as usize)?;
            self.skip_block(depth + 1)?;
        }
        Some(())
    }
}

/// Appends index `i` in the accessor's component type; `None` if it does not
/// fit.
fn put_index(out: &mut Vec<u8>, i: u64, c: ComponentType) -> Option<()> {
    match c {
        ComponentType::U8 => out.push(u8::try_from(i).ok()?),
        ComponentType::U16 => out.extend(u16::try_from(i).ok()?.to_le_bytes()),
        _ => out.extend(u32::try_from(i).ok()?.to_le_bytes()),
    }
    Some(())
}

/// Appends the values of Draco attribute `a` at each of its `points` points,
/// in the accessor's component type. Floats go to float accessors; integers
/// to integer accessors that hold every value (Draco keeps integer
/// attributes exact, so `normalized` applies to them as to the plain data).
fn put_attribute(
    out: &mut Vec<u8>,
    a: &draco_oxide_core::attribute::Attribute,
    t: &Target,
    points: u64,
) -> Result<(), String> {
    use draco_oxide_core::attribute::ComponentDataType as D;
    let from = a.get_component_type();
    let size = from.size();
    let n = t.components;
    let values = a.get_data_as_bytes();
    let map = a.point_map_as_slice();
    let mismatch = || {
        format!(
            "Draco attribute {} holds {from:?} values, its accessor {:?}",
            t.id, t.component
        )
    };
    if (from == D::F32) != (t.component == ComponentType::F32)
        || !matches!(
            from,
            D::F32 | D::U8 | D::I8 | D::U16 | D::I16 | D::U32 | D::I32
        )
    {
        return Err(mismatch());
    }
    for p in 0..points as usize {
        let v = map.map_or(Some(p), |m| m.get(p).map(|&v| usize::from(v)));
        let element = v
            .and_then(|v| values.get(v * n * size..(v + 1) * n * size))
            .ok_or_else(|| format!("Draco attribute {} has no value for vertex {p}", t.id))?;
        for c in element.chunks_exact(size) {
            if from == D::F32 {
                out.extend_from_slice(c);
                continue;
            }
            let x: i64 = match from {
                D::U8 => c[0].into(),
                D::I8 => (c[0] as i8).into(),
                D::U16 => u16::from_le_bytes([c[0], c[1]]).into(),
                D::I16 => i16::from_le_bytes([c[0], c[1]]).into(),
                D::U32 => u32::from_le_bytes([c[0], c[1], c[2], c[3]]).into(),
                _ => i32::from_le_bytes([c[0], c[1], c[2], c[3]]).into(),
            };
            let fits = match t.component {
                ComponentType::U8 => u8::try_from(x).map(|x| out.push(x)).is_ok(),
                ComponentType::I8 => i8::try_from(x).map(|x| out.push(x as u8)).is_ok(),
                ComponentType::U16 => u16::try_from(x)
                    .map(|x| out.extend(x.to_le_bytes()))
                    .is_ok(),
                ComponentType::I16 => i16::try_from(x)
                    .map(|x| out.extend(x.to_le_bytes()))
                    .is_ok(),
                _ => u32::try_from(x)
                    .map(|x| out.extend(x.to_le_bytes()))
                    .is_ok(),
            };
            if !fits {
                return Err(mismatch());
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_head_of_each_coding_is_read() {
        let seq = b"DRACO\x02\x02\x01\x00\x00\x00\x90\x03\x45\x00";
        assert_eq!(
            Head::read(seq),
            Ok(Head {
                faces: 400,
                vertices: Vertices::Exactly(0x45)
            })
        );
        let eb = b"DRACO\x02\x02\x01\x01\x00\x00\x00\x10\x20\x01\x20\x03";
        assert_eq!(
            Head::read(eb),
            Ok(Head {
                faces: 0x20,
                vertices: Vertices::AtMost(0x13)
            })
        );
        // With metadata (flag 0x8000): one attribute block with an entry,
        // and an empty geometry block.
        let meta = b"DRACO\x02\x02\x01\x00\x00\x80\x01\x00\x01\x01n\x02ab\x00\x00\x00\x05\x06";
        assert_eq!(
            Head::read(meta),
            Ok(Head {
                faces: 5,
                vertices: Vertices::Exactly(6)
            })
        );
        for bad in [
            &b"DRACO\x02\x02\x01\x00\x00\x00\x90"[..],
            b"DRACO\x02\x03\x01\x00\x00\x00\x01\x01",
            b"DRACX",
        ] {
            assert!(Head::read(bad).is_err(), "{bad:?}");
        }
    }
}
