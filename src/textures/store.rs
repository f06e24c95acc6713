//! A scene's images ([`TextureStore`], decoded in parallel) and a material
//! slot's reference to one of them ([`TextureRef`]).

use glam::{Vec2, Vec4};
use rayon::prelude::*;

use super::error::TextureError;
use super::texel::{ColorSpace, Image, Wrap};
use super::transform::TextureTransform;

/// One material slot's texture reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// The image's id in the [`TextureStore`].
    pub image: u32,
    /// Wrap mode along u (columns).
    pub wrap_s: Wrap,
    /// Wrap mode along v (rows).
    pub wrap_t: Wrap,
    /// The texture-coordinate set the lookup reads: 0 (`TEXCOORD_0`) or 1.
    pub tex_coord: u8,
    /// `KHR_texture_transform` applied to those coordinates.
    pub transform: TextureTransform,
}

impl TextureRef {
    /// A reference to `image` with glTF's defaults: repeat both ways, set 0, no
    /// transform.
    pub fn new(image: u32) -> Self {
        Self {
            image,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            tex_coord: 0,
            transform: TextureTransform::IDENTITY,
        }
    }
}

/// Every decoded image of a scene, named by `u32` ids in insertion order.
#[derive(Clone, Debug, Default)]
pub struct TextureStore {
    images: Vec<Image>,
}

impl TextureStore {
    /// Adds every image's size, layout and texels to `f` (see
    /// [`crate::Scene::fingerprint`]).
    pub fn fingerprint_into(&self, f: &mut crate::fingerprint::Fingerprint) {
        for image in &self.images {
            image.fingerprint_into(f);
        }
    }

    /// An empty store.
    pub fn new() -> Self {
        Self::default()
    }

    /// Decodes `(name, bytes)` images in parallel on rayon, one image per task;
    /// image `k` of `sources` gets id `k`. If any fails, the error of the first
    /// failing one in `sources`' order is returned (whichever finished first).
    pub fn decode_all(sources: Vec<(String, Vec<u8>)>) -> Result<TextureStore, TextureError> {
        Self::decode_all_within(sources, &crate::memory::Ledger::unlimited(), "")
    }

    /// [`decode_all`](Self::decode_all), first charging the decoded sizes
    /// their headers announce to `ledger` (an error naming `scene` if they do
    /// not fit), so that nothing is decoded for a scene over budget.
    pub fn decode_all_within(
        sources: Vec<(String, Vec<u8>)>,
        ledger: &crate::memory::Ledger,
        scene: &str,
    ) -> Result<TextureStore, TextureError> {
        let textures = sources
            .iter()
            .map(|(_, bytes)| Image::decoded_bytes(bytes).unwrap_or(0))
            .fold(0u64, u64::saturating_add);
        ledger.charge(
            scene,
            crate::memory::Needs {
                textures,
                ..Default::default()
            },
        )?;
        let decoded: Vec<Result<Image, TextureError>> = sources
            .into_par_iter()
            .with_max_len(1)
            .map(|(name, bytes)| Image::decode(&bytes, &name))
            .collect();
        let images = decoded.into_iter().collect::<Result<Vec<_>, _>>()?;
        Ok(Self { images })
    }

    /// Adds an image, returning its id.
    ///
    /// # Panics
    ///
    /// If the store already holds `u32::MAX` images.
    pub fn push(&mut self, image: Image) -> u32 {
        let id = u32::try_from(self.images.len()).expect("too many images");
        self.images.push(image);
        id
    }

    /// Moves every image of `other` to the end of this store, returning the id
    /// `other`'s image 0 now has (add it to `other`'s texture references).
    pub fn append(&mut self, other: TextureStore) -> u32 {
        let offset = u32::try_from(self.images.len()).expect("too many images");
        self.images.extend(other.images);
        offset
    }

    /// The image of id `id`.
    ///
    /// # Panics
    ///
    /// If there is no such image.
    #[inline]
    pub fn get(&self, id: u32) -> &Image {
        &self.images[id as usize]
    }

    /// The number of images.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    /// Whether the store holds no image.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }

    /// Bytes held by all the images' texels.
    pub fn memory_bytes(&self) -> usize {
        self.images.iter().map(Image::memory_bytes).sum()
    }

    /// Looks `texture` up at `uv`, the coordinates of its set
    /// [`TextureRef::tex_coord`] (which the caller picks): applies its transform,
    /// then [`Image::lookup`] with its wrap modes.
    ///
    /// # Panics
    ///
    /// If the store has no image `texture.image`.
    #[inline]
    pub fn lookup(&self, texture: &TextureRef, uv: Vec2, space: ColorSpace) -> Vec4 {
        let uv = if texture.transform.is_identity() {
            uv
        } else {
            texture.transform.apply(uv)
        };
        self.get(texture.image)
            .lookup(uv, texture.wrap_s, texture.wrap_t, space)
    }
}
