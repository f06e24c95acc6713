//! The scalar path tracer, one path at a time: the reference that
//! [`super::lanes`] equals bit for bit.

use glam::{Vec2, Vec3A};

use crate::geometry::ray::{Hit, Ray};
use crate::lights::environment::SkyRadiance;
use crate::materials::surface::{MaterialKind, SurfaceMaterial};
use crate::materials::{Frame, Material, spectrum};
use crate::sampling::sampler::Rng;
use crate::sampling::sobol;
use crate::scene::{Facing, LightSample, Scene, SurfaceHit};

/// Bounces after which Russian roulette may end a path.
pub const RR_DEPTH: u32 = 3;
/// Russian roulette keeps a path with probability `min(RR_SCALE · max(β), 0.95)`
/// (β the path throughput): only paths whose throughput has fallen below
/// `1/RR_SCALE` face it at all. Mitsuba's rule is `RR_SCALE = 1`; on the lab box 5
/// reaches a given relMSE in about a third less time (docs/path-tracing.md), and
/// the 0.95 cap still ends paths between perfect mirrors.
pub const RR_SCALE: f32 = 5.0;

/// Which sample points the path tracer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol' points ([`crate::sampling::sobol`]), a 2D pair per decision.
    Sobol,
    /// Independent uniform random numbers (PCG32 keyed by seed, pixel, sample).
    Independent,
}

impl SamplerKind {
    /// Every kind, for the command line.
    pub const ALL: [SamplerKind; 2] = [SamplerKind::Sobol, SamplerKind::Independent];

    /// The default, usable in constants.
    pub const DEFAULT: SamplerKind = SamplerKind::Sobol;

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        }
    }
}

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
    /// Whether the camera sees emitters (Mitsuba's `hide_emitters`).
    pub hide_emitters: HideEmitters,
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            max_depth: u32::MAX,
            sampler: SamplerKind::DEFAULT,
            filter: crate::sampling::filter::PixelFilter::Box,
            hide_emitters: HideEmitters::No,
        }
    }
}

/// A stream of sample values for one path (one pixel sample). The path tracer
/// asks for a 2D pair for the pixel position, then per bounce a pair for the
/// point on the light, a pair for the BSDF direction, a "minor" pair for the
/// choices of light and lobe (only when there is a choice), and one number for
/// Russian roulette (only where it may end the path); a path that meets a
/// dispersive surface (`KHR_materials_dispersion`) takes one more number there,
/// once, for its wavelength.
pub trait PathSampler {
    /// The next two values in `[0, 1)` for a decision that gains little from
    /// stratification (which light, which lobe).
    #[inline]
    fn next_2d_minor(&mut self) -> Vec2 {
        self.next_2d()
    }
    /// The next value in `[0, 1)`.
    fn next_1d(&mut self) -> f32;
    /// The next two values in `[0, 1)`.
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

impl PathSampler for Rng {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }
}

/// Pairs taken from Sobol' before [`SobolSampler`] goes on with independent
/// numbers: the pixel position and the first [`SOBOL_BOUNCES`] bounces' light
/// and BSDF pairs, where stratification pays.
pub const SOBOL_PAIRS: u32 = 1 + 2 * SOBOL_BOUNCES;
/// Bounces whose 2D decisions use Sobol' points. The first eight pairs cost the
/// same however many are used ([`sobol::first_pairs`]); on the lab box two
/// bounces give 3–4 % less relMSE than one at the same samples, three no more
/// than two (docs/path-tracing.md).
pub const SOBOL_BOUNCES: u32 = 2;

/// Owen-scrambled Sobol' pairs ([`crate::sampling::sobol`]) for the first
/// [`SOBOL_PAIRS`] 2D decisions, then independent numbers from the sample's own
/// PCG stream; single numbers (Russian roulette) and minor pairs (light and lobe
/// choices) are always independent.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    /// The first pairs, made together when the sampler is ([`sobol::first_pairs`]).
    xs: [f32; sobol::FIRST_PAIRS],
    ys: [f32; sobol::FIRST_PAIRS],
    rng: Rng,
    next_pair: u32,
}

const _: () = assert!(SOBOL_PAIRS as usize <= sobol::FIRST_PAIRS);

/// The Sobol' pair a thin lens takes its point from: the first after the
/// path's, made with them at no cost ([`sobol::first_pairs`]), so that the
/// lens is stratified as the pixel is and the path's own pairs stay as they
/// are with a pinhole.
pub const LENS_PAIR: usize = SOBOL_PAIRS as usize;
const _: () = assert!(LENS_PAIR < sobol::FIRST_PAIRS);

