//! Tests of the textures module: exact values at texel centres, bilinear
//! filtering, wrap modes, sRGB decoding, KHR_texture_transform, decoding.

use std::time::{Duration, Instant};

use glam::{Vec2, Vec4};
use image::ImageEncoder;
use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::PngEncoder;

use super::*;

/// A 4×3 RGBA8 image whose texel (i, j) is (10i + j, 40 + 50j + i, 255 − 17i, 60j + 3i).
fn rgba_4x3() -> (Image, Vec<[u8; 4]>) {
    let mut texels = Vec::new();
    for j in 0..3u8 {
        for i in 0..4u8 {
            texels.push([10 * i + j, 40 + 50 * j + i, 255 - 17 * i, 60 * j + 3 * i]);
        }
    }
    let image = Image::from_u8(4, 3, 4, texels.iter().flatten().copied().collect());
    (image, texels)
}

fn centre(i: u32, j: u32, w: u32, h: u32) -> Vec2 {
    Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32)
}

fn decode_byte(b: u8, space: ColorSpace) -> f32 {
    match space {
        ColorSpace::Linear => b as f32 / 255.0,
        ColorSpace::Srgb => srgb_to_linear(b as f32 / 255.0),
    }
}

/// A grey 8-bit image of one row.
fn grey_row(values: &[u8]) -> Image {
    Image::from_u8(values.len() as u32, 1, 1, values.to_vec())
}

#[test]
fn texel_centres_give_exact_decoded_values() {
    let (image, texels) = rgba_4x3();
    for space in [ColorSpace::Linear, ColorSpace::Srgb] {
        for j in 0..3 {
            for i in 0..4 {
                let t = texels[(j * 4 + i) as usize];
                let expected = Vec4::new(
                    decode_byte(t[0], space),
                    decode_byte(t[1], space),
                    decode_byte(t[2], space),
                    t[3] as f32 / 255.0, // alpha is linear in both spaces
                );
                let got = image.lookup(centre(i, j, 4, 3), Wrap::Repeat, Wrap::Repeat, space);
                assert_eq!(got, expected, "texel ({i}, {j}) in {space:?}");
                assert_eq!(image.texel(i, j, space), expected);
            }
        }
    }
    // Row 0 (the first of the data) is at the top, v near 0: texel (0, 0) has
    // green 40, texel (0, 2) (bottom row) green 140.
    let top = image.lookup(
        Vec2::new(0.1, 0.01),
        Wrap::ClampToEdge,
        Wrap::ClampToEdge,
        ColorSpace::Linear,
    );
    let bottom = image.lookup(
        Vec2::new(0.1, 0.99),
        Wrap::ClampToEdge,
        Wrap::ClampToEdge,
        ColorSpace::Linear,
    );
    assert_eq!(top.y, 40.0 / 255.0);
    assert_eq!(bottom.y, 140.0 / 255.0);
}

#[test]
fn texel_centres_are_exact_for_awkward_sizes() {
    // Sizes whose (i + 0.5)/W are not exact in f32.
    for (w, h) in [(3u32, 7u32), (5, 11), (13, 1), (100, 3)] {
        let n = (w * h) as usize;
        let image = Image::from_u8(w, h, 1, (0..n).map(|k| (k * 37 % 256) as u8).collect());
        for j in 0..h {
            for i in 0..w {
                let got = image.lookup(
                    centre(i, j, w, h),
                    Wrap::Repeat,
                    Wrap::Repeat,
                    ColorSpace::Srgb,
                );
                assert_eq!(
                    got,
                    image.texel(i, j, ColorSpace::Srgb),
                    "{w}×{h} texel ({i}, {j})"
                );
            }
        }
    }
}

