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
//! * Mitsuba 3's BSDFs ([`mitsuba`]) have Mitsuba's sides:
//!   [`Material::MiConductor`], [`Material::MiRoughConductor`],
//!   [`Material::MiPlastic`] and [`Material::MiRoughPlastic`] are one-sided
//!   like [`Material::Diffuse`] (zero unless `wo.z > 0` and `wi.z > 0`);
//!   [`Material::MiDielectric`], [`Material::MiThinDielectric`] and
//!   [`Material::MiRoughDielectric`] are interfaces (`+z` outside) and must
//!   not have their normal flipped; [`Material::MiPrincipled`] is one-sided
//!   without transmission and such an interface with it, and
//!   [`Material::MiPrincipledThin`] a sheet, the same from both sides.
//!   [`Material::MiBlend`] (Mitsuba's `blendbsdf`) has its parts' sides.
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
//! Mitsuba's dielectrics ([`mitsuba`]) do scale by `1/η²`, as Mitsuba does.
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
//!
//! # Files
//!
//! * `material.rs`: [`Material`], its evaluation, density and sampling, and
//!   [`BsdfAt`], a material seen from one direction;
//! * `dielectric.rs`: the smooth dielectric interface of
//!   [`Material::Dielectric`] (its Fresnel term, refraction and sampling);
//! * [`pbr`] (`pbr/`): the glTF BSDF, [`PbrBsdf`];
//! * `bsdf.rs`: what a BSDF gives back, [`BsdfSample`] and [`GuideLobes`];
//! * `frame.rs`: the local shading [`Frame`];
//! * `microfacet.rs`: GGX's distribution, masking and visible-normal sampling;
//!   its submodule `microfacet/mitsuba.rs` Mitsuba 3's Beckmann and GGX
//!   ([`MicrofacetDistribution`]: anisotropic, separable masking, Mitsuba's
//!   visible-normal sampling);
//! * [`mitsuba`] (`mitsuba/`): Mitsuba 3's `conductor`, `roughconductor`,
//!   `dielectric`, `thindielectric`, `roughdielectric`, `plastic`,
//!   `roughplastic`, `principled` and `principledthin`, a file each (Mitsuba's `diffuse` is
//!   [`Material::Diffuse`]);
//! * `blend.rs`: Mitsuba's `blendbsdf`, [`Blend`], the mixture of two of
//!   its BSDFs ([`BlendPart`]);
//! * `fresnel.rs`: the exact Fresnel terms, [`fresnel_dielectric`] and
//!   [`fresnel_conductor`], and Mitsuba's [`fresnel_mitsuba`] and
//!   [`fresnel_diffuse_reflectance`];
//! * `disk.rs`: the concentric mapping of the square onto the disk;
//! * [`sheen`], [`thin_film`] and [`spectrum`]: the sheen's microfibre BRDF,
//!   the iridescent film's Fresnel term and single wavelengths for dispersion;
//! * [`cie`] and [`blackbody`]: the CIE 1931 tables, and the colour of a
//!   blackbody at a temperature (emissive media's temperature grids);
//! * [`surface`]: the scene's material table (fixed BSDFs and glTF materials
//!   with their textures).

pub mod blackbody;
mod blend;
mod bsdf;
pub mod cie;
mod dielectric;
mod disk;
mod frame;
mod fresnel;
mod material;
mod microfacet;
pub mod mitsuba;
pub mod pbr;
pub mod sheen;
pub mod sheen_table;
pub mod spectrum;
pub mod surface;
#[cfg(test)]
pub(crate) mod test_util;
pub mod thin_film;

pub use blend::{Blend, BlendPart};
pub use bsdf::{BsdfSample, GUIDE_ALPHA, GuideLobes};
pub(crate) use disk::concentric_disk;
pub use frame::Frame;
pub use fresnel::{
    fresnel_conductor, fresnel_dielectric, fresnel_diffuse_reflectance, fresnel_mitsuba,
};
pub use material::{BsdfAt, Material};
pub(crate) use microfacet::gauss_legendre;
pub use microfacet::{ALPHA_SMOOTH, MicrofacetDistribution, MicrofacetKind};
pub use pbr::PbrBsdf;
