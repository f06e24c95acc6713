//! The OBJ text itself: `v`, `vt`, `vn` and `f` (all four forms, positive
//! and negative indices), `g` and `o` parts, `usemtl` and `mtllib`, read into
//! an [`ObjFile`] whose errors name the line.

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec3A};

use super::error::ObjError;
use crate::guard::quote;

/// Marks a missing index (no `vt` or `vn` at a corner, no `usemtl`).
pub const NONE: u32 = u32::MAX;

/// One corner of a face: indices into the file's positions, texture
/// coordinates and normals ([`NONE`] when absent).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Corner {
    /// Position index.
    pub position: u32,
    /// Texture coordinate index, or [`NONE`].
    pub uv: u32,
    /// Normal index, or [`NONE`].
    pub normal: u32,
}

/// An OBJ file as read: vertex data, triangles with their material and part.
#[derive(Clone, Debug, Default)]
pub struct ObjFile {
    /// `v` positions.
    pub positions: Vec<Vec3A>,
    /// `vt` coordinates as written (v up).
    pub uvs: Vec<Vec2>,
    /// `vn` normals.
    pub normals: Vec<Vec3>,
    /// Triangles in file order.
    pub triangles: Vec<[Corner; 3]>,
    /// Per triangle: index into `materials`, or [`NONE`] before any `usemtl`.
    pub material_of: Vec<u32>,
    /// `usemtl` names in order of first use.
    pub materials: Vec<String>,
    /// Named triangle ranges: every run of triangles under one `g` group or
    /// one `o` object (a name may have several runs).
    pub parts: Vec<(String, Range<usize>)>,
    /// `mtllib` files, resolved against the OBJ's folder.
    pub libraries: Vec<PathBuf>,
    /// Statement kinds skipped, with their counts.
    pub skipped: BTreeMap<String, usize>,
    /// `vn` lines with a NaN or infinite coordinate (kept as zero normals).
    pub bad_normals: usize,
}

/// Reads `n` numbers (at least `min`) after a keyword; finite ones only unless
/// `any` (normals: a non-finite one is repaired by the caller).
fn numbers<'a>(
    words: impl Iterator<Item = &'a str>,
    min: usize,
    max: usize,
    what: &str,
    any: bool,
) -> Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(max);
    for word in words.take(max) {
        match word.parse::<f32>() {
            Ok(v) if v.is_finite() || any => out.push(v),
            _ => {
                return Err(format!(
                    "{what} coordinate '{}' is not a finite number",
                    quote(word)
                ));
            }
        }
    }
    if out.len() < min {
        return Err(format!(
            "{what} has {} coordinates, expected {min}",
            out.len()
        ));
    }
    Ok(out)
}

/// Resolves a 1-based or negative (relative) OBJ index against `count`
/// entries read so far.
fn resolve(word: &str, count: usize, what: &str) -> Result<u32, String> {
    let n: i64 = word
        .parse()
        .map_err(|_| format!("face {what} '{}' is not an index", quote(word)))?;
    let resolved = match n {
        0 => return Err(format!("face {what} index 0 (OBJ counts from 1)")),
        n if n > 0 => n - 1,
        n => count as i64 + n,
    };
    if resolved < 0 || resolved >= NONE as i64 {
        return Err(format!("face {what} {n} does not exist"));
    }
    Ok(resolved as u32)
}

