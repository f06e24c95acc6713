//! Materials as BSDFs in a local shading frame.
//!
//! Every direction here is a unit vector in the *local* frame of a surface point,
//! built by [`Frame::from_normal`] with the shading normal as `+z`; both `wo` (towards
//! the viewer, the direction the path came from) and `wi` (towards the light, the
//! direction the path continues in) point *away* from the surface.
//!
//! # Sides
//!
//! * [`Material::Diffuse`], [`Material::Mirror`] and [`Material::RoughConductor`]
//!   are one-sided: they reflect only on the `+z` side. For `wo.z <= 0`,
//!   [`Material::eval`] and [`Material::pdf`] return zero and [`Material::sample`]
//!   returns `None`, as it does whenever a sampled `wi` lands on or below the
//!   horizon. An integrator that wants two-sided surfaces flips the shading normal
//!   towards `wo` before it builds the frame.
//! * [`Material::Dielectric`] is two-sided and must **not** have its normal flipped:
//!   `wo.z > 0` means `wo` is outside (in the medium of index 1 the normal points
//!   into), `wo.z < 0` means inside (the medium of index `ior`).
//! * [`Material::Pbr`] (the glTF metallic–roughness BSDF, [`pbr`]) decides its
//!   sides itself and must **not** have its normal flipped either: without a
//!   refracting volume it is two-sided (mirrored to `+z` for `wo.z < 0`), with
//!   one it is an interface like [`Material::Dielectric`].
//!
//! # Estimator
//!
//! [`Material::sample`] returns `weight = f(wo, wi) |cos θi| / pdf`, so a path's
//! throughput is simply multiplied by it. For the delta lobes (mirror, glass,
//! conductors with `alpha` below [`ALPHA_SMOOTH`]) `pdf` is the discrete
//! probability of the lobe that was chosen, `specular` is set, and
//! [`Material::eval`] / [`Material::pdf`] are zero for every direction (a delta lobe
//! can never be hit by a direction chosen elsewhere, e.g. by light sampling).
//! A material may mix both kinds ([`Material::Pbr`] when smooth but with a
//! diffuse part): `eval` and `pdf` then cover its non-delta lobes only, a sample
//! from a non-delta lobe has the mixture density of those as its `pdf`, and one
//! from a delta lobe is flagged `specular` as above.
//!
//! # Dielectrics and radiance scaling
//!
//! The transmitted weight is **not** scaled by `1/η²` (η the ratio of the indices
//! across the interface). Radiance does get compressed by `η²` when it enters a
//! denser medium, but along any path whose two ends (camera and light) lie in the
//! same medium the factors of entering and leaving telescope to exactly 1, so
//! leaving them out is exact for the closed glass objects of a scene in air and
//! keeps every glass weight at exactly 1 (energy conservation is then a plain
//! `R + T = 1`). It would be wrong only for a light or camera *inside* glass.
//!
//! # Rough conductors
//!
//! GGX (Trowbridge–Reitz) microfacets with Smith's **height-correlated** masking–
//! shadowing `G2 = 1 / (1 + Λ(wo) + Λ(wi))` (Heitz 2014), the exact Fresnel
//! reflectance of a conductor with complex index `η + ik` (per RGB channel), and
//! sampling of the visible normals (Heitz 2018), whose pdf is
//! `D_wo(wm) / (4 |wo·wm|) = G1(wo) D(wm) / (4 cos θo)` and whose weight is
//! therefore `F · G2 / G1(wo)` (never more than `F`). This model is single
//! scattering only: it loses energy as roughness grows (see the furnace tests).
//!
//! Nothing here allocates.

use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

pub mod pbr;
pub mod sheen;
pub mod sheen_table;
pub mod spectrum;
pub mod surface;
#[cfg(test)]
pub(crate) mod test_util;
pub mod thin_film;

pub use pbr::PbrBsdf;

/// Conductors with `alpha` below this are treated as perfectly smooth (a delta
/// lobe): GGX at such roughness is numerically a spike that f32 cannot resolve.
pub const ALPHA_SMOOTH: f32 = 1e-3;

