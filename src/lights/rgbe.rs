//! Radiance `.hdr` (RGBE) images, read and written by a small codec of our own:
//! it decodes exactly as `scene-conventions.md` says (value = mantissa ×
//! 2^(exponent − 136), no +0.5), checks the size against limits before
//! allocating, and names what is wrong with a file.
//!
//! Supported: the `32-bit_rle_rgbe` format with the standard orientation
//! `-Y H +X W` (and `+Y H +X W`, stored bottom-up), scanlines flat, in the old
//! run-length form, or in the adaptive run-length form (per-channel runs).

use std::io::Write;

/// An RGB image of floats, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row by row from the top.
    pub pixels: Vec<[f32; 3]>,
}

/// Decodes one RGBE pixel.
#[inline]
pub fn rgbe_to_rgb(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    // 2^(e − 136) built from its bits while it is a normal float (e ≥ 10).
    let scale = if p[3] >= 10 {
        f32::from_bits((p[3] as u32 - 9) << 23)
    } else {
        (p[3] as f32 - 136.0).exp2()
    };
    [
        p[0] as f32 * scale,
        p[1] as f32 * scale,
        p[2] as f32 * scale,
    ]
}

/// Encodes one RGB value as RGBE (the largest channel keeps 8 bits; values are
/// rounded down, so decoding gives back at most the input).
pub fn rgb_to_rgbe(c: [f32; 3]) -> [u8; 4] {
    let c = c.map(|x| if x.is_finite() && x > 0.0 { x } else { 0.0 });
    let m = c[0].max(c[1]).max(c[2]);
    if m < 1e-32 {
        return [0; 4];
    }
    // m = f · 2^e with f in [0.5, 1).
    let mut e = m.log2().floor() as i32 + 1;
    if m / (e as f32).exp2() >= 1.0 {
        e += 1;
    }
    let e = e.clamp(-128, 127);
    let scale = 256.0 / (e as f32).exp2();
    let q = |x: f32| (x * scale).min(255.0) as u8;
    [q(c[0]), q(c[1]), q(c[2]), (e + 128) as u8]
}

/// What a Radiance header says: the image's size, its orientation and where
/// its pixels start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Whether the rows are stored bottom-up (`+Y H +X W`).
    pub bottom_up: bool,
    /// Offset of the first scanline in the file.
    pub data_start: usize,
}

/// Reads a Radiance `.hdr` file's header (no pixel is read or allocated).
/// Errors say what is wrong, without the file name.
pub fn read_header(bytes: &[u8]) -> Result<Header, String> {
    let mut pos = 0usize;
    let next_line = |pos: &mut usize| -> Option<String> {
        let rest = bytes.get(*pos..)?;
        let end = rest.iter().position(|&b| b == b'\n')?;
        *pos += end + 1;
        Some(String::from_utf8_lossy(&rest[..end]).trim_end().to_string())
    };
    let first = next_line(&mut pos).ok_or("not a Radiance HDR file (no header)")?;
    if !first.starts_with("#?") {
        return Err("not a Radiance HDR file (it does not start with '#?')".into());
    }
    let mut header_lines = 0;
    loop {
        let line = next_line(&mut pos).ok_or("the header does not end (no empty line)")?;
        header_lines += 1;
        if header_lines > 4096 {
            return Err("the header has more than 4096 lines".into());
        }
        if line.is_empty() {
            break;
        }
        if let Some(f) = line.strip_prefix("FORMAT=")
            && f.trim() != "32-bit_rle_rgbe"
        {
            return Err(format!(
                "pixel format '{}' is not supported (only 32-bit_rle_rgbe)",
                crate::guard::quote(f.trim())
            ));
        }
    }
    let size = next_line(&mut pos).ok_or("no resolution line after the header")?;
    let size = crate::guard::quote(&size);
    let words: Vec<&str> = size.split_ascii_whitespace().collect();
    let parse = |w: &str| {
        w.parse::<usize>()
            .map_err(|_| format!("resolution line '{size}': '{w}' is not a size"))
    };
    let (height, width, bottom_up) = match words.as_slice() {
        ["-Y", h, "+X", w] => (parse(h)?, parse(w)?, false),
        ["+Y", h, "+X", w] => (parse(h)?, parse(w)?, true),
        _ => {
            return Err(format!(
                "resolution line '{size}' is not supported (only '-Y H +X W' or '+Y H +X W')"
            ));
        }
    };
    Ok(Header {
        width,
        height,
        bottom_up,
        data_start: pos,
    })
}

/// The fewest bytes a scanline of `width` pixels can take: one pixel and the
/// old-style repeat markers for the rest (4 bytes per 8 bits of the count), or
/// an adaptive run-length scanline (a 4-byte head, then per channel a 2-byte
/// run per 127 pixels), whichever is smaller.
fn min_scanline_bytes(width: usize) -> usize {
    let repeat_bytes = (usize::BITS - (width - 1).leading_zeros()).div_ceil(8) as usize;
    let flat = 4 + 4 * repeat_bytes;
    if (8..=0x7fff).contains(&width) {
        flat.min(4 + 4 * 2 * width.div_ceil(127))
    } else {
        flat
    }
}