#[test]
fn bilinear_midpoints_are_means_of_decoded_taps() {
    let (image, _) = rgba_4x3();
    for space in [ColorSpace::Linear, ColorSpace::Srgb] {
        // Between the centres of (1, 1) and (2, 1): u = 2/4.
        let a = image.texel(1, 1, space);
        let b = image.texel(2, 1, space);
        let got = image.lookup(Vec2::new(0.5, 1.5 / 3.0), Wrap::Repeat, Wrap::Repeat, space);
        assert_eq!(got, (a + b) * 0.5, "{space:?}");
        // Between the centres of (2, 0) and (2, 1): v = 1/3 (not exact in f32).
        let c = image.texel(2, 0, space);
        let got = image.lookup(
            Vec2::new(2.5 / 4.0, 1.0 / 3.0),
            Wrap::Repeat,
            Wrap::Repeat,
            space,
        );
        assert!(
            (got - (c + b) * 0.5).abs().max_element() < 1e-6,
            "{space:?}: {got}"
        );
        // The centre of four texels: their mean.
        let d = image.texel(1, 0, space);
        let got = image.lookup(Vec2::new(0.5, 1.0 / 3.0), Wrap::Repeat, Wrap::Repeat, space);
        assert!((got - (a + b + c + d) * 0.25).abs().max_element() < 1e-6);
    }
    // A quarter of the way from (0, 0) to (1, 0): 3/4 of one, 1/4 of the other.
    let image = grey_row(&[0, 200]);
    let got = image.lookup(
        Vec2::new(0.375, 0.5),
        Wrap::Repeat,
        Wrap::Repeat,
        ColorSpace::Linear,
    );
    assert!((got.x - 50.0 / 255.0).abs() < 1e-7, "{got}");
}

#[test]
fn srgb_is_decoded_before_filtering() {
    // Black and white texels: halfway between them is 0.5 linear, not the
    // decoded halfway byte, decode(127.5/255) ≈ 0.2140.
    let image = grey_row(&[0, 255]);
    let mid = image.lookup(
        Vec2::new(0.5, 0.5),
        Wrap::ClampToEdge,
        Wrap::ClampToEdge,
        ColorSpace::Srgb,
    );
    assert_eq!(mid, Vec4::new(0.5, 0.5, 0.5, 1.0));
    let decoded_after = srgb_to_linear(127.5 / 255.0);
    assert!((decoded_after - 0.2140).abs() < 1e-4);
    assert!((mid.x - decoded_after).abs() > 0.25);

    // The same with 16-bit texels.
    let image = Image::from_u16(2, 1, 1, vec![0, 65535]);
    let mid = image.lookup(
        Vec2::new(0.5, 0.5),
        Wrap::ClampToEdge,
        Wrap::ClampToEdge,
        ColorSpace::Srgb,
    );
    assert_eq!(mid.x, 0.5);
}

#[test]
fn srgb_decoding_of_known_values() {
    assert_eq!(srgb_to_linear(0.0), 0.0);
    assert_eq!(srgb_to_linear(1.0), 1.0);
    assert!((srgb_to_linear(188.0 / 255.0) - 0.502_886_5).abs() < 1e-6);
    // Linear segment: 10/255 ≤ 0.04045.
    assert!((srgb_to_linear(10.0 / 255.0) - 10.0 / 255.0 / 12.92).abs() < 1e-9);
    assert!((srgb_to_linear(10.0 / 255.0) - 0.003_035_27).abs() < 1e-8);
    // Through the lookup tables, 8- and 16-bit.
    let image = grey_row(&[0, 188, 255]);
    let at = |i| image.texel(i, 0, ColorSpace::Srgb).x;
    assert_eq!(at(0), 0.0);
    assert!((at(1) - 0.502_886_5).abs() < 1e-6);
    assert_eq!(at(2), 1.0);
    let image = Image::from_u16(3, 1, 1, vec![0, 188 * 257, 65535]);
    let at = |i| image.texel(i, 0, ColorSpace::Srgb).x;
    assert_eq!(at(0), 0.0);
    assert!((at(1) - 0.502_886_5).abs() < 1e-6);
    assert_eq!(at(2), 1.0);
    // Every 8-bit table entry (and a sample of the 16-bit ones) is the EOTF of
    // the f32 ratio, evaluated in f64 and rounded once, as a decode at load.
    let eotf = |x: f64| {
        if x <= 0.04045 {
            x / 12.92
        } else {
            ((x + 0.055) / 1.055).powf(2.4)
        }
    };
    for b in 0..=255u8 {
        let table = grey_row(&[b]).texel(0, 0, ColorSpace::Srgb).x;
        assert_eq!(table, eotf(f64::from(b as f32 / 255.0)) as f32, "byte {b}");
        assert!((f64::from(table) - eotf(b as f64 / 255.0)).abs() < 1e-7);
    }
    for w in (0..=65535u16).step_by(257 * 3 + 1) {
        let table = Image::from_u16(1, 1, 1, vec![w])
            .texel(0, 0, ColorSpace::Srgb)
            .x;
        assert_eq!(
            table,
            eotf(f64::from(w as f32 / 65535.0)) as f32,
            "word {w}"
        );
    }
}

