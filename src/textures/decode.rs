//! PNG, JPEG, WebP, BMP and KTX2 (Basis Universal, see [`super::ktx2`]) decoding
//! into [`Image`]s, with the size checked before any texel is allocated.

use std::io::Cursor;

use image::{DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, Limits};

use super::error::{MAX_SIDE, MAX_TEXELS, TextureError};
use super::texel::Image;

/// The PNG file signature.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
/// A JPEG file's start-of-image marker and the first byte of the next marker.
const JPEG_SIGNATURE: &[u8] = &[0xFF, 0xD8, 0xFF];

/// The format of an image file, by its signature: PNG, JPEG, BMP, or WebP (a RIFF
/// container of form type `WEBP`); `None` for anything else.
fn format_of(bytes: &[u8]) -> Option<ImageFormat> {
    if bytes.starts_with(PNG_SIGNATURE) {
        Some(ImageFormat::Png)
    } else if bytes.starts_with(JPEG_SIGNATURE) {
        Some(ImageFormat::Jpeg)
    } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some(ImageFormat::WebP)
    } else if bytes.starts_with(b"BM") {
        // Windows bitmaps (Mitsuba's test scenes use them).
        Some(ImageFormat::Bmp)
    } else {
        None
    }
}

/// Most decoded bytes per byte of file: PNG's deflate expands at most 1032
/// times and a 1-bit palette image with transparency decodes to 32 bits a
/// texel (33 024 in all); JPEG needs at least a bit per 8×8 block and
/// channel. A header announcing more than this from the bytes present lies
/// (or the file is cut), and is refused before its texels are allocated.
pub const MAX_EXPANSION: u64 = 1 << 16;

/// The decoder's limits: at most [`MAX_SIDE`] texels a side (checked by the
/// decoders on the header, before they allocate), and allocations bounded by
/// the largest image allowed in the widest format (RGBA, 16 bits) plus slack
/// for the decoders' own buffers.
fn limits() -> Limits {
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(MAX_TEXELS * 8 + (256 << 20));
    limits
}

