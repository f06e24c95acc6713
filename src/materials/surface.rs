//! Surface materials: what the scene's material table holds. A material is
//! either a fixed BSDF (the lab box's parts, OBJ colours) or the glTF 2.0
//! metallic–roughness material with its textures, which becomes a
//! [`Material::Pbr`] at each hit once its textures are looked up.

use glam::{Vec2, Vec3A, Vec4, Vec4Swizzles};

use super::{Material, PbrBsdf};
use crate::textures::{ColorSpace, TextureRef, TextureStore};

/// How a material's alpha (base colour alpha × texture alpha × `COLOR_0` alpha)
/// makes holes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Points with alpha below the cut-off are holes for every ray.
    Mask(f32),
    /// Alpha is the probability that a ray stops at the surface (stochastic and
    /// unbiased coverage).
    Blend,
}

/// Attributes interpolated at a hit that textures and colours depend on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitAttributes {
    /// Texture coordinate sets 0 and 1 (zero where the mesh has none).
    pub uv: [Vec2; 2],
    /// `COLOR_0` (white where the mesh has none).
    pub color: Vec4,
}

impl Default for HitAttributes {
    fn default() -> Self {
        Self {
            uv: [Vec2::ZERO; 2],
            color: Vec4::ONE,
        }
    }
}

