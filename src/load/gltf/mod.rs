//! glTF 2.0 scenes (`.gltf` with external or data-URI buffers and images, and
//! `.glb`), read into [`SceneParts`] following
//! `../shared/specs/scene-conventions.md`.
//!
//! The JSON is parsed by `gltf-json` (plain serde structures, no validation
//! pass that could index out of range); every reference, count, offset and
//! stride is checked here before use, so a bad file is refused with one line
//! naming it and what is wrong, never a panic or an allocation sized by an
//! unchecked number.

pub mod accessor;
pub mod animation;
pub mod draco;
pub mod meshopt;
pub(crate) mod object_model;
pub(crate) mod pointer;
pub(crate) mod skin;
pub(crate) mod tangents;

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat3A, Mat4, Quat, Vec2, Vec3, Vec3A, Vec4};
use gltf::json::{self, validation::Checked};
use thiserror::Error;

use accessor::{Buffers, Unreadable, read_floats, read_indices};
use animation::Pose;
pub use animation::{
    AT_EXPECTED, AnimationChoice, AnimationOptions, AnimationSummary, MAX_AT, MAX_FPS, at_in_range,
    fps_in_range,
};

use crate::camera::{Lens, SceneCamera};
use crate::geometry::triangle::Triangle;
use crate::lights::Light;
use crate::materials::surface::{
    AlphaMode, GltfMaterial, MaterialKind, SpecularGlossiness, SurfaceMaterial,
};
use crate::memory::{GEOMETRY_BYTES_PER_TRIANGLE, Ledger, Needs};
use crate::scene::mesh::{Instance, MeshData, Tangents};
use crate::scene::{NO_INSTANCE, PointLight, SceneParts};
use crate::textures::{TextureError, TextureRef, TextureStore, TextureTransform, Wrap};

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
const BASISU: &str = "KHR_texture_basisu";

/// The clear coat extension's name.
const CLEARCOAT: &str = "KHR_materials_clearcoat";

/// `KHR_materials_clearcoat`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Clearcoat {
    #[serde(default)]
    clearcoat_factor: f32,
    clearcoat_texture: Option<json::texture::Info>,
    #[serde(default)]
    clearcoat_roughness_factor: f32,
    clearcoat_roughness_texture: Option<json::texture::Info>,
    clearcoat_normal_texture: Option<json::material::NormalTexture>,
}

/// The sheen extension's name.
const SHEEN: &str = "KHR_materials_sheen";

/// `KHR_materials_sheen`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Sheen {
    #[serde(default)]
    sheen_color_factor: [f32; 3],
    sheen_color_texture: Option<json::texture::Info>,
    #[serde(default)]
    sheen_roughness_factor: f32,
    sheen_roughness_texture: Option<json::texture::Info>,
}

/// The dispersion extension's name.
const DISPERSION: &str = "KHR_materials_dispersion";

/// `KHR_materials_dispersion`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
struct Dispersion {
    /// `20 / V_d`; 0 (the default) disperses nothing.
    #[serde(default)]
    dispersion: f32,
}

/// The thin-film extension's name.
const IRIDESCENCE: &str = "KHR_materials_iridescence";

/// `KHR_materials_iridescence`'s object (`gltf-json` does not know it), with
/// the schema's defaults.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Iridescence {
    #[serde(default)]
    iridescence_factor: f32,
    iridescence_texture: Option<json::texture::Info>,
    /// The schema's spelling; the specification's prose and example write
    /// `iridescenceIOR`, read too.
    #[serde(default = "Iridescence::default_ior", alias = "iridescenceIOR")]
    iridescence_ior: f32,
    #[serde(default = "Iridescence::default_minimum")]
    iridescence_thickness_minimum: f32,
    #[serde(default = "Iridescence::default_maximum")]
    iridescence_thickness_maximum: f32,
    iridescence_thickness_texture: Option<json::texture::Info>,
}

impl Iridescence {
    fn default_ior() -> f32 {
        1.3
    }
    fn default_minimum() -> f32 {
        100.0
    }
    fn default_maximum() -> f32 {
        400.0
    }
}

/// The anisotropy extension's name.
const ANISOTROPY: &str = "KHR_materials_anisotropy";

/// `KHR_materials_anisotropy`'s object (`gltf-json` does not know it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Anisotropy {
    #[serde(default)]
    anisotropy_strength: f32,
    #[serde(default)]
    anisotropy_rotation: f32,
    anisotropy_texture: Option<json::texture::Info>,
}

/// The diffuse transmission extension's name.
const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";

/// `KHR_materials_diffuse_transmission`'s object (`gltf-json` does not know
/// it).
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct DiffuseTransmission {
    #[serde(default)]
    diffuse_transmission_factor: f32,
    diffuse_transmission_texture: Option<json::texture::Info>,
    #[serde(default = "white")]
    diffuse_transmission_color_factor: [f32; 3],
    diffuse_transmission_color_texture: Option<json::texture::Info>,
}

/// `[1, 1, 1]`, a colour factor's default.
fn white() -> [f32; 3] {
    [1.0; 3]
}

/// Deepest node hierarchy accepted.
pub const MAX_NODE_DEPTH: usize = 1024;
/// Largest file (JSON, GLB, buffer or image) read, in bytes.
pub const MAX_FILE_BYTES: u64 = 1 << 32;
/// Most triangles a scene may have after instancing (2^26: about 10 GB with
/// the BVH and per-triangle data, within a workstation's memory).
pub const MAX_TRIANGLES: u64 = 1 << 26;

/// Why a glTF file cannot be loaded.
#[derive(Debug, Error)]
pub enum GltfError {
    /// A file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        cause: std::io::Error,
    },
    /// The content is malformed or inconsistent.
    #[error("{0}")]
    Invalid(String),
    /// The scene would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

impl GltfError {
    /// An [`GltfError::Invalid`] with this message.
    pub fn invalid(message: impl Into<String>) -> Self {
        GltfError::Invalid(message.into())
    }
}

/// Which `KHR_materials_variants` variant a file is loaded with.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum VariantChoice {
    /// The primitives' own materials.
    #[default]
    Default,
    /// The variant of this name; a file without it is refused, with the
    /// names it has.
    Named(String),
    /// The variant of this name if the file has one, else the primitives' own
    /// materials (a scene file's `--variant`, which applies to the models
    /// that have it).
    IfDefined(String),
}

/// What [`load_gltf`] returns: the scene's parts and what to tell the user.
#[derive(Debug)]
pub struct GltfScene {
    /// Geometry, materials, textures, lights and cameras.
    pub parts: SceneParts,
    /// Whether the file had any punctual light.
    pub has_punctual_lights: bool,
    /// The names of the file's material variants (`KHR_materials_variants`),
    /// in the file's order.
    pub variants: Vec<String>,
    /// The variant shown, if any.
    pub variant: Option<String>,
    /// Things worth telling that do not stop the load (skipped primitives,
    /// ignored extensions), each once.
    pub warnings: Vec<String>,
    /// The names of the file's animations, in file order (empty strings for
    /// unnamed ones).
    pub animations: Vec<String>,
}

/// Reads a glTF or GLB file. Errors carry the file's name.
pub fn load_gltf(path: &Path) -> Result<GltfScene, GltfError> {
    load_gltf_with(path, &Ledger::unlimited())
}

/// [`load_gltf`], charging the decoded textures to `ledger` before decoding
/// them.
pub fn load_gltf_with(path: &Path, ledger: &Ledger) -> Result<GltfScene, GltfError> {
    load_gltf_variant(path, ledger, &VariantChoice::Default)
}