/// The largest GGX `α` at which a lobe counts as specular for the denoiser's
/// guides ([`Material::guide_lobes`]): Cycles' threshold for its denoising
/// features (`α ≤ 0.075`, glTF roughness up to about 0.27). Below it a
/// reflection is sharp enough that the denoiser should see what is reflected.
pub const GUIDE_ALPHA: f32 = 0.075;

/// A BSDF as the denoiser's guides see it from one direction
/// ([`Material::guide_lobes`]): its specular lobes (delta, or GGX with
/// `α ≤` [`GUIDE_ALPHA`]) as the one direction each sends light along, with
/// their values, and the albedo of everything else. The three values add up
/// to about [`Material::albedo`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideLobes {
    /// Albedo of the lobes that are not specular (diffuse, rough), per
    /// channel.
    pub rough: Vec3A,
    /// The specular reflection: its direction (local frame) and value.
    pub reflect: Option<(Vec3A, Vec3A)>,
    /// The specular transmission (refraction, or straight through a thin
    /// wall): its direction (local frame) and value.
    pub transmit: Option<(Vec3A, Vec3A)>,
}

impl GuideLobes {
    /// Nothing scattered.
    pub const NONE: GuideLobes = GuideLobes {
        rough: Vec3A::ZERO,
        reflect: None,
        transmit: None,
    };

    /// Only a rough part of albedo `rough`.
    pub fn rough(rough: Vec3A) -> GuideLobes {
        GuideLobes {
            rough: unit_range(rough),
            ..GuideLobes::NONE
        }
    }

    /// A lobe's direction and value if it carries anything.
    fn lobe(wi: Vec3A, value: Vec3A) -> Option<(Vec3A, Vec3A)> {
        let value = unit_range(value);
        (wi.is_finite() && value.max_element() > 0.0).then_some((wi, value))
    }
}

/// `v` clamped to `[0, 1]`, zero if not finite.
#[inline]
fn unit_range(v: Vec3A) -> Vec3A {
    finite_or_zero(v).clamp(Vec3A::ZERO, Vec3A::ONE)
}

/// An orthonormal basis `(t, b, n)` with `n` as the local `+z` axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent (local `+x`).
    pub t: Vec3A,
    /// Second tangent (local `+y`), `n × t`.
    pub b: Vec3A,
    /// The normal (local `+z`).
    pub n: Vec3A,
}

impl Frame {
    /// A right-handed frame around the unit normal `n`, without branches (Duff et
    /// al. 2017, "Building an orthonormal basis, revisited"); accurate for every
    /// unit `n`, including those near `±z`.
    #[inline]
    pub fn from_normal(n: Vec3A) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bt = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { t, b: bt, n }
    }

    /// World direction `v` in this frame's coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// Local direction `v` in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

/// A surface's scattering model. See the module documentation for the frame,
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

/// One direction drawn by [`Material::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction, in the local frame (unit length).
    pub wi: Vec3A,
    /// `f(wo, wi) |cos θi| / pdf`: what the path throughput is multiplied by.
    pub weight: Vec3A,
    /// Solid-angle density of `wi`; for a delta lobe (`specular`), the discrete
    /// probability with which that lobe was chosen.
    pub pdf: f32,
    /// Whether `wi` came from a delta lobe (no MIS with light sampling possible).
    pub specular: bool,
}

/// Mirror reflection of `wo` about the local normal `+z`.
#[inline]
fn reflect_z(wo: Vec3A) -> Vec3A {
    Vec3A::new(-wo.x, -wo.y, wo.z)
}

