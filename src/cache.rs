//! A cache of what loading a scene derives from its content: decoded textures
//! (keyed by the bytes of the image file) and BVHs (keyed by the triangles).
//!
//! The tasks of a render farm all load the same scene; with a cache folder on
//! a shared or local disk (`raylab render --cache DIR`, or
//! [`set_dir`] for library users) only the first decodes the textures and
//! builds the tree, and the others read them back. Entries are addressed by a
//! hash of their input and of this raylab's build, so an edited texture or
//! mesh, or another raylab, simply misses: there is nothing to invalidate.
//!
//! An entry is one file, `KIND-HASH.raylab-cache`, written atomically (so
//! tasks that fill the same entry at once never see half of one) and read
//! only after its length and checksum are verified; a damaged or foreign
//! entry is a miss, and a failure to write one is ignored: the cache can only
//! save time, never change an image or fail a render.

use std::path::{Path, PathBuf};
use std::sync::RwLock;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::fingerprint::Fingerprint;

/// The entries' magic.
const MAGIC: &[u8; 8] = b"RAYLABCA";
/// The entries' format (part of every key, so a new format misses).
const VERSION: u32 = 1;
/// magic, version, kind, key, payload length, then the payload and a checksum.
const HEADER: usize = 8 + 4 + 4 + 8 + 8;

static DIR: RwLock<Option<PathBuf>> = RwLock::new(None);
static HITS: AtomicU64 = AtomicU64::new(0);
static MISSES: AtomicU64 = AtomicU64::new(0);

/// Uses `dir` as the cache (created if missing) from now on in this process,
/// or no cache with `None` (the default).
pub fn set_dir(dir: Option<PathBuf>) -> std::io::Result<()> {
    if let Some(d) = &dir {
        std::fs::create_dir_all(d)?;
    }
    *DIR.write().unwrap_or_else(|e| e.into_inner()) = dir;
    Ok(())
}

/// The cache folder in use, if any.
pub fn dir() -> Option<PathBuf> {
    DIR.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Entries found and missed (then made) so far in this process.
pub fn stats() -> (u64, u64) {
    (HITS.load(Ordering::Relaxed), MISSES.load(Ordering::Relaxed))
}

/// What kind of entry (a tag in the file and its name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A decoded texture.
    Texture,
    /// A BVH.
    Bvh,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Texture => "texture",
            Kind::Bvh => "bvh",
        }
    }
    fn tag(self) -> u32 {
        match self {
            Kind::Texture => 1,
            Kind::Bvh => 2,
        }
    }
}

/// A key for an entry of `kind` made from `input`: the input's hash, with
/// this build of raylab (its version, and the size and time of its
/// executable, which change with every build) and the entry format.
pub(crate) fn key(kind: Kind, input: impl FnOnce(&mut Fingerprint)) -> u64 {
    let mut f = Fingerprint::new();
    f.update(env!("CARGO_PKG_VERSION").as_bytes());
    f.words32([VERSION, kind.tag()]);
    if let Some(meta) = std::env::current_exe()
        .ok()
        .and_then(|e| std::fs::metadata(e).ok())
    {
        f.update(&meta.len().to_le_bytes());
        if let Ok(t) = meta.modified()
            && let Ok(d) = t.duration_since(std::time::UNIX_EPOCH)
        {
            f.update(&d.as_nanos().to_le_bytes());
        }
    }
    input(&mut f);
    f.value()
}

fn entry_path(dir: &Path, kind: Kind, key: u64) -> PathBuf {
    dir.join(format!("{}-{key:016x}.raylab-cache", kind.name()))
}

/// The payload of entry (`kind`, `key`) if the cache holds a sound one of at
/// most `max_len` bytes; `None` without a cache.
pub(crate) fn get(kind: Kind, key: u64, max_len: u64) -> Option<Vec<u8>> {
    let dir = dir()?;
    let found = read_entry(&entry_path(&dir, kind, key), kind, key, max_len);
    match found {
        Some(_) => HITS.fetch_add(1, Ordering::Relaxed),
        None => MISSES.fetch_add(1, Ordering::Relaxed),
    };
    found
}

