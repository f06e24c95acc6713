//! Mitsuba 3 XML scenes read into a generic, fully resolved tree of objects
//! ([`SceneTree`]): every `$name` substituted, every `<include>` read, every
//! `<ref>` resolved to the (shared) object it names, every `<transform>`
//! composed into one matrix, old (0.x) files upgraded. Turning the tree into
//! raylab's scene is another step; this module knows no plugin's meaning.
//!
//! The rules are those of Mitsuba 3's parser (`src/core/parser.cpp`, which
//! replaced `xml.cpp` in v3.7.0), as of commit `b45b0a9` (v3.9.1-12) of
//! `mitsuba-renderer/mitsuba3`, and of its format documentation
//! (`docs/src/key_topics/scene_format.rst`). `docs/mitsuba-scenes.md` lists
//! them for users; in short:
//!
//! - **Elements.** Objects: `scene`, `bsdf`, `emitter`, `film`,
//!   `integrator`, `medium`, `phase`, `rfilter`, `sampler`, `sensor`,
//!   `shape`, `texture`, `volume`, and `spectrum` *with* a `type` (a spectrum
//!   plugin, a texture to Mitsuba). Values: `float`, `integer`, `boolean`,
//!   `string`, `rgb`, `spectrum`, `point`, `vector`, `transform` (of
//!   `translate`, `rotate`, `scale`, `matrix`, `lookat`). Directives: `ref`,
//!   `include`, `default`, `alias`, `path`. Anything else is an error, and so
//!   is an attribute an element does not take or a missing one it needs
//!   (Mitsuba's `check_attributes`).
//! - **The root** is an object with a `version="major.minor.patch"`; its
//!   `type` is optional (`scene`). Every included file needs its own version.
//! - **Values** (`values.rs`): lists split at commas and spaces; floats as
//!   Mitsuba's `stof` reads them (surrounding spaces or tabs, one leading
//!   `+`), computed in `f64` and stored as `f32`, the precision of Mitsuba's
//!   `scalar_rgb` plugins; integers as `i64` (no `+`); booleans `true` or
//!   `false` in any case; `rgb` of one value (grey) or three; `point`,
//!   `vector` of `value="x, y, z"` (or one value for all three) or all of `x`,
//!   `y`, `z`; `spectrum` a constant, `wavelength:value` pairs (at least two,
//!   wavelengths increasing) or a `filename` (resolved, kept as a path).
//! - **Transforms** (`transform.rs`): each operation left-multiplies the
//!   matrix so far (`M = op · M`), in document order, computed in `f64`.
//! - **Substitution**: in every attribute, `$name` is replaced by a `-D`
//!   definition (`defines`) or a `<default>` given earlier (the definition
//!   wins; longer names first); `\$` is a literal `$`; a `$name` left over is
//!   an error, and so is a definition nothing uses.
//! - **References**: `<ref id=…>` (optionally `name=`) may come before or
//!   after the object; ids are unique; `<alias id= as=>` gives an object a
//!   second id; a cycle of references is an error.
//! - **Includes**: `filename` is looked up in the including file's folder,
//!   then the search paths; an included `<scene>` gives its objects to the
//!   including object, any other root becomes one child (named by the
//!   include's `name`). Depth limit 15 as Mitsuba's; raylab also names a
//!   cycle of includes.
//! - **Search paths**: `<path value=…>` (a child of a file's root; relative
//!   to that file's folder, else to the search paths) is searched first from
//!   then on; one inside an included file only lasts for that file.
//! - **Version < 2.0** (`upgrade.rs`): Mitsuba's `upgrade_from_v1`.
//!
//! Where raylab differs (each is said where it is done): the current folder
//! and Mitsuba's install folder are not searched; non-finite numbers are
//! refused; a property name given twice in one object is an error even when
//! the second is an object (Mitsuba keeps the last object silently); a
//! `<ref>` directly inside an included `<scene>` is carried over (Mitsuba
//! drops it); a `<lookAt>` of a 0.x file is read as `<lookat>` (Mitsuba 3's
//! old `xml.cpp` did this, the new parser refuses it); nesting (through
//! references too) is limited to [`MAX_NESTING`] objects and a substituted
//! attribute to [`MAX_ATTRIBUTE_BYTES`] (all of them together to
//! [`MAX_SUBSTITUTION_BYTES`]); Mitsuba's later passes (merging
//! equal objects, merging meshes, reordering the scene's children) are not
//! done: the tree is the file.
//!
//! `tree.rs` is the tree, `xml.rs` walks the XML into a table of objects
//! (`table.rs`; `xml/include.rs` reads includes, `attrs.rs` checks
//! attributes), `build.rs` resolves references and makes the tree,
//! `values.rs` reads values,
//! `transform.rs` composes transforms, `upgrade.rs` upgrades 0.x files and
//! `error.rs` says why a file cannot be read.

mod attrs;
mod build;
mod error;
mod mesh;
mod ply;
mod scene;
mod serialized;
mod table;
mod transform;
mod tree;
mod upgrade;
mod values;
pub(crate) mod vol;
mod xml;

#[cfg(test)]
mod tests;

use std::path::Path;

pub use error::MitsubaError;
pub use mesh::{MAX_MESH_FACES, MAX_MESH_VERTICES, MeshAttribute, MitsubaMesh};
pub use ply::{parse_ply, read_ply};
pub use scene::{MitsubaScene, load_mitsuba, read_settings};
pub use serialized::{parse_serialized, read_serialized};
pub use tree::{
    Child, Location, MAX_ATTRIBUTE_BYTES, MAX_INCLUDE_DEPTH, MAX_NESTING, MAX_SUBSTITUTION_BYTES,
    Object, Property, SceneTree, Spectrum, Tag, Value, Version,
};
pub use vol::{VolFile, parse_sdf_vol, parse_vol, read_sdf_vol, read_vol};

/// Reads the Mitsuba XML scene at `path`, with `defines` as `mitsuba -D
/// NAME=VALUE` gives them (a later definition of a name replaces an
/// earlier one).
pub fn read(path: &Path, defines: &[(String, String)]) -> Result<SceneTree, MitsubaError> {
    xml::read_file(path, defines)
}

/// Reads a Mitsuba XML scene from `text`, as if it were the file `path`:
/// errors name `path`, and includes and `<path>`s are relative to its
/// folder (which need not hold a file of that name).
pub fn read_str(
    text: &str,
    path: &Path,
    defines: &[(String, String)],
) -> Result<SceneTree, MitsubaError> {
    xml::read_text(text, path, defines)
}
