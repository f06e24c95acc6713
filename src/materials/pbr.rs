//! The glTF 2.0 metallic–roughness BSDF (glTF specification, Appendix B), with
//! `KHR_materials_specular`, `KHR_materials_ior`, `KHR_materials_transmission`,
//! `KHR_materials_volume`, `KHR_materials_sheen`, `KHR_materials_clearcoat`,
//! `KHR_materials_iridescence`, `KHR_materials_anisotropy` and
//! `KHR_materials_diffuse_transmission`.
//!
//! The frame, side and estimator conventions are those of the parent module
//! ([`crate::materials`]): local frame with the shading normal as `+z`, `wo` and
//! `wi` both pointing away from the surface, `eval` = `f |cos θi|` of the
//! non-delta lobes only, and `sample` weights `f |cos θi| / pdf`.
//!
//! # The model
//!
//! With `c` the base colour, `m` metallic, `s` specular, `tr` transmission and `h`
//! the half vector of the pair being evaluated:
//!
//! * `D` is GGX with width `α`, `V = G2 / (4 |n·l| |n·v|)` Smith's
//!   height-correlated visibility with `G2 = 1 / (1 + Λ(wo) + Λ(wi))`, so that
//!   `specular_brdf |cos θi| = D G2 / (4 |cos θo|)`;
//! * Schlick's Fresnel `F(F0) = F0 + (1 − F0) (1 − |wo·h|)⁵`;
//! * `metal_brdf = F(c) D V`;
//! * `dielectric_brdf = (1 − s max(F_d)) base + s F_d D V` with
//!   `F_d = F(min(((ior − 1)/(ior + 1))² specular_color, 1))` and
//!   `base = mix(c / π, c btdf, tr)`;
//! * `f = mix(dielectric_brdf, metal_brdf, m)`, the exact mix: the diffuse and
//!   transmitted parts carry `(1 − m)`. There is no multiple-scattering
//!   compensation, and Appendix B is not energy conserving for dielectrics at
//!   grazing angles (the `1 − s max(F_d)` of the base uses the half vector of the
//!   pair, not an albedo): a white rough dielectric reflects more than it
//!   receives at 80°. That is the specified model.
//!
//! # Clear coat
//!
//! `KHR_materials_clearcoat` layers a GGX reflection of width `α_c` about the
//! coat's own normal `n_c` (the surface's normal without the base's normal
//! map, or the coat's normal map) over everything above, with the
//! specification's `fresnel_coat`: with `F_c = Schlick(0.04, |wo·n_c|)` and
//! coat weight `w`,
//!
//! `f = (1 − w F_c) f_base + w F_c D_c G2_c / (4 |wo·n_c| |wi·n_c|)`,
//!
//! whose cosine is the coat's (`|wi·n_c|`), as a microfacet BRDF about `n_c`
//! is. `F_c` depends on `wo` alone, so it is not reciprocal, as specified; a
//! white coat over a base that loses nothing reflects at most what it
//! receives. The coat reflects where `wi` is above both `n_c` and the shading
//! normal, and is smooth (a mirror about `n_c`) below
//! [`ALPHA_SMOOTH`](super::ALPHA_SMOOTH). Seen from inside a refracting volume
//! there is no coat (it lies on the outside).
//!
//! # Sheen
//!
//! `KHR_materials_sheen` layers a microfibre reflection of colour `C` and
//! roughness `ρ` ([`super::sheen`]) over the base with the specification's
//! albedo scaling, under the clear coat:
//!
//! `f_under_coat = C f_sheen + f_base min(1 − max(C) E(μo), 1 − max(C) E(μi))`
//!
//! for a reflected pair, and for a pair through a thin wall (sheen on both
//! faces); through a refracting volume, whose sheen lies on the outside
//! only, the transmitted pair is scaled by `1 − max(C) E(μ)` of its
//! direction outside, and there is no sheen inside. That keeps the layering
//! reciprocal. With `E ≤ 1` a white sheen over a base that loses nothing
//! reflects at most what it receives. It is sampled as a cosine-weighted
//! lobe of its own.
//!
//! # Iridescence
//!
//! `KHR_materials_iridescence` puts a thin film on the base: every Fresnel
//! term of the base, the metal's `F(c)` and the dielectric's `F_d` (which
//! also weights the diffuse and transmitted parts by `1 − s max(F_d)`),
//! becomes `mix(F, F_film, ι)` with `ι` the iridescence weight and `F_film`
//! the film's Fresnel ([`super::thin_film`]) at the same cosine, for the
//! base's `F0`: the dielectric's `F0` for `F_d`, the base colour for the
//! metal. Nothing else changes: the lobes, their sampling and the estimates
//! that choose them take the mixed Fresnel where they took Schlick's, so
//! densities and weights stay consistent. A film of thickness 0 is no film.
//! Under a clear coat the film's outside index is the coat's (see
//! [`PbrBsdf::iridescence`]).
//!
//! # Anisotropy
//!
//! `KHR_materials_anisotropy` replaces the base's `D` and `Λ` (metal and
//! dielectric reflection, rough and thin-walled transmission; not the coat)
//! by the anisotropic GGX of widths `α_t = mix(α, 1, k²)` along a unit
//! direction `t` of the tangent plane and `α_b = α` across it (strength `k`);
//! `t` comes in the mesh's tangent space and
//! [`PbrBsdf::orient_anisotropy`] puts it in the shading frame at each hit.
//! The visible normals are sampled in the frame `(t, b, n)` with the view
//! stretched by `(α_t, α_b)`. The delta (smooth) lobes are used only when
//! `α_t` too is below [`ALPHA_SMOOTH`](super::ALPHA_SMOOTH). With `k = 0`
//! the isotropic functions themselves are called: the same values bit for
//! bit as without the extension.
//!
//! # Diffuse transmission
//!
//! `KHR_materials_diffuse_transmission` splits the diffuse part (weight
//! `(1 − m)(1 − tr)(1 − s max(F_d))`) between the reflection `(1 − dt) c / π`
//! and a Lambertian lobe `dt c_t / π` on the far side, whose Fresnel weight
//! takes the half vector of `wo` and the mirrored `wi`: with `s` = 0 (or a
//! white, mirror-symmetric pair) it transmits exactly what the reflection no
//! longer has. It is sampled as a cosine lobe below the surface, a fifth lobe
//! of the same mixture, and does not refract (seen from inside a volume it is
//! the same lobe, with the inside's Fresnel term).
//!
//! # Transmission
//!
//! * Thin-walled (`thin_walled`, glTF transmission without a volume): light
//!   continues straight on. Rough, the transmission lobe is the reflection lobe
//!   mirrored through the surface plane, `btdf(wo, wi) = specular_brdf(wo,
//!   flip_z(wi))`, centred on `−wo`; smooth, a delta along `−wo`.
//! * With a volume: a refracting interface of index `ior` (Walter et al. 2007,
//!   GGX with height-correlated `G2`), tinted by `c`. Transmitted radiance is not
//!   scaled by `1/η²` (see the parent module). `wo.z > 0` is outside (index 1),
//!   `wo.z < 0` inside (index `ior`); the Fresnel term always uses the cosine on
//!   the air side (for `wo` inside and a reflected pair, that of the refracted
//!   direction) and is 1 under total internal reflection. With `α = 0`, a white
//!   base, `m = 0`, `s = 1` and `tr = 1` this is exactly a smooth glass interface
//!   (reflect with probability `F`, refract with `1 − F`, weights 1), but for
//!   Schlick's approximation of `F`.
//!
//! # Sides
//!
//! A material without a refracting volume (transmission 0, or thin-walled) is
//! two-sided: for `wo.z < 0` it is evaluated as if `wo` and `wi` were mirrored to
//! `+z`. A material with a volume is evaluated in the same mirrored frame, but the
//! interface's indices swap (seen from inside, the air is on the far side): from
//! inside, its metal, specular and diffuse parts reflect back into the volume as
//! they do outside, with the dielectric Fresnel term taken on the air side (1
//! under total internal reflection), and the transmission refracts out. In both
//! cases the caller passes the front normal unflipped. A pair is a reflection
//! if `wo.z wi.z > 0`, a transmission if `wo.z wi.z < 0`.
//!
//! # Smooth surfaces
//!
//! For `α <` [`ALPHA_SMOOTH`](super::ALPHA_SMOOTH) the specular reflection
//! (metal and dielectric together) and the transmission become delta lobes; the diffuse lobe stays, so
//! such a material is in general mixed and [`PbrBsdf::is_specular`] is true only
//! when the diffuse part has zero weight.
//!
//! # Sampling
//!
//! One of three lobes (specular reflection: GGX visible normals; diffuse: cosine
//! weighted; transmission: visible normals then refraction, or mirrored
//! reflection when thin-walled) is chosen with probabilities proportional to
//! estimates of their weights that depend on `wo` only (the Fresnel terms at
//! `cos θo`); for a non-delta sample, `pdf` is the mixture of the non-delta lobes'
//! densities (one-sample MIS, balance heuristic), exactly what [`PbrBsdf::pdf`]
//! returns, and the weight is `eval / pdf`. A delta lobe's weight is its value
//! (the Fresnel terms at `cos θo`) over its selection probability.
//!
//! Nothing here allocates.

use super::sheen;
use super::thin_film::{COAT_IOR, ThinFilm};
use super::{
    BsdfSample, Frame, GUIDE_ALPHA, GuideLobes, Material, concentric_disk, finite_or_zero, ggx_d,
    ggx_lambda, ggx_sample_visible_normal, ggx_sample_visible_normal_xy, reflect_z,
};
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, PI};

/// The smallest GGX `α` [`PbrBsdf::alpha_from_roughness`] returns.
pub const MIN_ALPHA: f32 = 1e-4;

/// Floor of the Fresnel estimates that choose the rough specular lobe: keeps its
/// probability positive wherever it can scatter (a black metal seen head-on).
const SPEC_FLOOR: f32 = 1e-3;

/// Floor, relative to its largest value `1 − s max(F0)`, of the `1 − s max(F)`
/// estimate that chooses the rough transmission and the diffuse lobes: near
/// grazing and under total internal reflection at `cos θo` it would vanish,
/// while the pairs' own half vectors still let light through.
const KD_FLOOR: f32 = 0.1;

/// Floor of the sheen's albedo estimate that chooses its lobe: a narrow
/// sheen seen head-on reflects little, but still at grazing `wi`.
const SHEEN_FLOOR: f32 = 0.02;

/// The glTF metallic–roughness BSDF at one surface point, textures already applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrBsdf {
    /// Linear RGB in `[0, 1]` (`baseColorFactor` × texture × `COLOR_0`).
    pub base_color: Vec3A,
    /// Metalness in `[0, 1]`.
    pub metallic: f32,
    /// GGX `α = max(roughness², 1e-4)`, computed by the caller (see
    /// [`PbrBsdf::alpha_from_roughness`]); below
    /// [`ALPHA_SMOOTH`](super::ALPHA_SMOOTH) the specular lobes are deltas.
    pub alpha: f32,
    /// Index of refraction (`KHR_materials_ior`, default 1.5).
    pub ior: f32,
    /// `KHR_materials_specular`: `specularFactor` × `specularTexture.a` (default 1).
    pub specular: f32,
    /// `specularColorFactor` × `specularColorTexture.rgb` (default `(1, 1, 1)`).
    pub specular_color: Vec3A,
    /// `KHR_materials_transmission`: factor × `texture.r` (default 0).
    pub transmission: f32,
    /// True for transmission without `KHR_materials_volume`: light passes
    /// straight through; false makes the surface a refracting interface.
    pub thin_walled: bool,
    /// `KHR_materials_clearcoat`: `clearcoatFactor` × `clearcoatTexture.r`
    /// in `[0, 1]` (0: no coat).
    pub coat: f32,
    /// The coat's GGX `α` (`clearcoatRoughness²`, at least [`MIN_ALPHA`]).
    pub coat_alpha: f32,
    /// The coat's unit normal in the shading frame (`+z` is the base's
    /// shading normal), above its horizon; set per hit by
    /// [`PbrBsdf::orient_coat`].
    pub coat_normal: Vec3A,
    /// `KHR_materials_sheen`: `sheenColorFactor` × `sheenColorTexture.rgb`,
    /// in `[0, 1]` (black: no sheen).
    pub sheen_color: Vec3A,
    /// `sheenRoughnessFactor` × `sheenRoughnessTexture.a`, in `[0, 1]`.
    pub sheen_roughness: f32,
    /// `KHR_materials_dispersion`: `20 / V_d` (`V_d` the Abbe number; 0, the
    /// default, disperses nothing). Only a refracting volume disperses
    /// ([`PbrBsdf::dispersive`]); a path that meets one is carried at one
    /// wavelength from there on, with `ior` replaced by the index at that
    /// wavelength ([`PbrBsdf::at_wavelength`]).
    pub dispersion: f32,
    /// `KHR_materials_iridescence`: `iridescenceFactor` ×
    /// `iridescenceTexture.r` in `[0, 1]` (0: no film, and so is a film of
    /// thickness 0). Under a clear coat of weight `w` the film lies under a
    /// medium of index `mix(1, 1.5, w)`: the coat's 1.5 under a full coat, as
    /// the specification has it, air without one.
    pub iridescence: f32,
    /// The film's index of refraction (`iridescenceIor`, default 1.3).
    pub film_ior: f32,
    /// The film's thickness at this point in nanometres:
    /// `mix(iridescenceThicknessMinimum, iridescenceThicknessMaximum,
    /// iridescenceThicknessTexture.g)`, the maximum without a texture.
    pub film_thickness: f32,
    /// `KHR_materials_anisotropy`: `anisotropyStrength` ×
    /// `anisotropyTexture.b` in `[0, 1]` (0: isotropic, the base's GGX as
    /// without the extension).
    pub anisotropy: f32,
    /// The unit direction of increased roughness: as the material gives it,
    /// in the mesh's tangent space (`x` along the tangent, `y` along the
    /// bitangent); [`PbrBsdf::orient_anisotropy`] turns it into the shading
    /// frame's tangent plane (`x`, `y` of the local frame) at each hit.
    pub anisotropy_direction: Vec2,
    /// `KHR_materials_diffuse_transmission`: `diffuseTransmissionFactor` ×
    /// `diffuseTransmissionTexture.a` in `[0, 1]`, the share of the diffuse
    /// part that is transmitted (0: none).
    pub diffuse_transmission: f32,
    /// `diffuseTransmissionColorFactor` × `diffuseTransmissionColorTexture.rgb`
    /// (linear, in `[0, 1]`): the colour of the diffusely transmitted light.
    pub diffuse_transmission_color: Vec3A,
}

/// The clear coat's `F0`: an index of 1.5, `((1.5 − 1)/(1.5 + 1))²`.
pub const COAT_F0: f32 = 0.04;

/// The clear coat's Fresnel term `F_c` at `cos = |wo·n_c|`.
#[inline]
pub fn coat_fresnel(cos: f32) -> f32 {
    schlick_grey(COAT_F0, cos)
}

impl Default for PbrBsdf {
    /// glTF's default material: white, fully metallic, roughness 1.
    fn default() -> PbrBsdf {
        PbrBsdf::new(Vec3A::ONE, 1.0, 1.0)
    }
}

/// The base's GGX distribution at one hit (the metal's and the dielectric's
/// specular reflection and the transmission; not the coat's).
#[derive(Clone, Copy, Debug)]
enum Ggx {
    /// Width `α` in every direction: the functions of the parent module, so
    /// that a material without `KHR_materials_anisotropy` is evaluated and
    /// sampled exactly as before it existed.
    Isotropic(f32),
    /// Width `at` along the unit direction `dir = (cos φ, sin φ)` of the
    /// local tangent plane and `ab` across it: `D(m) = 1 / (π at ab ((m_t /
    /// at)² + (m_b / ab)² + m_z²)²)` and `Λ(w) = (√(1 + (at² w_t² + ab²
    /// w_b²) / w_z²) − 1) / 2`, with `m_t = m·t`, `m_b = m·b`, `t = (cos φ,
    /// sin φ, 0)` and `b = n × t` (Heitz 2014, "Understanding the
    /// Masking-Shadowing Function", §5.4), as `KHR_materials_anisotropy`'s
    /// `D_GGX_anisotropic` and `V_GGX_anisotropic` write them.
    Anisotropic { at: f32, ab: f32, dir: Vec2 },
}

impl Ggx {
    /// `w` with its tangent-plane part turned into `(t, b)` coordinates.
    #[inline]
    fn to_tb(dir: Vec2, w: Vec3A) -> Vec3A {
        Vec3A::new(dir.x * w.x + dir.y * w.y, dir.x * w.y - dir.y * w.x, w.z)
    }

    /// The inverse of [`Ggx::to_tb`].
    #[inline]
    fn from_tb(dir: Vec2, w: Vec3A) -> Vec3A {
        Vec3A::new(dir.x * w.x - dir.y * w.y, dir.y * w.x + dir.x * w.y, w.z)
    }

    /// The microfacet density `D(m)` (zero below the horizon).
    #[inline]
    fn d(&self, m: Vec3A) -> f32 {
        match *self {
            Ggx::Isotropic(a) => ggx_d(a, m),
            Ggx::Anisotropic { at, ab, dir } => {
                if m.z <= 0.0 {
                    return 0.0;
                }
                let m = Self::to_tb(dir, m);
                let (x, y) = (m.x / at, m.y / ab);
                let s = x * x + y * y + m.z * m.z;
                1.0 / (PI * at * ab * s * s)
            }
        }
    }

    /// Smith's `Λ(w)`; infinite at the horizon.
    #[inline]
    fn lambda(&self, w: Vec3A) -> f32 {
        match *self {
            Ggx::Isotropic(a) => ggx_lambda(a, w),
            Ggx::Anisotropic { at, ab, dir } => {
                let z2 = w.z * w.z;
                if z2 == 0.0 {
                    return f32::INFINITY;
                }
                let w = Self::to_tb(dir, w);
                let (x, y) = (at * w.x, ab * w.y);
                let a2_tan2 = (x * x + y * y) / z2;
                a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
            }
        }
    }

