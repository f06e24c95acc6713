//! Reading the values of PLY records (binary or ASCII) and converting them
//! as Mitsuba's record converter does.

use crate::guard::one_line;

use super::header::{Field, Num, Ty};

/// Where the values of the records come from.
pub(super) enum Source<'a> {
    Binary { data: &'a [u8], pos: usize },
    Ascii { data: &'a [u8], pos: usize },
}

/// Why a value could not be read.
pub(super) enum ReadError {
    End,
    Bad(String),
}

impl Source<'_> {
    /// Bytes (binary) left.
    pub(super) fn remaining(&self) -> usize {
        match self {
            Source::Binary { data, pos } | Source::Ascii { data, pos } => data.len() - pos,
        }
    }

    pub(super) fn next_token(&mut self) -> Option<&[u8]> {
        let Source::Ascii { data, pos } = self else {
            return None;
        };
        let data: &[u8] = data;
        while *pos < data.len() && data[*pos].is_ascii_whitespace() {
            *pos += 1;
        }
        if *pos == data.len() {
            return None;
        }
        let start = *pos;
        while *pos < data.len() && !data[*pos].is_ascii_whitespace() {
            *pos += 1;
        }
        Some(&data[start..*pos])
    }

    pub(super) fn read(&mut self, ty: Ty, big_endian: bool) -> Result<Num, ReadError> {
        match self {
            Source::Binary { data, pos } => {
                let n = ty.size();
                if data.len() - *pos < n {
                    return Err(ReadError::End);
                }
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&data[*pos..*pos + n]);
                *pos += n;
                if big_endian {
                    b[..n].reverse();
                }
                Ok(match ty {
                    Ty::I8 => Num::I(b[0] as i8 as i64),
                    Ty::U8 => Num::U(b[0] as u64),
                    Ty::I16 => Num::I(i16::from_le_bytes([b[0], b[1]]) as i64),
                    Ty::U16 => Num::U(u16::from_le_bytes([b[0], b[1]]) as u64),
                    Ty::I32 => Num::I(i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64),
                    Ty::U32 => Num::U(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64),
                    Ty::I64 => Num::I(i64::from_le_bytes(b)),
                    Ty::U64 => Num::U(u64::from_le_bytes(b)),
                    Ty::F16 => Num::F(half_to_f32(u16::from_le_bytes([b[0], b[1]])) as f64),
                    Ty::F32 => Num::F(f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
                    Ty::F64 => Num::F(f64::from_le_bytes(b)),
                })
            }
            Source::Ascii { .. } => {
                let token = self.next_token().ok_or(ReadError::End)?;
                let text = std::str::from_utf8(token).unwrap_or("");
                let bad = || {
                    ReadError::Bad(format!(
                        "could not parse \"{}\" value \"{}\"",
                        ty.name(),
                        one_line(&String::from_utf8_lossy(token))
                    ))
                };
                Ok(match ty {
                    Ty::I8 => Num::I(text.parse::<i8>().map_err(|_| bad())? as i64),
                    Ty::U8 => Num::U(text.parse::<u8>().map_err(|_| bad())? as u64),
                    Ty::I16 => Num::I(text.parse::<i16>().map_err(|_| bad())? as i64),
                    Ty::U16 => Num::U(text.parse::<u16>().map_err(|_| bad())? as u64),
                    Ty::I32 => Num::I(text.parse::<i32>().map_err(|_| bad())? as i64),
                    Ty::U32 => Num::U(text.parse::<u32>().map_err(|_| bad())? as u64),
                    Ty::I64 => Num::I(text.parse::<i64>().map_err(|_| bad())?),
                    Ty::U64 => Num::U(text.parse::<u64>().map_err(|_| bad())?),
                    Ty::F16 | Ty::F32 => {
                        let v = text.parse::<f32>().map_err(|_| bad())?;
                        if !v.is_finite() {
                            return Err(bad());
                        }
                        Num::F(if ty == Ty::F16 { round_to_half(v) } else { v } as f64)
                    }
                    Ty::F64 => {
                        let v = text.parse::<f64>().map_err(|_| bad())?;
                        if !v.is_finite() {
                            return Err(bad());
                        }
                        Num::F(v)
                    }
                })
            }
        }
    }
}

/// An IEEE half (binary16) as `f32`.
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let mant = (h & 0x3ff) as f32;
    sign * match exp {
        0 => mant * (2f32).powi(-24),
        31 if mant == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        _ => (1.0 + mant / 1024.0) * (2f32).powi(exp - 15),
    }
}

/// `v` rounded to the nearest half (ties to even), as a text value stored
/// as a `half` is; beyond the largest half it becomes infinite.
fn round_to_half(v: f32) -> f32 {
    let a = v.abs() as f64;
    if a >= 65520.0 {
        return f32::INFINITY.copysign(v);
    }
    // The spacing of halves around `a`: 2^-24 below 2^-14 (subnormals), else
    // 2^(e - 10) for a in [2^e, 2^(e+1)).
    let quantum = if a < 2f64.powi(-14) {
        2f64.powi(-24)
    } else {
        let e = ((a.to_bits() >> 52) as i32 & 0x7ff) - 1023;
        2f64.powi(e - 10)
    };
    ((a / quantum).round_ties_even() * quantum).copysign(v as f64) as f32
}

/// sRGB-encoded `v` (in [0, 1]) to linear, as Mitsuba decodes normalised
/// integer properties.
fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A field's value as the float Mitsuba's converter makes of it.
pub(super) fn to_f32(field: &Field, v: Num) -> f32 {
    match v {
        Num::F(f) => f as f32,
        Num::I(_) | Num::U(_) => {
            let x = match v {
                Num::I(i) => i as f32,
                Num::U(u) => u as f32,
                Num::F(_) => unreachable!(),
            };
            if field.normalized {
                srgb_to_linear(x * (1.0 / field.ty.max()) as f32)
            } else {
                x
            }
        }
    }
}