#[test]
fn channels_expand_to_rgba() {
    let space = ColorSpace::Linear;
    let grey = Image::from_u8(1, 1, 1, vec![51]);
    assert_eq!(grey.texel(0, 0, space), Vec4::new(0.2, 0.2, 0.2, 1.0));
    let grey_alpha = Image::from_u8(1, 1, 2, vec![51, 102]);
    assert_eq!(grey_alpha.texel(0, 0, space), Vec4::new(0.2, 0.2, 0.2, 0.4));
    // Alpha stays linear in sRGB space.
    let srgb = grey_alpha.texel(0, 0, ColorSpace::Srgb);
    assert_eq!(srgb.w, 0.4);
    assert_eq!(srgb.x, srgb_to_linear(0.2));
    let rgb = Image::from_u16(1, 1, 3, vec![0, 13107, 65535]);
    assert_eq!(rgb.texel(0, 0, space), Vec4::new(0.0, 0.2, 1.0, 1.0));
    let rgba = Image::from_u16(1, 1, 4, vec![0, 13107, 65535, 26214]);
    assert_eq!(rgba.texel(0, 0, space), Vec4::new(0.0, 0.2, 1.0, 0.4));
}

#[test]
fn wrap_modes_apply_to_tap_indices() {
    let image = grey_row(&[10, 20, 30, 40]);
    let w = 4.0;
    let at = |u: f32, wrap| {
        image
            .lookup(
                Vec2::new(u, 0.5),
                wrap,
                Wrap::ClampToEdge,
                ColorSpace::Linear,
            )
            .x
            * 255.0
    };
    let close = |a: f32, b: f32| (a - b).abs() < 1e-4;

    // A quarter texel left of the left edge: taps -1 (weight 3/4) and 0 (1/4).
    let u = -0.25 / w;
    assert!(close(at(u, Wrap::Repeat), 0.75 * 40.0 + 0.25 * 10.0)); // the last column
    assert!(close(at(u, Wrap::MirroredRepeat), 10.0)); // -1 mirrors to 0
    assert!(close(at(u, Wrap::ClampToEdge), 10.0));

    // A quarter texel right of the right edge: x = 3.75, taps 3 (1/4) and 4 (3/4).
    let u = 1.0 + 0.25 / w;
    assert!(close(at(u, Wrap::Repeat), 0.25 * 40.0 + 0.75 * 10.0)); // 4 is column 0
    assert!(close(at(u, Wrap::MirroredRepeat), 40.0)); // 4 mirrors to 3
    assert!(close(at(u, Wrap::ClampToEdge), 40.0));

    // u = 1.75: x = 6.5, taps 6 and 7, mirrored to 1 and 0 (the mirror image
    // of u = 0.25); repeat reads 2 and 3 (as at u = 0.75); clamp the last.
    assert!(close(at(1.75, Wrap::MirroredRepeat), 15.0));
    assert!(close(at(0.25, Wrap::MirroredRepeat), 15.0));
    assert!(close(at(1.75, Wrap::Repeat), 35.0));
    assert!(close(at(1.75, Wrap::ClampToEdge), 40.0));
    // u = 1.3 (x = 4.7: taps 4, 5 → mirrored 3, 2, weight 0.7 on 2) is u = 0.7.
    // u = 0.7 (x = 2.3): 0.7 of texel 2 and 0.3 of texel 3.
    assert!(close(
        at(1.3, Wrap::MirroredRepeat),
        0.3 * 40.0 + 0.7 * 30.0
    ));
    assert!(close(
        at(0.7, Wrap::MirroredRepeat),
        0.3 * 40.0 + 0.7 * 30.0
    ));
    // Negative, several periods away: u = -2.25 (x = -9.5, taps -10, -9).
    // Repeat: -10 → 2, -9 → 3, half each; mirrored: period 8, -10 → 6 → 1,
    // -9 → 7 → 0.
    assert!(close(at(-2.25, Wrap::Repeat), 35.0));
    assert!(close(at(-2.25, Wrap::MirroredRepeat), 15.0));
    assert!(close(at(-2.25, Wrap::ClampToEdge), 10.0));

    // wrap_t works on rows, independently of wrap_s: a 1×4 column.
    let column = Image::from_u8(1, 4, 1, vec![10, 20, 30, 40]);
    let at = |v: f32, wrap| {
        column
            .lookup(Vec2::new(-3.0, v), Wrap::Repeat, wrap, ColorSpace::Linear)
            .x
            * 255.0
    };
    let v = -0.25 / 4.0;
    assert!(close(at(v, Wrap::Repeat), 32.5));
    assert!(close(at(v, Wrap::MirroredRepeat), 10.0));
    assert!(close(at(v, Wrap::ClampToEdge), 10.0));
}

