//! Tangents for normal mapping when a mesh has none: MikkTSpace, as the glTF
//! specification requires, run on `(u, 1 − v)` so that the bitangent points
//! toward decreasing v (up in the image), the convention of
//! `docs/scene-conventions.md` (three.js and Filament correct the
//! raw-UV sign the same way).

use glam::{Vec3, Vec4};

use crate::scene::mesh::{MeshData, Tangents};

struct Input<'a> {
    mesh: &'a MeshData,
    set: usize,
    /// The triangles given to MikkTSpace: those with three distinct, finite
    /// corners and finite texture coordinates. The `mikktspace` crate indexes
    /// out of bounds on some degenerate triangles (a repeated vertex, found by
    /// fuzzing), and they have no tangent frame anyway.
    faces: Vec<usize>,
    out: Vec<[Vec4; 3]>,
}

impl Input<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[self.faces[face]][vert] as usize
    }

    fn face_normal(&self, face: usize) -> Vec3 {
        let [a, b, c] =
            self.mesh.indices[self.faces[face]].map(|i| self.mesh.positions[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }
}

impl mikktspace::Geometry for Input<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match self.mesh.normals.get(self.vertex(face, vert)) {
            Some(n) => n.to_array(),
            None => self.face_normal(face).to_array(),
        }
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.mesh.uvs[self.set][self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.out[self.faces[face]][vert] = Vec4::from(tangent);
    }
}

/// Whether MikkTSpace can be given this triangle: three distinct, finite
/// positions with finite texture coordinates (degenerate triangles keep the
/// default tangent; they are never hit with a meaningful frame).
fn has_frame(mesh: &MeshData, set: usize, face: [u32; 3]) -> bool {
    let p = face.map(|i| mesh.positions[i as usize]);
    let uv_finite = face.iter().all(|&i| mesh.uvs[set][i as usize].is_finite());
    p.iter().all(|q| q.is_finite()) && uv_finite && p[0] != p[1] && p[1] != p[2] && p[0] != p[2]
}

/// MikkTSpace tangents of `mesh` from texture coordinate set `set`, one per
/// triangle corner; `Tangents::None` if the generator gives up.
pub fn generate(mesh: &MeshData, set: usize) -> Tangents {
    let faces = (0..mesh.indices.len())
        .filter(|&f| has_frame(mesh, set, mesh.indices[f]))
        .collect();
    let mut input = Input {
        mesh,
        set,
        faces,
        out: vec![[Vec4::new(1.0, 0.0, 0.0, 1.0); 3]; mesh.indices.len()],
    };
    if mikktspace::generate_tangents(&mut input) {
        Tangents::PerCorner(input.out)
    } else {
        Tangents::None
    }
}
