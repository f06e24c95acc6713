//! The glTF document: a GLB container's chunks, the JSON read into
//! `gltf-json`'s structures (with the forms the glTF-Validator accepts and
//! `gltf-json` does not read tolerated), and the extensions raylab supports.

use std::path::Path;

use gltf::json;

use super::error::GltfError;
use super::{draco, meshopt};
use crate::memory::{Ledger, Needs};

/// Extensions raylab reads; a file that requires any other is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_animation_pointer",
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_materials_volume_scatter",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "KHR_node_visibility",
    "EXT_mesh_gpu_instancing",
    "EXT_texture_webp",
    BASISU,
    meshopt::EXT,
    meshopt::KHR,
    draco::EXT,
];

/// The Basis Universal texture extension's name (KTX2 images, decoded by
/// [`crate::textures`]).
pub(super) const BASISU: &str = "KHR_texture_basisu";

/// Splits a GLB container into its JSON and binary chunks.
pub(super) fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), GltfError> {
    let u32_at = |o: usize| -> Option<u32> {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or_else(|| GltfError::invalid("GLB header is truncated"))?;
    if version != 2 {
        return Err(GltfError::invalid(format!(
            "GLB version {version}, expected 2"
        )));
    }
    let total = u32_at(8).unwrap_or(0) as usize;
    if total > bytes.len() {
        return Err(GltfError::invalid(format!(
            "GLB header claims {total} bytes but the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..total];
    let mut offset = 12;
    let mut json = None;
    let mut bin = None;
    while offset + 8 <= bytes.len() {
        let len = u32_at(offset).unwrap_or(0) as usize;
        let kind = u32_at(offset + 4).unwrap_or(0);
        let start = offset + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                GltfError::invalid(format!(
                    "GLB chunk at byte {offset} claims {len} bytes past the end"
                ))
            })?;
        match kind {
            0x4E4F_534A if json.is_none() => json = Some(&bytes[start..end]),
            0x004E_4942 if bin.is_none() => bin = Some(&bytes[start..end]),
            _ => {}
        }
        offset = end;
    }
    let json = json.ok_or_else(|| GltfError::invalid("GLB has no JSON chunk"))?;
    Ok((json, bin))
}

/// Reads the glTF JSON (of a `.gltf`, or a GLB's JSON chunk) into
/// `gltf-json`'s structures. Its types are stricter than the specification in
/// three ways that the Khronos glTF-Validator accepts: an integer written with a
/// fraction (`"count": 3.0`, `"mesh": 1.0`: JSON has one kind of number), an
/// animation channel whose `target` has no `node` (the specification
/// allows that; an extension may name the target instead), and a texture
/// without a core `source` whose `KHR_texture_basisu` or `EXT_texture_webp`
/// names its image. A file
/// refused for such a reason is read again as a JSON tree, with integral
/// numbers written as integers, node-less channels dropped (`pointer.rs`
/// reads `KHR_animation_pointer`'s from the JSON text) and such textures given their KTX2
/// or WebP image as `source`, and
/// then deserialized from the tree; files that parse as they are take the
/// first reading alone, so they load exactly as before. A fraction such as
/// `1.5` where an integer is required is still refused.
pub(super) fn parse_root(
    json_bytes: &[u8],
    path: &Path,
    ledger: &Ledger,
    held: u64,
) -> Result<json::Root, GltfError> {
    let refused = |e: serde_json::Error| GltfError::invalid(format!("not valid glTF JSON: {e}"));
    let strict = crate::guard::catch("gltf-json", || json::Root::from_slice(json_bytes))
        .map_err(GltfError::invalid)?;
    let strict_error = match strict {
        Ok(root) => return Ok(root),
        Err(e) => e,
    };
    // Only a value of the wrong type or a missing field can be one of the
    // tolerated forms; malformed JSON is reported with its line and column.
    if strict_error.classify() != serde_json::error::Category::Data {
        return Err(refused(strict_error));
    }
    // The tree takes more memory than the text: checked before it is built.
    let tree = Needs {
        geometry: held.saturating_add(json_tree_bytes(json_bytes)),
        ..Needs::default()
    };
    ledger.fits(&path.display().to_string(), tree)?;
    let mut tree = match crate::guard::catch("serde_json", || {
        serde_json::from_slice::<serde_json::Value>(json_bytes)
    })
    .map_err(GltfError::invalid)?
    {
        Ok(tree) => tree,
        Err(_) => return Err(refused(strict_error)),
    };
    if !tolerate(&mut tree) {
        return Err(refused(strict_error));
    }
    crate::guard::catch("gltf-json", || serde_json::from_value::<json::Root>(tree))
        .map_err(GltfError::invalid)?
        .map_err(refused)
}

/// Bytes that a `serde_json::Value` of JSON text `text` may take at most: the
/// text (strings are copied) and, for every value, a `Value` and its share of
/// an array or a map node (128 bytes, more than either takes). Every value
/// but the first follows a `[`, `{`, `,` or `:` outside a string, so those
/// are counted.
fn json_tree_bytes(text: &[u8]) -> u64 {
    const BYTES_PER_VALUE: u64 = 128;
    let (mut values, mut in_string, mut escaped) = (1u64, false, false);
    for &c in text {
        if in_string {
            match c {
                _ if escaped => escaped = false,
                b'\\' => escaped = true,
                b'"' => in_string = false,
                _ => {}
            }
        } else {
            match c {
                b'"' => in_string = true,
                b'[' | b'{' | b',' | b':' => values += 1,
                _ => {}
            }
        }
    }
    (text.len() as u64).saturating_add(values.saturating_mul(BYTES_PER_VALUE))
}

/// Rewrites a glTF JSON tree into the form `gltf-json` reads (see
/// [`parse_root`]): every number written with a fraction that is a whole
/// number from 0 to below 2⁶⁴ becomes that integer (a float field reads it
/// as the same value), animation channels whose target has no `node` are
/// dropped, a scene without `nodes` gets an empty list, an `extras` that is
/// not an object is dropped, and a texture without `source` takes its
/// `KHR_texture_basisu` or `EXT_texture_webp` image's (files that require the
/// extension may leave the core fallback out). Returns whether anything
/// changed.
fn tolerate(tree: &mut serde_json::Value) -> bool {
    use serde_json::Value;
    let mut changed = false;
    if let Some(textures) = tree.get_mut("textures").and_then(Value::as_array_mut) {
        for texture in textures.iter_mut().filter_map(Value::as_object_mut) {
            if texture.contains_key("source") {
                continue;
            }
            let extension_source = |ext: &str| {
                texture
                    .get("extensions")
                    .and_then(|e| e.get(ext))
                    .and_then(|w| w.get("source"))
                    .cloned()
            };
            let image = extension_source(BASISU).or_else(|| extension_source("EXT_texture_webp"));
            if let Some(source) = image {
                texture.insert("source".into(), source);
                changed = true;
            }
        }
    }
    // A scene's `nodes` is optional (a scene may be empty).
    if let Some(scenes) = tree.get_mut("scenes").and_then(Value::as_array_mut) {
        for scene in scenes.iter_mut().filter_map(Value::as_object_mut) {
            if !scene.contains_key("nodes") {
                scene.insert("nodes".into(), Value::Array(Vec::new()));
                changed = true;
            }
        }
    }
    if let Some(animations) = tree.get_mut("animations").and_then(Value::as_array_mut) {
        for animation in animations {
            if let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) {
                let before = channels.len();
                channels.retain(
                    |c| !matches!(c.get("target"), Some(Value::Object(t)) if !t.contains_key("node")),
                );
                changed |= channels.len() != before;
            }
        }
    }
    // Depth-first with a stack (serde_json nests at most 128 deep, but the
    // walk needs no recursion at all).
    let mut stack = vec![tree];
    while let Some(value) = stack.pop() {
        match value {
            Value::Number(n) => {
                if let Some(whole) = n.as_f64().filter(|_| n.is_f64()).and_then(whole_number) {
                    *n = whole.into();
                    changed = true;
                }
            }
            Value::Array(items) => stack.extend(items.iter_mut()),
            Value::Object(members) => {
                // `extras` may be any JSON value; raylab reads none, and
                // `gltf-json` takes only objects there.
                if members.get("extras").is_some_and(|e| !e.is_object()) {
                    members.remove("extras");
                    changed = true;
                }
                stack.extend(members.values_mut())
            }
            _ => {}
        }
    }
    changed
}

/// `x` as an integer if it is a whole number from +0 to below 2⁶⁴ (−0 stays a
/// float, so that a float field keeps its sign).
fn whole_number(x: f64) -> Option<u64> {
    const TWO_TO_64: f64 = 18_446_744_073_709_551_616.0;
    (x.is_sign_positive() && x.fract() == 0.0 && x < TWO_TO_64).then_some(x as u64)
}
