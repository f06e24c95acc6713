//! The scalar path tracer, one path at a time: the reference that
//! [`super::lanes`] equals bit for bit.

use glam::Vec3A;

use super::direct::direct_counted;
use super::options::{HideEmitters, PathOptions, RR_DEPTH, RR_SCALE};
use super::samples::PathSampler;
use super::vertex::{
    NeeWeights, PathEvent, PathTracer, emission, next_event, power_heuristic, take_wavelength,
    vertex_frame, vertex_numbers,
};
use crate::geometry::ray::{Hit, Ray};
use crate::materials::Material;
use crate::scene::{Facing, Scene, SurfaceHit};

/// Radiance arriving along `ray` (a unit direction), estimated by one path.
/// Adds the rays cast (closest-hit and shadow) to `rays`. May return a
/// non-finite value in pathological cases; the caller drops those.
pub fn radiance(
    scene: &Scene,
    ray: &Ray,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
) -> Vec3A {
    *rays += 1;
    let hit = scene.intersect(ray, f32::INFINITY);
    radiance_from(scene, ray, hit, options, sampler, rays)
}

/// [`radiance`] for a ray whose closest hit `first` is already known (camera
/// rays traced four at a time); does not count that ray.
pub fn radiance_from(
    scene: &Scene,
    ray: &Ray,
    first: Option<Hit>,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
) -> Vec3A {
    radiance_observed(scene, ray, first, options, sampler, rays, &mut |_, _| {})
}

/// [`radiance_from`] that shows `observe` the first hit's surface and BSDF as
/// the path shades them, so that the render's AOVs need not look the hit's
/// textures up again. Not called when the path ends before it shades that hit
/// (a miss, or `max_depth` 1).
#[inline]
pub fn radiance_observed(
    scene: &Scene,
    ray: &Ray,
    first: Option<Hit>,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
    observe: &mut impl FnMut(&SurfaceHit, &Material),
) -> Vec3A {
    radiance_traced(scene, ray, first, options, sampler, rays, observe, &mut ())
}

