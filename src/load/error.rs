//! Why a scene cannot be loaded ([`LoadError`]): each loader's own error,
//! and what the options and the scene's content can get wrong.

use thiserror::Error;

use super::gltf::GltfError;
use super::mitsuba::MitsubaError;
use super::obj::ObjError;
use super::shot::error::ShotError;
use crate::lights::environment::EnvError;
use crate::memory::MemoryError;
use crate::scene::SceneError;

/// Why a scene cannot be loaded; the message names the file.
#[derive(Debug, Error)]
pub enum LoadError {
    /// A Wavefront OBJ file is unreadable or malformed.
    #[error(transparent)]
    Obj(#[from] ObjError),
    /// A glTF file is unreadable or malformed.
    #[error(transparent)]
    Gltf(#[from] GltfError),
    /// A Mitsuba XML scene is unreadable or malformed.
    #[error(transparent)]
    Mitsuba(#[from] MitsubaError),
    /// The scene's content is invalid.
    #[error("{name}: {cause}")]
    Scene {
        /// The scene.
        name: String,
        /// What is wrong.
        cause: SceneError,
    },
    /// The name is neither a built-in scene nor a known file type.
    #[error(
        "scene '{0}': unknown scene (built in: cornell, cornell-area; or a Wavefront .obj, glTF .gltf or .glb file)"
    )]
    Unknown(String),
    /// An option does not fit the scene.
    #[error("{0}")]
    Usage(String),
    /// An environment map is unreadable or malformed.
    #[error(transparent)]
    Env(#[from] EnvError),
    /// A scene file is unreadable, malformed or inconsistent.
    #[error(transparent)]
    Shot(#[from] ShotError),
    /// The scene would need more memory than [`LoadOptions::max_memory`](super::LoadOptions::max_memory).
    #[error(transparent)]
    Memory(#[from] MemoryError),
}
