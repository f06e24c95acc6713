//! Mitsuba's `direct` integrator with its sample counts (`emitter_samples`,
//! `bsdf_samples`): at the camera ray's hit, `N` light samples and `M` BSDF
//! samples, each strategy's density scaled by its share of the `N + M`
//! samples in the power heuristic (Veach's multi-sample MIS), each sample
//! weighed by one over its strategy's count. With one of each it is a path
//! of depth 2, which [`super::scalar`] renders (and this module is not
//! called); the expected image is the same for every count.
//!
//! One difference from Mitsuba 3.7.1: Mitsuba gives a punctual light's
//! sample the weight 1 whatever `emitter_samples` is, so that a point light
//! is counted `N` times over; here each of its samples weighs `1/N`, as
//! every other light's does.

use glam::{Vec2, Vec3A};

use super::samples::PathSampler;
use super::vertex::{
    NeeWeights, PathEvent, PathTracer, emission, next_event, power_heuristic, vertex_frame,
};
use crate::geometry::ray::{Hit, Ray};
use crate::materials::{Material, spectrum};
use crate::scene::{Scene, SurfaceHit};

/// How many light and BSDF samples a path of depth 2 takes at the camera
/// ray's hit (Mitsuba's `direct`: `emitter_samples`, `bsdf_samples`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DirectSamples {
    /// Light samples (next-event estimation).
    pub emitter: u32,
    /// BSDF samples.
    pub bsdf: u32,
}

impl DirectSamples {
    /// One of each: the path tracer's own vertex.
    pub const ONE_EACH: Self = Self {
        emitter: 1,
        bsdf: 1,
    };

    /// The most samples of one kind a scene may ask for.
    pub const MAX: u32 = 4096;

    /// The counts, if they are valid: at most [`DirectSamples::MAX`] each,
    /// not both zero.
    pub fn new(emitter: u32, bsdf: u32) -> Option<Self> {
        (emitter.max(bsdf) <= Self::MAX && emitter + bsdf > 0).then_some(Self { emitter, bsdf })
    }
}

impl Default for DirectSamples {
    fn default() -> Self {
        Self::ONE_EACH
    }
}

