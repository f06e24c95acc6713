//! Checkpoints: a render's exact sums saved to a file, so that a render that was
//! stopped or killed can go on from them and reach the image an uninterrupted
//! render gives, bit for bit (see [`crate::render::Accumulator`]).
//!
//! A checkpoint holds a [`Key`] naming what its samples are samples of (the
//! program, the scene, the view and the sampling settings: everything that
//! changes sample `k` of pixel `p`), so that one made for something else is
//! refused rather than mixed in. The file, all little-endian:
//!
//! | bytes | what |
//! | --- | --- |
//! | 8 | magic `RAYLABCP` |
//! | 4 | format version (2; 1 held f64 sums) |
//! | 4 | AOVs gathered, in order: nibble `k` is the `k`-th one's index in [`Aov::ALL`] + 1 |
//! | 24 | the key: build, scene, settings (three u64) |
//! | 4 + 4 | width, height |
//! | 4 | samples per pixel taken |
//! | 4 | reserved (0) |
//! | 8 + 8 + 8 | time spent (ns), rays cast, samples dropped |
//! | 48 per pixel | the image's sums (three i128, [`crate::fixed`]) |
//! | 16 × stride per pixel | the AOVs' records ([`Accumulator::aov_stride`]) |
//! | 8 | [`Fingerprint`] of every byte before it |
//!
//! Everything read is checked: the header's sizes against the file's length
//! before anything is allocated, and the checksum before the sums are used.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;
use std::time::Duration;

use thiserror::Error;

use crate::aov::{Aov, AovSet};
use crate::film::{OutputError, write_atomic_with};
use crate::fingerprint::Fingerprint;
use crate::render::{Accumulator, Tally};

const MAGIC: &[u8; 8] = b"RAYLABCP";
const VERSION: u32 = 2;
const HEADER: usize = 80;

/// What a checkpoint's samples are samples of, as three fingerprints, so that
/// a mismatch can say which part differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Key {
    /// The program that took the samples (another build may take other ones).
    pub build: u64,
    /// The scene: its files and what was loaded from them.
    pub scene: u64,
    /// Image size, camera, integrator and its options, seed, AOVs.
    pub settings: u64,
}

impl Key {
    /// What differs between `self` (a checkpoint's) and `other`, in words
    /// (`None` when they match).
    pub fn mismatch(&self, other: &Key) -> Option<&'static str> {
        if self.build != other.build {
            Some("another build of raylab")
        } else if self.scene != other.scene {
            Some("another scene")
        } else if self.settings != other.settings {
            Some("other settings (size, camera, integrator, seed or AOVs)")
        } else {
            None
        }
    }
}

/// A checkpoint's header: what it is of and how far it got.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// What the samples are samples of.
    pub key: Key,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// AOVs gathered.
    pub aovs: AovSet,
    /// Samples per pixel taken.
    pub spp: u32,
    /// Time spent rendering them.
    pub spent: Duration,
    /// Rays cast and samples dropped taking them.
    pub tally: Tally,
}

/// A checkpoint read back.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Its header.
    pub header: Header,
    /// The sums, ready to take more samples.
    pub accumulator: Accumulator,
}

