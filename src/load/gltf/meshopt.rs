//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views whose
//! bytes are stored compressed (gltfpack's `-c` output), decoded once after
//! the buffers are read so that every accessor, skin, animation and instancing
//! reader sees plain bytes.
//!
//! The bitstreams (attributes, triangles, indices) and filters (octahedral,
//! quaternion, exponential, colour) are decoded by meshoptimizer itself,
//! through the `meshopt` crate (its C++ builds in about 9 s here). Its decoders
//! are written to be safe on untrusted input, but they `assert` their
//! arguments' shapes (stride, count divisibility), so every such precondition,
//! and the size of what is allocated, is checked here first from the
//! extension's JSON, against the bytes actually present.
//!
//! Fallback buffers (the uncompressed copy a file may carry for loaders
//! without the extension, often a placeholder without a URI) are never read.

use gltf::json;
use serde::Deserialize;

use super::error::GltfError;

/// The vendor extension's name.
pub const EXT: &str = "EXT_meshopt_compression";
/// The Khronos extension's name (a superset: vertex codec version 1 and the
/// colour filter).
pub const KHR: &str = "KHR_meshopt_compression";

/// The most bytes one compressed byte can decode to, over all modes: an
/// attribute block of 256 elements whose every byte is "all zero" (version 1
/// control mode 2) costs one control byte per 4 element bytes, so
/// 256 × 4 = 1024. A view claiming more than this many times its compressed
/// length (plus a tail's worth) is malformed, and is refused before anything
/// is allocated.
const MAX_EXPANSION: u64 = 1024;

/// How a compressed view's bytes are laid out (the extension's `mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Mode {
    /// Vertex attributes (and any other element data): mode 0.
    Attributes,
    /// A triangle list's indices: mode 1.
    Triangles,
    /// Any other index data: mode 2.
    Indices,
}

/// What is done to the decoded attribute bytes (the extension's `filter`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Filter {
    /// Used as decoded.
    #[default]
    None,
    /// Octahedral unit vectors (normals, tangents), 4 or 8 bytes.
    Octahedral,
    /// Quaternions with the largest component dropped, 8 bytes.
    Quaternion,
    /// Floats as a shared exponent and a 24-bit mantissa, 4-byte groups.
    Exponential,
    /// YCoCg colours, 4 or 8 bytes (`KHR_meshopt_compression` only).
    Color,
}

/// A buffer view's extension object.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Compressed {
    /// The buffer holding the compressed bytes.
    pub buffer: u64,
    /// Where they start in it.
    #[serde(default)]
    pub byte_offset: u64,
    /// How many there are.
    pub byte_length: u64,
    /// Bytes per decoded element.
    pub byte_stride: u64,
    /// Decoded elements.
    pub count: u64,
    /// The bitstream.
    pub mode: Mode,
    /// The post-decoding filter.
    #[serde(default)]
    pub filter: Filter,
}

/// Which of the two extensions a JSON object carries, and its object.
fn extension(
    others: &serde_json::Map<String, serde_json::Value>,
) -> Option<(&'static str, &serde_json::Value)> {
    [KHR, EXT]
        .into_iter()
        .find_map(|name| others.get(name).map(|v| (name, v)))
}

/// Whether buffer `b` is a fallback buffer (marked `"fallback": true` by
/// either extension): its bytes are never needed, and so never read.
pub fn is_fallback(b: &json::Buffer) -> bool {
    b.extensions
        .as_ref()
        .and_then(|e| extension(&e.others))
        .and_then(|(_, v)| v.get("fallback"))
        .and_then(serde_json::Value::as_bool)
        == Some(true)
}

/// Whether the file uses either extension (then buffers without a URI are
/// placeholders for uncompressed data the file does not carry).
pub fn used(root: &json::Root) -> bool {
    root.extensions_used.iter().any(|e| e == EXT || e == KHR)
}

