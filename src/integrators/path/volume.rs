//! The path tracer in scenes with participating media (Mitsuba's `volpath`,
//! pbrt's `volpath`): between two surfaces a path may scatter in the medium
//! it travels in, next-event estimation weighs a light sample by the
//! transmittance of the media (and index-matched boundaries) on its way, and
//! surfaces that bound media change the medium a path is in.
//!
//! It is `path` ([`super::scalar`]) with these differences, and only for
//! scenes that hold a medium ([`Scene::has_media`]), so that other scenes
//! render bit for bit as before:
//! - **Media.** A ray in a medium samples a flight distance
//!   ([`crate::media::Medium::sample_flight`], spectral MIS for chromatic
//!   media). A collision before the next surface is a scattering vertex:
//!   it counts as a bounce for `max_depth`, takes a light sample weighed by
//!   the phase function (MIS against phase sampling, power heuristic) and
//!   leaves by a direction sampled from the phase function.
//! - **Boundaries.** A surface's [`crate::scene::MediumInterface`] decides
//!   the medium a ray leaving it travels in (the interior behind its front
//!   normal, the exterior in front; a surface with neither leaves the
//!   medium as it was), as Mitsuba's `target_medium`. An index-matched
//!   boundary (Mitsuba's `null` BSDF) is crossed without a vertex: no
//!   bounce is counted, and the MIS of emission found later still weighs the
//!   last real vertex's choice.
//! - **Straight lobes.** A lobe that lets light through undeviated
//!   (Mitsuba's `thindielectric`, whose transmission Mitsuba flags `Null`)
//!   is crossed as such a boundary is, when the path samples it.
//! - **Shadow rays** ([`transmittance`]) cross index-matched boundaries and
//!   thin sheets (times what the sheet lets through) and multiply the
//!   transmittance of every medium on the way; any other surface blocks
//!   them.
//!
//! - **Subsurface media** ([`crate::media::Medium::subsurface`]) are
//!   crossed by a random walk ([`super::walk`]) from the surface a path
//!   enters by to the one it leaves by.
//!
//! Camera rays start in [`crate::scene::SceneMedia::camera`]. The rules for
//! `max_depth` are Mitsuba's: a path has at most `max_depth` segments, not
//! counting the crossings of index-matched boundaries.

use glam::Vec3A;

use super::equiangular::Segment;
use super::options::{HideEmitters, PathOptions, RR_DEPTH, RR_SCALE};
use super::samples::PathSampler;
use super::vertex::{
    emission, light_terms, power_heuristic, take_wavelength, vertex_frame, vertex_numbers,
};
use super::walk::walk;
use crate::geometry::ray::{Hit, Ray, SHADOW_EPSILON};
use crate::materials::Material;
use crate::media::{Flight, Homogeneous, Medium};
use crate::sampling::equiangular;
use crate::scene::{Facing, LightSample, Scene, SurfaceHit};

/// The most surfaces a shadow ray crosses (index-matched boundaries) before
/// it is taken as blocked, and the most a path crosses in a row without a
/// vertex: a bound against scenes of endless coplanar boundaries.
const MAX_CROSSINGS: u32 = 256;

