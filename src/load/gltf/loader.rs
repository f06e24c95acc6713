//! The state of one load: the [`Loader`] that the scene's node tree is walked
//! with (the tables that make each mesh, material and image read once, the
//! warnings, the lights found), and [`Loader::finish`], which decodes the
//! images and returns the [`GltfScene`].
//!
//! Its methods are split over the files by what they read: `nodes.rs` (the
//! node tree and the instances placed at its nodes), `mesh.rs` (primitives),
//! `material.rs` (materials and their extensions), `texture.rs` (texture
//! references and images), `camera.rs` and `lights.rs`.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use glam::{Mat4, Vec3A};
use gltf::json;

use super::animation::Pose;
use super::buffers::{Buffers, read_uri};
use super::error::GltfError;
use crate::lights::Light;
use crate::memory::Ledger;
use crate::scene::{NO_INSTANCE, PointLight, SceneParts};
use crate::textures::{TextureError, TextureStore};

/// What [`load_gltf`](super::load_gltf) returns: the scene's parts and what
/// to tell the user.
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

/// One load's state as the scene is walked.
pub(super) struct Loader<'a> {
    pub(super) root: &'a json::Root,
    pub(super) buffers: &'a Buffers<'a>,
    pub(super) base: &'a Path,
    /// Where the decoded textures are charged.
    pub(super) ledger: &'a Ledger,
    /// The file, naming it in a memory error.
    pub(super) name: String,
    pub(super) parts: SceneParts,
    /// (mesh, primitive) → mesh data index.
    pub(super) mesh_ids: HashMap<(usize, usize), u32>,
    /// glTF material (None: the default material) → table index.
    pub(super) material_ids: HashMap<Option<usize>, u32>,
    /// glTF image → texture store index.
    pub(super) image_ids: HashMap<usize, u32>,
    /// Images to decode, in store order: (name, bytes source).
    pub(super) image_sources: Vec<(String, usize)>,
    pub(super) warned: HashSet<String>,
    pub(super) warnings: Vec<String>,
    /// Point lights in node order; the first becomes the key light.
    pub(super) point_lights: Vec<(Vec3A, Vec3A)>,
    /// The index of the `KHR_materials_variants` variant shown, if any.
    pub(super) variant: Option<usize>,
    /// How many variants the file defines (mappings must name one of them).
    pub(super) variant_count: usize,
    /// The animation's pose, if the file is posed.
    pub(super) pose: Option<Pose>,
    /// Every node's global transform (posed), made for the first skin.
    pub(super) globals: Option<Vec<Option<Mat4>>>,
}

impl Loader<'_> {
    /// Adds `message` to the warnings unless one of the same `key` was.
    pub(super) fn warn_once(&mut self, key: &str, message: String) {
        if self.warned.insert(key.to_string()) {
            self.warnings.push(message);
        }
    }

    /// Reads and decodes the queued images (in parallel), picks the key light,
    /// and returns the parts.
    pub(super) fn finish(mut self) -> Result<GltfScene, GltfError> {
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
        crate::load::volumes::add_volume_media(&mut self.parts)
            .map_err(|e| GltfError::invalid(format!("KHR_materials_volume_scatter: {e}")))?;
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
