//! Surface materials: what the scene's material table holds. A material is
//! either a fixed BSDF (the lab box's parts, OBJ colours), the glTF 2.0
//! metallic–roughness material with its textures, which becomes a
//! [`Material::Pbr`] at each hit once its textures are looked up (a
//! `KHR_materials_pbrSpecularGlossiness` material too, converted there), or a
//! `KHR_materials_unlit` material, which shows its base colour and scatters
//! nothing.

use glam::{Vec2, Vec3A, Vec4, Vec4Swizzles};

use super::material::Material;
use super::mitsuba::Param;
use super::pbr::PbrBsdf;
use crate::textures::{ColorSpace, Pattern, TextureRef, TextureStore};

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
    /// `KHR_materials_sheen`: `sheenColorFactor` (linear, black: no sheen).
    pub sheen_color: Vec3A,
    /// Its `sheenColorTexture` (sRGB).
    pub sheen_color_texture: Option<TextureRef>,
    /// `sheenRoughnessFactor`.
    pub sheen_roughness: f32,
    /// Its `sheenRoughnessTexture` (alpha channel).
    pub sheen_roughness_texture: Option<TextureRef>,
    /// `KHR_materials_dispersion` `dispersion`, `20 / V_d` (0 by default: no
    /// dispersion); it disperses only with a volume (see
    /// [`PbrBsdf::dispersive`]).
    pub dispersion: f32,
    /// `KHR_materials_iridescence`: `iridescenceFactor` (0: no film).
    pub iridescence: f32,
    /// Its `iridescenceTexture` (red channel).
    pub iridescence_texture: Option<TextureRef>,
    /// `iridescenceIor`, the film's index (1.3 by default, at least 1).
    pub iridescence_ior: f32,
    /// `iridescenceThicknessMinimum` in nanometres (100 by default).
    pub iridescence_thickness_min: f32,
    /// `iridescenceThicknessMaximum` in nanometres (400 by default): the
    /// thickness without a thickness texture.
    pub iridescence_thickness_max: f32,
    /// `iridescenceThicknessTexture` (green channel), mixing the minimum and
    /// the maximum.
    pub iridescence_thickness_texture: Option<TextureRef>,
    /// `KHR_materials_anisotropy`: `anisotropyStrength` (0: isotropic).
    pub anisotropy_strength: f32,
    /// `(cos r, sin r)` of its `anisotropyRotation` `r` (radians,
    /// counter-clockwise from the tangent towards the bitangent).
    pub anisotropy_rotation: Vec2,
    /// Its `anisotropyTexture` (linear): direction in red and green (mapped
    /// to `[−1, 1]`, in tangent space, then turned by the rotation), strength
    /// in blue.
    pub anisotropy_texture: Option<TextureRef>,
    /// `KHR_materials_diffuse_transmission` `diffuseTransmissionFactor`
    /// (0: none).
    pub diffuse_transmission: f32,
    /// Its `diffuseTransmissionTexture` (alpha channel).
    pub diffuse_transmission_texture: Option<TextureRef>,
    /// `diffuseTransmissionColorFactor` (1 by default).
    pub diffuse_transmission_color: Vec3A,
    /// Its `diffuseTransmissionColorTexture` (sRGB).
    pub diffuse_transmission_color_texture: Option<TextureRef>,
    /// `KHR_materials_volume_scatter` `multiscatterColor`: the colour (the
    /// multiple-scattering albedo) of a scattering volume (`None`: the
    /// volume only absorbs).
    pub multiscatter_color: Option<Vec3A>,
    /// Its `scatterAnisotropy`: the phase function's mean cosine.
    pub scatter_anisotropy: f32,
    /// `KHR_materials_pbrSpecularGlossiness`: when present, it replaces the
    /// metallic–roughness parameters (the diffuse colour is `base_color` and
    /// `base_color_texture`), converted per hit by
    /// [`SpecularGlossiness::bsdf`].
    pub specular_glossiness: Option<SpecularGlossiness>,
}

