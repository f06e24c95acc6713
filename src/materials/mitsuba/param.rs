//! The scalar parameters of Mitsuba's BSDFs that a texture may vary over a
//! surface ([`Param`]): a Mitsuba scene's `<texture name="alpha_u" …>`
//! becomes a pattern evaluated at each hit and set with
//! [`Material::set_param`](super::super::Material::set_param).

/// A scalar parameter of a Mitsuba BSDF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// The microfacet width along the tangent (`alpha_u`; a textured
    /// isotropic `alpha` sets both widths).
    AlphaU,
    /// The microfacet width along the bitangent (`alpha_v`).
    AlphaV,
    /// A scalar parameter of `principled` or `principledthin`.
    Principled(super::principled::PrincipledParam),
    /// A `blendbsdf`'s `weight`, the share of its second BSDF
    /// ([`Blend::set_weight`](super::super::Blend::set_weight)).
    Weight,
}
