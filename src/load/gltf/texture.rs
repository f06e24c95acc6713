//! Texture references: a material's texture infos (the sampler's wrap modes,
//! the texture coordinate set, `KHR_texture_transform`) and the images they
//! name, each queued once for decoding (the KTX2 or WebP image where the
//! texture's `KHR_texture_basisu` or `EXT_texture_webp` names one).

use glam::Vec2;
use gltf::json::{self, validation::Checked};

use super::document::BASISU;
use super::error::GltfError;
use super::loader::Loader;
use crate::textures::{TextureRef, TextureTransform, Wrap};

impl Loader<'_> {
    /// A normal map's texture reference (as [`Self::texture`]; its
    /// `KHR_texture_transform` is among the extensions `gltf-json` keeps as
    /// JSON for normal textures).
    pub(super) fn normal_texture(
        &mut self,
        n: &json::material::NormalTexture,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let transform = n
            .extensions
            .as_ref()
            .and_then(|e| e.others.get("KHR_texture_transform"))
            .and_then(|v| serde_json::from_value(v.clone()).ok());
        self.texture_parts(n.index.value(), n.tex_coord, transform.as_ref(), what)
    }

    /// A texture reference: its image (queued for decoding), sampler, texture
    /// coordinate set and transform.
    pub(super) fn texture(
        &mut self,
        info: Option<&json::texture::Info>,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let Some(info) = info else {
            return Ok(None);
        };
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        self.texture_parts(info.index.value(), info.tex_coord, transform, what)
    }

    /// The reference of texture `t` with its coordinate set and transform.
    fn texture_parts(
        &mut self,
        t: usize,
        tex_coord: u32,
        transform: Option<&json::extensions::texture::TextureTransform>,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let texture = self
            .root
            .textures
            .get(t)
            .ok_or_else(|| GltfError::invalid(format!("{what}: texture {t} does not exist")))?;
        let (mut wrap_s, mut wrap_t) = (Wrap::Repeat, Wrap::Repeat);
        if let Some(s) = texture.sampler {
            let sampler = self.root.samplers.get(s.value()).ok_or_else(|| {
                GltfError::invalid(format!("texture {t}: sampler {} does not exist", s.value()))
            })?;
            let wrap = |w: &Checked<json::texture::WrappingMode>| match w {
                Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
                Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
                _ => Wrap::Repeat,
            };
            wrap_s = wrap(&sampler.wrap_s);
            wrap_t = wrap(&sampler.wrap_t);
        }
        // `KHR_texture_basisu`'s KTX2 image or `EXT_texture_webp`'s WebP
        // image where the texture names one (raylab decodes both; the
        // extension's image wins over the core one, as both specifications
        // say), else the core `source` (range-checked below).
        let extension_image = |ext: &str| {
            texture
                .extensions
                .as_ref()
                .and_then(|e| e.others.get(ext))
                .and_then(|w| w.get("source"))
                .and_then(serde_json::Value::as_u64)
                .map(|s| usize::try_from(s).unwrap_or(usize::MAX))
        };
        let basisu = extension_image(BASISU);
        let image = basisu
            .or_else(|| extension_image("EXT_texture_webp"))
            .unwrap_or(texture.source.value());
        if image >= self.root.images.len() {
            return Err(GltfError::invalid(format!(
                "texture {t}: image {image} does not exist"
            )));
        }
        let id = match self.image_ids.get(&image) {
            Some(&id) => id,
            None => {
                let id = self.image_sources.len() as u32;
                let uri = self.root.images[image]
                    .uri
                    .clone()
                    .filter(|u| !u.starts_with("data:"));
                // A KTX2 image's errors name its index, file and extension.
                let name = match (basisu, uri) {
                    (Some(_), Some(uri)) => format!("image {image} ({uri}, {BASISU})"),
                    (Some(_), None) => format!("image {image} ({BASISU})"),
                    (None, uri) => uri.unwrap_or_else(|| format!("image {image}")),
                };
                self.image_sources.push((name, image));
                self.image_ids.insert(image, id);
                id
            }
        };
        let mut tex_coord = tex_coord;
        let mut transform_out = TextureTransform::default();
        if let Some(tt) = transform {
            transform_out = TextureTransform {
                offset: Vec2::from(tt.offset.0),
                rotation: tt.rotation.0,
                scale: Vec2::from(tt.scale.0),
            };
            if let Some(tc) = tt.tex_coord {
                tex_coord = tc;
            }
        }
        if tex_coord > 1 {
            self.warn_once(
                "texcoord",
                format!("{what}: texture coordinate sets above 1 are not read; using set 1"),
            );
        }
        Ok(Some(TextureRef {
            image: id,
            wrap_s,
            wrap_t,
            tex_coord: tex_coord.min(1) as u8,
            transform: transform_out,
        }))
    }
}