impl SobolSampler {
    /// The sampler of sample `index` of pixel `pixel` in a render seeded `seed`.
    #[inline]
    pub fn new(pixel: u64, index: u32, seed: u64) -> Self {
        let (xs, ys) = sobol::first_pairs(index, sobol::pixel_seed(pixel, seed));
        Self {
            xs,
            ys,
            rng: Rng::for_sample(seed, pixel, index),
            next_pair: 0,
        }
    }

    /// The point of the camera's thin lens (the Sobol' pair `LENS_PAIR`);
    /// the path's pairs are left as they are.
    #[inline]
    pub fn lens_2d(&self) -> Vec2 {
        Vec2::new(self.xs[LENS_PAIR], self.ys[LENS_PAIR])
    }
}

impl PathSampler for SobolSampler {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }
    #[inline]
    fn next_2d_minor(&mut self) -> Vec2 {
        Vec2::new(self.rng.next_f32(), self.rng.next_f32())
    }
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let k = self.next_pair as usize;
        if k < SOBOL_PAIRS as usize {
            self.next_pair += 1;
            Vec2::new(self.xs[k], self.ys[k])
        } else {
            Vec2::new(self.rng.next_f32(), self.rng.next_f32())
        }
    }
}

/// What a path did at one vertex, shown to a [`PathTracer`] (see
/// [`radiance_traced`]): enough to find where a NaN or infinity entered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathEvent {
    /// The surface found at the vertex: hit point, shading normal (after
    /// normal mapping), geometric normal and texture coordinates.
    Surface {
        /// Hit point.
        point: Vec3A,
        /// Shading normal.
        shading_normal: Vec3A,
        /// Geometric normal.
        geometric_normal: Vec3A,
        /// First texture coordinate set.
        uv: Vec2,
    },
    /// Emission seen at the vertex: its radiance and MIS weight.
    Emission {
        /// Emitted radiance.
        le: Vec3A,
        /// MIS weight.
        weight: f32,
    },
    /// The environment seen when the path escaped: its radiance and MIS weight.
    Environment {
        /// Environment radiance.
        radiance: Vec3A,
        /// MIS weight.
        weight: f32,
    },
    /// Next-event estimation: the BSDF value, incoming radiance over the
    /// light's pdf, and MIS weight.
    Light {
        /// BSDF value (times nothing: the cosine is inside the BSDF's eval).
        f: Vec3A,
        /// Incident radiance divided by the light sample's pdf.
        li: Vec3A,
        /// MIS weight.
        weight: f32,
    },
    /// The BSDF sample that continues the path: its weight `f·cos/pdf` and pdf.
    Bounce {
        /// Throughput factor of the sample.
        weight: Vec3A,
        /// Its pdf (solid angle; 0 for a delta lobe's convention).
        pdf: f32,
    },
}

/// Watches a path vertex by vertex; `()` watches nothing and costs nothing.
pub trait PathTracer {
    /// `event` happened at vertex `depth` (0: the camera ray's hit) with path
    /// throughput `beta` before it.
    fn event(&mut self, depth: u32, beta: Vec3A, event: PathEvent);
}