/// The size a header announces, read again for the message of a refused image
/// (no texel is allocated): a PNG's from its IHDR, which is always the first
/// chunk and which the decoder has already validated; a JPEG's from its frame
/// header, through a decoder without limits (which only reads the headers).
fn header_size(bytes: &[u8], format: ImageFormat) -> Option<(u32, u32)> {
    if format == ImageFormat::Png {
        // Signature (8 bytes), chunk length (4), "IHDR", width, height.
        let field = |at: usize| Some(u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
        (bytes.get(12..16)? == b"IHDR").then_some((field(16)?, field(20)?))
    } else {
        let mut probe = ImageReader::with_format(Cursor::new(bytes), format);
        probe.no_limits();
        probe.into_dimensions().ok()
    }
}

/// The length of a PNG's PLTE chunk if it is not 3 to 768 bytes in whole RGB
/// entries; walks the chunk headers only (a chunk cut short ends the walk:
/// the decoder reports that).
fn bad_palette(bytes: &[u8]) -> Option<u32> {
    let mut at = PNG_SIGNATURE.len();
    while let (Some(len), Some(kind)) = (bytes.get(at..at + 4), bytes.get(at + 4..at + 8)) {
        let len = u32::from_be_bytes(len.try_into().ok()?);
        if kind == b"PLTE" {
            return (len % 3 != 0 || !(3..=768).contains(&len)).then_some(len);
        }
        if kind == b"IDAT" || kind == b"IEND" {
            return None;
        }
        // Length, type, data and CRC.
        at = at.checked_add(12)?.checked_add(len as usize)?;
    }
    None
}

impl Image {
    /// Decodes a PNG, JPEG, WebP, BMP or KTX2 image, telling them apart by their signatures (not
    /// by a file name); `name` (a file name, a glTF image index…) only labels
    /// errors.
    ///
    /// PNGs of 8 or 16 bits per channel keep their depth; smaller depths and
    /// palettes are expanded to 8 bits (grey, grey + alpha, RGB or RGBA as the
    /// file says, a palette with transparency to RGBA). JPEGs decode to 8-bit
    /// grey or RGB, WebPs (lossy or lossless) and KTX2 files (ETC1S or UASTC
    /// Basis Universal payloads, `KHR_texture_basisu`) to 8-bit RGB or RGBA. Colour-space information in the file (ICC profiles, gamma
    /// chunks) is ignored, as glTF requires: the material slot that uses the
    /// image decides ([`ColorSpace`](super::ColorSpace)); so is EXIF orientation.
    ///
    /// Images wider or taller than [`MAX_SIDE`] or of more than [`MAX_TEXELS`]
    /// texels are refused from their header, before their texels are allocated.
    pub fn decode(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
        // From the cache (see [`crate::cache`]) when there is one: decoding
        // is most of the time a glTF scene takes to load.
        if crate::cache::dir().is_none() {
            return Self::decode_guarded(bytes, name);
        }
        use crate::cache::{self, Kind};
        let key = cache::key(Kind::Texture, |f| f.update(bytes));
        if let Some(image) = cache::get(Kind::Texture, key, 16 + MAX_TEXELS * 8)
            .and_then(|p| Self::from_cache_bytes(&p))
        {
            return Ok(image);
        }
        let image = Self::decode_guarded(bytes, name)?;
        cache::put(Kind::Texture, key, &image.to_cache_bytes());
        Ok(image)
    }

    /// [`Image::decode`] without the cache.
    fn decode_guarded(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
        // A panic in the decoders (a bug of theirs a file can trip) is one
        // more error, not a crash.
        crate::guard::catch("image", || Self::decode_unguarded(bytes, name)).unwrap_or_else(
            |message| {
                Err(TextureError::DecoderPanic {
                    name: name.into(),
                    message,
                })
            },
        )
    }

    fn decode_unguarded(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
        if bytes.starts_with(super::ktx2::SIGNATURE) {
            return super::ktx2::decode(bytes, name);
        }
        let Some(format) = format_of(bytes) else {
            return Err(TextureError::UnknownFormat { name: name.into() });
        };
        let decode_error = |cause| TextureError::Decode {
            name: name.into(),
            cause,
        };
        let too_large = |width, height| TextureError::TooLarge {
            name: name.into(),
            width,
            height,
        };

        if format == ImageFormat::Png
            && let Some(len) = bad_palette(bytes)
        {
            return Err(TextureError::BadPalette {
                name: name.into(),
                len,
            });
        }
        let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
        reader.limits(limits());
        let decoder = match reader.into_decoder() {
            Ok(decoder) => decoder,
            Err(ImageError::Limits(cause)) => {
                // Refused from the header; the message names the size it gives.
                return Err(match header_size(bytes, format) {
                    Some((width, height)) => too_large(width, height),
                    None => decode_error(ImageError::Limits(cause)),
                });
            }
            Err(cause) => return Err(decode_error(cause)),
        };
        let (width, height) = decoder.dimensions();
        if width == 0 || height == 0 {
            return Err(TextureError::Empty { name: name.into() });
        }
        if u64::from(width) * u64::from(height) > MAX_TEXELS {
            return Err(too_large(width, height));
        }
        // (Not for WebP: its lossless coding spends no bits at all on the
        // texels of a one-colour image, so any size may come from a few
        // bytes; the limits above and the memory budget bound it.)
        if format != ImageFormat::WebP
            && decoder.total_bytes() > (bytes.len() as u64).saturating_mul(MAX_EXPANSION)
        {
            return Err(TextureError::Truncated {
                name: name.into(),
                width,
                height,
                bytes: bytes.len(),
            });
        }
        let decoded = DynamicImage::from_decoder(decoder).map_err(decode_error)?;
        Ok(Self::from_dynamic(decoded))
    }

    /// The bytes `bytes` would decode to, from its header alone (no texel
    /// decoded); `None` if the header is unreadable or refused (decoding then
    /// says why).
    pub fn decoded_bytes(bytes: &[u8]) -> Option<u64> {
        if bytes.starts_with(super::ktx2::SIGNATURE) {
            return super::ktx2::decoded_bytes(bytes);
        }
        let format = format_of(bytes)?;
        let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
        reader.limits(limits());
        Some(reader.into_decoder().ok()?.total_bytes())
    }

    /// Takes over a decoded image's buffer as is (no copy) when its layout is
    /// one of ours; anything else (not produced by the PNG and JPEG decoders)
    /// becomes 16-bit RGBA.
    fn from_dynamic(decoded: DynamicImage) -> Image {
        let (w, h) = (decoded.width(), decoded.height());
        match decoded {
            DynamicImage::ImageLuma8(b) => Self::from_u8(w, h, 1, b.into_raw()),
            DynamicImage::ImageLumaA8(b) => Self::from_u8(w, h, 2, b.into_raw()),
            DynamicImage::ImageRgb8(b) => Self::from_u8(w, h, 3, b.into_raw()),
            DynamicImage::ImageRgba8(b) => Self::from_u8(w, h, 4, b.into_raw()),
            DynamicImage::ImageLuma16(b) => Self::from_u16(w, h, 1, b.into_raw()),
            DynamicImage::ImageLumaA16(b) => Self::from_u16(w, h, 2, b.into_raw()),
            DynamicImage::ImageRgb16(b) => Self::from_u16(w, h, 3, b.into_raw()),
            DynamicImage::ImageRgba16(b) => Self::from_u16(w, h, 4, b.into_raw()),
            other => Self::from_u16(w, h, 4, other.into_rgba16().into_raw()),
        }
    }
}