    /// Smith's height-correlated `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
    #[inline]
    fn g2(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Smith's masking `G1(wo) = 1 / (1 + Λ(wo))`.
    #[inline]
    fn g1(&self, wo: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo))
    }

    /// A normal visible from `wo` (`wo.z > 0`), of density `G1(wo) max(0,
    /// wo·m) D(m) / cos θo` (Heitz 2018: the view stretched by `(at, ab)` in
    /// the `(t, b)` frame).
    #[inline]
    fn sample_visible_normal(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        match *self {
            Ggx::Isotropic(a) => ggx_sample_visible_normal(a, wo, u),
            Ggx::Anisotropic { at, ab, dir } => {
                let m = ggx_sample_visible_normal_xy(at, ab, Self::to_tb(dir, wo), u);
                Self::from_tb(dir, m)
            }
        }
    }
}

/// Which lobe [`PbrBsdf::sample`] draws from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lobe {
    Specular,
    Diffuse,
    Transmission,
    Sheen,
    /// `KHR_materials_diffuse_transmission`'s Lambertian lobe on the far side.
    DiffuseTransmission,
    Coat,
}

/// What the clear coat needs at one `wo` (see the module's "Clear coat").
#[derive(Clone, Copy, Debug)]
struct CoatLocal {
    /// The coat's frame (its normal as `+z`) in the canonical frame.
    frame: Frame,
    /// `wo` in the coat's frame.
    wo: Vec3A,
    /// `w F_c`: the coat's share, `1 − w F_c` the base's.
    weight: f32,
}

/// What depends on `wo` only: the canonical frame and the lobe probabilities.
#[derive(Clone, Copy, Debug)]
pub struct Local {
    /// `wo` mirrored to `+z` if it was below.
    wo: Vec3A,
    /// Whether directions are mirrored (`wo.z < 0` originally).
    flip: bool,
    /// Whether `wo` is inside a refracting volume (index `ior`).
    inside: bool,
    /// Whether the transmission refracts (a volume) rather than passing straight.
    volume: bool,
    /// Whether the specular and transmission lobes are deltas.
    smooth: bool,
    /// The base's microfacet distribution.
    ggx: Ggx,
    /// The dielectric's `F0` per channel.
    f0: Vec3A,
    /// Lobe selection probabilities (summing to 1).
    p_spec: f32,
    p_diff: f32,
    p_trans: f32,
    p_sheen: f32,
    p_dtrans: f32,
    p_coat: f32,
    /// Whether there is a sheen (`wo` may be inside a volume: see
    /// [`PbrBsdf::add_sheen`]).
    sheen: bool,
    /// `max(C) E(μo)`: the sheen's share at `wo`, `1 − max(C) E(μo)` the
    /// base's largest (0 without a sheen).
    sheen_o: f32,
    /// The clear coat, where there is one and `wo` is above it.
    coat: Option<CoatLocal>,
}

impl Local {
    /// A direction in (or out of) the canonical frame: the mirror is its own
    /// inverse.
    #[inline]
    fn map(&self, w: Vec3A) -> Vec3A {
        if self.flip {
            Vec3A::new(w.x, w.y, -w.z)
        } else {
            w
        }
    }

    fn choose(&self, u: f32) -> Lobe {
        // The sheen's, the diffuse transmission's and the coat's shares are
        // taken from the top of `[0, 1)` (the coat's highest, the sheen's
        // lowest), so that the other lobes' choices are those of the
        // material without them.
        let base = self.p_spec + self.p_diff + self.p_trans;
        let below_dtrans = base + self.p_sheen;
        if self.p_coat > 0.0 && u >= below_dtrans + self.p_dtrans {
            return Lobe::Coat;
        }
        if self.p_dtrans > 0.0 && u >= below_dtrans {
            return Lobe::DiffuseTransmission;
        }
        if self.p_sheen > 0.0 && u >= base {
            return Lobe::Sheen;
        }
        if u < self.p_spec || (self.p_diff <= 0.0 && self.p_trans <= 0.0) {
            Lobe::Specular
        } else if self.p_trans <= 0.0 || (self.p_diff > 0.0 && u < self.p_spec + self.p_diff) {
            Lobe::Diffuse
        } else {
            Lobe::Transmission
        }
    }
}

/// Schlick's Fresnel approximation for `cos = |wo·h|` (clamped to `[0, 1]`).
#[inline]
fn schlick(f0: Vec3A, cos: f32) -> Vec3A {
    let x = 1.0 - cos.clamp(0.0, 1.0);
    let x2 = x * x;
    f0 + (Vec3A::ONE - f0) * (x2 * x2 * x)
}

/// Schlick's Fresnel approximation for a grey `f0`.
#[inline]
fn schlick_grey(f0: f32, cos: f32) -> f32 {
    let x = 1.0 - cos.clamp(0.0, 1.0);
    let x2 = x * x;
    f0 + (1.0 - f0) * (x2 * x2 * x)
}

/// Rec. 709 luminance (the weights sum to 1), never negative.
#[inline]
fn luminance(c: Vec3A) -> f32 {
    c.dot(Vec3A::new(0.2126, 0.7152, 0.0722)).max(0.0)
}

/// Refracts `wo` (`wo·m > 0`) through the microfacet `m` into the medium whose
/// index relative to `wo`'s is `eta`; `None` under total internal reflection.
#[inline]
fn refract(wo: Vec3A, m: Vec3A, eta: f32) -> Option<Vec3A> {
    let cos_o = wo.dot(m).min(1.0);
    let sin2_t = (1.0 - cos_o * cos_o).max(0.0) / (eta * eta);
    if sin2_t.is_nan() || sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + (cos_o / eta - cos_t) * m).normalize())
}

/// Smith's height-correlated masking–shadowing `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
#[inline]
fn g2(alpha: f32, wo: Vec3A, wi: Vec3A) -> f32 {
    1.0 / (1.0 + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi))
}

/// Smith's masking `G1(wo) = 1 / (1 + Λ(wo))`.
#[inline]
fn g1(alpha: f32, wo: Vec3A) -> f32 {
    1.0 / (1.0 + ggx_lambda(alpha, wo))
}

impl PbrBsdf {
    /// The plain metallic–roughness material: `ior` 1.5, `specular` 1, white
    /// `specular_color`, no transmission (and thin-walled, as a glTF material
    /// without `KHR_materials_volume` is), `alpha` from `roughness`.
    pub fn new(base_color: Vec3A, metallic: f32, roughness: f32) -> PbrBsdf {
        PbrBsdf {
            base_color,
            metallic,
            alpha: Self::alpha_from_roughness(roughness),
            ior: 1.5,
            specular: 1.0,
            specular_color: Vec3A::ONE,
            transmission: 0.0,
            thin_walled: true,
            coat: 0.0,
            coat_alpha: 1.0,
            coat_normal: Vec3A::Z,
            sheen_color: Vec3A::ZERO,
            sheen_roughness: 0.0,
            dispersion: 0.0,
            iridescence: 0.0,
            film_ior: 1.3,
            film_thickness: 400.0,
            anisotropy: 0.0,
            anisotropy_direction: Vec2::X,
            diffuse_transmission: 0.0,
            diffuse_transmission_color: Vec3A::ONE,
        }
    }

    /// Turns [`PbrBsdf::anisotropy_direction`] from the mesh's tangent space
    /// into the shading frame `frame`, given the unit tangent `t` and
    /// bitangent `b` there (world space): `dx t + dy b` projected onto the
    /// shading plane. Without anisotropy nothing changes; where there is no
    /// tangent frame (`t` or `b` zero) or the direction is degenerate (along
    /// the shading normal), the material is isotropic at that hit: the
    /// extension gives no direction to stretch along.
    #[inline]
    pub fn orient_anisotropy(&mut self, frame: &Frame, t: Vec3A, b: Vec3A) {
        if self.anisotropy.is_nan() || self.anisotropy <= 0.0 {
            return;
        }
        let d = self.anisotropy_direction;
        let local = frame.to_local(d.x * t + d.y * b);
        let dir = Vec2::new(local.x, local.y).normalize_or_zero();
        if dir != Vec2::ZERO && dir.is_finite() {
            self.anisotropy_direction = dir;
        } else {
            self.anisotropy = 0.0;
        }
    }

    /// The GGX width along the direction of increased roughness:
    /// `mix(α, 1, strength²)` (`KHR_materials_anisotropy`), `α` without
    /// anisotropy; the larger of the two widths.
    #[inline]
    fn alpha_t(&self) -> f32 {
        if self.anisotropy > 0.0 {
            let k = self.anisotropy.min(1.0);
            self.alpha + (1.0 - self.alpha) * (k * k)
        } else {
            self.alpha
        }
    }

    /// The base's microfacet distribution: anisotropic only where the
    /// strength is positive.
    #[inline]
    fn ggx(&self) -> Ggx {
        if self.anisotropy > 0.0 {
            Ggx::Anisotropic {
                at: self.alpha_t(),
                ab: self.alpha,
                dir: self.anisotropy_direction,
            }
        } else {
            Ggx::Isotropic(self.alpha)
        }
    }

    /// The thin film, where there is one (`ι > 0` and a positive thickness).
    #[inline]
    fn film(&self) -> Option<ThinFilm> {
        (self.iridescence > 0.0 && self.film_thickness > 0.0).then(|| {
            let outside_ior = if self.coat > 0.0 {
                1.0 + (COAT_IOR - 1.0) * self.coat.min(1.0)
            } else {
                1.0
            };
            ThinFilm {
                ior: self.film_ior,
                thickness: self.film_thickness,
                outside_ior,
            }
        })
    }

    /// The metal's Fresnel term at `cos = |wo·h|`: Schlick's of the base
    /// colour, mixed with the film's by `ι` where there is a film (the
    /// film is evaluated only where the metal has weight).
    #[inline]
    fn fresnel_m(&self, cos: f32) -> Vec3A {
        let c = self.base_color;
        let f = schlick(c, cos);
        match self.film() {
            Some(film) if self.metallic > 0.0 => {
                f.lerp(film.fresnel(cos, c), self.iridescence.min(1.0))
            }
            _ => f,
        }
    }

    /// The dielectric's Fresnel term at the air-side cosine `cos`: Schlick's
    /// of `f0`, mixed with the film's by `ι` where there is a film (the film
    /// is evaluated only where the dielectric has weight).
    #[inline]
    fn fresnel_air(&self, f0: Vec3A, cos: f32) -> Vec3A {
        let f = schlick(f0, cos);
        match self.film() {
            Some(film) if self.metallic < 1.0 => {
                f.lerp(film.fresnel(cos, f0), self.iridescence.min(1.0))
            }
            _ => f,
        }
    }

    /// Whether this BSDF disperses light (`KHR_materials_dispersion`): a
    /// positive dispersion on a refracting volume that transmits something.
    /// Thin walls do not disperse (the extension builds on
    /// `KHR_materials_volume`).
    #[inline]
    pub fn dispersive(&self) -> bool {
        self.dispersion > 0.0 && self.transmission_scale() > 0.0 && !self.thin_walled
    }

    /// This BSDF at wavelength `lambda` (nm): `ior` becomes the extension's
    /// `n(λ)` ([`super::spectrum::dispersed_ior`]), for every lobe (the
    /// Fresnel terms and the refraction). A BSDF that is not
    /// [`PbrBsdf::dispersive`] is returned unchanged, bit for bit.
    #[inline]
    pub fn at_wavelength(&self, lambda: f32) -> PbrBsdf {
        if !self.dispersive() {
            return *self;
        }
        PbrBsdf {
            ior: super::spectrum::dispersed_ior(self.ior, self.dispersion, lambda),
            ..*self
        }
    }

    /// Whether the material has a sheen (`KHR_materials_sheen`).
    #[inline]
    fn has_sheen(&self) -> bool {
        self.sheen_color.max_element() > 0.0
    }

    /// Sets the coat's normal from `n_c`, in the coordinates of the shading
    /// frame `frame` (`n_c` on the same side as its normal); a normal at or
    /// below the shading horizon (or not finite) becomes the shading normal.
    #[inline]
    pub fn orient_coat(&mut self, frame: &Frame, n_c: Vec3A) {
        if self.coat > 0.0 {
            let n = frame.to_local(n_c).normalize_or_zero();
            self.coat_normal = if n.z > 0.0 && n.is_finite() {
                n
            } else {
                Vec3A::Z
            };
        }
    }

    /// Whether the coat is a delta lobe.
    #[inline]
    fn coat_smooth(&self) -> bool {
        Material::is_smooth(self.coat_alpha)
    }

    /// glTF's perceptual roughness to GGX width: `max(roughness², 1e-4)`.
    #[inline]
    pub fn alpha_from_roughness(roughness: f32) -> f32 {
        (roughness * roughness).max(MIN_ALPHA)
    }

    /// Whether every lobe is a delta (the surface is smooth and the diffuse part
    /// has zero weight, e.g. a smooth metal or smooth full transmission): next
    /// event estimation cannot hit it.
    pub fn is_specular(&self) -> bool {
        Material::is_smooth(self.alpha_t())
            && !self.has_diffuse()
            && !self.has_sheen()
            && (self.coat <= 0.0 || self.coat_smooth())
    }

    /// A cheap estimate of the directional albedo seen at cosine `cos_o` to the
    /// normal, per channel and clamped to `[0, 1]`, from the same Fresnel terms
    /// at `cos θo` that choose the lobes in [`PbrBsdf::sample`], but in colour:
    /// `m F(c) + (1 − m) (s F_d + (1 − s max(F_d)) c)`, the metal's tint plus the
    /// dielectric's white specular and its diffuse and transmitted parts (both
    /// tinted by `c`). Roughness is ignored (no masking loss), and so is the
    /// interface seen from inside a volume. A smooth metal gives its specular
    /// tint, clear smooth glass about 1.
    pub fn albedo(&self, cos_o: f32) -> Vec3A {
        let cos = cos_o.abs().min(1.0);
        let (m, s) = (self.metallic, self.specular);
        let fd = self.fresnel_air(self.f0(), cos);
        let dielectric = s * fd + (1.0 - s * fd.max_element()) * self.base_tint();
        let mut a = m * self.fresnel_m(cos) + (1.0 - m) * dielectric;
        if self.has_sheen() {
            let e = sheen::albedo(cos, self.sheen_roughness);
            a = a * (1.0 - self.sheen_color.max_element() * e) + self.sheen_color * e;
        }
        if self.coat > 0.0 {
            // About the shading normal (the coat's tilt is ignored here).
            let w = self.coat * schlick_grey(COAT_F0, cos);
            a = a * (1.0 - w) + Vec3A::splat(w);
        }
        if a.is_finite() {
            a.clamp(Vec3A::ZERO, Vec3A::ONE)
        } else {
            Vec3A::ZERO
        }
    }