/// Parses OBJ text; `path` names the file in errors and locates `mtllib` files.
pub fn parse_obj_file(text: &str, path: &Path) -> Result<ObjFile, ObjError> {
    let syntax = |line: usize, message: String| ObjError::Syntax {
        path: path.to_owned(),
        line,
        message,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut obj = ObjFile::default();
    let mut lines_of: Vec<usize> = Vec::new();
    let mut material_ids: HashMap<String, u32> = HashMap::new();
    let mut current_material = NONE;
    // The open runs of the current group and object: (name, first triangle).
    let mut group: Option<(String, usize)> = None;
    let mut object: Option<(String, usize)> = None;
    let close =
        |run: &mut Option<(String, usize)>, end: usize, parts: &mut Vec<(String, Range<usize>)>| {
            if let Some((name, start)) = run.take()
                && end > start
            {
                parts.push((name, start..end));
            }
        };
    let mut polygon: Vec<Corner> = Vec::with_capacity(8);
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let rest = line[keyword.len()..].trim();
        match keyword {
            "v" => {
                let c = numbers(words, 3, 3, "vertex", false).map_err(|m| syntax(line_no, m))?;
                obj.positions.push(Vec3A::new(c[0], c[1], c[2]));
            }
            "vt" => {
                let c = numbers(words, 1, 2, "texture", false).map_err(|m| syntax(line_no, m))?;
                obj.uvs
                    .push(Vec2::new(c[0], c.get(1).copied().unwrap_or(0.0)));
            }
            "vn" => {
                // A NaN or infinite normal (exporters write them for
                // degenerate faces) is repaired, not refused: the zero
                // normal stands for "none", and shading falls back to the
                // geometric normal.
                let c = numbers(words, 3, 3, "normal", true).map_err(|m| syntax(line_no, m))?;
                let n = Vec3::new(c[0], c[1], c[2]);
                if !n.is_finite() {
                    obj.bad_normals += 1;
                }
                obj.normals.push(if n.is_finite() {
                    n.normalize_or_zero()
                } else {
                    Vec3::ZERO
                });
            }
            "f" => {
                polygon.clear();
                for word in words {
                    let mut fields = word.split('/');
                    let v = fields.next().unwrap_or("");
                    let position = resolve(v, obj.positions.len(), "vertex")
                        .map_err(|m| syntax(line_no, m))?;
                    let uv = match fields.next() {
                        None | Some("") => NONE,
                        Some(t) => resolve(t, obj.uvs.len(), "texture coordinate")
                            .map_err(|m| syntax(line_no, m))?,
                    };
                    let normal = match fields.next() {
                        None | Some("") => NONE,
                        Some(n) => resolve(n, obj.normals.len(), "normal")
                            .map_err(|m| syntax(line_no, m))?,
                    };
                    polygon.push(Corner {
                        position,
                        uv,
                        normal,
                    });
                }
                if polygon.len() < 3 {
                    return Err(syntax(
                        line_no,
                        format!("face has {} vertices, needs 3", polygon.len()),
                    ));
                }
                for k in 1..polygon.len() - 1 {
                    obj.triangles.push([polygon[0], polygon[k], polygon[k + 1]]);
                    obj.material_of.push(current_material);
                    lines_of.push(line_no);
                }
            }
            "g" | "o" => {
                let n = obj.triangles.len();
                let run = if keyword == "g" {
                    &mut group
                } else {
                    &mut object
                };
                close(run, n, &mut obj.parts);
                if !rest.is_empty() {
                    *run = Some((rest.to_string(), n));
                }
            }
            "usemtl" => {
                let next = obj.materials.len() as u32;
                current_material = *material_ids.entry(rest.to_string()).or_insert_with(|| {
                    obj.materials.push(rest.to_string());
                    next
                });
            }
            "mtllib" => {
                // Several files, or one name with spaces: a name that exists
                // as a whole wins.
                let whole = dir.join(rest);
                if whole.is_file() || !rest.contains(char::is_whitespace) {
                    obj.libraries.push(whole);
                } else {
                    obj.libraries
                        .extend(rest.split_ascii_whitespace().map(|n| dir.join(n)));
                }
            }
            "s" => {}
            other => *obj.skipped.entry(other.to_string()).or_default() += 1,
        }
    }
    let n = obj.triangles.len();
    close(&mut group, n, &mut obj.parts);
    close(&mut object, n, &mut obj.parts);
    for (t, line_no) in obj.triangles.iter().zip(lines_of) {
        for c in t {
            let checks = [
                (c.position, obj.positions.len(), "vertex"),
                (c.uv, obj.uvs.len(), "texture coordinate"),
                (c.normal, obj.normals.len(), "normal"),
            ];
            for (index, count, what) in checks {
                if index != NONE && index as usize >= count {
                    return Err(syntax(
                        line_no,
                        format!(
                            "face refers to {what} {} but the file has {count}",
                            index as u64 + 1
                        ),
                    ));
                }
            }
        }
    }
    Ok(obj)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_groups_materials_and_skipped_statements() {
        let obj = parse_obj_file(
            "o thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
             g left side\nusemtl a\nf 1/1/1 2/2/1 3/-1/-1\ng right\nusemtl b\nf 1//1 3//1 4//1\n\
             usemtl a\nf -4/-2 -3/-1 -2/-2\ns off\ncurv 0 1\ncurv 0 2\nl 1 2\n",
            Path::new("d/m.obj"),
        )
        .unwrap();
        assert_eq!(obj.triangles.len(), 3);
        assert_eq!(
            obj.triangles[0][2],
            Corner {
                position: 2,
                uv: 1,
                normal: 0
            }
        );
        assert_eq!(
            obj.triangles[1][0],
            Corner {
                position: 0,
                uv: NONE,
                normal: 0
            }
        );
        assert_eq!(
            obj.triangles[2][1],
            Corner {
                position: 1,
                uv: 1,
                normal: NONE
            }
        );
        assert_eq!(obj.materials, ["a", "b"]);
        assert_eq!(obj.material_of, [0, 1, 0]);
        let parts: Vec<(&str, Range<usize>)> = obj
            .parts
            .iter()
            .map(|(n, r)| (n.as_str(), r.clone()))
            .collect();
        assert_eq!(
            parts,
            [("left side", 0..1), ("right", 1..3), ("thing", 0..3)]
        );
        assert_eq!(obj.skipped.get("curv"), Some(&2));
        assert_eq!(obj.skipped.get("l"), Some(&1));
        assert!(!obj.skipped.contains_key("s"));
        // Out-of-range texture coordinates and normals name the line.
        let err = parse_obj_file("v 0 0 0\nvt 0 0\nf 1/1 1/2 1/1\n", Path::new("m.obj"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "m.obj:3: face refers to texture coordinate 2 but the file has 1"
        );
        let err = parse_obj_file("v 0 0 0\nf 1//1 1//1 1//1\n", Path::new("m.obj"))
            .unwrap_err()
            .to_string();
        assert_eq!(err, "m.obj:2: face refers to normal 1 but the file has 0");
    }
}