#[test]
fn non_finite_coordinates_read_texel_zero() {
    let (image, _) = rgba_4x3();
    let first = image.texel(0, 0, ColorSpace::Srgb);
    for uv in [
        Vec2::new(f32::NAN, f32::NAN),
        Vec2::new(f32::INFINITY, f32::NEG_INFINITY),
        Vec2::new(f32::NAN, 0.5 / 3.0),
    ] {
        for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
            let got = image.lookup(uv, wrap, wrap, ColorSpace::Srgb);
            assert!(got.is_finite(), "{uv}: {got}");
            assert_eq!(got, first, "{uv}");
        }
    }
    // Huge finite coordinates stay finite too.
    for u in [f32::MAX, -f32::MAX, 1e30, -3e9] {
        for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
            assert!(
                image
                    .lookup(Vec2::new(u, u), wrap, wrap, ColorSpace::Linear)
                    .is_finite()
            );
        }
    }
}

#[test]
fn average_and_memory() {
    let image = Image::from_u8(2, 2, 3, vec![0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 51, 0]);
    let mean = image.average(ColorSpace::Linear);
    assert!(
        (mean - Vec4::new(0.5, 0.3, 0.25, 1.0)).abs().max_element() < 1e-6,
        "{mean}"
    );
    let mean = image.average(ColorSpace::Srgb);
    let g = srgb_to_linear(0.2);
    assert!(
        (mean - Vec4::new(0.5, (1.0 + g) / 4.0, 0.25, 1.0))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(image.memory_bytes(), 12);

    let (rgba, _) = rgba_4x3();
    assert_eq!(rgba.memory_bytes(), 48);
    let wide = Image::from_u16(2, 2, 3, vec![0; 12]);
    assert_eq!(wide.memory_bytes(), 24);
    let mut store = TextureStore::new();
    assert_eq!(store.push(rgba), 0);
    assert_eq!(store.push(wide), 1);
    assert_eq!(store.len(), 2);
    assert_eq!(store.memory_bytes(), 72);
    assert_eq!(store.get(1).bits_per_channel(), 16);
}

#[test]
fn khr_texture_transform_matches_the_specification() {
    let close = |a: Vec2, b: Vec2| (a - b).abs().max_element() < 1e-6;
    let identity = TextureTransform::default();
    assert!(identity.is_identity());
    assert_eq!(identity.apply(Vec2::new(0.3, -0.7)), Vec2::new(0.3, -0.7));

    // The specification's example: offset [0, 1], rotation π/2, scale [0.5, 0.5]
    // "utilizes only the lower left quadrant of the source image, rotated
    // clockwise 90°": u' = 0.5·v, v' = 1 − 0.5·u.
    let t = TextureTransform {
        offset: Vec2::new(0.0, 1.0),
        rotation: std::f32::consts::FRAC_PI_2,
        scale: Vec2::splat(0.5),
    };
    assert!(close(t.apply(Vec2::new(0.0, 0.0)), Vec2::new(0.0, 1.0)));
    assert!(close(t.apply(Vec2::new(1.0, 0.0)), Vec2::new(0.0, 0.5)));
    assert!(close(t.apply(Vec2::new(0.0, 1.0)), Vec2::new(0.5, 1.0)));
    assert!(close(t.apply(Vec2::new(1.0, 1.0)), Vec2::new(0.5, 0.5)));

    // The other example: offset [0, 1], scale [1, -1] flips v.
    let flip = TextureTransform {
        offset: Vec2::new(0.0, 1.0),
        rotation: 0.0,
        scale: Vec2::new(1.0, -1.0),
    };
    assert!(close(flip.apply(Vec2::new(0.2, 0.3)), Vec2::new(0.2, 0.7)));

    // A general case by hand: S = (0.8, 2.1); c = cos 0.3, s = sin 0.3;
    // R·S·uv = (0.8c + 2.1s, −0.8s + 2.1c) = (1.384862, 1.769790); plus offset.
    let t = TextureTransform {
        offset: Vec2::new(0.25, -0.5),
        rotation: 0.3,
        scale: Vec2::new(2.0, 3.0),
    };
    let expected = Vec2::new(1.634_861_6, 1.269_790_5);
    assert!(close(t.apply(Vec2::new(0.4, 0.7)), expected));
    assert!(close(
        t.matrix().transform_point2(Vec2::new(0.4, 0.7)),
        expected
    ));

    // Through a store lookup: the transform runs before the lookup.
    let mut store = TextureStore::new();
    let id = store.push(Image::from_u8(2, 2, 1, vec![0, 60, 120, 180]));
    let mut texture = TextureRef::new(id);
    texture.transform = TextureTransform {
        offset: Vec2::new(0.5, 0.5),
        rotation: 0.0,
        scale: Vec2::splat(0.0),
    };
    // Every uv maps to (0.5, 0.5): the mean of the four texels.
    let got = store.lookup(&texture, Vec2::new(0.9, 0.1), ColorSpace::Linear);
    assert!((got.x - 90.0 / 255.0).abs() < 1e-6);
}

fn encode_png(width: u32, height: u32, bytes: &[u8], color: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(bytes, width, height, color)
        .unwrap();
    out
}

#[test]
fn png_round_trip_8_bit() {
    let (reference, texels) = rgba_4x3();
    let bytes: Vec<u8> = texels.iter().flatten().copied().collect();
    let png = encode_png(4, 3, &bytes, image::ExtendedColorType::Rgba8);
    let image = Image::decode(&png, "rgba.png").unwrap();
    assert_eq!((image.width(), image.height(), image.channels()), (4, 3, 4));
    assert_eq!(image.bits_per_channel(), 8);
    assert_eq!(image.memory_bytes(), 48);
    for j in 0..3 {
        for i in 0..4 {
            for space in [ColorSpace::Linear, ColorSpace::Srgb] {
                assert_eq!(image.texel(i, j, space), reference.texel(i, j, space));
            }
        }
    }
    // Grey + alpha keeps its two channels.
    let png = encode_png(2, 1, &[10, 20, 30, 40], image::ExtendedColorType::La8);
    let image = Image::decode(&png, "la.png").unwrap();
    assert_eq!(image.channels(), 2);
    assert_eq!(
        image.texel(1, 0, ColorSpace::Linear),
        Vec4::new(30.0 / 255.0, 30.0 / 255.0, 30.0 / 255.0, 40.0 / 255.0)
    );
}

#[test]
fn png_round_trip_16_bit() {
    let words: [u16; 6] = [0, 1, 257, 32768, 65534, 65535];
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).collect();
    let png = encode_png(2, 1, &bytes, image::ExtendedColorType::Rgb16);
    let image = Image::decode(&png, "deep.png").unwrap();
    assert_eq!((image.width(), image.height(), image.channels()), (2, 1, 3));
    assert_eq!(image.bits_per_channel(), 16);
    assert_eq!(image.memory_bytes(), 12);
    let reference = Image::from_u16(2, 1, 3, words.to_vec());
    for space in [ColorSpace::Linear, ColorSpace::Srgb] {
        for i in 0..2 {
            assert_eq!(image.texel(i, 0, space), reference.texel(i, 0, space));
        }
    }
    assert_eq!(image.texel(0, 0, ColorSpace::Linear).y, 1.0 / 65535.0);
    assert_eq!(image.texel(1, 0, ColorSpace::Linear).x, 32768.0 / 65535.0);
}