/// The radiance arriving along `ray` (whose closest hit is `first`) in a
/// scene with media, estimated by one path; `observe` is shown the first
/// surface the path scatters at, as [`super::radiance_observed`] does.
pub(super) fn radiance(
    scene: &Scene,
    ray: &Ray,
    first: Option<Hit>,
    options: &PathOptions,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
    observe: &mut impl FnMut(&SurfaceHit, &Material),
) -> Vec3A {
    let media = scene.media();
    let mut medium = media.camera;
    let mut next_hit = first;
    let mut ray = *ray;
    let mut l = Vec3A::ZERO;
    let mut beta = Vec3A::ONE;
    let mut specular = true;
    let mut bsdf_pdf = 0.0f32;
    let mut from = ray.origin;
    let mut from_facing = Facing::Any;
    let mut depth = 0u32;
    let mut crossings = 0u32;
    let mut wavelength: Option<f32> = None;
    let textures = scene.textures();
    let lights_need_samples = scene.light_needs_samples();
    let hide = options.hide_emitters != HideEmitters::No;
    let mut observed = false;
    loop {
        let t_surface = next_hit.map_or(f32::INFINITY, |h| h.t);
        if let Some(m) = medium {
            let medium_here = &media.media[m as usize];
            if let Some(h) = medium_here.random_walk() {
                // Subsurface: a random walk to the surface the path leaves
                // by, shaded below as any hit.
                let Some(exit) = walk(scene, h, ray, next_hit, sampler, rays) else {
                    break;
                };
                beta *= exit.weight;
                ray = exit.ray;
                next_hit = Some(exit.hit);
                if exit.scattered {
                    // No light was sampled in the walk: what it finds
                    // counts in full.
                    specular = true;
                    from = ray.origin;
                    from_facing = Facing::Any;
                }
            } else {
                // Lights at points, sampled equiangularly along the stretch
                // in a homogeneous medium (weighed against the light sample
                // at the collision below).
                let segment = match medium_here {
                    Medium::Homogeneous(h)
                        if h.sample_emitters
                            && depth + 1 < options.max_depth
                            && h.sigma_s != Vec3A::ZERO
                            && !scene.positional_lights().is_empty() =>
                    {
                        h.span(&ray, t_surface)
                            .and_then(|(t0, t1)| Segment::new(scene, &ray, t0, t1))
                            .map(|s| (s, h))
                    }
                    _ => None,
                };
                if let Some((segment, h)) = &segment {
                    l += beta * equiangular_light(scene, segment, h, medium, sampler, rays);
                }
                let flight = medium_here.sample_flight(&ray, t_surface, &mut || sampler.next_1d());
                // Light the medium emits along the segment (found by paths
                // only: no light sample aims at it).
                let emitted = flight.emitted();
                if emitted != Vec3A::ZERO && depth < options.max_depth {
                    l += beta * emitted;
                }
                match flight {
                    Flight::Pass { weight, .. } => beta *= weight,
                    Flight::Scatter { t, weight, .. } => {
                        beta *= weight;
                        // The surfaces found after a scattering are not the
                        // camera ray's: the AOVs shade its hit themselves.
                        observed = true;
                        depth += 1;
                        if depth >= options.max_depth || beta == Vec3A::ZERO {
                            break;
                        }
                        crossings = 0;
                        let p = ray.origin + ray.dir * t;
                        let phase = medium_here.phase();
                        // Next-event estimation from the scattering point
                        // (unless the medium says not to: Mitsuba's
                        // `sample_emitters`, then emission found by the phase
                        // sample counts in full).
                        let sample_emitters = medium_here.sample_emitters();
                        let u_light = sampler.next_2d();
                        let u_choice = if lights_need_samples {
                            sampler.next_2d_minor()
                        } else {
                            glam::Vec2::ZERO
                        };
                        if sample_emitters
                            && let Some(light) =
                                scene.sample_light(p, Facing::Any, u_choice, u_light)
                        {
                            let (target, arriving, light_pdf) = light_terms(p, light);
                            if !arriving.is_zero() {
                                let wi = (target - p).normalize();
                                let f = phase.eval(ray.dir, wi);
                                let dist = (target - p).length();
                                let skip = dist * SHADOW_EPSILON;
                                let shadow = Ray::new(p, wi);
                                let tr = transmittance(
                                    scene,
                                    shadow,
                                    dist - skip,
                                    medium,
                                    sampler,
                                    rays,
                                );
                                if tr != Vec3A::ZERO {
                                    let weight = match (light, &segment) {
                                        // A light at a point: against the
                                        // equiangular strategy.
                                        (
                                            LightSample::Point {
                                                position, light, ..
                                            },
                                            Some((segment, h)),
                                        ) => power_heuristic(
                                            segment.flight_pdf(scene, h, light, t),
                                            segment.pdf(segment.pmf(scene, light), position, t),
                                        ),
                                        _ => light_pdf.map_or(1.0, |pdf| power_heuristic(pdf, f)),
                                    };
                                    l += beta * tr * arriving.value(scene) * (f * weight);
                                }
                            }
                        }
                        // Leave by the phase function (its weight is 1).
                        let (d, pdf) = phase.sample(ray.dir, sampler.next_2d());
                        specular = !sample_emitters;
                        bsdf_pdf = pdf;
                        from = p;
                        from_facing = Facing::Any;
                        ray = Ray::new(p, d);
                        if !roulette(&mut beta, depth, sampler) {
                            break;
                        }
                        *rays += 1;
                        next_hit = scene.intersect(&ray, f32::INFINITY);
                        continue;
                    }
                }
            }
            if beta == Vec3A::ZERO {
                break;
            }
        }
        let Some(hit) = next_hit else {
            if !(scene.environment().is_black() || (hide && depth == 0)) {
                let env = scene.environment_radiance(ray.dir);
                let weight = if specular {
                    1.0
                } else {
                    power_heuristic(bsdf_pdf, scene.environment_pdf(ray.dir, from, from_facing))
                };
                l += beta * env * weight;
            }
            break;
        };
        let surface = scene.surface(&hit);
        let material = &scene.materials()[surface.material as usize];
        let ng = surface.ng;
        let cos_out = -ng.dot(ray.dir);
        let interface = media.interface(surface.material);
        // Hidden emitters: the camera's segment passes them by.
        let skip_emitter = hide && depth == 0 && material.is_emissive();
        if !(hide && depth == 0)
            && let Some(le) = emission(scene, &surface, material, ray.dir, cos_out)
        {
            {
                let weight = if specular {
                    1.0
                } else {
                    // The light's pdf as seen from the last vertex (which
                    // index-matched crossings may lie between).
                    let h = Hit {
                        t: (surface.point.p - from).length(),
                        ..hit
                    };
                    power_heuristic(
                        bsdf_pdf,
                        scene.light_pdf_hit(&h, from, from_facing, cos_out),
                    )
                };
                l += beta * le * weight;
            }
        }
        if skip_emitter || material.is_null() {
            // Straight on without a vertex, into the medium beyond.
            crossings += 1;
            if crossings > MAX_CROSSINGS {
                break;
            }
            if interface.is_transition() {
                medium = interface.target(ng, ray.dir);
            }
            ray = Ray::new(surface.point.offset_origin(ray.dir), ray.dir);
            *rays += 1;
            next_hit = scene.intersect(&ray, f32::INFINITY);
            continue;
        }
        if material.is_unlit() {
            l += beta * material.unlit_color(&surface.attrs, textures);
            break;
        }
        let mut bsdf = material.bsdf(&surface.attrs, textures);
        // A lobe that passes straight through (Mitsuba's `thindielectric`)
        // is crossed without a bounce, so the path may go on through it at
        // the last depth.
        let straight = bsdf.passes_straight();
        if depth + 1 >= options.max_depth && !straight {
            break;
        }
        if !observed {
            observe(&surface, &bsdf);
            observed = true;
        }
        take_wavelength(&mut bsdf, &mut wavelength, &mut beta, sampler);
        let wo_world = -ray.dir;
        let (shading, frame, wo, facing) = vertex_frame(scene, &surface, &mut bsdf, wo_world);
        let sp = surface.point;
        let bsdf_at = bsdf.at(wo);
        let (light_sampled, u_light_pos, u_bsdf, u_choice) =
            vertex_numbers(&bsdf, lights_need_samples, sampler);
        if !straight {
            (from, from_facing) = (sp.p, facing);
        }
        if light_sampled
            && let Some(light) = scene.sample_light(sp.p, facing, u_choice, u_light_pos)
        {
            let (target, arriving, light_pdf) = light_terms(sp.p, light);
            if !arriving.is_zero() {
                let wi_world = (target - sp.p).normalize();
                let wi = frame.to_local(wi_world);
                let (f, pdf_here) = bsdf_at.eval_and_pdf(wi);
                let side = shading.weight(wi_world);
                if f != Vec3A::ZERO && side > 0.0 {
                    // The shadow ray starts in the medium on its side.
                    let start = if interface.is_transition() {
                        interface.target(ng, wi_world)
                    } else {
                        medium
                    };
                    let (shadow, t_max) = sp.ray_to(target);
                    let tr = transmittance(scene, shadow, t_max, start, sampler, rays);
                    if tr != Vec3A::ZERO {
                        let weight = light_pdf.map_or(1.0, |pdf| {
                            power_heuristic(pdf, pdf_here.unwrap_or_else(|| bsdf_at.pdf(wi)))
                        });
                        l += beta * f * side * tr * arriving.value(scene) * weight;
                    }
                }
            }
        }
        let Some(bs) = bsdf_at.sample(u_choice.y, u_bsdf) else {
            break;
        };
        let wi_world = frame.to_world(bs.wi);
        let side = shading.weight(wi_world);
        if side <= 0.0 {
            break;
        }
        beta *= bs.weight * side;
        if interface.is_transition() {
            medium = interface.target(ng, wi_world);
        }
        ray = Ray::new(sp.offset_origin(wi_world), wi_world);
        if straight && bs.wi == -wo {
            // Through, as across an index-matched boundary: no vertex.
            crossings += 1;
            if beta == Vec3A::ZERO || crossings > MAX_CROSSINGS {
                break;
            }
            *rays += 1;
            next_hit = scene.intersect(&ray, f32::INFINITY);
            continue;
        }
        if depth + 1 >= options.max_depth {
            break;
        }
        crossings = 0;
        specular = bs.specular;
        bsdf_pdf = bs.pdf;
        depth += 1;
        if beta == Vec3A::ZERO || !roulette(&mut beta, depth, sampler) {
            break;
        }
        *rays += 1;
        next_hit = scene.intersect(&ray, f32::INFINITY);
    }
    l
}

