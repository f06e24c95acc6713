//! [`Image`]: texels as decoded, and their filtered lookups, with the
//! lookups' modes: the colour space of the values ([`ColorSpace`]) and what
//! indices outside the image map to ([`Wrap`]).

use std::fmt;

use glam::{DVec4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::error::{MAX_SIDE, MAX_TEXELS};
use super::srgb::{linear8, linear16, srgb8, srgb16};

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

/// The stored channel values, row-major from the top-left, `channels` per texel.
#[derive(Clone)]
pub(super) enum Texels {
    /// 8 bits per channel.
    U8(Vec<u8>),
    /// 16 bits per channel.
    U16(Vec<u16>),
    /// Linear 32-bit floats (OpenEXR), whatever the colour space.
    F32(Vec<f32>),
}

/// A decoded image: `width × height` texels of 1–4 channels (grey, grey + alpha,
/// RGB, RGBA) of 8 or 16 bits each, stored as decoded and converted to floats
/// at lookup time (see the [module documentation](super)).
///
/// Row 0 is the first (top) row of the file, at v = 0.
#[derive(Clone)]
pub struct Image {
    width: u32,
    height: u32,
    channels: u8,
    texels: Texels,
}

impl fmt::Debug for Image {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Not the texels: an image may hold millions of them.
        f.debug_struct("Image")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("channels", &self.channels)
            .field("bits", &self.bits_per_channel())
            .finish()
    }
}

/// Sub-texel positions are rounded to 1/2^16 of a texel (GPUs use 1/2^8), so
/// that the centre of texel i, u = (i + 0.5)/W, which is not exact in `f32`,
/// gives exactly texel i's value (for i < 128; beyond, `f32` uv is coarser).
const SUBTEXEL: f64 = 65536.0;

impl Image {
    /// Adds the image's size, layout and texels to `f`.
    pub(crate) fn fingerprint_into(&self, f: &mut crate::fingerprint::Fingerprint) {
        f.words32([self.width, self.height, u32::from(self.channels)]);
        match &self.texels {
            Texels::U8(t) => {
                f.update(b"u8");
                f.update(t);
            }
            Texels::U16(t) => {
                f.update(b"u16");
                for chunk in t.chunks(256) {
                    let mut bytes = [0u8; 512];
                    for (b, v) in bytes.chunks_exact_mut(2).zip(chunk) {
                        b.copy_from_slice(&v.to_le_bytes());
                    }
                    f.update(&bytes[..2 * chunk.len()]);
                }
            }
            Texels::F32(t) => {
                f.update(b"f32");
                f.floats(t.iter().copied());
            }
        }
    }
}

impl Image {
    fn checked(width: u32, height: u32, channels: u8, len: usize) {
        assert!(width > 0 && height > 0, "empty {width}×{height} image");
        assert!(
            (1..=4).contains(&channels),
            "{channels} channels (must be 1 to 4)"
        );
        let expected = width as usize * height as usize * usize::from(channels);
        assert_eq!(
            len, expected,
            "{width}×{height}×{channels} image with {len} channel values"
        );
    }

    /// An image of 8-bit channel values, row-major from the top-left,
    /// `channels` (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) per texel.
    ///
    /// # Panics
    ///
    /// If a side is 0, `channels` is not 1 to 4, or `texels.len()` is not
    /// `width * height * channels`.
    pub fn from_u8(width: u32, height: u32, channels: u8, texels: Vec<u8>) -> Self {
        Self::checked(width, height, channels, texels.len());
        Self {
            width,
            height,
            channels,
            texels: Texels::U8(texels),
        }
    }

    /// An image of 16-bit channel values; as [`Image::from_u8`] otherwise.
    ///
    /// # Panics
    ///
    /// As [`Image::from_u8`].
    pub fn from_u16(width: u32, height: u32, channels: u8, texels: Vec<u16>) -> Self {
        Self::checked(width, height, channels, texels.len());
        Self {
            width,
            height,
            channels,
            texels: Texels::U16(texels),
        }
    }

    /// An image of linear 32-bit float channel values (an OpenEXR image),
    /// read as they are in either [`ColorSpace`]; as [`Image::from_u8`]
    /// otherwise.
    ///
    /// # Panics
    ///
    /// As [`Image::from_u8`].
    pub fn from_f32(width: u32, height: u32, channels: u8, texels: Vec<f32>) -> Self {
        Self::checked(width, height, channels, texels.len());
        Self {
            width,
            height,
            channels,
            texels: Texels::F32(texels),
        }
    }

