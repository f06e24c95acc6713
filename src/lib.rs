//! raylab: a fast, physically based CPU ray tracer that grew out of the classic
//! Cornell-box lab (ray–triangle intersection, a pinhole camera, a point light with
//! shadows and a constant ambient term).
//!
//! The crate follows pbrt's split into small modules, one concept each:
//!
//! * [`ray`]: rays and robust spawning of secondary rays off a surface;
//! * [`triangle`]: the watertight ray–triangle test;
//! * [`bvh`]: the bounding volume hierarchy that answers scene queries;
//! * [`scene`]: triangles with their materials and the light, behind the
//!   [`Scene::intersect`] / [`Scene::occluded`] seam;
//! * [`cornell`]: the lab's built-in Cornell box;
//! * [`obj`]: Wavefront OBJ/MTL meshes, and [`framing`]: a camera and light for them;
//! * [`camera`]: the lab's pinhole camera (yaw/pitch);
//! * [`integrator`]: `flat`, `direct` (the lab's lighting model) and `path`;
//! * [`path`]: the path tracer (next-event estimation, MIS, Russian roulette);
//! * [`material`]: BSDFs (diffuse, mirror, glass, rough conductor);
//! * [`sampler`]: PCG32 streams keyed by (seed, pixel, sample), and [`sobol`]:
//!   Owen-scrambled Sobol' points;
//! * [`render`]: tiles on rayon, deterministic per-pixel sampling;
//! * [`film`]: the image buffer and atomic PNG/EXR output;
//! * [`controls`]: the viewer's camera/light state and how input changes it;
//! * [`workload`]: the ray-casting workloads of `raylab bench`.

#![warn(missing_docs)]

pub mod bvh;
pub mod camera;
pub mod controls;
pub mod cornell;
pub mod film;
pub mod framing;
pub mod integrator;
pub mod material;
pub mod obj;
pub mod path;
pub mod ray;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod sobol;
pub mod transform;
pub mod triangle;
pub mod workload;

pub use camera::Camera;
pub use integrator::Integrator;
pub use ray::{Hit, Ray};
pub use scene::{LightSample, PointLight, Scene, SceneError};
pub use triangle::Triangle;
