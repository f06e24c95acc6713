//! Wavefront OBJ meshes (with MTL diffuse colours), read by a small parser of our
//! own: unlike the usual crates it names the line of every error, and it keeps
//! triangle `i` of the file at index `i` (polygons fanned in file order).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3A;
use thiserror::Error;

use crate::geometry::triangle::Triangle;

/// Reflectance of triangles without an MTL colour.
pub const DEFAULT_REFLECTANCE: f32 = 0.75;

/// A triangle mesh read from a file.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Triangles in file order (polygons fanned: `(0, k, k + 1)`).
    pub triangles: Vec<Triangle>,
    /// Diffuse reflectance per triangle (MTL `Kd`, or grey).
    pub reflectance: Vec<Vec3A>,
    /// Things worth telling the user that do not stop the load (missing MTL file,
    /// unknown material names).
    pub warnings: Vec<String>,
}

/// Why a mesh file could not be read; the message names the file and the line.
#[derive(Debug, Error)]
pub enum ObjError {
    /// The file could not be opened or read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said (in the message, so not also a `source`, which
        /// would print it twice in the command line's one-line error).
        cause: std::io::Error,
    },
    /// A line is malformed.
    #[error("{path}:{line}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file holds no triangles.
    #[error("{path}: no triangles (no 'f' lines with three or more vertices)")]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// Reads an OBJ file, its MTL colours, and returns the triangles.
pub fn load_obj(path: &Path) -> Result<Mesh, ObjError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ObjError::Io {
        path: path.to_owned(),
        cause,
    })?;
    parse_obj(&text, path)
}

/// Parses OBJ text; `path` names the file in errors and locates `mtllib` files.
pub fn parse_obj(text: &str, path: &Path) -> Result<Mesh, ObjError> {
    let syntax = |line: usize, message: String| ObjError::Syntax {
        path: path.to_owned(),
        line,
        message,
    };
    let mut positions: Vec<Vec3A> = Vec::new();
    // Faces as resolved vertex indices, checked once all vertices are known.
    let mut faces: Vec<([u32; 3], usize)> = Vec::new();
    let mut mesh = Mesh::default();
    let mut materials: HashMap<String, Vec3A> = HashMap::new();
    let mut current = Vec3A::splat(DEFAULT_REFLECTANCE);
    let mut polygon: Vec<u32> = Vec::with_capacity(8);
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                let mut c = [0.0f32; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let word = words.next().ok_or_else(|| {
                        syntax(line_no, format!("vertex has {k} coordinates, expected 3"))
                    })?;
                    *slot = match word.parse::<f32>() {
                        Ok(v) if v.is_finite() => v,
                        _ => {
                            return Err(syntax(
                                line_no,
                                format!("vertex coordinate '{word}' is not a finite number"),
                            ));
                        }
                    };
                }
                positions.push(Vec3A::from(c));
            }
            Some("f") => {
                polygon.clear();
                for word in words {
                    let index = word.split('/').next().unwrap_or("");
                    let n: i64 = index.parse().map_err(|_| {
                        syntax(line_no, format!("face vertex '{word}' is not an index"))
                    })?;
                    let resolved = match n {
                        0 => {
                            return Err(syntax(
                                line_no,
                                "face vertex index 0 (OBJ counts from 1)".into(),
                            ));
                        }
                        n if n > 0 => n - 1,
                        n => positions.len() as i64 + n,
                    };
                    if resolved < 0 || resolved >= u32::MAX as i64 {
                        return Err(syntax(line_no, format!("face vertex {n} does not exist")));
                    }
                    polygon.push(resolved as u32);
                }
                if polygon.len() < 3 {
                    return Err(syntax(
                        line_no,
                        format!("face has {} vertices, needs 3", polygon.len()),
                    ));
                }
                for k in 1..polygon.len() - 1 {
                    faces.push(([polygon[0], polygon[k], polygon[k + 1]], line_no));
                    mesh.reflectance.push(current);
                }
            }
            Some("mtllib") => {
                let name = line["mtllib".len()..].trim();
                let mtl = path.with_file_name(name);
                match std::fs::read_to_string(&mtl) {
                    Ok(text) => materials.extend(parse_mtl(&text, &mtl)?),
                    Err(e) => mesh.warnings.push(format!(
                        "{}:{line_no}: material library {}: {e}; surfaces without a colour are grey",
                        path.display(),
                        mtl.display()
                    )),
                }
            }
            Some("usemtl") => {
                let name = line["usemtl".len()..].trim();
                current = match materials.get(name) {
                    Some(&kd) => kd,
                    None => {
                        mesh.warnings.push(format!(
                            "{}:{line_no}: unknown material '{name}', using grey",
                            path.display()
                        ));
                        Vec3A::splat(DEFAULT_REFLECTANCE)
                    }
                };
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(ObjError::Empty {
            path: path.to_owned(),
        });
    }
    mesh.triangles.reserve(faces.len());
    for (f, line_no) in faces {
        if let Some(&bad) = f.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(syntax(
                line_no,
                format!(
                    "face refers to vertex {} but the file has {}",
                    bad as u64 + 1,
                    positions.len()
                ),
            ));
        }
        mesh.triangles.push(Triangle::new(
            positions[f[0] as usize],
            positions[f[1] as usize],
            positions[f[2] as usize],
        ));
    }
    Ok(mesh)
}