#[test]
fn jpeg_round_trip() {
    // 16×8, left half one colour, right half another (edges on block bounds).
    let (w, h) = (16u32, 8u32);
    let left = [200u8, 100, 50];
    let right = [20u8, 180, 240];
    let mut bytes = Vec::new();
    for _ in 0..h {
        for x in 0..w {
            bytes.extend_from_slice(if x < 8 { &left } else { &right });
        }
    }
    let mut jpeg = Vec::new();
    JpegEncoder::new_with_quality(&mut jpeg, 100)
        .write_image(&bytes, w, h, image::ExtendedColorType::Rgb8)
        .unwrap();
    let image = Image::decode(&jpeg, "photo.jpg").unwrap();
    assert_eq!(
        (image.width(), image.height(), image.channels()),
        (16, 8, 3)
    );
    assert_eq!(image.bits_per_channel(), 8);
    for (x, colour) in [(2, left), (13, right)] {
        let got = image.texel(x, 4, ColorSpace::Linear) * 255.0;
        for k in 0..3 {
            // Lossy (and chroma subsampled): within a few levels.
            assert!(
                (got[k] - colour[k] as f32).abs() <= 6.0,
                "x {x}: {got} vs {colour:?}"
            );
        }
        assert_eq!(got.w, 255.0);
    }
    // Grey JPEG: one channel.
    let mut jpeg = Vec::new();
    JpegEncoder::new_with_quality(&mut jpeg, 95)
        .write_image(&[128; 64], 8, 8, image::ExtendedColorType::L8)
        .unwrap();
    let image = Image::decode(&jpeg, "grey.jpg").unwrap();
    assert_eq!(image.channels(), 1);
    assert!((image.texel(3, 3, ColorSpace::Linear).x * 255.0 - 128.0).abs() <= 1.0);
}

