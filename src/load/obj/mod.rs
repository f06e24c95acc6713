//! Wavefront OBJ files with their MTL materials, read by a small parser of our
//! own: unlike the usual crates it names the line of every error, and it keeps
//! triangle `i` of the file at index `i` (polygons fanned `(0, k, k + 1)` in
//! file order).
//!
//! Read: `v`, `vt`, `vn`, `f` in all four forms (`v`, `v/vt`, `v//vn`,
//! `v/vt/vn`) with positive and negative (relative) indices, `g` and `o` (the
//! parts scene files can override), `usemtl`, `mtllib` (relative to the OBJ; a
//! missing library is a warning). `s` is ignored; every other statement is
//! skipped with one warning per kind. [`load_obj_scene`] maps the MTL
//! materials onto the glTF-style material (see [`material_from_mtl`]);
//! [`load_obj`] keeps only the triangles and `Kd` (for the lab box's `--add`
//! and `raylab bench`).

pub mod mtl;

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec2, Vec3, Vec3A, Vec4};
use thiserror::Error;

use crate::geometry::triangle::Triangle;
use crate::guard::quote;
use crate::materials::surface::{AlphaMode, GltfMaterial, MaterialKind, SurfaceMaterial};
use crate::scene::{Instance, MeshData, SceneParts, Tangents};
use crate::textures::{ColorSpace, Image, TextureRef, TextureStore, TextureTransform, Wrap};
use mtl::{MapRef, MtlMaterial, parse_mtl, phong_roughness};

/// Reflectance of triangles without an MTL colour.
pub const DEFAULT_REFLECTANCE: f32 = 0.75;

/// Marks a missing index (no `vt` or `vn` at a corner, no `usemtl`).
pub const NONE: u32 = u32::MAX;

/// Slope of a bump map's height field per unit of height difference between
/// neighbouring texels, before `-bm`: a step of 1/10 of the height range
/// across one texel tilts the normal by 45°.
pub const BUMP_SLOPE_SCALE: f32 = 10.0;

/// A triangle mesh read from a file: triangles and `Kd` only.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Triangles in file order (polygons fanned: `(0, k, k + 1)`).
    pub triangles: Vec<Triangle>,
    /// Diffuse reflectance per triangle (MTL `Kd`, or grey).
    pub reflectance: Vec<Vec3A>,
    /// Things worth telling the user that do not stop the load (missing MTL file,
    /// unknown material names, skipped statements).
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
    /// A texture could not be decoded.
    #[error("{0}")]
    Texture(String),
    /// The scene would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

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

fn read_text(path: &Path) -> Result<String, ObjError> {
    std::fs::read_to_string(path).map_err(|cause| ObjError::Io {
        path: path.to_owned(),
        cause,
    })
}

/// The OBJ's material libraries, read; a missing one is a warning.
fn read_libraries(
    obj: &ObjFile,
    path: &Path,
    skipped: &mut BTreeMap<String, usize>,
    warnings: &mut Vec<String>,
) -> Result<HashMap<String, MtlMaterial>, ObjError> {
    let mut materials = HashMap::new();
    for lib in &obj.libraries {
        match std::fs::read_to_string(lib) {
            Ok(text) => {
                for m in parse_mtl(&text, lib, skipped)? {
                    materials.insert(m.name.clone(), m);
                }
            }
            // A library that is there but unreadable (not UTF-8, a folder)
            // is an error, as an unreadable OBJ is; only a missing one is
            // forgiven, as exporters often name one they did not write.
            Err(cause) if cause.kind() != std::io::ErrorKind::NotFound => {
                return Err(ObjError::Io {
                    path: lib.clone(),
                    cause,
                });
            }
            Err(e) => warnings.push(format!(
                "{}: material library {}: {e}; its materials are grey",
                path.display(),
                lib.display()
            )),
        }
    }
    for name in &obj.materials {
        if !materials.contains_key(name) {
            warnings.push(format!(
                "{}: unknown material '{name}', using grey",
                path.display()
            ));
        }
    }
    Ok(materials)
}

/// One warning line for the skipped statement kinds.
fn skipped_warning(path: &Path, skipped: &BTreeMap<String, usize>) -> Option<String> {
    if skipped.is_empty() {
        return None;
    }
    let kinds: Vec<String> = skipped.iter().map(|(k, n)| format!("{n} '{k}'")).collect();
    Some(format!(
        "{}: skipped statements raylab does not read: {}",
        path.display(),
        kinds.join(", ")
    ))
}

