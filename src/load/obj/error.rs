//! Why an OBJ file (or one of its MTL libraries) cannot be read.

use std::path::PathBuf;

use thiserror::Error;

/// Why a mesh file could not be read; the message names the file and the line.
#[derive(Debug, Error)]
pub enum ObjError {
    /// The file could not be opened or read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said (in the message, so not also a `source`, which
        /// would print it twice in the command line's one-line error).
        cause: std::io::Error,
    },
    /// A line is malformed.
    #[error("{path}:{line}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file holds no triangles.
    #[error("{path}: no triangles (no 'f' lines with three or more vertices)")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A texture could not be decoded.
    #[error("{0}")]
    Texture(String),
    /// The scene would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}
