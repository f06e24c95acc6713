//! The file's bytes: files read within the memory budget, the buffers (a
//! GLB's binary chunk, base64 data URIs, files beside the glTF) and their
//! views. A buffer that cannot be read is kept with the reason, reported when
//! something raylab reads lies in it.

use std::path::Path;

use gltf::json;

use super::error::GltfError;
use super::meshopt;
use crate::memory::{Ledger, Needs};

/// Largest file (JSON, GLB, buffer or image) read, in bytes.
pub const MAX_FILE_BYTES: u64 = 1 << 32;

/// Reads a file (the glTF, a buffer or an image file) after checking that its
/// bytes fit the budget on top of `held`, the bytes already read and still
/// held for this load, which it then adds them to.
pub(super) fn read_file(
    path: &Path,
    ledger: &Ledger,
    held: &mut u64,
) -> Result<Vec<u8>, GltfError> {
    let io = |cause| GltfError::Io {
        path: path.to_owned(),
        cause,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > MAX_FILE_BYTES {
        return Err(GltfError::invalid(format!(
            "{} is {len} bytes, more than the limit of {MAX_FILE_BYTES}",
            path.display()
        )));
    }
    // The bytes are held while the scene is built from them.
    *held = held.saturating_add(len);
    let bytes = Needs {
        geometry: *held,
        ..Needs::default()
    };
    ledger.fits(&path.display().to_string(), bytes)?;
    std::fs::read(path).map_err(io)
}

/// The loaded buffers, indexed like the file's `buffers`.
pub struct Buffers<'a> {
    /// The file's JSON.
    pub root: &'a json::Root,
    /// Bytes of each buffer (exactly `byteLength` of them).
    pub data: &'a [Vec<u8>],
    /// Why a buffer could not be read (its `data` is then empty), reported
    /// when something in it is read.
    pub unreadable: &'a [Option<Unreadable>],
}

/// Why a buffer could not be read.
pub struct Unreadable {
    /// The message (`buffer 2 has no URI`, `… is not a local file`).
    pub reason: String,
    /// The buffer has no URI (and no GLB chunk for it): no data at all, as
    /// opposed to data that could not be had.
    pub placeholder: bool,
}

impl<'a> Buffers<'a> {
    /// Buffer `i`'s bytes; an error if it does not exist or could not be read.
    pub fn bytes(&self, i: usize, what: &str) -> Result<&'a [u8], GltfError> {
        if let Some(Some(u)) = self.unreadable.get(i) {
            return Err(GltfError::invalid(format!("{what}: {}", u.reason)));
        }
        self.data
            .get(i)
            .map(Vec::as_slice)
            .ok_or_else(|| GltfError::invalid(format!("{what}: buffer {i} does not exist")))
    }

    /// Buffer view `view`'s bytes and stride, after checking that the view
    /// exists and lies inside its buffer, which could be read.
    pub fn view(&self, view: usize) -> Result<(&'a [u8], Option<usize>), GltfError> {
        let v = self
            .root
            .buffer_views
            .get(view)
            .ok_or_else(|| GltfError::invalid(format!("buffer view {view} does not exist")))?;
        let buffer = self.bytes(v.buffer.value(), &format!("buffer view {view}"))?;
        let offset = v.byte_offset.map_or(0, |o| o.0);
        let end = offset.checked_add(v.byte_length.0);
        match end {
            Some(end) if end <= buffer.len() as u64 => Ok((
                &buffer[offset as usize..end as usize],
                v.byte_stride.map(|s| s.0),
            )),
            _ => Err(GltfError::invalid(format!(
                "buffer view {view} (bytes {offset}..+{}) lies outside buffer {} of {} bytes",
                v.byte_length.0,
                v.buffer.value(),
                buffer.len()
            ))),
        }
    }

    /// The buffer of accessor `accessor`'s view if it is a placeholder (see
    /// [`Unreadable::placeholder`]).
    pub fn placeholder_of(&self, accessor: usize) -> Option<usize> {
        let view = self.root.accessors.get(accessor)?.buffer_view?.value();
        let buffer = self.root.buffer_views.get(view)?.buffer.value();
        self.unreadable
            .get(buffer)?
            .as_ref()
            .filter(|u| u.placeholder)
            .map(|_| buffer)
    }
}

/// The bytes of every buffer, and why those left empty could not be read.
pub(super) type LoadedBuffers = (Vec<Vec<u8>>, Vec<Option<Unreadable>>);