/// Light scattered towards the ray from the stretch `segment` of it in the
/// homogeneous medium `h` (index `medium`), by the equiangular strategy: a
/// light at a point chosen by the stretch, a point on it equiangularly
/// towards the light, weighed by the power heuristic against next-event
/// estimation at the flight's collision (which may have chosen the same
/// light at the same point).
fn equiangular_light(
    scene: &Scene,
    segment: &Segment,
    h: &Homogeneous,
    medium: Option<u32>,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
) -> Vec3A {
    let (u_choice, u_t) = (sampler.next_1d(), sampler.next_1d());
    let Some((light, pmf)) = segment.choose(scene, u_choice) else {
        return Vec3A::ZERO;
    };
    let (origin, dir) = (segment.origin, segment.dir);
    let Some((t, pdf_t)) =
        equiangular::sample(light.position, origin, dir, segment.t0, segment.t1, u_t)
    else {
        return Vec3A::ZERO;
    };
    let x = origin + dir * t;
    let Some((position, intensity)) = scene.point_light_towards(light.light, x) else {
        return Vec3A::ZERO;
    };
    let to_light = position - x;
    let dist2 = to_light.length_squared();
    let dist = dist2.sqrt();
    if dist.is_nan() || dist <= 0.0 {
        return Vec3A::ZERO;
    }
    let wi = to_light / dist;
    let f = h.phase.eval(dir, wi);
    let shadow = Ray::new(x, wi);
    let tr = transmittance(
        scene,
        shadow,
        dist - dist * SHADOW_EPSILON,
        medium,
        sampler,
        rays,
    );
    if tr == Vec3A::ZERO || f == 0.0 {
        return Vec3A::ZERO;
    }
    let pdf = pmf * pdf_t;
    let weight = power_heuristic(pdf, segment.flight_pdf(scene, h, light.light, t));
    let tr_camera = (-h.sigma_t * (t - segment.t0)).exp();
    tr_camera * h.sigma_s * tr * intensity * (f * weight / (pdf * dist2))
}

