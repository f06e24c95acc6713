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
//!
//! `parse.rs` reads the OBJ text, `mtl.rs` the MTL libraries and `material.rs`
//! maps their materials onto raylab's; this file reads the files and makes
//! the mesh or the scene parts.

mod error;
mod material;
pub mod mtl;
mod parse;

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec2, Vec3, Vec3A};

use crate::geometry::triangle::Triangle;
use crate::materials::surface::SurfaceMaterial;
use crate::scene::{Instance, MeshData, SceneParts, Tangents};
use crate::textures::{TextureRef, TextureStore};
use material::{height_to_normal_map, looks_like_normal_map, maps, texture_ref};
use mtl::{MapRef, MtlMaterial, parse_mtl};

pub use error::ObjError;
pub use material::{BUMP_SLOPE_SCALE, DEFAULT_REFLECTANCE, MtlTextures, material_from_mtl};
pub use parse::{Corner, NONE, ObjFile, parse_obj_file};

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