/// Decodes a Radiance `.hdr` file's bytes. Images of more than `max_pixels`
/// pixels or wider or taller than `max_side`, or whose header promises more
/// scanlines than the bytes after it can hold, are refused before anything
/// is allocated for them. Errors say what is wrong, without the file name.
pub fn decode(bytes: &[u8], max_side: usize, max_pixels: usize) -> Result<RgbImage, String> {
    let Header {
        width,
        height,
        bottom_up,
        data_start,
    } = read_header(bytes)?;
    if width == 0 || height == 0 {
        return Err(format!("the image is {width}×{height}"));
    }
    if width > max_side || height > max_side || width.saturating_mul(height) > max_pixels {
        return Err(format!(
            "the image is {width}×{height}; at most {max_side} a side and {max_pixels} pixels are read"
        ));
    }
    let data = &bytes[data_start..];
    if data.len() / min_scanline_bytes(width) < height {
        return Err(format!(
            "the header says {width}×{height} but only {} bytes of pixels follow; the file is cut short or corrupt",
            data.len()
        ));
    }
    let mut pixels = vec![[0.0f32; 3]; width * height];
    let mut scanline = vec![[0u8; 4]; width];
    let mut at = 0usize;
    for row in 0..height {
        at = read_scanline(data, at, &mut scanline)
            .map_err(|e| format!("scanline {row} of {height}: {e}"))?;
        let y = if bottom_up { height - 1 - row } else { row };
        for (dst, &src) in pixels[y * width..(y + 1) * width].iter_mut().zip(&scanline) {
            *dst = rgbe_to_rgb(src);
        }
    }
    Ok(RgbImage {
        width,
        height,
        pixels,
    })
}

/// Reads one scanline starting at `at`; returns where the next one starts.
fn read_scanline(data: &[u8], mut at: usize, out: &mut [[u8; 4]]) -> Result<usize, String> {
    let width = out.len();
    let truncated = || "the file ends inside it".to_string();
    let head = data.get(at..at + 4).ok_or_else(truncated)?;
    let adaptive =
        (8..=0x7fff).contains(&width) && head[0] == 2 && head[1] == 2 && head[2] & 0x80 == 0;
    if adaptive {
        let stored = ((head[2] as usize) << 8) | head[3] as usize;
        if stored != width {
            return Err(format!(
                "run-length scanline of width {stored}, expected {width}"
            ));
        }
        at += 4;
        for channel in 0..4 {
            let mut x = 0;
            while x < width {
                let count = *data.get(at).ok_or_else(truncated)? as usize;
                at += 1;
                if count > 128 {
                    let run = count - 128;
                    let value = *data.get(at).ok_or_else(truncated)?;
                    at += 1;
                    if x + run > width {
                        return Err("a run passes the end of the scanline".into());
                    }
                    out[x..x + run].iter_mut().for_each(|p| p[channel] = value);
                    x += run;
                } else {
                    if count == 0 || x + count > width {
                        return Err(format!("a literal of {count} bytes does not fit"));
                    }
                    let src = data.get(at..at + count).ok_or_else(truncated)?;
                    for (p, &v) in out[x..x + count].iter_mut().zip(src) {
                        p[channel] = v;
                    }
                    at += count;
                    x += count;
                }
            }
        }
        return Ok(at);
    }
    // Flat pixels, with the old run-length marker (1, 1, 1, n): repeat the
    // previous pixel n << shift times.
    let mut x = 0;
    let mut shift = 0;
    while x < width {
        let p = data.get(at..at + 4).ok_or_else(truncated)?;
        at += 4;
        if p[0] == 1 && p[1] == 1 && p[2] == 1 {
            if x == 0 {
                return Err("a repeat marker before any pixel".into());
            }
            let run = (p[3] as usize).checked_shl(shift).unwrap_or(usize::MAX);
            if shift > 24 || run > width - x {
                return Err("a repeat runs past the end of the scanline".into());
            }
            let prev = out[x - 1];
            out[x..x + run].iter_mut().for_each(|q| *q = prev);
            x += run;
            shift += 8;
        } else {
            out[x] = [p[0], p[1], p[2], p[3]];
            x += 1;
            shift = 0;
        }
    }
    Ok(at)
}

