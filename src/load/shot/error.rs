//! Why a scene file cannot be used ([`ShotError`]: the file, and the line
//! and column where the parser knows them), and the checks of values that
//! say so.

use std::path::{Path, PathBuf};

use thiserror::Error;

/// Why a scene file cannot be used; the message starts with the file (and the
/// line and column where the parser knows them).
#[derive(Debug, Error)]
pub enum ShotError {
    /// The file could not be read.
    #[error("{}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        cause: std::io::Error,
    },
    /// The TOML is malformed, or a key is unknown or has the wrong type.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A value is out of range or the parts do not fit together.
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the section.
        message: String,
    },
}

/// A scene-file error; names quoted from the file (which may hold a newline)
/// are escaped, so that the message stays one line.
pub(super) fn invalid(path: &Path, message: String) -> ShotError {
    ShotError::Invalid {
        path: path.to_owned(),
        message: crate::guard::one_line(&message).into_owned(),
    }
}

/// Checks that every number of a list is finite (and `>= 0` if `non_negative`).
pub(super) fn check(
    path: &Path,
    what: &str,
    values: &[f32],
    non_negative: bool,
) -> Result<(), ShotError> {
    for &v in values {
        if !v.is_finite() || (non_negative && v < 0.0) {
            let need = if non_negative {
                "finite and >= 0"
            } else {
                "finite"
            };
            return Err(invalid(path, format!("{what}: {v} (must be {need})")));
        }
    }
    Ok(())
}