/// The specular–glossiness parameters of `KHR_materials_pbrSpecularGlossiness`
/// (its `diffuseFactor` and `diffuseTexture` are the material's base colour).
///
/// The extension defines the BRDF's inputs as `c_diff = diffuse ·
/// (1 − max(specular.rgb))`, `F0 = specular` and `α = (1 − glossiness)²`, on
/// the core specification's BRDF. raylab evaluates exactly those inputs with
/// its metallic–roughness BSDF as `KHR_materials_specular` (which superseded
/// the extension) expresses them: metallic 0, base colour `c_diff`, roughness
/// `1 − glossiness`, and a specular colour that makes the dielectric's `F0`
/// equal `specular` ([`SpecularGlossiness::bsdf`]). The one difference from
/// the extension's reference BRDF is the diffuse lobe's Fresnel weight,
/// `1 − max(F)` (as `KHR_materials_specular` has it) where the archived text
/// has `1 − F` per channel: the same for grey speculars.
///
/// The conversion is done per hit on the filtered texels, so textures stay as
/// decoded (no converted copy in memory) and nothing is allocated per ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularGlossiness {
    /// `specularFactor` (linear RGB, the reflectance at normal incidence).
    pub specular: Vec3A,
    /// `glossinessFactor` (1: smooth).
    pub glossiness: f32,
    /// `specularGlossinessTexture`: specular in RGB (sRGB), glossiness in A
    /// (linear), multiplying the factors.
    pub texture: Option<TextureRef>,
}

/// `F0` of raylab's dielectric of index `ior`, with the arithmetic
/// [`crate::materials::PbrBsdf`] uses, so that a specular colour of
/// `specular / dielectric_f0(ior)` gives `F0 = specular` to within a rounding.
fn dielectric_f0(ior: f32) -> f32 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

impl SpecularGlossiness {
    /// The metallic–roughness BSDF with this material's specular–glossiness
    /// inputs at a hit: `diffuse` is the diffuse colour there (factor ×
    /// texture × `COLOR_0`), `texel` the specular–glossiness texel (`None`
    /// without a texture). `transmission` passes `KHR_materials_transmission`
    /// through.
    pub fn bsdf(&self, diffuse: Vec3A, texel: Option<Vec4>, transmission: f32) -> PbrBsdf {
        let (specular, glossiness) = match texel {
            Some(t) => (self.specular * Vec3A::from(t.xyz()), self.glossiness * t.w),
            None => (self.specular, self.glossiness),
        };
        // (Finite: the factor is checked at load and texels are finite.)
        let specular = specular.clamp(Vec3A::ZERO, Vec3A::ONE);
        let roughness = 1.0 - unit_interval(glossiness);
        let ior = 1.5;
        PbrBsdf {
            base_color: (diffuse * (1.0 - specular.max_element())).clamp(Vec3A::ZERO, Vec3A::ONE),
            metallic: 0.0,
            alpha: PbrBsdf::alpha_from_roughness(roughness),
            ior,
            specular: 1.0,
            // `F0 = min(dielectric_f0 · specular_color, 1)` in the BSDF.
            specular_color: specular / dielectric_f0(ior),
            transmission: unit_interval(transmission),
            thin_walled: true,
            coat: 0.0,
            coat_alpha: 1.0,
            coat_normal: Vec3A::Z,
            sheen_color: Vec3A::ZERO,
            sheen_roughness: 0.0,
            dispersion: 0.0,
            iridescence: 0.0,
            film_ior: 1.3,
            film_thickness: 0.0,
            anisotropy: 0.0,
            anisotropy_direction: Vec2::X,
            diffuse_transmission: 0.0,
            diffuse_transmission_color: Vec3A::ONE,
        }
    }
}

