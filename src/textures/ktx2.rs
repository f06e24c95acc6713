//! KTX2 images with Basis Universal payloads (glTF's `KHR_texture_basisu`):
//! ETC1S with BasisLZ, and UASTC stored plain or with Zstandard, decoded to
//! 8-bit RGB(A) by the pure-Rust `basisu` transcoder.
//!
//! The container is checked here before the transcoder sees it, so that
//! nothing is allocated from an unchecked number: a 2D image (no depth, at
//! most one layer, one face) of at most [`MAX_SIDE`] texels a side and
//! [`MAX_TEXELS`] texels, a level count a mip chain can have, a payload that
//! `KHR_texture_basisu` allows (`vkFormat` 0, ETC1S with BasisLZ or UASTC
//! with none or Zstandard), every byte range inside the file, a UASTC base
//! level of exactly one 16-byte block per 4×4 texels (after Zstandard, whose
//! frame window is bounded too: the zstd decoder reserves it from the
//! header), and orientation and swizzle metadata raylab can honour.
//!
//! The decoded values are treated as a PNG's: the material slot using the
//! image decides whether they are sRGB (the DFD's transfer function, which the
//! extension requires to match that use, is not read), as glTF says of
//! every image. Only the base level is decoded (raylab samples no mip maps).

use super::error::{MAX_SIDE, MAX_TEXELS, TextureError};
use super::texel::Image;

/// The KTX2 file identifier (KTX 2.0 §3.1).
pub(super) const SIGNATURE: &[u8; 12] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// The header's size, before the level index (§3).
const HEADER_BYTES: usize = 80;
/// One level index entry: offset, length, uncompressed length (§3.9.7).
const LEVEL_BYTES: usize = 24;
/// `KHR_DF_MODEL_ETC1S` and `KHR_DF_MODEL_UASTC` (Khronos Data Format 1.3).
const MODEL_ETC1S: u32 = 163;
const MODEL_UASTC: u32 = 166;
/// Supercompression schemes (§3.12): none, BasisLZ, Zstandard.
const SCHEME_NONE: u32 = 0;
const SCHEME_BASISLZ: u32 = 1;
const SCHEME_ZSTD: u32 = 2;
/// The Zstandard frame magic number (RFC 8878 §3.1.1).
const ZSTD_MAGIC: u32 = 0xFD2F_B528;
/// The largest Zstandard window accepted when the level needs less: zstd
/// encoders shrink the window to the content they know, so a larger one is
/// a lie; 8 MiB (zstd's default at level 6 for unknown sizes) is harmless.
const ZSTD_WINDOW_FLOOR: u64 = 8 << 20;