    /// [`Material::guide_lobes`] of this BSDF: with `α ≤` [`GUIDE_ALPHA`],
    /// the metal's and the dielectric's specular reflection (their Fresnel
    /// terms at `cos θo`, as the smooth lobes of [`PbrBsdf::sample`]) along
    /// the mirror direction, the transmission (refracted through a volume,
    /// straight through a thin wall; none under total internal reflection)
    /// and the diffuse part as the rough albedo; rougher, the whole
    /// [`PbrBsdf::albedo`] is rough.
    ///
    /// A clear coat scales all of these by `1 − w F_c` and adds its own
    /// reflection: along its mirror direction where it is smooth (taking the
    /// reflection's place, with the base's reflected value added), to the
    /// rough part otherwise.
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        let Some(l) = self.local(wo) else {
            return GuideLobes::NONE;
        };
        let base = self.sheen_guide_lobes(self.base_guide_lobes(wo, &l), &l);
        let Some(coat) = l.coat else {
            return base;
        };
        let under = 1.0 - coat.weight;
        let scaled = |lobe: Option<(Vec3A, Vec3A)>| lobe.map(|(wi, v)| (wi, v * under));
        let w = Vec3A::splat(coat.weight);
        if self.coat_alpha > GUIDE_ALPHA {
            return GuideLobes {
                rough: super::unit_range(base.rough * under + w),
                reflect: scaled(base.reflect),
                transmit: scaled(base.transmit),
            };
        }
        let wi = l.map(coat.frame.to_world(reflect_z(coat.wo)));
        let reflected = base.reflect.map_or(Vec3A::ZERO, |(_, v)| v * under);
        GuideLobes {
            rough: base.rough * under,
            reflect: GuideLobes::lobe(wi, w + reflected),
            transmit: scaled(base.transmit),
        }
    }

    /// `base`'s guides under a sheen: scaled by `1 − max(C) E(μo)`, the
    /// sheen's albedo added to the rough part.
    fn sheen_guide_lobes(&self, base: GuideLobes, l: &Local) -> GuideLobes {
        if !l.sheen {
            return base;
        }
        let keep = 1.0 - l.sheen_o;
        let scaled = |lobe: Option<(Vec3A, Vec3A)>| lobe.map(|(wi, v)| (wi, v * keep));
        let e = sheen::albedo(l.wo.z, self.sheen_roughness);
        GuideLobes {
            rough: super::unit_range(base.rough * keep + self.sheen_color * e),
            reflect: scaled(base.reflect),
            transmit: scaled(base.transmit),
        }
    }

    /// [`PbrBsdf::guide_lobes`] of the material under the sheen and the coat.
    fn base_guide_lobes(&self, wo: Vec3A, l: &Local) -> GuideLobes {
        let l = *l;
        if self.alpha_t() > GUIDE_ALPHA {
            return GuideLobes::rough(self.albedo(wo.z));
        }
        let wo_l = l.wo;
        let cos_o = wo_l.z.min(1.0);
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let fd = self.fresnel_d(l.f0, cos_o, l.inside);
        let kd = 1.0 - s * fd.max_element();
        let reflect = m * self.fresnel_m(cos_o) + (1.0 - m) * s * fd;
        let transmit = if self.transmission_scale() > 0.0 {
            let wi = if l.volume {
                refract(wo_l, Vec3A::Z, self.eta(&l))
            } else {
                Some(-wo_l)
            };
            wi.and_then(|wi| GuideLobes::lobe(l.map(wi), c * (self.transmission_scale() * kd)))
        } else {
            None
        };
        GuideLobes {
            rough: super::unit_range(self.diffuse_tint() * (self.diffuse_scale() * kd)),
            reflect: GuideLobes::lobe(l.map(reflect_z(wo_l)), reflect),
            transmit,
        }
    }

    /// Whether the diffuse part can be non-zero anywhere: `(1 − m)(1 − tr)` and the
    /// base colour positive and `s max(F0) < 1` (`1 − s max(F)` is largest at
    /// normal incidence on the microfacet, where `F = F0`).
    #[inline]
    fn has_diffuse(&self) -> bool {
        (self.diffuse_scale() * luminance(self.base_color) > 0.0 || self.transmits_diffusely())
            && self.kd_max() > 0.0
    }

    /// Whether the diffuse part has a transmitted share
    /// (`KHR_materials_diffuse_transmission`) that can carry light: the
    /// surface is then lit from behind too.
    #[inline]
    pub fn transmits_diffusely(&self) -> bool {
        self.diffuse_transmission > 0.0
            && self.diffuse_scale() * luminance(self.diffuse_transmission_color) > 0.0
    }

    /// The diffuse part's albedo per unit weight: `c` reflected, mixed with
    /// the diffuse transmission's colour by its share.
    #[inline]
    fn diffuse_tint(&self) -> Vec3A {
        let dt = self.diffuse_transmission;
        if dt > 0.0 {
            self.base_color * (1.0 - dt) + self.diffuse_transmission_color * dt
        } else {
            self.base_color
        }
    }

    /// The tint of everything under the dielectric's specular layer: the
    /// diffuse part's ([`PbrBsdf::diffuse_tint`]) and the transmission's
    /// (`c`), mixed by the transmission.
    #[inline]
    fn base_tint(&self) -> Vec3A {
        if self.diffuse_transmission > 0.0 {
            let tr = self.transmission;
            self.diffuse_tint() * (1.0 - tr) + self.base_color * tr
        } else {
            self.base_color
        }
    }

    #[inline]
    fn diffuse_scale(&self) -> f32 {
        (1.0 - self.metallic) * (1.0 - self.transmission)
    }

    #[inline]
    fn transmission_scale(&self) -> f32 {
        (1.0 - self.metallic) * self.transmission
    }

    /// The dielectric `F0`: `min(((ior − 1)/(ior + 1))² specular_color, 1)`.
    #[inline]
    fn f0(&self) -> Vec3A {
        let r = (self.ior - 1.0) / (self.ior + 1.0);
        (r * r * self.specular_color).min(Vec3A::ONE)
    }

    /// `1 − s max(F0)`: the largest value of the base's Fresnel factor
    /// `1 − s max(F)` (Schlick's `F ≥ F0`). With a film mixed in by `ι`, whose
    /// term is at least 0, `F ≥ (1 − ι) F0`: the bound is `1 − s (1 − ι) max(F0)`.
    #[inline]
    fn kd_max(&self) -> f32 {
        self.kd_max_of(self.f0())
    }

    /// [`PbrBsdf::kd_max`] with the dielectric's `F0` at hand.
    #[inline]
    fn kd_max_of(&self, f0: Vec3A) -> f32 {
        let sf = self.specular * f0.max_element();
        if self.film().is_some() {
            1.0 - sf * (1.0 - self.iridescence.min(1.0))
        } else {
            1.0 - sf
        }
    }

    /// The cosine on the air side of the interface for the microfacet cosine
    /// `cos` of a direction on `wo`'s side: `cos` itself outside, the refracted
    /// cosine inside; `None` under total internal reflection.
    #[inline]
    fn air_cos(&self, cos: f32, inside: bool) -> Option<f32> {
        if !inside {
            return Some(cos);
        }
        let sin2 = (1.0 - cos * cos).max(0.0) * (self.ior * self.ior);
        if sin2 < 1.0 {
            Some((1.0 - sin2).sqrt())
        } else {
            None
        }
    }

    /// The dielectric's Fresnel term for a reflected pair with `|wo·h| = cos` on
    /// `wo`'s side: Schlick at the air-side cosine, 1 under total internal
    /// reflection.
    #[inline]
    fn fresnel_d(&self, f0: Vec3A, cos: f32, inside: bool) -> Vec3A {
        match self.air_cos(cos, inside) {
            Some(c) => self.fresnel_air(f0, c),
            None => Vec3A::ONE,
        }
    }

    /// The canonical frame and lobe probabilities for `wo`; `None` for a
    /// degenerate `wo` or a material that scatters nothing.
    pub fn local(&self, wo: Vec3A) -> Option<Local> {
        if !wo.is_finite() || wo.z == 0.0 {
            return None;
        }
        let flip = wo.z < 0.0;
        let volume = self.transmission > 0.0 && !self.thin_walled;
        let inside = volume && flip;
        let wo = if flip {
            Vec3A::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        let smooth = Material::is_smooth(self.alpha_t());
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let f0 = self.f0();
        let kd_max = self.kd_max_of(f0);
        let cos_o = wo.z.min(1.0);
        let air = self.air_cos(cos_o, inside);
        let fd = air.map_or(1.0, |a| self.fresnel_air(f0, a).max_element());
        let fm = self.fresnel_m(cos_o).max_element();
        let lum = luminance(c);
        let kd = 1.0 - s * fd;
        let (w_spec, w_trans) = if smooth {
            // Delta lobes: probabilities proportional to their exact values
            // (no transmission under total internal reflection).
            let tir = volume && air.is_none();
            let w_trans = if tir {
                0.0
            } else {
                self.transmission_scale() * lum * kd
            };
            (m * fm + (1.0 - m) * s * fd, w_trans)
        } else {
            let w_trans = if kd_max > 0.0 {
                self.transmission_scale() * lum * kd.max(KD_FLOOR * kd_max)
            } else {
                0.0
            };
            (
                m * fm.max(SPEC_FLOOR) + (1.0 - m) * s * fd.max(SPEC_FLOOR),
                w_trans,
            )
        };
        // As has_diffuse(), with what is at hand.
        let w_diff = if self.diffuse_scale() * lum > 0.0 && kd_max > 0.0 {
            self.diffuse_scale() * lum * kd.max(KD_FLOOR * kd_max)
        } else {
            0.0
        };
        // The diffuse part's transmitted share takes its weight from the
        // reflected one's (which is then the same number for dt = 0).
        let dt = self.diffuse_transmission;
        let (w_diff, w_dtrans) = if self.transmits_diffusely() && kd_max > 0.0 {
            let lum_t = luminance(self.diffuse_transmission_color);
            let w = self.diffuse_scale() * kd.max(KD_FLOOR * kd_max);
            (w_diff * (1.0 - dt), w * lum_t * dt)
        } else {
            (w_diff, 0.0)
        };
        // Negative inputs (out of range) count as absent lobes.
        let (mut w_spec, mut w_diff, mut w_trans, mut w_dtrans) = (
            w_spec.max(0.0),
            w_diff.max(0.0),
            w_trans.max(0.0),
            w_dtrans.max(0.0),
        );
        let sheen = self.has_sheen();
        let (mut w_sheen, mut sheen_o) = (0.0, 0.0);
        if sheen && !inside {
            let e = sheen::albedo(cos_o, self.sheen_roughness);
            sheen_o = self.sheen_color.max_element() * e;
            let keep = 1.0 - sheen_o;
            (w_spec, w_diff, w_trans, w_dtrans) = (
                w_spec * keep,
                w_diff * keep,
                w_trans * keep,
                w_dtrans * keep,
            );
            // Floored: the lobe reflects somewhere wherever its colour is
            // not black, and may be the only non-delta lobe.
            w_sheen = luminance(self.sheen_color).max(SPEC_FLOOR) * e.max(SHEEN_FLOOR);
        }
        let coat = self.coat_local(wo, flip, inside);
        let mut w_coat = 0.0;
        if let Some(c) = &coat {
            let base = 1.0 - c.weight;
            (w_spec, w_diff, w_trans, w_dtrans) = (
                w_spec * base,
                w_diff * base,
                w_trans * base,
                w_dtrans * base,
            );
            w_sheen *= base;
            w_coat = c.weight;
        }
        let total = w_spec + w_diff + w_trans + w_dtrans + w_sheen + w_coat;
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let inv = total.recip();
        Some(Local {
            wo,
            flip,
            inside,
            volume,
            smooth,
            ggx: self.ggx(),
            f0,
            p_spec: w_spec * inv,
            p_diff: w_diff * inv,
            p_trans: w_trans * inv,
            p_sheen: w_sheen * inv,
            p_dtrans: w_dtrans * inv,
            p_coat: w_coat * inv,
            sheen,
            sheen_o,
            coat,
        })
    }

    /// The coat at `wo` (canonical, mirrored if `flip`): none without a coat,
    /// seen from inside a volume, or with `wo` below the coat's horizon.
    #[inline]
    fn coat_local(&self, wo: Vec3A, flip: bool, inside: bool) -> Option<CoatLocal> {
        // (`coat` may be NaN: no coat then either.)
        if self.coat.is_nan() || self.coat <= 0.0 || inside {
            return None;
        }
        // Mirrored with the rest, the back's coat normal is −n_c seen from
        // the mirrored side: (−x, −y, z).
        let n = self.coat_normal;
        let n = if flip { Vec3A::new(-n.x, -n.y, n.z) } else { n };
        let frame = Frame::from_normal(n);
        let wo_c = frame.to_local(wo);
        (wo_c.z > 0.0 && wo_c.is_finite()).then(|| CoatLocal {
            frame,
            wo: wo_c,
            weight: self.coat.min(1.0) * schlick_grey(COAT_F0, wo_c.z.min(1.0)),
        })
    }

    /// The rough coat's `f |cos θi|` (about its normal, times `w F_c`) and
    /// its density for `wi` (canonical frame); zero for a smooth coat, or
    /// `wi` below the shading or the coat's horizon.
    #[inline]
    fn coat_eval_pdf(&self, c: &CoatLocal, wi: Vec3A) -> (f32, f32) {
        if wi.z <= 0.0 || self.coat_smooth() {
            return (0.0, 0.0);
        }
        let wi_c = c.frame.to_local(wi);
        if wi_c.z <= 0.0 {
            return (0.0, 0.0);
        }
        let a = self.coat_alpha;
        let h = (c.wo + wi_c).normalize();
        let d = ggx_d(a, h);
        let f = c.weight * ((d * g2(a, c.wo, wi_c)) / (4.0 * c.wo.z));
        let p = (g1(a, c.wo) * d) / (4.0 * c.wo.z);
        (f, p)
    }

    /// The generalized half vector of a refracted pair (`wo.z > 0 > wi.z`, `eta`
    /// the index of `wi`'s side over `wo`'s) and `(wo·h, wi·h)`, if both face it
    /// the right way (`wo·h > 0 > wi·h`).
    #[inline]
    fn refraction_half(wo: Vec3A, wi: Vec3A, eta: f32) -> Option<(Vec3A, f32, f32)> {
        let h = wo + eta * wi;
        let len2 = h.length_squared();
        if !(len2 > 0.0 && len2.is_finite()) {
            return None;
        }
        let h = h * (len2.sqrt().recip() * h.z.signum());
        let (cos_oh, cos_ih) = (wo.dot(h), wi.dot(h));
        (cos_oh > 0.0 && cos_ih < 0.0).then_some((h, cos_oh, cos_ih))
    }

    /// Relative index across the interface, `wi`'s side over `wo`'s.
    #[inline]
    fn eta(&self, l: &Local) -> f32 {
        if l.inside { 1.0 / self.ior } else { self.ior }
    }

    /// `f |cos θi|` of the non-delta lobes in the canonical frame (`l.wo.z > 0`).
    fn eval_local(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let base = self.eval_base(l, wi);
        let base = if l.sheen {
            self.add_sheen(l, wi, base, 0.0).0
        } else {
            base
        };
        match &l.coat {
            Some(c) => base * (1.0 - c.weight) + Vec3A::splat(self.coat_eval_pdf(c, wi).0),
            None => base,
        }
    }

    /// [`PbrBsdf::eval_local`] of the material under the coat.
    fn eval_base(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let wo = l.wo;
        let (m, s) = (self.metallic, self.specular);
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let cos_oh = wo.dot(h).min(1.0);
            let fd = self.fresnel_d(l.f0, cos_oh, l.inside);
            let kd = 1.0 - s * fd.max_element();
            let mut f = self.reflected_diffuse() * (self.diffuse_scale() * kd * FRAC_1_PI * wi.z);
            if !l.smooth {
                // D G2 / (4 cos θo); the numerator first so that a subnormal
                // cos θo next to G2 = 0 gives 0, not 0 · ∞.
                let spec = (l.ggx.d(h) * l.ggx.g2(wo, wi)) / (4.0 * wo.z);
                f += (m * self.fresnel_m(cos_oh) + (1.0 - m) * s * fd) * spec;
            }
            f
        } else if wi.z < 0.0 {
            let f = if !l.smooth && self.transmission_scale() != 0.0 {
                self.eval_specular_transmission(l, wi)
            } else {
                Vec3A::ZERO
            };
            if self.transmits_diffusely() {
                f + self.eval_diffuse_transmission(l, wi)
            } else {
                f
            }
        } else {
            Vec3A::ZERO
        }
    }

    /// The base colour's share in the diffuse reflection: `(1 − dt) c`.
    #[inline]
    fn reflected_diffuse(&self) -> Vec3A {
        let dt = self.diffuse_transmission;
        if dt > 0.0 {
            self.base_color * (1.0 - dt)
        } else {
            self.base_color
        }
    }

    /// The rough transmission's `f |cos θi|` for `wi.z < 0` (canonical frame).
    #[inline]
    fn eval_specular_transmission(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let wo = l.wo;
        let (s, c) = (self.specular, self.base_color);
        if l.volume {
            let eta = self.eta(l);
            let Some((h, cos_oh, cos_ih)) = Self::refraction_half(wo, wi, eta) else {
                return Vec3A::ZERO;
            };
            let air = if l.inside { -cos_ih } else { cos_oh };
            let kd = 1.0 - s * self.fresnel_air(l.f0, air).max_element();
            let denom = cos_ih + cos_oh / eta;
            // D G2 |wi·h| |wo·h| / (cos θo (wi·h + wo·h/η)²), without 1/η².
            let t = (l.ggx.d(h) * l.ggx.g2(wo, wi) * (-cos_ih * cos_oh)) / (wo.z * denom * denom);
            c * (self.transmission_scale() * kd * t)
        } else {
            let wr = Vec3A::new(wi.x, wi.y, -wi.z);
            let h = (wo + wr).normalize();
            let cos_oh = wo.dot(h).min(1.0);
            let kd = 1.0 - s * self.fresnel_air(l.f0, cos_oh).max_element();
            let spec = (l.ggx.d(h) * l.ggx.g2(wo, wr)) / (4.0 * wo.z);
            c * (self.transmission_scale() * kd * spec)
        }
    }

    /// `KHR_materials_diffuse_transmission`'s `f |cos θi|` for `wi.z < 0`
    /// (canonical frame): `(1 − m)(1 − tr) (1 − s max(F)) dt c_t |cos θi| / π`,
    /// the diffuse reflection's terms with `wi` mirrored through the surface
    /// (so the Fresnel term takes the half vector of `wo` and the mirrored
    /// `wi`, as the rough thin-walled transmission's does): a white diffuse
    /// part then transmits exactly what it no longer reflects.
    #[inline]
    fn eval_diffuse_transmission(&self, l: &Local, wi: Vec3A) -> Vec3A {
        let wr = Vec3A::new(wi.x, wi.y, -wi.z);
        let h = (l.wo + wr).normalize();
        let cos_oh = l.wo.dot(h).min(1.0);
        let kd = 1.0 - self.specular * self.fresnel_d(l.f0, cos_oh, l.inside).max_element();
        self.diffuse_transmission_color
            * (self.diffuse_scale() * self.diffuse_transmission * kd * FRAC_1_PI * wr.z)
    }

    /// [`PbrBsdf::eval_local`] and [`PbrBsdf::pdf_local`] together, the
    /// reflection's half vector and `D` computed once: the same two values
    /// bit for bit.
    #[inline]
    fn eval_pdf_local(&self, l: &Local, wi: Vec3A) -> (Vec3A, f32) {
        let (f, p) = self.eval_pdf_base(l, wi);
        let (f, p) = if l.sheen {
            self.add_sheen(l, wi, f, p)
        } else {
            (f, p)
        };
        match &l.coat {
            Some(c) => {
                let (fc, pc) = self.coat_eval_pdf(c, wi);
                (f * (1.0 - c.weight) + Vec3A::splat(fc), p + l.p_coat * pc)
            }
            None => (f, p),
        }
    }

    /// [`PbrBsdf::eval_pdf_local`] of the material under the coat (its
    /// density already weighted by the lobes' probabilities).
    #[inline]
    fn eval_pdf_base(&self, l: &Local, wi: Vec3A) -> (Vec3A, f32) {
        if wi.z <= 0.0 {
            return (self.eval_base(l, wi), self.pdf_base(l, wi));
        }
        let wo = l.wo;
        let (m, s) = (self.metallic, self.specular);
        let h = (wo + wi).normalize();
        let cos_oh = wo.dot(h).min(1.0);
        let fd = self.fresnel_d(l.f0, cos_oh, l.inside);
        let kd = 1.0 - s * fd.max_element();
        let mut f = self.reflected_diffuse() * (self.diffuse_scale() * kd * FRAC_1_PI * wi.z);
        let mut p = l.p_diff * FRAC_1_PI * wi.z;
        if !l.smooth {
            let d = l.ggx.d(h);
            let spec = (d * l.ggx.g2(wo, wi)) / (4.0 * wo.z);
            f += (m * self.fresnel_m(cos_oh) + (1.0 - m) * s * fd) * spec;
            if l.p_spec > 0.0 {
                p += l.p_spec * ((l.ggx.g1(wo) * d) / (4.0 * wo.z));
            }
        }
        (f, p)
    }

    /// The mixture density of the non-delta lobes in the canonical frame.
    fn pdf_local(&self, l: &Local, wi: Vec3A) -> f32 {
        let mut p = self.pdf_base(l, wi);
        if l.sheen && wi.z > 0.0 {
            p += l.p_sheen * FRAC_1_PI * wi.z;
        }
        match &l.coat {
            Some(c) if l.p_coat > 0.0 => p + l.p_coat * self.coat_eval_pdf(c, wi).1,
            _ => p,
        }
    }

    /// The sheen over the base's `f |cos θi|` and density `(f, p)` at `wi`
    /// (canonical frame): `f` scaled by the albedo scaling, the sheen's value
    /// and density added.
    #[inline]
    fn add_sheen(&self, l: &Local, wi: Vec3A, f: Vec3A, p: f32) -> (Vec3A, f32) {
        let rho = self.sheen_roughness;
        let keep_i = || 1.0 - self.sheen_color.max_element() * sheen::albedo(wi.z.abs(), rho);
        if l.inside {
            // Out through the outside's sheen, or back into the volume.
            return (if wi.z < 0.0 { f * keep_i() } else { f }, p);
        }
        if wi.z <= 0.0 {
            let keep = if l.volume {
                1.0 - l.sheen_o
            } else {
                (1.0 - l.sheen_o).min(keep_i())
            };
            return (f * keep, p);
        }
        let scaling = (1.0 - l.sheen_o).min(keep_i());
        let value = self.sheen_color * sheen::eval(l.wo, wi, rho);
        (f * scaling + value, p + l.p_sheen * FRAC_1_PI * wi.z)
    }

    /// [`PbrBsdf::pdf_local`] of the lobes under the sheen and the coat.
    fn pdf_base(&self, l: &Local, wi: Vec3A) -> f32 {
        let wo = l.wo;
        if wi.z > 0.0 {
            let mut p = l.p_diff * FRAC_1_PI * wi.z;
            if !l.smooth && l.p_spec > 0.0 {
                let h = (wo + wi).normalize();
                // D_wo(h) / (4 |wo·h|) = G1(wo) D(h) / (4 cos θo).
                p += l.p_spec * ((l.ggx.g1(wo) * l.ggx.d(h)) / (4.0 * wo.z));
            }
            p
        } else if wi.z < 0.0 {
            let p = if !l.smooth && l.p_trans > 0.0 {
                self.pdf_specular_transmission(l, wi)
            } else {
                0.0
            };
            if l.p_dtrans > 0.0 {
                // The cosine lobe on the far side.
                p + l.p_dtrans * FRAC_1_PI * -wi.z
            } else {
                p
            }
        } else {
            0.0
        }
    }

    /// The rough transmission's density for `wi.z < 0`, times its probability.
    #[inline]
    fn pdf_specular_transmission(&self, l: &Local, wi: Vec3A) -> f32 {
        let wo = l.wo;
        if l.volume {
            let eta = self.eta(l);
            let Some((h, cos_oh, cos_ih)) = Self::refraction_half(wo, wi, eta) else {
                return 0.0;
            };
            let denom = cos_ih + cos_oh / eta;
            // D_wo(h) |dh/dwi| = G1(wo) D(h) (wo·h) / cos θo · |wi·h| / denom².
            l.p_trans * ((l.ggx.g1(wo) * l.ggx.d(h) * (cos_oh * -cos_ih)) / (wo.z * denom * denom))
        } else {
            let wr = Vec3A::new(wi.x, wi.y, -wi.z);
            let h = (wo + wr).normalize();
            l.p_trans * ((l.ggx.g1(wo) * l.ggx.d(h)) / (4.0 * wo.z))
        }
    }

    /// Whether `wo` and `wi` are on different sides (or one on the horizon) of a
    /// surface without a non-delta transmission lobe: nothing to evaluate (a
    /// shortcut past [`PbrBsdf::local`], e.g. for lights behind an opaque surface).
    #[inline]
    fn nothing_between(&self, wo: Vec3A, wi: Vec3A) -> bool {
        wo.z * wi.z <= 0.0
            && (self.transmission_scale() == 0.0 || Material::is_smooth(self.alpha_t()))
            && !self.transmits_diffusely()
    }

    /// `f(wo, wi) |cos θi|` of the non-delta lobes (zero for the delta lobes of a
    /// smooth surface). Never negative or non-finite for valid inputs.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if self.nothing_between(wo, wi) {
            return Vec3A::ZERO;
        }
        let Some(l) = self.local(wo) else {
            return Vec3A::ZERO;
        };
        if !wi.is_finite() {
            return Vec3A::ZERO;
        }
        finite_or_zero(self.eval_local(&l, l.map(wi)))
    }

    /// [`PbrBsdf::eval`] and [`PbrBsdf::pdf`] of one pair of directions, the
    /// lobes' probabilities and the half vector worked out once (next-event
    /// estimation needs both): the same values bit for bit.
    pub fn eval_pdf(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        self.eval_pdf_at(self.local(wo).as_ref(), wo, wi)
    }

    /// [`PbrBsdf::eval_pdf`] with `local` = [`PbrBsdf::local`]`(wo)` already
    /// worked out (a path vertex's light sample and BSDF sample share it).
    #[inline]
    pub fn eval_pdf_at(&self, local: Option<&Local>, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        if self.nothing_between(wo, wi) {
            return (Vec3A::ZERO, 0.0);
        }
        let Some(&l) = local else {
            return (Vec3A::ZERO, 0.0);
        };
        if !wi.is_finite() {
            return (Vec3A::ZERO, 0.0);
        }
        let (f, p) = self.eval_pdf_local(&l, l.map(wi));
        (finite_or_zero(f), if p.is_finite() { p } else { 0.0 })
    }

    /// Solid-angle density with which [`PbrBsdf::sample`] produces `wi` from its
    /// non-delta lobes (their mixture, weighted by the selection probabilities).
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if self.nothing_between(wo, wi) {
            return 0.0;
        }
        let Some(l) = self.local(wo) else {
            return 0.0;
        };
        if !wi.is_finite() {
            return 0.0;
        }
        let p = self.pdf_local(&l, l.map(wi));
        if p.is_finite() { p } else { 0.0 }
    }

    /// Draws `wi` for `wo`: `u_lobe` chooses the lobe, `u ∈ [0, 1)²` the
    /// direction. `None` for a degenerate `wo`, a black material, or a draw that
    /// leaves the lobe's side of the surface (or totally internally reflects).
    pub fn sample(&self, wo: Vec3A, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.sample_at(self.local(wo), u_lobe, u)
    }

    /// [`PbrBsdf::sample`] with `local` = [`PbrBsdf::local`]`(wo)` already
    /// worked out.
    #[inline]
    pub fn sample_at(&self, local: Option<Local>, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let l = local?;
        let wo_l = l.wo;
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let lobe = l.choose(u_lobe);
        // The base's share under the coat and the sheen (a delta's `wi` has
        // `wo`'s cosine, so the sheen's scaling is `1 − max(C) E(μo)`).
        let under = l.coat.map_or(1.0, |coat| 1.0 - coat.weight);
        let under = if l.sheen {
            under * (1.0 - l.sheen_o)
        } else {
            under
        };
        let wi = match lobe {
            Lobe::Coat => {
                let coat = l.coat?;
                let wi_c = if self.coat_smooth() {
                    reflect_z(coat.wo)
                } else {
                    let h = ggx_sample_visible_normal(self.coat_alpha, coat.wo, u);
                    let cos_oh = coat.wo.dot(h);
                    if cos_oh.is_nan() || cos_oh <= 0.0 {
                        return None;
                    }
                    (2.0 * cos_oh * h - coat.wo).normalize()
                };
                let wi = coat.frame.to_world(wi_c);
                if wi_c.z <= 0.0 || wi.z <= 0.0 {
                    return None;
                }
                if self.coat_smooth() {
                    return Self::delta(l.map(wi), Vec3A::splat(coat.weight), l.p_coat);
                }
                wi
            }
            Lobe::Specular if l.smooth => {
                let cos_o = wo_l.z.min(1.0);
                let value = m * self.fresnel_m(cos_o)
                    + (1.0 - m) * s * self.fresnel_d(l.f0, cos_o, l.inside);
                return Self::delta(l.map(reflect_z(wo_l)), value * under, l.p_spec);
            }
            Lobe::Transmission if l.smooth => {
                let cos_o = wo_l.z.min(1.0);
                let wi = if l.volume {
                    refract(wo_l, Vec3A::Z, self.eta(&l))?
                } else {
                    -wo_l
                };
                let kd = 1.0 - s * self.fresnel_d(l.f0, cos_o, l.inside).max_element();
                // Out of a volume, through the outside's sheen.
                let under = if l.sheen && l.inside {
                    let e = sheen::albedo(wi.z.abs(), self.sheen_roughness);
                    under * (1.0 - self.sheen_color.max_element() * e)
                } else {
                    under
                };
                let value = c * (self.transmission_scale() * kd * under);
                return Self::delta(l.map(wi), value, l.p_trans);
            }
            Lobe::Specular => {
                let h = l.ggx.sample_visible_normal(wo_l, u);
                let cos_oh = wo_l.dot(h);
                if cos_oh.is_nan() || cos_oh <= 0.0 {
                    return None;
                }
                (2.0 * cos_oh * h - wo_l).normalize()
            }
            Lobe::Diffuse | Lobe::Sheen => {
                let d = concentric_disk(u);
                Vec3A::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
            }
            Lobe::DiffuseTransmission => {
                let d = concentric_disk(u);
                Vec3A::new(d.x, d.y, -(1.0 - d.length_squared()).max(0.0).sqrt())
            }
            Lobe::Transmission => {
                let h = l.ggx.sample_visible_normal(wo_l, u);
                let cos_oh = wo_l.dot(h);
                if cos_oh.is_nan() || cos_oh <= 0.0 {
                    return None;
                }
                if l.volume {
                    refract(wo_l, h, self.eta(&l))?
                } else {
                    let wr = (2.0 * cos_oh * h - wo_l).normalize();
                    Vec3A::new(wr.x, wr.y, -wr.z)
                }
            }
        };
        // The lobe's side: a draw across the horizon is lost (the pdf of the
        // other side does not include it).
        let side_ok = match lobe {
            Lobe::Transmission | Lobe::DiffuseTransmission => wi.z < 0.0,
            _ => wi.z > 0.0,
        };
        if !side_ok || !wi.is_finite() {
            return None;
        }
        // The same computation as pdf() and eval(): the returned pdf is
        // bit-identical to pdf(wo, wi) (MIS) and weight = eval / pdf.
        let pdf = self.pdf_local(&l, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval_local(&l, wi) / pdf;
        if !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: l.map(wi),
            weight,
            pdf,
            specular: false,
        })
    }

    /// A delta lobe's sample: `weight = value / probability`.
    #[inline]
    fn delta(wi: Vec3A, value: Vec3A, prob: f32) -> Option<BsdfSample> {
        let weight = value / prob;
        if !(prob > 0.0 && weight.is_finite() && wi.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf: prob,
            specular: true,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::super::{ALPHA_SMOOTH, fresnel_dielectric};
    use super::*;

    /// All χ² tests of this module, for the Šidák correction.
    const CHI2_TESTS: u32 = 3 * 3 * 2 + 4 + 4 + 4 + 2 + 5 + 10 + 5;

    const COLOR: Vec3A = Vec3A::new(0.8, 0.5, 0.2);

    /// A transmitting material with a refracting volume.
    fn volume(base: Vec3A, metallic: f32, roughness: f32, transmission: f32) -> PbrBsdf {
        PbrBsdf {
            transmission,
            thin_walled: false,
            ..PbrBsdf::new(base, metallic, roughness)
        }
    }

    /// A thin-walled transmitting material.
    fn thin(base: Vec3A, metallic: f32, roughness: f32, transmission: f32) -> PbrBsdf {
        PbrBsdf {
            transmission,
            ..PbrBsdf::new(base, metallic, roughness)
        }
    }

    fn flip(w: Vec3A) -> Vec3A {
        Vec3A::new(w.x, w.y, -w.z)
    }

    /// Schlick's `F` for a grey `F0`, written out independently of the module.
    fn schlick1(f0: f32, cos: f32) -> f32 {
        f0 + (1.0 - f0) * (1.0 - cos).powi(5)
    }

    // ------------------------------------------------- χ² goodness of fit

    fn chi2_cases(cases: &[(PbrBsdf, Vec3A, &str)], key: u64) {
        let mut min_p = 1.0f64;
        for (i, (p, wo, what)) in cases.iter().enumerate() {
            let pv = chi2_p_value(Material::Pbr(*p), *wo, key + i as u64);
            eprintln!("chi2 pbr {what}: p = {pv:.4}");
            assert!(pv > sidak_threshold(CHI2_TESTS), "{what}: p = {pv}, {p:?}");
            min_p = min_p.min(pv);
        }
        eprintln!("chi2 pbr: min p = {min_p:.4}");
    }

    fn chi2_opaque(metallic: f32, key: u64) {
        let mut cases = Vec::new();
        for roughness in [0.2f32, 0.5, 1.0] {
            for theta in [10.0f32, 45.0, 80.0] {
                let p = PbrBsdf::new(COLOR, metallic, roughness);
                let what = format!("m={metallic} r={roughness} θo={theta}");
                cases.push((p, dir(theta, 0.3), what));
            }
        }
        let cases: Vec<_> = cases.iter().map(|(p, w, s)| (*p, *w, s.as_str())).collect();
        chi2_cases(&cases, key);
    }

    #[test]
    fn chi2_dielectric_sampling_matches_pdf() {
        chi2_opaque(0.0, 300);
    }

    #[test]
    fn chi2_metal_sampling_matches_pdf() {
        chi2_opaque(1.0, 400);
    }

    #[test]
    fn chi2_transmission_sampling_matches_pdf() {
        chi2_cases(
            &[
                (
                    volume(Vec3A::ONE, 0.0, 0.5, 1.0),
                    dir(45.0, 0.3),
                    "volume outside",
                ),
                // From inside, beyond the critical angle of the macro surface
                // (41.8°): rough microfacets still let some light out.
                (
                    volume(COLOR, 0.2, 0.5, 0.6),
                    -dir(50.0, 0.3),
                    "volume inside, mixed",
                ),
                (thin(COLOR, 0.0, 0.5, 1.0), dir(45.0, 0.3), "thin-walled"),
                (
                    thin(COLOR, 0.3, 0.5, 0.5),
                    -dir(80.0, 2.0),
                    "thin-walled back side, mixed",
                ),
            ],
            500,
        );
    }

    /// `base` under a clear coat of weight `coat` and roughness
    /// `coat_roughness`, its normal tilted by `tilt` degrees from the shading
    /// normal.
    fn coated(base: PbrBsdf, coat: f32, coat_roughness: f32, tilt: f32) -> PbrBsdf {
        PbrBsdf {
            coat,
            coat_alpha: PbrBsdf::alpha_from_roughness(coat_roughness),
            coat_normal: dir(tilt, 1.1),
            ..base
        }
    }

    /// Coated materials: rough and smooth coats over rough, smooth, metal,
    /// dielectric and transmitting bases, with straight and tilted coat
    /// normals.
    fn coated_materials() -> Vec<PbrBsdf> {
        vec![
            coated(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 0.2, 0.0),
            coated(PbrBsdf::new(COLOR, 1.0, 0.6), 0.7, 0.4, 20.0),
            coated(PbrBsdf::new(COLOR, 0.0, 0.7), 1.0, 0.0, 0.0),
            coated(PbrBsdf::new(COLOR, 0.3, 0.0), 0.5, 0.3, 10.0),
            coated(thin(COLOR, 0.0, 0.4, 0.6), 1.0, 0.1, 0.0),
            coated(volume(COLOR, 0.0, 0.3, 0.8), 1.0, 0.3, 15.0),
        ]
    }

    #[test]
    fn chi2_coat_sampling_matches_pdf() {
        chi2_cases(
            &[
                (
                    coated(PbrBsdf::new(COLOR, 0.0, 0.6), 1.0, 0.3, 0.0),
                    dir(40.0, 0.3),
                    "coat over dielectric",
                ),
                (
                    coated(PbrBsdf::new(COLOR, 1.0, 0.5), 0.8, 0.2, 25.0),
                    dir(70.0, 0.3),
                    "tilted coat over metal",
                ),
                (
                    coated(PbrBsdf::new(COLOR, 0.0, 0.4), 1.0, 0.5, 0.0),
                    -dir(30.0, 1.3),
                    "coat, back side",
                ),
                (
                    coated(thin(COLOR, 0.0, 0.5, 0.7), 0.6, 0.25, 10.0),
                    dir(60.0, 2.0),
                    "coat over a thin wall",
                ),
            ],
            600,
        );
    }

    /// Over a base that reflects nothing (black, no specular), a smooth coat
    /// is a mirror about its normal whose weight is exactly the coat weight
    /// times Schlick's Fresnel at `|wo·n_c|` with `F0` = 0.04 (written out
    /// here from the specification), from either side.
    #[test]
    fn smooth_coat_over_black_is_the_coats_fresnel() {
        let black = PbrBsdf {
            specular: 0.0,
            ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0)
        };
        for (weight, tilt) in [(1.0f32, 0.0f32), (0.6, 0.0), (1.0, 25.0)] {
            let p = coated(black, weight, 0.0, tilt);
            let m = Material::Pbr(p);
            assert!(p.is_specular());
            for theta in [0.0f32, 30.0, 60.0, 80.0] {
                let wo = dir(theta, 1.1 + 0.3 * theta.to_radians());
                let n = p.coat_normal;
                let cos = wo.dot(n);
                let expected = weight * (0.04 + 0.96 * (1.0 - cos).powi(5));
                for ul in [0.0, 0.5, 0.999_999] {
                    let s = m.sample(wo, ul, Vec2::new(0.3, 0.6));
                    let Some(s) = s else {
                        // Only where the mirror about a tilted normal dips
                        // below the shading horizon.
                        assert!(tilt > 0.0 && (2.0 * cos * n - wo).z <= 0.0);
                        continue;
                    };
                    assert!(s.specular && (s.pdf - 1.0).abs() < 1e-6, "{s:?}");
                    let value = s.weight.x * s.pdf;
                    assert!(
                        (value - expected).abs() < 1e-6 && s.weight.x == s.weight.z,
                        "θo = {theta}, tilt {tilt}: {value} against {expected}"
                    );
                    assert!((s.wi - (2.0 * cos * n - wo)).length() < 1e-5);
                    // From the back, mirrored: the same Fresnel.
                    if tilt == 0.0 {
                        let back = m.sample(flip(wo), ul, Vec2::new(0.3, 0.6)).unwrap();
                        assert!((back.weight.x * back.pdf - expected).abs() < 1e-6);
                        assert!((back.wi - flip(s.wi)).length() < 1e-6);
                    }
                }
            }
        }
    }

    /// White furnaces: a clear coat over a white metal (which loses nothing
    /// when smooth) never reflects more than it receives, at any angle, coat
    /// roughness and tilt; smooth over smooth it loses nothing either.
    #[test]
    fn furnace_coat_over_white_metal() {
        let n = 60_000;
        for base_roughness in [0.0f32, 0.4] {
            for (coat_roughness, tilt) in [(0.0f32, 0.0f32), (0.1, 0.0), (0.5, 0.0), (0.3, 20.0)] {
                let p = coated(
                    PbrBsdf::new(Vec3A::ONE, 1.0, base_roughness),
                    1.0,
                    coat_roughness,
                    tilt,
                );
                for theta in [0.0f32, 45.0, 80.0] {
                    let (a, se) = albedo(Material::Pbr(p), dir(theta, 0.7), n, 800);
                    let what = format!(
                        "base r={base_roughness} coat r={coat_roughness} tilt {tilt} θo={theta}"
                    );
                    assert!(a < 1.0 + 4.0 * se + 1e-4, "{what}: albedo {a} ± {se}");
                    if base_roughness == 0.0 && coat_roughness == 0.0 && tilt == 0.0 {
                        assert!((a - 1.0).abs() < 1e-5, "{what}: {a}");
                    } else {
                        // Single scattering loses some, not most.
                        assert!(a > 0.6, "{what}: albedo {a}");
                    }
                }
            }
        }
    }

    fn sheened(base: PbrBsdf, color: Vec3A, roughness: f32) -> PbrBsdf {
        PbrBsdf {
            sheen_color: color,
            sheen_roughness: roughness,
            ..base
        }
    }

    /// Materials with a sheen: over rough and smooth dielectrics, a smooth
    /// metal (the sheen its only non-delta lobe), a black base, thin and
    /// volume transmission, and under a clear coat.
    fn sheened_materials() -> Vec<PbrBsdf> {
        let sheen = Vec3A::new(0.9, 0.4, 0.2);
        vec![
            sheened(PbrBsdf::new(COLOR, 0.0, 0.7), sheen, 0.5),
            sheened(PbrBsdf::new(COLOR, 1.0, 0.0), Vec3A::ONE, 0.3),
            sheened(PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5), sheen, 1.0),
            sheened(thin(COLOR, 0.0, 0.4, 0.6), sheen, 0.2),
            sheened(volume(COLOR, 0.0, 0.3, 0.8), sheen, 0.8),
            coated(
                sheened(PbrBsdf::new(COLOR, 0.0, 0.6), sheen, 0.4),
                1.0,
                0.2,
                10.0,
            ),
        ]
    }

    #[test]
    fn chi2_sheen_sampling_matches_pdf() {
        let sheen = Vec3A::new(0.9, 0.4, 0.2);
        chi2_cases(
            &[
                (
                    sheened(PbrBsdf::new(COLOR, 0.0, 0.6), sheen, 0.5),
                    dir(70.0, 0.3),
                    "sheen over dielectric",
                ),
                (
                    sheened(PbrBsdf::new(COLOR, 1.0, 0.3), Vec3A::ONE, 0.25),
                    dir(50.0, 0.3),
                    "sheen over rough metal",
                ),
                (
                    coated(
                        sheened(PbrBsdf::new(COLOR, 0.0, 0.4), sheen, 0.8),
                        1.0,
                        0.3,
                        0.0,
                    ),
                    dir(30.0, 1.0),
                    "coat over sheen",
                ),
                (
                    sheened(thin(COLOR, 0.0, 0.5, 0.7), sheen, 0.3),
                    -dir(80.0, 2.0),
                    "sheen over a thin wall, back side",
                ),
            ],
            700,
        );
    }

    /// A sheen over a base that reflects nothing reflects exactly its
    /// colour times the tabulated albedo `E(μo, ρ)` (estimated here by
    /// sampling the BSDF, not from the table), per channel.
    #[test]
    fn sheen_over_black_reflects_its_tabulated_albedo() {
        let black = PbrBsdf {
            specular: 0.0,
            ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5)
        };
        let color = Vec3A::new(1.0, 0.5, 0.25);
        for rho in [0.2f32, 0.5, 1.0] {
            for theta in [0.0f32, 50.0, 80.0] {
                let p = sheened(black, color, rho);
                let wo = dir(theta, 0.4);
                let (a, se) = albedo(Material::Pbr(p), wo, 200_000, 900);
                let e = sheen::albedo(wo.z, rho) as f64;
                assert!(
                    (a - e).abs() < 4.0 * se + 3e-3,
                    "ρ {rho} θo {theta}: sampled {a} ± {se}, table {e}"
                );
                // The other channels are the colour's share, sample by sample.
                let s = Material::Pbr(p)
                    .sample(wo, 0.5, Vec2::new(0.3, 0.7))
                    .unwrap();
                assert!((s.weight.y - 0.5 * s.weight.x).abs() <= 1e-6 * s.weight.x);
            }
        }
    }

    /// White furnaces: a white sheen over a white smooth metal (which loses
    /// nothing) never reflects more than it receives, at any angle and
    /// sheen roughness, grazing ones included (where the specification's
    /// Charlie BRDF alone would exceed 1); and it loses little.
    #[test]
    fn furnace_white_sheen_over_white_metal() {
        for rho in [0.0f32, 0.1, 0.3, 0.6, 1.0] {
            for theta in [0.0f32, 45.0, 80.0, 88.0] {
                let p = sheened(PbrBsdf::new(Vec3A::ONE, 1.0, 0.0), Vec3A::ONE, rho);
                let wo = dir(theta, 0.7);
                let (a, se) = albedo(Material::Pbr(p), wo, 60_000, 1000);
                let what = format!("sheen ρ={rho} θo={theta}");
                assert!(a < 1.0 + 4.0 * se + 1e-4, "{what}: albedo {a} ± {se}");
                assert!(a > 0.5, "{what}: albedo {a}");
                // A coat on top keeps it at most 1.
                let c = coated(p, 1.0, 0.3, 0.0);
                let (a, se) = albedo(Material::Pbr(c), wo, 60_000, 1001);
                assert!(
                    a < 1.0 + 4.0 * se + 1e-4,
                    "{what}, coated: albedo {a} ± {se}"
                );
            }
        }
    }

    // ------------------------------------------------------- iridescence

    /// The gold-like base colour of the iridescence tests.
    const GOLD: Vec3A = Vec3A::new(0.95, 0.64, 0.54);

    /// `base` under a thin film (`KHR_materials_iridescence`) of weight
    /// `iridescence`, index `ior` and thickness `d` nm.
    fn filmed(base: PbrBsdf, iridescence: f32, ior: f32, d: f32) -> PbrBsdf {
        PbrBsdf {
            iridescence,
            film_ior: ior,
            film_thickness: d,
            ..base
        }
    }

    /// Filmed materials: rough and smooth, metal, dielectric, mixed,
    /// transmitting (thin-walled and a volume) and under a clear coat.
    fn iridescent_materials() -> Vec<PbrBsdf> {
        vec![
            filmed(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 1.8, 350.0),
            filmed(PbrBsdf::new(GOLD, 1.0, 0.3), 1.0, 1.3, 500.0),
            filmed(PbrBsdf::new(COLOR, 0.4, 0.0), 0.7, 1.5, 250.0),
            filmed(thin(COLOR, 0.0, 0.4, 0.8), 1.0, 1.3, 550.0),
            filmed(volume(Vec3A::ONE, 0.0, 0.3, 1.0), 1.0, 1.3, 520.0),
            filmed(
                coated(PbrBsdf::new(COLOR, 0.2, 0.5), 1.0, 0.2, 0.0),
                1.0,
                1.3,
                400.0,
            ),
        ]
    }

    #[test]
    fn chi2_iridescent_sampling_matches_pdf() {
        let m = iridescent_materials();
        chi2_cases(
            &[
                (m[0], dir(30.0, 0.3), "film over a rough dielectric"),
                (m[1], dir(60.0, 0.3), "film over a rough metal"),
                (m[3], -dir(45.0, 2.0), "film on a thin wall, back side"),
                (m[4], -dir(50.0, 0.3), "film on a volume, inside"),
                (m[5], dir(70.0, 0.3), "film under a coat"),
            ],
            700,
        );
    }

    /// Mean sample weight per channel and its standard error.
    fn albedo_rgb(m: Material, wo: Vec3A, n: usize, key: u64) -> ([f64; 3], [f64; 3]) {
        let mut r = rng(key);
        let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let ul = r.next_f32();
            if let Some(s) = m.sample(wo, ul, u2(&mut r)) {
                for ch in 0..3 {
                    let w = s.weight[ch] as f64;
                    s1[ch] += w;
                    s2[ch] += w * w;
                }
            }
        }
        let n = n as f64;
        let mean = s1.map(|s| s / n);
        let se = std::array::from_fn(|ch| ((s2[ch] / n - mean[ch] * mean[ch]).max(0.0) / n).sqrt());
        (mean, se)
    }

    /// White furnaces with a film: the film changes the colour of the
    /// reflection, never the energy. A smooth white metal's reflection and
    /// a smooth white thin wall's reflection plus transmission (`F` and
    /// `1 − max F` per channel) are at most 1 in every channel, and the
    /// thin wall's brightest channel loses nothing; rough white metals, thin
    /// walls, volumes and a coat over a white metal never reflect more than
    /// they receive, at any angle, in any channel.
    #[test]
    fn furnace_iridescent_white() {
        let films = [(1.3f32, 100.0f32), (1.3, 400.0), (1.8, 550.0), (2.5, 250.0)];
        let mut colourful = 0.0f32;
        for (ior, d) in films {
            let metal = Material::Pbr(filmed(PbrBsdf::new(Vec3A::ONE, 1.0, 0.0), 1.0, ior, d));
            let wall = Material::Pbr(filmed(thin(Vec3A::ONE, 0.0, 0.0, 1.0), 1.0, ior, d));
            for theta in [0.0f32, 30.0, 60.0, 85.0] {
                let wo = dir(theta, 0.7);
                let s = metal.sample(wo, 0.5, Vec2::new(0.3, 0.6)).unwrap();
                let v = s.weight * s.pdf;
                assert!(
                    v.max_element() <= 1.0 + 1e-6,
                    "metal {ior} {d} θ {theta}: {v}"
                );
                let r = wall.sample(wo, 0.0, Vec2::new(0.3, 0.6)).unwrap();
                let t = wall.sample(wo, 0.999_999, Vec2::new(0.3, 0.6)).unwrap();
                assert!(r.wi.z > 0.0 && t.wi.z < 0.0 && r.specular && t.specular);
                let total = r.weight * r.pdf + t.weight * t.pdf;
                assert!(
                    total.max_element() <= 1.0 + 1e-5 && total.max_element() > 1.0 - 1e-5,
                    "thin wall {ior} {d} θ {theta}: {total}"
                );
                colourful = colourful.max(total.max_element() - total.min_element());
            }
        }
        // The film does colour the wall (else the test above says little).
        assert!(colourful > 0.05, "{colourful}");
        let n = 60_000;
        let rough = [
            filmed(PbrBsdf::new(Vec3A::ONE, 1.0, 0.3), 1.0, 1.3, 400.0),
            filmed(PbrBsdf::new(Vec3A::ONE, 1.0, 0.7), 1.0, 2.0, 300.0),
            filmed(thin(Vec3A::ONE, 0.0, 0.4, 1.0), 1.0, 1.8, 350.0),
            filmed(volume(Vec3A::ONE, 0.0, 0.3, 1.0), 1.0, 1.3, 520.0),
            filmed(
                coated(PbrBsdf::new(Vec3A::ONE, 1.0, 0.2), 1.0, 0.3, 0.0),
                1.0,
                1.8,
                300.0,
            ),
        ];
        for (i, p) in rough.into_iter().enumerate() {
            for theta in [0.0f32, 45.0, 80.0] {
                let (a, se) = albedo_rgb(Material::Pbr(p), dir(theta, 0.7), n, 900 + i as u64);
                for ch in 0..3 {
                    assert!(
                        a[ch] < 1.0 + 4.0 * se[ch] + 1e-4,
                        "material {i} θo={theta} channel {ch}: albedo {} ± {}",
                        a[ch],
                        se[ch]
                    );
                }
            }
        }
    }

    /// A film of thickness 0 is no film: the material is the one without
    /// it, bit for bit. As the thickness goes to 0 the film's reflection
    /// settles (continuously) on a limit within 0.01 of the base's own
    /// Schlick Fresnel at angles up to 40° (the specification's model is
    /// not exact there: its Schlick interfaces and the white point of its
    /// spectral integration leave that much; towards grazing angles its
    /// Schlick film interface reflects more, measured below). And `ι`
    /// mixes the two Fresnel terms linearly.
    #[test]
    fn a_film_of_no_thickness_is_no_film() {
        let mut r = rng(31);
        for base in test_materials().into_iter().chain(coated_materials()) {
            let p = filmed(base, 1.0, 1.8, 0.0);
            let (a, b) = (Material::Pbr(p), Material::Pbr(base));
            for _ in 0..2000 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                assert_eq!(a.eval(wo, wi), b.eval(wo, wi));
                assert_eq!(a.pdf(wo, wi), b.pdf(wo, wi));
                let (ul, u) = (r.next_f32(), u2(&mut r));
                assert_eq!(a.sample(wo, ul, u), b.sample(wo, ul, u));
            }
            assert_eq!(p.albedo(0.3), base.albedo(0.3));
        }
        let reflected = |p: PbrBsdf, theta: f32| {
            let s = Material::Pbr(p).sample(dir(theta, 0.2), 0.0, Vec2::new(0.5, 0.5));
            let s = s.unwrap();
            assert!(s.specular);
            s.weight * s.pdf
        };
        let black = PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0);
        let gold = PbrBsdf::new(GOLD, 1.0, 0.0);
        for (base, f0) in [(black, Vec3A::splat(0.04)), (gold, GOLD)] {
            for theta in [0.0f32, 20.0, 40.0, 70.0] {
                let limit = reflected(filmed(base, 1.0, 1.3, 1e-3), theta);
                for d in [0.1f32, 1.0] {
                    let f = reflected(filmed(base, 1.0, 1.3, d), theta);
                    assert!(
                        (f - limit).abs().max_element() < 1e-3,
                        "d {d}: {f} vs {limit}"
                    );
                }
                let cos = dir(theta, 0.2).z;
                let schlick = f0 + (Vec3A::ONE - f0) * (1.0 - cos).powi(5);
                let gap = (limit - schlick).abs().max_element();
                eprintln!("film → 0 at θ {theta}: {limit} against Schlick {schlick}: {gap:.4}");
                if theta <= 40.0 {
                    assert!(gap < 0.01, "θ {theta}: {limit} against {schlick}");
                }
                // ι mixes: half a film is halfway.
                let (none, full) = (
                    reflected(base, theta),
                    reflected(filmed(base, 1.0, 1.3, 300.0), theta),
                );
                let half = reflected(filmed(base, 0.5, 1.3, 300.0), theta);
                assert!((half - 0.5 * (none + full)).abs().max_element() < 1e-6);
            }
        }
    }

    /// `base` with `KHR_materials_diffuse_transmission`'s share `dt` and
    /// colour `color`.
    fn translucent(base: PbrBsdf, dt: f32, color: Vec3A) -> PbrBsdf {
        PbrBsdf {
            diffuse_transmission: dt,
            diffuse_transmission_color: color,
            ..base
        }
    }

    /// Diffusely transmitting materials: alone, smooth and rough, with
    /// (thin-walled and volume) transmission, metal, and a coat.
    fn translucent_materials() -> Vec<PbrBsdf> {
        let warm = Vec3A::new(1.0, 0.6, 0.3);
        vec![
            translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.6, warm),
            translucent(PbrBsdf::new(COLOR, 0.0, 0.0), 1.0, warm),
            translucent(PbrBsdf::new(COLOR, 0.4, 0.3), 0.5, Vec3A::ONE),
            translucent(thin(COLOR, 0.0, 0.4, 0.5), 0.7, warm),
            translucent(volume(COLOR, 0.0, 0.4, 0.3), 0.8, warm),
            translucent(volume(COLOR, 0.0, 0.5, 0.0), 0.5, warm),
            coated(
                translucent(PbrBsdf::new(COLOR, 0.0, 0.6), 0.5, warm),
                1.0,
                0.2,
                10.0,
            ),
        ]
    }

    #[test]
    fn chi2_diffuse_transmission_sampling_matches_pdf() {
        let warm = Vec3A::new(1.0, 0.6, 0.3);
        chi2_cases(
            &[
                (
                    translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.6, warm),
                    dir(40.0, 0.3),
                    "diffuse transmission",
                ),
                (
                    translucent(PbrBsdf::new(COLOR, 0.0, 0.25), 0.9, warm),
                    -dir(70.0, 1.3),
                    "diffuse transmission, back side",
                ),
                (
                    translucent(thin(COLOR, 0.2, 0.4, 0.5), 0.7, warm),
                    dir(60.0, 2.0),
                    "diffuse transmission and thin-walled transmission",
                ),
                (
                    translucent(volume(COLOR, 0.0, 0.5, 0.4), 0.8, warm),
                    -dir(30.0, 0.7),
                    "diffuse transmission and a volume, inside",
                ),
                (
                    coated(
                        translucent(PbrBsdf::new(COLOR, 0.0, 0.6), 0.5, warm),
                        1.0,
                        0.3,
                        0.0,
                    ),
                    dir(20.0, 0.5),
                    "diffuse transmission under a coat",
                ),
            ],
            700,
        );
    }

    /// White furnaces of `KHR_materials_diffuse_transmission`: without a
    /// specular layer (`specular` 0) the base is a white Lambertian lobe
    /// split between the two sides, which loses nothing at any angle,
    /// roughness and share (every sample weighs exactly 1); with the
    /// dielectric's specular layer the diffuse part transmits exactly what
    /// it no longer reflects, so the total (reflected + transmitted, by
    /// quadrature of eval) equals the opaque material's, and sampling finds
    /// the same value; head-on and at 45° that is below 1.
    #[test]
    fn furnace_diffuse_transmission() {
        for roughness in [0.0f32, 0.3, 1.0] {
            for dt in [0.3f32, 1.0] {
                let p = translucent(
                    PbrBsdf {
                        specular: 0.0,
                        ..PbrBsdf::new(Vec3A::ONE, 0.0, roughness)
                    },
                    dt,
                    Vec3A::ONE,
                );
                let m = Material::Pbr(p);
                for theta in [0.0f32, 45.0, 80.0] {
                    for wo in [dir(theta, 0.4), -dir(theta, 0.4)] {
                        let (a, se) = albedo(m, wo, 20_000, 900);
                        let what = format!("s=0 r={roughness} dt={dt} θo={theta} wo {wo}");
                        assert!((a - 1.0).abs() < 1e-5 && se < 1e-5, "{what}: {a} ± {se}");
                        // Both sides of the surface receive their share.
                        let t = albedo_by_quadrature(Material::Pbr(p), wo);
                        assert!(t > 0.99 && t < 1.01, "{what}: quadrature {t}");
                    }
                }
            }
        }
        for roughness in [0.2f32, 0.6] {
            for theta in [0.0f32, 45.0, 80.0] {
                let wo = dir(theta, 0.4);
                let opaque = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, roughness));
                let q_opaque = albedo_by_quadrature(opaque, wo);
                for dt in [0.5f32, 1.0] {
                    let p = translucent(PbrBsdf::new(Vec3A::ONE, 0.0, roughness), dt, Vec3A::ONE);
                    let m = Material::Pbr(p);
                    let q = albedo_by_quadrature(m, wo);
                    let (a, se) = albedo(m, wo, 100_000, 901);
                    let what = format!("s=1 r={roughness} dt={dt} θo={theta}");
                    eprintln!(
                        "furnace diffuse transmission {what}: MC {a:.5} ± {se:.5}, quadrature {q:.5}, opaque {q_opaque:.5}"
                    );
                    assert!(
                        (q - q_opaque).abs() < 2e-3,
                        "{what}: {q} vs opaque {q_opaque}"
                    );
                    assert!((a - q).abs() < 4.0 * se + 2e-3, "{what}: MC {a} vs {q}");
                    // Head-on the specified model loses a little; elsewhere it
                    // may gain what the opaque material gains (see
                    // `white_dielectric_is_brighter_than_white_at_grazing_angles`).
                    if theta == 0.0 {
                        assert!(a < 1.0 + 3.0 * se, "{what}: {a} ± {se}");
                    }
                }
            }
        }
        // Under a smooth coat over the lossless split: still exactly 1.
        let p = coated(
            translucent(
                PbrBsdf {
                    specular: 0.0,
                    ..PbrBsdf::new(Vec3A::ONE, 0.0, 0.5)
                },
                0.6,
                Vec3A::ONE,
            ),
            1.0,
            0.0,
            0.0,
        );
        for theta in [0.0f32, 60.0, 85.0] {
            let (a, se) = albedo(Material::Pbr(p), dir(theta, 0.2), 20_000, 902);
            assert!((a - 1.0).abs() < 1e-5, "coated, θo={theta}: {a} ± {se}");
        }
    }

    /// The diffuse transmission's value at a hand-computed pair: a smooth
    /// plate (its specular reflection and transmission are deltas, outside
    /// `eval`) of base colour `c`, metallic `m`, thin-walled transmission
    /// `tr`, share `dt` and colour `c_t`, seen head-on and lit from behind at
    /// 60°: `f |cos θi| = (1 − m)(1 − tr) (1 − F) dt c_t cos θi / π`, with
    /// `F` Schlick's at the half vector of `wo` and the mirrored `wi`
    /// (`wo·h = cos 30°`); nothing of `c` comes through. The mirrored pair
    /// reflects `(1 − dt)` of the opaque material's diffuse part, and the
    /// opaque material transmits nothing diffusely.
    #[test]
    fn diffuse_transmission_at_a_hand_computed_pair() {
        use std::f32::consts::PI;
        let (c, ct) = (Vec3A::new(0.2, 0.8, 0.3), Vec3A::new(1.0, 0.5, 0.25));
        let (m, tr, dt) = (0.25f32, 0.4f32, 0.7f32);
        let p = translucent(thin(c, m, 0.0, tr), dt, ct);
        let (wo, wi) = (Vec3A::Z, -dir(60.0, 0.0));
        let cos_oh = 30f32.to_radians().cos();
        let f = 0.04 + 0.96 * (1.0 - cos_oh).powi(5);
        // The diffuse part's weight at this pair times cos θi / π.
        let k = (1.0 - m) * (1.0 - tr) * (1.0 - f) * 0.5 / PI;
        let expected = ct * (k * dt);
        let got = p.eval(wo, wi);
        eprintln!("diffuse transmission at 60° behind: {got} (expected {expected})");
        assert!(rel_err(got, expected) < 1e-5, "{got} vs {expected}");
        // From the back, the same (two-sided).
        assert!(rel_err(p.eval(flip(wo), flip(wi)), expected) < 1e-5);
        // The mirrored pair reflects the rest of the diffuse part.
        let opaque = thin(c, m, 0.0, tr);
        let (reflected, want) = (p.eval(wo, flip(wi)), c * (k * (1.0 - dt)));
        assert!(rel_err(reflected, want) < 1e-5, "{reflected} vs {want}");
        assert!(rel_err(opaque.eval(wo, flip(wi)), c * k) < 1e-5);
        assert_eq!(opaque.eval(wo, wi), Vec3A::ZERO);
        assert!(Material::Pbr(p).transmits());
        assert!(!Material::Pbr(PbrBsdf::new(c, 0.0, 0.5)).transmits());
        // A full metal has no diffuse part to transmit.
        let metal = translucent(PbrBsdf::new(c, 1.0, 0.5), 1.0, ct);
        assert_eq!(metal.eval(wo, wi), Vec3A::ZERO);
        assert!(!metal.transmits_diffusely());
    }

    #[test]
    fn chi2_detects_wrong_pbr_pdfs() {
        // Sampling against the pdf of a slightly different material is rejected:
        // other lobe probabilities, and another roughness of the refraction lobe.
        let cases = [
            (
                PbrBsdf::new(COLOR, 0.5, 0.5),
                PbrBsdf::new(COLOR, 0.6, 0.5),
                dir(45.0, 0.3),
            ),
            (
                volume(Vec3A::ONE, 0.0, 0.5, 1.0),
                volume(Vec3A::ONE, 0.0, 0.55, 1.0),
                dir(45.0, 0.3),
            ),
            // The far side's share, claimed a little smaller.
            (
                translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.5, Vec3A::ONE),
                translucent(PbrBsdf::new(COLOR, 0.0, 0.5), 0.45, Vec3A::ONE),
                dir(45.0, 0.3),
            ),
        ];
        for (i, (m, claimed, wo)) in cases.into_iter().enumerate() {
            let p = chi2_p_value_of(Material::Pbr(m), Material::Pbr(claimed), wo, 600 + i as u64);
            eprintln!("chi2 wrong pdf {i}: p = {p:e}");
            assert!(p < 1e-6, "wrong pdf not detected: p = {p}");
        }
    }

    // ---------------------------------------------- weights and densities

    /// [`test_materials`] and every layered or extended set: the materials
    /// the generic checks (bit-for-bit eval/pdf, weight = eval/pdf, sides,
    /// degenerate inputs) run over.
    fn every_test_material() -> Vec<PbrBsdf> {
        let mut all = test_materials();
        all.extend(coated_materials());
        all.extend(sheened_materials());
        all.extend(iridescent_materials());
        all.extend(translucent_materials());
        all
    }

    fn test_materials() -> Vec<PbrBsdf> {
        vec![
            PbrBsdf::new(COLOR, 0.0, 0.5),
            PbrBsdf::new(COLOR, 1.0, 0.2),
            PbrBsdf::new(COLOR, 0.3, 1.0),
            PbrBsdf::new(Vec3A::ZERO, 1.0, 0.3),
            PbrBsdf {
                ior: 1.8,
                specular: 0.5,
                specular_color: Vec3A::new(1.0, 0.5, 20.0),
                ..PbrBsdf::new(COLOR, 0.1, 0.4)
            },
            volume(Vec3A::ONE, 0.0, 0.3, 1.0),
            PbrBsdf {
                ior: 1.33,
                ..volume(COLOR, 0.2, 0.7, 0.5)
            },
            thin(COLOR, 0.0, 0.35, 0.8),
            // Smooth, with a diffuse part: mixed delta and non-delta lobes.
            PbrBsdf::new(COLOR, 0.3, 0.0),
            thin(COLOR, 0.0, 0.0, 0.5),
            volume(COLOR, 0.0, 0.0, 0.5),
            // Anisotropic: rough, rough mostly along the direction (α_b small),
            // transmitting, and under a coat.
            aniso(PbrBsdf::new(COLOR, 0.4, 0.4), 0.8, 0.6),
            aniso(PbrBsdf::new(COLOR, 1.0, 0.15), 0.7, -1.2),
            aniso(volume(COLOR, 0.0, 0.3, 0.9), 0.9, 2.0),
            aniso(thin(COLOR, 0.0, 0.3, 0.7), 0.5, 0.3),
            aniso(
                coated(PbrBsdf::new(COLOR, 1.0, 0.3), 1.0, 0.2, 10.0),
                1.0,
                0.9,
            ),
        ]
    }

    #[test]
    fn eval_pdf_equals_eval_and_pdf_bit_for_bit() {
        // Random pairs on both sides, grazing and degenerate ones: the shared
        // computation must give exactly what the two separate calls give.
        let mut r = rng(17);
        let mut nonzero = 0;
        for p in every_test_material() {
            for k in 0..5_000 {
                let wo = sphere(&mut r);
                let wi = match k % 50 {
                    0 => Vec3A::new(wo.x, wo.y, 0.0),
                    1 => -wo,
                    2 => Vec3A::new(f32::NAN, 0.0, 1.0),
                    _ => sphere(&mut r),
                };
                let (f, pdf) = p.eval_pdf(wo, wi);
                let (f_alone, pdf_alone) = (p.eval(wo, wi), p.pdf(wo, wi));
                let bits = |f: Vec3A, pdf: f32| (f.to_array().map(f32::to_bits), pdf.to_bits());
                assert_eq!(
                    bits(f, pdf),
                    bits(f_alone, pdf_alone),
                    "{p:?} wo {wo:?} wi {wi:?}"
                );
                // And through the material seen from `wo`, sampling included.
                let m = Material::Pbr(p);
                let at = m.at(wo);
                let (f_at, pdf_at) = at.eval_and_pdf(wi);
                assert_eq!(bits(f_at, pdf_at.unwrap()), bits(f, pdf));
                let (u_lobe, u) = (r.next_f32(), u2(&mut r));
                assert_eq!(at.sample(u_lobe, u), m.sample(wo, u_lobe, u));
                nonzero += usize::from(pdf > 0.0 && f != Vec3A::ZERO);
            }
        }
        assert!(nonzero > 10_000, "only {nonzero} pairs with a value");
    }

    #[test]
    fn sample_weight_is_eval_over_pdf_and_pdf_matches() {
        let mut r = rng(3);
        let mut worst = 0.0f32;
        for p in every_test_material() {
            let m = Material::Pbr(p);
            let (mut hits, mut deltas) = (0, 0);
            for _ in 0..20_000 {
                let wo = sphere(&mut r);
                if wo.z.abs() < 1e-3 {
                    continue;
                }
                let Some(s) = m.sample(wo, r.next_f32(), u2(&mut r)) else {
                    continue;
                };
                assert!((s.wi.length() - 1.0).abs() < 1e-5, "{p:?}: {s:?}");
                assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
                if s.specular {
                    // A delta lobe: its selection probability, and a direction
                    // eval/pdf cannot see (a mixed material's diffuse part aside).
                    deltas += 1;
                    let smooth =
                        p.alpha < ALPHA_SMOOTH || (p.coat > 0.0 && p.coat_alpha < ALPHA_SMOOTH);
                    assert!(smooth && s.pdf > 0.0 && s.pdf <= 1.0);
                    continue;
                }
                hits += 1;
                let pdf = m.pdf(wo, s.wi);
                assert_eq!(s.pdf, pdf, "{p:?} wo {wo:?}: pdf {} vs {pdf}", s.pdf);
                let f = m.eval(wo, s.wi);
                let e = rel_err(s.weight, f / pdf);
                assert!(e < 1e-5, "{p:?} wo {wo:?}: {:?} vs {:?}", s.weight, f / pdf);
                worst = worst.max(e);
            }
            assert!(
                hits + deltas > 10_000,
                "{p:?}: only {hits} + {deltas} samples"
            );
            assert!(hits > 1000, "{p:?}: only {hits} non-delta samples");
            // Wherever eval is positive, so is pdf (else sampling would miss it).
            for _ in 0..20_000 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
                assert!(f.is_finite() && f.min_element() >= 0.0 && pdf.is_finite());
                assert!(f.max_element() == 0.0 || pdf > 0.0, "{p:?}: {wo} {wi}");
            }
        }
        eprintln!("pbr weight vs eval/pdf: worst relative error {worst:e}");
    }

    #[test]
    fn two_sided_and_reciprocal() {
        let mut r = rng(4);
        for p in every_test_material() {
            let m = Material::Pbr(p);
            let volume = p.transmission > 0.0 && !p.thin_walled;
            // Index of the medium a direction is in (1 for two-sided materials).
            let n = |w: Vec3A| if volume && w.z < 0.0 { p.ior } else { 1.0 };
            let mut checked = 0;
            for _ in 0..20_000 {
                let (wo, wi) = (sphere(&mut r), sphere(&mut r));
                let f = m.eval(wo, wi);
                if f.max_element() < 1e-4 || wo.z.abs() < 1e-3 || wi.z.abs() < 1e-3 {
                    continue;
                }
                checked += 1;
                // f(wo, wi) / n(wi)² = f(wi, wo) / n(wo)²: symmetric but for the
                // 1/η² the transmitted radiance leaves out. (A clear coat's
                // layering weighs by the Fresnel term at `wo` alone, as
                // specified: not reciprocal.)
                // (Nor is the diffuse transmission through a volume's
                // boundary: a Lambertian lobe on the far side, as specified,
                // with no refraction to pair with 1/η².)
                let lambertian_across = volume && p.diffuse_transmission > 0.0 && wo.z * wi.z < 0.0;
                if p.coat == 0.0 && !lambertian_across {
                    let a = f / (wi.z.abs() * n(wi) * n(wi));
                    let b = m.eval(wi, wo) / (wo.z.abs() * n(wo) * n(wo));
                    assert!(rel_err(a, b) < 2e-3, "{p:?}: {wo} {wi}: {a} vs {b}");
                }
                // Mirrored, a tilted coat normal is the back's, not the same.
                if !volume && (p.coat == 0.0 || p.coat_normal == Vec3A::Z) {
                    let g = m.eval(flip(wo), flip(wi));
                    assert!(rel_err(g, f) < 1e-6, "{p:?}: not two-sided");
                    assert_eq!(m.pdf(flip(wo), flip(wi)), m.pdf(wo, wi));
                }
            }
            assert!(checked > 1000, "{p:?}: {checked}");
        }
    }

    #[test]
    fn degenerate_inputs_are_safe() {
        let mut all = every_test_material();
        all.push(filmed(PbrBsdf::new(COLOR, 0.5, 0.5), 1.0, f32::NAN, 300.0));
        all.push(filmed(
            PbrBsdf::new(COLOR, 0.5, 0.0),
            1.0,
            1.3,
            f32::INFINITY,
        ));
        all.push(filmed(PbrBsdf::new(COLOR, 0.5, 0.3), f32::NAN, 1.3, 300.0));
        all.push(PbrBsdf {
            coat_normal: Vec3A::NAN,
            ..coated(PbrBsdf::new(COLOR, 0.0, 0.5), 1.0, 0.3, 0.0)
        });
        all.push(PbrBsdf {
            anisotropy_direction: Vec2::NAN,
            ..aniso(PbrBsdf::new(COLOR, 1.0, 0.5), 0.5, 0.0)
        });
        all.push(PbrBsdf {
            anisotropy_direction: Vec2::ZERO,
            ..aniso(volume(COLOR, 0.0, 0.5, 1.0), 1.0, 0.0)
        });
        all.push(aniso(PbrBsdf::new(COLOR, 1.0, 0.5), f32::NAN, 0.0));
        all.push(aniso(PbrBsdf::new(COLOR, 1.0, 0.5), f32::INFINITY, 0.0));
        all.extend([
            PbrBsdf {
                alpha: f32::NAN,
                ..PbrBsdf::new(COLOR, 0.5, 0.5)
            },
            PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5),
            PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0),
            PbrBsdf {
                specular: 0.0,
                ..PbrBsdf::new(Vec3A::ZERO, 0.0, 0.5)
            },
            PbrBsdf {
                ior: 1.0,
                ..volume(Vec3A::ONE, 0.0, 0.5, 1.0)
            },
            PbrBsdf {
                ior: 1.0,
                ..volume(Vec3A::ONE, 0.0, 0.0, 1.0)
            },
            PbrBsdf {
                specular_color: Vec3A::splat(100.0),
                ..PbrBsdf::new(COLOR, 0.0, 0.5)
            },
        ]);
        for p in all {
            let m = Material::Pbr(p);
            for wo in [
                Vec3A::Z,
                -Vec3A::Z,
                dir(89.99, 0.1),
                -dir(89.99, 0.1),
                Vec3A::new(1.0, 0.0, 1e-30).normalize(),
                Vec3A::new(1.0, 0.0, -1e-7).normalize(),
                Vec3A::X,
                Vec3A::ZERO,
                Vec3A::NAN,
            ] {
                for u in [
                    Vec2::ZERO,
                    Vec2::new(0.999_999_9, 0.999_999_9),
                    Vec2::new(0.5, 0.0),
                ] {
                    for wi in [
                        Vec3A::Z,
                        -Vec3A::Z,
                        -wo,
                        flip(wo),
                        Vec3A::new(-wo.x, -wo.y, wo.z),
                        dir(89.99, 3.0),
                    ] {
                        let (f, pdf) = (m.eval(wo, wi), m.pdf(wo, wi));
                        assert!(f.is_finite() && pdf.is_finite(), "{p:?} {wo} {wi}");
                        assert!(f.min_element() >= 0.0 && pdf >= 0.0);
                    }
                    for ul in [0.0, 0.3, 0.7, 0.999_999_9] {
                        if let Some(s) = m.sample(wo, ul, u) {
                            assert!(
                                s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                                "{p:?} {s:?}"
                            );
                            assert!(s.weight.min_element() >= 0.0);
                            assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn is_specular_only_without_a_non_delta_part() {
        assert!(PbrBsdf::new(COLOR, 1.0, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 0.0, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 0.999, 0.0).is_specular());
        assert!(!PbrBsdf::new(COLOR, 1.0, 0.1).is_specular());
        assert!(volume(COLOR, 0.0, 0.0, 1.0).is_specular());
        assert!(thin(COLOR, 0.0, 0.0, 1.0).is_specular());
        assert!(!thin(COLOR, 0.0, 0.0, 0.9).is_specular());
        assert!(!volume(COLOR, 0.0, 0.1, 1.0).is_specular());
        // No diffuse colour: only the delta reflection is left.
        assert!(PbrBsdf::new(Vec3A::ZERO, 0.0, 0.0).is_specular());
        assert!(Material::Pbr(PbrBsdf::new(COLOR, 1.0, 0.0)).is_specular());
        // A smooth surface's eval and pdf see only the diffuse part: zero for a
        // smooth metal even at the mirror direction.
        let wo = dir(30.0, 0.5);
        let metal = Material::Pbr(PbrBsdf::new(COLOR, 1.0, 0.0));
        assert_eq!(metal.eval(wo, reflect_z(wo)), Vec3A::ZERO);
        assert_eq!(metal.pdf(wo, reflect_z(wo)), 0.0);
        assert_eq!(PbrBsdf::alpha_from_roughness(0.0), MIN_ALPHA);
        assert_eq!(PbrBsdf::alpha_from_roughness(0.5), 0.25);
    }

    // ------------------------------------------------------------ furnaces

    #[test]
    fn furnace_white_metal() {
        // Smooth: the delta weight is exactly 1 at every angle, from both sides.
        let smooth = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, 0.0));
        assert!(smooth.is_specular());
        for theta in [0.0, 30.0, 60.0, 85.0, 89.9] {
            for wo in [dir(theta, 0.7), -dir(theta, 0.7)] {
                for ul in [0.0, 0.5, 0.999_999] {
                    let s = smooth.sample(wo, ul, Vec2::new(0.3, 0.6)).unwrap();
                    assert!(s.specular && s.pdf == 1.0);
                    assert_eq!(s.weight, Vec3A::ONE, "θo = {theta}");
                    assert!((s.wi - reflect_z(wo)).length() < 1e-6);
                }
            }
        }
        // Rough: single scattering loses energy but never gains any.
        let n = 100_000;
        for roughness in [0.1f32, 0.3, 0.5, 0.7, 1.0] {
            let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, roughness));
            for theta in [0.0, 45.0, 80.0] {
                let (a, se) = albedo(m, dir(theta, 0.7), n, 700);
                eprintln!("furnace white metal r={roughness} θo={theta}: {a:.5} ± {se:.5}");
                assert!(a <= 1.0 + 3.0 * se + 1e-6, "r = {roughness}: {a} ± {se}");
                if roughness == 0.1 {
                    assert!(a > 0.99, "r = 0.1, θo = {theta}: {a}");
                }
            }
        }
    }

    #[test]
    fn white_dielectric_is_brighter_than_white_at_grazing_angles() {
        // Appendix B as specified, unfixed: 1 − s max(F) of the diffuse base uses
        // the half vector of each pair, so at grazing incidence the specular lobe
        // (F near 1) and most of the diffuse lobe are both kept. (An independent
        // float64 quadrature of the formulas gives 1.0821 at roughness 0.5.)
        let wo = dir(80.0, 0.3);
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.5));
        let (a, se) = albedo(m, wo, 200_000, 800);
        let q = albedo_by_quadrature(m, wo);
        eprintln!("white dielectric r=0.5 θo=80°: MC {a:.5} ± {se:.5}, quadrature {q:.5}");
        assert!((a - q).abs() < 4.0 * se + 1e-3, "MC {a} vs quadrature {q}");
        assert!((q - 1.0821).abs() < 1e-3 && a > 1.05, "{a} {q}");
        // Smooth: the delta reflection's F(cos θo) plus the diffuse part, whose
        // eval the quadrature sees: 1.35.
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.0));
        let (a, se) = albedo(m, wo, 200_000, 801);
        let q = schlick1(0.04, wo.z) as f64 + albedo_by_quadrature(m, wo);
        eprintln!("white dielectric r=0 θo=80°: MC {a:.5} ± {se:.5}, F + quadrature {q:.5}");
        assert!(
            (a - q).abs() < 4.0 * se + 1e-3,
            "MC {a} vs F + quadrature {q}"
        );
        assert!(q > 1.3 && a > 1.3, "{a} {q}");
        // Head-on it is below 1.
        let m = Material::Pbr(PbrBsdf::new(Vec3A::ONE, 0.0, 0.5));
        let (a0, se0) = albedo(m, Vec3A::Z, 100_000, 802);
        eprintln!("white dielectric r=0.5 θo=0°: MC {a0:.5} ± {se0:.5}");
        assert!(a0 < 1.0);
    }

    #[test]
    fn exact_metallic_mix_at_a_hand_computed_point() {
        // α = 0.5² = 0.25, c = (0.8, 0.4, 0.2), m = 0.3, ior 1.5 (F0 = 0.04), s = 1.
        // wo = (0.6, 0, 0.8), wi = (−0.28, 0, 0.96): h = (0.32, 0, 1.76)/√3.2,
        //   wo·h = 1.6/√3.2 = 0.894427, (1 − wo·h)⁵ = 1.3114e-5, h_z = 0.983870.
        // D = α² / (π (h_z² (α² − 1) + 1)²) = 2.325127.
        // Λ(wo) = (√(1 + α² 0.6²/0.8²) − 1)/2 = 0.0087131,
        // Λ(wi) = (√(1 + α² 0.28²/0.96²) − 1)/2 = 0.0013274,
        // G2 = 1/(1 + Λo + Λi) = 0.990059, V = G2/(4·0.8·0.96) = 0.322285.
        // F_d = 0.04 + 0.96·1.3114e-5 = 0.0400126; F_m = c + (1 − c)·1.3114e-5.
        // f = 0.7 [(1 − F_d) c/π + F_d D V] + 0.3 F_m D V
        //   = (0.371955, 0.196473, 0.108732); f cos θi = f · 0.96:
        let expected = Vec3A::new(0.357_077, 0.188_614, 0.104_383);
        // The glTF sample viewer's shortcut (one F of the mixed F0 =
        // mix(0.04, c, m), diffuse (1 − F)(1 − m)c/π) gives instead
        let shortcut = Vec3A::new(0.318_061, 0.179_374, 0.102_330);
        let p = PbrBsdf::new(Vec3A::new(0.8, 0.4, 0.2), 0.3, 0.5);
        let (wo, wi) = (Vec3A::new(0.6, 0.0, 0.8), Vec3A::new(-0.28, 0.0, 0.96));
        let f = p.eval(wo, wi);
        eprintln!("hand-computed pbr f cos θi: {f} (expected {expected})");
        assert!(rel_err(f, expected) < 2e-5, "{f} vs {expected}");
        assert!(rel_err(shortcut, expected) > 0.01);
        // Both sides alike (a two-sided material), and reciprocal.
        assert!(rel_err(p.eval(flip(wo), flip(wi)), expected) < 2e-5);
        assert!(rel_err(p.eval(wi, wo) * (wi.z / wo.z), expected) < 2e-5);
    }

    // ------------------------------------------------------------- smooth

    #[test]
    fn smooth_volume_is_exactly_glass() {
        let ior = 1.5f32;
        let pbr = Material::Pbr(volume(Vec3A::ONE, 0.0, 0.0, 1.0));
        let glass = Material::Dielectric { ior };
        assert!(pbr.is_specular());
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let critical = (1.0 / ior).asin().to_degrees();
        let mut worst_schlick = 0.0f32;
        let mut compared = 0;
        for theta in [0.0f32, 20.0, 45.0, 70.0, 85.0, 89.5] {
            for outside in [true, false] {
                let wo = if outside {
                    dir(theta, 0.9)
                } else {
                    -dir(theta * 0.6, 0.9)
                };
                // Schlick at the air-side cosine; 1 under total internal reflection.
                let cos = wo.z.abs();
                let f_s = if outside {
                    schlick1(f0, cos)
                } else {
                    let sin2_t = (1.0 - cos * cos) * ior * ior;
                    if sin2_t >= 1.0 {
                        1.0
                    } else {
                        schlick1(f0, (1.0 - sin2_t).sqrt())
                    }
                };
                let f_e = fresnel_dielectric(wo.z, ior);
                worst_schlick = worst_schlick.max((f_s - f_e).abs());
                if !outside && theta * 0.6 > critical {
                    assert_eq!((f_s, f_e), (1.0, 1.0), "TIR at {}°", theta * 0.6);
                }
                for i in 0..100 {
                    let ul = (i as f32 + 0.5) / 100.0;
                    let u = Vec2::new(0.37, 0.61);
                    let a = pbr.sample(wo, ul, u).unwrap();
                    let b = glass.sample(wo, ul, u).unwrap();
                    assert!(a.specular && b.specular);
                    // Weights 1 (up to the rounding of (F + (1 − F) lum) / …).
                    assert!((a.weight - Vec3A::ONE).abs().max_element() < 1e-5, "{a:?}");
                    let reflected = a.wi.z * wo.z > 0.0;
                    let expected_pdf = if reflected { f_s } else { 1.0 - f_s };
                    assert!((a.pdf - expected_pdf).abs() < 1e-5, "{a:?} vs F {f_s}");
                    // The same lobe unless u_lobe falls between the two Fresnels.
                    if (ul - f_s) * (ul - f_e) > 0.0 {
                        compared += 1;
                        assert!((a.wi - b.wi).length() < 1e-6, "{a:?} vs {b:?}");
                        assert!((a.pdf - b.pdf).abs() <= (f_s - f_e).abs() + 1e-6);
                    }
                }
                // Nothing for eval/pdf: every lobe is a delta.
                let wi = reflect_z(wo);
                assert_eq!(pbr.eval(wo, wi), Vec3A::ZERO);
                assert_eq!(pbr.pdf(wo, -wo), 0.0);
            }
        }
        eprintln!(
            "smooth pbr volume = glass: {compared} samples, worst |Schlick − F| {worst_schlick:.4}"
        );
        assert!(compared > 1000 && worst_schlick < 0.05);
    }

    #[test]
    fn smooth_thin_wall_transmits_straight_on() {
        let c = Vec3A::new(0.9, 0.5, 0.2);
        let lum = 0.2126 * 0.9 + 0.7152 * 0.5 + 0.0722 * 0.2;
        for transmission in [1.0f32, 0.7] {
            let p = thin(c, 0.0, 0.0, transmission);
            let m = Material::Pbr(p);
            assert_eq!(m.is_specular(), transmission == 1.0);
            for theta in [0.0f32, 30.0, 60.0, 85.0] {
                for wo in [dir(theta, 1.3), -dir(theta, 1.3)] {
                    let f = schlick1(0.04, wo.z.abs());
                    // Lobe estimates: specular F, transmission tr (1 − F) lum(c),
                    // diffuse (1 − tr)(1 − max(F, floor)) lum(c).
                    let w_t = transmission * (1.0 - f) * lum;
                    let w_d = (1.0 - transmission) * (1.0 - f).max(0.1 * 0.96) * lum;
                    let p_t = w_t / (f + w_t + w_d);
                    let s = m.sample(wo, 0.999_999, Vec2::new(0.2, 0.8)).unwrap();
                    assert!(s.specular && (s.wi + wo).length() < 1e-6, "{s:?}");
                    assert!((s.pdf - p_t).abs() < 1e-5, "{} vs {p_t}", s.pdf);
                    let expected = c * (transmission * (1.0 - f) / p_t);
                    assert!(rel_err(s.weight, expected) < 1e-5, "{s:?} vs {expected}");
                    // And the specular reflection, weight F / p_spec.
                    let r = m.sample(wo, 0.0, Vec2::new(0.2, 0.8)).unwrap();
                    assert!(r.specular && (r.wi - reflect_z(wo)).length() < 1e-6);
                    let p_r = f / (f + w_t + w_d);
                    assert!(rel_err(r.weight, Vec3A::splat(f / p_r)) < 1e-5, "{r:?}");
                }
            }
        }
    }

    // ------------------------------------------------- dispersion

    /// Smooth clear glass of index 1.5 with `KHR_materials_dispersion`
    /// `dispersion`.
    fn dispersive_glass(dispersion: f32, roughness: f32) -> PbrBsdf {
        PbrBsdf {
            dispersion,
            ..volume(Vec3A::ONE, 0.0, roughness, 1.0)
        }
    }

    /// The refraction a smooth dispersive interface samples, in world
    /// coordinates: `d` arriving at a face of outward normal `n` (from
    /// outside if `d·n < 0`); `None` if it reflects (TIR).
    fn refract_through(bsdf: &PbrBsdf, n: Vec3A, d: Vec3A) -> Option<Vec3A> {
        let frame = Frame::from_normal(n);
        let wo = frame.to_local(-d);
        // u_lobe near 1 takes the transmission (there is no diffuse or coat).
        let s = bsdf.sample(wo, 0.999_999, Vec2::new(0.5, 0.5))?;
        // Clear smooth glass at any wavelength: R + T = 1, weight 1.
        assert!((s.weight - Vec3A::ONE).abs().max_element() < 1e-5, "{s:?}");
        (s.specular && s.wi.z * wo.z < 0.0).then(|| frame.to_world(s.wi))
    }

    /// A white beam through a 60° prism of dispersive glass: each
    /// wavelength's two refractions, as the path tracer samples them with the
    /// BSDF at that wavelength, turn it by the deviation Snell's law gives
    /// for the extension's n(λ), `δ = i₁ + asin(n sin(A − asin(sin i₁ / n))) −
    /// A`; blue turns more than red, by the analytic split; without
    /// dispersion every wavelength turns alike.
    #[test]
    fn a_prism_splits_white_light_by_snells_law_with_the_abbe_ior() {
        let apex = 60f32.to_radians();
        // The prism's faces in the xz plane, apex towards +z: outward normals
        // at ±(90° − A/2) from +z... (−cos 30°, 0, sin 30°) and (cos 30°, 0, sin 30°).
        let half = apex / 2.0;
        let n1 = Vec3A::new(-half.cos(), 0.0, half.sin());
        let n2 = Vec3A::new(half.cos(), 0.0, half.sin());
        for (dispersion, incidence) in [(1.0f32, 50f32), (0.36, 40.0), (2.04, 60.0)] {
            let base = dispersive_glass(dispersion, 0.0);
            // The beam in the xz plane at `incidence` to face 1's normal.
            let i1 = incidence.to_radians();
            let t = Vec3A::new(n1.z, 0.0, -n1.x); // in the plane, along face 1
            let d = (-n1 * i1.cos() + t * i1.sin()).normalize();
            let mut deviations = Vec::new();
            for lambda in [450.0f32, 550.0, 650.0] {
                let glass = base.at_wavelength(lambda);
                let n = super::super::spectrum::dispersed_ior(1.5, dispersion, lambda);
                assert_eq!(glass.ior, n);
                let inside = refract_through(&glass, n1, d).expect("enters");
                let out = refract_through(&glass, n2, inside).expect("leaves");
                let deviation = d.dot(out).clamp(-1.0, 1.0).acos();
                let r1 = (i1.sin() / n).asin();
                let want = i1 + (n * (apex - r1).sin()).asin() - apex;
                assert!(
                    (deviation - want).abs() < 2e-4,
                    "V = {}, λ {lambda}: deviation {} vs Snell {}",
                    20.0 / dispersion,
                    deviation.to_degrees(),
                    want.to_degrees()
                );
                deviations.push((deviation, want));
            }
            let (blue, red) = (deviations[0], deviations[2]);
            assert!(blue.0 > deviations[1].0 && deviations[1].0 > red.0);
            assert!(
                ((blue.0 - red.0) - (blue.1 - red.1)).abs() < 2e-4,
                "split {} vs {}",
                (blue.0 - red.0).to_degrees(),
                (blue.1 - red.1).to_degrees()
            );
            eprintln!(
                "dispersion {dispersion}: 450 nm turned {:.3}°, 650 nm {:.3}°",
                blue.0.to_degrees(),
                red.0.to_degrees()
            );
            assert!((blue.0 - red.0).to_degrees() > 0.1);
            // Without dispersion (or thin-walled) the BSDF ignores the wavelength.
            for plain in [dispersive_glass(0.0, 0.0), thin(Vec3A::ONE, 0.0, 0.0, 1.0)] {
                let plain = PbrBsdf {
                    dispersion: 0.0,
                    ..plain
                };
                assert!(!plain.dispersive());
                assert_eq!(plain.at_wavelength(450.0), plain);
            }
            let thin_dispersive = PbrBsdf {
                dispersion,
                ..thin(Vec3A::ONE, 0.0, 0.0, 1.0)
            };
            assert!(!thin_dispersive.dispersive());
            assert_eq!(thin_dispersive.at_wavelength(450.0), thin_dispersive);
        }
    }

    /// A rough dispersive dielectric at a fixed wavelength samples its own
    /// density (the index there: 1.58 at 420 nm for dispersion 2), from
    /// outside and from inside.
    #[test]
    fn chi2_rough_dispersive_dielectric_at_a_wavelength() {
        let glass = dispersive_glass(2.0, 0.4).at_wavelength(420.0);
        assert!((glass.ior - 1.5).abs() > 0.05, "{}", glass.ior);
        chi2_cases(
            &[
                (glass, dir(40.0, 0.7), "dispersive, outside, 420 nm"),
                (
                    dispersive_glass(2.0, 0.4).at_wavelength(680.0),
                    -dir(35.0, 0.7),
                    "dispersive, inside, 680 nm",
                ),
            ],
            900,
        );
    }

    /// A white furnace for the rough dispersive dielectric: at the ends of
    /// the spectrum, where its index is furthest from `ior`, from outside
    /// and inside, it never returns more than it receives (single
    /// scattering GGX loses a little).
    #[test]
    fn furnace_rough_dispersive_dielectric_at_every_wavelength() {
        for (k, lambda) in [380.0f32, 480.0, 700.0].into_iter().enumerate() {
            for roughness in [0.1f32, 0.5, 1.0] {
                let glass = dispersive_glass(2.04, roughness).at_wavelength(lambda);
                for theta in [0.0f32, 45.0, 80.0] {
                    for wo in [dir(theta, 0.4), -dir(theta, 0.4)] {
                        let key = 1000 + k as u64;
                        let (a, se) = albedo(Material::Pbr(glass), wo, 20_000, key);
                        assert!(
                            a <= 1.0 + 4.0 * se + 1e-6,
                            "λ {lambda}, r {roughness}, wo {wo}: albedo {a} ± {se}"
                        );
                        assert!(a > 0.3, "λ {lambda}, r {roughness}, wo {wo}: {a}");
                    }
                }
            }
        }
    }

    // ------------------------------------------------------ anisotropy

    /// `base` with `KHR_materials_anisotropy` of `strength`, its direction at
    /// `angle` radians from the local `+x` (already in the shading frame).
    fn aniso(base: PbrBsdf, strength: f32, angle: f32) -> PbrBsdf {
        let (s, c) = angle.sin_cos();
        PbrBsdf {
            anisotropy: strength,
            anisotropy_direction: Vec2::new(c, s),
            ..base
        }
    }

    #[test]
    fn chi2_anisotropic_sampling_matches_pdf() {
        let mut cases = Vec::new();
        // (metallic, roughness, strength, rotation, θo, φo): widths from
        // (α_t, α_b) = (0.52, 0.04) to (1, 0.25), directions along, across
        // and oblique to wo's azimuth.
        for (m, r, k, rot, theta, phi) in [
            (1.0f32, 0.2f32, 0.7f32, 0.0f32, 45.0f32, 0.0f32),
            (1.0, 0.5, 1.0, 0.8, 70.0, 2.0),
            (1.0, 0.3, 0.5, 1.6, 15.0, 0.3),
            (0.0, 0.4, 0.9, -0.5, 60.0, 1.0),
            (0.0, 0.2, 0.6, 2.5, 30.0, 4.0),
            (0.5, 0.35, 0.8, 0.4, 80.0, 0.4),
        ] {
            let p = aniso(PbrBsdf::new(COLOR, m, r), k, rot);
            let what = format!("aniso m={m} r={r} k={k} rot={rot} θo={theta}");
            cases.push((p, dir(theta, phi), what));
        }
        for (p, wo, what) in [
            (
                volume(Vec3A::ONE, 0.0, 0.4, 1.0),
                dir(40.0, 0.7),
                "volume outside",
            ),
            (
                volume(COLOR, 0.0, 0.3, 0.8),
                -dir(30.0, 2.2),
                "volume inside",
            ),
            (thin(COLOR, 0.0, 0.3, 1.0), dir(50.0, 1.1), "thin-walled"),
            (
                thin(COLOR, 0.3, 0.5, 0.6),
                -dir(70.0, 3.0),
                "thin back side",
            ),
        ] {
            cases.push((aniso(p, 0.8, 0.9), wo, format!("aniso {what}")));
        }
        let cases: Vec<_> = cases.iter().map(|(p, w, s)| (*p, *w, s.as_str())).collect();
        chi2_cases(&cases, 700);
    }

    #[test]
    fn chi2_detects_a_wrong_anisotropic_pdf() {
        // The sampler of one direction against the pdf of another (and of
        // the isotropic material) is rejected.
        let p = aniso(PbrBsdf::new(COLOR, 1.0, 0.3), 0.8, 0.0);
        let wo = dir(45.0, 0.7);
        for (i, claimed) in [
            aniso(p, 0.8, 0.4),
            PbrBsdf {
                anisotropy: 0.0,
                ..p
            },
        ]
        .into_iter()
        .enumerate()
        {
            let pv = chi2_p_value_of(Material::Pbr(p), Material::Pbr(claimed), wo, 720 + i as u64);
            eprintln!("chi2 wrong anisotropic pdf {i}: p = {pv:e}");
            assert!(pv < 1e-6, "wrong pdf not detected: p = {pv}");
        }
    }

    /// The anisotropic distribution of every test below.
    fn ggx_of(roughness: f32, strength: f32, angle: f32) -> Ggx {
        let p = aniso(PbrBsdf::new(COLOR, 1.0, roughness), strength, angle);
        let g = p.ggx();
        assert!(matches!(g, Ggx::Anisotropic { .. }));
        g
    }

    /// `∫ f(m) dω_m` over the upper hemisphere by the midpoint rule in
    /// `(θ, φ)`, in f64.
    fn hemisphere_integral(f: impl Fn(Vec3A) -> f64) -> f64 {
        let (nt, np) = (3000, 1000);
        let (dt, dp) = (
            std::f64::consts::FRAC_PI_2 / nt as f64,
            std::f64::consts::TAU / np as f64,
        );
        let phis: Vec<(f64, f64)> = (0..np).map(|j| ((j as f64 + 0.5) * dp).sin_cos()).collect();
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            let (st, ct) = t.sin_cos();
            let mut row = 0.0;
            for &(sp, cp) in &phis {
                row += f(Vec3A::new((st * cp) as f32, (st * sp) as f32, ct as f32));
            }
            sum += row * st;
        }
        sum * dt * dp
    }

    #[test]
    fn anisotropic_d_is_normalized_and_lambda_matches_it() {
        // ∫ D(m) (n·m) dm = 1, and the projected area seen from wo,
        // ∫ D(m) max(0, wo·m) dm = cos θo (1 + Λ(wo)): Λ is the Smith
        // function of this D (so the visible normals' density integrates to 1).
        for (r, k, angle) in [(0.2f32, 0.8f32, 0.3f32), (0.5, 0.5, -1.0), (0.3, 1.0, 2.0)] {
            let g = ggx_of(r, k, angle);
            let norm = hemisphere_integral(|m| g.d(m) as f64 * m.z as f64);
            eprintln!("aniso D r={r} k={k}: ∫ D cos = {norm:.6}");
            assert!((norm - 1.0).abs() < 2e-3, "r={r} k={k}: {norm}");
            for (theta, phi) in [(30.0f32, 0.3f32), (70.0, 1.9), (85.0, 0.3 + angle)] {
                let wo = dir(theta, phi);
                let area = hemisphere_integral(|m| g.d(m) as f64 * wo.dot(m).max(0.0) as f64);
                let expected = wo.z as f64 * (1.0 + g.lambda(wo) as f64);
                eprintln!("aniso r={r} k={k} θo={theta}: projected {area:.6} vs {expected:.6}");
                assert!(
                    (area / expected - 1.0).abs() < 3e-3,
                    "r={r} k={k} θo={theta}: {area} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn anisotropic_formulas_reduce_to_the_isotropic_ones() {
        // Equal widths: the anisotropic D, Λ and visible-normal samples are
        // the isotropic ones (to rounding), whatever the direction.
        let mut r = rng(31);
        for alpha in [0.01f32, 0.2, 0.7] {
            for angle in [0.0f32, 0.7, 2.5] {
                let dir2 = Vec2::new(angle.cos(), angle.sin());
                let a = Ggx::Anisotropic {
                    at: alpha,
                    ab: alpha,
                    dir: dir2,
                };
                let i = Ggx::Isotropic(alpha);
                for _ in 0..2000 {
                    let w = sphere(&mut r);
                    let w = Vec3A::new(w.x, w.y, w.z.abs().max(1e-3)).normalize();
                    let close = |x: f32, y: f32| (x - y).abs() <= 2e-5 * y.abs().max(1e-3);
                    assert!(close(a.d(w), i.d(w)), "{alpha} {w}: {} {}", a.d(w), i.d(w));
                    assert!(close(a.lambda(w), i.lambda(w)));
                    let u = u2(&mut r);
                    let (ma, mi) = (a.sample_visible_normal(w, u), i.sample_visible_normal(w, u));
                    assert!((ma - mi).length() < 1e-4, "{ma} vs {mi}");
                }
            }
        }
        // Strength 0 is no anisotropy at all: the isotropic path itself.
        let p = aniso(PbrBsdf::new(COLOR, 0.5, 0.4), 0.0, 1.0);
        assert!(matches!(p.ggx(), Ggx::Isotropic(a) if a == p.alpha));
        let plain = PbrBsdf::new(COLOR, 0.5, 0.4);
        for _ in 0..1000 {
            let (wo, wi) = (sphere(&mut r), sphere(&mut r));
            assert_eq!(p.eval_pdf(wo, wi), plain.eval_pdf(wo, wi));
            let (ul, u) = (r.next_f32(), u2(&mut r));
            assert_eq!(p.sample(wo, ul, u), plain.sample(wo, ul, u));
        }
    }

    #[test]
    fn anisotropic_metal_matches_the_specifications_formulas() {
        // BRDF_specularAnisotropicGGX of the extension's text, written out
        // in f64: F V D with at = mix(α, 1, k²), ab = α, on the pair
        // below; raylab's f cos θi over cos θi must equal it.
        let (r, k, angle) = (0.4f64, 0.7f64, 0.6f64);
        let c = Vec3A::new(0.9, 0.6, 0.3);
        let p = aniso(PbrBsdf::new(c, 1.0, r as f32), k as f32, angle as f32);
        let (wo, wi) = (dir(50.0, 0.2), dir(35.0, 2.9));
        let v = |w: Vec3A| [w.x as f64, w.y as f64, w.z as f64];
        let (l, vv) = (v(wi), v(wo));
        let hs = [l[0] + vv[0], l[1] + vv[1], l[2] + vv[2]];
        let hl = (hs[0] * hs[0] + hs[1] * hs[1] + hs[2] * hs[2]).sqrt();
        let h = hs.map(|x| x / hl);
        let t = [angle.cos(), angle.sin(), 0.0];
        let b = [-angle.sin(), angle.cos(), 0.0];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let alpha = r * r;
        let at = alpha * (1.0 - k * k) + k * k;
        let ab = alpha;
        // D_GGX_anisotropic.
        let a2 = at * ab;
        let f = [ab * dot(t, h), at * dot(b, h), a2 * h[2]];
        let w2 = a2 / dot(f, f);
        let d = a2 * w2 * w2 / std::f64::consts::PI;
        // V_GGX_anisotropic.
        let len = |x: f64, y: f64, z: f64| (x * x + y * y + z * z).sqrt();
        let ggxv = l[2] * len(at * dot(t, vv), ab * dot(b, vv), vv[2]);
        let ggxl = vv[2] * len(at * dot(t, l), ab * dot(b, l), l[2]);
        let vis = 0.5 / (ggxv + ggxl);
        let x5 = (1.0 - dot(vv, h)).powi(5);
        let expected = Vec3A::new(
            ((c.x as f64 + (1.0 - c.x as f64) * x5) * vis * d) as f32,
            ((c.y as f64 + (1.0 - c.y as f64) * x5) * vis * d) as f32,
            ((c.z as f64 + (1.0 - c.z as f64) * x5) * vis * d) as f32,
        );
        let got = p.eval(wo, wi) / wi.z;
        eprintln!("anisotropic metal: {got} against the specification's {expected}");
        assert!(rel_err(got, expected) < 1e-4, "{got} vs {expected}");
        // And the isotropic value differs (the test sees the anisotropy).
        let iso = PbrBsdf::new(c, 1.0, r as f32).eval(wo, wi) / wi.z;
        assert!(rel_err(iso, expected) > 0.05, "{iso} vs {expected}");
    }

    #[test]
    fn the_highlight_widens_along_the_anisotropy_direction() {
        // Seen head-on, a light 15° off the mirror direction towards the
        // direction t is reflected far more than one 15° off towards b
        // (the lobe is wider along t), and turning the direction by 90°
        // swaps the two; on a ring, the widest azimuth is ±t.
        use std::f32::consts::FRAC_PI_2;
        let wo = Vec3A::Z;
        for angle in [0.0f32, 0.5, 1.2] {
            let p = aniso(PbrBsdf::new(Vec3A::ONE, 1.0, 0.2), 0.8, angle);
            let along = p.eval(wo, dir(15.0, angle)).x;
            let across = p.eval(wo, dir(15.0, angle + FRAC_PI_2)).x;
            eprintln!("aniso highlight at {angle}: along t {along:.4}, along b {across:.4}");
            assert!(along > 5.0 * across, "{angle}: {along} vs {across}");
            let turned = aniso(p, 0.8, angle + FRAC_PI_2);
            let (a2, c2) = (
                turned.eval(wo, dir(15.0, angle)).x,
                turned.eval(wo, dir(15.0, angle + FRAC_PI_2)).x,
            );
            assert!(
                (a2 - across).abs() < 1e-4 * across.max(1e-3) && (c2 - along).abs() < 1e-4 * along
            );
            // The azimuth of the widest point on a 15° ring is ±t.
            let best = (0..360)
                .map(|i| (i as f32).to_radians())
                .max_by(|&x, &y| {
                    p.eval(wo, dir(15.0, x))
                        .x
                        .total_cmp(&p.eval(wo, dir(15.0, y)).x)
                })
                .unwrap();
            let x = (best - angle).rem_euclid(PI);
            let off = x.min(PI - x);
            assert!(off < 0.02, "{angle}: widest at {best}");
        }
    }

    /// White furnaces for anisotropic lobes: never more than is received,
    /// and between the isotropic materials of widths `α_t` and `α_b` (the
    /// single-scattering loss grows with roughness).
    #[test]
    fn furnace_anisotropic_white_metal_and_glass() {
        let n = 60_000;
        for (r, k) in [(0.1f32, 0.5f32), (0.3, 0.8), (0.5, 1.0), (0.05, 1.0)] {
            let p = aniso(PbrBsdf::new(Vec3A::ONE, 1.0, r), k, 0.7);
            let at = p.alpha_t().sqrt();
            for theta in [0.0f32, 45.0, 80.0] {
                let wo = dir(theta, 0.2);
                let (a, se) = albedo(Material::Pbr(p), wo, n, 900);
                let wide = albedo(Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, at)), wo, n, 901);
                let narrow = albedo(Material::Pbr(PbrBsdf::new(Vec3A::ONE, 1.0, r)), wo, n, 902);
                eprintln!(
                    "furnace aniso metal r={r} k={k} θo={theta}: {a:.5} ± {se:.5} (iso α_t {:.5}, α_b {:.5})",
                    wide.0, narrow.0
                );
                assert!(
                    a <= 1.0 + 3.0 * se + 1e-6,
                    "r={r} k={k} θo={theta}: {a} ± {se}"
                );
                assert!(
                    a >= wide.0 - 4.0 * (se + wide.1) && a <= narrow.0 + 4.0 * (se + narrow.1),
                    "r={r} k={k} θo={theta}: {a} not between {} and {}",
                    wide.0,
                    narrow.0
                );
            }
        }
        // Clear rough glass (reflection and refraction, Schlick): from
        // either side, no gain.
        for (r, k) in [(0.2f32, 0.8f32), (0.5, 1.0)] {
            let p = aniso(volume(Vec3A::ONE, 0.0, r, 1.0), k, -0.4);
            for wo in [
                dir(0.0, 0.0),
                dir(45.0, 1.0),
                dir(80.0, 0.3),
                -dir(30.0, 2.0),
            ] {
                let (a, se) = albedo(Material::Pbr(p), wo, n, 903);
                eprintln!("furnace aniso glass r={r} k={k} wo={wo}: {a:.5} ± {se:.5}");
                assert!(a <= 1.0 + 3.0 * se + 1e-6, "r={r} k={k} {wo}: {a} ± {se}");
                assert!(a > 0.5, "r={r} k={k} {wo}: {a}");
            }
        }
    }

    #[test]
    fn orienting_takes_the_tangent_frame_into_the_shading_frame() {
        // Direction (cos 30°, sin 30°) in a tangent frame turned 90° about
        // the normal: 120° in the shading frame; no tangent: isotropic.
        let frame = Frame::from_normal(Vec3A::Z);
        let (t, b) = (frame.b, -frame.t);
        let mut p = aniso(PbrBsdf::new(COLOR, 1.0, 0.3), 0.6, 30f32.to_radians());
        let mut q = p;
        p.orient_anisotropy(&frame, t, b);
        let expected = Vec2::new(120f32.to_radians().cos(), 120f32.to_radians().sin());
        assert!((p.anisotropy_direction - expected).length() < 1e-6, "{p:?}");
        q.orient_anisotropy(&frame, Vec3A::ZERO, Vec3A::ZERO);
        assert_eq!(q.anisotropy, 0.0);
        assert!(matches!(q.ggx(), Ggx::Isotropic(_)));
    }
}
