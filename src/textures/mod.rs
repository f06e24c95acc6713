//! Textures: decoded images shared by materials, and their lookups.
//!
//! A [`TextureStore`] holds every [`Image`] of a scene, decoded from PNG,
//! JPEG, WebP or KTX2 (Basis Universal) in parallel ([`TextureStore::decode_all`]) and named by `u32` ids; a
//! material slot refers to one with a [`TextureRef`] (image, glTF sampler wrap
//! modes, texture-coordinate set and `KHR_texture_transform`).
//!
//! Lookups follow glTF 2.0 exactly:
//!
//! * (u, v) = (0, 0) is the top-left corner of the image, row 0 its first row;
//!   texel (i, j) of a W × H image is centred on ((i + 0.5)/W, (j + 0.5)/H);
//! * bilinear filtering between the four texel centres around (u, v), no
//!   mip-mapping; the wrap modes ([`Wrap`]) apply to the taps' integer indices,
//!   as OpenGL does; positions within a texel are rounded to 1/65536 of a texel
//!   (GPUs: 1/256) so that texel centres give exact values;
//! * sRGB decoding (for base colour and emission, [`ColorSpace::Srgb`]) happens
//!   per texel, before filtering, with the exact sRGB EOTF
//!   ([`srgb_to_linear`]); alpha is always linear;
//! * [`TextureTransform`] is `KHR_texture_transform`'s `T · R · S`.
//!
//! # Storage
//!
//! Texels are kept as decoded, 8 or 16 bits per channel and 1 to 4 channels
//! (grey, grey + alpha, RGB, RGBA), and converted at lookup time through
//! tables: 256 `f32`s for 8-bit sRGB and 256 for 8-bit linear (`x / 255`), and
//! 65 536 for 16-bit sRGB, built once on first use (16-bit linear is a
//! division). The tables hold exactly the values a conversion to `f32` at load
//! would store, so lookups return the same numbers, from a quarter of the
//! memory for 8-bit images (a half for 16-bit ones) and without a pass over
//! every texel at load.

mod decode;
mod ktx2;
mod srgb;
mod texel;
mod transform;

#[cfg(test)]
mod tests;

use glam::{Vec2, Vec4};
use rayon::prelude::*;
use thiserror::Error;

pub use srgb::srgb_to_linear;
pub use texel::Image;
pub use transform::TextureTransform;

/// The widest or tallest image accepted, in texels.
pub const MAX_SIDE: u32 = 32768;

/// The most texels an image may have (2^28: 1 GiB as 8-bit RGBA).
pub const MAX_TEXELS: u64 = 1 << 28;

/// How a lookup decodes RGB (or grey) values; alpha is always linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorSpace {
    /// Values are linear: `byte / 255` (or `word / 65535`), e.g. metallic–roughness,
    /// occlusion, normal maps.
    Linear,
    /// Values are sRGB-encoded and decoded to linear per texel before filtering,
    /// e.g. base colour and emission.
    Srgb,
}

/// A glTF sampler's `wrapS` / `wrapT`: how texel indices outside the image map
/// back into it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tiles the image (glTF's default, `REPEAT`, 10497).
    #[default]
    Repeat,
    /// Tiles the image, every other copy mirrored (`MIRRORED_REPEAT`, 33648).
    MirroredRepeat,
    /// Repeats the edge texels (`CLAMP_TO_EDGE`, 33071).
    ClampToEdge,
}

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

/// Why an image could not be decoded; the one-line message names the image.
#[derive(Debug, Error)]
pub enum TextureError {
    /// The data is neither PNG, JPEG, WebP nor KTX2.
    #[error(
        "{name}: not a PNG, JPEG, WebP or KTX2 image (the data starts with none of their signatures)"
    )]
    UnknownFormat {
        /// The image.
        name: String,
    },
    /// The header announces an image too large to hold.
    #[error(
        "{name}: {width}×{height} texels is too large (at most {MAX_SIDE} a side and {MAX_TEXELS} texels)"
    )]
    TooLarge {
        /// The image.
        name: String,
        /// Its width in texels, as its header says.
        width: u32,
        /// Its height in texels, as its header says.
        height: u32,
    },
    /// The header announces more texels than the file's bytes can hold.
    #[error(
        "{name}: the header says {width}×{height} texels but {bytes} bytes cannot hold them; the file is cut short or corrupt"
    )]
    Truncated {
        /// The image.
        name: String,
        /// Its width in texels, as its header says.
        width: u32,
        /// Its height in texels, as its header says.
        height: u32,
        /// The bytes there are.
        bytes: usize,
    },
    /// Decoding the images would exceed the memory budget.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
    /// A PNG's palette chunk (PLTE) is not whole RGB entries. The `png` crate
    /// (0.18.1) panics on such a file while expanding the palette (its issue
    /// #694, found here by fuzzing), so it is refused before decoding.
    #[error(
        "{name}: the PNG palette (PLTE chunk) is {len} bytes, not a whole number of RGB entries from 1 to 256"
    )]
    BadPalette {
        /// The image (file name or glTF image).
        name: String,
        /// The chunk's length in bytes.
        len: u32,
    },
    /// The decoder panicked on the file (a bug in it; see [`crate::guard`]).
    #[error("{name}: {message}")]
    DecoderPanic {
        /// The image.
        name: String,
        /// What [`crate::guard::catch`] made of the panic.
        message: String,
    },
    /// The header announces no texels.
    #[error("{name}: the image is empty (a side of 0 texels)")]
    Empty {
        /// The image.
        name: String,
    },
    /// A KTX2 file that is not a 2D Basis Universal image raylab can decode,
    /// or whose payload the transcoder refuses.
    #[error("{name}: not a KTX2 Basis Universal image raylab can decode: {why}")]
    Ktx2 {
        /// The image.
        name: String,
        /// Why, in a few words.
        why: String,
    },
    /// The decoder failed: a truncated or corrupt file, an unsupported variant.
    #[error("{name}: {}", one_line(.cause))]
    Decode {
        /// The image.
        name: String,
        /// What the decoder said (in the message, so not also a `source`, which
        /// would print it twice in the command line's one-line error).
        cause: image::ImageError,
    },
}

/// A decoder's message on one line (some end theirs with a newline).
fn one_line(cause: &image::ImageError) -> String {
    cause
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
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
