//! glTF 2.0 scenes (`.gltf` with external or data-URI buffers and images, and
//! `.glb`), read into [`SceneParts`](crate::scene::SceneParts) following
//! `docs/scene-conventions.md`.
//!
//! The JSON is parsed by `gltf-json` (plain serde structures, no validation
//! pass that could index out of range); every reference, count, offset and
//! stride is checked here before use, so a bad file is refused with one line
//! naming it and what is wrong, never a panic or an allocation sized by an
//! unchecked number.
//!
//! The files, each of which imports only from files after it in this list
//! (`mod.rs` only declares them and re-exports the public items):
//!
//! * `load.rs`: the entry points ([`load_gltf`] and its forms) and the order
//!   of a load;
//! * the `Loader`'s methods, by what they read: `nodes.rs` (the node tree,
//!   node transforms, visibility and the instances placed at the nodes),
//!   `mesh.rs` (primitives), `material.rs` (materials and their extensions),
//!   `texture.rs` (texture references and images), `camera.rs`, `lights.rs`;
//! * `loader.rs`: the `Loader`'s state and `finish`, which decodes the images
//!   and returns the [`GltfScene`];
//! * [`animation`] (poses at a time) and `skin.rs` (skins and morph targets);
//! * `document.rs`: GLB chunks, the JSON and the forms of it tolerated, the
//!   [`SUPPORTED_EXTENSIONS`];
//! * [`draco`], [`accessor`] (typed reads of accessors), `buffers.rs` (files,
//!   buffers and views), [`meshopt`], `tangents.rs` (MikkTSpace);
//! * `error.rs`: [`GltfError`] and what every file shares.

pub mod accessor;
pub mod animation;
mod buffers;
mod camera;
mod document;
pub mod draco;
mod error;
mod lights;
mod load;
mod loader;
mod material;
mod mesh;
pub mod meshopt;
mod nodes;
pub(crate) mod object_model;
pub(crate) mod pointer;
pub(crate) mod skin;
pub(crate) mod tangents;
mod texture;

pub use animation::{
    AT_EXPECTED, AnimationChoice, AnimationOptions, AnimationSummary, MAX_AT, MAX_FPS, at_in_range,
    fps_in_range,
};
pub use buffers::{MAX_FILE_BYTES, decode_base64};
pub use document::SUPPORTED_EXTENSIONS;
pub use error::{GltfError, MAX_NODE_DEPTH};
pub use load::{
    VariantChoice, load_gltf, load_gltf_posed, load_gltf_variant, load_gltf_with, variant_list,
};
pub use loader::GltfScene;
pub use nodes::MAX_TRIANGLES;