/// Reads an OBJ file, its MTL colours, and returns the triangles.
pub fn load_obj(path: &Path) -> Result<Mesh, ObjError> {
    parse_obj(&read_text(path)?, path)
}

/// Parses OBJ text (triangles and `Kd` only); `path` names the file in errors
/// and locates `mtllib` files.
pub fn parse_obj(text: &str, path: &Path) -> Result<Mesh, ObjError> {
    let obj = parse_obj_file(text, path)?;
    // A mesh to place or to benchmark must have triangles (a scene may be
    // empty: see `load_obj_scene`).
    if obj.triangles.is_empty() {
        return Err(ObjError::Empty {
            path: path.to_owned(),
        });
    }
    let mut warnings = Vec::new();
    let mut skipped = obj.skipped.clone();
    let materials = read_libraries(&obj, path, &mut skipped, &mut warnings)?;
    let kd: Vec<Vec3A> = obj
        .materials
        .iter()
        .map(|name| {
            materials
                .get(name)
                .and_then(|m| m.kd)
                .map_or(Vec3A::splat(DEFAULT_REFLECTANCE), |c| {
                    c.clamp(Vec3A::ZERO, Vec3A::ONE)
                })
        })
        .collect();
    warnings.extend(skipped_warning(path, &skipped));
    let p = |c: &Corner| obj.positions[c.position as usize];
    Ok(Mesh {
        triangles: obj
            .triangles
            .iter()
            .map(|t| Triangle::new(p(&t[0]), p(&t[1]), p(&t[2])))
            .collect(),
        reflectance: obj
            .material_of
            .iter()
            .map(|&m| {
                kd.get(m as usize)
                    .copied()
                    .unwrap_or(Vec3A::splat(DEFAULT_REFLECTANCE))
            })
            .collect(),
        warnings,
    })
}

/// An OBJ file as scene parts, with its named parts (groups and objects).
#[derive(Clone, Debug)]
pub struct ObjScene {
    /// One mesh, one instance, the materials and their textures.
    pub parts: SceneParts,
    /// Named triangle ranges (`g` groups and `o` objects).
    pub named_parts: Vec<(String, Range<usize>)>,
    /// Missing libraries, textures and materials; skipped statements.
    pub warnings: Vec<String>,
}

/// Reads an OBJ file with its MTL materials and textures as scene parts (two-
/// sided, as OBJ windings vary; emitters emit from their counter-clockwise
/// side).
pub fn load_obj_scene(path: &Path) -> Result<ObjScene, ObjError> {
    load_obj_scene_with(path, &crate::memory::Ledger::unlimited())
}