/// [`radiance_observed`] that also shows `tracer` every vertex's surface and
/// contributions ([`PathEvent`]), for `--nan-check`; the same value, bit for
/// bit (with `()` the tracing compiles away).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn radiance_traced(
    scene: &Scene,
    ray: &Ray,
    first: Option<Hit>,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
    observe: &mut impl FnMut(&SurfaceHit, &Material),
    tracer: &mut impl PathTracer,
) -> Vec3A {
    if scene.has_media() {
        // Participating media: the volumetric path tracer (its vertices are
        // not shown to `tracer`).
        return super::volume::radiance(scene, ray, first, options, sampler, rays, observe);
    }
    if options.counts_direct() {
        let hide = options.hide_emitters != HideEmitters::No;
        return direct_counted(
            scene,
            ray,
            first,
            (options.direct, hide),
            sampler,
            rays,
            observe,
            tracer,
        );
    }
    let mut next_hit = first;
    let mut l = Vec3A::ZERO;
    let mut beta = Vec3A::ONE;
    let mut ray = *ray;
    // Emission reached through a delta lobe (or by the camera ray) cannot have
    // been sampled by next-event estimation: it counts in full.
    let mut specular = true;
    let mut bsdf_pdf = 0.0f32;
    // The last vertex's point and side, where the light's choice that MIS
    // weighs against the BSDF sample was made.
    let mut from = ray.origin;
    let mut from_facing = Facing::Any;
    let mut depth = 0u32;
    // Beer–Lambert attenuation per unit length of the medium the ray is in.
    let mut medium = Vec3A::ZERO;
    // The wavelength (nm) the path is carried at since it met a dispersive
    // surface; `None` while it is RGB.
    let mut wavelength: Option<f32> = None;
    let textures = scene.textures();
    let lights_need_samples = scene.light_needs_samples();
    // Mitsuba's `hide_emitters`: whether the path's value counts (yet).
    let hide = options.hide_emitters;
    let mut counts = hide == HideEmitters::No;
    loop {
        let Some(hit) = next_hit else {
            // Escaped: the environment is seen, weighted against having
            // sampled it directly.
            if !scene.environment().is_black() {
                let env = scene.environment_radiance(ray.dir);
                let weight = if specular {
                    1.0
                } else {
                    power_heuristic(bsdf_pdf, scene.environment_pdf(ray.dir, from, from_facing))
                };
                tracer.event(
                    depth,
                    beta,
                    PathEvent::Environment {
                        radiance: env,
                        weight,
                    },
                );
                l += beta * env * weight;
            }
            break;
        };
        if medium != Vec3A::ZERO {
            beta *= (-medium * hit.t).exp();
        }
        let surface = scene.surface(&hit);
        let material = &scene.materials()[surface.material as usize];
        if hide != HideEmitters::No && depth == 0 {
            if material.is_emissive() {
                // Hidden emitters: the camera ray goes on past this one,
                // from either side (Mitsuba's `skip_area_emitters`).
                ray = Ray::new(surface.point.offset_origin(ray.dir), ray.dir);
                *rays += 1;
                next_hit = scene.intersect(&ray, f32::INFINITY);
                continue;
            }
            counts |= hide == HideEmitters::Direct;
        }
        let ng = surface.ng;
        let cos_out = -ng.dot(ray.dir);
        tracer.event(
            depth,
            beta,
            PathEvent::Surface {
                point: surface.point.p,
                shading_normal: surface.ns,
                geometric_normal: ng,
                uv: surface.attrs.uv[0],
            },
        );

        // Emission from the front side of an area light (or either side).
        if let Some(le) = emission(scene, &surface, material, ray.dir, cos_out) {
            let weight = if specular {
                1.0
            } else {
                let light_pdf = scene.light_pdf_hit(&hit, from, from_facing, cos_out);
                power_heuristic(bsdf_pdf, light_pdf)
            };
            tracer.event(depth, beta, PathEvent::Emission { le, weight });
            l += beta * le * weight;
        }
        // An unlit surface (`KHR_materials_unlit`) shows its base colour and
        // scatters nothing. Light sampling never picks it (it is not in the
        // light table), so however the path reached it, it counts in full,
        // with no MIS weight, and the path ends.
        if material.is_unlit() {
            if depth == 0 {
                observe(&surface, &material.bsdf(&surface.attrs, textures));
            }
            let le = material.unlit_color(&surface.attrs, textures);
            tracer.event(depth, beta, PathEvent::Emission { le, weight: 1.0 });
            l += beta * le;
            break;
        }
        // Mitsuba's convention: a path of `max_depth` segments ends here.
        if depth + 1 >= options.max_depth {
            break;
        }

        let mut bsdf = material.bsdf(&surface.attrs, textures);
        if depth == 0 {
            observe(&surface, &bsdf);
        }
        // Mitsuba's `path` counts a path that scatters here, but off `null`.
        counts |= !bsdf.is_null();
        // `KHR_materials_dispersion`: the path's wavelength, drawn at its
        // first dispersive surface ([`take_wavelength`]).
        take_wavelength(&mut bsdf, &mut wavelength, &mut beta, sampler);
        let wo_world = -ray.dir;
        let (shading, frame, wo, facing) = vertex_frame(scene, &surface, &mut bsdf, wo_world);
        let sp = surface.point;
        let bsdf_at = bsdf.at(wo);
        let (light_sampled, u_light_pos, u_bsdf, u_choice) =
            vertex_numbers(&bsdf, lights_need_samples, sampler);
        let u_lobe = u_choice.y;

        (from, from_facing) = (sp.p, facing);
        if light_sampled
            && let Some(light) = scene.sample_light(sp.p, facing, u_choice, u_light_pos)
            && let Some((f, li, weight)) = next_event(
                scene,
                &sp,
                &frame,
                &shading,
                &bsdf_at,
                light,
                NeeWeights::PATH,
                rays,
            )
        {
            tracer.event(depth, beta, PathEvent::Light { f, li, weight });
            l += beta * f * li * weight;
        }

        // Continue the path by sampling the BSDF.
        let Some(bs) = bsdf_at.sample(u_lobe, u_bsdf) else {
            break;
        };
        let wi_world = frame.to_world(bs.wi);
        let side = shading.weight(wi_world);
        if side <= 0.0 {
            break;
        }
        let weight = bs.weight * side;
        tracer.event(
            depth,
            beta,
            PathEvent::Bounce {
                weight,
                pdf: bs.pdf,
            },
        );
        beta *= weight;
        specular = bs.specular;
        bsdf_pdf = bs.pdf;
        // Crossing a refracting surface enters or leaves its medium.
        if wi_world.dot(ng) * cos_out < 0.0 {
            medium = if cos_out > 0.0 {
                material.attenuation()
            } else {
                Vec3A::ZERO
            };
        }
        ray = Ray::new(sp.offset_origin(wi_world), wi_world);
        depth += 1;
        if beta == Vec3A::ZERO {
            break;
        }

        if depth >= RR_DEPTH {
            let survive = (beta.max_element() * RR_SCALE).min(0.95);
            // (A NaN throughput ends the path too.)
            if sampler.next_1d() >= survive || survive.is_nan() {
                break;
            }
            beta /= survive;
        }
        *rays += 1;
        next_hit = scene.intersect(&ray, f32::INFINITY);
    }
    if counts { l } else { Vec3A::ZERO }
}