/// Decodes every compressed buffer view: its decoded bytes are appended to
/// `data` as a new buffer and the view is pointed at them (offset 0, the
/// decoded length), so that readers downstream need not know. `budget` is
/// called with the bytes each decoded view adds before they are allocated.
pub fn decode_views(
    root: &mut json::Root,
    data: &mut Vec<Vec<u8>>,
    mut budget: impl FnMut(u64) -> Result<(), GltfError>,
) -> Result<(), GltfError> {
    for i in 0..root.buffer_views.len() {
        let view = &root.buffer_views[i];
        let Some((name, value)) = view.extensions.as_ref().and_then(|e| extension(&e.others))
        else {
            continue;
        };
        let what = format!("buffer view {i} ({name})");
        let c = Compressed::deserialize(value)
            .map_err(|e| GltfError::invalid(format!("{what}: {e}")))?;
        let decoded_len = check(&c, view.byte_length.0, name, &what)?;
        let source = compressed_bytes(data, &c, &what)?;
        if decoded_len > MAX_EXPANSION.saturating_mul(source.len() as u64 + 32) {
            return Err(GltfError::invalid(format!(
                "{what}: {decoded_len} bytes cannot come from {} compressed bytes",
                source.len()
            )));
        }
        budget(decoded_len)?;
        let decoded = decode(source, &c, name).map_err(|e| {
            GltfError::invalid(format!("{what}: the compressed data is malformed ({e})"))
        })?;
        let index = data.len();
        data.push(decoded);
        let view = &mut root.buffer_views[i];
        view.buffer = json::Index::new(index as u32);
        view.byte_offset = Some(json::validation::USize64(0));
        view.byte_length = json::validation::USize64(decoded_len);
    }
    Ok(())
}

/// Checks the extension object's rules (its README's "For the extension
/// object to be valid" list, which are also the decoder's preconditions) and
/// returns the decoded length.
fn check(c: &Compressed, parent_length: u64, name: &str, what: &str) -> Result<u64, GltfError> {
    let bad = |rule: &str| Err(GltfError::invalid(format!("{what}: {rule}")));
    let s = c.byte_stride;
    match c.mode {
        Mode::Attributes if s == 0 || !s.is_multiple_of(4) || s > 256 => {
            return bad("ATTRIBUTES needs a byteStride that is a multiple of 4 from 4 to 256");
        }
        Mode::Triangles | Mode::Indices if s != 2 && s != 4 => {
            return bad("TRIANGLES and INDICES need a byteStride of 2 or 4");
        }
        Mode::Triangles if !c.count.is_multiple_of(3) => {
            return bad("TRIANGLES needs a count divisible by 3");
        }
        Mode::Triangles | Mode::Indices if c.filter != Filter::None => {
            return bad("only ATTRIBUTES may have a filter");
        }
        _ => {}
    }
    match c.filter {
        Filter::Octahedral | Filter::Color if s != 4 && s != 8 => {
            return bad("the OCTAHEDRAL and COLOR filters need a byteStride of 4 or 8");
        }
        Filter::Quaternion if s != 8 => {
            return bad("the QUATERNION filter needs a byteStride of 8");
        }
        Filter::Color if name == EXT => {
            return bad("the COLOR filter is KHR_meshopt_compression's, not EXT_'s");
        }
        _ => {}
    }
    let len = c.count.checked_mul(s);
    match len {
        Some(len) if len == parent_length => Ok(len),
        _ => Err(GltfError::invalid(format!(
            "{what}: count {} × byteStride {s} is not the view's byteLength {parent_length}",
            c.count
        ))),
    }
}

/// The compressed bytes the extension object points at, checked to lie in
/// their buffer.
fn compressed_bytes<'d>(
    data: &'d [Vec<u8>],
    c: &Compressed,
    what: &str,
) -> Result<&'d [u8], GltfError> {
    let buffer = usize::try_from(c.buffer)
        .ok()
        .and_then(|b| data.get(b))
        .ok_or_else(|| GltfError::invalid(format!("{what}: buffer {} does not exist", c.buffer)))?;
    let end = c.byte_offset.checked_add(c.byte_length);
    match end {
        Some(end) if end <= buffer.len() as u64 => {
            Ok(&buffer[c.byte_offset as usize..end as usize])
        }
        _ => Err(GltfError::invalid(format!(
            "{what}: compressed bytes {}..+{} lie outside buffer {} of {} bytes",
            c.byte_offset,
            c.byte_length,
            c.buffer,
            buffer.len()
        ))),
    }
}