impl GltfMaterial {
    /// The clear coat's weight at a hit, `clearcoatFactor` ×
    /// `clearcoatTexture`.r in `[0, 1]` (0 without a coat; the texture is
    /// read only where the factor is positive).
    #[inline]
    pub fn coat_at(&self, attrs: &HitAttributes, textures: &TextureStore) -> f32 {
        let mut w = self.clearcoat;
        if w > 0.0
            && let Some(t) = &self.clearcoat_texture
        {
            w *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        unit_interval(w)
    }

    /// The sheen's colour and roughness at a hit, each in `[0, 1]` (black
    /// without a sheen; the textures are read only where there is one).
    #[inline]
    pub fn sheen_at(&self, attrs: &HitAttributes, textures: &TextureStore) -> (Vec3A, f32) {
        if self.sheen_color.max_element().is_nan() || self.sheen_color.max_element() <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let mut color = self.sheen_color;
        if let Some(t) = &self.sheen_color_texture {
            color *= Vec3A::from(lookup(t, attrs, textures, ColorSpace::Srgb).xyz());
        }
        let mut roughness = self.sheen_roughness;
        if let Some(t) = &self.sheen_roughness_texture {
            roughness *= lookup(t, attrs, textures, ColorSpace::Linear).w;
        }
        let color = Vec3A::new(
            unit_interval(color.x),
            unit_interval(color.y),
            unit_interval(color.z),
        );
        (color, unit_interval(roughness))
    }

    /// The thin film at a hit (`KHR_materials_iridescence`): its weight
    /// `iridescenceFactor` × `iridescenceTexture`.r in `[0, 1]` and its
    /// thickness in nanometres, `mix(minimum, maximum,
    /// iridescenceThicknessTexture.g)` or the maximum without that texture.
    /// `(0, 0)` without a film; the textures are read only where the factor
    /// is positive.
    #[inline]
    pub fn film_at(&self, attrs: &HitAttributes, textures: &TextureStore) -> (f32, f32) {
        // (NaN counts as no film.)
        if self.iridescence.is_nan() || self.iridescence <= 0.0 {
            return (0.0, 0.0);
        }
        let mut w = self.iridescence;
        if let Some(t) = &self.iridescence_texture {
            w *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        let w = unit_interval(w);
        if w == 0.0 {
            return (0.0, 0.0);
        }
        let (lo, hi) = (
            self.iridescence_thickness_min,
            self.iridescence_thickness_max,
        );
        let thickness = match &self.iridescence_thickness_texture {
            Some(t) => {
                let g = lookup(t, attrs, textures, ColorSpace::Linear).y;
                lo + (hi - lo) * g
            }
            None => hi,
        };
        (w, thickness.max(0.0))
    }
}

impl GltfMaterial {
    /// `KHR_materials_anisotropy` at a hit: the strength in `[0, 1]`
    /// (`anisotropyStrength` × the texture's blue) and the unit direction of
    /// increased roughness in tangent space (the texture's red and green
    /// mapped to `[−1, 1]` and normalized, or the tangent without a texture,
    /// turned counter-clockwise by `anisotropyRotation`), as the
    /// specification's reference code computes them. A texel whose direction
    /// is zero takes the tangent's. `(0, x)` without anisotropy; the texture
    /// is read only where the factor is positive.
    #[inline]
    pub fn anisotropy_at(&self, attrs: &HitAttributes, textures: &TextureStore) -> (f32, Vec2) {
        let mut strength = self.anisotropy_strength;
        if strength.is_nan() || strength <= 0.0 {
            return (0.0, Vec2::X);
        }
        let mut d = Vec2::X;
        if let Some(t) = &self.anisotropy_texture {
            let texel = lookup(t, attrs, textures, ColorSpace::Linear);
            strength *= texel.z;
            let v = Vec2::new(2.0 * texel.x - 1.0, 2.0 * texel.y - 1.0).normalize_or_zero();
            if v != Vec2::ZERO {
                d = v;
            }
        }
        let r = self.anisotropy_rotation;
        let d = Vec2::new(r.x * d.x - r.y * d.y, r.y * d.x + r.x * d.y);
        (unit_interval(strength), d)
    }

    /// The diffuse transmission's share and colour at a hit
    /// (`KHR_materials_diffuse_transmission`): factor × texture alpha in
    /// `[0, 1]`, colour factor × texture RGB (sRGB) in `[0, 1]`; the
    /// textures are read only where the factor is positive.
    #[inline]
    pub fn diffuse_transmission_at(
        &self,
        attrs: &HitAttributes,
        textures: &TextureStore,
    ) -> (f32, Vec3A) {
        let mut dt = self.diffuse_transmission;
        if dt.is_nan() || dt <= 0.0 {
            return (0.0, Vec3A::ONE);
        }
        if let Some(t) = &self.diffuse_transmission_texture {
            dt *= lookup(t, attrs, textures, ColorSpace::Linear).w;
        }
        let mut color = self.diffuse_transmission_color;
        if let Some(t) = &self.diffuse_transmission_color_texture {
            color *= Vec3A::from(lookup(t, attrs, textures, ColorSpace::Srgb).xyz());
        }
        (unit_interval(dt), color.clamp(Vec3A::ZERO, Vec3A::ONE))
    }
}

/// `x` clamped to `[0, 1]`, NaN as 0.
#[inline]
fn unit_interval(x: f32) -> f32 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
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
            sheen_color: Vec3A::ZERO,
            sheen_color_texture: None,
            sheen_roughness: 0.0,
            sheen_roughness_texture: None,
            dispersion: 0.0,
            iridescence: 0.0,
            iridescence_texture: None,
            iridescence_ior: 1.3,
            iridescence_thickness_min: 100.0,
            iridescence_thickness_max: 400.0,
            iridescence_thickness_texture: None,
            anisotropy_strength: 0.0,
            anisotropy_rotation: Vec2::X,
            anisotropy_texture: None,
            diffuse_transmission: 0.0,
            diffuse_transmission_texture: None,
            diffuse_transmission_color: Vec3A::ONE,
            diffuse_transmission_color_texture: None,
            multiscatter_color: None,
            scatter_anisotropy: 0.0,
            specular_glossiness: None,
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
    /// `KHR_materials_unlit`: the surface shows its base colour (factor ×
    /// texture × `COLOR_0`, with its alpha) as radiance, from either side,
    /// and scatters no light: `path` adds it where a path reaches the surface
    /// and ends the path there; `flat` shows it, and `direct` gives it the
    /// value its display shows as that colour (see
    /// [`crate::integrators::Integrator`]). It is not a light source: light
    /// sampling never picks it. Only the base colour and alpha of the glTF
    /// material are read (its other parameters are the fallback for viewers
    /// without the extension).
    Unlit(Box<GltfMaterial>),
    /// One BSDF whose reflectance and opacity may vary over the surface, and
    /// whose sides are its own (Mitsuba's materials).
    Textured(Box<TexturedBsdf>),
}

/// A BSDF of one kind whose reflectance and opacity may vary over the
/// surface ([`Pattern`]s), reflecting on one side or both: what a Mitsuba
/// scene's `diffuse` with a `bitmap` reflectance, `twosided` or `mask` is.
#[derive(Clone, Debug, PartialEq)]
pub struct TexturedBsdf {
    /// The BSDF where nothing varies.
    pub bsdf: Material,
    /// Replaces the BSDF's reflectance at each hit ([`with_reflectance`]).
    pub reflectance: Option<Pattern>,
    /// The probability that a ray meets the surface at a hit (Mitsuba's
    /// `mask`: its red channel; the material's alpha mode is then
    /// [`AlphaMode::Blend`]).
    pub opacity: Option<Pattern>,
    /// Whether a one-sided BSDF reflects on both sides (Mitsuba's
    /// `twosided`): its shading normal is turned towards the viewer even in
    /// a scene whose surfaces are one-sided.
    pub two_sided: bool,
    /// Two reflectances the `reflectance` pattern's first channel blends
    /// between (`(1 − w)·ρ₀ + w·ρ₁`): Mitsuba's `blendbsdf` of two Lambertian
    /// BSDFs, which is exactly the Lambertian BSDF of the blended
    /// reflectance. `None`: the pattern is the reflectance itself.
    pub blend: Option<[Vec3A; 2]>,
    /// Scalar parameters that textures vary over the surface (each set to
    /// its pattern's luminance at the hit, [`Material::set_param`]).
    pub params: Vec<(Param, Pattern)>,
    /// How the shading normal is perturbed (Mitsuba's `normalmap` and
    /// `bumpmap`), if it is.
    pub perturb: Option<Perturb>,
    /// The textures of the two BSDFs of a [`Material::MiBlend`] (Mitsuba's
    /// `blendbsdf`; its weight's texture is a [`Param::Weight`] in
    /// `params`): each part's reflectance and scalar parameters, looked up
    /// per hit into the blend's parts. `None` when no part is textured.
    /// The parts' own sides, opacity, perturbation and parts are not
    /// read (a blend's are the blend's).
    pub parts: Option<Box<[TexturedBsdf; 2]>>,
}

/// A perturbation of the shading normal, in Mitsuba's shading frame (whose
/// first axis is `∂p/∂u` made orthogonal to the interpolated normal; see
/// [`crate::scene::SurfaceHit`]), with Mitsuba 3.7.1's two options.
#[derive(Clone, Debug, PartialEq)]
pub struct Perturb {
    /// The map.
    pub map: PerturbMap,
    /// Mitsuba's `flip_invalid_normals` (default on): where the viewer is
    /// on different sides of the interpolated and the perturbed normal, the
    /// perturbed normal's tangential part is negated (Schüssler et al. 2017).
    pub flip_invalid: bool,
    /// Mitsuba's `use_shadowing_function` (default on): the BSDF is
    /// weighed by Estevez et al.'s (2019) microfacet shadowing term of the
    /// bump terminator.
    pub shadowing: bool,
}

/// How the shading normal is perturbed.
#[derive(Clone, Debug, PartialEq)]
pub enum PerturbMap {
    /// Mitsuba's `normalmap`: the pattern's RGB mapped from `[0, 1]` to
    /// `[−1, 1]` and normalized is the normal in the shading frame.
    NormalMap(Pattern),
    /// Mitsuba's `bumpmap`: the surface displaced along the interpolated
    /// normal by `scale` × the pattern's luminance (only its gradient is
    /// used: `∂p/∂u` and `∂p/∂v` get the height's derivatives as their
    /// normal parts, and the normal is their cross product, on the
    /// geometric normal's side).
    BumpMap {
        /// The height.
        height: Pattern,
        /// Its scale (Mitsuba's `scale`, default 1).
        scale: f32,
    },
}

impl TexturedBsdf {
    /// `bsdf` everywhere, one-sided, nothing textured or perturbed.
    pub fn new(bsdf: Material) -> Self {
        Self {
            bsdf,
            reflectance: None,
            opacity: None,
            two_sided: false,
            blend: None,
            params: Vec::new(),
            perturb: None,
            parts: None,
        }
    }