/// Reads every buffer: the GLB's binary chunk, a data URI or a file beside the
/// glTF. Each must hold at least `byteLength` bytes.
///
/// A buffer that cannot be had (no URI and no GLB chunk, a remote or non-base64
/// URI, a missing file) is left empty with the reason beside it, reported
/// only when something raylab reads lies in it: the glTF-Validator accepts
/// files with such buffers when nothing uses them (placeholders, unused
/// objects). `glb` says whether the file is a GLB, and gives its binary
/// chunk if it has one.
pub(super) fn load_buffers(
    root: &json::Root,
    base: &Path,
    glb: (bool, Option<&[u8]>),
    ledger: &Ledger,
    held: &mut u64,
) -> Result<LoadedBuffers, GltfError> {
    let (is_glb, glb_bin) = glb;
    let mut out = Vec::with_capacity(root.buffers.len().min(1024));
    let mut unreadable = Vec::with_capacity(out.capacity());
    let meshopt_used = meshopt::used(root);
    for (i, b) in root.buffers.iter().enumerate() {
        let want = b.byte_length.0;
        // A meshopt fallback buffer (marked, or a placeholder without a URI
        // beside the GLB's chunk) holds only what the compressed views
        // decode to: it is never read, and stays empty.
        if meshopt_used
            && (meshopt::is_fallback(b) || (b.uri.is_none() && (i > 0 || glb_bin.is_none())))
        {
            out.push(Vec::new());
            unreadable.push(None);
            continue;
        }
        let data = match &b.uri {
            None if i == 0 => glb_bin.map(<[u8]>::to_vec).ok_or_else(|| {
                GltfError::invalid("buffer 0 has no URI and the file has no GLB binary chunk")
            }),
            None => Err(GltfError::invalid(format!("buffer {i} has no URI"))),
            Some(uri) => read_uri(uri, base, &format!("buffer {i}"), ledger, held),
        };
        let data = match data {
            Ok(data) => data,
            Err(GltfError::Invalid(reason)) => {
                out.push(Vec::new());
                // A GLB's buffer 0 without a URI is its binary chunk: a GLB
                // without one is broken, not a placeholder.
                unreadable.push(Some(Unreadable {
                    reason,
                    placeholder: b.uri.is_none() && !(i == 0 && is_glb),
                }));
                continue;
            }
            Err(other) => return Err(other),
        };
        if (data.len() as u64) < want {
            return Err(GltfError::invalid(format!(
                "buffer {i} declares {want} bytes but only {} are there",
                data.len()
            )));
        }
        let mut data = data;
        data.truncate(want as usize);
        out.push(data);
        unreadable.push(None);
    }
    Ok((out, unreadable))
}

/// The bytes behind a URI: a base64 data URI or a relative file path.
pub(super) fn read_uri(
    uri: &str,
    base: &Path,
    what: &str,
    ledger: &Ledger,
    held: &mut u64,
) -> Result<Vec<u8>, GltfError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or_else(|| GltfError::invalid(format!("{what}: malformed data URI")))?;
        if !header.ends_with(";base64") {
            return Err(GltfError::invalid(format!(
                "{what}: data URI is not base64"
            )));
        }
        return decode_base64(payload)
            .ok_or_else(|| GltfError::invalid(format!("{what}: data URI is not valid base64")));
    }
    if uri.contains("://") {
        return Err(GltfError::invalid(format!(
            "{what}: URI {} is not a local file",
            crate::guard::one_line(uri)
        )));
    }
    let file = base.join(percent_decode(uri));
    match read_file(&file, ledger, held) {
        Err(GltfError::Io { cause, .. }) => Err(GltfError::invalid(format!(
            "{what}: cannot read {}: {cause}",
            crate::guard::one_line(&file.display().to_string())
        ))),
        other => other,
    }
}

/// Decodes standard base64 (padding optional, whitespace refused); `None` if
/// malformed.
pub fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let text = text.trim_end_matches('=').as_bytes();
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    if text.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    for chunk in text.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * k);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// `%XX` escapes of a URI decoded (invalid escapes are kept as they are).
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%'
            && i + 2 < b.len()
            && let Ok(v) =
                u8::from_str_radix(std::str::from_utf8(&b[i + 1..i + 3]).unwrap_or("zz"), 16)
        {
            out.push(v);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}
