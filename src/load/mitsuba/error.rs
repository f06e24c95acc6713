//! Why a Mitsuba scene cannot be read ([`MitsubaError`]): one line naming
//! the file and, where the reader knows it, the line.

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::guard::one_line;

/// Why a Mitsuba XML scene (or a file it includes) cannot be read; the
/// message is one line that starts with the file and, for anything inside
/// the XML, its line (`scene.xml:12: …`).
#[derive(Debug, Error)]
pub enum MitsubaError {
    /// The file could not be opened or read.
    #[error("{}: {cause}", one_line(&path.display().to_string()))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        cause: std::io::Error,
    },
    /// Something at a line of the file is wrong: malformed XML, an unknown
    /// element, a missing or unexpected attribute, a bad value, an unknown
    /// `$name` or id, a missing or cyclic include…
    #[error("{}:{line}: {message}", one_line(&path.display().to_string()))]
    At {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u32,
        /// What is wrong (one line; names quoted from the file are escaped).
        message: String,
    },
    /// A mesh file (`ply`, `serialized`) cannot be read: malformed,
    /// truncated, or beyond a limit. The message names the element or shape
    /// (`bunny.ply: face 12: vertex index 900 out of range (453 vertices)`).
    #[error("{}: {message}", one_line(&path.display().to_string()))]
    Mesh {
        /// The mesh file.
        path: PathBuf,
        /// What is wrong (one line).
        message: String,
    },
    /// A mesh file's header asks for more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
    /// Something about the whole scene is wrong (a `-D` definition that no
    /// attribute uses).
    #[error("{}: {message}", one_line(&path.display().to_string()))]
    Scene {
        /// The scene's main file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl MitsubaError {
    /// An error at `line` of `path`; `message` is made one line.
    pub(super) fn at(path: &Path, line: u32, message: impl AsRef<str>) -> Self {
        MitsubaError::At {
            path: path.to_owned(),
            line,
            message: one_line(message.as_ref()).into_owned(),
        }
    }

    /// An error reading the mesh file `path`; `message` is made one line.
    pub(super) fn mesh(path: &Path, message: impl AsRef<str>) -> Self {
        MitsubaError::Mesh {
            path: path.to_owned(),
            message: one_line(message.as_ref()).into_owned(),
        }
    }

    /// The same error, saying which `<include>` led to it (`(included from
    /// main.xml:7)`, replacing an inner one), so that an error deep in an
    /// included file still tells where to look in the file the user named.
    pub(super) fn included_from(self, path: &Path, line: u32) -> Self {
        let from = format!(
            " (included from {}:{line})",
            one_line(&path.display().to_string())
        );
        match self {
            MitsubaError::At {
                path: p,
                line: l,
                mut message,
            } => {
                // Only the outermost include is named: the line of the file
                // the user gave.
                if let Some(cut) = message.find(" (included from ") {
                    message.truncate(cut);
                }
                message.push_str(&from);
                MitsubaError::At {
                    path: p,
                    line: l,
                    message,
                }
            }
            MitsubaError::Io { path: p, cause } => MitsubaError::At {
                path: path.to_owned(),
                line,
                message: format!("<include>: {}: {cause}", one_line(&p.display().to_string())),
            },
            other => other,
        }
    }
}
