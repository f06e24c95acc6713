//! Reading glTF accessors from buffers: every component type, normalized
//! integers, interleaved views and sparse accessors. Every count, offset and
//! stride is checked against the bytes actually present before anything is
//! allocated.

use gltf::json::{self, accessor::ComponentType, accessor::Type};

// Defined in `buffers.rs`, beside the code that reads the buffers; still
// reachable here, where they were first.
pub use super::buffers::{Buffers, Unreadable};
use super::error::{GltfError, valid};

/// Most elements an accessor may have (2^28: far above any real asset, well
/// below what would exhaust memory).
pub const MAX_ELEMENTS: u64 = 1 << 28;

/// Bytes per component.
fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Components per element.
pub fn type_components(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// One component at `bytes[0..]` as f32, normalized to `[0, 1]` / `[−1, 1]` if
/// asked (glTF's rules: signed values clamp at −1).
#[inline]
fn component(bytes: &[u8], c: ComponentType, normalized: bool) -> f32 {
    let b = |n: usize| -> [u8; 4] {
        let mut a = [0u8; 4];
        a[..n].copy_from_slice(&bytes[..n]);
        a
    };
    match c {
        ComponentType::F32 => f32::from_le_bytes(b(4)),
        ComponentType::U32 => u32::from_le_bytes(b(4)) as f32,
        ComponentType::U8 => {
            let v = bytes[0] as f32;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I8 => {
            let v = bytes[0] as i8 as f32;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized { v / 65535.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
    }
}

/// An index component as u32 (unsigned integer types only).
#[inline]
fn index_component(bytes: &[u8], c: ComponentType) -> Option<u32> {
    match c {
        ComponentType::U8 => Some(bytes[0] as u32),
        ComponentType::U16 => Some(u16::from_le_bytes([bytes[0], bytes[1]]) as u32),
        ComponentType::U32 => Some(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        _ => None,
    }
}

/// The bytes of a buffer view after checking it lies inside its buffer
/// ([`Buffers::view`]), a missing view named as `what`'s.
fn view_bytes<'b>(
    buffers: &Buffers<'b>,
    view: usize,
    what: &str,
) -> Result<(&'b [u8], Option<usize>), GltfError> {
    if view >= buffers.root.buffer_views.len() {
        return Err(GltfError::invalid(format!(
            "{what}: buffer view {view} does not exist"
        )));
    }
    buffers.view(view)
}

/// Element `i`'s bytes of `count` elements of `elem` bytes each, `stride` apart
/// from `offset` in `bytes`, after checking that the last one fits.
fn checked_layout(
    bytes_len: usize,
    offset: u64,
    count: u64,
    elem: usize,
    stride: usize,
    what: &str,
) -> Result<(), GltfError> {
    if count == 0 {
        return Ok(());
    }
    let end = (count - 1)
        .checked_mul(stride as u64)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem as u64));
    match end {
        Some(end) if end <= bytes_len as u64 => Ok(()),
        _ => Err(GltfError::invalid(format!(
            "{what}: {count} elements of {elem} bytes (stride {stride}, offset {offset}) do not fit the buffer view's {bytes_len} bytes"
        ))),
    }
}

/// Reads accessor `index` as `N` floats per element (converting integer and
/// normalized types), with sparse substitution applied. `what` names the use
/// in errors (e.g. "mesh 0 primitive 1 POSITION").
pub fn read_floats<const N: usize>(
    buffers: &Buffers,
    index: usize,
    what: &str,
) -> Result<Vec<[f32; N]>, GltfError> {
    let acc = accessor(buffers, index, what)?;
    let (c, t) = kinds(acc, index)?;
    let n = type_components(t);
    if n != N && !(N == 4 && n == 3) {
        return Err(GltfError::invalid(format!(
            "{what}: accessor {index} has {n} components per element, expected {N}"
        )));
    }
    let count = acc.count.0;
    let csize = component_size(c);
    let elem = n * csize;
    // Check the layout before allocating anything sized by the count.
    let mut dense = None;
    if let Some(view) = acc.buffer_view {
        let (bytes, stride) = view_bytes(buffers, view.value(), what)?;
        let stride = stride.unwrap_or(elem);
        if stride < elem {
            return Err(GltfError::invalid(format!(
                "{what}: byte stride {stride} is smaller than an element ({elem} bytes)"
            )));
        }
        let offset = acc.byte_offset.map_or(0, |o| o.0);
        checked_layout(bytes.len(), offset, count, elem, stride, what)?;
        dense = Some((bytes, stride, offset as usize));
    }
    let mut out = vec![[0.0f32; N]; count as usize];
    if N == 4 && n == 3 {
        // A colour without alpha: alpha 1.
        for v in &mut out {
            v[3] = 1.0;
        }
    }
    let read = |bytes: &[u8], v: &mut [f32; N]| {
        for (k, slot) in v.iter_mut().take(n).enumerate() {
            *slot = component(&bytes[k * csize..], c, acc.normalized);
        }
    };
    if let Some((bytes, stride, offset)) = dense {
        for (i, v) in out.iter_mut().enumerate() {
            read(&bytes[offset + i * stride..], v);
        }
    }
    if let Some(sparse) = sparse_part(buffers, acc, elem, what)? {
        for (target, bytes) in sparse.entries() {
            let v = out
                .get_mut(target as usize)
                .ok_or_else(|| sparse.outside(target))?;
            read(bytes, v);
        }
    }
    Ok(out)
}

/// Reads accessor `index` as vertex indices (unsigned integer scalars).
pub fn read_indices(buffers: &Buffers, index: usize, what: &str) -> Result<Vec<u32>, GltfError> {
    let acc = accessor(buffers, index, what)?;
    let (c, t) = kinds(acc, index)?;
    if t != Type::Scalar
        || !matches!(
            c,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        )
    {
        return Err(GltfError::invalid(format!(
            "{what}: index accessor {index} must hold unsigned integer scalars"
        )));
    }
    let count = acc.count.0;
    let size = component_size(c);
    let mut out = match acc.buffer_view {
        None => vec![0; count as usize],
        Some(view) => {
            let (bytes, stride) = view_bytes(buffers, view.value(), what)?;
            let stride = stride.unwrap_or(size).max(size);
            let offset = acc.byte_offset.map_or(0, |o| o.0);
            checked_layout(bytes.len(), offset, count, size, stride, what)?;
            let offset = offset as usize;
            (0..count as usize)
                .map(|i| index_component(&bytes[offset + i * stride..], c).unwrap_or(0))
                .collect()
        }
    };
    // Sparse substitution, read as integers (a float path would round indices
    // above 2^24).
    if let Some(sparse) = sparse_part(buffers, acc, size, what)? {
        for (target, bytes) in sparse.entries() {
            let slot = out
                .get_mut(target as usize)
                .ok_or_else(|| sparse.outside(target))?;
            *slot = index_component(bytes, c).unwrap_or(0);
        }
    }
    Ok(out)
}

/// The sparse part of an accessor: which elements it replaces and the bytes of
/// their new values, laid out and checked.
struct SparsePart<'b> {
    indices: &'b [u8],
    index_type: ComponentType,
    values: &'b [u8],
    value_size: usize,
    what: String,
    count: u64,
}

impl SparsePart<'_> {
    /// (element replaced, bytes of its new value), in order.
    fn entries(&self) -> impl Iterator<Item = (u32, &[u8])> {
        let index_size = component_size(self.index_type);
        self.indices
            .chunks_exact(index_size)
            .zip(self.values.chunks_exact(self.value_size))
            .map(|(i, v)| (index_component(i, self.index_type).unwrap_or(u32::MAX), v))
    }

    fn outside(&self, target: u32) -> GltfError {
        GltfError::invalid(format!(
            "{}: sparse index {target} is outside the accessor's {} elements",
            self.what, self.count
        ))
    }
}