/// [`load_obj_scene`], charging the decoded textures to `ledger` before
/// decoding them.
pub fn load_obj_scene_with(
    path: &Path,
    ledger: &crate::memory::Ledger,
) -> Result<ObjScene, ObjError> {
    // The text is held while it is parsed.
    if let Ok(meta) = std::fs::metadata(path) {
        let text = crate::memory::Needs {
            geometry: meta.len(),
            ..Default::default()
        };
        ledger.fits(&path.display().to_string(), text)?;
    }
    let obj = parse_obj_file(&read_text(path)?, path)?;
    let mut warnings = Vec::new();
    let mut skipped = obj.skipped.clone();
    let library = read_libraries(&obj, path, &mut skipped, &mut warnings)?;
    warnings.extend(skipped_warning(path, &skipped));
    if obj.triangles.is_empty() {
        warnings.push(format!(
            "{}: no triangles (no 'f' lines with three or more vertices); the image shows only the background",
            path.display()
        ));
    }
    if obj.bad_normals > 0 {
        warnings.push(format!(
            "{}: {} 'vn' normals are not finite; their corners use the face's normal",
            path.display(),
            obj.bad_normals
        ));
    }

    // Textures: every map file once, read (missing: a warning), then decoded
    // in parallel.
    let mut files: Vec<PathBuf> = Vec::new();
    let used: Vec<Option<&MtlMaterial>> = obj.materials.iter().map(|n| library.get(n)).collect();
    for m in used.iter().flatten() {
        for map in maps(m).into_iter().flatten() {
            if !files.contains(&map.path) {
                files.push(map.path.clone());
            }
        }
    }
    let mut sources = Vec::new();
    let mut image_of: HashMap<PathBuf, u32> = HashMap::new();
    for f in files {
        match std::fs::read(&f) {
            Ok(bytes) => {
                image_of.insert(f.clone(), sources.len() as u32);
                sources.push((f.display().to_string(), bytes));
            }
            Err(e) => warnings.push(format!(
                "{}: texture {}: {e}; ignored",
                path.display(),
                f.display()
            )),
        }
    }
    let mut textures =
        TextureStore::decode_all_within(sources, ledger, &path.display().to_string()).map_err(
            |e| match e {
                crate::textures::TextureError::Memory(m) => ObjError::Memory(m),
                e => ObjError::Texture(e.to_string()),
            },
        )?;

    // Bump maps that are height fields become normal maps (with `-bm`
    // applied); those that are normal maps already are used as they are (with
    // `-bm` scaling x and y). Value: the image and the normal scale.
    let mut bump_normal: HashMap<(PathBuf, u32), (u32, f32)> = HashMap::new();
    for m in used.iter().flatten() {
        if let Some(b) = &m.bump
            && let Some(&id) = image_of.get(&b.path)
            && let std::collections::hash_map::Entry::Vacant(slot) =
                bump_normal.entry((b.path.clone(), b.bump_multiplier.to_bits()))
        {
            let image = textures.get(id);
            slot.insert(if looks_like_normal_map(image) {
                (id, b.bump_multiplier)
            } else {
                (
                    textures.push(height_to_normal_map(image, b.bump_multiplier)),
                    1.0,
                )
            });
        }
    }

    let texture = |map: &Option<MapRef>| -> Option<TextureRef> {
        let map = map.as_ref()?;
        let image = *image_of.get(&map.path)?;
        Some(texture_ref(image, map))
    };
    let mut materials: Vec<SurfaceMaterial> = used
        .iter()
        .zip(&obj.materials)
        .map(|(m, name)| match m {
            Some(m) => {
                let bump = m.bump.as_ref().and_then(|b| {
                    let &(id, scale) =
                        bump_normal.get(&(b.path.clone(), b.bump_multiplier.to_bits()))?;
                    Some((texture_ref(id, b), scale))
                });
                let norm = texture(&m.norm)
                    .map(|t| (t, m.norm.as_ref().map_or(1.0, |n| n.bump_multiplier)));
                let alpha_has_channel = m
                    .map_d
                    .as_ref()
                    .and_then(|d| image_of.get(&d.path))
                    .is_some_and(|&id| matches!(textures.get(id).channels(), 2 | 4));
                material_from_mtl(
                    m,
                    &MtlTextures {
                        kd: texture(&m.map_kd),
                        ks: texture(&m.map_ks),
                        d: texture(&m.map_d).map(|t| (t, alpha_has_channel)),
                        normal: norm.or(bump),
                        pr: texture(&m.map_pr),
                        pm: texture(&m.map_pm),
                        ke: texture(&m.map_ke),
                    },
                )
            }
            None => SurfaceMaterial {
                name: name.clone(),
                ..SurfaceMaterial::diffuse(Vec3A::splat(DEFAULT_REFLECTANCE))
            },
        })
        .collect();
    // Triangles before any usemtl.
    let default_material = materials.len() as u32;
    materials.push(SurfaceMaterial::diffuse(Vec3A::splat(DEFAULT_REFLECTANCE)));

    // One mesh with a vertex per distinct (position, uv, normal) corner.
    let mut mesh = MeshData::default();
    let has_uv = obj.triangles.iter().flatten().any(|c| c.uv != NONE);
    let has_normals = obj.triangles.iter().flatten().any(|c| c.normal != NONE);
    let mut vertex_of: HashMap<Corner, u32> = HashMap::new();
    for t in &obj.triangles {
        let idx = t.map(|c| {
            *vertex_of.entry(c).or_insert_with(|| {
                mesh.positions
                    .push(obj.positions[c.position as usize].into());
                if has_uv {
                    // OBJ's v points up; textures' rows go down.
                    let uv = if c.uv == NONE {
                        Vec2::ZERO
                    } else {
                        obj.uvs[c.uv as usize]
                    };
                    mesh.uvs[0].push(Vec2::new(uv.x, 1.0 - uv.y));
                }
                if has_normals {
                    mesh.normals.push(if c.normal == NONE {
                        Vec3::ZERO
                    } else {
                        obj.normals[c.normal as usize]
                    });
                }
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.indices.push(idx);
    }
    if materials.iter().any(|m| m.normal_texture().is_some()) && has_uv {
        mesh.tangents = crate::load::gltf::tangents::generate(&mesh, 0);
    } else {
        mesh.tangents = Tangents::None;
    }
    let triangles: Vec<Triangle> = obj
        .triangles
        .iter()
        .map(|t| {
            let p = |k: usize| obj.positions[t[k].position as usize];
            Triangle::new(p(0), p(1), p(2))
        })
        .collect();
    let normals = triangles
        .iter()
        .map(|t| (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize_or_zero())
        .collect();
    let n = triangles.len();
    let parts = SceneParts {
        triangles,
        normals,
        material_of: obj
            .material_of
            .iter()
            .map(|&m| if m == NONE { default_material } else { m })
            .collect(),
        instance_of: vec![0; n],
        meshes: vec![mesh],
        instances: vec![Instance::new(0, 0, Affine3A::IDENTITY)],
        materials,
        textures,
        two_sided: true,
        ..SceneParts::default()
    };
    Ok(ObjScene {
        parts,
        named_parts: obj.parts,
        warnings,
    })
}

/// Every texture statement of a material.
fn maps(m: &MtlMaterial) -> [&Option<MapRef>; 8] {
    [
        &m.map_kd, &m.map_ks, &m.map_d, &m.bump, &m.norm, &m.map_pr, &m.map_pm, &m.map_ke,
    ]
}

/// A texture reference with the statement's options: `-o`/`-s` as a texture
/// transform (converted from OBJ's v-up coordinates), `-clamp on`.
fn texture_ref(image: u32, map: &MapRef) -> TextureRef {
    let wrap = if map.clamp {
        Wrap::ClampToEdge
    } else {
        Wrap::Repeat
    };
    // OBJ: u' = s·u + o with v up; ours: v_ours = 1 − v_obj, so
    // v'_ours = s_v·v_ours + (1 − s_v − o_v).
    let transform = TextureTransform {
        offset: Vec2::new(map.offset.x, 1.0 - map.scale.y - map.offset.y),
        rotation: 0.0,
        scale: map.scale,
    };
    TextureRef {
        wrap_s: wrap,
        wrap_t: wrap,
        transform,
        ..TextureRef::new(image)
    }
}

/// Whether an image is a tangent-space normal map rather than a height field:
/// RGB whose mean is near (0.5, 0.5, 1) (mostly "blue").
fn looks_like_normal_map(image: &Image) -> bool {
    if image.channels() < 3 {
        return false;
    }
    let mean = image.average(ColorSpace::Linear);
    (mean.x - 0.5).abs() < 0.15 && (mean.y - 0.5).abs() < 0.15 && mean.z > 0.7
}

/// A tangent-space normal map of a height field (the image's mean of R, G, B):
/// slopes from central differences, times `multiplier` and
/// [`BUMP_SLOPE_SCALE`]; +x along increasing u, +y towards the image's top
/// (decreasing v), as the normal maps raylab reads.
fn height_to_normal_map(image: &Image, multiplier: f32) -> Image {
    let (w, h) = (image.width(), image.height());
    let height = |x: i64, y: i64| {
        let x = x.rem_euclid(w as i64) as u32;
        let y = y.rem_euclid(h as i64) as u32;
        let t: Vec4 = image.texel(x, y, ColorSpace::Linear);
        (t.x + t.y + t.z) / 3.0
    };
    let k = 0.5 * multiplier * BUMP_SLOPE_SCALE;
    let mut texels = Vec::with_capacity(w as usize * h as usize * 3);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let du = (height(x + 1, y) - height(x - 1, y)) * k;
            // Up in the image is y − 1.
            let dv = (height(x, y - 1) - height(x, y + 1)) * k;
            let n = Vec3::new(-du, -dv, 1.0).normalize();
            texels.extend(
                n.to_array()
                    .map(|c| ((c * 0.5 + 0.5) * 255.0).round() as u8),
            );
        }
    }
    Image::from_u8(w, h, 3, texels)
}

/// The textures a material uses, as references into the scene's store.
#[derive(Clone, Debug, Default)]
pub struct MtlTextures {
    /// `map_Kd`.
    pub kd: Option<TextureRef>,
    /// `map_Ks`.
    pub ks: Option<TextureRef>,
    /// `map_d`, and whether the image has an alpha channel (else its red).
    pub d: Option<(TextureRef, bool)>,
    /// `norm`, or `map_Bump` as a normal map, with the scale of its x and y.
    pub normal: Option<(TextureRef, f32)>,
    /// `map_Pr`.
    pub pr: Option<TextureRef>,
    /// `map_Pm`.
    pub pm: Option<TextureRef>,
    /// `map_Ke`.
    pub ke: Option<TextureRef>,
}

/// An MTL material as raylab's glTF-style material. The mapping (README.md,
/// "OBJ/MTL"):
///
/// * base colour `Kd` × `map_Kd` (sRGB); metallic `Pm` × `map_Pm` (else 0);
///   roughness `Pr` × `map_Pr`, else from `Ns` by [`phong_roughness`];
/// * `Ks` scales the specular reflectance at normal incidence: `F0 = 0.08 Ks`
///   (Ks 0.5 is the usual dielectric's 0.04; Ks 0 turns specular off; without
///   `Ks`, 0.04), times `map_Ks` (sRGB);
/// * `illum` 3 and 5: a mirror-like metal of colour `Ks` (white without it);
///   `illum` 4, 6, 7, 9: glass, refracting with index `Ni` (1.5 when absent or
///   below 1), tinted by `Tf`;
/// * `Ke` × `map_Ke`: emission (front faces); `map_Ke` without `Ke` emits the
///   map as radiance;
/// * `d` < 1 (or `Tr` > 0): stochastic transparency (blend); `map_d`: a cut-out
///   at 0.5 from the map's alpha (its red channel without alpha);
/// * `norm` (or `map_Bump`/`bump`, see [`load_obj_scene`]): a tangent-space
///   normal map with `-bm` scaling x and y.
pub fn material_from_mtl(m: &MtlMaterial, t: &MtlTextures) -> SurfaceMaterial {
    let kd =
        m.kd.unwrap_or(Vec3A::splat(DEFAULT_REFLECTANCE))
            .min(Vec3A::ONE);
    let roughness = m.pr.unwrap_or_else(|| m.ns.map_or(1.0, phong_roughness));
    let mirror = matches!(m.illum, Some(3 | 5));
    let glass = matches!(m.illum, Some(4 | 6 | 7 | 9));
    let ior = match m.ni {
        Some(n) if glass && n > 1.0 && n.is_finite() => n.min(4.0),
        _ => 1.5,
    };
    // F0 = 0.04 · specular_color at ior 1.5: 2 Ks gives 0.08 Ks.
    let f0_ior = ((ior - 1.0) / (ior + 1.0)).powi(2);
    let specular_color = match (glass, m.ks) {
        (false, Some(ks)) => ks * (0.08 / f0_ior),
        _ => Vec3A::ONE,
    };
    let mut g = GltfMaterial {
        base_color: kd.extend(m.dissolve.unwrap_or(1.0)),
        base_color_texture: t.kd,
        metallic: m.pm.unwrap_or(0.0),
        roughness,
        ior,
        specular_color,
        specular_color_texture: t.ks,
        normal_texture: t.normal.map(|(texture, _)| texture),
        normal_scale: t.normal.map_or(1.0, |(_, scale)| scale),
        roughness_texture: t.pr,
        metallic_texture: t.pm,
        alpha_texture: t.d.map(|(texture, _)| texture),
        alpha_from_red: t.d.is_some_and(|(_, has_alpha)| !has_alpha),
        ..GltfMaterial::default()
    };
    if mirror {
        g.base_color = m.ks.unwrap_or(Vec3A::ONE).min(Vec3A::ONE).extend(1.0);
        g.base_color_texture = None;
        g.metallic = 1.0;
        g.roughness = m.pr.unwrap_or_else(|| m.ns.map_or(0.0, phong_roughness));
    }
    if glass {
        g.base_color = m.tf.unwrap_or(Vec3A::ONE).extend(1.0);
        g.metallic = 0.0;
        g.transmission = 1.0;
        g.thin_walled = false;
        g.roughness = m.pr.unwrap_or_else(|| m.ns.map_or(0.0, phong_roughness));
    }
    let alpha = if t.d.is_some() {
        AlphaMode::Mask(0.5)
    } else if m.dissolve.is_some_and(|d| d < 1.0) && !glass {
        AlphaMode::Blend
    } else {
        AlphaMode::Opaque
    };
    let emission = match (m.ke, t.ke) {
        (Some(ke), _) => ke,
        (None, Some(_)) => Vec3A::ONE,
        (None, None) => Vec3A::ZERO,
    };
    SurfaceMaterial {
        name: m.name.clone(),
        reflectance: kd,
        kind: MaterialKind::Gltf(Box::new(g)),
        emission,
        emission_texture: if emission.max_element() > 0.0 {
            t.ke
        } else {
            None
        },
        emits_both_sides: false,
        alpha,
    }
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

    fn mtl(text: &str) -> MtlMaterial {
        let mut skipped = BTreeMap::new();
        parse_mtl(text, Path::new("m.mtl"), &mut skipped)
            .unwrap()
            .remove(0)
    }

    fn gltf(m: &SurfaceMaterial) -> &GltfMaterial {
        match &m.kind {
            MaterialKind::Gltf(g) => g,
            _ => panic!("not a metallic–roughness material"),
        }
    }

    #[test]
    fn mtl_statements_map_onto_the_gltf_material() {
        let none = MtlTextures::default();
        // Phong: Kd the base colour, Ks 0.5 the usual F0 of 0.04, Ns a roughness.
        let m = material_from_mtl(
            &mtl("newmtl p\nKd 0.8 0.2 0.1\nKs 0.5 0.5 0.5\nNs 98\n"),
            &none,
        );
        let g = gltf(&m);
        assert_eq!(g.base_color, Vec4::new(0.8, 0.2, 0.1, 1.0));
        assert_eq!((g.metallic, g.transmission), (0.0, 0.0));
        assert!((g.roughness - phong_roughness(98.0)).abs() < 1e-7);
        let f0 = ((g.ior - 1.0) / (g.ior + 1.0)).powi(2) * g.specular_color;
        assert!((f0 - Vec3A::splat(0.04)).abs().max_element() < 1e-6, "{f0}");
        assert_eq!(m.alpha, AlphaMode::Opaque);
        // Ks 0: no specular reflection.
        let m = material_from_mtl(&mtl("newmtl p\nKs 0 0 0\n"), &none);
        assert_eq!(gltf(&m).specular_color, Vec3A::ZERO);
        // PBR extension.
        let m = material_from_mtl(&mtl("newmtl m\nKd 1 0.8 0.3\nPm 1\nPr 0.25\n"), &none);
        assert_eq!((gltf(&m).metallic, gltf(&m).roughness), (1.0, 0.25));
        // Mirror and glass.
        let m = material_from_mtl(&mtl("newmtl m\nKs 0.9 0.9 0.9\nNs 10000\nillum 3\n"), &none);
        assert_eq!(gltf(&m).metallic, 1.0);
        assert_eq!(gltf(&m).base_color, Vec4::new(0.9, 0.9, 0.9, 1.0));
        assert!(gltf(&m).roughness < 0.12);
        let m = material_from_mtl(
            &mtl("newmtl g\nNi 1.33\nTf 1 0.9 0.8\nillum 7\nd 0.1\n"),
            &none,
        );
        let g = gltf(&m);
        assert_eq!((g.transmission, g.ior, g.thin_walled), (1.0, 1.33, false));
        assert_eq!(g.base_color.truncate(), glam::Vec3::new(1.0, 0.9, 0.8));
        assert_eq!(m.alpha, AlphaMode::Opaque, "a glass's d is not a cut-out");
        // Emission, dissolve and a cut-out.
        let m = material_from_mtl(&mtl("newmtl e\nKe 5 4 3\nd 0.5\n"), &none);
        assert_eq!(m.emission, Vec3A::new(5.0, 4.0, 3.0));
        assert_eq!(m.alpha, AlphaMode::Blend);
        assert_eq!(gltf(&m).base_color.w, 0.5);
        let cut = MtlTextures {
            d: Some((TextureRef::new(0), false)),
            ..MtlTextures::default()
        };
        let m = material_from_mtl(&mtl("newmtl c\n"), &cut);
        assert_eq!(m.alpha, AlphaMode::Mask(0.5));
        assert!(gltf(&m).alpha_from_red);
    }

    #[test]
    fn height_fields_become_normal_maps() {
        // A ramp rising to the right: normals lean left (−x), y stays 0.
        let w = 16;
        let texels: Vec<u8> = (0..w * w).map(|k| ((k % w) * 8) as u8).collect();
        let ramp = Image::from_u8(w as u32, w as u32, 1, texels);
        assert!(!looks_like_normal_map(&ramp));
        let n = height_to_normal_map(&ramp, 1.0);
        let t = n.texel(5, 7, ColorSpace::Linear);
        let slope = 8.0 / 255.0 * BUMP_SLOPE_SCALE;
        let want = Vec3::new(-slope, 0.0, 1.0).normalize() * 0.5 + Vec3::splat(0.5);
        assert!(
            (t.truncate() - want).abs().max_element() < 1.0 / 255.0,
            "{t} vs {want}"
        );
        assert!(looks_like_normal_map(&n));
    }
}
