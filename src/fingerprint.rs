//! [`Fingerprint`]: the one stable hash of the crate, for checkpoints' keys
//! and checksums, the cache's keys and entries, and the fingerprints of
//! scenes, textures and environments that those keys are made of.

use std::io::Write;

/// A stable 64-bit hash (FxHash's word step with a final mix), the same on
/// every machine and build: a checkpoint's checksum and its key's parts.
/// Each 8-byte word goes through `h = (rotl(h, 5) ^ w) · K`, a bijection of `h`,
/// so that a change of any one word always changes the result.
#[derive(Clone, Debug)]
pub struct Fingerprint {
    h: u64,
    pending: [u8; 8],
    n_pending: usize,
    len: u64,
}

impl Default for Fingerprint {
    fn default() -> Self {
        Self::new()
    }
}

impl Fingerprint {
    const K: u64 = 0x517c_c1b7_2722_0a95;

    /// An empty fingerprint.
    pub fn new() -> Self {
        Self {
            h: 0x243f_6a88_85a3_08d3,
            pending: [0; 8],
            n_pending: 0,
            len: 0,
        }
    }

    #[inline]
    fn word(&mut self, w: u64) {
        self.h = (self.h.rotate_left(5) ^ w).wrapping_mul(Self::K);
    }

    /// Adds `bytes`.
    pub fn update(&mut self, mut bytes: &[u8]) {
        self.len += bytes.len() as u64;
        if self.n_pending > 0 {
            let take = (8 - self.n_pending).min(bytes.len());
            self.pending[self.n_pending..self.n_pending + take].copy_from_slice(&bytes[..take]);
            self.n_pending += take;
            bytes = &bytes[take..];
            if self.n_pending < 8 {
                return;
            }
            self.word(u64::from_le_bytes(self.pending));
            self.n_pending = 0;
        }
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        let rest = words.remainder();
        self.pending[..rest.len()].copy_from_slice(rest);
        self.n_pending = rest.len();
    }

    /// Adds the bits of `xs` (little-endian), e.g. a mesh's coordinates.
    pub fn floats(&mut self, xs: impl IntoIterator<Item = f32>) {
        self.words32(xs.into_iter().map(f32::to_bits));
    }

    /// Adds `xs` (little-endian), e.g. a mesh's indices.
    pub fn words32(&mut self, xs: impl IntoIterator<Item = u32>) {
        // Through a small buffer: `update` per value would cost more than
        // the hashing itself.
        let mut buf = [0u8; 512];
        let mut n = 0;
        for x in xs {
            buf[n..n + 4].copy_from_slice(&x.to_le_bytes());
            n += 4;
            if n == buf.len() {
                self.update(&buf);
                n = 0;
            }
        }
        self.update(&buf[..n]);
    }

    /// The hash of everything added.
    pub fn value(&self) -> u64 {
        let mut f = self.clone();
        if f.n_pending > 0 {
            let mut last = [0u8; 8];
            last[..f.n_pending].copy_from_slice(&f.pending[..f.n_pending]);
            f.word(u64::from_le_bytes(last));
        }
        f.word(f.len);
        // MurmurHash3's finaliser: every bit of the state reaches every bit.
        let mut h = f.h;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

impl Write for Fingerprint {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.update(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl std::fmt::Write for Fingerprint {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.update(s.as_bytes());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingerprints_do_not_depend_on_how_the_bytes_are_split() {
        let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let mut whole = Fingerprint::new();
        whole.update(&bytes);
        for split in [1, 3, 8, 13, 500] {
            let mut f = Fingerprint::new();
            for c in bytes.chunks(split) {
                f.update(c);
            }
            assert_eq!(f.value(), whole.value(), "{split}");
        }
        let mut other = bytes.clone();
        other[999] ^= 1;
        let mut f = Fingerprint::new();
        f.update(&other);
        assert_ne!(f.value(), whole.value());
        // A trailing zero byte is not the same as none.
        let mut f = Fingerprint::new();
        f.update(&bytes);
        f.update(&[0]);
        assert_ne!(f.value(), whole.value());
    }
}