/// Exact unpolarised Fresnel reflectance of a smooth dielectric interface.
///
/// `eta` is the index of the medium the normal points away from (inside) over
/// that of the medium it points into (outside): `ior` for glass in air. `cos_i` is
/// the cosine between the normal and the direction light arrives from (or leaves
/// to): positive on the outside, negative on the inside, where the media swap
/// roles. Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Exact unpolarised Fresnel reflectance of a conductor with complex index of
/// refraction `eta + i k` (relative to the outside medium), per channel, for light
/// arriving at angle `acos(cos_i)` (clamped to `[0, 1]`). A channel with infinite
/// `k` is a perfect conductor and reflects exactly 1.
///
/// This is the closed form of the complex Fresnel equations used by pbrt-v3
/// (`FrConductor`), exact for unpolarised light.
pub fn fresnel_conductor(cos_i: f32, eta: Vec3A, k: Vec3A) -> Vec3A {
    let c = cos_i.clamp(0.0, 1.0);
    let f = |eta: f32, k: f32| -> f32 {
        if k.is_infinite() {
            return 1.0;
        }
        let cos2 = c * c;
        let sin2 = 1.0 - cos2;
        let eta2 = eta * eta;
        let k2 = k * k;
        let t0 = eta2 - k2 - sin2;
        let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).max(0.0).sqrt();
        let t1 = a2_plus_b2 + cos2;
        let a = (0.5 * (a2_plus_b2 + t0)).max(0.0).sqrt();
        let t2 = 2.0 * c * a;
        let r_s = (t1 - t2) / (t1 + t2);
        let t3 = cos2 * a2_plus_b2 + sin2 * sin2;
        let t4 = t2 * sin2;
        let r_p = r_s * (t3 - t4) / (t3 + t4);
        let r = 0.5 * (r_p + r_s);
        // 0/0 only for the degenerate index 0 + 0i at grazing incidence.
        if r.is_finite() {
            r.clamp(0.0, 1.0)
        } else {
            1.0
        }
    };
    Vec3A::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

/// GGX / Trowbridge–Reitz microfacet distribution for a unit microfacet normal
/// `m` in the local frame (zero below the horizon).
#[inline]
fn ggx_d(alpha: f32, m: Vec3A) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    // α² / (π (z²(α²−1) + 1)²), written without the cancellation of 1 − z² near
    // the pole: (x² + y²)/α² + z² is accurate for m close to +z.
    let a2 = alpha * alpha;
    let s = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    1.0 / (PI * a2 * s * s)
}

/// Smith's Λ for GGX: `(√(1 + α² tan² θ) − 1) / 2`; infinite at the horizon.
#[inline]
fn ggx_lambda(alpha: f32, w: Vec3A) -> f32 {
    let z2 = w.z * w.z;
    let xy2 = w.x * w.x + w.y * w.y;
    if z2 == 0.0 {
        return f32::INFINITY;
    }
    let a2_tan2 = alpha * alpha * xy2 / z2;
    // (√(1+x) − 1)/2 = x / (2 (√(1+x) + 1)), without cancellation for small x.
    a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
}

/// Samples a GGX normal visible from `wo` (`wo.z > 0`) with density
/// `G1(wo) max(0, wo·m) D(m) / cos θo` (Heitz 2018, "Sampling the GGX
/// Distribution of Visible Normals").
#[inline]
fn ggx_sample_visible_normal(alpha: f32, wo: Vec3A, u: Vec2) -> Vec3A {
    ggx_sample_visible_normal_xy(alpha, alpha, wo, u)
}

/// [`ggx_sample_visible_normal`] of the anisotropic GGX of widths `alpha_x`
/// along local `x` and `alpha_y` along `y` (the same arithmetic: with equal
/// widths, the isotropic sample bit for bit).
#[inline]
fn ggx_sample_visible_normal_xy(alpha_x: f32, alpha_y: f32, wo: Vec3A, u: Vec2) -> Vec3A {
    // Stretch the view direction to the hemisphere configuration (α = 1).
    let vh = Vec3A::new(alpha_x * wo.x, alpha_y * wo.y, wo.z).normalize();
    // An orthonormal basis around it (T1 lies in the tangent plane).
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3A::new(-vh.y, vh.x, 0.0) * len2.sqrt().recip()
    } else {
        Vec3A::X
    };
    let t2 = vh.cross(t1);
    // A point on the projected disk, warped to the visible half.
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (sin_phi, cos_phi) = phi.sin_cos();
    let p1 = r * cos_phi;
    let p2 = r * sin_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    // Unstretch.
    Vec3A::new(alpha_x * nh.x, alpha_y * nh.y, nh.z.max(0.0)).normalize()
}