/// Little-endian `u32` at `at`, or `None` past the end.
fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        bytes.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// Little-endian `u64` at `at`, or `None` past the end.
fn u64_at(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        bytes.get(at..at.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// The bytes `offset..offset + length` of the file, if they lie inside it.
fn range(bytes: &[u8], offset: u64, length: u64) -> Option<&[u8]> {
    let end = offset.checked_add(length)?;
    bytes.get(usize::try_from(offset).ok()?..usize::try_from(end).ok()?)
}

/// What the checks read from a KTX2 file that decoding needs.
#[derive(Debug)]
struct Header {
    width: u32,
    height: u32,
    /// `KTXorientation`'s flips: columns run right to left, rows bottom to top.
    flip_x: bool,
    flip_y: bool,
}

/// The image size a KTX2 header announces, if the file starts like one
/// (for the memory ledger: 4 bytes a texel at most are kept).
pub(super) fn decoded_bytes(bytes: &[u8]) -> Option<u64> {
    let header = check(bytes, "").ok()?;
    Some(u64::from(header.width) * u64::from(header.height) * 4)
}

/// Checks a KTX2 file (see the module's documentation), returning why it is
/// refused in a few words.
fn check(bytes: &[u8], name: &str) -> Result<Header, TextureError> {
    let refuse = |why: String| TextureError::Ktx2 {
        name: name.into(),
        why,
    };
    let field = |at: usize| u32_at(bytes, at).unwrap_or(0);
    if bytes.len() < HEADER_BYTES + LEVEL_BYTES || !bytes.starts_with(SIGNATURE) {
        return Err(refuse(format!(
            "{} bytes are too few for a KTX2 header and level index",
            bytes.len()
        )));
    }
    let [
        vk_format,
        _type_size,
        width,
        height,
        depth,
        layers,
        faces,
        levels,
        scheme,
    ] = [12, 16, 20, 24, 28, 32, 36, 40, 44].map(field);
    if vk_format != 0 {
        return Err(refuse(format!(
            "vkFormat {vk_format} is not a Basis Universal payload (those have vkFormat 0)"
        )));
    }
    if width == 0 || height == 0 {
        return Err(TextureError::Empty { name: name.into() });
    }
    if width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_TEXELS {
        return Err(TextureError::TooLarge {
            name: name.into(),
            width,
            height,
        });
    }
    if depth != 0 || layers > 1 || faces != 1 {
        return Err(refuse(format!(
            "a 2D image is required (depth {depth}, {layers} layers, {faces} faces)"
        )));
    }
    // A full mip chain of a W × H image has 1 + ⌊log₂ max(W, H)⌋ levels; 0
    // (levels to be generated) is not allowed for block-compressed data.
    let most_levels = 32 - width.max(height).leading_zeros();
    if levels == 0 || levels > most_levels {
        return Err(refuse(format!(
            "{levels} mip levels for {width}×{height} texels (1 to {most_levels})"
        )));
    }
    let index_end = HEADER_BYTES + levels as usize * LEVEL_BYTES;
    if index_end > bytes.len() {
        return Err(refuse(format!(
            "the level index ({levels} levels) runs past the end of the file"
        )));
    }
    for level in 0..levels as usize {
        let at = HEADER_BYTES + level * LEVEL_BYTES;
        let (offset, length) = (u64_at(bytes, at), u64_at(bytes, at + 8));
        let inside = offset
            .zip(length)
            .and_then(|(o, l)| range(bytes, o, l))
            .is_some_and(|r| !r.is_empty());
        if !inside {
            return Err(refuse(format!(
                "level {level}'s data lies outside the file"
            )));
        }
    }

    // The Data Format Descriptor: its total size, a block header of two
    // words, then colour model, primaries, transfer function and flags.
    let (dfd_offset, dfd_length) = (field(48), field(52));
    let dfd = range(bytes, dfd_offset.into(), dfd_length.into())
        .filter(|d| d.len() >= 16)
        .ok_or_else(|| refuse("its data format descriptor lies outside the file".into()))?;
    let model = u32::from(dfd[12]);
    match (model, scheme) {
        (MODEL_ETC1S, SCHEME_BASISLZ) => {
            let sgd = u64_at(bytes, 64).zip(u64_at(bytes, 72));
            if sgd
                .and_then(|(o, l)| range(bytes, o, l))
                .is_none_or(<[u8]>::is_empty)
            {
                return Err(refuse(
                    "its BasisLZ global data lies outside the file".into(),
                ));
            }
        }
        (MODEL_UASTC, SCHEME_NONE | SCHEME_ZSTD) => {
            // One 16-byte block per 4×4 texels (partial blocks at the edges).
            let blocks = u64::from(width.div_ceil(4)) * u64::from(height.div_ceil(4));
            let want = blocks * 16;
            let (offset, length, unpacked) = (
                u64_at(bytes, HEADER_BYTES).unwrap_or(0),
                u64_at(bytes, HEADER_BYTES + 8).unwrap_or(0),
                u64_at(bytes, HEADER_BYTES + 16).unwrap_or(0),
            );
            let size = if scheme == SCHEME_ZSTD {
                unpacked
            } else {
                length
            };
            if size != want {
                return Err(refuse(format!(
                    "its UASTC base level holds {size} bytes, not the {want} of {width}×{height} texels"
                )));
            }
            if scheme == SCHEME_ZSTD {
                // Checked inside the file above.
                let level = range(bytes, offset, length).unwrap_or_default();
                let window = zstd_window(level)
                    .ok_or_else(|| refuse("its base level is not a Zstandard frame".into()))?;
                if window > want.saturating_mul(2).max(ZSTD_WINDOW_FLOOR) {
                    return Err(refuse(format!(
                        "its base level's Zstandard window of {window} bytes is far more than its {want} bytes need"
                    )));
                }
            }
        }
        (MODEL_ETC1S | MODEL_UASTC, _) => {
            return Err(refuse(format!(
                "supercompression scheme {scheme} does not go with its {} payload",
                if model == MODEL_ETC1S {
                    "ETC1S"
                } else {
                    "UASTC"
                }
            )));
        }
        _ => {
            return Err(refuse(format!(
                "colour model {model} is neither ETC1S nor UASTC (Basis Universal)"
            )));
        }
    }

    let (kvd_offset, kvd_length) = (field(56), field(60));
    range(bytes, kvd_offset.into(), kvd_length.into())
        .ok_or_else(|| refuse("its key/value data lies outside the file".into()))?;
    let (mut flip_x, mut flip_y) = (false, false);
    for (key, value) in
        key_values(bytes, kvd_offset as usize, kvd_length as usize).map_err(refuse)?
    {
        // Values are NUL-terminated strings (KTX 2.0 §5.3, §5.4).
        let value = value.split(|&b| b == 0).next().unwrap_or_default();
        match key {
            b"KTXorientation" => {
                // "rd" (glTF's own: row 0 at the top) is the only value the
                // extension allows; the flipped ones are honoured anyway.
                match value {
                    [x, y, ..] if matches!(x, b'r' | b'l') && matches!(y, b'd' | b'u') => {
                        flip_x = *x == b'l';
                        flip_y = *y == b'u';
                    }
                    _ => {
                        return Err(refuse(format!(
                            "orientation {:?} is not a 2D one",
                            String::from_utf8_lossy(value)
                        )));
                    }
                }
            }
            b"KTXswizzle" if !value.starts_with(b"rgba") => {
                return Err(refuse(format!(
                    "swizzle {:?} is not rgba (the extension allows no other)",
                    String::from_utf8_lossy(value)
                )));
            }
            _ => {}
        }
    }
    Ok(Header {
        width,
        height,
        flip_x,
        flip_y,
    })
}

/// A key and its value, as bytes.
type KeyValue<'a> = (&'a [u8], &'a [u8]);

/// The key/value pairs of the KTX2 key/value data at `offset..offset + length`
/// of `bytes` (§3.11): each a `u32` length, then the key (NUL-terminated) and
/// value, padded to 4 bytes of the file. Reading ends, as the transcoder's
/// does, at an entry too short to hold a key or with 4 bytes or fewer left;
/// an entry, or its padding, running past the data's end is refused (the
/// transcoder's own scan would step past the end: basisu 0.1.0 panics).
fn key_values(bytes: &[u8], offset: usize, length: usize) -> Result<Vec<KeyValue<'_>>, String> {
    let end = offset + length;
    let mut at = offset;
    let mut pairs = Vec::new();
    while end - at > 4 {
        let len = u32_at(bytes, at).unwrap_or(0) as usize;
        at += 4;
        if len < 2 {
            break;
        }
        let past = |at: usize| {
            format!(
                "its key/value entry at byte {} runs past the key/value data's {length} bytes",
                at - 4
            )
        };
        if end - at < len {
            return Err(past(at));
        }
        let entry = &bytes[at..at + len];
        let start = at;
        at = (at + len).next_multiple_of(4);
        if at > end {
            return Err(past(start));
        }
        let Some(nul) = entry.iter().position(|&b| b == 0) else {
            continue;
        };
        pairs.push((&entry[..nul], &entry[nul + 1..]));
    }
    Ok(pairs)
}

/// The window size a Zstandard frame header asks for (RFC 8878 §3.1.1.1),
/// or `None` if `frame` does not start with one.
fn zstd_window(frame: &[u8]) -> Option<u64> {
    if u32_at(frame, 0)? != ZSTD_MAGIC {
        return None;
    }
    let descriptor = *frame.get(4)?;
    if descriptor & 0x20 == 0 {
        // A window descriptor: exponent and mantissa.
        let wd = *frame.get(5)?;
        let base = 1u64 << (10 + (wd >> 3));
        return Some(base + base / 8 * u64::from(wd & 7));
    }
    // A single segment: the window is the content size, whose field
    // follows the dictionary id.
    let dict_bytes = [0usize, 1, 2, 4][usize::from(descriptor & 3)];
    let at = 5 + dict_bytes;
    Some(match descriptor >> 6 {
        0 => u64::from(*frame.get(at)?),
        1 => u64::from(u16::from_le_bytes(frame.get(at..at + 2)?.try_into().ok()?)) + 256,
        2 => u64::from(u32_at(frame, at)?),
        _ => u64_at(frame, at)?,
    })
}

/// Decodes a KTX2 file's base level to 8-bit RGBA (RGB when the payload has
/// no alpha), after [`check`]ing it.
pub(super) fn decode(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
    let header = check(bytes, name)?;
    let refuse = |why: String| TextureError::Ktx2 {
        name: name.into(),
        why,
    };
    // A panic in the transcoder (a bug of its own a file can trip) is one
    // more refusal, named after it.
    let (rgba, has_alpha) = crate::guard::catch("basisu", || {
        let transcoder = basisu::Transcoder::new(bytes)
            .map_err(|e| format!("the Basis Universal transcoder refuses it ({e:?})"))?;
        if transcoder.base_dimensions() != (header.width, header.height) {
            return Err("the transcoder reads another size".to_string());
        }
        let rgba = transcoder
            .transcode(0, basisu::TargetFormat::Rgba32, basisu::DecodeFlags::NONE)
            .map_err(|e| format!("its base level does not transcode ({e:?})"))?;
        Ok((rgba, transcoder.has_alpha()))
    })
    .and_then(|r| r)
    .map_err(refuse)?;
    let (w, h) = (header.width as usize, header.height as usize);
    if rgba.len() != w * h * 4 {
        return Err(refuse("the transcoder returned another size".into()));
    }
    // In place, so that the transcoder's output (the 4 bytes a texel charged
    // to the memory budget) is the only image held: flips, then RGB from
    // RGBA without alpha (which keeps the RGBA buffer's capacity: what was
    // charged).
    let mut texels = rgba;
    if header.flip_y {
        for y in 0..h / 2 {
            let (top, bottom) = texels.split_at_mut((h - 1 - y) * w * 4);
            top[y * w * 4..(y + 1) * w * 4].swap_with_slice(&mut bottom[..w * 4]);
        }
    }
    if header.flip_x {
        for row in texels.chunks_exact_mut(w * 4) {
            for x in 0..w / 2 {
                for c in 0..4 {
                    row.swap(x * 4 + c, (w - 1 - x) * 4 + c);
                }
            }
        }
    }
    let channels = if has_alpha { 4 } else { 3 };
    if channels == 3 {
        for i in 0..w * h {
            texels.copy_within(i * 4..i * 4 + 3, i * 3);
        }
        texels.truncate(w * h * 3);
    }
    Ok(Image::from_u8(
        header.width,
        header.height,
        channels as u8,
        texels,
    ))
}