/// The radiance along the camera ray `ray` (closest hit `first`) by
/// Mitsuba's `direct` with `counts` samples, emitters hidden (its
/// `hide_emitters`) or not; adds the rays it casts to `rays`. `observe` and
/// `tracer` as in `radiance_traced`.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn direct_counted(
    scene: &Scene,
    ray: &Ray,
    first: Option<Hit>,
    (counts, hide): (DirectSamples, bool),
    sampler: &mut impl PathSampler,
    rays: &mut u64,
    observe: &mut impl FnMut(&SurfaceHit, &Material),
    tracer: &mut impl PathTracer,
) -> Vec3A {
    let textures = scene.textures();
    let mut ray = *ray;
    let mut next_hit = first;
    // Hidden emitters: the camera ray goes on past every emitting surface.
    let surface = loop {
        let Some(hit) = next_hit else {
            if hide || scene.environment().is_black() {
                return Vec3A::ZERO;
            }
            let radiance = scene.environment_radiance(ray.dir);
            let weight = 1.0;
            tracer.event(0, Vec3A::ONE, PathEvent::Environment { radiance, weight });
            return radiance;
        };
        let surface = scene.surface(&hit);
        if !(hide && scene.materials()[surface.material as usize].is_emissive()) {
            break surface;
        }
        ray = Ray::new(surface.point.offset_origin(ray.dir), ray.dir);
        *rays += 1;
        next_hit = scene.intersect(&ray, f32::INFINITY);
    };
    let material = &scene.materials()[surface.material as usize];
    let ng = surface.ng;
    let cos_out = -ng.dot(ray.dir);
    tracer.event(
        0,
        Vec3A::ONE,
        PathEvent::Surface {
            point: surface.point.p,
            shading_normal: surface.ns,
            geometric_normal: ng,
            uv: surface.attrs.uv[0],
        },
    );
    let mut l = Vec3A::ZERO;
    if let Some(le) = emission(scene, &surface, material, ray.dir, cos_out) {
        tracer.event(0, Vec3A::ONE, PathEvent::Emission { le, weight: 1.0 });
        l = le;
    }
    let mut bsdf = material.bsdf(&surface.attrs, textures);
    observe(&surface, &bsdf);
    if material.is_unlit() {
        let le = material.unlit_color(&surface.attrs, textures);
        tracer.event(0, Vec3A::ONE, PathEvent::Emission { le, weight: 1.0 });
        return l + le;
    }
    // A dispersive surface carries the path at one wavelength (as in `path`).
    let mut beta = Vec3A::ONE;
    if bsdf.dispersive() {
        let (lambda, w) = spectrum::sample_weighted(sampler.next_1d());
        beta = w;
        bsdf.set_wavelength(lambda);
    }
    let (shading, frame, wo, facing) = vertex_frame(scene, &surface, &mut bsdf, -ray.dir);
    let sp = surface.point;
    let bsdf_at = bsdf.at(wo);
    let total = (counts.emitter + counts.bsdf) as f32;
    let (frac_light, frac_bsdf) = (counts.emitter as f32 / total, counts.bsdf as f32 / total);

    // Light samples, off surfaces with a lobe that is not a delta.
    if !bsdf.is_specular() && counts.emitter > 0 {
        let nee = NeeWeights {
            light: frac_light,
            bsdf: frac_bsdf,
            share: 1.0 / counts.emitter as f32,
        };
        for _ in 0..counts.emitter {
            let u = sampler.next_2d();
            let u_choice = if scene.light_needs_samples() {
                sampler.next_2d_minor()
            } else {
                Vec2::ZERO
            };
            if let Some(light) = scene.sample_light(sp.p, facing, u_choice, u)
                && let Some((f, li, weight)) =
                    next_event(scene, &sp, &frame, &shading, &bsdf_at, light, nee, rays)
            {
                tracer.event(0, beta, PathEvent::Light { f, li, weight });
                l += beta * f * li * weight;
            }
        }
    }

    // BSDF samples: what each finds emitting (or the sky), weighed against
    // having been found by a light sample.
    let share = 1.0 / counts.bsdf.max(1) as f32;
    for _ in 0..counts.bsdf {
        let u_lobe = if bsdf.chooses_lobe() {
            sampler.next_2d_minor().y
        } else {
            0.0
        };
        let u = sampler.next_2d();
        let Some(bs) = bsdf_at.sample(u_lobe, u) else {
            continue;
        };
        let wi = frame.to_world(bs.wi);
        let side = shading.weight(wi);
        if side.is_nan() || side <= 0.0 {
            continue;
        }
        let weight = bs.weight * side;
        tracer.event(
            0,
            beta,
            PathEvent::Bounce {
                weight,
                pdf: bs.pdf,
            },
        );
        let throughput = beta * weight;
        let ray = Ray::new(sp.offset_origin(wi), wi);
        *rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            if !scene.environment().is_black() {
                let radiance = scene.environment_radiance(wi);
                let mis = if bs.specular {
                    share
                } else {
                    let pdf = scene.environment_pdf(wi, sp.p, facing);
                    power_heuristic(bs.pdf * frac_bsdf, pdf * frac_light) * share
                };
                tracer.event(
                    1,
                    throughput,
                    PathEvent::Environment {
                        radiance,
                        weight: mis,
                    },
                );
                l += throughput * radiance * mis;
            }
            continue;
        };
        let found = scene.surface(&hit);
        let emitter = &scene.materials()[found.material as usize];
        let cos_found = -found.ng.dot(wi);
        // Through a refracting surface into its medium (`KHR_materials_volume`).
        let medium = if wi.dot(ng) * cos_out < 0.0 && cos_out > 0.0 {
            (-material.attenuation() * hit.t).exp()
        } else {
            Vec3A::ONE
        };
        if let Some(le) = emission(scene, &found, emitter, wi, cos_found) {
            let mis = if bs.specular {
                share
            } else {
                let pdf = scene.light_pdf_hit(&hit, sp.p, facing, cos_found);
                power_heuristic(bs.pdf * frac_bsdf, pdf * frac_light) * share
            };
            tracer.event(1, throughput, PathEvent::Emission { le, weight: mis });
            l += throughput * medium * le * mis;
        }
        // An unlit surface counts in full (no light sample finds it).
        if emitter.is_unlit() {
            let le = emitter.unlit_color(&found.attrs, textures);
            tracer.event(1, throughput, PathEvent::Emission { le, weight: share });
            l += throughput * medium * le * share;
        }
    }
    l
}