/// Maps `u ∈ [0,1)²` to the unit disk, preserving area and strata (Shirley and
/// Chiu 1997, concentric mapping).
#[inline]
pub(crate) fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // The angle from the larger axis, φ ∈ [−π/4, π/4]; on the y side the
    // point's angle is π/2 − φ, whose cosine and sine are φ's sine and cosine.
    // (One division for either side.)
    let x_major = o.x.abs() > o.y.abs();
    let (r, other) = if x_major { (o.x, o.y) } else { (o.y, o.x) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * (other / r));
    let (x, y) = if x_major { (c, s) } else { (s, c) };
    r * Vec2::new(x, y)
}

/// Sine and cosine of `x` in `[−π/4, π/4]` by Cephes' minimax polynomials
/// (within 2 ulp of the library's, tested): the library call took 36
/// instructions, a tenth of a diffuse bounce's own work.
#[inline]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let sin = x + x * x2 * (-1.666_665_5e-1 + x2 * (8.332_161e-3 + x2 * -1.951_529_6e-4));
    let cos =
        1.0 - 0.5 * x2 + x2 * x2 * (4.166_664_6e-2 + x2 * (-1.388_731_6e-3 + x2 * 2.443_315_7e-5));
    (sin, cos)
}

/// Whether `w` is strictly above the local horizon (false for NaN).
#[inline]
fn above(w: Vec3A) -> bool {
    w.z > 0.0
}

