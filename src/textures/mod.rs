//! Textures: decoded images shared by materials, and their lookups.
//!
//! A [`TextureStore`] holds every [`Image`] of a scene, decoded from PNG,
//! JPEG, WebP or KTX2 (Basis Universal) in parallel ([`TextureStore::decode_all`]),
//! or from OpenEXR as linear floats ([`Image::decode_exr`], for Mitsuba's
//! `bitmap`), and named by `u32` ids; a
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
//! Texels are kept as decoded, 8 or 16 bits per channel (32-bit floats for
//! OpenEXR images, read as they are in either colour space) and 1 to 4 channels
//! (grey, grey + alpha, RGB, RGBA), and converted at lookup time through
//! tables: 256 `f32`s for 8-bit sRGB and 256 for 8-bit linear (`x / 255`), and
//! 65 536 for 16-bit sRGB, built once on first use (16-bit linear is a
//! division). The tables hold exactly the values a conversion to `f32` at load
//! would store, so lookups return the same numbers, from a quarter of the
//! memory for 8-bit images (a half for 16-bit ones) and without a pass over
//! every texel at load.

mod decode;
mod error;
mod exr;
mod ktx2;
mod pattern;
mod srgb;
mod store;
mod texel;
mod transform;

#[cfg(test)]
mod tests;

pub use error::{MAX_SIDE, MAX_TEXELS, TextureError};
pub use pattern::{Pattern, mitsuba_luminance};
pub use srgb::srgb_to_linear;
pub use store::{TextureRef, TextureStore};
pub use texel::{ColorSpace, Image, Wrap};
pub use transform::TextureTransform;
