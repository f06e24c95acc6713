//! A surface's scattering model, [`Material`]: the lab's diffuse, mirror,
//! glass and rough conductor, the glTF BSDF and Mitsuba 3's BSDFs
//! ([`mitsuba`]), with their evaluation,
//! density and sampling, and [`BsdfAt`], a material seen from one direction.
//! The frame, side and estimator conventions are the module's
//! ([`crate::materials`]).

use super::blend::{Blend, BlendPart};
use super::bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes, finite_or_zero};
use super::dielectric::{dielectric_interface, dielectric_refraction, sample_dielectric};
use super::disk::concentric_disk;
use super::frame::{Frame, above, reflect_z};
use super::fresnel::fresnel_conductor;
use super::microfacet::{
    MicrofacetDistribution, ggx_d, ggx_lambda, ggx_sample_visible_normal, is_smooth,
};
use super::mitsuba;
use super::pbr::{self, PbrBsdf};
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// A surface's scattering model. See [the module documentation](super) for the frame,
/// side and estimator conventions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflection, `f = ρ / π`.
    Diffuse {
        /// Reflectance ρ per RGB channel, in `[0, 1]`.
        reflectance: Vec3A,
    },
    /// Perfect specular reflection scaled by a constant reflectance.
    Mirror {
        /// Reflectance per RGB channel, in `[0, 1]`.
        reflectance: Vec3A,
    },
    /// A smooth interface between air (index 1, on the `+z` side) and a dielectric
    /// of index `ior` (on the `-z` side): exact unpolarised Fresnel reflection and
    /// Snell refraction, from both sides, with total internal reflection.
    Dielectric {
        /// Index of refraction of the inside (`> 0`; 1 makes the surface invisible).
        ior: f32,
    },
    /// A rough metal: GGX microfacets, height-correlated Smith masking, exact
    /// conductor Fresnel. `alpha < ALPHA_SMOOTH` is a smooth (delta) conductor.
    RoughConductor {
        /// GGX width α: the microfacet slope at which the slope distribution
        /// falls to a quarter of its peak (glTF/Disney `roughness²`); 0.1 is
        /// glossy, 1 is very rough.
        alpha: f32,
        /// Real part of the complex index of refraction, per RGB channel.
        eta: Vec3A,
        /// Imaginary part (extinction coefficient), per RGB channel; `+∞` in a
        /// channel makes that channel a perfect conductor (Fresnel exactly 1).
        k: Vec3A,
    },
    /// The glTF 2.0 metallic–roughness BSDF (with the specular, ior, transmission
    /// and volume extensions); see [`pbr`]. Two-sided: never flip its normal.
    Pbr(PbrBsdf),
    /// Mitsuba 3's `conductor` (smooth, one-sided); see [`mitsuba`].
    MiConductor(mitsuba::Conductor),
    /// Mitsuba 3's `roughconductor` (one-sided).
    MiRoughConductor(mitsuba::RoughConductor),
    /// Mitsuba 3's `dielectric` (smooth interface, two-sided: never flip
    /// its normal).
    MiDielectric(mitsuba::SmoothDielectric),
    /// Mitsuba 3's `thindielectric` (two-sided).
    MiThinDielectric(mitsuba::ThinDielectric),
    /// Mitsuba 3's `roughdielectric` (rough interface, two-sided).
    MiRoughDielectric(mitsuba::RoughDielectric),
    /// Mitsuba 3's `plastic` (smooth coating on a diffuse base, one-sided).
    MiPlastic(mitsuba::Plastic),
    /// Mitsuba 3's `roughplastic` (one-sided).
    MiRoughPlastic(mitsuba::RoughPlastic),
    /// Mitsuba 3's `principled` (Burley's Disney BSDF): one-sided without
    /// transmission, an interface (`+z` outside: never flip its normal)
    /// with it.
    MiPrincipled(mitsuba::Principled),
    /// Mitsuba 3's `principledthin` (a thin sheet, the same from both
    /// sides).
    MiPrincipledThin(mitsuba::PrincipledThin),
    /// Mitsuba 3's `blendbsdf`: a mixture of two of its BSDFs (see
    /// `materials::blend`); its sides are its parts'.
    MiBlend(Blend),
}

impl From<BlendPart> for Material {
    /// The part as the material it is on its own.
    #[inline]
    fn from(part: BlendPart) -> Material {
        match part {
            BlendPart::Diffuse(reflectance) => Material::Diffuse { reflectance },
            BlendPart::Conductor(c) => Material::MiConductor(c),
            BlendPart::RoughConductor(c) => Material::MiRoughConductor(c),
            BlendPart::Dielectric(d) => Material::MiDielectric(d),
            BlendPart::ThinDielectric(d) => Material::MiThinDielectric(d),
            BlendPart::RoughDielectric(d) => Material::MiRoughDielectric(d),
            BlendPart::Plastic(p) => Material::MiPlastic(p),
            BlendPart::RoughPlastic(p) => Material::MiRoughPlastic(p),
            BlendPart::Principled(p) => Material::MiPrincipled(p),
            BlendPart::PrincipledThin(p) => Material::MiPrincipledThin(p),
        }
    }
}

/// A material seen from one direction `wo` ([`Material::at`]): its
/// evaluations and samples equal [`Material::eval`], [`Material::pdf`] and
/// [`Material::sample`] at that `wo` bit for bit; the glTF BSDF's lobe
/// probabilities ([`pbr::Local`]) are worked out once for all of them.
#[derive(Clone, Copy, Debug)]
pub enum BsdfAt<'a> {
    /// The glTF BSDF with `PbrBsdf::local(wo)`.
    Pbr {
        /// The BSDF.
        bsdf: &'a PbrBsdf,
        /// The outgoing direction (local).
        wo: Vec3A,
        /// Its lobe probabilities (`None`: it scatters nothing).
        local: Option<pbr::Local>,
    },
    /// Any other material, which has nothing to work out ahead.
    Other {
        /// The material.
        material: &'a Material,
        /// The outgoing direction (local).
        wo: Vec3A,
    },
}

