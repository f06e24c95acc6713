//! The scalar path tracer, one path at a time: the reference that
//! [`super::lanes`] equals bit for bit.

use glam::{Vec2, Vec3A};

use super::direct::{DirectSamples, direct_counted};
use super::samples::{PathSampler, SamplerKind};
use super::vertex::{
    NeeWeights, PathEvent, PathTracer, emission, next_event, power_heuristic, vertex_frame,
};
use crate::geometry::ray::{Hit, Ray};
use crate::materials::{Material, spectrum};
use crate::scene::{Facing, Scene, SurfaceHit};

/// Bounces after which Russian roulette may end a path.
pub const RR_DEPTH: u32 = 3;
/// Russian roulette keeps a path with probability `min(RR_SCALE · max(β), 0.95)`
/// (β the path throughput): only paths whose throughput has fallen below
/// `1/RR_SCALE` face it at all. Mitsuba's rule is `RR_SCALE = 1`; on the lab box 5
/// reaches a given relMSE in about a third less time (docs/path-tracing.md), and
/// the 0.95 cap still ends paths between perfect mirrors.
pub const RR_SCALE: f32 = 5.0;

/// Whether the camera sees emitters: Mitsuba's `hide_emitters`, as its
/// `path` and `direct` integrators (3.7.1) define it. Hidden, the camera
/// ray passes through every emitting surface it meets first (as through
/// glass without refraction) and an environment it escapes to is black; a
/// path's value then counts only once the path has met a surface that
/// Mitsuba counts as the path's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HideEmitters {
    /// Emitters are seen (raylab's own integrators, Mitsuba's default).
    #[default]
    No,
    /// Mitsuba's `path`: a path counts once it scatters off a surface other
    /// than a `null` one (raylab's dielectric of index 1,
    /// [`crate::materials::Material::is_null`]); seen only through `null`
    /// surfaces, light and sky are black.
    Path,
    /// Mitsuba's `direct`: a path counts once the camera ray (past the
    /// emitters) hits any surface; what a `null` surface lets through
    /// stays seen.
    Direct,
}

/// Options of the `path` integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PathOptions {
    /// Longest path in segments, as in Mitsuba: 1 sees only emitters, 2 adds
    /// direct light, ...; `u32::MAX` leaves it to Russian roulette.
    pub max_depth: u32,
    /// Sample points.
    pub sampler: SamplerKind,
    /// How each pixel weighs the image around it (its samples' image points
    /// are drawn from it; the box by default).
    pub filter: crate::sampling::filter::PixelFilter,
    /// Whether samples are drawn from the filter or splatted through it.
    pub reconstruction: crate::sampling::filter::Reconstruction,
    /// Whether the camera sees emitters (Mitsuba's `hide_emitters`).
    pub hide_emitters: HideEmitters,
    /// The light and BSDF samples a path of depth 2 takes at its one
    /// vertex (Mitsuba's `direct`); other depths take one of each.
    pub direct: DirectSamples,
}

impl PathOptions {
    /// Whether paths are Mitsuba's `direct` with other counts than one light
    /// and one BSDF sample ([`PathOptions::direct`] at depth 2), which the
    /// eight-lane path tracer does not render.
    #[inline]
    pub fn counts_direct(&self) -> bool {
        self.max_depth == 2 && self.direct != DirectSamples::ONE_EACH
    }
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            max_depth: u32::MAX,
            sampler: SamplerKind::DEFAULT,
            filter: crate::sampling::filter::PixelFilter::Box,
            reconstruction: crate::sampling::filter::Reconstruction::Sample,
            hide_emitters: HideEmitters::No,
            direct: DirectSamples::ONE_EACH,
        }
    }
}

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
        // `KHR_materials_dispersion`: the first dispersive surface a path
        // meets draws the path's wavelength (from the path's own stream, so
        // that images stay the same on any number of threads) and weighs the
        // throughput by that wavelength's RGB response, white in expectation;
        // from there on every dispersive surface takes its index at that
        // wavelength, for its light sample and its BSDF sample alike. A path
        // that meets none draws nothing and stays RGB.
        if bsdf.dispersive() {
            let lambda = *wavelength.get_or_insert_with(|| {
                let (lambda, w) = spectrum::sample_weighted(sampler.next_1d());
                beta *= w;
                lambda
            });
            bsdf.set_wavelength(lambda);
        }
        let wo_world = -ray.dir;
        let (shading, frame, wo, facing) = vertex_frame(scene, &surface, &mut bsdf, wo_world);
        let sp = surface.point;
        let bsdf_at = bsdf.at(wo);

        // Choices and the roulette's number are drawn only where they are
        // used: each independent number costs about a dozen instructions, and
        // a vertex of the lab box (one point light, diffuse walls) has no
        // choice to make. (Skipping the point on the light too, which the key
        // light does not need, saved 1 % on the box but cost 0.5 % a ray on
        // `cornell-area`.)
        // Next-event estimation only off non-delta lobes (a delta lobe has
        // nothing to gain from it).
        let light_sampled = !bsdf.is_specular();
        let u_light_pos = sampler.next_2d();
        let u_bsdf = sampler.next_2d();
        // One pair for both choices: `x` picks the light, `y` settles the
        // light table's coin and picks the lobe.
        let u_choice = if (light_sampled && lights_need_samples) || bsdf.chooses_lobe() {
            sampler.next_2d_minor()
        } else {
            Vec2::ZERO
        };
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
