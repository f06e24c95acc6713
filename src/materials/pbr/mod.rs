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
//!
//! # Files
//!
//! Each file adds to `impl PbrBsdf` what it is about, with its tests:
//!
//! * `params.rs`: the parameters, [`PbrBsdf`], and the weights of the parts
//!   that follow from them alone;
//! * `ggx.rs`: the base's GGX, isotropic or anisotropic
//!   (`KHR_materials_anisotropy`);
//! * `fresnel.rs`: the base's Fresnel terms, Schlick's mixed with a thin
//!   film's (`KHR_materials_iridescence`);
//! * `coat.rs`: the clear coat (`KHR_materials_clearcoat`);
//! * `lobes.rs`: what depends on `wo` alone, [`Local`]: the canonical frame
//!   and the lobes' probabilities;
//! * `sheen.rs`: the sheen over the base (`KHR_materials_sheen`);
//! * `transmission.rs`: rough transmission through a volume or a thin wall,
//!   dispersion and diffuse transmission;
//! * `eval.rs`: `f |cos θi|` and the mixture density;
//! * `sample.rs`: choosing a lobe and drawing a direction;
//! * `guides.rs`: the albedo and the denoiser's guides.

mod coat;
mod eval;
mod fresnel;
mod ggx;
mod guides;
mod lobes;
mod params;
mod sample;
mod sheen;
#[cfg(test)]
mod test_util;
mod transmission;

pub use coat::{COAT_F0, coat_fresnel};
pub use lobes::Local;
pub use params::{MIN_ALPHA, PbrBsdf};
