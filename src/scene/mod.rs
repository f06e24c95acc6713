//! The scene: one representation for every source (the lab's built-in boxes,
//! OBJ, glTF). Triangles in world space for the BVH, with a material index
//! each; meshes whose vertex attributes (shading normals, two UV sets, tangents,
//! colours) are looked up from a hit; a material table; a texture store shared
//! by the materials; lights (the key point light, other punctual lights,
//! emitting triangles); cameras; analytic spheres, disks and cylinders. Rays see it through one query seam
//! ([`Scene::intersect`], [`Scene::occluded`]), which also makes alpha-masked
//! surfaces holes. The loaders that make scenes from files are in
//! [`crate::load`], above this model.
//!
//! The files, from the bottom up: `mesh.rs` (meshes and their instances),
//! `analytic.rs` (the analytic shapes and their hierarchy),
//! `parts.rs` (what a scene is made of, [`SceneParts`]) with `compose.rs`
//! (placing and appending parts), `light_tree.rs` (the light tree, and
//! [`Facing`]), `light_table.rs` (the light tables a scene keeps), `media.rs` (where
//! participating media are), `model.rs`
//! ([`Scene`]: building it, the query seam, what it holds), and the rest of
//! its methods: `surface.rs` (what a hit looks like), `light_sampling.rs`
//! (choosing lights, their densities), `emission.rs` (light leaving the
//! lights, for paths started at them) and `lanes.rs` (eight rays in AVX2
//! lanes).

pub mod analytic;
pub mod compose;
mod emission;
mod lanes;
mod light_sampling;
mod light_table;
mod light_tree;
mod media;
pub mod mesh;
mod model;
mod parts;
mod surface;

pub use analytic::{AnalyticShape, SceneShape};
pub use emission::{Emitter, EmitterPoint, InfiniteEmitter, PunctualEmission};
pub use light_sampling::{LightSample, MAX_IMPORTANCE_LIGHTS};
pub use light_table::{KEY_LIGHT, LightNumbers, LightSelection, PositionalLight};
pub use light_tree::Facing;
pub use media::{MediumInterface, SceneMedia};
pub use mesh::{Instance, MeshData, Tangents};
pub use model::{MAX_ALPHA_LAYERS, Scene};
pub use parts::{NO_INSTANCE, PointLight, SceneError, SceneParts};
pub use surface::SurfaceHit;