/// [`load_gltf_with`] showing a material variant (`KHR_materials_variants`):
/// each primitive whose mappings name the variant gets that mapping's
/// material.
pub fn load_gltf_variant(
    path: &Path,
    ledger: &Ledger,
    variant: &VariantChoice,
) -> Result<GltfScene, GltfError> {
    load_gltf_posed(path, ledger, variant, &AnimationOptions::default())
}

/// [`load_gltf_variant`], posed by one of the file's animations at a time
/// (see [`animation`]); the default options pose nothing.
pub fn load_gltf_posed(
    path: &Path,
    ledger: &Ledger,
    variant: &VariantChoice,
    animation: &AnimationOptions,
) -> Result<GltfScene, GltfError> {
    let name = path.display().to_string();
    load_gltf_inner(path, ledger, variant, animation).map_err(|e| match e {
        GltfError::Invalid(m) => GltfError::Invalid(format!("{name}: {m}")),
        io => io,
    })
}

/// Reads a file (the glTF, a buffer or an image file) after checking that its
/// bytes fit the budget on top of `held`, the bytes already read and still
/// held for this load, which it then adds them to.
fn read_file(path: &Path, ledger: &Ledger, held: &mut u64) -> Result<Vec<u8>, GltfError> {
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

/// Splits a GLB container into its JSON and binary chunks.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), GltfError> {
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

fn load_gltf_inner(
    path: &Path,
    ledger: &Ledger,
    variant: &VariantChoice,
    animation: &AnimationOptions,
) -> Result<GltfScene, GltfError> {
    let mut held = 0;
    let bytes = read_file(path, ledger, &mut held)?;
    let (json_bytes, glb_bin) = if bytes.starts_with(b"glTF") {
        split_glb(&bytes)?
    } else {
        (&bytes[..], None)
    };
    let mut root = parse_root(json_bytes, path, ledger, held)?;
    let mut warnings = Vec::new();
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
    {
        return Err(GltfError::invalid(format!(
            "requires the extension {ext}, which raylab does not support (supported: {})",
            SUPPORTED_EXTENSIONS.join(", ")
        )));
    }
    for ext in root
        .extensions_used
        .iter()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
    {
        warnings.push(format!("{}: ignoring the extension {ext}", path.display()));
    }
    let variants: Vec<String> = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_materials_variants.as_ref())
        .map(|v| {
            v.variants
                .iter()
                .map(|v| crate::guard::one_line(&v.name).into_owned())
                .collect()
        })
        .unwrap_or_default();
    let shown = match variant {
        VariantChoice::Default => None,
        VariantChoice::Named(name) | VariantChoice::IfDefined(name) => {
            match variants.iter().position(|v| v == name) {
                Some(k) => Some(k),
                None if matches!(variant, VariantChoice::IfDefined(_)) => None,
                None => {
                    return Err(GltfError::invalid(format!(
                        "has no material variant '{}' ({})",
                        crate::guard::one_line(name),
                        variant_list(&variants)
                    )));
                }
            }
        }
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let is_glb = bytes.starts_with(b"glTF");
    let (mut buffer_data, unreadable) =
        load_buffers(&root, base, (is_glb, glb_bin), ledger, &mut held)?;
    // Compressed views are decoded into buffers of their own, the bytes held
    // with the rest until the scene is built.
    let mut charge = |bytes: u64| {
        held = held.saturating_add(bytes);
        let needs = Needs {
            geometry: held,
            ..Needs::default()
        };
        Ok(ledger.fits(&path.display().to_string(), needs)?)
    };
    meshopt::decode_views(&mut root, &mut buffer_data, &mut charge)?;
    // Draco primitives (whose streams a meshopt view could hold) likewise.
    draco::decode_primitives(&mut root, &mut buffer_data, &unreadable, &mut charge)?;
    // KHR_animation_pointer (pointer.rs): the chosen animation's pointer
    // channels written into the objects they animate.
    pointer::apply(
        json_bytes,
        &mut root,
        &buffer_data,
        &unreadable,
        animation,
        &mut warnings,
    )?;
    let buffers = Buffers {
        root: &root,
        data: &buffer_data,
        unreadable: &unreadable,
    };
    let pose = animation::pose(&root, &buffers, animation, &mut warnings)?;
    let mut loader = Loader {
        root: &root,
        buffers: &buffers,
        base,
        ledger,
        name: path.display().to_string(),
        parts: SceneParts {
            two_sided: true,
            ..SceneParts::default()
        },
        mesh_ids: HashMap::new(),
        material_ids: HashMap::new(),
        image_ids: HashMap::new(),
        image_sources: Vec::new(),
        warned: HashSet::new(),
        warnings,
        point_lights: Vec::new(),
        variant: shown,
        variant_count: variants.len(),
        pose,
        globals: None,
    };
    loader.walk_scene()?;
    let mut scene = loader.finish()?;
    scene.variant = shown.map(|k| variants[k].clone());
    scene.variants = variants;
    Ok(scene)
}

/// Node `index`'s own `KHR_node_visibility` `visible` (true without the
/// extension); anything but a boolean there is refused.
fn node_visible(node: &json::Node, index: usize) -> Result<bool, GltfError> {
    let Some(ext) = node
        .extensions
        .as_ref()
        .and_then(|e| e.others.get("KHR_node_visibility"))
    else {
        return Ok(true);
    };
    match ext.get("visible") {
        None => Ok(true),
        Some(serde_json::Value::Bool(b)) => Ok(*b),
        Some(other) => Err(GltfError::invalid(format!(
            "node {index}: KHR_node_visibility's visible is {}, not true or false",
            crate::guard::one_line(&other.to_string())
        ))),
    }
}

/// The variants a file has, for a message: "variants: a, b, c" or "the file
/// has no material variants".
pub fn variant_list(variants: &[String]) -> String {
    if variants.is_empty() {
        "the file has no material variants".into()
    } else {
        format!("variants: {}", variants.join(", "))
    }
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
fn parse_root(
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

/// The bytes of every buffer, and why those left empty could not be read.
type LoadedBuffers = (Vec<Vec<u8>>, Vec<Option<Unreadable>>);

/// Reads every buffer: the GLB's binary chunk, a data URI or a file beside the
/// glTF. Each must hold at least `byteLength` bytes.
///
/// A buffer that cannot be had (no URI and no GLB chunk, a remote or non-base64
/// URI, a missing file) is left empty with the reason beside it, reported
/// only when something raylab reads lies in it: the glTF-Validator accepts
/// files with such buffers when nothing uses them (placeholders, unused
/// objects). `glb` says whether the file is a GLB, and gives its binary
/// chunk if it has one.
fn load_buffers(
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
fn read_uri(
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

struct Loader<'a> {
    root: &'a json::Root,
    buffers: &'a Buffers<'a>,
    base: &'a Path,
    /// Where the decoded textures are charged.
    ledger: &'a Ledger,
    /// The file, naming it in a memory error.
    name: String,
    parts: SceneParts,
    /// (mesh, primitive) → mesh data index.
    mesh_ids: HashMap<(usize, usize), u32>,
    /// glTF material (None: the default material) → table index.
    material_ids: HashMap<Option<usize>, u32>,
    /// glTF image → texture store index.
    image_ids: HashMap<usize, u32>,
    /// Images to decode, in store order: (name, bytes source).
    image_sources: Vec<(String, usize)>,
    warned: HashSet<String>,
    warnings: Vec<String>,
    /// Point lights in node order; the first becomes the key light.
    point_lights: Vec<(Vec3A, Vec3A)>,
    /// The index of the `KHR_materials_variants` variant shown, if any.
    variant: Option<usize>,
    /// How many variants the file defines (mappings must name one of them).
    variant_count: usize,
    /// The animation's pose, if the file is posed.
    pose: Option<Pose>,
    /// Every node's global transform (posed), made for the first skin.
    globals: Option<Vec<Option<Mat4>>>,
}

impl Loader<'_> {
    fn warn_once(&mut self, key: &str, message: String) {
        if self.warned.insert(key.to_string()) {
            self.warnings.push(message);
        }
    }

    /// Walks the default scene's node tree depth first (children in array
    /// order), composing transforms parent × child.
    fn walk_scene(&mut self) -> Result<(), GltfError> {
        let root = self.root;
        let roots: Vec<usize> = match root
            .scene
            .map(|s| s.value())
            .or((!root.scenes.is_empty()).then_some(0))
        {
            Some(s) => root
                .scenes
                .get(s)
                .ok_or_else(|| GltfError::invalid(format!("the default scene {s} does not exist")))?
                .nodes
                .iter()
                .map(|n| n.value())
                .collect(),
            None => {
                // No scenes: every node that is nobody's child.
                let children: HashSet<usize> = root
                    .nodes
                    .iter()
                    .flat_map(|n| n.children.iter().flatten().map(|c| c.value()))
                    .collect();
                (0..root.nodes.len())
                    .filter(|i| !children.contains(i))
                    .collect()
            }
        };
        let mut visited = vec![false; root.nodes.len()];
        // (node, parent transform, depth, parent visible), popped in
        // depth-first pre-order.
        let mut stack: Vec<(usize, Mat4, usize, bool)> = roots
            .iter()
            .rev()
            .map(|&n| (n, Mat4::IDENTITY, 0, true))
            .collect();
        while let Some((index, parent, depth, parent_visible)) = stack.pop() {
            let node = root
                .nodes
                .get(index)
                .ok_or_else(|| GltfError::invalid(format!("node {index} does not exist")))?;
            if std::mem::replace(&mut visited[index], true) {
                return Err(GltfError::invalid(format!(
                    "node {index} appears twice in the scene's node tree (a cycle or a shared child)"
                )));
            }
            if depth >= MAX_NODE_DEPTH {
                return Err(GltfError::invalid(format!(
                    "the node tree is deeper than {MAX_NODE_DEPTH} levels"
                )));
            }
            let world = parent * local_transform(node, index, self.pose.as_ref())?;
            // `KHR_node_visibility`: a hidden node hides its meshes and
            // lights and all its descendants'; its cameras still see.
            let visible = parent_visible && node_visible(node, index)?;
            if let Some(cam) = node.camera {
                self.camera(cam.value(), &world)?;
            }
            if let Some(light) = node
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
                .filter(|_| visible)
            {
                self.light(light.light.value(), &world)?;
            }
            if let Some(mesh) = node.mesh.filter(|_| visible) {
                match node
                    .extensions
                    .as_ref()
                    .and_then(|e| e.others.get("EXT_mesh_gpu_instancing"))
                {
                    Some(ext) => self.gpu_instances(index, ext, mesh.value(), &world)?,
                    None => self.mesh_instance(index, mesh.value(), &world)?,
                }
            }
            for child in node.children.iter().flatten().rev() {
                stack.push((child.value(), world, depth + 1, visible));
            }
        }
        Ok(())
    }

    fn camera(&mut self, index: usize, world: &Mat4) -> Result<(), GltfError> {
        let cam = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| GltfError::invalid(format!("camera {index} does not exist")))?;
        let position = Vec3A::from(world.transform_point3(Vec3::ZERO));
        let forward = Vec3A::from(world.transform_vector3(Vec3::NEG_Z)).normalize_or_zero();
        let right = Vec3A::from(world.transform_vector3(Vec3::X));
        let right = (right - forward * forward.dot(right)).normalize_or_zero();
        if forward == Vec3A::ZERO || right == Vec3A::ZERO || !position.is_finite() {
            return Err(GltfError::invalid(format!(
                "camera {index}'s node transform is degenerate"
            )));
        }
        let down = forward.cross(right);
        let (lens, aspect_ratio) = match (&cam.perspective, &cam.orthographic) {
            (Some(p), _) => {
                if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(GltfError::invalid(format!(
                        "camera {index}: yfov {} is not between 0 and π",
                        p.yfov
                    )));
                }
                (
                    Lens::from_yfov(p.yfov),
                    p.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0),
                )
            }
            (None, Some(o)) => {
                if !(o.ymag.is_finite() && o.ymag != 0.0) {
                    return Err(GltfError::invalid(format!(
                        "camera {index}: ymag {} must be non-zero",
                        o.ymag
                    )));
                }
                let aspect = (o.xmag / o.ymag).abs();
                (
                    Lens::Orthographic {
                        half_height: o.ymag.abs(),
                    },
                    (aspect.is_finite() && aspect > 0.0).then_some(aspect),
                )
            }
            (None, None) => {
                return Err(GltfError::invalid(format!(
                    "camera {index} is neither perspective nor orthographic"
                )));
            }
        };
        self.parts.cameras.push(SceneCamera {
            name: cam.name.clone().unwrap_or_default(),
            position,
            rotation: Mat3A::from_cols(right, down, forward),
            lens,
            aspect_ratio,
            depth_of_field: crate::camera::DepthOfField::default(),
        });
        Ok(())
    }

    fn light(&mut self, index: usize, world: &Mat4) -> Result<(), GltfError> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| GltfError::invalid(format!("light {index} does not exist")))?;
        let color = Vec3A::from(light.color);
        let value = color * light.intensity;
        if !(value.is_finite() && value.min_element() >= 0.0) {
            return Err(GltfError::invalid(format!(
                "light {index}: colour × intensity {value} must be finite and >= 0"
            )));
        }
        let position = Vec3A::from(world.transform_point3(Vec3::ZERO));
        let direction = Vec3A::from(world.transform_vector3(Vec3::NEG_Z)).normalize_or_zero();
        let kind = valid(&light.type_)
            .ok_or_else(|| GltfError::invalid(format!("light {index}: unknown type")))?;
        if light.range.is_some() {
            self.warn_once(
                "range",
                "glTF light `range` is ignored (inverse-square falloff everywhere)".into(),
            );
        }
        match kind {
            Type::Point => self.point_lights.push((position, value)),
            Type::Directional => {
                if direction == Vec3A::ZERO {
                    return Err(GltfError::invalid(format!(
                        "light {index}: degenerate direction"
                    )));
                }
                self.parts.lights.push(Light::Directional {
                    direction,
                    irradiance: value,
                })
            }
            Type::Spot => {
                let spot = light.spot.as_ref();
                let inner = spot.map_or(0.0, |s| s.inner_cone_angle);
                let outer = spot.map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle);
                if direction == Vec3A::ZERO || !(inner.is_finite() && outer.is_finite()) {
                    return Err(GltfError::invalid(format!(
                        "light {index}: degenerate spot light"
                    )));
                }
                self.parts.lights.push(Light::Spot {
                    position,
                    direction,
                    intensity: value,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                })
            }
        }
        Ok(())
    }

    /// `EXT_mesh_gpu_instancing` on node `node`: one instance of the node's
    /// mesh per element of its TRANSLATION, ROTATION and SCALE accessors, each
    /// at `world` × the element's T·R·S, sharing the mesh as node instances
    /// do. The node's mesh is drawn only through them.
    fn gpu_instances(
        &mut self,
        node: usize,
        ext: &serde_json::Value,
        mesh: usize,
        world: &Mat4,
    ) -> Result<(), GltfError> {
        let what = format!("node {node} EXT_mesh_gpu_instancing");
        let attributes = ext
            .get("attributes")
            .and_then(|a| a.as_object())
            .ok_or_else(|| GltfError::invalid(format!("{what}: no attributes object")))?;
        let index_of = |name: &str| -> Result<Option<usize>, GltfError> {
            let Some(v) = attributes.get(name) else {
                return Ok(None);
            };
            // An integer, also when written as one with a fraction of zero.
            match v.as_u64().or_else(|| {
                v.as_f64()
                    .filter(|f| f.fract() == 0.0 && *f >= 0.0 && *f < u32::MAX as f64)
                    .map(|f| f as u64)
            }) {
                Some(i) => Ok(Some(i as usize)),
                None => Err(GltfError::invalid(format!(
                    "{what}: {name} is not an accessor index"
                ))),
            }
        };
        let (t, r, s) = (
            index_of("TRANSLATION")?,
            index_of("ROTATION")?,
            index_of("SCALE")?,
        );
        let counts: Vec<(&str, u64)> = [("TRANSLATION", t), ("ROTATION", r), ("SCALE", s)]
            .into_iter()
            .filter_map(|(name, a)| a.map(|a| (name, a)))
            .map(|(name, a)| {
                self.root
                    .accessors
                    .get(a)
                    .map(|acc| (name, acc.count.0))
                    .ok_or_else(|| {
                        GltfError::invalid(format!("{what}: {name} accessor {a} does not exist"))
                    })
            })
            .collect::<Result<_, _>>()?;
        let Some(&(_, count)) = counts.first() else {
            return Err(GltfError::invalid(format!(
                "{what}: none of TRANSLATION, ROTATION and SCALE is given"
            )));
        };
        if let Some((name, n)) = counts.iter().find(|(_, n)| *n != count) {
            return Err(GltfError::invalid(format!(
                "{what}: {name} has {n} elements but {} has {count}",
                counts[0].0
            )));
        }
        if let Some(a) = r {
            // read_floats::<4> would take a VEC3 as a colour without alpha.
            let n = valid(&self.root.accessors[a].type_).map(|&t| accessor::type_components(t));
            if n != Some(4) {
                return Err(GltfError::invalid(format!(
                    "{what}: ROTATION accessor {a} is not VEC4"
                )));
            }
        }
        // Each array is checked against the bytes behind it before it is
        // allocated (read_floats), so `count` is backed by the file.
        let read3 = |a: Option<usize>, name: &str| -> Result<Option<Vec<[f32; 3]>>, GltfError> {
            a.map(|a| read_floats::<3>(self.buffers, a, &format!("{what} {name}")))
                .transpose()
        };
        let translations = read3(t, "TRANSLATION")?;
        let scales = read3(s, "SCALE")?;
        let rotations = r
            .map(|a| read_floats::<4>(self.buffers, a, &format!("{what} ROTATION")))
            .transpose()?;
        let count = count as usize;
        for k in 0..count {
            let t = translations
                .as_ref()
                .map_or(Vec3::ZERO, |v| Vec3::from(v[k]));
            let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[k]));
            let q = rotations
                .as_ref()
                .map_or(Quat::IDENTITY, |v| Quat::from_array(v[k]));
            if !(t.is_finite() && s.is_finite() && q.is_finite()) {
                return Err(GltfError::invalid(format!(
                    "{what}: instance {k}'s transform is not finite"
                )));
            }
            // As a node's rotation: normalized, the identity if zero.
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                Quat::IDENTITY
            };
            let before = self.parts.triangles.len();
            let local = Mat4::from_scale_rotation_translation(s, q, t);
            self.mesh_instance(node, mesh, &(*world * local))?;
            let per = self.parts.triangles.len() - before;
            if k == 0 {
                // The first instance read the mesh: the whole count is checked
                // against the ceiling before any more are made (each is also
                // charged to the memory budget as it is made).
                let total = (before as u64).saturating_add(per as u64 * count as u64);
                if total > MAX_TRIANGLES {
                    return Err(GltfError::invalid(format!(
                        "{what}: {count} instances of {per} triangles make more than {MAX_TRIANGLES} triangles"
                    )));
                }
                if per == 0 {
                    // Nothing to place (a mesh of points or lines).
                    break;
                }
            }
        }
        Ok(())
    }

    /// Skin `s`'s joint matrices at the pose (the nodes' global transforms
    /// are made once, for the first skin).
    fn joint_matrices(&mut self, s: usize) -> Result<Vec<Mat4>, GltfError> {
        let (root, pose) = (self.root, self.pose.as_ref());
        let globals = match self.globals.take() {
            Some(g) => g,
            None => skin::node_globals(root, |i| local_transform(&root.nodes[i], i, pose))?,
        };
        let joints = skin::joint_matrices(root, self.buffers, s, &globals);
        self.globals = Some(globals);
        joints
    }

    fn mesh_instance(
        &mut self,
        node: usize,
        mesh_index: usize,
        world: &Mat4,
    ) -> Result<(), GltfError> {
        let mesh = self
            .root
            .meshes
            .get(mesh_index)
            .ok_or_else(|| GltfError::invalid(format!("mesh {mesh_index} does not exist")))?;
        let to_world = Affine3A::from_mat4(*world);
        if !to_world.is_finite() {
            return Err(GltfError::invalid(format!(
                "mesh {mesh_index}'s node transform is not finite"
            )));
        }
        let posed_weights = self.pose.as_ref().and_then(|p| p.weights.get(&node));
        let weights = skin::morph_weights(self.root, node, mesh_index, posed_weights)?;
        let joints = match self.root.nodes[node].skin {
            Some(s) => Some(self.joint_matrices(s.value())?),
            None => None,
        };
        let deformation = skin::Deformation {
            joints: joints.as_deref(),
            weights: &weights,
            node_global: *world,
        };
        for p in 0..mesh.primitives.len() {
            let Some(mut id) = self.primitive(mesh_index, p)? else {
                continue;
            };
            let mut to_world = to_world;
            if deformation.applies_to(&mesh.primitives[p]) {
                id = self.deformed(mesh_index, p, id, &deformation)?;
                if deformation.skins(&mesh.primitives[p]) {
                    // Skinned vertices are in world space already.
                    to_world = Affine3A::IDENTITY;
                }
            }
            let data = &self.parts.meshes[id as usize];
            let first = self.parts.triangles.len();
            if (first + data.indices.len()) as u64 > MAX_TRIANGLES {
                return Err(GltfError::invalid(format!(
                    "the scene has more than {MAX_TRIANGLES} triangles after instancing"
                )));
            }
            // Each instance's triangles are charged before they are made: a
            // small file may instance a big mesh many times.
            self.ledger.charge(
                &self.name,
                Needs {
                    geometry: data.indices.len() as u64 * GEOMETRY_BYTES_PER_TRIANGLE,
                    ..Needs::default()
                },
            )?;
            let instance = Instance::new(id, first as u32, to_world);
            let sign = if instance.mirrors { -1.0 } else { 1.0 };
            let instance_id = self.parts.instances.len() as u32;
            for idx in &data.indices {
                let [a, b, c] = idx.map(|i| instance.point(data.positions[i as usize]));
                self.parts.triangles.push(Triangle::new(a, b, c));
                self.parts
                    .normals
                    .push(sign * (b - a).cross(c - a).normalize_or_zero());
                self.parts.material_of.push(data.material);
                self.parts.instance_of.push(instance_id);
            }
            self.parts.instances.push(instance);
        }
        Ok(())
    }

    /// A copy of mesh data `id` (primitive `p` of mesh `m`) deformed by a
    /// node's skin and morph weights, charged to the budget; its index.
    fn deformed(
        &mut self,
        m: usize,
        p: usize,
        id: u32,
        deformation: &skin::Deformation,
    ) -> Result<u32, GltfError> {
        let base = &self.parts.meshes[id as usize];
        let tangent_set = self.parts.materials[base.material as usize]
            .tangent_set()
            .unwrap_or(0);
        let data = skin::deform(self.buffers, m, p, base, deformation, tangent_set)?;
        self.ledger.charge(
            &self.name,
            Needs {
                geometry: data.memory_bytes() as u64,
                ..Needs::default()
            },
        )?;
        self.parts.meshes.push(data);
        Ok(self.parts.meshes.len() as u32 - 1)
    }

    /// Reads primitive `p` of mesh `m` once (instances share it); `None` when
    /// it is skipped (points, lines).
    fn primitive(&mut self, m: usize, p: usize) -> Result<Option<u32>, GltfError> {
        use json::mesh::{Mode, Semantic};
        if let Some(&id) = self.mesh_ids.get(&(m, p)) {
            return Ok(Some(id));
        }
        let prim = &self.root.meshes[m].primitives[p];
        let what = format!("mesh {m} primitive {p}");
        let mode = *valid(&prim.mode)
            .ok_or_else(|| GltfError::invalid(format!("{what}: unknown mode")))?;
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.warn_once(
                &format!("{mode:?}"),
                format!("skipping primitives of mode {mode:?} (only triangles are rendered)"),
            );
            return Ok(None);
        }
        let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let positions_acc = attr(Semantic::Positions)
            .ok_or_else(|| GltfError::invalid(format!("{what} has no POSITION")))?;
        // Vertices in a buffer with no data at all (no URI, and no GLB chunk
        // for it): a placeholder the glTF-Validator accepts, with nothing to
        // render. (A buffer whose file is missing is an error when read.)
        if let Some(b) = self.buffers.placeholder_of(positions_acc) {
            self.warn_once(
                &format!("placeholder buffer {b}"),
                format!(
                    "skipping the primitives whose vertices lie in buffer {b}, which has no data (no URI and no GLB binary chunk)"
                ),
            );
            return Ok(None);
        }
        let positions: Vec<Vec3> =
            read_floats::<3>(self.buffers, positions_acc, &format!("{what} POSITION"))?
                .into_iter()
                .map(Vec3::from)
                .collect();
        if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
            return Err(GltfError::invalid(format!(
                "{what}: POSITION {i} is not finite (NaN or infinite)"
            )));
        }
        let n = positions.len();
        let read_attr = |name: &str, s: Semantic| -> Result<Option<usize>, GltfError> {
            match attr(s) {
                None => Ok(None),
                Some(a) => {
                    let count = self.root.accessors.get(a).map_or(0, |x| x.count.0);
                    if count != n as u64 {
                        return Err(GltfError::invalid(format!(
                            "{what}: {name} has {count} elements but POSITION has {n}"
                        )));
                    }
                    Ok(Some(a))
                }
            }
        };
        let mut data = MeshData {
            positions,
            ..MeshData::default()
        };
        if let Some(a) = read_attr("NORMAL", Semantic::Normals)? {
            data.normals = read_floats::<3>(self.buffers, a, &format!("{what} NORMAL"))?
                .into_iter()
                .map(|v| Vec3::from(v).normalize_or_zero())
                .collect();
            if data.normals.iter().any(|v| !v.is_finite()) {
                data.normals.clear();
            }
        }
        for set in 0..2u32 {
            if let Some(a) = read_attr(&format!("TEXCOORD_{set}"), Semantic::TexCoords(set))? {
                data.uvs[set as usize] =
                    read_floats::<2>(self.buffers, a, &format!("{what} TEXCOORD_{set}"))?
                        .into_iter()
                        .map(|v| {
                            let v = Vec2::from(v);
                            if v.is_finite() { v } else { Vec2::ZERO }
                        })
                        .collect();
            }
        }
        if let Some(a) = read_attr("COLOR_0", Semantic::Colors(0))? {
            data.colors = read_floats::<4>(self.buffers, a, &format!("{what} COLOR_0"))?
                .into_iter()
                .map(|v| Vec4::from(v).clamp(Vec4::ZERO, Vec4::ONE))
                .collect();
        }
        // Triangles from the index list (or 0..n) by the primitive's mode.
        let indices = match prim.indices {
            Some(a) => read_indices(self.buffers, a.value(), &format!("{what} indices"))?,
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(GltfError::invalid(format!(
                "{what}: index {bad} is out of range (the primitive has {n} vertices)"
            )));
        }
        data.indices = match mode {
            Mode::Triangles => indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    // glTF: p_i = {v_i, v_(i+(1+i%2)), v_(i+(2−i%2))}.
                    let k = i % 2;
                    [indices[i], indices[i + 1 + k], indices[i + 2 - k]]
                })
                .collect(),
            _ => (0..indices.len().saturating_sub(2))
                // glTF: p_i = {v_(i+1), v_(i+2), v_0}.
                .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
                .collect(),
        };
        data.material = self.material(self.primitive_material(prim, &what)?)?;
        let material = &self.parts.materials[data.material as usize];
        if let Some(set) = material.tangent_set() {
            data.tangents = match read_attr("TANGENT", Semantic::Tangents)? {
                Some(a) => Tangents::PerVertex(
                    read_floats::<4>(self.buffers, a, &format!("{what} TANGENT"))?
                        .into_iter()
                        .map(Vec4::from)
                        .collect(),
                ),
                None if !data.uvs[set.min(1)].is_empty() => tangents::generate(&data, set.min(1)),
                None => Tangents::None,
            };
        }
        if matches!(data.tangents, Tangents::None) && material.has_anisotropy() {
            // The specification requires tangents (or a normal map's UVs to
            // make them from); without them there is no direction.
            self.warn_once(
                &format!("{ANISOTROPY} {what}"),
                format!(
                    "{what}: its material is anisotropic ({ANISOTROPY}) but the \
                     primitive has neither TANGENT nor texture coordinates: rendered isotropic"
                ),
            );
        }
        let id = self.parts.meshes.len() as u32;
        self.parts.meshes.push(data);
        self.mesh_ids.insert((m, p), id);
        Ok(Some(id))
    }

    /// The glTF material a primitive shows: its own, or the one its
    /// `KHR_materials_variants` mappings give the variant shown.
    fn primitive_material(
        &self,
        prim: &json::mesh::Primitive,
        what: &str,
    ) -> Result<Option<usize>, GltfError> {
        let own = prim.material.map(|m| m.value());
        let Some(mappings) = prim
            .extensions
            .as_ref()
            .and_then(|e| e.khr_materials_variants.as_ref())
        else {
            return Ok(own);
        };
        let mut shown = own;
        for mapping in &mappings.mappings {
            if let Some(&v) = mapping
                .variants
                .iter()
                .find(|&&v| v as usize >= self.variant_count)
            {
                return Err(GltfError::invalid(format!(
                    "{what}: a KHR_materials_variants mapping names variant {v}, but the file defines {}",
                    self.variant_count
                )));
            }
            if let Some(k) = self.variant
                && mapping.variants.contains(&(k as u32))
            {
                shown = Some(mapping.material as usize);
            }
        }
        Ok(shown)
    }

    /// The table index of glTF material `index` (None: the default material).
    fn material(&mut self, index: Option<usize>) -> Result<u32, GltfError> {
        if let Some(&id) = self.material_ids.get(&index) {
            return Ok(id);
        }
        let material = match index {
            None => SurfaceMaterial {
                name: "default".into(),
                reflectance: Vec3A::ONE,
                kind: MaterialKind::Gltf(Box::default()),
                emission: Vec3A::ZERO,
                emission_texture: None,
                emits_both_sides: false,
                alpha: AlphaMode::Opaque,
            },
            Some(i) => self.convert_material(i)?,
        };
        let id = self.parts.materials.len() as u32;
        self.parts.materials.push(material);
        self.material_ids.insert(index, id);
        Ok(id)
    }

    fn convert_material(&mut self, i: usize) -> Result<SurfaceMaterial, GltfError> {
        use json::material::AlphaMode as Mode;
        let m = self
            .root
            .materials
            .get(i)
            .ok_or_else(|| GltfError::invalid(format!("material {i} does not exist")))?;
        let what = format!("material {i}");
        let pbr = &m.pbr_metallic_roughness;
        let ext = m.extensions.as_ref();
        if let Some(e) = ext {
            for name in e.others.keys() {
                let read = [
                    CLEARCOAT,
                    SHEEN,
                    DISPERSION,
                    IRIDESCENCE,
                    ANISOTROPY,
                    DIFFUSE_TRANSMISSION,
                ];
                if !read.contains(&name.as_str()) {
                    self.warn_once(name, format!("ignoring the material extension {name}"));
                }
            }
        }
        let finite = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(GltfError::invalid(format!("{what}: {name} is not finite")))
            }
        };
        let alpha = match valid(&m.alpha_mode) {
            Some(Mode::Opaque) | None => AlphaMode::Opaque,
            Some(Mode::Mask) => AlphaMode::Mask(m.alpha_cutoff.map_or(0.5, |c| c.0)),
            Some(Mode::Blend) => AlphaMode::Blend,
        };
        if ext.is_some_and(|e| e.unlit.is_some()) {
            // KHR_materials_unlit: the base colour and alpha only; the rest is
            // the fallback for viewers without the extension, and its textures
            // are not decoded. (With another shading model's extension the
            // result is undefined; unlit wins.)
            let g = GltfMaterial {
                base_color: Vec4::from(pbr.base_color_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                base_color_texture: self.texture(pbr.base_color_texture.as_ref(), &what)?,
                ..GltfMaterial::default()
            };
            return Ok(SurfaceMaterial {
                name: m.name.clone().unwrap_or_default(),
                reflectance: Vec3A::from(g.base_color.truncate()),
                kind: MaterialKind::Unlit(Box::new(g)),
                emission: Vec3A::ZERO,
                emission_texture: None,
                emits_both_sides: m.double_sided,
                alpha,
            });
        }
        let spec_gloss = ext.and_then(|e| e.pbr_specular_glossiness.as_ref());
        let mut g = match spec_gloss {
            // The specular–glossiness parameters replace the metallic–roughness
            // ones, whose textures are then not decoded.
            Some(sg) => {
                let specular = Vec3A::from(sg.specular_factor.0);
                if !specular.is_finite() {
                    return Err(GltfError::invalid(format!(
                        "{what}: specularFactor is not finite"
                    )));
                }
                GltfMaterial {
                    base_color: Vec4::from(sg.diffuse_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                    base_color_texture: self.texture(sg.diffuse_texture.as_ref(), &what)?,
                    metallic: 0.0,
                    specular_glossiness: Some(SpecularGlossiness {
                        specular: specular.clamp(Vec3A::ZERO, Vec3A::ONE),
                        glossiness: finite(sg.glossiness_factor.0, "glossinessFactor")?
                            .clamp(0.0, 1.0),
                        texture: self.texture(sg.specular_glossiness_texture.as_ref(), &what)?,
                    }),
                    ..GltfMaterial::default()
                }
            }
            None => GltfMaterial {
                base_color: Vec4::from(pbr.base_color_factor.0).clamp(Vec4::ZERO, Vec4::ONE),
                base_color_texture: self.texture(pbr.base_color_texture.as_ref(), &what)?,
                metallic: finite(pbr.metallic_factor.0, "metallicFactor")?.clamp(0.0, 1.0),
                roughness: finite(pbr.roughness_factor.0, "roughnessFactor")?.clamp(0.0, 1.0),
                metallic_roughness_texture: self
                    .texture(pbr.metallic_roughness_texture.as_ref(), &what)?,
                ..GltfMaterial::default()
            },
        };
        if let Some(n) = &m.normal_texture {
            g.normal_texture = self.normal_texture(n, &what)?;
            g.normal_scale = finite(n.scale, "normalTexture.scale")?;
        }
        if let Some(e) = ext {
            if let Some(ior) = &e.ior {
                let v = finite(ior.ior.0, "ior")?;
                // glTF: ior 0 means an infinitely dense (fully reflective) medium; keep sane.
                g.ior = if v == 0.0 { 1e4 } else { v.max(1.0) };
            }
            if let Some(s) = &e.specular {
                g.specular = finite(s.specular_factor.0, "specularFactor")?.clamp(0.0, 1.0);
                g.specular_texture = self.texture(s.specular_texture.as_ref(), &what)?;
                g.specular_color = Vec3A::from(s.specular_color_factor.0).max(Vec3A::ZERO);
                g.specular_color_texture =
                    self.texture(s.specular_color_texture.as_ref(), &what)?;
            }
            if let Some(t) = &e.transmission {
                g.transmission =
                    finite(t.transmission_factor.0, "transmissionFactor")?.clamp(0.0, 1.0);
                g.transmission_texture = self.texture(t.transmission_texture.as_ref(), &what)?;
            }
            if let Some(v) = &e.volume {
                g.thin_walled = v.thickness_factor.0.is_nan() || v.thickness_factor.0 <= 0.0;
                let color =
                    Vec3A::from(v.attenuation_color.0).clamp(Vec3A::splat(1e-6), Vec3A::ONE);
                let distance = v.attenuation_distance.0;
                if distance.is_finite() && distance > 0.0 {
                    g.attenuation =
                        -Vec3A::new(color.x.ln(), color.y.ln(), color.z.ln()) / distance;
                }
            }
        }
        if let Some(value) = ext.and_then(|e| e.others.get(CLEARCOAT)) {
            self.clearcoat(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(SHEEN)) {
            self.sheen(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(DISPERSION)) {
            let d: Dispersion = serde_json::from_value(value.clone())
                .map_err(|e| GltfError::invalid(format!("{what}: {DISPERSION}: {e}")))?;
            // Any value from 0 up is valid (above 1 exaggerates); a negative
            // one, outside the schema, reads as none.
            g.dispersion = finite(d.dispersion, "dispersion")?.max(0.0);
        }
        if let Some(value) = ext.and_then(|e| e.others.get(IRIDESCENCE)) {
            self.iridescence(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(ANISOTROPY)) {
            self.anisotropy(value, &mut g, &what)?;
        }
        if let Some(value) = ext.and_then(|e| e.others.get(DIFFUSE_TRANSMISSION)) {
            self.diffuse_transmission(value, &mut g, &what)?;
        }
        let strength = ext
            .and_then(|e| e.emissive_strength.as_ref())
            .map_or(1.0, |s| s.emissive_strength.0);
        let emission = Vec3A::from(m.emissive_factor.0) * finite(strength, "emissiveStrength")?;
        if !(emission.is_finite() && emission.min_element() >= 0.0) {
            return Err(GltfError::invalid(format!(
                "{what}: emission {emission} must be finite and >= 0"
            )));
        }
        let emission_texture = self.texture(m.emissive_texture.as_ref(), &what)?;
        Ok(SurfaceMaterial {
            name: m.name.clone().unwrap_or_default(),
            reflectance: Vec3A::from(g.base_color.truncate()),
            kind: MaterialKind::Gltf(Box::new(g)),
            emission,
            emission_texture,
            emits_both_sides: m.double_sided,
            alpha,
        })
    }

    /// Reads `KHR_materials_clearcoat` (`value`, the extension's object) into
    /// `g`.
    fn clearcoat(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let c: Clearcoat = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {CLEARCOAT}: {e}")))?;
        let unit = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v.clamp(0.0, 1.0))
            } else {
                Err(GltfError::invalid(format!(
                    "{what}: {CLEARCOAT}: {name} is not finite"
                )))
            }
        };
        g.clearcoat = unit(c.clearcoat_factor, "clearcoatFactor")?;
        g.clearcoat_roughness = unit(c.clearcoat_roughness_factor, "clearcoatRoughnessFactor")?;
        g.clearcoat_texture = self.texture(c.clearcoat_texture.as_ref(), what)?;
        g.clearcoat_roughness_texture =
            self.texture(c.clearcoat_roughness_texture.as_ref(), what)?;
        if let Some(n) = &c.clearcoat_normal_texture {
            g.clearcoat_normal_texture = self.normal_texture(n, what)?;
            if !n.scale.is_finite() {
                return Err(GltfError::invalid(format!(
                    "{what}: {CLEARCOAT}: clearcoatNormalTexture.scale is not finite"
                )));
            }
            g.clearcoat_normal_scale = n.scale;
        }
        Ok(())
    }

    /// Reads `KHR_materials_sheen` (`value`, the extension's object) into `g`.
    fn sheen(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let s: Sheen = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {SHEEN}: {e}")))?;
        let color = Vec3A::from(s.sheen_color_factor);
        if !color.is_finite() {
            return Err(GltfError::invalid(format!(
                "{what}: {SHEEN}: sheenColorFactor is not finite"
            )));
        }
        if !s.sheen_roughness_factor.is_finite() {
            return Err(GltfError::invalid(format!(
                "{what}: {SHEEN}: sheenRoughnessFactor is not finite"
            )));
        }
        g.sheen_color = color.clamp(Vec3A::ZERO, Vec3A::ONE);
        g.sheen_roughness = s.sheen_roughness_factor.clamp(0.0, 1.0);
        g.sheen_color_texture = self.texture(s.sheen_color_texture.as_ref(), what)?;
        g.sheen_roughness_texture = self.texture(s.sheen_roughness_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_iridescence` (`value`, the extension's object)
    /// into `g`: a value that is not finite is refused; out of the schema's
    /// ranges, the factor is clamped to `[0, 1]`, the index to at least 1 and
    /// the thicknesses to `[0, 1 mm]` (see
    /// [`MAX_THICKNESS_NM`](crate::materials::thin_film::MAX_THICKNESS_NM)).
    fn iridescence(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        use crate::materials::thin_film::MAX_THICKNESS_NM;
        let f: Iridescence = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {IRIDESCENCE}: {e}")))?;
        let finite = |v: f32, name: &str| -> Result<f32, GltfError> {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(GltfError::invalid(format!(
                    "{what}: {IRIDESCENCE}: {name} is not finite"
                )))
            }
        };
        g.iridescence = finite(f.iridescence_factor, "iridescenceFactor")?.clamp(0.0, 1.0);
        g.iridescence_ior = finite(f.iridescence_ior, "iridescenceIor")?.max(1.0);
        let thickness = |v: f32, name: &str| -> Result<f32, GltfError> {
            Ok(finite(v, name)?.clamp(0.0, MAX_THICKNESS_NM))
        };
        g.iridescence_thickness_min = thickness(
            f.iridescence_thickness_minimum,
            "iridescenceThicknessMinimum",
        )?;
        g.iridescence_thickness_max = thickness(
            f.iridescence_thickness_maximum,
            "iridescenceThicknessMaximum",
        )?;
        g.iridescence_texture = self.texture(f.iridescence_texture.as_ref(), what)?;
        g.iridescence_thickness_texture =
            self.texture(f.iridescence_thickness_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_anisotropy` (`value`, the extension's object)
    /// into `g`: the strength clamped to `[0, 1]`, the rotation as its
    /// cosine and sine; a non-finite number is refused.
    fn anisotropy(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let a: Anisotropy = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {ANISOTROPY}: {e}")))?;
        for (v, name) in [
            (a.anisotropy_strength, "anisotropyStrength"),
            (a.anisotropy_rotation, "anisotropyRotation"),
        ] {
            if !v.is_finite() {
                return Err(GltfError::invalid(format!(
                    "{what}: {ANISOTROPY}: {name} is not finite"
                )));
            }
        }
        g.anisotropy_strength = a.anisotropy_strength.clamp(0.0, 1.0);
        let (sin, cos) = a.anisotropy_rotation.sin_cos();
        g.anisotropy_rotation = Vec2::new(cos, sin);
        g.anisotropy_texture = self.texture(a.anisotropy_texture.as_ref(), what)?;
        Ok(())
    }

    /// Reads `KHR_materials_diffuse_transmission` (`value`, the extension's
    /// object) into `g`: factors that are not finite are refused, the
    /// factor is clamped to `[0, 1]` and the colour to `[0, 1]` per channel
    /// (as the base colour is: the diffuse part reflects and transmits at
    /// most what it receives).
    fn diffuse_transmission(
        &mut self,
        value: &serde_json::Value,
        g: &mut GltfMaterial,
        what: &str,
    ) -> Result<(), GltfError> {
        let d: DiffuseTransmission = serde_json::from_value(value.clone())
            .map_err(|e| GltfError::invalid(format!("{what}: {DIFFUSE_TRANSMISSION}: {e}")))?;
        let not_finite = |name: &str| {
            GltfError::invalid(format!(
                "{what}: {DIFFUSE_TRANSMISSION}: {name} is not finite"
            ))
        };
        if !d.diffuse_transmission_factor.is_finite() {
            return Err(not_finite("diffuseTransmissionFactor"));
        }
        let color = Vec3A::from(d.diffuse_transmission_color_factor);
        if !color.is_finite() {
            return Err(not_finite("diffuseTransmissionColorFactor"));
        }
        g.diffuse_transmission = d.diffuse_transmission_factor.clamp(0.0, 1.0);
        g.diffuse_transmission_color = color.clamp(Vec3A::ZERO, Vec3A::ONE);
        g.diffuse_transmission_texture =
            self.texture(d.diffuse_transmission_texture.as_ref(), what)?;
        g.diffuse_transmission_color_texture =
            self.texture(d.diffuse_transmission_color_texture.as_ref(), what)?;
        Ok(())
    }

    /// A normal map's texture reference (as [`Self::texture`]; its
    /// `KHR_texture_transform` is among the extensions `gltf-json` keeps as
    /// JSON for normal textures).
    fn normal_texture(
        &mut self,
        n: &json::material::NormalTexture,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let transform = n
            .extensions
            .as_ref()
            .and_then(|e| e.others.get("KHR_texture_transform"))
            .and_then(|v| serde_json::from_value(v.clone()).ok());
        self.texture_parts(n.index.value(), n.tex_coord, transform.as_ref(), what)
    }

    /// A texture reference: its image (queued for decoding), sampler, texture
    /// coordinate set and transform.
    fn texture(
        &mut self,
        info: Option<&json::texture::Info>,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let Some(info) = info else {
            return Ok(None);
        };
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        self.texture_parts(info.index.value(), info.tex_coord, transform, what)
    }

    fn texture_parts(
        &mut self,
        t: usize,
        tex_coord: u32,
        transform: Option<&json::extensions::texture::TextureTransform>,
        what: &str,
    ) -> Result<Option<TextureRef>, GltfError> {
        let texture = self
            .root
            .textures
            .get(t)
            .ok_or_else(|| GltfError::invalid(format!("{what}: texture {t} does not exist")))?;
        let (mut wrap_s, mut wrap_t) = (Wrap::Repeat, Wrap::Repeat);
        if let Some(s) = texture.sampler {
            let sampler = self.root.samplers.get(s.value()).ok_or_else(|| {
                GltfError::invalid(format!("texture {t}: sampler {} does not exist", s.value()))
            })?;
            let wrap = |w: &Checked<json::texture::WrappingMode>| match w {
                Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
                Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
                _ => Wrap::Repeat,
            };
            wrap_s = wrap(&sampler.wrap_s);
            wrap_t = wrap(&sampler.wrap_t);
        }
        // `KHR_texture_basisu`'s KTX2 image or `EXT_texture_webp`'s WebP
        // image where the texture names one (raylab decodes both; the
        // extension's image wins over the core one, as both specifications
        // say), else the core `source` (range-checked below).
        let extension_image = |ext: &str| {
            texture
                .extensions
                .as_ref()
                .and_then(|e| e.others.get(ext))
                .and_then(|w| w.get("source"))
                .and_then(serde_json::Value::as_u64)
                .map(|s| usize::try_from(s).unwrap_or(usize::MAX))
        };
        let basisu = extension_image(BASISU);
        let image = basisu
            .or_else(|| extension_image("EXT_texture_webp"))
            .unwrap_or(texture.source.value());
        if image >= self.root.images.len() {
            return Err(GltfError::invalid(format!(
                "texture {t}: image {image} does not exist"
            )));
        }
        let id = match self.image_ids.get(&image) {
            Some(&id) => id,
            None => {
                let id = self.image_sources.len() as u32;
                let uri = self.root.images[image]
                    .uri
                    .clone()
                    .filter(|u| !u.starts_with("data:"));
                // A KTX2 image's errors name its index, file and extension.
                let name = match (basisu, uri) {
                    (Some(_), Some(uri)) => format!("image {image} ({uri}, {BASISU})"),
                    (Some(_), None) => format!("image {image} ({BASISU})"),
                    (None, uri) => uri.unwrap_or_else(|| format!("image {image}")),
                };
                self.image_sources.push((name, image));
                self.image_ids.insert(image, id);
                id
            }
        };
        let mut tex_coord = tex_coord;
        let mut transform_out = TextureTransform::default();
        if let Some(tt) = transform {
            transform_out = TextureTransform {
                offset: Vec2::from(tt.offset.0),
                rotation: tt.rotation.0,
                scale: Vec2::from(tt.scale.0),
            };
            if let Some(tc) = tt.tex_coord {
                tex_coord = tc;
            }
        }
        if tex_coord > 1 {
            self.warn_once(
                "texcoord",
                format!("{what}: texture coordinate sets above 1 are not read; using set 1"),
            );
        }
        Ok(Some(TextureRef {
            image: id,
            wrap_s,
            wrap_t,
            tex_coord: tex_coord.min(1) as u8,
            transform: transform_out,
        }))
    }

    /// Reads and decodes the queued images (in parallel), picks the key light,
    /// and returns the parts.
    fn finish(mut self) -> Result<GltfScene, GltfError> {
        let mut sources = Vec::with_capacity(self.image_sources.len());
        for (name, image) in &self.image_sources {
            let img = &self.root.images[*image];
            let bytes = match (&img.uri, img.buffer_view) {
                (Some(uri), _) => read_uri(
                    uri,
                    self.base,
                    &format!("image {image}"),
                    self.ledger,
                    &mut 0,
                )?,
                (None, Some(view)) => {
                    let (bytes, _) = self
                        .buffers
                        .view(view.value())
                        .map_err(|e| GltfError::invalid(format!("image {image}: {e}")))?;
                    bytes.to_vec()
                }
                (None, None) => {
                    return Err(GltfError::invalid(format!(
                        "image {image} has neither a URI nor a buffer view"
                    )));
                }
            };
            sources.push((name.clone(), bytes));
        }
        self.parts.textures = TextureStore::decode_all_within(sources, self.ledger, &self.name)
            .map_err(|e| match e {
                TextureError::Memory(m) => GltfError::Memory(m),
                e => GltfError::invalid(e.to_string()),
            })?;
        let has_punctual_lights = !self.point_lights.is_empty() || !self.parts.lights.is_empty();
        let mut points = self.point_lights.into_iter();
        if let Some((position, intensity)) = points.next() {
            self.parts.light = PointLight {
                position,
                power: intensity * (4.0 * std::f32::consts::PI),
            };
        }
        let rest: Vec<Light> = points
            .map(|(position, intensity)| Light::Point {
                position,
                intensity,
            })
            .collect();
        self.parts.lights.splice(0..0, rest);
        if self.parts.instance_of.iter().all(|&i| i == NO_INSTANCE) {
            self.parts.instance_of.clear();
        }
        Ok(GltfScene {
            parts: self.parts,
            has_punctual_lights,
            variants: Vec::new(),
            variant: None,
            warnings: self.warnings,
            animations: (self.root.animations.iter())
                .map(|a| a.name.clone().unwrap_or_default())
                .collect(),
        })
    }
}

/// The value of a field the JSON parser could read, `None` for an invalid one.
pub(crate) fn valid<T>(c: &Checked<T>) -> Option<&T> {
    match c {
        Checked::Valid(v) => Some(v),
        Checked::Invalid => None,
    }
}

/// A node's local transform: its matrix, or T·R·S (each of them the pose's
/// if it animates them).
fn local_transform(
    node: &json::Node,
    index: usize,
    pose: Option<&Pose>,
) -> Result<Mat4, GltfError> {
    let m = if let Some(m) = node.matrix {
        Mat4::from_cols_array(&m)
    } else {
        let t = pose
            .and_then(|p| p.translation.get(&index).copied())
            .unwrap_or_else(|| Vec3::from(node.translation.unwrap_or([0.0; 3])));
        let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
        let s = pose
            .and_then(|p| p.scale.get(&index).copied())
            .unwrap_or_else(|| Vec3::from(node.scale.unwrap_or([1.0; 3])));
        let q = pose
            .and_then(|p| p.rotation.get(&index).copied())
            .unwrap_or_else(|| Quat::from_array(r));
        let q = if q.length_squared() > 0.0 {
            q.normalize()
        } else {
            Quat::IDENTITY
        };
        Mat4::from_scale_rotation_translation(s, q, t)
    };
    if !m.is_finite() {
        return Err(GltfError::invalid(format!(
            "node {index}'s transform is not finite"
        )));
    }
    Ok(m)
}
