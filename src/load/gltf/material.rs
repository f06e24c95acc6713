//! Materials: glTF's metallic–roughness core, `KHR_materials_unlit`,
//! specular–glossiness and the other material extensions raylab reads (their
//! objects, which `gltf-json` does not know, deserialized here) into the
//! scene's [`SurfaceMaterial`]s, each made once.

use glam::{Vec2, Vec3A, Vec4};
use gltf::json;

use super::error::{GltfError, valid};
use super::loader::Loader;
use crate::materials::surface::{
    AlphaMode, GltfMaterial, MaterialKind, SpecularGlossiness, SurfaceMaterial,
};
use crate::media::phase::MAX_G;

/// The clear coat extension's name.
const CLEARCOAT: &str = "KHR_materials_clearcoat";

/// `KHR_materials_clearcoat`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Clearcoat {
    #[serde(default)]
    clearcoat_factor: f32,
    clearcoat_texture: Option<json::texture::Info>,
    #[serde(default)]
    clearcoat_roughness_factor: f32,
    clearcoat_roughness_texture: Option<json::texture::Info>,
    clearcoat_normal_texture: Option<json::material::NormalTexture>,
}

/// The sheen extension's name.
const SHEEN: &str = "KHR_materials_sheen";

/// `KHR_materials_sheen`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Sheen {
    #[serde(default)]
    sheen_color_factor: [f32; 3],
    sheen_color_texture: Option<json::texture::Info>,
    #[serde(default)]
    sheen_roughness_factor: f32,
    sheen_roughness_texture: Option<json::texture::Info>,
}

/// The dispersion extension's name.
const DISPERSION: &str = "KHR_materials_dispersion";

/// `KHR_materials_dispersion`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
struct Dispersion {
    /// `20 / V_d`; 0 (the default) disperses nothing.
    #[serde(default)]
    dispersion: f32,
}

/// The thin-film extension's name.
const IRIDESCENCE: &str = "KHR_materials_iridescence";

/// `KHR_materials_iridescence`'s object (`gltf-json` does not know it), with
/// the schema's defaults.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Iridescence {
    #[serde(default)]
    iridescence_factor: f32,
    iridescence_texture: Option<json::texture::Info>,
    /// The schema's spelling; the specification's prose and example write
    /// `iridescenceIOR`, read too.
    #[serde(default = "Iridescence::default_ior", alias = "iridescenceIOR")]
    iridescence_ior: f32,
    #[serde(default = "Iridescence::default_minimum")]
    iridescence_thickness_minimum: f32,
    #[serde(default = "Iridescence::default_maximum")]
    iridescence_thickness_maximum: f32,
    iridescence_thickness_texture: Option<json::texture::Info>,
}

impl Iridescence {
    fn default_ior() -> f32 {
        1.3
    }
    fn default_minimum() -> f32 {
        100.0
    }
    fn default_maximum() -> f32 {
        400.0
    }
}

/// The anisotropy extension's name.
pub(super) const ANISOTROPY: &str = "KHR_materials_anisotropy";

/// `KHR_materials_anisotropy`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Anisotropy {
    #[serde(default)]
    anisotropy_strength: f32,
    #[serde(default)]
    anisotropy_rotation: f32,
    anisotropy_texture: Option<json::texture::Info>,
}

/// The diffuse transmission extension's name.
const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";

/// `KHR_materials_diffuse_transmission`'s object (`gltf-json` does not know
/// it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct DiffuseTransmission {
    #[serde(default)]
    diffuse_transmission_factor: f32,
    diffuse_transmission_texture: Option<json::texture::Info>,
    #[serde(default = "white")]
    diffuse_transmission_color_factor: [f32; 3],
    diffuse_transmission_color_texture: Option<json::texture::Info>,
}

/// The volume scattering extension's name (the Khronos draft of
/// glTF pull request 2453).
pub(super) const VOLUME_SCATTER: &str = "KHR_materials_volume_scatter";

/// `KHR_materials_volume_scatter`'s object.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct VolumeScatter {
    #[serde(default)]
    multiscatter_color: [f32; 3],
    #[serde(default)]
    scatter_anisotropy: f32,
}

/// `[1, 1, 1]`, a colour factor's default.
fn white() -> [f32; 3] {
    [1.0; 3]
}

