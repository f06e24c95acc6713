//! The glTF BSDF's parameters at one surface point, [`PbrBsdf`], and what
//! follows from them alone: the default material, the GGX width of a
//! roughness, and the weights and tints of the diffuse, transmitted,
//! diffusely transmitted and sheen parts.

use glam::{Vec2, Vec3A};

/// The smallest GGX `α` [`PbrBsdf::alpha_from_roughness`] returns.
pub const MIN_ALPHA: f32 = 1e-4;

/// The glTF metallic–roughness BSDF at one surface point, textures already applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrBsdf {
    /// Linear RGB in `[0, 1]` (`baseColorFactor` × texture × `COLOR_0`).
    pub base_color: Vec3A,
    /// Metalness in `[0, 1]`.
    pub metallic: f32,
    /// GGX `α = max(roughness², 1e-4)`, computed by the caller (see
    /// [`PbrBsdf::alpha_from_roughness`]); below
    /// [`ALPHA_SMOOTH`](crate::materials::ALPHA_SMOOTH) the specular lobes are deltas.
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

impl Default for PbrBsdf {
    /// glTF's default material: white, fully metallic, roughness 1.
    fn default() -> PbrBsdf {
        PbrBsdf::new(Vec3A::ONE, 1.0, 1.0)
    }
}

/// Rec. 709 luminance (the weights sum to 1), never negative.
#[inline]
pub(super) fn luminance(c: Vec3A) -> f32 {
    c.dot(Vec3A::new(0.2126, 0.7152, 0.0722)).max(0.0)
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

    /// glTF's perceptual roughness to GGX width: `max(roughness², 1e-4)`.
    #[inline]
    pub fn alpha_from_roughness(roughness: f32) -> f32 {
        (roughness * roughness).max(MIN_ALPHA)
    }

    /// Whether the material has a sheen (`KHR_materials_sheen`).
    #[inline]
    pub(super) fn has_sheen(&self) -> bool {
        self.sheen_color.max_element() > 0.0
    }

    #[inline]
    pub(super) fn diffuse_scale(&self) -> f32 {
        (1.0 - self.metallic) * (1.0 - self.transmission)
    }

    #[inline]
    pub(super) fn transmission_scale(&self) -> f32 {
        (1.0 - self.metallic) * self.transmission
    }

    /// The diffuse part's albedo per unit weight: `c` reflected, mixed with
    /// the diffuse transmission's colour by its share.
    #[inline]
    pub(super) fn diffuse_tint(&self) -> Vec3A {
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
    pub(super) fn base_tint(&self) -> Vec3A {
        if self.diffuse_transmission > 0.0 {
            let tr = self.transmission;
            self.diffuse_tint() * (1.0 - tr) + self.base_color * tr
        } else {
            self.base_color
        }
    }

    /// The base colour's share in the diffuse reflection: `(1 − dt) c`.
    #[inline]
    pub(super) fn reflected_diffuse(&self) -> Vec3A {
        let dt = self.diffuse_transmission;
        if dt > 0.0 {
            self.base_color * (1.0 - dt)
        } else {
            self.base_color
        }
    }

    /// Whether the diffuse part has a transmitted share
    /// (`KHR_materials_diffuse_transmission`) that can carry light: the
    /// surface is then lit from behind too.
    #[inline]
    pub fn transmits_diffusely(&self) -> bool {
        self.diffuse_transmission > 0.0
            && self.diffuse_scale() * luminance(self.diffuse_transmission_color) > 0.0
    }
}
