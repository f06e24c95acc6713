//! What every file of the loader shares: [`GltfError`], the deepest node
//! hierarchy accepted, and [`valid`], which reads a field `gltf-json` could
//! parse.

use std::path::PathBuf;

use gltf::json::validation::Checked;
use thiserror::Error;

/// Deepest node hierarchy accepted.
pub const MAX_NODE_DEPTH: usize = 1024;

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

/// The value of a field the JSON parser could read, `None` for an invalid one.
pub(crate) fn valid<T>(c: &Checked<T>) -> Option<&T> {
    match c {
        Checked::Valid(v) => Some(v),
        Checked::Invalid => None,
    }
}