fn read_entry(path: &Path, kind: Kind, key: u64, max_len: u64) -> Option<Vec<u8>> {
    let len = std::fs::metadata(path).ok()?.len();
    // The length is checked before the file is read into memory.
    if len < (HEADER + 8) as u64 || len - (HEADER + 8) as u64 > max_len {
        return None;
    }
    let bytes = std::fs::read(path).ok()?;
    let (head, rest) = bytes.split_at(HEADER);
    let word = |at: usize| u64::from_le_bytes(head[at..at + 8].try_into().expect("8 bytes"));
    let sound = &head[..8] == MAGIC
        && head[8..12] == VERSION.to_le_bytes()
        && head[12..16] == kind.tag().to_le_bytes()
        && word(16) == key
        && word(24) == rest.len() as u64 - 8;
    if !sound {
        return None;
    }
    let (payload, sum) = rest.split_at(rest.len() - 8);
    let mut f = Fingerprint::new();
    f.update(&bytes[..bytes.len() - 8]);
    (f.value().to_le_bytes() == sum).then(|| payload.to_vec())
}

/// Stores `payload` as entry (`kind`, `key`), if there is a cache; a failure
/// is ignored (the cache is only an optimisation).
pub(crate) fn put(kind: Kind, key: u64, payload: &[u8]) {
    let Some(dir) = dir() else { return };
    let mut bytes = Vec::with_capacity(HEADER + payload.len() + 8);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&kind.tag().to_le_bytes());
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(payload);
    let mut f = Fingerprint::new();
    f.update(&bytes);
    bytes.extend_from_slice(&f.value().to_le_bytes());
    let _ = crate::film::write_bytes(&bytes, &entry_path(&dir, kind, key));
}

/// Little-endian reading of a payload, failing (with `None`) past its end.
pub(crate) struct Reader<'a>(pub(crate) &'a [u8]);

impl Reader<'_> {
    pub(crate) fn take(&mut self, n: usize) -> Option<&[u8]> {
        if n > self.0.len() {
            return None;
        }
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        Some(a)
    }
    pub(crate) fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    pub(crate) fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    pub(crate) fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_round_trip_and_damage_is_a_miss() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("e");
        // Written as `put` writes, without the process-wide folder.
        let write = |payload: &[u8]| {
            let mut bytes = Vec::new();
            bytes.extend_from_slice(MAGIC);
            bytes.extend_from_slice(&VERSION.to_le_bytes());
            bytes.extend_from_slice(&Kind::Bvh.tag().to_le_bytes());
            bytes.extend_from_slice(&7u64.to_le_bytes());
            bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
            bytes.extend_from_slice(payload);
            let mut f = Fingerprint::new();
            f.update(&bytes);
            bytes.extend_from_slice(&f.value().to_le_bytes());
            std::fs::write(&path, &bytes).unwrap();
            bytes
        };
        let bytes = write(b"hello");
        assert_eq!(
            read_entry(&path, Kind::Bvh, 7, 100).as_deref(),
            Some(&b"hello"[..])
        );
        // Another key or kind, a payload over the limit: misses.
        assert_eq!(read_entry(&path, Kind::Bvh, 8, 100), None);
        assert_eq!(read_entry(&path, Kind::Texture, 7, 100), None);
        assert_eq!(read_entry(&path, Kind::Bvh, 7, 4), None);
        // Any flipped byte or a cut file: a miss.
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x40;
            std::fs::write(&path, &b).unwrap();
            assert_eq!(read_entry(&path, Kind::Bvh, 7, 100), None, "byte {i}");
        }
        std::fs::write(&path, &bytes[..bytes.len() - 1]).unwrap();
        assert_eq!(read_entry(&path, Kind::Bvh, 7, 100), None);
    }
}
