//! What a scene is made of, before it is built: the parts every loader
//! produces ([`SceneParts`]), the key point light, and why a scene cannot be
//! built ([`SceneError`]).

use std::collections::HashMap;

use glam::Vec3A;
use thiserror::Error;

use super::analytic::SceneShape;
use super::media::SceneMedia;
use super::mesh::{Instance, MeshData};
use crate::camera::SceneCamera;
use crate::geometry::sdfgrid::SdfGrid;
use crate::geometry::triangle::Triangle;
use crate::lights::Light;
use crate::materials::surface::SurfaceMaterial;
use crate::textures::TextureStore;

/// The lab's point light: position and power per colour channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointLight {
    /// Where the light is.
    pub position: Vec3A,
    /// Emitted power `P` per colour channel (the lab's "light colour"); its
    /// intensity is `P/(4π)` W/sr.
    pub power: Vec3A,
}

/// Why a scene cannot be built.
#[derive(Debug, Error, PartialEq)]
pub enum SceneError {
    /// A vertex has a NaN or infinite coordinate.
    #[error("triangle {index} has a non-finite vertex")]
    NonFiniteVertex {
        /// Index of the triangle.
        index: usize,
    },
    /// A reflectance is outside `[0, 1]` or not finite.
    #[error("triangle {index} has reflectance {value:?} outside [0, 1]")]
    BadReflectance {
        /// Index of the triangle.
        index: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// An emitted radiance is negative or not finite.
    #[error("triangle {index} has emitted radiance {value:?} (must be finite and >= 0)")]
    BadEmission {
        /// Index of the triangle.
        index: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// Per-triangle lists differ in length.
    #[error("{triangles} triangles but {reflectances} reflectances")]
    LengthMismatch {
        /// Number of triangles.
        triangles: usize,
        /// Number of entries in the other list.
        reflectances: usize,
    },
    /// A triangle names a material, instance or texture that does not exist.
    #[error("{what}")]
    BadReference {
        /// What is wrong.
        what: String,
    },
}

/// Everything a scene is made of, for loaders; [`Scene::from_parts`](crate::scene::Scene::from_parts) checks it
/// and builds the BVH and the light tables.
#[derive(Clone, Debug, Default)]
pub struct SceneParts {
    /// Triangles in world space, in the order of the per-triangle lists.
    pub triangles: Vec<Triangle>,
    /// Unit front normal of each triangle (light leaves emitters on this side;
    /// one-sided scenes reflect only on it). Zero for degenerate triangles.
    pub normals: Vec<Vec3A>,
    /// Material of each triangle.
    pub material_of: Vec<u32>,
    /// Instance of each triangle, or [`NO_INSTANCE`] for bare triangles (face
    /// normal, no texture coordinates); may be empty when all are bare.
    pub instance_of: Vec<u32>,
    /// Meshes with their vertex attributes.
    pub meshes: Vec<MeshData>,
    /// Meshes placed in the world.
    pub instances: Vec<Instance>,
    /// The material table.
    pub materials: Vec<SurfaceMaterial>,
    /// Images the materials' textures refer to.
    pub textures: TextureStore,
    /// The key point light (`direct`'s light, the viewer's movable light).
    pub light: PointLight,
    /// Other punctual lights.
    pub lights: Vec<Light>,
    /// The lab's ambient term.
    pub ambient: Vec3A,
    /// Whether surfaces reflect on both sides (everything but the lab box).
    pub two_sided: bool,
    /// Cameras from the file.
    pub cameras: Vec<SceneCamera>,
    /// Analytic spheres, disks and cylinders, and the cells of signed
    /// distance grids (primitives `triangles.len() + k` of the scene).
    pub shapes: Vec<SceneShape>,
    /// The signed distance grids whose cells are among `shapes` (a cell's
    /// `grid` indexes this).
    pub sdf_grids: Vec<SdfGrid>,
    /// Participating media and the surfaces that bound them.
    pub media: SceneMedia,
}

impl SceneParts {
    /// The parts of a scene of bare triangles with diffuse reflectances in the
    /// lab's form (one-sided, lab normals `cross(v2 − v0, v1 − v0)`, one
    /// material per distinct colour); see [`Scene::new`](crate::scene::Scene::new).
    pub fn lab(
        triangles: Vec<Triangle>,
        reflectance: Vec<Vec3A>,
        light: PointLight,
        ambient: Vec3A,
    ) -> Result<Self, SceneError> {
        if triangles.len() != reflectance.len() {
            return Err(SceneError::LengthMismatch {
                triangles: triangles.len(),
                reflectances: reflectance.len(),
            });
        }
        let valid = |r: &Vec3A| r.is_finite() && r.min_element() >= 0.0 && r.max_element() <= 1.0;
        if let Some(index) = reflectance.iter().position(|r| !valid(r)) {
            return Err(SceneError::BadReflectance {
                index,
                value: reflectance[index].into(),
            });
        }
        // One material per distinct colour.
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let mut materials = Vec::new();
        let material_of = reflectance
            .iter()
            .map(|r| {
                *ids.entry(r.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        materials.push(SurfaceMaterial::diffuse(*r));
                        materials.len() as u32 - 1
                    })
            })
            .collect();
        let normals = triangles.iter().map(Triangle::lab_normal).collect();
        Ok(SceneParts {
            triangles,
            normals,
            material_of,
            materials,
            light,
            ambient,
            ..SceneParts::default()
        })
    }
}

/// Marks a bare triangle in [`SceneParts::instance_of`].
pub const NO_INSTANCE: u32 = u32::MAX;
