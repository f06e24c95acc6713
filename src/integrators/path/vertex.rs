//! What the path tracer does at one vertex, shared by its integrators
//! (`scalar`'s path, `direct`'s counted samples, `lanes`): the shading
//! frame and the rule by which light meets it ([`shading`]), next-event
//! estimation ([`next_event`]), the power heuristic, and the events a
//! [`PathTracer`] watches.

use glam::{Vec2, Vec3A};

use super::samples::PathSampler;
use crate::geometry::ray::SurfacePoint;
use crate::lights::environment::SkyRadiance;
use crate::materials::surface::{MaterialKind, SurfaceMaterial};
use crate::materials::{BsdfAt, Frame, Material};
use crate::scene::{Facing, LightSample, Scene, SurfaceHit};

/// What a path did at one vertex, shown to a [`PathTracer`] (see
/// [`super::radiance_traced`]): enough to find where a NaN or infinity entered.
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

/// A vertex made ready to shade: its [`Shading`] for `bsdf` seen from
/// `wo_world` (away from the surface), the shading frame (the BSDF's coat
/// and anisotropy turned into it), `wo` in that frame, and the side light
/// counts on, for choosing lights by what they send here.
#[inline(always)]
pub(crate) fn vertex_frame(
    scene: &Scene,
    surface: &SurfaceHit,
    bsdf: &mut Material,
    wo_world: Vec3A,
) -> (Shading, Frame, Vec3A, Facing) {
    let shading = shading(scene, surface, bsdf, wo_world);
    let n = shading.n;
    let frame = Frame::from_normal(n);
    bsdf.orient_coat(&frame, coat_normal(surface, n));
    bsdf.orient_anisotropy(&frame, surface.tangent, surface.bitangent);
    let facing = if bsdf.transmits() {
        Facing::Both(n)
    } else if n.dot(wo_world) < 0.0 {
        Facing::Side(-n)
    } else {
        Facing::Side(n)
    };
    (shading, frame, frame.to_local(wo_world), facing)
}

/// `KHR_materials_dispersion`: the first dispersive surface a path meets
/// draws the path's wavelength (from the path's own stream, so that images
/// stay the same on any number of threads) and weighs the throughput `beta`
/// by that wavelength's RGB response, white in expectation; from there on
/// every dispersive surface takes its index at that wavelength, for its
/// light sample and its BSDF sample alike. A path that meets none draws
/// nothing and stays RGB.
#[inline(always)]
pub(crate) fn take_wavelength(
    bsdf: &mut Material,
    wavelength: &mut Option<f32>,
    beta: &mut Vec3A,
    sampler: &mut impl PathSampler,
) {
    if bsdf.dispersive() {
        let lambda = *wavelength.get_or_insert_with(|| {
            let (lambda, w) = crate::materials::spectrum::sample_weighted(sampler.next_1d());
            *beta *= w;
            lambda
        });
        bsdf.set_wavelength(lambda);
    }
}

/// The numbers a surface vertex draws, in the order every path tracer
/// draws them: whether it samples a light (only off non-delta lobes: a
/// delta lobe has nothing to gain from it), the light's point, the BSDF's
/// pair, and one minor pair for both choices (`x` picks the light, `y`
/// settles the light table's coin and picks the lobe), drawn only where
/// used. (Choices and the roulette's number are drawn only where they are
/// used: each independent number costs about a dozen instructions, and a
/// vertex of the lab box, one point light and diffuse walls, has no choice
/// to make. Skipping the point on the light too, which the key light does
/// not need, saved 1 % on the box but cost 0.5 % a ray on `cornell-area`.)
#[inline(always)]
pub(crate) fn vertex_numbers(
    bsdf: &Material,
    lights_need_samples: bool,
    sampler: &mut impl PathSampler,
) -> (bool, Vec2, Vec2, Vec2) {
    let light_sampled = !bsdf.is_specular();
    let u_light_pos = sampler.next_2d();
    let u_bsdf = sampler.next_2d();
    let u_choice = if (light_sampled && lights_need_samples) || bsdf.chooses_lobe() {
        sampler.next_2d_minor()
    } else {
        Vec2::ZERO
    };
    (light_sampled, u_light_pos, u_bsdf, u_choice)
}

/// What the surface `surface` (of `material`, met by a ray along `dir`
/// whose cosine with its geometric normal is `-cos_out`) emits towards the
/// ray's origin (a clear coat dimming it); `None` unless it emits on that
/// side.
#[inline(always)]
pub(crate) fn emission(
    scene: &Scene,
    surface: &SurfaceHit,
    material: &SurfaceMaterial,
    dir: Vec3A,
    cos_out: f32,
) -> Option<Vec3A> {
    if !(material.is_emissive() && (cos_out > 0.0 || material.emits_both_sides)) {
        return None;
    }
    let textures = scene.textures();
    let mut le = material.emitted(&surface.attrs, textures);
    if material.has_coat() {
        le *= material.coat_dimming(&surface.attrs, textures, surface.nc, dir);
    }
    Some(le)
}

/// How next-event estimation weighs a light sample: the power heuristic of
/// its density times `light` against the BSDF's times `bsdf`, times
/// `share`; a punctual light (which BSDF sampling cannot find) gets `share`
/// alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NeeWeights {
    /// What the light sample's density is scaled by (its strategy's share of
    /// the samples).
    pub light: f32,
    /// What the BSDF's density is scaled by.
    pub bsdf: f32,
    /// What the weight is multiplied by (one over the light samples taken).
    pub share: f32,
}

impl NeeWeights {
    /// The path tracer's: one light sample against one BSDF sample (exact:
    /// a product with 1 changes no bit).
    pub const PATH: Self = Self {
        light: 1.0,
        bsdf: 1.0,
        share: 1.0,
    };
}

/// Next-event estimation at the surface point `sp` (shading frame `frame`,
/// rule `shading`, BSDF `bsdf_at`) with the light sample `light`: the BSDF
/// value, the incident radiance over the sample's pdf and the MIS weight,
/// when the light arrives (a shadow ray, counted in `rays`, found nothing
/// in the way); `None` when it sends nothing.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn next_event(
    scene: &Scene,
    sp: &SurfacePoint,
    frame: &Frame,
    shading: &Shading,
    bsdf_at: &BsdfAt<'_>,
    light: LightSample,
    mis: NeeWeights,
    rays: &mut u64,
) -> Option<(Vec3A, Vec3A, f32)> {
    let (target, arriving, light_pdf) = light_terms(sp.p, light);
    if arriving.is_zero() {
        return None;
    }
    let wi_world = (target - sp.p).normalize();
    let wi = frame.to_local(wi_world);
    let (f, pdf_here) = bsdf_at.eval_and_pdf(wi);
    // With shading normals, which directions count (and how much) is
    // `shading`'s rule.
    let side = shading.weight(wi_world);
    if f == Vec3A::ZERO || side.is_nan() || side <= 0.0 {
        return None;
    }
    let f = f * side;
    let (shadow, t_max) = sp.ray_to(target);
    *rays += 1;
    if scene.occluded(&shadow, t_max) {
        return None;
    }
    let li = arriving.value(scene);
    let weight = light_pdf.map_or(mis.share, |pdf| {
        let pdf_bsdf = pdf_here.unwrap_or_else(|| bsdf_at.pdf(wi));
        power_heuristic(pdf * mis.light, pdf_bsdf * mis.bsdf) * mis.share
    });
    Some((f, li, weight))
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
            ..
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