impl BsdfAt<'_> {
    /// [`Material::eval`] towards `wi`, and [`Material::pdf`] where it comes
    /// almost free with it (the glTF BSDF shares its half vector between the
    /// two; `None` elsewhere, where the pdf costs no more on its own and is
    /// only worth computing once a shadow ray has found the light).
    #[inline]
    pub fn eval_and_pdf(&self, wi: Vec3A) -> (Vec3A, Option<f32>) {
        match *self {
            BsdfAt::Pbr { bsdf, wo, local } => {
                let (f, pdf) = bsdf.eval_pdf_at(local.as_ref(), wo, wi);
                (f, Some(pdf))
            }
            BsdfAt::Other { material, wo } => (material.eval(wo, wi), None),
        }
    }

    /// [`Material::pdf`] towards `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3A) -> f32 {
        match *self {
            BsdfAt::Pbr { bsdf, wo, .. } => bsdf.pdf(wo, wi),
            BsdfAt::Other { material, wo } => material.pdf(wo, wi),
        }
    }

    /// [`Material::sample`].
    #[inline(always)]
    pub fn sample(&self, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match *self {
            BsdfAt::Pbr { bsdf, local, .. } => bsdf.sample_at(local, u_lobe, u),
            BsdfAt::Other { material, wo } => material.sample(wo, u_lobe, u),
        }
    }
}

impl Material {
    /// Gives a clear coat (of [`Material::Pbr`]) its normal `n_c` in the
    /// shading frame `frame`; nothing for other materials or without a coat.
    #[inline]
    pub fn orient_coat(&mut self, frame: &Frame, n_c: Vec3A) {
        if let Material::Pbr(p) = self {
            p.orient_coat(frame, n_c);
        }
    }

    /// Whether the material disperses light (a [`Material::Pbr`] that is
    /// [`PbrBsdf::dispersive`]): a path that meets it is carried at one
    /// wavelength from there on.
    #[inline]
    pub fn dispersive(&self) -> bool {
        matches!(self, Material::Pbr(p) if p.dispersive())
    }

    /// The material at wavelength `lambda` (nm) ([`PbrBsdf::at_wavelength`]):
    /// a dispersive glTF material takes the index of refraction there; every
    /// other material is unchanged.
    #[inline]
    pub fn set_wavelength(&mut self, lambda: f32) {
        if let Material::Pbr(p) = self {
            *p = p.at_wavelength(lambda);
        }
    }

