//! The `path` integrator: a unidirectional path tracer in physical units.
//!
//! Radiance is estimated along paths from the camera. At every non-specular
//! vertex one light is picked in proportion to its power (among punctual lights,
//! by what each sends there: [`crate::scene::Scene::sample_light`]) and sampled (next-event
//! estimation); emission found by following the BSDF sample is weighted against
//! it with the power heuristic (multiple importance sampling), so area lights get
//! the better of both strategies. The point light can only be reached by
//! next-event estimation. Russian roulette ([`RR_SCALE`]) ends paths after
//! [`RR_DEPTH`] bounces; `max_depth` can cut them earlier.
//!
//! Units: a point light of power `P` has intensity `P/(4π)` W/sr, emitting
//! triangles radiance `Le`, diffuse surfaces reflect `ρ/π`. Nothing is added for
//! ambient light: the path tracer computes it.
//!
//! Colour is linear RGB, but for paths that meet a dispersive glTF material
//! (`KHR_materials_dispersion`): from there on such a path is carried at one
//! wavelength, drawn once, its throughput weighted by that wavelength's RGB
//! response ([`crate::materials::spectrum`]).
//!
//! The path tracer is `scalar`'s, one path at a time; `lanes` shades eight
//! paths at once in AVX2 registers where the scene allows, with the same
//! values bit for bit.

mod direct;
mod equiangular;
pub(crate) mod lanes;
mod options;
mod samples;
mod scalar;
mod vertex;
mod volume;
mod walk;

pub use direct::DirectSamples;
pub use options::{HideEmitters, PathOptions, RR_DEPTH, RR_SCALE};
pub use samples::{PathSampler, SOBOL_BOUNCES, SOBOL_PAIRS, SamplerKind, SobolSampler};
pub use scalar::{radiance, radiance_from, radiance_observed, radiance_traced};
pub use vertex::{PathEvent, PathTracer, consistent_normal, power_heuristic};
pub(crate) use vertex::{Shading, coat_normal, emission, shading, vertex_frame};
pub use walk::MAX_WALK_STEPS;