impl Loader<'_> {
    /// The table index of glTF material `index` (None: the default material).
    pub(super) fn material(&mut self, index: Option<usize>) -> Result<u32, GltfError> {
        if let Some(&id) = self.material_ids.get(&index) {
            return Ok(id);
        }
        let material = match index {
            None => SurfaceMaterial {
                name: "default".into(),
                reflectance: Vec3A::ONE,
                kind: MaterialKind::Gltf(Box::default()),
                emission: Vec3A::ZERO,
                emission_texture: None,
                emits_both_sides: false,
                alpha: AlphaMode::Opaque,
            },
            Some(i) => self.convert_material(i)?,
        };
        let id = self.parts.materials.len() as u32;
        self.parts.materials.push(material);
        self.material_ids.insert(index, id);
        Ok(id)
    }

    /// glTF material `i` as a [`SurfaceMaterial`], its textures queued.
    fn convert_material(&mut self, i: usize) -> Result<SurfaceMaterial, GltfError> {
        use json::material::AlphaMode as Mode;
        let m = self
            .root
            .materials
            .get(i)
            .ok_or_else(|| GltfError::invalid(format!("material {i} does not exist")))?;
        let what = format!("material {i}");
        let pbr = &m.pbr_metallic_roughness;
        let ext = m.extensions.as_ref();
        if let Some(e) = ext {
            for name in e.others.keys() {
                let read = [
                    CLEARCOAT,
                    SHEEN,
                    DISPERSION,
                    IRIDESCENCE,
                    ANISOTROPY,
                    DIFFUSE_TRANSMISSION,
                    VOLUME_SCATTER,
                ];
                if !read.contains(&name.as_str()) {
                    self.warn_once(name, format!("ignoring the material extension {name}"));
                }
            }
        }
        let finite = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(GltfError::invalid(format!("{what}: {name} is not finite")))
            }
        };
        let alpha = match valid(&m.alpha_mode) {
            Some(Mode::Opaque) | None => AlphaMode::Opaque,
            Some(Mode::Mask) => AlphaMode::Mask(m.alpha_cutoff.map_or(0.5, |c| c.0)),
            Some(Mode::Blend) => AlphaMode::Blend,
        };
        if ext.is_some_and(|e| e.unlit.is_some()) {
            // KHR_materials_unlit: the base colour and alpha only; the rest is
            // the fallback for viewers without the extension, and its textures
            // are not decoded. (With another shading model's extension the
            // result is undefined; unlit wins.)
            let g = GltfMaterial {
                base_color: Vec4::from(pbr.base_color_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                base_color_texture: self.texture(pbr.base_color_texture.as_ref(), &what)?,
                ..GltfMaterial::default()
            };
            return Ok(SurfaceMaterial {
                name: m.name.clone().unwrap_or_default(),
                reflectance: Vec3A::from(g.base_color.truncate()),
                kind: MaterialKind::Unlit(Box::new(g)),
                emission: Vec3A::ZERO,
                emission_texture: None,
                emits_both_sides: m.double_sided,
                alpha,
            });
        }
        let spec_gloss = ext.and_then(|e| e.pbr_specular_glossiness.as_ref());
        let mut g = match spec_gloss {
            // The specular–glossiness parameters replace the metallic–roughness
            // ones, whose textures are then not decoded.
            Some(sg) => {
                let specular = Vec3A::from(sg.specular_factor.0);
                if !specular.is_finite() {
                    return Err(GltfError::invalid(format!(
                        "{what}: specularFactor is not finite"
                    )));
                }
                GltfMaterial {
                    base_color: Vec4::from(sg.diffuse_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                    base_color_texture: self.texture(sg.diffuse_texture.as_ref(), &what)?,
                    metallic: 0.0,
                    specular_glossiness: Some(SpecularGlossiness {
                        specular: specular.clamp(Vec3A::ZERO, Vec3A::ONE),
                        glossiness: finite(sg.glossiness_factor.0, "glossinessFactor")?
                            .clamp(0.0, 1.0),
                        texture: self.texture(sg.specular_glossiness_texture.as_ref(), &what)?,
                    }),
                    ..GltfMaterial::default()
                }
            }
            None => GltfMaterial {
                base_color: Vec4::from(pbr.base_color_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                base_color_texture: self.texture(pbr.base_color_texture.as_ref(), &what)?,
                metallic: finite(pbr.metallic_factor.0, "metallicFactor")?.clamp(0.0, 1.0),
                roughness: finite(pbr.roughness_factor.0, "roughnessFactor")?.clamp(0.0, 1.0),
                metallic_roughness_texture: self
                    .texture(pbr.metallic_roughness_texture.as_ref(), &what)?,
                ..GltfMaterial::default()
            },
        };
        if let Some(n) = &m.normal_texture {
            g.normal_texture = self.normal_texture(n, &what)?;
            g.normal_scale = finite(n.scale, "normalTexture.scale")?;
        }
        if let Some(e) = ext {
            if let Some(ior) = &e.ior {
                let v = finite(ior.ior.0, "ior")?;
                // glTF: ior 0 means an infinitely dense (fully reflective) medium; keep sane.
                g.ior = if v == 0.0 { 1e4 } else { v.max(1.0) };
            }
            if let Some(s) = &e.specular {
                g.specular = finite(s.specular_factor.0, "specularFactor")?.clamp(0.0, 1.0);
                g.specular_texture = self.texture(s.specular_texture.as_ref(), &what)?;
                g.specular_color = Vec3A::from(s.specular_color_factor.0).max(Vec3A::ZERO);
                g.specular_color_texture =
                    self.texture(s.specular_color_texture.as_ref(), &what)?;
            }
            if let Some(t) = &e.transmission {
                g.transmission =
                    finite(t.transmission_factor.0, "transmissionFactor")?.clamp(0.0, 1.0);
                g.transmission_texture = self.texture(t.transmission_texture.as_ref(), &what)?;
            }
            if let Some(v) = &e.volume {
                g.thin_walled = v.thickness_factor.0.is_nan() || v.thickness_factor.0 <= 0.0;
                let color =
                    Vec3A::from(v.attenuation_color.0).clamp(Vec3A::splat(1e-6), Vec3A::ONE);
                let distance = v.attenuation_distance.0;
                if distance.is_finite() && distance > 0.0 {
                    g.attenuation =
                        -Vec3A::new(color.x.ln(), color.y.ln(), color.z.ln()) / distance;
                }
            }
        }
        if let Some(value) = ext.and_then(|e| e.others.get(CLEARCOAT)) {
            self.clearcoat(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(SHEEN)) {
            self.sheen(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(DISPERSION)) {
            let d: Dispersion = serde_json::from_value(value.clone())
                .map_err(|e| GltfError::invalid(format!("{what}: {DISPERSION}: {e}")))?;
            // Any value from 0 up is valid (above 1 exaggerates); a negative
            // one, outside the schema, reads as none.
            g.dispersion = finite(d.dispersion, "dispersion")?.max(0.0);
        }
        if let Some(value) = ext.and_then(|e| e.others.get(IRIDESCENCE)) {
            self.iridescence(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(ANISOTROPY)) {
            self.anisotropy(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(DIFFUSE_TRANSMISSION)) {
            self.diffuse_transmission(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(VOLUME_SCATTER)) {
            let v: VolumeScatter = serde_json::from_value(value.clone())
                .map_err(|e| GltfError::invalid(format!("{what}: {VOLUME_SCATTER}: {e}")))?;
            let color = Vec3A::from(v.multiscatter_color);
            if !color.is_finite() || !v.scatter_anisotropy.is_finite() {
                return Err(GltfError::invalid(format!(
                    "{what}: {VOLUME_SCATTER}: multiscatterColor and scatterAnisotropy must be finite"
                )));
            }
            g.multiscatter_color = Some(color.clamp(Vec3A::ZERO, Vec3A::ONE));
            g.scatter_anisotropy = v.scatter_anisotropy.clamp(-MAX_G, MAX_G);
        }
        let strength = ext
            .and_then(|e| e.emissive_strength.as_ref())
            .map_or(1.0, |s| s.emissive_strength.0);
        let emission = Vec3A::from(m.emissive_factor.0) * finite(strength, "emissiveStrength")?;
        if !(emission.is_finite() && emission.min_element() >= 0.0) {
            return Err(GltfError::invalid(format!(
                "{what}: emission {emission} must be finite and >= 0"
            )));
        }
        let emission_texture = self.texture(m.emissive_texture.as_ref(), &what)?;
        Ok(SurfaceMaterial {
            name: m.name.clone().unwrap_or_default(),
            reflectance: Vec3A::from(g.base_color.truncate()),
            kind: MaterialKind::Gltf(Box::new(g)),
            emission,
            emission_texture,
            emits_both_sides: m.double_sided,
            alpha,
        })
    }

    /// Reads `KHR_materials_clearcoat` (`value`, the extension's object) into
    /// `g`.
    fn clearcoat(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let c: Clearcoat = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {CLEARCOAT}: {e}")))?;
        let unit = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v.clamp(0.0, 1.0))
            } else {
                Err(GltfError::invalid(format!(
                    "{what}: {CLEARCOAT}: {name} is not finite"
                )))
            }
        };
        g.clearcoat = unit(c.clearcoat_factor, "clearcoatFactor")?;
        g.clearcoat_roughness = unit(c.clearcoat_roughness_factor, "clearcoatRoughnessFactor")?;
        g.clearcoat_texture = self.texture(c.clearcoat_texture.as_ref(), what)?;
        g.clearcoat_roughness_texture =
            self.texture(c.clearcoat_roughness_texture.as_ref(), what)?;
        if let Some(n) = &c.clearcoat_normal_texture {
            g.clearcoat_normal_texture = self.normal_texture(n, what)?;
            if !n.scale.is_finite() {
                return Err(GltfError::invalid(format!(
                    "{what}: {CLEARCOAT}: clearcoatNormalTexture.scale is not finite"
                )));
            }
            g.clearcoat_normal_scale = n.scale;
        }
        Ok(())
    }

    /// Reads `KHR_materials_sheen` (`value`, the extension's object) into `g`.
    fn sheen(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let s: Sheen = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {SHEEN}: {e}")))?;
        let color = Vec3A::from(s.sheen_color_factor);
        if !color.is_finite() {
            return Err(GltfError::invalid(format!(
                "{what}: {SHEEN}: sheenColorFactor is not finite"
            )));
        }
        if !s.sheen_roughness_factor.is_finite() {
            return Err(GltfError::invalid(format!(
                "{what}: {SHEEN}: sheenRoughnessFactor is not finite"
            )));
        }
        g.sheen_color = color.clamp(Vec3A::ZERO, Vec3A::ONE);
        g.sheen_roughness = s.sheen_roughness_factor.clamp(0.0, 1.0);
        g.sheen_color_texture = self.texture(s.sheen_color_texture.as_ref(), what)?;
        g.sheen_roughness_texture = self.texture(s.sheen_roughness_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_iridescence` (`value`, the extension's object)
    /// into `g`: a value that is not finite is refused; out of the schema's
    /// ranges, the factor is clamped to `[0, 1]`, the index to at least 1 and
    /// the thicknesses to `[0, 1 mm]` (see
    /// [`MAX_THICKNESS_NM`](crate::materials::thin_film::MAX_THICKNESS_NM)).
    fn iridescence(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        use crate::materials::thin_film::MAX_THICKNESS_NM;
        let f: Iridescence = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {IRIDESCENCE}: {e}")))?;
        let finite = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(GltfError::invalid(format!(
                    "{what}: {IRIDESCENCE}: {name} is not finite"
                )))
            }
        };
        g.iridescence = finite(f.iridescence_factor, "iridescenceFactor")?.clamp(0.0, 1.0);
        g.iridescence_ior = finite(f.iridescence_ior, "iridescenceIor")?.max(1.0);
        let thickness = |v: f32, name: &str| -> Result<f32, GltfError> {
            Ok(finite(v, name)?.clamp(0.0, MAX_THICKNESS_NM))
        };
        g.iridescence_thickness_min = thickness(
            f.iridescence_thickness_minimum,
            "iridescenceThicknessMinimum",
        )?;
        g.iridescence_thickness_max = thickness(
            f.iridescence_thickness_maximum,
            "iridescenceThicknessMaximum",
        )?;
        g.iridescence_texture = self.texture(f.iridescence_texture.as_ref(), what)?;
        g.iridescence_thickness_texture =
            self.texture(f.iridescence_thickness_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_anisotropy` (`value`, the extension's object)
    /// into `g`: the strength clamped to `[0, 1]`, the rotation as its
    /// cosine and sine; a non-finite number is refused.
    fn anisotropy(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let a: Anisotropy = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {ANISOTROPY}: {e}")))?;
        for (v, name) in [
            (a.anisotropy_strength, "anisotropyStrength"),
            (a.anisotropy_rotation, "anisotropyRotation"),
        ] {
            if !v.is_finite() {
                return Err(GltfError::invalid(format!(
                    "{what}: {ANISOTROPY}: {name} is not finite"
                )));
            }
        }
        g.anisotropy_strength = a.anisotropy_strength.clamp(0.0, 1.0);
        let (sin, cos) = a.anisotropy_rotation.sin_cos();
        g.anisotropy_rotation = Vec2::new(cos, sin);
        g.anisotropy_texture = self.texture(a.anisotropy_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_diffuse_transmission` (`value`, the extension's
    /// object) into `g`: factors that are not finite are refused, the
    /// factor is clamped to `[0, 1]` and the colour to `[0, 1]` per channel
    /// (as the base colour is: the diffuse part reflects and transmits at
    /// most what it receives).
    fn diffuse_transmission(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let d: DiffuseTransmission = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {DIFFUSE_TRANSMISSION}: {e}")))?;
        let not_finite = |name: &str| {
            GltfError::invalid(format!(
                "{what}: {DIFFUSE_TRANSMISSION}: {name} is not finite"
            ))
        };
        if !d.diffuse_transmission_factor.is_finite() {
            return Err(not_finite("diffuseTransmissionFactor"));
        }
        let color = Vec3A::from(d.diffuse_transmission_color_factor);
        if !color.is_finite() {
            return Err(not_finite("diffuseTransmissionColorFactor"));
        }
        g.diffuse_transmission = d.diffuse_transmission_factor.clamp(0.0, 1.0);
        g.diffuse_transmission_color = color.clamp(Vec3A::ZERO, Vec3A::ONE);
        g.diffuse_transmission_texture =
            self.texture(d.diffuse_transmission_texture.as_ref(), what)?;
        g.diffuse_transmission_color_texture =
            self.texture(d.diffuse_transmission_color_texture.as_ref(), what)?;
        Ok(())
    }
}