    /// The image as [`Image::from_cache_bytes`] reads it (little-endian).
    pub(crate) fn to_cache_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let bits = u32::from(self.bits_per_channel());
        for v in [self.width, self.height, u32::from(self.channels), bits] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        match &self.texels {
            Texels::U8(t) => out.extend_from_slice(t),
            Texels::U16(t) => out.extend(t.iter().flat_map(|v| v.to_le_bytes())),
            Texels::F32(t) => out.extend(t.iter().flat_map(|v| v.to_le_bytes())),
        }
        out
    }

    /// An image [`Image::to_cache_bytes`] wrote, if the bytes make one within
    /// the limits of decoded images.
    pub(crate) fn from_cache_bytes(bytes: &[u8]) -> Option<Image> {
        let mut r = crate::cache::Reader(bytes);
        let (width, height, channels, bits) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?);
        let texels = u64::from(width) * u64::from(height);
        let sound = (1..=MAX_SIDE).contains(&width)
            && (1..=MAX_SIDE).contains(&height)
            && texels <= MAX_TEXELS
            && (1..=4).contains(&channels)
            && (bits == 8 || bits == 16 || bits == 32)
            && r.0.len() as u64 == texels * u64::from(channels) * u64::from(bits / 8);
        if !sound {
            return None;
        }
        let channels = channels as u8;
        Some(if bits == 8 {
            Self::from_u8(width, height, channels, r.0.to_vec())
        } else if bits == 32 {
            let values =
                r.0.chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            Self::from_f32(width, height, channels, values.collect())
        } else {
            let values =
                r.0.chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]));
            Self::from_u16(width, height, channels, values.collect())
        })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Channels per texel: 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA.
    pub fn channels(&self) -> u8 {
        self.channels
    }

    /// Bits per channel as stored: 8 or 16 (32: floats).
    pub fn bits_per_channel(&self) -> u8 {
        match self.texels {
            Texels::U8(_) => 8,
            Texels::U16(_) => 16,
            Texels::F32(_) => 32,
        }
    }

    /// Bytes held by the texels.
    pub fn memory_bytes(&self) -> usize {
        match &self.texels {
            Texels::U8(t) => t.len(),
            Texels::U16(t) => 2 * t.len(),
            Texels::F32(t) => 4 * t.len(),
        }
    }

    /// Texel (`x`, `y`) (column, row from the top) as linear RGBA: RGB (or grey)
    /// decoded from `space`, alpha always linear and 1 where there is none.
    ///
    /// # Panics
    ///
    /// If `x ≥ width` or `y ≥ height`.
    #[inline]
    pub fn texel(&self, x: u32, y: u32, space: ColorSpace) -> Vec4 {
        assert!(
            x < self.width && y < self.height,
            "texel ({x}, {y}) outside"
        );
        let c = usize::from(self.channels);
        let base = (y as usize * self.width as usize + x as usize) * c;
        match &self.texels {
            Texels::U8(t) => {
                let t = &t[base..base + c];
                let alpha = linear8();
                let rgb = match space {
                    ColorSpace::Linear => alpha,
                    ColorSpace::Srgb => srgb8(),
                };
                expand(c, |k| rgb[usize::from(t[k])], |k| alpha[usize::from(t[k])])
            }
            Texels::U16(t) => {
                let t = &t[base..base + c];
                match space {
                    ColorSpace::Linear => expand(c, |k| linear16(t[k]), |k| linear16(t[k])),
                    ColorSpace::Srgb => {
                        let rgb = srgb16();
                        expand(c, |k| rgb[usize::from(t[k])], |k| linear16(t[k]))
                    }
                }
            }
            Texels::F32(t) => {
                let t = &t[base..base + c];
                expand(c, |k| t[k], |k| t[k])
            }
        }
    }

    /// The bilinearly filtered value at `uv` as linear RGBA (see
    /// [`Image::texel`] for the channels), glTF conventions: (0, 0) is the
    /// top-left corner of the image, texel (i, j) is centred on
    /// ((i + 0.5)/W, (j + 0.5)/H), the four taps around `uv` have their indices
    /// wrapped by `wrap_s` (columns) and `wrap_t` (rows), and each tap is decoded
    /// (from sRGB if `space` says so) before they are interpolated.
    ///
    /// The position within a texel is rounded to 1/65536 of a texel, so that a
    /// texel's centre gives exactly its value although (i + 0.5)/W is rounded
    /// in `f32`. A NaN or infinite coordinate reads as 0 (a finite result, no
    /// panic).
    #[inline]
    pub fn lookup(&self, uv: Vec2, wrap_s: Wrap, wrap_t: Wrap, space: ColorSpace) -> Vec4 {
        let (x0, x1, fx) = taps(uv.x, self.width, wrap_s);
        let (y0, y1, fy) = taps(uv.y, self.height, wrap_t);
        // a·(1 − f) + b·f rather than a lerp: exactly a at f = 0 and b at f = 1.
        let row = |y| self.texel(x0, y, space) * (1.0 - fx) + self.texel(x1, y, space) * fx;
        row(y0) * (1.0 - fy) + row(y1) * fy
    }

    /// The partial derivatives of [`Image::lookup`]'s bilinear value at `uv`
    /// with respect to `u` and `v` (each texel's value as [`Image::texel`]
    /// decodes it), the derivative of the bilinear patch the point lies in:
    /// Mitsuba's `Texture::eval_1_grad` of a bilinear `bitmap`.
    #[inline]
    pub fn lookup_gradient(
        &self,
        uv: Vec2,
        wrap_s: Wrap,
        wrap_t: Wrap,
        space: ColorSpace,
    ) -> (Vec4, Vec4) {
        let (x0, x1, fx) = taps(uv.x, self.width, wrap_s);
        let (y0, y1, fy) = taps(uv.y, self.height, wrap_t);
        let (f00, f10) = (self.texel(x0, y0, space), self.texel(x1, y0, space));
        let (f01, f11) = (self.texel(x0, y1, space), self.texel(x1, y1, space));
        let d_dx = (f10 - f00) * (1.0 - fy) + (f11 - f01) * fy;
        let d_dy = (f01 - f00) * (1.0 - fx) + (f11 - f10) * fx;
        (d_dx * self.width as f32, d_dy * self.height as f32)
    }

    /// The texel nearest to `uv` (the one whose square holds it), its indices
    /// wrapped as in [`Image::lookup`]: Mitsuba's `filter_type = "nearest"`.
    /// A NaN or infinite coordinate reads texel 0.
    #[inline]
    pub fn nearest(&self, uv: Vec2, wrap_s: Wrap, wrap_t: Wrap, space: ColorSpace) -> Vec4 {
        let index = |c: f32, size: u32, wrap: Wrap| {
            let k = (c * size as f32).floor();
            let k = if k.is_finite() {
                k.clamp(-1e15, 1e15) as i64
            } else {
                0
            };
            wrap_index(k, size, wrap)
        };
        self.texel(
            index(uv.x, self.width, wrap_s),
            index(uv.y, self.height, wrap_t),
            space,
        )
    }

    /// The mean of all texels, decoded as by [`Image::texel`] (e.g. to estimate
    /// the power an emissive texture radiates). Summed in `f64`, row by row in
    /// parallel and then in row order: the same result on every run.
    pub fn average(&self, space: ColorSpace) -> Vec4 {
        let rows: Vec<DVec4> = (0..self.height)
            .into_par_iter()
            .map(|y| {
                (0..self.width)
                    .map(|x| self.texel(x, y, space).as_dvec4())
                    .sum()
            })
            .collect();
        let total: DVec4 = rows.into_iter().sum();
        (total / (f64::from(self.width) * f64::from(self.height))).as_vec4()
    }
}