/// The standard CRC-32 of PNG chunks.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn png_chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let mut chunk = (data.len() as u32).to_be_bytes().to_vec();
    chunk.extend_from_slice(kind);
    chunk.extend_from_slice(data);
    let crc = crc32(&chunk[4..]);
    chunk.extend_from_slice(&crc.to_be_bytes());
    chunk
}

/// A PNG signature and IHDR (8 bits; `color_type`), nothing else.
fn png_header(width: u32, height: u32, color_type: u8) -> Vec<u8> {
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, color_type, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(png_chunk(b"IHDR", &ihdr));
    png
}

/// zlib data of one stored (uncompressed) deflate block.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01, 0x01];
    let len = data.len() as u16;
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(&(!len).to_le_bytes());
    out.extend_from_slice(data);
    let (mut a, mut b) = (1u32, 0u32);
    for &x in data {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
}

#[test]
fn palette_png_expands() {
    // 3×1, palette red, green, blue; blue half transparent (tRNS).
    let mut png = png_header(3, 1, 3);
    png.extend(png_chunk(b"PLTE", &[255, 0, 0, 0, 255, 0, 0, 0, 255]));
    png.extend(png_chunk(b"tRNS", &[255, 255, 128]));
    png.extend(png_chunk(b"IDAT", &zlib_stored(&[0, 2, 1, 0])));
    png.extend(png_chunk(b"IEND", &[]));
    let image = Image::decode(&png, "palette.png").unwrap();
    assert_eq!((image.width(), image.height(), image.channels()), (3, 1, 4));
    assert_eq!(image.bits_per_channel(), 8);
    let linear = ColorSpace::Linear;
    assert_eq!(
        image.texel(0, 0, linear),
        Vec4::new(0.0, 0.0, 1.0, 128.0 / 255.0)
    );
    assert_eq!(image.texel(1, 0, linear), Vec4::new(0.0, 1.0, 0.0, 1.0));
    assert_eq!(image.texel(2, 0, linear), Vec4::new(1.0, 0.0, 0.0, 1.0));
}