    /// Turns the glTF BSDF's anisotropy direction (`KHR_materials_anisotropy`)
    /// into the shading frame `frame`, given the mesh's unit tangent `t` and
    /// bitangent `b` at the hit (see [`PbrBsdf::orient_anisotropy`]); nothing
    /// for other materials or without anisotropy.
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A, b: Vec3A) {
        match self {
            Material::Pbr(p) => p.orient_anisotropy(frame, t, b),
            Material::MiRoughConductor(c) => c.orient_anisotropy(frame, t),
            Material::MiRoughDielectric(d) => d.orient_anisotropy(frame, t),
            Material::MiPrincipled(p) => p.orient_anisotropy(frame, t),
            Material::MiPrincipledThin(p) => p.orient_anisotropy(frame, t),
            Material::MiBlend(blend) => {
                for part in &mut blend.parts {
                    let mut m = Material::from(*part);
                    m.orient_anisotropy(frame, t, b);
                    *part = m.blend_part().unwrap_or(*part);
                }
            }
            _ => {}
        }
    }

    /// The material as a part of a [`Blend`] (Mitsuba's BSDFs other than a
    /// blend; `None` for raylab's own and the glTF BSDF).
    #[inline]
    pub fn blend_part(&self) -> Option<BlendPart> {
        Some(match *self {
            Material::Diffuse { reflectance } => BlendPart::Diffuse(reflectance),
            Material::MiConductor(c) => BlendPart::Conductor(c),
            Material::MiRoughConductor(c) => BlendPart::RoughConductor(c),
            Material::MiDielectric(d) => BlendPart::Dielectric(d),
            Material::MiThinDielectric(d) => BlendPart::ThinDielectric(d),
            Material::MiRoughDielectric(d) => BlendPart::RoughDielectric(d),
            Material::MiPlastic(p) => BlendPart::Plastic(p),
            Material::MiRoughPlastic(p) => BlendPart::RoughPlastic(p),
            Material::MiPrincipled(p) => BlendPart::Principled(p),
            Material::MiPrincipledThin(p) => BlendPart::PrincipledThin(p),
            _ => return None,
        })
    }

    /// Whether the BSDF's microfacets are anisotropic (a Mitsuba rough
    /// conductor or dielectric with `alpha_u ≠ alpha_v`, a principled BSDF
    /// with `anisotropic > 0`; the glTF BSDF's anisotropy is the
    /// material's, see
    /// [`crate::materials::surface::SurfaceMaterial::has_anisotropy`]).
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Material::MiRoughConductor(c) => !c.distribution.is_isotropic(),
            Material::MiRoughDielectric(d) => !d.distribution.is_isotropic(),
            Material::MiPrincipled(m) => m.anisotropic > 0.0,
            Material::MiPrincipledThin(m) => m.anisotropic > 0.0,
            Material::MiBlend(b) => b.parts.iter().any(|p| Material::from(*p).is_anisotropic()),
            _ => false,
        }
    }

    /// Sets a Mitsuba BSDF's scalar parameter `param` to `value` (a texture's
    /// value at a hit); nothing for a material without it. A microfacet
    /// width is clamped as [`MicrofacetDistribution::new`] clamps it. Set
    /// a principled BSDF's `anisotropic` before
    /// [`Material::orient_anisotropy`].
    #[inline]
    pub fn set_param(&mut self, param: mitsuba::Param, value: f32) {
        if param == mitsuba::Param::Weight {
            if let Material::MiBlend(b) = self {
                b.set_weight(value);
            }
            return;
        }
        if let mitsuba::Param::Principled(p) = param {
            match self {
                Material::MiPrincipled(m) => m.set(p, value),
                Material::MiPrincipledThin(m) => m.set(p, value),
                _ => false,
            };
            return;
        }
        let distribution = match self {
            Material::MiRoughConductor(c) => &mut c.distribution,
            Material::MiRoughDielectric(d) => &mut d.distribution,
            _ => return,
        };
        let (mut u, mut v) = (distribution.alpha_u, distribution.alpha_v);
        match param {
            mitsuba::Param::AlphaU => u = value,
            mitsuba::Param::AlphaV => v = value,
            mitsuba::Param::Principled(_) | mitsuba::Param::Weight => {}
        }
        *distribution = MicrofacetDistribution::new(distribution.kind, u, v);
    }

    /// Gold: RGB `eta`/`k` from Mitsuba's spectral data for Au integrated to linear
    /// sRGB (as tabulated in Tungsten's `ComplexIorData.hpp`).
    pub fn gold(alpha: f32) -> Material {
        Material::RoughConductor {
            alpha,
            eta: Vec3A::new(0.143_118_96, 0.374_957_04, 1.442_478_6),
            k: Vec3A::new(3.983_160_4, 2.385_720_7, 1.603_215_3),
        }
    }

    /// Copper: RGB `eta`/`k` for Cu from the same source as [`Material::gold`].
    pub fn copper(alpha: f32) -> Material {
        Material::RoughConductor {
            alpha,
            eta: Vec3A::new(0.200_437_7, 0.924_033_4, 1.102_212),
            k: Vec3A::new(3.912_948_5, 2.452_847_7, 2.142_188),
        }
    }

    /// Aluminium: RGB `eta`/`k` for Al from the same source as [`Material::gold`].
    pub fn aluminium(alpha: f32) -> Material {
        Material::RoughConductor {
            alpha,
            eta: Vec3A::new(1.657_46, 0.880_369, 0.521_228_7),
            k: Vec3A::new(9.223_869, 6.269_523, 4.837_001),
        }
    }

    /// Silver: RGB `eta`/`k` for Ag from the same source as [`Material::gold`].
    pub fn silver(alpha: f32) -> Material {
        Material::RoughConductor {
            alpha,
            eta: Vec3A::new(0.155_264_65, 0.116_723_3, 0.138_380_7),
            k: Vec3A::new(4.828_343, 3.122_246, 2.146_950_4),
        }
    }

    /// A conductor whose Fresnel reflectance is exactly 1 at every angle
    /// (infinite extinction `k`): only the microfacet shadowing loses energy, which
    /// makes it the material of white-furnace tests.
    pub fn perfect_conductor(alpha: f32) -> Material {
        Material::RoughConductor {
            alpha,
            eta: Vec3A::ONE,
            k: Vec3A::splat(f32::INFINITY),
        }
    }

    /// Whether [`Material::sample`] reads `u_lobe` (glass, plastics and the
    /// glTF material choose between lobes).
    #[inline]
    pub fn chooses_lobe(&self) -> bool {
        matches!(
            self,
            Material::Dielectric { .. }
                | Material::Pbr(_)
                | Material::MiDielectric(_)
                | Material::MiThinDielectric(_)
                | Material::MiRoughDielectric(_)
                | Material::MiPlastic(_)
                | Material::MiRoughPlastic(_)
                | Material::MiPrincipled(_)
                | Material::MiPrincipledThin(_)
                | Material::MiBlend(_)
        )
    }

    /// Whether the material lets light through unchanged, as nothing were
    /// there: a dielectric of index 1, which is how Mitsuba's `null` BSDF
    /// is made (its `hide_emitters` tells it from other surfaces).
    pub fn is_null(&self) -> bool {
        matches!(*self, Material::Dielectric { ior } if ior == 1.0)
    }

    /// Whether one of its lobes lets light through undeviated, which
    /// Mitsuba flags `Null` (its `thindielectric`): its `volpath` crosses
    /// such a lobe without counting a bounce, and shadow rays pass it
    /// ([`crate::materials::surface::SurfaceMaterial::null_transmission`]).
    #[inline]
    pub fn passes_straight(&self) -> bool {
        matches!(self, Material::MiThinDielectric(_))
    }

    /// Whether the material has only delta lobes (mirror, glass, smooth
    /// conductors, a smooth [`Material::Pbr`] without a diffuse part):
    /// next-event estimation cannot hit them, so an integrator should only follow
    /// [`Material::sample`].
    pub fn is_specular(&self) -> bool {
        match *self {
            Material::Diffuse { .. } => false,
            Material::Mirror { .. } | Material::Dielectric { .. } => true,
            Material::RoughConductor { alpha, .. } => is_smooth(alpha),
            Material::Pbr(ref p) => p.is_specular(),
            Material::MiConductor(_)
            | Material::MiDielectric(_)
            | Material::MiThinDielectric(_) => true,
            Material::MiRoughConductor(_)
            | Material::MiRoughDielectric(_)
            | Material::MiPlastic(_)
            | Material::MiRoughPlastic(_)
            | Material::MiPrincipled(_)
            | Material::MiPrincipledThin(_) => false,
            Material::MiBlend(ref b) => b.parts.iter().all(|p| Material::from(*p).is_specular()),
        }
    }

    /// A cheap estimate of the directional albedo seen from a direction at
    /// cosine `cos_o` to the shading normal (either side), in `[0, 1]` per
    /// channel: the albedo a denoiser takes as its guide (see
    /// [`crate::aov`]). Diffuse: the reflectance. Mirror: its reflectance (the
    /// specular tint). Glass: 1 (clear, `R + T = 1`). Conductors, rough or
    /// smooth: the Fresnel reflectance at `cos_o` (their tint; the energy that
    /// single-scattering GGX loses at high roughness is not subtracted). The
    /// glTF BSDF: [`PbrBsdf::albedo`].
    pub fn albedo(&self, cos_o: f32) -> Vec3A {
        let cos = cos_o.abs().min(1.0);
        let a = match *self {
            Material::Diffuse { reflectance } | Material::Mirror { reflectance } => reflectance,
            Material::Dielectric { .. } => Vec3A::ONE,
            Material::RoughConductor { eta, k, .. } => fresnel_conductor(cos, eta, k),
            Material::Pbr(ref p) => p.albedo(cos),
            Material::MiConductor(ref c) => c.reflectance(cos),
            Material::MiRoughConductor(ref c) => c.reflectance(cos),
            Material::MiDielectric(ref d) => d.albedo(cos),
            Material::MiThinDielectric(ref d) => d.albedo(cos),
            Material::MiRoughDielectric(ref d) => d.albedo(cos),
            Material::MiPlastic(ref p) => p.albedo(cos),
            Material::MiRoughPlastic(ref p) => p.albedo(cos),
            Material::MiPrincipled(ref p) => p.albedo(cos),
            Material::MiPrincipledThin(ref p) => p.albedo(cos),
            Material::MiBlend(ref b) => b.mix(|p| Material::from(*p).albedo(cos)),
        };
        finite_or_zero(a).clamp(Vec3A::ZERO, Vec3A::ONE)
    }

    /// Whether light may pass through the surface (glass, glTF transmission
    /// or diffuse transmission): it is then lit from both sides.
    #[inline]
    pub fn transmits(&self) -> bool {
        match *self {
            Material::Dielectric { .. }
            | Material::MiDielectric(_)
            | Material::MiThinDielectric(_)
            | Material::MiRoughDielectric(_) => true,
            Material::Pbr(ref p) => {
                (p.transmission > 0.0 && p.metallic < 1.0) || p.transmits_diffusely()
            }
            Material::MiPrincipled(ref p) => p.transmits(),
            Material::MiPrincipledThin(ref p) => p.transmits(),
            Material::MiBlend(ref b) => b.parts.iter().any(|p| Material::from(*p).transmits()),
            _ => false,
        }
    }

    /// What the denoiser's guides follow from `wo` (local frame, as for
    /// [`Material::sample`]): the specular lobes (mirror, glass, smooth and
    /// near-smooth metals, the glTF BSDF's specular and transmission lobes
    /// when `α ≤` [`GUIDE_ALPHA`]) each as the single direction a perfectly
    /// smooth surface would send light (mirror reflection, refraction) and
    /// their values (Fresnel terms and tints at `wo`), and the albedo of the
    /// other lobes. No random numbers: the guides are the same for every
    /// sample through the same point.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        if !wo.is_finite() || wo.z == 0.0 {
            return GuideLobes::NONE;
        }
        let specular = |alpha: f32| is_smooth(alpha) || alpha <= GUIDE_ALPHA;
        match *self {
            Material::Diffuse { reflectance } if above(wo) => GuideLobes::rough(reflectance),
            Material::Mirror { reflectance } if above(wo) => GuideLobes {
                reflect: GuideLobes::lobe(reflect_z(wo), reflectance),
                ..GuideLobes::NONE
            },
            Material::Diffuse { .. } | Material::Mirror { .. } => GuideLobes::NONE,
            Material::Dielectric { ior } => {
                if ior.is_nan() || ior <= 0.0 {
                    return GuideLobes::NONE;
                }
                let (eta, sin2_t, f) = dielectric_interface(ior, wo);
                let transmit = (sin2_t < 1.0)
                    .then(|| dielectric_refraction(wo, eta, sin2_t))
                    .and_then(|wi| GuideLobes::lobe(wi, Vec3A::splat(1.0 - f)));
                GuideLobes {
                    rough: Vec3A::ZERO,
                    reflect: GuideLobes::lobe(reflect_z(wo), Vec3A::splat(f)),
                    transmit,
                }
            }
            Material::RoughConductor { alpha, eta, k } => {
                if !above(wo) {
                    return GuideLobes::NONE;
                }
                let f = fresnel_conductor(wo.z, eta, k);
                if specular(alpha) {
                    GuideLobes {
                        reflect: GuideLobes::lobe(reflect_z(wo), f),
                        ..GuideLobes::NONE
                    }
                } else {
                    GuideLobes::rough(f)
                }
            }
            Material::Pbr(ref p) => p.guide_lobes(wo),
            Material::MiConductor(ref c) => c.guide_lobes(wo),
            Material::MiRoughConductor(ref c) => c.guide_lobes(wo),
            Material::MiDielectric(ref d) => d.guide_lobes(wo),
            Material::MiThinDielectric(ref d) => d.guide_lobes(wo),
            Material::MiRoughDielectric(ref d) => d.guide_lobes(wo),
            Material::MiPlastic(ref p) => p.guide_lobes(wo),
            Material::MiRoughPlastic(ref p) => p.guide_lobes(wo),
            Material::MiPrincipled(ref p) => p.guide_lobes(wo),
            Material::MiPrincipledThin(ref p) => p.guide_lobes(wo),
            Material::MiBlend(ref b) => {
                b.mix_guides(b.parts.map(|p| Material::from(p).guide_lobes(wo)))
            }
        }
    }

    /// `f(wo, wi) |cos θi|` for the non-delta lobes; zero for delta materials, for
    /// directions on the wrong side and for one-sided materials seen from below.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        match *self {
            Material::Diffuse { reflectance } => {
                if !above(wo) || !above(wi) {
                    return Vec3A::ZERO;
                }
                reflectance * (FRAC_1_PI * wi.z)
            }
            Material::Mirror { .. } | Material::Dielectric { .. } => Vec3A::ZERO,
            Material::RoughConductor { alpha, eta, k } => {
                if is_smooth(alpha) || !above(wo) || !above(wi) {
                    return Vec3A::ZERO;
                }
                let h = wo + wi;
                if h == Vec3A::ZERO {
                    return Vec3A::ZERO;
                }
                let m = h.normalize();
                let d = ggx_d(alpha, m);
                let g2 = 1.0 / (1.0 + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi));
                let f = fresnel_conductor(wo.dot(m), eta, k);
                // f_r cos θi = D G2 F / (4 cos θo); the numerator first so that a
                // subnormal cos θo next to G2 = 0 gives 0, not 0 · ∞.
                finite_or_zero(f * (d * g2) / (4.0 * wo.z))
            }
            Material::Pbr(ref p) => p.eval(wo, wi),
            Material::MiConductor(_)
            | Material::MiDielectric(_)
            | Material::MiThinDielectric(_) => Vec3A::ZERO,
            Material::MiRoughConductor(ref c) => c.eval(wo, wi),
            Material::MiRoughDielectric(ref d) => d.eval(wo, wi),
            Material::MiPlastic(ref p) => p.eval(wo, wi),
            Material::MiRoughPlastic(ref p) => p.eval(wo, wi),
            Material::MiPrincipled(ref p) => p.eval(wo, wi),
            Material::MiPrincipledThin(ref p) => p.eval(wo, wi),
            Material::MiBlend(ref b) => blend_eval(b, wo, wi),
        }
    }

    /// The BSDF seen from `wo` (local): what depends on `wo` alone worked
    /// out once for a path vertex's light sample and BSDF sample.
    #[inline]
    pub fn at(&self, wo: Vec3A) -> BsdfAt<'_> {
        match self {
            Material::Pbr(bsdf) => BsdfAt::Pbr {
                bsdf,
                wo,
                local: bsdf.local(wo),
            },
            material => BsdfAt::Other { material, wo },
        }
    }

    /// Solid-angle density with which [`Material::sample`] produces `wi` (zero for
    /// delta lobes and wherever [`Material::eval`] is zero).
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match *self {
            Material::Diffuse { .. } => {
                if !above(wo) || !above(wi) {
                    return 0.0;
                }
                FRAC_1_PI * wi.z
            }
            Material::Mirror { .. } | Material::Dielectric { .. } => 0.0,
            Material::RoughConductor { alpha, .. } => {
                if is_smooth(alpha) || !above(wo) || !above(wi) {
                    return 0.0;
                }
                let h = wo + wi;
                if h == Vec3A::ZERO {
                    return 0.0;
                }
                let m = h.normalize();
                // D_wo(m) / (4 |wo·m|) = G1(wo) D(m) / (4 cos θo).
                let g1 = 1.0 / (1.0 + ggx_lambda(alpha, wo));
                let p = (g1 * ggx_d(alpha, m)) / (4.0 * wo.z);
                if p.is_finite() { p } else { 0.0 }
            }
            Material::Pbr(ref p) => p.pdf(wo, wi),
            Material::MiConductor(_)
            | Material::MiDielectric(_)
            | Material::MiThinDielectric(_) => 0.0,
            Material::MiRoughConductor(ref c) => c.pdf(wo, wi),
            Material::MiRoughDielectric(ref d) => d.pdf(wo, wi),
            Material::MiPlastic(ref p) => p.pdf(wo, wi),
            Material::MiRoughPlastic(ref p) => p.pdf(wo, wi),
            Material::MiPrincipled(ref p) => p.pdf(wo, wi),
            Material::MiPrincipledThin(ref p) => p.pdf(wo, wi),
            Material::MiBlend(ref b) => blend_pdf(b, wo, wi),
        }
    }

    /// Draws `wi` for the outgoing direction `wo` (both local). `u_lobe` chooses
    /// between reflection and refraction for [`Material::Dielectric`] and the lobe
    /// of [`Material::Pbr`] (unused by the others); `u` is a 2D sample in
    /// `[0, 1)²`. `None` when nothing is scattered (back side of a one-sided
    /// material, a sample below the horizon, or a degenerate configuration).
    /// (Inlined: as a call its sample came back through memory, 1.2 % of
    /// the lab box's `path`.)
    #[inline(always)]
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match *self {
            Material::Diffuse { reflectance } => {
                if !above(wo) {
                    return None;
                }
                let d = concentric_disk(u);
                let z = (1.0 - d.length_squared()).max(0.0).sqrt();
                if z <= 0.0 {
                    return None;
                }
                Some(BsdfSample {
                    wi: Vec3A::new(d.x, d.y, z),
                    weight: reflectance,
                    pdf: FRAC_1_PI * z,
                    specular: false,
                })
            }
            Material::Mirror { reflectance } => {
                if !above(wo) {
                    return None;
                }
                Some(BsdfSample {
                    wi: reflect_z(wo),
                    weight: reflectance,
                    pdf: 1.0,
                    specular: true,
                })
            }
            Material::Dielectric { ior } => sample_dielectric(ior, wo, u_lobe),
            Material::RoughConductor { alpha, eta, k } => {
                if !above(wo) {
                    return None;
                }
                if is_smooth(alpha) {
                    let weight = fresnel_conductor(wo.z, eta, k);
                    return Some(BsdfSample {
                        wi: reflect_z(wo),
                        weight,
                        pdf: 1.0,
                        specular: true,
                    });
                }
                let m = ggx_sample_visible_normal(alpha, wo, u);
                let wo_m = wo.dot(m);
                if wo_m.is_nan() || wo_m <= 0.0 {
                    return None;
                }
                let wi = (2.0 * wo_m * m - wo).normalize();
                if !above(wi) {
                    return None;
                }
                // The half vector exactly as pdf() and eval() recompute it, so that
                // the returned pdf is bit-identical to pdf(wo, wi) (MIS) and
                // weight = eval / pdf despite f32 rounding of m.
                let m = (wo + wi).normalize();
                let lambda_o = ggx_lambda(alpha, wo);
                let lambda_i = ggx_lambda(alpha, wi);
                let g1 = 1.0 / (1.0 + lambda_o);
                let pdf = (g1 * ggx_d(alpha, m)) / (4.0 * wo.z);
                // weight = f cos θi / pdf = F G2 / G1(wo): D cancels.
                let ratio = (1.0 + lambda_o) / (1.0 + lambda_o + lambda_i);
                let weight = fresnel_conductor(wo.dot(m), eta, k) * ratio;
                if !pdf.is_finite() || pdf <= 0.0 || !weight.is_finite() {
                    return None;
                }
                Some(BsdfSample {
                    wi,
                    weight,
                    pdf,
                    specular: false,
                })
            }
            Material::Pbr(ref p) => p.sample(wo, u_lobe, u),
            Material::MiConductor(ref c) => c.sample(wo),
            Material::MiRoughConductor(ref c) => c.sample(wo, u),
            Material::MiDielectric(ref d) => d.sample(wo, u_lobe),
            Material::MiThinDielectric(ref d) => d.sample(wo, u_lobe),
            Material::MiRoughDielectric(ref d) => d.sample(wo, u_lobe, u),
            Material::MiPlastic(ref p) => p.sample(wo, u_lobe, u),
            Material::MiRoughPlastic(ref p) => p.sample(wo, u_lobe, u),
            Material::MiPrincipled(ref p) => p.sample(wo, u_lobe, u),
            Material::MiPrincipledThin(ref p) => p.sample(wo, u_lobe, u),
            Material::MiBlend(ref b) => blend_sample(b, wo, u_lobe, u),
        }
    }
}