/// Decodes `source` as `c` describes (its shape already checked by `check`). The
/// error is meshoptimizer's reason, in words.
pub fn decode(source: &[u8], c: &Compressed, name: &str) -> Result<Vec<u8>, &'static str> {
    let count = c.count as usize;
    let stride = c.byte_stride as usize;
    // EXT_ allows only version 0 of the vertex bitstream (header 0xa0);
    // KHR_ adds version 1 (0xa1).
    if c.mode == Mode::Attributes && name == EXT && source.first() != Some(&0xa0) {
        return Err("an attribute stream must start with 0xa0");
    }
    let mut out = vec![0u8; count * stride];
    // SAFETY: `out` holds exactly `count × stride` bytes, what each decoder
    // writes for `count` elements of `stride` bytes; `source` is a live slice
    // of its stated length, which the decoders never read past. `check` has
    // established each function's asserted preconditions: ATTRIBUTES strides
    // are multiples of 4 in 4..=256, index sizes 2 or 4, triangle counts
    // divisible by 3, and each filter's stride is one it accepts.
    let code = unsafe {
        let dst = out.as_mut_ptr().cast();
        let src = source.as_ptr();
        match c.mode {
            Mode::Attributes => {
                meshopt::ffi::meshopt_decodeVertexBuffer(dst, count, stride, src, source.len())
            }
            Mode::Triangles => {
                meshopt::ffi::meshopt_decodeIndexBuffer(dst, count, stride, src, source.len())
            }
            Mode::Indices => {
                meshopt::ffi::meshopt_decodeIndexSequence(dst, count, stride, src, source.len())
            }
        }
    };
    match code {
        0 => {}
        -1 => return Err("unsupported bitstream version"),
        -2 => return Err("the stream ends early"),
        -3 => return Err("bytes are left over after the stream"),
        _ => return Err("the stream is invalid"),
    }
    if count > 0 {
        // SAFETY: as above; each filter rewrites `count` elements of `stride`
        // bytes in place, and `check` allowed only the strides it accepts.
        unsafe {
            let buf = out.as_mut_ptr().cast();
            match c.filter {
                Filter::None => {}
                Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(buf, count, stride),
                Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(buf, count, stride),
                Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(buf, count, stride),
                Filter::Color => meshopt::ffi::meshopt_decodeFilterColor(buf, count, stride),
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // components indexed in step
mod tests {
    use super::*;

    fn layout(count: usize, stride: usize, mode: Mode, filter: Filter) -> Compressed {
        Compressed {
            buffer: 0,
            byte_offset: 0,
            byte_length: 0,
            byte_stride: stride as u64,
            count: count as u64,
            mode,
            filter,
        }
    }

    /// 300 elements of 12 bytes: three slowly varying u32s, as quantized
    /// positions are.
    fn elements() -> Vec<[u32; 3]> {
        (0..300u32)
            .map(|i| [i * 7, 1000 + (i * i) % 97, u32::MAX - i * 3])
            .collect()
    }

    fn bytes<T: Copy + Into<i64>, const N: usize>(v: &[[T; N]]) -> Vec<u8> {
        let size = std::mem::size_of::<T>();
        v.iter()
            .flatten()
            .flat_map(|&c| c.into().to_le_bytes()[..size].to_vec())
            .collect()
    }

    #[test]
    fn attributes_round_trip_in_both_codec_versions() {
        let v = elements();
        let plain = bytes(&v);
        let c = layout(v.len(), 12, Mode::Attributes, Filter::None);
        let v0 = meshopt::encode_vertex_buffer_level(&v, 2, Some(0)).unwrap();
        let v1 = meshopt::encode_vertex_buffer_level(&v, 2, Some(1)).unwrap();
        assert_eq!((v0[0], v1[0]), (0xa0, 0xa1));
        assert_eq!(decode(&v0, &c, EXT).unwrap(), plain);
        assert_eq!(decode(&v0, &c, KHR).unwrap(), plain);
        assert_eq!(decode(&v1, &c, KHR).unwrap(), plain);
        // Version 1 is KHR_'s only.
        assert!(decode(&v1, &c, EXT).is_err());
    }

    #[test]
    fn triangles_and_index_sequences_round_trip_at_both_index_sizes() {
        // A 10 × 10 grid of quads: 200 triangles over 121 vertices.
        let mut tris = Vec::new();
        for y in 0..10u32 {
            for x in 0..10u32 {
                let a = y * 11 + x;
                tris.extend([a, a + 1, a + 11, a + 11, a + 1, a + 12]);
            }
        }
        for (mode, encoded) in [
            (
                Mode::Triangles,
                meshopt::encode_index_buffer(&tris, 121).unwrap(),
            ),
            (
                Mode::Indices,
                meshopt::encode_index_sequence(&tris, 121).unwrap(),
            ),
        ] {
            let wide = decode(&encoded, &layout(tris.len(), 4, mode, Filter::None), EXT).unwrap();
            let narrow = decode(&encoded, &layout(tris.len(), 2, mode, Filter::None), EXT).unwrap();
            let to_u32 = |b: &[u8], size: usize| -> Vec<u32> {
                b.chunks_exact(size)
                    .map(|c| c.iter().rev().fold(0, |a, &x| a << 8 | x as u32))
                    .collect()
            };
            let (wide, narrow) = (to_u32(&wide, 4), to_u32(&narrow, 2));
            assert_eq!(wide, narrow, "{mode:?}");
            if mode == Mode::Indices {
                assert_eq!(wide, tris);
            } else {
                // The triangle codec may start a triangle at another corner
                // (keeping its winding): compare each rotated to its
                // smallest index.
                let turn = |t: &[u32]| {
                    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
                    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
                };
                let got: Vec<_> = wide.chunks_exact(3).map(turn).collect();
                let want: Vec<_> = tris.chunks_exact(3).map(turn).collect();
                assert!(got == want, "the triangles differ");
            }
        }
    }

    /// Encodes `filtered` elements (already filter-encoded) as an attribute
    /// stream and decodes them with `filter`.
    fn through<T>(filtered: &[T], stride: usize, filter: Filter, name: &str) -> Vec<u8> {
        let version = if name == EXT { 0 } else { 1 };
        let encoded = meshopt::encode_vertex_buffer_level(filtered, 2, Some(version)).unwrap();
        decode(
            &encoded,
            &layout(filtered.len(), stride, Mode::Attributes, filter),
            name,
        )
        .unwrap()
    }

    fn unit(i: usize) -> [f32; 3] {
        let a = i as f32 * 0.37;
        let b = i as f32 * 0.11 - 1.5;
        [a.cos() * b.cos(), b.sin(), a.sin() * b.cos()]
    }

    #[test]
    fn the_octahedral_filter_gives_back_unit_vectors_within_its_step() {
        let n: Vec<[f32; 4]> = (0..200)
            .map(|i| {
                let u = unit(i);
                [u[0], u[1], u[2], 0.0]
            })
            .collect();
        // 16-bit components with 12 bits of octahedral precision.
        let enc: Vec<[i16; 4]> = meshopt::encode_filter_oct(&n, 12);
        let out = through(&enc, 8, Filter::Octahedral, EXT);
        for (k, v) in n.iter().enumerate() {
            for c in 0..3 {
                let d = i16::from_le_bytes([out[k * 8 + 2 * c], out[k * 8 + 2 * c + 1]]);
                let got = d as f32 / 32767.0;
                assert!(
                    (got - v[c]).abs() < 2.0 / 2047.0,
                    "{k} {c}: {got} vs {}",
                    v[c]
                );
            }
        }
    }

    #[test]
    fn the_quaternion_filter_gives_back_rotations_within_its_step() {
        let q: Vec<[f32; 4]> = (0..200)
            .map(|i| {
                let u = unit(i);
                let h = i as f32 * 0.05;
                let s = h.sin();
                [u[0] * s, u[1] * s, u[2] * s, h.cos()]
            })
            .collect();
        let enc = meshopt::encode_filter_quat(&q, 12);
        let out = through(&enc, 8, Filter::Quaternion, EXT);
        for (k, v) in q.iter().enumerate() {
            let got: Vec<f32> = (0..4)
                .map(|c| {
                    i16::from_le_bytes([out[k * 8 + 2 * c], out[k * 8 + 2 * c + 1]]) as f32
                        / 32767.0
                })
                .collect();
            // q and −q are one rotation: compare up to sign, each component
            // within two steps of 12 bits scaled by √2 (the filter's range).
            let sign = if (0..4).map(|c| got[c] * v[c]).sum::<f32>() < 0.0 {
                -1.0
            } else {
                1.0
            };
            for c in 0..4 {
                assert!(
                    (sign * got[c] - v[c]).abs() < 2.0 / 2047.0,
                    "{k}: {got:?} vs {v:?}"
                );
            }
        }
    }

    #[test]
    fn the_exponential_filter_gives_back_floats_within_its_mantissa() {
        let f: Vec<[f32; 3]> = (0..200)
            .map(|i| [i as f32 * 0.731 - 50.0, (i as f32).sqrt() * 1e-3, 12345.678])
            .collect();
        let enc = meshopt::encode_filter_exp(&f, 15, meshopt::EncodeExpMode::Separate);
        let out = through(&enc, 12, Filter::Exponential, EXT);
        for (k, v) in f.iter().enumerate() {
            for c in 0..3 {
                let o = k * 12 + 4 * c;
                let got = f32::from_le_bytes([out[o], out[o + 1], out[o + 2], out[o + 3]]);
                // 15 bits of mantissa: a relative error below 2^−14.
                assert!(
                    (got - v[c]).abs() <= v[c].abs() * 2f32.powi(-14),
                    "{k} {c}: {got} vs {}",
                    v[c]
                );
            }
        }
    }

    #[test]
    fn the_color_filter_gives_back_colours_within_its_step() {
        let rgba: Vec<[f32; 4]> = (0..200)
            .map(|i| {
                let t = i as f32 / 199.0;
                [t, 1.0 - t, (t * 7.0).fract(), 0.5]
            })
            .collect();
        let enc: Vec<[u8; 4]> = meshopt::encode_filter_color(&rgba, 8);
        let out = through(&enc, 4, Filter::Color, KHR);
        for (k, v) in rgba.iter().enumerate() {
            for c in 0..4 {
                let got = out[k * 4 + c] as f32 / 255.0;
                assert!(
                    (got - v[c]).abs() <= 2.0 / 255.0,
                    "{k} {c}: {got} vs {}",
                    v[c]
                );
            }
        }
    }

    #[test]
    fn shapes_outside_the_extensions_rules_are_refused_before_decoding() {
        let rule = |stride, count, mode, filter, parent, name| {
            let c = layout(count, stride, mode, filter);
            check(&c, parent, name, "view").is_ok()
        };
        use Filter as F;
        use Mode as M;
        assert!(rule(12, 10, M::Attributes, F::None, 120, EXT));
        assert!(!rule(12, 10, M::Attributes, F::None, 121, EXT));
        assert!(!rule(6, 10, M::Attributes, F::None, 60, EXT));
        assert!(!rule(260, 1, M::Attributes, F::None, 260, EXT));
        assert!(!rule(0, 0, M::Attributes, F::None, 0, EXT));
        assert!(!rule(4, 4, M::Triangles, F::None, 16, EXT));
        assert!(!rule(3, 3, M::Indices, F::None, 9, EXT));
        assert!(!rule(4, 3, M::Triangles, F::Octahedral, 12, EXT));
        assert!(!rule(4, 1, M::Attributes, F::Quaternion, 4, EXT));
        assert!(!rule(12, 1, M::Attributes, F::Octahedral, 12, EXT));
        assert!(rule(4, 1, M::Attributes, F::Color, 4, KHR));
        assert!(!rule(4, 1, M::Attributes, F::Color, 4, EXT));
        // count × stride overflowing u64.
        assert!(!rule(256, 1 << 60, M::Attributes, F::None, 0, EXT));
    }

    #[test]
    fn every_cut_and_every_flipped_byte_is_decoded_or_refused() {
        // The decoders must return (garbage or an error), never crash or
        // read out of bounds, whatever the bytes.
        let v = elements();
        let c = layout(v.len(), 12, Mode::Attributes, Filter::Exponential);
        let mut tris = Vec::new();
        for i in 0..60u32 {
            tris.extend([i, i + 1, i + 2]);
        }
        let t = layout(tris.len(), 4, Mode::Triangles, Filter::None);
        let s = layout(tris.len(), 2, Mode::Indices, Filter::None);
        for (encoded, c) in [
            (
                meshopt::encode_vertex_buffer_level(&v, 2, Some(1)).unwrap(),
                &c,
            ),
            (meshopt::encode_index_buffer(&tris, 62).unwrap(), &t),
            (meshopt::encode_index_sequence(&tris, 62).unwrap(), &s),
        ] {
            let mut refused = 0;
            for len in 0..encoded.len() {
                refused += decode(&encoded[..len], c, KHR).is_err() as usize;
            }
            assert_eq!(refused, encoded.len(), "a cut stream decoded");
            for at in 0..encoded.len() {
                for bit in [0x01u8, 0x80, 0xff] {
                    let mut e = encoded.clone();
                    e[at] ^= bit;
                    let _ = decode(&e, c, KHR);
                }
            }
        }
    }
}