/// Returns `v` if every component is finite, else zero.
#[inline]
fn finite_or_zero(v: Vec3A) -> Vec3A {
    if v.is_finite() { v } else { Vec3A::ZERO }
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
        if let Material::Pbr(p) = self {
            p.orient_anisotropy(frame, t, b);
        }
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

    /// Whether [`Material::sample`] reads `u_lobe` (glass and the glTF
    /// material choose between lobes).
    #[inline]
    pub fn chooses_lobe(&self) -> bool {
        matches!(self, Material::Dielectric { .. } | Material::Pbr(_))
    }

    /// Whether the material has only delta lobes (mirror, glass, smooth
    /// conductors, a smooth [`Material::Pbr`] without a diffuse part):
    /// next-event estimation cannot hit them, so an integrator should only follow
    /// [`Material::sample`].
    pub fn is_specular(&self) -> bool {
        match *self {
            Material::Diffuse { .. } => false,
            Material::Mirror { .. } | Material::Dielectric { .. } => true,
            Material::RoughConductor { alpha, .. } => Self::is_smooth(alpha),
            Material::Pbr(ref p) => p.is_specular(),
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
        };
        finite_or_zero(a).clamp(Vec3A::ZERO, Vec3A::ONE)
    }

    /// Whether light may pass through the surface (glass, glTF transmission
    /// or diffuse transmission): it is then lit from both sides.
    #[inline]
    pub fn transmits(&self) -> bool {
        match *self {
            Material::Dielectric { .. } => true,
            Material::Pbr(ref p) => {
                (p.transmission > 0.0 && p.metallic < 1.0) || p.transmits_diffusely()
            }
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
        let specular = |alpha: f32| Self::is_smooth(alpha) || alpha <= GUIDE_ALPHA;
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
        }
    }

    /// NaN counts as smooth too: never a NaN in the microfacet code.
    #[inline]
    fn is_smooth(alpha: f32) -> bool {
        alpha.is_nan() || alpha < ALPHA_SMOOTH
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
                if Self::is_smooth(alpha) || !above(wo) || !above(wi) {
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
                if Self::is_smooth(alpha) || !above(wo) || !above(wi) {
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
            Material::Dielectric { ior } => Self::sample_dielectric(ior, wo, u_lobe),
            Material::RoughConductor { alpha, eta, k } => {
                if !above(wo) {
                    return None;
                }
                if Self::is_smooth(alpha) {
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
        }
    }

    /// Smooth glass: reflect with probability `F`, refract otherwise; both weights
    /// are exactly 1 (see the module documentation on radiance scaling).
    fn sample_dielectric(ior: f32, wo: Vec3A, u_lobe: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() || ior.is_nan() || ior <= 0.0 {
            return None;
        }
        let (eta, sin2_t, f) = dielectric_interface(ior, wo);
        if sin2_t >= 1.0 || u_lobe < f {
            return Some(BsdfSample {
                wi: reflect_z(wo),
                weight: Vec3A::ONE,
                pdf: f,
                specular: true,
            });
        }
        Some(BsdfSample {
            wi: dielectric_refraction(wo, eta, sin2_t),
            weight: Vec3A::ONE,
            pdf: 1.0 - f,
            specular: true,
        })
    }
}

/// For `wo` at a smooth dielectric interface of index `ior` (inside, on the
/// `−z` side): the relative index across it as seen from `wo`'s side, the
/// refracted sine squared (at least 1 under total internal reflection) and
/// the Fresnel reflectance.
#[inline]
fn dielectric_interface(ior: f32, wo: Vec3A) -> (f32, f32, f32) {
    let (eta, cos_o) = if wo.z > 0.0 {
        (ior, wo.z)
    } else {
        (1.0 / ior, -wo.z)
    };
    let cos_o = cos_o.min(1.0);
    let sin2_t = (1.0 - cos_o * cos_o) / (eta * eta);
    (eta, sin2_t, fresnel_dielectric(cos_o, eta))
}

/// The direction `wo` refracts to through a smooth dielectric interface (the
/// local `z = 0` plane), `eta` the index across it as seen from `wo`'s side
/// and `sin2_t < 1` the refracted sine squared.
#[inline]
fn dielectric_refraction(wo: Vec3A, eta: f32, sin2_t: f32) -> Vec3A {
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // Snell: the tangential part shrinks by 1/eta, the normal part flips side.
    let side = wo.z.signum();
    Vec3A::new(-wo.x / eta, -wo.y / eta, -side * cos_t).normalize()
}

#[cfg(test)]
mod tests {
    use super::test_util::*;
    use super::*;

    /// The polynomial sine and cosine stay within 2 ulp of the library's over
    /// the quarter circle the concentric mapping uses.
    #[test]
    fn quarter_sine_and_cosine_match_the_library() {
        let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).abs();
        let n = 200_000;
        for i in 0..=n {
            let x = FRAC_PI_4 * (2.0 * i as f32 / n as f32 - 1.0);
            let (s, c) = sin_cos_quarter(x);
            let (ls, lc) = x.sin_cos();
            assert!(ulps(c, lc) <= 2, "cos({x}) = {c}, library {lc}");
            assert!(
                ulps(s, ls) <= 2 || (s - ls).abs() <= 1e-10,
                "sin({x}) = {s}, library {ls}"
            );
        }
    }

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

    // ---------------------------------------------------------------- Frame

    #[test]
    fn frame_is_orthonormal_for_random_normals_incl_poles() {
        let mut r = rng(1);
        let mut normals: Vec<Vec3A> = (0..10_000).map(|_| sphere(&mut r)).collect();
        // The troublesome neighbourhoods of ±z, down to f32 resolution.
        for &e in &[0.0f32, 1e-8, 1e-6, 1e-4, 1e-2] {
            for &s in &[1.0f32, -1.0] {
                normals.push(Vec3A::new(e, 0.0, s).normalize());
                normals.push(Vec3A::new(-e, e, s).normalize());
                normals.push(Vec3A::new(0.0, -e, s).normalize());
            }
        }
        // z = −0.0 picks the −z branch of the frame.
        normals.push(Vec3A::new(1.0, 0.0, -0.0));
        let mut worst = 0.0f32;
        for n in normals {
            let f = Frame::from_normal(n);
            let errs = [
                (f.t.length() - 1.0).abs(),
                (f.b.length() - 1.0).abs(),
                f.t.dot(f.b).abs(),
                f.t.dot(f.n).abs(),
                f.b.dot(f.n).abs(),
                (f.t.cross(f.b) - f.n).abs().max_element(),
            ];
            let v = sphere(&mut r);
            let round_trip = (f.to_world(f.to_local(v)) - v).abs().max_element();
            let local_n = (f.to_local(n) - Vec3A::Z).abs().max_element();
            let e = errs.into_iter().fold(round_trip.max(local_n), f32::max);
            assert!(e < 1e-5, "frame of {n:?}: error {e}, {f:?}");
            worst = worst.max(e);
        }
        eprintln!("frame: worst orthonormality error {worst:e}");
    }

    // ------------------------------------------------- χ² goodness of fit

    #[test]
    fn chi2_p_value_matches_known_quantiles() {
        // χ²(1) at 3.841459 and χ²(10) at 23.209251 have p = 0.05 and 0.01.
        assert!((gamma_q(0.5, 3.841_459 / 2.0) - 0.05).abs() < 1e-6);
        assert!((gamma_q(5.0, 23.209_251 / 2.0) - 0.01).abs() < 1e-6);
        assert!((gamma_q(50.0, 135.807 / 2.0) - 0.01).abs() < 1e-5);
        assert!((gamma_q(15.0, 43.773 / 2.0) - 0.05).abs() < 1e-5);
    }

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

    // ------------------------------------------------------- dielectrics

    #[test]
    fn dielectric_fresnel_at_normal_incidence() {
        for ior in [1.0f32, 1.33, 1.5, 2.4] {
            let r0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, ior) - r0).abs() < 1e-6);
            assert!(
                (fresnel_dielectric(-1.0, ior) - r0).abs() < 1e-6,
                "from inside"
            );
            if ior == 1.0 {
                continue; // F = 0: no reflection lobe to check
            }
            // The reflected lobe's probability is F.
            let m = Material::Dielectric { ior };
            let s = m.sample(Vec3A::Z, 0.0, Vec2::ZERO).unwrap();
            assert!(s.specular && (s.pdf - r0).abs() < 1e-6, "{s:?}");
            assert_eq!(s.wi, Vec3A::Z);
        }
        // F(glass, 1.5) at normal incidence is 0.04; at 60° it is 0.0892 (s 0.1774,
        // p 0.0018), and grazing reflects everything.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(0.5, 1.5) - 0.089_6).abs() < 5e-4);
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn dielectric_total_internal_reflection_from_inside() {
        let ior = 1.5f32;
        let critical = (1.0 / ior).asin().to_degrees(); // 41.81°
        let m = Material::Dielectric { ior };
        for theta in [critical + 0.05, 50.0, 70.0, 89.0] {
            let wo = -dir(theta, 0.4); // inside: wo.z < 0
            assert!(wo.z < 0.0);
            assert_eq!(fresnel_dielectric(wo.z, ior), 1.0);
            for ul in [0.0, 0.5, 0.999_999] {
                let s = m.sample(wo, ul, Vec2::ZERO).unwrap();
                assert_eq!(s.pdf, 1.0);
                assert!(s.wi.z < 0.0, "TIR stays inside: {s:?}");
                assert!((s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
            }
        }
        // Just inside the critical angle, some light still escapes.
        let wo = -dir(critical - 0.5, 0.4);
        let s = m.sample(wo, 0.999, Vec2::ZERO).unwrap();
        assert!(s.wi.z > 0.0 && s.pdf > 0.0 && s.pdf < 1.0, "{s:?}");
    }

    #[test]
    fn dielectric_refraction_obeys_snell() {
        let mut worst = 0.0f32;
        for ior in [1.33f32, 1.5, 2.4] {
            let m = Material::Dielectric { ior };
            for theta in [0.0f32, 10.0, 30.0, 60.0, 85.0] {
                for (outside, wo) in [(true, dir(theta, 1.1)), (false, -dir(theta * 0.5, 1.1))] {
                    let Some(s) = m.sample(wo, 0.999_999, Vec2::ZERO) else {
                        panic!("no sample");
                    };
                    if s.wi.z * wo.z > 0.0 {
                        continue; // total internal reflection
                    }
                    let (n_o, n_i) = if outside { (1.0, ior) } else { (ior, 1.0) };
                    let sin_o = (wo.x * wo.x + wo.y * wo.y).sqrt();
                    let sin_i = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
                    assert!((s.wi.length() - 1.0).abs() < 1e-6);
                    assert!(
                        (n_o * sin_o - n_i * sin_i).abs() < 1e-5,
                        "Snell {ior} {theta}"
                    );
                    // In the plane of incidence, on the other side of the normal.
                    if sin_o > 1e-6 {
                        let c = wo.x * s.wi.y - wo.y * s.wi.x;
                        assert!(c.abs() < 1e-6 && wo.x * s.wi.x + wo.y * s.wi.y < 0.0);
                        worst = worst.max((sin_o / sin_i - n_i / n_o).abs());
                    }
                    assert!(s.pdf > 0.0 && s.weight == Vec3A::ONE);
                }
            }
        }
        eprintln!("Snell: worst |sin ratio − index ratio| {worst:e}");
    }

    #[test]
    fn dielectric_conserves_energy_at_normal_and_grazing_incidence() {
        let m = Material::Dielectric { ior: 1.5 };
        for theta in [0.0, 45.0, 85.0, 89.9] {
            for wo in [dir(theta, 0.2), -dir(theta * 0.4, 0.2)] {
                let f = fresnel_dielectric(wo.z, 1.5);
                // R + T: the two lobes' probabilities add to one and each weight
                // is 1, so the mean weight is exactly 1.
                let r = m.sample(wo, 0.0, Vec2::ZERO).unwrap();
                let t = m.sample(wo, 0.999_999, Vec2::ZERO).unwrap();
                assert_eq!(r.weight, Vec3A::ONE);
                assert_eq!(t.weight, Vec3A::ONE);
                if f < 1.0 {
                    assert!((r.pdf + t.pdf - 1.0).abs() < 1e-6 && r.wi != t.wi);
                }
                // The fraction reflected is F.
                let mut rg = rng(41);
                let n = 200_000;
                let mut reflected = 0usize;
                let mut total = 0.0f64;
                for _ in 0..n {
                    let s = m.sample(wo, rg.next_f32(), Vec2::ZERO).unwrap();
                    total += s.weight.x as f64;
                    reflected += (s.wi.z * wo.z > 0.0) as usize;
                }
                let frac = reflected as f64 / n as f64;
                let sigma = (f as f64 * (1.0 - f as f64) / n as f64).sqrt();
                assert_eq!(total / n as f64, 1.0);
                assert!(
                    (frac - f as f64).abs() < 5.0 * sigma + 1e-6,
                    "{frac} vs F {f}"
                );
            }
        }
        eprintln!("dielectric furnace: R + T = 1 (exact) at θ = 0°, 45°, 85°, 89.9°, both sides");
    }

    // ------------------------------------------------- conductor Fresnel

    #[test]
    fn conductor_fresnel_known_values() {
        // Normal incidence: ((n−1)² + k²) / ((n+1)² + k²).
        let (eta, k) = (Vec3A::new(0.2, 0.9, 1.5), Vec3A::new(3.9, 2.4, 0.0));
        let f = fresnel_conductor(1.0, eta, k);
        let r0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!(rel_err(f, r0) < 1e-5, "{f:?} vs {r0:?}");
        // k = 0 is a dielectric, at every angle.
        for c in [1.0f32, 0.8, 0.5, 0.2, 0.01] {
            let fc = fresnel_conductor(c, Vec3A::splat(1.5), Vec3A::ZERO).x;
            assert!((fc - fresnel_dielectric(c, 1.5)).abs() < 1e-5, "cos {c}");
        }
        // Grazing reflects everything; a perfect conductor reflects everything always.
        assert!(
            (fresnel_conductor(0.0, eta, k) - Vec3A::ONE)
                .abs()
                .max_element()
                < 1e-5
        );
        for c in [0.0f32, 0.3, 1.0] {
            assert_eq!(
                fresnel_conductor(c, Vec3A::ONE, Vec3A::splat(f32::INFINITY)),
                Vec3A::ONE
            );
        }
        // Gold is yellow: red reflects more than blue at normal incidence.
        let Material::RoughConductor { eta, k, .. } = Material::gold(0.1) else {
            unreachable!()
        };
        let g = fresnel_conductor(1.0, eta, k);
        eprintln!("gold F0 = {g:?}");
        assert!(g.x > 0.9 && g.z < 0.5, "{g:?}");
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