/// The checked sparse part of `acc` (values of `value_size` bytes), if any.
fn sparse_part<'b>(
    buffers: &Buffers<'b>,
    acc: &json::Accessor,
    value_size: usize,
    what: &str,
) -> Result<Option<SparsePart<'b>>, GltfError> {
    let Some(sparse) = &acc.sparse else {
        return Ok(None);
    };
    let (k, count) = (sparse.count.0, acc.count.0);
    if k == 0 {
        return Ok(None);
    }
    if k > count {
        return Err(GltfError::invalid(format!(
            "{what}: a sparse accessor replaces {k} of {count} elements"
        )));
    }
    let index_type = valid(&sparse.indices.component_type)
        .map(|c| c.0)
        .filter(|c| {
            matches!(
                c,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            )
        })
        .ok_or_else(|| {
            GltfError::invalid(format!("{what}: sparse indices must be unsigned integers"))
        })?;
    let index_size = component_size(index_type);
    let (ibytes, _) = view_bytes(buffers, sparse.indices.buffer_view.value(), what)?;
    let ioff = sparse.indices.byte_offset.0;
    checked_layout(ibytes.len(), ioff, k, index_size, index_size, what)?;
    let (vbytes, _) = view_bytes(buffers, sparse.values.buffer_view.value(), what)?;
    let voff = sparse.values.byte_offset.0;
    checked_layout(vbytes.len(), voff, k, value_size, value_size, what)?;
    let (k, ioff, voff) = (k as usize, ioff as usize, voff as usize);
    Ok(Some(SparsePart {
        indices: &ibytes[ioff..ioff + k * index_size],
        index_type,
        values: &vbytes[voff..voff + k * value_size],
        value_size,
        what: what.to_string(),
        count,
    }))
}

/// The accessor, with its count checked against the ceiling.
fn accessor<'r>(
    buffers: &Buffers<'r>,
    index: usize,
    what: &str,
) -> Result<&'r json::Accessor, GltfError> {
    let acc =
        buffers.root.accessors.get(index).ok_or_else(|| {
            GltfError::invalid(format!("{what}: accessor {index} does not exist"))
        })?;
    if acc.count.0 > MAX_ELEMENTS {
        return Err(GltfError::invalid(format!(
            "{what}: accessor {index} claims {} elements (the limit is {MAX_ELEMENTS})",
            acc.count.0
        )));
    }
    // An accessor without a buffer view is all zeros (plus sparse values): no
    // bytes back its count, so it may not exceed what the buffers could hold.
    let total: u64 = buffers.data.iter().map(|d| d.len() as u64).sum();
    if acc.buffer_view.is_none() && acc.count.0 > total.max(1 << 16) {
        return Err(GltfError::invalid(format!(
            "{what}: accessor {index} claims {} elements with no buffer view behind them",
            acc.count.0
        )));
    }
    Ok(acc)
}

/// The component type and element type of an accessor.
fn kinds(acc: &json::Accessor, index: usize) -> Result<(ComponentType, Type), GltfError> {
    let c = valid(&acc.component_type)
        .ok_or_else(|| GltfError::invalid(format!("accessor {index}: unknown component type")))?
        .0;
    let t = *valid(&acc.type_)
        .ok_or_else(|| GltfError::invalid(format!("accessor {index}: unknown element type")))?;
    Ok((c, t))
}