/// [`Material::eval`] of a blend: its parts' values mixed.
#[inline(never)]
fn blend_eval(b: &Blend, wo: Vec3A, wi: Vec3A) -> Vec3A {
    b.mix(|p| Material::from(*p).eval(wo, wi))
}

/// [`Material::pdf`] of a blend: its parts' densities mixed.
#[inline(never)]
fn blend_pdf(b: &Blend, wo: Vec3A, wi: Vec3A) -> f32 {
    b.mix_scalar(|p| Material::from(*p).pdf(wo, wi))
}

/// [`Material::sample`] of a blend ([`Blend::sample`]). (Out of line: the
/// other materials' sampling stays as it was.)
#[inline(never)]
fn blend_sample(b: &Blend, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    b.sample(
        u_lobe,
        |p, u_lobe| Material::from(*p).sample(wo, u_lobe, u),
        |wi| (blend_eval(b, wo, wi), blend_pdf(b, wo, wi)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::test_util::*;

    /// All χ² tests of this module, for the Šidák correction.
    const CHI2_TESTS: u32 = 3 + 3 * 4;

    // --------------------------------------------------------------- Albedo

    #[test]
    fn albedo_is_the_reflectance_tint_or_white_and_stays_in_range() {
        let rho = Vec3A::new(0.75, 0.15, 0.5);
        for cos in [1.0, 0.5, -0.3, 0.0] {
            assert_eq!(Material::Diffuse { reflectance: rho }.albedo(cos), rho);
            assert_eq!(Material::Mirror { reflectance: rho }.albedo(cos), rho);
            assert_eq!(Material::Dielectric { ior: 1.5 }.albedo(cos), Vec3A::ONE);
            assert_eq!(Material::perfect_conductor(0.3).albedo(cos), Vec3A::ONE);
        }
        let Material::RoughConductor { eta, k, .. } = Material::gold(0.2) else {
            unreachable!()
        };
        let gold = Material::gold(0.2).albedo(1.0);
        assert_eq!(gold, fresnel_conductor(1.0, eta, k));
        assert!(gold.x > gold.z && gold.max_element() <= 1.0, "{gold}");
        // glTF: head-on, Schlick's terms are F0: a metal gives its base colour,
        // a dielectric F0 + (1 − F0)·c; smooth clear glass is white at any angle.
        let c = Vec3A::new(0.8, 0.4, 0.2);
        let metal = PbrBsdf::new(c, 1.0, 0.5);
        assert!((Material::Pbr(metal).albedo(1.0) - c).abs().max_element() < 1e-6);
        let plastic = PbrBsdf::new(c, 0.0, 0.5);
        let want = 0.04 + 0.96 * c;
        assert!((plastic.albedo(-1.0) - want).abs().max_element() < 1e-6);
        // Towards grazing the Fresnel terms grow: brighter, never above 1.
        assert!(plastic.albedo(0.1).cmpgt(want).all());
        let glass = PbrBsdf {
            transmission: 1.0,
            thin_walled: false,
            ..PbrBsdf::new(Vec3A::ONE, 0.0, 0.0)
        };
        for cos in [1.0, 0.7, 0.2, 0.01] {
            assert!((glass.albedo(cos) - Vec3A::ONE).abs().max_element() < 1e-6);
        }
        // Out-of-range and NaN inputs still give an albedo in [0, 1].
        let hot = PbrBsdf::new(Vec3A::splat(3.0), 0.5, 0.5).albedo(0.5);
        assert!(hot.cmple(Vec3A::ONE).all() && hot.cmpge(Vec3A::ZERO).all());
        let nan = PbrBsdf::new(Vec3A::splat(f32::NAN), 0.0, 0.5);
        assert_eq!(Material::Pbr(nan).albedo(1.0), Vec3A::ZERO);
    }

    // ------------------------------------------------- χ² goodness of fit

    #[test]
    fn chi2_diffuse_sampling_matches_pdf() {
        let m = Material::Diffuse {
            reflectance: Vec3A::splat(0.7),
        };
        let mut min_p = 1.0f64;
        for (i, theta) in [0.0, 45.0, 89.0].into_iter().enumerate() {
            let p = chi2_p_value(m, dir(theta, 0.3), 100 + i as u64);
            eprintln!("chi2 diffuse theta_o={theta}: p = {p:.4}");
            assert!(
                p > sidak_threshold(CHI2_TESTS),
                "diffuse, θo = {theta}°: p = {p}"
            );
            min_p = min_p.min(p);
        }
        eprintln!("chi2 diffuse: min p = {min_p:.4}");
    }

    #[test]
    fn chi2_rough_conductor_sampling_matches_pdf() {
        let mut min_p = 1.0f64;
        let mut key = 200;
        for alpha in [0.1, 0.3, 0.8] {
            for theta in [0.0, 40.0, 70.0, 88.0] {
                key += 1;
                let p = chi2_p_value(Material::gold(alpha), dir(theta, 0.3), key);
                eprintln!("chi2 conductor alpha={alpha} theta_o={theta}: p = {p:.4}");
                assert!(
                    p > sidak_threshold(CHI2_TESTS),
                    "α = {alpha}, θo = {theta}°: p = {p}"
                );
                min_p = min_p.min(p);
            }
        }
        eprintln!("chi2 conductor: min p = {min_p:.4}");
    }

    #[test]
    fn chi2_detects_a_wrong_pdf() {
        // The test must be able to fail: sampling GGX with α = 0.3 against the pdf
        // of α = 0.33 is rejected.
        let wrong = Material::perfect_conductor(0.33);
        let right = Material::perfect_conductor(0.3);
        let wo = dir(40.0, 0.3);
        let expected = integrate_bins(|wi| wrong.pdf(wo, wi));
        let mut observed = vec![0.0f64; expected.len()];
        let mut r = rng(7);
        let n = 100_000;
        for _ in 0..n {
            if let Some(s) = right.sample(wo, 0.5, u2(&mut r)) {
                observed[bin_of(s.wi)] += 1.0;
            }
        }
        let chi2: f64 = expected
            .iter()
            .zip(&observed)
            .filter(|(e, _)| **e * n as f64 >= 5.0)
            .map(|(e, o)| (o - e * n as f64).powi(2) / (e * n as f64))
            .sum();
        let cells = expected.iter().filter(|e| **e * n as f64 >= 5.0).count();
        let p = gamma_q((cells - 1) as f64 / 2.0, chi2 / 2.0);
        assert!(p < 1e-6, "wrong pdf not detected: p = {p}");
    }

    // ------------------------------------------ weights, pdf normalisation

    fn non_delta_materials() -> Vec<Material> {
        vec![
            Material::Diffuse {
                reflectance: Vec3A::new(0.8, 0.5, 0.2),
            },
            Material::gold(0.05),
            Material::copper(0.3),
            Material::aluminium(0.8),
            Material::silver(1.0),
            Material::perfect_conductor(0.2),
        ]
    }

    #[test]
    fn sample_weight_is_eval_over_pdf() {
        let mut r = rng(3);
        let mut worst = 0.0f32;
        for m in non_delta_materials() {
            let mut hits = 0;
            for _ in 0..20_000 {
                let mut wo = sphere(&mut r);
                wo.z = wo.z.abs().max(1e-3);
                let wo = wo.normalize();
                let Some(s) = m.sample(wo, r.next_f32(), u2(&mut r)) else {
                    continue;
                };
                hits += 1;
                assert!(!s.specular);
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                let pdf = m.pdf(wo, s.wi);
                let f = m.eval(wo, s.wi);
                assert!(
                    ((s.pdf - pdf) / pdf).abs() < 1e-4,
                    "{m:?}: pdf {} vs {pdf}",
                    s.pdf
                );
                let e = rel_err(s.weight, f / pdf);
                assert!(
                    e < 1e-4,
                    "{m:?} wo {wo:?}: weight {:?} vs {:?}",
                    s.weight,
                    f / pdf
                );
                worst = worst.max(e);
            }
            assert!(hits > 10_000, "{m:?}: only {hits} samples");
        }
        eprintln!("weight vs eval/pdf: worst relative error {worst:e}");
    }

    #[test]
    fn pdf_integrates_to_at_most_one() {
        let diffuse = Material::Diffuse {
            reflectance: Vec3A::ONE,
        };
        let total: f64 = integrate_bins(|wi| diffuse.pdf(dir(30.0, 0.0), wi))
            .iter()
            .sum();
        eprintln!("∫ pdf, diffuse: {total:.6}");
        assert!(
            (total - 1.0).abs() < 1e-4,
            "diffuse pdf integrates to {total}"
        );
        for alpha in [0.1, 0.3, 0.8] {
            for theta in [0.0, 60.0, 85.0] {
                let m = Material::perfect_conductor(alpha);
                let wo = dir(theta, 1.0);
                let total: f64 = integrate_bins(|wi| m.pdf(wo, wi)).iter().sum();
                // Monte Carlo estimate of the mass sample() puts above the horizon.
                let mut r = rng(11);
                let n = 200_000;
                let above = (0..n)
                    .filter(|_| m.sample(wo, 0.5, u2(&mut r)).is_some())
                    .count() as f64
                    / n as f64;
                let sigma = (above * (1.0 - above) / n as f64).sqrt().max(1e-6);
                eprintln!(
                    "∫ pdf, conductor α={alpha} θo={theta}: {total:.5} (sampled above horizon {above:.5})"
                );
                assert!(total <= 1.0 + 1e-4, "α = {alpha}, θo = {theta}: {total}");
                assert!(
                    (total - above).abs() < 5.0 * sigma + 1e-4,
                    "α = {alpha}, θo = {theta}: ∫pdf {total} vs {above}"
                );
            }
        }
    }

    // -------------------------------------------------------- furnaces

    #[test]
    fn furnace_diffuse_and_mirror_are_exactly_one() {
        let white = Material::Diffuse {
            reflectance: Vec3A::ONE,
        };
        let mirror = Material::Mirror {
            reflectance: Vec3A::ONE,
        };
        for theta in [0.0, 60.0, 89.9] {
            let wo = dir(theta, 2.0);
            let (a, _) = albedo(white, wo, 100_000, 21);
            assert_eq!(a, 1.0, "diffuse θo = {theta}");
            let q = albedo_by_quadrature(white, wo);
            assert!((q - 1.0).abs() < 1e-4, "diffuse ∫ f cos = {q}");
            let (a, _) = albedo(mirror, wo, 1000, 22);
            assert_eq!(a, 1.0, "mirror θo = {theta}");
        }
        eprintln!("furnace: diffuse albedo 1 (exact), mirror 1 (exact)");
    }

    #[test]
    fn furnace_perfect_conductor() {
        let n = 400_000;
        // Smooth-ish: almost nothing is lost to shadowing.
        for theta in [0.0, 45.0, 80.0] {
            let wo = dir(theta, 0.7);
            let (a, se) = albedo(Material::perfect_conductor(0.01), wo, n, 31);
            eprintln!("furnace perfect conductor α=0.01 θo={theta}: {a:.5} ± {se:.5}");
            assert!(a <= 1.0 + 4.0 * se + 1e-6, "α = 0.01 gains energy: {a}");
            assert!(a > 0.99, "α = 0.01, θo = {theta}: albedo {a}");
        }
        // Delta limit: exactly 1.
        let (a, _) = albedo(Material::perfect_conductor(0.0), dir(50.0, 0.0), 100, 32);
        assert_eq!(a, 1.0);
        // Very rough: single scattering loses energy. At normal incidence and
        // α = 1 half of the visible normals are tilted by more than 45°
        // (P(θm > 45°) = α² / (1 + α²)) and reflect below the horizon, and G2/G1
        // takes more: E(0°) = 0.307. At θo = 80°, E = 0.668. (Both from an
        // independent float64 numpy integration of the same model.)
        for (theta, expected) in [(0.0, 0.307), (80.0, 0.668)] {
            let wo = dir(theta, 0.7);
            let m = Material::perfect_conductor(1.0);
            let (a, se) = albedo(m, wo, n, 33);
            let q = albedo_by_quadrature(m, wo);
            eprintln!(
                "furnace perfect conductor α=1 θo={theta}: MC {a:.5} ± {se:.5}, quadrature {q:.5}"
            );
            assert!((a - q).abs() < 4.0 * se + 2e-4, "MC {a} vs quadrature {q}");
            assert!(
                a < 1.0 && (a - expected).abs() < 0.02,
                "α = 1, θo = {theta}: {a}"
            );
        }
        // Energy is monotone in roughness at normal incidence, and never above 1.
        let mut last = 1.0 + 1e-9;
        for alpha in [0.01, 0.1, 0.3, 0.6, 1.0] {
            let (a, se) = albedo(Material::perfect_conductor(alpha), Vec3A::Z, n, 34);
            assert!(a <= last + 4.0 * se, "α = {alpha}: {a} > {last}");
            last = a;
        }
    }

    // ------------------------------------------------------------ guards

    #[test]
    fn back_side_grazing_and_degenerate_inputs_are_safe() {
        let mut r = rng(51);
        let all = [
            Material::Diffuse {
                reflectance: Vec3A::ONE,
            },
            Material::Mirror {
                reflectance: Vec3A::ONE,
            },
            Material::gold(0.3),
            Material::gold(1e-5),
            Material::gold(f32::NAN),
            Material::perfect_conductor(0.001),
            Material::Dielectric { ior: 1.5 },
        ];
        for m in all {
            // One-sided materials: nothing from below.
            if !matches!(m, Material::Dielectric { .. }) {
                for _ in 0..100 {
                    let mut wo = sphere(&mut r);
                    wo.z = -wo.z.abs();
                    let wi = sphere(&mut r);
                    assert!(m.sample(wo, 0.5, u2(&mut r)).is_none(), "{m:?}");
                    assert_eq!(m.eval(wo, wi), Vec3A::ZERO);
                    assert_eq!(m.pdf(wo, wi), 0.0);
                }
            }
            // Grazing and exact-normal wo, extreme u: finite or None, never NaN.
            for wo in [
                Vec3A::Z,
                dir(89.99, 0.1),
                Vec3A::new(1.0, 0.0, 1e-30).normalize(),
                Vec3A::new(1.0, 0.0, 1e-7).normalize(),
                Vec3A::new(0.0, 0.0, 0.0),
                Vec3A::NAN,
            ] {
                for u in [
                    Vec2::ZERO,
                    Vec2::new(0.999_999_9, 0.999_999_9),
                    Vec2::new(0.5, 0.0),
                ] {
                    for wi in [
                        Vec3A::Z,
                        -wo,
                        Vec3A::new(-wo.x, -wo.y, wo.z),
                        dir(89.99, 3.0),
                    ] {
                        assert!(m.eval(wo, wi).is_finite() && m.pdf(wo, wi).is_finite());
                        assert!(m.eval(wo, wi).min_element() >= 0.0 && m.pdf(wo, wi) >= 0.0);
                    }
                    if let Some(s) = m.sample(wo, 0.3, u) {
                        assert!(
                            s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                            "{m:?} {s:?}"
                        );
                        assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4);
                        if !matches!(m, Material::Dielectric { .. }) {
                            assert!(s.wi.z >= 0.0, "{m:?}: {s:?}");
                        }
                    }
                }
            }
        }
        // Tiny α is a smooth conductor: delta lobe, F at the mirror direction.
        let m = Material::gold(1e-5);
        assert!(m.is_specular() && !Material::gold(0.01).is_specular());
        let wo = dir(30.0, 0.0);
        let s = m.sample(wo, 0.5, Vec2::new(0.3, 0.6)).unwrap();
        assert!(s.specular && s.pdf == 1.0);
        assert!((s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        assert_eq!(m.eval(wo, s.wi), Vec3A::ZERO);
        assert!(Material::Dielectric { ior: 1.5 }.is_specular());
        assert!(
            !Material::Diffuse {
                reflectance: Vec3A::ONE
            }
            .is_specular()
        );
    }
}
