//! The PLY header: elements, their properties, and the record layout
//! Mitsuba's reader makes of them.

use std::path::Path;

use crate::guard::one_line;

use super::super::error::MitsubaError;

/// A property's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F16,
    F32,
    F64,
}

impl Ty {
    pub(super) fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "long" => Ty::I64,
            "ulong" => Ty::U64,
            "half" | "float16" => Ty::F16,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 | Ty::F16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::I64 | Ty::U64 | Ty::F64 => 8,
        }
    }

    pub(super) fn is_int(self) -> bool {
        !matches!(self, Ty::F16 | Ty::F32 | Ty::F64)
    }

    /// Mitsuba's name of the type in its ASCII errors.
    pub(super) fn name(self) -> &'static str {
        match self {
            Ty::I8 => "char",
            Ty::U8 => "uchar",
            Ty::I16 => "short",
            Ty::U16 => "ushort",
            Ty::I32 => "int",
            Ty::U32 => "uint",
            Ty::I64 => "long",
            Ty::U64 => "ulong",
            Ty::F16 => "half",
            Ty::F32 => "float",
            Ty::F64 => "double",
        }
    }

    /// The largest value of an integer type (what a normalised value is
    /// divided by).
    pub(super) fn max(self) -> f64 {
        match self {
            Ty::I8 => i8::MAX as f64,
            Ty::U8 => u8::MAX as f64,
            Ty::I16 => i16::MAX as f64,
            Ty::U16 => u16::MAX as f64,
            Ty::I32 => i32::MAX as f64,
            Ty::U32 => u32::MAX as f64,
            Ty::I64 => i64::MAX as f64,
            Ty::U64 => u64::MAX as f64,
            _ => 1.0,
        }
    }
}

/// A value as read, before conversion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Num {
    I(i64),
    U(u64),
    F(f64),
}

impl Num {
    /// Whether the value is 3 (a list's required length; Mitsuba compares
    /// the stored value with 3 in the count's own type).
    pub(super) fn is_three(self) -> bool {
        matches!(self, Num::I(3) | Num::U(3)) || self == Num::F(3.0)
    }

    /// A list length that is a non-negative whole number.
    pub(super) fn as_len(self) -> Option<u64> {
        match self {
            Num::I(i) => u64::try_from(i).ok(),
            Num::U(u) => Some(u),
            Num::F(f) if f >= 0.0 && f.fract() == 0.0 && f < 1.8e19 => Some(f as u64),
            Num::F(_) => None,
        }
    }

    /// The value as an index, converted as Mitsuba's converter does: C's
    /// integer conversion (wrapping), or a float rounded to nearest and
    /// clamped.
    pub(super) fn as_index(self) -> u32 {
        match self {
            Num::I(i) => i as u32,
            Num::U(u) => u as u32,
            Num::F(f) => f.round_ties_even().clamp(0.0, u32::MAX as f64) as u32,
        }
    }
}

/// A property of an element as the header declares it.
#[derive(Clone, Debug)]
pub(super) enum Prop {
    /// A value.
    Scalar { ty: Ty },
    /// A list: its length, then its entries.
    List { count: Ty, item: Ty },
}

/// One field of a record as Mitsuba lays it out: a scalar property, or a
/// list's `NAME.count` followed by `i0`, `i1`, `i2`.
#[derive(Clone, Debug)]
pub(super) struct Field {
    /// The name (renamed as Mitsuba renames: `texture_u` → `u`, `red` → `r`).
    pub(super) name: String,
    pub(super) ty: Ty,
    /// An integer scalar: normalised and sRGB-decoded when read as a float.
    pub(super) normalized: bool,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    /// The properties with their names.
    pub(super) props: Vec<(String, Prop)>,
    pub(super) big_endian: bool,
    /// The fields, one value of a record each (lists as four).
    pub(super) fields: Vec<Field>,
}

impl Element {
    /// The first field called `name` (the one Mitsuba's converter reads).
    pub(super) fn field(&self, name: &str) -> Option<usize> {
        self.fields.iter().position(|f| f.name == name)
    }

    pub(super) fn has(&self, name: &str) -> bool {
        self.field(name).is_some()
    }

    /// Renames the first field called `from` (as Mitsuba renames fields of
    /// its record layout).
    pub(super) fn rename(&mut self, from: &str, to: &str) {
        if let Some(i) = self.field(from) {
            self.fields[i].name = to.to_owned();
        }
    }
}

