//! The `bdpt` integrator: bidirectional path tracing (Veach 1997, ch. 10;
//! the formulation of pbrt-v4's `bdpt`, written here from the formulas).
//!
//! Each pixel sample traces a camera subpath (its camera ray as `path`
//! would, then BSDF samples) and a light subpath (a light chosen by power,
//! a point and direction on it, then BSDF samples of the adjoint transport),
//! and joins every prefix of one to every prefix of the other: strategy
//! `(s, t)` joins the first `s` light vertices to the first `t` camera
//! vertices by a shadow ray. `(0, t)` is the camera subpath finding a light,
//! `(1, t)` next-event estimation with a light point drawn afresh, and
//! `(s, 1)` light tracing: the light subpath's vertex seen by the camera,
//! splatted onto the image wherever it lands. Every strategy's value is
//! weighted by the power heuristic over all strategies that could have made
//! the same path, from the densities each walk records per vertex
//! (`vertex.rs`); the weights of a path sum to one.
//!
//! So caustics that a path tracer cannot find (a point or spot light seen
//! through glass or off a mirror by a diffuse surface) are found by light
//! tracing, and small bright lights seen via glossy bounces are found by
//! connections.
//!
//! Transport: light subpaths use the adjoint BSDF (the BSDF seen from the
//! direction light leaves by) with Veach's correction for shading normals;
//! Mitsuba's smooth dielectric's radiance scaling `η²` is undone for light
//! passing through it. The shading frame of a light subpath's vertex is
//! built from the direction light arrived from.
//!
//! Lights at infinity (the environment, directional lights) start light
//! subpaths on a disk the size of the scene facing their direction, as in
//! Veach's thesis and pbrt; a camera subpath that escapes ends at the
//! environment.
//!
//! What it does not do (yet; `Job` refuses such scenes with a clear line):
//! participating media, emitting signed distance grids, orthographic cameras,
//! dispersion, adaptive sampling, and reconstruction filters other
//! than the box.
//!
//! The `vcm` integrator is the same with vertex merging (`merge.rs`):
//! each iteration (one sample of every pixel) first traces one light
//! subpath per pixel, keeps them in a hash grid, then each pixel's camera
//! subpath connects to its own light subpath as above and also merges each
//! of its vertices with the light vertices within a shrinking radius, the
//! merges weighed against the connections in the same power heuristic
//! (Georgiev et al. 2012). Merging finds what no connection can sample
//! from a small light: caustics seen through glass or in a mirror, and
//! caustics on diffuse surfaces as a blurred density estimate that
//! sharpens as the radius shrinks (consistent, not unbiased).
//!
//! Files: `vertex.rs` (vertices and their densities), `walk.rs` (the two
//! walks), `connect.rs` (the strategies and their weights), `merge.rs`
//! (the light subpaths of an iteration and their grid).

mod connect;
mod merge;
mod vertex;
mod walk;

pub use connect::{Scratch, sample};
pub use merge::{DEFAULT_RADIUS_PIXELS, LightPaths, first_radius, radius_at};
pub use vertex::MAX_VERTICES;
