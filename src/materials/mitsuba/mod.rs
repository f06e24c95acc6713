//! Mitsuba 3's BSDFs, with its exact definitions (its RGB variant,
//! `scalar_rgb`), so that raylab renders a Mitsuba scene as Mitsuba does:
//! one file per Mitsuba plugin.
//!
//! * `conductor.rs`: `conductor`, [`Conductor`] (smooth metal);
//! * `rough_conductor.rs`: `roughconductor`, [`RoughConductor`];
//! * `dielectric.rs`: `dielectric`, [`SmoothDielectric`];
//! * `thin_dielectric.rs`: `thindielectric`, [`ThinDielectric`];
//! * `rough_dielectric.rs`: `roughdielectric`, [`RoughDielectric`];
//! * `plastic.rs`: `plastic`, [`Plastic`];
//! * `rough_plastic.rs`: `roughplastic`, [`RoughPlastic`], with its table of
//!   the rough interface's transmittance ([`RoughPlasticTable`]);
//! * `principled.rs`: `principled`, [`Principled`] (Burley's Disney BSDF),
//!   and the names of the principled BSDFs' scalar parameters
//!   ([`PrincipledParam`]);
//! * `principled_thin.rs`: `principledthin`, [`PrincipledThin`];
//! * `principled_common.rs`: what the two share (Mitsuba's
//!   `principledhelpers.h`).
//!
//! Mitsuba's `diffuse` is [`Material::Diffuse`](super::Material::Diffuse)
//! (the same one-sided Lambertian). The microfacet model they share is
//! [`MicrofacetDistribution`](super::MicrofacetDistribution).
//!
//! # Conventions
//!
//! raylab's `wo` (towards the viewer) is Mitsuba's `si.wi` and raylab's `wi`
//! Mitsuba's `wo`; Mitsuba's `eval` already includes the cosine, as raylab's
//! does. Mitsuba's conductors and plastics are one-sided (zero unless both
//! directions are above the surface); its dielectrics are interfaces whose
//! `+z` side is the outside (`ext_ior`), seen from either side. Its
//! `principled` is one-sided without transmission and an interface (`+z`
//! outside) with it; its `principledthin` is a sheet, the same from both
//! sides.
//!
//! Radiance mode: Mitsuba scales light *transmitted* through a dielectric by
//! `1/η²`, `η` the relative index across the interface in the direction the
//! path travels (Mitsuba's `eta_ti²` in `sample`, `inv_eta²` in `eval`), so a
//! sample that enters glass of index 1.5 weighs `1/2.25` and one that leaves
//! it `2.25`. raylab's own [`Material::Dielectric`](super::Material::Dielectric)
//! leaves that out (the factors telescope along a path whose ends are in
//! the same medium); these BSDFs keep it, as Mitsuba does, so that every
//! path's weight is Mitsuba's.
//!
//! # Parameters
//!
//! Mitsuba lets reflectances (and alpha, except `roughplastic`'s) be
//! textures. These types take plain values: whoever builds them evaluates
//! the textures at the hit and builds (or updates) the BSDF there, which is
//! cheap for all of them; the plastics' specular sampling weight, which
//! Mitsuba computes from the textures' *means*, is a parameter of its own
//! for that reason ([`specular_sampling_weight`]). The rough plastic's table
//! depends only on the distribution, alpha and the index, which Mitsuba
//! does not let vary. The principled BSDFs' scalar parameters are public
//! fields, also settable by name ([`PrincipledParam`],
//! [`Material::set_param`](super::Material::set_param)); their
//! base colour is the reflectance a texture replaces.
//!
//! Every `eta` here is Mitsuba's relative index `int_ior / ext_ior`; note
//! that Mitsuba's default `ext_ior` is air, 1.000277, not 1. Anisotropic
//! BSDFs turn with [`Material::orient_anisotropy`](super::Material::orient_anisotropy):
//! Mitsuba's `alpha_u` lies along its shading frame's first axis, `dp/du`.

mod common;
mod conductor;
mod dielectric;
mod param;
mod plastic;
mod principled;
mod principled_common;
mod principled_thin;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic;
#[cfg(test)]
mod tests;
mod thin_dielectric;

pub use common::Tangent;
pub use conductor::Conductor;
pub use dielectric::SmoothDielectric;
pub use param::Param;
pub use plastic::{Plastic, specular_sampling_weight};
pub use principled::{Principled, PrincipledParam};
pub use principled_thin::PrincipledThin;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::{RoughPlastic, RoughPlasticTable};
pub use thin_dielectric::ThinDielectric;
