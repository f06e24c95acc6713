//! The decompressors an OpenVDB file may use: Blosc 1 chunks (what OpenVDB
//! writes by default: LZ4 with byte shuffling) and LZ4 blocks, written from
//! the formats' descriptions (the Blosc chunk format of c-blosc 1.x, the LZ4
//! block format). zlib streams go to `flate2`.
//!
//! Every size is checked before use: the output's size is the caller's,
//! known from the tree, never a number from the chunk alone.

/// A Blosc chunk's 16-byte header.
const HEADER: usize = 16;
/// Flag: the bytes of each block were shuffled (grouped by byte position).
const SHUFFLE: u8 = 0x1;
/// Flag: the data follows the header uncompressed.
const MEMCPYED: u8 = 0x2;
/// Flag: bit shuffling (not written by OpenVDB).
const BITSHUFFLE: u8 = 0x4;
/// Flag: blocks are not split into a stream per byte of a value.
const DONT_SPLIT: u8 = 0x10;

/// Decompresses the Blosc 1 chunk `src` into exactly `expected` bytes.
pub fn decompress(src: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    if src.len() < HEADER {
        return Err(format!(
            "a Blosc chunk of {} bytes is shorter than its header",
            src.len()
        ));
    }
    let (version, flags, typesize) = (src[0], src[2], usize::from(src[3]));
    let word = |at: usize| u32::from_le_bytes(src[at..at + 4].try_into().unwrap()) as usize;
    let (nbytes, blocksize, cbytes) = (word(4), word(8), word(12));
    if version == 0 || version > 2 {
        return Err(format!(
            "Blosc format version {version} is not supported (1 or 2 are)"
        ));
    }
    if nbytes != expected {
        return Err(format!(
            "a Blosc chunk holds {nbytes} bytes where the tree needs {expected}"
        ));
    }
    if cbytes > src.len() {
        return Err(format!(
            "a Blosc chunk says it is {cbytes} bytes long; {} are left",
            src.len()
        ));
    }
    if flags & BITSHUFFLE != 0 {
        return Err("Blosc bit shuffling is not supported".into());
    }
    if nbytes == 0 {
        return Ok(Vec::new());
    }
    if flags & MEMCPYED != 0 {
        if cbytes < HEADER + nbytes {
            return Err("a stored Blosc chunk is shorter than its data".into());
        }
        return Ok(src[HEADER..HEADER + nbytes].to_vec());
    }
    if blocksize == 0 || typesize == 0 {
        return Err("a Blosc chunk with blocks or values of 0 bytes".into());
    }
    let codec = flags >> 5;
    let blocks = nbytes.div_ceil(blocksize);
    let starts_end = blocks
        .checked_mul(4)
        .and_then(|b| b.checked_add(HEADER))
        .filter(|&e| e <= cbytes)
        .ok_or("a Blosc chunk's block table runs past its end")?;
    let src = &src[..cbytes];
    let mut out = vec![0u8; nbytes];
    let mut scratch = vec![0u8; blocksize.min(nbytes)];
    for b in 0..blocks {
        let start = u32::from_le_bytes(src[HEADER + 4 * b..HEADER + 4 * b + 4].try_into().unwrap())
            as usize;
        if start < starts_end || start > src.len() {
            return Err(format!("Blosc block {b} starts outside the chunk"));
        }
        let size = blocksize.min(nbytes - b * blocksize);
        let leftover = size < blocksize;
        let split =
            flags & DONT_SPLIT == 0 && typesize <= 16 && blocksize / typesize >= 128 && !leftover;
        let streams = if split { typesize } else { 1 };
        let stream_len = size / streams;
        let shuffled = flags & SHUFFLE != 0 && typesize > 1;
        let dest = &mut out[b * blocksize..b * blocksize + size];
        let target: &mut [u8] = if shuffled { &mut scratch[..size] } else { dest };
        let mut at = start;
        for j in 0..streams {
            if at + 4 > src.len() {
                return Err(format!("Blosc block {b} ends early"));
            }
            let clen = u32::from_le_bytes(src[at..at + 4].try_into().unwrap()) as usize;
            at += 4;
            let input = src
                .get(at..at.saturating_add(clen))
                .ok_or_else(|| format!("Blosc block {b} ends early"))?;
            at += clen;
            let piece = &mut target[j * stream_len..(j + 1) * stream_len];
            if clen == stream_len {
                piece.copy_from_slice(input);
                continue;
            }
            match codec {
                1 => lz4_block(input, piece)?,
                3 => zlib(input, piece)?,
                0 => {
                    return Err(
                        "Blosc's BloscLZ codec is not supported (OpenVDB writes LZ4)".into(),
                    );
                }
                2 => {
                    return Err("Blosc's Snappy codec is not supported (OpenVDB writes LZ4)".into());
                }
                4 => {
                    return Err(
                        "Blosc's Zstandard codec is not supported (OpenVDB writes LZ4)".into(),
                    );
                }
                c => return Err(format!("unknown Blosc codec {c}")),
            }
        }
        if shuffled {
            unshuffle(&scratch[..size], typesize, dest);
        }
    }
    Ok(out)
}

