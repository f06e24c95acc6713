//! Reading a glTF or GLB file: the entry points ([`load_gltf`] and the forms
//! that take a memory budget, a material variant and a pose), and the order
//! of one load: the document and its required extensions, the variants, the
//! buffers (meshopt views and Draco primitives decoded into buffers of their
//! own), the animation's pose, then the [`Loader`]'s walk of the default
//! scene.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::animation::{self, AnimationOptions};
use super::buffers::{Buffers, load_buffers, read_file};
use super::document::{SUPPORTED_EXTENSIONS, parse_root, split_glb};
use super::error::GltfError;
use super::loader::{GltfScene, Loader};
use super::{draco, meshopt, pointer};
use crate::memory::{Ledger, Needs};
use crate::scene::SceneParts;

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

/// [`load_gltf_posed`] without the file's name in its messages.
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

/// The variants a file has, for a message: "variants: a, b, c" or "the file
/// has no material variants".
pub fn variant_list(variants: &[String]) -> String {
    if variants.is_empty() {
        "the file has no material variants".into()
    } else {
        format!("variants: {}", variants.join(", "))
    }
}
