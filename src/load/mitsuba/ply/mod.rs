//! Mitsuba 3's `ply` shape plugin: a Stanford PLY file read into a
//! [`MitsubaMesh`], following `src/shapes/ply.cpp` and `ply.h` (as of
//! `b45b0a9`, and v3.9.1, which reads the same) and the record conversion of
//! its `struct-jit` library.
//!
//! - **Header**: `ply`, `format ascii|binary_little_endian|binary_big_endian
//!   1.0`, `comment`, `element NAME COUNT`, `property TYPE NAME`, `property
//!   list COUNT_TYPE ITEM_TYPE NAME`, `end_header`; anything else (an
//!   `obj_info` line too) is an error, as in Mitsuba. Types: `char uchar short
//!   ushort int uint float double` and `int8 uint8 int16 uint16 int32 uint32
//!   long ulong half float16 float32 float64`.
//! - **`vertex`**: `x y z` (required, finite); normals when `nx ny nz` are
//!   all there; texture coordinates from `u v`, else `texture_u texture_v`,
//!   else `s t` (`flip_tex_coords`: `v ← 1 − v`). Every other property is an
//!   attribute (below).
//! - **`face`**: the indices come from the `vertex_indices` (or
//!   `vertex_index`) list. Mitsuba reads every list as exactly three
//!   entries and refuses any other count ("is this a triangle mesh?"):
//!   quads and polygons are refused, not triangulated; so is any face
//!   element's list of another length. Every other property is an attribute.
//! - **Other elements** are skipped with a warning.
//! - **Values**: an *integer* property read as a number (a position, a
//!   normal, an attribute) is normalised (divided by its type's maximum:
//!   `uchar` 255 → 1) and decoded from sRGB to linear, as Mitsuba's PLY
//!   header marks every integer property; float properties are taken as
//!   they are. Indices are converted as C does (an `int` −1 becomes
//!   4 294 967 295, then out of range).
//! - **Attributes** (Mitsuba's `find_other_fields`): `r g b [a]` or `red
//!   green blue [alpha]` become `vertex_color` (`face_color`); then runs of
//!   consecutive properties `PREFIX_x y z [w]`, `PREFIX_r g b [a]`,
//!   `PREFIX_0 1 2 [3]` or `PREFIX_1 2 3 [4]` become `vertex_PREFIX` (with
//!   `_color` appended for the `r g b` scheme), kept only with 1 or 3
//!   properties. Everything else is ignored with Mitsuba's warning.
//! - A binary file must end after its last element, an ASCII file's data
//!   must hold no token more.
//!
//! Where raylab differs: the lists of a *skipped* element are read with the
//! length each record gives (Mitsuba skips three entries a list); indices are
//! checked against the vertex count; two `vertex` (or `face`) elements are an
//! error; an ASCII number must be the whole token (`1.5` is no `int`), and an
//! ASCII float must be finite.

use std::collections::HashSet;
use std::path::Path;

use crate::guard::one_line;
use crate::memory::Ledger;

mod attributes;
mod header;
mod values;

use super::error::MitsubaError;
use super::mesh::{MeshAttribute, MitsubaMesh, check_size, read_file};
use attributes::find_other_fields;
use header::{Element, Header, Num, Prop, parse_header};
use values::{ReadError, Source, to_f32};

/// Reads the PLY file `path` as Mitsuba's `ply` plugin does, checking the
/// memory it needs against `ledger` (nothing is charged).
pub fn read_ply(
    path: &Path,
    flip_tex_coords: bool,
    ledger: &Ledger,
) -> Result<MitsubaMesh, MitsubaError> {
    let bytes = read_file(path, ledger)?;
    parse_ply(&bytes, path, flip_tex_coords, ledger)
}

/// Reads `bytes` as the PLY file `path` (which errors and warnings name).
pub fn parse_ply(
    bytes: &[u8],
    path: &Path,
    flip_tex_coords: bool,
    ledger: &Ledger,
) -> Result<MitsubaMesh, MitsubaError> {
    let (header, data_start) = parse_header(bytes, path)?;
    Reader {
        path,
        file: one_line(&path.display().to_string()).into_owned(),
        ledger,
    }
    .read(header, &bytes[data_start..], flip_tex_coords)
}

