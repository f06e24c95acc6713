//! Why an image could not be decoded ([`TextureError`]), and the largest
//! image accepted ([`MAX_SIDE`], [`MAX_TEXELS`]).

use thiserror::Error;

/// The widest or tallest image accepted, in texels.
pub const MAX_SIDE: u32 = 32768;

/// The most texels an image may have (2^28: 1 GiB as 8-bit RGBA).
pub const MAX_TEXELS: u64 = 1 << 28;

/// Why an image could not be decoded; the one-line message names the image.
#[derive(Debug, Error)]
pub enum TextureError {
    /// The data is neither PNG, JPEG, WebP, BMP nor KTX2.
    #[error(
        "{name}: not a PNG, JPEG, WebP, BMP or KTX2 image (the data starts with none of their signatures)"
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
    /// An OpenEXR file that could not be read as a texture.
    #[error("{name}: cannot read it as an OpenEXR texture: {why}")]
    Exr {
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
