//! Scene files ("shots"): a small TOML format that composes a whole picture —
//! models (glTF, OBJ, the built-in boxes) with transforms and material
//! overrides, lights, the environment, the camera and render settings — so
//! that it renders the same way every time. README.md documents the format;
//! `scenes/` has examples.
//!
//! Every key is checked: a key the format does not know is an error with its
//! line and column (the parser's spans). Paths are relative to the file.
//!
//! The files, from the bottom up: `error.rs` (the errors and the checks that
//! make them), `schema.rs` (the TOML as written, and parsing it),
//! `settings.rs` (`[render]`), `camera.rs` (`[camera]`), `materials.rs`
//! (`[[material]]` and overrides), `model.rs` (one `[[model]]` loaded and
//! placed) and `compose.rs` (the whole file composed into scene parts).

mod camera;
mod compose;
pub(super) mod error;
mod materials;
mod model;
mod schema;
pub(crate) mod settings;

pub use camera::ShotCamera;
pub use compose::{
    Shot, compose, compose_posed, compose_variant, compose_with, load_shot, load_shot_posed,
    load_shot_variant, load_shot_with,
};
pub use error::ShotError;
pub use schema::{
    AnimationKey, CameraSection, EnvironmentSection, LightSection, MaterialSection, ModelSection,
    RenderSection, Scale, ShotFile, parse,
};
pub use settings::{ShotSettings, read_settings};