/// Undoes Blosc's byte shuffle of one block: byte `j` of every value was
/// stored together, then the bytes left over after the last whole value.
fn unshuffle(src: &[u8], typesize: usize, dest: &mut [u8]) {
    let n = src.len() / typesize;
    for j in 0..typesize {
        for i in 0..n {
            dest[i * typesize + j] = src[j * n + i];
        }
    }
    let whole = n * typesize;
    dest[whole..].copy_from_slice(&src[whole..]);
}

/// Decompresses the zlib stream `src` into exactly `out.len()` bytes.
pub fn zlib(src: &[u8], out: &mut [u8]) -> Result<(), String> {
    use std::io::Read;
    let mut d = flate2::read::ZlibDecoder::new(src);
    d.read_exact(out)
        .map_err(|e| format!("a zlib stream: {e} (expected {} bytes)", out.len()))?;
    let mut extra = [0u8; 1];
    match d.read(&mut extra) {
        Ok(0) => Ok(()),
        Ok(_) => Err(format!(
            "a zlib stream holds more than the {} bytes expected",
            out.len()
        )),
        Err(e) => Err(format!("a zlib stream: {e}")),
    }
}

/// Decompresses the LZ4 block `src` into exactly `out.len()` bytes.
pub fn lz4_block(src: &[u8], out: &mut [u8]) -> Result<(), String> {
    let bad = |what: &str| Err(format!("an LZ4 block {what}"));
    let (mut i, mut o) = (0usize, 0usize);
    let length = |i: &mut usize, mut n: usize| -> Option<usize> {
        if n == 15 {
            loop {
                let b = *src.get(*i)?;
                *i += 1;
                n = n.checked_add(usize::from(b))?;
                if b != 255 {
                    break;
                }
            }
        }
        Some(n)
    };
    loop {
        let Some(&token) = src.get(i) else {
            return bad("ends early");
        };
        i += 1;
        let Some(literals) = length(&mut i, usize::from(token >> 4)) else {
            return bad("ends early");
        };
        let (Some(from), Some(to)) = (
            src.get(i..i.saturating_add(literals)),
            out.get_mut(o..o.saturating_add(literals)),
        ) else {
            return bad("holds more literals than fit");
        };
        to.copy_from_slice(from);
        i += literals;
        o += literals;
        if i == src.len() {
            break;
        }
        let Some(offset) = src.get(i..i + 2) else {
            return bad("ends early");
        };
        let offset = usize::from(u16::from_le_bytes([offset[0], offset[1]]));
        i += 2;
        let Some(len) = length(&mut i, usize::from(token & 15)) else {
            return bad("ends early");
        };
        let len = len + 4;
        if offset == 0 || offset > o {
            return bad("refers before its start");
        }
        if len > out.len() - o {
            return bad("holds more than fits");
        }
        // Byte by byte: a match may overlap what it writes.
        for k in 0..len {
            out[o + k] = out[o + k - offset];
        }
        o += len;
    }
    if o != out.len() {
        return Err(format!(
            "an LZ4 block holds {o} bytes where {} are expected",
            out.len()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-made LZ4 block: literals, then an overlapping match (a run).
    #[test]
    fn lz4_blocks_decode_literals_and_overlapping_matches() {
        // "ab", then 10 bytes copied from 2 back ("ababababab"), then the
        // last literals "xyz!!" (an LZ4 block ends with literals).
        let block = [0x26, b'a', b'b', 2, 0, 0x50, b'x', b'y', b'z', b'!', b'!'];
        let mut out = [0u8; 17];
        lz4_block(&block, &mut out).unwrap();
        assert_eq!(&out, b"ababababababxyz!!");
        let mut short = [0u8; 16];
        assert!(lz4_block(&block, &mut short).is_err());
        assert!(lz4_block(&[0x26, b'a', b'b', 9, 0, 0], &mut [0u8; 12]).is_err());
        assert!(lz4_block(&[0xf0], &mut [0u8; 20]).is_err());
    }

    #[test]
    fn shuffled_stored_and_refused_chunks() {
        // A chunk of two 4-byte values stored shuffled without compression:
        // each stream "compressed" to its own length is stored as is.
        let values = [1u8, 2, 3, 4, 5, 6, 7, 8];
        let shuffled = [1u8, 5, 2, 6, 3, 7, 4, 8];
        let mut chunk = vec![2, 1, SHUFFLE | DONT_SPLIT | (1 << 5), 4];
        let total = HEADER + 4 + 4 + 8;
        for w in [8u32, 8, total as u32, HEADER as u32 + 4] {
            chunk.extend(w.to_le_bytes());
        }
        chunk.extend(8u32.to_le_bytes());
        chunk.extend(shuffled);
        assert_eq!(decompress(&chunk, 8).unwrap(), values);
        assert!(
            decompress(&chunk, 12).is_err(),
            "a size other than the tree's"
        );
        assert!(decompress(&chunk[..total - 1], 8).is_err(), "cut short");
        let mut memcpyed = vec![2, 1, MEMCPYED, 4];
        for w in [8u32, 8, (HEADER + 8) as u32] {
            memcpyed.extend(w.to_le_bytes());
        }
        memcpyed.extend(values);
        assert_eq!(decompress(&memcpyed, 8).unwrap(), values);
        let mut zstd = chunk.clone();
        zstd[2] = SHUFFLE | DONT_SPLIT | (4 << 5);
        zstd[HEADER + 4..HEADER + 8].copy_from_slice(&7u32.to_le_bytes());
        assert!(decompress(&zstd, 8).unwrap_err().contains("Zstandard"));
    }
}