struct Reader<'a> {
    path: &'a Path,
    /// The file as errors and warnings name it.
    file: String,
    ledger: &'a Ledger,
}

impl Reader<'_> {
    fn err(&self, m: impl AsRef<str>) -> MitsubaError {
        MitsubaError::mesh(self.path, m)
    }

    fn read(
        &self,
        mut header: Header,
        data: &[u8],
        flip_tex_coords: bool,
    ) -> Result<MitsubaMesh, MitsubaError> {
        let mut mesh = MitsubaMesh::default();
        for name in ["vertex", "face"] {
            if header.elements.iter().filter(|e| e.name == name).count() > 1 {
                return Err(self.err(format!("more than one \"{name}\" element")));
            }
        }
        let vertex_count = header
            .elements
            .iter()
            .find(|e| e.name == "vertex")
            .map_or(0, |e| e.count);
        let mut source = if header.ascii {
            Source::Ascii { data, pos: 0 }
        } else {
            Source::Binary { data, pos: 0 }
        };
        for el in &mut header.elements {
            self.check_present(el, &source)?;
            match el.name.as_str() {
                "vertex" => self.read_vertices(el, &mut source, flip_tex_coords, &mut mesh)?,
                "face" => self.read_faces(el, &mut source, vertex_count, &mut mesh)?,
                _ => {
                    mesh.warnings.push(format!(
                        "{}: skipping unknown element \"{}\"",
                        self.file,
                        one_line(&el.name)
                    ));
                    let mut values = Vec::new();
                    // (An element without properties has nothing to read,
                    // however many records it declares.)
                    let records = if el.props.is_empty() { 0 } else { el.count };
                    for i in 0..records {
                        self.read_record(el, &mut source, i, false, &mut values)?;
                    }
                }
            }
        }
        let left = source.remaining();
        let ascii = matches!(source, Source::Ascii { .. });
        if ascii && source.next_token().is_some() {
            Err(self.err("trailing tokens after the last element"))
        } else if !ascii && left > 0 {
            Err(self.err(format!(
                "invalid file: {left} bytes of trailing content after the last element"
            )))
        } else {
            Ok(mesh)
        }
    }

    /// Checks that the data left can hold `el`'s records (each at least its
    /// fixed bytes, or one token a value) before any is allocated for.
    fn check_present(&self, el: &Element, source: &Source) -> Result<(), MitsubaError> {
        let triangles = el.name == "vertex" || el.name == "face";
        let ascii = matches!(source, Source::Ascii { .. });
        let per_record: u64 = el
            .props
            .iter()
            .map(|(_, p)| match (p, ascii) {
                (Prop::Scalar { .. }, true) => 1,
                (Prop::Scalar { ty }, false) => ty.size() as u64,
                (Prop::List { .. }, true) => 1 + if triangles { 3 } else { 0 },
                (Prop::List { count, item }, false) => {
                    (count.size() + if triangles { 3 * item.size() } else { 0 }) as u64
                }
            })
            .sum();
        let (unit, per) = if ascii {
            // Values in text are separated: a value takes 2 bytes but the last.
            ("values", per_record)
        } else {
            ("bytes", per_record)
        };
        let room = source.remaining() as u64;
        let room = if ascii { room.div_ceil(2) } else { room };
        if per > 0 && el.count > room / per {
            return Err(self.err(format!(
                "element \"{}\": {} records of at least {per} {unit} each, but {} {unit} at most follow",
                one_line(&el.name),
                el.count,
                room
            )));
        }
        Ok(())
    }

    /// Reads record `index` of `el` into `values` (one per field). In a
    /// `vertex` or `face` element (`triangles`), every list must have three
    /// entries; elsewhere lists are skipped whatever their length.
    fn read_record(
        &self,
        el: &Element,
        source: &mut Source,
        index: u64,
        triangles: bool,
        values: &mut Vec<Num>,
    ) -> Result<(), MitsubaError> {
        values.clear();
        let what = || format!("{} {index}", one_line(&el.name));
        let fail = |e: ReadError, prop: &str| match e {
            ReadError::End => self.err(format!("{}: the file ends early", what())),
            ReadError::Bad(m) => self.err(format!(
                "{}: {m} for property \"{}\"",
                what(),
                one_line(prop)
            )),
        };
        for (name, prop) in &el.props {
            match *prop {
                Prop::Scalar { ty } => {
                    values.push(source.read(ty, el.big_endian).map_err(|e| fail(e, name))?);
                }
                Prop::List { count, item } => {
                    let n = source
                        .read(count, el.big_endian)
                        .map_err(|e| fail(e, name))?;
                    if triangles {
                        if !n.is_three() {
                            return Err(self.err(format!(
                                "{}: list \"{}\" has {} entries, not 3 (Mitsuba's ply reads triangles only)",
                                what(),
                                one_line(name),
                                match n {
                                    Num::I(i) => i.to_string(),
                                    Num::U(u) => u.to_string(),
                                    Num::F(f) => f.to_string(),
                                }
                            )));
                        }
                        values.push(n);
                        for _ in 0..3 {
                            values.push(
                                source
                                    .read(item, el.big_endian)
                                    .map_err(|e| fail(e, name))?,
                            );
                        }
                    } else {
                        let Some(n) = n.as_len() else {
                            return Err(self.err(format!(
                                "{}: list \"{}\" has no valid length",
                                what(),
                                one_line(name)
                            )));
                        };
                        match source {
                            Source::Binary { data, pos } => {
                                let bytes = n.checked_mul(item.size() as u64);
                                match bytes {
                                    Some(b) if b <= (data.len() - *pos) as u64 => {
                                        *pos += b as usize;
                                    }
                                    _ => return Err(fail(ReadError::End, name)),
                                }
                            }
                            Source::Ascii { .. } => {
                                for _ in 0..n {
                                    source
                                        .read(item, el.big_endian)
                                        .map_err(|e| fail(e, name))?;
                                }
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    fn read_vertices(
        &self,
        el: &mut Element,
        source: &mut Source,
        flip_tex_coords: bool,
        mesh: &mut MitsubaMesh,
    ) -> Result<(), MitsubaError> {
        let has_normals = el.has("nx") && el.has("ny") && el.has("nz");
        if !(el.has("u") && el.has("v")) {
            if el.has("texture_u") && el.has("texture_v") {
                el.rename("texture_u", "u");
                el.rename("texture_v", "v");
            } else if el.has("s") && el.has("t") {
                el.rename("s", "u");
                el.rename("t", "v");
            }
        }
        let has_uvs = el.has("u") && el.has("v");
        let mut position = [0; 3];
        for (p, n) in position.iter_mut().zip(["x", "y", "z"]) {
            *p = el
                .field(n)
                .ok_or_else(|| self.err(format!("the vertex element has no property \"{n}\"")))?;
        }
        let normal = has_normals.then(|| ["nx", "ny", "nz"].map(|n| el.field(n).unwrap_or(0)));
        let uv = has_uvs.then(|| ["u", "v"].map(|n| el.field(n).unwrap_or(0)));
        let mut reserved: HashSet<String> = ["x", "y", "z", "nx", "ny", "nz", "u", "v"]
            .into_iter()
            .map(String::from)
            .collect();
        let descriptors =
            find_other_fields("vertex_", el, &mut reserved, &self.file, &mut mesh.warnings)
                .map_err(|m| self.err(m))?;
        let channels: u64 = descriptors.iter().map(|d| d.fields.len() as u64).sum();
        let per_vertex =
            12 + if has_normals { 12 } else { 0 } + if has_uvs { 8 } else { 0 } + 4 * channels;
        check_size(self.path, "", el.count, 0, per_vertex, self.ledger)?;

        let n = el.count as usize;
        let mut positions = Vec::with_capacity(n);
        let mut normals = normal.map(|_| Vec::with_capacity(n));
        let mut uvs = uv.map(|_| Vec::with_capacity(n));
        let mut attrs: Vec<Vec<f32>> = descriptors
            .iter()
            .map(|d| Vec::with_capacity(n * d.fields.len()))
            .collect();
        let mut values = Vec::with_capacity(el.fields.len());
        let f = |values: &[Num], i: usize| to_f32(&el.fields[i], values[i]);
        for index in 0..el.count {
            self.read_record(el, source, index, true, &mut values)?;
            let p = position.map(|i| f(&values, i));
            if !p.iter().all(|c| c.is_finite()) {
                return Err(self.err(format!("vertex {index}: position is not finite")));
            }
            positions.push(p);
            if let (Some(normals), Some(idx)) = (&mut normals, normal) {
                normals.push(idx.map(|i| f(&values, i)));
            }
            if let (Some(uvs), Some(idx)) = (&mut uvs, uv) {
                let [u, v] = idx.map(|i| f(&values, i));
                uvs.push([u, if flip_tex_coords { 1.0 - v } else { v }]);
            }
            for (d, out) in descriptors.iter().zip(&mut attrs) {
                out.extend(d.fields.iter().map(|&i| f(&values, i)));
            }
        }
        mesh.positions = positions;
        mesh.normals = normals;
        mesh.uvs = uvs;
        for (d, values) in descriptors.into_iter().zip(attrs) {
            if d.name == "vertex_color" && d.fields.len() >= 3 {
                let c = d.fields.len();
                mesh.colors = Some(values.chunks_exact(c).map(|v| [v[0], v[1], v[2]]).collect());
            }
            mesh.vertex_attributes.push(MeshAttribute {
                name: d.name,
                channels: d.fields.len(),
                values,
            });
        }
        Ok(())
    }

    fn read_faces(
        &self,
        el: &mut Element,
        source: &mut Source,
        vertex_count: u64,
        mesh: &mut MitsubaMesh,
    ) -> Result<(), MitsubaError> {
        let list = el
            .props
            .iter()
            .position(|(n, p)| matches!(p, Prop::List { .. }) && n == "vertex_indices")
            .or_else(|| {
                el.props
                    .iter()
                    .position(|(n, p)| matches!(p, Prop::List { .. }) && n == "vertex_index")
            })
            .ok_or_else(|| {
                self.err("the face element has no vertex_index or vertex_indices list")
            })?;
        // The field of the list's first entry: after the fields of the
        // properties before it.
        let first: usize = el.props[..list]
            .iter()
            .map(|(_, p)| match p {
                Prop::Scalar { .. } => 1,
                Prop::List { .. } => 4,
            })
            .sum::<usize>()
            + 1;
        let mut reserved: HashSet<String> = [
            "vertex_index.count",
            "vertex_indices.count",
            "i0",
            "i1",
            "i2",
        ]
        .into_iter()
        .map(String::from)
        .collect();
        let descriptors =
            find_other_fields("face_", el, &mut reserved, &self.file, &mut mesh.warnings)
                .map_err(|m| self.err(m))?;
        let channels: u64 = descriptors.iter().map(|d| d.fields.len() as u64).sum();
        check_size(self.path, "", 0, el.count, 0, self.ledger)?;
        // The face attributes' share, beyond the triangles' estimate.
        check_size(
            self.path,
            "",
            el.count.saturating_mul(channels) / 3,
            0,
            0,
            self.ledger,
        )?;

        let n = el.count as usize;
        let mut indices = Vec::with_capacity(n);
        let mut attrs: Vec<Vec<f32>> = descriptors
            .iter()
            .map(|d| Vec::with_capacity(n * d.fields.len()))
            .collect();
        let mut values = Vec::with_capacity(el.fields.len());
        for index in 0..el.count {
            self.read_record(el, source, index, true, &mut values)?;
            let tri = [0, 1, 2].map(|k| values[first + k].as_index());
            if let Some(&bad) = tri.iter().find(|&&i| i as u64 >= vertex_count) {
                return Err(self.err(format!(
                    "face {index}: vertex index {bad} out of range ({vertex_count} vertices)"
                )));
            }
            indices.push(tri);
            for (d, out) in descriptors.iter().zip(&mut attrs) {
                out.extend(d.fields.iter().map(|&i| to_f32(&el.fields[i], values[i])));
            }
        }
        mesh.indices = indices;
        for (d, values) in descriptors.into_iter().zip(attrs) {
            mesh.face_attributes.push(MeshAttribute {
                name: d.name,
                channels: d.fields.len(),
                values,
            });
        }
        Ok(())
    }
}
