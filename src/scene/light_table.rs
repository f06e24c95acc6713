//! The scene's light tables, as [`Scene`](super::Scene) keeps them: how
//! lights are chosen ([`LightSelection`]), the table that chooses among the
//! lights other than the key light, and the emitting triangles with their
//! power. `light_sampling.rs` builds and reads them.

use super::light_tree::LightTree;
use crate::sampling::distribution::AliasTable;

/// How the light tree's choice gets its number (`Scene::set_light_numbers`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightNumbers {
    /// A number of its own, independent of the point's on the light (the
    /// images of glTF, OBJ, scene files and the lab as they always were).
    #[default]
    Independent,
    /// The light sample's own first number (with an independent number filling in below its last bit), whose
    /// leftover then places the point: Sobol' points stay stratified across
    /// the lights (the default for Mitsuba scenes).
    Stratified,
}

/// How [`Scene::sample_light`](crate::scene::Scene::sample_light) chooses among the lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightSelection {
    /// By a bound on what each light can send to the point being lit
    /// (distance, orientation, the surface's side), through a light tree over
    /// the emitting triangles and the point and spot lights, beside the key
    /// light, the environment and the directional lights.
    #[default]
    Tree,
    /// In proportion to each light's estimated power (the punctual lights
    /// among themselves by what each sends to the point).
    Power,
    /// Every light (every emitting triangle) equally: for comparisons.
    Uniform,
}

/// [`LightSample::Point::light`](crate::scene::LightSample::Point::light) of the key light (the scene's
/// [`PointLight`](crate::scene::PointLight)).
pub const KEY_LIGHT: u32 = u32::MAX;

/// A light at a point (the key light, a point light, a spot or a beam), as
/// the volumetric path tracer chooses among them for the stretches of rays
/// in media ([`Scene::positional_lights`](crate::scene::Scene::positional_lights)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionalLight {
    /// Which light: an index of [`Scene::lights`](crate::scene::Scene::lights), or [`KEY_LIGHT`].
    pub light: u32,
    /// Where it is.
    pub position: glam::Vec3A,
    /// Its greatest intensity (W/sr, the mean over the colour channels): a
    /// spot's on its axis.
    pub intensity: f32,
}

/// A light other than the key light, as the light table names it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum LightRef {
    /// Punctual light `i` of [`Scene::lights`](crate::scene::Scene::lights).
    Punctual(u32),
    /// The environment.
    Environment,
    /// An emitting triangle.
    Triangle(u32),
}

/// The lights other than the key light and an alias table that chooses among
/// them by weight.
#[derive(Clone, Debug, Default)]
pub(super) struct LightTable {
    /// The lights at a point ([`Scene::positional_lights`](crate::scene::Scene::positional_lights)).
    pub(super) positional: Vec<PositionalLight>,
    /// The table's probability of picking one of the punctual lights.
    pub(super) punctual_pmf: f32,
    /// Whether the punctual light picked is chosen by importance at the point
    /// ([`Scene::pick_punctual`](crate::scene::Scene::pick_punctual)).
    pub(super) by_importance: bool,
    pub(super) alias: AliasTable,
    /// Sum of the weights (the table's, as `f32`: read per sample).
    pub(super) total: f32,
    pub(super) entries: Vec<LightRef>,
    /// The environment's entry, if it is a light.
    pub(super) environment: Option<u32>,
    /// Every triangle's entry (`u32::MAX` for non-emitters); empty when none
    /// emits.
    pub(super) prim_entry: Vec<u32>,
    /// [`LightSelection::Tree`]: the emitting triangles, point and spot lights.
    pub(super) tree: LightTree,
    /// [`LightSelection::Tree`]: the directional lights (indices of
    /// [`Scene::lights`](crate::scene::Scene::lights)).
    pub(super) directional: Vec<u32>,
    /// [`LightSelection::Tree`]: the environment's weight (0: none).
    pub(super) env_importance: f32,
    /// Whether the light tree chooses ([`Scene::uses_tree`](crate::scene::Scene::uses_tree)).
    pub(super) tree_active: bool,
}

/// The emitting triangles and their power, for power-proportional selection.
#[derive(Clone, Debug, Default)]
pub(super) struct AreaLights {
    /// Emitting triangles.
    pub(super) prims: Vec<u32>,
    /// Sum of their powers.
    pub(super) total: f32,
    /// Power and area of every triangle (zero power for non-emitters); empty
    /// when none emits.
    pub(super) per_prim: Vec<(f32, f32)>,
}
