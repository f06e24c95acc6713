//! `--nan-check`: which sample of a render came out NaN or infinite, and where
//! along its path the bad number entered.
//!
//! Renders drop non-finite samples (they count as black) and count them. Every
//! sample is a pure function of (scene, camera, integrator, seed, pixel, sample
//! index), so the first bad one can be found after the render by evaluating
//! samples again, and replayed alone with a [`PathTracer`] that records the
//! first vertex where a non-finite number appears: the surface (position,
//! normals, texture coordinates), emission, the environment, a light sample or
//! the BSDF sample that continues the path.

use std::fmt;
use std::ops::Range;

use glam::Vec3A;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::integrators::Integrator;
use crate::integrators::path::{PathEvent, PathTracer};
use crate::render::probe_sample;
use crate::scene::Scene;

/// The first non-finite sample of a render (in pixel order, then sample order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BadSample {
    /// Pixel column.
    pub x: u32,
    /// Pixel row (0 at the top).
    pub y: u32,
    /// Sample index within the pixel.
    pub sample: u32,
    /// Seed of the render.
    pub seed: u64,
    /// The sample's value.
    pub value: Vec3A,
    /// Where along the path the first non-finite number appeared (`path`
    /// only; `None` for `flat` and `direct`, or when every vertex's numbers
    /// were finite and only their sum overflowed).
    pub vertex: Option<BadVertex>,
}

/// The path vertex where a non-finite number first appeared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BadVertex {
    /// Vertex depth: 0 is the camera ray's hit (or the environment seen
    /// directly), 1 the first bounce's, ...
    pub depth: u32,
    /// Path throughput before the event.
    pub beta: Vec3A,
    /// What happened there.
    pub event: PathEvent,
    /// The surface at that vertex, if the path had reached one.
    pub surface: Option<PathEvent>,
}

/// Records the first event with a non-finite number, and the surface it
/// happened on.
#[derive(Default)]
struct FirstBad {
    surface: Option<PathEvent>,
    found: Option<BadVertex>,
}

fn finite_event(e: &PathEvent) -> bool {
    match *e {
        PathEvent::Surface {
            point,
            shading_normal,
            geometric_normal,
            uv,
        } => {
            point.is_finite()
                && shading_normal.is_finite()
                && geometric_normal.is_finite()
                && uv.is_finite()
        }
        PathEvent::Emission { le, weight } => le.is_finite() && weight.is_finite(),
        PathEvent::Environment { radiance, weight } => radiance.is_finite() && weight.is_finite(),
        PathEvent::Light { f, li, weight } => f.is_finite() && li.is_finite() && weight.is_finite(),
        PathEvent::Bounce { weight, pdf } => weight.is_finite() && pdf.is_finite(),
    }
}

impl PathTracer for FirstBad {
    fn event(&mut self, depth: u32, beta: Vec3A, event: PathEvent) {
        if self.found.is_some() {
            return;
        }
        if matches!(event, PathEvent::Surface { .. }) {
            self.surface = Some(event);
        }
        if !beta.is_finite() || !finite_event(&event) {
            self.found = Some(BadVertex {
                depth,
                beta,
                event,
                surface: self.surface,
            });
        }
    }
}

/// The first sample among `samples` of every pixel whose value is NaN or
/// infinite, in pixel order (rows from the top, left to right) and then sample
/// order, with the path vertex where it went bad; `None` if there is none.
/// Costs up to one more render of those samples (single rays, all cores).
pub fn first_bad_sample(
    scene: &Scene,
    camera: &Camera,
    integrator: Integrator,
    seed: u64,
    samples: Range<u32>,
) -> Option<BadSample> {
    let (x, y, sample) = (0..camera.height).into_par_iter().find_map_first(|y| {
        (0..camera.width).find_map(|x| {
            samples.clone().find_map(|s| {
                let v = probe_sample(scene, camera, integrator, seed, x, y, s, &mut ());
                (!v.is_finite()).then_some((x, y, s))
            })
        })
    })?;
    let mut tracer = FirstBad::default();
    let value = probe_sample(scene, camera, integrator, seed, x, y, sample, &mut tracer);
    Some(BadSample {
        x,
        y,
        sample,
        seed,
        value,
        vertex: tracer.found,
    })
}

struct V(Vec3A);

impl fmt::Display for V {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {}, {})", self.0.x, self.0.y, self.0.z)
    }
}

impl fmt::Display for BadSample {
    /// One line: the pixel, the sample and seed to reproduce it, and what went
    /// bad where.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "first NaN/Inf sample: pixel ({}, {}), sample {}, seed {}, value {}",
            self.x,
            self.y,
            self.sample,
            self.seed,
            V(self.value)
        )?;
        let Some(v) = &self.vertex else {
            return write!(
                f,
                "; every path vertex was finite (the sum overflowed, or not `path`)"
            );
        };
        write!(
            f,
            "; at path vertex {} (0: the camera ray's hit): ",
            v.depth
        )?;
        if !v.beta.is_finite() {
            write!(f, "throughput {} before it; ", V(v.beta))?;
        }
        match v.event {
            PathEvent::Surface {
                point,
                shading_normal,
                geometric_normal,
                uv,
            } => write!(
                f,
                "the surface: point {}, shading normal {}, geometric normal {}, uv ({}, {})",
                V(point),
                V(shading_normal),
                V(geometric_normal),
                uv.x,
                uv.y
            )?,
            PathEvent::Emission { le, weight } => {
                write!(f, "emission {} with MIS weight {weight}", V(le))?
            }
            PathEvent::Environment { radiance, weight } => write!(
                f,
                "the environment, radiance {} with MIS weight {weight}",
                V(radiance)
            )?,
            PathEvent::Light {
                f: bsdf,
                li,
                weight,
            } => write!(
                f,
                "a light sample: BSDF {}, radiance/pdf {}, MIS weight {weight}",
                V(bsdf),
                V(li)
            )?,
            PathEvent::Bounce { weight, pdf } => {
                write!(f, "the BSDF sample: weight {}, pdf {pdf}", V(weight))?
            }
        }
        if let Some(PathEvent::Surface { point, .. }) = v.surface
            && !matches!(v.event, PathEvent::Surface { .. })
        {
            write!(f, ", on the surface at {}", V(point))?;
        }
        Ok(())
    }
}