/// Encodes an image as a Radiance `.hdr` file (flat scanlines: larger than
/// run-length ones, but simple and exact).
pub fn encode(image: &RgbImage, out: &mut impl Write) -> std::io::Result<()> {
    write!(
        out,
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n",
        image.height, image.width
    )?;
    let mut bytes = Vec::with_capacity(image.width * 4);
    for row in image.pixels.chunks(image.width.max(1)) {
        bytes.clear();
        for &p in row {
            bytes.extend_from_slice(&rgb_to_rgbe(p));
        }
        out.write_all(&bytes)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_decode_as_the_conventions_say() {
        // mantissa × 2^(e − 136), no +0.5.
        assert_eq!(rgbe_to_rgb([128, 64, 0, 129]), [1.0, 0.5, 0.0]);
        assert_eq!(rgbe_to_rgb([255, 1, 3, 136]), [255.0, 1.0, 3.0]);
        assert_eq!(rgbe_to_rgb([7, 7, 7, 0]), [0.0; 3]);
        for e in 1..=255u8 {
            let want = 200.0 * (e as f64 - 136.0).exp2();
            assert_eq!(
                rgbe_to_rgb([200, 0, 0, e])[0] as f64,
                want as f32 as f64,
                "e = {e}"
            );
        }
        // Round trip: exact for values RGBE can hold (8 bits under a shared exponent).
        for c in [[1.0, 0.5, 0.25], [30720.0, 1024.0, 0.0], [0.125, 0.25, 0.5]] {
            assert_eq!(rgbe_to_rgb(rgb_to_rgbe(c)), c);
        }
        let c = [0.3f32, 0.6, 0.9];
        let d = rgbe_to_rgb(rgb_to_rgbe(c));
        for k in 0..3 {
            assert!(d[k] <= c[k] && c[k] - d[k] < 0.9 / 128.0, "{d:?}");
        }
    }

    fn header(size: &str) -> Vec<u8> {
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1\n\n{size}\n").into_bytes()
    }

    #[test]
    fn flat_old_and_adaptive_run_lengths_decode_alike() {
        let width = 10;
        let px = |x: usize| [x as u8 * 10, 128, 5, 130];
        // Adaptive: per channel, a literal of 10 for R, runs for the others.
        let mut adaptive = header("-Y 1 +X 10");
        adaptive.extend_from_slice(&[2, 2, 0, 10]);
        adaptive.push(10);
        adaptive.extend((0..width).map(|x| px(x)[0]));
        adaptive.extend_from_slice(&[128 + 10, 128, 128 + 10, 5, 128 + 10, 130]);
        // Flat.
        let mut flat = header("-Y 1 +X 10");
        flat.extend((0..width).flat_map(px));
        let a = decode(&adaptive, 100, 100).unwrap();
        let f = decode(&flat, 100, 100).unwrap();
        assert_eq!(a, f);
        assert_eq!(a.pixels[3], rgbe_to_rgb(px(3)));
        // Old run-length: one pixel, repeated 9 times.
        let mut old = header("-Y 1 +X 10");
        old.extend_from_slice(&px(0));
        old.extend_from_slice(&[1, 1, 1, 9]);
        let o = decode(&old, 100, 100).unwrap();
        assert!(o.pixels.iter().all(|&p| p == rgbe_to_rgb(px(0))));
        // Bottom-up storage is flipped to rows from the top.
        let mut up = header("+Y 2 +X 1");
        up.extend_from_slice(&[128, 0, 0, 129, 0, 128, 0, 129]);
        assert_eq!(
            decode(&up, 10, 10).unwrap().pixels,
            [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]
        );
    }

    #[test]
    fn encode_then_decode_round_trips() {
        let image = RgbImage {
            width: 9,
            height: 3,
            pixels: (0..27).map(|i| [8.0 * i as f32, 64.0, 1024.0]).collect(),
        };
        let mut bytes = Vec::new();
        encode(&image, &mut bytes).unwrap();
        assert_eq!(decode(&bytes, 16, 100).unwrap(), image);
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let err = |bytes: &[u8]| decode(bytes, 64, 1000).unwrap_err();
        assert!(err(b"P6\n").contains("not a Radiance"));
        assert!(err(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n").contains("xyze"));
        assert!(err(&header("-Y 1 +X 100")).contains("at most 64"));
        assert!(err(&header("-Y 40 +X 40")).contains("1000 pixels"));
        assert!(err(&header("+X 4 -Y 4")).contains("not supported"));
        // Fewer bytes than any scanline of that width takes (8 here: a
        // pixel and one repeat marker): refused before the pixels are
        // allocated.
        assert!(err(&header("-Y 1 +X 8")).contains("says 8×1 but only 0 bytes"));
        let mut lying = header("-Y 60 +X 1");
        lying.extend_from_slice(&[128; 236]);
        assert!(err(&lying).contains("only 236 bytes"));
        let mut short = header("-Y 1 +X 8");
        short.extend_from_slice(&[128, 0, 0, 129, 128, 0, 0, 129]);
        assert!(err(&short).contains("ends inside"));
        let mut long = header("-Y 1 +X 8");
        long.extend_from_slice(&[2, 2, 0, 8, 128 + 9, 0, 0, 0]);
        assert!(err(&long).contains("passes the end"));
        let mut zero = header("-Y 1 +X 8");
        zero.extend_from_slice(&[2, 2, 0, 8, 0, 0, 0, 0]);
        assert!(err(&zero).contains("does not fit"));
        let mut lead = header("-Y 1 +X 2");
        lead.extend_from_slice(&[1, 1, 1, 1, 1, 1, 1, 1]);
        assert!(err(&lead).contains("before any pixel"));
        assert!(err(&header("-Y 0 +X 4")).contains("0"));
        assert!(err(&header("-Y -4 +X 4")).contains("not a size"));
    }
}