pub(super) struct Header {
    pub(super) ascii: bool,
    pub(super) elements: Vec<Element>,
}

/// Parses the header; returns it and where the data starts.
pub(super) fn parse_header(bytes: &[u8], path: &Path) -> Result<(Header, usize), MitsubaError> {
    let err = |m: String| MitsubaError::mesh(path, format!("invalid PLY header: {m}"));
    let mut pos = 0;
    let mut ply_seen = false;
    let mut format_seen = false;
    let mut big_endian = false;
    let mut ascii = false;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(err("the file ends before \"end_header\"".into()));
        }
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let line = String::from_utf8_lossy(&bytes[pos..end]);
        pos = (end + 1).min(bytes.len());
        let mut tokens = line.split_ascii_whitespace();
        let Some(first) = tokens.next() else { continue };
        let mut next = |what: &str| {
            tokens
                .next()
                .map(str::to_owned)
                .ok_or_else(|| err(format!("missing token after \"{what}\"")))
        };
        match first {
            "comment" => continue,
            "ply" => {
                if ply_seen {
                    return Err(err("duplicate \"ply\" tag".into()));
                }
                ply_seen = true;
            }
            "format" => {
                if !ply_seen {
                    return Err(err("\"format\" before \"ply\" tag".into()));
                }
                if format_seen {
                    return Err(err("duplicate \"format\" tag".into()));
                }
                match next("format")?.as_str() {
                    "ascii" => ascii = true,
                    "binary_little_endian" => big_endian = false,
                    "binary_big_endian" => big_endian = true,
                    other => {
                        return Err(err(format!("unknown format \"{}\"", one_line(other))));
                    }
                }
                let version = next("format")
                    .map_err(|_| err("missing version number after \"format\"".into()))?;
                if version != "1.0" {
                    return Err(MitsubaError::mesh(
                        path,
                        format!(
                            "PLY file has unknown version number \"{}\"",
                            one_line(&version)
                        ),
                    ));
                }
                format_seen = true;
            }
            "element" => {
                let name = next("element")?;
                let count = next("element")?;
                let count = count.parse::<u64>().map_err(|_| {
                    err(format!(
                        "element \"{}\": count \"{}\" is not a number",
                        one_line(&name),
                        one_line(&count)
                    ))
                })?;
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                    // An element declared before `format` keeps the native
                    // (little-endian) order, as in Mitsuba.
                    big_endian,
                    fields: Vec::new(),
                });
            }
            "property" => {
                if !format_seen {
                    return Err(err("encountered \"property\" before \"format\"".into()));
                }
                let Some(element) = elements.last_mut() else {
                    return Err(err("encountered \"property\" before \"element\"".into()));
                };
                let ty = |t: String| {
                    Ty::parse(&t)
                        .ok_or_else(|| err(format!("unknown format type \"{}\"", one_line(&t))))
                };
                let token = next("property")?;
                if token == "list" {
                    let count = ty(next("property list")?)?;
                    let item = ty(next("property list")?)?;
                    let name = next("property list")?;
                    element.fields.push(Field {
                        name: format!("{name}.count"),
                        ty: count,
                        normalized: false,
                    });
                    for i in 0..3 {
                        element.fields.push(Field {
                            name: format!("i{i}"),
                            ty: item,
                            normalized: false,
                        });
                    }
                    element.props.push((name, Prop::List { count, item }));
                } else {
                    let t = ty(token)?;
                    let name = next("property")?;
                    element.fields.push(Field {
                        name: name.clone(),
                        ty: t,
                        normalized: t.is_int(),
                    });
                    element.props.push((name, Prop::Scalar { ty: t }));
                }
            }
            "end_header" => {
                if tokens.next().is_some() {
                    return Err(err("excess tokens after \"end_header\"".into()));
                }
                break;
            }
            other => return Err(err(format!("unknown token \"{}\"", one_line(other)))),
        }
        // (Mitsuba ignores what follows an element's count.)
        if first == "element" {
            continue;
        }
        if let Some(extra) = tokens.next() {
            return Err(err(format!(
                "excess token \"{}\" after \"{first}\"",
                one_line(extra)
            )));
        }
    }
    if !format_seen {
        return Err(MitsubaError::mesh(
            path,
            "invalid PLY file: no header information (no \"format\" line)",
        ));
    }
    Ok((Header { ascii, elements }, pos))
}