#[test]
fn oversized_png_is_refused_from_its_header() {
    let start = Instant::now();
    // 65536 × 65536: over the per-side limit, refused by image's Limits.
    let png = png_header(65536, 65536, 6);
    let err = Image::decode(&png, "huge.png").unwrap_err();
    assert!(
        matches!(
            err,
            TextureError::TooLarge {
                width: 65536,
                height: 65536,
                ..
            }
        ),
        "{err:?}"
    );
    let message = err.to_string();
    assert!(message.starts_with("huge.png: "), "{message}");
    assert!(message.contains("65536×65536"), "{message}");
    // 20000 × 20000: sides allowed, but 4·10^8 > 2^28 texels. (The decoder
    // reads up to the first IDAT before the size is known to be valid.)
    let mut png = png_header(20000, 20000, 2);
    png.extend(png_chunk(b"IDAT", &zlib_stored(&[0; 16])));
    png.extend(png_chunk(b"IEND", &[]));
    let err = Image::decode(&png, "wide.png").unwrap_err();
    assert!(
        matches!(
            err,
            TextureError::TooLarge {
                width: 20000,
                height: 20000,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        err.to_string().starts_with("wide.png: 20000×20000"),
        "{err}"
    );
    // 40000 × 1: too wide, few texels.
    let err = Image::decode(&png_header(40000, 1, 0), "strip.png").unwrap_err();
    assert!(
        matches!(
            err,
            TextureError::TooLarge {
                width: 40000,
                height: 1,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        start.elapsed() < Duration::from_millis(500),
        "{:?}",
        start.elapsed()
    );
}

#[test]
fn garbage_is_an_error_naming_the_image() {
    let err = Image::decode(b"GIF89a not supported", "anim.gif").unwrap_err();
    assert!(matches!(err, TextureError::UnknownFormat { .. }), "{err:?}");
    assert!(err.to_string().starts_with("anim.gif: "), "{err}");
    let err = Image::decode(&[], "empty").unwrap_err();
    assert!(err.to_string().starts_with("empty: "), "{err}");
    // Right signatures, corrupt data.
    for (bytes, name) in [
        (
            b"\x89PNG\r\n\x1a\nthis is not a chunk".to_vec(),
            "broken.png",
        ),
        (vec![0xFF, 0xD8, 0xFF, 0xE0, 1, 2, 3], "broken.jpg"),
        (png_header(2, 2, 6), "truncated.png"),
    ] {
        let err = Image::decode(&bytes, name).unwrap_err();
        assert!(
            matches!(err, TextureError::Decode { .. }),
            "{name}: {err:?}"
        );
        let message = err.to_string();
        assert!(message.starts_with(&format!("{name}: ")), "{message}");
        assert!(!message.contains('\n'), "{message:?}");
    }
}

#[test]
fn decode_all_keeps_order_and_reports_the_first_failure() {
    let png = |w: u32| encode_png(w, 1, &vec![7; w as usize], image::ExtendedColorType::L8);
    let sources: Vec<(String, Vec<u8>)> =
        (1..=6).map(|w| (format!("img{w}.png"), png(w))).collect();
    let store = TextureStore::decode_all(sources.clone()).unwrap();
    assert_eq!(store.len(), 6);
    for id in 0..6 {
        assert_eq!(store.get(id).width(), id + 1);
    }
    assert_eq!(store.memory_bytes(), 21);

    // Failures at 1 and 4 (and a large valid image in between, slower to decode
    // than the later failure): the error is 1's.
    let mut sources = sources;
    sources[1] = ("bad1.bin".into(), b"nonsense".to_vec());
    sources[2] = (
        "big.png".into(),
        encode_png(512, 512, &vec![3; 512 * 512], image::ExtendedColorType::L8),
    );
    sources[4] = ("bad4.png".into(), png_header(65536, 65536, 6));
    let err = TextureStore::decode_all(sources).unwrap_err();
    assert!(err.to_string().starts_with("bad1.bin: "), "{err}");

    assert!(TextureStore::decode_all(Vec::new()).unwrap().is_empty());
}

/// WebP (`EXT_texture_webp`): a lossless RGBA image decodes texel for texel,
/// told apart from PNG and JPEG by its RIFF signature; a cut file is an error
/// naming it, not a panic.
#[test]
fn webp_lossless_round_trip() {
    let (w, h) = (5u32, 3u32);
    let rgba: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            [
                (i * 17) as u8,
                (255 - i * 9) as u8,
                (i * i) as u8,
                (100 + i) as u8,
            ]
        })
        .collect();
    let mut webp = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut webp)
        .write_image(&rgba, w, h, image::ExtendedColorType::Rgba8)
        .unwrap();
    assert!(webp.starts_with(b"RIFF") && &webp[8..12] == b"WEBP");
    let image = Image::decode(&webp, "texture.webp").unwrap();
    assert_eq!((image.width(), image.height(), image.channels()), (w, h, 4));
    for y in 0..h {
        for x in 0..w {
            let got = image.texel(x, y, ColorSpace::Linear) * 255.0;
            let at = 4 * (y * w + x) as usize;
            for k in 0..4 {
                assert_eq!(got[k].round() as u8, rgba[at + k], "({x}, {y}) channel {k}");
            }
        }
    }
    assert_eq!(Image::decoded_bytes(&webp), Some(u64::from(w * h * 4)));
    let cut = &webp[..webp.len() - 8];
    let err = Image::decode(cut, "cut.webp").unwrap_err().to_string();
    assert!(err.contains("cut.webp"), "{err}");
}

/// A Windows bitmap (24-bit, bottom-up rows, padded to 4 bytes, BGR) decodes
/// to its texels, top row first; a cut one is an error naming it.
#[test]
fn bmp_decodes_top_row_first() {
    // 2 × 2: top row red, green; bottom row blue, white.
    let mut bmp = Vec::new();
    let pixels: [[u8; 3]; 4] = [[255, 0, 0], [255, 255, 255], [0, 0, 255], [0, 255, 0]];
    let row_bytes = 8; // 2 × 3 bytes, padded to 8.
    let size = 54 + 2 * row_bytes;
    bmp.extend_from_slice(b"BM");
    bmp.extend_from_slice(&(size as u32).to_le_bytes());
    bmp.extend_from_slice(&[0; 4]);
    bmp.extend_from_slice(&54u32.to_le_bytes());
    bmp.extend_from_slice(&40u32.to_le_bytes());
    bmp.extend_from_slice(&2i32.to_le_bytes());
    bmp.extend_from_slice(&2i32.to_le_bytes());
    bmp.extend_from_slice(&1u16.to_le_bytes());
    bmp.extend_from_slice(&24u16.to_le_bytes());
    bmp.extend_from_slice(&[0; 24]);
    // Rows bottom-up: blue, white; then red, green. Each texel BGR.
    for row in [[pixels[0], pixels[1]], [pixels[2], pixels[3]]] {
        for bgr in row {
            bmp.extend_from_slice(&bgr);
        }
        bmp.extend_from_slice(&[0, 0]);
    }
    let image = Image::decode(&bmp, "flower.bmp").unwrap();
    assert_eq!((image.width(), image.height()), (2, 2));
    let at = |x, y| image.texel(x, y, ColorSpace::Linear);
    assert_eq!(at(0, 0), Vec4::new(1.0, 0.0, 0.0, 1.0));
    assert_eq!(at(1, 0), Vec4::new(0.0, 1.0, 0.0, 1.0));
    assert_eq!(at(0, 1), Vec4::new(0.0, 0.0, 1.0, 1.0));
    assert_eq!(at(1, 1), Vec4::ONE);
    let err = Image::decode(&bmp[..60], "cut.bmp").unwrap_err();
    assert!(err.to_string().starts_with("cut.bmp: "), "{err}");
}