/// RGBA from `channels` values: grey → (g, g, g, 1), grey + alpha → (g, g, g, a),
/// RGB → (r, g, b, 1), RGBA.
#[inline(always)]
fn expand(channels: usize, rgb: impl Fn(usize) -> f32, alpha: impl Fn(usize) -> f32) -> Vec4 {
    match channels {
        1 => Vec3::splat(rgb(0)).extend(1.0),
        2 => Vec3::splat(rgb(0)).extend(alpha(1)),
        3 => Vec4::new(rgb(0), rgb(1), rgb(2), 1.0),
        _ => Vec4::new(rgb(0), rgb(1), rgb(2), alpha(3)),
    }
}

/// The two texel indices a bilinear lookup at `coord` reads along an axis of
/// `size` texels, wrapped, and the weight of the second.
#[inline]
fn taps(coord: f32, size: u32, wrap: Wrap) -> (u32, u32, f32) {
    // In f64 the product is exact; texel centres are at integers.
    let x = if coord.is_finite() {
        f64::from(coord) * f64::from(size) - 0.5
    } else {
        0.0
    };
    let floor = x.floor();
    let frac = ((x - floor) * SUBTEXEL).round() / SUBTEXEL;
    // Saturating conversion: huge coordinates stay finite indices.
    let i0 = floor as i64;
    let i1 = i0.saturating_add(1);
    (
        wrap_index(i0, size, wrap),
        wrap_index(i1, size, wrap),
        frac as f32,
    )
}

/// Wraps a texel index into `0..size` (OpenGL's rules for integer indices).
#[inline]
fn wrap_index(i: i64, size: u32, wrap: Wrap) -> u32 {
    let n = i64::from(size);
    if (0..n).contains(&i) {
        // Inside the image every mode keeps the index; the remainders below
        // are 64-bit divisions, four for each bilinear lookup otherwise.
        return i as u32;
    }
    let w = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        // GL_MIRRORED_REPEAT: (size − 1) − mirror((i mod 2·size) − size), with
        // mirror(a) = a ≥ 0 ? a : −(1 + a); i.e. 0..n−1 then n−1..0, repeated.
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
        Wrap::ClampToEdge => i.clamp(0, n - 1),
    };
    w as u32
}