impl PathTracer for () {
    #[inline(always)]
    fn event(&mut self, _: u32, _: Vec3A, _: PathEvent) {}
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
        if material.is_emissive() && (cos_out > 0.0 || material.emits_both_sides) {
            let mut le = material.emitted(&surface.attrs, textures);
            if material.has_coat() {
                le *= material.coat_dimming(&surface.attrs, textures, surface.nc, ray.dir);
            }
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
        let shading = shading(scene, &surface, &bsdf, wo_world);
        let n = shading.n;
        let sp = surface.point;
        let frame = Frame::from_normal(n);
        bsdf.orient_coat(&frame, coat_normal(&surface, n));
        bsdf.orient_anisotropy(&frame, surface.tangent, surface.bitangent);
        let wo = frame.to_local(wo_world);
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

        // Which side of the surface light counts on, for choosing among
        // punctual lights by what they send here.
        let facing = if bsdf.transmits() {
            Facing::Both(n)
        } else if n.dot(wo_world) < 0.0 {
            Facing::Side(-n)
        } else {
            Facing::Side(n)
        };
        (from, from_facing) = (sp.p, facing);
        if light_sampled
            && let Some(light) = scene.sample_light(sp.p, facing, u_choice, u_light_pos)
        {
            let (target, arriving, light_pdf) = light_terms(sp.p, light);
            if !arriving.is_zero() {
                let wi_world = (target - sp.p).normalize();
                let wi = frame.to_local(wi_world);
                let (f, pdf_here) = bsdf_at.eval_and_pdf(wi);
                // With shading normals, which directions count (and how
                // much) is `shading`'s rule.
                let side = shading.weight(wi_world);
                if f != Vec3A::ZERO && side > 0.0 {
                    let f = f * side;
                    let (shadow, t_max) = sp.ray_to(target);
                    *rays += 1;
                    if !scene.occluded(&shadow, t_max) {
                        let li = arriving.value(scene);
                        let weight = light_pdf.map_or(1.0, |pdf| {
                            power_heuristic(pdf, pdf_here.unwrap_or_else(|| bsdf_at.pdf(wi)))
                        });
                        tracer.event(depth, beta, PathEvent::Light { f, li, weight });
                        l += beta * f * li * weight;
                    }
                }
            }
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

/// The incident radiance over its pdf that a light sample brings
/// ([`light_terms`]), or, for the environment, what it will be once its
/// texels are read, which [`Arriving::value`] does after the shadow ray (the
/// read is a cache miss that the trace hides, or that a blocked ray saves).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Arriving {
    /// The value itself.
    Value(Vec3A),
    /// The environment's radiance in a sampled direction, over `pdf`.
    Sky { radiance: SkyRadiance, pdf: f32 },
}

impl Arriving {
    /// Whether it is known to be zero (nothing to trace a shadow ray for).
    #[inline(always)]
    pub(crate) fn is_zero(&self) -> bool {
        matches!(self, Arriving::Value(v) if *v == Vec3A::ZERO)
    }

    /// The incident radiance over the sample's pdf.
    #[inline(always)]
    pub(crate) fn value(self, scene: &Scene) -> Vec3A {
        match self {
            Arriving::Value(v) => v,
            Arriving::Sky { radiance, pdf } => scene.environment().radiance_of(radiance) / pdf,
        }
    }
}

/// What next-event estimation needs of a light sample for the point `p`: the
/// point the shadow ray goes to, the incident radiance over the sample's pdf
/// (zero where an area light faces away; the environment's read later:
/// [`Arriving`]), and that pdf for MIS (`None` for punctual lights, which
/// BSDF sampling cannot find).
#[inline(always)]
pub(crate) fn light_terms(p: Vec3A, light: LightSample) -> (Vec3A, Arriving, Option<f32>) {
    match light {
        LightSample::Point {
            position,
            intensity,
        } => {
            let r2 = (position - p).length_squared();
            (position, Arriving::Value(intensity / r2), None)
        }
        LightSample::Directional {
            to_light,
            irradiance,
            distance,
        } => (p + to_light * distance, Arriving::Value(irradiance), None),
        LightSample::Environment {
            to_light,
            radiance,
            pdf,
            distance,
        } => (
            p + to_light * distance,
            Arriving::Sky { radiance, pdf },
            Some(pdf),
        ),
        LightSample::Area {
            position,
            normal,
            radiance,
            two_sided,
            pdf_area,
        } => {
            let d = position - p;
            let r2 = d.length_squared();
            let mut cos_l = -normal.dot(d) / r2.sqrt();
            if two_sided {
                cos_l = cos_l.abs();
            }
            if cos_l > 0.0 {
                let pdf = pdf_area * r2 / cos_l;
                (position, Arriving::Value(radiance / pdf), Some(pdf))
            } else {
                (position, Arriving::Value(Vec3A::ZERO), None)
            }
        }
    }
}

/// The shading frame's normal at a hit and the rule by which directions
/// meet it ([`shading`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shading {
    /// The normal of the shading frame.
    pub n: Vec3A,
    rule: SideRule,
}

/// How a direction of light meets the shading normal.
#[derive(Clone, Copy, Debug)]
enum SideRule {
    /// No shading normal: every direction counts.
    None,
    /// raylab's: a direction must be on the same side of the geometric
    /// surface (`ng` taken on the shading normal's side) as of the shading
    /// one, or light would leak through it.
    SameSide(Vec3A),
    /// Mitsuba's `normalmap` and `bumpmap`: a direction must be on the same
    /// side of the interpolated normal (`ni`, on the side the BSDF was
    /// turned to) as of the perturbed one, and, where `alpha2 ≥ 0`, the BSDF
    /// is weighed by the shadowing term of the bump terminator (Estevez et
    /// al. 2019, "A Microfacet-Based Shadowing Function to Solve the Bump
    /// Terminator Problem") `2 / (1 + √(1 + α² tan²θ))`, `θ` the
    /// direction's angle to `ni` and `α² = min(tan²θₙ / 8, 1)`, `θₙ` the
    /// perturbed normal's.
    Perturbed { ni: Vec3A, alpha2: f32 },
}

impl Shading {
    /// What a BSDF value or sample towards the light direction `w` (world,
    /// away from the surface) is multiplied by: 0 where the rule rejects it,
    /// else 1 (or Mitsuba's shadowing term).
    #[inline(always)]
    pub fn weight(&self, w: Vec3A) -> f32 {
        match self.rule {
            SideRule::None => 1.0,
            SideRule::SameSide(ng) => {
                if (w.dot(ng) > 0.0) == (w.dot(self.n) > 0.0) {
                    1.0
                } else {
                    0.0
                }
            }
            SideRule::Perturbed { ni, alpha2 } => {
                let c = w.dot(ni);
                if c * w.dot(self.n) > 0.0 {
                    if alpha2 >= 0.0 {
                        2.0 / (1.0 + (1.0 + alpha2 * tan_theta_2(c)).sqrt())
                    } else {
                        1.0
                    }
                } else {
                    0.0
                }
            }
        }
    }
}

/// `tan²θ` of a direction whose cosine to the normal is `c` (Mitsuba's
/// `Frame::tan_theta_2`).
#[inline]
fn tan_theta_2(c: f32) -> f32 {
    (1.0 - c * c).max(0.0) / (c * c)
}

/// The shading frame's normal at `surface` for the BSDF `bsdf` seen from
/// `wo` (pointing away from the surface), and the rule for directions of
/// light. raylab's materials: the shading normal made consistent with `wo`
/// ([`consistent_normal`]), on the front side; two-sided BSDFs (glass,
/// glTF) take the front normal and tell the sides apart themselves,
/// one-sided ones face `wo` in two-sided scenes and reflect nothing from
/// behind in the lab box. Mitsuba's materials (which have their own sides)
/// follow Mitsuba's rules instead: [`mitsuba_shading`].
#[inline(always)]
pub(crate) fn shading(scene: &Scene, surface: &SurfaceHit, bsdf: &Material, wo: Vec3A) -> Shading {
    let material = &scene.materials()[surface.material as usize];
    if material.has_own_sides() {
        return mitsuba_shading(material, surface, bsdf, wo);
    }
    let ng = surface.ng;
    let mut n = if surface.ns != ng {
        consistent_normal(surface.ns, ng, wo)
    } else {
        ng
    };
    if scene.material_turns(surface.material) && !two_sided(bsdf) && ng.dot(wo) < 0.0 {
        n = -n;
    }
    let rule = if surface.ns != ng {
        SideRule::SameSide(if n.dot(ng) < 0.0 { -ng } else { ng })
    } else {
        SideRule::None
    };
    Shading { n, rule }
}

/// [`shading`] of a Mitsuba material, as Mitsuba 3.7.1 shades: the
/// interpolated (or normal- or bump-mapped) normal as it is, no check
/// against the geometric normal; `twosided` turns the frame where the
/// viewer is behind the interpolated normal (Mitsuba mirrors the
/// directions through the shading frame's tangent plane: the same as
/// negating the interpolated normal and mirroring the perturbed one); a
/// normal or bump map's normal has its tangential part negated where the
/// viewer is on different sides of it and of the interpolated normal
/// (`flip_invalid_normals`), and directions of light meet it by
/// [`SideRule::Perturbed`].
#[inline(never)]
fn mitsuba_shading(
    material: &SurfaceMaterial,
    surface: &SurfaceHit,
    bsdf: &Material,
    wo: Vec3A,
) -> Shading {
    let perturb = match &material.kind {
        MaterialKind::Textured(t) => t.perturb.as_ref(),
        _ => None,
    };
    let (mut ni, mut n) = (surface.ni, surface.ns);
    if material.two_sided() && !two_sided(bsdf) && ni.dot(wo) < 0.0 {
        n -= 2.0 * ni.dot(n) * ni;
        ni = -ni;
    }
    let Some(perturb) = perturb else {
        return Shading {
            n,
            rule: SideRule::None,
        };
    };
    if perturb.flip_invalid && ni.dot(wo) * n.dot(wo) <= 0.0 {
        n = 2.0 * ni.dot(n) * ni - n;
    }
    let alpha2 = if perturb.shadowing {
        (0.125 * tan_theta_2(ni.dot(n))).min(1.0)
    } else {
        -1.0
    };
    Shading {
        n,
        rule: SideRule::Perturbed { ni, alpha2 },
    }
}

/// The clear coat's normal on the side of the shading normal `n` (which
/// [`shading`] may have turned to the back).
#[inline]
pub(crate) fn coat_normal(surface: &SurfaceHit, n: Vec3A) -> Vec3A {
    if n.dot(surface.ns) < 0.0 {
        -surface.nc
    } else {
        surface.nc
    }
}

/// The shading normal `ns` (on the front side, like `ng`) adjusted so that the
/// mirror reflection of `wo` about it stays above the geometric surface
/// (Keller et al. 2017, "Towards Consistent Normal Mapping"): interpolated and
/// normal-mapped normals can tilt so far that `wo` falls below the shading
/// horizon or its reflection below the surface, which would turn the surface
/// black or leak light. If so, the reflection is moved just above the
/// geometric horizon and the shading normal becomes the half vector between
/// `wo` and it.
#[inline]
pub fn consistent_normal(ns: Vec3A, ng: Vec3A, wo: Vec3A) -> Vec3A {
    /// How far above the geometric horizon the corrected reflection lies (a cosine).
    const MARGIN: f32 = 0.01;
    let flip = wo.dot(ng) < 0.0;
    let (ng_side, ns_side) = if flip { (-ng, -ns) } else { (ng, ns) };
    let r = 2.0 * wo.dot(ns_side) * ns_side - wo;
    let d = r.dot(ng_side);
    if d >= MARGIN {
        return ns;
    }
    let tangent = (r - ng_side * d).normalize_or_zero();
    let h = (wo + tangent * (1.0 - MARGIN * MARGIN).sqrt() + ng_side * MARGIN).normalize_or_zero();
    if tangent == Vec3A::ZERO || h == Vec3A::ZERO {
        return ng;
    }
    if flip { -h } else { h }
}

/// The power heuristic (β = 2) weight of a strategy with density `a` against one
/// with density `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// Whether a BSDF tells the two sides of a surface apart itself (glass,
/// Mitsuba's dielectrics and principled BSDFs that transmit, a blend with
/// such a part, the glTF material, whose transmission refracts into the
/// inside); the others are one-sided and face the side their normal points
/// to.
#[inline]
fn two_sided(material: &Material) -> bool {
    matches!(
        material,
        Material::Dielectric { .. }
            | Material::Pbr(_)
            | Material::MiDielectric(_)
            | Material::MiThinDielectric(_)
            | Material::MiRoughDielectric(_)
            | Material::MiPrincipledThin(_)
    ) || matches!(material, Material::MiPrincipled(p) if p.transmits())
        || matches!(material, Material::MiBlend(b)
            if b.parts.iter().any(|&p| two_sided(&Material::from(p))))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba's rule for a perturbed normal: a direction on different sides
    /// of the interpolated and the perturbed normal counts for nothing; one
    /// along the interpolated normal is not shadowed; a grazing one under a
    /// tilted normal is, by Estevez et al.'s term (here the perturbed
    /// normal at 45°: α² = 1/8, and a direction at 60° from `ni`:
    /// tan²θ = 3, so 2 / (1 + √(1 + 3/8))).
    #[test]
    fn perturbed_normals_weigh_directions_as_mitsuba() {
        let ni = Vec3A::Z;
        let n = Vec3A::new(1.0, 0.0, 1.0).normalize();
        let alpha2 = (0.125 * tan_theta_2(ni.dot(n))).min(1.0);
        assert!((alpha2 - 0.125).abs() < 1e-6);
        let shading = Shading {
            n,
            rule: SideRule::Perturbed { ni, alpha2 },
        };
        assert_eq!(shading.weight(Vec3A::Z), 1.0);
        // Above ni, below n.
        assert_eq!(shading.weight(Vec3A::new(-1.0, 0.0, 0.5).normalize()), 0.0);
        let w = Vec3A::new(3f32.sqrt() / 2.0, 0.0, 0.5);
        let expect = 2.0 / (1.0 + (1.0f32 + 3.0 / 8.0).sqrt());
        assert!(
            (shading.weight(w) - expect).abs() < 1e-5,
            "{}",
            shading.weight(w)
        );
        // Without the shadowing term only the sides count.
        let plain = Shading {
            n,
            rule: SideRule::Perturbed { ni, alpha2: -1.0 },
        };
        assert_eq!(plain.weight(w), 1.0);
        // raylab's rule: the same side of the geometric and shading normal.
        let raylab = Shading {
            n,
            rule: SideRule::SameSide(ni),
        };
        assert_eq!(raylab.weight(w), 1.0);
        assert_eq!(raylab.weight(Vec3A::new(-1.0, 0.0, 0.5).normalize()), 0.0);
    }
}
