//! raylab: a fast, physically based CPU ray tracer that grew out of the classic
//! Cornell-box lab (ray–triangle intersection, a pinhole camera, a point light with
//! shadows and a constant ambient term).
//!
//! The crate follows pbrt's split into small modules, one concept each:
//!
//! * [`geometry`]: rays and robust spawning of secondary rays, the watertight
//!   ray–triangle test and the eight-wide BVH;
//! * [`scene`]: the one scene representation of every source (triangles, their
//!   vertex attributes, materials, textures, lights, cameras) behind the
//!   [`Scene::intersect`] / [`Scene::occluded`] seam;
//! * [`load`]: the scene's loaders above it (the lab's built-in boxes,
//!   Wavefront OBJ, glTF 2.0, scene files);
//! * [`camera`]: pinhole (and orthographic) cameras;
//! * [`materials`]: BSDFs (diffuse, mirror, glass, rough conductor, the glTF
//!   metallic–roughness BRDF);
//! * [`textures`]: decoded images shared by materials, and their lookups;
//! * [`lights`]: point, spot and directional lights, and area lights;
//! * [`integrators`]: `flat`, `direct` (the lab's lighting model) and `path`
//!   (next-event estimation, MIS, Russian roulette);
//! * [`sampling`]: PCG32 streams keyed by (seed, pixel, sample), and
//!   Owen-scrambled Sobol' points;
//! * [`render`]: tiles on rayon, deterministic per-pixel sampling;
//! * [`limits`]: the largest image, sample count and time a render accepts;
//! * [`aov`]: albedo and normal guides (through specular chains), depth,
//!   position and variance per pixel, gathered by the render;
//! * [`denoise`]: Open Image Denoise, loaded at run time, on an image and its
//!   guides, blended back towards the noisy image where it is good enough;
//! * [`film`]: the image buffer, tone mapping and atomic PNG/EXR output;
//! * [`checkpoint`]: a render's sums saved to resume it after a stop or a kill;
//! * [`fingerprint`]: the stable hash of checkpoints, the cache's entries and
//!   scenes;
//! * [`job`]: the render job, which owns the command line's policy (defaults,
//!   a scene file's settings merged with the options, output, checkpoints,
//!   parts, frames, denoising): `raylab render`, `raylab view` and `raylab
//!   merge` are thin shells around it;
//! * [`controls`]: the viewer's camera/light state and how input changes it;
//! * [`interactive`]: a view that refines while it rests and denoises on a
//!   thread of its own (`raylab view` shows it in a window);
//! * [`workload`]: the ray-casting workloads of `raylab bench`, and [`bench`](mod@bench)
//!   which times them.
//!
//! ## Rendering from Rust
//!
//! A [`job::Job`] does what `raylab render` does, with the same options,
//! defaults and files (`examples/render_gltf.rs`; ARCHITECTURE.md maps the
//! code):
//!
//! ```
//! use raylab::job::{Job, JobOptions};
//!
//! let mut options = JobOptions::new("assets/models/DamagedHelmet/DamagedHelmet.gltf");
//! options.output = Some(std::env::temp_dir().join("raylab-doc-helmet.png"));
//! options.scene.width = Some(160); // the height follows the camera's aspect ratio
//! Job::new(options)?.run()?;
//! # Ok::<(), anyhow::Error>(())
//! ```

#![warn(missing_docs)]

pub mod aov;
pub mod bench;
pub mod cache;
pub mod camera;
pub mod checkpoint;
pub mod controls;
pub mod denoise;
pub mod farm;
pub mod film;
pub mod fingerprint;
pub mod fixed;
pub mod geometry;
pub mod guard;
pub mod integrators;
pub mod interactive;
pub mod job;
pub mod lights;
pub mod limits;
pub mod load;
pub mod materials;
pub mod media;
pub mod memory;
pub mod nan_check;
pub mod render;
pub mod sampling;
pub mod scene;
mod simd;
pub mod textures;
pub mod workload;

pub use camera::Camera;
pub use geometry::ray::{Hit, Ray};
pub use geometry::triangle::Triangle;
pub use integrators::Integrator;
pub use scene::{LightSample, PointLight, Scene, SceneError};