/// Why a checkpoint could not be read.
#[derive(Debug, Error)]
pub enum CheckpointError {
    /// Opening or reading failed.
    #[error("cannot read it: {0}")]
    Io(#[from] std::io::Error),
    /// Not a checkpoint, or a damaged one.
    #[error("{0}")]
    Invalid(String),
}

fn invalid(s: impl Into<String>) -> CheckpointError {
    CheckpointError::Invalid(s.into())
}

/// The AOVs in their order (which is the order of their sums in a record):
/// nibble `k` is the `k`-th AOV's index in [`Aov::ALL`] plus one, 0 after the
/// last.
fn aov_bits(set: AovSet) -> u32 {
    set.iter()
        .enumerate()
        .fold(0, |b, (k, a)| b | (a as u32 + 1) << (4 * k))
}

fn aovs_from_bits(bits: u32) -> Option<AovSet> {
    let mut list = Vec::new();
    let mut rest = bits;
    while rest != 0 {
        let i = (rest & 15) as usize;
        list.push(*Aov::ALL.get(i.checked_sub(1)?)?);
        rest >>= 4;
        if list.len() > Aov::ALL.len() {
            return None;
        }
    }
    AovSet::new(&list).ok()
}

/// Bytes of a checkpoint of a `width × height` image with `aovs`, or `None`
/// if that does not fit in a `u64`.
fn file_len(width: u32, height: u32, aovs: AovSet) -> Option<u64> {
    let per_pixel = 48 + 16 * Accumulator::aov_stride(aovs) as u64;
    (width as u64 * height as u64)
        .checked_mul(per_pixel)?
        .checked_add(HEADER as u64 + 8)
}

/// Writes `acc` (which took `spent`) as a checkpoint of `key` to `path`,
/// atomically: the previous checkpoint stays until the new one is complete.
pub fn write(
    path: &Path,
    key: &Key,
    acc: &Accumulator,
    spent: Duration,
) -> Result<(), OutputError> {
    write_atomic_with(path, |file| {
        let mut out = HashingWriter {
            inner: BufWriter::with_capacity(1 << 16, file),
            fingerprint: Fingerprint::new(),
        };
        let tally = acc.tally();
        let mut header = Vec::with_capacity(HEADER);
        header.extend_from_slice(MAGIC);
        header.extend_from_slice(&VERSION.to_le_bytes());
        header.extend_from_slice(&aov_bits(acc.aov_set()).to_le_bytes());
        for k in [key.build, key.scene, key.settings] {
            header.extend_from_slice(&k.to_le_bytes());
        }
        for v in [acc.width(), acc.height(), acc.spp(), 0] {
            header.extend_from_slice(&v.to_le_bytes());
        }
        let nanos = u64::try_from(spent.as_nanos()).unwrap_or(u64::MAX);
        for v in [nanos, tally.rays, tally.dropped] {
            header.extend_from_slice(&v.to_le_bytes());
        }
        debug_assert_eq!(header.len(), HEADER);
        out.write_all(&header)?;
        let mut buf = Vec::with_capacity(1 << 16);
        for chunk in acc.image_sums().chunks(1 << 11) {
            buf.clear();
            for p in chunk {
                for c in p {
                    buf.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.write_all(&buf)?;
        }
        for chunk in acc.aov_sums().chunks(1 << 13) {
            buf.clear();
            for c in chunk {
                buf.extend_from_slice(&c.to_le_bytes());
            }
            out.write_all(&buf)?;
        }
        let sum = out.fingerprint.value();
        out.inner.write_all(&sum.to_le_bytes())?;
        out.inner.flush()
    })
}

/// A writer that fingerprints what goes through it.
struct HashingWriter<W> {
    inner: W,
    fingerprint: Fingerprint,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.fingerprint.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Reads a checkpoint's header only (cheap: to see whether it is one for this
/// render before reading its sums), checked against the file's length.
pub fn read_header(path: &Path) -> Result<Header, CheckpointError> {
    let mut file = File::open(path)?;
    let len = file.metadata()?.len();
    parse_header(&mut file, len)
}

fn parse_header(r: &mut impl Read, len: u64) -> Result<Header, CheckpointError> {
    let mut h = [0u8; HEADER];
    if len < HEADER as u64 {
        return Err(invalid(format!(
            "not a raylab checkpoint ({len} bytes, too short)"
        )));
    }
    r.read_exact(&mut h)?;
    if &h[..8] != MAGIC {
        return Err(invalid("not a raylab checkpoint (wrong magic bytes)"));
    }
    let u32_at = |i: usize| u32::from_le_bytes(h[i..i + 4].try_into().expect("4 bytes"));
    let u64_at = |i: usize| u64::from_le_bytes(h[i..i + 8].try_into().expect("8 bytes"));
    let version = u32_at(8);
    if version != VERSION {
        return Err(invalid(format!(
            "checkpoint format {version}, this raylab reads format {VERSION}"
        )));
    }
    let aovs = aovs_from_bits(u32_at(12))
        .ok_or_else(|| invalid(format!("damaged: AOV bits {:#x}", u32_at(12))))?;
    let key = Key {
        build: u64_at(16),
        scene: u64_at(24),
        settings: u64_at(32),
    };
    let (width, height, spp) = (u32_at(40), u32_at(44), u32_at(48));
    if width == 0 || height == 0 {
        return Err(invalid(format!(
            "damaged: image of {width}×{height} pixels"
        )));
    }
    let want = file_len(width, height, aovs)
        .ok_or_else(|| invalid(format!("damaged: image of {width}×{height} pixels")))?;
    if len != want {
        return Err(invalid(format!(
            "truncated or damaged: {len} bytes where a {width}×{height} checkpoint has {want}"
        )));
    }
    Ok(Header {
        key,
        width,
        height,
        aovs,
        spp,
        spent: Duration::from_nanos(u64_at(56)),
        tally: Tally {
            rays: u64_at(64),
            dropped: u64_at(72),
        },
    })
}

/// Reads a whole checkpoint and checks its checksum.
pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let file = File::open(path)?;
    let len = file.metadata()?.len();
    let mut r = HashingReader {
        inner: BufReader::with_capacity(1 << 16, file),
        fingerprint: Fingerprint::new(),
    };
    let header = parse_header(&mut r, len)?;
    let pixels = header.width as usize * header.height as usize;
    // The length was checked against the header: these sizes are the file's.
    let mut image = Vec::with_capacity(pixels);
    let mut buf = vec![0u8; 48 << 11];
    let mut left = pixels;
    while left > 0 {
        let n = left.min(1 << 11);
        r.read_exact(&mut buf[..48 * n])?;
        image.extend(buf[..48 * n].chunks_exact(48).map(|p| {
            let f = |i: usize| i128::from_le_bytes(p[i..i + 16].try_into().expect("16 bytes"));
            [f(0), f(16), f(32)]
        }));
        left -= n;
    }
    let n_aov = pixels * Accumulator::aov_stride(header.aovs);
    let mut aov_sums = Vec::with_capacity(n_aov);
    let mut left = n_aov;
    while left > 0 {
        let n = left.min(3 << 11);
        r.read_exact(&mut buf[..16 * n])?;
        aov_sums.extend(
            buf[..16 * n]
                .chunks_exact(16)
                .map(|c| i128::from_le_bytes(c.try_into().expect("16 bytes"))),
        );
        left -= n;
    }
    let want = r.fingerprint.value();
    let mut sum = [0u8; 8];
    r.inner.read_exact(&mut sum)?;
    if u64::from_le_bytes(sum) != want {
        return Err(invalid("damaged: its checksum does not match its contents"));
    }
    let accumulator = Accumulator::from_parts(
        header.width,
        header.height,
        header.aovs,
        header.spp,
        header.tally,
        image,
        aov_sums,
    )
    .map_err(|e| invalid(format!("damaged: {e}")))?;
    Ok(Checkpoint {
        header,
        accumulator,
    })
}

/// A reader that fingerprints what goes through it.
struct HashingReader<R> {
    inner: R,
    fingerprint: Fingerprint,
}

impl<R: Read> Read for HashingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.fingerprint.update(&buf[..n]);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_round_trip_and_damage_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        // Not in `Aov::ALL`'s order: the records follow the set's.
        let set: AovSet = "depth,normal".parse().unwrap();
        let stride = Accumulator::aov_stride(set);
        let image: Vec<[i128; 3]> = (0..6).map(|i| [i << 60, -i, i128::MAX - i]).collect();
        let aovs: Vec<i128> = (0..6 * stride).map(|i| i as i128 * 12_345).collect();
        let tally = Tally {
            rays: 99,
            dropped: 2,
        };
        let acc = Accumulator::from_parts(3, 2, set, 5, tally, image, aovs).unwrap();
        let key = Key {
            build: 1,
            scene: 2,
            settings: 3,
        };
        write(&path, &key, &acc, Duration::from_millis(1500)).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.accumulator, acc);
        assert_eq!(back.header.key, key);
        assert_eq!(back.header.spent, Duration::from_millis(1500));
        assert_eq!(read_header(&path).unwrap(), back.header);
        let bytes = std::fs::read(&path).unwrap();
        // Truncated, flipped, not one at all: each refused with a reason.
        for (damaged, why) in [
            (bytes[..bytes.len() - 1].to_vec(), "truncated"),
            (
                {
                    let mut b = bytes.clone();
                    b[100] ^= 4;
                    b
                },
                "checksum",
            ),
            (b"hello".to_vec(), "not a raylab checkpoint"),
            (
                {
                    let mut b = bytes.clone();
                    b[40..44].copy_from_slice(&u32::MAX.to_le_bytes());
                    b
                },
                "truncated or damaged",
            ),
        ] {
            std::fs::write(&path, &damaged).unwrap();
            let err = read(&path).unwrap_err().to_string();
            assert!(err.contains(why), "{err}");
        }
    }
}
