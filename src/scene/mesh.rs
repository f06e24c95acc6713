//! Triangle meshes with vertex attributes, and their instances.
//!
//! A mesh keeps its attributes in its own (object) space once, however many
//! nodes instance it; the BVH gets world-space copies of the positions only,
//! and attributes are looked up from a hit (triangle, barycentrics) and
//! transformed by the instance.

use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A, Vec4};

/// Tangents of a mesh: from the file (per vertex) or generated (MikkTSpace gives
/// one per triangle corner).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Tangents {
    /// None (no normal map needs them).
    #[default]
    None,
    /// `TANGENT` per vertex: xyz and the bitangent sign w.
    PerVertex(Vec<Vec4>),
    /// One per triangle corner, in the order of the triangle's indices.
    PerCorner(Vec<[Vec4; 3]>),
}

/// A triangle mesh in object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices, counter-clockwise seen from the front.
    pub indices: Vec<[u32; 3]>,
    /// Shading normals per vertex (empty: flat shading with the face normal).
    pub normals: Vec<Vec3>,
    /// Tangents for normal mapping.
    pub tangents: Tangents,
    /// Texture coordinate sets 0 and 1 (each empty when absent).
    pub uvs: [Vec<Vec2>; 2],
    /// `COLOR_0` per vertex (empty when absent).
    pub colors: Vec<Vec4>,
    /// Index of the material in the scene's table.
    pub material: u32,
}

impl MeshData {
    /// Bytes held by the mesh's arrays.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of_val;
        let tangents = match &self.tangents {
            Tangents::None => 0,
            Tangents::PerVertex(t) => size_of_val(t.as_slice()),
            Tangents::PerCorner(t) => size_of_val(t.as_slice()),
        };
        size_of_val(self.positions.as_slice())
            + size_of_val(self.indices.as_slice())
            + size_of_val(self.normals.as_slice())
            + tangents
            + size_of_val(self.uvs[0].as_slice())
            + size_of_val(self.uvs[1].as_slice())
            + size_of_val(self.colors.as_slice())
    }
}

/// A mesh placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index of the mesh.
    pub mesh: u32,
    /// The scene's index of the instance's first triangle (its triangles are
    /// consecutive, in the mesh's order).
    pub first_triangle: u32,
    /// Object to world.
    pub to_world: Affine3A,
    /// The inverse transpose of the linear part, for normals.
    pub normal_to_world: Mat3A,
    /// Whether the transform mirrors (negative determinant): the winding, and so
    /// the front face and tangents' handedness, flip.
    pub mirrors: bool,
}

impl Instance {
    /// An instance of mesh `mesh` whose triangles start at `first_triangle`.
    pub fn new(mesh: u32, first_triangle: u32, to_world: Affine3A) -> Self {
        let linear = to_world.matrix3;
        Self {
            mesh,
            first_triangle,
            to_world,
            normal_to_world: linear.inverse().transpose(),
            mirrors: linear.determinant() < 0.0,
        }
    }

    /// A point in world space.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3A {
        self.to_world.transform_point3a(p.into())
    }
}

/// A grid of `(cols + 1) × (rows + 1)` vertices over `(s, t) ∈ [0, 1]²`,
/// placed by `at` (position, normal, uv), two triangles per cell wound so
/// that the normal `at` gives is their front.
pub fn grid(cols: u32, rows: u32, at: impl Fn(f32, f32) -> (Vec3, Vec3, Vec2)) -> MeshData {
    let mut mesh = MeshData::default();
    for j in 0..=rows {
        for i in 0..=cols {
            let (p, n, uv) = at(i as f32 / cols as f32, j as f32 / rows as f32);
            mesh.positions.push(p);
            mesh.normals.push(n);
            mesh.uvs[0].push(uv);
        }
    }
    let v = |i: u32, j: u32| j * (cols + 1) + i;
    for j in 0..rows {
        for i in 0..cols {
            for tri in [
                [v(i, j), v(i + 1, j), v(i + 1, j + 1)],
                [v(i, j), v(i + 1, j + 1), v(i, j + 1)],
            ] {
                let p = tri.map(|k| mesh.positions[k as usize]);
                let face = (p[1] - p[0]).cross(p[2] - p[0]);
                if face.length_squared() <= 0.0 {
                    continue;
                }
                let n = mesh.normals[tri[0] as usize]
                    + mesh.normals[tri[1] as usize]
                    + mesh.normals[tri[2] as usize];
                mesh.indices.push(match face.dot(n) >= 0.0 {
                    true => tri,
                    false => [tri[0], tri[2], tri[1]],
                });
            }
        }
    }
    mesh
}

/// Mitsuba's unit sphere as a mesh of `segments` around and `segments / 2`
/// from pole to pole: (u, v) = (φ/2π, θ/π) of `(sin θ cos φ, sin θ sin φ,
/// cos θ)`, normals outwards (inwards, and wound so, when `flip`).
pub fn unit_sphere_mesh(segments: u32, flip: bool) -> MeshData {
    use std::f32::consts::PI;
    let mut mesh = grid(segments, segments / 2, |s, t| {
        let phi = 2.0 * PI * s;
        // The poles exactly (sin π is not 0 in f32): their triangles are
        // then exactly degenerate and left out.
        let (sin_t, cos_t) = match t {
            0.0 => (0.0, 1.0),
            1.0 => (0.0, -1.0),
            _ => (PI * t).sin_cos(),
        };
        let p = glam::Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
        (p, p, glam::Vec2::new(s, t))
    });
    if flip {
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
        for n in &mut mesh.normals {
            *n = -*n;
        }
    }
    mesh
}