/// The `Kd` colour of each material in an MTL file, clamped to `[0, 1]`.
fn parse_mtl(text: &str, path: &Path) -> Result<HashMap<String, Vec3A>, ObjError> {
    let mut out = HashMap::new();
    let mut name: Option<String> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("newmtl") => {
                let n = line["newmtl".len()..].trim().to_string();
                out.insert(n.clone(), Vec3A::splat(DEFAULT_REFLECTANCE));
                name = Some(n);
            }
            Some("Kd") => {
                let c: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
                if c.len() != 3 || c.iter().any(|v| !v.is_finite()) {
                    return Err(ObjError::Syntax {
                        path: path.to_owned(),
                        line: i + 1,
                        message: "Kd needs three finite numbers".into(),
                    });
                }
                if let Some(n) = &name {
                    out.insert(
                        n.clone(),
                        Vec3A::new(c[0], c[1], c[2]).clamp(Vec3A::ZERO, Vec3A::ONE),
                    );
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh, ObjError> {
        parse_obj(text, Path::new("m.obj"))
    }

    #[test]
    fn polygons_are_fanned_in_file_order_with_all_index_forms() {
        let mesh = parse(
            "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
             vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3//1 4\nf -1 -3 -2\n",
        )
        .unwrap();
        assert_eq!(mesh.triangles.len(), 3);
        let v = |x: f32, y: f32| Vec3A::new(x, y, 0.0);
        assert_eq!(mesh.triangles[0].v, [v(0., 0.), v(1., 0.), v(1., 1.)]);
        assert_eq!(mesh.triangles[1].v, [v(0., 0.), v(1., 1.), v(0., 1.)]);
        assert_eq!(mesh.triangles[2].v, [v(0., 1.), v(1., 0.), v(1., 1.)]);
        assert!(mesh.reflectance.iter().all(|r| *r == Vec3A::splat(0.75)));
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases = [
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 3\n",
                "m.obj:3: face refers to vertex 3 but the file has 2",
            ),
            (
                "v 0 0 nan\n",
                "m.obj:1: vertex coordinate 'nan' is not a finite number",
            ),
            (
                "v 0 0 inf\n",
                "m.obj:1: vertex coordinate 'inf' is not a finite number",
            ),
            ("v 0 0\n", "m.obj:1: vertex has 2 coordinates, expected 3"),
            (
                "v 0 0 0\nf 1 0 1\n",
                "m.obj:2: face vertex index 0 (OBJ counts from 1)",
            ),
            (
                "v 0 0 0\nf 1 x 1\n",
                "m.obj:2: face vertex 'x' is not an index",
            ),
            (
                "v 0 0 0\nf 1 -5 1\n",
                "m.obj:2: face vertex -5 does not exist",
            ),
            (
                "v 0 0 0\nv 0 0 0\nf 1 2\n",
                "m.obj:3: face has 2 vertices, needs 3",
            ),
            (
                "v 0 0 0\n",
                "m.obj: no triangles (no 'f' lines with three or more vertices)",
            ),
            (
                "",
                "m.obj: no triangles (no 'f' lines with three or more vertices)",
            ),
        ];
        for (text, want) in cases {
            assert_eq!(parse(text).unwrap_err().to_string(), want);
        }
        let missing = load_obj(Path::new("/no/such/mesh.obj"))
            .unwrap_err()
            .to_string();
        assert!(missing.starts_with("/no/such/mesh.obj: "), "{missing}");
    }

    #[test]
    fn mtl_diffuse_colours_become_reflectance() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.mtl"),
            "newmtl red\nKd 0.8 0.1 0.1\nnewmtl bright\nKd 2 0.5 0.5\n",
        )
        .unwrap();
        let obj = dir.path().join("m.obj");
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl red\nf 1 2 3\n\
             usemtl bright\nf 1 2 3\nusemtl nosuch\nf 1 2 3\n",
        )
        .unwrap();
        let mesh = load_obj(&obj).unwrap();
        assert_eq!(
            mesh.reflectance,
            [
                Vec3A::splat(0.75),
                Vec3A::new(0.8, 0.1, 0.1),
                Vec3A::new(1.0, 0.5, 0.5),
                Vec3A::splat(0.75)
            ]
        );
        assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
        assert!(mesh.warnings[0].contains("nosuch"));
        // A missing library is a warning, not an error.
        std::fs::write(
            &obj,
            "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let mesh = load_obj(&obj).unwrap();
        assert!(mesh.warnings[0].contains("gone.mtl"));
    }
}
