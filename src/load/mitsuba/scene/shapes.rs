//! Mitsuba's shapes as triangle meshes in their own space: `obj` (Mitsuba's
//! vertex merging, `flip_tex_coords`, `face_normals`, and its angle-weighted
//! normals where the file has none), `rectangle`, `cube` (Mitsuba's vertex
//! order and texture coordinates); `sphere`, `disk` and `cylinder` as
//! raylab's analytic shapes, or, where they cannot be (in shape groups, a
//! sphere under an uneven scale), tessellated finely with their exact
//! normals and Mitsuba's parametrisation (an approximation: their
//! silhouettes are polygons; the load says so). `sdfgrid`'s properties
//! (its grid is read by `vol.rs` and placed as exact cells).

use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4};

use super::super::error::MitsubaError;
use super::super::mesh::MitsubaMesh;
use super::super::tree::{SceneTree, Tag};
use super::props::Props;
use crate::geometry::cylinder::Cylinder;
use crate::geometry::disk::Disk;
use crate::geometry::placement::Placement;
use crate::geometry::sphere::Sphere;
use crate::load::obj::parse_obj_file;
use crate::scene::{AnalyticShape, MeshData, SceneShape};

/// A member of a shape group, placed by each instance of the group.
#[derive(Clone, Copy)]
pub(super) enum Member {
    /// A mesh: its index, its own `to_world`, its material and whether its
    /// normals are its own (see `Builder::place`).
    Mesh(u32, Mat4, u32, bool),
    /// A signed distance grid (`sdfgrid`): its index in the parts' grids,
    /// its own `to_world`, its material and whether its normals are
    /// `smooth`.
    Sdf(u32, Mat4, u32, bool),
    /// A `sphere`, `disk` or `cylinder`: its plugin, its own `to_world`, its
    /// material and `flip_normals`; each instance places it analytic where
    /// its placement suits (a sphere's a similarity), else tessellated.
    Analytic(&'static str, Mat4, u32, bool),
}

/// An `sdfgrid`'s properties, all of them read (the shape's BSDF and
/// emitter aside): its `.vol` file, whether its `normals` are `smooth` (the
/// default; else `analytic`) and its `to_world`. A sensor inside
/// it is refused, as for every shape; its interior and exterior media are
/// read with its material.
pub(super) fn sdfgrid_props(
    p: &Props,
    tree: &SceneTree,
) -> Result<(PathBuf, bool, Mat4), MitsubaError> {
    let file = p.string_opt("filename")?.ok_or_else(|| {
        p.error("needs a 'filename' (its 'grid' tensor can only be given from Python or C++)")
    })?;
    let path = tree
        .resolve(file)
        .ok_or_else(|| p.error(format!("cannot find '{}'", crate::guard::quote(file))))?;
    let smooth = p.choice("normals", "smooth", &["analytic", "smooth"])? == "smooth";
    let to_world = p.transform("to_world")?;
    finish(p)?;
    Ok((path, smooth, to_world))
}

/// Ends a shape's properties: a sensor inside it is refused (a medium
/// other than its `interior` and `exterior` is unread), its `id` needs no
/// reader, and any property left unread is an error.
pub(super) fn finish(p: &Props) -> Result<(), MitsubaError> {
    if let Some(o) = p.children_of(Tag::Sensor).first() {
        return Err(p.error(format!(
            "{} inside a shape is not supported yet",
            o.describe()
        )));
    }
    p.ignore(&["id"]);
    p.finish()
}

/// Segments around a tessellated sphere, disk or cylinder (rings: half).
pub(super) const SEGMENTS: u32 = crate::scene::compose::SPHERE_SEGMENTS;

/// Mitsuba's vertex normals of a mesh without them: each face's unit normal
/// added to its corners' positions weighted by the corner's angle
/// (Thürmer and Wüthrich 1998), normalised; per position (vertices that
/// share a position share the normal).
fn angle_weighted_normals(mesh: &mut MeshData, position_of: &[u32], positions: usize) {
    let mut acc = vec![Vec3::ZERO; positions];
    for tri in &mesh.indices {
        let p = tri.map(|i| mesh.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        if n.length_squared() <= 0.0 {
            continue;
        }
        let n = n.normalize();
        for k in 0..3 {
            let a = (p[(k + 1) % 3] - p[k]).normalize_or_zero();
            let b = (p[(k + 2) % 3] - p[k]).normalize_or_zero();
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            acc[position_of[tri[k] as usize] as usize] += n * angle;
        }
    }
    mesh.normals = position_of
        .iter()
        .map(|&p| {
            let n = acc[p as usize];
            if n.length_squared() > 0.0 {
                n.normalize()
            } else {
                Vec3::X
            }
        })
        .collect();
}

/// An OBJ file as Mitsuba's `obj` reads it: one vertex per distinct
/// (position, texture coordinate, normal) corner, `v` flipped to `1 − v`
/// if `flip_tex_coords`, no normals if `face_normals`, else the file's or
/// Mitsuba's angle-weighted ones; and whether the normals are the file's.
pub(super) fn obj_mesh(
    path: &Path,
    flip_tex_coords: bool,
    face_normals: bool,
) -> Result<(MeshData, bool), MitsubaError> {
    let text = std::fs::read_to_string(path).map_err(|cause| MitsubaError::Io {
        path: path.to_owned(),
        cause,
    })?;
    let obj = parse_obj_file(&text, path).map_err(|e| MitsubaError::Scene {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    let mut mesh = MeshData::default();
    let mut vertex_of = HashMap::new();
    let mut position_of = Vec::new();
    let has_uv = obj
        .triangles
        .iter()
        .any(|t| t.iter().any(|c| c.uv != u32::MAX));
    let has_normals = !face_normals
        && obj
            .triangles
            .iter()
            .all(|t| t.iter().all(|c| c.normal != u32::MAX));
    for tri in &obj.triangles {
        let mut idx = [0u32; 3];
        for (k, c) in tri.iter().enumerate() {
            let key = (
                c.position,
                if has_uv { c.uv } else { 0 },
                if has_normals { c.normal } else { 0 },
            );
            idx[k] = *vertex_of.entry(key).or_insert_with(|| {
                mesh.positions
                    .push(obj.positions[c.position as usize].into());
                position_of.push(c.position);
                if has_uv {
                    let uv = obj.uvs.get(c.uv as usize).copied().unwrap_or(Vec2::ZERO);
                    mesh.uvs[0].push(match flip_tex_coords {
                        true => Vec2::new(uv.x, 1.0 - uv.y),
                        false => uv,
                    });
                }
                if has_normals {
                    mesh.normals.push(obj.normals[c.normal as usize]);
                }
                mesh.positions.len() as u32 - 1
            });
        }
        mesh.indices.push(idx);
    }
    if !face_normals && !has_normals {
        angle_weighted_normals(&mut mesh, &position_of, obj.positions.len());
    }
    Ok((mesh, has_normals))
}

/// A mesh read by the `ply` or `serialized` reader as raylab's, with
/// Mitsuba's normals: none if `face_normals`, else the file's (normalised)
/// or, without them, the angle-weighted ones.
///
/// With `attribute` (a `mesh_attribute` its material reads), the mesh
/// carries that attribute as its colours (1 channel as grey): a vertex
/// attribute interpolated as Mitsuba interpolates it, a face attribute
/// constant over each face (the mesh's vertices are then made one per
/// corner). An attribute the file lacks is an error.
pub(super) fn from_mitsuba_mesh(
    m: MitsubaMesh,
    face_normals: bool,
    attribute: Option<&str>,
) -> Result<MeshData, String> {
    let values = match attribute {
        None => None,
        Some(name) => {
            let a = m.attribute(name).ok_or_else(|| {
                let mut known: Vec<&str> = m
                    .vertex_attributes
                    .iter()
                    .chain(&m.face_attributes)
                    .map(|a| a.name.as_str())
                    .collect();
                known.sort_unstable();
                format!(
                    "the mesh has no attribute '{}' (it has: {})",
                    crate::guard::quote(name),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                )
            })?;
            let count = a.values.len() / a.channels.max(1);
            let values: Vec<Vec4> = (0..count)
                .map(|i| {
                    let v = &a.values[i * a.channels..(i + 1) * a.channels];
                    match a.channels {
                        1 => Vec3::splat(v[0]).extend(1.0),
                        _ => Vec4::new(v[0], v[1], v[2], 1.0),
                    }
                })
                .collect();
            Some((name.starts_with("face_"), values))
        }
    };
    let mut mesh = MeshData {
        positions: m.positions.iter().map(|p| Vec3::from(*p)).collect(),
        indices: m.indices,
        ..MeshData::default()
    };
    if let Some(uvs) = m.uvs {
        mesh.uvs[0] = uvs.iter().map(|uv| Vec2::from(*uv)).collect();
    }
    if let Some(colors) = m.colors {
        mesh.colors = colors.iter().map(|c| Vec3::from(*c).extend(1.0)).collect();
    }
    if !face_normals {
        match m.normals {
            Some(n) => {
                mesh.normals = n
                    .iter()
                    .map(|n| Vec3::from(*n).normalize_or(Vec3::X))
                    .collect()
            }
            None => {
                let identity: Vec<u32> = (0..mesh.positions.len() as u32).collect();
                let count = mesh.positions.len();
                angle_weighted_normals(&mut mesh, &identity, count);
            }
        }
    }
    if let Some((per_face, values)) = values {
        let value = |i: usize| values.get(i).copied().unwrap_or(Vec4::ONE);
        if per_face {
            // One vertex per corner, each face's value on its three.
            let mut split = MeshData::default();
            for (f, tri) in mesh.indices.iter().enumerate() {
                let base = split.positions.len() as u32;
                for &v in tri {
                    let v = v as usize;
                    split.positions.push(mesh.positions[v]);
                    if !mesh.normals.is_empty() {
                        split.normals.push(mesh.normals[v]);
                    }
                    if !mesh.uvs[0].is_empty() {
                        split.uvs[0].push(mesh.uvs[0][v]);
                    }
                    split.colors.push(value(f));
                }
                split.indices.push([base, base + 1, base + 2]);
            }
            mesh = split;
        } else {
            mesh.colors = (0..mesh.positions.len()).map(value).collect();
        }
    }
    Ok(mesh)
}

/// Mitsuba's `rectangle`: `[−1, 1]²` at z = 0 facing +z, (u, v) = ((x + 1)/2,
/// (y + 1)/2).
pub(super) fn rectangle() -> MeshData {
    let p = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];
    MeshData {
        positions: p.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
        indices: vec![[1, 2, 0], [1, 3, 2]],
        normals: vec![Vec3::Z; 4],
        uvs: [
            p.iter()
                .map(|&(x, y)| Vec2::new((x + 1.0) / 2.0, (y + 1.0) / 2.0))
                .collect(),
            Vec::new(),
        ],
        ..MeshData::default()
    }
}

/// Mitsuba's `cube`: `[−1, 1]³`, four vertices per side with the side's
/// normal and texture coordinates, in Mitsuba's order.
pub(super) fn cube() -> MeshData {
    const NORMALS: [[f32; 3]; 6] = [
        [0.0, -1.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
    ];
    const UV: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    const CORNER: [u32; 24] = [
        1, 5, 4, 0, 3, 2, 6, 7, 1, 3, 7, 5, 5, 7, 6, 4, 4, 6, 2, 0, 3, 1, 0, 2,
    ];
    let corner = |c: u32| {
        let s = |bit: u32| if c & bit != 0 { 1.0 } else { -1.0 };
        Vec3::new(s(1), s(2), s(4))
    };
    let mut mesh = MeshData::default();
    for (side, n) in NORMALS.iter().enumerate() {
        let v = 4 * side as u32;
        for (k, uv) in UV.iter().enumerate() {
            mesh.positions.push(corner(CORNER[4 * side + k]));
            mesh.normals.push(Vec3::from(*n));
            mesh.uvs[0].push(Vec2::from(*uv));
        }
        mesh.indices.push([v, v + 1, v + 2]);
        mesh.indices.push([v + 3, v, v + 2]);
    }
    mesh
}

/// The analytic shape of plugin `sphere`, `disk` or `cylinder` placed by
/// `to_world` (its own parameters applied: see `mesh`), its front flipped
/// by `flip` (material 0), or `None` where it cannot be one: a sphere
/// under anything but a similarity, a degenerate placement.
pub(super) fn analytic(plugin: &str, to_world: Affine3A, flip: bool) -> Option<SceneShape> {
    let shape = match plugin {
        "sphere" => {
            let linear = to_world.matrix3;
            let scale = crate::scene::compose::similarity(linear)?;
            AnalyticShape::Sphere(Sphere {
                center: to_world.translation,
                radius: scale,
                frame: linear * (1.0 / scale),
            })
        }
        "disk" => AnalyticShape::Disk(Disk::new(Placement::from_affine(to_world)?)),
        "cylinder" => AnalyticShape::Cylinder(Cylinder::new(Placement::from_affine(to_world)?)),
        _ => return None,
    };
    Some(SceneShape {
        shape,
        flip,
        material: 0,
    })
}

/// The unit mesh of an analytic plugin (`sphere`, `disk`, `cylinder`), for
/// where it cannot stay analytic (empty for other plugins).
pub(super) fn tessellated(plugin: &str) -> MeshData {
    match plugin {
        "sphere" => sphere(),
        "disk" => disk(),
        "cylinder" => cylinder(),
        _ => MeshData::default(),
    }
}

/// Mitsuba's unit `sphere` tessellated (where it cannot stay analytic):
/// see [`crate::scene::mesh::unit_sphere_mesh`].
pub(super) fn sphere() -> MeshData {
    crate::scene::mesh::unit_sphere_mesh(SEGMENTS, false)
}

/// Mitsuba's unit `disk` at z = 0 facing +z tessellated: (u, v) = (r, φ/2π).
pub(super) fn disk() -> MeshData {
    crate::scene::mesh::grid(SEGMENTS, SEGMENTS / 8, |s, t| {
        let phi = 2.0 * PI * s;
        (
            Vec3::new(t * phi.cos(), t * phi.sin(), 0.0),
            Vec3::Z,
            Vec2::new(t, s),
        )
    })
}

/// Mitsuba's unit `cylinder` (radius 1, z from 0 to 1, open) tessellated:
/// (u, v) = (φ/2π, z), normals outwards.
pub(super) fn cylinder() -> MeshData {
    crate::scene::mesh::grid(SEGMENTS, 1, |s, t| {
        let phi = 2.0 * PI * s;
        let n = Vec3::new(phi.cos(), phi.sin(), 0.0);
        (n + Vec3::Z * t, n, Vec2::new(s, t))
    })
}

/// Turns the mesh around (Mitsuba's `flip_normals`): reversed windings and
/// normals.
pub(super) fn flip(mesh: &mut MeshData) {
    for t in &mut mesh.indices {
        t.swap(1, 2);
    }
    for n in &mut mesh.normals {
        *n = -*n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn front(mesh: &MeshData, t: usize) -> Vec3 {
        let p = mesh.indices[t].map(|i| mesh.positions[i as usize]);
        (p[1] - p[0]).cross(p[2] - p[0]).normalize()
    }

    #[test]
    fn built_in_shapes_face_their_normals() {
        for (name, mesh) in [
            ("rectangle", rectangle()),
            ("cube", cube()),
            ("sphere", sphere()),
            ("disk", disk()),
            ("cylinder", cylinder()),
        ] {
            for t in 0..mesh.indices.len() {
                let n = mesh.indices[t].map(|i| mesh.normals[i as usize]);
                let f = front(&mesh, t);
                assert!(n.iter().all(|n| n.dot(f) > 0.5), "{name} triangle {t}");
            }
        }
    }

    #[test]
    fn the_sphere_has_area_four_pi_to_tessellation_accuracy() {
        let m = sphere();
        let area: f64 = (0..m.indices.len())
            .map(|t| {
                let p = m.indices[t].map(|i| m.positions[i as usize].as_dvec3());
                0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
            })
            .sum();
        // An inscribed polyhedron: a little less than 4π (by about
        // (π/N)²/3 for N segments around: 5e-5 at 256).
        let ratio = area / (4.0 * std::f64::consts::PI);
        assert!(ratio < 1.0 && ratio > 1.0 - 2e-4, "{area}");
    }

    #[test]
    fn rectangle_corners_carry_mitsubas_coordinates() {
        let m = rectangle();
        assert_eq!(m.positions[1], Vec3::new(1.0, -1.0, 0.0));
        assert_eq!(m.uvs[0][1], Vec2::new(1.0, 0.0));
        assert_eq!(m.uvs[0][2], Vec2::new(0.0, 1.0));
    }
}