    /// Whether shading needs Mitsuba's frame at a hit: a normal or bump map,
    /// or a BSDF that is (or may be, by its textures) anisotropic.
    #[inline]
    pub fn needs_frame(&self) -> bool {
        self.perturb.is_some()
            || !self.params.is_empty()
            || self.bsdf.is_anisotropic()
            || self
                .parts
                .as_ref()
                .is_some_and(|p| p.iter().any(|t| !t.params.is_empty()))
    }

    /// The reflectance at `attrs` (the pattern's, or the BSDF's own `fixed`).
    #[inline]
    fn reflectance_at(
        &self,
        fixed: Vec3A,
        attrs: &HitAttributes,
        textures: &TextureStore,
    ) -> Vec3A {
        let Some(p) = &self.reflectance else {
            return fixed;
        };
        match self.blend {
            // Mitsuba reads the weight with `eval_1`, clipped to [0, 1].
            Some([a, b]) => {
                let w = p.eval_1(attrs.uv[0], attrs.color, textures);
                let w = if w.is_nan() { 0.0 } else { w.clamp(0.0, 1.0) };
                a * (1.0 - w) + b * w
            }
            None => Vec3A::from(p.eval(attrs.uv[0], attrs.color, textures).xyz()),
        }
    }
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
            MaterialKind::Fixed(_) | MaterialKind::Unlit(_) | MaterialKind::Textured(_) => None,
        }
    }

    /// Base colour (RGB) and alpha at a hit: the fixed reflectance with alpha 1,
    /// or glTF's `baseColorFactor × baseColorTexture × COLOR_0`.
    #[inline]
    pub fn base_color(&self, attrs: &HitAttributes, textures: &TextureStore) -> Vec4 {
        match &self.kind {
            MaterialKind::Fixed(_) => self.reflectance.extend(1.0),
            MaterialKind::Textured(t) => {
                let alpha = t
                    .opacity
                    .as_ref()
                    .map_or(1.0, |p| p.eval(attrs.uv[0], attrs.color, textures).x);
                t.reflectance_at(self.reflectance, attrs, textures)
                    .extend(alpha)
            }
            MaterialKind::Gltf(g) | MaterialKind::Unlit(g) => {
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

    /// Whether the material is `KHR_materials_unlit` (shows its base colour,
    /// scatters nothing).
    #[inline(always)]
    pub fn is_unlit(&self) -> bool {
        matches!(self.kind, MaterialKind::Unlit(_))
    }

    /// The BSDF at a hit. (The fixed materials inlined, the glTF one out of
    /// line: as one call, the lab box's `path` spent 1.8 % more.) An unlit
    /// material, which the integrators do not scatter off, answers a
    /// Lambertian reflector of its base colour: what the denoiser's albedo
    /// guide should see there.
    #[inline(always)]
    pub fn bsdf(&self, attrs: &HitAttributes, textures: &TextureStore) -> Material {
        match &self.kind {
            MaterialKind::Fixed(m) => *m,
            MaterialKind::Gltf(g) => self.gltf_bsdf(g, attrs, textures),
            MaterialKind::Unlit(_) => Material::Diffuse {
                reflectance: self.unlit_color(attrs, textures),
            },
            MaterialKind::Textured(t) => textured_bsdf(t, attrs, textures),
        }
    }

    /// Whether the material turns its shading normal towards the viewer in
    /// a scene of one-sided surfaces (a [`TexturedBsdf`] that is
    /// `two_sided`).
    #[inline]
    pub fn two_sided(&self) -> bool {
        matches!(&self.kind, MaterialKind::Textured(t) if t.two_sided)
    }

    /// Whether the material decides its sides itself (a [`TexturedBsdf`]),
    /// whatever the scene it is in says.
    #[inline]
    pub fn has_own_sides(&self) -> bool {
        matches!(&self.kind, MaterialKind::Textured(_))
    }

    /// What an unlit material shows at a hit: its base colour (RGB), clamped
    /// to `[0, 1]` as the glTF material's is.
    #[inline]
    pub fn unlit_color(&self, attrs: &HitAttributes, textures: &TextureStore) -> Vec3A {
        Vec3A::from(self.base_color(attrs, textures).xyz()).clamp(Vec3A::ZERO, Vec3A::ONE)
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
        let mut transmission = g.transmission;
        if let Some(t) = &g.transmission_texture {
            transmission *= lookup(t, attrs, textures, ColorSpace::Linear).x;
        }
        if let Some(sg) = &g.specular_glossiness {
            // Specular in sRGB, glossiness in the (always linear) alpha.
            let texel = sg
                .texture
                .as_ref()
                .map(|t| lookup(t, attrs, textures, ColorSpace::Srgb));
            return Material::Pbr(sg.bsdf(base, texel, transmission));
        }
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
        let roughness = unit_interval(roughness);
        let coat = g.coat_at(attrs, textures);
        let mut coat_roughness = g.clearcoat_roughness;
        if coat > 0.0
            && let Some(t) = &g.clearcoat_roughness_texture
        {
            coat_roughness *= lookup(t, attrs, textures, ColorSpace::Linear).y;
        }
        let coat_roughness = unit_interval(coat_roughness);
        let (sheen_color, sheen_roughness) = g.sheen_at(attrs, textures);
        let (iridescence, film_thickness) = g.film_at(attrs, textures);
        let (anisotropy, anisotropy_direction) = g.anisotropy_at(attrs, textures);
        let (diffuse_transmission, diffuse_transmission_color) =
            g.diffuse_transmission_at(attrs, textures);
        Material::Pbr(PbrBsdf {
            base_color: base.clamp(Vec3A::ZERO, Vec3A::ONE),
            metallic: unit_interval(metallic),
            alpha: PbrBsdf::alpha_from_roughness(roughness),
            ior: g.ior,
            specular: unit_interval(specular),
            specular_color: specular_color.max(Vec3A::ZERO),
            transmission: unit_interval(transmission),
            thin_walled: g.thin_walled,
            coat,
            coat_alpha: PbrBsdf::alpha_from_roughness(coat_roughness),
            coat_normal: Vec3A::Z,
            sheen_color,
            sheen_roughness,
            dispersion: g.dispersion,
            iridescence,
            film_ior: g.iridescence_ior,
            film_thickness,
            anisotropy,
            anisotropy_direction,
            diffuse_transmission,
            diffuse_transmission_color,
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

    /// Whether light passes the surface unchanged everywhere (Mitsuba's
    /// `null` BSDF, [`Material::is_null`], without a mask): an
    /// index-matched boundary of a medium, which shadow rays cross.
    #[inline]
    pub fn is_null(&self) -> bool {
        self.fixed_bsdf().is_some_and(Material::is_null)
    }

    /// What of a shadow ray passes the surface straight on at `|cos θ| =
    /// cos` to its shading normal (Mitsuba's `eval_null_transmission`): all
    /// of it for a `null` BSDF, the sheet's transmission for a
    /// `thindielectric`; `None` for surfaces that block it.
    #[inline]
    pub fn null_transmission(&self, cos: f32) -> Option<Vec3A> {
        match self.fixed_bsdf()? {
            m if m.is_null() => Some(Vec3A::ONE),
            Material::MiThinDielectric(t) => Some(t.null_transmission(cos)),
            _ => None,
        }
    }

    /// Whether shadow rays may pass the surface at all
    /// ([`SurfaceMaterial::null_transmission`] is `Some`).
    #[inline]
    pub fn passes_shadow_rays(&self) -> bool {
        self.fixed_bsdf()
            .is_some_and(|m| m.is_null() || m.passes_straight())
    }

    /// The BSDF of a material that is the same everywhere and opaque (no
    /// texture varies it, no mask makes holes in it).
    #[inline]
    fn fixed_bsdf(&self) -> Option<&Material> {
        if self.alpha != AlphaMode::Opaque {
            return None;
        }
        match &self.kind {
            MaterialKind::Fixed(m) => Some(m),
            MaterialKind::Textured(t)
                if t.opacity.is_none() && t.reflectance.is_none() && t.params.is_empty() =>
            {
                Some(&t.bsdf)
            }
            _ => None,
        }
    }

    /// Beer–Lambert attenuation inside the material's volume (zero if none).
    pub fn attenuation(&self) -> Vec3A {
        match &self.kind {
            MaterialKind::Gltf(g) if !g.thin_walled => g.attenuation,
            _ => Vec3A::ZERO,
        }
    }

    /// The share of emitted light that leaves through a clear coat towards
    /// the unit direction `dir`: `1 − w F_c(|dir·n_c|)`, as
    /// `KHR_materials_clearcoat` dims emission (1 without a coat).
    #[inline]
    pub fn coat_dimming(
        &self,
        attrs: &HitAttributes,
        textures: &TextureStore,
        n_c: Vec3A,
        dir: Vec3A,
    ) -> f32 {
        let MaterialKind::Gltf(g) = &self.kind else {
            return 1.0;
        };
        let w = g.coat_at(attrs, textures);
        if w <= 0.0 {
            return 1.0;
        }
        let cos = dir.dot(n_c).abs().min(1.0);
        let dim = 1.0 - w * crate::materials::pbr::coat_fresnel(cos);
        if dim.is_finite() { dim } else { 1.0 }
    }

    /// Whether the material is anisotropic anywhere
    /// (`KHR_materials_anisotropy` with a positive strength): its hits need
    /// the mesh's tangent frame.
    #[inline]
    pub fn has_anisotropy(&self) -> bool {
        matches!(&self.kind, MaterialKind::Gltf(g) if g.anisotropy_strength > 0.0)
    }

    /// The texture coordinate set the mesh's tangents follow when the file
    /// gives none (MikkTSpace on it): the normal map's, else the anisotropy
    /// texture's, else 0; `None` when the material needs no tangents (no
    /// normal map and no anisotropy).
    pub fn tangent_set(&self) -> Option<usize> {
        if let Some((t, _)) = self.normal_texture() {
            return Some((t.tex_coord as usize).min(1));
        }
        match &self.kind {
            MaterialKind::Gltf(g) if g.anisotropy_strength > 0.0 => Some(
                g.anisotropy_texture
                    .as_ref()
                    .map_or(0, |t| (t.tex_coord as usize).min(1)),
            ),
            _ => None,
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

/// [`SurfaceMaterial::bsdf`] of a [`TexturedBsdf`] (out of line).
#[inline(never)]
fn textured_bsdf(t: &TexturedBsdf, attrs: &HitAttributes, textures: &TextureStore) -> Material {
    let mut bsdf = match &t.reflectance {
        Some(_) => with_reflectance(t.bsdf, t.reflectance_at(Vec3A::ZERO, attrs, textures)),
        None => t.bsdf,
    };
    if let (Some(parts), Material::MiBlend(b)) = (&t.parts, &mut bsdf) {
        for (part, textured) in b.parts.iter_mut().zip(parts.iter()) {
            if textured.reflectance.is_some() || !textured.params.is_empty() {
                let m = textured_bsdf(textured, attrs, textures);
                *part = m.blend_part().unwrap_or(*part);
            }
        }
    }
    for (param, pattern) in &t.params {
        bsdf.set_param(*param, pattern.eval_1(attrs.uv[0], attrs.color, textures));
    }
    bsdf
}

/// `bsdf` with its reflectance replaced by `rho` (the diffuse reflectance
/// of a Lambertian surface or a plastic, the specular one of a mirror, the
/// base colour of a principled BSDF);
/// other BSDFs are returned unchanged.
#[inline]
pub fn with_reflectance(bsdf: Material, rho: Vec3A) -> Material {
    match bsdf {
        Material::Diffuse { .. } => Material::Diffuse { reflectance: rho },
        Material::Mirror { .. } => Material::Mirror { reflectance: rho },
        Material::MiPlastic(mut m) => {
            m.diffuse_reflectance = rho;
            Material::MiPlastic(m)
        }
        Material::MiRoughPlastic(mut m) => {
            m.diffuse_reflectance = rho;
            Material::MiRoughPlastic(m)
        }
        Material::MiPrincipled(mut m) => {
            m.base_color = rho;
            Material::MiPrincipled(m)
        }
        Material::MiPrincipledThin(mut m) => {
            m.base_color = rho;
            Material::MiPrincipledThin(m)
        }
        other => other,
    }
}

/// The images a material's [`Pattern`]s read, for changing them (when the
/// material's images move to another store).
pub fn pattern_images_mut(m: &mut SurfaceMaterial) -> impl Iterator<Item = &mut u32> {
    let textured = match &mut m.kind {
        MaterialKind::Textured(t) => Some(t.as_mut()),
        _ => None,
    };
    textured.into_iter().flat_map(|t| {
        let perturb = t.perturb.as_mut().map(|p| match &mut p.map {
            PerturbMap::NormalMap(p) | PerturbMap::BumpMap { height: p, .. } => p,
        });
        // A blend's parts (one level: a part is never a blend).
        let parts = t.parts.as_deref_mut().into_iter().flat_map(|parts| {
            parts.iter_mut().flat_map(|part| {
                part.reflectance
                    .as_mut()
                    .into_iter()
                    .chain(part.params.iter_mut().map(|(_, p)| p))
            })
        });
        [t.reflectance.as_mut(), t.opacity.as_mut(), perturb]
            .into_iter()
            .flatten()
            .chain(t.params.iter_mut().map(|(_, p)| p))
            .chain(parts)
            .filter_map(Pattern::image_mut)
    })
}

/// Every texture a material refers to.
pub fn texture_refs(m: &SurfaceMaterial) -> impl Iterator<Item = &TextureRef> {
    let gltf = match &m.kind {
        MaterialKind::Gltf(g) | MaterialKind::Unlit(g) => Some(g.as_ref()),
        MaterialKind::Fixed(_) | MaterialKind::Textured(_) => None,
    };
    let textures = gltf.into_iter().flat_map(|g| {
        let specular_glossiness = g.specular_glossiness.as_ref().map(|s| &s.texture);
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
            &g.sheen_color_texture,
            &g.sheen_roughness_texture,
            &g.iridescence_texture,
            &g.iridescence_thickness_texture,
            &g.anisotropy_texture,
            &g.diffuse_transmission_texture,
            &g.diffuse_transmission_color_texture,
        ]
        .into_iter()
        .chain(specular_glossiness)
    });
    textures.chain([&m.emission_texture]).flatten()
}

/// Every texture a material refers to, for changing them (say, when the
/// material's images move to another store).
pub fn texture_refs_mut(m: &mut SurfaceMaterial) -> impl Iterator<Item = &mut TextureRef> {
    let gltf = match &mut m.kind {
        MaterialKind::Gltf(g) | MaterialKind::Unlit(g) => Some(g.as_mut()),
        MaterialKind::Fixed(_) | MaterialKind::Textured(_) => None,
    };
    let textures = gltf.into_iter().flat_map(|g| {
        let specular_glossiness = g.specular_glossiness.as_mut().map(|s| &mut s.texture);
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
            &mut g.sheen_color_texture,
            &mut g.sheen_roughness_texture,
            &mut g.iridescence_texture,
            &mut g.iridescence_thickness_texture,
            &mut g.anisotropy_texture,
            &mut g.diffuse_transmission_texture,
            &mut g.diffuse_transmission_color_texture,
        ]
        .into_iter()
        .chain(specular_glossiness)
    });
    textures.chain([&mut m.emission_texture]).flatten()
}
