//! Reading the text of values as Mitsuba 3 does (`parser.cpp`, with
//! `string.cpp`'s `tokenize` and `stof`, `properties.cpp`'s spectrum and
//! `util.h`'s `Version`). Every function returns the message of what is
//! wrong; the caller adds the file and line.

use glam::Vec3;

use super::tree::Spectrum;
use crate::guard::quote;

/// The items of a list: split at commas and spaces (Mitsuba's `tokenize`
/// with its default delimiters `", "`), empty items dropped. Tabs and line
/// breaks inside an attribute are spaces already (XML normalizes them).
pub(super) fn tokens(text: &str) -> impl Iterator<Item = &str> {
    text.split([',', ' ']).filter(|t| !t.is_empty())
}

/// A number as Mitsuba's `stof<double>` reads it: spaces and tabs around
/// it, one leading `+`, then a decimal number (`1`, `-2.5`, `.5`, `3.`,
/// `1e-3`); unlike Mitsuba, `inf` and `nan` (and numbers beyond `f64`) are
/// refused: no plugin wants them.
pub(super) fn number(text: &str) -> Result<f64, String> {
    let bad = || format!("could not parse floating point value \"{}\"", quote(text));
    let t = text.trim_matches([' ', '\t']);
    let t = t.strip_prefix('+').unwrap_or(t);
    // Rust's parser also takes a second '+', and words Mitsuba's does not.
    let first = t.bytes().next().ok_or_else(bad)?;
    if !(first.is_ascii_digit() || first == b'-' || first == b'.') {
        return Err(bad());
    }
    let v: f64 = t.parse().map_err(|_| bad())?;
    match v.is_finite() {
        true => Ok(v),
        false => Err(format!(
            "floating point value \"{}\" is not finite",
            quote(text)
        )),
    }
}

/// `v` in single precision, refused if it does not fit (1e39).
pub(super) fn single(v: f64, text: &str) -> Result<f32, String> {
    let s = v as f32;
    match s.is_finite() {
        true => Ok(s),
        false => Err(format!(
            "value \"{}\" is beyond single precision",
            quote(text)
        )),
    }
}

/// A `<float value=…>`: one number, in single precision.
pub(super) fn float(text: &str) -> Result<f32, String> {
    single(number(text)?, text)
}

/// An `<integer value=…>` as Mitsuba reads it (`std::from_chars` into an
/// `int64_t`): leading and trailing white space, an optional `-`, digits;
/// no `+`, no fraction; beyond 64 bits is an error.
pub(super) fn integer(text: &str) -> Result<i64, String> {
    let t = text.trim_matches(|c: char| c.is_ascii_whitespace() || c == '\u{b}');
    let digits = t.strip_prefix('-').unwrap_or(t);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("could not parse integer value \"{}\"", quote(text)));
    }
    t.parse()
        .map_err(|_| format!("integer value \"{}\" does not fit in 64 bits", quote(text)))
}

/// A `<boolean value=…>`: `true` or `false`, in any case.
pub(super) fn boolean(text: &str) -> Result<bool, String> {
    if text.eq_ignore_ascii_case("true") {
        Ok(true)
    } else if text.eq_ignore_ascii_case("false") {
        Ok(false)
    } else {
        Err(format!(
            "could not parse boolean value \"{}\" (must be \"true\" or \"false\")",
            quote(text)
        ))
    }
}

/// An `<rgb value=…>`: three numbers, or one for all three.
pub(super) fn rgb(text: &str) -> Result<[f32; 3], String> {
    let list: Vec<&str> = tokens(text).take(4).collect();
    let one = |t: &str| number(t).and_then(|v| single(v, t));
    match list.as_slice() {
        [v] => Ok([one(v)?; 3]),
        [r, g, b] => Ok([one(r)?, one(g)?, one(b)?]),
        _ => Err(format!(
            "<rgb> needs one or three values, not {} (\"{}\")",
            count(text),
            quote(text)
        )),
    }
}

/// How many items a list has (for messages only).
fn count(text: &str) -> usize {
    tokens(text).count()
}

/// Exactly three numbers (`lookat`'s `origin`, `target`, `up`), in `f64`.
pub(super) fn triple(text: &str) -> Result<[f64; 3], String> {
    let list: Vec<&str> = tokens(text).take(4).collect();
    match list.as_slice() {
        [x, y, z] => Ok([number(x)?, number(y)?, number(z)?]),
        _ => Err(format!(
            "expected 3 values, got {} (\"{}\")",
            count(text),
            quote(text)
        )),
    }
}

/// The `x`, `y`, `z` a `value=` stands for (Mitsuba's
/// `expand_value_to_xyz`): one item for all three, or three.
pub(super) fn expand_xyz(text: &str) -> Result<[&str; 3], String> {
    let list: Vec<&str> = tokens(text).take(4).collect();
    match list.as_slice() {
        [v] => Ok([v, v, v]),
        [x, y, z] => Ok([x, y, z]),
        _ => Err(format!(
            "\"value\" must have 1 or 3 elements, not {} (\"{}\")",
            count(text),
            quote(text)
        )),
    }
}

/// A point or vector from its three components, in single precision.
pub(super) fn vec3(xyz: [&str; 3]) -> Result<Vec3, String> {
    let mut v = [0.0f32; 3];
    for (out, t) in v.iter_mut().zip(xyz) {
        *out = single(number(t)?, t)?;
    }
    Ok(Vec3::from(v))
}

/// A `<spectrum value=…>` (Mitsuba's `Properties::Spectrum(string)`): one
/// number without a colon is a constant; otherwise every item is
/// `wavelength:value`, at least two, wavelengths strictly increasing.
pub(super) fn spectrum(text: &str) -> Result<Spectrum, String> {
    let list: Vec<&str> = tokens(text).collect();
    if let [v] = list.as_slice()
        && !v.contains(':')
    {
        return Ok(Spectrum::Constant(single(number(v)?, v)?));
    }
    let mut pairs = Vec::with_capacity(list.len());
    for item in list {
        let parts: Vec<&str> = item.split(':').filter(|p| !p.is_empty()).collect();
        let [w, v] = parts.as_slice() else {
            return Err(format!(
                "invalid spectrum value \"{}\" (expected wavelength:value pairs)",
                quote(item)
            ));
        };
        let pair = (single(number(w)?, w)?, single(number(v)?, v)?);
        if let Some(&(last, _)) = pairs.last()
            && pair.0 <= last
        {
            return Err(format!(
                "spectrum wavelengths must increase: {} after {last}",
                pair.0
            ));
        }
        pairs.push(pair);
    }
    if pairs.len() < 2 {
        return Err(format!(
            "a spectrum needs one value or at least two wavelength:value pairs (\"{}\")",
            quote(text)
        ));
    }
    Ok(Spectrum::Sampled(pairs))
}
