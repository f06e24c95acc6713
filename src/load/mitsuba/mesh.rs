//! The triangle mesh that Mitsuba's mesh plugins (`ply`, `serialized`) read
//! ([`MitsubaMesh`]), as the file holds it: no transform applied, normals not
//! normalised, nothing merged or recomputed. What `to_world`,
//! `flip_normals`, `face_normals` and missing normals mean is the scene
//! translation's business.
//!
//! Conventions, as Mitsuba 3's meshes have them:
//!
//! - **Winding**: a triangle `[a, b, c]`'s geometric normal is
//!   `(p_b − p_a) × (p_c − p_a)`, normalised (Mitsuba's `face_normal`); its
//!   front side is the one the normal points to, so seen from the front the
//!   corners run counter-clockwise. `flip_normals` reverses the normal, not
//!   the indices.
//! - **Texture coordinates** are Mitsuba's: a `bitmap` texture is sampled
//!   at `(u, v)` with `v = 0` at the image's top row (as glTF). Mitsuba's
//!   `obj` flips `v` by default (`flip_tex_coords`, default `true`) because
//!   OBJ counts `v` from the bottom; `ply` does not (its `flip_tex_coords`
//!   defaults to `false`: the file's values are used as they are), and
//!   `serialized` has no such parameter (never flipped).
//! - **Attributes** are named as Mitsuba's `mesh_attribute` texture asks for
//!   them: `vertex_<name>` (one value per vertex) and `face_<name>` (one per
//!   triangle), 1, 3 or 4 channels (see `ply.rs` for how PLY properties are
//!   grouped and named).

use crate::memory::{GEOMETRY_BYTES_PER_TRIANGLE, Ledger, Needs};

use super::error::MitsubaError;

/// Most vertices a mesh file may declare (the data must also be present in
/// the file: every count is checked against the bytes that follow).
pub const MAX_MESH_VERTICES: u64 = 1 << 28;

/// Most triangles a mesh file may declare.
pub const MAX_MESH_FACES: u64 = 1 << 28;

/// One attribute of a mesh: `channels` values per vertex (or per face),
/// consecutive in `values`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// Mitsuba's name: `vertex_…` or `face_…` (`vertex_color`,
    /// `face_weight`).
    pub name: String,
    /// Values per vertex or face: 1, 3 or 4.
    pub channels: usize,
    /// `channels` × the vertex (or face) count values.
    pub values: Vec<f32>,
}

/// A triangle mesh read from a Mitsuba `ply` or `serialized` file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MitsubaMesh {
    /// The shape's name where the file has one (a version 4 `serialized`
    /// shape), else empty.
    pub name: String,
    /// Vertex positions, object space.
    pub positions: Vec<[f32; 3]>,
    /// Shading normals per vertex as stored (not normalised), if the file
    /// has them. Mitsuba computes normals for a mesh without them (unless
    /// `face_normals` is set).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Texture coordinates per vertex (see the module's conventions; a
    /// `ply`'s `flip_tex_coords` is already applied).
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Vertex colours, linear RGB. For `ply` the first three channels of the
    /// `vertex_color` attribute (which stays in [`Self::vertex_attributes`],
    /// where Mitsuba has it); for `serialized` the colours the file stores,
    /// which Mitsuba 3 reads past and drops (no attribute).
    pub colors: Option<Vec<[f32; 3]>>,
    /// Triangles, as indices into the vertices (all in range).
    pub indices: Vec<[u32; 3]>,
    /// Per-vertex attributes (`vertex_…`), in the file's order.
    pub vertex_attributes: Vec<MeshAttribute>,
    /// Per-face attributes (`face_…`), in the file's order.
    pub face_attributes: Vec<MeshAttribute>,
    /// What Mitsuba warns about while reading (properties it ignores,
    /// elements it skips), one line each, naming the file.
    pub warnings: Vec<String>,
}

impl MitsubaMesh {
    /// The attribute called `name` (`vertex_…` or `face_…`), if any.
    pub fn attribute(&self, name: &str) -> Option<&MeshAttribute> {
        self.vertex_attributes
            .iter()
            .chain(&self.face_attributes)
            .find(|a| a.name == name)
    }
}

/// Checks that a mesh of `vertices` and `faces` from the file `path` is
/// within [`MAX_MESH_VERTICES`] and [`MAX_MESH_FACES`] and fits `ledger`
/// (with `bytes_per_vertex` for its vertex data), before anything is
/// allocated for it; `what` prefixes the error (`shape 2: `).
pub(super) fn check_size(
    path: &std::path::Path,
    what: &str,
    vertices: u64,
    faces: u64,
    bytes_per_vertex: u64,
    ledger: &Ledger,
) -> Result<(), MitsubaError> {
    if vertices > MAX_MESH_VERTICES {
        return Err(MitsubaError::mesh(
            path,
            format!("{what}{vertices} vertices, more than the {MAX_MESH_VERTICES} raylab reads"),
        ));
    }
    if faces > MAX_MESH_FACES {
        return Err(MitsubaError::mesh(
            path,
            format!("{what}{faces} triangles, more than the {MAX_MESH_FACES} raylab reads"),
        ));
    }
    let needs = Needs {
        geometry: faces
            .saturating_mul(GEOMETRY_BYTES_PER_TRIANGLE)
            .saturating_add(vertices.saturating_mul(bytes_per_vertex)),
        ..Default::default()
    };
    ledger.fits(&path.display().to_string(), needs)?;
    Ok(())
}

/// Reads the file `path` whole, after checking that its size fits `ledger`.
pub(super) fn read_file(path: &std::path::Path, ledger: &Ledger) -> Result<Vec<u8>, MitsubaError> {
    let io = |cause| MitsubaError::Io {
        path: path.to_owned(),
        cause,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    ledger.fits(
        &path.display().to_string(),
        Needs {
            geometry: len,
            ..Default::default()
        },
    )?;
    std::fs::read(path).map_err(io)
}