/// The glTF metallic–roughness material and the extensions raylab reads, with
/// factors and textures as the file gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    /// `baseColorFactor` (linear RGBA).
    pub base_color: Vec4,
    /// `baseColorTexture` (sRGB).
    pub base_color_texture: Option<TextureRef>,
    /// `metallicFactor`.
    pub metallic: f32,
    /// `roughnessFactor`.
    pub roughness: f32,
    /// `metallicRoughnessTexture`: roughness in G, metallic in B (linear).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// `normalTexture` (linear, tangent space).
    pub normal_texture: Option<TextureRef>,
    /// `normalTexture.scale`: multiplies the normal's x and y.
    pub normal_scale: f32,
    /// `KHR_materials_ior` (1.5 by default).
    pub ior: f32,
    /// `KHR_materials_specular` `specularFactor` (1 by default).
    pub specular: f32,
    /// Its `specularTexture` (alpha channel).
    pub specular_texture: Option<TextureRef>,
    /// `specularColorFactor` (1 by default).
    pub specular_color: Vec3A,
    /// Its `specularColorTexture` (sRGB).
    pub specular_color_texture: Option<TextureRef>,
    /// `KHR_materials_transmission` `transmissionFactor` (0 by default).
    pub transmission: f32,
    /// Its `transmissionTexture` (red channel).
    pub transmission_texture: Option<TextureRef>,
    /// Transmission without `KHR_materials_volume` (or with zero thickness):
    /// light continues straight through.
    pub thin_walled: bool,
    /// Beer–Lambert attenuation coefficient per unit length inside the volume
    /// (`−ln(attenuationColor) / attenuationDistance`); zero for clear media.
    pub attenuation: Vec3A,
    /// OBJ `map_Pr`: multiplies the roughness by its red (grey) channel.
    pub roughness_texture: Option<TextureRef>,
    /// OBJ `map_Pm`: multiplies the metallic factor by its red (grey) channel.
    pub metallic_texture: Option<TextureRef>,
    /// OBJ `map_d`: multiplies alpha by its alpha channel, or by its red
    /// channel when `alpha_from_red` (images without alpha).
    pub alpha_texture: Option<TextureRef>,
    /// Whether `alpha_texture`'s red channel is the alpha.
    pub alpha_from_red: bool,
    /// `KHR_materials_clearcoat`: `clearcoatFactor` (0: no coat).
    pub clearcoat: f32,
    /// Its `clearcoatTexture` (red channel).
    pub clearcoat_texture: Option<TextureRef>,
    /// `clearcoatRoughnessFactor`.
    pub clearcoat_roughness: f32,
    /// Its `clearcoatRoughnessTexture` (green channel).
    pub clearcoat_roughness_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture`; without it the coat takes the surface's
    /// normal before the base's normal map.
    pub clearcoat_normal_texture: Option<TextureRef>,
    /// That normal map's `scale`.
    pub clearcoat_normal_scale: f32,
}

impl Default for GltfMaterial {
    /// glTF's default material: white, fully metallic and rough.
    fn default() -> Self {
        Self {
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            ior: 1.5,
            specular: 1.0,
            specular_texture: None,
            specular_color: Vec3A::ONE,
            specular_color_texture: None,
            transmission: 0.0,
            transmission_texture: None,
            thin_walled: true,
            attenuation: Vec3A::ZERO,
            roughness_texture: None,
            metallic_texture: None,
            alpha_texture: None,
            alpha_from_red: false,
            clearcoat: 0.0,
            clearcoat_texture: None,
            clearcoat_roughness: 0.0,
            clearcoat_roughness_texture: None,
            clearcoat_normal_texture: None,
            clearcoat_normal_scale: 1.0,
        }
    }
}

/// What the BSDF of a material is.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// One BSDF everywhere (the box's parts, OBJ colours).
    Fixed(Material),
    /// The glTF material, evaluated per hit.
    Gltf(Box<GltfMaterial>),
}

/// One entry of a scene's material table.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMaterial {
    /// The name in the file (empty when it has none).
    pub name: String,
    /// The lab's reflectance ρ, which `flat` and `direct` show for fixed
    /// materials (glTF materials show their base colour).
    pub reflectance: Vec3A,
    /// The BSDF.
    pub kind: MaterialKind,
    /// Emitted radiance (`emissiveFactor × KHR_materials_emissive_strength`).
    pub emission: Vec3A,
    /// `emissiveTexture` (sRGB), multiplying `emission`.
    pub emission_texture: Option<TextureRef>,
    /// Whether light leaves both faces (`doubleSided`), not only the front.
    pub emits_both_sides: bool,
    /// How alpha makes holes.
    pub alpha: AlphaMode,
}

impl SurfaceMaterial {
    /// A Lambertian material of reflectance `rho`, for `path` and for the lab's
    /// `flat` and `direct`.
    pub fn diffuse(rho: Vec3A) -> Self {
        Self::fixed(rho, Material::Diffuse { reflectance: rho })
    }

    /// A fixed BSDF, with `rho` for `flat` and `direct`.
    pub fn fixed(rho: Vec3A, bsdf: Material) -> Self {
        Self {
            name: String::new(),
            reflectance: rho,
            kind: MaterialKind::Fixed(bsdf),
            emission: Vec3A::ZERO,
            emission_texture: None,
            emits_both_sides: false,
            alpha: AlphaMode::Opaque,
        }
    }

    /// Whether the material can emit light at all.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Whether a normal map perturbs the shading normal.
    pub fn normal_texture(&self) -> Option<(&TextureRef, f32)> {
        match &self.kind {
            MaterialKind::Gltf(g) => g.normal_texture.as_ref().map(|t| (t, g.normal_scale)),
            MaterialKind::Fixed(_) => None,
        }
    }

    /// Base colour (RGB) and alpha at a hit: the fixed reflectance with alpha 1,
    /// or glTF's `baseColorFactor × baseColorTexture × COLOR_0`.
    #[inline]
    pub fn base_color(&self, attrs: &HitAttributes, textures: &TextureStore) -> Vec4 {
        match &self.kind {
            MaterialKind::Fixed(_) => self.reflectance.extend(1.0),
            MaterialKind::Gltf(g) => {
                let mut c = g.base_color * attrs.color;
                if let Some(t) = &g.base_color_texture {
                    c *= lookup(t, attrs, textures, ColorSpace::Srgb);
                }
                if let Some(t) = &g.alpha_texture {
                    let a = lookup(t, attrs, textures, ColorSpace::Linear);
                    c.w *= if g.alpha_from_red { a.x } else { a.w };
                }
                c
            }
        }
    }

    /// The alpha that decides holes (1 for opaque materials).
    #[inline]
    pub fn alpha_at(&self, attrs: &HitAttributes, textures: &TextureStore) -> f32 {
        match self.alpha {
            AlphaMode::Opaque => 1.0,
            _ => self.base_color(attrs, textures).w,
        }
    }

    /// The BSDF at a hit. (The fixed materials inlined, the glTF one out of
    /// line: as one call, the lab box's `path` spent 1.8 % more.)
    #[inline(always)]
    pub fn bsdf(&self, attrs: &HitAttributes, textures: &TextureStore) -> Material {
        match &self.kind {
            MaterialKind::Fixed(m) => *m,
            MaterialKind::Gltf(g) => self.gltf_bsdf(g, attrs, textures),
        }
    }

    /// [`SurfaceMaterial::bsdf`] of a glTF material: textures looked up.
    #[inline(never)]
    fn gltf_bsdf(
        &self,
        g: &GltfMaterial,
        attrs: &HitAttributes,
        textures: &TextureStore,
    ) -> Material {
        let base = Vec3A::from(self.base_color(attrs, textures).xyz());
        let (mut metallic, mut roughness) = (g.metallic, g.roughness);
        if let Some(t) = &g.metallic_roughness_texture {
            let mr = lookup(t, attrs, textures, ColorSpace::Linear);
            roughness *= mr.y;
            metallic *= mr.z;
        }
        if let Some(t) = &g.roughness_texture {
            roughness *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        if let Some(t) = &g.metallic_texture {
            metallic *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        let mut specular = g.specular;
        if let Some(t) = &g.specular_texture {
            specular *= lookup(t, attrs, textures, ColorSpace::Linear).w;
        }
        let mut specular_color = g.specular_color;
        if let Some(t) = &g.specular_color_texture {
            specular_color *= Vec3A::from(lookup(t, attrs, textures, ColorSpace::Srgb).xyz());
        }
        let mut transmission = g.transmission;
        if let Some(t) = &g.transmission_texture {
            transmission *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        let clamp01 = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        let roughness = clamp01(roughness);
        let (mut coat, mut coat_roughness) = (g.clearcoat, g.clearcoat_roughness);
        if coat > 0.0 {
            if let Some(t) = &g.clearcoat_texture {
                coat *= lookup(t, attrs, textures, ColorSpace::Linear).x;
            }
            if let Some(t) = &g.clearcoat_roughness_texture {
                coat_roughness *= lookup(t, attrs, textures, ColorSpace::Linear).y;
            }
        }
        let coat_roughness = clamp01(coat_roughness);
        Material::Pbr(PbrBsdf {
            base_color: base.clamp(Vec3A::ZERO, Vec3A::ONE),
            metallic: clamp01(metallic),
            alpha: (roughness * roughness).max(1e-4),
            ior: g.ior,
            specular: clamp01(specular),
            specular_color: specular_color.max(Vec3A::ZERO),
            transmission: clamp01(transmission),
            thin_walled: g.thin_walled,
            coat: clamp01(coat),
            coat_alpha: PbrBsdf::alpha_from_roughness(coat_roughness),
            coat_normal: Vec3A::Z,
        })
    }

    /// Emitted radiance at a hit (before the side test).
    #[inline]
    pub fn emitted(&self, attrs: &HitAttributes, textures: &TextureStore) -> Vec3A {
        match &self.emission_texture {
            Some(t) if self.is_emissive() => {
                self.emission * Vec3A::from(lookup(t, attrs, textures, ColorSpace::Srgb).xyz())
            }
            _ => self.emission,
        }
    }

    /// The tangent-space normal of the normal map at a hit: the texel mapped
    /// from `[0, 1]` to `[−1, 1]`, x and y scaled by `normalTexture.scale`.
    #[inline]
    pub fn mapped_normal(&self, attrs: &HitAttributes, textures: &TextureStore) -> Option<Vec3A> {
        let (t, scale) = self.normal_texture()?;
        Some(tangent_normal(t, scale, attrs, textures))
    }

    /// Beer–Lambert attenuation inside the material's volume (zero if none).
    pub fn attenuation(&self) -> Vec3A {
        match &self.kind {
            MaterialKind::Gltf(g) if !g.thin_walled => g.attenuation,
            _ => Vec3A::ZERO,
        }
    }

    /// Whether the material has a clear coat (`KHR_materials_clearcoat`).
    #[inline]
    pub fn has_coat(&self) -> bool {
        matches!(&self.kind, MaterialKind::Gltf(g) if g.clearcoat > 0.0)
    }

    /// The clear coat's normal map's tangent-space normal at a hit (not
    /// normalized), if it has one.
    #[inline]
    pub fn mapped_coat_normal(
        &self,
        attrs: &HitAttributes,
        textures: &TextureStore,
    ) -> Option<Vec3A> {
        match &self.kind {
            MaterialKind::Gltf(g) if g.clearcoat > 0.0 => {
                let t = g.clearcoat_normal_texture.as_ref()?;
                Some(tangent_normal(t, g.clearcoat_normal_scale, attrs, textures))
            }
            _ => None,
        }
    }
}

/// The tangent-space normal of normal map `t` with `scale` at a hit (not
/// normalized).
#[inline]
fn tangent_normal(
    t: &TextureRef,
    scale: f32,
    attrs: &HitAttributes,
    textures: &TextureStore,
) -> Vec3A {
    let texel = lookup(t, attrs, textures, ColorSpace::Linear);
    Vec3A::new(
        (2.0 * texel.x - 1.0) * scale,
        (2.0 * texel.y - 1.0) * scale,
        2.0 * texel.z - 1.0,
    )
}

/// A texture's value at a hit: the texture coordinate set it names, its
/// `KHR_texture_transform`, its sampler's wrap modes.
#[inline]
pub fn lookup(
    t: &TextureRef,
    attrs: &HitAttributes,
    textures: &TextureStore,
    space: ColorSpace,
) -> Vec4 {
    textures.lookup(t, attrs.uv[(t.tex_coord as usize).min(1)], space)
}

/// Every texture a material refers to.
pub fn texture_refs(m: &SurfaceMaterial) -> impl Iterator<Item = &TextureRef> {
    let gltf = match &m.kind {
        MaterialKind::Gltf(g) => Some(g.as_ref()),
        MaterialKind::Fixed(_) => None,
    };
    let textures = gltf.into_iter().flat_map(|g| {
        [
            &g.base_color_texture,
            &g.metallic_roughness_texture,
            &g.normal_texture,
            &g.specular_texture,
            &g.specular_color_texture,
            &g.transmission_texture,
            &g.roughness_texture,
            &g.metallic_texture,
            &g.alpha_texture,
            &g.clearcoat_texture,
            &g.clearcoat_roughness_texture,
            &g.clearcoat_normal_texture,
        ]
    });
    textures.chain([&m.emission_texture]).flatten()
}

/// Every texture a material refers to, for changing them (say, when the
/// material's images move to another store).
pub fn texture_refs_mut(m: &mut SurfaceMaterial) -> impl Iterator<Item = &mut TextureRef> {
    let gltf = match &mut m.kind {
        MaterialKind::Gltf(g) => Some(g.as_mut()),
        MaterialKind::Fixed(_) => None,
    };
    let textures = gltf.into_iter().flat_map(|g| {
        [
            &mut g.base_color_texture,
            &mut g.metallic_roughness_texture,
            &mut g.normal_texture,
            &mut g.specular_texture,
            &mut g.specular_color_texture,
            &mut g.transmission_texture,
            &mut g.roughness_texture,
            &mut g.metallic_texture,
            &mut g.alpha_texture,
            &mut g.clearcoat_texture,
            &mut g.clearcoat_roughness_texture,
            &mut g.clearcoat_normal_texture,
        ]
    });
    textures.chain([&mut m.emission_texture]).flatten()
}