/// Russian roulette after `depth` bounces, as `path` plays it; false when
/// the path ends.
#[inline]
fn roulette(beta: &mut Vec3A, depth: u32, sampler: &mut impl PathSampler) -> bool {
    if depth < RR_DEPTH {
        return true;
    }
    let survive = (beta.max_element() * RR_SCALE).min(0.95);
    if sampler.next_1d() >= survive || survive.is_nan() {
        return false;
    }
    *beta /= survive;
    true
}

/// The fraction of light that travels along `ray` for `t_max` from a point
/// in `medium`: the product of the transmittances of the media it crosses
/// and of the surfaces it passes straight through (index-matched
/// boundaries, thin dielectric sheets: Mitsuba's `eval_null_transmission`),
/// which may change the medium; zero if any other surface lies in the way.
/// Counts the rays it casts; heterogeneous media draw their numbers from
/// `sampler`.
pub(super) fn transmittance(
    scene: &Scene,
    ray: Ray,
    t_max: f32,
    medium: Option<u32>,
    sampler: &mut impl PathSampler,
    rays: &mut u64,
) -> Vec3A {
    let media = scene.media();
    let end = ray.origin + ray.dir * t_max;
    let (mut ray, mut t_max, mut medium) = (ray, t_max, medium);
    let mut tr = Vec3A::ONE;
    for _ in 0..=MAX_CROSSINGS {
        *rays += 1;
        let hit = scene.intersect(&ray, t_max);
        // A surface that blocks shadow rays ends the walk before the
        // medium's transmittance is estimated or the hit is shaded.
        let material = hit.map(|h| &scene.materials()[scene.material_index(h.prim)]);
        if material.is_some_and(|m| !m.passes_shadow_rays()) {
            return Vec3A::ZERO;
        }
        if let Some(m) = medium {
            let t = hit.map_or(t_max, |h| h.t);
            tr *= media.media[m as usize].transmittance(&ray, t, &mut || sampler.next_1d());
        }
        let (Some(hit), Some(material)) = (hit, material) else {
            return tr;
        };
        if tr == Vec3A::ZERO {
            return tr;
        }
        let surface = scene.surface(&hit);
        match material.null_transmission(surface.ns.dot(ray.dir).abs()) {
            Some(t) if t != Vec3A::ZERO => tr *= t,
            _ => return Vec3A::ZERO,
        }
        let interface = media.interface(surface.material);
        if interface.is_transition() {
            medium = interface.target(surface.ng, ray.dir);
        }
        let origin = surface.point.offset_origin(ray.dir);
        t_max = (end - origin).dot(ray.dir);
        if t_max <= 0.0 {
            return tr;
        }
        ray = Ray::new(origin, ray.dir);
    }
    Vec3A::ZERO
}
